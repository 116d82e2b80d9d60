//! The figures `ternary` draws: which artifacts each reads, how polars turns
//! their tables into the figure table, and how it is laid out.

use polars::prelude::{ChunkCompareEq, ChunkCompareIneq, DataFrame, Float64Chunked};
use serde::Serialize;

use super::frames::{failed, frame, log_groups, numbers, series, series_by, series_of, stack};
use super::{Axis, Layout, Mark, Panel, Style};
use crate::contract;
use crate::pipeline::{Input, StageError};
use crate::stats::Estimate;

/// Kernel axis label.
const G_AXIS: &str = "G(u' → u) [ρ² l v_th / v_th]";
/// Velocity change axis label.
const DU_AXIS: &str = "u − u' [v_th]";

/// A figure of the study, with the series labels its inputs get (in input order).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Figure {
    /// `G(0 -> u)` of every inverse power law on log axes (paper: the kernel for every n).
    KernelsEveryN {
        /// Legend label of each kernel input.
        labels: Vec<String>,
    },
    /// `G(0 -> u)` of every `theta = kT/eps` of one family with a well, in
    /// scaled units (paper, Lennard-Jones: scaling holds at low `T`, breaks
    /// at high `T`).
    KernelsAtTheta {
        /// The family's name (`Lennard-Jones`).
        family: String,
        /// Its id prefix, which names the figure (`kernels_lj`).
        prefix: String,
        /// Its length unit (`l = l0 (eps/kT)^(1/6)`).
        unit: String,
        /// Legend label of each kernel input.
        labels: Vec<String>,
    },
    /// `G(0 -> u)` of one potential with its fitted shape `alpha x^-beta exp(-x^2/2 sigma^2)`.
    KernelFit {
        /// The potential's id (the figure's name).
        id: String,
        /// Its legend label.
        label: String,
    },
    /// Self drift and variance rates against `u'`, and the Fokker-Planck drift.
    Rates {
        /// The potential's id.
        id: String,
        /// Its legend label.
        label: String,
    },
    /// MD against Boltzmann on one ring: `h(u, t_f)` by both estimators.
    MdBoltzmann {
        /// The ring (a row label of the comparison table).
        ring: String,
    },
    /// `a_n(X)`: the self variance rate against the truncation `X`, with the
    /// paper's `X = 0.04` marked.
    Truncation {
        /// The potential's id.
        id: String,
        /// Its legend label.
        label: String,
    },
    /// The special particle's final velocity against the launch delay, one
    /// curve per scanned launch pair (mono-energetic collisions).
    Kicks {
        /// The potential's id.
        id: String,
    },
    /// The scaling collapse: tagged `h(u, t_f)` of rings with one `N` at
    /// different `rho` and `T` (the same `rho^2 l v_th t_f`), with Boltzmann.
    Collapse {
        /// The rings (rows of the comparison table), the first also gives Boltzmann.
        rings: Vec<String>,
        /// The legend label of each ring (`N = 161, R = 51.2 mm, 100 meV`).
        labels: Vec<String>,
    },
    /// The tagged particle's `h(u, t)` approaching `f0` (a) and the early
    /// variance growing as `t kappa_2` (b).
    Evolution {
        /// The evolved kernel's instance (`ipp-6_u0_rho0`).
        instance: String,
        /// Times drawn in panel (a), `1/Gamma`.
        times: Vec<f64>,
    },
    /// MD over Boltzmann window variances against `rho l`, one series per `N`:
    /// tagged (a) and thermal (b) estimators.
    FiniteSize,
    /// `G(u' -> u)` of one potential at each configured `u'` (dilute), both
    /// sides of `u'` on log axes of `|u - u'|` (paper: `u' = 0, -0.25, -3`).
    KernelsAtUPrime {
        /// The potential's id.
        id: String,
        /// The `u'` of each kernel input.
        u_primes: Vec<f64>,
    },
    /// `G(0 -> u)` of one potential in the dilute limit and at finite `rho l`
    /// with the literal algorithm's `exp(-r |delay|)` (the paper's launch
    /// rule: an artifact of its observation region `L`, not the gas's
    /// density dependence), and each against the dilute one.
    KernelsAtDensity {
        /// The potential's id.
        id: String,
        /// Legend label of each kernel input, the dilute one ([`DILUTE`]) first.
        labels: Vec<String>,
    },
    /// The relaxation spectrum of one potential: the slowest rates over
    /// `Gamma` (a), the shapes of the slowest modes (b), the slowest rate
    /// against the randomizations it is estimated from (c).
    Spectrum {
        /// The potential's id.
        id: String,
        /// Its legend label.
        label: String,
    },
    /// The relaxation gaps of every inverse power law with a spectrum against
    /// `n`: over `Gamma` (a) and in rate units beside `Gamma` (b).
    Gaps,
    /// How the rates of `r^-n` vanish as `n -> 2+`: `Gamma` and the gaps
    /// against `n - 2` with their fitted near-integrable laws (a), the gaps
    /// over `Gamma` (b).
    NearIntegrable,
    /// The pulls of the study's cross-checks (the `pulls` stage) against
    /// the standard normal they follow when the errors are right.
    Pulls,
    /// `h(u, t)` of one ring at several final times: MD (tagged) and Boltzmann.
    MdTimes {
        /// The ring's name (the figure's).
        ring: String,
        /// The rings simulating it to each time (rows of the comparison table).
        rings: Vec<String>,
        /// Their final times, ns.
        times_ns: Vec<f64>,
    },
}

/// Legend label of the dilute kernel in [`Figure::KernelsAtDensity`].
pub const DILUTE: &str = "dilute";

/// Names of every figure kind, for documentation and tests.
pub const FIGURES: [&str; 17] = [
    "kernels",
    "kernels_lj",
    "kernel_fit",
    "rates",
    "md_boltzmann",
    "truncation",
    "kicks",
    "collapse",
    "evolution",
    "finite_size",
    "md_times",
    "kernels_u_prime",
    "kernels_density",
    "spectrum",
    "gaps",
    "near_integrable",
    "pulls",
];

