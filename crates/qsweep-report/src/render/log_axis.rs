//! A logarithmic axis of ratios, for the figures that plot them (the replication's forest plot,
//! `qsweep compare`'s figure): its domain is what it must show widened to the 1-2-5 values around
//! it, within 10⁻³ to 10³ (beyond, a value sits on the edge), and its pixels come from the
//! engine's own logarithm, so a figure's bytes are the same on every machine.

use qsweep_engine::math::{exp, ln};

/// Values in `domain` onto the pixels `pixels` (left, right), logarithmically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogAxis {
    /// The smallest and largest value shown.
    pub domain: (f64, f64),
    /// The pixels of the domain's ends.
    pub pixels: (i32, i32),
}

impl LogAxis {
    /// The axis showing `start` (a range always shown, e.g. a margin) and every finite positive
    /// value of `values`, onto `pixels`.
    pub fn around(start: (f64, f64), values: impl IntoIterator<Item = f64>, pixels: (i32, i32)) -> Self {
        let (mut lo, mut hi) = start;
        for v in values {
            if v.is_finite() && v > 0.0 {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        let steps = one_two_five(1e-3, 1e3);
        let lo = steps.iter().rev().find(|&&s| s <= lo * (1.0 + 1e-9)).copied().unwrap_or(1e-3);
        let hi = steps.iter().find(|&&s| s >= hi * (1.0 - 1e-9)).copied().unwrap_or(1e3);
        Self { domain: (lo, hi), pixels }
    }

    /// The x pixel of `v`, clamped to the domain.
    pub fn x(&self, v: f64) -> i32 {
        let (a, b) = (ln(self.domain.0), ln(self.domain.1));
        let t = if v > 0.0 { ((ln(v.min(1e300)) - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
        self.pixels.0 + (t * f64::from(self.pixels.1 - self.pixels.0)).round() as i32
    }

    /// The value at x pixel `x` (the inverse of [`LogAxis::x`], up to rounding).
    pub fn value(&self, x: f64) -> f64 {
        let (a, b) = (ln(self.domain.0), ln(self.domain.1));
        exp(a + (x - f64::from(self.pixels.0)) / f64::from(self.pixels.1 - self.pixels.0) * (b - a))
    }

    /// The ticks: the 1-2-5 values in the domain.
    pub fn ticks(&self) -> Vec<f64> {
        one_two_five(self.domain.0, self.domain.1)
    }
}

/// 1, 2, 5 × 10^k within `[lo, hi]`, for k from −3 to 3.
pub fn one_two_five(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for decade in [1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3] {
        for m in [1.0, 2.0, 5.0] {
            let v = m * decade;
            if v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9) {
                out.push(v);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_domain_widens_to_1_2_5_values_and_pixels_invert() {
        let ax = LogAxis::around((0.8, 1.25), [0.3, f64::NAN, 0.0, 7.0], (100, 700));
        assert_eq!(ax.domain, (0.2, 10.0));
        assert_eq!(ax.ticks(), vec![0.2, 0.5, 1.0, 2.0, 5.0, 10.0]);
        assert_eq!((ax.x(0.2), ax.x(10.0), ax.x(1e9), ax.x(-1.0)), (100, 700, 700, 100));
        assert!((ax.value(f64::from(ax.x(1.0))) - 1.0).abs() < 0.01);
        assert_eq!(LogAxis::around((0.5, 2.0), [1e-9], (0, 1)).domain, (1e-3, 2.0));
    }
}
