//! `figures`: one instance per figure. Its table (`points.parquet`) is built
//! with polars from the tables of the artifacts it draws; its files are the
//! figure drawn from that table as SVG and PNG, one journal column wide and at
//! a screen size ([`crate::figures`]).

use serde_json::{Value, json};

use crate::config::{MdParams, Study};
use crate::contract::instances;
use crate::contract::{self, TableSpec};
use crate::figures::{DILUTE, Figure, FigureRows, Size, frames, render};
use crate::physics::potential::{Family, Potential};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};

/// The figure table's name (`points.parquet`).
const POINTS: &str = "points";

/// Metadata key of the figure's layout (panels, axis labels with units, log
/// scales, marks) in `points.parquet`.
const AXES: &str = "ternary.axes";

/// The `figures` stage for one figure.
pub struct FiguresStage {
    figure: Figure,
    inputs: Vec<InstanceId>,
}

impl FiguresStage {
    /// The stage drawing `figure` from `inputs` (in the figure's input order).
    pub fn new(figure: Figure, inputs: Vec<InstanceId>) -> FiguresStage {
        FiguresStage { figure, inputs }
    }

    /// The figure table's declaration; each table carries its own figure's
    /// description.
    const SPEC: TableSpec = TableSpec {
        stage: contract::figures::STAGE,
        name: POINTS,
        description: "the points a figure draws",
    };
}

/// The figures of a study whose inputs `plan` computes: kernels of every
/// scale-free potential with kicks (the inverse power laws) and, per family
/// with a temperature in its shape, of its every `theta`; for `n = 6` (or the first such potential) the
/// kernel with its fit, the rates against `u'` and `a_n(X)`; MD against
/// Boltzmann for the compared ring.
pub fn figure_stages(study: &Study, plan: &[Box<dyn Stage>]) -> Vec<FiguresStage> {
    let present = |id: &InstanceId| plan.iter().any(|stage| stage.id() == *id);
    let kicked: Vec<Potential> = study
        .potentials()
        .into_iter()
        .filter(|p| !p.family().is_integrable())
        .collect();
    let target = |stage: &str, p: &Potential| {
        InstanceId::new(
            stage,
            &instances::target(&study.kernel_params(*p, 0.0, 0.0)),
        )
    };
    let mut figures = Vec::new();
    let (at_theta, scale_free): (Vec<Potential>, Vec<Potential>) =
        kicked.iter().partition(|p| p.family().theta().is_some());
    let kernels = |potentials: &[Potential]| -> (Vec<String>, Vec<InstanceId>) {
        let labels = potentials.iter().map(|p| p.family().label()).collect();
        let inputs = potentials
            .iter()
            .map(|p| target(contract::kernel::STAGE, p))
            .collect();
        (labels, inputs)
    };
    if !scale_free.is_empty() {
        let (labels, inputs) = kernels(&scale_free);
        figures.push(FiguresStage::new(Figure::KernelsEveryN { labels }, inputs));
    }
    let mut families: Vec<&dyn Family> = Vec::new();
    for p in &at_theta {
        if families.iter().all(|f| f.name() != p.family().name()) {
            families.push(p.family());
        }
    }
    for family in families {
        let members: Vec<Potential> = at_theta
            .iter()
            .filter(|p| p.family().name() == family.name())
            .copied()
            .collect();
        let (labels, inputs) = kernels(&members);
        let figure = Figure::KernelsAtTheta {
            family: family.name().into(),
            prefix: family.id().split('-').next().unwrap_or_default().into(),
            unit: family.length_unit().into(),
            labels,
        };
        figures.push(FiguresStage::new(figure, inputs));
    }
    let main = kicked
        .iter()
        .find(|p| **p == Potential::inverse_power(6.0))
        .or(kicked.first());
    if let Some(p) = main {
        let (id, label) = (p.id(), p.family().label());
        figures.push(FiguresStage::new(
            Figure::KernelFit {
                id: id.clone(),
                label: label.clone(),
            },
            vec![
                target(contract::kernel::STAGE, p),
                target(contract::fit::STAGE, p),
            ],
        ));
        figures.push(FiguresStage::new(
            Figure::Truncation {
                id: id.clone(),
                label: label.clone(),
            },
            vec![target(contract::moments::STAGE, p)],
        ));
        let sweep = InstanceId::new(contract::sweep::STAGE, &id);
        if present(&sweep) {
            figures.push(FiguresStage::new(Figure::Rates { id, label }, vec![sweep]));
        }
    }
    if let Some(p) = main {
        let u_primes: Vec<f64> = study
            .kernel_targets()
            .into_iter()
            .filter(|(_, density)| *density == 0.0)
            .map(|(u_prime, _)| u_prime)
            .collect();
        if u_primes.len() > 1 {
            let inputs = u_primes
                .iter()
                .map(|&u| {
                    let params = study.kernel_params(*p, u, 0.0);
                    InstanceId::new(contract::kernel::STAGE, &instances::target(&params))
                })
                .collect();
            figures.push(FiguresStage::new(
                Figure::KernelsAtUPrime {
                    id: p.id(),
                    u_primes,
                },
                inputs,
            ));
        }
        let scan = instances::scan(p);
        if present(&scan) {
            figures.push(FiguresStage::new(Figure::Kicks { id: p.id() }, vec![scan]));
        }
    }
    if let Some(evolve) = study.evolve_params() {
        let instance = instances::target(&evolve.kernel);
        let id = InstanceId::new(contract::evolve::STAGE, &instance);
        if present(&id) && !evolve.times.is_empty() {
            let times = spread(&evolve.times, EVOLUTION_CURVES);
            figures.push(FiguresStage::new(
                Figure::Evolution { instance, times },
                vec![id],
            ));
        }
    }
    if let Some(figure) = kernels_at_density(study) {
        figures.push(figure);
    }
    let compare = instances::compare();
    let rings = study.md_params();
    if let (true, Some(first)) = (present(&compare), rings.first()) {
        figures.push(FiguresStage::new(
            Figure::MdBoltzmann {
                ring: first.name.clone(),
            },
            vec![compare.clone()],
        ));
        let compared = study.compared_rings();
        let compared: Vec<&MdParams> = compared.iter().collect();
        let collapsing = study.collapse_rings();
        if collapsing.len() > 1 {
            let rings = collapsing.iter().map(|r| r.name.clone()).collect();
            let labels = collapsing.iter().map(ring_label).collect();
            figures.push(FiguresStage::new(
                Figure::Collapse { rings, labels },
                vec![compare.clone()],
            ));
        }
        if let Some(figure) = md_times(&compared) {
            figures.push(FiguresStage::new(figure, vec![compare.clone()]));
        }
        // Finite size compares the rings at u' = 0: none, no figure.
        if !compared.is_empty() {
            figures.push(FiguresStage::new(Figure::FiniteSize, vec![compare]));
        }
    }
    figures
}

