//! Which MD rings `compare` sets against the Boltzmann evolution, and which
//! of them make the `rho^2 T^(1/2 - 1/n)` collapse.

use super::{MdParams, Study};

impl Study {
    /// The rings `compare` sets against the Boltzmann evolution: those of the
    /// first ring's potential at `u' = 0`, in file order.
    pub fn compared_rings(&self) -> Vec<MdParams> {
        self.at_rest(|ring, first| ring.potential == first.potential)
    }

    /// The rings `compare` also sets against the Boltzmann evolution of
    /// their own potential's kernel (`h` and the goodness of fit only): those
    /// at `u' = 0` of another potential than the first ring's that kicks
    /// (e.g. Lennard-Jones; not the integrable `n = 2`), in file order.
    pub fn other_compared_rings(&self) -> Vec<MdParams> {
        self.at_rest(|ring, first| {
            ring.potential != first.potential && !ring.potential.family().is_integrable()
        })
    }

    /// The rings at `u' = 0` that `keep(ring, first ring)` accepts, in file order.
    fn at_rest(&self, keep: impl Fn(&MdParams, &MdParams) -> bool) -> Vec<MdParams> {
        let rings = self.md_params();
        let Some(first) = rings.first().cloned() else {
            return Vec::new();
        };
        rings
            .into_iter()
            .filter(|ring| ring.u_prime == 0.0 && keep(ring, &first))
            .collect()
    }

    /// The compared rings sharing the first ring's `N` and `rho^2 l v_th t_f`
    /// (different `rho` and `T`, the same dilute physics: the `rho^2
    /// T^(1/2 - 1/n)` collapse), the first ring first.
    pub fn collapse_rings(&self) -> Vec<MdParams> {
        let compared = self.compared_rings();
        let Some(first) = compared.first().cloned() else {
            return Vec::new();
        };
        compared
            .into_iter()
            .filter(|r| r.particles == first.particles)
            .filter(|r| (r.scaled_final_time() / first.scaled_final_time() - 1.0).abs() < 1e-9)
            .collect()
    }
}
