//! `cargo bench`: the same measurement as `qsweep bench`, through the same library function.
//! An optional first non-flag argument filters configurations by name, e.g.
//! `cargo bench --bench engine -- cart-pole/fuzzy`.

use qsweep_pipeline::bench;

fn main() {
    // cargo passes `--bench`; any other non-flag argument is the filter.
    let filter = std::env::args().skip(1).find(|a| !a.starts_with('-')).unwrap_or_default();
    println!("{}", bench::header());
    bench::run_cases(&bench::standard_cases(), &filter, bench::DEFAULT_STEPS, bench::DEFAULT_REPEATS, |r| {
        println!("{}", bench::format_row(r))
    });
}
