//! Mono-energetic collisions (physics.md §6): the special particle's final
//! velocity `u1f` against the delay between two launches.
//!
//! Frame: the special particle rests at the origin (`u1 = 0`). Particle 2
//! reaches the origin (in free flight) at `t = 0`, particle 3 at
//! `t = arrival_offset`. The launch delay of the published setup (entry at
//! `x = -sign(u) L/2`) follows as `offset + L/(2|u2|) - L/(2|u3|)`.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::launch::thermal_launch_speed;
use super::potential::Potential;
use super::scene::{Collision, EngineSettings, FreeLine, collide};

/// Velocities of the two thermal particles in units of `v_th`, relative to the
/// special particle at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaunchPair {
    /// Velocity `u2` of the first arrival.
    pub u2: f64,
    /// Velocity `u3` of the second arrival.
    pub u3: f64,
}

impl LaunchPair {
    /// Free asymptotes for an arrival offset `offset` (scaled time `l / v_th`).
    pub fn lines(&self, offset: f64) -> [FreeLine; 3] {
        [
            FreeLine {
                position: 0.0,
                velocity: 0.0,
            },
            FreeLine {
                position: 0.0,
                velocity: self.u2,
            },
            FreeLine {
                position: -self.u3 * offset,
                velocity: self.u3,
            },
        ]
    }

    /// Launch delay for entry at `-sign(u) L/2` (physics.md §3 step 3).
    pub fn launch_delay(&self, offset: f64, launch_length: f64) -> f64 {
        offset + 0.5 * launch_length * (1.0 / self.u2.abs() - 1.0 / self.u3.abs())
    }

    /// Collision time scale `T = 1/|u2| + 1/|u3|` (numerics.md).
    pub fn collision_time(&self) -> f64 {
        1.0 / self.u2.abs() + 1.0 / self.u3.abs()
    }
}

/// The special particle's final velocity `u1f` (sorted matching, physics.md §3).
pub fn special_final_velocity(collision: &Collision) -> f64 {
    collision.self_kick(0.0)
}

/// One point of a kick curve.
#[derive(Clone, Copy, Debug)]
pub struct ScanPoint {
    /// Arrival offset of particle 3 after particle 2, scaled time.
    pub offset: f64,
    /// The integrated scene.
    pub collision: Collision,
}

/// Integrates the scene of `launch` at one arrival offset.
pub fn scan_point(
    potential: &Potential,
    settings: &EngineSettings,
    launch: LaunchPair,
    offset: f64,
) -> ScanPoint {
    ScanPoint {
        offset,
        collision: collide(potential, settings, launch.lines(offset)),
    }
}

/// The largest `|u1f|` on a curve, refined between grid points.
#[derive(Clone, Copy, Debug)]
pub struct Peak {
    /// `|u1f,max|` in `v_th`, from the tight-tolerance rerun.
    pub kick: f64,
    /// Error bound on `kick`: tolerance sensitivity (tolerance vs. 100x tighter)
    /// plus the spread of `|u1f|` over the final bracket.
    pub kick_error: f64,
    /// Arrival offset at the maximum (NaN when the maximum is within three
    /// error bounds of zero, as for the integrable n = 2).
    pub offset: f64,
    /// Half-width of the final offset bracket (NaN with `offset`).
    pub offset_error: f64,
}

/// Golden-section refinement of the maximum of `|u1f|` on `[low, high]`,
/// which must bracket a single peak (the neighbours of the best grid point).
pub fn refine_peak(
    potential: &Potential,
    settings: &EngineSettings,
    launch: LaunchPair,
    low: f64,
    high: f64,
) -> Peak {
    let kick_at = |settings: &EngineSettings, offset: f64| {
        special_final_velocity(&scan_point(potential, settings, launch, offset).collision).abs()
    };
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (low, high);
    let mut c = b - ratio * (b - a);
    let mut d = a + ratio * (b - a);
    let (mut fc, mut fd) = (kick_at(settings, c), kick_at(settings, d));
    // Stop when the bracket is at the resolution of offsets near the peak.
    let resolution = 1e-9 * launch.collision_time();
    while b - a > resolution {
        if fc >= fd {
            (b, d, fd) = (d, c, fc);
            c = b - ratio * (b - a);
            fc = kick_at(settings, c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + ratio * (b - a);
            fd = kick_at(settings, d);
        }
    }
    let offset = 0.5 * (a + b);
    let tight = EngineSettings {
        tolerance: (settings.tolerance * 0.01).max(TIGHTEST_TOLERANCE),
        ..*settings
    };
    let kick = kick_at(&tight, offset);
    let nominal = kick_at(settings, offset);
    let bracket_spread = (fc - fd).abs().max((kick_at(settings, a) - nominal).abs());
    let kick_error = (kick - nominal).abs() + bracket_spread;
    // A maximum indistinguishable from zero (n = 2) has no location.
    let located = kick > 3.0 * kick_error;
    Peak {
        kick,
        kick_error,
        offset: if located { offset } else { f64::NAN },
        offset_error: if located { 0.5 * (b - a) } else { f64::NAN },
    }
}

/// The tightest tolerance used for error estimates: below it roundoff of the
/// gaps (relative 1e-16) dominates the local error.
pub const TIGHTEST_TOLERANCE: f64 = 1e-15;
/// Thermal scenes at `u' = 0`: launch speeds from the exact inverse CDF, random
/// directions, arrival offsets uniform within `+-1.5 T` (`T = 1/|u2| + 1/|u3|`),
/// where over 99% of the thermalization rate comes from (numerics.md).
pub fn thermal_scenes(scenes: usize, seed: u64) -> Vec<[FreeLine; 3]> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..scenes)
        .map(|_| {
            let mut velocity = || {
                let speed = thermal_launch_speed(rng.random::<f64>());
                if rng.random::<bool>() { speed } else { -speed }
            };
            let pair = LaunchPair {
                u2: velocity(),
                u3: velocity(),
            };
            let offset = (2.0 * rng.random::<f64>() - 1.0) * 1.5 * pair.collision_time();
            pair.lines(offset)
        })
        .collect()
}
