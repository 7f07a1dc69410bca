//! The guide's reference tables against the code: a field the code defines and the guide does not
//! list fails, and so does one the guide lists and the code does not. The code's side is taken
//! from what the code itself emits or declares, so there is one definition of each list: the
//! `--json` objects the binary prints (docs/json.md), the cache's Arrow schema
//! (docs/reading-results.md), the columns of a committed `table3.csv` (docs/reports.md), and the
//! setting names the pipeline parser offers in its unknown-field error (docs/pipelines.md).
//! README's and REPLICATION.md's answer (counts, example rows, the yardstick) is checked against
//! the committed report by `tests/python/test_readme_answer.py`.

use crate::markdown::{prose_lines, repo};
use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

/// The backticked names of the first column of the Markdown table that starts after the first
/// line of `text` containing `marker` (e.g. "`qsweep run --json`").
fn table_after(text: &str, marker: &str) -> BTreeSet<String> {
    let lines = prose_lines(text);
    let start =
        lines.iter().position(|l| l.contains(marker)).unwrap_or_else(|| panic!("no `{marker}` in the guide"));
    lines[start..]
        .iter()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2) // header and rule
        .flat_map(|row| backticked(row.split('|').nth(1).unwrap_or("")))
        .collect()
}

/// The `…`-quoted words of `s`.
fn backticked(s: &str) -> Vec<String> {
    s.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

fn guide(chapter: &str) -> String {
    std::fs::read_to_string(repo().join("docs").join(chapter)).unwrap()
}

/// Runs the binary in `dir` and returns stdout, asserting exit 0.
fn qsweep(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_qsweep"))
        .args(args)
        .current_dir(dir)
        .env_remove("QSWEEP_CACHE")
        .output()
        .unwrap();
    assert!(out.status.success(), "qsweep {}: {}", args.join(" "), String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// The top-level keys of a JSON object printed by the binary.
fn json_keys(stdout: &str) -> BTreeSet<String> {
    let v: serde_json::Value = serde_json::from_str(stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    v.as_object().expect("a JSON object").keys().cloned().collect()
}

#[test]
fn json_tables_list_exactly_the_fields_each_command_prints() {
    let dir = tempfile::tempdir().unwrap();
    let fixtures = repo().join("tests/fixtures/pipelines");
    for f in ["tiny.yaml", "race.yaml"] {
        std::fs::copy(fixtures.join(f), dir.path().join(f)).unwrap();
    }
    let d = dir.path();
    let text = guide("json.md");
    let trial = [
        "trial",
        "--env",
        "cart-pole",
        "--repr",
        "crisp",
        "--resolution",
        "2,2,2,2",
        "--algorithm",
        "q0",
        "--set",
        "max_episodes=3",
        "--json",
    ];
    // A program pipeline too: its run adds `unfinished`, its status has a table of its own.
    std::fs::write(
        d.join("prog.yaml"),
        "name: prog\nprogram:\n  command: [sh, -c, 'cat >/dev/null; echo \"{\\\"x\\\": 1}\"']\n  \
         metrics: { x: int }\nparams: { a: 1 }\nseeds: 1\n",
    )
    .unwrap();
    // And a raced one, so its status prints the optional `race` list.
    std::fs::write(
        d.join("prog-race.yaml"),
        "name: prog-race\nprogram:\n  command: [sh, -c, 'cat >/dev/null; echo \"{\\\"x\\\": 1}\"']\n  \
         metrics: { x: int }\n  objective: { metric: x, goal: minimize }\nparams: { a: 1 }\nseeds: 2\n\
         race: { confidence: 0.95, batch: 1, max_seeds: 3 }\nexperiments:\n  - { id: e, vary: { a: [1, 2] } }\n",
    )
    .unwrap();
    let program_run = qsweep(d, &["run", "prog.yaml", "--json", "--quiet"]);
    let engine_run = qsweep(d, &["run", "tiny.yaml", "--json", "--no-report", "--quiet"]);
    // The program pipeline against itself: one cell, one trial a side (no test, but every field).
    let compare = qsweep(d, &["compare", "prog.yaml", "prog.yaml", "--metric", "x", "--json"]);
    let cell: serde_json::Value =
        serde_json::from_str::<serde_json::Value>(&compare).unwrap()["cells"][0].clone();
    assert_eq!(
        table_after(&text, "Each of `cells`:"),
        cell.as_object().expect("a compared cell").keys().cloned().collect::<BTreeSet<String>>(),
        "docs/json.md's table of a compared cell against `qsweep compare --json`'s cells"
    );
    let cases: Vec<(&str, String)> = vec![
        ("`qsweep status --json` on a", qsweep(d, &["status", "prog-race.yaml", "--json"])),
        ("`qsweep report --json`", qsweep(d, &["report", "tiny.yaml", "--json", "--out", "r"])),
        // A raced pipeline, so the optional `race` list is printed too.
        ("`qsweep status --json`", qsweep(d, &["status", "race.yaml", "--json"])),
        ("`qsweep trial --json`", qsweep(d, &trial)),
        ("`qsweep compare --json`", compare),
        (
            "`qsweep bench --json`",
            qsweep(d, &["bench", "--steps", "1000", "--filter", "cart-pole/crisp/q0/2^4", "--json"]),
        ),
        (
            "`qsweep bench --pipeline P --json`",
            qsweep(d, &["bench", "--pipeline", "tiny.yaml", "--top", "1", "--json"]),
        ),
        (
            "`qsweep feasible --json`",
            qsweep(
                d,
                &["feasible", "--env", "cart-pole", "--resolution", "2", "--max-nodes", "100", "--json"],
            ),
        ),
    ];
    let run_keys: BTreeSet<String> =
        json_keys(&program_run).union(&json_keys(&engine_run)).cloned().collect();
    assert_eq!(
        table_after(&text, "`qsweep run --json`"),
        run_keys,
        "docs/json.md's table after `qsweep run --json` against the binary's output (engine and program)"
    );
    for (marker, stdout) in cases {
        assert_eq!(
            table_after(&text, marker),
            json_keys(&stdout),
            "docs/json.md's table after {marker} against the binary's output"
        );
    }
}

#[test]
fn the_cache_column_table_lists_exactly_the_schema() {
    let documented = table_after(&guide("reading-results.md"), "cache's columns, one row per trial");
    let schema: BTreeSet<String> =
        qsweep_pipeline::cache::rows::schema().fields().iter().map(|f| f.name().clone()).collect();
    assert_eq!(documented, schema, "docs/reading-results.md's cache columns against cache::rows::schema()");
}

#[test]
fn the_uncertainty_table_lists_exactly_table3_csv_s_last_columns() {
    let documented = table_after(&guide("reports.md"), "The uncertainty columns of `table3.csv`");
    // A committed report of a pipeline with references and fresh seeds: every column is written.
    let csv = std::fs::read_to_string(repo().join("reports/paper/as-written/table3.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let from = header.iter().position(|c| *c == "ci_lo").expect("table3.csv has ci_lo");
    let written: BTreeSet<String> = header[from..].iter().map(|c| c.to_string()).collect();
    assert_eq!(
        documented, written,
        "docs/reports.md's uncertainty columns against reports/paper/as-written/table3.csv"
    );
}

#[test]
fn the_settings_list_names_exactly_the_settings_the_parser_accepts() {
    let text = guide("pipelines.md");
    let para: String = prose_lines(&text)
        .iter()
        .skip_while(|l| !l.starts_with("Settings (any level"))
        .take_while(|l| !l.trim().is_empty())
        .cloned()
        .collect::<Vec<_>>()
        .join(" ");
    let list = para
        .split("experiment `settings`):")
        .nth(1)
        .expect("the settings paragraph")
        .split("; e.g.")
        .next()
        .unwrap();
    // Backticked words that are names, not values in parentheses (`random`|`first`).
    let mut documented = BTreeSet::new();
    let mut depth = 0;
    for (i, part) in list.split('`').enumerate() {
        if i % 2 == 0 {
            depth += part.matches('(').count() as i32 - part.matches(')').count() as i32;
        } else if depth == 0 {
            documented.insert(part.to_string());
        }
    }
    // The parser's own list: an unknown setting's error names every accepted one.
    let accepted = parser_fields("defaults: { bogus: 1 }\nsystems: {}\n");
    assert_eq!(documented, accepted, "docs/pipelines.md's settings against the parser's");
}

/// The keys the pipeline parser accepts in the section where `body` (after `name` and `seeds`)
/// puts the unknown key `bogus`: its error lists them ("expected one of `a`, `b`", "expected `a`
/// or `b`", "expected `a`").
fn parser_fields(body: &str) -> BTreeSet<String> {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("t.yaml"), format!("name: t\nseeds: 1\n{body}")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_qsweep"))
        .args(["status", "t.yaml"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("unknown field `bogus`"), "not an unknown-field error for {body}: {stderr}");
    let list = stderr.split("unknown field `bogus`, expected").nth(1).unwrap().split(';').next().unwrap();
    backticked(list).into_iter().collect()
}

#[test]
fn the_field_tables_list_exactly_the_keys_the_parser_accepts() {
    let text = guide("pipelines.md");
    let exp = "systems:\n  ball-beam:\n    experiments:\n      - { id: 1, bogus: 1, repr: crisp, vary: { x: [2], x_dot: [2] } }\n";
    let cases = [
        ("### Top level", "bogus: 1\nsystems: {}\n"),
        ("### A system (`systems.NAME`)", "systems:\n  ball-beam:\n    bogus: 1\n"),
        ("### An experiment (`systems.NAME.experiments.N`)", exp),
        ("### A variant (`variants.N`)", "variants: [{ id: a, bogus: 1 }]\nsystems: {}\n"),
        ("### `race`", "race: { bogus: 1 }\nsystems: {}\n"),
        ("### `fresh`", "fresh: { bogus: 1 }\nsystems: {}\n"),
        ("### `exploratory`", "exploratory: { bogus: 1 }\nsystems: {}\n"),
    ];
    for (heading, body) in cases {
        assert_eq!(
            table_after(&text, heading),
            parser_fields(body),
            "docs/pipelines.md's table under {heading} against the parser"
        );
    }
}

/// The column names of a committed CSV's header.
fn csv_header(rel: &str) -> Vec<String> {
    let text = std::fs::read_to_string(repo().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
    text.lines().next().unwrap_or("").split(',').map(str::to_string).collect()
}

/// The column names of a committed Parquet file.
fn parquet_columns(rel: &str) -> BTreeSet<String> {
    let file = std::fs::File::open(repo().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
    let reader = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file).unwrap();
    reader.schema().fields().iter().map(|f| f.name().clone()).collect()
}

#[test]
fn the_report_column_tables_list_exactly_the_columns_written() {
    let text = guide("reports.md");
    let table3 = csv_header("reports/paper/as-written/table3.csv");
    let leading: BTreeSet<String> = table3.iter().take_while(|c| *c != "ci_lo").cloned().collect();
    assert_eq!(
        table_after(&text, "The first columns of `table3.csv`"),
        leading,
        "docs/reports.md against table3.csv"
    );
    // The paper's cells carry `variant` and the fresh columns, a raced pipeline's `contender`.
    let mut cells = parquet_columns("reports/paper/as-written/cells.parquet");
    cells.extend(parquet_columns("reports/paper-race/cells.parquet"));
    assert_eq!(
        table_after(&text, "`cells.parquet`, one row per heatmap cell"),
        cells,
        "docs/reports.md against cells.parquet"
    );
    let variants: BTreeSet<String> = csv_header("reports/paper/variants.csv").into_iter().collect();
    assert_eq!(
        table_after(&text, "`variants.csv` (the comparison folder)"),
        variants,
        "docs/reports.md against variants.csv"
    );
}

#[test]
fn the_trials_parquet_table_lists_exactly_the_columns_written() {
    // trials.parquet is not committed: write one, of a pipeline with variants and fresh seeds so
    // that the conditional `variant` and `fresh` columns are there (a fraction of a second).
    let dir = tempfile::tempdir().unwrap();
    let fixture = std::fs::read_to_string(repo().join("tests/fixtures/pipelines/fresh.yaml")).unwrap();
    let pipeline = format!("{fixture}variants:\n  - id: a\n  - id: b\n    set: {{ defaults.q_init: 1 }}\n");
    std::fs::write(dir.path().join("p.yaml"), pipeline).unwrap();
    qsweep(dir.path(), &["run", "p.yaml", "--cache", "c", "--out", "r", "--formats", "trials", "--quiet"]);
    let file = std::fs::File::open(dir.path().join("r/trials.parquet")).unwrap();
    let reader = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file).unwrap();
    let written: BTreeSet<String> = reader.schema().fields().iter().map(|f| f.name().clone()).collect();
    let documented = table_after(&guide("reports.md"), "`trials.parquet`, one row per trial of each cell");
    assert_eq!(documented, written, "docs/reports.md's trials.parquet columns against a report's");
}

#[test]
fn the_program_cells_parquet_table_lists_exactly_the_columns_written() {
    let documented = table_after(&guide("reports.md"), "`cells.parquet` of a program pipeline");
    let written: BTreeSet<String> =
        qsweep_report::render::program::CELL_COLUMNS.iter().map(|c| c.to_string()).collect();
    assert_eq!(documented, written, "docs/reports.md's program cells.parquet columns against CELL_COLUMNS");
}
