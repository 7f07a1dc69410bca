//! The documentation's own tests (`cargo test --test docs`): every console example in README.md
//! and the guide runs against the built binary ([`examples`]), every relative link and anchor
//! resolves ([`links`]), the guide's field tables match the code ([`fields`]), README.md and the
//! guide hold no history (issue numbers, commit hashes, dates), which belongs in CHANGELOG.md
//! ([`history`]), and every crate has a README whose Rust example is code that runs
//! ([`crate_readmes`]).

mod crate_readmes;
mod examples;
mod fields;
mod history;
mod links;
mod markdown;
