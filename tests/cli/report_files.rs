//! The report stage end to end: plan `pipelines/quick.yaml`, give every planned trial a record
//! (a few computed by the real simulation, the rest synthesised with every kind of outcome), store
//! them in a cache, write the report with the stage `qsweep report` runs ([`report::write`]) and
//! check its files: all present, PNGs decode at the expected size, SVGs are XML, `index.html`
//! links only local files, and a second run is byte-identical.

use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{run_trial, Algorithm, Outcome, StopReason};
use qsweep_pipeline::cache::store::Store;
use qsweep_pipeline::cache::{Key, TrialRecord};
use qsweep_pipeline::declared::Reference;
use qsweep_pipeline::plan::Plan;
use qsweep_report::formats::{Format, Formats};
use qsweep_report::render::{curves, figures};
use qsweep_report::{ReportOptions, ReportSummary};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

fn quick_plan() -> Plan {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/quick.yaml");
    let loaded = qsweep_pipeline::declared::load(&path, &[]).expect("quick.yaml loads");
    qsweep_pipeline::plan::plan(&loaded, None).expect("quick.yaml plans")
}

/// A deterministic outcome for a trial: mostly converged after a key-dependent number of
/// episodes; some capped, one diverged; every crisp Cart-Pole Q(0) trial fails.
fn synthetic(cap: u32, key: &Key, all_fail: bool) -> Outcome {
    let h = u32::from_le_bytes(key.0[..4].try_into().unwrap());
    let (converged, episodes, stop, failure) = if all_fail || h % 11 == 0 {
        (false, cap, StopReason::MaxEpisodes, None)
    } else if h % 97 == 1 {
        (false, 3, StopReason::Diverged, Some("non-finite TD error at episode 3, step 7".to_string()))
    } else {
        (true, 1 + h % 60, StopReason::Goal, None)
    };
    let episode_lengths: Vec<u32> = (0..episodes).map(|i| 10 + (h >> 8).wrapping_add(i * 7) % 500).collect();
    Outcome {
        converged,
        episodes_to_goal: converged.then_some(episodes),
        episodes,
        total_steps: episode_lengths.iter().map(|&l| u64::from(l)).sum(),
        stop,
        failure,
        episode_lengths,
    }
}

/// Records for every planned trial; the two trials of the first Ball-Beam cell are real.
fn records(plan: &Plan) -> HashMap<Key, TrialRecord> {
    let mut out = HashMap::new();
    let first = &plan.experiments[0].cells[0];
    assert_eq!(plan.experiments[0].system, SystemKind::BallBeam);
    for t in &first.trials {
        let mut cfg = first.config.clone();
        cfg.limits.max_episodes = 5; // keep the real trials short in debug builds
        let outcome = run_trial(&cfg, t.seed);
        out.insert(t.key, TrialRecord::new(first.config.clone(), t.seed, outcome, 0.25));
    }
    for (e, c, t) in plan.trials() {
        // Keys are shared between experiments (same configuration), so choose failures by configuration.
        let all_fail =
            e.system == SystemKind::CartPole && e.repr == ReprKind::Crisp && c.algorithm == Algorithm::Q0;
        out.entry(t.key).or_insert_with(|| {
            let outcome = synthetic(c.config.limits.max_episodes, &t.key, all_fail);
            TrialRecord::new(c.config.clone(), t.seed, outcome, 0.5)
        });
    }
    out
}

/// A cache in `dir` holding `records`, one segment.
fn cache_of(records: &HashMap<Key, TrialRecord>, dir: &Path) -> Store {
    let store = Store::open(dir).unwrap();
    let mut rows: Vec<TrialRecord> = records.values().cloned().collect();
    rows.sort_by_key(|r| r.key.0);
    store.write_segment(&rows).unwrap();
    store
}

/// The report of `plan` from `store` into `dir` in `formats`, as `qsweep report` writes it.
fn write_report(plan: &Plan, store: &Store, dir: &Path, formats: Formats) -> ReportSummary {
    let scan = qsweep_pipeline::run::scan(store).unwrap();
    let opts = ReportOptions { dir: dir.to_path_buf(), formats, force: false, rebuild: false };
    qsweep_report::write(plan.clone(), store, &scan.stored, &opts).unwrap().summary
}

fn files_under(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            for (k, v) in files_under(&p) {
                out.insert(PathBuf::from(p.file_name().unwrap()).join(k), v);
            }
        } else {
            out.insert(p.file_name().unwrap().into(), std::fs::read(&p).unwrap());
        }
    }
    out
}

/// Every `href="…"` and `src="…"` target of a page.
fn links(html: &str) -> Vec<String> {
    let mut out = Vec::new();
    for attr in ["href=\"", "src=\""] {
        let mut rest = html;
        while let Some(i) = rest.find(attr) {
            rest = &rest[i + attr.len()..];
            let end = rest.find('"').unwrap();
            out.push(rest[..end].to_string());
            rest = &rest[end..];
        }
    }
    out
}

