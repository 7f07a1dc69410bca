//! `race:` blocks: racing seeds into the cells of a heatmap that can still be the best.
//!
//! ```yaml
//! seeds: 10                       # the first round
//! race: { confidence: 0.95, batch: 5, max_seeds: 40 }   # pipeline-wide, or per experiment
//! ```
//!
//! The block is checked here (each value by its own rule while parsing, then the rules that need
//! the whole pipeline: `max_seeds` against the first round's seeds, one goal measure per heatmap)
//! so a bad race stops before anything runs, with the file position of the offending field.
//! What a race does is `crate::race`.

use super::values::{AtLeastOne, Confidence};
use serde::de::{self, Deserializer};
use serde::Deserialize;

/// A `race:` block, as written (every field required, so a race never runs on a guessed value).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RaceSpec {
    /// Confidence of "significantly worse than the best", in (0, 1); α = 1 − confidence.
    pub confidence: Confidence,
    /// Seeds added to every contender per round, ≥ 1.
    #[serde(deserialize_with = "batch")]
    pub batch: u32,
    /// Most seeds a cell gets, at least the first round's.
    #[serde(deserialize_with = "batch")]
    pub max_seeds: u32,
}

fn batch<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let AtLeastOne(v) = AtLeastOne::deserialize(d)?;
    u32::try_from(v)
        .map_err(|_| de::Error::custom(format!("{v} is too large; expected at most {}", u32::MAX)))
}
