//! The Lennard-Jones potential `U = eps ((l0/d)^12 - (l0/d)^6)`, scaled
//! `U/kT = theta x^-12 - x^-6` with `theta = kT/eps` and `l = l0 (eps/kT)^(1/6)`
//! (physics.md §1): a well of depth `1 / (4 theta)` that binds pairs.

use serde::{Deserialize, Serialize};

use super::{
    Family, Listed, PairPotential, Potential, bound_weight, parameters, simpson_on_unit_interval,
};

/// Lennard-Jones `U = theta x^-12 - x^-6` with `theta = kT / eps`
/// (physics.md §1: length unit `l = l0 (eps/kT)^(1/6)`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LennardJones {
    /// `theta = kT / eps`.
    pub theta: f64,
}

impl PairPotential for LennardJones {
    fn energy(&self, x: f64) -> f64 {
        let inverse6 = x.recip().powi(6);
        (self.theta * inverse6 - 1.0) * inverse6
    }
    #[inline]
    fn force(&self, x: f64) -> f64 {
        let inverse = x.recip();
        let inverse6 = inverse.powi(6);
        (12.0 * self.theta * inverse6 - 6.0) * inverse6 * inverse
    }
    fn tail_integral(&self, x: f64) -> f64 {
        let inverse = x.recip();
        let inverse5 = inverse.powi(5);
        (self.theta * inverse.powi(6) / 11.0 - 0.2) * inverse5
    }
    /// The minimum sits at `x^6 = 2 theta` with `U = -1 / (4 theta)`.
    fn well_depth(&self) -> f64 {
        0.25 / self.theta
    }
    /// Each of the two terms is below `level / 2` beyond this separation.
    fn range(&self, level: f64) -> f64 {
        libm::pow(2.0 * self.theta / level, 1.0 / 12.0).max(libm::pow(2.0 / level, 1.0 / 6.0))
    }
}

impl LennardJones {
    /// Range of `theta = kT/eps`: below it nearly every pair is bound, above
    /// it the well does not matter.
    pub const THETA_RANGE: [f64; 2] = [1e-3, 1e3];

    /// How `[potentials]` lists Lennard-Jones potentials: by `theta`.
    pub const LISTED: Listed = Listed {
        key: "lennard_jones",
        example: "lennard_jones = [1.0]",
        prefix: "lj",
        id_fields: "<theta>",
        id_meaning: "Lennard-Jones at theta = kT/eps",
        potential: |value| Ok(Potential::LennardJones(Self::new(parameters(value)?)?)),
    };

    /// The Lennard-Jones potential at `theta = kT/eps` within `THETA_RANGE`.
    pub fn new(theta: f64) -> Result<LennardJones, String> {
        let [low, high] = Self::THETA_RANGE;
        if (low..=high).contains(&theta) {
            Ok(LennardJones { theta })
        } else {
            Err(format!(
                "theta = kT/eps = {theta} is outside [{low}, {high}]"
            ))
        }
    }
}

impl Family for LennardJones {
    fn id(&self) -> String {
        format!("{}-{}", self.prefix(), self.theta)
    }
    fn prefix(&self) -> &'static str {
        Self::LISTED.prefix
    }
    fn label(&self) -> String {
        format!("LJ θ = {}", self.theta)
    }
    fn name(&self) -> &'static str {
        "Lennard-Jones"
    }
    fn length_unit(&self) -> &'static str {
        "l = l0 (eps/kT)^(1/6)"
    }
    /// The attractive `x^-6` tail sets the length unit.
    fn length_exponent(&self) -> Option<f64> {
        Some(6.0)
    }
    fn theta(&self) -> Option<f64> {
        Some(self.theta)
    }
    fn has_well(&self) -> bool {
        true
    }
    /// Length `K_b = int_(U<0) exp(-U(x)) erf(sqrt(-U(x))) dx`, in `l`: the
    /// phase-space weight of a bound pair. In a dilute thermal gas a neighbour
    /// gap lies at `x` with density `rho exp(-U(x))` and its relative velocity
    /// `w ~ N(0, 2)` binds it (`w^2/4 + U < 0`) with probability
    /// `erf(sqrt(-U))`, so a fraction `rho K_b (1 + O(rho l))` of the gaps is
    /// bound. Composite Simpson over `s` with `x = x0 / (1 - s^2)` (`U(x0) = 0`),
    /// which makes the integrand smooth at both ends.
    fn bound_pair_length(&self) -> f64 {
        let zero = libm::pow(self.theta, 1.0 / 6.0);
        simpson_on_unit_interval(|s: f64| {
            let y = (1.0 - s * s) / zero;
            if y <= 0.0 {
                return 0.0;
            }
            let binding = -self.energy(y.recip()).min(0.0);
            bound_weight(binding) * 2.0 * s / (zero * y * y)
        })
    }
    fn is_integrable(&self) -> bool {
        false
    }
    fn ring_obstacle(&self) -> Option<String> {
        None
    }
}
