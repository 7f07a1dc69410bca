//! A variant's identity, as the pipeline declares it.

/// A variant's identity, as the pipeline declares it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VariantInfo {
    /// Identifier (also its report folder's name).
    pub id: String,
    /// Optional title.
    pub title: Option<String>,
    /// Declared exploratory: ranked after the declared variants, folder on demand.
    pub exploratory: bool,
}
