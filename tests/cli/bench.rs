//! `qsweep bench` from the command line: JSON shape, filtering and argument errors.

use crate::helpers::qsweep;

#[test]
fn json_lists_config_steps_seconds_and_rate() {
    let out = qsweep()
        .args(["bench", "--steps", "2000", "--repeat", "1", "--filter", "cart-pole/crisp/q0/", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 3, "2^4/2a, 10^4/2a and 10^4/10a");
    for r in rows {
        assert!(r["config"].as_str().unwrap().starts_with("cart-pole/crisp/q0/"));
        let steps = r["steps"].as_u64().unwrap();
        assert!((2000..4000).contains(&steps));
        assert!(r["seconds"].as_f64().unwrap() > 0.0);
        assert!(r["steps_per_s"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn unknown_filter_and_bad_budget_are_usage_errors() {
    let out = qsweep().args(["bench", "--filter", "no-such-system"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cart-pole/fuzzy/q-lambda/4^4/2a"));
    let out = qsweep().args(["bench", "--steps", "0"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}
