//! MD estimators: labels of `md`'s summary rows and of `compare`'s goodness rows.

/// The published estimator.
pub const PUBLISHED: &str = "published";
/// The tagged-velocity estimator.
pub const TAGGED: &str = "tagged";
/// The thermal estimator.
pub const THERMAL: &str = "thermal";
