//! `variant_grid:`: variants generated as the product of value lists, one per dotted path.
//!
//! ```yaml
//! variant_grid:
//!   systems.ball-beam.params.beam_length: [2, 4]
//!   defaults.q_init: [-1, 0, 1]
//!   sample: 4                     # optional: a seeded random subset of the 6 combinations
//!   seed: 7                       # the subset's seed (default 0)
//! ```
//!
//! Each combination becomes an ordinary variant whose `set` is the combination, with a stable,
//! readable id built from the paths' last segments and the values (`beam_length=4,q_init=-1`), so
//! adding a value to a list adds variants without renaming the others. Everything variants do
//! (shared trials, `--variant`, reports, the comparison) works for them. Paths and values are
//! checked like a variant's `set` (in `variants`), at the line of the grid entry.

use qsweep_engine::rng::TrialRng;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use serde_yaml::Value;
use std::fmt;

/// Generated variants above this many need `--yes`.
pub const DEFAULT_MAX_VARIANTS: usize = 256;

/// No grid generates more variants than this, `--yes` or not (each is a whole pipeline to plan):
/// a larger product needs `sample:`.
pub const MAX_VARIANTS: usize = 10_000;

/// A `variant_grid:` section, checked: at least one path, every list non-empty.
#[derive(Debug, Clone, PartialEq)]
pub struct VariantGrid {
    /// Dotted path → values, in file order (the first path varies slowest).
    pub axes: Vec<(String, Vec<Value>)>,
    /// Keep only this many combinations, chosen at random with `seed`.
    pub sample: Option<usize>,
    /// Seed of the sample.
    pub seed: u64,
}

/// One generated combination: its id, title and `set` entries (path, value).
#[derive(Debug, Clone, PartialEq)]
pub struct Combination {
    /// The variant's id, e.g. `beam_length=4,q_init=-1`.
    pub id: String,
    /// Its `set`, in grid order.
    pub set: Vec<(String, Value)>,
}

impl<'de> Deserialize<'de> for VariantGrid {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = VariantGrid;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map from dotted paths to lists of values (plus optional `sample` and `seed`)")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<VariantGrid, A::Error> {
                let mut g = VariantGrid { axes: Vec::new(), sample: None, seed: 0 };
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "sample" => {
                            let n = qsweep_engine::rules::at_least_one(map.next_value::<u64>()?)
                                .map_err(|m| super::fields::at_field(&["sample"], m))?;
                            g.sample = Some(usize::try_from(n).unwrap_or(usize::MAX));
                        }
                        "seed" => g.seed = map.next_value()?,
                        path => {
                            if path.split('.').any(|p| p.trim().is_empty()) {
                                return Err(super::fields::at_field(
                                    &[path],
                                    "the path has an empty part; write e.g. systems.cart-pole.crisp.alpha",
                                ));
                            }
                            if path.split('.').next() == Some("variants") || path.starts_with("variant_grid")
                            {
                                return Err(super::fields::at_field(
                                    &[path],
                                    "a grid cannot change the variants",
                                ));
                            }
                            if g.axes.iter().any(|(p, _)| p == path) {
                                return Err(super::fields::at_field(&[path], "the path is given twice"));
                            }
                            let values = match map.next_value::<Value>()? {
                                Value::Sequence(v) if v.is_empty() => {
                                    return Err(super::fields::at_field(
                                        &[path],
                                        "the list is empty; give at least one value",
                                    ))
                                }
                                Value::Sequence(v) => v,
                                _ => {
                                    return Err(super::fields::at_field(
                                        &[path],
                                        "give a list of values, e.g. [2, 4] (one value is [2])",
                                    ))
                                }
                            };
                            for (i, v) in values.iter().enumerate() {
                                if values[..i].contains(v) {
                                    return Err(super::fields::at_field(
                                        &[path],
                                        format!("the value {} is listed twice", shown(v)),
                                    ));
                                }
                            }
                            g.axes.push((path.to_string(), values));
                        }
                    }
                }
                if g.axes.is_empty() {
                    return Err(de::Error::custom(
                        "no paths; give at least one, e.g. defaults.q_init: [-1, 0, 1]",
                    ));
                }
                let product = g.axes.iter().try_fold(1usize, |n, (_, v)| n.checked_mul(v.len()));
                let variants = product.map(|p| g.sample.map_or(p, |s| s.min(p)));
                if variants.is_none_or(|r| r > MAX_VARIANTS) {
                    let size = product.map_or_else(|| "more than 2^64".to_string(), |p| p.to_string());
                    return Err(de::Error::custom(format!(
                        "the grid has {size} combinations; at most {MAX_VARIANTS} variants can be generated, \
                         so add `sample: N` (N ≤ {MAX_VARIANTS}) or shorten the lists"
                    )));
                }
                // Two values of one path that read alike would give two variants one id.
                for (path, values) in &g.axes {
                    let ids: Vec<String> = values.iter().map(|v| id_value(v, false)).collect();
                    for (i, id) in ids.iter().enumerate() {
                        if let Some(j) = ids[..i].iter().position(|o| o == id) {
                            return Err(super::fields::at_field(
                                &[path],
                                format!(
                                    "the values {} and {} give the same variant id `{id}`; keep one",
                                    shown(&values[j]),
                                    shown(&values[i])
                                ),
                            ));
                        }
                    }
                }
                Ok(g)
            }
        }
        d.deserialize_map(V)
    }
}

