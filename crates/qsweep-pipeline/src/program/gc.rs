//! Housekeeping of the program folders (`qsweep gc`): each `<cache>/_programs/<schema-id>/`
//! compacted on its own (its segments merged into few, a key stored more than once kept once, by
//! [`super::stored`]'s rule: a row that succeeded over a failed one, then the newest segment's),
//! so rows of two schemas are never mixed; and, when program pipelines are given, pruned to the
//! keys they reference. A folder is pruned only by the program pipelines whose schema it holds:
//! one no given program pipeline maps to is left alone, and engine pipelines never prune program
//! rows. The folder's schema is read back from its segments' own columns
//! ([`super::folders::schema_of`]), so no pipeline is needed to compact it.
//!
//! The engine's gc rules hold unchanged ([`crate::cache::gc`]): compacted segments are written
//! before any old one is removed, only segments listed at the start are removed, the segments of
//! a live run's mark (each folder has its own `_runs/` and `_leases/`) are left exactly as they
//! are, and a gc with nothing to change rewrites nothing.

use super::folders::{list, schema_of, Folder};
use super::model::ProgramRow;
use super::rows::{read_segment, write_segment, RowSchema};
use crate::cache::leases::runs;
use crate::cache::store::writer_of;
use crate::cache::Key;
use std::collections::{HashMap, HashSet};
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// Rows per compacted segment.
const ROWS_PER_SEGMENT: usize = 5000;

/// What [`gc`] did to the program folders (or would do, for a dry run).
#[derive(Debug, Default, PartialEq)]
pub struct ProgramGcReport {
    /// Folders compacted (and pruned, when pipelines were given).
    pub folders: usize,
    /// Folders left alone: no given program pipeline has their schema.
    pub left_alone: Vec<String>,
    /// Segments before, in the folders compacted.
    pub segments_before: usize,
    /// Segments after.
    pub segments_after: usize,
    /// Distinct rows kept in the compacted segments.
    pub rows_kept: usize,
    /// Distinct rows removed because no given program pipeline references them.
    pub rows_removed: usize,
    /// Distinct rows in the segments of live runs, left as they are.
    pub rows_live: usize,
    /// Rows dropped because another row of their key wins.
    pub duplicates: usize,
    /// Bytes of segment files before.
    pub bytes_before: u64,
    /// Bytes after (unchanged for a dry run).
    pub bytes_after: u64,
    /// Segments left in place because they cannot be read as their folder's rows.
    pub skipped: Vec<String>,
    /// Temp files of killed writers removed.
    pub stale_temps: usize,
    /// Leases and run marks of dead holders removed.
    pub stale_leases: usize,
}

/// Compact every program folder of the cache at `cache`; with `keep` (schema id → the keys the
/// given program pipelines of that schema reference), prune the folders it names to those keys
/// and leave the others alone. With `dry_run`, change nothing.
pub fn gc(
    cache: &Path,
    keep: Option<&HashMap<String, HashSet<Key>>>,
    dry_run: bool,
) -> anyhow::Result<ProgramGcReport> {
    let mut report = ProgramGcReport::default();
    for folder in list(cache)? {
        let keep_here = match keep {
            None => None,
            Some(by_schema) => match by_schema.get(&folder.id) {
                Some(keys) => Some(keys),
                None => {
                    report.left_alone.push(folder.id);
                    continue;
                }
            },
        };
        report.folders += 1;
        gc_folder(&folder, keep_here, dry_run, &mut report)?;
    }
    Ok(report)
}

/// A row's rank by [`super::stored`]'s rule: succeeded first, then the newest segment.
type Rank = (bool, SystemTime);

/// The rows gc read from one folder's segments it may rewrite.
#[derive(Default)]
struct Gathered {
    /// The schema of the folder's rows, once one segment was read.
    schema: Option<RowSchema>,
    /// Each key's winning row so far, with its rank and the order it was first seen in.
    best: HashMap<Key, (Rank, usize, ProgramRow)>,
    /// Rows read.
    rows: usize,
    /// The segments read (removed once the compacted ones are written).
    read: Vec<PathBuf>,
}

