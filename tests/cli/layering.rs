//! The architecture's import rules inside each crate (ARCHITECTURE.md), checked on the source.
//! Between crates the compiler holds the layers (a crate cannot name one that does not depend on
//! it); inside a crate only this test does: every top-level module of `qsweep-pipeline` and of
//! `qsweep-report` imports only modules of lower layers (the report's memo at the bottom, its
//! replication above the generic parts, which never import it), the replication's own parts are
//! layered too, the engine's representations never import the learner, in no crate do two
//! top-level parts import each other (directly or through others), and in no crate does a file
//! import a file that imports it back. Test code (`*tests.rs`, `mod tests { … }`) is left out.

use crate::helpers::repo;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The crates' source folders, relative to the repository.
const CRATES: &[&str] =
    &["crates/qsweep-engine/src", "crates/qsweep-pipeline/src", "crates/qsweep-report/src", "src"];

/// The layers of `qsweep-pipeline`, lowest first: a module may import only modules of a strictly
/// lower layer.
const PIPELINE_LAYERS: &[&[&str]] = &[
    &["atomic", "parquet_io", "error"],
    &["analysis", "cache", "declared"],
    &["plan"],
    &["fresh"],
    &["race"],
    &["exec"],
    &["run"],
    // Any program as a trial: its own vertical, on the cache, leases and shards below it.
    &["program"],
    &["bench", "slurm", "status"],
    // Test fixtures (`test-support`), above everything they build.
    &["testing"],
];

/// The layers of `qsweep-report`, lowest first: which files a report writes, the memo of what
/// reports derived (which knows no report part above it), the generic numbers, the generic files,
/// the replication of the paper (built on the generic parts, never imported by them) beside
/// `qsweep compare`'s comparison of two program pipelines (generic too), the stage.
const REPORT_LAYERS: &[&[&str]] =
    &[&["formats"], &["memo"], &["derive"], &["render"], &["replication", "comparison"], &["stage"]];

/// The layers inside the report's `replication`: its statistics, what the generic data holds of
/// the paper, a row judged, Table III and the comparison's numbers, the comparison's pages.
const REPLICATION_LAYERS: &[&[&str]] =
    &[&["stats"], &["published"], &["judgement"], &["table3", "compare"], &["pages"]];

fn layer_in(layers: &[&[&str]], module: &str) -> Option<usize> {
    layers.iter().position(|l| l.contains(&module))
}

