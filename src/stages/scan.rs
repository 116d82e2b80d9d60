//! `scan`: mono-energetic kick curves of one potential (physics.md §6).
//!
//! Outputs `curve` (one row per launch pair and arrival offset) and `peak`
//! (one row per launch pair: `|u1f,max|` with its error bound and location).
//! Every `u1f` carries an error estimate from a rerun at 100x tighter tolerance.

use rayon::prelude::*;
use serde_json::Value;

use crate::config::{NamedLaunch, ScanParams};
use crate::physics::scan::{
    LaunchPair, Peak, ScanPoint, TIGHTEST_TOLERANCE, refine_peak, scan_point,
    special_final_velocity,
};
use crate::physics::scene::EngineSettings;
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

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

impl Stage for ScanStage {
    fn id(&self) -> InstanceId {
        InstanceId::new("scan", &self.params.potential.id())
    }

    fn version(&self) -> u32 {
        2
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["curve", "peak"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    fn work_units(&self) -> u64 {
        self.params.launches.len() as u64 * u64::from(self.params.grid.points)
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
        let rows = || {
            self.params
                .launches
                .iter()
                .zip(curves)
                .flat_map(|(l, c)| c.iter().map(move |p| (l, p)))
        };
        let f64_of = |f: &dyn Fn(&NamedLaunch, &CurvePoint) -> f64| {
            rows().map(|(l, p)| f(l, p)).collect::<Vec<f64>>()
        };
        let u32_of =
            |f: &dyn Fn(&CurvePoint) -> u32| rows().map(|(_, p)| f(p)).collect::<Vec<u32>>();
        let length = self.params.launch_length;
        let columns = vec![
            Column::text(
                "launch",
                "name of the launch pair",
                rows().map(|(l, _)| l.name.clone()).collect(),
            ),
            Column::f64(
                "u2",
                "v_th",
                "velocity of the first arrival (special particle at rest)",
                f64_of(&|l, _| l.u2),
            ),
            Column::f64(
                "u3",
                "v_th",
                "velocity of the second arrival",
                f64_of(&|l, _| l.u3),
            ),
            Column::f64(
                "arrival_offset",
                "l/v_th",
                "free-flight arrival time of particle 3 minus that of particle 2 at the special particle",
                f64_of(&|_, p| p.nominal.offset),
            ),
            Column::f64(
                "launch_delay",
                "l/v_th",
                "launch time of particle 3 minus that of particle 2 for entry at -sign(u) L/2",
                f64_of(&|l, p| pair_of(l).launch_delay(p.nominal.offset, length)),
            ),
            Column::f64(
                "u1_final",
                "v_th",
                "final velocity of the special particle (sorted matching)",
                f64_of(&|_, p| p.kick()),
            ),
            Column::f64(
                "u1_final_error",
                "v_th",
                "|u1_final - u1_final at 100x tighter tolerance|",
                f64_of(&|_, p| p.kick_error()),
            ),
            Column::f64(
                "out_slow",
                "v_th",
                "slowest outgoing velocity",
                f64_of(&|_, p| p.nominal.collision.outgoing[0]),
            ),
            Column::f64(
                "out_middle",
                "v_th",
                "middle outgoing velocity",
                f64_of(&|_, p| p.nominal.collision.outgoing[1]),
            ),
            Column::f64(
                "out_fast",
                "v_th",
                "fastest outgoing velocity",
                f64_of(&|_, p| p.nominal.collision.outgoing[2]),
            ),
            Column::text(
                "outcome",
                "scattered, recombined or failed_*",
                rows()
                    .map(|(_, p)| p.nominal.collision.outcome.name().to_string())
                    .collect(),
            ),
            Column::f64(
                "energy_error",
                "1",
                "(E_out - E_in) / E_in of the relative motion",
                f64_of(&|_, p| p.nominal.collision.energy_error),
            ),
            Column::f64(
                "momentum_error",
                "1",
                "|P_out - P_in| / relative-speed scale",
                f64_of(&|_, p| p.nominal.collision.momentum_error),
            ),
            Column::u32(
                "steps",
                "1",
                "accepted integrator steps",
                u32_of(&|p| p.nominal.collision.steps),
            ),
            Column::u32(
                "rejected_steps",
                "1",
                "rejected integrator steps",
                u32_of(&|p| p.nominal.collision.rejected_steps),
            ),
            Column::u32(
                "force_evaluations",
                "1",
                "evaluations of the three pair forces",
                u32_of(&|p| p.nominal.collision.evaluations),
            ),
        ];
        Ok(Table::new("curve", columns)?.with_metadata(
            "ternary.description",
            "mono-energetic kick curves u1f(arrival offset)".into(),
        ))
    }

    fn peak_table(
        &self,
        curves: &[Vec<CurvePoint>],
        peaks: &[Option<Peak>],
    ) -> Result<Table, StageError> {
        let launches = &self.params.launches;
        let grid = self.params.grid;
        let spacing = (grid.offset_max - grid.offset_min) / f64::from(grid.points - 1);
        let peak_of = |f: &dyn Fn(&Peak) -> f64| {
            peaks
                .iter()
                .map(|p| p.as_ref().map_or(f64::NAN, f))
                .collect::<Vec<f64>>()
        };
        let length = self.params.launch_length;
        let delays = launches
            .iter()
            .zip(peaks)
            .map(|(l, p)| {
                p.as_ref()
                    .map_or(f64::NAN, |p| pair_of(l).launch_delay(p.offset, length))
            })
            .collect();
        let failures = curves
            .iter()
            .map(|c| c.iter().filter(|p| p.failed()).count() as u32)
            .collect();
        let worst_energy = curves
            .iter()
            .map(|c| {
                c.iter()
                    .filter(|p| !p.failed())
                    .map(|p| p.nominal.collision.energy_error.abs())
                    .fold(0.0, f64::max)
            })
            .collect();
        let columns = vec![
            Column::text(
                "launch",
                "name of the launch pair",
                launches.iter().map(|l| l.name.clone()).collect(),
            ),
            Column::f64(
                "u2",
                "v_th",
                "velocity of the first arrival",
                launches.iter().map(|l| l.u2).collect(),
            ),
            Column::f64(
                "u3",
                "v_th",
                "velocity of the second arrival",
                launches.iter().map(|l| l.u3).collect(),
            ),
            Column::f64(
                "u1_final_max_abs",
                "v_th",
                "largest |u1f| over arrival offsets, refined between grid points",
                peak_of(&|p| p.kick),
            ),
            Column::f64(
                "u1_final_max_abs_error",
                "v_th",
                "error bound of u1_final_max_abs (tolerance sensitivity plus bracket spread)",
                peak_of(&|p| p.kick_error),
            ),
            Column::f64(
                "arrival_offset_at_max",
                "l/v_th",
                "arrival offset of the maximum",
                peak_of(&|p| p.offset),
            ),
            Column::f64(
                "arrival_offset_at_max_error",
                "l/v_th",
                "half-width of the final bracket",
                peak_of(&|p| p.offset_error),
            ),
            Column::f64(
                "launch_delay_at_max",
                "l/v_th",
                "launch delay of the maximum for entry at -sign(u) L/2",
                delays,
            ),
            Column::f64(
                "grid_spacing",
                "l/v_th",
                "spacing of the offset grid",
                vec![spacing; launches.len()],
            ),
            Column::u32(
                "failed_scenes",
                "1",
                "scenes of the curve that failed (excluded)",
                failures,
            ),
            Column::f64(
                "worst_energy_error",
                "1",
                "largest |relative energy error| on the curve",
                worst_energy,
            ),
        ];
        Ok(Table::new("peak", columns)?
            .with_metadata("ternary.description", "peak of each kick curve".into()))
    }
}
