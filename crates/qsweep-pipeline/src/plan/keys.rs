//! Keying a plan's trials: each trial's key is blake3 of its cell's canonical configuration and
//! its seed ([`Key::from_canonical`]); [`KeyMemo`] computes each distinct cell's keys once across
//! the variants of a pipeline.

use super::resolved::PlannedTrial;
use crate::cache::Key;

/// The trials of the cells planned so far, by a digest of each cell's canonical configuration
/// and seeds: a pipeline's variants share most of their cells (the paper's 378,000 planned trials
/// are 100,000 distinct), and a key hashes the whole configuration once per seed, so each
/// distinct cell's keys are computed once. Off (`enabled: false`) for a single plan.
#[derive(Default)]
pub(super) struct KeyMemo {
    enabled: bool,
    cells: std::sync::Mutex<std::collections::HashMap<Key, Vec<PlannedTrial>>>,
}

impl KeyMemo {
    /// A memo shared by the plans of several variants.
    pub(super) fn shared() -> Self {
        Self { enabled: true, ..Self::default() }
    }

    /// A cell's trials on `seeds`, keyed ([`Key::from_canonical`]).
    pub(super) fn trials(&self, canonical: &str, seeds: &[u64]) -> Vec<PlannedTrial> {
        let compute = || -> Vec<PlannedTrial> {
            seeds
                .iter()
                .map(|&seed| PlannedTrial {
                    seed,
                    key: Key::from_canonical(canonical, seed, crate::cache::ENGINE_VERSION),
                })
                .collect()
        };
        if !self.enabled {
            return compute();
        }
        let mut id = blake3::Hasher::new();
        id.update(b"qsweep-cell\0");
        id.update(&(seeds.len() as u64).to_le_bytes());
        id.update(&seeds.iter().flat_map(|s| s.to_le_bytes()).collect::<Vec<u8>>());
        id.update(canonical.as_bytes());
        let id = Key(*id.finalize().as_bytes());
        let lock = || self.cells.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(trials) = lock().get(&id) {
            return trials.clone();
        }
        let trials = compute();
        lock().insert(id, trials.clone());
        trials
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_memoized_cells_trials_are_the_ones_computed_for_it() {
        let memo = KeyMemo::shared();
        let direct = KeyMemo::default();
        let (a, b) = ("{\"a\":1}", "{\"a\":2}");
        let first = memo.trials(a, &[1, 2, 3]);
        assert_eq!(first, direct.trials(a, &[1, 2, 3]));
        assert_eq!(
            first[1],
            PlannedTrial { seed: 2, key: Key::from_canonical(a, 2, crate::cache::ENGINE_VERSION) }
        );
        assert_eq!(memo.trials(a, &[1, 2, 3]), first, "reused");
        // Another configuration or other seeds are other cells.
        assert_eq!(memo.trials(b, &[1, 2, 3]), direct.trials(b, &[1, 2, 3]));
        assert_eq!(memo.trials(a, &[1, 2]), direct.trials(a, &[1, 2]));
        assert_eq!(memo.trials(a, &[2, 1, 3]), direct.trials(a, &[2, 1, 3]));
        assert_ne!(memo.trials(a, &[1, 2, 3]), memo.trials(b, &[1, 2, 3]));
    }
}
