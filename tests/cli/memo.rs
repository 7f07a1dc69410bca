//! The report reruns only what changed (issue 37): a file whose bytes would not change is not
//! rewritten (its mtime stays), and the report line says how many files were rewritten.

use crate::helpers::Sandbox;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// Every file under `dir` (recursively) with its mtime.
fn mtimes(dir: &Path) -> BTreeMap<PathBuf, SystemTime> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    e.metadata().unwrap().modified().unwrap(),
                );
            }
        }
    }
    out
}

/// `files: N rewritten, M unchanged` of a report line.
fn files_line(stdout: &str) -> (usize, usize) {
    let tail = stdout.split("files: ").nth(1).unwrap_or_else(|| panic!("no files count: {stdout}"));
    let n: Vec<usize> = tail
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .take(2)
        .map(|s| s.parse().unwrap())
        .collect();
    (n[0], n[1])
}

#[test]
fn a_second_report_rewrites_no_file_and_keeps_every_mtime() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let (p, out) = (p.to_str().unwrap(), sb.path("rep"));
    let o = out.to_str().unwrap();
    let first = crate::helpers::stdout(&mut sb.qsweep(&["run", p, "--out", o]));
    let (written, unchanged) = files_line(&first);
    assert!(written > 20 && unchanged == 0, "{first}");
    let before = mtimes(&out);
    std::thread::sleep(std::time::Duration::from_millis(50));
    let again = crate::helpers::stdout(&mut sb.qsweep(&["report", p, "--out", o]));
    assert_eq!(files_line(&again), (0, written), "{again}");
    assert_eq!(mtimes(&out), before, "no file rewritten, trials.parquet included");
    assert!(before.contains_key(Path::new("trials.parquet")));
}

/// Every file under `dir` with its bytes.
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    mtimes(dir).into_keys().map(|p| (p.clone(), std::fs::read(dir.join(&p)).unwrap())).collect()
}

/// The cache's statistics' memos with their bytes.
fn derived_files(sb: &Sandbox) -> BTreeMap<PathBuf, Vec<u8>> {
    let dir = sb.cache().join("_derived");
    if dir.is_dir() {
        tree(&dir)
    } else {
        BTreeMap::new()
    }
}

/// Report `pipeline` incrementally into `inc` (with `run`, so new trials are computed) and with
/// `--rebuild` into a fresh folder; the two must be byte-identical, memos and trials included.
/// Returns the incremental report's line.
fn same_as_rebuild(sb: &Sandbox, pipeline: &Path, inc: &Path, extra: &[&str], what: &str) -> String {
    let p = pipeline.to_str().unwrap();
    let mut args = vec!["run", p, "--out", inc.to_str().unwrap()];
    args.extend(extra);
    let said = crate::helpers::stdout(&mut sb.qsweep(&args));
    let derived = derived_files(sb);
    let fresh = sb.path("rebuilt");
    let _ = std::fs::remove_dir_all(&fresh);
    let mut args = vec!["report", p, "--rebuild", "--out", fresh.to_str().unwrap()];
    args.extend(extra);
    crate::helpers::stdout(&mut sb.qsweep(&args));
    // The statistics' memo holds what --rebuild computes, bit for bit, once the report computed
    // something (a report of some variants adds to it; one that computed nothing leaves it).
    if !extra.contains(&"--variant")
        && said.contains("intervals: ")
        && !said.contains("intervals: 0 computed")
    {
        assert!(derived == derived_files(sb), "{what}: the statistics' memo differs from --rebuild's");
    }
    let (a, b) = (tree(inc), tree(&fresh));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>(), "{what}: the same files");
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{what}: {} differs from --rebuild's", name.display());
    }
    said
}

