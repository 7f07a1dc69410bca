//! Crisp discretisation: `n` bins per variable over `[lo, hi]`, placed by a [`Binning`] rule; values
//! outside the range fall into the edge bins. The state's bin tuple is one table row (weight 1).
//!
//! `midpoint` (the default) splits `[lo, hi]` into `n` equal bins: edges at `lo + k (hi − lo) / n`,
//! k = 1..n−1 (2 bins of a symmetric range split at 0). This is also what tutorials that write
//! `np.digitize(x, np.linspace(lo, hi, n + 1)[1:-1])` get.
//!
//! `digitize` is the other common tutorial convention, `np.digitize(x, np.linspace(lo, hi, n)) - 1`
//! ("np.digitize is 1-indexed, so subtract one"), clipped to the n bins `0..n−1`: its edges are
//! `np.linspace(lo, hi, n)[1:]`, i.e. `lo + k (hi − lo) / (n − 1)`, k = 1..n−1 (the last is `hi`).
//! So bin 0 is everything below the second grid point, and the top bin holds only `x ≥ hi`:
//! over [−2, 2], 4 bins are (−∞, −2/3), [−2/3, 2/3), [2/3, 2), [2, ∞), and 2 bins split at 2.
//! (Python code that forgets the clip indexes −1 for `x < lo`, which wraps to the top bin; qsweep
//! clips it to bin 0 instead.) The variant `min(np.digitize(x, np.linspace(lo, hi, n)), n - 1)`,
//! without the `- 1`, is this one mirrored (edges `linspace(lo, hi, n)[:-1]`); for the paper's
//! symmetric ranges, start states and action sets the two give the same results up to mirroring.

use super::activation::{strides, Activations, Encode, OneHot, Representation};
use serde::{Deserialize, Serialize};

/// Where crisp bin edges lie (see the module documentation for the exact edges).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Binning {
    /// `n` equal bins over `[lo, hi]` (2 bins of a symmetric range split at 0).
    #[default]
    Midpoint,
    /// `np.digitize(x, np.linspace(lo, hi, n)) - 1` clipped to `0..n−1`: inner edges
    /// `np.linspace(lo, hi, n)[1:]` (2 bins split at `hi`).
    Digitize,
}

impl Binning {
    /// Whether this is the default (left out of the canonical JSON).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// YAML / command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Midpoint => "midpoint",
            Self::Digitize => "digitize",
        }
    }
}

/// Crisp bins per state variable.
#[derive(Debug, Clone)]
pub struct Crisp {
    /// One per state variable, together so that a step reads each variable's bin rule from one
    /// place (no bounds check per field).
    axes: Vec<Axis>,
    binning: Binning,
    n_features: usize,
}

/// One state variable's bins.
#[derive(Debug, Clone)]
struct Axis {
    lo: f64,
    /// `n / (hi − lo)`: bins per unit.
    scale: f64,
    /// The top bin, `n − 1`.
    top: u32,
    /// Row-major stride of this variable's bin in the feature index.
    stride: u32,
    /// `digitize` only: the inner edges, ascending (empty for `midpoint`).
    edges: Vec<f64>,
}

impl Axis {
    #[inline(always)]
    fn bin(&self, value: f64, binning: Binning) -> u32 {
        if binning == Binning::Digitize {
            // np.digitize(x, linspace)[right=False] − 1, clipped at 0: the number of inner edges
            // ≤ x. A NaN compares false everywhere and lands in bin 0.
            return self.edges.partition_point(|&e| e <= value) as u32;
        }
        let t = (value - self.lo) * self.scale;
        // Negative, NaN and too-large values land in the edge bins. For t ≥ 0 the saturating cast
        // truncates, which is floor; and floor(t) ≥ 0 exactly when t ≥ 0. So this is bin =
        // floor(t) without a call to `floor` (a library call on baseline x86-64, which lacks SSE4.1).
        if t >= 0.0 {
            (t as u32).min(self.top)
        } else {
            0
        }
    }
}