/// Compact (and with `keep`, prune) one folder, adding to `report`.
fn gc_folder(
    folder: &Folder,
    keep: Option<&HashSet<Key>>,
    dry_run: bool,
    report: &mut ProgramGcReport,
) -> anyhow::Result<()> {
    let store = folder.store()?;
    let listed = store.segments()?;
    // Judged after the listing: a run that wrote a listed segment had begun before it.
    let live = runs::live(&store)?;
    let (theirs, ours): (Vec<PathBuf>, Vec<PathBuf>) =
        listed.into_iter().partition(|p| writer_of(p).is_some_and(|w| live.contains(w)));
    let (bytes_start, skipped_start) = (report.bytes_before, report.skipped.len());
    let mut g = Gathered::default();
    let (live_best, live_segments) = tally_live(&theirs, &folder.id, &mut g.schema, report)?;
    report.rows_live += live_best.len();
    gather(&ours, &folder.id, &mut g, report)?;
    let mut duplicates = g.rows - g.best.len();
    let mut removed = 0;
    let mut kept: Vec<(usize, ProgramRow)> = Vec::new();
    for (key, (rank, order, row)) in g.best {
        if keep.is_some_and(|k| !k.contains(&key)) {
            removed += 1;
        } else if live_best.get(&key).is_some_and(|live| *live >= rank) {
            // A live run's row of this key wins: this one is never served.
            duplicates += 1;
        } else {
            kept.push((order, row));
        }
    }
    kept.sort_by_key(|(order, _)| *order);
    let kept: Vec<ProgramRow> = kept.into_iter().map(|(_, r)| r).collect();
    report.duplicates += duplicates;
    report.rows_removed += removed;
    report.rows_kept += kept.len();
    let compact = kept.len().div_ceil(ROWS_PER_SEGMENT);
    // Rewriting what would come out the same only makes readers list again.
    let rewrite = removed + duplicates > 0 || g.read.len() > compact;
    let skipped = report.skipped.len() - skipped_start;
    report.segments_after += if rewrite { compact } else { g.read.len() } + live_segments + skipped;
    report.stale_temps += store.sweep_temps(dry_run)?;
    report.stale_leases +=
        crate::cache::leases::sweep(&store, dry_run)?.removed + runs::sweep(&store, dry_run)?.removed;
    let bytes =
        |paths: &[PathBuf]| paths.iter().map(|p| std::fs::metadata(p).map_or(0, |m| m.len())).sum::<u64>();
    if dry_run {
        report.bytes_after += report.bytes_before - bytes_start;
        return Ok(());
    }
    if rewrite {
        let mut written = Vec::new();
        if let Some(schema) = &g.schema {
            for chunk in kept.chunks(ROWS_PER_SEGMENT) {
                written.push(write_segment(&store, schema, chunk)?);
            }
        }
        for path in g.read.iter().filter(|p| !written.contains(p)) {
            match std::fs::remove_file(path) {
                // Another gc removed it first: its rows are in that gc's segments.
                Err(e) if e.kind() == ErrorKind::NotFound => {}
                r => r.map_err(|e| anyhow::anyhow!("cannot remove {}: {e}", path.display()))?,
            }
        }
    }
    report.bytes_after += bytes(&store.segments()?);
    Ok(())
}

