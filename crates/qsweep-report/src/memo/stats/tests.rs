//! Tests of the statistics' memo: reuse, what makes another entry, damaged files, gc and
//! pruning.

use super::*;

fn values() -> Vec<f64> {
    vec![3.0, 7.0, 7.0, 12.0, 40.0]
}

#[test]
fn memoized_intervals_equal_computed_ones_and_are_reused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.bin");
    let m = StatsMemo::fresh(7);
    let ci = m.bootstrap_ci(&values(), 2000, 11);
    assert_eq!(ci, qsweep_pipeline::analysis::bootstrap_ci(&values(), 2000, 11));
    let d = m.bootstrap_diff_ci(&values(), &[1.0, 2.0], 2000, 5);
    assert_eq!(d, qsweep_pipeline::analysis::bootstrap_diff_ci(&values(), &[1.0, 2.0], 2000, 5));
    assert_eq!(m.counts(), MemoCounts { computed: 2, reused: 0 });
    assert!(m.save(&path, true).unwrap());
    assert!(!m.save(&path, true).unwrap(), "the same entries are the same bytes: not rewritten");

    let again = StatsMemo::load(&path, 7, true);
    assert!(again.has_ci(&values(), 2000, 11) && !again.has_ci(&values(), 2000, 12));
    assert!(!StatsMemo::load(&path, 7, false).has_ci(&values(), 2000, 11), "--rebuild reuses nothing");
    assert_eq!(again.bootstrap_ci(&values(), 2000, 11), ci);
    assert_eq!(again.bootstrap_diff_ci(&values(), &[1.0, 2.0], 2000, 5), d);
    assert_eq!(again.counts(), MemoCounts { computed: 0, reused: 2 });
    // Another seed, another resample count or one value changed: another entry.
    again.bootstrap_ci(&values(), 2000, 12);
    again.bootstrap_ci(&values(), 1999, 11);
    let mut v = values();
    v[4] = f64::from_bits(40f64.to_bits() + 1);
    again.bootstrap_ci(&v, 2000, 11);
    assert_eq!(again.counts(), MemoCounts { computed: 3, reused: 2 });
}

#[test]
fn another_version_a_damaged_or_a_truncated_file_is_read_as_empty() {
    let cache = tempfile::tempdir().unwrap();
    let path = StatsMemo::path(cache.path(), "p");
    let m = StatsMemo::fresh(7);
    m.bootstrap_ci(&values(), 100, 1);
    m.save(&path, true).unwrap();
    assert_eq!(StatsMemo::load(&path, 7, true).kept.len(), 1);
    assert_eq!((check(cache.path()).intact, check(cache.path()).entries), (1, 1));
    assert_eq!(StatsMemo::load(&path, 8, true).kept.len(), 0, "other definitions");
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[30] ^= 1;
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(StatsMemo::load(&path, 7, true).kept.len(), 0, "checksum");
    assert_eq!((check(cache.path()).intact, check(cache.path()).damaged.len()), (0, 1));
    std::fs::write(&path, &bytes[..20]).unwrap();
    assert_eq!(StatsMemo::load(&path, 7, true).kept.len(), 0, "truncated");
    assert_eq!(StatsMemo::load(&cache.path().join("none.bin"), 7, true).kept.len(), 0, "missing");
    // gc drops the damaged file, and a pipeline's file no given pipeline names.
    assert_eq!(gc(cache.path(), None, 7, true).unwrap().removed, 1);
    assert!(path.is_file(), "a dry run removes nothing");
    assert_eq!(gc(cache.path(), None, 7, false).unwrap().removed, 1);
    assert!(!path.is_file());
    m.save(&path, true).unwrap();
    let keep: std::collections::HashSet<String> = ["p".to_string()].into();
    assert_eq!(gc(cache.path(), Some(&keep), 7, false).unwrap().removed, 0);
    assert_eq!(gc(cache.path(), Some(&["q".to_string()].into()), 7, false).unwrap().removed, 1);
}

#[test]
fn gc_leaves_the_parts_a_report_is_reading() {
    let cache = tempfile::tempdir().unwrap();
    let parts = cache.path().join(DERIVED_DIR).join("q.trials");
    std::fs::create_dir_all(&parts).unwrap();
    std::fs::write(parts.join("a.parquet"), "part").unwrap();
    let keep: std::collections::HashSet<String> = ["p".to_string()].into();
    let reading = readers::Reading::hold(&parts);
    for dry_run in [true, false] {
        let r = gc(cache.path(), Some(&keep), 7, dry_run).unwrap();
        assert_eq!(r, StatsGc { removed: 0, in_use: vec![parts.clone()] });
        assert!(parts.join("a.parquet").is_file());
    }
    drop(reading);
    let lock = parts.join(readers::LOCK_FILE);
    std::fs::remove_file(&lock).unwrap();
    assert_eq!(gc(cache.path(), Some(&keep), 7, true).unwrap().removed, 1);
    assert!(parts.join("a.parquet").is_file() && !lock.exists(), "a dry run makes and removes nothing");
    assert_eq!(gc(cache.path(), Some(&keep), 7, false).unwrap(), StatsGc { removed: 1, in_use: vec![] });
    assert!(!parts.exists());
}

#[test]
fn a_full_report_prunes_what_it_did_not_use_a_partial_one_adds() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.bin");
    let m = StatsMemo::fresh(1);
    m.bootstrap_ci(&values(), 100, 1);
    m.bootstrap_ci(&values(), 100, 2);
    m.save(&path, true).unwrap();
    let partial = StatsMemo::load(&path, 1, true);
    partial.bootstrap_ci(&values(), 100, 3);
    partial.save(&path, false).unwrap();
    assert_eq!(StatsMemo::load(&path, 1, true).kept.len(), 3);
    let full = StatsMemo::load(&path, 1, true);
    full.bootstrap_ci(&values(), 100, 3);
    full.save(&path, true).unwrap();
    assert_eq!(StatsMemo::load(&path, 1, true).kept.len(), 1);
    // Without reuse (--rebuild) a kept entry is computed again, and still kept by a partial
    // report.
    let rebuild = StatsMemo::load(&path, 1, false);
    rebuild.bootstrap_ci(&values(), 100, 4);
    rebuild.bootstrap_ci(&values(), 100, 3);
    assert_eq!(rebuild.counts(), MemoCounts { computed: 2, reused: 0 });
    rebuild.save(&path, false).unwrap();
    assert_eq!(StatsMemo::load(&path, 1, true).kept.len(), 2);
}
