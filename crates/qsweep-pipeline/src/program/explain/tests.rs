//! Tests of `status --explain` for a program pipeline: every kind of reason a trial is missing.

use super::*;
use crate::program::declared::{load_str, LoadedProgram};
use crate::program::model::{InputFile, MetricType, MetricValue, Program, Protocol, Provenance};
use crate::program::plan::plan_with;
use std::time::Duration;

const TEXT: &str = "name: e\nseeds: 2\nprogram:\n  command: [python3, agents/q_learning.py]\n  \
                    metrics: { episodes: int }\nparams: { alpha: 0.1, bins: 6 }\n\
                    experiments: [{ id: a, vary: { alpha: [0.1, 0.2] } }]\n";

fn program(inputs: &[(&str, &str)], pip: &str) -> Program {
    Program {
        command: vec!["python3".into(), "agents/q_learning.py".into()],
        input_globs: vec!["agents/*.py".into()],
        inputs: inputs
            .iter()
            .map(|(p, d)| InputFile { path: p.to_string(), digest: d.to_string() })
            .collect(),
        protocol: Protocol::Process,
        timeout: Duration::from_secs(60),
        metrics: vec![("episodes".into(), MetricType::Int)],
        objective: None,
        provenance: vec![
            Provenance { command: vec!["pip".into(), "freeze".into()], key: true },
            Provenance { command: vec!["date".into()], key: false },
        ],
        provenance_outputs: vec![pip.to_string(), "Mon".to_string()],
    }
}

fn plan_of(text: &str, program: Program) -> ProgramPlan {
    let decl = load_str(text, "p.yaml", &[]).unwrap();
    let loaded = LoadedProgram { decl, path: "p.yaml".into(), text: text.to_string(), overrides: vec![] };
    plan_with(&loaded, program, &[]).unwrap()
}

/// The identities of every trial of `plan`, as the rows it would store.
fn stored(plan: &ProgramPlan) -> Vec<StoredIdentity> {
    let id = Identity::of(&plan.program);
    let mut out = Vec::new();
    for c in plan.experiments.iter().flat_map(|e| &e.cells) {
        for t in &c.trials {
            out.push(StoredIdentity {
                seed: t.seed,
                params: plan.params.iter().map(|(n, _)| n.clone()).zip(c.params.clone()).collect(),
                command_json: id.command_json.clone(),
                inputs_json: id.inputs_json.clone(),
                provenance_json: id.provenance_json.clone(),
            });
        }
    }
    out
}

fn keys(plan: &ProgramPlan) -> HashSet<Key> {
    plan.experiments.iter().flat_map(|e| &e.cells).flat_map(|c| &c.trials).map(|t| t.key).collect()
}

fn reasons(now: &ProgramPlan, before: &ProgramPlan) -> Vec<String> {
    why_missing(now, &keys(before), &stored(before)).iter().map(|m| m.reason.to_string()).collect()
}

#[test]
fn nothing_missing_nothing_said() {
    let p = plan_of(TEXT, program(&[("agents/q.py", "d1")], "gym 0.29"));
    assert!(why_missing(&p, &keys(&p), &stored(&p)).is_empty());
}

#[test]
fn an_edited_an_added_and_a_removed_input_are_named() {
    let before = plan_of(TEXT, program(&[("agents/q.py", "d1"), ("agents/old.py", "d0")], "gym 0.29"));
    let now = plan_of(TEXT, program(&[("agents/q.py", "d2"), ("agents/new.py", "d3")], "gym 0.29"));
    let m = why_missing(&now, &keys(&before), &stored(&before));
    assert_eq!(m.len(), 2);
    assert_eq!((m[0].experiment, m[0].cell, m[0].missing, m[0].trials), (0, 0, 2, 2));
    assert_eq!(
        m[0].reason,
        Reason::Differences(vec![
            "input agents/new.py added".into(),
            "input agents/q.py changed".into(),
            "input agents/old.py removed".into(),
        ])
    );
}

