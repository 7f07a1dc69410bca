//! Comparison of a pipeline's variants (placeholder until the comparison report lands).

use super::ReportData;
use std::path::{Path, PathBuf};

/// A variant's identity in the comparison.
#[derive(Debug, Clone)]
pub struct VariantInfo {
    /// Identifier (report sub-folder).
    pub id: String,
    /// Title.
    pub title: Option<String>,
}

/// Write the comparison files into `dir`; returns the files written.
pub fn write_comparison(
    _dir: &Path,
    _variants: &[(VariantInfo, ReportData)],
) -> anyhow::Result<Vec<PathBuf>> {
    Ok(Vec::new())
}