#[test]
fn the_incremental_report_equals_rebuild_after_each_kind_of_change() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let text = std::fs::read_to_string(&p).unwrap();
    let inc = sb.path("rep");
    same_as_rebuild(&sb, &p, &inc, &[], "first report");
    let said = same_as_rebuild(&sb, &p, &inc, &[], "nothing changed");
    assert_eq!(files_line(&said).0, 0, "nothing rewritten: {said}");

    // Seeds added (to every experiment, then back).
    same_as_rebuild(&sb, &p, &inc, &["--set", "seeds=3"], "seeds added");
    let said = same_as_rebuild(&sb, &p, &inc, &[], "seeds back");
    assert!(files_line(&said).0 > 0, "{said}");
    // A variant added.
    let added = format!("{text}  - id: slow-crisp\n    set: {{ systems.mountain-car.crisp.alpha: 0.002 }}\n");
    std::fs::write(&p, &added).unwrap();
    let kept = std::fs::read(inc.join("as-written/memo.json")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a variant added");
    // The other variants' folders stand as they were: their memos still match.
    assert_eq!(std::fs::read(inc.join("as-written/memo.json")).unwrap(), kept, "a variant added");
    // A variant's set changed.
    std::fs::write(&p, added.replace("alpha: 0.002", "alpha: 0.003")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a variant's set changed");
    // A reference value changed.
    std::fs::write(&p, added.replace("mean: 20, std: 5", "mean: 25, std: 5")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a reference value changed");
    // The formats changed (and back).
    same_as_rebuild(&sb, &p, &inc, &["--formats", "md,csv"], "formats changed");
    same_as_rebuild(&sb, &p, &inc, &[], "formats back");
}

#[test]
fn a_deleted_or_damaged_memo_or_report_is_recomputed_never_trusted() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let inc = sb.path("rep");
    same_as_rebuild(&sb, &p, &inc, &[], "first report");
    std::fs::remove_file(inc.join("fast-crisp/memo.json")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a memo deleted");
    std::fs::write(inc.join("memo.json"), "{\"format_version\": 1, \"inputs\": ").unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a memo corrupted");
    let m = std::fs::read_to_string(inc.join("as-written/memo.json")).unwrap();
    let forged = m.replace("\"experiments\": ", "\"experiments\": 1");
    assert_ne!(forged, m);
    std::fs::write(inc.join("as-written/memo.json"), forged).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a memo's counts forged");
    std::fs::remove_dir_all(inc.join("short-episodes")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a report folder deleted by hand");
    std::fs::write(inc.join("fast-crisp/table3.md"), "edited by hand").unwrap();
    let said = same_as_rebuild(&sb, &p, &inc, &[], "a report file edited by hand");
    assert!(files_line(&said).0 >= 1, "the edited file is rewritten: {said}");
    std::fs::remove_file(inc.join("trials.parquet")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "trials.parquet deleted");
}

#[test]
fn a_pipeline_without_variants_skips_its_intact_folder_and_rebuild_recomputes() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let inc = sb.path("rep");
    same_as_rebuild(&sb, &p, &inc, &[], "first report");
    let before = mtimes(&inc);
    let said = same_as_rebuild(&sb, &p, &inc, &[], "nothing changed");
    assert_eq!(files_line(&said).0, 0, "{said}");
    assert_eq!(mtimes(&inc), before);
    std::fs::write(inc.join("index.html"), "edited").unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a file edited");
    same_as_rebuild(&sb, &p, &inc, &["--set", "seeds=3"], "seeds added");
}

#[test]
fn grids_races_fresh_seeds_and_variant_subsets_are_skipped_when_intact() {
    for fixture in ["grid.yaml", "race.yaml", "fresh.yaml"] {
        let sb = Sandbox::new();
        let p = sb.fixture(fixture);
        let inc = sb.path("rep");
        same_as_rebuild(&sb, &p, &inc, &[], fixture);
        let before = mtimes(&inc);
        let said = same_as_rebuild(&sb, &p, &inc, &[], fixture);
        assert_eq!(files_line(&said).0, 0, "{fixture}: {said}");
        assert_eq!(mtimes(&inc), before, "{fixture}");
    }
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let inc = sb.path("rep");
    same_as_rebuild(&sb, &p, &inc, &["--variant", "fast-crisp"], "one variant");
    let said = same_as_rebuild(&sb, &p, &inc, &["--variant", "fast-crisp"], "one variant again");
    assert_eq!(files_line(&said).0, 0, "{said}");
}

/// The digest of every report file of the variants fixture (the memo and the trial rows, whose
/// informational `seconds` vary, left out) recorded with the [`ANALYSIS_VERSION`] it was written
/// under.
///
/// [`ANALYSIS_VERSION`]: qsweep_report::memo::ANALYSIS_VERSION
const GOLDEN: (u32, &str) = (6, "69db455647dfea8f97466ba2cedf57ca0d0cb119b631ab52b896b4807261d427");

#[test]
fn analysis_golden_outputs_change_only_with_analysis_version() {
    let sb = Sandbox::new();
    sb.fixture("variants.yaml");
    let out = sb.path("rep");
    // Relative paths: the pipeline's path is shown in the report.
    let formats = "md,csv,tex,cells,svg,html";
    sb.qsweep(&["run", "variants.yaml", "--quiet", "--formats", formats, "--out", "rep"]).assert().success();
    let mut h = blake3::Hasher::new();
    for (name, bytes) in tree(&out).iter().filter(|(n, _)| n.file_name().unwrap() != "memo.json") {
        h.update(name.to_string_lossy().as_bytes());
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    }
    let got = (qsweep_report::memo::ANALYSIS_VERSION, h.finalize().to_hex().to_string());
    assert_eq!(
        (got.0, got.1.as_str()),
        GOLDEN,
        "the report of a fixed input changed: if a definition or a file's layout changed on purpose, \
         bump ANALYSIS_VERSION (crates/qsweep-report/src/memo/mod.rs) so that no memo keeps the old files, and record \
         the new pair here"
    );
}

#[test]
fn report_json_says_what_was_recomputed_reused_and_written() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let (p, o) = (p.to_str().unwrap(), sb.path("rep"));
    let o = o.to_str().unwrap();
    let json = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["report", p, "--json", "--out", o];
        args.extend(extra);
        serde_json::from_str(&crate::helpers::stdout(&mut sb.qsweep(&args))).unwrap()
    };
    sb.qsweep(&["run", p, "--quiet", "--no-report"]).assert().success();
    let first = json(&[]);
    assert_eq!(first["format_version"], 1);
    assert_eq!(first["pipeline"], "variants");
    assert_eq!(first["cells_reused"], 0);
    assert_eq!(first["files_unchanged"], 0);
    let cells = first["cells_recomputed"].as_u64().unwrap();
    let files = first["files_written"].as_u64().unwrap();
    assert_eq!(cells, 3 * 12, "three variants of 12 cells");
    assert!(first["seconds"].as_f64().unwrap() >= 0.0);
    let again = json(&[]);
    assert_eq!((again["cells_recomputed"].as_u64(), again["cells_reused"].as_u64()), (Some(0), Some(cells)));
    assert_eq!((again["files_written"].as_u64(), again["files_unchanged"].as_u64()), (Some(0), Some(files)));
    let rebuilt = json(&["--rebuild"]);
    assert_eq!(
        (rebuilt["cells_recomputed"].as_u64(), rebuilt["files_written"].as_u64()),
        (Some(cells), Some(0))
    );
}

