//! Checking the cache like `git fsck`, moving damaged segments aside, and recomputing a sample of
//! trials to check that this machine reproduces the stored outcomes.
//!
//! A segment is damaged when it cannot be read as Parquet, lacks a column or has one of the wrong
//! type, or holds a row whose stored configuration no longer hashes to its key (bit rot, a
//! hand-edited file, a bug). Damaged segments are moved to `<cache>/_quarantine/` (the leading `_`
//! keeps pandas, polars and DuckDB globs from reading them), never deleted, so the next run simply
//! recomputes their trials.
//!
//! Recomputing ([`Store::recompute`]) goes further than re-hashing: a row's key names its
//! configuration, seed and engine version, and a trial's outcome is a pure function of those on
//! every IEEE-754 machine, so running the trial again must reproduce every outcome field of the
//! row. A difference means a row computed by another engine under the same version number, a
//! platform whose floating point is not IEEE-754 binary64 with round-to-nearest, or a bug.

use super::key::{Key, ENGINE_VERSION};
use super::record::TrialRecord;
use super::rows::read_segment;
use super::store::{is_vanished, relisting, vanished_or, Damaged, Store};
use qsweep_engine::{run_trial, Outcome, TrialConfig};
use rayon::prelude::*;
use std::collections::HashSet;
use std::path::PathBuf;

/// Folder inside the cache that holds quarantined segments.
pub const QUARANTINE: &str = "_quarantine";

/// What `verify` found.
#[derive(Debug, Default)]
pub struct VerifyReport {
    /// Segments checked.
    pub segments: usize,
    /// Rows in intact segments.
    pub rows: usize,
    /// Distinct keys in intact segments.
    pub distinct: usize,
    /// Damaged segments and why.
    pub damaged: Vec<Damaged>,
}

/// What [`Store::recompute`] found.
#[derive(Debug, Default)]
pub struct RecomputeReport {
    /// Distinct trials of this binary's engine version in the intact segments (the population).
    pub eligible: usize,
    /// Distinct trials of other engine versions, which this binary cannot recompute.
    pub other_engine: usize,
    /// Trials recomputed.
    pub checked: usize,
    /// The recomputed trials whose outcome differs from the stored row.
    pub differing: Vec<Mismatch>,
}

/// A stored row that its recomputation does not reproduce.
#[derive(Debug)]
pub struct Mismatch {
    /// The row's key.
    pub key: Key,
    /// The outcome fields that differ (in any of its stored rows), by their column names.
    pub fields: Vec<&'static str>,
}

/// The outcome fields in which `stored` and `again` differ, by their cache column names.
fn differing_fields(stored: &Outcome, again: &Outcome) -> Vec<&'static str> {
    let mut out = Vec::new();
    let mut check = |differs: bool, name| {
        if differs {
            out.push(name);
        }
    };
    check(stored.converged != again.converged, "converged");
    check(stored.episodes_to_goal != again.episodes_to_goal, "episodes_to_goal");
    check(stored.episodes != again.episodes, "episodes");
    check(stored.total_steps != again.total_steps, "total_steps");
    check(stored.stop != again.stop, "stop");
    check(stored.failure != again.failure, "failure");
    check(stored.episode_lengths != again.episode_lengths, "episode_lengths");
    out
}

impl Store {
    /// Recompute `n` trials of this engine version drawn at random from the readable segments (the
    /// draw is a fixed function of `seed` and the set of stored keys) and compare every outcome
    /// field with every stored row of the trial (two machines may each have stored one). Segments
    /// that cannot be read are left out ([`verify`](Self::verify) reports them); all eligible
    /// trials are recomputed when there are at most `n`.
    pub fn recompute(&self, n: usize, seed: u64) -> anyhow::Result<RecomputeReport> {
        let mut report = RecomputeReport::default();
        // Listed again if gc replaces a segment meanwhile (see `store`).
        let mut rows = relisting(self.dir(), || self.draw(n, seed, &mut report))?;
        rows.sort_by_key(|r| r.key);
        // One recomputation per trial, compared with each of its stored rows.
        let trials: Vec<&[TrialRecord]> = rows.chunk_by(|a, b| a.key == b.key).collect();
        report.checked = trials.len();
        // As `qsweep run` computes them: crisp trials in lockstep (in other company than the run
        // that stored them), unless QSWEEP_LOCKSTEP=off.
        let jobs: Vec<(&TrialConfig, u64)> =
            trials.iter().map(|same| (&same[0].config, same[0].seed)).collect();
        let again: Vec<Outcome> = if qsweep_engine::lanes::enabled() {
            jobs.par_chunks(4 * qsweep_engine::lanes::LANES)
                .flat_map_iter(qsweep_engine::lanes::run_batch)
                .collect()
        } else {
            jobs.par_iter().map(|&(c, seed)| run_trial(c, seed)).collect()
        };
        report.differing = trials
            .par_iter()
            .zip(&again)
            .filter_map(|(same, again)| {
                let mut fields: Vec<&'static str> = Vec::new();
                for r in *same {
                    for f in differing_fields(&r.outcome, again) {
                        if !fields.contains(&f) {
                            fields.push(f);
                        }
                    }
                }
                (!fields.is_empty()).then_some(Mismatch { key: same[0].key, fields })
            })
            .collect();
        Ok(report)
    }

