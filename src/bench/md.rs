//! The molecular-dynamics benchmark.

use std::fmt::Write as _;
use std::time::Instant;

use rand::SeedableRng;
use rand::rngs::StdRng;

/// What `ternary bench md` measures: one ring of the published configuration
/// (physics.md §7), advanced by cluster stepping and by whole-ring stepping.
#[derive(Clone, Copy, Debug)]
pub struct MdBenchOptions {
    /// Particles `N`.
    pub particles: usize,
    /// Ring radius, um.
    pub radius_um: f64,
    /// Temperature, eV.
    pub kt_ev: f64,
    /// Final time, ns.
    pub final_time_ns: f64,
    /// Neighbours on each side that interact.
    pub neighbours: usize,
    /// Seed of the initial state.
    pub seed: u64,
}

/// One way of advancing the ring, timed.
struct MdRun {
    seconds: f64,
    energy_error: f64,
    evaluations: u64,
    particle_forces: u64,
    velocities: Vec<f64>,
}

/// `ternary bench md`: wall time and energy error of one run of `N` electrons
/// (`n = 6`, `l0 = 1 um`, `eps = 1 eV`) to the final time, cluster stepping
/// against whole-ring stepping at the same tolerances, in one process.
pub fn md(options: &MdBenchOptions) -> Result<String, String> {
    use ternary::physics::clusters::ClusterRing;
    use ternary::physics::potential::InverseIntegerPower;
    use ternary::physics::ring::{Reach, RingForces, RingState, evolve, thermal_start};
    use ternary::physics::units::{Mass, PhysicalGas};

    let gas = PhysicalGas {
        l0_um: 1.0,
        eps_ev: 1.0,
        kt_ev: options.kt_ev,
        mass: Mass::ElectronMasses(1.0),
        density_per_um: 0.0,
    };
    let length = gas.length_unit_um(Some(6.0));
    let circumference = 2.0 * std::f64::consts::PI * options.radius_um / length;
    let duration = options.final_time_ns / gas.time_unit_ns(Some(6.0));
    let forces = RingForces {
        potential: InverseIntegerPower::<6>,
        circumference,
        reach: Reach::Neighbours(options.neighbours),
    };
    let mut rng = StdRng::seed_from_u64(options.seed);
    let (positions, velocities) =
        thermal_start(&forces, options.particles, Some(0.0), &mut rng, 1000)
            .map_err(|error| error.to_string())?;
    let start = RingState::new(&positions, &velocities, circumference);
    let energy = start.energy(&forces);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Ring of N = {} (n = 6, R = {} um, kT = {} eV, electrons): C = {circumference:.0} l, rho l = {:.2e}, t_f = {} ns = {duration:.4e} l/v_th, {} neighbours per side.\n",
        options.particles,
        options.radius_um,
        options.kt_ev,
        (options.particles - 1) as f64 / circumference,
        options.final_time_ns,
        options.neighbours
    );
    let _ = writeln!(
        out,
        "| stepping | tolerance | wall s | relative energy error | force sweeps | pair forces |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|");
    let mut rows = Vec::new();
    for tolerance in [1e-10, 1e-12] {
        let clock = Instant::now();
        let mut ring = ClusterRing::new(forces, &positions, &velocities, tolerance);
        ring.advance(duration, u64::MAX)
            .map_err(|error| format!("cluster stepping: {error}"))?;
        let cluster = MdRun {
            seconds: clock.elapsed().as_secs_f64(),
            energy_error: (ring.energy() - energy).abs() / energy,
            evaluations: ring.work.evaluations,
            particle_forces: ring.pair_forces,
            velocities: ring.velocities.clone(),
        };
        let clock = Instant::now();
        let mut whole = start.clone();
        let work = evolve(&forces, &mut whole, duration, tolerance, u64::MAX)
            .map_err(|error| format!("whole-ring stepping: {error}"))?;
        let global = MdRun {
            seconds: clock.elapsed().as_secs_f64(),
            energy_error: (whole.energy(&forces) - energy).abs() / energy,
            evaluations: work.evaluations,
            particle_forces: work.evaluations * (options.particles * options.neighbours) as u64,
            velocities: whole.velocities(),
        };
        for (name, run) in [("cluster", &cluster), ("whole ring", &global)] {
            let _ = writeln!(
                out,
                "| {name} | {tolerance:.0e} | {:.2} | {:.1e} | {} | {:.2e} |",
                run.seconds, run.energy_error, run.evaluations, run.particle_forces as f64
            );
        }
        rows.push((tolerance, cluster, global));
    }
    let _ = writeln!(out);
    for (tolerance, cluster, global) in &rows {
        let largest = cluster
            .velocities
            .iter()
            .zip(&global.velocities)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "tolerance {tolerance:.0e}: cluster stepping {:.1}x faster than whole-ring stepping; largest final velocity difference {largest:.1e} v_th",
            global.seconds / cluster.seconds
        );
    }
    Ok(out)
}