impl Crisp {
    /// Equal (`midpoint`) bins per variable over the given `[lo, hi]` ranges (lo < hi, bins ≥ 1).
    pub fn new(bins: &[u32], ranges: &[[f64; 2]]) -> Self {
        Self::with_binning(bins, ranges, Binning::Midpoint)
    }

    /// Bins per variable over the given `[lo, hi]` ranges (lo < hi, bins ≥ 1), placed by `binning`.
    pub fn with_binning(bins: &[u32], ranges: &[[f64; 2]], binning: Binning) -> Self {
        assert_eq!(bins.len(), ranges.len());
        let axes = ranges
            .iter()
            .zip(bins)
            .zip(strides(bins))
            .map(|((r, &n), stride)| Axis {
                lo: r[0],
                scale: f64::from(n) / (r[1] - r[0]),
                top: n - 1,
                stride,
                edges: match binning {
                    Binning::Midpoint => Vec::new(),
                    Binning::Digitize => linspace(r[0], r[1], n)[1..].to_vec(),
                },
            })
            .collect();
        let n_features = bins.iter().map(|&b| b as usize).product();
        Self { axes, binning, n_features }
    }

    /// The upper edges of bins 0..n−2 of one variable (bin k is `[edge k−1, edge k)`).
    pub fn edges(&self, var: usize) -> Vec<f64> {
        let a = &self.axes[var];
        match self.binning {
            Binning::Digitize => a.edges.clone(),
            Binning::Midpoint => (1..=a.top).map(|k| a.lo + f64::from(k) / a.scale).collect(),
        }
    }

    /// Bin of one variable's value.
    #[inline(always)]
    pub fn bin(&self, var: usize, value: f64) -> u32 {
        self.axes[var].bin(value, self.binning)
    }

    /// The one feature (table row) `state` activates.
    #[inline(always)]
    pub fn feature(&self, state: &[f64]) -> u32 {
        let mut index = 0;
        for (a, &v) in self.axes.iter().zip(state) {
            index += a.stride * a.bin(v, self.binning);
        }
        index
    }
}

/// `np.linspace(lo, hi, n)` as numpy computes it: `lo + k·step` with `step = (hi − lo)/(n − 1)`,
/// the last point set to `hi` exactly.
fn linspace(lo: f64, hi: f64, n: u32) -> Vec<f64> {
    if n == 1 {
        return vec![lo];
    }
    let step = (hi - lo) / f64::from(n - 1);
    let mut v: Vec<f64> = (0..n).map(|k| f64::from(k) * step + lo).collect();
    v[n as usize - 1] = hi;
    v
}

impl Representation for Crisp {
    fn n_features(&self) -> usize {
        self.n_features
    }

    fn max_active(&self) -> usize {
        1
    }

    #[inline(always)]
    fn activate(&self, state: &[f64], out: &mut Activations) {
        out.clear();
        out.index.push(self.feature(state));
        out.weight.push(1.0);
    }
}

impl Encode for Crisp {
    type Active = OneHot;

