//! Physical units and the scaled units of the engine (physics.md §1).
//!
//! Inputs: `l0` in um, `eps` and `kT` in eV, the mass in electron masses or
//! atomic mass units, the linear density in 1/um. Scaled units: length
//! `l = l0 (eps/kT)^(1/n)` (`n = 6` for Lennard-Jones), speed
//! `v_th = sqrt(kT/m)`, time `l / v_th`. The thermalization rate of
//! physics.md §2 is `Gamma = a_n rho^2 l v_th`.

use serde::{Deserialize, Serialize};

/// Electron mass, kg (CODATA 2018).
pub const ELECTRON_MASS_KG: f64 = 9.109_383_701_5e-31;
/// Atomic mass unit, kg (CODATA 2018).
pub const ATOMIC_MASS_UNIT_KG: f64 = 1.660_539_066_60e-27;
/// Electron volt, J (exact).
pub const ELECTRON_VOLT_J: f64 = 1.602_176_634e-19;
/// Boltzmann constant, J/K (exact).
pub const BOLTZMANN_J_PER_K: f64 = 1.380_649e-23;
/// Angstrom, um.
pub const ANGSTROM_UM: f64 = 1e-4;

/// Particle mass.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mass {
    /// In electron masses.
    ElectronMasses(f64),
    /// In atomic mass units.
    AtomicMassUnits(f64),
}

impl Mass {
    /// In kg.
    pub fn kilograms(self) -> f64 {
        match self {
            Mass::ElectronMasses(m) => m * ELECTRON_MASS_KG,
            Mass::AtomicMassUnits(m) => m * ATOMIC_MASS_UNIT_KG,
        }
    }
}

/// A gas in physical units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhysicalGas {
    /// Potential length `l0`, um.
    pub l0_um: f64,
    /// Potential energy scale `eps`, eV.
    pub eps_ev: f64,
    /// Temperature `kT`, eV.
    pub kt_ev: f64,
    /// Particle mass.
    pub mass: Mass,
    /// Linear number density `rho`, 1/um.
    pub density_per_um: f64,
}

impl PhysicalGas {
    /// A gas whose energies are given as temperatures (K) and its length in
    /// Angstrom: `eps = k_B eps_over_k`, `kT = k_B temperature_k`,
    /// `l0 = sigma` (a Lennard-Jones species, `physics::species`).
    pub fn from_kelvin(
        eps_over_k: f64,
        sigma_angstrom: f64,
        temperature_k: f64,
        mass: Mass,
        density_per_um: f64,
    ) -> PhysicalGas {
        let electron_volts = |kelvin: f64| kelvin * BOLTZMANN_J_PER_K / ELECTRON_VOLT_J;
        PhysicalGas {
            l0_um: sigma_angstrom * ANGSTROM_UM,
            eps_ev: electron_volts(eps_over_k),
            kt_ev: electron_volts(temperature_k),
            mass,
            density_per_um,
        }
    }

    /// Length unit `l = l0 (eps/kT)^(1/n)`, um (`n` the length exponent;
    /// `l = l0` without one).
    pub fn length_unit_um(&self, length_exponent: Option<f64>) -> f64 {
        length_exponent.map_or(self.l0_um, |n| {
            self.l0_um * libm::pow(self.eps_ev / self.kt_ev, 1.0 / n)
        })
    }

    /// Thermal speed `v_th = sqrt(kT/m)`, um/ns (1 m/s = 1e-3 um/ns).
    pub fn thermal_speed_um_per_ns(&self) -> f64 {
        (self.kt_ev * ELECTRON_VOLT_J / self.mass.kilograms()).sqrt() * 1e-3
    }

    /// Scaled density `rho l`.
    pub fn scaled_density(&self, length_exponent: Option<f64>) -> f64 {
        self.density_per_um * self.length_unit_um(length_exponent)
    }

    /// Time unit `l / v_th`, ns.
    pub fn time_unit_ns(&self, length_exponent: Option<f64>) -> f64 {
        self.length_unit_um(length_exponent) / self.thermal_speed_um_per_ns()
    }

