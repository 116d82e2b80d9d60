//! `[[gas]]`: gases in physical units, their rates tabulated and their rings simulated.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, check_name, check_unique, positive, potential_named};
use crate::physics::potential::Potential;
use crate::physics::units::{Mass, PhysicalGas, ring_density_per_um};

/// `[[gas]]`: a gas in physical units.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GasConfig {
    /// Label used in tables.
    pub name: String,
    /// Id of a configured potential (`ipp-6`, `lj-1`).
    pub potential: String,
    /// Potential length `l0`, um.
    pub l0_um: f64,
    /// Potential energy `eps`, eV.
    pub eps_ev: f64,
    /// Temperature `kT`, eV.
    pub kt_ev: f64,
    /// Mass in electron masses (give this or `mass_amu`).
    pub mass_electron: Option<f64>,
    /// Mass in atomic mass units.
    pub mass_amu: Option<f64>,
    /// Linear density, 1/um (give this or the ring).
    pub density_per_um: Option<f64>,
    /// Particles on a ring (with `ring_radius_um`): density `(N - 1) / (2 pi R)`.
    pub ring_particles: Option<u32>,
    /// Ring radius, um.
    pub ring_radius_um: Option<f64>,
}

/// Resolved parameters of one gas.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GasParams {
    /// Label.
    pub name: String,
    /// The potential.
    pub potential: Potential,
    /// The gas.
    pub gas: PhysicalGas,
}

impl GasParams {
    /// The kernel parameters of this gas's density (`u' = 0`).
    pub fn scaled_density(&self) -> f64 {
        self.gas
            .scaled_density(self.potential.family().length_exponent())
    }
}

/// The range of a gas's physical values (`l0_um`, `eps_ev`, `kt_ev` and the
/// mass) in their own units: wide enough for any gas, narrow enough that
/// rates in 1/ns stay finite numbers.
const PHYSICAL_RANGE: std::ops::RangeInclusive<f64> = 1e-9..=1e9;

/// Largest particles of a ring.
pub const MAX_RING_PARTICLES: u32 = 100_000;

/// Largest `rho * l` of a gas, as for `kernel.density`.
pub const MAX_GAS_DENSITY: f64 = 0.1;

/// Checks every `[[gas]]` entry and resolves it with its potential and its
/// physical gas.
pub(super) fn resolve(
    configs: &[GasConfig],
    potentials: &[Potential],
) -> Result<Vec<GasParams>, Invalid> {
    let gases = configs
        .iter()
        .enumerate()
        .map(|(k, gas)| gas.resolve(k, potentials))
        .collect::<Result<Vec<_>, _>>()?;
    let names: Vec<&str> = configs.iter().map(|g| g.name.as_str()).collect();
    check_unique(&names, |k| format!("gas[{k}].name"))?;
    Ok(gases)
}

impl GasConfig {
    /// Checks entry `k` and resolves it.
    fn resolve(&self, k: usize, potentials: &[Potential]) -> Result<GasParams, Invalid> {
        let gas = self;
        let key = |name: &str| format!("gas[{k}].{name}");
        check_name(&gas.name, key("name"))?;
        let potential = potential_named(&gas.potential, potentials, key("potential"))?;
        for (name, value) in [
            ("l0_um", gas.l0_um),
            ("eps_ev", gas.eps_ev),
            ("kt_ev", gas.kt_ev),
        ] {
            check(
                PHYSICAL_RANGE.contains(&value),
                key(name),
                format!("{value} is outside [1e-9, 1e9] of its unit"),
            )?;
        }
        if let Some(theta) = potential.family().theta() {
            let ratio = gas.kt_ev / gas.eps_ev;
            check(
                (ratio / theta - 1.0).abs() <= 1e-9,
                key("kt_ev"),
                format!(
                    "kt_ev / eps_ev = {ratio} differs from theta = kT/eps = {theta} of `{}`",
                    gas.potential
                ),
            )?;
        }
        let mass = match (gas.mass_electron, gas.mass_amu) {
            (Some(m), None) => Mass::ElectronMasses(m),
            (None, Some(m)) => Mass::AtomicMassUnits(m),
            (Some(_), Some(_)) => {
                return Err((
                    key("mass_electron"),
                    "give exactly one mass: mass_electron or mass_amu, not both".into(),
                ));
            }
            (None, None) => {
                return Err((
                    format!("gas[{k}]"),
                    "gives no mass: give mass_electron or mass_amu".into(),
                ));
            }
        };
        let (mass_key, mass_value) = match mass {
            Mass::ElectronMasses(m) => ("mass_electron", m),
            Mass::AtomicMassUnits(m) => ("mass_amu", m),
        };
        check(
            PHYSICAL_RANGE.contains(&mass_value),
            key(mass_key),
            format!("{mass_value} is outside [1e-9, 1e9] of its unit"),
        )?;
        let (density_per_um, density_key) = gas.density(k)?;
        let physical = PhysicalGas {
            l0_um: gas.l0_um,
            eps_ev: gas.eps_ev,
            kt_ev: gas.kt_ev,
            mass,
            density_per_um,
        };
        let density = physical.scaled_density(potential.family().length_exponent());
        check(
            density <= MAX_GAS_DENSITY,
            key(density_key),
            format!(
                "gives rho*l = {density:.4e}, above {MAX_GAS_DENSITY}: the three-body kernel describes dilute gases (rho*l << 1)"
            ),
        )?;
        Ok(GasParams {
            name: gas.name.clone(),
            potential,
            gas: physical,
        })
    }

    /// The linear density (1/um), given or from the ring, and the key that sets it.
    fn density(&self, k: usize) -> Result<(f64, &'static str), Invalid> {
        let key = |name: &str| format!("gas[{k}].{name}");
        let ring = self.ring_particles.is_some() || self.ring_radius_um.is_some();
        check(
            self.density_per_um.is_some() != ring,
            key("density_per_um"),
            "give either density_per_um or ring_particles with ring_radius_um",
        )?;
        if let Some(density) = self.density_per_um {
            check(
                positive(density),
                key("density_per_um"),
                format!("{density} must be > 0"),
            )?;
            return Ok((density, "density_per_um"));
        }
        let particles = self
            .ring_particles
            .filter(|n| (3..=MAX_RING_PARTICLES).contains(n))
            .ok_or_else(|| {
                (
                    key("ring_particles"),
                    format!("needs 3 to {MAX_RING_PARTICLES} particles"),
                )
            })?;
        let radius = self
            .ring_radius_um
            .filter(|r| positive(*r))
            .ok_or_else(|| (key("ring_radius_um"), "needs a ring radius > 0".to_string()))?;
        Ok((ring_density_per_um(particles, radius), "ring_radius_um"))
    }
}
