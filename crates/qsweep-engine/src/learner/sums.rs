//! Q(s, ·) = Σᵢ wᵢ qᵢ· (eq. 18) over an activation: the sparse sums over a list of active rules,
//! a kernel per action count, and the grid sums over a two-variable rule base's windows
//! ([`GridView`]), which keep the sparse sums' order of additions bit for bit.

use crate::repr::{GridView, GRID};
use crate::simd::dispatch;
use crate::simd::Simd;

/// Action counts up to this get a Q(s, ·) kernel with every action's sum in registers.
pub(super) const MAX_UNROLLED_ACTIONS: usize = 16;

dispatch! {
    /// [`q_values_by_count`] at `simd`'s vector width (the same sums in the same order).
    pub(super) fn q_values_at => q_values_by_count(q: &[f64], na: usize, index: &[u32], weight: &[f64], out: &mut [f64])
}

/// Q(s, ·) for several active features: a kernel per action count.
#[inline(always)]
pub(super) fn q_values_by_count(q: &[f64], na: usize, index: &[u32], weight: &[f64], out: &mut [f64]) {
    macro_rules! unrolled {
        ($($n:literal)*) => {
            match na {
                $($n => q_values_fixed::<$n>(q, index, weight, out),)*
                _ => q_values_any(q, na, index, weight, out),
            }
        };
    }
    const _: () = assert!(MAX_UNROLLED_ACTIONS == 16);
    unrolled!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
}

/// Q(s, ·) over a window grid's slots, the same bits as the sparse sums over its windows
/// ([`q_values_fixed`]): each slot goes to the partial sum of its position in the sparse list,
/// and the slots outside the windows add w·q = ±0, which changes no partial sum (started at +0,
/// one is never −0) unless q is infinite or NaN there: a NaN result is recomputed from the sparse
/// list. `out` holds [`grid_out_len`] values; those past the actions are scratch.
#[inline(always)]
pub(super) fn grid_q_values_by_count(q: &[f64], na: usize, v: &GridView, out: &mut [f64], simd: Simd) {
    macro_rules! unrolled {
        ($($n:literal)*) => {
            match na {
                $($n => grid_q_values_fixed::<$n>(q, v, out, simd),)*
                _ => true,
            }
        };
    }
    if unrolled!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16) {
        let (n, index, weight) = v.sparse(na);
        q_values_by_count(q, na, &index[..n], &weight[..n], out);
    }
}

/// The lanes a grid kernel reads a table row as, for `n` actions: a whole vector of four, eight
/// or sixteen values.
pub(super) const fn grid_width(n: usize) -> usize {
    if n <= 4 {
        4
    } else if n <= 8 {
        8
    } else {
        16
    }
}

/// The row length of a grid trial's table for `actions` actions: a whole vector of four, eight or
/// sixteen values (one or two actions: their own), so that every rule's row is vectors of its own,
/// read and written whole (the values past the actions stay as they started, never read back).
/// Q(s, ·)'s partial sums are the same for the padded row: as many for four actions as for three
/// ([`lanes`]), one for eight as for five.
pub fn grid_row_len(actions: usize) -> usize {
    if actions <= 2 || actions > MAX_UNROLLED_ACTIONS {
        actions
    } else {
        grid_width(actions)
    }
}

/// How many values a Q(s, ·) buffer holds for `na` actions: room for a grid kernel's whole
/// vector (the lanes past the actions are scratch, so the kernel keeps every lane of its rows).
pub(super) const fn grid_out_len(na: usize) -> usize {
    if na <= MAX_UNROLLED_ACTIONS {
        grid_width(na)
    } else {
        na
    }
}

