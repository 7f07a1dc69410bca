//! A program pipeline's pages: `README.md` (for a repository's web page) and `index.html` (for a
//! browser), from one list of blocks so the two say the same thing. Per experiment: its best cell
//! by the objective, its figure, and a table of every cell's n, failures and, per scalar metric,
//! mean ± std with the 95 % bootstrap interval of the mean; then the list metrics' curves.

use super::figures;
use super::num;
use crate::derive::program::{ExperimentStats, ProgramStats};
use crate::render::escape;
use qsweep_pipeline::analysis::Summary;
use qsweep_pipeline::program::model::{Goal, ProgramPlan};
use qsweep_pipeline::program::race::RaceStanding;

/// The counts a page states at its top.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    /// Planned trials.
    pub planned: usize,
    /// Of those, present in the cache.
    pub present: usize,
    /// Of those, failed.
    pub failed: usize,
}

/// One block of a page.
enum Block {
    Heading(String),
    /// Text and the links in it: `(text, target)` pairs follow the text.
    Para(String, Vec<(String, String)>),
    Image(String, String),
    Table(Vec<String>, Vec<Vec<String>>),
}

fn blocks(plan: &ProgramPlan, stats: &ProgramStats, counts: Counts) -> Vec<Block> {
    let mut b = vec![Block::Heading(format!("qsweep report: {}", plan.name))];
    if let Some(d) = &plan.description {
        b.push(Block::Para(d.trim().to_string(), vec![]));
    }
    b.push(Block::Para(
        format!(
            "Trials present: {} of {} planned; {} failed. Each cell: n trials that succeeded, and per metric \
             mean ± sample std with the 95 % bootstrap interval of the mean (a bool's mean is its share of true). \
             Every trial's row is in trials.parquet beside this page (written with the report, not committed: \
             the cache holds the rows); every cell:",
            counts.present, counts.planned, counts.failed
        ),
        vec![("cells.parquet".into(), "cells.parquet".into())],
    ));
    if stats.objective.is_none() {
        b.push(Block::Para(
            "No objective declared (program.objective), so no cell is named best; figures show the first metric."
                .into(),
            vec![],
        ));
    }
    for e in &stats.experiments {
        let variant = e.variant.as_deref().map(|v| format!(" (variant {v})")).unwrap_or_default();
        let title = e.title.as_deref().map(|t| format!(": {t}")).unwrap_or_default();
        b.push(Block::Heading(format!("Experiment {}{title}{variant}", e.id)));
        b.extend(best_cell(stats, e).map(|t| Block::Para(t, vec![])));
        b.extend(e.race.as_ref().map(|r| Block::Para(race(r), vec![])));
        for f in figures::listed(stats, e) {
            b.push(Block::Image(f.path, f.alt));
        }
        b.push(cell_table(stats, e));
    }
    b
}

/// The best cell's line: its selection estimate and, with fresh seeds, its estimate on those.
fn best_cell(stats: &ProgramStats, e: &ExperimentStats) -> Option<String> {
    let ((m, goal), i) = (stats.objective?, e.best?);
    let c = &e.cells[i];
    let at: Vec<String> = e.axes.iter().zip(&c.coords).map(|(a, v)| format!("{a} = {v}")).collect();
    let at = if at.is_empty() { "the defaults".to_string() } else { at.join(", ") };
    let among = if e.race.is_some() { " among the race's contenders" } else { "" };
    let fresh = match &c.fresh {
        Some(f) => format!(
            " On {} fresh seeds, which took no part in choosing it: {} (95 % interval) over n = {}{}.",
            f.planned,
            estimate(&f.scalars[m]),
            f.scalars[m].n,
            if f.failed > 0 { format!(" ({} failed)", f.failed) } else { String::new() }
        ),
        None if e.fresh_seeds > 0 => {
            " Its fresh seeds are not run yet (they run once the best cell is decided).".to_string()
        }
        None => String::new(),
    };
    Some(format!(
        "Best cell by {} ({}{among}): {at}, {} over n = {} (selection estimate: on the seeds that \
         chose it).{fresh}",
        stats.scalars[m].0,
        match goal {
            Goal::Minimize => "lowest mean",
            Goal::Maximize => "highest mean",
        },
        estimate(&c.scalars[m]),
        c.scalars[m].n
    ))
}

/// What a race spent and where it stands.
fn race(r: &RaceStanding) -> String {
    format!(
        "Raced: {} of {} cells still contenders after {} of at most {} rounds{}; the race spent {} \
         trials where the full grid at max_seeds would take {}. A cell left the race when its mean \
         was significantly worse than the best's (one-sided Welch test, Holm over the round).",
        r.contenders,
        r.cells,
        r.rounds_done,
        r.rounds_max,
        if r.finished { " (over)" } else { " (not over yet)" },
        r.trials,
        r.without_race
    )
}

