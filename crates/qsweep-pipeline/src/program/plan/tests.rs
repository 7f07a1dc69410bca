//! Tests of a program pipeline's plan: cells, seeds, variants, keys, the trial limit, inputs and
//! provenance errors at their lines.

use super::*;
use crate::program::declared::{load, LoadedProgram};
use crate::program::model::ParamValue::{Float, Int, Str};
use std::path::PathBuf;

/// A directory holding the agents and `p.yaml` with `text`; the loaded pipeline.
fn fixture(text: &str) -> (tempfile::TempDir, LoadedProgram) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("agents")).unwrap();
    std::fs::write(dir.path().join("agents/q_learning.py"), "import sys\nprint('{\"episodes\": 1}')\n")
        .unwrap();
    std::fs::write(dir.path().join("agents/util.py"), "X = 1\n").unwrap();
    std::fs::write(dir.path().join("agents/notes.txt"), "not an input\n").unwrap();
    let path = dir.path().join("p.yaml");
    std::fs::write(&path, text).unwrap();
    let loaded = load(&path, &[]).unwrap();
    (dir, loaded)
}

fn plan_in(dir: &tempfile::TempDir, loaded: &LoadedProgram, select: &[&str]) -> anyhow::Result<ProgramPlan> {
    let select: Vec<String> = select.iter().map(|s| s.to_string()).collect();
    plan(loaded, dir.path(), Some(crate::plan::DEFAULT_MAX_TRIALS), &select)
}

const EXAMPLE: &str = crate::program::declared::tests::EXAMPLE;

fn without_variants(text: &str) -> String {
    text[..text.find("variants:").unwrap()].to_string()
}

#[test]
fn the_issues_example_plans_every_variant() {
    let (dir, loaded) = fixture(EXAMPLE);
    let p = plan_in(&dir, &loaded, &[]).unwrap();
    assert_eq!(p.name, "my-sweep");
    assert_eq!(p.source, dir.path().join("p.yaml"));
    let inputs: Vec<&str> = p.program.inputs.iter().map(|f| f.path.as_str()).collect();
    assert_eq!(inputs, ["agents/q_learning.py", "agents/util.py"]);
    // By name, whatever order the file declares them in (the rows' columns and folder follow).
    assert_eq!(
        p.params.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(),
        ["alpha", "bins", "env", "gamma"]
    );
    let metrics: Vec<&str> = p.program.metrics.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(metrics, ["episodes", "returns", "solved"]);
    assert_eq!(p.seeds, [0, 1, 2, 3, 4]);
    // With variants, the plan is the variants' (here one), as for the engine.
    assert_eq!(p.variants.len(), 1);
    assert_eq!(p.variants[0].set, ["params.env=MountainCar-v0"]);
    assert_eq!(p.experiments.len(), 2);
    let e = &p.experiments[0];
    assert_eq!((e.variant.as_deref(), e.id.as_str()), (Some("mountain-car"), "bins-alpha"));
    assert_eq!(e.axes, ["bins", "alpha"]);
    assert_eq!(e.cells.len(), 27);
    // The first axis is outermost.
    assert_eq!(e.cells[0].coords, [Int(2), Float(0.05)]);
    assert_eq!(e.cells[1].coords, [Int(2), Float(0.1)]);
    assert_eq!(e.cells[3].coords, [Int(3), Float(0.05)]);
    assert_eq!(e.cells[26].coords, [Int(10), Float(0.2)]);
    assert_eq!(e.cells[1].params, [Float(0.1), Int(2), Str("MountainCar-v0".into()), Float(0.99)]);
    assert_eq!(e.cells[1].trials.iter().map(|t| t.seed).collect::<Vec<_>>(), [0, 1, 2, 3, 4]);
    let g = &p.experiments[1];
    assert_eq!(g.fixed, [("bins".to_string(), Int(6))]);
    assert_eq!(g.cells[2].params, [Float(0.1), Int(6), Str("MountainCar-v0".into()), Float(0.999)]);
    // Every trial has its own key, but for the one cell both experiments hold (bins 6, alpha 0.1,
    // gamma 0.99): its trials are the same trials.
    let keys: HashSet<_> =
        p.experiments.iter().flat_map(|e| &e.cells).flat_map(|c| &c.trials).map(|t| t.key).collect();
    assert_eq!(keys.len(), 30 * 5 - 5);
    assert_eq!(e.cells[13].params, g.cells[1].params);
    assert_eq!(e.cells[13].trials, g.cells[1].trials);
    assert!(p.warnings.is_empty());
}

