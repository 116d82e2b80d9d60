//! The code each stage runs: fingerprints the build script computes from the
//! source (`src/build/code.rs`), one per stage file, which enter every
//! artifact's key. A stage's fingerprint covers the items its computation
//! reaches (its own impl, the functions, types and constants it uses,
//! transitively, in whichever module), the files they include, the external
//! crates they name at their locked versions, and the executor's encoding of
//! tables into bytes. Comments and formatting do not count; no number is
//! kept by hand.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// One part of a stage's code: a source file (the items of it the stage
/// reaches), a file those include, or an external crate.
#[derive(Debug)]
pub struct Part {
    /// `src/kernel/segments.rs`, or `crate rustfft 6.4.1`.
    pub name: &'static str,
    /// Hex SHA-256 of what the stage reaches of it.
    pub digest: &'static str,
}

/// The fingerprint of the code one stage runs.
#[derive(Debug)]
pub struct Code {
    /// The file of the stage's impl (`file!()` there).
    pub root: &'static str,
    /// Hex SHA-256 of the parts: what enters the key.
    pub fingerprint: &'static str,
    /// The parts, sorted by name.
    pub parts: &'static [Part],
}

include!(concat!(env!("OUT_DIR"), "/stage_code.rs"));

/// The code of the stage implemented in `root` (its `file!()`). Evaluated in
/// a constant, a file without a fingerprint fails the build.
pub const fn of(root: &str) -> &'static Code {
    let mut index = 0;
    while index < STAGE_CODE.len() {
        if same(STAGE_CODE[index].root, root) {
            return &STAGE_CODE[index];
        }
        index += 1;
    }
    panic!("no code fingerprint for this file: it holds no `impl Stage`")
}

const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut index = 0;
    while index < a.len() {
        if a[index] != b[index] {
            return false;
        }
        index += 1;
    }
    true
}

/// A stage's code as manifests and refs record it.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CodeRecord {
    /// [`Code::fingerprint`]; empty in records written before fingerprints.
    pub fingerprint: String,
    /// [`Code::parts`] by name.
    pub parts: BTreeMap<String, String>,
}

impl From<&Code> for CodeRecord {
    fn from(code: &Code) -> CodeRecord {
        CodeRecord {
            fingerprint: code.fingerprint.to_string(),
            parts: code
                .parts
                .iter()
                .map(|part| (part.name.to_string(), part.digest.to_string()))
                .collect(),
        }
    }
}

impl CodeRecord {
    /// The parts that differ between `self` (before) and `now`: changed,
    /// added or no longer reached, by name.
    pub fn changed_parts(&self, now: &CodeRecord) -> Vec<String> {
        let mut names: Vec<&String> = self.parts.keys().chain(now.parts.keys()).collect();
        names.sort();
        names.dedup();
        names
            .into_iter()
            .filter(|name| self.parts.get(*name) != now.parts.get(*name))
            .cloned()
            .collect()
    }
}
