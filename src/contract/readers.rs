//! Readers: the tables of one stage decoded into the library types the
//! stages that read them compute with (events, launch points, rates). Each
//! reader lives here, beside the columns it reads, so that no stage imports
//! another.

use arrow_array::RecordBatch;

use crate::kernel::{Draws, Event};
use crate::physics::sampling::{LaunchPoint, Stratum};
use crate::physics::scan::LaunchPair;
use crate::pipeline::{Input, StageError};
use crate::stats::Estimate;

/// The stratum whose index row `row` of a table stores (an input error
/// naming the row when no stratum has that index).
fn stratum_of_row(row: usize, index: u32) -> Result<Stratum, StageError> {
    Stratum::from_index(index)
        .ok_or_else(|| StageError::Input(format!("row {row}: unknown stratum {index}")))
}

/// The events of a `collisions` artifact, for the kernel estimators.
pub fn read_events(input: &Input) -> Result<Vec<Event>, StageError> {
    use super::collisions::*;
    let batch = TABLE.of(input)?;
    let randomization = RANDOMIZATION.read(batch)?;
    let stratum = STRATUM.read(batch)?;
    let point = POINT.read(batch)?;
    let node = NODE.read(batch)?;
    let (u2, u3) = (U2.read(batch)?, U3.read(batch)?);
    let offset = ARRIVAL_OFFSET.read(batch)?;
    let density = PROPOSAL_DENSITY.read(batch)?;
    let outgoing = [
        OUT_SLOW.read(batch)?,
        OUT_MIDDLE.read(batch)?,
        OUT_FAST.read(batch)?,
    ];
    let outcome = OUTCOME.read(batch)?;
    let binding = BINDING_ENERGY.optional(batch)?;
    (0..batch.num_rows())
        .map(|k| {
            let stratum = stratum_of_row(k, stratum[k])?;
            let failed = outcome[k].starts_with("failed");
            Ok(Event {
                stratum,
                randomization: randomization[k],
                point: point[k],
                node: node[k],
                u2: u2[k],
                u3: u3[k],
                offset: offset[k],
                proposal_density: density[k],
                outgoing: (!failed).then(|| [outgoing[0][k], outgoing[1][k], outgoing[2][k]]),
                bound_pair_energy: binding[k],
            })
        })
        .collect()
}

/// The launch points of a `launches` artifact whose randomization lies in
/// `randomizations`, in table order.
pub fn read_launches(
    input: &Input,
    randomizations: std::ops::Range<u32>,
) -> Result<Vec<LaunchPoint>, StageError> {
    use super::launches::*;
    let batch = TABLE.of(input)?;
    let randomization = RANDOMIZATION.read(batch)?;
    let stratum = STRATUM.read(batch)?;
    let point = POINT.read(batch)?;
    let (u2, u3) = (U2.read(batch)?, U3.read(batch)?);
    let density = LAUNCH_DENSITY.read(batch)?;
    let coordinate = OFFSET_COORDINATE.read(batch)?;
    (0..batch.num_rows())
        .filter(|&k| randomizations.contains(&randomization[k]))
        .map(|k| {
            let stratum = stratum_of_row(k, stratum[k])?;
            Ok(LaunchPoint {
                randomization: randomization[k],
                stratum,
                point: point[k],
                launch: LaunchPair {
                    u2: u2[k],
                    u3: u3[k],
                },
                density: density[k],
                offset_coordinate: coordinate[k],
            })
        })
        .collect()
}

/// The events of a `collisions` input, their draw counts, and failures.
pub fn collision_events(input: &Input) -> Result<(Vec<Event>, Draws, usize), StageError> {
    let events = read_events(input)?;
    let draws = Draws::count(&events);
    if draws.replicates() < 2 {
        return Err(StageError::Input(format!(
            "{}: fewer than 2 randomizations",
            input.id
        )));
    }
    let failed = events.iter().filter(|e| e.outgoing.is_none()).count();
    Ok((events, draws, failed))
}

/// The events of the single (first) input.
pub fn input_events(inputs: &[Input]) -> Result<(Vec<Event>, Draws, usize), StageError> {
    collision_events(
        inputs
            .first()
            .ok_or_else(|| StageError::Input("no collisions input".into()))?,
    )
}

/// The special particle's variance rate at truncation `limit` (a value of
/// the table's grid, or infinity for the row without truncation, whose
/// truncation is null) from a moments table, `rho^2 l v_th`: `a_n`
/// at the window edge for `u' = 0` in the dilute limit.
pub fn self_variance_at(batch: &RecordBatch, limit: f64) -> Result<Estimate, StageError> {
    use super::moments::*;
    let row = TRUNCATION
        .optional(batch)?
        .into_iter()
        .map(|x| x.unwrap_or(f64::INFINITY))
        // The grid's edge is `edge * 10^0`: equal up to rounding of the limit's own arithmetic.
        .position(|x| x == limit || (limit.is_finite() && (x - limit).abs() <= 1e-12 * limit))
        .ok_or_else(|| StageError::Input(format!("no truncation {limit} in the moments table")))?;
    Ok(SELF_VARIANCE.read(batch)?[row])
}