#[test]
fn golden_key_of_a_planned_trial() {
    let text = "name: g\nseeds: [7]\nprogram:\n  command: [python3, agents/q_learning.py]\n  inputs: [agents/*.py]\n  \
                metrics: { episodes: int }\nparams: { alpha: 0.1, bins: 6, env: CartPole-v1 }\n";
    let (dir, loaded) = fixture(text);
    let p = plan_in(&dir, &loaded, &[]).unwrap();
    assert_eq!(p.experiments.len(), 1);
    assert_eq!((p.experiments[0].id.as_str(), p.experiments[0].variant.as_deref()), ("default", None));
    let cells = &p.experiments[0].cells;
    assert_eq!(cells.len(), 1);
    assert!(cells[0].coords.is_empty());
    // Written down once (the agents' contents are the fixture's).
    assert_eq!(
        cells[0].trials[0].key.hex(),
        "cd3d25e19740d114a71c8b69bb4df77e1a4a03be511bc41896f398c62b9b3a35"
    );
}

#[test]
fn reordering_params_or_metrics_in_the_file_moved_the_rows_to_another_folder() {
    // Regression: the rows' folder hashed params and metrics in declared order, so a file that
    // listed them in another order ran every trial again.
    let (dir, loaded) = fixture(EXAMPLE);
    let a = plan_in(&dir, &loaded, &[]).unwrap();
    let swapped = EXAMPLE
        .replace("  env: CartPole-v1\n  alpha: 0.1\n", "  alpha: 0.1\n  env: CartPole-v1\n")
        .replace("    episodes: int\n    solved: bool\n", "    solved: bool\n    episodes: int\n");
    assert_ne!(swapped, EXAMPLE, "the fixture lists them as the test expects");
    let (dir2, loaded2) = fixture(&swapped);
    let b = plan_in(&dir2, &loaded2, &[]).unwrap();
    assert_eq!((&a.params, &a.program.metrics), (&b.params, &b.program.metrics));
    let keys = |p: &ProgramPlan| {
        p.experiments.iter().flat_map(|e| &e.cells).map(|c| c.trials[0].key).collect::<Vec<_>>()
    };
    assert_eq!(keys(&a), keys(&b));
    let cells = |p: &ProgramPlan| {
        p.experiments.iter().flat_map(|e| &e.cells).map(|c| c.params.clone()).collect::<Vec<_>>()
    };
    assert_eq!(cells(&a), cells(&b));
    assert_eq!(
        crate::program::model::schema_id(&a.params, &a.program.metrics),
        crate::program::model::schema_id(&b.params, &b.program.metrics)
    );
}

#[test]
fn the_pipeline_as_written_plans_without_variants() {
    let (dir, loaded) = fixture(&without_variants(EXAMPLE));
    let p = plan_in(&dir, &loaded, &[]).unwrap();
    assert!(p.variants.is_empty());
    assert_eq!(p.experiments.len(), 2);
    assert!(p.experiments.iter().all(|e| e.variant.is_none()));
    assert_eq!(p.experiments[0].cells[0].params[2], Str("CartPole-v1".into()), "env, third by name");
    let e = plan_in(&dir, &loaded, &["x"]).unwrap_err().to_string();
    assert_eq!(e, format!("--variant x: {} declares no variants; remove --variant", loaded.origin()));
}

#[test]
fn variants_share_the_trials_they_have_in_common_and_warn_when_they_change_none() {
    let text = format!(
        "{}variants:\n  - {{ id: as-written }}\n  - {{ id: mountain-car, set: {{ params.env: MountainCar-v0 }} }}\n  \
         - {{ id: same, set: {{ params.env: CartPole-v1 }} }}\n",
        without_variants(EXAMPLE)
    );
    let (dir, loaded) = fixture(&text);
    let p = plan_in(&dir, &loaded, &[]).unwrap();
    assert_eq!(p.experiments.len(), 6);
    let ids: Vec<_> = p.variants.iter().map(|v| v.id.as_str()).collect();
    assert_eq!(ids, ["as-written", "mountain-car", "same"]);
    let keys = |v: &str| -> Vec<Key> {
        p.experiments
            .iter()
            .filter(|e| e.variant.as_deref() == Some(v))
            .flat_map(|e| &e.cells)
            .flat_map(|c| &c.trials)
            .map(|t| t.key)
            .collect()
    };
    assert_eq!(keys("as-written"), keys("same"));
    assert!(keys("mountain-car").iter().all(|k| !keys("as-written").contains(k)));
    assert_eq!(
        p.warnings,
        ["variant `same` changes no trial (its set gives the same configurations as the pipeline as written)"]
    );
    let one = plan_in(&dir, &loaded, &["mountain-car"]).unwrap();
    assert_eq!(one.variants.len(), 1);
    assert_eq!(keys("mountain-car"), {
        one.experiments
            .iter()
            .flat_map(|e| &e.cells)
            .flat_map(|c| &c.trials)
            .map(|t| t.key)
            .collect::<Vec<_>>()
    });
    let e = plan_in(&dir, &loaded, &["mountain-cat"]).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "--variant mountain-cat: {} has no such variant; its variants are as-written, mountain-car, same; did \
             you mean `mountain-car`?",
            loaded.origin()
        )
    );
}

