//! `scan`: mono-energetic kick curves of one potential (physics.md §6).
//!
//! Outputs `curve` (one row per launch pair and arrival offset) and `peak`
//! (one row per launch pair: `|u1f,max|` with its error bound and location).
//! Every `u1f` carries an error estimate from a rerun at 100x tighter tolerance.

use rayon::prelude::*;
use serde_json::Value;

use crate::config::{NamedLaunch, ScanParams};
use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::physics::scan::{
    LaunchPair, Peak, ScanPoint, TIGHTEST_TOLERANCE, refine_peak, scan_point,
    special_final_velocity,
};
use crate::physics::scene::EngineSettings;
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `scan` stage for one potential.
pub struct ScanStage {
    params: ScanParams,
}

impl ScanStage {
    /// A scan with resolved parameters.
    pub fn new(params: ScanParams) -> ScanStage {
        ScanStage { params }
    }

    fn tight_engine(&self) -> EngineSettings {
        EngineSettings {
            tolerance: (self.params.engine.tolerance * 0.01).max(TIGHTEST_TOLERANCE),
            ..self.params.engine
        }
    }

    fn offsets(&self) -> Vec<f64> {
        let grid = self.params.grid;
        let last = f64::from(grid.points - 1);
        (0..grid.points)
            .map(|k| grid.offset_min + (grid.offset_max - grid.offset_min) * f64::from(k) / last)
            .collect()
    }
}

/// A curve point at the configured tolerance, with the tight-tolerance rerun.
struct CurvePoint {
    nominal: ScanPoint,
    tight: ScanPoint,
}

impl CurvePoint {
    fn kick(&self) -> f64 {
        special_final_velocity(&self.nominal.collision)
    }
    fn kick_error(&self) -> f64 {
        (self.kick() - special_final_velocity(&self.tight.collision)).abs()
    }
    fn failed(&self) -> bool {
        self.nominal.collision.outcome.is_failure() || self.tight.collision.outcome.is_failure()
    }
}

