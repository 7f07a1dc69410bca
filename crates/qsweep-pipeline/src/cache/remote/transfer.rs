//! `qsweep cache push` and `pull`: the trials one cache holds and another lacks, copied by key.
//!
//! Each segment of the source is looked at once against the keys the destination holds: one
//! whose keys are all there is skipped; one with none of them is copied whole under its own name
//! (its bytes as they are, one create-only write: a name is never reused, so a segment already
//! there is the same segment); one with some of them gives its missing rows as a new segment.
//! Every write is whole or absent, so an interrupted copy leaves nothing half written, and the
//! next one copies what is still missing: copying again copies nothing.

use crate::cache::key::Key;
use crate::cache::rows::read_segment;
use crate::cache::store::Store;
use std::collections::HashSet;

/// What a copy did (or, with `dry_run`, would do).
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Copied {
    /// Distinct trials the source holds.
    pub source_trials: usize,
    /// Of those, trials the destination held already.
    pub present: usize,
    /// Trials copied.
    pub copied: usize,
    /// Segments written in the destination.
    pub segments: usize,
    /// Bytes written.
    pub bytes: u64,
    /// Unreadable segments of the source, skipped (see `qsweep verify`).
    pub damaged: Vec<String>,
}

/// Copy every trial `from` holds and `to` lacks into `to`; with `dry_run`, only count them.
pub fn copy(from: &Store, to: &Store, dry_run: bool) -> anyhow::Result<Copied> {
    let source = from.keys()?;
    let mut have: HashSet<Key> = to.keys()?.keys;
    let mut out = Copied {
        source_trials: source.keys.len(),
        present: source.keys.iter().filter(|k| have.contains(k)).count(),
        damaged: source.damaged.iter().map(|d| d.to_string()).collect(),
        ..Copied::default()
    };
    for (path, keys) in &source.segments {
        let missing: HashSet<Key> = keys.iter().copied().filter(|k| !have.contains(k)).collect();
        if missing.is_empty() {
            continue;
        }
        out.copied += missing.len();
        out.segments += 1;
        if missing.len() == keys.iter().collect::<HashSet<_>>().len() {
            let bytes =
                std::fs::read(path).map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))?;
            out.bytes += bytes.len() as u64;
            if !dry_run {
                to.put_segment(&super::object_of(path)?, &bytes)?;
            }
        } else {
            let rows = read_segment(path, &|k| missing.contains(k))?;
            if !dry_run {
                let written = to.write_segment(&dedup(rows))?;
                out.bytes += std::fs::metadata(&written).map_or(0, |m| m.len());
            }
        }
        have.extend(missing);
    }
    Ok(out)
}

/// One row per key, the first.
fn dedup(rows: Vec<crate::cache::TrialRecord>) -> Vec<crate::cache::TrialRecord> {
    let mut seen = HashSet::new();
    rows.into_iter().filter(|r| seen.insert(r.key)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::remote::dir::DirRemote;
    use crate::cache::TrialRecord;
    use qsweep_engine::env::SystemKind;
    use qsweep_engine::repr::ReprKind;
    use qsweep_engine::{run_trial, Algorithm, TrialConfig};
    use std::sync::Arc;

    fn record(seed: u64) -> TrialRecord {
        let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
        c.limits.max_episodes = 3;
        TrialRecord::new(c.clone(), seed, run_trial(&c, seed), 0.0)
    }

    #[test]
    fn a_push_copies_each_missing_trial_once_and_a_second_push_copies_nothing() {
        let d = tempfile::tempdir().unwrap();
        let local = Store::open(&d.path().join("local")).unwrap();
        let remote = Arc::new(DirRemote::new(&d.path().join("bucket")).unwrap());
        let bucket = Store::open_remote(remote.clone(), &d.path().join("copy")).unwrap();
        local.write_segment(&[record(1), record(2)]).unwrap();
        local.write_segment(&[record(3)]).unwrap();
        bucket.write_segment(&[record(2)]).unwrap();
        let first = copy(&local, &bucket, false).unwrap();
        assert_eq!((first.source_trials, first.present, first.copied, first.segments), (3, 1, 2, 2));
        assert_eq!(copy(&local, &bucket, false).unwrap().copied, 0, "idempotent");
        // What the bucket holds is what another machine's copy of it reads.
        let elsewhere = Store::open_remote(remote, &d.path().join("copy2")).unwrap();
        let mut keys: Vec<Key> = elsewhere.read_all().unwrap().iter().map(|r| r.key).collect();
        keys.sort();
        let mut want: Vec<Key> = [1, 2, 3].map(|s| record(s).key).to_vec();
        want.sort();
        assert_eq!(keys, want);
        // And back: a pull into an empty cache gets every row, identical.
        let fresh = Store::open(&d.path().join("fresh")).unwrap();
        assert_eq!(copy(&elsewhere, &fresh, false).unwrap().copied, 3);
        let mut a = fresh.read_all().unwrap();
        let mut b = local.read_all().unwrap();
        a.sort_by_key(|r| r.key);
        b.sort_by_key(|r| r.key);
        assert_eq!(a, b);
    }
}
