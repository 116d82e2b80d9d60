//! Pair potentials in scaled units (physics.md §1).
//!
//! Energies are in units of `kT`, separations in units of `l = l0 (eps/kT)^(1/n)`
//! (`n = 6` for Lennard-Jones), forces in `kT / l`. A [`Potential`] is the
//! configuration-facing description; the scene engine dispatches it once to a
//! concrete [`PairPotential`] so that hot loops are monomorphic.

use serde::{Deserialize, Serialize};

use super::quasi_random::standard_normal_cdf;
use crate::linalg::simpson_weight;

/// A repulsive-core pair interaction `U(x)` between two particles at scaled
/// separation `x > 0`.
pub trait PairPotential: Copy + Send + Sync {
    /// `U(x) / kT`.
    fn energy(&self, x: f64) -> f64;
    /// `-dU/dx` in `kT / l`; positive pushes the pair apart.
    fn force(&self, x: f64) -> f64;
    /// `Phi(x) = integral_x^inf U(s) ds` in `kT l`: the first-order position
    /// shift of a pair in its free-flight tail is `Phi / w^2` (numerics.md).
    fn tail_integral(&self, x: f64) -> f64;
    /// Depth `-min U` of the attractive well in `kT` (0 when purely repulsive).
    fn well_depth(&self) -> f64;
    /// A separation beyond which `|U(x)| <= level` for every larger `x`.
    fn range(&self, level: f64) -> f64;
}

/// Inverse power law `U = x^-n` with any real exponent `n > 1`.
#[derive(Clone, Copy, Debug)]
pub struct InversePower {
    /// Exponent `n`.
    pub n: f64,
}

impl PairPotential for InversePower {
    fn energy(&self, x: f64) -> f64 {
        libm::pow(x, -self.n)
    }
    fn force(&self, x: f64) -> f64 {
        self.n * libm::pow(x, -self.n - 1.0)
    }
    fn tail_integral(&self, x: f64) -> f64 {
        libm::pow(x, 1.0 - self.n) / (self.n - 1.0)
    }
    fn well_depth(&self) -> f64 {
        0.0
    }
    fn range(&self, level: f64) -> f64 {
        libm::pow(level, -1.0 / self.n)
    }
}

/// Inverse power law `U = x^-N` with an integer exponent known at compile
/// time: the same physics as [`InversePower`], evaluated by an unrolled chain
/// of multiplications (the force is the hot spot of every scene).
#[derive(Clone, Copy, Debug)]
pub struct InverseIntegerPower<const N: i32>;

impl<const N: i32> PairPotential for InverseIntegerPower<N> {
    fn energy(&self, x: f64) -> f64 {
        x.recip().powi(N)
    }
    fn force(&self, x: f64) -> f64 {
        let inverse = x.recip();
        f64::from(N) * inverse.powi(N + 1)
    }
    fn tail_integral(&self, x: f64) -> f64 {
        x.recip().powi(N - 1) / f64::from(N - 1)
    }
    fn well_depth(&self) -> f64 {
        0.0
    }
    fn range(&self, level: f64) -> f64 {
        libm::pow(level, -1.0 / f64::from(N))
    }
}

/// Lennard-Jones `U = theta x^-12 - x^-6` with `theta = kT / eps`
/// (physics.md §1: length unit `l = l0 (eps/kT)^(1/6)`).
#[derive(Clone, Copy, Debug)]
pub struct LennardJones {
    /// `theta = kT / eps`.
    pub theta: f64,
}

impl PairPotential for LennardJones {
    fn energy(&self, x: f64) -> f64 {
        let inverse6 = x.recip().powi(6);
        (self.theta * inverse6 - 1.0) * inverse6
    }
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
    /// Length `K_b = int_(U<0) exp(-U(x)) erf(sqrt(-U(x))) dx`, in `l`: the
    /// phase-space weight of a bound pair. In a dilute thermal gas a neighbour
    /// gap lies at `x` with density `rho exp(-U(x))` and its relative velocity
    /// `w ~ N(0, 2)` binds it (`w^2/4 + U < 0`) with probability
    /// `erf(sqrt(-U))`, so a fraction `rho K_b (1 + O(rho l))` of the gaps is
    /// bound. Composite Simpson over `s` with `x = x0 / (1 - s^2)` (`U(x0) = 0`),
    /// which makes the integrand smooth at both ends.
    pub fn bound_pair_length(&self) -> f64 {
        const INTERVALS: usize = 4000;
        let zero = libm::pow(self.theta, 1.0 / 6.0);
        let integrand = |s: f64| {
            let y = (1.0 - s * s) / zero;
            if y <= 0.0 {
                return 0.0;
            }
            let binding = -self.energy(y.recip()).min(0.0);
            let erf = 1.0 - 2.0 * standard_normal_cdf(-(2.0 * binding).sqrt());
            libm::exp(binding) * erf * 2.0 * s / (zero * y * y)
        };
        let h = 1.0 / INTERVALS as f64;
        let sum: f64 = (0..=INTERVALS)
            .map(|k| simpson_weight(k, INTERVALS) * integrand(k as f64 * h))
            .sum();
        sum * h / 3.0
    }
}

/// A pair potential as configured by a study.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Potential {
    /// `U = eps (l0/d)^n`; scaled `U/kT = x^-n`.
    InversePower {
        /// Exponent `n > 1` (any real value).
        n: f64,
    },
    /// `U = eps ((l0/d)^12 - (l0/d)^6)`; scaled `U/kT = theta x^-12 - x^-6`.
    LennardJones {
        /// `theta = kT / eps > 0`.
        theta: f64,
    },
}

