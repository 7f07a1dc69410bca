//! The paper's conclusions tested in every variant ([`crate::replication::stats::claims`]):
//! `conclusions.csv` (one row per variant and claim) and the variant ×
//! claim matrix of the comparison pages.
//!
//! `conclusions.csv` schema (one row per variant and claim, in pipeline × claim order):
//!
//! | column | type | meaning |
//! |---|---|---|
//! | `variant` | string | the variant |
//! | `exploratory` | `yes` / `no` | declared exploratory in the pipeline |
//! | `claim` | string | the claim's id (`docs/preregistration.md`) |
//! | `text` | string | the paper's claim, shortened, and where it is |
//! | `statistic` | string | what the estimate measures |
//! | `estimate` | float, empty | the statistic on the cells as they are |
//! | `ci_lo`, `ci_hi` | float, empty | its 95 % percentile-bootstrap interval |
//! | `null` | float | the value the interval is compared with |
//! | `side` | `above` / `below` | where the paper puts the statistic |
//! | `verdict` | `holds` / `reversed` / `undecided` / `—` | the interval against the null |

use crate::derive::table::{Align, Column, Row, Table, Value};
use crate::replication::compare::digest::VariantDigest;
use crate::replication::stats::claims::{ClaimResult, ClaimVerdict, Side, CLAIMS, CLAIM_RULE};

fn interval(r: &ClaimResult) -> Value {
    r.interval.map_or(Value::Missing, |(lo, hi)| Value::Range { lo, hi, decimals: 3 })
}

/// `conclusions.csv`/`.md` as a table: one row per variant and claim.
pub fn conclusions_table(variants: &[VariantDigest]) -> Table {
    let columns = vec![
        Column::new("Variant", "variant", Align::Left),
        Column::new("Exploratory", "exploratory", Align::Left),
        Column::new("Claim", "claim", Align::Left),
        Column::new("Paper", "text", Align::Left),
        Column::new("Statistic", "statistic", Align::Left),
        Column::new("Estimate", "estimate", Align::Right),
        Column::new("95% CI", "ci_lo", Align::Right).fields(&["ci_lo", "ci_hi"]),
        Column::new("Null", "null", Align::Right),
        Column::new("Side", "side", Align::Left),
        Column::new("Verdict", "verdict", Align::Left),
    ];
    let mut rows = Vec::new();
    for v in variants {
        for r in &v.claims {
            rows.push(Row {
                values: vec![
                    Value::User(v.info.id.clone()),
                    Value::Text(if v.info.exploratory { "yes" } else { "no" }.into()),
                    Value::Text(r.claim.id.into()),
                    Value::Text(r.claim.text.into()),
                    Value::Text(r.claim.statistic.into()),
                    r.estimate.map_or(Value::Missing, |value| Value::Num {
                        value,
                        decimals: 3,
                        signed: false,
                    }),
                    interval(r),
                    Value::Num { value: r.claim.null, decimals: 2, signed: false },
                    Value::Text(
                        match r.claim.side {
                            Side::Above => "above",
                            Side::Below => "below",
                        }
                        .into(),
                    ),
                    Value::Text(r.verdict.word().into()),
                ],
                highlight: false,
            });
        }
    }
    Table {
        title: "Conclusions".into(),
        caption: format!("The paper's conclusions as tests, per variant. {CLAIM_RULE}"),
        columns,
        rows,
    }
}

/// The variant × claim matrix: one row per claim, one column per variant (declared first), each
/// value the verdict and its interval.
pub fn matrix_table(variants: &[VariantDigest]) -> Table {
    let order: Vec<&VariantDigest> = variants
        .iter()
        .filter(|v| !v.info.exploratory)
        .chain(variants.iter().filter(|v| v.info.exploratory))
        .collect();
    let mut columns = vec![Column::new("Claim", "claim", Align::Left)];
    for v in &order {
        let label =
            if v.info.exploratory { format!("{} (exploratory)", v.info.id) } else { v.info.id.clone() };
        columns.push(Column::new(&label, &v.info.id, Align::Left));
    }
    let rows = CLAIMS
        .iter()
        .enumerate()
        .map(|(k, claim)| {
            let mut values = vec![Value::Text(format!("{}: {}", claim.id, claim.text))];
            for v in &order {
                values.push(match v.claims.get(k) {
                    Some(r) if r.verdict != ClaimVerdict::Missing => {
                        let (lo, hi) = r.interval.expect("a verdict has an interval");
                        Value::Text(format!("{} [{lo:.2}, {hi:.2}]", r.verdict.word()))
                    }
                    _ => Value::Missing,
                });
            }
            Row { values, highlight: false }
        })
        .collect();
    let tally: Vec<String> = order
        .iter()
        .map(|v| {
            let holds = v.claims.iter().filter(|r| r.verdict == ClaimVerdict::Holds).count();
            let rev = v.claims.iter().filter(|r| r.verdict == ClaimVerdict::Reversed).count();
            format!("{} {holds} hold / {rev} reversed", v.info.id)
        })
        .collect();
    Table {
        title: "Claims × variants".into(),
        caption: format!(
            "Each of the paper's conclusions in each variant: verdict [95% interval of its statistic] \
             (statistics, nulls and sides in conclusions.csv). {CLAIM_RULE} Tally: {}.",
            tally.join("; ")
        ),
        columns,
        rows,
    }
}