#[test]
fn verify_reports_damaged_memos_and_edited_report_files() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    sb.qsweep(&["run", p.to_str().unwrap(), "--quiet"]).assert().success();
    let ok = crate::helpers::stdout(&mut sb.qsweep(&["verify"]));
    assert!(ok.contains("report memos in reports: 4 intact, 0 damaged, 0 with edited files"), "{ok}");
    std::fs::write(sb.path("reports/variants/fast-crisp/table3.md"), "edited").unwrap();
    std::fs::write(sb.path("reports/variants/memo.json"), "{").unwrap();
    let out = sb.qsweep(&["verify"]).assert().code(1).get_output().stdout.clone();
    let out = String::from_utf8(out).unwrap();
    assert!(out.contains("damaged memo: reports/variants/memo.json"), "{out}");
    assert!(out.contains("differs from its memo: reports/variants/fast-crisp/table3.md"), "{out}");
    assert!(out.contains("2 intact, 1 damaged, 1 with edited files"), "{out}");
}

#[test]
fn status_explain_says_which_report_folders_are_stale_and_why() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let p = p.to_str().unwrap();
    sb.qsweep(&["run", p, "--quiet"]).assert().success();
    let fresh = crate::helpers::stdout(&mut sb.qsweep(&["status", p, "--explain"]));
    assert!(fresh.contains("report folders: 4 of 4 up to date"), "{fresh}");
    assert!(fresh.contains("cell intervals: 36 of 36 in the statistics' memo"), "{fresh}");
    assert!(!fresh.contains("interval computed by the next report"), "{fresh}");
    std::fs::write(sb.path("reports/variants/fast-crisp/table3.md"), "edited").unwrap();
    sb.qsweep(&["run", p, "--quiet", "--no-report", "--variant", "short-episodes", "--set", "seeds=3"])
        .assert()
        .success();
    let said = crate::helpers::stdout(&mut sb.qsweep(&["status", p, "--explain"]));
    assert!(
        said.contains("report reports/variants/fast-crisp is recomputed by the next report: files edited or missing since written: table3.md"),
        "{said}"
    );
    assert!(
        said.contains("report folders: 3 of 4 up to date"),
        "trials cached for another plan change nothing: {said}"
    );
    let more = crate::helpers::stdout(&mut sb.qsweep(&["status", p, "--explain", "--set", "seeds=3"]));
    // Only the cells that got a third seed need a new interval; the others' samples are as before.
    let stale: Vec<&str> =
        more.lines().filter(|l| l.starts_with("interval computed by the next report")).collect();
    assert!(!stale.is_empty() && stale.iter().all(|l| l.contains(": short-episodes:")), "{more}");
    assert!(more.contains(&format!("cell intervals: {} of 36", 36 - stale.len())), "{more}");
    assert!(
        more.contains("reports/variants/as-written is recomputed by the next report: its inputs changed"),
        "{more}"
    );
}

