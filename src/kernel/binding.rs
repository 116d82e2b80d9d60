//! The binding energy of the pairs three-body recombination leaves bound
//! (A + A + A -> A2 + A, potentials with a well): per replicate, the
//! recombination rate at `u'` split into bins of the binding energy
//! `B = -(w^2/4 + U)` of the bound pair (`kT`; 0 at the dissociation
//! threshold, the well depth `D` at the bottom of the well), and the
//! rate-weighted mean of `B`. The same reweighted sum as
//! [`recombination_rates`](super::recombination_rates), split by `B`
//! ([`recombination_sums`]). Pure math: no IO.

use super::{Draws, Event, Target, recombination_sums};
use crate::stats::Estimate;

/// Bins of the binding energy `B` uniform on `[0, D]`, `kT`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BindingBins {
    /// Well depth `D`, `kT`.
    pub depth: f64,
    /// Number of bins: [`BindingBins::PER_WELL`], none without a well.
    pub count: usize,
}

impl BindingBins {
    /// Bins across the well: uniform in `B / D`, so that families and
    /// temperatures compare bin by bin; at `theta = 0.1` (Lennard-Jones,
    /// `D = 2.5 kT`) a bin is `0.1 kT`, well below the `kT` over which the
    /// thermal distribution of the third atom's energy varies.
    pub const PER_WELL: usize = 25;

    /// The bins of a well of depth `depth` (`kT`; none when it is 0: no bound states).
    pub fn of_well(depth: f64) -> BindingBins {
        BindingBins {
            depth,
            count: if depth > 0.0 { Self::PER_WELL } else { 0 },
        }
    }

    /// Width of a bin, `kT`.
    pub fn width(&self) -> f64 {
        self.depth / self.count as f64
    }

    /// Edge `j` (`0..=count`) of the bins, `kT`: 0 first, exactly `D` last.
    pub fn edge(&self, j: usize) -> f64 {
        self.depth * (j as f64 / self.count as f64)
    }

    /// The bin of binding energy `binding` (`kT`), `None` outside `[0, D]`
    /// (`B = D`, the bottom of the well, in the last bin).
    pub fn index(&self, binding: f64) -> Option<usize> {
        let inside = self.count > 0 && (0.0..=self.depth).contains(&binding);
        inside.then(|| ((binding / self.width()) as usize).min(self.count - 1))
    }
}

/// Slot of [`binding_sums`] holding the recombination rate, `rho^2 l v_th`.
const RATE: usize = 0;
/// Slot holding the rate weighted by `B`, `rho^2 l v_th kT`.
const BINDING_WEIGHTED: usize = 1;
/// Slot of the first bin's rate; bin `k` is `FIRST_BIN + k`.
const FIRST_BIN: usize = 2;

/// Per replicate at `target`: the recombination rate, the rate weighted by
/// `B`, and the rate into each bin of `bins` (`rho^2 l v_th`), as
/// [`BindingSums`]. The rate's sum is the one of
/// [`recombination_rates`](super::recombination_rates), bit for bit.
pub fn binding_sums(
    events: &[Event],
    target: &Target,
    draws: &Draws,
    bins: &BindingBins,
) -> BindingSums {
    let slots = FIRST_BIN + bins.count;
    let replicates = recombination_sums(events, target, draws, slots, |sums, energy, rate| {
        let binding = -energy;
        sums[RATE] += rate;
        sums[BINDING_WEIGHTED] += binding * rate;
        if let Some(k) = bins.index(binding) {
            sums[FIRST_BIN + k] += rate;
        }
    });
    BindingSums { replicates }
}

/// Recombination sums per replicate ([`binding_sums`]), at one `u'` or
/// averaged over some (every sum is linear in the weights).
#[derive(Clone, Debug, PartialEq)]
pub struct BindingSums {
    /// Per replicate: the rate, the `B`-weighted rate, the rate of each bin.
    replicates: Vec<Vec<f64>>,
}

impl BindingSums {
    /// All sums in one list, replicate after replicate (for averaging).
    pub fn flat(&self) -> Vec<f64> {
        self.replicates.concat()
    }

    /// The sums of `flat` (as [`BindingSums::flat`] lists them) of `bins`.
    pub fn from_flat(flat: &[f64], bins: &BindingBins) -> BindingSums {
        BindingSums {
            replicates: flat
                .chunks(FIRST_BIN + bins.count)
                .map(<[f64]>::to_vec)
                .collect(),
        }
    }

    /// Slot `slot` of every replicate.
    fn slot(&self, slot: usize) -> Vec<f64> {
        self.replicates.iter().map(|sums| sums[slot]).collect()
    }

    /// The recombination rate, `rho^2 l v_th`, with its error from the randomizations.
    pub fn rate(&self) -> Estimate {
        Estimate::from_replicates(&self.slot(RATE))
    }

    /// The rate-weighted mean binding energy `<B>` of the bound pairs,
    /// `kT`: `sum B w / sum w` over the replicates' means, its error to
    /// first order with the two sums' correlation kept
    /// ([`Estimate::paired_ratio`]); NaN without recombination.
    pub fn mean_binding(&self) -> Estimate {
        Estimate::paired_ratio(&self.slot(BINDING_WEIGHTED), &self.slot(RATE))
    }

    /// The rate per unit binding energy in bin `k` of `bins`,
    /// `rho^2 l v_th / kT`: the bin's rate over its width.
    pub fn density(&self, bins: &BindingBins, k: usize) -> Estimate {
        let width = bins.width();
        let densities: Vec<f64> = self
            .slot(FIRST_BIN + k)
            .iter()
            .map(|rate| rate / width)
            .collect();
        Estimate::from_replicates(&densities)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Edges run from 0 to exactly `D`; every `B` in `[0, D]` falls in the
    /// bin whose edges enclose it, `D` itself in the last; none outside.
    #[test]
    fn bins_cover_the_well_and_nothing_else() {
        let bins = BindingBins::of_well(2.5);
        assert_eq!((bins.edge(0), bins.edge(bins.count)), (0.0, 2.5));
        for binding in [0.0, 0.05, 0.1, 1.234, 2.45, 2.5] {
            let k = bins.index(binding).unwrap();
            assert!(
                bins.edge(k) <= binding && binding <= bins.edge(k + 1),
                "{binding}"
            );
        }
        assert_eq!(bins.index(-1e-12), None);
        assert_eq!(bins.index(2.5 + 1e-12), None);
        let none = BindingBins::of_well(0.0);
        assert_eq!((none.count, none.index(0.0)), (0, None));
    }
}
