//! Housekeeping: compact many small segments into few, dropping duplicate rows and, when asked,
//! rows that no given pipeline references.
//!
//! Safe against crashes, live runs and readers:
//! - the compacted segments are written (atomically) before any old segment is removed, and only
//!   segments listed at the start are removed, so a crash leaves at worst duplicate rows (dropped
//!   on read) and rows stored after gc started are untouched;
//! - the segments of a run that is still alive are left exactly as they are, neither compacted
//!   nor pruned, whatever pipelines gc was given: a run names its segments after its mark in
//!   `_runs/`, which gc judges after listing the segments ([`super::leases::runs`]), so a row a
//!   live run stored is never removed (`N rows kept: written by a live run`), and the run's
//!   segments are compacted by a later gc;
//! - a reader that listed a segment gc removes lists the segments again and reads what replaced it
//!   ([`super::store`]); a gc with nothing to change (no row to drop, its segments already few and
//!   in the current layout) rewrites nothing, so gcs run in a loop do not make readers read again.
//!
//! A dry run reports the same, changing nothing. The rules need nothing but listing, reading,
//! writing whole files and removing them, so a bucket store keeps them as they are.

use super::key::Key;
use super::leases::runs;
use super::record::TrialRecord;
use super::rows::{in_current_layout, read_keys, read_segment};
use super::store::{writer_of, Store};
use std::collections::HashSet;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};

/// Rows per compacted segment.
const ROWS_PER_SEGMENT: usize = 5000;

/// What `gc` did (or would do, for a dry run).
#[derive(Debug, Default, PartialEq)]
pub struct GcReport {
    /// Segments before.
    pub segments_before: usize,
    /// Segments after.
    pub segments_after: usize,
    /// Distinct rows kept in the compacted segments (those of live runs apart: [`Self::rows_live`]).
    pub rows_kept: usize,
    /// Distinct rows removed because no pipeline references them.
    pub rows_removed: usize,
    /// Distinct rows in the segments of runs still alive, left as they are (neither compacted nor
    /// removed, referenced or not).
    pub rows_live: usize,
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
    /// Leases and run marks of dead holders (and their stray temp files) in `_leases/` and
    /// `_runs/`, removed; live runs' are left alone ([`super::leases::sweep`], [`runs::sweep`]).
    pub stale_leases: usize,
}

/// A temp file this old cannot belong to a live writer (writing a segment takes milliseconds).
pub const STALE_TEMP: std::time::Duration = std::time::Duration::from_secs(600);

/// The rows gc keeps of the segments it may rewrite, and those segments.
#[derive(Default)]
struct Compacted {
    kept: Vec<TrialRecord>,
    read: Vec<PathBuf>,
}

impl Store {
    /// Compact the cache; keep only keys in `keep` when given (and every row of a live run). With
    /// `dry_run`, change nothing.
    pub fn gc(&self, keep: Option<&HashSet<Key>>, dry_run: bool) -> anyhow::Result<GcReport> {
        let mut report = GcReport::default();
        let listed = self.segments()?;
        // Judged after the listing: a run that wrote a listed segment had begun before it.
        let live = runs::live(self)?;
        let (theirs, ours): (Vec<PathBuf>, Vec<PathBuf>) =
            listed.into_iter().partition(|p| writer_of(p).is_some_and(|w| live.contains(w)));
        let mut seen = HashSet::new();
        let live_segments = tally_live(&theirs, &mut seen, &mut report)?;
        let Compacted { kept, read } = gather(&ours, keep, &mut seen, &mut report)?;
        report.stale_temps = self.sweep_temps(dry_run)?;
        report.stale_leases =
            super::leases::sweep(self, dry_run)?.removed + runs::sweep(self, dry_run)?.removed;
        report.rows_kept = kept.len();
        let compact = kept.len().div_ceil(ROWS_PER_SEGMENT);
        // Rewriting what would come out the same only makes readers list again.
        let rewrite = report.rows_removed + report.duplicates > 0
            || read.len() > compact
            || !read.iter().all(|p| in_current_layout(p));
        report.segments_after =
            if rewrite { compact } else { read.len() } + live_segments + report.skipped.len();
        if dry_run {
            report.bytes_after = report.bytes_before;
            return Ok(report);
        }
        if rewrite {
            let mut written = Vec::new();
            for chunk in kept.chunks(ROWS_PER_SEGMENT) {
                written.push(self.write_segment(chunk)?);
            }
            for path in read.iter().filter(|p| !written.contains(p)) {
                // Another gc removed it first: its rows are in that gc's segments.
                self.remove_segment(path)?;
            }
        }
        let now = self.segments()?;
        report.bytes_after = now.iter().map(|p| std::fs::metadata(p).map_or(0, |m| m.len())).sum();
        self.prune_copies(&now)?;
        Ok(report)
    }