#[test]
fn the_statistics_memo_recomputes_only_the_intervals_whose_trials_changed() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let text = std::fs::read_to_string(&p).unwrap();
    let (ps, out) = (p.to_str().unwrap(), sb.path("rep"));
    let o = out.to_str().unwrap();
    let json = || -> serde_json::Value {
        let s = crate::helpers::stdout(&mut sb.qsweep(&["report", ps, "--json", "--out", o]));
        serde_json::from_str(&s).unwrap()
    };
    let counts = |v: &serde_json::Value| {
        (v["intervals_computed"].as_u64().unwrap(), v["intervals_reused"].as_u64().unwrap())
    };
    sb.qsweep(&["run", ps, "--quiet", "--no-report"]).assert().success();
    let (all, none) = counts(&json());
    assert!(all > 36 && none == 0, "every cell's interval and every difference's: {all}");
    let memo = sb.cache().join("_derived/variants.bin");
    assert!(memo.is_file());

    // The report recomputed (its memo.json gone): every interval is taken from the memo, and
    // the memo, nothing computed, is left as it was (so is one for fewer formats elsewhere).
    let kept = std::fs::read(&memo).unwrap();
    std::fs::remove_file(out.join("memo.json")).unwrap();
    let again = json();
    assert_eq!(counts(&again), (0, all));
    assert_eq!(again["files_written"], 1, "only memo.json, written again");
    let elsewhere = sb.path("csv-only");
    sb.qsweep(&["report", ps, "--out", elsewhere.to_str().unwrap(), "--formats", "csv,cells", "--quiet"])
        .assert()
        .success();
    assert_eq!(std::fs::read(&memo).unwrap(), kept, "a report that computed nothing keeps the memo");

    // A variant added: its own intervals and differences are computed, the others' reused (and
    // its cells whose trials are the base's too).
    let added = format!("{text}  - id: slow-crisp\n    set: {{ systems.mountain-car.crisp.alpha: 0.002 }}\n");
    std::fs::write(&p, &added).unwrap();
    sb.qsweep(&["run", ps, "--quiet", "--no-report"]).assert().success();
    let (computed, reused) = counts(&json());
    assert!(computed > 0 && computed < all && reused > 0, "{computed} computed, {reused} reused of {all}");

    // A damaged memo: verify says so (exit 1), the report recomputes everything and mends it.
    let mut bytes = std::fs::read(&memo).unwrap();
    bytes[40] ^= 0xff;
    std::fs::write(&memo, &bytes).unwrap();
    let v = sb.qsweep(&["verify", "--reports", o]).assert().code(1).get_output().stdout.clone();
    let v = String::from_utf8(v).unwrap();
    assert!(v.contains("damaged statistics' memo: ") && v.contains("0 intact (0 entries), 1 damaged"), "{v}");
    std::fs::remove_file(out.join("memo.json")).unwrap();
    assert_eq!(counts(&json()), (computed + reused, 0));
    same_as_rebuild(&sb, &p, &out, &[], "after a damaged statistics' memo");
    let v = crate::helpers::stdout(&mut sb.qsweep(&["verify", "--reports", o]));
    assert!(v.contains("statistics' memos: 1 intact"), "{v}");

    // gc keeps the memo of the pipelines it is given, drops the others'.
    let kept = crate::helpers::stdout(&mut sb.qsweep(&["gc", ps]));
    assert!(kept.contains(", 0 statistics' memos and trial parts;") && memo.is_file(), "{kept}");
    let other = sb.fixture("tiny.yaml");
    let gone = crate::helpers::stdout(&mut sb.qsweep(&["gc", other.to_str().unwrap()]));
    assert!(gone.contains(", 2 statistics' memos and trial parts;") && !memo.exists(), "{gone}");
    assert!(!sb.cache().join("_derived/variants.trials").exists(), "its trial parts go with it");
}

