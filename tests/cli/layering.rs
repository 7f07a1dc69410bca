//! The architecture's import rules inside each crate (ARCHITECTURE.md), checked on the source.
//! Between crates the compiler holds the layers (a crate cannot name one that does not depend on
//! it); inside a crate only this test does: every top-level module of `qsweep-pipeline` imports
//! only modules of lower layers, the report's `derive` never imports its `render`, the engine's
//! representations never import the learner, and in no crate does a file import a
//! file that imports it back (directly or through others). Test code (`*tests.rs`,
//! `mod tests { … }`) is left out.

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
    &["bench", "slurm", "status"],
    // Test fixtures (`test-support`), above everything they build.
    &["testing"],
];

fn layer(module: &str) -> Option<usize> {
    PIPELINE_LAYERS.iter().position(|l| l.contains(&module))
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

#[test]
fn no_pipeline_module_imports_a_higher_layer() {
    let mut wrong = Vec::new();
    for (module, targets) in graph("crates/qsweep-pipeline/src") {
        let top = module.split("::").next().unwrap().to_string();
        let Some(own) = layer(&top) else {
            wrong.push(format!("{module}: top-level module `{top}` is in no layer of tests/cli/layering.rs"));
            continue;
        };
        for t in targets {
            let other = t.split("::").next().unwrap();
            if other != top && layer(other).is_none_or(|l| l >= own) {
                wrong.push(format!("{module} imports {t} (layer {:?} ≥ {own})", layer(other)));
            }
        }
    }
    assert!(wrong.is_empty(), "imports against the layers:\n{}", wrong.join("\n"));
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
fn the_report_derives_before_it_renders() {
    let src = "crates/qsweep-report/src";
    let wrong = [
        forbidden(src, "derive", "render"),
        forbidden(src, "derive", "stage"),
        forbidden(src, "render", "stage"),
    ]
    .concat();
    assert!(wrong.is_empty(), "derive < render < stage: {wrong:?}");
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
        no_cycles(src);
    }
}

fn no_cycles(src: &str) {
    let edges = graph(src);
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
        edges: &edges,
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
    let g = graph("crates/qsweep-engine/src");
    assert!(g["repr::fuzzy"].contains("repr::activation"), "{:?}", g["repr::fuzzy"]);
    assert!(g["repr"].contains("repr::crisp"), "re-exports count: {:?}", g["repr"]);
    let g = graph("src");
    assert!(g["cli::verify"].contains("cli::pipeline_args"), "{:?}", g["cli::verify"]);
}
