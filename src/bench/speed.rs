//! This machine's speed against the machine the stages' cost estimates were
//! calibrated on, so that `ternary status` estimates this machine's CPU time.

use ternary::physics::potential::Potential;
use ternary::physics::scan::thermal_scenes;
use ternary::physics::scene::{EngineSettings, Method, collide_all};

use super::integrators::{one_by_one, timed};

/// Microseconds per scene on the machine whose default study calibrated the
/// stages' costs (2026-12-03, a498217): DPRKN12 at tolerance 1e-6 on the 2000
/// thermal scenes of `n = 6` (seed 1), one by one and interleaved (`ternary
/// bench integrators --n 6 --scenes 2000 --seed 1`, docs/benchmarks.md).
const CALIBRATION_MICROSECONDS: [f64; 2] = [8.11, 4.38];

/// Timed runs of each way; the fastest counts (other work on the cores only
/// slows). Three keep `status` at 0.12 s against five's 0.2 s (the fault
/// tests call it ~150 times) and read the same factors: 1.39-1.48 against
/// 1.38-1.50 in six alternating calls on idle cores (2026-12-04).
const RUNS: usize = 3;

/// How many times longer this machine takes than the calibration machine:
/// the geometric mean of the two ways' ratios, the fastest of [`RUNS`] runs
/// of the calibration's scenes each, on the calling thread (~0.12 s in
/// all). Both count: `collisions`, the largest stage, integrates interleaved
/// scenes, the rest of the study runs scalar code that follows the scenes
/// one by one (on a slower machine of 2026-12-03 the ratios were 1.90 and
/// 2.33, the default study's CPU time 2.09x).
pub fn machine_slowness() -> f64 {
    let scenes = thermal_scenes(2000, 1);
    let settings = EngineSettings::new(Method::Dprkn12, 1e-6, 100_000);
    let potential = Potential::inverse_power(6.0);
    let (_, alone) = timed(RUNS, || one_by_one(&potential, &settings, &scenes));
    let (_, together) = timed(RUNS, || collide_all(&potential, &settings, &scenes));
    let per_scene = |seconds: f64| 1e6 * seconds / scenes.len() as f64;
    let [alone_calibration, together_calibration] = CALIBRATION_MICROSECONDS;
    (per_scene(alone) / alone_calibration * per_scene(together) / together_calibration).sqrt()
}
