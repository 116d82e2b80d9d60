//! Thresholds shared by the science modules, the configuration and the
//! report: plain constants, each with its one home here, so that the
//! configuration (a default) and the report (a verdict on a table) read the
//! value without reaching into the modules that compute with it. No logic.

/// Default kick floor (`v_th`): velocity changes up to this size are the
/// scattering engine's error floor and count as exactly zero. 1000x the
/// engine's velocity error at the default tolerance (~1e-13 `v_th`,
/// docs/benchmarks.md), far below any kernel bin.
pub const DEFAULT_KICK_FLOOR: f64 = 1e-10;

/// Share of a detailed-balance imbalance's spread over randomizations above
/// which its most deviant randomization (one heavy scene) carries the error:
/// the pair or joint test is then no evidence for or against detailed
/// balance (its z-score means nothing).
pub const DOMINATED_SHARE: f64 = 0.5;

/// Significance at which a comparison of molecular dynamics with its
/// reference rejects agreement, per test (the shape's chi-square, the window
/// variance's ratio): one in a thousand, so that the default study's ~30
/// comparisons of two tests each reject a ring that agrees in ~6% of studies.
pub const REJECTED_P: f64 = 1e-3;

/// `|z|` beyond which a ratio that should be 1 rejects agreement: the
/// two-sided normal quantile of [`REJECTED_P`].
pub const REJECTED_Z: f64 = 3.29;
