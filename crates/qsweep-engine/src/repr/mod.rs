//! State representations (Section III-C): each maps a state to sparse feature activations
//! `(feature index, weight)`. A crisp bin is a one-hot "membership" of weight 1; a fuzzy rule base
//! activates several rules with normalised firing strengths (eqs. 9–11) that sum to 1.

mod activation;
mod crisp;
mod dense;
#[cfg(target_arch = "x86_64")]
mod dense_x86;
mod fuzzy;

pub(crate) use activation::strides;
pub use activation::{Activations, Encode, Features, GridView, OneHot, Representation, GRID};
pub use crisp::{Binning, Crisp};
pub use dense::{DenseActive, DenseFuzzy};
pub use fuzzy::{Fuzzy, HALF_CROSSING_WIDTH, MAX_SETS};

use serde::{Deserialize, Serialize};

/// Crisp bins or fuzzy sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ReprKind {
    /// Uniform bins per variable (tabular Q).
    Crisp,
    /// Gaussian fuzzy sets per variable, zero-order Takagi–Sugeno rule base.
    Fuzzy,
}

impl ReprKind {
    /// Command-line / YAML name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Crisp => "crisp",
            Self::Fuzzy => "fuzzy",
        }
    }
}
