//! Ring molecular dynamics against the three-body scattering engine: two
//! independent integrations of the same collision (different coordinates,
//! step control, start and stop logic) give the same outgoing velocities.

use ternary::physics::clusters::ClusterRing;
use ternary::physics::potential::{InverseIntegerPower, Potential};
use ternary::physics::ring::{Reach, RingForces};
use ternary::physics::scan::LaunchPair;
use ternary::physics::scene::{EngineSettings, Method, collide};

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
