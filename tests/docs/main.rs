//! The documentation's own tests (`cargo test --test docs`): every console example in README.md
//! and the guide runs against the built binary ([`examples`]), every relative link and anchor
//! resolves ([`links`]), and the guide's field tables match the code ([`fields`]).

mod examples;
mod fields;
mod links;
mod markdown;
