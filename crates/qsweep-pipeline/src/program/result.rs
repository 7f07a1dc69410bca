//! A program's result line, parsed against its declared metrics: one JSON object holding every
//! declared metric and nothing else, each of its declared type, into typed values in declared
//! order, or a reason that names the line and the field (stored with the failed trial).

use super::model::{MetricType, MetricValue};
use serde_json::Value;

/// How much of a bad line a reason quotes (in characters).
const QUOTED: usize = 200;

/// The last non-empty line of `stdout` (process mode: earlier lines are the program's log), its
/// trailing `\r` and surrounding whitespace trimmed; `None` when every line is blank.
pub fn last_line(stdout: &[u8]) -> Option<&[u8]> {
    stdout.split(|&b| b == b'\n').map(|l| l.trim_ascii()).rfind(|l| !l.is_empty())
}

/// Parse `line` against `metrics` (name and type, in declared order): every declared metric's
/// value in declared order, or why not, naming the line and the field.
pub fn parse(line: &[u8], metrics: &[(String, MetricType)]) -> Result<Vec<MetricValue>, String> {
    let text = match std::str::from_utf8(line) {
        Ok(t) => t.trim(),
        Err(_) => return Err(format!("result line {} is not UTF-8", quote(&String::from_utf8_lossy(line)))),
    };
    let bad = |what: String| format!("result line {}: {what}", quote(text));
    let value: Value = serde_json::from_str(text).map_err(|e| {
        // Python's json.dumps writes NaN and Infinity, which JSON (and so qsweep) does not have.
        let hint = if ["NaN", "Infinity"].iter().any(|w| text.contains(w)) {
            "; JSON has no NaN or Infinity"
        } else {
            ""
        };
        bad(format!("not JSON ({e}){hint}"))
    })?;
    let Value::Object(object) = value else {
        return Err(bad(format!("not a JSON object but {}", kind(&value, MetricType::Str))));
    };
    let undeclared: Vec<&str> =
        object.keys().map(String::as_str).filter(|k| !metrics.iter().any(|(n, _)| n == k)).collect();
    if !undeclared.is_empty() {
        let names = undeclared.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
        let declared = metrics.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ");
        let s = if undeclared.len() == 1 { "" } else { "s" };
        return Err(bad(format!("undeclared metric{s} {names} (declared: {declared})")));
    }
    let missing: Vec<String> = metrics
        .iter()
        .filter(|(n, _)| !object.contains_key(n))
        .map(|(n, t)| format!("`{n}` ({})", t.name()))
        .collect();
    if !missing.is_empty() {
        let s = if missing.len() == 1 { "" } else { "s" };
        return Err(bad(format!("missing metric{s} {}", missing.join(", "))));
    }
    metrics
        .iter()
        .map(|(name, ty)| {
            let v = &object[name];
            typed(v, *ty).ok_or_else(|| {
                bad(format!("metric `{name}` should be {} but is {}", expected(*ty), kind(v, *ty)))
            })
        })
        .collect()
}

/// `value` as a `ty`, if it is one (an integer is a float; a float without a fraction is an int).
fn typed(value: &Value, ty: MetricType) -> Option<MetricValue> {
    match ty {
        MetricType::Int => int(value).map(MetricValue::Int),
        MetricType::Float => value.as_f64().map(MetricValue::Float),
        MetricType::Bool => value.as_bool().map(MetricValue::Bool),
        MetricType::Str => value.as_str().map(|s| MetricValue::Str(s.to_string())),
        MetricType::ListFloat => {
            value.as_array()?.iter().map(Value::as_f64).collect::<Option<_>>().map(MetricValue::ListFloat)
        }
        MetricType::ListU32 => value
            .as_array()?
            .iter()
            .map(|v| int(v).and_then(|i| u32::try_from(i).ok()))
            .collect::<Option<_>>()
            .map(MetricValue::ListU32),
    }
}

/// An integer: a JSON integer in i64's range, or a float with no fraction in it (`3.0`).
fn int(value: &Value) -> Option<i64> {
    if let Some(i) = value.as_i64() {
        return Some(i);
    }
    let f = value.as_f64().filter(|f| value.is_f64() && f.fract() == 0.0)?;
    // -2^63 ..= 2^63 - 1: every such whole float converts exactly.
    (f >= -(2f64.powi(63)) && f < 2f64.powi(63)).then_some(f as i64)
}

