//! A window grid's slots in the learner's padded table ([`GridView`]): the bound every slot's
//! value lies within, and the portable loop over the slots that the grid Q(0) update and the
//! traces' extension share.

use crate::repr::{GridView, GRID};

/// That every slot's value for `action` in `x` (a padded table), and the whole vector of four
/// holding it, lies inside `x`: checked once an update, since every slot's row starts at most at
/// the last one's.
#[inline(always)]
pub(super) fn check_slots(x: &[f64], v: &GridView, action: usize) {
    let last = v.last_at() + action / 4 * 4 + 4;
    assert!(last <= x.len(), "grid slots past the padded table");
}

/// `f(x[at + action], w)` for each slot of the windows' slot rows (the rows past variable 0's
/// window weigh 0: skipped), in slot order.
#[inline(always)]
pub(super) fn each_slot(x: &mut [f64], v: &GridView, action: usize, mut f: impl FnMut(&mut f64, f64)) {
    check_slots(x, v, action);
    for i0 in 0..(v.len[0] as usize).min(GRID) {
        for i1 in 0..GRID {
            // SAFETY: checked above.
            f(unsafe { x.get_unchecked_mut(v.at(i0, i1) + action) }, v.weight[i0][i1]);
        }
    }
}