#[test]
fn trial_parts_are_reused_and_a_damaged_one_is_encoded_again() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let inc = sb.path("rep");
    same_as_rebuild(&sb, &p, &inc, &[], "first report");
    let parts_dir = sb.cache().join("_derived/variants.trials");
    let parts = || -> BTreeMap<PathBuf, SystemTime> {
        mtimes(&parts_dir)
            .into_iter()
            .filter(|(p, _)| p.extension().is_some_and(|x| x == "parquet"))
            .collect()
    };
    let before = parts();
    assert_eq!(before.len(), 3, "one part per declared variant: {before:?}");
    // The comparison recomputed: every part is reused as it is.
    std::fs::remove_file(inc.join("memo.json")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "the comparison recomputed");
    std::fs::remove_file(inc.join("memo.json")).unwrap();
    let after_rebuild = parts();
    let said = crate::helpers::stdout(&mut sb.qsweep(&[
        "report",
        p.to_str().unwrap(),
        "--out",
        inc.to_str().unwrap(),
    ]));
    assert_eq!(parts(), after_rebuild, "no part encoded again: {said}");
    // A damaged part is encoded again, and the combined file is still --rebuild's.
    let (name, _) = after_rebuild.iter().next().unwrap();
    let part = parts_dir.join(name);
    let bytes = std::fs::read(&part).unwrap();
    std::fs::write(&part, &bytes[..bytes.len() / 2]).unwrap();
    let v = sb
        .qsweep(&["verify", "--reports", inc.to_str().unwrap()])
        .assert()
        .code(1)
        .get_output()
        .stdout
        .clone();
    let v = String::from_utf8(v).unwrap();
    assert!(
        v.contains("damaged trial part: ") && v.contains("trial parts: 2 whole, 1 damaged, 0 without"),
        "{v}"
    );
    std::fs::remove_file(inc.join("memo.json")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a damaged part");
    // A part whose bytes changed in place (its footer intact) is encoded again too.
    let mut flipped = bytes.clone();
    flipped[100] ^= 0xff;
    std::fs::write(&part, &flipped).unwrap();
    std::fs::remove_file(inc.join("memo.json")).unwrap();
    same_as_rebuild(&sb, &p, &inc, &[], "a part changed in place");
    assert_eq!(std::fs::read(&part).unwrap(), bytes);
    assert_eq!(std::fs::read(&part).unwrap(), bytes, "the part encoded again is the same");
    // A variant changed: its part is replaced, the others stay.
    same_as_rebuild(&sb, &p, &inc, &["--set", "seeds=3"], "seeds added");
    assert_eq!(parts().len(), 3, "a full report keeps only the parts it used");
}