/// What a `ty` value must be, for messages.
fn expected(ty: MetricType) -> &'static str {
    match ty {
        MetricType::Int => "an integer (int64)",
        MetricType::Float => "a number",
        MetricType::Bool => "true or false",
        MetricType::Str => "a string",
        MetricType::ListFloat => "a list of numbers",
        MetricType::ListU32 => "a list of integers in 0..=4294967295",
    }
}

/// What `value` is, for messages where a `ty` was wanted: a number shows itself (so one out of
/// range is plain to see), a list the first element that is not of `ty`'s element type.
fn kind(value: &Value, ty: MetricType) -> String {
    match value {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(_) => "a string".into(),
        Value::Array(a) => {
            let element = match ty {
                MetricType::ListU32 => MetricType::Int,
                _ => MetricType::Float,
            };
            let fits = |v: &Value| match ty {
                MetricType::ListU32 => int(v).and_then(|i| u32::try_from(i).ok()).is_some(),
                _ => v.is_number(),
            };
            match a.iter().find(|v| !fits(v)) {
                Some(v) => format!("a list holding {}", kind(v, element)),
                None => "a list".into(),
            }
        }
        Value::Object(_) => "an object".into(),
    }
}

/// `line` in backquotes, cut after [`QUOTED`] characters.
fn quote(line: &str) -> String {
    match line.char_indices().nth(QUOTED) {
        Some((i, _)) => format!("`{}…` ({} bytes)", &line[..i], line.len()),
        None => format!("`{line}`"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics() -> Vec<(String, MetricType)> {
        [
            ("episodes", MetricType::Int),
            ("score", MetricType::Float),
            ("solved", MetricType::Bool),
            ("note", MetricType::Str),
            ("returns", MetricType::ListFloat),
            ("lengths", MetricType::ListU32),
        ]
        .into_iter()
        .map(|(n, t)| (n.to_string(), t))
        .collect()
    }

    const GOOD: &str = r#"{"episodes": 12, "score": 2, "solved": true, "note": "ok", "returns": [1.5, 2], "lengths": [3, 4.0]}"#;

    fn reason(line: &str) -> String {
        parse(line.as_bytes(), &metrics()).unwrap_err()
    }

    #[test]
    fn a_valid_line_gives_every_metric_in_declared_order() {
        let v = parse(GOOD.as_bytes(), &metrics()).unwrap();
        assert_eq!(
            v,
            vec![
                MetricValue::Int(12),
                MetricValue::Float(2.0),
                MetricValue::Bool(true),
                MetricValue::Str("ok".into()),
                MetricValue::ListFloat(vec![1.5, 2.0]),
                MetricValue::ListU32(vec![3, 4]),
            ]
        );
        // Key order in the line does not matter; surrounding whitespace and `\r` do not either.
        let reordered = r#" {"lengths": [], "returns": [], "note": "", "solved": false, "score": -1e-3, "episodes": 3.0}"#;
        let v = parse(format!("{reordered}\r").as_bytes(), &metrics()).unwrap();
        assert_eq!(v[0], MetricValue::Int(3));
        assert_eq!(v[1], MetricValue::Float(-0.001));
        assert_eq!(v[5], MetricValue::ListU32(vec![]));
    }

    #[test]
    fn the_result_is_the_last_non_empty_line() {
        assert_eq!(last_line(b"log 1\nlog 2\n{\"a\": 1}\n\n  \n"), Some(&b"{\"a\": 1}"[..]));
        assert_eq!(last_line(b"only\r\n"), Some(&b"only"[..]));
        assert_eq!(last_line(b"no newline at the end"), Some(&b"no newline at the end"[..]));
        assert_eq!(last_line(b""), None);
        assert_eq!(last_line(b"\n \n\t\n"), None);
    }

    #[test]
    fn a_line_that_is_not_json_is_named() {
        let r = reason("episode 12 done");
        assert!(r.starts_with("result line `episode 12 done`: not JSON ("), "{r}");
        let r = reason(r#"{"score": NaN}"#);
        assert!(r.contains("not JSON") && r.contains("no NaN or Infinity"), "{r}");
        let r = parse(b"\xff\xfe{}", &metrics()).unwrap_err();
        assert!(r.contains("not UTF-8"), "{r}");
    }

    #[test]
    fn a_json_value_that_is_not_an_object_is_named() {
        assert_eq!(reason("[1, 2]"), "result line `[1, 2]`: not a JSON object but a list");
        assert_eq!(reason("12"), "result line `12`: not a JSON object but 12");
        assert_eq!(reason("\"done\""), "result line `\"done\"`: not a JSON object but a string");
    }

    #[test]
    fn a_missing_metric_is_named_with_its_type() {
        let line = GOOD.replace(r#""solved": true, "#, "");
        assert_eq!(reason(&line), format!("result line `{line}`: missing metric `solved` (bool)"));
        let r = reason("{}");
        assert!(r.ends_with("missing metrics `episodes` (int), `score` (float), `solved` (bool), `note` (string), `returns` (list<float>), `lengths` (list<uint32>)"), "{r}");
    }

    #[test]
    fn an_undeclared_key_is_named() {
        let line = GOOD.replace('}', r#", "extra": 1}"#);
        assert_eq!(
            reason(&line),
            format!(
                "result line `{line}`: undeclared metric `extra` (declared: episodes, score, solved, note, returns, lengths)"
            )
        );
    }

    #[test]
    fn a_wrong_type_is_named_with_the_field_and_the_value() {
        let cases = [
            (r#""episodes": 12"#, r#""episodes": 12.5"#, "metric `episodes` should be an integer (int64) but is 12.5"),
            (r#""episodes": 12"#, r#""episodes": "12""#, "metric `episodes` should be an integer (int64) but is a string"),
            (r#""episodes": 12"#, r#""episodes": 1e300"#, "metric `episodes` should be an integer (int64) but is 1e+300"),
            (r#""episodes": 12"#, r#""episodes": 9223372036854775808"#, "metric `episodes` should be an integer (int64) but is 9223372036854775808"),
            (r#""score": 2"#, r#""score": null"#, "metric `score` should be a number but is null"),
            (r#""solved": true"#, r#""solved": 1"#, "metric `solved` should be true or false but is 1"),
            (r#""note": "ok""#, r#""note": 3"#, "metric `note` should be a string but is 3"),
            (r#""returns": [1.5, 2]"#, r#""returns": 1.5"#, "metric `returns` should be a list of numbers but is 1.5"),
            (r#""returns": [1.5, 2]"#, r#""returns": [1.5, "x"]"#, "metric `returns` should be a list of numbers but is a list holding a string"),
            (r#""lengths": [3, 4.0]"#, r#""lengths": [3, -1]"#, "metric `lengths` should be a list of integers in 0..=4294967295 but is a list holding -1"),
            (r#""lengths": [3, 4.0]"#, r#""lengths": [4294967296]"#, "metric `lengths` should be a list of integers in 0..=4294967295 but is a list holding 4294967296"),
            (r#""lengths": [3, 4.0]"#, r#""lengths": [3, 0.5]"#, "metric `lengths` should be a list of integers in 0..=4294967295 but is a list holding 0.5"),
        ];
        for (from, to, why) in cases {
            let line = GOOD.replace(from, to);
            assert_ne!(line, GOOD, "{from}");
            assert_eq!(reason(&line), format!("result line `{line}`: {why}"));
        }
        // The edges of the ranges are fine.
        let line = GOOD
            .replace(r#""episodes": 12"#, r#""episodes": -9223372036854775808"#)
            .replace(r#""lengths": [3, 4.0]"#, r#""lengths": [0, 4294967295]"#);
        let v = parse(line.as_bytes(), &metrics()).unwrap();
        assert_eq!(v[0], MetricValue::Int(i64::MIN));
        assert_eq!(v[5], MetricValue::ListU32(vec![0, u32::MAX]));
    }

    #[test]
    fn a_long_line_is_quoted_cut_short() {
        let line = format!("{}é", "x".repeat(300));
        let r = reason(&line);
        assert!(r.starts_with(&format!("result line `{}…` (302 bytes): not JSON", "x".repeat(200))), "{r}");
        // Cut on a character boundary.
        let r = reason(&"é".repeat(250));
        assert!(r.starts_with(&format!("result line `{}…` (500 bytes)", "é".repeat(200))), "{r}");
    }
}