/// [`grid_q_values_by_count`] for `N` actions; whether a value came out NaN (to be recomputed).
#[inline(always)]
fn grid_q_values_fixed<const N: usize>(q: &[f64], v: &GridView, out: &mut [f64], simd: Simd) -> bool {
    #[cfg(target_arch = "x86_64")]
    if simd != Simd::Baseline && N >= 3 {
        // The same sums in AVX2 vectors (`simd` is capped by what the CPU has).
        const W: usize = 4;
        check_rows(q, v, grid_width(N));
        // SAFETY: the CPU has AVX2 (AVX-512 includes it), and the rows are checked above.
        return unsafe {
            match const { grid_width(N) / W } {
                1 => super::grid_x86::pair_sums::<N>(q, v, (&mut out[..W]).try_into().expect("four")),
                2 => super::grid_x86::sum::<N, 2>(q, v, &mut out[..2 * W]),
                _ => super::grid_x86::sum::<N, 4>(q, v, &mut out[..4 * W]),
            }
        };
    }
    let _ = simd;
    match const { lanes(N) } {
        4 => {
            let s = grid_lane_sums::<N>(q, v);
            for a in 0..N {
                out[a] = (s[0][a] + s[1][a]) + (s[2][a] + s[3][a]);
            }
        }
        2 => {
            let [x, y] = grid_pair_sums::<N, 4>(q, v);
            let out: &mut [f64; 4] = (&mut out[..4]).try_into().expect("a Q(s, ·) buffer of four");
            for l in 0..4 {
                out[l] = x[l] + y[l];
            }
        }
        _ => {
            if N <= 8 {
                let out: &mut [f64; 8] = (&mut out[..8]).try_into().expect("a Q(s, ·) buffer of eight");
                *out = grid_sum::<N, 8>(q, v);
            } else {
                let out: &mut [f64; 16] = (&mut out[..16]).try_into().expect("a Q(s, ·) buffer of 16");
                *out = grid_sum::<N, 16>(q, v);
            }
        }
    }
    out[..N].iter().any(|x| x.is_nan())
}

/// Slot (i0, i1)'s weight and its table row as `W` ≥ `N` lanes: the row's `N` values, then values
/// past it, which go into lanes that are never read back.
///
/// # Safety
/// `v.last_at() + W ≤ q.len()` ([`check_rows`]).
#[inline(always)]
unsafe fn slot<'q, const N: usize, const W: usize>(
    q: &'q [f64],
    v: &GridView,
    i0: usize,
    i1: usize,
) -> (f64, &'q [f64; W]) {
    // Read from the activation, so that the compiler sees each slot's row on its own (it knows
    // nothing of how one slot's row lies to the next's, and reads each as one whole vector).
    let at = v.at(i0, i1);
    // SAFETY: the last slot's row is the greatest (the caller's bound).
    (v.weight[i0][i1], unsafe { &*(q.as_ptr().add(at) as *const [f64; W]) })
}

/// Checked once a sum, so that its slots read `width` values of their rows without a check each.
#[inline(always)]
fn check_rows(q: &[f64], v: &GridView, width: usize) {
    assert!(v.last_at() + width <= q.len(), "grid rows past the padded table");
}

/// Q(s, ·) with two interleaved partial sums over the grid's slots, row by row: in each row the
/// slots alternate between the sums, and a row that follows an odd window starts on the other
/// sum, so the sums trade places between rows ([`GridView::swap`], a bit blend: the values' bits
/// are moved, never computed). The two are added at the end, which cannot tell which is which.
#[inline(always)]
fn grid_pair_sums<const N: usize, const W: usize>(q: &[f64], v: &GridView) -> [[f64; W]; 2] {
    const { assert!(GRID.is_multiple_of(2)) };
    check_rows(q, v, W);
    let (mut x, mut y) = ([0.0f64; W], [0.0f64; W]);
    for i0 in 0..(v.len[0] as usize).min(GRID) {
        for i1 in (0..GRID).step_by(2) {
            // SAFETY: checked above.
            let ((wa, qa), (wb, qb)) =
                unsafe { (slot::<N, W>(q, v, i0, i1), slot::<N, W>(q, v, i0, i1 + 1)) };
            for l in 0..W {
                x[l] += wa * qa[l];
            }
            for l in 0..W {
                y[l] += wb * qb[l];
            }
        }
        for l in 0..W {
            let (a, b) = (x[l].to_bits(), y[l].to_bits());
            let d = (a ^ b) & v.swap;
            (x[l], y[l]) = (f64::from_bits(a ^ d), f64::from_bits(b ^ d));
        }
    }
    [x, y]
}

/// Q(s, ·) with one sum per action over the grid's slots in order (many actions), rows read as
/// `W` lanes: the sparse list's sum with a +0 (w·q = ±0) between its terms where a slot lies
/// outside the windows.
#[inline(always)]
fn grid_sum<const N: usize, const W: usize>(q: &[f64], v: &GridView) -> [f64; W] {
    check_rows(q, v, W);
    let mut acc = [0.0f64; W];
    for i0 in 0..GRID {
        for i1 in 0..GRID {
            // SAFETY: checked above.
            let (w, row) = unsafe { slot::<N, W>(q, v, i0, i1) };
            for l in 0..W {
                acc[l] += w * row[l];
            }
        }
    }
    acc
}

