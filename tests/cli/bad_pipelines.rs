//! The corpus in `tests/bad_pipelines/`: every malformed pipeline exits 2 with a message naming the
//! file (and, for anything inside the file, the line), never panics, and writes nothing.
//! Each file's first line says what the message must contain: `# expect: TEXT`.

use crate::helpers::{repo, Sandbox};

#[test]
fn every_bad_pipeline_is_a_clean_usage_error_that_writes_nothing() {
    let dir = repo().join("tests/bad_pipelines");
    let mut entries: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    assert!(entries.len() >= 30, "the corpus has {} entries", entries.len());
    let sb = Sandbox::new();
    let mut with_line = 0;
    for path in &entries {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let expect = if path.is_file() {
            let first = String::from_utf8_lossy(&std::fs::read(path).unwrap())
                .lines()
                .next()
                .unwrap_or("")
                .to_string();
            first.strip_prefix("# expect:").map(|s| s.trim().to_string()).unwrap_or_default()
        } else {
            "is a directory".to_string()
        };
        // An expectation that every message meets (empty, or just `:`) tests nothing.
        assert!(
            expect.chars().filter(|c| c.is_alphanumeric()).count() >= 4,
            "{name}: `# expect:` must name a real part of the message, not {expect:?}"
        );
        let out = sb
            .qsweep(&["run", path.to_str().unwrap()])
            .timeout(std::time::Duration::from_secs(30))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(&name), "{name}: the message must name the file: {err}");
        assert!(err.contains(&expect), "{name}: wanted {expect:?} in: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        with_line += usize::from(
            err.contains(&format!("{name}:")) && {
                let after = &err[err.find(&format!("{name}:")).unwrap() + name.len() + 1..];
                after.starts_with(|c: char| c.is_ascii_digit())
            },
        );
    }
    assert!(with_line + 6 >= entries.len(), "only {with_line} of {} messages name a line", entries.len());
    assert_eq!(sb.segments(), 0, "nothing was written to the cache");
}