/// Every library source file of the crate at `src` by module path (`compare::fit`), with its
/// non-test text.
fn sources(src: &str) -> BTreeMap<String, (String, bool)> {
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let src = repo().join(src);
    let mut files = Vec::new();
    walk(&src, &mut files);
    let mut out = BTreeMap::new();
    for p in files {
        let rel = p.strip_prefix(&src).unwrap().with_extension("");
        let mut parts: Vec<String> = rel.iter().map(|s| s.to_string_lossy().into_owned()).collect();
        let is_dir = parts.last().is_some_and(|l| l == "mod");
        if is_dir {
            parts.pop();
        }
        let module = parts.join("::");
        if module == "lib" || module == "main" || module.ends_with("tests") {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        let code = match text.find("#[cfg(test)]\nmod tests {") {
            Some(i) => &text[..i],
            None => &text[..],
        };
        let code: String = code
            .lines()
            .filter(|l| !l.trim_start().starts_with("//") && !l.contains("#[cfg(test)]"))
            .collect::<Vec<_>>()
            .join("\n");
        out.insert(module, (code, is_dir));
    }
    out
}

/// The paths a file names: every `use` tree expanded, and every inline `crate::`/`super::` path.
fn paths(code: &str) -> Vec<Vec<String>> {
    fn expand(prefix: &str, tree: &str, out: &mut Vec<String>) {
        let tree = tree.trim();
        if let Some(open) = tree.find('{') {
            let pre = &tree[..open];
            let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
            let (mut depth, mut start) = (0, 0);
            for (i, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        expand(&format!("{prefix}{pre}"), &inner[start..i], out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            expand(&format!("{prefix}{pre}"), &inner[start..], out);
        } else if !tree.is_empty() {
            out.push(format!("{prefix}{}", tree.split(" as ").next().unwrap().trim()));
        }
    }
    let mut found = Vec::new();
    // `use` items start a line (after any visibility); a tree may span lines up to its `;`.
    let mut offset = 0;
    for line in code.split_inclusive('\n') {
        let t = line.trim_start();
        let t = t
            .strip_prefix("pub(crate) ")
            .or_else(|| t.strip_prefix("pub(super) "))
            .or_else(|| t.strip_prefix("pub "))
            .unwrap_or(t);
        if let Some(after) = t.strip_prefix("use ") {
            let start = offset + (line.len() - after.len());
            let tail = &code[start..];
            expand("", &tail[..tail.find(';').unwrap_or(tail.len())], &mut found);
        }
        offset += line.len();
    }
    for head in ["crate::", "super::", "self::"] {
        let mut rest = code;
        while let Some(i) = rest.find(head) {
            let ok =
                i == 0 || !rest.as_bytes()[i - 1].is_ascii_alphanumeric() && rest.as_bytes()[i - 1] != b':';
            let tail = &rest[i..];
            let end =
                tail.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(tail.len());
            let path = tail[..end].trim_end_matches(':');
            // `super::{a, b}` is a `use` tree, expanded above; a bare `super` names nothing here.
            if ok && path.contains("::") {
                found.push(path.to_string());
            }
            rest = &tail[end..];
        }
    }
    found.into_iter().map(|p| p.split("::").map(str::to_string).collect()).collect()
}

/// The module files each file of the crate at `src` imports.
fn graph(src: &str) -> BTreeMap<String, BTreeSet<String>> {
    let files = sources(src);
    let resolve = |segs: &[String]| -> Option<String> {
        (1..=segs.len()).rev().map(|n| segs[..n].join("::")).find(|m| files.contains_key(m))
    };
    let mut edges = BTreeMap::new();
    for (module, (code, is_dir)) in &files {
        let _ = is_dir; // `super` and `self` mean the same for `a/b.rs` and `a/b/mod.rs`
        let here: Vec<String> = module.split("::").map(str::to_string).collect();
        let mut targets = BTreeSet::new();
        for p in paths(code) {
            let full: Vec<String> = match p[0].as_str() {
                "crate" => p[1..].to_vec(),
                "self" => [here.clone(), p[1..].to_vec()].concat(),
                "super" => {
                    let mut base = here[..here.len() - 1].to_vec();
                    let mut k = 1;
                    while p.get(k).is_some_and(|s| s == "super") {
                        base.pop();
                        k += 1;
                    }
                    [base, p[k..].to_vec()].concat()
                }
                // A path relative to this module: one of its submodules (a re-export).
                first if files.contains_key(&[here.clone(), vec![first.to_string()]].concat().join("::")) => {
                    [here.clone(), p.clone()].concat()
                }
                _ => continue,
            };
            if let Some(t) = resolve(&full) {
                if &t != module {
                    targets.insert(t);
                }
            }
        }
        edges.insert(module.clone(), targets);
    }
    edges
}

/// The imports of the modules under `root` (`""`: the whole crate) against `layers` of the parts
/// directly under it: a part may import only parts of a strictly lower layer.
fn against_layers(src: &str, root: &str, layers: &[&[&str]]) -> Vec<String> {
    let part_of = |m: &str| -> Option<String> {
        let rest = if root.is_empty() { m } else { m.strip_prefix(root)?.strip_prefix("::")? };
        rest.split("::").next().map(str::to_string)
    };
    let mut wrong = Vec::new();
    for (module, targets) in graph(src) {
        let Some(top) = part_of(&module) else { continue };
        let Some(own) = layer_in(layers, &top) else {
            wrong.push(format!("{module}: `{top}` is in no layer of tests/cli/layering.rs"));
            continue;
        };
        for t in targets {
            let Some(other) = part_of(&t) else { continue };
            if other != top && layer_in(layers, &other).is_none_or(|l| l >= own) {
                wrong.push(format!("{module} imports {t} (layer {:?} ≥ {own})", layer_in(layers, &other)));
            }
        }
    }
    wrong
}

#[test]
fn no_pipeline_module_imports_a_higher_layer() {
    let wrong = against_layers("crates/qsweep-pipeline/src", "", PIPELINE_LAYERS);
    assert!(wrong.is_empty(), "imports against the layers:\n{}", wrong.join("\n"));
}

#[test]
fn no_report_part_imports_a_higher_layer() {
    let wrong = [
        against_layers("crates/qsweep-report/src", "", REPORT_LAYERS),
        against_layers("crates/qsweep-report/src", "replication", REPLICATION_LAYERS),
    ]
    .concat();
    assert!(wrong.is_empty(), "imports against the report's layers:\n{}", wrong.join("\n"));
}

/// The rules above would pass vacuously if a part were missing from the lists or named wrongly:
/// every top-level part of the report and of its replication is in a layer.
#[test]
fn every_report_part_is_in_a_layer() {
    let g = graph("crates/qsweep-report/src");
    for m in g.keys() {
        let top = m.split("::").next().unwrap();
        assert!(layer_in(REPORT_LAYERS, top).is_some(), "{m}: `{top}` is in no report layer");
        if let Some(part) = m.strip_prefix("replication::") {
            let part = part.split("::").next().unwrap();
            assert!(layer_in(REPLICATION_LAYERS, part).is_some(), "{m}: `{part}` is in no replication layer");
        }
    }
}

/// Imports from a module (and its children) into another that must never happen in one crate.
fn forbidden(src: &str, from: &str, to: &str) -> Vec<String> {
    let under = |m: &str, top: &str| m == top || m.starts_with(&format!("{top}::"));
    graph(src)
        .into_iter()
        .filter(|(m, _)| under(m, from))
        .flat_map(|(m, ts)| ts.into_iter().filter(|t| under(t, to)).map(move |t| format!("{m} imports {t}")))
        .collect()
}

#[test]
fn the_generic_report_never_imports_the_replication() {
    let src = "crates/qsweep-report/src";
    let wrong: Vec<String> = ["formats", "memo", "derive", "render", "comparison"]
        .into_iter()
        .flat_map(|generic| forbidden(src, generic, "replication"))
        .collect();
    assert!(wrong.is_empty(), "the generic report works for any pipeline: {wrong:?}");
}

#[test]
fn representations_never_import_the_learner() {
    let wrong = forbidden("crates/qsweep-engine/src", "repr", "learner");
    assert!(
        wrong.is_empty(),
        "the learner reads `Features` (repr/activation.rs), not the reverse: {wrong:?}"
    );
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    for src in CRATES {
        no_cycles(src, &graph(src));
    }
}

/// Files may form no cycle, and neither may the parts they belong to: in every crate, the graph of
/// its top-level modules (a file's imports counted for the part that holds it) has no cycle, so
/// its parts stack in layers with no import running back up.
#[test]
fn no_top_level_part_imports_one_that_imports_it_back() {
    for src in CRATES {
        let mut parts: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (m, targets) in graph(src) {
            let top = m.split("::").next().unwrap().to_string();
            let entry = parts.entry(top.clone()).or_default();
            entry.extend(
                targets.iter().map(|t| t.split("::").next().unwrap().to_string()).filter(|t| *t != top),
            );
        }
        no_cycles(src, &parts);
    }
}

fn no_cycles(src: &str, edges: &BTreeMap<String, BTreeSet<String>>) {
    // Tarjan's strongly connected components: any component of two or more files is a cycle.
    struct S<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        next: usize,
        cycles: Vec<Vec<&'a str>>,
    }
    fn visit<'a>(s: &mut S<'a>, v: &'a str) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on.insert(v);
        for w in s.edges.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on.remove(w);
                comp.push(w);
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                s.cycles.push(comp);
            }
        }
    }
    let mut s = S {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        cycles: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    assert!(s.cycles.is_empty(), "{src}: files that import each other: {:?}", s.cycles);
}

/// The checks above must see real imports: they would pass vacuously on a parser that found none.
#[test]
fn the_import_scan_sees_known_imports() {
    let g = graph("crates/qsweep-pipeline/src");
    assert!(g["race"].contains("analysis"), "{:?}", g["race"]);
    let g = graph("crates/qsweep-report/src");
    assert!(g["stage::steps"].contains("render::folder"), "{:?}", g["stage::steps"]);
    assert!(g["replication::table3"].contains("render::addition"), "{:?}", g["replication::table3"]);
    let g = graph("crates/qsweep-engine/src");
    assert!(g["repr::fuzzy"].contains("repr::activation"), "{:?}", g["repr::fuzzy"]);
    assert!(g["repr"].contains("repr::crisp"), "re-exports count: {:?}", g["repr"]);
    let g = graph("src");
    assert!(g["cli::verify"].contains("cli::pipeline_args"), "{:?}", g["cli::verify"]);
}
