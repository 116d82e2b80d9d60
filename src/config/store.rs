//! `[store]`: where artifacts live.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// `[store]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct StoreConfig {
    /// Artifact store directory, relative to the configuration file.
    pub path: PathBuf,
}

impl Default for StoreConfig {
    fn default() -> Self {
        StoreConfig {
            path: PathBuf::from("data"),
        }
    }
}

/// Longest store path, bytes (Linux's `PATH_MAX`).
const LONGEST_PATH: usize = 4096;

impl StoreConfig {
    /// Checks that the path can name a directory: not empty, at most
    /// [`LONGEST_PATH`] bytes, no NUL or control character.
    pub(super) fn validate(&self) -> Result<(), super::check::Invalid> {
        let text = self.path.to_string_lossy();
        super::check::check(
            !text.is_empty() && text.len() <= LONGEST_PATH && !text.chars().any(char::is_control),
            "store.path",
            format!(
                "`{}` is no directory path: give 1 to {LONGEST_PATH} bytes without control characters",
                text.escape_default()
            ),
        )
    }
}