impl VariantGrid {
    /// Combinations in the full product (checked not to overflow while parsing).
    pub fn product_size(&self) -> usize {
        self.axes.iter().map(|(_, v)| v.len()).product()
    }

    /// The grid's combinations: the whole product in order (first path slowest), or the seeded
    /// sample of `sample` of them, kept in product order.
    pub fn combinations(&self) -> Vec<Combination> {
        let total = self.product_size();
        let chosen: Vec<usize> = match self.sample {
            Some(n) if n < total => {
                // A partial Fisher–Yates shuffle of the indices, from a ChaCha stream: the same
                // subset on every machine. The index array is virtual (only moved slots are
                // stored), so a sample of a huge product costs memory for the sample alone.
                let mut rng = TrialRng::new(self.seed);
                let mut moved: std::collections::HashMap<usize, usize> = std::collections::HashMap::new();
                let mut out = Vec::with_capacity(n);
                for i in 0..n {
                    let j = i + rng.below(total - i);
                    let (at_i, at_j) = (*moved.get(&i).unwrap_or(&i), *moved.get(&j).unwrap_or(&j));
                    moved.insert(j, at_i);
                    out.push(at_j);
                }
                out.sort_unstable();
                out
            }
            _ => (0..total).collect(),
        };
        let names = short_names(&self.axes.iter().map(|(p, _)| p.as_str()).collect::<Vec<_>>());
        // Each axis writes its values short (4 significant digits) unless two would read alike.
        let labels: Vec<Vec<String>> = self
            .axes
            .iter()
            .map(|(_, values)| {
                let short: Vec<String> = values.iter().map(|v| id_value(v, true)).collect();
                let distinct = short.iter().enumerate().all(|(i, a)| !short[..i].contains(a));
                if distinct {
                    short
                } else {
                    values.iter().map(|v| id_value(v, false)).collect()
                }
            })
            .collect();
        chosen
            .into_iter()
            .map(|mut k| {
                let mut picks = vec![0; self.axes.len()];
                for (a, (_, values)) in self.axes.iter().enumerate().rev() {
                    picks[a] = k % values.len();
                    k /= values.len();
                }
                let set: Vec<(String, Value)> =
                    self.axes.iter().zip(&picks).map(|((p, v), &i)| (p.clone(), v[i].clone())).collect();
                let id = names
                    .iter()
                    .zip(&labels)
                    .zip(&picks)
                    .map(|((n, l), &i)| format!("{n}={}", l[i]))
                    .collect::<Vec<_>>()
                    .join(",");
                Combination { id, set }
            })
            .collect()
    }
}

/// The shortest distinct suffix of each path: its last segment, or more where two paths share it.
fn short_names(paths: &[&str]) -> Vec<String> {
    let segs: Vec<Vec<&str>> = paths.iter().map(|p| p.split('.').collect()).collect();
    let mut take = vec![1usize; paths.len()];
    loop {
        let names: Vec<String> =
            segs.iter().zip(&take).map(|(s, &t)| s[s.len() - t.min(s.len())..].join(".")).collect();
        let mut changed = false;
        for i in 0..names.len() {
            if names.iter().enumerate().any(|(j, n)| j != i && *n == names[i]) && take[i] < segs[i].len() {
                take[i] += 1;
                changed = true;
            }
        }
        if !changed {
            return names;
        }
    }
}

/// A value as written in an id: numbers in their shortest form (`short`: at most 4 significant
/// digits, so π/4 reads 0.7854), lists joined by `_`, and any character a folder name should not
/// hold replaced by `_`.
fn id_value(v: &Value, short: bool) -> String {
    let raw = match v {
        Value::Sequence(items) => items.iter().map(|i| id_value(i, short)).collect::<Vec<_>>().join("_"),
        Value::Number(n) => match n.as_f64() {
            Some(x) if short && x != 0.0 && x.is_finite() => {
                let digits = (3 - x.abs().log10().floor() as i32).max(0) as usize;
                let rounded: f64 = format!("{x:.digits$}").parse().unwrap_or(x);
                super::experiment::format_value(rounded)
            }
            Some(x) => super::experiment::format_value(x),
            None => n.to_string(),
        },
        other => shown(other),
    };
    raw.chars().map(|c| if c.is_ascii_alphanumeric() || "-_.+".contains(c) { c } else { '_' }).collect()
}

