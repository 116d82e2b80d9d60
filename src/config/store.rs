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