#[test]
fn quick_report_is_complete_valid_and_deterministic() {
    let plan = quick_plan();
    let recs = records(&plan);
    let tmp = tempfile::tempdir().unwrap();
    let store = cache_of(&recs, &tmp.path().join("cache"));
    let dir = tmp.path().join("quick");
    let all = Formats::of(&Format::ALL);
    let summary = write_report(&plan, &store, &dir, all);
    assert_eq!(summary.experiments, 12);
    assert_eq!(summary.trials_planned, plan.trial_count());
    assert_eq!(summary.trials_cached, plan.trial_count());
    assert_eq!(summary.trials_missing, 0);
    assert_eq!(summary.cells_with_trials, summary.cells);

    let files = files_under(&dir);
    let mut expected: Vec<PathBuf> = [
        "table3.md",
        "table3.csv",
        "table3.tex",
        "cells.parquet",
        "trials.parquet",
        "index.html",
        "README.md",
        "manifest.json",
        "memo.json",
    ]
    .iter()
    .map(PathBuf::from)
    .collect();
    for s in SystemKind::ALL {
        expected.push(Path::new("figures").join(format!("{}.svg", s.name())));
        expected.push(Path::new("figures").join(format!("{}.png", s.name())));
        expected.push(Path::new("figures").join(format!("{}-curves.svg", s.name())));
        expected.push(Path::new("figures").join(format!("{}-curves.png", s.name())));
    }
    expected.sort();
    let mut written = summary.files.clone();
    written.sort();
    assert_eq!(written, expected);
    assert_eq!(files.keys().cloned().collect::<Vec<_>>(), expected, "no temporary files are left behind");

    // PNGs decode at the figure's size; SVGs are XML with the same size.
    for s in SystemKind::ALL {
        let exps: Vec<_> = qsweep_report::ReportData::build(&plan, &recs)
            .experiments
            .into_iter()
            .filter(|e| e.exp.system == s)
            .collect();
        let (w, h) = figures::figure_size(&exps.iter().collect::<Vec<_>>());
        assert_eq!(
            (w, h),
            (2 * figures::PANEL_W, figures::HEADER_H + 4 * figures::PANEL_H + figures::FOOTER_H)
        );
        let png = &files[&Path::new("figures").join(format!("{}.png", s.name()))];
        let mut reader = png::Decoder::new(std::io::Cursor::new(png.as_slice())).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (w, h), "{s} PNG size");
        assert!(buf.iter().any(|&b| b < 128), "{s} PNG has dark pixels (text, cells)");
        let svg = String::from_utf8(files[&Path::new("figures").join(format!("{}.svg", s.name()))].clone())
            .unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{s} SVG: {e}"));
        assert_eq!(doc.root_element().tag_name().name(), "svg");
        assert_eq!(doc.root_element().attribute("width"), Some(w.to_string().as_str()));
        assert!(svg.contains("Q(λ)-learning"), "{s} SVG has the panel titles");
        // The learning curves: one panel per experiment, two per row.
        let png = &files[&Path::new("figures").join(format!("{}-curves.png", s.name()))];
        let reader = png::Decoder::new(std::io::Cursor::new(png.as_slice())).read_info().unwrap();
        assert_eq!(
            (reader.info().width, reader.info().height),
            curves::figure_size(4),
            "{s} curves PNG size"
        );
    }

    // The page links only files of the report (or anchors on itself).
    let html = String::from_utf8(files[Path::new("index.html")].clone()).unwrap();
    assert!(!html.contains("http"), "index.html must not reference the network");
    let targets = links(&html);
    assert!(targets.iter().any(|t| t == "figures/cart-pole.svg"));
    assert!(targets.iter().any(|t| t == "figures/cart-pole-curves.svg"));
    for t in targets {
        if let Some(anchor) = t.strip_prefix('#') {
            assert!(html.contains(&format!("id=\"{anchor}\"")), "anchor {t}");
        } else {
            assert!(files.contains_key(Path::new(&t)), "index.html links {t}, which is not in the report");
        }
    }

    // Table III: 3 systems × 4 experiments × 2 algorithms; the all-failed cell uses the fallback.
    let csv = String::from_utf8(files[Path::new("table3.csv")].clone()).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 1 + 24);
    assert!(lines[0]
        .starts_with("system,experiment,algorithm,mean,std,x,x_dot,theta,theta_dot,actions,n,successes"));
    let md = String::from_utf8(files[Path::new("table3.md")].clone()).unwrap();
    for exp in ["1", "2"] {
        let row =
            md.lines().find(|l| l.starts_with(&format!("| Cart-Pole | {exp} | Q(0)-learning"))).unwrap();
        assert!(row.contains("400.00 ± 0.00†"), "{row}");
    }
    assert!(md.contains("lowest mean among the cells where every seed reached"));
    assert!(md.contains("count at the episode cap"));

    // The Markdown page shows Table III and links the SVG figures.
    let readme = String::from_utf8(files[Path::new("README.md")].clone()).unwrap();
    assert!(readme.starts_with("# qsweep report: quick\n"), "{readme}");
    assert!(
        readme.contains("](figures/cart-pole.svg)") && readme.contains("**Table III (quick).**"),
        "{readme}"
    );

    // A second run, into the same directory and into another, is byte-identical.
    write_report(&plan, &store, &dir, all);
    assert_eq!(files_under(&dir), files);
    let other = tmp.path().join("again");
    write_report(&plan, &store, &other, all);
    assert_eq!(files_under(&other), files);

    // The default formats: no PNG, the same bytes for everything else (but the manifest and the
    // memo, which list the formats and files).
    let default = tmp.path().join("default");
    let s = write_report(&plan, &store, &default, Formats::default());
    assert!(s.files.iter().all(|f| f.extension().is_some_and(|e| e != "png")), "{:?}", s.files);
    let d = files_under(&default);
    assert_eq!(d.len() + 6, files.len());
    let own = |n: &Path| n == Path::new("manifest.json") || n == Path::new("memo.json");
    for (name, bytes) in d.iter().filter(|(n, _)| !own(n)) {
        assert_eq!(&files[name], bytes, "{}", name.display());
    }
}