impl Potential {
    /// Short stable identifier, e.g. `ipp-6` or `lj-0.05`.
    pub fn id(&self) -> String {
        match self {
            Potential::InversePower { n } => format!("ipp-{n}"),
            Potential::LennardJones { theta } => format!("lj-{theta}"),
        }
    }

    /// The exponent `n` that defines the length unit `l` (6 for Lennard-Jones).
    pub fn length_exponent(&self) -> f64 {
        match self {
            Potential::InversePower { n } => *n,
            Potential::LennardJones { .. } => 6.0,
        }
    }

    /// Phase-space length `K_b` of a bound pair, `l` (0 without a well):
    /// a fraction `rho K_b` of a dilute gas's neighbour gaps is bound
    /// ([`LennardJones::bound_pair_length`]).
    pub fn bound_pair_length(&self) -> f64 {
        match *self {
            Potential::InversePower { .. } => 0.0,
            Potential::LennardJones { theta } => LennardJones { theta }.bound_pair_length(),
        }
    }

    /// `true` for the integrable Calogero case `U = x^-2`, whose outgoing
    /// velocities are an exact permutation of the incoming ones.
    pub fn is_integrable(&self) -> bool {
        matches!(self, Potential::InversePower { n } if *n == 2.0)
    }

    /// Calls `visitor` with the concrete potential: the one dispatch point.
    /// The study's even exponents 2..=12 get compile-time powers.
    pub fn visit<V: PotentialVisitor>(&self, visitor: V) -> V::Output {
        match *self {
            Potential::InversePower { n: 2.0 } => visitor.visit(InverseIntegerPower::<2>),
            Potential::InversePower { n: 4.0 } => visitor.visit(InverseIntegerPower::<4>),
            Potential::InversePower { n: 6.0 } => visitor.visit(InverseIntegerPower::<6>),
            Potential::InversePower { n: 8.0 } => visitor.visit(InverseIntegerPower::<8>),
            Potential::InversePower { n: 10.0 } => visitor.visit(InverseIntegerPower::<10>),
            Potential::InversePower { n: 12.0 } => visitor.visit(InverseIntegerPower::<12>),
            Potential::InversePower { n } => visitor.visit(InversePower { n }),
            Potential::LennardJones { theta } => visitor.visit(LennardJones { theta }),
        }
    }
}

/// Generic code to run with a concrete [`PairPotential`] (see [`Potential::visit`]).
pub trait PotentialVisitor {
    /// What the visit returns.
    type Output;
    /// Runs with the concrete potential.
    fn visit<P: PairPotential>(self, potential: P) -> Self::Output;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central difference of the energy, for checking forces.
    fn numerical_force<P: PairPotential>(potential: P, x: f64) -> f64 {
        let h = 1e-6 * x;
        -(potential.energy(x + h) - potential.energy(x - h)) / (2.0 * h)
    }

    /// Trapezoid-free check of `Phi`: `-dPhi/dx = U`.
    fn numerical_tail_derivative<P: PairPotential>(potential: P, x: f64) -> f64 {
        let h = 1e-6 * x;
        -(potential.tail_integral(x + h) - potential.tail_integral(x - h)) / (2.0 * h)
    }

    fn check_consistency<P: PairPotential>(potential: P) {
        for &x in &[0.7, 1.0, 1.3, 2.0, 5.0] {
            let force = potential.force(x);
            // Central differences are exact to O(h^2) ~ 1e-12 relative; 1e-7 leaves room for cancellation.
            assert!((force - numerical_force(potential, x)).abs() <= 1e-7 * force.abs().max(1e-3));
            let energy = potential.energy(x);
            let tail = numerical_tail_derivative(potential, x);
            assert!((energy - tail).abs() <= 1e-7 * energy.abs().max(1e-3));
        }
    }

    #[test]
    fn force_is_minus_energy_gradient_and_tail_integrates_energy() {
        check_consistency(InversePower { n: 6.5 });
        check_consistency(InverseIntegerPower::<2>);
        check_consistency(InverseIntegerPower::<12>);
        check_consistency(LennardJones { theta: 0.05 });
        check_consistency(LennardJones { theta: 10.0 });
    }

    #[test]
    fn integer_and_real_exponents_agree() {
        let real = InversePower { n: 6.0 };
        let integer = InverseIntegerPower::<6>;
        for &x in &[0.5, 1.0, 3.0] {
            assert!((real.energy(x) / integer.energy(x) - 1.0).abs() < 1e-14);
            assert!((real.force(x) / integer.force(x) - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn range_bounds_the_energy() {
        let potentials = [LennardJones { theta: 0.05 }, LennardJones { theta: 10.0 }];
        for potential in potentials {
            for &level in &[1e-3, 1e-8, 1e-14] {
                let x = potential.range(level);
                for k in 0..100 {
                    let beyond = x * (1.0 + 0.1 * f64::from(k));
                    assert!(potential.energy(beyond).abs() <= level);
                }
            }
        }
        assert!((InverseIntegerPower::<6>.range(1e-12) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn lennard_jones_well_depth_is_minus_minimum() {
        let potential = LennardJones { theta: 0.05 };
        let x_min = libm::pow(2.0 * potential.theta, 1.0 / 6.0);
        assert!((potential.energy(x_min) + potential.well_depth()).abs() < 1e-12);
        assert!(potential.force(x_min).abs() < 1e-10);
    }
}
