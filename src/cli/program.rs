//! The commands on a program pipeline (a file that declares `program:`; docs/programs.md):
//! `dispatch` (cli/mod.rs) sends `run`, `status`, `report` and `slurm` of such a pipeline here,
//! and `verify` and `gc` call in for their program parts; this file loads and plans the pipeline,
//! then calls the library (`qsweep_pipeline::program`, the report's `stage::program`) and prints.
//! It takes the commands' arguments from their files, which never import it back.

use super::pipeline_args::{unwritable, CacheArgs, PipelineArgs};
use super::report::ReportArgs;
use super::run::RunArgs;
use super::slurm::SlurmArgs;
use super::status::StatusArgs;
use qsweep_pipeline::declared::Override;
use qsweep_pipeline::error::{exit, user_error};
use qsweep_pipeline::exec::{ExecOptions, Reporter, INTERRUPTED};
use qsweep_pipeline::program::model::ProgramPlan;
use qsweep_pipeline::program::race::{ProgramReplayed, RaceStanding};
use qsweep_pipeline::program::rows::RowSchema;
use qsweep_pipeline::program::runner::RunnerOptions;
use qsweep_pipeline::program::status::ProgramStatus;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Whether the pipeline file of `a` declares `program:` (an unreadable file is not: the engine's
/// loader says why).
pub fn is_program(a: &PipelineArgs) -> bool {
    is_program_file(&a.pipeline)
}

/// Whether the pipeline file at `path` declares `program:`.
pub fn is_program_file(path: &Path) -> bool {
    std::fs::read_to_string(path).is_ok_and(|t| qsweep_pipeline::program::declared::is_program(&t))
}

/// The arguments of a pipeline given by its path alone (`verify`, `gc`): no overrides, every
/// variant, no size confirmation.
pub fn bare(pipeline: &Path, cache: &CacheArgs) -> PipelineArgs {
    PipelineArgs {
        pipeline: pipeline.to_path_buf(),
        set: vec![],
        variant: vec![],
        cache: cache.clone(),
        yes: true,
    }
}

/// Load, override and plan the program pipeline of `a`, in the working directory (where its
/// inputs are globbed and its provenance run).
pub fn plan(a: &PipelineArgs) -> anyhow::Result<ProgramPlan> {
    let overrides =
        a.set.iter().map(|s| Override::parse(s).map_err(user_error)).collect::<Result<Vec<_>, _>>()?;
    let loaded = qsweep_pipeline::program::declared::load(&a.pipeline, &overrides)?;
    let base = std::env::current_dir()?;
    let max = (!a.yes).then_some(qsweep_pipeline::plan::DEFAULT_MAX_TRIALS);
    let plan = qsweep_pipeline::program::plan::plan(&loaded, &base, max, &a.variant)?;
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    Ok(plan)
}

/// How programs are run: under this binary's `__supervise`, so none outlives qsweep.
fn runner_options() -> RunnerOptions {
    RunnerOptions { supervisor: std::env::current_exe().ok(), ..RunnerOptions::default() }
}

/// `qsweep run` on a program pipeline.
pub fn run(a: RunArgs) -> anyhow::Result<u8> {
    let start = Instant::now();
    let plan = plan(&a.pipeline)?;
    let cache = a.pipeline.cache.program_dir()?;
    let store = qsweep_pipeline::program::run::store(&cache, &plan).map_err(|e| unwritable(&cache, &e))?;
    super::run::install_ctrlc("ending the running programs (they run next time)");
    let opts = ExecOptions {
        jobs: a.jobs.unwrap_or_else(|| ExecOptions::default().jobs).max(1),
        batch_trials: a.batch_trials.max(1),
        batch_interval: std::time::Duration::from_secs_f64(a.batch_seconds.clamp(0.0, 1e9)),
        leases: Some(super::run::leases(&store)?),
        ..ExecOptions::default()
    };
    let sel = qsweep_pipeline::program::run::Selection {
        shard: a.shard,
        force: a.force,
        retry_failed: a.retry_failed,
    };
    let mut bar = super::progress::ProgressReporter::default();
    let reporter: &mut dyn Reporter = if a.quiet || a.json { &mut () } else { &mut bar };
    let staged =
        qsweep_pipeline::program::run::run_stages(&plan, &store, sel, &opts, &runner_options(), reporter)?;
    let done = &staged.summary;
    let report = &done.exec.exec;
    let unfinished = done.exec.unfinished.len();
    let seconds = start.elapsed().as_secs_f64();
    let v = crate::json::RunSummary {
        format_version: crate::json::RunSummary::FORMAT_VERSION,
        pipeline: plan.name.clone(),
        executed: report.executed,
        cached: done.cached,
        elsewhere: report.elsewhere,
        failed: report.failed,
        unfinished: Some(unfinished),
        interrupted: report.interrupted,
        seconds,
    };
    super::run::print_summary(&v, a.json, a.quiet)?;
    if report.interrupted || INTERRUPTED.load(Ordering::Relaxed) {
        if !a.quiet {
            eprintln!("interrupted: {} finished trials are stored; run again to continue", report.executed);
        }
        return Ok(exit::INTERRUPTED);
    }
    for (key, why) in done.exec.unfinished.iter().take(5) {
        eprintln!("did not finish: trial {} ({why}); it runs next time", &key.hex()[..16]);
    }
    if unfinished > 0 {
        eprintln!("{unfinished} trials did not finish (timed out or killed): nothing stored for them; they run next time");
    }
    if report.failed > 0 {
        eprintln!(
            "{} trials failed: their rows say why (`error`, `exit_code`, `stderr_tail` in trials.parquet); rerun them with --retry-failed",
            report.failed
        );
    }
    if !a.no_report {
        let dir = report_dir(&plan, a.report.out.as_deref());
        let written = write_report(&staged.replayed, Some(&store), &dir, false)?;
        if !(a.quiet || a.json) {
            print_report(&dir, &written);
        }
    }
    Ok(if report.failed > 0 || unfinished > 0 { exit::FAILURE } else { exit::OK })
}

/// The report directory of `plan`: `--out`, else `reports/<name>`.
fn report_dir(plan: &ProgramPlan, out: Option<&Path>) -> PathBuf {
    out.map_or_else(|| Path::new("reports").join(&plan.name), Path::to_path_buf)
}

/// Write the report of the `replayed` plan into `dir` from its schema folder's `store` (`None`:
/// no rows yet).
fn write_report(
    replayed: &ProgramReplayed,
    store: Option<&qsweep_pipeline::cache::Store>,
    dir: &Path,
    force: bool,
) -> anyhow::Result<qsweep_report::stage::program::ProgramReport> {
    let plan = &replayed.plan;
    let schema = qsweep_pipeline::program::run::schema(plan);
    let rows = qsweep_pipeline::program::stored::plan_rows(plan, store)?;
    qsweep_report::stage::program::write(replayed, &schema, &rows, dir, force)
}

/// `plan` replayed against the rows of `store` (its race's rounds, its fresh seeds).
fn replayed(
    plan: ProgramPlan,
    store: Option<&qsweep_pipeline::cache::Store>,
) -> anyhow::Result<ProgramReplayed> {
    qsweep_pipeline::program::race::replay_store(plan, store)
}

/// The report's closing line.
fn print_report(dir: &Path, r: &qsweep_report::stage::program::ProgramReport) {
    println!(
        "report: {} ({} of {} planned trials present, {} failed)",
        dir.join("README.md").display(),
        r.present,
        r.planned,
        r.failed
    );
}

/// The store folder of `plan`'s rows in the cache of `cache`, if it exists (nothing is created).
pub fn existing_folder(
    cache: &CacheArgs,
    plan: &ProgramPlan,
) -> anyhow::Result<Option<qsweep_pipeline::cache::Store>> {
    let dir = qsweep_pipeline::program::rows::folder(
        &cache.program_dir()?,
        &qsweep_pipeline::program::run::schema(plan),
    );
    dir.is_dir().then(|| qsweep_pipeline::cache::Store::open(&dir)).transpose().map_err(Into::into)
}

/// `qsweep report` on a program pipeline: `trials.parquet` and `README.md`
/// (`qsweep_report::stage::program`).
pub fn report(a: ReportArgs) -> anyhow::Result<u8> {
    let start = Instant::now();
    super::report::install_ctrlc();
    let plan = plan(&a.pipeline)?;
    a.pipeline.cache.required_store()?;
    let dir = report_dir(&plan, a.report.out.as_deref());
    let store = existing_folder(&a.pipeline.cache, &plan)?;
    let replayed = replayed(plan, store.as_ref())?;
    let plan = &replayed.plan;
    let written = write_report(&replayed, store.as_ref(), &dir, a.force)?;
    if a.json {
        let v = crate::json::ReportJson {
            format_version: crate::json::ReportJson::FORMAT_VERSION,
            pipeline: plan.name.clone(),
            dir: dir.display().to_string(),
            cells_recomputed: plan.experiments.iter().map(|e| e.cells.len()).sum(),
            cells_reused: 0,
            intervals_computed: written.intervals,
            intervals_reused: 0,
            files_written: written.written,
            files_unchanged: written.files.len() - written.written,
            seconds: start.elapsed().as_secs_f64(),
        };
        println!("{}", serde_json::to_string(&v)?);
    } else if !a.quiet {
        print_report(&dir, &written);
    }
    Ok(exit::OK)
}

/// `qsweep status` on a program pipeline: its distinct trials stored as succeeded, as failed,
/// and missing, per experiment; with `--explain`, why each cell's trials are missing.
pub fn status(a: StatusArgs) -> anyhow::Result<u8> {
    let plan = plan(&a.pipeline)?;
    let cache = a.pipeline.cache.program_dir()?;
    let store = existing_folder(&a.pipeline.cache, &plan)?;
    let replayed = replayed(plan, store.as_ref())?;
    let plan = &replayed.plan;
    let s = qsweep_pipeline::program::status::status(plan, &cache, a.explain)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&status_json(plan, &s, &replayed.races))?);
    } else {
        print_status(plan, &s, &cache);
        print_races(plan, &replayed.races);
    }
    if let Some(cells) = &s.explanation {
        print_explanation(plan, cells);
    }
    Ok(exit::OK)
}

