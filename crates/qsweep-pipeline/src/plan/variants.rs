//! Planning a loaded pipeline: the `--variant` selection checked, the confirmation limits
//! ([`super::limits`]) applied, then the pipeline as written or each chosen variant expanded
//! ([`super::resolve`]), with a warning for each variant that changes no trial.

use super::keys::KeyMemo;
use super::limits::{check_trial_count, check_variant_count};
use super::resolve::expand_all;
use super::resolved::{Experiment, Plan, Variant};
use crate::cache::Key;
use crate::declared::{each_system, LoadedSpec, LoadedVariant, PipelineSpec};
use crate::error::user_error;
use std::collections::HashSet;

/// Expand a loaded pipeline into a plan (every variant). Fails (as a user error naming the
/// file) if a resolved configuration is invalid or the plan exceeds `max_trials`.
pub fn plan(loaded: &LoadedSpec, max_trials: Option<usize>) -> anyhow::Result<Plan> {
    plan_variants(loaded, max_trials, &[])
}

/// Like [`plan`], with only the variants named in `select` (all when empty; `--variant`).
pub fn plan_variants(
    loaded: &LoadedSpec,
    max_trials: Option<usize>,
    select: &[String],
) -> anyhow::Result<Plan> {
    let spec = &loaded.spec;
    let origin = loaded.path.display().to_string();
    check_selection(loaded, &origin, select)?;
    if max_trials.is_some() {
        check_variant_count(loaded, &origin)?;
    }
    let chosen: Vec<&LoadedVariant> =
        loaded.variants.iter().filter(|v| select.is_empty() || select.contains(&v.id)).collect();
    if let Some(limit) = max_trials {
        check_trial_count(spec, &chosen, &origin, limit)?;
    }
    let expanded = if chosen.is_empty() {
        let mut experiments = Vec::new();
        expand_all(spec, &origin, None, &mut experiments, &KeyMemo::default())?;
        Expanded { experiments, variants: Vec::new(), warnings: Vec::new() }
    } else {
        expand_variants(loaded, &origin, chosen)?
    };
    Ok(assemble(loaded, select, expanded))
}

/// What expanding the chosen variants gave: their experiments, in variant order, each variant's
/// description, and the warnings about them.
struct Expanded {
    /// Every chosen variant's experiments, tagged with its id.
    experiments: Vec<Experiment>,
    /// The chosen variants, in file order.
    variants: Vec<Variant>,
    /// One line per variant that changes no trial.
    warnings: Vec<String>,
}

/// Refuse a `--variant` the pipeline does not declare (with the closest id it does).
fn check_selection(loaded: &LoadedSpec, origin: &str, select: &[String]) -> anyhow::Result<()> {
    if loaded.variants.is_empty() && !select.is_empty() {
        return Err(user_error(format!(
            "--variant {}: {origin} declares no variants; remove --variant",
            select[0]
        )));
    }
    for id in select {
        if !loaded.variants.iter().any(|v| &v.id == id) {
            let ids: Vec<&str> = loaded.variants.iter().map(|v| v.id.as_str()).collect();
            let hint = crate::declared::suggest(id, ids.iter().copied())
                .map(|s| format!("; did you mean `{s}`?"))
                .unwrap_or_default();
            return Err(user_error(format!(
                "--variant {id}: {origin} has no such variant; its variants are {}{hint}",
                ids.join(", ")
            )));
        }
    }
    Ok(())
}

/// Expand each chosen variant in file order, warning about those whose trials are all the
/// pipeline's as written.
fn expand_variants(
    loaded: &LoadedSpec,
    origin: &str,
    chosen: Vec<&LoadedVariant>,
) -> anyhow::Result<Expanded> {
    // The variants share most of their cells: each distinct cell's keys are computed once.
    let memo = KeyMemo::shared();
    let mut chosen = chosen;
    chosen.sort_by_key(|v| !v.set.is_empty());
    let (written, mut by_variant) = plan_as_written(loaded, origin, &chosen, &memo)?;
    chosen.sort_by_key(|v| loaded.variants.iter().position(|x| x.id == v.id));
    let mut out = Expanded { experiments: Vec::new(), variants: Vec::new(), warnings: Vec::new() };
    for v in chosen {
        let origin = format!("{origin} (variant {})", v.id);
        let first = out.experiments.len();
        let at = loaded.variants.iter().position(|x| x.id == v.id).unwrap_or(0);
        if let Some(i) = by_variant.iter().position(|(a, _)| *a == at) {
            out.experiments.extend(by_variant.swap_remove(i).1);
        } else {
            expand_all(&v.spec, &origin, Some(&v.id), &mut out.experiments, &memo)?;
        }
        if let Some(warning) = unchanged_warning(v, &out.experiments[first..], &written) {
            out.warnings.push(warning);
        }
        out.variants.push(variant_of(v));
    }
    Ok(out)
}

