//! Tests of the program pipeline's loader: the issue's example, every error at its line and column,
//! the timeout and provenance forms, `--set`.

use super::*;
use crate::program::model::{Goal, MetricType, ParamValue, Protocol, Provenance};
use std::time::Duration;

/// Issue 61's example, as written there.
pub(crate) const EXAMPLE: &str = "\
name: my-sweep
description: Tabular Q-learning on Gymnasium's CartPole-v1
seeds: 5
program:
  command: [python3, agents/q_learning.py]   # argv, run without a shell
  inputs: [agents/*.py]                     # files (globs) whose contents go into every trial's key
  protocol: process                         # process: one process per trial; worker: one process, many trials
  timeout: 10m                              # per trial
  metrics:                                  # what the program reports, typed
    episodes: int
    solved: bool
    returns: list<float>
  objective: { metric: episodes, goal: minimize }
params:                                     # every parameter with its default
  env: CartPole-v1
  alpha: 0.1
  gamma: 0.99
  bins: 6
experiments:
  - { id: bins-alpha, title: Bins x learning rate, vary: { bins: 2..10, alpha: [0.05, 0.1, 0.2] } }
  - { id: gamma, vary: { gamma: [0.9, 0.99, 0.999] }, fixed: { bins: 6 } }
variants:
  - { id: mountain-car, set: { params.env: MountainCar-v0 } }
";

fn load(text: &str) -> anyhow::Result<ProgramDecl> {
    load_str(text, "p.yaml", &[])
}

fn sets(text: &str, sets: &[&str]) -> anyhow::Result<ProgramDecl> {
    let o: Vec<Override> = sets.iter().map(|s| Override::parse(s).unwrap()).collect();
    load_str(text, "p.yaml", &o)
}

/// The error of `text`, checked to be a user error (exit 2).
fn err(text: &str) -> String {
    let e = load(text).unwrap_err();
    assert!(e.downcast_ref::<crate::error::UserError>().is_some(), "not a user error: {e}");
    e.to_string()
}

/// `p.yaml:LINE:COL:` of the first `needle` in `text` on the `nth` (0-based) line holding it.
fn at(text: &str, needle: &str) -> String {
    let (line, l) = text.lines().enumerate().find(|(_, l)| l.contains(needle)).expect("needle in text");
    format!("p.yaml:{}:{}:", line + 1, l.find(needle).unwrap() + 1)
}

/// `EXAMPLE` with `from` replaced by `to` (exactly once).
fn edit(from: &str, to: &str) -> String {
    assert_eq!(EXAMPLE.matches(from).count(), 1, "{from}");
    EXAMPLE.replace(from, to)
}

fn p(v: &[(&str, ParamValue)]) -> Vec<(String, ParamValue)> {
    v.iter().map(|(n, v)| (n.to_string(), v.clone())).collect()
}

#[test]
fn the_issues_example_loads() {
    let d = load(EXAMPLE).unwrap();
    assert_eq!(d.name, "my-sweep");
    assert_eq!(d.seeds, vec![0, 1, 2, 3, 4]);
    assert_eq!(d.command, ["python3", "agents/q_learning.py"]);
    assert_eq!(d.inputs, ["agents/*.py"]);
    assert_eq!(d.protocol, Protocol::Process);
    assert_eq!(d.timeout, Duration::from_secs(600));
    assert_eq!(
        d.metrics,
        [
            ("episodes".into(), MetricType::Int),
            ("solved".into(), MetricType::Bool),
            ("returns".into(), MetricType::ListFloat)
        ]
    );
    assert_eq!(
        d.objective,
        Some(crate::program::model::Objective { metric: "episodes".into(), goal: Goal::Minimize })
    );
    use ParamValue::*;
    assert_eq!(
        d.params,
        p(&[
            ("env", Str("CartPole-v1".into())),
            ("alpha", Float(0.1)),
            ("gamma", Float(0.99)),
            ("bins", Int(6))
        ])
    );
    let e = &d.experiments;
    assert_eq!(e.len(), 2);
    assert_eq!((e[0].id.as_str(), e[0].title.as_deref()), ("bins-alpha", Some("Bins x learning rate")));
    assert_eq!(e[0].axes[0], ("bins".to_string(), (2..=10).map(Int).collect::<Vec<_>>()));
    assert_eq!(e[0].axes[1], ("alpha".to_string(), vec![Float(0.05), Float(0.1), Float(0.2)]));
    assert_eq!(e[0].cell_count(), 27);
    assert_eq!(e[1].fixed, p(&[("bins", Int(6))]));
    assert_eq!(d.variants.len(), 1);
    assert_eq!(d.variants[0].set, ["params.env=MountainCar-v0"]);
    assert_eq!(d.variants[0].defaults[0], Str("MountainCar-v0".into()));
    assert_eq!(d.variants[0].defaults[1..], d.defaults()[1..]);
}

#[test]
fn defaults_and_optional_sections() {
    let text = "name: tiny\nseeds: [3, 7]\nprogram:\n  command: [./run.sh]\n  metrics: { score: float }\n";
    let d = load(text).unwrap();
    assert_eq!(d.seeds, vec![3, 7]);
    assert_eq!(d.protocol, Protocol::Process);
    assert_eq!(d.timeout, DEFAULT_TIMEOUT);
    assert!(d.inputs.is_empty() && d.params.is_empty() && d.variants.is_empty() && d.provenance.is_empty());
    assert_eq!(d.objective, None);
    // No experiments: one cell of the defaults.
    assert_eq!(d.experiments.len(), 1);
    assert_eq!(d.experiments[0].id, DEFAULT_EXPERIMENT);
    assert_eq!(d.experiments[0].cell_count(), 1);
}

#[test]
fn is_program_looks_at_the_top_level() {
    assert!(is_program(EXAMPLE));
    assert!(!is_program("name: x\nseeds: 2\nsystems: { cart-pole: {} }\n"));
    assert!(!is_program("name: x\nvariants: [{ id: a, set: { program: 1 } }]\n"));
    assert!(!is_program("not: [yaml"));
}

#[test]
fn program_and_systems_together_are_refused_by_both_loaders() {
    let text =
        "name: x\nseeds: 2\nsystems: { cart-pole: {} }\nprogram: { command: [a], metrics: { m: int } }\n";
    let want =
        "p.yaml:4:1: program: a pipeline declares either `systems:` (the built-in engine) or `program:` \
                (your own program), not both; put each in a pipeline file of its own";
    assert_eq!(err(text), want);
    let e = crate::declared::load_str(text, "p.yaml", &[]).unwrap_err();
    assert!(e.downcast_ref::<crate::error::UserError>().is_some());
    assert_eq!(e.to_string(), want);
}

#[test]
fn timeouts_protocols_and_provenance_forms() {
    for (written, secs) in
        [("30s", 30.0), ("10m", 600.0), ("2h", 7200.0), ("90", 90.0), ("1.5", 1.5), ("0.5h", 1800.0)]
    {
        let d = load(&edit("timeout: 10m", &format!("timeout: {written}"))).unwrap();
        assert_eq!(d.timeout, Duration::from_secs_f64(secs), "{written}");
    }
    let e = err(&edit("timeout: 10m", "timeout: 10 min"));
    assert_eq!(
        e,
        format!(
            "{} program.timeout: `10 min` is not a duration; write e.g. 30s, 10m, 2h or a number of seconds",
            at(EXAMPLE, "timeout")
        )
    );
    assert!(
        err(&edit("timeout: 10m", "timeout: 0s")).ends_with("`0s`: a timeout must be more than 0 seconds")
    );
    assert!(err(&edit("timeout: 10m", "timeout: 800h")).contains("at most 30 days"));
    let d = load(&edit("protocol: process", "protocol: worker")).unwrap();
    assert_eq!(d.protocol, Protocol::Worker);
    let e = err(&edit("protocol: process", "protocol: workers"));
    assert!(e.starts_with(&at(EXAMPLE, "protocol")), "{e}");
    assert!(e.ends_with("did you mean `worker`?"), "{e}");
    let text = edit(
        "  objective:",
        "  provenance:\n    - [python3, -c, 'import sys; print(sys.version)']\n    - { command: [pip, freeze], key: true }\n  objective:",
    );
    let d = load(&text).unwrap();
    assert_eq!(
        d.provenance,
        [
            Provenance {
                command: vec!["python3".into(), "-c".into(), "import sys; print(sys.version)".into()],
                key: false
            },
            Provenance { command: vec!["pip".into(), "freeze".into()], key: true },
        ]
    );
    let e = err(&edit("  objective:", "  provenance: [\"pip freeze\"]\n  objective:"));
    assert!(
        e.contains("program.provenance.0: the command `pip freeze` is one text; write it as a list"),
        "{e}"
    );
    let e = err(&edit("  objective:", "  provenance: [{ command: [pip], keys: true }]\n  objective:"));
    assert!(e.contains("unknown field `keys`"), "{e}");
    assert!(e.ends_with("did you mean `key`?"), "{e}");
}

#[test]
fn unknown_params_in_vary_fixed_and_set_name_the_nearest() {
    let text = edit("vary: { bins: 2..10", "vary: { bin: 2..10");
    assert_eq!(
        err(&text),
        format!(
            "{} experiments.0.vary.bin: unknown param `bin`; did you mean `bins`?; the params are env, alpha, gamma, \
             bins (declare a new one under `params:` with its default)",
            at(&text, "bin:")
        )
    );
    let text = edit("fixed: { bins: 6 }", "fixed: { bims: 6 }");
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} experiments.1.fixed.bims: unknown param `bims`; did you mean `bins`?",
            at(&text, "bims")
        )),
        "{e}"
    );
    let text = edit("params.env: MountainCar-v0", "params.envv: MountainCar-v0");
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} variants.0.set.params.envv: unknown param `envv`; did you mean `env`?",
            at(&text, "params.envv")
        )),
        "{e}"
    );
}

#[test]
fn values_must_have_their_params_type() {
    // An integer is fine for a float param.
    let d = load(&edit("alpha: [0.05, 0.1, 0.2]", "alpha: [1, 0.1]")).unwrap();
    assert_eq!(d.experiments[0].axes[1].1, [ParamValue::Float(1.0), ParamValue::Float(0.1)]);
    let text = edit("alpha: [0.05, 0.1, 0.2]", "alpha: [0.05, true, 0.2]");
    assert_eq!(
        err(&text),
        format!(
            "{} experiments.0.vary.alpha.1: `alpha` is a float param (its default is 0.1), so true (true/false) is not \
             allowed here",
            at(&text, "true")
        )
    );
    let text = edit("fixed: { bins: 6 }", "fixed: { bins: 6.5 }");
    assert_eq!(
        err(&text),
        format!(
            "{} experiments.1.fixed.bins: `bins` is an int param (its default is 6), so 6.5 (a number with a \
             fraction) is not allowed here; give a whole number, or write the default with a fraction (6.0) to \
             make `bins` a float param",
            at(&text, "bins: 6.5")
        )
    );
    let text = edit("params.env: MountainCar-v0", "params.env: 3");
    assert!(
        err(&text).ends_with("so 3 (a whole number) is not allowed here; quote it to give it as text: \"3\"")
    );
    let text = edit("gamma: [0.9, 0.99, 0.999]", "gamma: [0.9, 0.99, 0.990]");
    assert_eq!(
        err(&text),
        format!("{} experiments.1.vary.gamma.2: value 0.99 is listed twice", at(&text, "0.990"))
    );
    // A range of a float param gives floats; a range must be a range.
    let d = load(&edit("gamma: [0.9, 0.99, 0.999]", "gamma: 1..3")).unwrap();
    assert_eq!(d.experiments[1].axes[0].1, [1.0, 2.0, 3.0].map(ParamValue::Float));
    let text = edit("bins: 2..10", "bins: 10..2");
    assert!(err(&text).ends_with("range \"10..2\" is empty; the first bound must be ≤ the second"));
    let text = edit("bins: 2..10", "bins: 2..x");
    assert!(err(&text).contains("\"2..x\" is not a range"));
}

#[test]
fn unknown_metric_types_list_the_known_ones() {
    let text = edit("returns: list<float>", "returns: list<int>");
    assert_eq!(
        err(&text),
        format!(
            "{} program.metrics.returns: unknown metric type `list<int>`; the types are int, float, bool, string, \
             list<float>, list<uint32>; did you mean `list<uint32>`?",
            at(&text, "returns")
        )
    );
    let text = edit("    returns: list<float>\n", "");
    assert!(load(&text).is_ok());
    let e = err("name: x\nseeds: 1\nprogram:\n  command: [a]\n  metrics: {}\n");
    assert!(e.starts_with("p.yaml:5:3: program.metrics: no metric is declared"), "{e}");
}

#[test]
fn reserved_and_unsafe_names_are_refused() {
    let text = edit("  bins: 6\n", "  bins: 6\n  seed: 1\n");
    assert_eq!(
        err(&text),
        format!(
            "{} params.seed: `seed` is reserved: qsweep gives each trial its seed itself (`seed` in the JSON it \
             sends); rename this param",
            at(&text, "seed: 1")
        )
    );
    let text = edit("  bins: 6\n", "  bins: 6\n  qsweep_x: 1\n");
    assert!(err(&text).ends_with(
        "params.qsweep_x: names starting with `qsweep_` are reserved for qsweep; rename this param"
    ));
    let text = edit("  bins: 6\n", "  bins: 6\n  a.b: 1\n");
    assert!(err(&text).contains("param name `a.b` is not allowed"));
    let text = edit("    solved: bool", "    seed: bool");
    assert!(err(&text).contains("program.metrics.seed: `seed` is reserved"));
    let text = edit("    solved: bool", "    alpha: bool");
    assert!(err(&text)
        .ends_with("`alpha` is both a param and a metric; rename one (each is a column of the trial rows)"));
    let text = edit("name: my-sweep", "name: my sweep");
    assert!(
        err(&text).starts_with("p.yaml:1:1: name: name `my sweep` is not allowed; use 1-100 letters"),
        "{}",
        err(&text)
    );
    let text = edit("id: gamma,", "id: ../gamma,");
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} experiments.1.id: id `../gamma` is not allowed",
            at(&text, "id: ../gamma")
        )),
        "{e}"
    );
    let text = edit("id: mountain-car", "id: figures");
    assert!(err(&text).contains("variants.0.id: variant id `figures` is not allowed"));
}

#[test]
fn objectives_need_a_declared_numeric_metric() {
    let text = edit("metric: episodes", "metric: solved");
    assert_eq!(
        err(&text),
        format!(
            "{} program.objective.metric: `solved` is a bool metric; the objective must be an int or float metric",
            at(&text, "metric: solved")
        )
    );
    let text = edit("metric: episodes", "metric: episode");
    assert!(err(&text).contains("unknown metric `episode`; did you mean `episodes`?; the objective is one of the metrics: episodes, solved, returns"));
    let text = edit("goal: minimize", "goal: lower");
    assert!(err(&text).contains("unknown variant `lower`, expected `minimize` or `maximize`"));
}

#[test]
fn commands_must_be_argv_lists() {
    let text = edit("command: [python3, agents/q_learning.py]", "command: []");
    assert_eq!(
        err(&text),
        format!(
            "{} program.command: the command is empty; write it as a list of arguments, e.g. [python3, \
             agents/q_learning.py]; no shell runs it",
            at(&text, "command")
        )
    );
    let text = edit("command: [python3, agents/q_learning.py]", "command: python3 agents/q_learning.py");
    assert!(err(&text).contains("the command `python3 agents/q_learning.py` is one text"));
    let d = load(&edit("command: [python3, agents/q_learning.py]", "command: [sleep, 1]")).unwrap();
    assert_eq!(d.command, ["sleep", "1"]);
    let text = edit("inputs: [agents/*.py]", "inputs: [agents/*.py, '']");
    assert!(err(&text).contains("program.inputs.1: the glob is empty; remove it"));
}

#[test]
fn experiment_rules() {
    let text = edit("fixed: { bins: 6 }", "fixed: { gamma: 0.9 }");
    assert_eq!(
        err(&text),
        format!(
            "{} experiments.1.fixed.gamma: `gamma` is both varied (vary:) and fixed in experiment gamma; remove it \
             from one of them",
            at(&text, "gamma: 0.9 }")
        )
    );
    let text = edit("id: gamma,", "id: bins-alpha,");
    assert_eq!(
        err(&text),
        format!(
            "{} experiments.1.id: id `bins-alpha` is used twice; experiment ids must be unique",
            at(&text, "id: bins-alpha, vary")
        )
    );
    let text = edit("vary: { gamma: [0.9, 0.99, 0.999] }", "vary: { gamma: [0.9], gamma: [0.5] }");
    assert!(err(&text).starts_with(&format!(
        "{} experiments.1.vary.gamma: `gamma` is varied twice",
        at(&text, "gamma: [0.5]")
    )));
    let text =
        "name: x\nseeds: 1\nprogram: { command: [a], metrics: { m: int } }\nexperiments: [{ id: a }]\n";
    assert!(err(text).starts_with(
        "p.yaml:4:1: experiments: experiments vary and fix params, but `params:` declares none"
    ));
    let text = edit("  - { id: gamma, vary", "  - { id: 7, vary");
    assert_eq!(load(&text).unwrap().experiments[1].id, "7");
}

#[test]
fn variant_rules() {
    let text = edit(
        "  - { id: mountain-car, set: { params.env: MountainCar-v0 } }\n",
        "  - { id: mountain-car, set: { params.env: MountainCar-v0 } }\n  - { id: mountain-car }\n",
    );
    assert!(err(&text).contains("variants.1.id: id `mountain-car` is used twice; variant ids must be unique"));
    let text = edit("params.env: MountainCar-v0", "program.timeout: 5m");
    assert_eq!(
        err(&text),
        format!(
            "{} variants.0.set.program.timeout: a variant sets params only, as `params.NAME: VALUE` (it runs the same \
             program with other params); `program.timeout` is not one (`--set` on the command line may change any field)",
            at(&text, "program.timeout")
        )
    );
    let text = edit("params.env: MountainCar-v0", "params.alpha: 0.5");
    assert!(err(&text).contains(
        "variants.0.set.params.alpha: experiment bins-alpha varies `alpha` (vary:), so this value would be ignored there"
    ));
    let text = edit("{ params.env: MountainCar-v0 }", "{ params: { env: MountainCar-v0 } }");
    assert!(err(&text).contains("write each param as its own entry, `params.NAME: VALUE`"));
    let text = edit("params.env: MountainCar-v0", "params.env: [a, b]");
    assert!(
        err(&text).contains("variants.0.set.params.env: `params.env`: invalid type: sequence"),
        "{}",
        err(&text)
    );
}

#[test]
fn unknown_keys_are_refused_with_a_suggestion() {
    let text = edit("protocol: process", "protocl: process");
    assert_eq!(
        err(&text),
        format!(
            "{} program: unknown field `protocl`, expected one of `command`, `inputs`, `protocol`, `timeout`, \
             `metrics`, `objective`, `provenance`; did you mean `protocol`?",
            at(&text, "protocl")
        )
    );
    let e = err(&edit("seeds: 5", "seeds: 5\nseed: 1"));
    assert!(e.starts_with("p.yaml:4:1: unknown field `seed`, expected one of `name`"), "{e}");
}

#[test]
fn set_overrides_apply_before_typing_and_name_themselves() {
    let d = sets(EXAMPLE, &["params.alpha=0.2", "program.timeout=5m", "seeds=2"]).unwrap();
    assert_eq!(d.params[1], ("alpha".to_string(), ParamValue::Float(0.2)));
    assert_eq!(d.timeout, Duration::from_secs(300));
    assert_eq!(d.seeds, vec![0, 1]);
    // An integer for a float param stays a float; the file's default fixes the type.
    let d = sets(EXAMPLE, &["params.gamma=1"]).unwrap();
    assert_eq!(d.params[2].1, ParamValue::Float(1.0));
    let e = sets(EXAMPLE, &["params.bins=2.5"]).unwrap_err().to_string();
    assert!(
        e.starts_with(
            "p.yaml with --set params.bins=2.5: params.bins: `bins` is an int param (its default is 6)"
        ),
        "{e}"
    );
    let e = sets(EXAMPLE, &["program.protocl=worker"]).unwrap_err().to_string();
    assert!(
        e.starts_with("p.yaml with --set program.protocl=worker: program: unknown field `protocl`"),
        "{e}"
    );
    // An error the --set does not touch keeps its position.
    let text = edit("vary: { bins: 2..10", "vary: { bin: 2..10");
    let e = sets(&text, &["seeds=2"]).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{} experiments.0.vary.bin: unknown param", at(&text, "bin:"))), "{e}");
    // The command line's --set wins over a variant's set.
    let d = sets(EXAMPLE, &["params.env=Acrobot-v1"]).unwrap();
    assert_eq!(d.variants[0].defaults[0], ParamValue::Str("Acrobot-v1".into()));
    assert_eq!(d.variants[0].set, ["params.env=MountainCar-v0"]);
}

#[test]
fn load_reads_files_and_refuses_empty_ones() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.yaml");
    std::fs::write(&path, EXAMPLE).unwrap();
    let l = super::load(&path, &[]).unwrap();
    assert_eq!(l.decl, load(EXAMPLE).unwrap());
    assert_eq!(l.text, EXAMPLE);
    let e = l.error_at(&["program", "inputs", "0"], "boom").to_string();
    assert_eq!(e, format!("{}:6:12: program.inputs.0: boom", path.display()));
    std::fs::write(&path, "# nothing\n").unwrap();
    let e = super::load(&path, &[]).unwrap_err().to_string();
    assert!(e.ends_with("the file is empty; a program pipeline needs at least name, seeds and program (its command and metrics)"));
}
