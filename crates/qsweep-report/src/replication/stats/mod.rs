//! The replication's own statistics, used by no other part: equivalence with a published value
//! (TOST, [`equivalence`]) and the verdict scale with each row's cause ([`verdict`]), the paper
//! against itself ([`consistency`]), the paper's conclusions as tests ([`claims`]), what choosing
//! among variants is worth ([`selection`], a permutation yardstick) and survival under the episode
//! cap ([`survival`], Kaplan–Meier). Pure, seeded functions of their inputs.

pub mod claims;
pub mod consistency;
pub mod equivalence;
pub mod selection;
pub mod survival;
pub mod verdict;