#[test]
fn a_variant_of_a_param_every_experiment_fixes_changes_no_trial() {
    let text = "name: f\nseeds: 2\nprogram: { command: [a], metrics: { m: int } }\nparams: { alpha: 0.1, bins: 6 }\n\
                experiments: [{ id: a, vary: { alpha: [0.1, 0.2] }, fixed: { bins: 4 } }]\n\
                variants: [{ id: w }, { id: b8, set: { params.bins: 8 } }]\n";
    let (dir, loaded) = fixture(text);
    let p = plan_in(&dir, &loaded, &[]).unwrap();
    assert_eq!(p.experiments[0].cells, p.experiments[1].cells);
    assert_eq!(
        p.warnings,
        ["variant `b8` changes no trial (its set gives the same configurations as the pipeline as written)"]
    );
}

#[test]
fn large_plans_need_confirmation() {
    let (dir, loaded) = fixture(EXAMPLE);
    assert_eq!(planned_trials(&loaded.decl, &[]), 150);
    let e = plan(&loaded, dir.path(), Some(100), &[]).unwrap_err();
    assert!(e.downcast_ref::<crate::error::UserError>().is_some());
    assert_eq!(
        e.to_string(),
        format!(
            "{}: the plan has 150 trials, more than the confirmation limit of 100; rerun with --yes if this is \
             intended, or shrink the grid or the seeds",
            loaded.origin()
        )
    );
    assert!(plan(&loaded, dir.path(), None, &[]).is_ok());
}

#[test]
fn a_glob_that_matches_nothing_is_an_error_at_its_line() {
    let (dir, loaded) = fixture(&EXAMPLE.replace("inputs: [agents/*.py]", "inputs: [agents/*.py, lib/*.py]"));
    let e = plan_in(&dir, &loaded, &[]).unwrap_err();
    assert!(e.downcast_ref::<crate::error::UserError>().is_some());
    assert_eq!(
        e.to_string(),
        format!(
            "{}:6:25: program.inputs.1: `lib/*.py` matches no file (in {}); fix the glob or remove it",
            loaded.origin(),
            dir.path().display()
        )
    );
}

#[test]
fn provenance_runs_once_in_the_base_directory_and_a_failure_names_it() {
    let text = EXAMPLE.replace(
        "  objective:",
        "  provenance:\n    - [sh, -c, 'cat agents/util.py']\n    - { command: [sh, -c, 'echo v2'], key: true }\n  objective:",
    );
    let (dir, loaded) = fixture(&text);
    let p = plan_in(&dir, &loaded, &[]).unwrap();
    assert_eq!(p.program.provenance_outputs, ["X = 1", "v2"]);
    let text = EXAMPLE.replace("  objective:", "  provenance:\n    - [sh, -c, 'exit 4']\n  objective:");
    let (dir, loaded) = fixture(&text);
    let e = plan_in(&dir, &loaded, &[]).unwrap_err();
    assert!(e.downcast_ref::<crate::error::UserError>().is_some());
    assert_eq!(
        e.to_string(),
        format!(
            "{}:14:7: program.provenance.0: provenance command `sh -c 'exit 4'` failed (exit code 4)",
            loaded.origin()
        )
    );
}

#[test]
fn editing_an_input_rekeys_every_trial_and_an_added_value_adds_only_its_cells() {
    let (dir, loaded) = fixture(&without_variants(EXAMPLE));
    let all = |p: &ProgramPlan| -> Vec<Key> {
        p.experiments.iter().flat_map(|e| &e.cells).flat_map(|c| &c.trials).map(|t| t.key).collect()
    };
    let before = all(&plan_in(&dir, &loaded, &[]).unwrap());
    std::fs::write(dir.path().join("agents/util.py"), "X = 2\n").unwrap();
    let after = all(&plan_in(&dir, &loaded, &[]).unwrap());
    assert_eq!(before.len(), after.len());
    assert!(after.iter().all(|k| !before.contains(k)));
    // A text file the globs do not take changes nothing.
    std::fs::write(dir.path().join("agents/notes.txt"), "edited\n").unwrap();
    assert_eq!(all(&plan_in(&dir, &loaded, &[]).unwrap()), after);
    // One more alpha: exactly its 9 cells × 5 seeds are new.
    let path: PathBuf = dir.path().join("p.yaml");
    std::fs::write(&path, without_variants(EXAMPLE).replace("[0.05, 0.1, 0.2]", "[0.05, 0.1, 0.2, 0.4]"))
        .unwrap();
    let more = all(&plan_in(&dir, &load(&path, &[]).unwrap(), &[]).unwrap());
    let old: HashSet<Key> = after.iter().copied().collect();
    assert_eq!(more.iter().filter(|k| !old.contains(k)).count(), 9 * 5);
    assert!(after.iter().all(|k| more.contains(k)));
}
