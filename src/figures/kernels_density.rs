//! `kernels_density_<id>`: the kernel in the dilute limit and at finite density.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, numbers, series_of, stack};
use super::kernel_groups::{GROUPS_PER_DECADE, positive_kernel, resolved};
use super::planning::kt_mev;
use super::{Axis, DU_AXIS, Drawn, FigureKind, G_AXIS, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};
use crate::stats::Estimate;

/// `G(0 -> u)` of one potential in the dilute limit and at finite `rho l`
/// with the literal algorithm's `exp(-r |delay|)` (the paper's launch
/// rule: an artifact of its observation region `L`, not the gas's
/// density dependence), and each against the dilute one.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "kernels_at_density")]
pub struct KernelsAtDensity {
    /// The potential's id.
    pub id: String,
    /// Legend label of each kernel input, the dilute one ([`DILUTE`]) first.
    pub labels: Vec<String>,
}

impl KernelsAtDensity {
    /// `G(0 -> u)` of the collapse rings' potential in the dilute limit and
    /// at each of those rings' own `rho l` (the kernel instances the plan
    /// adds for them), when the potential kicks.
    pub fn planned(study: &Study, _present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let rings = study.collapse_rings();
        let Some(first) = rings.first() else {
            return Vec::new();
        };
        let potential = first.potential;
        if potential.family().is_integrable() {
            return Vec::new();
        }
        let instance =
            |density: f64| instances::kernel(&study.kernel_params(potential, 0.0, density));
        // Densities relative to the first ring's, as the paper names its
        // rings: (rho, 100 meV), (2 rho, 100 meV), (2 rho, 800 meV).
        let rho = first.gas.density_per_um;
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
        if inputs.len() < 2 {
            return Vec::new();
        }
        let figure = KernelsAtDensity {
            id: potential.id(),
            labels,
        };
        vec![Drawn::new(figure, inputs)]
    }
}

impl FigureKind for KernelsAtDensity {
    fn topic(&self) -> Topic {
        Topic::MainKernel
    }

    fn name(&self) -> String {
        format!("kernels_density_{}", self.id)
    }

    fn description(&self) -> String {
        "G(0 -> u) in the dilute limit and at finite rho l with the paper's launch rule (exp(-r |delay|) in an observation region of length L: an artifact of that algorithm, not the gas's density dependence) against u - u' > 0, log axes, +- standard error (a); each against the dilute kernel (b), errors combined as if independent (the kernels share their scenes: an upper bound); bins grouped 20 per decade, groups with relative error above 0.5 left out".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![
                Panel::new(
                    "kernels",
                    Axis::log(DU_AXIS),
                    Axis::log(G_AXIS),
                    vec![("", Style::Band)],
                ),
                Panel::new(
                    "ratio",
                    Axis::log(DU_AXIS),
                    Axis::linear("G(ρl) / G(dilute)"),
                    vec![(DILUTE, Style::Line)],
                ),
            ],
        }
    }

    /// Panel (a): each kernel's resolved groups; panel (b): each over the
    /// dilute kernel (the first input) on coarser groups both resolve, the
    /// dilute one as the line at 1.
    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::figures::points::{X, Y, Y_ERROR};
        let labels = &self.labels;
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
}

/// Legend label of the dilute kernel in [`KernelsAtDensity`].
pub const DILUTE: &str = "dilute";

/// Kernel groups per decade of the ratios to the dilute kernel: the ratio
/// changes slowly, and coarser groups resolve it better.
const RATIO_GROUPS_PER_DECADE: f64 = 5.0;
