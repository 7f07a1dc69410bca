//! `qsweep slurm`: print a script that submits a pipeline to Slurm as a job array of shards plus
//! a report job that waits for it.

use super::pipeline_args::PipelineArgs;
use clap::Args;
use qsweep_pipeline::slurm::{memory, plain_text, sbatch_option, time_limit, Submission};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// Arguments of `qsweep slurm`.
#[derive(Debug, Args)]
#[command(after_help = "\
Example, on a login node with the cache on the shared filesystem:
  qsweep slurm pipelines/paper.yaml --array 16 --time 2:00:00 --cpus-per-task 8 > submit.sh
  bash submit.sh        # submits the array, then the report job (--dependency=afterok)
Running submit.sh again is safe: every task skips the trials already cached.")]
pub struct SlurmArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Number of array tasks N: task I runs `qsweep run --shard I/N`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub array: u32,
    /// Run at most M tasks at once (sbatch --array=1-N%M).
    #[arg(long, value_name = "M", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_running: Option<u32>,
    /// Slurm partition for both jobs.
    #[arg(long, value_parser = plain_text)]
    pub partition: Option<String>,
    /// Time limit per task and for the report job: minutes, HH:MM:SS or D-HH:MM:SS.
    #[arg(long, value_parser = time_limit)]
    pub time: Option<String>,
    /// CPUs per task; each task runs that many worker threads.
    #[arg(long, default_value_t = 1, value_name = "C", value_parser = clap::value_parser!(u32).range(1..))]
    pub cpus_per_task: u32,
    /// Memory per task and for the report job (sbatch --mem), e.g. 2G.
    #[arg(long, value_parser = memory)]
    pub mem: Option<String>,
    /// Slurm account to charge.
    #[arg(long, value_parser = plain_text)]
    pub account: Option<String>,
    /// Job name [default: qsweep-<pipeline name>]; the report job appends -report.
    #[arg(long, value_parser = plain_text)]
    pub job_name: Option<String>,
    /// Further sbatch option for both jobs, e.g. --sbatch-arg=--qos=long (repeatable).
    #[arg(long, value_name = "OPTION", allow_hyphen_values = true, value_parser = sbatch_option)]
    pub sbatch_arg: Vec<String>,
    /// Directory for the jobs' log files (created by the script).
    #[arg(long, default_value = "slurm-logs", value_name = "DIR")]
    pub log_dir: PathBuf,
    /// Report directory [default: reports/<pipeline name>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// The qsweep executable the jobs run [default: this one, by absolute path].
    #[arg(long, value_name = "PATH", value_parser = plain_text)]
    pub qsweep: Option<String>,
}

/// Run `qsweep slurm`: the script goes to stdout, a summary of the split to stderr.
pub fn run(a: SlurmArgs) -> anyhow::Result<u8> {
    // Plan now, so a broken pipeline fails here rather than in N jobs on the cluster.
    let plan = a.pipeline.plan()?;
    let report_dir = a.out.clone().unwrap_or_else(|| qsweep_report::default_dir(&plan));
    let submission = submission(&a, &plan.name, (report_dir, "index.html"), plan.stages_max())?;
    let script = submission.render()?;
    print!("{script}");

    let unique = qsweep_pipeline::exec::jobs(&plan);
    let cached: HashSet<_> = match a.pipeline.cache.existing_store()? {
        Some(store) => store.keys()?.keys,
        None => HashSet::new(),
    };
    let per_shard = qsweep_pipeline::run::shard_counts(&plan, &unique, &cached, a.array);
    print_split(&plan.name, unique.len(), &per_shard, a.array);
    if submission.rounds > 1 {
        eprintln!(
            "staged plan: up to {} stages (race rounds, fresh seeds), one job array each, each after the one \
             before (afterany); the counts above are the first stage's (each later one is planned from the \
             outcomes of the stages before)",
            submission.rounds
        );
    }
    Ok(qsweep_pipeline::error::exit::OK)
}

/// The submission of pipeline `name` as `a` asks, its report into `report.0` (its page
/// `report.1`), in `rounds` chained arrays (the engine's and a program's pipelines alike).
pub(super) fn submission(
    a: &SlurmArgs,
    name: &str,
    report: (PathBuf, &str),
    rounds: u32,
) -> anyhow::Result<Submission> {
    let (report_dir, report_page) = report;
    let workdir = std::env::current_dir()?;
    let abs = |p: &Path| -> anyhow::Result<PathBuf> { Ok(std::path::absolute(p)?) };
    let qsweep = match &a.qsweep {
        Some(q) => q.clone(),
        None => {
            let exe = std::env::current_exe()?;
            exe.to_str()
                .ok_or_else(|| anyhow::anyhow!("the path of this executable is not UTF-8; pass --qsweep"))?
                .to_string()
        }
    };
    Ok(Submission {
        pipeline_name: name.to_string(),
        generated_by: std::env::args_os()
            .map(|w| qsweep_pipeline::slurm::quote(&w.to_string_lossy()))
            .collect::<Vec<_>>()
            .join(" "),
        qsweep,
        pipeline: abs(&a.pipeline.pipeline)?,
        sets: a.pipeline.set.clone(),
        variants: a.pipeline.variant.clone(),
        yes: a.pipeline.yes,
        cache: match a.pipeline.cache.bucket() {
            Some(url) => PathBuf::from(url),
            None => abs(&a.pipeline.cache.dir())?,
        },
        report_dir: abs(&report_dir)?,
        report_page: report_page.to_string(),
        tasks: a.array,
        max_running: a.max_running,
        cpus_per_task: a.cpus_per_task,
        partition: a.partition.clone(),
        time: a.time.clone(),
        mem: a.mem.clone(),
        account: a.account.clone(),
        job_name: a.job_name.clone().unwrap_or_else(|| format!("qsweep-{name}")),
        log_dir: abs(&a.log_dir)?,
        sbatch_args: a.sbatch_arg.clone(),
        rounds,
        workdir,
    })
}

/// The split's summary on stderr: `distinct` trials of pipeline `name` in `tasks` shards
/// (`per_shard`), with warnings for idle tasks and Slurm's array limit.
pub(super) fn print_split(
    name: &str,
    distinct: usize,
    per_shard: &[qsweep_pipeline::run::ShardCount],
    tasks: u32,
) {
    let sizes = |f: fn(&qsweep_pipeline::run::ShardCount) -> usize| {
        let v: Vec<usize> = per_shard.iter().map(f).collect();
        (v.iter().min().copied().unwrap_or(0), v.iter().max().copied().unwrap_or(0))
    };
    let ((lo, hi), (mlo, mhi)) = (sizes(|p| p.trials), sizes(|p| p.missing));
    let missing: usize = per_shard.iter().map(|p| p.missing).sum();
    eprintln!(
        "pipeline '{name}': {distinct} distinct trials ({missing} not cached) in {tasks} shards of {lo}-{hi} trials \
         ({mlo}-{mhi} to run)"
    );
    if tasks as usize > distinct {
        eprintln!(
            "warning: {tasks} tasks for {distinct} trials: {} tasks will have nothing to run",
            tasks as usize - distinct
        );
    }
    if tasks > 1000 {
        eprintln!(
            "warning: Slurm's default MaxArraySize (1001) allows at most 1000 tasks; \
             check `scontrol show config | grep MaxArraySize`"
        );
    }
}
