//! The replication of the paper, in its own room: everything that reads the paper's published
//! values or speaks of its study. The generic report ([`crate::derive`], [`crate::render`]) works
//! for any pipeline and never imports this module; the stage adds what this module makes.
//!
//! - [`stats`]: the statistics only the replication uses (equivalence, verdicts, consistency,
//!   claims, selection, survival);
//! - [`table3`]: Table III (best cell per system, experiment and algorithm, against the paper's
//!   values where the pipeline gives them), its files and its sections of a folder's pages;
//! - [`published`]: what the generic report data holds of the paper (published rows, the pairs
//!   they contradict, the cell at the paper's configuration, the claims' cells);
//! - [`judgement`]: one Table III row judged at one assumed number of paper runs;
//! - [`compare`]: the numbers of a comparison of variants (fit, verdicts, selection,
//!   consistency, conclusions, the forest's rows, what is kept of each variant);
//! - [`pages`]: the comparison's files, pages and figures (the answer, the forest plot, the
//!   difference figures).

pub mod compare;
pub mod judgement;
pub mod pages;
pub mod published;
pub mod stats;
pub mod table3;
