//! `[figures]`: whether the `figures` stage draws the study's figures.

use serde::{Deserialize, Serialize};

/// `[figures]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FiguresConfig {
    /// Draw the figures (SVG and PNG) of every computed result that has one.
    pub enabled: bool,
}

impl Default for FiguresConfig {
    fn default() -> Self {
        FiguresConfig { enabled: true }
    }
}