/// [`lane_sums`] over the grid's slots (one or two actions): slot (i0, i1) goes to partial sum
/// j mod 4, j = i0·len₁ + i1 its position in the sparse list. The slots of a row go to the sums
/// in turn; after each row the sums are rotated by len₁ mod 4, so that the next row's first slot
/// meets the sum its position names. Four rows rotate by 4·len₁ ≡ 0 in all, which leaves every
/// sum in its place for the final additions.
#[inline(always)]
fn grid_lane_sums<const N: usize>(q: &[f64], v: &GridView) -> [[f64; N]; 4] {
    const { assert!(GRID == 4) };
    check_rows(q, v, N);
    let mut acc = [[0.0f64; N]; 4];
    let turn = v.len[1] as usize % 4;
    for i0 in 0..GRID {
        for (i1, sum) in acc.iter_mut().enumerate() {
            // SAFETY: checked above.
            let (w, row) = unsafe { slot::<N, N>(q, v, i0, i1) };
            for a in 0..N {
                sum[a] += w * row[a];
            }
        }
        rotate_left_by(&mut acc, turn);
    }
    acc
}

/// `acc.rotate_left(s)` for s < L without a branch or a memory round trip: a rotation by each
/// power of two in s, each a bitwise blend (the values' bits are moved, never computed).
#[inline(always)]
fn rotate_left_by<const N: usize, const L: usize>(acc: &mut [[f64; N]; L], s: usize) {
    let mut shift = 1;
    while shift < L {
        let m = 0u64.wrapping_sub(u64::from(s & shift != 0));
        let old = *acc;
        for i in 0..L {
            for a in 0..N {
                let (x, y) = (old[i][a].to_bits(), old[(i + shift) % L][a].to_bits());
                acc[i][a] = f64::from_bits(x ^ ((x ^ y) & m));
            }
        }
        shift *= 2;
    }
}

/// Interleaved partial sums per action for `N` actions: enough independent additions in flight to
/// hide their latency (with many actions the actions' own sums already are).
pub(super) const fn lanes(n: usize) -> usize {
    if n <= 2 {
        4
    } else if n <= 4 {
        2
    } else {
        1
    }
}

/// `L` interleaved partial sums of Σᵢ wᵢ·q[iᵢ·N + a] for a = 0..N: rule j goes to partial sum
/// j mod L, each summed in activation order from 0.
#[inline(always)]
fn lane_sums<const N: usize, const L: usize>(q: &[f64], index: &[u32], weight: &[f64]) -> [[f64; N]; L] {
    let mut acc = [[0.0f64; N]; L];
    // Rows as arrays: one bounds check per rule, not two.
    let rows: &[[f64; N]] = q.as_chunks::<N>().0;
    let (ic, wc) = (index.as_chunks::<L>(), weight.as_chunks::<L>());
    for (ii, ww) in ic.0.iter().zip(wc.0) {
        for l in 0..L {
            let (r, w) = (&rows[ii[l] as usize], ww[l]);
            for a in 0..N {
                acc[l][a] += w * r[a];
            }
        }
    }
    for (l, (&i, &w)) in ic.1.iter().zip(wc.1).enumerate() {
        let r = &rows[i as usize];
        for a in 0..N {
            acc[l][a] += w * r[a];
        }
    }
    acc
}

/// Q(s, ·) with `N` actions: every action's partial sums stay in registers across the activation,
/// added at the end as (s₀ + s₁) + (s₂ + s₃).
#[inline(always)]
fn q_values_fixed<const N: usize>(q: &[f64], index: &[u32], weight: &[f64], out: &mut [f64]) {
    let out: &mut [f64; N] = (&mut out[..N]).try_into().expect("N actions");
    match const { lanes(N) } {
        4 => {
            let s = lane_sums::<N, 4>(q, index, weight);
            for a in 0..N {
                out[a] = (s[0][a] + s[1][a]) + (s[2][a] + s[3][a]);
            }
        }
        2 => {
            let s = lane_sums::<N, 2>(q, index, weight);
            for a in 0..N {
                out[a] = s[0][a] + s[1][a];
            }
        }
        _ => *out = lane_sums::<N, 1>(q, index, weight)[0],
    }
}

/// Q(s, ·) for any action count, summing in `out` directly.
#[inline(always)]
pub(super) fn q_values_any(q: &[f64], na: usize, index: &[u32], weight: &[f64], out: &mut [f64]) {
    out.fill(0.0);
    for (&i, &w) in index.iter().zip(weight) {
        let row = &q[i as usize * na..(i as usize + 1) * na];
        for (o, v) in out.iter_mut().zip(row) {
            *o += w * v;
        }
    }
}