    #[inline(always)]
    fn encode(&self, state: &[f64], out: &mut OneHot) {
        *out = OneHot(self.feature(state));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_and_out_of_range_values_fall_in_edge_bins() {
        let c = Crisp::new(&[3], &[[-1.0, 1.0]]);
        assert_eq!(c.bin(0, -5.0), 0);
        assert_eq!(c.bin(0, -1.0), 0);
        assert_eq!(c.bin(0, -0.34), 0);
        assert_eq!(c.bin(0, 0.0), 1);
        assert_eq!(c.bin(0, 0.34), 2);
        assert_eq!(c.bin(0, 1.0), 2);
        assert_eq!(c.bin(0, 9.0), 2);
    }

    #[test]
    fn digitize_edges_are_the_linspace_grid_without_its_first_point() {
        // np.linspace(-2, 2, 4) = [-2, -2/3, 2/3, 2]; np.digitize(x, ·) - 1, clipped to 0..3.
        let c = Crisp::with_binning(&[4], &[[-2.0, 2.0]], Binning::Digitize);
        let third = -2.0 + 4.0 / 3.0; // numpy's second point: 1·step + lo
        assert_eq!(c.edges(0), vec![third, 2.0 * (4.0 / 3.0) - 2.0, 2.0]);
        for (x, bin) in [
            (-9.0, 0), // below lo: Python's −1 would wrap to bin 3; clipped to 0
            (-2.0, 0),
            (-0.67, 0),
            (third, 1), // np.digitize is right-open: an edge belongs to the bin above
            (0.0, 1),
            (0.66, 1),
            (0.67, 2),
            (1.99, 2),
            (2.0, 3), // only x ≥ hi reaches the top bin
            (9.0, 3),
            (f64::NAN, 0),
        ] {
            assert_eq!(c.bin(0, x), bin, "x = {x}");
        }
        // Two bins: np.linspace(lo, hi, 2) = [lo, hi], so the split is at hi.
        let c = Crisp::with_binning(&[2, 1], &[[-2.0, 2.0], [0.0, 1.0]], Binning::Digitize);
        assert_eq!(c.edges(0), vec![2.0]);
        assert_eq!(c.edges(1), Vec::<f64>::new());
        assert_eq!((c.bin(0, 1.999), c.bin(0, 2.0), c.bin(1, 5.0), c.bin(1, -5.0)), (0, 1, 0, 0));
        // Three bins over the paper's Cart-Pole θ range: edges at 0 and at θ_max.
        let th = 12.0 * 2.0 * std::f64::consts::PI / 360.0;
        let c = Crisp::with_binning(&[3], &[[-th, th]], Binning::Digitize);
        assert_eq!(c.edges(0), vec![0.0, th]);
        assert_eq!((c.bin(0, -1e-9), c.bin(0, 0.0), c.bin(0, th * 0.999)), (0, 1, 1));
    }

    #[test]
    fn midpoint_edges_split_symmetric_ranges_at_zero() {
        let c = Crisp::new(&[2, 4], &[[-2.0, 2.0], [-2.0, 2.0]]);
        assert_eq!(c.edges(0), vec![0.0]);
        assert_eq!(c.edges(1), vec![-1.0, 0.0, 1.0]);
        assert_eq!((c.bin(0, -1e-12), c.bin(0, 0.0)), (0, 1));
    }

    #[test]
    fn the_one_hot_encoding_is_the_activation_list_of_weight_one() {
        for binning in [Binning::Midpoint, Binning::Digitize] {
            let c = Crisp::with_binning(&[4, 3], &[[-2.0, 2.0], [-1.0, 1.0]], binning);
            let values = [f64::NAN, f64::NEG_INFINITY, -9.0, -2.0, -0.5, 0.0, 1e-12, 0.9, 2.0, 9.0];
            let mut list = Activations::default();
            let mut hot = OneHot::default();
            for &x in &values {
                for &v in &values {
                    c.activate(&[x, v], &mut list);
                    c.encode(&[x, v], &mut hot);
                    assert_eq!((list.index.as_slice(), list.weight.as_slice()), (&[hot.0][..], &[1.0][..]));
                }
            }
        }
    }

    #[test]
    fn fig4_cell_is_one_state_of_six() {
        // Fig. 4a: x ∈ [−1, 1] in 2 bins, ẋ ∈ [−1, 1] in 3 bins; x ∈ [0,1], ẋ ∈ [−1/3,1/3] is one cell.
        let c = Crisp::new(&[2, 3], &[[-1.0, 1.0], [-1.0, 1.0]]);
        assert_eq!(c.n_features(), 6);
        let mut a = Activations::default();
        let mut seen = std::collections::BTreeSet::new();
        for x in [0.01, 0.5, 0.99] {
            for v in [-0.3, 0.0, 0.3] {
                c.activate(&[x, v], &mut a);
                assert_eq!(a.weight, vec![1.0]);
                seen.insert(a.index[0]);
            }
        }
        assert_eq!(seen.into_iter().collect::<Vec<_>>(), vec![4]);
    }
}
