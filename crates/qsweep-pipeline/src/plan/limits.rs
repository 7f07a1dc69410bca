//! The confirmation limits: how many variants and trials a pipeline plans, counted from the
//! spec before any configuration is built or hashed, so that an accidental huge grid is refused
//! at once (`--yes` lifts the limits).

use crate::declared::{
    each_system, LoadedSpec, LoadedVariant, PipelineSpec, RaceSpec, SystemMarker, SystemSpec,
};
use crate::error::user_error;

/// Plans larger than this many trials need confirmation (`--yes`).
pub const DEFAULT_MAX_TRIALS: usize = 200_000;

/// Refuse a `variant_grid:` that generates more variants than the confirmation limit.
pub(super) fn check_variant_count(loaded: &LoadedSpec, origin: &str) -> anyhow::Result<()> {
    let generated = loaded.variants.iter().filter(|v| v.generated).count();
    if generated > crate::declared::grid::DEFAULT_MAX_VARIANTS {
        // The position is read again from the file: the typed pipeline does not keep it.
        let pos = std::fs::read_to_string(&loaded.path)
            .ok()
            .and_then(|t| crate::declared::locate(&t, &["variant_grid".to_string()]))
            .map(|(l, c)| format!("{l}:{c}:"))
            .unwrap_or_default();
        return Err(user_error(format!(
            "{origin}:{pos} variant_grid: {generated} variants, more than the confirmation limit of {}; \
             rerun with --yes if this is intended, or add `sample: N` to try a random N of them",
            crate::declared::grid::DEFAULT_MAX_VARIANTS
        )));
    }
    Ok(())
}

/// Refuse a plan of more than `limit` trials: the pipeline as written when `chosen` is empty,
/// else the chosen variants.
pub(super) fn check_trial_count(
    spec: &PipelineSpec,
    chosen: &[&LoadedVariant],
    origin: &str,
    limit: usize,
) -> anyhow::Result<()> {
    let n: u128 = if chosen.is_empty() { planned_trials(spec) } else { variants_trials(chosen) };
    if n > limit as u128 {
        return Err(too_many(origin, n, limit));
    }
    Ok(())
}

/// Trials the chosen variants expand to. A variant that differs from an earlier one only in
/// report settings plans the same trials: counted once.
fn variants_trials(chosen: &[&LoadedVariant]) -> u128 {
    let mut seen = Vec::new();
    chosen
        .iter()
        .filter(|v| {
            let s = trial_set(v);
            let new = !seen.contains(&s);
            seen.push(s);
            new
        })
        .map(|v| planned_trials(&v.spec))
        .sum()
}

/// A variant's `set` entries that change trials (not report settings), sorted.
fn trial_set(v: &LoadedVariant) -> Vec<&String> {
    let mut s: Vec<&String> = v.set.iter().filter(|e| !crate::declared::is_report_setting(e)).collect();
    s.sort();
    s
}

/// The error of a plan over the trial limit.
fn too_many(origin: &str, n: u128, limit: usize) -> anyhow::Error {
    user_error(format!(
        "{origin}: the plan has {n} trials, more than the confirmation limit of {limit}; \
         rerun with --yes if this is intended, or shrink the grid or the seeds"
    ))
}

/// Trials the spec expands to (cells × seeds; a raced experiment counted at `max_seeds`, the most
/// its race can run), without building anything.
fn planned_trials(spec: &PipelineSpec) -> u128 {
    let seeds = spec.seeds.0.len() as u128;
    let system = |experiments: Vec<(u128, Option<RaceSpec>)>| -> u128 {
        experiments
            .into_iter()
            .map(|(cells, race)| {
                cells * race.or(spec.race).map_or(seeds, |r| seeds.max(u128::from(r.max_seeds)))
            })
            .sum()
    };
    fn cells<M: SystemMarker>(s: &SystemSpec<M>) -> Vec<(u128, Option<RaceSpec>)> {
        s.experiments
            .iter()
            .map(|e| {
                let n = e.axes.iter().map(|a| a.values.len() as u128).product::<u128>()
                    * e.algorithms.len() as u128;
                (n, e.race)
            })
            .collect()
    }
    // A `fresh:` block adds its seeds to one cell per heatmap (experiment × algorithm).
    let heatmaps = |s: Vec<u128>| -> u128 { s.into_iter().sum() };
    fn algorithms<M: SystemMarker>(s: &SystemSpec<M>) -> Vec<u128> {
        s.experiments.iter().map(|e| e.algorithms.len() as u128).collect()
    }
    let (mut trials, mut maps) = (0, 0);
    each_system!(&spec.systems, |s| {
        trials += system(cells(s));
        maps += heatmaps(algorithms(s));
    });
    trials + spec.fresh.map_or(0, |f| u128::from(f.seeds)) * maps
}
