//! Which vector instructions the learner's kernels and the fuzzy activation run with: the build's
//! baseline (SSE2 on x86-64), AVX2 or AVX-512, chosen once per process from what the CPU has, or
//! forced by `QSWEEP_SIMD`.
//!
//! The choice never changes a result. Only kernels whose every output is a fixed sequence of
//! IEEE-754 operations on its own inputs are dispatched (the dense trace pass, the Q(0) update,
//! the activation and the systems' steps in lockstep, element by element), or whose sums keep the
//! engine's order of additions whatever the register width (Q(s, ·): the same partial sums, each
//! in activation order). A vector lane does exactly what the scalar code does to that element, and
//! Rust never fuses a multiply and an add (no FMA) nor reassociates, so every level gives the same
//! bits (`learner::tests` and `pinned_tests` run every level the CPU has and compare).
//!
//! `QSWEEP_SIMD`: `off` (the baseline), `avx2`, `avx512` (each capped by what the CPU has) or
//! `auto` (the default: AVX2 where the CPU has it). AVX-512 is opt-in: on the 2-core Sapphire
//! Rapids VM it ran no faster than AVX2 in any measurement that noise let us read
//! (docs/speed.md), and some Intel CPUs lower their clock while 512-bit instructions run.

use std::sync::OnceLock;

/// The vector instructions a kernel may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Simd {
    /// What the build targets without run-time detection (SSE2 on x86-64, NEON on aarch64).
    Baseline,
    /// x86-64 AVX2 (256-bit vectors).
    Avx2,
    /// x86-64 AVX-512F (512-bit vectors).
    Avx512,
}

impl Simd {
    /// Name as `QSWEEP_SIMD` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Baseline => "off",
            Self::Avx2 => "avx2",
            Self::Avx512 => "avx512",
        }
    }

    /// Every level this CPU can run, narrowest first (always starts with `Baseline`).
    pub fn available() -> Vec<Simd> {
        let best = detected();
        [Self::Baseline, Self::Avx2, Self::Avx512].into_iter().filter(|&s| s <= best).collect()
    }

    /// This level, or the widest the CPU has if it lacks this one.
    pub fn capped(self) -> Simd {
        self.min(detected())
    }
}

/// The widest level this CPU has.
fn detected() -> Simd {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return Simd::Avx512;
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            return Simd::Avx2;
        }
    }
    Simd::Baseline
}

/// The level `QSWEEP_SIMD` asks for (`None`: auto), or an error naming the accepted values.
pub fn parse(value: &str) -> Result<Option<Simd>, String> {
    match value.trim().to_ascii_lowercase().as_str() {
        "" | "auto" => Ok(None),
        "off" | "0" | "none" | "baseline" => Ok(Some(Simd::Baseline)),
        "avx2" => Ok(Some(Simd::Avx2)),
        "avx512" | "avx-512" => Ok(Some(Simd::Avx512)),
        other => Err(format!("QSWEEP_SIMD={other:?}: expected off, avx2, avx512 or auto")),
    }
}

/// What `auto` picks: AVX2 where the CPU has it (AVX-512 only when asked for; see the module doc).
pub const AUTO: Simd = Simd::Avx2;

/// The level this process runs with: `QSWEEP_SIMD`, else [`AUTO`], capped by the CPU. An
/// unreadable `QSWEEP_SIMD` falls back to the baseline (it never changes a result) after one
/// warning on stderr.
pub fn level() -> Simd {
    static LEVEL: OnceLock<Simd> = OnceLock::new();
    *LEVEL.get_or_init(|| {
        let best = detected();
        match std::env::var("QSWEEP_SIMD").map(|v| parse(&v)) {
            Err(_) | Ok(Ok(None)) => AUTO.min(best),
            Ok(Ok(Some(want))) => want.min(best),
            Ok(Err(msg)) => {
                eprintln!("warning: {msg}; using the baseline");
                Simd::Baseline
            }
        }
    })
}

/// Define `$name(level, args…)` that runs the `#[inline(always)]` function `$body(args…)`
/// compiled for the given level: one copy per level, each with its vector width.
macro_rules! dispatch {
    ($(#[$doc:meta])* $vis:vis fn $name:ident => $body:ident ($($arg:ident : $ty:ty),* $(,)?)) => {
        $(#[$doc])*
        #[inline(always)]
        $vis fn $name(level: $crate::simd::Simd, $($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                fn avx512($($arg: $ty),*) {
                    $body($($arg),*)
                }
                #[target_feature(enable = "avx2")]
                fn avx2($($arg: $ty),*) {
                    $body($($arg),*)
                }
                match level {
                    // SAFETY: every `Simd` a kernel is given went through `Simd::capped` or
                    // `simd::level()`, both capped by what the CPU has.
                    $crate::simd::Simd::Avx512 => return unsafe { avx512($($arg),*) },
                    $crate::simd::Simd::Avx2 => return unsafe { avx2($($arg),*) },
                    $crate::simd::Simd::Baseline => {}
                }
            }
            let _ = level;
            $body($($arg),*)
        }
    };
}
pub(crate) use dispatch;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_accepts_the_documented_values_and_names_them_otherwise() {
        assert_eq!(parse("off"), Ok(Some(Simd::Baseline)));
        assert_eq!(parse("AVX2"), Ok(Some(Simd::Avx2)));
        assert_eq!(parse("avx512"), Ok(Some(Simd::Avx512)));
        assert_eq!(parse("auto"), Ok(None));
        assert_eq!(parse(""), Ok(None));
        let err = parse("sse9").unwrap_err();
        assert!(err.contains("off, avx2, avx512 or auto"), "{err}");
        for s in Simd::available() {
            assert_eq!(parse(s.name()), Ok(Some(s)));
        }
    }

    #[test]
    fn available_levels_start_at_the_baseline_and_include_the_chosen_one() {
        let all = Simd::available();
        assert_eq!(all[0], Simd::Baseline);
        assert!(all.contains(&level()));
    }
}