/// Experiments already expanded, with their variant's index among the loaded variants.
type ByVariant = Vec<(usize, Vec<Experiment>)>;

/// The keys of the pipeline as written, to tell which variants change nothing. A variant without
/// a `set` is exactly that, so it is planned first (`chosen` lists those first) and its
/// experiments come back to be reused (no second plan).
fn plan_as_written(
    loaded: &LoadedSpec,
    origin: &str,
    chosen: &[&LoadedVariant],
    memo: &KeyMemo,
) -> anyhow::Result<(HashSet<Key>, ByVariant)> {
    let mut written: Option<HashSet<Key>> = None;
    let mut by_variant: ByVariant = Vec::new();
    for v in chosen {
        if v.set.is_empty() && written.is_none() {
            let mut mine = Vec::new();
            expand_all(&v.spec, &format!("{origin} (variant {})", v.id), Some(&v.id), &mut mine, memo)?;
            written = Some(keys_of(&mine));
            let at = loaded.variants.iter().position(|x| x.id == v.id).unwrap_or(0);
            by_variant.push((at, mine));
        }
    }
    let written = match written {
        Some(w) => w,
        None => {
            let mut as_written = Vec::new();
            expand_all(&loaded.spec, origin, None, &mut as_written, memo)?;
            keys_of(&as_written)
        }
    };
    Ok((written, by_variant))
}

/// Every trial key of `exps`.
fn keys_of(exps: &[Experiment]) -> HashSet<Key> {
    exps.iter().flat_map(|e| e.cells.iter().flat_map(|c| c.trials.iter().map(|t| t.key))).collect()
}

/// The warning for variant `v` when its experiments `mine` plan no trial outside `written`.
fn unchanged_warning(v: &LoadedVariant, mine: &[Experiment], written: &HashSet<Key>) -> Option<String> {
    let changed = mine
        .iter()
        .flat_map(|e| e.cells.iter().flat_map(|c| c.trials.iter()))
        .any(|t| !written.contains(&t.key));
    // A report setting changes what the trials count, not the trials: no warning for it.
    (!changed && v.set.iter().any(|e| !crate::declared::is_report_setting(e))).then(|| {
        format!(
            "variant `{}` changes no trial (its set gives the same configurations as the pipeline as written)",
            v.id
        )
    })
}

/// The plan's description of a loaded variant.
fn variant_of(v: &LoadedVariant) -> Variant {
    Variant {
        id: v.id.clone(),
        title: v.title.clone(),
        description: v.description.clone(),
        set: v.set.clone(),
        seeds: v.spec.seeds.0.clone(),
        generated: v.generated,
        exploratory: v.exploratory,
    }
}

/// The plan of `loaded` from its expanded experiments and variants.
fn assemble(loaded: &LoadedSpec, select: &[String], expanded: Expanded) -> Plan {
    let spec = &loaded.spec;
    let Expanded { experiments, variants, warnings } = expanded;
    Plan {
        name: spec.name.clone(),
        description: spec.description.clone(),
        source: loaded.path.clone(),
        reference_source: spec.reference_source.clone(),
        seeds: spec.seeds.0.clone(),
        variant_subset: !select.is_empty() && variants.len() < loaded.variants.len(),
        // Over every variant, selected or not, so a variant's folder has the same columns however
        // it was reported.
        raced: if loaded.variants.is_empty() {
            spec_races(spec)
        } else {
            loaded.variants.iter().any(|v| spec_races(&v.spec))
        },
        exploratory: spec.exploratory.clone(),
        variant_count: loaded.variants.len(),
        experiments,
        variants,
        warnings,
    }
}

/// Whether some experiment of `spec` races.
fn spec_races(spec: &PipelineSpec) -> bool {
    let mut races = spec.race.is_some();
    each_system!(&spec.systems, |s| races |= s.experiments.iter().any(|e| e.race.is_some()));
    races
}
