//! Which figures a study draws: each figure whose inputs the plan computes,
//! with those inputs in the figure's order.

use super::rings::{collapse_rings, compared_rings};
use crate::config::{MdParams, Study};
use crate::contract::{self, instances};
use crate::figures::collapse::Collapse;
use crate::figures::evolution::Evolution;
use crate::figures::finite_size::FiniteSize;
use crate::figures::gaps::Gaps;
use crate::figures::kernel_fit::KernelFit;
use crate::figures::kernels::KernelsEveryN;
use crate::figures::kernels_at_theta::KernelsAtTheta;
use crate::figures::kernels_density::{DILUTE, KernelsAtDensity};
use crate::figures::kernels_u_prime::KernelsAtUPrime;
use crate::figures::kicks::Kicks;
use crate::figures::md_boltzmann::MdBoltzmann;
use crate::figures::md_times::MdTimes;
use crate::figures::near_integrable::NearIntegrable;
use crate::figures::pulls::Pulls;
use crate::figures::rates::Rates;
use crate::figures::spectrum::Spectrum;
use crate::figures::truncation::Truncation;
use crate::figures::{Figure, PALETTE};
use crate::physics::potential::{Family, Potential};
use crate::pipeline::{InstanceId, Stage};
use crate::stages::figures::FiguresStage;

/// The figures of a study whose inputs `plan` computes: kernels of every
/// scale-free potential with kicks (the inverse power laws) and, per family
/// with a temperature in its shape, of its `theta`s (at most one per colour,
/// spread over them); for `n = 6` (or
/// the first such potential) the kernel with its fit, `a_n(X)`, the rates
/// against `u'`, the kernels at each `u'`, the spectrum and the kicks; the evolution; MD
/// against Boltzmann for the compared rings.
pub(super) fn figure_stages(study: &Study, plan: &[Box<dyn Stage>]) -> Vec<FiguresStage> {
    let planned: std::collections::HashSet<InstanceId> = plan.iter().map(|s| s.id()).collect();
    let present = |id: &InstanceId| planned.contains(id);
    let kicked: Vec<Potential> = study
        .potentials()
        .into_iter()
        .filter(|p| !p.family().is_integrable())
        .collect();
    let mut figures = kernel_figures(study, &kicked);
    let main = kicked
        .iter()
        .find(|p| **p == Potential::inverse_power(6.0))
        .or(kicked.first());
    if let Some(p) = main {
        figures.extend(main_figures(study, p, &present));
    }
    figures.extend(gaps_figure(&study.potentials(), &present));
    let near_integrable = instances::near_integrable();
    if present(&near_integrable) {
        figures.push(FiguresStage::new(
            Figure::NearIntegrable(NearIntegrable),
            vec![near_integrable],
        ));
    }
    let pulls = instances::pulls();
    if present(&pulls) {
        figures.push(FiguresStage::new(Figure::Pulls(Pulls), vec![pulls]));
    }
    figures.extend(evolution_figure(study, &present));
    figures.extend(kernels_at_density(study));
    figures.extend(md_figures(study, &present));
    figures
}

/// The `stage` instance of `potential`'s dilute kernel at `u' = 0`.
fn dilute(study: &Study, stage: &str, potential: &Potential) -> InstanceId {
    let params = study.kernel_params(*potential, 0.0, 0.0);
    InstanceId::new(stage, &instances::target(&params))
}

/// The kernels of the scale-free potentials in one figure, and of each
/// family with a `theta` in one figure per family.
fn kernel_figures(study: &Study, kicked: &[Potential]) -> Vec<FiguresStage> {
    let kernels = |potentials: &[Potential]| -> (Vec<String>, Vec<InstanceId>) {
        let labels = potentials.iter().map(|p| p.family().label()).collect();
        let inputs = potentials
            .iter()
            .map(|p| dilute(study, contract::kernel::STAGE, p))
            .collect();
        (labels, inputs)
    };
    let mut figures = Vec::new();
    let (at_theta, scale_free): (Vec<Potential>, Vec<Potential>) =
        kicked.iter().partition(|p| p.family().theta().is_some());
    if !scale_free.is_empty() {
        let (labels, inputs) = kernels(&scale_free);
        figures.push(FiguresStage::new(
            Figure::KernelsEveryN(KernelsEveryN { labels }),
            inputs,
        ));
    }
    let mut families: Vec<(&dyn Family, Vec<Potential>)> = Vec::new();
    for p in &at_theta {
        match families
            .iter_mut()
            .find(|(f, _)| f.name() == p.family().name())
        {
            Some((_, members)) => members.push(*p),
            None => families.push((p.family(), vec![*p])),
        }
    }
    for (family, members) in families {
        let (labels, inputs) = kernels(&spread(&members, PALETTE.len()));
        let figure = Figure::KernelsAtTheta(KernelsAtTheta {
            family: family.name().into(),
            prefix: family.prefix().into(),
            unit: family.length_unit().into(),
            labels,
        });
        figures.push(FiguresStage::new(figure, inputs));
    }
    figures
}

