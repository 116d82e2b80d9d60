//! Lennard-Jones parameters of real gases, and how a species maps onto the
//! engine's Lennard-Jones `U = eps ((l0/d)^12 - (l0/d)^6)` (physics.md §1).
//!
//! Pure data: the table [`SPECIES`] and the two readings of its `eps`.
//! The compilation's potential is `U = 4 eps_t ((sigma/d)^12 - (sigma/d)^6)`,
//! well depth `eps_t` at `d = 2^(1/6) sigma`. The paper's N2 example takes the
//! table's `eps_t` as the `eps` of its own form (`theta = kT / eps_t`, about
//! 0.105 at 10 K), whose well is `eps_t / 4` deep ([`Reading::Paper`]);
//! the compilation's own potential is `eps = 4 eps_t`, `l0 = sigma`
//! ([`Reading::FourEps`], `theta = kT / (4 eps_t)`). Both keep `l0 = sigma`.

/// Where the parameters of [`SPECIES`] come from.
pub const SOURCE: &str = "J. O. Hirschfelder, C. F. Curtiss and R. B. Bird, Molecular Theory of Gases and Liquids (Wiley, 1954), Table I-A: Lennard-Jones (12-6) parameters from second virial coefficients";

/// Whether the table's particle is one atom or a molecule (a molecule
/// enters the 1D gas as one point particle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Particle {
    /// A noble-gas atom.
    Atom,
    /// A molecule, its parameters the molecule-molecule potential's.
    Molecule,
}

/// One species of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Species {
    /// Formula (`N2`).
    pub name: &'static str,
    /// Atom or molecule.
    pub particle: Particle,
    /// Well depth `eps_t / k_B` of `4 eps_t ((sigma/d)^12 - (sigma/d)^6)`, K.
    pub eps_over_k: f64,
    /// `sigma`, Angstrom.
    pub sigma_angstrom: f64,
    /// Mass of the particle the parameters describe (the atom, or the
    /// whole molecule), amu: standard atomic weights.
    pub mass_amu: f64,
    /// Mass of one of its atoms, amu, for a homonuclear diatomic molecule
    /// (the paper's "nitrogen atom gas" with N2-N2 parameters); `None` for
    /// an atom (its own mass) and for CH4 (no single atom).
    pub atom_mass_amu: Option<f64>,
}

/// Which mass a gas of a species uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MassChoice {
    /// The particle the parameters describe (the molecule for N2).
    Particle,
    /// One atom of a homonuclear diatomic molecule (N for N2).
    Atom,
}

/// How the table's `eps_t` becomes the engine's `eps` (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reading {
    /// `eps = eps_t`: the paper's N2 example (a well `eps_t / 4` deep).
    Paper,
    /// `eps = 4 eps_t`: the compilation's potential itself.
    FourEps,
}

impl Reading {
    /// The engine's `eps / k_B`, K, of a table well depth `eps_t / k_B`.
    pub fn eps_over_k(self, table_eps_over_k: f64) -> f64 {
        match self {
            Reading::Paper => table_eps_over_k,
            Reading::FourEps => 4.0 * table_eps_over_k,
        }
    }
}

impl Species {
    /// The mass `choice` names, amu, or why the species has none.
    pub fn mass(&self, choice: MassChoice) -> Result<f64, String> {
        match (choice, self.particle, self.atom_mass_amu) {
            (MassChoice::Particle, ..) | (MassChoice::Atom, Particle::Atom, _) => Ok(self.mass_amu),
            (MassChoice::Atom, Particle::Molecule, Some(atom)) => Ok(atom),
            (MassChoice::Atom, Particle::Molecule, None) => Err(format!(
                "{} is not a homonuclear diatomic molecule: it has no single atom mass",
                self.name
            )),
        }
    }
}

/// The species, from [`SOURCE`]; masses from the standard atomic weights
/// (IUPAC), summed over the molecule.
pub const SPECIES: [Species; 9] = [
    Species {
        name: "He",
        particle: Particle::Atom,
        eps_over_k: 10.22,
        sigma_angstrom: 2.556,
        mass_amu: 4.0026,
        atom_mass_amu: None,
    },
    Species {
        name: "Ne",
        particle: Particle::Atom,
        eps_over_k: 35.60,
        sigma_angstrom: 2.749,
        mass_amu: 20.180,
        atom_mass_amu: None,
    },
    Species {
        name: "Ar",
        particle: Particle::Atom,
        eps_over_k: 119.8,
        sigma_angstrom: 3.405,
        mass_amu: 39.948,
        atom_mass_amu: None,
    },
    Species {
        name: "Kr",
        particle: Particle::Atom,
        eps_over_k: 171.0,
        sigma_angstrom: 3.60,
        mass_amu: 83.798,
        atom_mass_amu: None,
    },
    Species {
        name: "Xe",
        particle: Particle::Atom,
        eps_over_k: 221.0,
        sigma_angstrom: 4.10,
        mass_amu: 131.293,
        atom_mass_amu: None,
    },
    Species {
        name: "H2",
        particle: Particle::Molecule,
        eps_over_k: 37.0,
        sigma_angstrom: 2.928,
        mass_amu: 2.016,
        atom_mass_amu: Some(1.008),
    },
    Species {
        name: "N2",
        particle: Particle::Molecule,
        eps_over_k: 95.05,
        sigma_angstrom: 3.698,
        mass_amu: 28.0134,
        atom_mass_amu: Some(14.0067),
    },
    Species {
        name: "O2",
        particle: Particle::Molecule,
        eps_over_k: 117.5,
        sigma_angstrom: 3.58,
        mass_amu: 31.998,
        atom_mass_amu: Some(15.999),
    },
    Species {
        name: "CH4",
        particle: Particle::Molecule,
        eps_over_k: 148.2,
        sigma_angstrom: 3.817,
        mass_amu: 16.043,
        atom_mass_amu: None,
    },
];

/// The species named `name` (case-insensitive), or a message listing the table.
pub fn species(name: &str) -> Result<&'static Species, String> {
    SPECIES
        .iter()
        .find(|s| s.name.eq_ignore_ascii_case(name))
        .ok_or_else(|| {
            let names: Vec<&str> = SPECIES.iter().map(|s| s.name).collect();
            format!(
                "no species `{name}` in the table ({}); give --eps-k, --sigma-angstrom and --mass-amu instead",
                names.join(", ")
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The study's `N2_10K` gas (pipeline.toml) is this table's N2 under the
    /// paper's reading: `eps = 95.05 K k_B`, `l0 = 3.698 A`, the molecule's mass.
    #[test]
    fn nitrogen_is_the_studys_gas() {
        let n2 = species("n2").unwrap();
        assert_eq!((n2.eps_over_k, n2.sigma_angstrom), (95.05, 3.698));
        assert_eq!(n2.mass(MassChoice::Particle), Ok(28.0134));
        // The atom weighs half the molecule (standard atomic weights).
        assert_eq!(n2.mass(MassChoice::Atom), Ok(14.0067));
        assert_eq!(Reading::FourEps.eps_over_k(n2.eps_over_k), 380.2);
    }

    #[test]
    fn an_atom_is_its_own_atom_and_methane_has_none() {
        let argon = species("Ar").unwrap();
        assert_eq!(
            argon.mass(MassChoice::Atom),
            argon.mass(MassChoice::Particle)
        );
        assert!(species("CH4").unwrap().mass(MassChoice::Atom).is_err());
        assert!(species("Rn").unwrap_err().contains("N2"));
    }
}
