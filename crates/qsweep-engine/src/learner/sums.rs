//! Q(s, ·) = Σᵢ wᵢ qᵢ· (eq. 18) over an activation: the sparse sums over a list of active rules,
//! a kernel per action count, and the dense sums over every rule of a small two-variable rule
//! base ([`DenseView`]), which keep the sparse sums' order of additions bit for bit.

use crate::repr::DenseView;
use crate::simd::dispatch;

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

/// Q(s, ·) over every rule of a dense activation, the same bits as the sparse sums over its
/// windows ([`q_values_fixed`]): each rule goes to the partial sum of its position in the sparse
/// list, and the rules outside the windows add w·q = ±0, which changes no partial sum (started at
/// +0, one is never −0) unless q is infinite or NaN there: a NaN result is recomputed from the
/// sparse list.
#[inline(always)]
pub(super) fn dense_q_values_by_count(q: &[f64], na: usize, v: DenseView<'_>, out: &mut [f64]) {
    macro_rules! unrolled {
        ($($n:literal)*) => {
            match na {
                $($n => dense_q_values_fixed::<$n>(q, v, out),)*
                _ => out[0] = f64::NAN,
            }
        };
    }
    unrolled!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
    if out.iter().any(|x| x.is_nan()) {
        let (n, index, weight) = v.sparse();
        q_values_by_count(q, na, &index[..n], &weight[..n], out);
    }
}

#[inline(always)]
fn dense_q_values_fixed<const N: usize>(q: &[f64], v: DenseView<'_>, out: &mut [f64]) {
    let out: &mut [f64; N] = (&mut out[..N]).try_into().expect("N actions");
    match const { lanes(N) } {
        4 => {
            let s = dense_lane_sums::<N, 4>(q, v);
            for a in 0..N {
                out[a] = (s[0][a] + s[1][a]) + (s[2][a] + s[3][a]);
            }
        }
        // Rows read as four lanes (3 or 4 actions): one vector a rule.
        2 => {
            let [x, y] = dense_pair_sums::<N, 4>(q, v);
            for a in 0..N {
                out[a] = x[a] + y[a];
            }
        }
        _ => {
            if N <= 8 {
                out.copy_from_slice(&dense_sum::<N, 8>(q, v)[..N]);
            } else {
                out.copy_from_slice(&dense_sum::<N, 16>(q, v)[..N]);
            }
        }
    }
}

/// Rule r's row of the (padded) table as `W` ≥ `N` lanes: its `N` values, then values past it,
/// which go into lanes that are never read back.
#[inline(always)]
fn padded_row<const N: usize, const W: usize>(q: &[f64], r: usize) -> &[f64; W] {
    q[r * N..][..W].try_into().expect("W values")
}

/// Q(s, ·) with two interleaved partial sums over every rule, the same bits as the sparse sums
/// over the windows ([`q_values_fixed`]): each rule goes to the partial sum of its position in
/// the sparse list, in the [`PairOrder`](crate::repr::PairOrder) that the window's length picks,
/// and the rules outside the windows add w·q = ±0, which changes no partial sum (started at +0,
/// one is never −0) unless q is infinite or NaN there, which the NaN check of the caller
/// recomputes from the sparse list.
#[inline(always)]
fn dense_pair_sums<const N: usize, const W: usize>(q: &[f64], v: DenseView<'_>) -> [[f64; W]; 2] {
    let (mut x, mut y) = ([0.0f64; W], [0.0f64; W]);
    let rules = v.weight.len();
    // Checked once, so that the loop reads without a check a rule: every rule index of the order
    // is below `rules` (`PairOrder::split`), and each row r·N + W lies inside the padded table.
    assert!(v.order.rules() == rules && rules * N + (W - N) <= q.len(), "dense view of {rules} rules");
    let (pairs, rest) = v.order.split();
    // SAFETY: a, b < rules (the order is a permutation of the rules), so the weights are in
    // bounds and row a ends at a·N + W ≤ (rules − 1)·N + W ≤ q.len() (asserted above).
    let row = |a: u8| unsafe {
        let a = a as usize;
        (*v.weight.get_unchecked(a), &*(q.as_ptr().add(a * N) as *const [f64; W]))
    };
    for &[a, b] in pairs {
        let ((wa, qa), (wb, qb)) = (row(a), row(b));
        for l in 0..W {
            x[l] += wa * qa[l];
        }
        for l in 0..W {
            y[l] += wb * qb[l];
        }
    }
    for &a in rest {
        let (wa, qa) = row(a);
        for l in 0..W {
            x[l] += wa * qa[l];
        }
    }
    [x, y]
}

/// Q(s, ·) with one sum per action over every rule in order (many actions), rows read as `W`
/// lanes: the sparse list's sum with a +0 (w·q = ±0) between its terms where a rule lies outside
/// the windows.
#[inline(always)]
fn dense_sum<const N: usize, const W: usize>(q: &[f64], v: DenseView<'_>) -> [f64; W] {
    let mut acc = [0.0f64; W];
    for (r, &w) in v.weight.iter().enumerate() {
        let row = padded_row::<N, W>(q, r);
        for l in 0..W {
            acc[l] += w * row[l];
        }
    }
    acc
}

/// [`lane_sums`] over every rule: rule (k0, k1) goes to partial sum j mod L, j its position in the
/// sparse list, (k0 − first₀)·len₁ + (k1 − first₁). Along a row j grows by one a rule, so the
/// partial sums are rotated by the row's first position and then indexed by k1 mod L (a rule
/// outside the windows adds 0, so its partial sum does not matter).
#[inline(always)]
fn dense_lane_sums<const N: usize, const L: usize>(q: &[f64], v: DenseView<'_>) -> [[f64; N]; L] {
    let mut acc = [[0.0f64; N]; L];
    let rows: &[[f64; N]] = q.as_chunks::<N>().0;
    let n1 = v.n1 as usize;
    for (k0, (row_q, row_w)) in rows.chunks_exact(n1).zip(v.weight.chunks_exact(n1)).enumerate() {
        // Wrapping arithmetic is exact mod L, a power of two.
        let j0 = (k0 as u32).wrapping_sub(v.first[0]).wrapping_mul(v.len[1]).wrapping_sub(v.first[1]);
        let start = j0 as usize % L;
        rotate_left_by(&mut acc, start);
        let ((qc, qt), (wc, wt)) = (row_q.as_chunks::<L>(), row_w.as_chunks::<L>());
        for (qq, ww) in qc.iter().zip(wc) {
            for l in 0..L {
                for a in 0..N {
                    acc[l][a] += ww[l] * qq[l][a];
                }
            }
        }
        for l in 0..L {
            if l < qt.len() {
                for a in 0..N {
                    acc[l][a] += wt[l] * qt[l][a];
                }
            }
        }
        rotate_left_by(&mut acc, (L - start) % L);
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