fn pair_of(launch: &NamedLaunch) -> LaunchPair {
    LaunchPair {
        u2: launch.u2,
        u3: launch.u3,
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for ScanStage {
    fn id(&self) -> InstanceId {
        instances::scan(&self.params.potential)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[
            contract::scan::curve::TABLE.name,
            contract::scan::peak::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    fn work_units(&self) -> u64 {
        self.params.launches.len() as u64 * u64::from(self.params.grid.points)
    }

    /// One tightly integrated scene per offset and launch pair (the default
    /// study: 70 us each on 2026-12-01, 54 bytes per row).
    fn cost(&self, _inputs: &[Cost]) -> Cost {
        let scenes = self.work_units() as f64;
        Cost {
            cpu_seconds: scenes * 7e-5,
            bytes: scenes * 54.0,
            rows: scenes,
        }
    }

    fn run(&self, _inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let potential = &self.params.potential;
        let tight = self.tight_engine();
        let offsets = self.offsets();
        let mut curves = Vec::new();
        let mut peaks = Vec::new();
        for launch in &self.params.launches {
            let pair = pair_of(launch);
            let curve: Vec<CurvePoint> = offsets
                .par_iter()
                .map(|&offset| {
                    let point = CurvePoint {
                        nominal: scan_point(potential, &self.params.engine, pair, offset),
                        tight: scan_point(potential, &tight, pair, offset),
                    };
                    progress.advance(1);
                    point
                })
                .collect();
            peaks.push(self.peak(pair, &curve));
            curves.push(curve);
        }
        Ok(vec![
            self.curve_table(&curves)?,
            self.peak_table(&curves, &peaks)?,
        ])
    }
}

impl ScanStage {
    /// Refines the largest `|u1f|` of a curve between its grid neighbours.
    fn peak(&self, pair: LaunchPair, curve: &[CurvePoint]) -> Option<Peak> {
        let best = (0..curve.len())
            .filter(|&k| !curve[k].failed())
            .max_by(|&a, &b| curve[a].kick().abs().total_cmp(&curve[b].kick().abs()))?;
        let low = curve[best.saturating_sub(1)].nominal.offset;
        let high = curve[(best + 1).min(curve.len() - 1)].nominal.offset;
        Some(refine_peak(
            &self.params.potential,
            &self.params.engine,
            pair,
            low,
            high,
        ))
    }

    fn curve_table(&self, curves: &[Vec<CurvePoint>]) -> Result<Table, StageError> {
        use contract::scan::{curve::*, *};
        let rows: Vec<(&NamedLaunch, &CurvePoint)> = self
            .params
            .launches
            .iter()
            .zip(curves)
            .flat_map(|(l, c)| c.iter().map(move |p| (l, p)))
            .collect();
        let length = self.params.launch_length;
        Ok(Rows::new(&rows)
            .with(LAUNCH, |(l, _)| l.name.clone())
            .with(U2, |(l, _)| l.u2)
            .with(U3, |(l, _)| l.u3)
            .with(ARRIVAL_OFFSET, |(_, p)| p.nominal.offset)
            .with(LAUNCH_DELAY, |(l, p)| {
                pair_of(l).launch_delay(p.nominal.offset, length)
            })
            .with(U1_FINAL, |(_, p)| p.kick())
            .with(U1_FINAL_ERROR, |(_, p)| p.kick_error())
            .with(OUT_SLOW, |(_, p)| p.nominal.collision.outgoing[0])
            .with(OUT_MIDDLE, |(_, p)| p.nominal.collision.outgoing[1])
            .with(OUT_FAST, |(_, p)| p.nominal.collision.outgoing[2])
            .with(OUTCOME, |(_, p)| {
                p.nominal.collision.outcome.name().to_string()
            })
            .with(ENERGY_ERROR, |(_, p)| p.nominal.collision.energy_error)
            .with(MOMENTUM_ERROR, |(_, p)| p.nominal.collision.momentum_error)
            .with(STEPS, |(_, p)| p.nominal.collision.steps)
            .with(REJECTED_STEPS, |(_, p)| p.nominal.collision.rejected_steps)
            .with(FORCE_EVALUATIONS, |(_, p)| p.nominal.collision.evaluations)
            .table(&TABLE)?)
    }

    fn peak_table(
        &self,
        curves: &[Vec<CurvePoint>],
        peaks: &[Option<Peak>],
    ) -> Result<Table, StageError> {
        use contract::scan::{peak::*, *};
        let grid = self.params.grid;
        let spacing = (grid.offset_max - grid.offset_min) / f64::from(grid.points - 1);
        let length = self.params.launch_length;
        let rows: Vec<PeakRow> = self
            .params
            .launches
            .iter()
            .zip(peaks)
            .zip(curves)
            .map(|((launch, peak), curve)| PeakRow {
                launch,
                peak: peak.as_ref(),
                curve,
            })
            .collect();
        Ok(Rows::new(&rows)
            .with(LAUNCH, |r| r.launch.name.clone())
            .with(U2, |r| r.launch.u2)
            .with(U3, |r| r.launch.u3)
            .estimate(U1_FINAL_MAX_ABS, |r| {
                r.bounded(|p| p.kick, |p| p.kick_error)
            })
            .estimate(ARRIVAL_OFFSET_AT_MAX, |r| {
                r.bounded(|p| p.offset, |p| p.offset_error)
            })
            .with(LAUNCH_DELAY_AT_MAX, |r| {
                r.peak.map_or(f64::NAN, |p| {
                    pair_of(r.launch).launch_delay(p.offset, length)
                })
            })
            .with(GRID_SPACING, |_| spacing)
            .with(FAILED_SCENES, |r| {
                r.curve.iter().filter(|p| p.failed()).count() as u32
            })
            .with(WORST_ENERGY_ERROR, |r| {
                r.curve
                    .iter()
                    .filter(|p| !p.failed())
                    .map(|p| p.nominal.collision.energy_error.abs())
                    .fold(0.0, f64::max)
            })
            .table(&TABLE)?)
    }
}

/// One launch pair's curve and refined peak (none when every scene failed).
struct PeakRow<'a> {
    launch: &'a NamedLaunch,
    peak: Option<&'a Peak>,
    curve: &'a [CurvePoint],
}

impl PeakRow<'_> {
    /// A peak quantity with its error bound (NaN without a peak).
    fn bounded(&self, value: fn(&Peak) -> f64, bound: fn(&Peak) -> f64) -> Estimate {
        Estimate {
            mean: self.peak.map_or(f64::NAN, value),
            stderr: self.peak.map_or(f64::NAN, bound),
        }
    }
}
