//! Crisp discretisation: `n` uniform bins per variable over `[lo, hi]`; values outside the range
//! fall into the edge bin. The state's bin tuple is one table row (weight 1).

use super::{strides, Activations, Representation};

/// Uniform bins per state variable.
#[derive(Debug, Clone)]
pub struct Crisp {
    lo: Vec<f64>,
    scale: Vec<f64>,
    bins: Vec<u32>,
    strides: Vec<u32>,
    n_features: usize,
}

impl Crisp {
    /// Bins per variable over the given `[lo, hi]` ranges (lo < hi, bins ≥ 1).
    pub fn new(bins: &[u32], ranges: &[[f64; 2]]) -> Self {
        assert_eq!(bins.len(), ranges.len());
        let lo = ranges.iter().map(|r| r[0]).collect();
        let scale = ranges.iter().zip(bins).map(|(r, &n)| f64::from(n) / (r[1] - r[0])).collect();
        let n_features = bins.iter().map(|&b| b as usize).product();
        Self { lo, scale, bins: bins.to_vec(), strides: strides(bins), n_features }
    }

    /// Bin of one variable's value.
    #[inline(always)]
    pub fn bin(&self, var: usize, value: f64) -> u32 {
        let t = (value - self.lo[var]) * self.scale[var];
        // Negative, NaN and too-large values land in the edge bins. For t ≥ 0 the saturating cast
        // truncates, which is floor; and floor(t) ≥ 0 exactly when t ≥ 0. So this is bin =
        // floor(t) without a call to `floor` (a library call on baseline x86-64, which lacks SSE4.1).
        if t >= 0.0 {
            (t as u32).min(self.bins[var] - 1)
        } else {
            0
        }
    }

    /// The one feature (table row) `state` activates.
    #[inline(always)]
    pub fn feature(&self, state: &[f64]) -> u32 {
        let mut index = 0;
        for (j, &v) in state[..self.bins.len()].iter().enumerate() {
            index += self.strides[j] * self.bin(j, v);
        }
        index
    }
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
