//! Physics invariants of the scattering engine (physics.md §8, numerics.md):
//! conservation laws, the integrable n = 2 case, mirror symmetry, agreement of
//! independent integrators, and stress scenes.

use ternary::physics::potential::{Family, Morse, PairPotential, Potential};
use ternary::physics::scan::LaunchPair;
use ternary::physics::scan::thermal_scenes;
use ternary::physics::scene::{
    Collision, EngineSettings, FreeLine, Method, Outcome, collide, collide_all,
};

fn engine(method: Method, tolerance: f64) -> EngineSettings {
    EngineSettings::new(method, tolerance, 100_000)
}

fn default_engine() -> EngineSettings {
    engine(Method::Dprkn12, 1e-12)
}

fn ipp(n: f64) -> Potential {
    Potential::inverse_power(n)
}

/// Relative energy error bound stated in README: 1e-11 at the default tolerance.
const ENERGY_BOUND: f64 = 1e-11;
/// Momentum is conserved by construction (centre-of-mass velocity is not
/// integrated); only reconstruction rounding remains.
const MOMENTUM_BOUND: f64 = 1e-13;

fn assert_conserved(collision: &Collision, what: &str) {
    assert!(!collision.outcome.is_failure(), "{what}: {collision:?}");
    assert!(
        collision.energy_error.abs() <= ENERGY_BOUND,
        "{what}: energy {collision:?}"
    );
    assert!(
        collision.momentum_error <= MOMENTUM_BOUND,
        "{what}: momentum {collision:?}"
    );
}

#[test]
fn thermal_scenes_conserve_energy_and_momentum() {
    let potentials = [
        ipp(3.0),
        ipp(4.0),
        ipp(6.0),
        ipp(7.5),
        ipp(12.0),
        Potential::lennard_jones(1.0),
    ];
    for potential in potentials {
        for (k, lines) in thermal_scenes(1000, 7).into_iter().enumerate() {
            let collision = collide(&potential, &default_engine(), lines);
            assert_conserved(&collision, &format!("{} scene {k}", potential.id()));
        }
    }
}

