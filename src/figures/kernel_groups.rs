//! The kernels' log-spaced groups that the figures of kernels draw.

use polars::prelude::{ChunkCompareIneq, DataFrame, Float64Chunked};

use super::frames::{failed, log_groups};
use crate::contract;
use crate::pipeline::{Input, StageError};

/// Kernel groups per decade of `u - u'` on log axes.
pub(super) const GROUPS_PER_DECADE: f64 = 20.0;

/// `G` at `du > 0` of a kernel artifact as a series, averaged over
/// log-spaced groups of bins (errors from the randomizations).
pub(super) fn positive_kernel(
    input: &Input,
    panel: &str,
    label: &str,
    per_decade: f64,
) -> Result<DataFrame, StageError> {
    let (replicates, du) =
        contract::kernel::replicates::read(input, contract::kernel::replicates::G)?;
    log_groups((panel, label), &du, &replicates, per_decade)
}

/// Largest relative error of a group drawn among the kernels of every `n`:
/// beyond it the tails' bands would hide the curves.
const RESOLVED: f64 = 0.5;

/// The groups of a kernel series whose relative error is below [`RESOLVED`].
pub(super) fn resolved(groups: &DataFrame) -> Result<DataFrame, StageError> {
    use contract::figures::points::{Y, Y_ERROR};
    let column = |name: &str| -> Result<Float64Chunked, StageError> {
        Ok(groups
            .column(name)
            .map_err(failed)?
            .f64()
            .map_err(failed)?
            .clone())
    };
    let mask = column(Y_ERROR.name)?.lt(&(column(Y.name)? * RESOLVED));
    groups.filter(&mask).map_err(failed)
}