#[test]
fn a_changed_param_is_named_against_the_nearest_row() {
    let before = plan_of(TEXT, program(&[], "gym 0.29"));
    let now = plan_of(&TEXT.replace("[0.1, 0.2]", "[0.1, 0.3]"), program(&[], "gym 0.29"));
    // The 0.1 cell is stored; the 0.3 cell is nearest to both stored cells (one param each):
    // the tie goes to the text that sorts first.
    assert_eq!(reasons(&now, &before), ["params.alpha: 0.1 → 0.3"]);
    let now = plan_of(&TEXT.replace("bins: 6", "bins: 7"), program(&[], "gym 0.29"));
    assert_eq!(reasons(&now, &before), ["params.bins: 6 → 7", "params.bins: 6 → 7"]);
}

#[test]
fn a_param_added_or_removed_shows_unset() {
    let before = plan_of(TEXT, program(&[], "gym 0.29"));
    let now = plan_of(&TEXT.replace("bins: 6 }", "bins: 6, env: CartPole-v1 }"), program(&[], "gym 0.29"));
    assert_eq!(reasons(&now, &before)[0], "params.env: (unset) → CartPole-v1");
    let now = plan_of(&TEXT.replace(", bins: 6 }", " }"), program(&[], "gym 0.29"));
    assert_eq!(reasons(&now, &before)[0], "params.bins: 6 → (unset)");
}

#[test]
fn command_and_keyed_provenance_are_named() {
    let before = plan_of(TEXT, program(&[], "gym 0.29"));
    let mut p = program(&[], "gym 0.29");
    p.command.push("--fast".into());
    let now = plan_of(TEXT, p);
    assert_eq!(
        reasons(&now, &before)[0],
        "command changed: python3 agents/q_learning.py → python3 agents/q_learning.py --fast"
    );
    let now = plan_of(TEXT, program(&[], "gym 1.0\nnumpy 2"));
    assert_eq!(reasons(&now, &before)[0], "provenance changed: `pip freeze`: gym 0.29 → gym 1.0…");
    // An unkeyed output that changed is recorded, not keyed: nothing is missing.
    let mut p = program(&[], "gym 0.29");
    p.provenance_outputs[1] = "Tue".into();
    let now = plan_of(TEXT, p);
    assert!(why_missing(&now, &keys(&before), &stored(&before)).is_empty());
    let mut p = program(&[], "gym 0.29");
    p.provenance[1].key = true;
    let now = plan_of(TEXT, p);
    assert_eq!(reasons(&now, &before)[0], "provenance added: `date` (key: true)");
}

#[test]
fn a_seed_never_stored_is_never_computed() {
    let before = plan_of(TEXT, program(&[], "gym 0.29"));
    let now = plan_of(&TEXT.replace("seeds: 2", "seeds: [0, 1, 5]"), program(&[], "gym 0.29"));
    let m = why_missing(&now, &keys(&before), &stored(&before));
    assert_eq!(m.len(), 2);
    assert_eq!((m[0].missing, m[0].trials), (1, 3));
    assert_eq!(m[0].reason, Reason::NeverComputed { seed: 5 });
    assert_eq!(m[0].reason.to_string(), "never computed (no stored trial has seed 5)");
}

#[test]
fn differences_of_one_trial_and_identities_of_rows() {
    let before = plan_of(TEXT, program(&[("agents/q.py", "d1")], "gym 0.29"));
    let now = plan_of(TEXT, program(&[("agents/q.py", "d2")], "gym 0.29"));
    let row = ProgramRow {
        key: before.experiments[0].cells[0].trials[0].key,
        seed: 0,
        params: before.experiments[0].cells[0].params.clone(),
        result: Ok(vec![MetricValue::Int(3)]),
        seconds: 1.0,
        cpu_seconds: None,
        command_json: stored(&before)[0].command_json.clone(),
        inputs_json: stored(&before)[0].inputs_json.clone(),
        provenance_json: stored(&before)[0].provenance_json.clone(),
    };
    let s = StoredIdentity::of_row(&row, &before.params);
    assert_eq!(s, stored(&before)[0]);
    let params: Vec<(String, ParamValue)> =
        vec![("alpha".into(), ParamValue::Float(0.2)), ("bins".into(), ParamValue::Int(6))];
    assert_eq!(differences(&now, &params, &s), ["params.alpha: 0.1 → 0.2", "input agents/q.py changed"]);
}