    /// The rows of `n` trials of this engine version drawn at random (see [`Self::recompute`]),
    /// the population counted into `report`.
    fn draw(&self, n: usize, seed: u64, report: &mut RecomputeReport) -> anyhow::Result<Vec<TrialRecord>> {
        let (mut current, mut other) = (HashSet::new(), HashSet::new());
        let mut intact = Vec::new();
        for path in self.segments()? {
            let records = match read_segment(&path, &|_| true).map_err(|e| vanished_or(&path, e)) {
                Ok(records) => records,
                Err(e) if is_vanished(&e) => return Err(e),
                Err(_) => continue,
            };
            for r in &records {
                if r.engine_version == ENGINE_VERSION {
                    current.insert(r.key);
                } else {
                    other.insert(r.key);
                }
            }
            intact.push(path);
        }
        report.eligible = current.len();
        report.other_engine = other.len();
        // A partial Fisher–Yates shuffle of the sorted keys by the trial random stream: the same
        // sample for the same seed and cache contents on every machine.
        let mut keys: Vec<Key> = current.into_iter().collect();
        keys.sort_unstable();
        let take = n.min(keys.len());
        let mut rng = qsweep_engine::rng::TrialRng::new(seed);
        for i in 0..take {
            let j = i + rng.below(keys.len() - i);
            keys.swap(i, j);
        }
        let sample: HashSet<Key> = keys[..take].iter().copied().collect();
        let mut rows: Vec<TrialRecord> = Vec::with_capacity(take);
        for path in &intact {
            rows.extend(read_segment(path, &|k| sample.contains(k)).map_err(|e| vanished_or(path, e))?);
        }
        Ok(rows)
    }

    /// Read every segment in full and re-hash every row's configuration; listed again if gc
    /// replaces a segment meanwhile (a segment gone is not damage).
    pub fn verify(&self) -> anyhow::Result<VerifyReport> {
        relisting(self.dir(), || {
            let mut report = VerifyReport::default();
            let mut keys = std::collections::HashSet::new();
            for path in self.segments()? {
                report.segments += 1;
                let mut read = read_segment(&path, &|_| true);
                // A bucket's segment is judged by the bucket's bytes, not by a damaged copy.
                if read.is_err() && self.refetch(&path)? {
                    read = read_segment(&path, &|_| true);
                }
                match read.map_err(|e| vanished_or(&path, e)) {
                    Ok(records) => {
                        let bad = records.iter().position(|r| {
                            let canonical = r.config_json();
                            Key::from_canonical(&canonical, r.seed, r.engine_version) != r.key
                        });
                        if let Some(i) = bad {
                            let error = format!("row {i}: the stored configuration does not hash to its key");
                            report.damaged.push(Damaged { path, error });
                        } else {
                            report.rows += records.len();
                            keys.extend(records.iter().map(|r| r.key));
                        }
                    }
                    Err(e) if is_vanished(&e) => return Err(e),
                    Err(e) => report.damaged.push(Damaged { path, error: format!("{e:#}") }),
                }
            }
            report.distinct = keys.len();
            Ok(report)
        })
    }

    /// Move a damaged segment into the quarantine folder; returns where it went. In a bucket the
    /// object is copied to `_quarantine/` there (created only if absent) before the segment is
    /// removed, and the copy in the directory goes to the directory's `_quarantine/`; the bucket's
    /// address is returned.
    pub fn quarantine(&self, segment: &std::path::Path) -> anyhow::Result<PathBuf> {
        if let Some(remote) = self.remote() {
            let name = super::remote::object_of(segment)?;
            let kept = super::remote::join(QUARANTINE, &name);
            let bytes = std::fs::read(segment)
                .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", segment.display()))?;
            remote.create(&kept, &bytes)?;
            remote.delete(&name)?;
            self.quarantine_copy(segment)?;
            return Ok(PathBuf::from(super::remote::join(remote.url(), &kept)));
        }
        self.quarantine_copy(segment)
    }

