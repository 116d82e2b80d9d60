//! The `kernel` stage: `kernel.parquet`, one row per bin.

pub use super::DU;
use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "kernel";

/// Unit of `G`.
const G_UNIT: &str = "rho^2 l v_th / v_th";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "kernel",
    description: "collision kernel G(u' -> u) in units of rho^2 l v_th per v_th",
};
/// Lab velocity of the bin.
pub const U: Col<f64> = Col::f64("u", "v_th", "bin centre (lab velocity)");
/// The kernel.
pub const G: Pair = pair!(
    "G",
    G_UNIT,
    "kernel G(u' -> u): rate per unit velocity, +-1 rule, self plus bath",
    "standard error of G from the spread of randomizations"
);
/// Its self part.
pub const G_SELF: Pair = pair!(
    "G_self",
    G_UNIT,
    "part of G from the special particle's own velocity",
    "standard error of G_self"
);
/// Its bath part.
pub const G_BATH: Pair = pair!(
    "G_bath",
    G_UNIT,
    "part of G from the bath particles' velocities",
    "standard error of G_bath"
);

/// `kernel_replicates.parquet`: `G` of every randomization alone, one row
/// per randomization and bin (what `fit` refits one by one, and what any
/// other error analysis of the kernel starts from).
pub mod replicates {
    pub use super::super::collisions::RANDOMIZATION;
    use super::*;
    use crate::pipeline::{Input, StageError};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_replicates",
        description: "collision kernel G(u' -> u) of each randomization alone, in units of rho^2 l v_th per v_th",
    };
    /// The kernel of one randomization.
    pub const G: Col<f64> = Col::f64(
        "G",
        G_UNIT,
        "kernel G(u' -> u) of this randomization alone: self plus bath",
    );
    /// Its self part.
    pub const G_SELF: Col<f64> = Col::f64(
        "G_self",
        G_UNIT,
        "self part of G of this randomization alone (the bath part is G - G_self)",
    );

    /// The kernel of every randomization (`[randomization][bin]`) from
    /// a `kernel` input's replicates table, and the bins' centres
    /// relative to `u'`: the whole kernel (`column` [`G`]) or its self part
    /// ([`G_SELF`]).
    pub fn read(input: &Input, column: Col<f64>) -> Result<(Vec<Vec<f64>>, Vec<f64>), StageError> {
        let batch = TABLE.of(input)?;
        let (du, randomization, g) = (
            super::DU.read(batch)?,
            RANDOMIZATION.read(batch)?,
            column.read(batch)?,
        );
        let mut kernels: Vec<Vec<f64>> = Vec::new();
        let mut offsets = Vec::new();
        for k in 0..batch.num_rows() {
            let r = randomization[k] as usize;
            if r >= kernels.len() {
                kernels.resize(r + 1, Vec::new());
            }
            kernels[r].push(g[k]);
            if r == 0 {
                offsets.push(du[k]);
            }
        }
        if kernels.iter().any(|kernel| kernel.len() != offsets.len()) {
            return Err(StageError::Input(format!(
                "{}: randomizations with different bins",
                input.id
            )));
        }
        Ok((kernels, offsets))
    }
}

/// `kernel_log.parquet`: the kernel averaged over log-spaced groups of
/// bins on either side of `u'` (`kernel::tail`), one row per group.
pub mod log {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_log",
        description: "collision kernel G(u' -> u) averaged over groups of bins a twentieth of a decade of |u - u'| wide, in units of rho^2 l v_th per v_th",
    };
    /// Mean bin centre of the group.
    pub const DU: Col<f64> = Col::f64(
        "du",
        "v_th",
        "mean of the group's bin centres relative to u'",
    );
    /// Inner edge.
    pub const DU_INNER: Col<f64> = Col::f64(
        "du_inner",
        "v_th",
        "edge of the group nearest u', relative to u'",
    );
    /// Outer edge.
    pub const DU_OUTER: Col<f64> = Col::f64(
        "du_outer",
        "v_th",
        "edge of the group farthest from u', relative to u'",
    );
    /// Width.
    pub const WIDTH: Col<f64> =
        Col::f64("width", "v_th", "width of the group, |du_outer - du_inner|");
    /// Fine bins in the group.
    pub const BINS: Col<u32> = Col::u32("bins", "1", "fine bins of kernel.parquet averaged");
}
