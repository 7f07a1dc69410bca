//! Splitting a plan's trials into N disjoint shards of similar estimated cost, for job arrays.
//!
//! The partition is computed over *every* distinct trial of the plan, not only the missing ones,
//! so it does not depend on what the cache holds when a shard starts: shards started at different
//! times, or a requeued array task, agree on who runs what. Trials are taken longest-first (ties by
//! key) and each goes to the shard with the least cost so far (LPT scheduling), deterministically.

use super::{estimated_cost, Job};
use crate::cache::Key;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Shard `I` of `N` (1-based, as `sbatch --array=1-N` numbers tasks).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 1..=count.
    pub index: u32,
    /// Number of shards.
    pub count: u32,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("'{s}' is not a shard; write I/N with 1 ≤ I ≤ N, e.g. 2/8");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (u32, u32) =
            (i.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }
}

/// The shard (1..=count) that owns a trial by its key alone: a fixed owner whatever else the
/// plan holds. A race's plan grows as its rounds are decided, so a cost-balanced split of it
/// would move trials between shards that started at different times; this one never does.
pub fn key_owner(key: &Key, count: u32) -> u32 {
    let h = u64::from_le_bytes(key.0[..8].try_into().expect("8 bytes"));
    (h % u64::from(count.max(1))) as u32 + 1
}

/// The shard (1..=count) of each trial, in the order given.
pub fn assign(trials: &[Job], count: u32) -> Vec<u32> {
    let mut order: Vec<(f64, Key, usize)> =
        trials.iter().enumerate().map(|(i, t)| (estimated_cost(t.config), t.key, i)).collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    // A min-heap of (load, shard): the least-loaded shard, ties to the lowest index. Loads are
    // non-negative finite costs, so their bit patterns order like the values.
    let mut heap: BinaryHeap<Reverse<(u64, u32)>> = (1..=count.max(1)).map(|s| Reverse((0, s))).collect();
    let mut owner = vec![0; trials.len()];
    for (cost, _, i) in order {
        let Some(Reverse((load, s))) = heap.pop() else { break };
        owner[i] = s;
        heap.push(Reverse(((f64::from_bits(load) + cost).to_bits(), s)));
    }
    owner
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsweep_engine::env::SystemKind;
    use qsweep_engine::repr::ReprKind;
    use qsweep_engine::{Algorithm, TrialConfig};
    use std::collections::HashSet;

    #[test]
    fn shards_are_disjoint_cover_everything_and_balance_cost() {
        let mut configs = Vec::new();
        for res in 2..=9 {
            for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
                configs.push(TrialConfig::paper(
                    SystemKind::CartPole,
                    repr,
                    Algorithm::QLambda,
                    vec![res; 4],
                    2,
                ));
            }
        }
        let trials: Vec<_> = configs
            .iter()
            .flat_map(|c| (0..5).map(move |seed| Job { config: c, seed, key: Key::of(c, seed) }))
            .collect();
        let n = 4;
        let shard_keys = |i: u32| -> HashSet<Key> {
            trials.iter().zip(assign(&trials, n)).filter(|&(_, s)| s == i).map(|(t, _)| t.key).collect()
        };
        let parts: Vec<_> = (1..=n).map(shard_keys).collect();
        let total: usize = parts.iter().map(HashSet::len).sum();
        assert_eq!(total, trials.len());
        let union: HashSet<_> = parts.iter().flatten().copied().collect();
        assert_eq!(union.len(), trials.len());
        let cost = |p: &HashSet<Key>| {
            trials.iter().filter(|t| p.contains(&t.key)).map(|t| estimated_cost(t.config)).sum::<f64>()
        };
        let costs: Vec<f64> = parts.iter().map(cost).collect();
        let (lo, hi) = costs.iter().fold((f64::MAX, 0.0f64), |(l, h), &c| (l.min(c), h.max(c)));
        assert!(hi <= lo * 1.5, "unbalanced: {costs:?}");
        assert_eq!(parts[1], shard_keys(2), "deterministic");
    }

    #[test]
    fn assignment_is_plain_lpt() {
        // The heap must pick exactly what a linear scan for the least-loaded shard picks.
        let configs: Vec<_> = (2..=7)
            .flat_map(|res| {
                [ReprKind::Crisp, ReprKind::Fuzzy].map(|repr| {
                    TrialConfig::paper(SystemKind::BallBeam, repr, Algorithm::Q0, vec![res, res], 3)
                })
            })
            .collect();
        let trials: Vec<_> = configs
            .iter()
            .flat_map(|c| (0..3).map(move |seed| Job { config: c, seed, key: Key::of(c, seed) }))
            .collect();
        for n in 1..=7u32 {
            let mut order: Vec<usize> = (0..trials.len()).collect();
            let cost = |i: usize| estimated_cost(trials[i].config);
            order.sort_by(|&a, &b| cost(b).total_cmp(&cost(a)).then(trials[a].key.cmp(&trials[b].key)));
            let mut load = vec![0.0f64; n as usize];
            let mut expected = vec![0; trials.len()];
            for i in order {
                let s = (0..load.len()).min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b))).unwrap();
                load[s] += cost(i);
                expected[i] = s as u32 + 1;
            }
            assert_eq!(assign(&trials, n), expected, "{n} shards");
        }
    }

    #[test]
    fn shard_syntax() {
        assert_eq!("3/8".parse::<Shard>(), Ok(Shard { index: 3, count: 8 }));
        for bad in ["0/4", "5/4", "1/0", "x/2", "3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}