/// A value as YAML text on one line.
pub fn shown(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => serde_yaml::to_string(other).unwrap_or_default().trim().replace('\n', " "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(text: &str) -> VariantGrid {
        serde_yaml::from_str(text).unwrap()
    }

    #[test]
    fn the_product_in_order_with_readable_stable_ids() {
        let g = grid("systems.ball-beam.params.beam_length: [2, 4]\ndefaults.q_init: [-1, 0, 1.5]\n");
        let ids: Vec<String> = g.combinations().into_iter().map(|c| c.id).collect();
        assert_eq!(
            ids,
            [
                "beam_length=2,q_init=-1",
                "beam_length=2,q_init=0",
                "beam_length=2,q_init=1.5",
                "beam_length=4,q_init=-1",
                "beam_length=4,q_init=0",
                "beam_length=4,q_init=1.5"
            ]
        );
        // Adding a value keeps every earlier id.
        let more = grid("systems.ball-beam.params.beam_length: [2, 4, 8]\ndefaults.q_init: [-1, 0, 1.5]\n");
        let more: Vec<String> = more.combinations().into_iter().map(|c| c.id).collect();
        assert!(ids.iter().all(|i| more.contains(i)) && more.len() == 9);
    }

    #[test]
    fn shared_last_segments_take_more_of_the_path_and_lists_join() {
        let g = grid(
            "systems.ball-beam.crisp.epsilon: [0.1]\nsystems.ball-beam.fuzzy.epsilon: [0.2]\nsystems.ball-beam.ranges.x_dot: [[-1, 1]]\ndefaults.tie_break: [first]\n",
        );
        assert_eq!(g.combinations()[0].id, "crisp.epsilon=0.1,fuzzy.epsilon=0.2,x_dot=-1_1,tie_break=first");
        // Long numbers read short, unless that would make two values of an axis alike.
        let g = grid("a.angle: [0.7853981633974483, 0.2]\nb.eps: [1.0e-6, 0.1]\nc.k: [0.123451, 0.123459]\n");
        assert_eq!(g.combinations()[0].id, "angle=0.7854,eps=0.000001,k=0.123451");
    }

    #[test]
    fn a_sample_is_seeded_and_kept_in_product_order() {
        let text = "a.x: [1, 2, 3, 4]\nb.y: [1, 2, 3]\nsample: 5\nseed: 7\n";
        let a: Vec<String> = grid(text).combinations().into_iter().map(|c| c.id).collect();
        assert_eq!(a, grid(text).combinations().into_iter().map(|c| c.id).collect::<Vec<_>>());
        assert_eq!(a.len(), 5);
        let full: Vec<String> =
            grid("a.x: [1, 2, 3, 4]\nb.y: [1, 2, 3]\n").combinations().into_iter().map(|c| c.id).collect();
        let pos: Vec<usize> = a.iter().map(|i| full.iter().position(|f| f == i).unwrap()).collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "{pos:?}");
        let other: Vec<String> =
            grid(&text.replace("seed: 7", "seed: 8")).combinations().into_iter().map(|c| c.id).collect();
        assert_ne!(a, other, "another seed, another subset");
        assert_eq!(
            grid("a.x: [1, 2]\nsample: 9\n").combinations().len(),
            2,
            "a sample above the product is all of it"
        );
    }

    #[test]
    fn bad_grids_say_what_is_wrong() {
        let err = |t: &str| serde_yaml::from_str::<VariantGrid>(t).unwrap_err().to_string();
        assert!(err("defaults.q_init: []\n").contains("the list is empty"));
        assert!(err("defaults.q_init: 3\n").contains("give a list of values"));
        assert!(err("defaults.q_init: [1, 1]\n").contains("listed twice"));
        assert!(err("sample: 0\ndefaults.q_init: [1]\n").contains("0 is not allowed"));
        assert!(err("defaults.q_init: [1, 1.0]\n").contains("give the same variant id `1`"));
        let lists = |paths: usize, values: usize| -> String {
            let v: Vec<String> = (0..values).map(|k| k.to_string()).collect();
            (0..paths).map(|i| format!("p.v{i}: [{}]\n", v.join(", "))).collect()
        };
        assert!(err(&lists(16, 16)).contains("more than 2^64 combinations"));
        assert!(err(&lists(10, 10)).contains("10000000000 combinations"));
        // A sample of a product far too large to list is drawn without listing it.
        let g = grid(&format!("{}sample: 12\nseed: 1\n", lists(10, 10)));
        assert_eq!(g.combinations().len(), 12);
        assert!(err("{}\n").contains("no paths"));
    }
}