impl Figure {
    /// The figure's name: its instance and file stem.
    pub fn name(&self) -> String {
        match self {
            Figure::KernelsEveryN { .. } => "kernels".into(),
            Figure::KernelsAtTheta { prefix, .. } => format!("kernels_{prefix}"),
            Figure::KernelFit { id, .. } => format!("kernel_fit_{id}"),
            Figure::Rates { id, .. } => format!("rates_{id}"),
            Figure::MdBoltzmann { ring } => format!("md_boltzmann_{ring}"),
            Figure::Truncation { id, .. } => format!("truncation_{id}"),
            Figure::Kicks { id } => format!("kicks_{id}"),
            Figure::Collapse { .. } => "collapse".into(),
            Figure::Evolution { instance, .. } => format!("evolution_{instance}"),
            Figure::FiniteSize => "finite_size".into(),
            Figure::MdTimes { ring, .. } => format!("md_times_{ring}"),
            Figure::KernelsAtUPrime { id, .. } => format!("kernels_u_prime_{id}"),
            Figure::KernelsAtDensity { id, .. } => format!("kernels_density_{id}"),
            Figure::Spectrum { id, .. } => format!("spectrum_{id}"),
            Figure::Gaps => "gaps".into(),
            Figure::NearIntegrable => "near_integrable".into(),
            Figure::Pulls => "pulls".into(),
        }
    }

    /// What the figure shows (its table's description).
    pub fn description(&self) -> String {
        match self {
            Figure::KernelsEveryN { .. } => {
                "G(0 -> u) of every inverse power law (u' = 0, dilute) against u - u' > 0, log axes, +- standard error; bins grouped 20 per decade, groups with relative error above 0.5 left out".into()
            }
            Figure::KernelsAtTheta { family, unit, .. } => {
                format!("G(0 -> u) of every {family} theta = kT/eps (u' = 0, dilute, units of {unit}) against u - u' > 0, log axes, +- standard error; bins grouped 20 per decade, groups with relative error above 0.5 left out")
            }
            Figure::KernelFit { .. } => {
                "G(0 -> u) against u - u' > 0, +- standard error, with the fitted shape alpha x^-beta exp(-x^2 / 2 sigma^2); bars whose lower end is at or below zero are drawn open downward (an arrow to the frame's bottom)".into()
            }
            Figure::Rates { .. } => {
                "self variance rate D2 (a) and drift D1 with the Fokker-Planck drift (D2' - u D2)/2 (b) against u'".into()
            }
            Figure::MdBoltzmann { .. } => {
                "h(u, t_f) of a ring: the Boltzmann master equation against MD, tagged particles (a) and the published estimator (b)".into()
            }
            Figure::Truncation { .. } => {
                "self variance rate a_n(X) of the kernel truncated at |u - u'| <= X, with the paper's X = 0.04".into()
            }
            Figure::Kicks { .. } => {
                "final velocity u1f of the special particle (u1 = 0) against the launch delay, per scanned launch pair, +- error bound".into()
            }
            Figure::Collapse { .. } => {
                "tagged h(u, t_f) of rings with one N at different rho and T and the same rho^2 l v_th t_f (the rho^2 T^(1/2 - 1/n) collapse), with the Boltzmann h".into()
            }
            Figure::Evolution { .. } => {
                "tagged particle's h(u, t) relaxing to f0 (a, log scale), the early variance of h with its closed form t kappa_2 (b), and the early h at each of evolve.early_times scaled to unit variance against the standard normal (c): a cusp from the kernel at first, the central limit's Gaussian by t ~ 1e-2 / Gamma; bars and bands whose lower end is at or below zero are drawn open downward (to the frame's bottom)".into()
            }
            Figure::FiniteSize => {
                "MD / Boltzmann window variance at t_f against rho l, one series per N (drawn side by side: N = 41, 81, 161 at one rho l are moved apart by 1.2% of the axis), tagged (a) and thermal (b) estimators; the rings at the study's common rho^2 l v_th t_f (others, such as a ring's earlier time, are in the table, not drawn)".into()
            }
            Figure::MdTimes { .. } => {
                "h(u, t) of one ring at several times: Boltzmann (band) and MD, tagged particles (markers)".into()
            }
            Figure::KernelsAtDensity { .. } => {
                "G(0 -> u) in the dilute limit and at finite rho l with the paper's launch rule (exp(-r |delay|) in an observation region of length L: an artifact of that algorithm, not the gas's density dependence) against u - u' > 0, log axes, +- standard error (a); each against the dilute kernel (b), errors combined as if independent (the kernels share their scenes: an upper bound); bins grouped 20 per decade, groups with relative error above 0.5 left out".into()
            }
            Figure::KernelsAtUPrime { .. } => {
                "G(u' -> u) at each u' (dilute) against |u - u'| on both sides of u', log axes, +- standard error; bins grouped 20 per decade, groups with relative error above 0.5 left out".into()
            }
            Figure::Spectrum { label, .. } => {
                format!("relaxation spectrum of {label}: the slowest rates r_k over Gamma (the tagged variance rate at u' = 0) of the linearized three-body operator and of the tagged particle's generator, +- jackknife error (a); the shapes f0 g_k(u) of the two slowest modes of each (b); the slowest rate of each from disjoint groups of randomizations against the group size, +- spread of the groups (c: noise pulls the lowest rate down until the estimate converges)")
            }
            Figure::NearIntegrable => {
                "the rates of the inverse power laws near the Calogero point n = 2 (near_integrable stage) against n - 2, log axes: Gamma (the tagged variance rate at u' = 0), the gap of the gas (linearized three-body operator) and of one particle (tagged generator), +- jackknife standard error, each with its fitted law A (n - 2)^p exp(q (n - 2)) over the fitted range (a, p with its error in the legend; perturbation theory: p = 2); the gaps over Gamma (b, p = 0 expected). Only resolved rates (positive by three standard errors) are drawn and fitted".into()
            }
            Figure::Pulls => {
                "the pulls (a - b) / combined error of every cross-check of the study (pulls stage): their histogram as a density in bins of 0.5 on [-4, 4] (pulls beyond counted in the outer bins), +- Poisson error, against the standard normal density they follow when the errors are right".into()
            }
            Figure::Gaps => {
                "relaxation gaps of the inverse power laws against n (the table's rows with a spectrum): the slowest relaxation rate of the gas (linearized three-body operator) and of one particle (tagged generator) over Gamma, the tagged variance rate at u' = 0 (a), and in rate units with Gamma (b, log axis: rates that vanish, n = 2, are left out), +- jackknife standard error".into()
            }
        }
    }

