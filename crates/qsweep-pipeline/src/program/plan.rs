//! The plan of a program pipeline: its input files digested and its provenance commands run
//! (once, in the directory the program will run in), then each experiment's grid expanded into
//! cells (the product of its axes in declared order, the first axis outermost), each cell's
//! params (the defaults, then the experiment's `fixed`, then the cell's axis values) with one
//! keyed trial per seed.
//!
//! Variants follow the engine's rule (`crate::plan::plan_variants`): a pipeline without
//! variants plans its experiments as written; a pipeline with variants plans every chosen
//! variant (all, or those named by `--variant`), each the whole set of experiments with the
//! variant's `set` applied to the params' defaults and tagged with its id; the pipeline as
//! written is planned only through a variant without `set` (and is used to warn about a variant
//! that changes no trial). Trials two variants share have one key and run once. A plan larger
//! than the confirmation limit (`crate::plan::DEFAULT_MAX_TRIALS` by default) is refused before
//! anything is read or run.

use crate::cache::Key;
use crate::declared::suggest;
use crate::error::user_error;
use crate::program::declared::{ExperimentDecl, LoadedProgram, ProgramDecl};
use crate::program::key::Identity;
use crate::program::model::{
    ParamType, ParamValue, Program, ProgramCell, ProgramExperiment, ProgramPlan, ProgramTrial, ProgramVariant,
};
use std::collections::HashSet;
use std::path::Path;

/// Plan `loaded`: `base` is the directory the program runs in (qsweep's working directory),
/// where `inputs:` globs are expanded and provenance commands run; `max_trials` the confirmation
/// limit (`None`: `--yes`); `select` the `--variant` ids (empty: every variant).
pub fn plan(
    loaded: &LoadedProgram,
    base: &Path,
    max_trials: Option<usize>,
    select: &[String],
) -> anyhow::Result<ProgramPlan> {
    check_selection(loaded, select)?;
    if let Some(limit) = max_trials {
        let n = planned_trials(&loaded.decl, select);
        if n > limit as u128 {
            return Err(user_error(format!(
                "{}: the plan has {n} trials, more than the confirmation limit of {limit}; \
                 rerun with --yes if this is intended, or shrink the grid or the seeds",
                loaded.origin()
            )));
        }
    }
    let program = resolve_program(loaded, base)?;
    plan_with(loaded, program, select)
}

/// The program of `loaded` resolved in `base`: its input files found and digested, its
/// provenance commands run. Errors (a glob that matches nothing, a failing command) are user
/// errors at the entry's line.
pub fn resolve_program(loaded: &LoadedProgram, base: &Path) -> anyhow::Result<Program> {
    let d = &loaded.decl;
    let inputs = crate::program::inputs::resolve(&d.inputs, base)
        .map_err(|e| loaded.error_at(&["program", "inputs", &e.glob.to_string()], &e.message))?;
    let provenance_outputs = crate::program::provenance::run_all(&d.provenance, base)
        .map_err(|(i, m)| loaded.error_at(&["program", "provenance", &i.to_string()], &m))?;
    Ok(Program {
        command: d.command.clone(),
        input_globs: d.inputs.clone(),
        inputs,
        protocol: d.protocol,
        timeout: d.timeout,
        // By name, as the plan's params: the rows' columns and their folder do not depend on the
        // order the file lists them in.
        metrics: sorted_by_name(d.metrics.clone()),
        objective: d.objective.clone(),
        provenance: d.provenance.clone(),
        provenance_outputs,
    })
}

/// Plan `loaded` with `program` already resolved (no file is read, nothing runs).
pub fn plan_with(loaded: &LoadedProgram, program: Program, select: &[String]) -> anyhow::Result<ProgramPlan> {
    check_selection(loaded, select)?;
    let d = &loaded.decl;
    let identity = Identity::of(&program);
    let params = d.param_types();
    let grid = Grid { decl: d, params: &params, identity: &identity };
    let chosen: Vec<_> = d.variants.iter().filter(|v| select.is_empty() || select.contains(&v.id)).collect();
    let mut experiments = Vec::new();
    let mut warnings = Vec::new();
    if chosen.is_empty() {
        grid.expand(&d.defaults(), None, &mut experiments);
    } else {
        let written = grid.cell_keys(&d.defaults());
        for v in &chosen {
            let first = experiments.len();
            grid.expand(&v.defaults, Some(&v.id), &mut experiments);
            let changed = experiments[first..]
                .iter()
                .flat_map(|e| &e.cells)
                .any(|c| !c.trials.first().is_some_and(|t| written.contains(&t.key)));
            if !changed && !v.set.is_empty() {
                warnings.push(format!(
                    "variant `{}` changes no trial (its set gives the same configurations as the pipeline as written)",
                    v.id
                ));
            }
        }
    }
    let (params, experiments) = by_name(params, experiments);
    Ok(ProgramPlan {
        name: d.name.clone(),
        description: d.description.clone(),
        source: loaded.path.clone(),
        program,
        params,
        seeds: d.seeds.clone(),
        experiments,
        variants: chosen
            .iter()
            .map(|v| ProgramVariant { id: v.id.clone(), title: v.title.clone(), set: v.set.clone() })
            .collect(),
        warnings,
    })
}

/// `entries` sorted by name.
fn sorted_by_name<T>(mut entries: Vec<(String, T)>) -> Vec<(String, T)> {
    entries.sort_by(|a, b| a.0.cmp(&b.0));
    entries
}

