//! Which files a report writes (`qsweep report --formats`): the tables, the Parquet data, the
//! figures as SVG and/or PNG, and the HTML page. The default is everything a reader looks at
//! plus the trial rows (`trials.parquet`, not committed), without PNG.

use std::fmt;

/// One kind of report output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Format {
    /// `table3.md` (and the comparison's `variants.md`, and `README.md` for repository pages).
    Md,
    /// `table3.csv` (and `variants.csv`).
    Csv,
    /// `table3.tex`.
    Tex,
    /// `cells.parquet`: one row per cell.
    Cells,
    /// `trials.parquet`: one row per trial of each cell (for pandas, polars, DuckDB).
    Trials,
    /// Figures as SVG.
    Svg,
    /// Figures as PNG.
    Png,
    /// `index.html`, linking the figures.
    Html,
}

impl Format {
    /// Every format, in the order of [`Format::name`]s in `--help`.
    pub const ALL: [Format; 8] = [
        Format::Md,
        Format::Csv,
        Format::Tex,
        Format::Cells,
        Format::Trials,
        Format::Svg,
        Format::Png,
        Format::Html,
    ];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Format::Md => "md",
            Format::Csv => "csv",
            Format::Tex => "tex",
            Format::Cells => "cells",
            Format::Trials => "trials",
            Format::Svg => "svg",
            Format::Png => "png",
            Format::Html => "html",
        }
    }
}

/// The default of `--formats`, as written in `--help`.
pub const DEFAULT_FORMATS: &str = "md,csv,tex,cells,trials,svg,html";

/// A set of formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Formats(u16);

impl Formats {
    /// The set of `formats`.
    pub fn of(formats: &[Format]) -> Self {
        Self(formats.iter().fold(0, |m, f| m | (1 << *f as u16)))
    }

    /// Whether `f` is in the set.
    pub fn has(self, f: Format) -> bool {
        self.0 & (1 << f as u16) != 0
    }

    /// The figure file type the HTML and Markdown pages show: SVG when written, else PNG.
    pub fn figure_ext(self) -> Option<&'static str> {
        if self.has(Format::Svg) {
            Some("svg")
        } else if self.has(Format::Png) {
            Some("png")
        } else {
            None
        }
    }
}

impl Default for Formats {
    /// Every format but PNG (SVG shows the same figures, and committed reports hold one format).
    fn default() -> Self {
        let all: Vec<Format> = Format::ALL.into_iter().filter(|f| *f != Format::Png).collect();
        Self::of(&all)
    }
}

impl fmt::Display for Formats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = Format::ALL.iter().filter(|x| self.has(**x)).map(|x| x.name()).collect();
        f.write_str(&names.join(","))
    }
}

// clap's names are the ones `--formats` takes, so these tests need its `ValueEnum`.
#[cfg(all(test, feature = "clap"))]
mod tests {
    use super::*;
    use clap::ValueEnum;

    #[test]
    fn the_default_is_what_help_says() {
        let parsed: Vec<Format> =
            DEFAULT_FORMATS.split(',').map(|s| Format::from_str(s, false).unwrap()).collect();
        assert_eq!(Formats::of(&parsed), Formats::default());
        assert_eq!(Formats::default().to_string(), DEFAULT_FORMATS);
        assert!(!Formats::default().has(Format::Png));
        for f in Format::ALL {
            assert_eq!(Format::from_str(f.name(), false).unwrap(), f, "clap names match");
        }
        assert_eq!(Formats::of(&[Format::Png]).figure_ext(), Some("png"));
        assert_eq!(Formats::of(&[Format::Md]).figure_ext(), None);
    }
}