    /// In a bucket cache's copy, remove the copies of segments the bucket no longer lists
    /// (compacted by this gc or another machine's): older than [`STALE_TEMP`], so a copy a run of
    /// this machine has just written, of a segment uploaded since the listing, stays.
    fn prune_copies(&self, listed: &[PathBuf]) -> anyhow::Result<()> {
        if self.remote().is_none() {
            return Ok(());
        }
        let listed: HashSet<&PathBuf> = listed.iter().collect();
        for entry in std::fs::read_dir(self.dir())? {
            let path = entry?.path();
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            let segment = name.starts_with(super::store::SEGMENT_PREFIX) && name.ends_with(".parquet");
            let old = || {
                std::fs::metadata(&path)
                    .and_then(|m| m.modified())
                    .is_ok_and(|t| t.elapsed().is_ok_and(|a| a > STALE_TEMP))
            };
            if segment && !listed.contains(&path) && old() {
                let _ = std::fs::remove_file(&path);
            }
        }
        Ok(())
    }

    /// Remove (or, with `dry_run`, count) temp files left by killed writers.
    pub(crate) fn sweep_temps(&self, dry_run: bool) -> anyhow::Result<usize> {
        let mut n = 0;
        for entry in std::fs::read_dir(self.dir())? {
            let entry = entry?;
            let stale = entry.metadata()?.modified()?.elapsed().is_ok_and(|age| age > STALE_TEMP);
            if entry.file_name().to_string_lossy().starts_with(crate::atomic::TEMP_PREFIX) && stale {
                n += 1;
                if !dry_run {
                    std::fs::remove_file(entry.path())?;
                }
            }
        }
        Ok(n)
    }
}

