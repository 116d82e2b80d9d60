//! Pair potentials in scaled units (physics.md §1).
//!
//! Energies are in units of `kT`, separations in units of `l = l0 (eps/kT)^(1/n)`
//! (`n = 6` for Lennard-Jones), forces in `kT / l`. A [`Potential`] is the
//! configuration-facing description; the scene engine dispatches it once to a
//! concrete [`PairPotential`] so that hot loops are monomorphic.

use serde::{Deserialize, Serialize};

use super::quasi_random::standard_normal_cdf;
use crate::linalg::simpson_weight;

mod inverse_power;
mod lennard_jones;
mod morse;

pub use inverse_power::{InverseIntegerPower, InversePower};
pub use lennard_jones::LennardJones;
pub use morse::Morse;

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

/// What the pipeline asks of a potential family besides its forces: one
/// implementation per family, one file each, so that configuration, tables,
/// figures and the command line ask the family instead of matching on it.
pub trait Family {
    /// Short stable identifier naming instances and files, e.g. `ipp-6`:
    /// [`Family::prefix`], then the parameters (its [`Listed::id_fields`]).
    fn id(&self) -> String;
    /// The family's part of every [`Family::id`], e.g. `ipp`: its
    /// [`Listed::prefix`].
    fn prefix(&self) -> &'static str;
    /// Legend label of figures, e.g. `n = 6`.
    fn label(&self) -> String;
    /// The family's name in prose, e.g. `Lennard-Jones`.
    fn name(&self) -> &'static str;
    /// The scaled length unit, e.g. `l = l0 (eps/kT)^(1/6)`.
    fn length_unit(&self) -> &'static str;
    /// The exponent `n` of the length unit `l = l0 (eps/kT)^(1/n)`
    /// (physics.md §1), and of the rate's scaling with temperature; `None`
    /// when the length unit is the family's own `l0` (no scaling with `kT`).
    fn length_exponent(&self) -> Option<f64>;
    /// `theta = kT / eps` when the potential's shape depends on temperature
    /// (a well's depth in `kT`); `None` for a scale-free family.
    fn theta(&self) -> Option<f64>;
    /// Whether pairs can bind: bound and orbiting pairs make the kick a
    /// non-smooth function of the arrival offset, and a ring holds dimers.
    fn has_well(&self) -> bool;
    /// Phase-space length `K_b` of a bound pair, `l` (0 without a well): a
    /// fraction `rho K_b` of a dilute gas's neighbour gaps is bound.
    fn bound_pair_length(&self) -> f64;
    /// `true` for an integrable potential (the Calogero `U = x^-2`), whose
    /// outgoing velocities are an exact permutation of the incoming ones.
    fn is_integrable(&self) -> bool;
    /// Why the ring MD cannot run this potential (`None`: it can).
    fn ring_obstacle(&self) -> Option<String>;
}

/// A family as a study's `[potentials]` section lists it: the key, and how
/// one listed value (a number or a table of the family's parameters) becomes
/// a potential.
pub struct Listed {
    /// Key under `[potentials]`, e.g. `inverse_power`.
    pub key: &'static str,
    /// An entry that lists one potential, for messages: `inverse_power = [6]`.
    pub example: &'static str,
    /// What every id of the family begins with (before a `-`), e.g. `ipp`.
    pub prefix: &'static str,
    /// The parameters an id spells after the prefix, e.g. `<theta>-<x0>`.
    pub id_fields: &'static str,
    /// What an id names, for the bundle's naming guide: `an inverse power
    /// law potential of exponent n`.
    pub id_meaning: &'static str,
    /// The potential one listed value describes, or why the value is refused.
    pub potential: fn(serde_json::Value) -> Result<Potential, String>,
}

/// Every family, in the order a study lists its potentials.
pub const FAMILIES: [Listed; 3] = [InversePower::LISTED, LennardJones::LISTED, Morse::LISTED];

impl Listed {
    /// The family's ids as a pattern, e.g. `morse-<theta>-<x0>`.
    pub fn id_pattern(&self) -> String {
        format!("{}-{}", self.prefix, self.id_fields)
    }
}

/// `exp(B) erf(sqrt(B))` for a pair at binding energy `B = -U >= 0` (in
/// `kT`): the integrand of the bound-pair length `K_b` (the Boltzmann weight
/// of the gap times the probability that a relative velocity `w ~ N(0, 2)`
/// binds it, `w^2/4 < B`).
pub fn bound_weight(binding: f64) -> f64 {
    let erf = 1.0 - 2.0 * standard_normal_cdf(-(2.0 * binding).sqrt());
    libm::exp(binding) * erf
}

/// Composite Simpson rule of `f` over `[0, 1]` with 4000 intervals: the
/// bound-pair lengths' quadrature after a substitution that makes their
/// integrands smooth.
fn simpson_on_unit_interval(f: impl Fn(f64) -> f64) -> f64 {
    const INTERVALS: usize = 4000;
    let h = 1.0 / INTERVALS as f64;
    let sum: f64 = (0..=INTERVALS)
        .map(|k| simpson_weight(k, INTERVALS) * f(k as f64 * h))
        .sum();
    sum * h / 3.0
}

/// The listed parameters of a family, or the deserializer's complaint.
fn parameters<T: serde::de::DeserializeOwned>(value: serde_json::Value) -> Result<T, String> {
    serde_json::from_value(value).map_err(|e| e.to_string())
}

