//! `exploratory:`: a search over readings that keeps its fit honest. The Table III rows named in
//! `fit_rows` choose the best reading; every other row with a reference is held out and only
//! judged, after the choice.
//!
//! ```yaml
//! exploratory:
//!   fit_rows:
//!     - { system: ball-beam, experiment: 1, algorithm: q0 }
//!     - { system: ball-beam, experiment: 2 }        # both algorithms of experiment 2
//! ```
//!
//! A row names a system, and optionally an experiment id and an algorithm (all of them when left
//! out). Checked against the pipeline: each entry must name rows that exist and carry a
//! `reference:` (a fit needs one), and at least one row with a reference must be held out.

use super::{PipelineSpec, Problem, SystemMarker, SystemSpec};
use crate::sim::env::SystemKind;
use crate::sim::Algorithm;
use serde::{Deserialize, Deserializer};

/// The `exploratory:` block.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Exploratory {
    /// The rows that choose the reading; the rest are held out.
    pub fit_rows: Vec<RowSelector>,
}

/// Some Table III rows: a system, optionally one experiment and one algorithm.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RowSelector {
    /// The system.
    pub system: SystemKind,
    /// An experiment id (all of the system's when absent).
    #[serde(default, deserialize_with = "opt_id")]
    pub experiment: Option<String>,
    /// An algorithm (both when absent).
    #[serde(default)]
    pub algorithm: Option<Algorithm>,
}

fn opt_id<'de, D: Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Id {
        N(u64),
        S(String),
    }
    Ok(Some(match Id::deserialize(d)? {
        Id::N(n) => n.to_string(),
        Id::S(s) => s,
    }))
}

impl RowSelector {
    /// Whether the Table III row (system, experiment id, algorithm) is one of these.
    pub fn matches(&self, system: SystemKind, experiment: &str, algorithm: Algorithm) -> bool {
        self.system == system
            && self.experiment.as_deref().is_none_or(|e| e == experiment)
            && self.algorithm.is_none_or(|a| a == algorithm)
    }

    /// As written in messages: `ball-beam exp 1 q0`.
    pub fn label(&self) -> String {
        format!(
            "{}{}{}",
            self.system,
            self.experiment.as_ref().map(|e| format!(" exp {e}")).unwrap_or_default(),
            self.algorithm.map(|a| format!(" {}", a.name())).unwrap_or_default()
        )
    }
}

impl Exploratory {
    /// Whether a row is a fit row (else, with a reference, it is held out).
    pub fn is_fit_row(&self, system: SystemKind, experiment: &str, algorithm: Algorithm) -> bool {
        self.fit_rows.iter().any(|r| r.matches(system, experiment, algorithm))
    }
}

/// Every Table III row of the pipeline: (system, experiment id, algorithm, has a reference).
fn rows(spec: &PipelineSpec) -> Vec<(SystemKind, String, Algorithm, bool)> {
    fn of<M: SystemMarker>(s: Option<&SystemSpec<M>>) -> Vec<(SystemKind, String, Algorithm, bool)> {
        s.iter()
            .flat_map(|s| &s.experiments)
            .flat_map(|e| {
                e.algorithms.iter().map(move |&a| (M::SYSTEM, e.id.clone(), a, e.reference.contains_key(&a)))
            })
            .collect()
    }
    let s = &spec.systems;
    [of(s.ball_beam.as_ref()), of(s.cart_pole.as_ref()), of(s.mountain_car.as_ref())].concat()
}

/// Check the block against the pipeline's rows.
pub fn check(spec: &PipelineSpec) -> Result<(), Problem> {
    let Some(x) = &spec.exploratory else { return Ok(()) };
    let all = rows(spec);
    let at = |i: usize| vec!["exploratory".to_string(), "fit_rows".to_string(), i.to_string()];
    if x.fit_rows.is_empty() {
        return Err(Problem {
            path: vec!["exploratory".into(), "fit_rows".into()],
            message: "the list is empty; name the Table III rows that choose the reading".into(),
        });
    }
    for (i, r) in x.fit_rows.iter().enumerate() {
        let hit: Vec<_> = all.iter().filter(|(s, e, a, _)| r.matches(*s, e, *a)).collect();
        if hit.is_empty() {
            let of_system: Vec<String> = all
                .iter()
                .filter(|(s, ..)| *s == r.system)
                .map(|(_, e, a, _)| format!("exp {e} {}", a.name()))
                .collect();
            let known = if of_system.is_empty() {
                format!("the pipeline has no {}", r.system)
            } else {
                format!("its rows are {}", of_system.join(", "))
            };
            return Err(Problem {
                path: at(i),
                message: format!("no Table III row is {}; {known}", r.label()),
            });
        }
        if !hit.iter().any(|h| h.3) {
            return Err(Problem {
                path: at(i),
                message: format!(
                    "{} has no `reference:` value, so it cannot choose a reading; name rows with a reference",
                    r.label()
                ),
            });
        }
    }
    let held_out = all.iter().filter(|(s, e, a, r)| *r && !x.is_fit_row(*s, e, *a)).count();
    if held_out == 0 {
        return Err(Problem {
            path: vec!["exploratory".into(), "fit_rows".into()],
            message: "the fit rows cover every row with a reference, so nothing is held out to judge the \
                      chosen reading; leave some rows out"
                .into(),
        });
    }
    Ok(())
}