/// The params sorted by name, and every cell's values in that order: a plan lists its params (and
/// its program its metrics) by name, so the rows' columns and their folder (`model::schema_id`)
/// are the same whatever order the file declares them in. A trial's key never depended on it (the
/// canonical JSON sorts its keys).
fn by_name(
    params: Vec<(String, ParamType)>,
    mut experiments: Vec<ProgramExperiment>,
) -> (Vec<(String, ParamType)>, Vec<ProgramExperiment>) {
    let mut order: Vec<usize> = (0..params.len()).collect();
    order.sort_by(|&a, &b| params[a].0.cmp(&params[b].0));
    for c in experiments.iter_mut().flat_map(|e| &mut e.cells) {
        c.params = order.iter().map(|&i| c.params[i].clone()).collect();
    }
    (order.iter().map(|&i| params[i].clone()).collect(), experiments)
}

/// How many trials `decl` plans at most with the variants `select` (all when empty), counted
/// without building anything.
pub fn planned_trials(decl: &ProgramDecl, select: &[String]) -> u128 {
    // A raced experiment counts at `max_seeds`, the most its race can run; `fresh:` adds its
    // seeds to one cell per experiment.
    let seeds = decl.seeds.len() as u128;
    let per_plan: u128 = decl
        .experiments
        .iter()
        .map(|e| {
            e.cell_count() * e.race.map_or(seeds, |r| seeds.max(u128::from(r.max_seeds)))
                + decl.fresh.len() as u128
        })
        .sum();
    let variants = decl.variants.iter().filter(|v| select.is_empty() || select.contains(&v.id)).count();
    per_plan * variants.max(1) as u128
}

/// Refuse a `--variant` the pipeline does not declare (with the closest id it does).
fn check_selection(loaded: &LoadedProgram, select: &[String]) -> anyhow::Result<()> {
    let variants = &loaded.decl.variants;
    let origin = loaded.origin();
    if variants.is_empty() && !select.is_empty() {
        return Err(user_error(format!(
            "--variant {}: {origin} declares no variants; remove --variant",
            select[0]
        )));
    }
    for id in select {
        if !variants.iter().any(|v| &v.id == id) {
            let ids: Vec<&str> = variants.iter().map(|v| v.id.as_str()).collect();
            let hint = suggest(id, ids.iter().copied())
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

/// What expanding an experiment needs: the pipeline, its params and the trials' identity.
struct Grid<'a> {
    decl: &'a ProgramDecl,
    params: &'a [(String, ParamType)],
    identity: &'a Identity,
}

impl Grid<'_> {
    /// Every experiment with `defaults` as the params' defaults, tagged with `variant`.
    fn expand(&self, defaults: &[ParamValue], variant: Option<&str>, out: &mut Vec<ProgramExperiment>) {
        for e in &self.decl.experiments {
            let cells = self
                .cells(e, defaults)
                .into_iter()
                .map(|(params, coords)| {
                    let trials = self
                        .decl
                        .seeds
                        .iter()
                        .map(|&seed| ProgramTrial {
                            seed,
                            key: self.identity.key(self.params, &params, seed),
                        })
                        .collect();
                    ProgramCell { params, coords, trials, contender: None, fresh: Vec::new() }
                })
                .collect();
            out.push(ProgramExperiment {
                variant: variant.map(String::from),
                id: e.id.clone(),
                title: e.title.clone(),
                axes: e.axes.iter().map(|(n, _)| n.clone()).collect(),
                fixed: e.fixed.clone(),
                race: e.race,
                fresh: self.decl.fresh.clone(),
                cells,
            });
        }
    }

    /// The key of each cell's first-seed trial over every experiment with `defaults`: two
    /// cells with the same such key have the same params, so the same trials.
    fn cell_keys(&self, defaults: &[ParamValue]) -> HashSet<Key> {
        let Some(&seed) = self.decl.seeds.first() else { return HashSet::new() };
        self.decl
            .experiments
            .iter()
            .flat_map(|e| self.cells(e, defaults))
            .map(|(params, _)| self.identity.key(self.params, &params, seed))
            .collect()
    }

    /// The cells of `e`: each one's params (in the plan's param order) and coordinates, the
    /// product of the axes with the first outermost.
    fn cells(&self, e: &ExperimentDecl, defaults: &[ParamValue]) -> Vec<(Vec<ParamValue>, Vec<ParamValue>)> {
        let index = |name: &str| self.params.iter().position(|(n, _)| n == name).expect("a checked param");
        let mut base = defaults.to_vec();
        for (name, v) in &e.fixed {
            base[index(name)] = v.clone();
        }
        let slots: Vec<usize> = e.axes.iter().map(|(n, _)| index(n)).collect();
        let mut out = Vec::with_capacity(e.cell_count().min(1 << 20) as usize);
        let mut at = vec![0usize; e.axes.len()];
        loop {
            let coords: Vec<ParamValue> =
                e.axes.iter().zip(&at).map(|((_, vals), &i)| vals[i].clone()).collect();
            let mut params = base.clone();
            for (slot, v) in slots.iter().zip(&coords) {
                params[*slot] = v.clone();
            }
            out.push((params, coords));
            // Odometer: the last axis turns fastest, so the first is outermost.
            let mut k = at.len();
            loop {
                if k == 0 {
                    return out;
                }
                k -= 1;
                at[k] += 1;
                if at[k] < e.axes[k].1.len() {
                    break;
                }
                at[k] = 0;
            }
        }
    }
}

#[cfg(test)]
mod tests;
