//! Every crate has a README, and its Rust example is code that runs: the engine's README is the
//! engine crate's documentation, so `cargo test -p qsweep-engine` runs its example as a doctest;
//! the other crates' examples are excerpts of `examples/*.rs`, which `cargo build --examples`
//! compiles and `tests/cli/library.rs` runs the way `examples/library_run.rs` does, so each of
//! their Rust blocks must appear in an example file line for line.

use crate::markdown::{crate_readmes, fences, repo, Doc};

#[test]
fn every_crate_has_a_readme_whose_rust_blocks_are_examples_code() {
    let examples: Vec<String> = std::fs::read_dir(repo().join("examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    let readmes = crate_readmes();
    assert!(readmes.len() >= 3, "{readmes:?}");
    for path in readmes {
        let doc = Doc::read(&path);
        let rust: Vec<_> = fences(&doc.text).into_iter().filter(|f| f.info == "rust").collect();
        assert!(!rust.is_empty(), "{}: a crate README shows one example", path.display());
        if path.starts_with("crates/qsweep-engine") {
            let lib = std::fs::read_to_string(repo().join("crates/qsweep-engine/src/lib.rs")).unwrap();
            assert!(lib.contains("include_str!(\"../README.md\")"), "the engine's README is its doctest");
            continue;
        }
        for f in rust {
            let block = f.lines.join("\n");
            assert!(
                examples.iter().any(|e| e.contains(&block)),
                "{}:{}: this Rust block is not an excerpt of examples/*.rs:\n{block}",
                path.display(),
                f.first_line
            );
        }
    }
}
