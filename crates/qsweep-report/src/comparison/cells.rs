//! A side of a comparison given as cells already gathered: an engine pipeline's cells with each
//! metric's per-trial values ([`super::engine`]), or a report folder's cells with the moments of
//! their one metric ([`super::folder`]). Both name their params alike ([`ENGINE_PARAMS`]), so an
//! engine pipeline, an engine report folder and a program pipeline that declares those params (or
//! maps its own onto them with `--map`) match cell by cell.

use qsweep_pipeline::analysis::Moments;
use qsweep_pipeline::program::model::ParamValue;

/// A param's value where a cell has none (a state variable its system lacks, a setting its
/// experiment does not vary): text, so it never matches a number.
pub const ABSENT: &str = "-";

/// The params every engine cell has, in order, before the varied settings: `system`, `repr`,
/// `algorithm`, `experiment` (an integer when the id is one), the bins or fuzzy sets of each
/// state variable (`-` where the system lacks it), `actions`, and `resolution` (the bins per
/// variable when all of a cell's variables have the same, else the list, e.g. `6x3x6x3`). Each
/// varied setting or physical parameter (`alpha`, `gravity`) follows under its own name.
pub const ENGINE_PARAMS: [&str; 10] = [
    "system",
    "repr",
    "algorithm",
    "experiment",
    "x",
    "x_dot",
    "theta",
    "theta_dot",
    "actions",
    "resolution",
];

/// The metric of an engine cell that Table III averages and the default of `qsweep compare`: the
/// episodes to the learning goal, counted as the pipeline's `counting:` says, at the cap for a
/// trial that never reached it ([`qsweep_pipeline::analysis::episodes_counted`]).
pub const EPISODES: &str = "episodes";

/// One side's values of the metric in one cell.
#[derive(Debug, Clone, PartialEq)]
pub enum Sample {
    /// Every trial's value (a pipeline's cells).
    Values(Vec<f64>),
    /// The mean, sample std and n alone (a report folder's `cells.parquet`).
    Moments(Moments),
}

impl Sample {
    /// Trials in the sample.
    pub fn n(&self) -> usize {
        match self {
            Self::Values(v) => v.len(),
            Self::Moments(m) => m.n,
        }
    }

    /// Its moments.
    pub fn moments(&self) -> Moments {
        match self {
            Self::Values(v) => Moments::of(v),
            Self::Moments(m) => *m,
        }
    }
}

/// A side's cells.
#[derive(Debug, Clone, PartialEq)]
pub struct CellSet {
    /// What the side is, for messages: `engine pipeline`, `report folder`.
    pub what: &'static str,
    /// The params' names, in order.
    pub params: Vec<String>,
    /// The metrics each cell has a sample of, the default first.
    pub metrics: Vec<String>,
    /// The cells, in plan (or file) order.
    pub cells: Vec<SetCell>,
}

/// One cell of a [`CellSet`].
#[derive(Debug, Clone, PartialEq)]
pub struct SetCell {
    /// Its params' values, in [`CellSet::params`] order.
    pub params: Vec<ParamValue>,
    /// Equal for two cells of one configuration (the same trials), e.g. in two experiments: such
    /// cells are one cell when they share the matched params.
    pub identity: String,
    /// Its sample of each metric, in [`CellSet::metrics`] order.
    pub samples: Vec<Sample>,
}

/// An experiment id as a param: an integer when it is one (`experiment: 1` in a program's
/// params matches the paper's experiment `1`), else text.
pub fn experiment_value(id: &str) -> ParamValue {
    id.parse::<i64>().map_or_else(|_| ParamValue::Str(id.to_string()), ParamValue::Int)
}

/// A count (bins, actions) as a param; [`ABSENT`] when there is none.
pub fn count_value(v: Option<u32>) -> ParamValue {
    v.map_or_else(|| ParamValue::Str(ABSENT.to_string()), |v| ParamValue::Int(i64::from(v)))
}

/// The `resolution` param of a cell with `resolution` (its bins per state variable).
pub fn resolution_value(resolution: &[u32]) -> ParamValue {
    match resolution.first() {
        Some(&first) if resolution.iter().all(|&r| r == first) => ParamValue::Int(i64::from(first)),
        _ => ParamValue::Str(resolution.iter().map(u32::to_string).collect::<Vec<_>>().join("x")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn engine_param_values_are_numbers_where_a_program_writes_numbers() {
        assert_eq!(experiment_value("3"), ParamValue::Int(3));
        assert_eq!(experiment_value("3b"), ParamValue::Str("3b".into()));
        assert_eq!(resolution_value(&[6, 6, 6, 6]), ParamValue::Int(6));
        assert_eq!(resolution_value(&[6, 3, 6, 3]), ParamValue::Str("6x3x6x3".into()));
        assert_eq!(count_value(None), ParamValue::Str("-".into()));
        assert_eq!(Sample::Values(vec![1.0, 3.0]).moments().mean, 2.0);
    }
}
