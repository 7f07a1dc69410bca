//! Any program as a trial: a pipeline that declares `program:` instead of the built-in systems runs
//! a researcher's own command once per (params, seed), keyed, cached, leased and reported like an
//! engine trial (docs/programs.md). Its parts, lowest first, each importing only those before it:
//!
//! - [`model`]: the types every part shares (params, metrics, the program, the plan, a result, a row);
//! - [`declared`]: the pipeline file (`program:`, `params:`, experiments, variants) read and checked,
//!   every error `FILE:LINE:COL`; [`inputs`]: the declared input files globbed and digested;
//!   [`provenance`]: the provenance commands run once per plan;
//! - [`key`]: a trial's key and the identity a row records; [`plan`]: the cells × seeds of every
//!   experiment (and variant), keyed; [`explain`]: why a planned trial is not in the cache;
//! - [`result`]: a result line parsed against the declared metrics, or why not (line and field);
//! - [`supervise`]: `qsweep __supervise`, every program's parent: its group dies with qsweep;
//! - `child`: one running program, its pipes, limits, deadline, kill and CPU time;
//! - [`runner`]: the process protocol (one process per trial) and how an ending becomes a result;
//! - [`worker`]: the worker protocol (one process per slot, one line per trial each way);
//! - [`rows`]: a pipeline's rows as typed Parquet in its schema's store folder of the cache;
//! - [`stored`]: what the cache holds of a pipeline, one row per key;
//! - [`folders`]: the program folders of a cache, and a segment's schema read back from its columns;
//! - [`race`]: the stages (`race:` rounds, `fresh:` seeds) replayed from the stored rows by the
//!   objective, with the engine's round (`crate::race::eliminate`);
//! - [`exec`]: running the missing trials on worker threads under leases, storing them in batches;
//! - [`run`]: one run of a pipeline: its store, the selection, the runners, the rows, stage by stage;
//! - [`status`]: what the cache holds of a plan (succeeded, failed, missing) and why trials are missing;
//! - [`verify`]: every program segment checked and re-hashed; a sample of trials rerun and compared;
//! - [`gc`]: each program folder compacted, and pruned by the program pipelines of its schema.

mod child;
pub mod declared;
pub mod exec;
pub mod explain;
pub mod folders;
pub mod gc;
pub mod inputs;
pub mod key;
pub mod model;
pub mod plan;
pub mod provenance;
pub mod race;
pub mod result;
pub mod rows;
pub mod run;
pub mod runner;
pub mod status;
pub mod stored;
pub mod supervise;
pub mod verify;
pub mod worker;
