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
use super::{PipelineSpec, SystemMarker, SystemSpec, Target};
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

/// A rule broken by a whole pipeline (a race, an exploratory block): the field's dotted path and
/// what to do.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// Path of the offending field, e.g. `["race", "max_seeds"]`.
    pub path: Vec<String>,
    /// What is wrong and the fix.
    pub message: String,
}

/// Check every race of `spec` against the rest of the pipeline: the first round has at least two
/// seeds (a test needs a spread) and no more than `max_seeds`, the extended seed numbers fit, and
/// every raced experiment has one goal measure (its cells count episodes at one cap, so
/// `max_episodes` is not one of its axes).
pub fn check(spec: &PipelineSpec) -> Result<(), Problem> {
    let seeds = &spec.seeds.0;
    let top = ["race".to_string()];
    if let Some(r) = &spec.race {
        check_one(r, seeds, &top)?;
    }
    let s = &spec.systems;
    check_system(spec, s.ball_beam.as_ref(), "ball-beam")?;
    check_system(spec, s.cart_pole.as_ref(), "cart-pole")?;
    check_system(spec, s.mountain_car.as_ref(), "mountain-car")
}

fn check_system<M: SystemMarker>(
    spec: &PipelineSpec,
    sys: Option<&SystemSpec<M>>,
    name: &str,
) -> Result<(), Problem> {
    let Some(sys) = sys else { return Ok(()) };
    for (i, e) in sys.experiments.iter().enumerate() {
        let at = |tail: &[&str]| -> Vec<String> {
            ["systems", name, "experiments", &i.to_string()]
                .iter()
                .chain(tail)
                .map(|s| s.to_string())
                .collect()
        };
        if let Some(r) = &e.race {
            check_one(r, &spec.seeds.0, &at(&["race"]))?;
        }
        let raced = e.race.is_some() || spec.race.is_some();
        let capped = e.axes.iter().find(|a| a.targets.contains(&Target::Setting("max_episodes")));
        if let (true, Some(axis)) = (raced, capped) {
            return Err(Problem {
                path: at(&["vary", &axis.label]),
                message: format!(
                    "a race needs one goal measure per heatmap, but experiment {} varies max_episodes, so its \
                     cells count failed trials at different caps; remove the `{}` axis or race only the \
                     experiments without it (a `race:` block inside each)",
                    e.id, axis.label
                ),
            });
        }
    }
    Ok(())
}

fn check_one(r: &RaceSpec, seeds: &[u64], at: &[String]) -> Result<(), Problem> {
    let path = |field: &str| at.iter().cloned().chain([field.to_string()]).collect::<Vec<_>>();
    let n = seeds.len();
    if n < 2 {
        return Err(Problem {
            path: vec!["seeds".into()],
            message: format!(
                "a race starts from at least 2 seeds per cell (a test needs a spread), but `seeds` gives {n}; \
                 use e.g. `seeds: 5`"
            ),
        });
    }
    if (r.max_seeds as usize) < n {
        return Err(Problem {
            path: path("max_seeds"),
            message: format!(
                "max_seeds {} is below the {n} seeds of the first round; set max_seeds ≥ {n} (or fewer `seeds`)",
                r.max_seeds
            ),
        });
    }
    let last = seeds.iter().max().copied().unwrap_or(0);
    if last.checked_add(u64::from(r.max_seeds)).is_none() {
        return Err(Problem {
            path: vec!["seeds".into()],
            message: format!(
                "a race numbers its extra seeds after the largest first-round seed ({last}), which leaves no room; \
                 use smaller seeds"
            ),
        });
    }
    Ok(())
}