#[test]
fn missing_trials_are_counted_and_reference_values_compared() {
    let mut plan = quick_plan();
    plan.experiments[0].reference.insert(
        Algorithm::Q0,
        Reference { mean: 90.5, std: 25.8, resolution: Some(vec![5, 3]), actions: Some(3) },
    );
    let mut recs = records(&plan);
    // Drop every trial of the last cell and one trial of the first cell.
    let last = plan.experiments.last().unwrap().cells.last().unwrap();
    for t in &last.trials {
        recs.remove(&t.key);
    }
    recs.remove(&plan.experiments[0].cells[0].trials[0].key);
    let tmp = tempfile::tempdir().unwrap();
    let store = cache_of(&recs, &tmp.path().join("cache"));
    let out = tmp.path().join("report");
    let summary = write_report(&plan, &store, &out, Formats::default());
    // A removed key is missing from every cell that plans it (configurations recur across experiments).
    let missing = plan.trials().filter(|(_, _, t)| !recs.contains_key(&t.key)).count();
    assert!(missing > last.trials.len());
    assert_eq!(summary.trials_missing, missing);
    let empty = plan
        .experiments
        .iter()
        .flat_map(|e| &e.cells)
        .filter(|c| c.trials.iter().all(|t| !recs.contains_key(&t.key)))
        .count();
    assert!(empty >= 1);
    assert_eq!(summary.cells_with_trials, summary.cells - empty);

    let csv = std::fs::read_to_string(out.join("table3.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(header.contains(
        ",paper_mean,paper_std,paper_x,paper_x_dot,paper_theta,paper_theta_dot,paper_actions,diff_mean,"
    ));
    // The uncertainty columns follow, then ours at the paper's configuration, the verdicts and the
    // cause, so the earlier fields keep their positions.
    assert!(header.contains(
        ",ci_lo,ci_hi,censored,km_median,ratio,ratio_lo,ratio_hi,tost_p_n10,equivalent_n10,tost_p_n100,equivalent_n100,paper_cell_mean,"
    ), "{header}");
    assert!(
        header.ends_with(
            ",verdict_2se,paper_cell_verdict_2se,cause_2se,contradictory_pair,paper_inconsistent,\
             tost2x_p_n10,paper_cell_tost2x_p_n10,verdict,paper_cell_verdict,cause,std_ratio,\
             std_ratio_lo,std_ratio_hi,spread_differs"
        ),
        "{header}"
    );
    let row = csv.lines().nth(1).unwrap();
    assert!(row.starts_with("Ball-Beam,1,Q(0)-learning,"), "{row}");
    // The uncertainty columns agree with the row's own numbers.
    let r = &crate::helpers::csv_rows(&csv)[0];
    let f = |k: &str| r[k].parse::<f64>().unwrap_or_else(|_| panic!("{k}: {:?}", r[k]));
    assert!((f("ratio") - f("mean") / f("paper_mean")).abs() < 1e-12, "{r:?}");
    assert!((f("ratio_lo") - f("ci_lo") / f("paper_mean")).abs() < 1e-12, "{r:?}");
    assert!(f("ci_lo") <= f("mean") && f("mean") <= f("ci_hi"), "{r:?}");
    assert!((f("censored") - (f("n") - f("successes")) / f("n")).abs() < 1e-12, "{r:?}");
    // 27 against 90.5: far outside the 0.80-1.25 margin, never equivalent, whatever the paper's n.
    assert!(f("ratio_hi") < 0.8, "{r:?}");
    assert_eq!((r["equivalent_n10"].as_str(), r["equivalent_n100"].as_str()), ("no", "no"), "{r:?}");
    assert!(f("tost_p_n10") > 0.05 && f("tost_p_n100") > 0.05, "{r:?}");
    assert!(row.contains(",90.5,25.8,5,3,,,3,"), "{row}");
    let md = std::fs::read_to_string(out.join("table3.md")).unwrap();
    assert!(md.contains(&format!(
        "Only {} of {} planned trials are present.",
        summary.trials_cached, summary.trials_planned
    )));
    assert!(md.contains("| 90.50 ± 25.80 | 5, 3, —, —, 3 |"), "{md}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains(&format!("{} missing", summary.trials_missing)));
}