    /// How the figure is drawn.
    pub fn layout(&self) -> Layout {
        let linear = Axis::linear;
        let log = Axis::log;
        let panel = Panel::new;
        let panels = match self {
            Figure::KernelsEveryN { .. } | Figure::KernelsAtTheta { .. } => vec![panel(
                "kernels",
                log(DU_AXIS),
                log(G_AXIS),
                vec![("", Style::Band)],
            )],
            Figure::KernelFit { .. } => vec![panel(
                "kernel",
                log(DU_AXIS),
                log(G_AXIS),
                vec![("fit", Style::Line), ("Monte Carlo", Style::Markers)],
            )],
            Figure::Rates { .. } => vec![
                panel(
                    "variance",
                    linear("u' [v_th]"),
                    linear("D2 [ρ² l v_th]"),
                    vec![("", Style::Band)],
                ),
                panel(
                    "drift",
                    linear("u' [v_th]"),
                    linear("D1 [ρ² l v_th]"),
                    vec![("Fokker", Style::Band), ("", Style::Markers)],
                ),
            ],
            Figure::MdBoltzmann { .. } => ["tagged", "published"]
                .into_iter()
                .map(|name| {
                    panel(
                        name,
                        linear(DU_AXIS),
                        linear("h(u, t_f) [1 / v_th]"),
                        vec![("Boltzmann", Style::Band)],
                    )
                })
                .collect(),
            Figure::Truncation { .. } => vec![Panel {
                marks: vec![Mark {
                    x: 0.04,
                    label: "X = 0.04 (paper)",
                }],
                ..panel(
                    "a_n",
                    log("X [v_th]"),
                    linear("a_n(X) [ρ² l v_th]"),
                    vec![("", Style::Band)],
                )
            }],
            Figure::Kicks { .. } => vec![panel(
                "kick",
                linear("launch delay Δt [l / v_th]"),
                linear("u1f [v_th]"),
                vec![("", Style::Line)],
            )],
            Figure::Collapse { .. } => vec![panel(
                "collapse",
                linear(DU_AXIS),
                linear("h(u, t_f) [1 / v_th]"),
                vec![("Boltzmann", Style::Band)],
            )],
            Figure::Evolution { .. } => vec![
                panel(
                    "h",
                    linear("u [v_th]"),
                    log("h(u, t) [1 / v_th]"),
                    vec![("", Style::Line)],
                ),
                panel(
                    "variance",
                    log("t [1 / Γ]"),
                    log("variance of h [v_th²]"),
                    vec![("t κ₂", Style::Line)],
                ),
                panel(
                    "early",
                    linear("(u − u') / s, s² = variance of h"),
                    log("s h(u, t)"),
                    vec![(STANDARD_NORMAL, Style::Line), ("", Style::Band)],
                ),
            ],
            Figure::KernelsAtDensity { .. } => vec![
                panel(
                    "kernels",
                    log(DU_AXIS),
                    log(G_AXIS),
                    vec![("", Style::Band)],
                ),
                panel(
                    "ratio",
                    log(DU_AXIS),
                    linear("G(ρl) / G(dilute)"),
                    vec![(DILUTE, Style::Line)],
                ),
            ],
            Figure::KernelsAtUPrime { .. } => vec![Panel {
                dashed: true,
                ..panel(
                    "kernels",
                    log("|u − u'| [v_th]"),
                    log(G_AXIS),
                    vec![("", Style::Band)],
                )
            }],
            Figure::Spectrum { .. } => vec![
                panel(
                    "rates",
                    linear("mode k (slowest first)"),
                    linear("r_k / Γ"),
                    vec![("", Style::Markers)],
                ),
                panel(
                    "modes",
                    linear("u [v_th]"),
                    linear("f0 g_k(u) [1 / v_th]"),
                    vec![("", Style::Band)],
                ),
                panel(
                    "scenes",
                    log("randomizations per estimate"),
                    linear("r_1 / r_1(all randomizations)"),
                    vec![("", Style::Markers)],
                ),
            ],
            Figure::NearIntegrable => vec![
                Panel {
                    paired: true,
                    pair_order: NEAR_INTEGRABLE_PAIRS,
                    ..panel(
                        "rates",
                        log("n - 2"),
                        log("rate [ρ² l v_th]"),
                        vec![("fit", Style::Line)],
                    )
                },
                Panel {
                    paired: true,
                    pair_order: NEAR_INTEGRABLE_PAIRS,
                    ..panel(
                        "ratio",
                        log("n - 2"),
                        linear("gap / Γ"),
                        vec![("fit", Style::Line)],
                    )
                },
            ],
            Figure::Pulls => vec![panel(
                "pulls",
                linear("pull = (a - b) / combined error"),
                linear("density"),
                vec![(NORMAL, Style::Line)],
            )],
            Figure::Gaps => vec![
                panel(
                    "ratio",
                    linear("n"),
                    Axis::from_zero("gap / Γ"),
                    vec![("", Style::Markers)],
                ),
                panel(
                    "rates",
                    linear("n"),
                    log("rate [ρ² l v_th]"),
                    vec![("", Style::Markers)],
                ),
            ],
            Figure::MdTimes { .. } => vec![Panel {
                paired: true,
                ..panel(
                    "h",
                    linear(DU_AXIS),
                    linear("h(u, t) [1 / v_th]"),
                    vec![("Boltzmann", Style::Band)],
                )
            }],
            Figure::FiniteSize => [
                ("tagged", "tagged particles"),
                ("thermal", "thermal estimator"),
            ]
            .into_iter()
            .map(|(name, title)| Panel {
                dodge: true,
                title,
                level: Some(1.0),
                ..panel(name, linear("ρ l"), linear("MD / Boltzmann"), Vec::new())
            })
            .collect(),
        };
        Layout { panels }
    }

