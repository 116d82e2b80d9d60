//! The Morse potential `U = eps (1 - e^{-a (d - d0)})^2 - eps`, scaled
//! `U/kT = (e^{-2y} - 2 e^{-y}) / theta` with `y = x - x0`, `x = a d`,
//! `x0 = a d0` and `theta = kT/eps`: lengths in units of the range
//! `l = 1/a` (which does not scale with temperature), a well of depth
//! `1/theta` at `x0`. Its core is soft: `U(0)` is finite, so the family
//! admits only walls high enough that no thermal scene crosses them.

use serde::{Deserialize, Serialize};

use super::{
    Family, Listed, PairPotential, Potential, bound_weight, parameters, simpson_on_unit_interval,
};

/// Morse potential in scaled units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Morse {
    /// `theta = kT / eps`.
    pub theta: f64,
    /// Well position `x0 = a d0`, in `l = 1/a`.
    pub x0: f64,
}

impl Morse {
    /// Range of `theta = kT/eps` (as for Lennard-Jones).
    pub const THETA_RANGE: [f64; 2] = [1e-3, 1e3];

    /// Lowest admitted wall `U(0)/kT`: a pair crosses it with probability
    /// of order `e^-50 ~ 2e-22` per thermal encounter, never in practice.
    pub const MIN_WALL: f64 = 50.0;

    /// Largest well position `x0`: beyond it the wall `e^{2 x0}` overflows
    /// nothing but the id's length.
    pub const MAX_X0: f64 = 100.0;

    /// How `[potentials]` lists Morse potentials: a table per potential,
    /// `morse = [{ theta = 1.0, x0 = 4.0 }]`.
    pub const LISTED: Listed = Listed {
        key: "morse",
        example: "morse = [{ theta = 1.0, x0 = 4.0 }]",
        prefix: "morse",
        id_fields: "<theta>-<x0>",
        id_meaning: "Morse at theta = kT/eps with its well at x0 = a d0",
        potential: |value| {
            let Morse { theta, x0 } = parameters(value)?;
            Ok(Potential::Morse(Self::new(theta, x0)?))
        },
    };

    /// The Morse potential at `theta = kT/eps` with its well at `x0`, when
    /// `theta` lies in `THETA_RANGE` and the wall `U(0)` reaches `MIN_WALL`.
    pub fn new(theta: f64, x0: f64) -> Result<Morse, String> {
        let [low, high] = Self::THETA_RANGE;
        if !(low..=high).contains(&theta) {
            return Err(format!(
                "theta = kT/eps = {theta} is outside [{low}, {high}]"
            ));
        }
        if !(x0 > 0.0 && x0 <= Self::MAX_X0) {
            return Err(format!("x0 = a d0 = {x0} is outside (0, {}]", Self::MAX_X0));
        }
        let morse = Morse { theta, x0 };
        let wall = morse.energy(0.0);
        if wall < Self::MIN_WALL {
            return Err(format!(
                "the wall U(0) = {wall} kT is below {} kT: thermal pairs would pass through each other (raise x0 or lower theta)",
                Self::MIN_WALL
            ));
        }
        Ok(morse)
    }

    /// `e^{-y}` with `y = x - x0`.
    fn decay(&self, x: f64) -> f64 {
        libm::exp(self.x0 - x)
    }
}

impl PairPotential for Morse {
    fn energy(&self, x: f64) -> f64 {
        let e = self.decay(x);
        (e * e - 2.0 * e) / self.theta
    }
    fn force(&self, x: f64) -> f64 {
        let e = self.decay(x);
        2.0 * (e * e - e) / self.theta
    }
    fn tail_integral(&self, x: f64) -> f64 {
        let e = self.decay(x);
        (0.5 * e * e - 2.0 * e) / self.theta
    }
    /// The minimum sits at `x0` with `U = -1/theta`.
    fn well_depth(&self) -> f64 {
        self.theta.recip()
    }
    /// Beyond `x0`, `|U| <= 2 e^{-y} / theta`.
    fn range(&self, level: f64) -> f64 {
        self.x0 + libm::log(2.0 / (self.theta * level)).max(0.0)
    }
}

impl Family for Morse {
    fn id(&self) -> String {
        format!("{}-{}-{}", self.prefix(), self.theta, self.x0)
    }
    fn prefix(&self) -> &'static str {
        Self::LISTED.prefix
    }
    fn label(&self) -> String {
        format!("Morse θ = {}, x0 = {}", self.theta, self.x0)
    }
    fn name(&self) -> &'static str {
        "Morse"
    }
    fn length_unit(&self) -> &'static str {
        "l = 1/a"
    }
    /// The range `1/a` is the length unit: it does not scale with `kT`.
    fn length_exponent(&self) -> Option<f64> {
        None
    }
    fn theta(&self) -> Option<f64> {
        Some(self.theta)
    }
    fn has_well(&self) -> bool {
        true
    }
    /// `K_b = int_(U<0) exp(-U) erf(sqrt(-U)) dx` (as for Lennard-Jones), by
    /// composite Simpson over `s` with `e^{-y} = 2 s^2`: `U = -4 s^2 (1 - s^2)
    /// / theta`, `dx = -2 ds / s`, and the integrand is smooth on `[0, 1]`
    /// (it tends to `8 / sqrt(pi theta)` at `s = 0`, the far tail).
    fn bound_pair_length(&self) -> f64 {
        simpson_on_unit_interval(|s: f64| {
            if s == 0.0 {
                return 8.0 / (std::f64::consts::PI * self.theta).sqrt();
            }
            bound_weight(4.0 * s * s * (1.0 - s * s) / self.theta) * 2.0 / s
        })
    }
    fn is_integrable(&self) -> bool {
        false
    }
    fn ring_obstacle(&self) -> Option<String> {
        None
    }
}
