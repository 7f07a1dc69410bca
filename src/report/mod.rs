//! The report stage: from a plan and the trial records found for it, write Table III, the data
//! behind it and the paper's Figures 5–7.

pub mod figures;
pub mod glyphs;
pub mod model;
pub mod parquet;
pub mod stats;
pub mod table;

pub use model::ReportData;
