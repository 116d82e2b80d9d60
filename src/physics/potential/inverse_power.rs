//! The inverse power laws `U = eps (l0/d)^n`, scaled `U/kT = x^-n` with
//! `l = l0 (eps/kT)^(1/n)` (physics.md §1): scale-free, no well, integrable
//! at `n = 2` (Calogero).

use serde::{Deserialize, Serialize};

use super::{Family, Listed, PairPotential, Potential, PotentialVisitor, parameters};

/// Inverse power law `U = x^-n` with any real exponent `n > 1`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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

impl Family for InversePower {
    fn id(&self) -> String {
        format!("{}-{}", self.prefix(), self.n)
    }
    fn prefix(&self) -> &'static str {
        Self::LISTED.prefix
    }
    fn label(&self) -> String {
        format!("n = {}", self.n)
    }
    fn name(&self) -> &'static str {
        "inverse power law"
    }
    fn length_unit(&self) -> &'static str {
        "l = l0 (eps/kT)^(1/n)"
    }
    fn length_exponent(&self) -> Option<f64> {
        Some(self.n)
    }
    fn theta(&self) -> Option<f64> {
        None
    }
    fn has_well(&self) -> bool {
        false
    }
    fn bound_pair_length(&self) -> f64 {
        0.0
    }
    fn is_integrable(&self) -> bool {
        self.n == 2.0
    }
    /// `n = 2` runs as a whole ring, larger `n` by cluster stepping; softer
    /// tails reach too far for either.
    fn ring_obstacle(&self) -> Option<String> {
        (self.n < 2.0).then(|| {
            "the md stage runs inverse power laws with n >= 2 (n = 2 as a whole ring, larger n by cluster stepping)".to_string()
        })
    }
}

impl InversePower {
    /// Largest exponent: steeper walls are hard spheres.
    pub const MAX_EXPONENT: f64 = 100.0;

    /// How `[potentials]` lists inverse power laws: by exponent.
    pub const LISTED: Listed = Listed {
        key: "inverse_power",
        example: "inverse_power = [6]",
        prefix: "ipp",
        id_fields: "<n>",
        id_meaning: "an inverse power law potential of exponent n",
        potential: |value| Ok(Potential::InversePower(Self::new(parameters(value)?)?)),
    };

    /// The inverse power law of exponent `n` in `(1, MAX_EXPONENT]`: the
    /// potential tail must be integrable.
    pub fn new(n: f64) -> Result<InversePower, String> {
        if n > 1.0 && n <= Self::MAX_EXPONENT {
            Ok(InversePower { n })
        } else {
            Err(format!(
                "n = {n} is outside (1, {}] (the potential tail must be integrable; steeper walls are hard spheres)",
                Self::MAX_EXPONENT
            ))
        }
    }

    /// Calls `visitor` with this potential; the study's even exponents
    /// 2..=12 get compile-time powers.
    pub fn visit<V: PotentialVisitor>(self, visitor: V) -> V::Output {
        match self.n {
            2.0 => visitor.visit(InverseIntegerPower::<2>),
            4.0 => visitor.visit(InverseIntegerPower::<4>),
            6.0 => visitor.visit(InverseIntegerPower::<6>),
            8.0 => visitor.visit(InverseIntegerPower::<8>),
            10.0 => visitor.visit(InverseIntegerPower::<10>),
            12.0 => visitor.visit(InverseIntegerPower::<12>),
            _ => visitor.visit(self),
        }
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