fn status_json(
    plan: &ProgramPlan,
    s: &ProgramStatus,
    races: &[RaceStanding],
) -> crate::json::ProgramStatusReport {
    crate::json::ProgramStatusReport {
        format_version: crate::json::ProgramStatusReport::FORMAT_VERSION,
        pipeline: plan.name.clone(),
        folder: s.folder.display().to_string(),
        trials: s.total.trials,
        cached: s.total.cached(),
        failed: s.total.failed,
        missing: s.total.missing(),
        running_elsewhere: s.running_elsewhere,
        experiments: plan
            .experiments
            .iter()
            .zip(&s.experiments)
            .map(|(e, n)| crate::json::ProgramStatusExperiment {
                variant: e.variant.clone(),
                experiment: e.id.clone(),
                cells: e.cells.len(),
                trials: n.trials,
                cached: n.cached(),
                failed: n.failed,
                missing: n.missing(),
            })
            .collect(),
        damaged_segments: s.damaged.len(),
        other_schemas: s.other_schemas.clone(),
        race: (!races.is_empty()).then(|| {
            races
                .iter()
                .map(|r| {
                    let e = &plan.experiments[r.experiment];
                    crate::json::ProgramStatusRace {
                        variant: e.variant.clone(),
                        experiment: e.id.clone(),
                        cells: r.cells,
                        rounds_done: r.rounds_done,
                        rounds_max: r.rounds_max,
                        finished: r.finished,
                        contenders: r.contenders,
                        trials: r.trials,
                        without_race: r.without_race,
                    }
                })
                .collect()
        }),
    }
}

