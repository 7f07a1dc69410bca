//! Tests of the comparison: the fit recomputed from the trials, the files written, the
//! difference figures' markers, determinism.

use crate::derive::report_data::ReportData;
use crate::replication::compare::*;
use crate::replication::pages::*;
use plotters::style::RGBColor;
use qsweep_engine::run_trial;
use qsweep_pipeline::analysis::bootstrap_diff_ci;
use qsweep_pipeline::cache::{Key, TrialRecord};
use qsweep_pipeline::declared::{load_str, LoadedSpec, Override};
use qsweep_pipeline::plan::plan;
use std::collections::{BTreeMap, HashMap};

/// A statistics' memo that reuses nothing.
fn memo() -> crate::memo::stats::StatsMemo {
    crate::memo::stats::StatsMemo::fresh(0)
}

/// Two Ball-Beam experiments (a 2 × 2 grid and a 3-cell row), 4 seeds, short trials.
const PIPELINE: &str = "\
name: vt
seeds: 4
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
          q0: { mean: 6.0, std: 3.0, resolution: [3, 3], actions: 3 }
          q-lambda: { mean: 2.0, std: 1.0, resolution: [2, 3], actions: 3 }
      - id: 2
        repr: crisp
        vary: { x: [2, 3, 4] }
        fixed: { x_dot: 3, actions: 3 }
        reference:
          q0: { mean: 8.0, std: 3.0 }
";

fn plan_with(sets: &[&str]) -> Plan {
    let overrides: Vec<Override> = sets.iter().map(|s| Override::parse(s).unwrap()).collect();
    let spec = load_str(PIPELINE, "vt.yaml", &overrides).unwrap();
    plan(&LoadedSpec { spec, path: "vt.yaml".into(), variants: Vec::new() }, None).unwrap()
}

fn run_all(plan: &Plan) -> HashMap<Key, TrialRecord> {
    plan.unique_trials()
        .into_iter()
        .map(|(c, t)| (t.key, TrialRecord::new(c.clone(), t.seed, run_trial(c, t.seed), 0.0)))
        .collect()
}

fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    for sub in ["", "figures"] {
        for entry in std::fs::read_dir(dir.join(sub)).unwrap() {
            let p = entry.unwrap().path();
            if p.is_file() {
                let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.insert(name, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// The fit recomputed from the trials, independently of [`Fit::from_rows`]: (rows, replicating,
/// within 2×, config matches, order matches, experiments ordered, geometric mean).
fn by_hand(d: &ReportData) -> (usize, usize, usize, usize, usize, usize, f64) {
    let (mut rows, mut rep, mut w2, mut cfg, mut ord, mut ord_n, mut logs) = (0, 0, 0, 0, 0, 0, vec![]);
    for e in &d.experiments {
        let mut means = vec![];
        for &a in &e.exp.algorithms {
            let Some(r) = e.exp.reference.get(&a) else { continue };
            let c = &e.cells[e.best_of(a).unwrap().cell];
            let v: Vec<f64> = c.trials.iter().map(|t| f64::from(t.counted)).collect();
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            let s = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0)).sqrt();
            rows += 1;
            if (m - r.mean).abs() <= 2.0 * (r.std * r.std / 10.0 + s * s / n).sqrt() {
                rep += 1;
            } else if m / r.mean >= 0.5 && m / r.mean <= 2.0 {
                w2 += 1;
            }
            let res = &c.cell.config.repr.resolution;
            if r.resolution.as_ref() == Some(res) && r.actions == Some(c.cell.config.actions) {
                cfg += 1;
            }
            logs.push((m / r.mean).ln());
            means.push((m, r.mean));
        }
        if means.len() == 2 {
            ord_n += 1;
            if (means[0].0 <= means[1].0) == (means[0].1 <= means[1].1) {
                ord += 1;
            }
        }
    }
    (rows, rep, w2, cfg, ord, ord_n, (logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

#[test]
fn fit_order_and_diff_labels() {
    // The verdicts themselves are tested in replication::stats::verdict; here the order they rank.
    let f = |within_2se, ratio_within_2x, geo_mean| Fit {
        within_2se,
        ratio_within_2x,
        geo_mean,
        ..Fit::default()
    };
    let fits = [f(1, 3, Some(1.1)), f(2, 0, None), f(1, 3, Some(0.95)), f(1, 3, None), f(1, 4, Some(3.0))];
    assert_eq!(fit_order(&fits), vec![1, 4, 2, 0, 3]);
    assert_eq!(diff_label(-12.345), "−12.3");
    assert_eq!(diff_label(0.001), "0.00");
    assert_eq!(diff_label(150.0), "+150");
    assert_eq!(diverging(0.0), RGBColor(247, 247, 247));
    assert_eq!(diverging(-1.0), RGBColor(33, 102, 172));
    assert_eq!(diverging(9.0), RGBColor(178, 24, 43));
}

#[test]
fn comparison_of_two_variants_is_right_and_deterministic() {
    let base = plan_with(&[]);
    let other = plan_with(&["systems.ball-beam.crisp.alpha=0.5", "systems.ball-beam.crisp.lambda=0.3"]);
    let rec_base = run_all(&base);
    let mut rec_other = run_all(&other);
    // The other variant lacks every trial of one cell: grey in its difference figure.
    let gone = &other.experiments[1].cells[2];
    for t in &gone.trials {
        rec_other.remove(&t.key);
    }
    let data = [ReportData::build(&base, &rec_base), ReportData::build(&other, &rec_other)];
    let variants = vec![
        VariantDigest::of(
            VariantInfo { id: "as-written".into(), title: Some("The text".into()), exploratory: false },
            &base,
            &data[0],
            &memo(),
        ),
        VariantDigest::of(
            VariantInfo { id: "fast".into(), title: None, exploratory: false },
            &other,
            &data[1],
            &memo(),
        ),
    ];
    let all = Formats::of(&Format::ALL);
    let tmp = tempfile::tempdir().unwrap();
    let written = write_comparison(tmp.path(), &base, &variants, all, &memo()).unwrap();
    let names: Vec<String> = written.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    assert_eq!(
        names,
        [
            "variants.md",
            "variants.csv",
            "verdicts_by_n.csv",
            "cross_validation.csv",
            "consistency.md",
            "consistency.csv",
            "figures/forest.svg",
            "figures/forest.png",
            "figures/diff-fast-ball-beam.svg",
            "figures/diff-fast-ball-beam.png",
            "index.html",
            "README.md"
        ]
    );
    // The claims speak of all three systems: a Ball-Beam-only pipeline has no conclusions.
    assert!(variants.iter().all(|v| v.claims.is_empty()));
    let out = files(tmp.path());
    assert_eq!(
        out.keys().cloned().collect::<Vec<_>>().len(),
        12,
        "no temporary files left: {:?}",
        out.keys()
    );

    // The CSV's numbers, recomputed from the trials.
    let csv = String::from_utf8(out["variants.csv"].clone()).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "rank",
            "variant",
            "title",
            "rows",
            "replicating_n10",
            "equivalent_n10",
            "within_2x_n10",
            "consistent_but_wide_n10",
            "differs_n10",
            "replicating_n5",
            "replicating_n3",
            "within_2se",
            "ratio_within_2x",
            "config_match",
            "order_match",
            "order_experiments",
            "geo_mean_ratio",
            "equivalent_n100",
            "exploratory"
        ]
    );
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2);
    let fits: Vec<_> = data.iter().map(by_hand).collect();
    for (v, d) in variants.iter().map(|v| &v.info).zip(&data) {
        let row = rows.iter().find(|r| r[1] == v.id).unwrap();
        let (n, rep, w2, cfg, ord, ord_n, geo) = by_hand(d);
        let ints: Vec<usize> =
            ["rows", "within_2se", "ratio_within_2x", "config_match", "order_match", "order_experiments"]
                .iter()
                .map(|c| row[col(c)].parse().unwrap())
                .collect();
        assert_eq!(ints, [n, rep, w2, cfg, ord, ord_n], "{}", v.id);
        assert_eq!(n, 3);
        assert_eq!(ord_n, 1);
        let scale: usize = ["equivalent_n10", "within_2x_n10", "consistent_but_wide_n10", "differs_n10"]
            .iter()
            .map(|c| row[col(c)].parse::<usize>().unwrap())
            .sum();
        assert!(scale <= n, "every row has one verdict (undecided not listed)");
        let replicating: usize = row[col("replicating_n10")].parse().unwrap();
        let strict: usize =
            ["equivalent_n10", "within_2x_n10"].iter().map(|c| row[col(c)].parse::<usize>().unwrap()).sum();
        assert_eq!(replicating, strict);
        let g: f64 = row[col("geo_mean_ratio")].parse().unwrap();
        assert!((g - geo).abs() < 1e-12, "{g} vs {geo}");
        assert_eq!(row[2], v.title.as_deref().unwrap_or(""));
    }
    // Rows are in fit order.
    let first =
        if (fits[0].1, fits[0].2, -fits[0].6.ln().abs()) >= (fits[1].1, fits[1].2, -fits[1].6.ln().abs()) {
            "as-written"
        } else {
            "fast"
        };
    assert_eq!((rows[0][0], rows[0][1]), ("1", first));
    let md = String::from_utf8(out["variants.md"].clone()).unwrap();
    assert!(md.starts_with("**Variants.** How well each variant"));
    assert!(md.contains("most rows within 2 SE first"));

    // Markers exactly where the difference's interval excludes 0.
    let (b, o) = (&variants[0], &variants[1]);
    let mut marked = 0;
    let mut unmarked = 0;
    let mut missing = 0;
    let diffs = all_diffs(b, o, &memo());
    for (k, e) in o.exps.iter().enumerate() {
        for (i, c) in e.cells.iter().enumerate() {
            let Some(d) = matching(b, e, i).and_then(|bc| CellDiff::of(bc, c, &memo())) else {
                missing += 1;
                assert_eq!(diffs[k][i], None);
                continue;
            };
            assert_eq!(diffs[k][i], Some(d));
            // Recomputed from the trials themselves, not the digest.
            let bd = &data[0].experiments[k];
            let od = &data[1].experiments[k];
            let j = bd.find(c.cell.algorithm, &c.cell.coords).unwrap();
            let va: Vec<f64> = bd.cells[j].trials.iter().map(|t| f64::from(t.counted)).collect();
            let vb: Vec<f64> = od.cells[i].trials.iter().map(|t| f64::from(t.counted)).collect();
            let bc = matching(b, e, i).unwrap();
            let ci = bootstrap_diff_ci(&va, &vb, 2000, diff_seed(bc, c));
            assert_eq!(d.ci, ci);
            assert!(
                (d.diff - (qsweep_pipeline::analysis::mean(&vb) - qsweep_pipeline::analysis::mean(&va)))
                    .abs()
                    < 1e-12
            );
            assert_eq!(d.significant, ci.0 > 0.0 || ci.1 < 0.0);
            if d.significant {
                marked += 1;
            } else {
                unmarked += 1;
            }
        }
    }
    assert_eq!(missing, 1, "only the removed cell");
    assert!(marked >= 1 && unmarked >= 1, "{marked} marked, {unmarked} unmarked");
    let svg = String::from_utf8(out["figures/diff-fast-ball-beam.svg"].clone()).unwrap();
    assert_eq!(svg.matches("<circle").count(), marked + 1, "one dot per marked cell, one in the legend");
    assert!(svg.contains("#C8C8C8"), "the missing cell is grey");

    let html = String::from_utf8(out["index.html"].clone()).unwrap();
    for link in [
        "as-written/index.html",
        "fast/index.html",
        "variants.csv",
        "figures/forest.svg",
        "figures/diff-fast-ball-beam.svg",
    ] {
        assert!(html.contains(&format!("\"{link}\"")), "index.html links {link}");
    }

    // Determinism: a second write gives identical bytes.
    let again = tempfile::tempdir().unwrap();
    write_comparison(again.path(), &base, &variants, all, &memo()).unwrap();
    assert_eq!(files(again.path()), out);
    write_comparison(tmp.path(), &base, &variants, all, &memo()).unwrap();
    assert_eq!(files(tmp.path()), out);
}
