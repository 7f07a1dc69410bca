//! `qsweep bench`: steps per second of the production engine on the standard configurations.

use crate::bench::{self, BenchResult};
use crate::error::user_error;
use clap::Args;

/// Arguments of `qsweep bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Step budget per timed trial (each trial runs at least this many steps, under twice as many).
    #[arg(long, default_value_t = bench::DEFAULT_STEPS)]
    pub steps: u64,
    /// Timed trials per configuration; the fastest is reported.
    #[arg(long, default_value_t = bench::DEFAULT_REPEATS)]
    pub repeat: u32,
    /// Only configurations whose name contains this, e.g. `cart-pole/fuzzy`.
    #[arg(long, default_value = "")]
    pub filter: String,
    /// Print JSON (`{format_version, results: [{config, steps, seconds, steps_per_s}]}`) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Run `qsweep bench`.
pub fn run(a: BenchArgs) -> anyhow::Result<u8> {
    if !(1..=u64::from(u32::MAX)).contains(&a.steps) {
        return Err(user_error(format!("--steps: {} is not allowed; use 1 to {}", a.steps, u32::MAX)));
    }
    if a.repeat == 0 {
        return Err(user_error("--repeat: must be at least 1"));
    }
    let cases = bench::standard_cases();
    if !cases.iter().any(|c| c.name.contains(&a.filter)) {
        let names: Vec<_> = cases.iter().map(|c| c.name.as_str()).collect();
        return Err(user_error(format!(
            "--filter: no configuration contains '{}'; they are:\n  {}",
            a.filter,
            names.join("\n  ")
        )));
    }
    let print_row = |r: &BenchResult| {
        if !a.json {
            println!("{}", bench::format_row(r));
        }
    };
    if !a.json {
        println!("{}", bench::header());
    }
    let results = bench::run_cases(&cases, &a.filter, a.steps, a.repeat, print_row);
    if a.json {
        let v =
            super::json::BenchReport { format_version: super::json::BenchReport::FORMAT_VERSION, results };
        println!("{}", serde_json::to_string_pretty(&v)?);
    }
    Ok(0)
}
