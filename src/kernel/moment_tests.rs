//! [`super::add_moments`] against the moment sums' definition, truncation by
//! truncation: the same terms in the same order, so the same bits.

use super::*;
use rand::{RngExt, SeedableRng};

/// Adds one contribution to `sums` by the definition: at each truncation
/// `X`, every velocity `x` counted where `|x| <= X` (a factor 1 or 0).
fn add_by_definition(
    sums: &mut [MomentSums],
    truncations: &[f64],
    contribution: &Contribution,
    weight: f64,
) {
    let squares = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>();
    let kick = contribution.self_kick();
    for (slot, &limit) in sums.iter_mut().zip(truncations) {
        let inside = |x: f64| if x.abs() <= limit { 1.0 } else { 0.0 };
        slot.self_drift += weight * kick * inside(kick);
        slot.self_variance += weight * kick * kick * inside(kick);
        for (out, incoming) in contribution.outgoing.iter().zip(contribution.incoming) {
            slot.window_drift += weight * (out * inside(*out) - incoming * inside(incoming));
            slot.window_variance +=
                weight * (out * out * inside(*out) - incoming * incoming * inside(incoming));
        }
        if limit.is_infinite() {
            slot.energy_change +=
                weight * (squares(&contribution.outgoing) - squares(&contribution.incoming)).abs();
        }
    }
}

/// A velocity relative to `u'`: zero, a truncation itself (the edge counts),
/// or spread over six decades of either sign.
fn velocity(rng: &mut rand::rngs::StdRng, truncations: &[f64]) -> f64 {
    let sign = if rng.random() { 1.0 } else { -1.0 };
    match rng.random_range(0..4) {
        0 => 0.0,
        1 => sign * truncations[rng.random_range(0..truncations.len() - 1)],
        _ => sign * libm::exp10(rng.random_range(-5.0..1.0)),
    }
}

#[test]
fn moment_sums_are_the_definitions_bits() {
    let truncations: Vec<f64> = (0..=15)
        .map(|k| 0.04 * libm::exp10((f64::from(k) - 15.0) / 5.0))
        .chain([f64::INFINITY])
        .collect();
    let mut rng = rand::rngs::StdRng::seed_from_u64(59);
    let mut sums = vec![MomentSums::default(); truncations.len()];
    let mut expected = sums.clone();
    for _ in 0..2000 {
        let incoming = [
            0.0,
            velocity(&mut rng, &truncations),
            velocity(&mut rng, &truncations),
        ];
        let mut outgoing = incoming.map(|_| velocity(&mut rng, &truncations));
        outgoing.sort_by(f64::total_cmp);
        let contribution = Contribution {
            weight: rng.random_range(0.1..10.0),
            incoming,
            outgoing,
            self_rank: rng.random_range(0..3),
        };
        add_moments(&mut sums, &truncations, &contribution, contribution.weight);
        add_by_definition(
            &mut expected,
            &truncations,
            &contribution,
            contribution.weight,
        );
    }
    let bits = |s: &[MomentSums]| -> Vec<[u64; 5]> {
        s.iter()
            .map(|m| {
                [
                    m.self_drift,
                    m.self_variance,
                    m.window_drift,
                    m.window_variance,
                    m.energy_change,
                ]
                .map(f64::to_bits)
            })
            .collect()
    };
    assert_eq!(bits(&sums), bits(&expected));
    assert!(sums[0].self_variance > 0.0 && sums[0].self_variance < sums[15].self_variance);
}
