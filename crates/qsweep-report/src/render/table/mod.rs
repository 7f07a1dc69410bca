//! The table renderers: one [`crate::derive::table::TableWriter`] per format.

mod csv;
pub(crate) mod html;
mod latex;
mod markdown;

pub use csv::Csv;
pub use html::Html;
pub use latex::Latex;
pub use markdown::Markdown;

// The format-neutral table and the exporter trait every renderer implements.
pub use crate::derive::table::{render, Align, Column, Row, Table, TableWriter, Value};