/// Count the segments of live runs, left as they are: each key's best rank among their rows, and
/// how many of them are readable.
fn tally_live(
    paths: &[PathBuf],
    id: &str,
    schema: &mut Option<RowSchema>,
    report: &mut ProgramGcReport,
) -> anyhow::Result<(HashMap<Key, Rank>, usize)> {
    let mut best: HashMap<Key, Rank> = HashMap::new();
    let mut readable = 0;
    for path in paths {
        let Some((bytes, written)) = size(path)? else { continue };
        match read_rows(path, id, schema) {
            Ok(rows) => {
                readable += 1;
                for r in rows {
                    let rank = (r.result.is_ok(), written);
                    let e = best.entry(r.key).or_insert(rank);
                    *e = (*e).max(rank);
                }
            }
            Err(_) if size(path)?.is_none() => continue,
            Err(e) => report.skipped.push(format!("{}: {e:#}", path.display())),
        }
        report.segments_before += 1;
        report.bytes_before += bytes;
    }
    Ok((best, readable))
}

/// Read the segments gc may rewrite into `g`: each key's winning row.
fn gather(paths: &[PathBuf], id: &str, g: &mut Gathered, report: &mut ProgramGcReport) -> anyhow::Result<()> {
    for path in paths {
        let Some((bytes, written)) = size(path)? else { continue };
        match read_rows(path, id, &mut g.schema) {
            Ok(rows) => {
                for r in rows {
                    g.rows += 1;
                    let rank = (r.result.is_ok(), written);
                    let order = g.best.len();
                    match g.best.get(&r.key) {
                        Some((at, _, _)) if *at >= rank => {}
                        Some((_, first, _)) => {
                            let first = *first;
                            g.best.insert(r.key, (rank, first, r));
                        }
                        None => {
                            g.best.insert(r.key, (rank, order, r));
                        }
                    }
                }
                g.read.push(path.clone());
            }
            Err(_) if size(path)?.is_none() => continue,
            Err(e) => report.skipped.push(format!("{}: {e:#}", path.display())),
        }
        report.segments_before += 1;
        report.bytes_before += bytes;
    }
    Ok(())
}

/// The rows of the segment at `path` in the folder of schema `id`; the folder's schema is that
/// of its first segment read (`schema`), and a segment of another schema is an error (it stays).
fn read_rows(path: &Path, id: &str, schema: &mut Option<RowSchema>) -> anyhow::Result<Vec<ProgramRow>> {
    let found = schema_of(path)?;
    anyhow::ensure!(
        found.id() == id,
        "rows of schema {}, not of its folder's ({id}): left in place",
        found.id()
    );
    let rows = read_segment(path, &found, &|_| true)?;
    schema.get_or_insert(found);
    Ok(rows)
}