    /// The figure's long table, built with polars from its inputs' tables.
    pub fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        match self {
            Figure::KernelsEveryN { labels } | Figure::KernelsAtTheta { labels, .. } => {
                let parts = labels
                    .iter()
                    .zip(inputs)
                    .map(|(label, input)| {
                        positive_kernel(input, "kernels", label, GROUPS_PER_DECADE)
                            .and_then(|groups| resolved(&groups))
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                stack(parts)
            }
            Figure::KernelFit { .. } => {
                let measured =
                    positive_kernel(&inputs[0], "kernel", "Monte Carlo", GROUPS_PER_DECADE)?;
                let fitted = fitted_shape(&measured, &inputs[1])?;
                stack(vec![measured, fitted])
            }
            Figure::Rates { .. } => rates(&inputs[0]),
            Figure::MdBoltzmann { ring } => md_boltzmann(&inputs[0], ring),
            Figure::Truncation { label, .. } => truncation(&inputs[0], label),
            Figure::Kicks { .. } => kicks(&inputs[0]),
            Figure::Collapse { rings, labels } => collapse(&inputs[0], rings, labels),
            Figure::Evolution { times, .. } => evolution(&inputs[0], times),
            Figure::FiniteSize => finite_size(&inputs[0]),
            Figure::MdTimes {
                rings, times_ns, ..
            } => md_times(&inputs[0], rings, times_ns),
            Figure::KernelsAtDensity { labels, .. } => kernels_at_density(inputs, labels),
            Figure::Spectrum { .. } => spectrum(&inputs[0]),
            Figure::Gaps => gaps(&inputs[0]),
            Figure::NearIntegrable => near_integrable(&inputs[0]),
            Figure::Pulls => pulls(&inputs[0]),
            Figure::KernelsAtUPrime { u_primes, .. } => {
                let mut parts = Vec::new();
                for (input, u_prime) in inputs.iter().zip(u_primes) {
                    parts.extend(kernel_sides(input, *u_prime)?);
                }
                stack(parts)
            }
        }
    }
}

/// Kernel groups per decade of `u - u'` on log axes.
const GROUPS_PER_DECADE: f64 = 20.0;

/// `G` at `du > 0` of a kernel artifact as a series, averaged over
/// log-spaced groups of bins (errors from the randomizations).
fn positive_kernel(
    input: &Input,
    panel: &str,
    label: &str,
    per_decade: f64,
) -> Result<DataFrame, StageError> {
    let (replicates, du) = contract::kernel::replicates::read(input)?;
    log_groups((panel, label), &du, &replicates, per_decade)
}

/// Kernel groups per decade of the ratios to the dilute kernel: the ratio
/// changes slowly, and coarser groups resolve it better.
const RATIO_GROUPS_PER_DECADE: f64 = 5.0;

/// Panel (a): each kernel's resolved groups; panel (b): each over the
/// dilute kernel (the first input) on coarser groups both resolve, the
/// dilute one as the line at 1.
fn kernels_at_density(inputs: &[Input], labels: &[String]) -> Result<DataFrame, StageError> {
    use contract::figures::points::{X, Y, Y_ERROR};
    let grouped = |panel: &str, per_decade: f64| {
        labels
            .iter()
            .zip(inputs)
            .map(|(label, input)| {
                positive_kernel(input, panel, label, per_decade)
                    .and_then(|groups| resolved(&groups))
            })
            .collect::<Result<Vec<_>, _>>()
    };
    let groups = grouped("kernels", GROUPS_PER_DECADE)?;
    let coarse = grouped("ratio", RATIO_GROUPS_PER_DECADE)?;
    let dilute = coarse.first().ok_or_else(|| failed("no dilute kernel"))?;
    let columns = |frame: &DataFrame| -> Result<[Vec<f64>; 3], StageError> {
        Ok([
            numbers(frame, X.name)?,
            numbers(frame, Y.name)?,
            numbers(frame, Y_ERROR.name)?,
        ])
    };
    let [x0, y0, e0] = columns(dilute)?;
    let mut ratios = Vec::new();
    for (label, dense) in labels.iter().zip(&coarse) {
        let [x, y, e] = columns(dense)?;
        let (mut xs, mut ys, mut errors) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..x.len() {
            // Both kernels share their bins, hence their groups' mean x.
            if let Some(j) = x0.iter().position(|&shared| shared == x[k]) {
                let ratio = Estimate {
                    mean: y[k],
                    stderr: e[k],
                }
                .ratio(Estimate {
                    mean: y0[j],
                    stderr: e0[j],
                });
                xs.push(x[k]);
                ys.push(ratio.mean);
                errors.push(if label == DILUTE { 0.0 } else { ratio.stderr });
            }
        }
        ratios.push(series_of("ratio", label, xs, ys, Some(errors))?);
    }
    stack(groups.into_iter().chain(ratios).collect())
}

/// `G(u' -> u)` of a kernel artifact above and below `u'`, each averaged
/// over log-spaced groups of `|u - u'|` and left with its resolved groups.
fn kernel_sides(input: &Input, u_prime: f64) -> Result<Vec<DataFrame>, StageError> {
    let (replicates, du) = contract::kernel::replicates::read(input)?;
    let below: Vec<f64> = du.iter().map(|d| -d).collect();
    [("u > u'", du), ("u < u'", below)]
        .iter()
        .map(|(side, x)| {
            // The legend's minus sign is U+2212, as on the axes.
            let name = format!("u' = {}, {side}", u_prime.to_string().replace('-', "−"));
            resolved(&log_groups(
                ("kernels", &name),
                x,
                &replicates,
                GROUPS_PER_DECADE,
            )?)
        })
        .collect()
}

/// Largest relative error of a group drawn among the kernels of every `n`:
/// beyond it the tails' bands would hide the curves.
const RESOLVED: f64 = 0.5;

/// The groups of a kernel series whose relative error is below [`RESOLVED`].
fn resolved(groups: &DataFrame) -> Result<DataFrame, StageError> {
    use contract::figures::points::{Y, Y_ERROR};
    let column = |name: &str| -> Result<Float64Chunked, StageError> {
        Ok(groups
            .column(name)
            .map_err(failed)?
            .f64()
            .map_err(failed)?
            .clone())
    };
    let mask = column(Y_ERROR.name)?.lt(&(column(Y.name)? * RESOLVED));
    groups.filter(&mask).map_err(failed)
}

/// The fit's mean shape `alpha x^-beta exp(-x^2 / 2 sigma^2)` on the kernel's
/// `x` within the fit range.
fn fitted_shape(kernel: &DataFrame, fit: &Input) -> Result<DataFrame, StageError> {
    use contract::figures::points::X;
    use contract::fit::{ALPHA, BETA, RANGE_MAX, RANGE_MIN, SIGMA, TABLE};
    let table = frame(TABLE.of(fit)?)?;
    let first = |name: &str| -> Result<f64, StageError> {
        let column = table.column(name).map_err(failed)?.f64().map_err(failed)?;
        column.get(0).ok_or_else(|| failed("empty fit table"))
    };
    let (alpha, beta, sigma) = (
        first(ALPHA.value.name)?,
        first(BETA.value.name)?,
        first(SIGMA.value.name)?,
    );
    let (low, high) = (first(RANGE_MIN.name)?, first(RANGE_MAX.name)?);
    let xs: Vec<f64> = kernel
        .column(X.name)
        .map_err(failed)?
        .f64()
        .map_err(failed)?
        .iter()
        .flatten()
        .filter(|x| (low..=high).contains(x))
        .collect();
    let ys: Vec<f64> = xs
        .iter()
        .map(|x| alpha * libm::pow(*x, -beta) * libm::exp(-x * x / (2.0 * sigma * sigma)))
        .collect();
    series_of("kernel", "fit", xs, ys, None)
}

fn rates(input: &Input) -> Result<DataFrame, StageError> {
    use contract::sweep::rates::{FOKKER_PLANCK_DRIFT, SELF_DRIFT, SELF_VARIANCE, TABLE, U_PRIME};
    let table = frame(TABLE.of(input)?)?;
    let pair = |pair: &contract::Pair| (U_PRIME.name, pair.value.name, Some(pair.stderr.name));
    stack(vec![
        series(&table, "variance", "D2 (Monte Carlo)", pair(&SELF_VARIANCE))?,
        series(&table, "drift", "D1 (Monte Carlo)", pair(&SELF_DRIFT))?,
        series(
            &table,
            "drift",
            "Fokker-Planck (D2' − u D2)/2",
            pair(&FOKKER_PLANCK_DRIFT),
        )?,
    ])
}

/// Slowest modes drawn in [`Figure::Spectrum`]'s panel (a).
const SPECTRUM_MODES: u32 = 10;
/// Mode shapes drawn per generator in its panel (b).
const SPECTRUM_SHAPES: u32 = 2;

/// The gaps figure's panels from the `table` stage's rows of inverse power
/// laws (no `theta`) with a gap; panel (b) only its positive rates.
fn gaps(input: &Input) -> Result<DataFrame, StageError> {
    use contract::table::{
        A_N_UNTRUNCATED, GAP, GAP_OVER_VARIANCE_RATE, N, PARTICLE_GAP,
        PARTICLE_GAP_OVER_VARIANCE_RATE, TABLE, THETA,
    };
    let table = frame(TABLE.of(input)?)?;
    let (n, theta) = (numbers(&table, N.name)?, numbers(&table, THETA.name)?);
    let power_law = |i: usize| n[i].is_finite() && theta[i].is_nan();
    let panel = |panel: &str, title: &str, pair: contract::Pair, positive: bool| {
        let (values, errors) = (
            numbers(&table, pair.value.name)?,
            numbers(&table, pair.stderr.name)?,
        );
        let rows: Vec<usize> = (0..n.len())
            .filter(|&i| power_law(i) && values[i].is_finite() && (!positive || values[i] > 0.0))
            .collect();
        series_of(
            panel,
            title,
            rows.iter().map(|&i| n[i]).collect(),
            rows.iter().map(|&i| values[i]).collect(),
            Some(rows.iter().map(|&i| errors[i]).collect()),
        )
    };
    stack(vec![
        panel("ratio", GAS, GAP_OVER_VARIANCE_RATE, false)?,
        panel(
            "ratio",
            ONE_PARTICLE,
            PARTICLE_GAP_OVER_VARIANCE_RATE,
            false,
        )?,
        panel("rates", GAS, GAP, true)?,
        panel("rates", ONE_PARTICLE, PARTICLE_GAP, true)?,
        panel("rates", "a_n untruncated (Γ)", A_N_UNTRUNCATED, true)?,
    ])
}

/// Legend label of the standard normal density in [`Figure::Pulls`].
const NORMAL: &str = "N(0, 1)";
/// Width of [`Figure::Pulls`]' bins.
const PULL_BIN: f64 = 0.5;
/// Its bins cover `[-PULL_RANGE, PULL_RANGE]`.
const PULL_RANGE: f64 = 4.0;

/// The pulls figure: the histogram of the pulls with a value as a density
/// (count / (pulls x bin width), +- its Poisson error), those beyond the
/// range in the outer bins, and the standard normal density.
fn pulls(input: &Input) -> Result<DataFrame, StageError> {
    use contract::pulls::checks::{PULL, TABLE};
    let table = frame(TABLE.of(input)?)?;
    let values: Vec<f64> = numbers(&table, PULL.name)?
        .into_iter()
        .filter(|v| v.is_finite())
        .collect();
    let bins = (2.0 * PULL_RANGE / PULL_BIN) as usize;
    let mut counts = vec![0.0; bins];
    for value in &values {
        let k = ((value + PULL_RANGE) / PULL_BIN)
            .floor()
            .clamp(0.0, (bins - 1) as f64);
        counts[k as usize] += 1.0;
    }
    let per_pull = 1.0 / (values.len() as f64 * PULL_BIN);
    let centres = (0..bins)
        .map(|k| -PULL_RANGE + (k as f64 + 0.5) * PULL_BIN)
        .collect();
    let normal_x: Vec<f64> = (0..=160)
        .map(|k| -PULL_RANGE + 0.05 * f64::from(k))
        .collect();
    stack(vec![
        series_of(
            "pulls",
            &format!("{} pulls", values.len()),
            centres,
            counts.iter().map(|c| c * per_pull).collect(),
            Some(counts.iter().map(|c| c.sqrt() * per_pull).collect()),
        )?,
        standard_normal("pulls", NORMAL, normal_x)?,
    ])
}

/// The near-integrable figure: per fitted quantity its resolved rates
/// against `n - 2` and its law over the fitted range, paired by name.
fn near_integrable(input: &Input) -> Result<DataFrame, StageError> {
    use contract::near_integrable::{fits, rates};
    let rates_table = rates::TABLE.of(input)?;
    let fits_table = fits::TABLE.of(input)?;
    let excess = rates::EXCESS.read(rates_table).map_err(failed)?;
    let quantities = fits::QUANTITY.read(fits_table).map_err(failed)?;
    let exponents = fits::EXPONENT.read(fits_table).map_err(failed)?;
    let amplitudes = fits::AMPLITUDE.read(fits_table).map_err(failed)?;
    let corrections = fits::CORRECTION.read(fits_table).map_err(failed)?;
    let mut parts = Vec::new();
    for (panel, quantity, label, pair) in [
        ("rates", "variance_rate", "Γ", rates::VARIANCE_RATE),
        ("rates", "gap", GAS, rates::GAP),
        ("rates", "particle_gap", ONE_PARTICLE, rates::PARTICLE_GAP),
        (
            "ratio",
            "gap_over_variance_rate",
            GAS,
            rates::GAP_OVER_VARIANCE_RATE,
        ),
        (
            "ratio",
            "particle_gap_over_variance_rate",
            ONE_PARTICLE,
            rates::PARTICLE_GAP_OVER_VARIANCE_RATE,
        ),
    ] {
        let row = quantities
            .iter()
            .position(|q| q == quantity)
            .ok_or_else(|| failed(format!("near_integrable has no fit of {quantity}")))?;
        let values = pair.read(rates_table).map_err(failed)?;
        let used: Vec<usize> = (0..values.len())
            .filter(|&i| contract::near_integrable::resolved(values[i]))
            .collect();
        parts.push(series_of(
            panel,
            &format!("spectrum, {label}"),
            used.iter().map(|&i| excess[i]).collect(),
            used.iter().map(|&i| values[i].mean).collect(),
            Some(used.iter().map(|&i| values[i].stderr).collect()),
        )?);
        let (exponent, amplitude, correction) =
            (exponents[row], amplitudes[row].mean, corrections[row].mean);
        if !exponent.mean.is_finite() {
            continue;
        }
        let ends = used.iter().map(|&i| excess[i]);
        let (low, high) = ends.fold((f64::INFINITY, 0.0_f64), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
        let xs: Vec<f64> = (0..=FIT_CURVE_POINTS)
            .map(|k| low * libm::pow(high / low, k as f64 / FIT_CURVE_POINTS as f64))
            .collect();
        let ys = xs
            .iter()
            .map(|&x| amplitude * libm::pow(x, exponent.mean) * libm::exp(correction * x))
            .collect();
        let name = format!(
            "fit, p = {:.3} ± {:.3}, {label}",
            exponent.mean, exponent.stderr
        );
        parts.push(series_of(panel, &name, xs, ys, None)?);
    }
    stack(parts)
}

/// Intervals of a fitted law's curve (log-spaced in `n - 2`).
const FIT_CURVE_POINTS: usize = 48;

/// Series title of the linearized operator's rates.
const GAS: &str = "gas (linearized operator)";
/// The `near_integrable` figure's pairs, coloured alike in both panels.
const NEAR_INTEGRABLE_PAIRS: &[&str] = &["Γ", GAS, ONE_PARTICLE];
/// Series title of the tagged generator's rates.
const ONE_PARTICLE: &str = "one particle";

/// The spectrum figure's three panels, per generator (full, tagged).
fn spectrum(input: &Input) -> Result<DataFrame, StageError> {
    use contract::spectrum::{modes, rates, scenes, summary};
    let rates_table = rates::TABLE.of(input)?;
    let modes_table = modes::TABLE.of(input)?;
    let scenes_table = scenes::TABLE.of(input)?;
    let summary_table = summary::TABLE.of(input)?;
    let generators = summary::GENERATOR.read(summary_table).map_err(failed)?;
    let mut parts = Vec::new();
    for (name, title) in [("full", "linearized operator"), ("tagged", "one particle")] {
        if !generators.iter().any(|g| g == name) {
            continue;
        }
        parts.push(generator_rates(rates_table, name, title)?);
        parts.extend(mode_shapes(modes_table, name, title)?);
        // Over the estimate from every randomization (the largest group),
        // so that both generators' convergence reads on one axis.
        let (sizes, rate) = slowest_by_group(scenes_table, name)?;
        let all = rate.last().map_or(f64::NAN, |r| r.mean);
        let ys = rate.iter().map(|r| r.mean / all).collect();
        let errors = rate.iter().map(|r| r.stderr / all).collect();
        parts.push(series_of("scenes", title, sizes, ys, Some(errors))?);
    }
    stack(parts)
}

/// The slowest [`SPECTRUM_MODES`] rates of `generator` over `Gamma` against
/// the mode number, as the series `title`.
fn generator_rates(
    table: &arrow::array::RecordBatch,
    generator: &str,
    title: &str,
) -> Result<DataFrame, StageError> {
    use contract::spectrum::rates::{GENERATOR, MODE, RATE_OVER_VARIANCE_RATE};
    let names = GENERATOR.read(table).map_err(failed)?;
    let modes = MODE.read(table).map_err(failed)?;
    let ratios = RATE_OVER_VARIANCE_RATE.read(table).map_err(failed)?;
    let rows: Vec<usize> = (0..names.len())
        .filter(|&i| names[i] == generator && modes[i] <= SPECTRUM_MODES)
        .collect();
    series_of(
        "rates",
        title,
        rows.iter().map(|&i| f64::from(modes[i])).collect(),
        rows.iter().map(|&i| ratios[i].mean).collect(),
        Some(rows.iter().map(|&i| ratios[i].stderr).collect()),
    )
}

/// `f0 g_k(u)` of the slowest [`SPECTRUM_SHAPES`] modes of `generator`.
fn mode_shapes(
    table: &arrow::array::RecordBatch,
    generator: &str,
    title: &str,
) -> Result<Vec<DataFrame>, StageError> {
    use contract::spectrum::modes::{DENSITY, GENERATOR, MODE, U};
    let names = GENERATOR.read(table).map_err(failed)?;
    let modes = MODE.read(table).map_err(failed)?;
    let (u, density) = (
        U.read(table).map_err(failed)?,
        DENSITY.read(table).map_err(failed)?,
    );
    (1..=SPECTRUM_SHAPES)
        .map(|k| {
            let rows: Vec<usize> = (0..names.len())
                .filter(|&i| names[i] == generator && modes[i] == k)
                .collect();
            series_of(
                "modes",
                &format!("{title}, mode {k}"),
                rows.iter().map(|&i| u[i]).collect(),
                rows.iter().map(|&i| density[i].mean).collect(),
                Some(rows.iter().map(|&i| density[i].stderr).collect()),
            )
        })
        .collect()
}

/// The slowest rate of `generator` from groups of each size: sizes and the
/// groups' mean rate (the all-randomization estimate has no spread: error 0).
fn slowest_by_group(
    table: &arrow::array::RecordBatch,
    generator: &str,
) -> Result<(Vec<f64>, Vec<Estimate>), StageError> {
    use contract::spectrum::scenes::{GENERATOR, MODE, RANDOMIZATIONS, RATE};
    let names = GENERATOR.read(table).map_err(failed)?;
    let modes = MODE.read(table).map_err(failed)?;
    let sizes = RANDOMIZATIONS.read(table).map_err(failed)?;
    let rates = RATE.read(table).map_err(failed)?;
    Ok((0..names.len())
        .filter(|&i| names[i] == generator && modes[i] == 1)
        .map(|i| {
            let rate = rates[i];
            let stderr = if rate.stderr.is_finite() {
                rate.stderr
            } else {
                0.0
            };
            (f64::from(sizes[i]), Estimate { stderr, ..rate })
        })
        .unzip())
}

fn md_boltzmann(input: &Input, ring: &str) -> Result<DataFrame, StageError> {
    use contract::compare::comparison::{DU, H_BOLTZMANN, H_PUBLISHED, H_TAGGED, RING, TABLE};
    let rows = rows_where(&frame(TABLE.of(input)?)?, RING.name, ring)?;
    let pair = |pair: &contract::Pair| (DU.name, pair.value.name, Some(pair.stderr.name));
    stack(vec![
        series(&rows, "tagged", "Boltzmann", pair(&H_BOLTZMANN))?,
        series(&rows, "tagged", "MD, tagged particles", pair(&H_TAGGED))?,
        series(&rows, "published", "Boltzmann", pair(&H_BOLTZMANN))?,
        series(
            &rows,
            "published",
            "MD, published estimator",
            pair(&H_PUBLISHED),
        )?,
    ])
}

fn truncation(input: &Input, label: &str) -> Result<DataFrame, StageError> {
    use contract::moments::{SELF_VARIANCE, TABLE, TRUNCATION};
    let all = frame(TABLE.of(input)?)?;
    let mask = all.column(TRUNCATION.name).map_err(failed)?.is_not_null();
    let finite = all.filter(&mask).map_err(failed)?;
    series(
        &finite,
        "a_n",
        label,
        (
            TRUNCATION.name,
            SELF_VARIANCE.value.name,
            Some(SELF_VARIANCE.stderr.name),
        ),
    )
}

fn kicks(input: &Input) -> Result<DataFrame, StageError> {
    use contract::scan::LAUNCH;
    use contract::scan::curve::{LAUNCH_DELAY, TABLE, U1_FINAL, U1_FINAL_ERROR};
    let curve = frame(TABLE.of(input)?)?;
    let columns = (LAUNCH_DELAY.name, U1_FINAL.name, Some(U1_FINAL_ERROR.name));
    stack(series_by(
        &curve,
        "kick",
        LAUNCH.name,
        |launch| launch.to_string(),
        columns,
    )?)
}

/// The rows of `all` whose text column `key` equals `value`.
fn rows_where(all: &DataFrame, key: &str, value: &str) -> Result<DataFrame, StageError> {
    let mask = all
        .column(key)
        .map_err(failed)?
        .str()
        .map_err(failed)?
        .equal(value);
    all.filter(&mask).map_err(failed)
}

fn collapse(input: &Input, rings: &[String], labels: &[String]) -> Result<DataFrame, StageError> {
    use contract::compare::comparison::{DU, H_BOLTZMANN, H_TAGGED, RING, TABLE};
    let all = frame(TABLE.of(input)?)?;
    let pair = |pair: &contract::Pair| (DU.name, pair.value.name, Some(pair.stderr.name));
    let first = rings.first().ok_or_else(|| failed("no ring to collapse"))?;
    let mut parts = vec![series(
        &rows_where(&all, RING.name, first)?,
        "collapse",
        "Boltzmann",
        pair(&H_BOLTZMANN),
    )?];
    for (ring, label) in rings.iter().zip(labels) {
        let rows = rows_where(&all, RING.name, ring)?;
        parts.push(series(&rows, "collapse", label, pair(&H_TAGGED))?);
    }
    stack(parts)
}

fn evolution(input: &Input, times: &[f64]) -> Result<DataFrame, StageError> {
    use contract::evolve::{TIME_GAMMA, early_summary, evolution};
    let h = frame(evolution::TABLE.of(input)?)?;
    let at = |t: f64| -> Result<DataFrame, StageError> {
        let mask = h
            .column(TIME_GAMMA.name)
            .map_err(failed)?
            .f64()
            .map_err(failed)?
            .equal(t);
        h.filter(&mask).map_err(failed)
    };
    let tagged =
        |pair: &contract::Pair| (evolution::U.name, pair.value.name, Some(pair.stderr.name));
    let mut parts = Vec::new();
    for &t in times {
        let label = format!("t = {t} / Γ");
        parts.push(series(&at(t)?, "h", &label, tagged(&evolution::H_TAGGED))?);
    }
    let first = times.first().ok_or_else(|| failed("no time to draw"))?;
    let equilibrium = (evolution::U.name, evolution::EQUILIBRIUM_TAGGED.name, None);
    parts.push(series(&at(*first)?, "h", "f0", equilibrium)?);
    let early = frame(early_summary::TABLE.of(input)?)?;
    let variance =
        |pair: &contract::Pair| (TIME_GAMMA.name, pair.value.name, Some(pair.stderr.name));
    parts.push(series(
        &early,
        "variance",
        "master equation",
        variance(&early_summary::VARIANCE),
    )?);
    parts.push(series(
        &early,
        "variance",
        "t κ₂",
        variance(&early_summary::VARIANCE_CLOSED_FORM),
    )?);
    parts.extend(early_shapes(input)?);
    stack(parts)
}

/// Reach of the early panel, in standard deviations of `h`.
const EARLY_REACH: f64 = 5.0;

/// Panel (c): the early `h(u, t)` at each of `evolve.early_times`, scaled to
/// unit variance (`x = (u - u') / s`, `y = s h`, `s^2` its variance at `t`),
/// against the standard normal density: a cusp inherited from the kernel at
/// the earliest times, the central limit's Gaussian by `t ~ 1e-2 / Gamma`
/// (physics.md §4).
fn early_shapes(input: &Input) -> Result<Vec<DataFrame>, StageError> {
    use contract::evolve::{TIME_GAMMA, early_evolution, early_summary};
    let summary = early_summary::TABLE.of(input)?;
    let h = early_evolution::TABLE.of(input)?;
    let (times, variances) = (
        TIME_GAMMA.read(summary)?,
        early_summary::VARIANCE.read(summary)?,
    );
    let (at, du, values) = (
        TIME_GAMMA.read(h)?,
        early_evolution::DU.read(h)?,
        early_evolution::H.read(h)?,
    );
    let mut parts = Vec::new();
    for (&t, variance) in times.iter().zip(&variances) {
        let scale = variance.mean.sqrt();
        let (mut xs, mut ys, mut errors) = (Vec::new(), Vec::new(), Vec::new());
        for k in (0..du.len()).filter(|&k| at[k] == t) {
            let x = du[k] / scale;
            if x.abs() <= EARLY_REACH {
                xs.push(x);
                ys.push(values[k].mean * scale);
                errors.push(values[k].stderr * scale);
            }
        }
        // Three significant digits: a ring's time converted to 1/Gamma
        // carries seventeen.
        let t: f64 = format!("{t:.2e}").parse().map_err(failed)?;
        parts.push(series_of(
            "early",
            &format!("t = {t} / Γ"),
            xs,
            ys,
            Some(errors),
        )?);
    }
    let xs: Vec<f64> = (-100..=100)
        .map(|k| EARLY_REACH * f64::from(k) / 100.0)
        .collect();
    parts.push(standard_normal("early", STANDARD_NORMAL, xs)?);
    Ok(parts)
}

/// The standard normal density at `xs`, a series `name` of `panel` without errors.
fn standard_normal(panel: &str, name: &str, xs: Vec<f64>) -> Result<DataFrame, StageError> {
    let density = xs
        .iter()
        .map(|x| libm::exp(-0.5 * x * x) / libm::sqrt(2.0 * std::f64::consts::PI))
        .collect();
    series_of(panel, name, xs, density, None)
}

/// The reference series of the early panel.
const STANDARD_NORMAL: &str = "standard normal";

fn finite_size(input: &Input) -> Result<DataFrame, StageError> {
    use contract::compare::finite_size::{
        DENSITY, PARTICLES, RATIO, SCALED_TIME, TABLE, THERMAL_RATIO,
    };
    let rings = at_common_time(&frame(TABLE.of(input)?)?, SCALED_TIME.name)?;
    let named = |n: &str| format!("N = {n}");
    let pair = |pair: &contract::Pair| (DENSITY.name, pair.value.name, Some(pair.stderr.name));
    let mut parts = series_by(&rings, "tagged", PARTICLES.name, named, pair(&RATIO))?;
    parts.extend(series_by(
        &rings,
        "thermal",
        PARTICLES.name,
        named,
        pair(&THERMAL_RATIO),
    )?);
    stack(parts)
}

/// The rows of `rings` at their median scaled time `rho^2 l v_th t_f` (within
/// 1e-6 of it): a figure against `rho l` compares rings at one scaled time.
fn at_common_time(rings: &DataFrame, scaled_time: &str) -> Result<DataFrame, StageError> {
    let mut sorted = numbers(rings, scaled_time)?;
    sorted.sort_by(f64::total_cmp);
    let median = *sorted
        .get(sorted.len() / 2)
        .ok_or_else(|| failed("no ring to draw"))?;
    let times = rings
        .column(scaled_time)
        .map_err(failed)?
        .f64()
        .map_err(failed)?;
    let keep = times.gt_eq(median * (1.0 - 1e-6)) & times.lt_eq(median * (1.0 + 1e-6));
    rings.filter(&keep).map_err(failed)
}

fn md_times(input: &Input, rings: &[String], times_ns: &[f64]) -> Result<DataFrame, StageError> {
    use contract::compare::comparison::{DU, H_BOLTZMANN, H_TAGGED, RING, TABLE};
    let all = frame(TABLE.of(input)?)?;
    let pair = |pair: &contract::Pair| (DU.name, pair.value.name, Some(pair.stderr.name));
    let mut parts = Vec::new();
    for (ring, time) in rings.iter().zip(times_ns) {
        let rows = rows_where(&all, RING.name, ring)?;
        parts.push(series(
            &rows,
            "h",
            &format!("Boltzmann, {time} ns"),
            pair(&H_BOLTZMANN),
        )?);
        parts.push(series(
            &rows,
            "h",
            &format!("MD, {time} ns"),
            pair(&H_TAGGED),
        )?);
    }
    stack(parts)
}
