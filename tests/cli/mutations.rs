//! Property test: any mutation of a valid pipeline either plans or fails with a clean usage error
//! naming the file — never a panic. Runs in-process on `pipelines/quick.yaml`.

use crate::helpers::repo;
use proptest::prelude::*;
use qsweep_pipeline::error::UserError;

/// One edit of the text: insert, delete or replace a character, or duplicate, drop or swap lines.
#[derive(Debug, Clone)]
enum Edit {
    Insert(usize, char),
    Delete(usize),
    Replace(usize, char),
    DuplicateLine(usize),
    DropLine(usize),
    SwapLines(usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let ch = prop::sample::select(vec![
        ':', '-', ' ', '\t', '\n', '[', ']', '{', '}', ',', '&', '*', '#', '"', '\'', '0', '9', '.', 'e',
        'x', '=', '|', '>', '!', '%', '@', 'é',
    ]);
    prop_oneof![
        (any::<usize>(), ch.clone()).prop_map(|(i, c)| Edit::Insert(i, c)),
        any::<usize>().prop_map(Edit::Delete),
        (any::<usize>(), ch).prop_map(|(i, c)| Edit::Replace(i, c)),
        any::<usize>().prop_map(Edit::DuplicateLine),
        any::<usize>().prop_map(Edit::DropLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::SwapLines(a, b)),
    ]
}

fn apply(text: &str, e: &Edit) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    let mut lines: Vec<&str> = text.lines().collect();
    let n = chars.len().max(1);
    let l = lines.len().max(1);
    match *e {
        Edit::Insert(i, c) => chars.insert(i % (n + 1).min(chars.len() + 1), c),
        Edit::Delete(i) if !chars.is_empty() => {
            chars.remove(i % n);
        }
        Edit::Replace(i, c) if !chars.is_empty() => chars[i % n] = c,
        Edit::DuplicateLine(i) if !lines.is_empty() => {
            let line = lines[i % l];
            lines.insert(i % l, line);
            return lines.join("\n");
        }
        Edit::DropLine(i) if !lines.is_empty() => {
            lines.remove(i % l);
            return lines.join("\n");
        }
        Edit::SwapLines(a, b) if !lines.is_empty() => {
            lines.swap(a % l, b % l);
            return lines.join("\n");
        }
        _ => {}
    }
    chars.into_iter().collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_pipelines_plan_or_fail_cleanly(edits in prop::collection::vec(edit(), 1..4)) {
        let mut text = std::fs::read_to_string(repo().join("pipelines/quick.yaml")).unwrap();
        for e in &edits {
            text = apply(&text, e);
        }
        match qsweep_pipeline::declared::load_str(&text, "mutant.yaml", &[]) {
            Ok(spec) => {
                let loaded = qsweep_pipeline::declared::LoadedSpec { spec, path: "mutant.yaml".into(), variants: Vec::new() };
                if let Err(err) = qsweep_pipeline::plan::plan(&loaded, Some(200_000)) {
                    prop_assert!(err.downcast_ref::<UserError>().is_some(), "{err:#}");
                    prop_assert!(err.to_string().contains("mutant.yaml"), "{err:#}");
                }
            }
            Err(err) => {
                prop_assert!(err.downcast_ref::<UserError>().is_some(), "{err:#}");
                prop_assert!(err.to_string().starts_with("mutant.yaml"), "{err:#}");
            }
        }
    }
}
