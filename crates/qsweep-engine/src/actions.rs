//! Action sets A_n of eq. (22): n values evenly spaced between a system's fixed extremes.

/// The n action values `−max + k·2max/(n−1)`, k = 0..n−1 (eq. 22 with bounds ±max). Requires n ≥ 2.
pub fn action_set(max: f64, n: u32) -> Vec<f64> {
    assert!(n >= 2, "an action set needs at least two actions");
    let step = (max - -max) / f64::from(n - 1);
    (0..n).map(|k| -max + f64::from(k) * step).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_4;

    #[test]
    fn ball_beam_a3_is_the_papers_set() {
        assert_eq!(action_set(FRAC_PI_4, 3), vec![-FRAC_PI_4, 0.0, FRAC_PI_4]);
    }

    #[test]
    fn endpoints_and_spacing_match_eq_22() {
        for n in 2..=10 {
            let a = action_set(FRAC_PI_4, n);
            assert_eq!(a.len(), n as usize);
            assert_eq!(a[0], -FRAC_PI_4);
            assert!((a[n as usize - 1] - FRAC_PI_4).abs() < 1e-15);
            for (k, v) in a.iter().enumerate() {
                let eq22 = -FRAC_PI_4 + k as f64 * std::f64::consts::PI / (2.0 * f64::from(n - 1));
                assert!((v - eq22).abs() < 1e-15);
            }
        }
        assert_eq!(action_set(10.0, 2), vec![-10.0, 10.0]);
        assert_eq!(action_set(1.0, 3), vec![-1.0, 0.0, 1.0]);
    }
}
