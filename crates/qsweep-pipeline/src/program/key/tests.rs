//! Tests of a program trial's key: a golden key, what changes it and what does not.

use super::*;
use crate::program::declared::load_str;
use crate::program::model::{InputFile, Protocol, Provenance};
use std::time::Duration;

fn program(inputs: &[(&str, &str)], provenance: &[(&str, bool, &str)]) -> Program {
    Program {
        command: vec!["python3".into(), "agents/q_learning.py".into()],
        input_globs: vec!["agents/*.py".into()],
        inputs: inputs
            .iter()
            .map(|(p, contents)| InputFile {
                path: p.to_string(),
                digest: blake3::hash(contents.as_bytes()).to_hex().to_string(),
            })
            .collect(),
        protocol: Protocol::Process,
        timeout: Duration::from_secs(600),
        metrics: vec![("episodes".into(), crate::program::model::MetricType::Int)],
        objective: None,
        provenance: provenance
            .iter()
            .map(|(c, k, _)| Provenance { command: vec![c.to_string()], key: *k })
            .collect(),
        provenance_outputs: provenance.iter().map(|(_, _, o)| o.to_string()).collect(),
    }
}

fn params() -> (Vec<(String, ParamType)>, Vec<ParamValue>) {
    (
        vec![
            ("env".into(), ParamType::Str),
            ("alpha".into(), ParamType::Float),
            ("bins".into(), ParamType::Int),
        ],
        vec![ParamValue::Str("CartPole-v1".into()), ParamValue::Float(0.1), ParamValue::Int(6)],
    )
}

#[test]
fn golden_key() {
    let id = Identity::of(&program(&[("agents/q_learning.py", "print(1)\n")], &[("pyver", true, "3.12")]));
    let (names, values) = params();
    assert_eq!(
        id.canonical(&names, &values, 3),
        format!(
            r#"{{"command":["python3","agents/q_learning.py"],"inputs":{{"agents/q_learning.py":"{}"}},"params":{{"alpha":0.1,"bins":6,"env":"CartPole-v1"}},"provenance":["3.12"],"seed":3}}"#,
            blake3::hash(b"print(1)\n").to_hex()
        )
    );
    // Written down once: a change here changes every stored program trial's key.
    assert_eq!(
        id.key(&names, &values, 3).hex(),
        "3a0dfe6ff95ccaca55d8e3a8f7f719669061d85844ca2f92ac12e124964c20b8"
    );
}

#[test]
fn the_canonical_text_is_the_canonical_json_of_the_key_object() {
    let id = Identity::of(&program(
        &[("b.py", "b"), ("a.py", "a")],
        &[("x", false, "1"), ("y", true, "two\n\"2\"")],
    ));
    let (names, values) = params();
    let whole = serde_json::json!({
        "seed": 9u64,
        "provenance": ["two\n\"2\""],
        "params": { "bins": 6, "env": "CartPole-v1", "alpha": 0.1 },
        "inputs": { "a.py": blake3::hash(b"a").to_hex().to_string(), "b.py": blake3::hash(b"b").to_hex().to_string() },
        "command": ["python3", "agents/q_learning.py"],
    });
    assert_eq!(id.canonical(&names, &values, 9), canonical_json(&whole));
}

#[test]
fn a_float_param_is_keyed_as_a_float() {
    let id = Identity::of(&program(&[], &[]));
    let names = vec![("alpha".to_string(), ParamType::Float)];
    let text = id.canonical(&names, &[ParamValue::Float(1.0)], 0);
    assert!(text.contains(r#""params":{"alpha":1.0}"#), "{text}");
    assert_ne!(id.key(&names, &[ParamValue::Float(1.0)], 0), id.key(&names, &[ParamValue::Int(1)], 0));
}

#[test]
fn what_changes_a_key_and_what_does_not() {
    let (names, values) = params();
    let key = |p: &Program, seed| Identity::of(p).key(&names, &values, seed);
    let base =
        program(&[("agents/q_learning.py", "v1")], &[("pip", true, "gym 0.29"), ("date", false, "Mon")]);
    let k = key(&base, 0);
    assert_ne!(k, key(&base, 1));
    // Protocol and timeout: not in the key.
    let mut other = base.clone();
    other.protocol = Protocol::Worker;
    other.timeout = Duration::from_secs(5);
    assert_eq!(key(&other, 0), k);
    // An unkeyed provenance output is recorded, not keyed.
    let mut other = base.clone();
    other.provenance_outputs[1] = "Tue".into();
    assert_eq!(key(&other, 0), k);
    assert_ne!(Identity::of(&other).provenance_json, Identity::of(&base).provenance_json);
    // A keyed one is keyed.
    let mut other = base.clone();
    other.provenance_outputs[0] = "gym 1.0".into();
    assert_ne!(key(&other, 0), k);
    // An edited input file, an added one, another command.
    assert_ne!(
        key(
            &program(&[("agents/q_learning.py", "v2")], &[("pip", true, "gym 0.29"), ("date", false, "Mon")]),
            0
        ),
        k
    );
    let mut other = base.clone();
    other.inputs.push(InputFile { path: "agents/new.py".into(), digest: "00".into() });
    assert_ne!(key(&other, 0), k);
    let mut other = base.clone();
    other.command.push("--fast".into());
    assert_ne!(key(&other, 0), k);
    // Another param value.
    let mut v = values.clone();
    v[1] = ParamValue::Float(0.2);
    assert_ne!(Identity::of(&base).key(&names, &v, 0), k);
}

#[test]
fn reformatting_the_pipeline_changes_no_key() {
    let a = "name: s\nseeds: 2\nprogram:\n  command: [python3, q.py]\n  metrics: { episodes: int }\n\
             params:\n  alpha: 0.10\n  bins: 6\nexperiments:\n  - { id: e, vary: { alpha: [0.05, 0.10] } }\n";
    let b = "# the same pipeline, rewritten\nexperiments:\n  - id: e\n    vary:\n      alpha:\n        - 5e-2\n        - 0.1\n\
             params: { bins: 6, alpha: 0.1 }   # other order\nprogram:\n  metrics:\n    episodes: int\n  \
             command:\n    - python3\n    - q.py\n  timeout: 5m\n  protocol: worker\nseeds: [0, 1]\nname: s\n";
    let keys = |text: &str| -> Vec<(Vec<(String, ParamValue)>, crate::cache::Key)> {
        let d = load_str(text, "p.yaml", &[]).unwrap();
        let id = Identity::of(&program(&[], &[]));
        let names = d.param_types();
        let mut out = Vec::new();
        for (_, vals) in &d.experiments[0].axes {
            for v in vals {
                let mut values = d.defaults();
                values[names.iter().position(|(n, _)| n == "alpha").unwrap()] = v.clone();
                let named: Vec<(String, ParamValue)> =
                    names.iter().map(|(n, _)| n.clone()).zip(values.clone()).collect();
                let mut named = named;
                named.sort_by(|x, y| x.0.cmp(&y.0));
                for s in &d.seeds {
                    out.push((named.clone(), id.key(&names, &values, *s)));
                }
            }
        }
        out
    };
    let (ka, kb) = (keys(a), keys(b));
    assert_eq!(ka.len(), 4);
    assert_eq!(ka, kb);
}
