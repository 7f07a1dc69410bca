//! Issue #40 end to end: a pipeline whose two Ball-Beam experiments overlap, with the paper's two
//! contradictory Q(0) values as references. Each variant's table3.csv gains ours at the paper's
//! configuration, the verdicts and a cause per row; the comparison lists the pair in
//! consistency.csv and opens with the tally of causes.

use crate::helpers::{csv_rows, stdout, Sandbox};

/// Exp. 2's published configuration (3 × 3 bins, 3 actions) is a cell of Exp. 1's grid, whose
/// published minimum (90.5 ± 25.8) is far above it (43.2 ± 20.4): the paper's Ball-Beam Q(0) rows.
const PIPELINE: &str = "\
name: causes
seeds: 2
defaults: { max_episodes: 25 }
systems:
  ball-beam:
    crisp: { epsilon: 1.0e-6, gamma: 0.9, alpha: 0.1, lambda: 0.9 }
    success: { steps: 300 }
    experiments:
      - id: 1
        repr: crisp
        vary: { x: [2, 3], x_dot: [2, 3] }
        fixed: { actions: 3 }
        reference:
          q0: { mean: 90.5, std: 25.8, resolution: [3, 2], actions: 3 }
      - id: 2
        repr: crisp
        vary: { x == x_dot: [2, 3], actions: [2, 3] }
        reference:
          q0: { mean: 43.2, std: 20.4, resolution: [3, 3], actions: 3 }
variants:
  - id: base
  - id: fast
    set: { systems.ball-beam.crisp.alpha: 0.5 }
";

#[test]
fn table3_has_the_paper_cell_and_a_cause_per_row_and_the_comparison_lists_contradictions() {
    let sb = Sandbox::new();
    let p = sb.write("causes.yaml", PIPELINE);
    sb.run_json(&p, &[]);
    stdout(&mut sb.qsweep(&["report", p.to_str().unwrap(), "--out", "rep"]));
    for v in ["base", "fast"] {
        let text = std::fs::read_to_string(sb.path(&format!("rep/{v}/table3.csv"))).unwrap();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let at = header.iter().position(|h| *h == "paper_cell_mean").expect("paper_cell_mean");
        assert_eq!(header[at - 1], "equivalent_n100", "new columns after the existing ones");
        let tail = [
            "verdict_2se",
            "paper_cell_verdict_2se",
            "cause_2se",
            "contradictory_pair",
            "paper_inconsistent",
            "tost2x_p_n10",
            "paper_cell_tost2x_p_n10",
            "verdict",
            "paper_cell_verdict",
            "cause",
            "std_ratio",
            "std_ratio_lo",
            "std_ratio_hi",
            "spread_differs",
        ];
        assert_eq!(&header[header.len() - tail.len()..], tail);
        for h in ["paper_cell_n", "paper_cell_ci_hi", "paper_cell_ratio_lo", "paper_cell_equivalent_n10"] {
            assert!(header.contains(&h), "{h} in {header:?}");
        }
        let rows = csv_rows(&text);
        assert_eq!(rows.len(), 4, "two experiments × two algorithms");
        for r in &rows {
            if r["algorithm"] == "Q(0)-learning" {
                // Ours takes a few episodes (at most 25): nowhere near 43 or 90, so the row does
                // not replicate, and it is in the contradictory pair, which costs Exp. 1's row
                // (the minimum a cell of its own grid undercuts); Exp. 2's is judged as any row.
                assert_eq!(r["verdict_2se"], "no", "{r:?}");
                assert!(!["equivalent", "within-2x"].contains(&r["verdict"].as_str()), "{r:?}");
                assert_eq!(r["contradictory_pair"], "yes");
                assert_eq!(r["cause_2se"], "paper-inconsistent", "the old rule marked both rows");
                let first = r["experiment"] == "1";
                assert_eq!(r["paper_inconsistent"], if first { "yes" } else { "no" }, "{r:?}");
                assert_eq!(r["cause"], if first { "paper-inconsistent" } else { "differs-at-paper-config" });
                assert_eq!(r["paper_cell_n"], "2", "the paper's configuration is a cell of the grid");
                assert!(r["paper_cell_mean"].parse::<f64>().unwrap() <= 25.0);
            } else {
                // No published value: no verdict and no cause.
                assert_eq!((r["verdict"].as_str(), r["cause"].as_str()), ("", ""), "{r:?}");
            }
        }
    }
    let pairs = csv_rows(&std::fs::read_to_string(sb.path("rep/consistency.csv")).unwrap());
    assert_eq!(pairs.len(), 1);
    let pair = &pairs[0];
    assert_eq!((pair["experiment_a"].as_str(), pair["experiment_b"].as_str()), ("1", "2"));
    assert_eq!((pair["implied"].as_str(), pair["contradictory"].as_str()), ("a ≤ b", "yes"));
    let p_value: f64 = pair["p"].parse().unwrap();
    assert!((p_value - 2.816e-4).abs() < 1e-6, "{p_value}");
    let html = std::fs::read_to_string(sb.path("rep/index.html")).unwrap();
    assert!(html.contains("<p id=\"causes\">"), "{html}");
    assert!(html
        .contains("0 replicates, 0 argmin, 1 paper-inconsistent, 1 differs-at-paper-config, 0 unexplained"));
    assert_eq!(pair["marked"], "a", "the pair costs Exp. 1's row");
    assert!(html.contains("href=\"consistency.csv\""));
    let md = std::fs::read_to_string(sb.path("rep/consistency.md")).unwrap();
    assert!(md.contains("1 comparable pair of Table III rows, 1 contradictory"), "{md}");
}
