//! The format-neutral table: typed values in rows and columns, and the exporter trait that writes
//! one.

/// Horizontal alignment of a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Align {
    /// Text columns.
    Left,
    /// Number columns.
    Right,
}

/// A table column.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Heading as printed (Unicode, e.g. `ẋ`).
    pub title: String,
    /// Heading in LaTeX (e.g. `$\dot{x}$`); `None`: `title`, escaped.
    pub latex: Option<String>,
    /// CSV field names: one per field the column's values write.
    pub csv: Vec<String>,
    /// Alignment.
    pub align: Align,
}

impl Column {
    /// A column writing one CSV field.
    pub fn new(title: &str, csv: &str, align: Align) -> Self {
        Self { title: title.into(), latex: None, csv: vec![csv.into()], align }
    }

    /// Set the LaTeX heading.
    pub fn latex(mut self, latex: &str) -> Self {
        self.latex = Some(latex.into());
        self
    }

    /// Set the CSV fields (for values spanning several).
    pub fn fields(mut self, names: &[&str]) -> Self {
        self.csv = names.iter().map(|s| s.to_string()).collect();
        self
    }
}

/// One table value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// Absent (printed as a dash, an empty CSV field per field of the column).
    Missing,
    /// qsweep's own text (a word, a verdict, a computed label).
    Text(String),
    /// Text the pipeline's author wrote (a title, an id): shown as written in every format, so
    /// escaped as plain text where a format gives qsweep's own text more room (Markdown).
    User(String),
    /// A count or resolution.
    Int(u64),
    /// A number with `decimals` places; `signed` prints a leading `+` for positive values.
    Num {
        /// The number.
        value: f64,
        /// Decimal places in text formats (CSV writes the shortest exact form).
        decimals: usize,
        /// Print `+` before positive numbers.
        signed: bool,
    },
    /// `mean ± std` (two CSV fields); `marked` appends † (best cell chosen by the fallback rule).
    MeanStd {
        /// Mean.
        mean: f64,
        /// Standard deviation (missing for a single trial).
        std: Option<f64>,
        /// Decimal places in text formats.
        decimals: usize,
        /// Append the † mark.
        marked: bool,
    },
    /// An interval `[lo, hi]` (two CSV fields).
    Range {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
        /// Decimal places in text formats.
        decimals: usize,
    },
    /// Several small integers printed `a, b, —` (one CSV field each).
    List(Vec<Option<u32>>),
}

/// One table row.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// One value per column.
    pub values: Vec<Value>,
    /// Highlighted (the best cell in cell tables); formats that can show it do.
    pub highlight: bool,
}

/// A table: caption, columns and rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Short title, e.g. "Table III".
    pub title: String,
    /// Caption text (plain Unicode; writers escape it).
    pub caption: String,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows.
    pub rows: Vec<Row>,
}

/// How a format writes a table: its caption, header and rows. `begin` and `end` frame the whole.
pub trait TableWriter {
    /// Write whatever opens the table, including the caption where the format puts it first.
    fn begin(&self, table: &Table, out: &mut String);
    /// Write the header row.
    fn header(&self, columns: &[Column], out: &mut String);
    /// Write one row.
    fn row(&self, columns: &[Column], row: &Row, out: &mut String);
    /// Write whatever closes the table.
    fn end(&self, table: &Table, out: &mut String);
}

/// Render `table` with `writer`.
pub fn render(table: &Table, writer: &dyn TableWriter) -> String {
    let mut out = String::new();
    writer.begin(table, &mut out);
    writer.header(&table.columns, &mut out);
    for row in &table.rows {
        writer.row(&table.columns, row, &mut out);
    }
    writer.end(table, &mut out);
    out
}

/// The symbols and escaping of a text format.
pub(crate) struct Symbols {
    /// Missing value.
    pub dash: &'static str,
    /// Between mean and std.
    pub pm: &'static str,
    /// The fallback mark.
    pub dagger: &'static str,
    /// Escape qsweep's own text ([`Value::Text`]).
    pub escape: fn(&str) -> String,
    /// Escape the text a pipeline's author wrote ([`Value::User`]).
    pub user: fn(&str) -> String,
}

/// A fixed-point number, `-0.00` printed as `0.00`.
pub(crate) fn fixed(v: f64, decimals: usize, signed: bool) -> String {
    let s = format!("{v:.decimals$}");
    let s = if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    };
    if signed && !s.starts_with('-') && v != 0.0 && s.chars().any(|c| c.is_ascii_digit() && c != '0') {
        format!("+{s}")
    } else {
        s
    }
}

/// A value as text in a format with the given symbols.
pub(crate) fn display(v: &Value, sym: &Symbols) -> String {
    match v {
        Value::Missing => sym.dash.to_string(),
        Value::Text(t) => (sym.escape)(t),
        Value::User(t) => (sym.user)(t),
        Value::Int(i) => i.to_string(),
        Value::Num { value, decimals, signed } => fixed(*value, *decimals, *signed),
        Value::MeanStd { mean, std, decimals, marked } => {
            let std = std.map_or_else(|| sym.dash.to_string(), |s| fixed(s, *decimals, false));
            let mark = if *marked { sym.dagger } else { "" };
            format!("{}{}{std}{mark}", fixed(*mean, *decimals, false), sym.pm)
        }
        Value::Range { lo, hi, decimals } => {
            format!("[{}, {}]", fixed(*lo, *decimals, false), fixed(*hi, *decimals, false))
        }
        Value::List(items) => items
            .iter()
            .map(|i| i.map_or_else(|| sym.dash.to_string(), |i| i.to_string()))
            .collect::<Vec<_>>()
            .join(", "),
    }
}