/// `G(0 -> u)` of the collapse rings' potential in the dilute limit and at
/// each of those rings' own `rho l` (the kernel instances `plan` adds for
/// them), when the potential kicks.
fn kernels_at_density(study: &Study) -> Option<FiguresStage> {
    let rings = study.collapse_rings();
    let potential = rings.first()?.potential;
    if potential.family().is_integrable() {
        return None;
    }
    let instance = |density: f64| {
        let params = study.kernel_params(potential, 0.0, density);
        InstanceId::new(contract::kernel::STAGE, &instances::target(&params))
    };
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
            Figure::KernelsAtDensity {
                id: potential.id(),
                labels,
            },
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
        Some(Figure::MdTimes {
            ring: group.last().map(|r| r.name.clone()).unwrap_or_default(),
            rings: group.iter().map(|r| r.name.clone()).collect(),
            times_ns: group.iter().map(|r| r.final_time_ns).collect(),
        })
    })
}

/// Curves of `h(u, t)` in the evolution figure, at most.
const EVOLUTION_CURVES: usize = 5;

/// At most `count` of `values`, spread evenly over them, first and last included.
fn spread(values: &[f64], count: usize) -> Vec<f64> {
    if values.len() <= count {
        return values.to_vec();
    }
    let last = values.len() - 1;
    let mut picked: Vec<f64> = (0..count)
        .map(|k| values[(k * last + (count - 1) / 2) / (count - 1)])
        .collect();
    picked.dedup();
    picked
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for FiguresStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(contract::figures::STAGE, &self.figure.name())
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        json!({ "figure": self.figure, "layout": self.figure.layout() })
    }

    fn tables(&self) -> &'static [&'static str] {
        &[POINTS]
    }

    fn files(&self) -> Vec<String> {
        let name = self.figure.name();
        [Size::COLUMN_SVG.suffix, Size::SCREEN.suffix]
            .iter()
            .flat_map(|suffix| [format!("{name}{suffix}.svg"), format!("{name}{suffix}.png")])
            .collect()
    }

    fn inputs(&self) -> Vec<InstanceId> {
        self.inputs.clone()
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let frame = self.figure.frame(inputs)?;
        let points = frames::points(&frame)?;
        progress.advance(1);
        let layout = serde_json::to_string(&self.figure.layout())
            .map_err(|error| StageError::Input(format!("figure layout: {error}")))?;
        let table = FigureRows::table(&points, &Self::SPEC, &self.figure.description())?
            .with_metadata(AXES, layout);
        Ok(vec![table])
    }

    fn render(&self, tables: &[Table]) -> Result<Vec<(String, Vec<u8>)>, StageError> {
        let points = FigureRows::read(&tables[0])?;
        render(&self.figure.name(), &self.figure.layout(), &points)
            .map_err(|error| StageError::Input(format!("drawing {}: {error}", self.figure.name())))
    }
}
