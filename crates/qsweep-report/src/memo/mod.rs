//! The one owner of the report's derived results kept between reports, each addressed by content
//! so that a kept result is exactly what recomputation would give:
//!
//! - [`stats`]: the statistics' memo, `<cache>/_derived/<pipeline>.bin` (bootstrap intervals,
//!   difference intervals, claims), its file format, its check (`qsweep verify`) and its
//!   garbage collection (`qsweep gc`, which also sweeps the report's `.trials/` parts);
//! - [`parts`]: a comparison's `trials.parquet` assembled from one part per variant;
//! - [`folders`]: each report folder's `memo.json` (the digest of its inputs and of its files),
//!   which lets a rerun skip a folder whose inputs have not changed.
//!
//! Every id and digest mixes in [`ANALYSIS_VERSION`], so a change of definitions never reuses an
//! older result.

pub mod folders;
pub mod parts;
pub mod stats;

/// The version of the report's definitions: every statistic, every rule (counting, best cell,
/// intervals, claims) and every file's layout. **Bump it whenever a change to the code changes
/// any report output for the same plan and trials**: the memo then recomputes every folder
/// instead of keeping files an older definition wrote. The golden test
/// (`tests/cli/memo.rs::analysis_golden_*`) fails when the outputs of a fixed input change while
/// this does not.
pub const ANALYSIS_VERSION: u32 = 6;
