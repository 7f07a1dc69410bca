//! What a report is asked to do ([`ReportOptions`]) and what it did ([`ReportWritten`]).

use crate::formats::Formats;
use crate::memo::stats::MemoCounts;
use crate::render::folder::ReportSummary;
use crate::stage::manifest::Counts;
use std::path::PathBuf;

/// How to write a pipeline's report.
#[derive(Debug, Clone)]
pub struct ReportOptions {
    /// The report directory (`reports/<name>` unless `--out`).
    pub dir: PathBuf,
    /// Which files to write.
    pub formats: Formats,
    /// Replace a kept report even when the new one holds fewer trials.
    pub force: bool,
    /// Ignore the folders' memos: recompute every folder (`--rebuild`).
    pub rebuild: bool,
}

/// What the stage wrote.
#[derive(Debug, Clone)]
pub struct ReportWritten {
    /// Counts over the whole plan and every file written (relative to the directory).
    pub summary: ReportSummary,
    /// The whole plan's distinct-trial counts.
    pub counts: Counts,
    /// One line per replaced folder whose contents changed: `DIR: 216 trials, 24 cells → 144
    /// trials, 16 cells`.
    pub replaced: Vec<String>,
    /// Files of the kept reports that this one no longer writes, removed.
    pub removed: Vec<PathBuf>,
    /// Files (manifests included) whose bytes changed or that were new: written.
    pub files_written: usize,
    /// Files whose bytes would not change: left alone, their mtimes kept.
    pub files_unchanged: usize,
    /// Cells whose statistics were computed (those of every folder or variant not skipped).
    pub cells_recomputed: usize,
    /// Cells of the folders skipped as their memos say (nothing read, nothing computed).
    pub cells_reused: usize,
    /// Bootstrap intervals and claim sets computed, and taken from the statistics' memo
    /// ([`crate::memo::stats::StatsMemo`]), by the folders recomputed.
    pub statistics: MemoCounts,
    /// What went wrong without failing the report (the statistics' memo could not be saved).
    pub warnings: Vec<String>,
}

impl ReportWritten {
    /// Nothing written yet, of a plan with these counts.
    pub(super) fn empty(counts: Counts) -> Self {
        Self {
            summary: ReportSummary::default(),
            counts,
            replaced: Vec::new(),
            removed: Vec::new(),
            files_written: 0,
            files_unchanged: 0,
            cells_recomputed: 0,
            cells_reused: 0,
            statistics: MemoCounts::default(),
            warnings: Vec::new(),
        }
    }
}
