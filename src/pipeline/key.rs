//! Content keys: SHA-256 over a canonical encoding of what determines an
//! artifact (stage name, the fingerprint of the code it runs, resolved
//! parameters, and the content hashes of the input files). Identical inputs give identical keys; a
//! recomputed input with identical bytes leaves downstream keys unchanged
//! (early cutoff).

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};

/// Lower-case hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lower-case hex of a digest.
pub fn hex(digest: &[u8]) -> String {
    digest
        .iter()
        .fold(String::with_capacity(2 * digest.len()), |mut hex, byte| {
            let _ = write!(hex, "{byte:02x}");
            hex
        })
}

/// JSON with object keys sorted at every level and no whitespace: the
/// canonical form that keys hash (independent of map implementations).
pub fn canonical_json(value: &Value) -> String {
    let mut out = String::new();
    write_canonical(value, &mut out);
    out
}

fn write_canonical(value: &Value, out: &mut String) {
    match value {
        Value::Object(map) => {
            let mut entries: Vec<(&String, &Value)> = map.iter().collect();
            entries.sort_by(|a, b| a.0.cmp(b.0));
            out.push('{');
            for (k, (name, item)) in entries.into_iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                out.push_str(&Value::String(name.clone()).to_string());
                out.push(':');
                write_canonical(item, out);
            }
            out.push('}');
        }
        Value::Array(items) => {
            out.push('[');
            for (k, item) in items.iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                write_canonical(item, out);
            }
            out.push(']');
        }
        scalar => out.push_str(&scalar.to_string()),
    }
}

/// One input of a stage instance as it enters the key: the upstream instance
/// and the content hashes of its files.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputRecord {
    /// Upstream stage name.
    pub stage: String,
    /// Upstream instance name.
    pub instance: String,
    /// Upstream artifact key.
    pub key: String,
    /// `(file name, content sha256)` of every upstream output file, sorted by name.
    pub files: Vec<(String, String)>,
}

/// What of the inputs a key hashes: upstream stage names and file contents.
/// Upstream keys and instance names are left out so that only file contents
/// matter (early cutoff).
fn keyed_inputs(inputs: &[InputRecord]) -> Value {
    inputs
        .iter()
        .map(|input| serde_json::json!({ "stage": input.stage, "files": input.files }))
        .collect()
}

/// The inputs as every output file embeds them (`ternary.inputs`): exactly
/// what the key hashes, so that one key always means the same bytes (the
/// manifest keeps the upstream keys and instances).
pub fn embedded_inputs(inputs: &[InputRecord]) -> String {
    canonical_json(&keyed_inputs(inputs))
}

/// The key of a stage instance: stage, the fingerprint of its code
/// ([`super::code`]), parameters and `keyed_inputs`. Encoding 3: keys
/// follow the code (encodings 1 and 2 hashed a hand-kept stage version).
pub fn stage_key(stage: &str, code: &str, params: &Value, inputs: &[InputRecord]) -> String {
    let document = serde_json::json!({
        "encoding": "ternary-stage-key/3",
        "stage": stage,
        "code": code,
        "params": params,
        "inputs": keyed_inputs(inputs),
    });
    sha256_hex(canonical_json(&document).as_bytes())
}

/// Dotted paths of the leaves that differ between two parameter documents,
/// with old and new values (for `status`).
pub fn changed_params(old: &Value, new: &Value) -> Vec<String> {
    let mut changes = Vec::new();
    diff(old, new, String::new(), &mut changes);
    changes
}

fn diff(old: &Value, new: &Value, path: String, changes: &mut Vec<String>) {
    match (old, new) {
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                diff(x, y, format!("{path}[{i}]"), changes);
            }
        }
        (Value::Array(a), Value::Array(b)) => {
            let missing = |from: &[Value], to: &[Value]| -> Vec<String> {
                from.iter()
                    .enumerate()
                    .filter(|(_, x)| !to.contains(x))
                    .map(|(i, x)| format!("[{i}] {}", brief(x)))
                    .collect()
            };
            let mut change = format!("{}: {} -> {} entries", shown(&path), a.len(), b.len());
            for (verb, entries) in [("removed", missing(a, b)), ("added", missing(b, a))] {
                if !entries.is_empty() {
                    change.push_str(&format!("; {verb} {}", entries.join(", ")));
                }
            }
            changes.push(change);
        }
        (Value::Object(a), Value::Object(b)) => {
            let mut names: Vec<&String> = a.keys().chain(b.keys()).collect();
            names.sort();
            names.dedup();
            for name in names {
                let child = if path.is_empty() {
                    name.clone()
                } else {
                    format!("{path}.{name}")
                };
                diff(
                    a.get(name).unwrap_or(&Value::Null),
                    b.get(name).unwrap_or(&Value::Null),
                    child,
                    changes,
                );
            }
        }
        _ if old != new => changes.push(format!(
            "{}: {} -> {}",
            shown(&path),
            brief(old),
            brief(new)
        )),
        _ => {}
    }
}

