//! Ring molecular dynamics against the three-body scattering engine: two
//! independent integrations of the same collision (different coordinates,
//! step control, start and stop logic) give the same outgoing velocities,
//! and equilibrium rings break their bound pairs at the rate the scenes give.

use ternary::physics::clusters::ClusterRing;
use ternary::physics::dissociation::{dissociation_rate, sobol_dissociation_scenes};
use ternary::physics::md::CLUSTER_STEP_BUDGET;
use ternary::physics::pair_kinetics::{
    KineticsSettings, RelaxationSettings, dense_bound_length, equilibrium_runs, pair_relaxation,
};
use ternary::physics::potential::{InverseIntegerPower, Potential};
use ternary::physics::ring::{Reach, RingForces};
use ternary::physics::scan::LaunchPair;
use ternary::physics::scene::{EngineSettings, Method, collide};
use ternary::stats::Estimate;

/// A three-body collision on a ring far larger than the collision: cluster
/// stepping from free flight 300 time units before to 600 after gives the
/// scene engine's asymptotic outgoing velocities.
#[test]
fn ring_collision_matches_the_scattering_engine() {
    let engine = EngineSettings::new(Method::Dprkn12, 1e-12, 100_000);
    let circumference = 1e5;
    for (u2, u3, offset) in [
        (1.0, -1.0, 0.76),
        (1.1, -0.9, 0.3),
        (2.3, -0.4, -1.2),
        (0.8, 1.9, 2.0),
    ] {
        let pair = LaunchPair { u2, u3 };
        let lines = pair.lines(offset);
        let scene = collide(&Potential::inverse_power(6.0), &engine, lines);
        let start = -300.0;
        let mut particles: Vec<(f64, f64)> = lines
            .iter()
            .map(|l| {
                (
                    l.position + l.velocity * start + 0.5 * circumference,
                    l.velocity,
                )
            })
            .collect();
        particles.sort_by(|a, b| a.0.total_cmp(&b.0));
        let positions: Vec<f64> = particles.iter().map(|p| p.0).collect();
        let velocities: Vec<f64> = particles.iter().map(|p| p.1).collect();
        let forces = RingForces {
            potential: InverseIntegerPower::<6>,
            circumference,
            reach: Reach::Neighbours(1),
        };
        let mut ring = ClusterRing::new(forces, &positions, &velocities, 1e-12);
        ring.advance(900.0, 10_000_000).unwrap();
        let mut outgoing = ring.velocities.clone();
        outgoing.sort_by(f64::total_cmp);
        for (a, b) in outgoing.iter().zip(scene.outgoing) {
            assert!(
                (a - b).abs() < 1e-9,
                "u2 {u2} u3 {u3} offset {offset}: ring {outgoing:?} vs scene {:?}",
                scene.outgoing
            );
        }
    }
}

/// Lennard-Jones rings at theta = 1 and rho l = 0.02 in equilibrium: the
/// mean number of bound pairs is the exact equilibrium's at that density
/// (mass action with `K_b`, corrected for the density), and the early
/// relaxation of its fluctuations gives the dissociation rate `k_d` of the
/// three-body scenes that start from thermal bound pairs: ring molecular
/// dynamics of 128 particles against an independent integration of one
/// pair and one atom at a time (physics::pair_kinetics).
#[test]
fn ring_bound_pairs_relax_at_the_dissociation_rate_of_the_scenes() {
    let potential = Potential::lennard_jones(1.0);
    let (particles, density) = (128, 0.02);
    let circumference = particles as f64 / density;
    let settings = KineticsSettings {
        particles,
        duration: 16_000.0,
        interval: 1.0,
        tolerance: 1e-6,
        max_steps: CLUSTER_STEP_BUDGET,
    };
    let seeds: Vec<u64> = (0..32).collect();
    let runs = equilibrium_runs(&potential, circumference, 3, &settings, &seeds, || {}).unwrap();
    let relaxation = RelaxationSettings {
        particles,
        circumference,
        interval: 1.0,
        fit_from: 20.0,
        fit_down_to: 0.8,
    };
    let measured = pair_relaxation(&runs, &relaxation).unwrap();

    let engine = EngineSettings::new(Method::Dprkn12, 1e-10, 100_000);
    let rates: Vec<f64> = (0..8)
        .map(|randomization| {
            let scenes =
                sobol_dissociation_scenes(&potential, &engine, (34, randomization, 1024), || {})
                    .unwrap();
            dissociation_rate(&scenes)
        })
        .collect();
    let k_d = Estimate::from_replicates(&rates);
    let k_b = dense_bound_length(&potential, density);

    let z = |md: Estimate, predicted: Estimate| {
        (md.mean - predicted.mean) / libm::hypot(md.stderr, predicted.stderr)
    };
    let exact = Estimate {
        mean: k_b,
        stderr: 0.0,
    };
    let bound = z(measured.bound_length, exact);
    let dissociation = z(measured.dissociation, k_d);
    println!(
        "n_b / rho_f^2: MD {:?} exact {k_b} (z {bound:.2}); k_d: MD {:?} scenes {k_d:?} (z {dissociation:.2})",
        measured.bound_length, measured.dissociation
    );
    assert!(bound.abs() < 3.0, "n_b / rho_f^2: z = {bound}");
    assert!(dissociation.abs() < 3.0, "k_d: z = {dissociation}");
    // Power: the rate is measured to 15% or better, K_b to 8%.
    assert!(measured.dissociation.stderr < 0.15 * k_d.mean);
    assert!(measured.bound_length.stderr < 0.08 * k_b);
}