    /// `Gamma = a rho^2 l v_th` in 1/ns for a rate `a` in units of `rho^2 l v_th`.
    pub fn rate_per_ns(&self, scaled_rate: f64, length_exponent: Option<f64>) -> f64 {
        scaled_rate
            * self.density_per_um.powi(2)
            * self.length_unit_um(length_exponent)
            * self.thermal_speed_um_per_ns()
    }
}

/// Linear density `(N - 1) / (2 pi R)` of `N` particles on a ring of radius `R` um
/// (physics.md §7: the special particle is not counted).
pub fn ring_density_per_um(particles: u32, radius_um: f64) -> f64 {
    f64::from(particles - 1) / (2.0 * std::f64::consts::PI * radius_um)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn published() -> PhysicalGas {
        PhysicalGas {
            l0_um: 1.0,
            eps_ev: 1.0,
            kt_ev: 0.1,
            mass: Mass::ElectronMasses(1.0),
            density_per_um: ring_density_per_um(161, 51200.0),
        }
    }

    /// `v_th = sqrt(0.1 eV / m_e) = 1.3262e5 m/s` (worked by hand from CODATA
    /// 2018: 1.602176634e-20 J / 9.1093837015e-31 kg), and the length unit is
    /// where the pair energy `eps (l0 / r)^6` equals `kT`: a property of `l`,
    /// not its formula again. At `r = l` the scaled potential `x^-n` is 1.
    #[test]
    fn published_gas_in_scaled_units() {
        let gas = published();
        assert!((gas.thermal_speed_um_per_ns() / 132.620_5 - 1.0).abs() < 1e-5);
        let l = gas.length_unit_um(Some(6.0));
        let pair_energy_ev = gas.eps_ev * (gas.l0_um / l).powi(6);
        assert!((pair_energy_ev / gas.kt_ev - 1.0).abs() < 1e-14);
        // The time unit is l / v_th, and rho l v_th is a rate per ns.
        assert!(
            (gas.time_unit_ns(Some(6.0)) * gas.thermal_speed_um_per_ns() / l - 1.0).abs() < 1e-14
        );
    }

    /// N2's well depth 95.05 K and sigma 3.698 A give the study's `N2_10K`
    /// gas (pipeline.toml: eps_ev = 8.19077526e-3, to its 9 digits).
    #[test]
    fn kelvin_and_angstrom_convert_to_electron_volts_and_micrometres() {
        let mass = Mass::AtomicMassUnits(28.0134);
        let gas = PhysicalGas::from_kelvin(95.05, 3.698, 0.1052 * 95.05, mass, 0.1);
        assert!((gas.eps_ev / 8.190_775_26e-3 - 1.0).abs() < 1e-9);
        assert!((gas.kt_ev / 8.616_695_573_52e-4 - 1.0).abs() < 1e-9);
        assert_eq!(gas.l0_um, 3.698e-4);
    }

    /// The published collapse (physics.md §7): `(rho, T, t_f)`,
    /// `(2 rho, T, t_f/4)` and `(2 rho, 8 T, t_f/8)` share `Gamma t_f` for n = 6
    /// (`Gamma ~ rho^2 T^(1/2 - 1/n)`); `rho -> a rho, T -> a^n T` even keeps `rho l`.
    #[test]
    fn rate_scales_as_rho_squared_t_to_one_half_minus_one_over_n() {
        let base = published();
        let denser = PhysicalGas {
            density_per_um: 2.0 * base.density_per_um,
            ..base
        };
        let hotter = PhysicalGas {
            kt_ev: 8.0 * base.kt_ev,
            ..denser
        };
        let exposure = |gas: &PhysicalGas, time_ns: f64| gas.rate_per_ns(1.0, Some(6.0)) * time_ns;
        assert!((exposure(&denser, 3200.0) / exposure(&base, 12800.0) - 1.0).abs() < 1e-12);
        assert!((exposure(&hotter, 1600.0) / exposure(&base, 12800.0) - 1.0).abs() < 1e-12);
        let scaled = PhysicalGas {
            kt_ev: 64.0 * base.kt_ev,
            ..denser
        };
        assert!(
            (scaled.scaled_density(Some(6.0)) / base.scaled_density(Some(6.0)) - 1.0).abs() < 1e-12
        );
    }
}