#[test]
fn memos_of_an_older_analysis_version_are_recomputed() {
    use qsweep_report::memo::folders::Memo;
    use qsweep_report::memo::ANALYSIS_VERSION;
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let inc = sb.path("rep");
    same_as_rebuild(&sb, &p, &inc, &[], "first report");
    // Every memo as an older build would have written it: sealed, of the version before.
    for dir in ["", "as-written", "fast-crisp", "short-episodes"] {
        let path = inc.join(dir).join("memo.json");
        let mut m: Memo = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        m.analysis_version = ANALYSIS_VERSION - 1;
        m.seal = String::new();
        m.seal = blake3::hash(&serde_json::to_vec(&m).unwrap()).to_hex().to_string();
        std::fs::write(&path, serde_json::to_string_pretty(&m).unwrap() + "\n").unwrap();
    }
    // The statistics' memo too: its header names the version, and so does every entry's id.
    let stats = sb.cache().join("_derived/variants.bin");
    let mut bytes = std::fs::read(&stats).unwrap();
    bytes[12..16].copy_from_slice(&(ANALYSIS_VERSION - 1).to_le_bytes());
    let n = bytes.len() - 32;
    let sum = *blake3::hash(&bytes[..n]).as_bytes();
    bytes[n..].copy_from_slice(&sum);
    std::fs::write(&stats, &bytes).unwrap();
    let said = same_as_rebuild(&sb, &p, &inc, &[], "an older ANALYSIS_VERSION");
    assert!(
        said.contains("cells: 36 recomputed, 0 reused; intervals: ")
            && !said.contains("intervals: 0 computed"),
        "{said}"
    );
}

#[test]
fn a_cache_that_cannot_keep_trial_parts_still_gets_the_same_report() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let inc = sb.path("rep");
    sb.qsweep(&["run", p.to_str().unwrap(), "--quiet", "--no-report"]).assert().success();
    // Where the parts would go is a file: the cache cannot keep them.
    std::fs::create_dir_all(sb.cache().join("_derived")).unwrap();
    std::fs::write(sb.cache().join("_derived/variants.trials"), "not a folder").unwrap();
    let out = sb
        .qsweep(&["report", p.to_str().unwrap(), "--out", inc.to_str().unwrap()])
        .assert()
        .success()
        .get_output()
        .clone();
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("cannot keep trial parts"), "{err}");
    same_as_rebuild(&sb, &p, &inc, &[], "parts not kept");
    let left: Vec<_> = std::fs::read_dir(&inc).unwrap().flatten().map(|e| e.file_name()).collect();
    assert!(left.iter().all(|n| !n.to_string_lossy().starts_with(".tmp-")), "{left:?}");
}
