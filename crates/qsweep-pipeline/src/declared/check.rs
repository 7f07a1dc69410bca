//! The rules that need the whole pipeline: races against the seeds and the experiments, the
//! exploratory block against the references, and the rules across a success section's fields
//! (checked on the whole section, so a variant may set its fields one `set` entry at a time).

use super::experiment::Target;
use super::pipeline::{each_system, PipelineSpec};
use super::race::RaceSpec;
use super::settings::SystemMarker;
use super::system::SystemSpec;
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;

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
pub fn check_races(spec: &PipelineSpec) -> Result<(), Problem> {
    let seeds = &spec.seeds.0;
    let top = ["race".to_string()];
    if let Some(r) = &spec.race {
        check_one(r, seeds, &top)?;
    }
    each_system!(&spec.systems, |s| check_system(spec, s)?);
    Ok(())
}

pub(super) fn check_system<M: SystemMarker>(spec: &PipelineSpec, sys: &SystemSpec<M>) -> Result<(), Problem> {
    let name = M::SYSTEM.name();
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

/// Check one `race:` block (at path `at`) against the first round's `seeds`: at least two of them,
/// no more than `max_seeds`, and room for the extra seeds' numbers. Shared with program pipelines.
pub fn check_one(r: &RaceSpec, seeds: &[u64], at: &[String]) -> Result<(), Problem> {
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

/// Every Table III row of the pipeline: (system, experiment id, algorithm, has a reference).
pub(super) fn rows(spec: &PipelineSpec) -> Vec<(SystemKind, String, Algorithm, bool)> {
    fn of<M: SystemMarker>(s: &SystemSpec<M>) -> Vec<(SystemKind, String, Algorithm, bool)> {
        s.experiments
            .iter()
            .flat_map(|e| {
                e.algorithms.iter().map(move |&a| (M::SYSTEM, e.id.clone(), a, e.reference.contains_key(&a)))
            })
            .collect()
    }
    let mut out = Vec::new();
    each_system!(&spec.systems, |s| out.extend(of(s)));
    out
}

/// Check the block against the pipeline's rows.
pub fn check_exploratory(spec: &PipelineSpec) -> Result<(), Problem> {
    let Some(x) = &spec.exploratory else { return Ok(()) };
    let all = rows(spec);
    let at = |i: usize| vec!["exploratory".to_string(), "fit_rows".to_string(), i.to_string()];
    if x.fit_rows.is_empty() {
        return Err(Problem {
            path: vec!["exploratory".into(), "fit_rows".into()],
            message: "the list is empty; name the Table III rows that choose the variant".into(),
        });
    }
    for (i, r) in x.fit_rows.iter().enumerate() {
        let hit: Vec<_> = all.iter().filter(|(s, e, a, _)| r.matches(*s, e, *a)).collect();
        if hit.is_empty() {
            let of_system: Vec<String> = all
                .iter()
                .filter(|(s, ..)| *s == r.system)
                .map(|(_, e, a, _)| format!("exp {e} {}", a.name()))
                .collect();
            let known = if of_system.is_empty() {
                format!("the pipeline has no {}", r.system)
            } else {
                format!("its rows are {}", of_system.join(", "))
            };
            return Err(Problem {
                path: at(i),
                message: format!("no Table III row is {}; {known}", r.label()),
            });
        }
        if !hit.iter().any(|h| h.3) {
            return Err(Problem {
                path: at(i),
                message: format!(
                    "{} has no `reference:` value, so it cannot choose a variant; name rows with a reference",
                    r.label()
                ),
            });
        }
    }
    let held_out = all.iter().filter(|(s, e, a, r)| *r && !x.is_fit_row(*s, e, *a)).count();
    if held_out == 0 {
        return Err(Problem {
            path: vec!["exploratory".into(), "fit_rows".into()],
            message: "the fit rows cover every row with a reference, so nothing is held out to judge the \
                      chosen variant; leave some rows out"
                .into(),
        });
    }
    Ok(())
}

/// Check the `fresh:` block against the seeds the grid and its races use: a fresh seed that also
/// chose the best cell would not be fresh.
pub fn check_fresh(spec: &PipelineSpec) -> Result<(), Problem> {
    let Some(f) = &spec.fresh else { return Ok(()) };
    check_fresh_seeds(f, &spec.seeds.0, &race_blocks(spec))
}

/// Check a `fresh:` block against the grid's `seeds` and the extra seeds of the pipeline's
/// `races`: a fresh seed that also chose the best cell would not be fresh. Shared with program
/// pipelines.
pub fn check_fresh_seeds(
    f: &super::fresh::FreshSpec,
    seeds: &[u64],
    races: &[RaceSpec],
) -> Result<(), Problem> {
    let at = |field: &str| vec!["fresh".to_string(), field.to_string()];
    let Some(fresh) = f.seed_list() else {
        return Err(Problem {
            path: at("first_seed"),
            message: format!(
                "{} fresh seeds from {} run past the largest seed; use a smaller first_seed",
                f.seeds, f.first_seed
            ),
        });
    };
    let (lo, hi) = (fresh[0], fresh[fresh.len() - 1]);
    if let Some(s) = seeds.iter().find(|s| (lo..=hi).contains(*s)) {
        return Err(Problem {
            path: at("first_seed"),
            message: format!(
                "fresh seeds {lo}..{hi} include seed {s}, which the grid uses to choose the best cells; \
                 start them after the grid's seeds, e.g. `first_seed: {}`",
                seeds.iter().max().map_or(0, |m| m + 1)
            ),
        });
    }
    // A race numbers its extra seeds on from the largest first-round seed.
    if let Some(max_seeds) = races.iter().map(|r| u64::from(r.max_seeds)).max() {
        let first = seeds.iter().max().map_or(0, |m| m + 1);
        let last = first.saturating_add(max_seeds.saturating_sub(seeds.len() as u64 + 1));
        if lo <= last && first <= hi && seeds.len() < max_seeds as usize {
            return Err(Problem {
                path: at("first_seed"),
                message: format!(
                    "fresh seeds {lo}..{hi} overlap the race's extra seeds {first}..{last}; \
                     start them after, e.g. `first_seed: {}`",
                    last + 1
                ),
            });
        }
    }
    Ok(())
}

fn race_blocks(spec: &PipelineSpec) -> Vec<RaceSpec> {
    let mut out: Vec<RaceSpec> = spec.race.into_iter().collect();
    each_system!(&spec.systems, |s| out.extend(s.experiments.iter().filter_map(|e| e.race)));
    out
}

/// Every success section (a system's and its experiments') against the rules across its fields
/// (`SystemMarker::check_success`: the solved rule's `window` and `mean_length` come together).
pub fn check_successes(spec: &PipelineSpec) -> Result<(), Problem> {
    fn of<M: SystemMarker>(sys: &SystemSpec<M>) -> Result<(), Problem> {
        let name = M::SYSTEM.name();
        let at =
            |path: &[&str], message| Problem { path: path.iter().map(|s| s.to_string()).collect(), message };
        if let Some(s) = &sys.success {
            M::check_success(s).map_err(|m| at(&["systems", name, "success"], m))?;
        }
        for (i, e) in sys.experiments.iter().enumerate() {
            if let Some(s) = &e.success {
                let i = i.to_string();
                M::check_success(s).map_err(|m| at(&["systems", name, "experiments", &i, "success"], m))?;
            }
        }
        Ok(())
    }
    each_system!(&spec.systems, |s| of(s)?);
    Ok(())
}

/// The rules that need the whole pipeline: success sections, races, fresh seeds and the
/// exploratory block.
pub(crate) fn check_whole(spec: &PipelineSpec) -> Result<(), Problem> {
    check_successes(spec)?;
    check_races(spec)?;
    check_fresh(spec)?;
    check_exploratory(spec)
}