/// Every cell of `e`: its axes' values, n, failed, its race standing and each scalar metric.
fn cell_table(stats: &ProgramStats, e: &ExperimentStats) -> Block {
    let mut header: Vec<String> = e.axes.clone();
    header.extend(["n".to_string(), "failed".to_string()]);
    if e.race.is_some() {
        header.push("race".to_string());
    }
    for (name, _) in &stats.scalars {
        header.push(format!("{name}: mean ± std"));
        header.push(format!("{name}: 95 % interval"));
    }
    let rows = e
        .cells
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut r: Vec<String> = c.coords.iter().map(ToString::to_string).collect();
            if e.best == Some(i) {
                if let Some(first) = r.first_mut() {
                    first.push_str(" (best)");
                }
            }
            r.push(c.scalars.first().map_or(c.present - c.failed, |s| s.n).to_string());
            r.push(c.failed.to_string());
            if e.race.is_some() {
                r.push(if c.contender == Some(false) { "out" } else { "contender" }.to_string());
            }
            for s in &c.scalars {
                r.push(mean_std(s));
                r.push(interval(s));
            }
            r
        })
        .collect();
    Block::Table(header, rows)
}

/// `mean ± std [lo, hi]`, or what is known of it.
fn estimate(s: &Summary) -> String {
    format!("{} {}", mean_std(s), interval(s))
}

fn mean_std(s: &Summary) -> String {
    match (s.mean, s.std) {
        (Some(m), Some(sd)) => format!("{} ± {}", num(m), num(sd)),
        (Some(m), None) => num(m),
        _ => "—".into(),
    }
}

fn interval(s: &Summary) -> String {
    match (s.ci_lo, s.ci_hi) {
        (Some(lo), Some(hi)) => format!("[{}, {}]", num(lo), num(hi)),
        _ => "—".into(),
    }
}

/// `README.md`.
pub fn markdown(plan: &ProgramPlan, stats: &ProgramStats, counts: Counts) -> String {
    let mut m = String::new();
    for (i, b) in blocks(plan, stats, counts).into_iter().enumerate() {
        match b {
            Block::Heading(t) => {
                let level = if i == 0 { "#" } else { "##" };
                m.push_str(&format!("{level} {}\n\n", escape::markdown(&t)));
            }
            Block::Para(t, links) => {
                let links: Vec<String> =
                    links.iter().map(|(t, href)| format!("[{}]({href})", escape::markdown(t))).collect();
                let tail = if links.is_empty() { String::new() } else { format!(" {}.", links.join(", ")) };
                m.push_str(&format!("{}{tail}\n\n", escape::markdown(&t)));
            }
            Block::Image(src, alt) => m.push_str(&format!("![{}]({src})\n\n", escape::markdown(&alt))),
            Block::Table(header, rows) => {
                let cells = |r: &[String]| {
                    r.iter().map(|c| escape::markdown_in_cell(c)).collect::<Vec<_>>().join(" | ")
                };
                m.push_str(&format!("| {} |\n|{}\n", cells(&header), "---|".repeat(header.len())));
                for r in rows {
                    m.push_str(&format!("| {} |\n", cells(&r)));
                }
                m.push('\n');
            }
        }
    }
    m.truncate(m.trim_end().len());
    m.push('\n');
    m
}

/// `index.html`.
pub fn html(plan: &ProgramPlan, stats: &ProgramStats, counts: Counts) -> String {
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>qsweep report: {}</title>\n\
         <style>body{{font-family:sans-serif;max-width:70em;margin:auto;padding:1em}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:0.2em 0.5em;text-align:right}}\
         img{{max-width:100%}}</style>\n</head>\n<body>\n",
        escape::html(&plan.name)
    );
    for (i, b) in blocks(plan, stats, counts).into_iter().enumerate() {
        match b {
            Block::Heading(t) => {
                let tag = if i == 0 { "h1" } else { "h2" };
                h.push_str(&format!("<{tag}>{}</{tag}>\n", escape::html(&t)));
            }
            Block::Para(t, links) => {
                let links: Vec<String> = links
                    .iter()
                    .map(|(t, href)| format!("<a href=\"{}\">{}</a>", escape::html(href), escape::html(t)))
                    .collect();
                let tail = if links.is_empty() { String::new() } else { format!(" {}.", links.join(", ")) };
                h.push_str(&format!("<p>{}{tail}</p>\n", escape::html(&t)));
            }
            Block::Image(src, alt) => {
                h.push_str(&format!(
                    "<p><img src=\"{}\" alt=\"{}\"></p>\n",
                    escape::html(&src),
                    escape::html(&alt)
                ));
            }
            Block::Table(header, rows) => {
                h.push_str("<table>\n<tr>");
                for c in &header {
                    h.push_str(&format!("<th>{}</th>", escape::html(c)));
                }
                h.push_str("</tr>\n");
                for r in rows {
                    h.push_str("<tr>");
                    for c in &r {
                        h.push_str(&format!("<td>{}</td>", escape::html(c)));
                    }
                    h.push_str("</tr>\n");
                }
                h.push_str("</table>\n");
            }
        }
    }
    h.push_str("</body>\n</html>\n");
    h
}
