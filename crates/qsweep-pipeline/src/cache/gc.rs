//! Housekeeping: compact many small segments into few, dropping duplicate rows and, when asked,
//! rows that no given pipeline references.
//!
//! Safe against crashes and concurrent runs: the compacted segments are written (atomically)
//! before any old segment is removed, and only segments listed at the start are removed, so a
//! crash leaves at worst duplicate rows (dropped on read) and rows written meanwhile are untouched.

use super::key::Key;
use super::record::TrialRecord;
use super::rows::read_segment;
use super::store::Store;
use std::collections::HashSet;

/// Rows per compacted segment.
const ROWS_PER_SEGMENT: usize = 5000;

/// What `gc` did (or would do, for a dry run).
#[derive(Debug, Default, PartialEq)]
pub struct GcReport {
    /// Segments before.
    pub segments_before: usize,
    /// Segments after.
    pub segments_after: usize,
    /// Distinct rows kept.
    pub rows_kept: usize,
    /// Distinct rows removed because no pipeline references them.
    pub rows_removed: usize,
    /// Duplicate rows dropped.
    pub duplicates: usize,
    /// Bytes of segment files before.
    pub bytes_before: u64,
    /// Bytes of segment files after (estimated as unchanged for a dry run).
    pub bytes_after: u64,
    /// Unreadable segments left in place (see `qsweep verify`).
    pub skipped: Vec<String>,
    /// Temp files left by killed writers (older than [`STALE_TEMP`]), removed.
    pub stale_temps: usize,
    /// Leases of dead holders (and their stray temp files) in `_leases/`, removed; live runs'
    /// leases are left alone ([`super::leases::sweep`]).
    pub stale_leases: usize,
}

/// A temp file this old cannot belong to a live writer (writing a segment takes milliseconds).
pub const STALE_TEMP: std::time::Duration = std::time::Duration::from_secs(600);

impl Store {
    /// Compact the cache; keep only keys in `keep` when given. With `dry_run`, change nothing.
    pub fn gc(&self, keep: Option<&HashSet<Key>>, dry_run: bool) -> anyhow::Result<GcReport> {
        let mut report = GcReport::default();
        let mut seen = HashSet::new();
        let mut kept: Vec<TrialRecord> = Vec::new();
        let mut read = Vec::new();
        for path in self.segments()? {
            report.segments_before += 1;
            report.bytes_before += std::fs::metadata(&path)?.len();
            match read_segment(&path, &|_| true) {
                Ok(records) => {
                    for r in records {
                        if !seen.insert(r.key) {
                            report.duplicates += 1;
                        } else if keep.is_none_or(|k| k.contains(&r.key)) {
                            kept.push(r);
                        } else {
                            report.rows_removed += 1;
                        }
                    }
                    read.push(path);
                }
                Err(e) => report.skipped.push(format!("{}: {e:#}", path.display())),
            }
        }
        for entry in std::fs::read_dir(self.dir())? {
            let entry = entry?;
            let stale = entry.metadata()?.modified()?.elapsed().is_ok_and(|age| age > STALE_TEMP);
            if entry.file_name().to_string_lossy().starts_with(crate::atomic::TEMP_PREFIX) && stale {
                report.stale_temps += 1;
                if !dry_run {
                    std::fs::remove_file(entry.path())?;
                }
            }
        }
        report.stale_leases = super::leases::sweep(self, dry_run)?.removed;
        report.rows_kept = kept.len();
        let unreadable = report.segments_before - read.len();
        report.segments_after = kept.len().div_ceil(ROWS_PER_SEGMENT) + unreadable;
        if dry_run {
            report.bytes_after = report.bytes_before;
            return Ok(report);
        }
        let mut written = Vec::new();
        for chunk in kept.chunks(ROWS_PER_SEGMENT) {
            written.push(self.write_segment(chunk)?);
        }
        for path in &read {
            if !written.contains(path) {
                std::fs::remove_file(path)?;
            }
        }
        report.bytes_after =
            self.segments()?.iter().map(|p| std::fs::metadata(p).map_or(0, |m| m.len())).sum();
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsweep_engine::env::SystemKind;
    use qsweep_engine::repr::ReprKind;
    use qsweep_engine::{run_trial, Algorithm, TrialConfig};

    #[test]
    fn compacts_dedupes_and_keeps_exactly_the_referenced_rows() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
        c.limits.max_episodes = 2;
        let recs: Vec<_> = (0..6).map(|s| TrialRecord::new(c.clone(), s, run_trial(&c, s), 0.0)).collect();
        for r in recs.chunks(2) {
            store.write_segment(r).unwrap();
        }
        store.write_segment(&recs[..1]).unwrap();
        let keep: HashSet<_> = recs[..4].iter().map(|r| r.key).collect();
        let dry = store.gc(Some(&keep), true).unwrap();
        assert_eq!((dry.segments_before, dry.rows_kept, dry.rows_removed, dry.duplicates), (4, 4, 2, 1));
        assert_eq!(store.segments().unwrap().len(), 4, "a dry run changes nothing");
        let r = store.gc(Some(&keep), false).unwrap();
        assert_eq!((r.segments_after, r.rows_kept, r.rows_removed), (1, 4, 2));
        assert_eq!(store.segments().unwrap().len(), 1);
        let mut back: Vec<_> = store.read_all().unwrap().into_iter().map(|r| r.key).collect();
        back.sort();
        let mut want: Vec<_> = keep.into_iter().collect();
        want.sort();
        assert_eq!(back, want);
        // Compaction alone keeps everything.
        let r = store.gc(None, false).unwrap();
        assert_eq!((r.rows_kept, r.rows_removed, r.segments_after), (4, 0, 1));
    }
}
