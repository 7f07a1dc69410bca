//! `fresh:` blocks: re-estimating each heatmap's best cell on seeds that took no part in choosing
//! it (the winner's curse of a minimum over many noisy cell means).
//!
//! ```yaml
//! seeds: 10                               # the grid: chooses each heatmap's best cell
//! fresh: { first_seed: 1000, seeds: 20 }  # then the best cells again, on seeds 1000..1019
//! ```
//!
//! Each value is checked while parsing; that the fresh seeds are disjoint from the grid's (and a
//! race's) is checked with the whole pipeline (`check`). What the stage does is `crate::fresh`.

use super::values::AtLeastOne;
use serde::de::{self, Deserializer};
use serde::Deserialize;

/// A `fresh:` block, as written (both fields required, so no estimate rests on a guessed seed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FreshSpec {
    /// The first fresh seed; the others follow it.
    pub first_seed: u64,
    /// How many fresh seeds each best cell gets, ≥ 2 (an interval needs a spread).
    #[serde(deserialize_with = "fresh_count")]
    pub seeds: u32,
}

impl FreshSpec {
    /// The fresh seeds, in order (`first_seed`, `first_seed` + 1, …), or `None` when they would
    /// run past the largest seed.
    pub fn seed_list(&self) -> Option<Vec<u64>> {
        let last = self.first_seed.checked_add(u64::from(self.seeds) - 1)?;
        Some((self.first_seed..=last).collect())
    }
}

fn fresh_count<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let AtLeastOne(v) = AtLeastOne::deserialize(d)?;
    if v < 2 {
        return Err(de::Error::custom(
            "1 fresh seed gives no spread (no interval, no test); use at least 2, e.g. `seeds: 20`",
        ));
    }
    u32::try_from(v)
        .map_err(|_| de::Error::custom(format!("{v} is too large; expected at most {}", u32::MAX)))
}