/// Largest difference between sorted outgoing and sorted incoming velocities.
fn permutation_defect(collision: &Collision) -> f64 {
    (0..3)
        .map(|k| (collision.outgoing[k] - collision.incoming[k]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn calogero_outgoing_velocities_permute_incoming() {
    let potential = ipp(2.0);
    let mut worst: f64 = 0.0;
    for lines in thermal_scenes(2000, 3) {
        let collision = collide(&potential, &default_engine(), lines);
        assert_conserved(&collision, "n = 2 thermal");
        worst = worst.max(permutation_defect(&collision));
    }
    for launch in [
        LaunchPair { u2: 1.0, u3: -1.0 },
        LaunchPair { u2: 1.1, u3: -0.9 },
    ] {
        for k in 0..=400 {
            let offset = -8.0 + 0.04 * f64::from(k);
            let collision = collide(&potential, &default_engine(), launch.lines(offset));
            assert_conserved(&collision, "n = 2 scan");
            worst = worst.max(permutation_defect(&collision));
        }
    }
    assert!(worst <= 1e-10, "worst permutation defect {worst:e}");
}

fn mirrored(lines: [FreeLine; 3]) -> [FreeLine; 3] {
    lines.map(|line| FreeLine {
        position: -line.position,
        velocity: -line.velocity,
    })
}

#[test]
fn mirror_image_negates_every_outgoing_velocity() {
    for potential in [ipp(6.0), ipp(12.0), Potential::lennard_jones(0.5)] {
        for lines in thermal_scenes(500, 11) {
            let direct = collide(&potential, &default_engine(), lines);
            let mirror = collide(&potential, &default_engine(), mirrored(lines));
            let speed = direct.incoming[2] - direct.incoming[0];
            for k in 0..3 {
                // Sorted ascending, so the mirror image reverses the order. The
                // two integrations differ by rounding and the step control's
                // local error, 1e-12 of the speed scale per step.
                let difference = (direct.outgoing[k] + mirror.outgoing[2 - k]).abs();
                assert!(
                    difference <= 1e-10 * speed,
                    "{potential:?}: {direct:?} vs {mirror:?}"
                );
            }
        }
    }
}

#[test]
fn independent_integrators_agree() {
    let potential = ipp(6.0);
    for lines in thermal_scenes(300, 5) {
        let reference = collide(&potential, &engine(Method::Dprkn12, 1e-14), lines);
        for method in [Method::Dop853, Method::Dopri5] {
            let other = collide(&potential, &engine(method, 1e-13), lines);
            let speed = reference.incoming[2] - reference.incoming[0];
            for k in 0..3 {
                let difference = (reference.outgoing[k] - other.outgoing[k]).abs();
                assert!(
                    difference <= 1e-10 * speed,
                    "{method:?}: {reference:?} vs {other:?}"
                );
            }
        }
    }
}

/// Stress scenes: each must end in the right class with conservation intact.
#[test]
fn head_on_at_eight_thermal_speeds() {
    let launch = LaunchPair { u2: 8.0, u3: -8.0 };
    for potential in [
        ipp(2.0),
        ipp(6.0),
        ipp(12.0),
        Potential::lennard_jones(0.05),
    ] {
        for offset in [-0.05, 0.0, 0.01, 0.1] {
            let collision = collide(&potential, &default_engine(), launch.lines(offset));
            assert_eq!(collision.outcome, Outcome::Scattered);
            assert_conserved(
                &collision,
                &format!("{} head-on at {offset}", potential.id()),
            );
        }
    }
}

#[test]
fn slow_collision_at_relative_speed_one_thousandth() {
    let launch = LaunchPair {
        u2: 1e-3,
        u3: -1e-3,
    };
    for potential in [
        ipp(2.0),
        ipp(6.0),
        ipp(12.0),
        Potential::lennard_jones(10.0),
    ] {
        for offset in [-500.0, 0.0, 300.0] {
            let collision = collide(&potential, &default_engine(), launch.lines(offset));
            assert_conserved(&collision, &format!("{} slow at {offset}", potential.id()));
        }
    }
}

#[test]
fn lennard_jones_shallow_and_deep_wells_conserve_energy() {
    for theta in [0.05, 10.0] {
        let potential = Potential::lennard_jones(theta);
        for lines in thermal_scenes(500, 13) {
            let collision = collide(&potential, &default_engine(), lines);
            assert_conserved(&collision, &format!("theta = {theta}"));
        }
    }
}

/// Widely separated arrivals are two binary encounters joined by an analytic
/// free-flight jump with first-order tail impulses; for n = 2 the outcome must
/// still be an exact permutation, for any n energy must be conserved.
#[test]
fn free_flight_jumps_keep_integrability_and_conservation() {
    let launches = [
        LaunchPair { u2: 1.0, u3: -1.0 },
        LaunchPair { u2: 1.1, u3: 0.4 },
        LaunchPair { u2: -0.3, u3: 2.0 },
    ];
    let mut jumps = 0;
    for launch in launches {
        for offset in [-4e6, -300.0, -40.0, -12.0, 12.0, 40.0, 300.0, 3e6] {
            let calogero = collide(&ipp(2.0), &default_engine(), launch.lines(offset));
            assert_conserved(&calogero, "n = 2 with jump");
            assert!(permutation_defect(&calogero) <= 1e-10, "{calogero:?}");
            for potential in [ipp(6.0), Potential::lennard_jones(1.0)] {
                let collision = collide(&potential, &default_engine(), launch.lines(offset));
                assert_conserved(
                    &collision,
                    &format!("{} at offset {offset}", potential.id()),
                );
                jumps += collision.jumps;
            }
        }
    }
    assert!(jumps > 0, "no scene exercised the free-flight jump");
}

/// A thermal scene in a deep Lennard-Jones well (theta = 0.05, depth 5 kT)
/// that leaves a bound pair: the pair members share the pair's centre-of-mass
/// velocity, its internal energy lies inside the well, and energy including
/// the binding energy is conserved.
#[test]
fn deep_lennard_jones_well_recombines_a_pair() {
    let potential = Potential::lennard_jones(0.05);
    let lines = [
        FreeLine {
            position: 0.0,
            velocity: 0.0,
        },
        FreeLine {
            position: 0.0,
            velocity: 0.8400737840527969,
        },
        FreeLine {
            position: -0.02467460864074322,
            velocity: -0.7965549477643259,
        },
    ];
    let collision = collide(&potential, &default_engine(), lines);
    assert_eq!(collision.outcome, Outcome::Recombined, "{collision:?}");
    assert_conserved(&collision, "recombination");
    assert!(collision.binding_energy < 0.0 && collision.binding_energy > -5.0);
    let [slow, middle, fast] = collision.outgoing;
    assert!(middle == fast || middle == slow, "{collision:?}");
    // The free particle carries away the released binding energy.
    let energy_in: f64 = collision.incoming.iter().map(|u| u * u / 2.0).sum();
    let kinetic_out: f64 = collision.outgoing.iter().map(|u| u * u / 2.0).sum();
    assert!((kinetic_out + collision.binding_energy - energy_in).abs() < 1e-10);
}

/// The analytic free-flight step against integrating the same flight: two
/// independent treatments of the tails must give the same outgoing velocities.
#[test]
fn free_flight_skipping_agrees_with_integrating_through() {
    let through = EngineSettings {
        free_flight: false,
        ..default_engine()
    };
    let launches = [
        LaunchPair { u2: 1.0, u3: -1.0 },
        LaunchPair { u2: 1.1, u3: 0.4 },
        LaunchPair { u2: -0.3, u3: 2.0 },
    ];
    for potential in [ipp(2.0), ipp(6.0), Potential::lennard_jones(1.0)] {
        for launch in launches {
            for offset in [-300.0, -40.0, -12.0, 12.0, 40.0, 300.0] {
                let skipped = collide(&potential, &default_engine(), launch.lines(offset));
                let integrated = collide(&potential, &through, launch.lines(offset));
                assert_eq!(integrated.jumps, 0);
                assert_conserved(&integrated, "integrated through");
                let speed = skipped.incoming[2] - skipped.incoming[0];
                for k in 0..3 {
                    // Both are within the tolerance-level error of the exact result.
                    let difference = (skipped.outgoing[k] - integrated.outgoing[k]).abs();
                    assert!(
                        difference <= 1e-10 * speed,
                        "{potential:?} {launch:?} {offset}: {skipped:?} vs {integrated:?}"
                    );
                }
            }
        }
    }
}

/// Thermal scenes of a Morse gas (a well, a soft but high wall) conserve
/// energy and momentum like Lennard-Jones ones, deep well and shallow.
#[test]
fn morse_shallow_and_deep_wells_conserve_energy() {
    for (theta, x0) in [(0.2, 4.0), (5.0, 6.0)] {
        let potential = Potential::Morse(Morse::new(theta, x0).expect("valid"));
        for lines in thermal_scenes(300, 17) {
            let collision = collide(&potential, &default_engine(), lines);
            assert_conserved(&collision, &potential.id());
        }
    }
}

/// The Morse bound-pair length `K_b = int_(U<0) exp(-U) erf(sqrt(-U)) dx`
/// (Simpson in the family's substitution) against a plain trapezoid over `x`
/// with libm's `erf`: two independent quadratures of one integral.
#[test]
fn morse_bound_pair_length_agrees_with_a_direct_quadrature() {
    for (theta, x0) in [(0.2, 4.0), (1.0, 4.0), (5.0, 6.0)] {
        let morse = Morse::new(theta, x0).expect("valid");
        let start = x0 - std::f64::consts::LN_2;
        let steps = 2_000_000;
        let h = 60.0 / f64::from(steps);
        let integrand = |x: f64| {
            let binding = -morse.energy(x).min(0.0);
            libm::exp(binding) * libm::erf(binding.sqrt())
        };
        let direct: f64 = (0..=steps)
            .map(|k| {
                let weight = if k == 0 || k == steps { 0.5 } else { 1.0 };
                weight * integrand(start + h * f64::from(k))
            })
            .sum::<f64>()
            * h;
        let simpson = morse.bound_pair_length();
        // The trapezoid's error is O(h^2 f'') ~ 1e-9 here (the integrand has a
        // square-root edge at the start, which costs O(h^1.5) ~ 1e-8).
        assert!(
            (simpson / direct - 1.0).abs() < 1e-6,
            "theta = {theta}: {simpson} against {direct}"
        );
    }
}

/// Scenes integrated together on interleaved steps (as the pipeline integrates them) are the
/// scenes integrated one by one, to the last bit of every outgoing velocity and every counter:
/// thermal scenes of a steep and a soft power law, a deep Lennard-Jones well that recombines
/// pairs, and a step budget that some scenes exhaust, in any order of the batch.
#[test]
fn interleaved_scenes_are_the_scenes_alone_to_the_bit() {
    let bits = |c: &Collision| {
        let floats = [
            c.outgoing,
            c.incoming,
            [c.energy_error, c.binding_energy, 0.0],
        ];
        (
            floats.map(|v| v.map(f64::to_bits)),
            c.outcome,
            c.steps,
            c.rejected_steps,
            c.jumps,
            c.evaluations,
        )
    };
    let scenes = thermal_scenes(203, 11);
    let cases = [
        (ipp(12.0), default_engine()),
        (ipp(3.0), engine(Method::Dprkn12, 1e-8)),
        (Potential::lennard_jones(0.05), default_engine()),
        (ipp(6.0), EngineSettings::new(Method::Dprkn12, 1e-12, 60)),
    ];
    for (potential, settings) in cases {
        let alone: Vec<Collision> = scenes
            .iter()
            .map(|&lines| collide(&potential, &settings, lines))
            .collect();
        let outcomes = |want: Outcome| alone.iter().filter(|c| c.outcome == want).count();
        let together = collide_all(&potential, &settings, &scenes);
        let reversed: Vec<[FreeLine; 3]> = scenes.iter().rev().copied().collect();
        let backwards = collide_all(&potential, &settings, &reversed);
        for (k, collision) in alone.iter().enumerate() {
            let what = format!("{} scene {k}", potential.id());
            assert_eq!(bits(collision), bits(&together[k]), "{what}");
            assert_eq!(
                bits(collision),
                bits(&backwards[scenes.len() - 1 - k]),
                "{what}"
            );
        }
        // Every ending the batch must keep apart: the deep well recombines some scenes, the
        // short budget ends some and not others.
        assert!(outcomes(Outcome::Scattered) > 0, "{}", potential.id());
        if potential.id() == "lj-0.05" {
            assert!(outcomes(Outcome::Recombined) > 0);
        }
        if settings.max_steps < 100 {
            assert!(outcomes(Outcome::StepBudgetExhausted) > 0);
        }
    }
}

/// Scaling invariance of an inverse power law `r^-n`: launches `lambda` times
/// faster at offsets `lambda^-(n+2)/n` as long give `lambda` times the
/// outgoing velocities (lengths scale as `lambda^-2/n`). So the largest kick
/// of the symmetric pair `(1, -1)` (`n = 6`: 0.0308 `v_th`, the paper's
/// `|u1f,max|`) becomes 0.12 at `(4, -4)`: thermal launches near 4 `v_th`
/// kick the special particle past the default window's edge (0.1), which is
/// why `a_n` is read without truncation.
#[test]
fn kicks_scale_with_the_launch_speeds_and_reach_past_the_window_edge() {
    use ternary::config::KernelConfig;
    use ternary::physics::scan::{refine_peak, special_final_velocity};
    let (n, lambda) = (6.0, 4.0);
    let potential = ipp(n);
    let settings = default_engine();
    let unit = LaunchPair { u2: 1.0, u3: -1.0 };
    let kick = |launch: LaunchPair, offset: f64| {
        let collision = collide(&potential, &settings, launch.lines(offset));
        assert_conserved(&collision, &format!("{launch:?} at {offset}"));
        special_final_velocity(&collision)
    };
    let grid: Vec<f64> = (-200..=200).map(|k| f64::from(k) * 0.01).collect();
    let best = (1..grid.len() - 1)
        .max_by(|&a, &b| {
            kick(unit, grid[a])
                .abs()
                .total_cmp(&kick(unit, grid[b]).abs())
        })
        .unwrap();
    let peak = refine_peak(&potential, &settings, unit, grid[best - 1], grid[best + 1]);
    assert!((peak.kick - 0.0308).abs() < 5e-4, "{peak:?}");
    let fast = LaunchPair {
        u2: lambda,
        u3: -lambda,
    };
    let time_scale = libm::pow(lambda, -(n + 2.0) / n);
    for offset in [peak.offset, peak.offset + 0.3, -1.0] {
        let (slow, scaled) = (kick(unit, offset), kick(fast, offset * time_scale));
        assert!(
            (scaled - lambda * slow).abs() <= 1e-9 * scaled.abs(),
            "offset {offset}: {scaled} against {lambda} x {slow}"
        );
    }
    let edge = 0.5 * KernelConfig::default().window;
    let largest = kick(fast, peak.offset * time_scale).abs();
    assert!(
        largest > 1.1 * edge,
        "{largest} within the window's edge {edge}"
    );
}
