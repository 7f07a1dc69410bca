//! The pruning rule of the trial parts: a full report removes the parts it did not use only when
//! no other report holds the folder.

use super::*;

/// A part file (and its sidecar) in the parts folder of pipeline `p` in `cache`.
fn part(cache: &Path, name: &str) -> PathBuf {
    let dir = cache.join(crate::memo::stats::DERIVED_DIR).join("p.trials");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.parquet"));
    std::fs::write(&path, name).unwrap();
    std::fs::write(sidecar(&path), "b3").unwrap();
    path
}

fn parts(cache: &Path, out: &Path) -> TrialParts {
    TrialParts::new(cache, "p", out, &KeySet::default(), false)
}

#[test]
fn a_full_report_prunes_only_when_no_other_report_holds_the_parts() {
    let (cache, out) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (cache, trials) = (cache.path(), out.path().join("trials.parquet"));
    let old = part(cache, "old");
    // Two reports at once: the first to finish leaves every part, the other may still read it.
    let (a, b) = (parts(cache, out.path()), parts(cache, out.path()));
    assert!(a.kept() && b.kept());
    assert!(!b.finish(&trials, true).unwrap(), "no part used: no file");
    assert!(old.is_file() && sidecar(&old).is_file(), "another report holds the folder: kept");
    // The last one, alone, prunes what it did not use.
    a.finish(&trials, true).unwrap();
    assert!(!old.exists() && !sidecar(&old).exists(), "alone: pruned");
    assert!(old.with_file_name(readers::LOCK_FILE).is_file(), "the lock file is no part");

    // A partial report never prunes, alone or not.
    let old = part(cache, "old");
    parts(cache, out.path()).finish(&trials, false).unwrap();
    assert!(old.is_file());
    // Any hold keeps the parts: a report's, or `qsweep gc`'s while it removes the folder.
    let dir = old.parent().unwrap();
    let reading = readers::Reading::hold(dir);
    assert!(!prune_unused(dir, &[]), "held: left");
    drop(reading);
    assert!(prune_unused(dir, std::slice::from_ref(&old)) && old.is_file(), "a used part stays");
    assert!(prune_unused(dir, &[]) && !old.exists());
}

#[test]
fn a_part_removed_under_a_report_is_named_with_what_to_do() {
    let (cache, out) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let mut p = parts(cache.path(), out.path());
    let gone = p.dir.join("gone.parquet");
    p.used.push(gone.clone());
    let e = p.finish(&out.path().join("trials.parquet"), true).unwrap_err().to_string();
    assert!(e.starts_with(&format!("cannot read {}: ", gone.display())), "{e}");
    assert!(e.contains("the trial part was removed while this report used it") && e.ends_with("anew"), "{e}");
    assert!(!out.path().join("trials.parquet").exists());
}