/// The status table, in the engine's style (`status.rs`), with a `failed` column.
fn print_status(plan: &ProgramPlan, s: &ProgramStatus, cache: &Path) {
    let width = plan.variants.iter().map(|v| v.id.len()).max().map_or(0, |w| w.max(7) + 1);
    let ew = plan.experiments.iter().map(|e| e.id.len()).max().unwrap_or(0).max(4);
    if width > 0 {
        print!("{:<width$}", "variant");
    }
    println!(
        "{:<ew$} {:>6} {:>7} {:>7} {:>7} {:>8}",
        "exp", "cells", "trials", "cached", "failed", "missing"
    );
    for (e, n) in plan.experiments.iter().zip(&s.experiments) {
        if width > 0 {
            print!("{:<width$}", e.variant.as_deref().unwrap_or_default());
        }
        println!(
            "{:<ew$} {:>6} {:>7} {:>7} {:>7} {:>8}",
            e.id,
            e.cells.len(),
            n.trials,
            n.cached(),
            n.failed,
            n.missing()
        );
    }
    let t = &s.total;
    println!(
        "total: {} trials, {} cached ({} failed), {} missing{} (cache: {}{})",
        t.trials,
        t.cached(),
        t.failed,
        t.missing(),
        match s.running_elsewhere {
            0 => String::new(),
            n => format!(", {n} of them running elsewhere (another run on this cache)"),
        },
        cache.display(),
        if s.exists { String::new() } else { ", no rows of this pipeline yet".to_string() }
    );
    if t.failed > 0 {
        println!(
            "{} stored trials failed: their rows say why (`error`, `exit_code`, `stderr_tail` in trials.parquet); `qsweep run --retry-failed` runs them again",
            t.failed
        );
    }
    for d in &s.damaged {
        println!("damaged segment: {d}");
    }
    if !s.other_schemas.is_empty() {
        let folders: Vec<String> = s
            .other_schemas
            .iter()
            .map(|id| format!("{}/{id}", qsweep_pipeline::program::rows::PROGRAMS_DIR))
            .collect();
        println!(
            "no rows under this pipeline's schema ({}), but the cache holds program rows under {}: rows may be under another schema (a param's type or the metrics changed since they were stored)",
            s.folder.strip_prefix(cache).unwrap_or(&s.folder).display(),
            folders.join(", ")
        );
    }
}

