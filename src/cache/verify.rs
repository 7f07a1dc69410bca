//! Checking the cache like `git fsck`, and moving damaged segments aside.
//!
//! A segment is damaged when it cannot be read as Parquet, lacks a column or has one of the wrong
//! type, or holds a row whose stored configuration no longer hashes to its key (bit rot, a
//! hand-edited file, a bug). Damaged segments are moved to `<cache>/_quarantine/` (the leading `_`
//! keeps pandas, polars and DuckDB globs from reading them), never deleted, so the next run simply
//! recomputes their trials.

use super::store::{read_segment, Damaged, Store};
use super::Key;
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

impl Store {
    /// Read every segment in full and re-hash every row's configuration.
    pub fn verify(&self) -> anyhow::Result<VerifyReport> {
        let mut report = VerifyReport::default();
        let mut keys = std::collections::HashSet::new();
        for path in self.segments()? {
            report.segments += 1;
            match read_segment(&path, &|_| true) {
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
                Err(e) => report.damaged.push(Damaged { path, error: format!("{e:#}") }),
            }
        }
        report.distinct = keys.len();
        Ok(report)
    }

    /// Move a damaged segment into the quarantine folder; returns where it went.
    pub fn quarantine(&self, segment: &std::path::Path) -> anyhow::Result<PathBuf> {
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
    use crate::cache::TrialRecord;
    use crate::sim::env::SystemKind;
    use crate::sim::repr::ReprKind;
    use crate::sim::{run_trial, Algorithm, TrialConfig};

    fn records(n: u64) -> Vec<TrialRecord> {
        let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
        c.limits.max_episodes = 3;
        (0..n).map(|seed| TrialRecord::new(c.clone(), seed, run_trial(&c, seed), 0.0)).collect()
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
