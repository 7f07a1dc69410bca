//! Running a pipeline from the library alone, without the CLI or a terminal: load and plan
//! `tests/fixtures/pipelines/tiny.yaml`, run its trials into a fresh cache while collecting the execution's
//! events, then write its report. `cargo run --release --example library_run [CACHE_DIR]`.

use qsweep_pipeline::exec::{Event, ExecOptions};
use qsweep_pipeline::run::{run_trials, scan, Selection};
use qsweep_report::formats::{Format, Formats};
use qsweep_report::ReportOptions;

fn main() -> anyhow::Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let work = match std::env::args().nth(1) {
        Some(dir) => std::path::PathBuf::from(dir),
        None => std::env::temp_dir().join(format!("qsweep-example-{}", std::process::id())),
    };
    let loaded = qsweep_pipeline::declared::load(&root.join("tests/fixtures/pipelines/tiny.yaml"), &[])?;
    let plan = qsweep_pipeline::plan::plan(&loaded, None)?;
    let store = qsweep_pipeline::cache::Store::open(&work.join("cache"))?;
    let keys = scan(&store)?.stored;

    let mut events: Vec<Event> = Vec::new();
    let sel = Selection { shard: None, force: false };
    let done = run_trials(&plan, &store, &keys, sel, &ExecOptions::default(), &mut events)?;
    let finished = events.iter().filter(|e| matches!(e, Event::Finished { .. })).count();
    let flushes = events.iter().filter(|e| matches!(e, Event::Flushed { .. })).count();
    println!(
        "executed {}, cached {}; events: {} trials finished, {} batches stored, last {:?}",
        done.exec.executed,
        done.cached,
        finished,
        flushes,
        events.last()
    );

    let keys = scan(&store)?.stored;
    let opts = ReportOptions {
        dir: work.join("report"),
        formats: Formats::of(&[Format::Md, Format::Csv]),
        force: false,
        rebuild: false,
    };
    let report = qsweep_report::write(plan.clone(), &store, &keys, &opts)?;
    println!(
        "report: {} files in {} ({} of {} planned trials present)",
        report.summary.files.len(),
        opts.dir.display(),
        report.summary.trials_cached,
        report.summary.trials_planned
    );
    Ok(())
}