/// A parameter path as `status` names it (`(all)` for the whole document).
fn shown(path: &str) -> &str {
    if path.is_empty() { "(all)" } else { path }
}

/// Longest value `status` shows whole, in characters of JSON.
const BRIEF_CHARS: usize = 80;

/// `value` as JSON, cut to [`BRIEF_CHARS`] with its length after it.
fn brief(value: &Value) -> String {
    let text = value.to_string();
    match text.char_indices().nth(BRIEF_CHARS) {
        Some((cut, _)) => format!("{}... ({} characters)", &text[..cut], text.chars().count()),
        None => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn changed_params_name_list_entries_and_cut_long_values() {
        let old = json!([{"name": "a", "n": 1}, {"name": "b", "n": 2}]);
        let same_length = json!([{"name": "a", "n": 1}, {"name": "b", "n": 3}]);
        assert_eq!(changed_params(&old, &same_length), ["[1].n: 2 -> 3"]);
        let longer = json!([{"name": "a", "n": 1}, {"name": "c", "n": 4}, {"name": "b", "n": 2}]);
        assert_eq!(
            changed_params(&old, &longer),
            [r#"(all): 2 -> 3 entries; added [1] {"n":4,"name":"c"}"#]
        );
        let long = json!({"list": "x".repeat(200)});
        let changes = changed_params(&json!({"list": "y"}), &long);
        assert_eq!(changes.len(), 1);
        assert!(
            changes[0].starts_with(r#"list: "y" -> "xxx"#),
            "{changes:?}"
        );
        assert!(changes[0].ends_with("... (202 characters)"), "{changes:?}");
    }

    #[test]
    fn canonical_json_sorts_keys_at_every_level() {
        let a = json!({"b": 1, "a": {"y": [1.5, 2], "x": "s"}});
        assert_eq!(canonical_json(&a), r#"{"a":{"x":"s","y":[1.5,2]},"b":1}"#);
    }

    #[test]
    fn key_depends_on_params_code_and_input_files_but_not_upstream_keys() {
        let params = json!({"n": 6.0});
        let input = |key: &str, sha: &str| InputRecord {
            stage: "scan".into(),
            instance: "ipp-6".into(),
            key: key.into(),
            files: vec![("curve.parquet".into(), sha.into())],
        };
        let base = stage_key("table", "c1", &params, &[input("k1", "aa")]);
        assert_eq!(base.len(), 64);
        assert_eq!(
            base,
            stage_key("table", "c1", &params, &[input("k2", "aa")])
        );
        assert_ne!(
            base,
            stage_key("table", "c2", &params, &[input("k1", "aa")])
        );
        assert_ne!(
            base,
            stage_key("table", "c1", &json!({"n": 8.0}), &[input("k1", "aa")])
        );
        assert_ne!(
            base,
            stage_key("table", "c1", &params, &[input("k1", "ab")])
        );
    }

    /// Records that differ only in upstream key and instance embed the same
    /// text and give the same key.
    #[test]
    fn embedded_inputs_are_what_the_key_hashes() {
        let record = |key: &str, instance: &str| InputRecord {
            stage: "md".into(),
            instance: instance.into(),
            key: key.into(),
            files: vec![("h.parquet".into(), "abc".into())],
        };
        let (a, b) = ([record("k1", "ring")], [record("k2", "other")]);
        assert_eq!(embedded_inputs(&a), embedded_inputs(&b));
        let params = serde_json::json!({});
        assert_eq!(
            stage_key("compare", "c", &params, &a),
            stage_key("compare", "c", &params, &b)
        );
        assert!(!embedded_inputs(&a).contains("k1"));
    }

    #[test]
    fn changed_params_lists_leaf_paths() {
        let old = json!({"grid": {"points": 11, "offset_min": -5.0}, "n": 6.0});
        let new = json!({"grid": {"points": 21, "offset_min": -5.0}, "n": 6.0});
        assert_eq!(
            changed_params(&old, &new),
            vec!["grid.points: 11 -> 21".to_string()]
        );
    }

    #[test]
    fn sha256_matches_known_vector() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