    /// Move the segment file at `segment` into the directory's quarantine folder.
    fn quarantine_copy(&self, segment: &std::path::Path) -> anyhow::Result<PathBuf> {
        let dir = self.dir().join(QUARANTINE);
        std::fs::create_dir_all(&dir)?;
        let name =
            segment.file_name().ok_or_else(|| anyhow::anyhow!("{} is not a file", segment.display()))?;
        let to = dir.join(name);
        std::fs::rename(segment, &to)
            .map_err(|e| anyhow::anyhow!("cannot move {} to {}: {e}", segment.display(), to.display()))?;
        Ok(to)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsweep_engine::env::SystemKind;
    use qsweep_engine::repr::ReprKind;
    use qsweep_engine::{Algorithm, TrialConfig};

    fn records(n: u64) -> Vec<TrialRecord> {
        let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
        c.limits.max_episodes = 3;
        (0..n).map(|seed| TrialRecord::new(c.clone(), seed, run_trial(&c, seed), 0.0)).collect()
    }

    /// Regression for `verify --recompute`: a row whose key hashes correctly but whose outcome is
    /// not what its configuration and seed compute (a planted wrong row) is found and named, with
    /// the fields that differ; the other rows agree; other engine versions are counted apart.
    #[test]
    fn recompute_finds_a_planted_wrong_row() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        store.write_segment(&records(6)).unwrap();
        let mut planted = records(8).split_off(6);
        planted[1].outcome.episode_lengths[0] += 1;
        planted[1].outcome.total_steps += 1;
        let wrong = planted[1].key;
        let mut old = records(9).split_off(8);
        old[0].engine_version = ENGINE_VERSION - 1;
        old[0].key = Key::from_canonical(&old[0].config_json(), 8, ENGINE_VERSION - 1);
        store.write_segment(&planted).unwrap();
        store.write_segment(&old).unwrap();
        assert!(store.verify().unwrap().damaged.is_empty(), "the planted row hashes correctly");
        let r = store.recompute(100, 0).unwrap();
        assert_eq!((r.eligible, r.other_engine, r.checked), (8, 1, 8));
        assert_eq!(r.differing.len(), 1);
        assert_eq!(r.differing[0].key, wrong);
        assert_eq!(r.differing[0].fields, ["total_steps", "episode_lengths"]);
        // A sample: the same draw for the same seed, another for another seed.
        let draw = |seed| {
            let r = store.recompute(3, seed).unwrap();
            (r.checked, r.differing.iter().map(|m| m.key).collect::<Vec<_>>())
        };
        assert_eq!(draw(7), draw(7));
        assert_eq!(draw(7).0, 3);
        let found: usize = (0..40).map(|s| draw(s).1.len()).sum();
        assert!(found > 0 && found < 40, "some draws of 3 of 8 include the planted row: {found}");
        // A second, disagreeing row of a correct trial (another machine's) is found too.
        let mut twin = records(1);
        twin[0].outcome.stop = qsweep_engine::StopReason::Diverged;
        store.write_segment(&twin).unwrap();
        let r = store.recompute(100, 0).unwrap();
        assert_eq!(r.checked, 8, "one recomputation per trial");
        let keys: Vec<Key> = r.differing.iter().map(|m| m.key).collect();
        assert_eq!(keys.len(), 2, "{keys:?}");
        assert!(keys.contains(&twin[0].key) && keys.contains(&wrong));
    }

    #[test]
    fn a_row_whose_config_no_longer_hashes_to_its_key_is_damage() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        store.write_segment(&records(2)).unwrap();
        let mut forged = records(1);
        forged[0].config.learner.alpha = 0.5; // key still that of alpha = 0.1
        let bad = store.write_segment(&forged).unwrap();
        let r = store.verify().unwrap();
        assert_eq!((r.segments, r.rows, r.distinct), (2, 2, 2));
        assert_eq!(r.damaged.len(), 1);
        assert_eq!(r.damaged[0].path, bad);
        assert!(r.damaged[0].error.contains("does not hash"), "{}", r.damaged[0].error);
        let moved = store.quarantine(&bad).unwrap();
        assert!(moved.starts_with(dir.path().join(QUARANTINE)));
        assert!(store.verify().unwrap().damaged.is_empty());
        assert_eq!(store.segments().unwrap().len(), 1, "quarantined segments are not read");
    }
}
