//! From derived numbers to files, for any pipeline: tables in CSV, Markdown, LaTeX and HTML
//! ([`table`]), the heatmaps (the paper's Figures 5–7) and learning curves as SVG or PNG
//! ([`figures`], [`curves`]), the pages (`index.html`, `README.md`), the Parquet datasets, and one
//! report folder written atomically ([`folder`]) with what a higher part adds to it
//! ([`addition`]); a program pipeline's files ([`program`]). Pure functions of what [`crate::derive`] computed: the same numbers give the
//! same bytes.

pub mod addition;
pub mod canvas;
pub mod curves;
pub mod datasets;
pub mod escape;
pub mod figures;
pub mod folder;
pub mod glyphs;
pub mod html;
pub mod log_axis;
pub mod markdown;
pub mod program;
pub mod svg;
pub mod svg_grid;
pub mod svg_text;
pub mod table;
pub mod text_fit;