/// A listed segment's size, `None` when it is gone (another gc removed it since the listing).
fn size(path: &Path) -> std::io::Result<Option<u64>> {
    match std::fs::metadata(path) {
        Ok(m) => Ok(Some(m.len())),
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

/// Count the segments of live runs, left as they are: their distinct rows into `seen` first (so
/// a copy of one elsewhere is a duplicate). Returns how many of them are readable.
fn tally_live(paths: &[PathBuf], seen: &mut HashSet<Key>, report: &mut GcReport) -> std::io::Result<usize> {
    let mut readable = 0;
    for path in paths {
        let Some(bytes) = size(path)? else { continue };
        match read_keys(path) {
            Ok(keys) => {
                readable += 1;
                report.rows_live += keys.into_iter().filter(|k| seen.insert(*k)).count();
            }
            Err(_) if size(path)?.is_none() => continue,
            Err(e) => report.skipped.push(format!("{}: {e:#}", path.display())),
        }
        report.segments_before += 1;
        report.bytes_before += bytes;
    }
    Ok(readable)
}

/// Read the segments gc may rewrite: the rows to keep (first of each key, in `keep` when given),
/// the duplicates and unreferenced rows counted.
fn gather(
    paths: &[PathBuf],
    keep: Option<&HashSet<Key>>,
    seen: &mut HashSet<Key>,
    report: &mut GcReport,
) -> std::io::Result<Compacted> {
    let mut out = Compacted::default();
    for path in paths {
        let Some(bytes) = size(path)? else { continue };
        match read_segment(path, &|_| true) {
            Ok(records) => {
                for r in records {
                    if !seen.insert(r.key) {
                        report.duplicates += 1;
                    } else if keep.is_none_or(|k| k.contains(&r.key)) {
                        out.kept.push(r);
                    } else {
                        report.rows_removed += 1;
                    }
                }
                out.read.push(path.clone());
            }
            Err(_) if size(path)?.is_none() => continue,
            Err(e) => report.skipped.push(format!("{}: {e:#}", path.display())),
        }
        report.segments_before += 1;
        report.bytes_before += bytes;
    }
    Ok(out)
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
        // Compaction alone keeps everything; with nothing to change, it rewrites nothing.
        let before = store.segments().unwrap();
        let r = store.gc(None, false).unwrap();
        assert_eq!((r.rows_kept, r.rows_removed, r.segments_after), (4, 0, 1));
        assert_eq!(store.segments().unwrap(), before, "the segment stays, so no reader lists again");
    }

    /// Regression (issue 64): `gc PIPELINES` removed the rows a live run of another plan had just
    /// stored. A live run's segments stay as they are, whatever gc is given; once the run is over,
    /// they are ordinary segments.
    #[test]
    fn a_live_runs_segments_stay_as_they_are_and_are_collected_once_it_is_over() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
        c.limits.max_episodes = 2;
        let recs: Vec<_> = (0..6).map(|s| TrialRecord::new(c.clone(), s, run_trial(&c, s), 0.0)).collect();
        store.write_segment(&recs[..2]).unwrap();
        store.write_segment(&recs[2..3]).unwrap();
        let mark = runs::RunMark::register(&store).unwrap();
        let run = store.clone().writing_as(mark.name());
        let theirs = [run.write_segment(&recs[3..5]).unwrap(), run.write_segment(&recs[5..]).unwrap()];
        assert_eq!(theirs.iter().map(|p| writer_of(p)).collect::<Vec<_>>(), [Some(mark.name()); 2]);
        // A copy of one of its rows elsewhere is the duplicate.
        store.write_segment(&recs[4..5]).unwrap();
        let keep: HashSet<_> = recs[..2].iter().map(|r| r.key).collect();
        let dry = store.gc(Some(&keep), true).unwrap();
        let r = store.gc(Some(&keep), false).unwrap();
        assert_eq!(dry.bytes_after, dry.bytes_before);
        assert_eq!((dry.rows_kept, dry.rows_removed, dry.rows_live, dry.duplicates), (2, 1, 3, 1));
        assert_eq!((r.segments_before, r.segments_after), (dry.segments_before, dry.segments_after));
        assert_eq!(
            (r.segments_before, r.segments_after, r.rows_kept, r.rows_removed, r.rows_live),
            (5, 3, 2, 1, 3)
        );
        assert!(theirs.iter().all(|p| p.exists()), "left exactly as they were");
        let stored = |s: &Store| s.keys().unwrap().keys;
        assert_eq!(stored(&store), recs.iter().filter(|r| r.seed != 2).map(|r| r.key).collect());
        drop(mark);
        let r = store.gc(Some(&keep), false).unwrap();
        assert_eq!((r.segments_after, r.rows_kept, r.rows_removed, r.rows_live), (1, 2, 3, 0));
        assert_eq!(stored(&store), keep);
    }

    /// A reader that listed the segments before gc replaced them reads the same rows after.
    #[test]
    fn a_scan_taken_before_gc_compacts_reads_the_same_outcomes_after() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Fuzzy, Algorithm::Q0, vec![2, 2], 3);
        c.limits.max_episodes = 3;
        let recs: Vec<_> = (0..6).map(|s| TrialRecord::new(c.clone(), s, run_trial(&c, s), 0.1)).collect();
        for r in recs.chunks(2) {
            store.write_segment(r).unwrap();
        }
        let scan = store.keys().unwrap();
        let wanted: HashSet<Key> = recs[1..5].iter().map(|r| r.key).collect();
        let before = store.read_outcomes(&scan, &wanted, true).unwrap();
        assert_eq!(store.gc(None, false).unwrap().segments_after, 1);
        assert!(scan.segments.iter().all(|(p, _)| !p.exists()), "every listed segment was replaced");
        assert_eq!(store.read_outcomes(&scan, &wanted, true).unwrap(), before);
        // Rows gc removed (given other pipelines) cannot be read: a clear error, not a short read.
        let scan = store.keys().unwrap();
        let keep: HashSet<Key> = recs[..2].iter().map(|r| r.key).collect();
        store.gc(Some(&keep), false).unwrap();
        let e = store.read_outcomes(&scan, &wanted, false).unwrap_err();
        assert!(format!("{e:#}").contains("3 trials read from the cache"), "{e:#}");
    }
}