/// A pair potential as configured by a study; its serialized form (`kind`
/// and the family's parameters) enters the keys of every stage it reaches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Potential {
    /// `U = eps (l0/d)^n`; scaled `U/kT = x^-n`.
    InversePower(InversePower),
    /// `U = eps ((l0/d)^12 - (l0/d)^6)`; scaled `U/kT = theta x^-12 - x^-6`.
    LennardJones(LennardJones),
    /// `U = eps (1 - e^{-a (d - d0)})^2 - eps`; scaled with `l = 1/a`.
    Morse(Morse),
}

impl Potential {
    /// The inverse power law `U/kT = x^-n`.
    pub const fn inverse_power(n: f64) -> Potential {
        Potential::InversePower(InversePower { n })
    }

    /// The Lennard-Jones potential at `theta = kT / eps`.
    pub const fn lennard_jones(theta: f64) -> Potential {
        Potential::LennardJones(LennardJones { theta })
    }

    /// The potential's family: what it can do and how it is named.
    pub fn family(&self) -> &dyn Family {
        match self {
            Potential::InversePower(family) => family,
            Potential::LennardJones(family) => family,
            Potential::Morse(family) => family,
        }
    }

    /// Short stable identifier, e.g. `ipp-6` or `lj-0.05` ([`Family::id`]).
    pub fn id(&self) -> String {
        self.family().id()
    }

    /// Depth `D` of the well, `kT` (0 without one).
    pub fn well_depth(&self) -> f64 {
        struct WellDepth;
        impl PotentialVisitor for WellDepth {
            type Output = f64;
            fn visit<P: PairPotential>(self, potential: P) -> f64 {
                potential.well_depth()
            }
        }
        self.visit(WellDepth)
    }

    /// Calls `visitor` with the concrete potential: the one dispatch point.
    pub fn visit<V: PotentialVisitor>(&self, visitor: V) -> V::Output {
        match *self {
            Potential::InversePower(family) => family.visit(visitor),
            Potential::LennardJones(family) => visitor.visit(family),
            Potential::Morse(family) => visitor.visit(family),
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

    /// The potential each family's `example` lists has an id of the family's
    /// pattern: its prefix, then one value per field.
    #[test]
    fn listed_examples_have_ids_of_their_family_pattern() {
        for family in FAMILIES {
            let entry: toml::Table = toml::from_str(family.example).unwrap();
            let value = serde_json::to_value(&entry[family.key][0]).unwrap();
            let id = (family.potential)(value).unwrap().id();
            let (prefix, values) = id.split_once('-').unwrap();
            assert_eq!(prefix, family.prefix, "{id}");
            assert_eq!(
                values.split('-').count(),
                family.id_fields.split('-').count(),
                "{id} against {}",
                family.id_pattern()
            );
        }
    }

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
        check_consistency(Morse {
            theta: 0.5,
            x0: 4.0,
        });
        check_consistency(Morse {
            theta: 20.0,
            x0: 6.0,
        });
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
        fn bounded<P: PairPotential>(potential: P) {
            for &level in &[1e-3, 1e-8, 1e-14] {
                let x = potential.range(level);
                for k in 0..100 {
                    let beyond = x * (1.0 + 0.1 * f64::from(k));
                    assert!(potential.energy(beyond).abs() <= level);
                }
            }
        }
        bounded(LennardJones { theta: 0.05 });
        bounded(LennardJones { theta: 10.0 });
        bounded(Morse {
            theta: 0.05,
            x0: 4.0,
        });
        bounded(Morse {
            theta: 500.0,
            x0: 8.0,
        });
        assert!((InverseIntegerPower::<6>.range(1e-12) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn morse_well_depth_is_minus_minimum_at_x0_and_low_walls_are_refused() {
        let potential = Morse::new(0.5, 4.0).expect("a high wall");
        assert!((potential.energy(potential.x0) + potential.well_depth()).abs() < 1e-15);
        assert!(potential.force(potential.x0).abs() < 1e-15);
        // U(0)/kT = (e^8 - 2 e^4) / 0.5 ~ 5852: the wall holds.
        assert!(potential.energy(0.0) > 5000.0);
        // x0 = 2 at kT = eps: U(0) = e^4 - 2 e^2 ~ 39.8 kT, below the 50 kT floor.
        assert!(Morse::new(1.0, 2.0).unwrap_err().contains("wall"));
        assert!(Morse::new(1.0, 3.0).is_ok());
        assert!(Morse::new(1e4, 4.0).unwrap_err().contains("theta"));
    }

    #[test]
    fn lennard_jones_well_depth_is_minus_minimum() {
        let potential = LennardJones { theta: 0.05 };
        let x_min = libm::pow(2.0 * potential.theta, 1.0 / 6.0);
        assert!((potential.energy(x_min) + potential.well_depth()).abs() < 1e-12);
        assert!(potential.force(x_min).abs() < 1e-10);
    }

    /// The serialized form enters every key: a family's parameters appear
    /// under `kind` as they always have, so a refactor keeps the keys' params.
    #[test]
    fn serialized_potentials_keep_their_form() {
        let json = |p: Potential| serde_json::to_string(&p).expect("serializes");
        assert_eq!(
            json(Potential::inverse_power(6.0)),
            r#"{"kind":"inverse_power","n":6.0}"#
        );
        assert_eq!(
            json(Potential::lennard_jones(0.1)),
            r#"{"kind":"lennard_jones","theta":0.1}"#
        );
        let back: Potential =
            serde_json::from_str(r#"{"kind":"lennard_jones","theta":0.1}"#).expect("deserializes");
        assert_eq!(back, Potential::lennard_jones(0.1));
        assert!(
            serde_json::from_str::<Potential>(r#"{"kind":"inverse_power","n":6.0,"m":1}"#).is_err()
        );
    }
}
