//! `--set PATH=VALUE` overrides: a dotted YAML path (list items by index) and a YAML value, applied
//! to the parsed document before it is typed, the way Hydra overrides work.

use serde_yaml::Value;

/// One `--set` override.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// Dotted path, e.g. `systems.cart-pole.crisp.alpha`.
    pub path: Vec<String>,
    /// The value, parsed as YAML (`3`, `0.05`, `[1, 2]`, `random`).
    pub value: Value,
    /// The argument as given, for messages.
    pub raw: String,
}

impl Override {
    /// Parse `PATH=VALUE`. An `=` that is part of `==` (a variable group) does not split.
    pub fn parse(arg: &str) -> Result<Self, String> {
        let bytes = arg.as_bytes();
        let split = (0..bytes.len()).find(|&i| {
            bytes[i] == b'=' && bytes.get(i + 1) != Some(&b'=') && (i == 0 || bytes[i - 1] != b'=')
        });
        let Some(i) = split else {
            return Err(format!("--set {arg}: expected PATH=VALUE, e.g. --set seeds=3"));
        };
        let (path, value) = (arg[..i].trim(), arg[i + 1..].trim());
        if path.is_empty() || path.split('.').any(|p| p.trim().is_empty()) {
            return Err(format!(
                "--set {arg}: the path has an empty part; write e.g. systems.cart-pole.crisp.alpha"
            ));
        }
        if value.is_empty() {
            return Err(format!("--set {arg}: the value is empty"));
        }
        let value: Value = serde_yaml::from_str(value)
            .map_err(|e| format!("--set {arg}: the value is not valid YAML: {e}"))?;
        Ok(Self {
            path: path.split('.').map(|p| p.trim().to_string()).collect(),
            value,
            raw: arg.to_string(),
        })
    }

    /// The override of `path` by a typed value (what `--set PATH=VALUE` with that value gives).
    pub fn setting(path: &[&str], value: impl serde::Serialize) -> Self {
        let value = serde_yaml::to_value(value).unwrap_or(Value::Null);
        let shown = serde_yaml::to_string(&value).unwrap_or_default();
        Self {
            path: path.iter().map(|p| p.to_string()).collect(),
            raw: format!("{}={}", path.join("."), shown.trim()),
            value,
        }
    }

    /// Apply to a document, creating missing mappings along the path.
    pub fn apply(&self, doc: &mut Value) -> Result<(), String> {
        let mut node = doc;
        for (depth, seg) in self.path.iter().enumerate() {
            let here = self.path[..depth].join(".");
            if node.is_null() {
                *node = Value::Mapping(Default::default());
            }
            node = match node {
                Value::Mapping(m) => {
                    let key = Value::String(seg.clone());
                    if !m.contains_key(&key) {
                        m.insert(key.clone(), Value::Null);
                    }
                    m.get_mut(&key).expect("just inserted")
                }
                Value::Sequence(s) => {
                    let len = s.len();
                    let i: usize = seg.parse().map_err(|_| {
                        format!(
                            "--set {}: `{here}` is a list; index it with a number (0..{len}), not `{seg}`",
                            self.raw
                        )
                    })?;
                    s.get_mut(i).ok_or_else(|| {
                        format!("--set {}: `{here}` has {len} items; index {i} is out of range", self.raw)
                    })?
                }
                _ => return Err(format!("--set {}: `{here}` is a single value, not a section", self.raw)),
            };
        }
        *node = self.value.clone();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_paths_values_and_variable_groups() {
        let o = Override::parse("seeds=3").unwrap();
        assert_eq!(o.path, vec!["seeds"]);
        assert_eq!(o.value, Value::Number(3.into()));
        let o = Override::parse("systems.cart-pole.experiments.0.vary.x == theta=[2, 3]").unwrap();
        assert_eq!(o.path.last().unwrap(), "x == theta");
        assert!(o.value.is_sequence());
        assert!(Override::parse("seeds").is_err());
        assert!(Override::parse("=3").is_err());
        assert!(Override::parse("a..b=3").is_err());
    }

    #[test]
    fn applies_and_creates_sections() {
        let mut doc: Value = serde_yaml::from_str("a: {b: 1}\nl: [x, y]").unwrap();
        Override::parse("a.c.d=2").unwrap().apply(&mut doc).unwrap();
        Override::parse("l.1=z").unwrap().apply(&mut doc).unwrap();
        assert_eq!(doc["a"]["c"]["d"], Value::Number(2.into()));
        assert_eq!(doc["l"][1], Value::String("z".into()));
        assert!(Override::parse("l.5=z").unwrap().apply(&mut doc).is_err());
        assert!(Override::parse("a.b.c=1").unwrap().apply(&mut doc).is_err());
    }
}
