//! A program trial's key: blake3, in its own domain (`qsweep-program-trial\0`), over the
//! canonical JSON ([`canonical_json`]) of
//! `{"command": [...], "inputs": {"<path>": "<blake3 hex>"}, "params": {...}, "provenance":
//! [<outputs of key: true commands>], "seed": N}`: object keys sorted, no whitespace, a float
//! param always written as a float (`1.0`). So reformatting the pipeline file (comments, key
//! order, `0.10` for `0.1`) changes no key, while editing an input file, the command, a param or
//! a keyed provenance output changes every key it touches. The protocol and the timeout are not
//! in the key. The parts every trial of a plan shares are written once ([`Identity`]); they are
//! also what a row records of the trial's identity.

use crate::cache::Key;
use crate::program::model::{canonical_json, InputFile, ParamType, ParamValue, Program};
use serde_json::Value;

/// The domain of program keys: no engine key (`qsweep-trial\0`) can equal one.
pub const DOMAIN: &[u8] = b"qsweep-program-trial\0";

/// What every trial of a plan shares: the command, the input files' digests and the provenance,
/// as keyed and as recorded in each row (`model::ProgramRow`'s `command_json`, `inputs_json`,
/// `provenance_json`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// The command, a JSON array.
    pub command_json: String,
    /// The input files, a JSON object path → blake3 hex (sorted by path).
    pub inputs_json: String,
    /// Every provenance command with its output (`provenance::record_json`).
    pub provenance_json: String,
    /// The outputs of the `key: true` provenance commands, a JSON array: what the key hashes.
    pub keyed_provenance_json: String,
}

impl Identity {
    /// The identity of `program`'s trials.
    pub fn of(program: &Program) -> Self {
        let keyed: Vec<Value> = program
            .provenance
            .iter()
            .zip(&program.provenance_outputs)
            .filter(|(p, _)| p.key)
            .map(|(_, out)| Value::String(out.clone()))
            .collect();
        Self {
            command_json: command_json(&program.command),
            inputs_json: inputs_json(&program.inputs),
            provenance_json: crate::program::provenance::record_json(
                &program.provenance,
                &program.provenance_outputs,
            ),
            keyed_provenance_json: canonical_json(&Value::Array(keyed)),
        }
    }

    /// The key of the trial with these params (`values` in `params` order) and seed.
    pub fn key(&self, params: &[(String, ParamType)], values: &[ParamValue], seed: u64) -> Key {
        let mut h = blake3::Hasher::new();
        h.update(DOMAIN);
        h.update(self.canonical(params, values, seed).as_bytes());
        Key(*h.finalize().as_bytes())
    }

    /// The text [`Identity::key`] hashes: the canonical JSON of the whole key object (written
    /// from the shared parts; equal to `canonical_json` of the object, which the tests check).
    pub fn canonical(&self, params: &[(String, ParamType)], values: &[ParamValue], seed: u64) -> String {
        let params = canonical_json(&Value::Object(params_object(params, values)));
        format!(
            "{{\"command\":{},\"inputs\":{},\"params\":{params},\"provenance\":{},\"seed\":{seed}}}",
            self.command_json, self.inputs_json, self.keyed_provenance_json
        )
    }
}

/// A command as JSON (an array of strings).
pub fn command_json(command: &[String]) -> String {
    canonical_json(&Value::from(command.to_vec()))
}

/// Input files as JSON: an object path → blake3 hex, sorted by path.
pub fn inputs_json(inputs: &[InputFile]) -> String {
    let m: serde_json::Map<String, Value> =
        inputs.iter().map(|f| (f.path.clone(), Value::String(f.digest.clone()))).collect();
    canonical_json(&Value::Object(m))
}

/// The params as a JSON object (name → value; a float param's value always a float).
pub fn params_object(
    params: &[(String, ParamType)],
    values: &[ParamValue],
) -> serde_json::Map<String, Value> {
    params.iter().zip(values).map(|((n, _), v)| (n.clone(), v.to_json())).collect()
}

#[cfg(test)]
mod tests;