/// One line per raced experiment: its rounds, contenders and trials so far against the full grid.
fn print_races(plan: &ProgramPlan, races: &[RaceStanding]) {
    for r in races {
        let e = &plan.experiments[r.experiment];
        println!(
            "race {}exp {}: {} of at most {} rounds decided{}, {} of {} cells contenders, {} trials so far of {} for the full grid",
            e.variant.as_deref().map(|v| format!("[{v}] ")).unwrap_or_default(),
            e.id,
            r.rounds_done,
            r.rounds_max,
            if r.finished { " (over)" } else { "" },
            r.contenders,
            r.cells,
            r.trials,
            r.without_race
        );
    }
}

/// One line per missing cell, then how many cells each reason explains when there are several.
fn print_explanation(plan: &ProgramPlan, cells: &[qsweep_pipeline::program::explain::MissingCell]) {
    let mut reasons: std::collections::BTreeMap<String, usize> = std::collections::BTreeMap::new();
    for m in cells {
        let e = &plan.experiments[m.experiment];
        let c = &e.cells[m.cell];
        let coords: Vec<String> = e.axes.iter().zip(&c.coords).map(|(a, v)| format!("{a}={v}")).collect();
        println!(
            "missing {}exp {} {} ({} of {} seeds): {}",
            e.variant.as_deref().map(|v| format!("[{v}] ")).unwrap_or_default(),
            e.id,
            coords.join(" "),
            m.missing,
            m.trials,
            m.reason
        );
        *reasons.entry(m.reason.to_string()).or_default() += 1;
    }
    if reasons.len() > 1 {
        println!("summary of reasons:");
        for (why, n) in reasons {
            println!("  {n} cells: {why}");
        }
    }
}