/// The main potential's kernel with its fit, `a_n(X)`, its rates against
/// `u'` (with a sweep), its kernels at each dilute `u'` (more than one), its
/// relaxation spectrum (with a spectrum) and its kicks (with a scan).
fn main_figures(
    study: &Study,
    p: &Potential,
    present: &dyn Fn(&InstanceId) -> bool,
) -> Vec<FiguresStage> {
    let (id, label) = (p.id(), p.family().label());
    let mut figures = vec![
        FiguresStage::new(
            Figure::KernelFit(KernelFit {
                id: id.clone(),
                label: label.clone(),
            }),
            vec![
                dilute(study, contract::kernel::STAGE, p),
                dilute(study, contract::fit::STAGE, p),
            ],
        ),
        FiguresStage::new(
            Figure::Truncation(Truncation {
                id: id.clone(),
                label: label.clone(),
            }),
            vec![dilute(study, contract::moments::STAGE, p)],
        ),
    ];
    let sweep = InstanceId::new(contract::sweep::STAGE, &id);
    if present(&sweep) {
        let rates = Figure::Rates(Rates {
            id: id.clone(),
            label,
        });
        figures.push(FiguresStage::new(rates, vec![sweep]));
    }
    let u_primes: Vec<f64> = study
        .kernel_targets()
        .into_iter()
        .filter(|(_, density)| *density == 0.0)
        .map(|(u_prime, _)| u_prime)
        .collect();
    if u_primes.len() > 1 {
        let inputs = u_primes
            .iter()
            .map(|&u| instances::kernel(&study.kernel_params(*p, u, 0.0)))
            .collect();
        let figure = Figure::KernelsAtUPrime(KernelsAtUPrime {
            id: id.clone(),
            u_primes,
        });
        figures.push(FiguresStage::new(figure, inputs));
    }
    let spectrum = instances::spectrum(p);
    if present(&spectrum) {
        let figure = Figure::Spectrum(Spectrum {
            id: id.clone(),
            label: p.family().label(),
        });
        figures.push(FiguresStage::new(figure, vec![spectrum]));
    }
    let scan = instances::scan(p);
    if present(&scan) {
        figures.push(FiguresStage::new(Figure::Kicks(Kicks { id }), vec![scan]));
    }
    figures
}

/// The gaps against `n`, when at least two inverse power laws (kicked,
/// without a `theta`) have a spectrum; from the `table` stage's rows.
fn gaps_figure(
    kicked: &[Potential],
    present: &dyn Fn(&InstanceId) -> bool,
) -> Option<FiguresStage> {
    let with_spectrum = kicked
        .iter()
        .filter(|p| p.family().theta().is_none() && present(&instances::spectrum(p)))
        .count();
    let table = instances::table();
    (with_spectrum >= 2 && present(&table))
        .then(|| FiguresStage::new(Figure::Gaps(Gaps), vec![table]))
}