/// A listed segment's size and modification time, `None` when it is gone.
fn size(path: &Path) -> std::io::Result<Option<(u64, SystemTime)>> {
    match std::fs::metadata(path) {
        Ok(m) => Ok(Some((m.len(), m.modified().unwrap_or(SystemTime::UNIX_EPOCH)))),
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::store::Store;
    use crate::program::model::{Failure, MetricType, MetricValue, ParamType, ParamValue};
    use crate::program::rows::folder;
    use crate::program::stored::rows;

    fn schema() -> RowSchema {
        RowSchema { params: vec![("x".into(), ParamType::Int)], metrics: vec![("y".into(), MetricType::Int)] }
    }

    fn key(i: u64) -> Key {
        Key(*blake3::hash(&i.to_le_bytes()).as_bytes())
    }

    fn row(i: u64, y: Option<i64>) -> ProgramRow {
        ProgramRow {
            key: key(i),
            seed: i,
            params: vec![ParamValue::Int(i as i64)],
            result: match y {
                Some(y) => Ok(vec![MetricValue::Int(y)]),
                None => {
                    Err(Failure { exit_code: Some(1), reason: "exit 1".into(), stderr_tail: String::new() })
                }
            },
            seconds: 0.0,
            cpu_seconds: None,
            command_json: "[]".into(),
            inputs_json: "{}".into(),
            provenance_json: "[]".into(),
        }
    }

    /// A segment of `rows`, written `age` seconds ago (its time orders it under the store's rule).
    fn segment(store: &Store, rows: &[ProgramRow], age: u64) -> PathBuf {
        let path = write_segment(store, &schema(), rows).unwrap();
        let at = SystemTime::now() - std::time::Duration::from_secs(age);
        std::fs::File::options().write(true).open(&path).unwrap().set_modified(at).unwrap();
        path
    }

    /// What the cache serves of every key of the folder.
    fn served(store: &Store) -> HashMap<Key, ProgramRow> {
        let all: HashSet<Key> = (0..10).map(key).collect();
        rows(&store.keys().unwrap(), &schema(), &all).unwrap()
    }

    #[test]
    fn compaction_keeps_the_row_the_cache_serves_and_prunes_only_the_folders_given() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(&folder(dir.path(), &schema())).unwrap();
        segment(&store, &[row(1, None), row(2, Some(1))], 30);
        segment(&store, &[row(1, Some(5)), row(2, Some(2)), row(3, Some(3))], 20);
        segment(&store, &[row(1, None)], 10);
        let before = served(&store);
        assert_eq!(before[&key(1)].result, Ok(vec![MetricValue::Int(5)]), "ok over failed");
        assert_eq!(before[&key(2)].result, Ok(vec![MetricValue::Int(2)]), "then the newest");
        let dry = gc(dir.path(), None, true).unwrap();
        assert_eq!((dry.segments_before, dry.segments_after, dry.rows_kept, dry.duplicates), (3, 1, 3, 3));
        assert_eq!(store.segments().unwrap().len(), 3, "a dry run changes nothing");
        let r = gc(dir.path(), None, false).unwrap();
        assert_eq!((r.folders, r.segments_after, r.rows_kept, r.duplicates, r.rows_removed), (1, 1, 3, 3, 0));
        assert_eq!(served(&store), before);
        // Nothing to change: nothing rewritten.
        let one = store.segments().unwrap();
        assert_eq!(gc(dir.path(), None, false).unwrap().duplicates, 0);
        assert_eq!(store.segments().unwrap(), one);
        // A folder no given program pipeline maps to is left alone.
        let others = HashMap::from([("0123456789abcdef".to_string(), HashSet::new())]);
        let r = gc(dir.path(), Some(&others), false).unwrap();
        assert_eq!((r.folders, r.left_alone.clone()), (0, vec![schema().id()]));
        assert_eq!(served(&store).len(), 3);
        // The pipelines of its schema prune it to their keys.
        let mine = HashMap::from([(schema().id(), HashSet::from([key(1), key(3)]))]);
        let r = gc(dir.path(), Some(&mine), false).unwrap();
        assert_eq!((r.rows_kept, r.rows_removed), (2, 1));
        assert_eq!(served(&store).keys().copied().collect::<HashSet<_>>(), HashSet::from([key(1), key(3)]));
    }

    /// The engine's rule (issue 64) in a program folder: a live run's segments stay as they are,
    /// whatever gc is given, and a row of ours that it beats is a duplicate.
    #[test]
    fn a_live_runs_segments_in_a_program_folder_stay_as_they_are() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(&folder(dir.path(), &schema())).unwrap();
        segment(&store, &[row(1, Some(1)), row(2, Some(2))], 30);
        let mark = runs::RunMark::register(&store).unwrap();
        let run = store.clone().writing_as(mark.name());
        let theirs = write_segment(&run, &schema(), &[row(2, Some(2)), row(4, Some(4))]).unwrap();
        let keep = HashMap::from([(schema().id(), HashSet::from([key(1)]))]);
        let r = gc(dir.path(), Some(&keep), false).unwrap();
        assert_eq!((r.rows_kept, r.rows_removed, r.rows_live), (1, 1, 2));
        assert!(theirs.exists(), "left exactly as it was");
        assert_eq!(served(&store).len(), 3);
        drop(mark);
        let r = gc(dir.path(), Some(&keep), false).unwrap();
        assert_eq!((r.rows_kept, r.rows_removed, r.rows_live, r.segments_after), (1, 2, 0, 1));
    }
}
