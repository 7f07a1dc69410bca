//! `exploratory:`: a search over variants that keeps its fit honest. The Table III rows named in
//! `fit_rows` choose the best variant; every other row with a reference is held out and only
//! judged, after the choice.
//!
//! ```yaml
//! exploratory:
//!   fit_rows:
//!     - { system: ball-beam, experiment: 1, algorithm: q0 }
//!     - { system: ball-beam, experiment: 2 }        # both algorithms of experiment 2
//! ```
//!
//! A row names a system, and optionally an experiment id and an algorithm (all of them when left
//! out). Checked against the pipeline: each entry must name rows that exist and carry a
//! `reference:` (a fit needs one), and at least one row with a reference must be held out.

use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;
use serde::{Deserialize, Deserializer};

/// The `exploratory:` block.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Exploratory {
    /// The rows that choose the variant; the rest are held out.
    pub fit_rows: Vec<RowSelector>,
}

/// Some Table III rows: a system, optionally one experiment and one algorithm.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RowSelector {
    /// The system.
    pub system: SystemKind,
    /// An experiment id (all of the system's when absent).
    #[serde(default, deserialize_with = "opt_id")]
    pub experiment: Option<String>,
    /// An algorithm (both when absent).
    #[serde(default)]
    pub algorithm: Option<Algorithm>,
}

fn opt_id<'de, D: Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Id {
        N(u64),
        S(String),
    }
    Ok(Some(match Id::deserialize(d)? {
        Id::N(n) => n.to_string(),
        Id::S(s) => s,
    }))
}

impl RowSelector {
    /// Whether the Table III row (system, experiment id, algorithm) is one of these.
    pub fn matches(&self, system: SystemKind, experiment: &str, algorithm: Algorithm) -> bool {
        self.system == system
            && self.experiment.as_deref().is_none_or(|e| e == experiment)
            && self.algorithm.is_none_or(|a| a == algorithm)
    }

    /// As written in messages: `ball-beam exp 1 q0`.
    pub fn label(&self) -> String {
        format!(
            "{}{}{}",
            self.system,
            self.experiment.as_ref().map(|e| format!(" exp {e}")).unwrap_or_default(),
            self.algorithm.map(|a| format!(" {}", a.name())).unwrap_or_default()
        )
    }
}

impl Exploratory {
    /// Whether a row is a fit row (else, with a reference, it is held out).
    pub fn is_fit_row(&self, system: SystemKind, experiment: &str, algorithm: Algorithm) -> bool {
        self.fit_rows.iter().any(|r| r.matches(system, experiment, algorithm))
    }
}