/// `h(u, t)` at up to [`EVOLUTION_CURVES`] of the evolution's times.
fn evolution_figure(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Option<FiguresStage> {
    let evolve = study.evolve_params()?;
    let instance = instances::target(&evolve.kernel);
    let id = InstanceId::new(contract::evolve::STAGE, &instance);
    (present(&id) && !evolve.times.is_empty()).then(|| {
        let times = spread(&evolve.times, EVOLUTION_CURVES);
        FiguresStage::new(Figure::Evolution(Evolution { instance, times }), vec![id])
    })
}

/// MD against Boltzmann: the first ring, the collapse, `h` at several
/// times and the finite-size table's rings, when `compare` is planned.
fn md_figures(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<FiguresStage> {
    let compare = instances::compare();
    let rings = study.md_params();
    let (true, Some(first)) = (present(&compare), rings.first()) else {
        return Vec::new();
    };
    let from_compare = |figure: Figure| FiguresStage::new(figure, vec![compare.clone()]);
    let mut figures = vec![from_compare(Figure::MdBoltzmann(MdBoltzmann {
        ring: first.name.clone(),
    }))];
    let compared = compared_rings(study);
    let compared: Vec<&MdParams> = compared.iter().collect();
    let collapsing = collapse_rings(study);
    if collapsing.len() > 1 {
        let rings = collapsing.iter().map(|r| r.name.clone()).collect();
        let labels = collapsing.iter().map(ring_label).collect();
        figures.push(from_compare(Figure::Collapse(Collapse { rings, labels })));
    }
    figures.extend(md_times(&compared).map(from_compare));
    // Finite size compares the rings at u' = 0: none, no figure.
    if !compared.is_empty() {
        figures.push(from_compare(Figure::FiniteSize(FiniteSize)));
    }
    figures
}

/// `G(0 -> u)` of the collapse rings' potential in the dilute limit and at
/// each of those rings' own `rho l` (the kernel instances `plan` adds for
/// them), when the potential kicks.
fn kernels_at_density(study: &Study) -> Option<FiguresStage> {
    let rings = collapse_rings(study);
    let potential = rings.first()?.potential;
    if potential.family().is_integrable() {
        return None;
    }
    let instance = |density: f64| instances::kernel(&study.kernel_params(potential, 0.0, density));
    // Densities relative to the first ring's, as the paper names its rings:
    // (rho, 100 meV), (2 rho, 100 meV), (2 rho, 800 meV).
    let rho = rings.first()?.gas.density_per_um;
    let mut labels = vec![DILUTE.to_string()];
    let mut inputs = vec![instance(0.0)];
    for ring in &rings {
        let id = instance(ring.scaled_density());
        if !inputs.contains(&id) {
            let factor = (ring.gas.density_per_um / rho * 1e6).round() / 1e6;
            let density = if factor == 1.0 {
                "ρ".to_string()
            } else {
                format!("{factor}ρ")
            };
            labels.push(format!("{density}, {} meV", kt_mev(ring)));
            inputs.push(id);
        }
    }
    (inputs.len() > 1).then(|| {
        FiguresStage::new(
            Figure::KernelsAtDensity(KernelsAtDensity {
                id: potential.id(),
                labels,
            }),
            inputs,
        )
    })
}

/// A ring's `kT`, meV (to a micro-electronvolt).
fn kt_mev(ring: &MdParams) -> f64 {
    (ring.gas.kt_ev * 1e6).round() / 1e3
}

/// A ring's legend label: `N = 161, R = 51.2 mm, 100 meV`.
fn ring_label(ring: &MdParams) -> String {
    let radius_mm = ring.radius_um / 1e3;
    format!(
        "N = {}, R = {radius_mm} mm, {} meV",
        ring.particles,
        kt_mev(ring)
    )
}

/// `h(u, t)` at several times: the first compared ring simulated to more
/// than one final time (same gas and ring), its rings in order of time.
fn md_times(compared: &[&MdParams]) -> Option<Figure> {
    let same_ring = |a: &MdParams, b: &MdParams| {
        a.gas == b.gas && a.particles == b.particles && a.radius_um == b.radius_um
    };
    compared.iter().find_map(|ring| {
        let mut group: Vec<&MdParams> = compared
            .iter()
            .copied()
            .filter(|other| same_ring(ring, other))
            .collect();
        if group.len() < 2 {
            return None;
        }
        group.sort_by(|a, b| a.final_time_ns.total_cmp(&b.final_time_ns));
        Some(Figure::MdTimes(MdTimes {
            ring: group.last().map(|r| r.name.clone()).unwrap_or_default(),
            rings: group.iter().map(|r| r.name.clone()).collect(),
            times_ns: group.iter().map(|r| r.final_time_ns).collect(),
        }))
    })
}

/// Curves of `h(u, t)` in the evolution figure, at most.
const EVOLUTION_CURVES: usize = 5;

/// At most `count` of `values`, spread evenly over them, first and last
/// included (more curves than colours, or than a panel shows, cannot be
/// told apart).
fn spread<T: Copy + PartialEq>(values: &[T], count: usize) -> Vec<T> {
    if values.len() <= count {
        return values.to_vec();
    }
    let last = values.len() - 1;
    let mut picked: Vec<T> = (0..count)
        .map(|k| values[(k * last + (count - 1) / 2) / (count - 1)])
        .collect();
    picked.dedup();
    picked
}