/// `qsweep verify PIPELINE --recompute N` on a program pipeline: rerun `n` of its stored
/// trials (drawn with `seed`) each in a fresh process and print each whose metrics differ;
/// whether all agree.
pub fn recompute(pipeline: &Path, cache: &CacheArgs, n: usize, seed: u64) -> anyhow::Result<bool> {
    let started = Instant::now();
    let plan = plan(&bare(pipeline, cache))?;
    let store = existing_folder(cache, &plan)?;
    let plan = replayed(plan, store.as_ref())?.plan;
    let scan = store.map(|s| s.keys()).transpose()?.unwrap_or_default();
    let threads = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    let r = qsweep_pipeline::program::verify::recompute(&plan, &scan, n, seed, threads, &runner_options())?;
    if n > 0 && r.checked == 0 {
        println!(
            "recompute: no stored trial of pipeline '{}' succeeded, nothing to recompute (`qsweep run` it first)",
            plan.name
        );
        return Ok(false);
    }
    for d in &r.differing {
        let params: Vec<String> = d.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
        println!(
            "differs: trial {} ({} seed={}): {}",
            &d.key.hex()[..16],
            params.join(" "),
            d.seed,
            d.what.join("; ")
        );
    }
    println!(
        "recomputed {} of {} stored trials of pipeline '{}' (draw seed {seed}), each in a fresh process, in {:.1} s: {}",
        r.checked,
        r.eligible,
        plan.name,
        started.elapsed().as_secs_f64(),
        if r.differing.is_empty() {
            format!("all {} agree with the stored rows", r.checked)
        } else {
            format!("{} differ from the stored rows", r.differing.len())
        }
    );
    Ok(r.differing.is_empty())
}

/// For `qsweep gc PIPELINES`: the keys each given program pipeline references, by the schema id
/// of its rows (two pipelines of one schema share a folder).
pub fn referenced_keys(
    pipelines: &[PathBuf],
    cache: &CacheArgs,
) -> anyhow::Result<HashMap<String, std::collections::HashSet<qsweep_pipeline::cache::Key>>> {
    let mut out: HashMap<String, std::collections::HashSet<_>> = HashMap::new();
    for p in pipelines {
        let plan = plan(&bare(p, cache))?;
        // A race's rounds and the fresh seeds are referenced too: replayed from the cache.
        let store = existing_folder(cache, &plan)?;
        let plan = replayed(plan, store.as_ref())?.plan;
        let schema: RowSchema = qsweep_pipeline::program::run::schema(&plan);
        out.entry(schema.id())
            .or_default()
            .extend(qsweep_pipeline::program::exec::jobs(&plan).iter().map(|j| j.key));
    }
    Ok(out)
}

/// `qsweep slurm` on a program pipeline: the same script (its tasks run `qsweep run --shard I/N`,
/// its report job `qsweep report`), the split counted by program keys.
pub fn slurm(a: SlurmArgs) -> anyhow::Result<u8> {
    let plan = plan(&a.pipeline)?;
    let report_dir = report_dir(&plan, a.out.as_deref());
    // One job array per possible stage (a race's rounds, the fresh seeds), as for the engine.
    let submission = super::slurm::submission(&a, &plan.name, (report_dir, "README.md"), plan.stages_max())?;
    print!("{}", submission.render()?);
    let store = existing_folder(&a.pipeline.cache, &plan)?;
    let plan = replayed(plan, store.as_ref())?.plan;
    let cached = match store {
        Some(store) => store.keys()?.keys,
        None => std::collections::HashSet::new(),
    };
    let per_shard = qsweep_pipeline::program::run::shard_counts(&plan, &cached, a.array);
    let distinct = qsweep_pipeline::program::exec::jobs(&plan).len();
    super::slurm::print_split(&plan.name, distinct, &per_shard, a.array);
    Ok(exit::OK)
}
