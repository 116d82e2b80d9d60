//! Figures: every figure table holds exactly the numbers of the artifacts it
//! draws (recomputed here from those artifacts' own tables), every PNG decodes
//! at its configured size with every series' colour on it, and every SVG
//! parses as XML with one legend entry per series.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

use arrow_array::RecordBatch;
use serde_json::Value;
use ternary::contract::{self, Pair};
use ternary::figures::{PALETTE, Size};
use ternary::kernel::model::Part;
use ternary::pipeline::table::read_parquet;

mod common;

use common::{REDUCED_STUDY, run_counts, small_study, stdout, ternary, workspace, write_config};

/// One stored artifact: its directory and manifest.
struct Artifact {
    dir: PathBuf,
    manifest: Value,
}

impl Artifact {
    fn table(&self, name: &str) -> RecordBatch {
        read_parquet(&self.dir.join(format!("{name}.parquet")))
            .unwrap()
            .0
    }

    /// The `k`-th input artifact.
    fn input(&self, store: &Path, k: usize) -> Artifact {
        let input = &self.manifest["inputs"][k];
        artifact(
            &store
                .join("artifacts")
                .join(input["stage"].as_str().unwrap())
                .join(input["key"].as_str().unwrap()),
        )
    }

    fn kind(&self) -> &str {
        self.manifest["params"]["figure"]["kind"].as_str().unwrap()
    }

    fn name(&self) -> &str {
        self.manifest["instance"].as_str().unwrap()
    }

    fn panels(&self) -> u32 {
        self.manifest["params"]["layout"]["panels"]
            .as_array()
            .unwrap()
            .len() as u32
    }
}

fn artifact(dir: &Path) -> Artifact {
    let manifest =
        serde_json::from_str(&fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    Artifact {
        dir: dir.to_path_buf(),
        manifest,
    }
}

fn figures(store: &Path) -> Vec<Artifact> {
    let mut dirs: Vec<PathBuf> = fs::read_dir(store.join("artifacts/figures"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .collect();
    dirs.sort();
    dirs.iter().map(|dir| artifact(dir)).collect()
}

/// A plotted row: panel, series, x, y, error of y.
type Row = (String, String, f64, f64, f64);

fn points(figure: &Artifact) -> Vec<Row> {
    use contract::figures::points::{PANEL, SERIES, X, Y, Y_ERROR};
    let batch = figure.table("points");
    let (panels, series) = (PANEL.read(&batch).unwrap(), SERIES.read(&batch).unwrap());
    let (x, y, e) = (
        X.read(&batch).unwrap(),
        Y.read(&batch).unwrap(),
        Y_ERROR.read(&batch).unwrap(),
    );
    (0..batch.num_rows())
        .map(|k| (panels[k].clone(), series[k].clone(), x[k], y[k], e[k]))
        .collect()
}

/// The rows of one series: `x` from a column, `y` and its error from a pair.
fn rows(panel: &str, series: &str, x: &[f64], y: &[ternary::stats::Estimate]) -> Vec<Row> {
    x.iter()
        .zip(y)
        .map(|(x, y)| (panel.into(), series.into(), *x, y.mean, y.stderr))
        .collect()
}

fn pair_rows(batch: &RecordBatch, panel: &str, series: &str, x: &[f64], pair: &Pair) -> Vec<Row> {
    rows(panel, series, x, &pair.read(batch).unwrap())
}

/// The rows of one ring of a comparison table as a series against `du`.
fn ring_rows(
    compare: &RecordBatch,
    ring: &str,
    panel: &str,
    series: &str,
    pair: &Pair,
) -> Vec<Row> {
    use contract::compare::comparison::{DU, RING};
    let names = RING.read(compare).unwrap();
    pair_rows(compare, panel, series, &DU.read(compare).unwrap(), pair)
        .into_iter()
        .zip(&names)
        .filter(|(_, name)| *name == ring)
        .map(|(row, _)| row)
        .collect()
}

/// A group of bins: the `x` of each, and per randomization the sum of `G`
/// and the count.
type Group = (Vec<f64>, BTreeMap<u32, (f64, f64)>);

/// `G(0 -> u)` at `du > 0` averaged over groups of 1/20 decade of `du`,
/// in order ([`grouped_side`]).
fn grouped_kernel(kernel: &Artifact, panel: &str, series: &str) -> Vec<Row> {
    grouped_side(kernel, panel, series, 1.0, 20.0)
}

/// The bins at `sign du > 0`, against `x = |du|`, in groups of 1/`per_decade`
/// decade counted down from the largest `x` (bin in group `ceil(per_decade
/// log10(x / x_max))`), ascending: mean `x`, and the mean and standard error
/// of the randomizations' own group means of `G` (from
/// `kernel_replicates.parquet`).
fn grouped_side(
    kernel: &Artifact,
    panel: &str,
    series: &str,
    sign: f64,
    per_decade: f64,
) -> Vec<Row> {
    use contract::kernel::DU;
    use contract::kernel::replicates::{G, RANDOMIZATION};
    let batch = kernel.table("kernel_replicates");
    let du = DU.read(&batch).unwrap();
    let (randomization, g) = (RANDOMIZATION.read(&batch).unwrap(), G.read(&batch).unwrap());
    let largest = du.iter().map(|d| sign * d).fold(0.0, f64::max);
    let mut groups: BTreeMap<i64, Group> = BTreeMap::new();
    for k in 0..du.len() {
        let x = sign * du[k];
        if x <= 0.0 {
            continue;
        }
        let group = (per_decade * libm::log10(x / largest)).ceil() as i64;
        let (xs, sums) = groups.entry(group).or_default();
        if randomization[k] == 0 {
            xs.push(x);
        }
        let (sum, count) = sums.entry(randomization[k]).or_default();
        *sum += g[k];
        *count += 1.0;
    }
    groups
        .values()
        .map(|(xs, sums)| {
            let means: Vec<f64> = sums.values().map(|(sum, count)| sum / count).collect();
            let r = means.len() as f64;
            let mean = means.iter().sum::<f64>() / r;
            let variance = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (r - 1.0);
            (
                panel.into(),
                series.into(),
                xs.iter().sum::<f64>() / xs.len() as f64,
                mean,
                (variance / r).sqrt(),
            )
        })
        .collect()
}

/// The rows a figure must hold, from its input artifacts' tables.
fn expected(store: &Path, figure: &Artifact) -> Vec<Row> {
    let params = &figure.manifest["params"]["figure"];
    match figure.kind() {
        "kernels_every_n" | "kernels_at_theta" => params["labels"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
            .flat_map(|(k, label)| {
                let groups =
                    grouped_kernel(&figure.input(store, k), "kernels", label.as_str().unwrap());
                groups.into_iter().filter(|row| row.4 < 0.5 * row.3)
            })
            .collect(),
        "kernel_fit" => {
            use contract::fit::{ALPHA, BETA, RANGE_MAX, RANGE_MIN, SIGMA};
            let measured = grouped_kernel(&figure.input(store, 0), "kernel", "Monte Carlo");
            let fit = figure.input(store, 1).table("fit");
            let first = |col: contract::Col<f64>| col.read(&fit).unwrap()[0];
            let (alpha, beta, sigma) = (first(ALPHA.value), first(BETA.value), first(SIGMA.value));
            let range = first(RANGE_MIN)..=first(RANGE_MAX);
            let line: Vec<Row> = measured
                .iter()
                .filter(|row| range.contains(&row.2))
                .map(|row| {
                    let x = row.2;
                    let y = alpha * libm::pow(x, -beta) * libm::exp(-x * x / (2.0 * sigma * sigma));
                    ("kernel".into(), "fit".into(), x, y, 0.0)
                })
                .collect();
            // The whole kernel's model: its group means and residuals above
            // u', as the fit stage's kernel_model_groups holds them.
            use contract::fit::model_groups::{DU, G_MODEL, RESIDUAL};
            let groups = figure.input(store, 1).table("kernel_model_groups");
            let (du, model, residual) = (
                DU.read(&groups).unwrap(),
                G_MODEL.read(&groups).unwrap(),
                RESIDUAL.read(&groups).unwrap(),
            );
            let total = contract::fit::part_rows(&groups, Part::Total).unwrap();
            let above = || total.iter().copied().filter(|&k| du[k] > 0.0);
            let series = |panel: &str, values: &[f64]| -> Vec<Row> {
                above()
                    .map(|k| (panel.into(), "model".into(), du[k], values[k], 0.0))
                    .collect()
            };
            [
                measured,
                line,
                series("kernel", &model),
                series("residuals", &residual),
            ]
            .concat()
        }
        "rates" => {
            use contract::sweep::rates::{FOKKER_PLANCK_DRIFT, SELF_DRIFT, SELF_VARIANCE, U_PRIME};
            let sweep = figure.input(store, 0).table("rates");
            let u = U_PRIME.read(&sweep).unwrap();
            [
                pair_rows(&sweep, "variance", "D2 (Monte Carlo)", &u, &SELF_VARIANCE),
                pair_rows(&sweep, "drift", "D1 (Monte Carlo)", &u, &SELF_DRIFT),
                pair_rows(
                    &sweep,
                    "drift",
                    "Fokker-Planck (D2' − u D2)/2",
                    &u,
                    &FOKKER_PLANCK_DRIFT,
                ),
            ]
            .concat()
        }
        "truncation" => {
            use contract::moments::{SELF_VARIANCE, TRUNCATION};
            let moments = figure.input(store, 0).table("moments");
            let x = TRUNCATION.read(&moments).unwrap();
            let label = params["label"].as_str().unwrap();
            rows("a_n", label, &x, &SELF_VARIANCE.read(&moments).unwrap())
                .into_iter()
                .filter(|row| row.2.is_finite())
                .collect()
        }
        "md_boltzmann" => {
            use contract::compare::comparison::{H_BOLTZMANN, H_PUBLISHED, H_TAGGED};
            let compare = figure.input(store, 0).table("comparison");
            let ring = params["ring"].as_str().unwrap();
            let pick = |series: &str, panel: &str, pair: &Pair| {
                ring_rows(&compare, ring, panel, series, pair)
            };
            [
                pick("Boltzmann", "tagged", &H_BOLTZMANN),
                pick("MD, tagged particles", "tagged", &H_TAGGED),
                pick("Boltzmann", "published", &H_BOLTZMANN),
                pick("MD, published estimator", "published", &H_PUBLISHED),
            ]
            .concat()
        }
        "kicks" => {
            use contract::scan::LAUNCH;
            use contract::scan::curve::{LAUNCH_DELAY, U1_FINAL, U1_FINAL_ERROR};
            let curve = figure.input(store, 0).table("curve");
            let launches = LAUNCH.read(&curve).unwrap();
            let (delay, kick, bound) = (
                LAUNCH_DELAY.read(&curve).unwrap(),
                U1_FINAL.read(&curve).unwrap(),
                U1_FINAL_ERROR.read(&curve).unwrap(),
            );
            in_order(&launches)
                .iter()
                .flat_map(|launch| {
                    (0..launches.len())
                        .filter(|&k| launches[k] == *launch)
                        .map(|k| ("kick".into(), launch.clone(), delay[k], kick[k], bound[k]))
                        .collect::<Vec<Row>>()
                })
                .collect()
        }
        "collapse" => {
            use contract::compare::comparison::{H_BOLTZMANN, H_TAGGED};
            let compare = figure.input(store, 0).table("comparison");
            let of = |ring: &str, series: &str, pair: &Pair| {
                ring_rows(&compare, ring, "collapse", series, pair)
            };
            let rings = texts(&params["rings"]);
            let mut rows = of(rings[0], "Boltzmann", &H_BOLTZMANN);
            for (ring, label) in rings.iter().zip(texts(&params["labels"])) {
                rows.extend(of(ring, label, &H_TAGGED));
            }
            rows
        }
        "evolution" => {
            use contract::evolve::{TIME_GAMMA, early_evolution, early_summary, evolution};
            let input = figure.input(store, 0);
            let h = input.table("evolution");
            let (time, u) = (TIME_GAMMA.read(&h).unwrap(), evolution::U.read(&h).unwrap());
            let tagged = evolution::H_TAGGED.read(&h).unwrap();
            let f0 = evolution::EQUILIBRIUM_TAGGED.read(&h).unwrap();
            let times: Vec<f64> = params["times"]
                .as_array()
                .unwrap()
                .iter()
                .map(|t| t.as_f64().unwrap())
                .collect();
            let mut rows: Vec<Row> = Vec::new();
            for t in &times {
                let label = format!("t = {t} / Γ");
                rows.extend((0..u.len()).filter(|&k| time[k] == *t).map(|k| {
                    (
                        "h".into(),
                        label.clone(),
                        u[k],
                        tagged[k].mean,
                        tagged[k].stderr,
                    )
                }));
            }
            rows.extend(
                (0..u.len())
                    .filter(|&k| time[k] == times[0])
                    .map(|k| ("h".into(), "f0".into(), u[k], f0[k], 0.0)),
            );
            let early = input.table("early_summary");
            let t = TIME_GAMMA.read(&early).unwrap();
            rows.extend(pair_rows(
                &early,
                "variance",
                "master equation",
                &t,
                &early_summary::VARIANCE,
            ));
            rows.extend(pair_rows(
                &early,
                "variance",
                "t κ₂",
                &t,
                &early_summary::VARIANCE_CLOSED_FORM,
            ));
            // Panel (c): each early h scaled to unit variance within 5 of
            // its standard deviations, then the standard normal density.
            let fine = input.table("early_evolution");
            let (at, du, values) = (
                TIME_GAMMA.read(&fine).unwrap(),
                early_evolution::DU.read(&fine).unwrap(),
                early_evolution::H.read(&fine).unwrap(),
            );
            let variances = early_summary::VARIANCE.read(&early).unwrap();
            for (time, variance) in t.iter().zip(&variances) {
                let s = variance.mean.sqrt();
                let shown: f64 = format!("{time:.2e}").parse().unwrap();
                let label = format!("t = {shown} / Γ");
                rows.extend(
                    (0..du.len())
                        .filter(|&k| at[k] == *time && (du[k] / s).abs() <= 5.0)
                        .map(|k| {
                            let h = values[k];
                            (
                                "early".into(),
                                label.clone(),
                                du[k] / s,
                                h.mean * s,
                                h.stderr * s,
                            )
                        }),
                );
            }
            rows.extend((-100..=100).map(|k| {
                let x = 5.0 * f64::from(k) / 100.0;
                let density = libm::exp(-0.5 * x * x) / libm::sqrt(2.0 * std::f64::consts::PI);
                ("early".into(), "standard normal".into(), x, density, 0.0)
            }));
            rows
        }
        "finite_size" => {
            use contract::compare::finite_size::{
                DENSITY, PARTICLES, RATIO, SCALED_TIME, THERMAL_RATIO,
            };
            let rings = figure.input(store, 0).table("finite_size");
            let particles = PARTICLES.read(&rings).unwrap();
            let density = DENSITY.read(&rings).unwrap();
            // Only the rings at the median scaled time, N ascending.
            let times = SCALED_TIME.read(&rings).unwrap();
            let mut sorted = times.clone();
            sorted.sort_by(f64::total_cmp);
            let median = sorted[sorted.len() / 2];
            let drawn: Vec<bool> = times
                .iter()
                .map(|t| (t - median).abs() <= 1e-6 * median)
                .collect();
            let mut counts = in_order(&particles);
            counts.sort_unstable();
            let mut rows = Vec::new();
            for (panel, pair) in [("tagged", RATIO), ("thermal", THERMAL_RATIO)] {
                let all = pair_rows(&rings, panel, "", &density, &pair);
                for &n in &counts {
                    rows.extend(
                        all.iter()
                            .zip(particles.iter().zip(&drawn))
                            .filter(|(_, (p, drawn))| **p == n && **drawn)
                            .map(|(row, _)| {
                                (row.0.clone(), format!("N = {n}"), row.2, row.3, row.4)
                            }),
                    );
                }
            }
            rows
        }
        "kernels_at_u_prime" => params["u_primes"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
            .flat_map(|(k, u)| {
                let kernel = figure.input(store, k);
                // Labels print a minus sign, as typeset.
                let u = u.as_f64().unwrap().to_string().replace('-', "\u{2212}");
                let name = format!("u' = {u}");
                let above = grouped_side(&kernel, "above", &name, 1.0, 20.0);
                let below = grouped_side(&kernel, "below", &name, -1.0, 20.0);
                [above, below]
                    .concat()
                    .into_iter()
                    .filter(|row| row.4 < 0.5 * row.3)
            })
            .collect(),
        "kernels_at_density" => {
            // Groups whose relative error is below 0.5, as drawn.
            let resolved = |rows: Vec<Row>| -> Vec<Row> {
                rows.into_iter().filter(|row| row.4 < 0.5 * row.3).collect()
            };
            let labels = texts(&params["labels"]);
            let kernels: Vec<Artifact> =
                (0..labels.len()).map(|k| figure.input(store, k)).collect();
            let mut rows: Vec<Row> = labels
                .iter()
                .zip(&kernels)
                .flat_map(|(label, kernel)| resolved(grouped_kernel(kernel, "kernels", label)))
                .collect();
            // Panel (b): 5 groups per decade, each kernel over the dilute one
            // (the first), errors combined as if independent.
            let coarse = |kernel: &Artifact, label: &str| {
                resolved(grouped_side(kernel, "ratio", label, 1.0, 5.0))
            };
            let dilute = coarse(&kernels[0], labels[0]);
            for (k, (label, kernel)) in labels.iter().zip(&kernels).enumerate() {
                for row in coarse(kernel, label) {
                    if let Some(d) = dilute.iter().find(|d| d.2 == row.2) {
                        let ratio = row.3 / d.3;
                        let error = if k == 0 {
                            0.0
                        } else {
                            ratio.abs() * libm::hypot(row.4 / row.3, d.4 / d.3)
                        };
                        rows.push(("ratio".into(), label.to_string(), row.2, ratio, error));
                    }
                }
            }
            rows
        }
        "md_times" => {
            use contract::compare::comparison::{H_BOLTZMANN, H_TAGGED};
            let compare = figure.input(store, 0).table("comparison");
            let of = |ring: &str, series: &str, pair: &Pair| {
                ring_rows(&compare, ring, "h", series, pair)
            };
            let rings = params["rings"].as_array().unwrap();
            let times = params["times_ns"].as_array().unwrap();
            let mut rows = Vec::new();
            for (ring, time) in rings.iter().zip(times) {
                let (ring, time) = (ring.as_str().unwrap(), time.as_f64().unwrap());
                rows.extend(of(ring, &format!("Boltzmann, {time} ns"), &H_BOLTZMANN));
                rows.extend(of(ring, &format!("MD, {time} ns"), &H_TAGGED));
            }
            rows
        }
        "spectrum" => {
            use contract::spectrum::{modes, rates, scenes, summary};
            let input = figure.input(store, 0);
            let (rate_table, mode_table) = (input.table("spectrum"), input.table("spectrum_modes"));
            let (scene_table, summary_table) = (
                input.table("spectrum_scenes"),
                input.table("spectrum_summary"),
            );
            let generators = summary::GENERATOR.read(&summary_table).unwrap();
            let mut rows = Vec::new();
            for (name, title) in [("full", "linearized operator"), ("tagged", "one particle")] {
                assert!(generators.iter().any(|g| g == name));
                let of = |batch: &RecordBatch, col: contract::Col<String>| -> Vec<bool> {
                    col.read(batch).unwrap().iter().map(|g| g == name).collect()
                };
                let (mine, k) = (
                    of(&rate_table, rates::GENERATOR),
                    rates::MODE.read(&rate_table).unwrap(),
                );
                let ratio = rates::RATE_OVER_VARIANCE_RATE.read(&rate_table).unwrap();
                for i in (0..k.len()).filter(|&i| mine[i] && k[i] <= 10) {
                    rows.push((
                        "rates".into(),
                        title.into(),
                        f64::from(k[i]),
                        ratio[i].mean,
                        ratio[i].stderr,
                    ));
                }
                let (mine, k) = (
                    of(&mode_table, modes::GENERATOR),
                    modes::MODE.read(&mode_table).unwrap(),
                );
                let (u, density) = (
                    modes::U.read(&mode_table).unwrap(),
                    modes::DENSITY.read(&mode_table).unwrap(),
                );
                for mode in 1..=2 {
                    let series = format!("{title}, mode {mode}");
                    for i in (0..k.len()).filter(|&i| mine[i] && k[i] == mode) {
                        rows.push((
                            "modes".into(),
                            series.clone(),
                            u[i],
                            density[i].mean,
                            density[i].stderr,
                        ));
                    }
                }
                let (mine, k) = (
                    of(&scene_table, scenes::GENERATOR),
                    scenes::MODE.read(&scene_table).unwrap(),
                );
                let sizes = scenes::RANDOMIZATIONS.read(&scene_table).unwrap();
                let rate = scenes::RATE.read(&scene_table).unwrap();
                let slowest: Vec<usize> = (0..k.len()).filter(|&i| mine[i] && k[i] == 1).collect();
                // Over the slowest rate from every randomization: the largest group.
                let all = slowest
                    .iter()
                    .max_by_key(|&&i| sizes[i])
                    .map(|&i| rate[i].mean);
                let all = all.unwrap();
                for i in slowest {
                    let error = if rate[i].stderr.is_finite() {
                        rate[i].stderr / all
                    } else {
                        0.0
                    };
                    rows.push((
                        "scenes".into(),
                        title.into(),
                        f64::from(sizes[i]),
                        rate[i].mean / all,
                        error,
                    ));
                }
            }
            rows
        }
        "gaps" => {
            use contract::spectrum::study::{
                GAP, GAP_OVER_VARIANCE_RATE, PARTICLE_GAP, PARTICLE_GAP_OVER_VARIANCE_RATE,
            };
            use contract::table::{A_N, N, THETA};
            let table = figure.input(store, 0).table("table");
            let n = N.optional(&table).unwrap();
            let theta = THETA.optional(&table).unwrap();
            let mut rows = Vec::new();
            for (panel, series, pair, positive) in [
                (
                    "ratio",
                    "gas (linearized operator)",
                    GAP_OVER_VARIANCE_RATE,
                    false,
                ),
                (
                    "ratio",
                    "one particle",
                    PARTICLE_GAP_OVER_VARIANCE_RATE,
                    false,
                ),
                ("rates", "gas (linearized operator)", GAP, true),
                ("rates", "one particle", PARTICLE_GAP, true),
                ("rates", "a_n (Γ)", A_N, true),
            ] {
                for (i, value) in pair.read(&table).unwrap().into_iter().enumerate() {
                    let drawn = theta[i].is_none()
                        && value.mean.is_finite()
                        && (!positive || value.mean > 0.0);
                    if let (true, Some(n)) = (drawn, n[i]) {
                        rows.push((panel.into(), series.into(), n, value.mean, value.stderr));
                    }
                }
            }
            rows
        }
        "near_integrable" => near_integrable_rows(&figure.input(store, 0)),
        "pulls" => pulls_rows(&figure.input(store, 0)),
        other => panic!("figure kind `{other}` has no check here"),
    }
}

/// The pulls figure's points, counted here from the pulls table: bins of
/// 0.5 on [-4, 4] (the outer ones open), each a density +- its Poisson
/// error, then the standard normal density on a grid of 0.05.
fn pulls_rows(input: &Artifact) -> Vec<Row> {
    use contract::pulls::checks::PULL;
    let pulls: Vec<f64> = PULL
        .read(&input.table("pulls"))
        .unwrap()
        .into_iter()
        .filter(|p| p.is_finite())
        .collect();
    let per_pull = 1.0 / (pulls.len() as f64 * 0.5);
    let series = format!("{} pulls", pulls.len());
    let mut rows: Vec<Row> = (0..16)
        .map(|k| {
            let low = -4.0 + 0.5 * f64::from(k);
            let inside = pulls
                .iter()
                .filter(|&&p| (k == 0 || p >= low) && (k == 15 || p < low + 0.5))
                .count() as f64;
            let density = inside * per_pull;
            (
                "pulls".into(),
                series.clone(),
                low + 0.25,
                density,
                inside.sqrt() * per_pull,
            )
        })
        .collect();
    rows.extend((0..=160).map(|k| {
        let x = -4.0 + 0.05 * f64::from(k);
        let density = libm::exp(-0.5 * x * x) / libm::sqrt(2.0 * std::f64::consts::PI);
        ("pulls".into(), "N(0, 1)".into(), x, density, 0.0)
    }));
    rows
}

/// A JSON array of strings.
fn texts(array: &Value) -> Vec<&str> {
    array
        .as_array()
        .unwrap()
        .iter()
        .map(|text| text.as_str().unwrap())
        .collect()
}

/// The near-integrable figure's rows from its stage's tables: per quantity
/// the rates positive by three standard errors, then its law `A x^p e^(q x)`
/// on 49 log-spaced `x = n - 2` across them, where fitted.
fn near_integrable_rows(input: &Artifact) -> Vec<Row> {
    use contract::near_integrable::{fits, rates};
    let (points, laws) = (
        input.table(rates::TABLE.name),
        input.table(fits::TABLE.name),
    );
    let excess = rates::EXCESS.read(&points).unwrap();
    let mut rows = Vec::new();
    for (k, (panel, label, pair)) in [
        ("rates", "Γ", rates::VARIANCE_RATE),
        ("rates", "gas (linearized operator)", rates::GAP),
        ("rates", "one particle", rates::PARTICLE_GAP),
        (
            "ratio",
            "gas (linearized operator)",
            rates::GAP_OVER_VARIANCE_RATE,
        ),
        (
            "ratio",
            "one particle",
            rates::PARTICLE_GAP_OVER_VARIANCE_RATE,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let values = pair.read(&points).unwrap();
        let resolved: Vec<usize> = (0..values.len())
            .filter(|&i| values[i].stderr > 0.0 && values[i].mean > 3.0 * values[i].stderr)
            .collect();
        for &i in &resolved {
            let series = format!("spectrum, {label}");
            rows.push((
                panel.into(),
                series,
                excess[i],
                values[i].mean,
                values[i].stderr,
            ));
        }
        let exponent = fits::EXPONENT.read(&laws).unwrap()[k];
        if !exponent.mean.is_finite() {
            continue;
        }
        let amplitude = fits::AMPLITUDE.read(&laws).unwrap()[k].mean;
        let correction = fits::CORRECTION.read(&laws).unwrap()[k].mean;
        let xs: Vec<f64> = resolved.iter().map(|&i| excess[i]).collect();
        let low = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let high = xs.iter().copied().fold(0.0, f64::max);
        let series = format!(
            "fit, p = {:.3} ± {:.3}, {label}",
            exponent.mean, exponent.stderr
        );
        for j in 0..=48 {
            let x = low * libm::pow(high / low, j as f64 / 48.0);
            let y = amplitude * libm::pow(x, exponent.mean) * libm::exp(correction * x);
            rows.push((panel.into(), series.clone(), x, y, 0.0));
        }
    }
    rows
}

/// The distinct values of `values` in order of first appearance.
fn in_order<T: PartialEq + Clone>(values: &[T]) -> Vec<T> {
    let mut distinct: Vec<T> = Vec::new();
    for value in values {
        if !distinct.contains(value) {
            distinct.push(value.clone());
        }
    }
    distinct
}

/// Equal as numbers: exactly, or for group means (summed in another order
/// by polars) to a few ulps.
fn same(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-13 * a.abs().max(b.abs())
}

/// The reduced study computed in a workspace of its own, `name`.
fn reduced_study(name: &str) -> PathBuf {
    let dir = workspace(name);
    let config = write_config(&dir, REDUCED_STUDY);
    let output = ternary(&config, &["run", "--quiet"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    dir.join("data")
}

/// Every figure kind of src/figures/ (an `impl FigureKind for <Kind>` each,
/// one file per kind) as it is serialized: `<Kind>` in snake case.
fn figure_kinds() -> BTreeSet<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/figures");
    let mut kinds = BTreeSet::new();
    for entry in fs::read_dir(dir).unwrap() {
        let text = fs::read_to_string(entry.unwrap().path()).unwrap_or_default();
        let implemented = text.lines().filter_map(|line| {
            line.strip_prefix("impl FigureKind for ")?
                .strip_suffix(" {")
        });
        for kind in implemented {
            let mut snake = String::new();
            for (k, c) in kind.chars().enumerate() {
                if c.is_uppercase() && k > 0 {
                    snake.push('_');
                }
                snake.push(c.to_ascii_lowercase());
            }
            kinds.insert(snake);
        }
    }
    kinds
}

#[test]
fn every_figure_table_holds_its_sources_numbers() {
    let store = reduced_study("figures-tables");
    let all = figures(&store);
    let kinds: BTreeSet<String> = all.iter().map(|f| f.kind().to_string()).collect();
    assert_eq!(kinds, figure_kinds(), "the reduced study draws every kind");
    for figure in &all {
        let (got, want) = (points(figure), expected(&store, figure));
        assert_eq!(got.len(), want.len(), "{}: rows", figure.name());
        assert!(!got.is_empty(), "{}", figure.name());
        for (g, w) in got.iter().zip(&want) {
            let close =
                g.0 == w.0 && g.1 == w.1 && same(g.2, w.2) && same(g.3, w.3) && same(g.4, w.4);
            assert!(close, "{}: {g:?} != {w:?}", figure.name());
        }
    }
    let kernels = fs::read_dir(store.join("artifacts").join("kernel")).unwrap();
    for dir in kernels {
        log_table_holds_the_groups(&artifact(&dir.unwrap().path()));
    }
}

/// A kernel's `kernel_log` table: below `u'` then above, the groups the
/// figures draw (recomputed here from the replicates), each as wide as its
/// fine bins together; the groups hold the fine bins' whole measure, the
/// centre bin aside.
fn log_table_holds_the_groups(kernel: &Artifact) {
    use contract::kernel::log::{BINS, DU, DU_INNER, DU_OUTER, TABLE, WIDTH};
    let batch = kernel.table(TABLE.name);
    let (du, inner, outer, width, bins) = (
        DU.read(&batch).unwrap(),
        DU_INNER.read(&batch).unwrap(),
        DU_OUTER.read(&batch).unwrap(),
        WIDTH.read(&batch).unwrap(),
        BINS.read(&batch).unwrap(),
    );
    let g = contract::kernel::G.value.read(&batch).unwrap();
    let errors = contract::kernel::G.stderr.read(&batch).unwrap();
    let mut below = grouped_side(kernel, "", "", -1.0, 20.0);
    below.reverse();
    let above = grouped_side(kernel, "", "", 1.0, 20.0);
    let expected: Vec<(f64, Row)> = below
        .into_iter()
        .map(|row| (-1.0, row))
        .chain(above.into_iter().map(|row| (1.0, row)))
        .collect();
    assert_eq!(du.len(), expected.len(), "{}", kernel.name());
    let fine = kernel.table(contract::kernel::TABLE.name);
    let fine_du = contract::kernel::DU.read(&fine).unwrap();
    let bin_width = fine_du[1] - fine_du[0];
    for (k, (side, row)) in expected.iter().enumerate() {
        assert!(
            same(du[k], side * row.2),
            "{}: {} vs {}",
            kernel.name(),
            du[k],
            row.2
        );
        assert!(
            same(g[k], row.3) && same(errors[k], row.4),
            "{}: row {k}",
            kernel.name()
        );
        assert!((width[k] - f64::from(bins[k]) * bin_width).abs() < 1e-9 * width[k]);
        assert!((outer[k] - inner[k] - side * width[k]).abs() < 1e-12);
        assert!(side * inner[k] >= 0.5 * bin_width - 1e-12 && side * du[k] > side * inner[k]);
    }
    let measure = |values: &[f64], widths: &[f64]| -> f64 {
        values.iter().zip(widths).map(|(v, w)| v * w).sum()
    };
    let fine_g = contract::kernel::G.value.read(&fine).unwrap();
    let off_centre: Vec<f64> = fine_du
        .iter()
        .zip(&fine_g)
        .map(|(d, v)| if d.abs() < 0.5 * bin_width { 0.0 } else { *v })
        .collect();
    let (grouped, all) = (
        measure(&g, &width),
        measure(&off_centre, &vec![bin_width; off_centre.len()]),
    );
    let scale: f64 = off_centre.iter().map(|v| (v * bin_width).abs()).sum();
    assert!(
        (grouped - all).abs() <= 1e-9 * scale,
        "{}: {grouped} vs {all}",
        kernel.name()
    );
}

/// The colours a figure's panels must show: one per series, or one per
/// pair of series named alike after their last `", "` in a paired panel.
fn colours_per_panel(figure: &Artifact) -> Vec<Vec<[u8; 3]>> {
    let layout = &figure.manifest["params"]["layout"]["panels"];
    series_per_panel(figure)
        .iter()
        .enumerate()
        .map(|(k, names)| {
            let paired = layout[k]["paired"].as_bool().unwrap_or(false);
            let mut keys: Vec<&str> = Vec::new();
            for name in names {
                let key = match name.rsplit_once(", ") {
                    Some((_, pair)) if paired => pair,
                    _ => name,
                };
                if !keys.contains(&key) {
                    keys.push(key);
                }
            }
            PALETTE[..keys.len()]
                .iter()
                .map(|c| [c.0, c.1, c.2])
                .collect()
        })
        .collect()
}

/// The series of each panel of a figure, in legend order.
fn series_per_panel(figure: &Artifact) -> Vec<Vec<String>> {
    let rows = points(figure);
    let mut panels: Vec<(String, Vec<String>)> = Vec::new();
    for (panel, series, ..) in rows {
        match panels.iter_mut().find(|(name, _)| *name == panel) {
            Some((_, names)) if names.contains(&series) => {}
            Some((_, names)) => names.push(series),
            None => panels.push((panel, vec![series])),
        }
    }
    panels.into_iter().map(|(_, names)| names).collect()
}

/// A journal column, cm: the printed width of a column figure.
const COLUMN_CM: f64 = 8.6;

/// The resolution a PNG's `pHYs` chunk states: px per metre along x and y.
fn stated_resolution(reader: &png::Reader<std::io::BufReader<fs::File>>) -> (u32, u32) {
    let dims = reader.info().pixel_dims.expect("a pHYs chunk");
    assert_eq!(dims.unit, png::Unit::Meter);
    (dims.xppu, dims.yppu)
}

#[test]
fn every_png_decodes_at_its_size_and_resolution_with_every_series_drawn() {
    let store = reduced_study("figures-png");
    for figure in figures(&store) {
        let colours: BTreeSet<[u8; 3]> = colours_per_panel(&figure).into_iter().flatten().collect();
        // 600 dpi on paper, 96 on a screen: 600 / 0.0254 m and 96 / 0.0254 m.
        for (size, per_metre) in [(Size::COLUMN_PNG, 23622), (Size::SCREEN, 3780)] {
            let file = figure
                .dir
                .join(format!("{}{}.png", figure.name(), size.suffix));
            let decoder =
                png::Decoder::new(std::io::BufReader::new(fs::File::open(&file).unwrap()));
            let mut reader = decoder.read_info().unwrap();
            let what = file.display();
            assert_eq!(stated_resolution(&reader), (per_metre, per_metre), "{what}");
            let mut pixels = vec![0; reader.output_buffer_size()];
            let frame = reader.next_frame(&mut pixels).unwrap();
            assert_eq!(
                (frame.width, frame.height),
                (size.width, size.panel_height * figure.panels()),
                "{what}"
            );
            if size == Size::COLUMN_PNG {
                // Width over resolution: the printed width, within 0.1 mm.
                let width_cm = 100.0 * f64::from(frame.width) / f64::from(per_metre);
                assert!((width_cm - COLUMN_CM).abs() < 0.01, "{what}: {width_cm} cm");
            }
            assert_eq!(frame.color_type, png::ColorType::Rgb, "{what}");
            let rgb: Vec<[u8; 3]> = pixels.chunks(3).map(|p| [p[0], p[1], p[2]]).collect();
            let inked = rgb.iter().filter(|p| **p != [255, 255, 255]).count();
            assert!(
                inked * 100 > rgb.len(),
                "{what}: blank ({inked} pixels inked)"
            );
            for colour in &colours {
                let drawn = rgb.iter().filter(|p| *p == colour).count();
                assert!(
                    drawn > 100,
                    "{what}: series colour {colour:?} drawn on {drawn} pixels"
                );
            }
        }
    }
}

/// The vertices of an SVG `points` attribute scaled by `px_per_unit`.
fn vertices(points: &str, px_per_unit: f64) -> Vec<(f64, f64)> {
    points
        .split_whitespace()
        .map(|pair| {
            let (x, y) = pair.split_once(',').unwrap();
            let coordinate = |v: &str| v.parse::<f64>().unwrap() * px_per_unit;
            (coordinate(x), coordinate(y))
        })
        .collect()
}

/// A column SVG's long lines (100 vertices or more) keep their shape: in
/// pixels of the figure, their vertices carry fractions of a pixel and are
/// distinct (not snapped onto a staircase); returns how many it has.
fn long_lines_are_smooth(root: roxmltree::Node, what: &str) -> usize {
    let view_width: f64 = root
        .attribute("viewBox")
        .unwrap()
        .split_whitespace()
        .nth(2)
        .unwrap()
        .parse()
        .unwrap();
    let px_per_unit = root.attribute("width").unwrap().parse::<f64>().unwrap() / view_width;
    let lines: Vec<Vec<(f64, f64)>> = root
        .descendants()
        .filter(|node| node.has_tag_name("polyline"))
        .map(|node| vertices(node.attribute("points").unwrap(), px_per_unit))
        .filter(|line| line.len() >= 100)
        .collect();
    for line in &lines {
        let fractional = line
            .iter()
            .filter(|(x, y)| x.fract() != 0.0 || y.fract() != 0.0)
            .count();
        assert!(
            fractional * 2 > line.len(),
            "{what}: {fractional} of {} vertices off whole pixels",
            line.len()
        );
        let mut distinct: Vec<(f64, f64)> = line.clone();
        distinct.sort_by(|a, b| a.partial_cmp(b).unwrap());
        distinct.dedup();
        assert!(
            distinct.len() * 100 >= line.len() * 98,
            "{what}: {} distinct of {} vertices",
            distinct.len(),
            line.len()
        );
    }
    lines.len()
}

#[test]
fn every_svg_parses_with_one_legend_entry_per_series_in_dejavu_sans_and_smooth_lines() {
    let store = reduced_study("figures-svg");
    let mut long_lines = 0;
    for figure in figures(&store) {
        let panels = series_per_panel(&figure);
        for size in [Size::COLUMN_SVG, Size::SCREEN] {
            let file = figure
                .dir
                .join(format!("{}{}.svg", figure.name(), size.suffix));
            let text = fs::read_to_string(&file).unwrap();
            let document = roxmltree::Document::parse(&text).unwrap();
            let root = document.root_element();
            let what = file.display();
            assert_eq!(root.tag_name().name(), "svg", "{what}");
            let height = (size.panel_height * figure.panels()).to_string();
            assert_eq!(
                root.attribute("width"),
                Some(size.width.to_string().as_str()),
                "{what}"
            );
            assert_eq!(root.attribute("height"), Some(height.as_str()), "{what}");
            for text in root.descendants().filter(|node| node.has_tag_name("text")) {
                let family = text.attribute("font-family").unwrap();
                assert!(family.starts_with("'DejaVu Sans', "), "{what}: {family}");
                assert!(family.ends_with(", sans-serif"), "{what}: {family}");
            }
            if size == Size::COLUMN_SVG {
                long_lines += long_lines_are_smooth(root, &what.to_string());
            }
            let labels: Vec<String> = root
                .descendants()
                .filter(|node| node.has_tag_name("text"))
                .filter_map(|node| node.text().map(|t| t.trim().to_string()))
                .collect();
            for names in &panels {
                for name in names {
                    let entries = labels.iter().filter(|label| *label == name).count();
                    let panels_with_it = panels.iter().filter(|p| p.contains(name)).count();
                    assert_eq!(
                        entries, panels_with_it,
                        "{what}: legend entries of `{name}`"
                    );
                }
            }
            let colours: BTreeSet<[u8; 3]> =
                colours_per_panel(&figure).into_iter().flatten().collect();
            for (k, colour) in colours.iter().enumerate() {
                let hex = format!("#{:02X}{:02X}{:02X}", colour[0], colour[1], colour[2]);
                assert!(text.contains(&hex), "{what}: series {k} ({hex}) not drawn");
            }
        }
    }
    assert!(long_lines > 0, "no long line to check");
}

#[test]
fn a_new_potential_redraws_only_the_figures_that_show_it() {
    let dir = workspace("figures-redraw");
    let config = write_config(&dir, &small_study("data"));
    let (computed, _) = run_counts(&config, &[]);
    assert!(computed > 0);
    let with_n8 = small_study("data").replace("inverse_power = [6]", "inverse_power = [6, 8]");
    write_config(&dir, &with_n8);
    let status = stdout(&ternary(&config, &["status"]));
    let line = |id: &str| {
        status
            .lines()
            .find(|line| line.starts_with(id))
            .unwrap_or_else(|| panic!("{id} in {status}"))
            .to_string()
    };
    assert!(line("figures[kernels] ").contains("stale"), "{status}");
    assert!(
        line("figures[kernel_fit_ipp-6] ").contains("fresh"),
        "{status}"
    );
    assert!(
        line("figures[truncation_ipp-6] ").contains("fresh"),
        "{status}"
    );
    run_counts(&config, &[]);
    let (computed, _) = run_counts(&config, &[]);
    assert_eq!(computed, 0, "a second run recomputes nothing");
}

/// `bench integrators --figures DIR` draws the work-precision curves it
/// measured: both files at both sizes, the PNG at its size with each
/// method's colour, the SVG with one legend entry per method, and every
/// method's table row in the report (10 tolerances each).
#[test]
fn bench_draws_its_work_precision_figure() {
    let dir = workspace("bench-figure");
    let output = ternary(
        &dir.join("absent.toml"),
        &[
            "bench",
            "integrators",
            "--scenes",
            "20",
            "--figures",
            dir.to_str().unwrap(),
        ],
    );
    assert!(output.status.success(), "{}", common::stderr(&output));
    let report = stdout(&output);
    let methods = ["dopri5", "dop853", "dprkn12"];
    for method in methods {
        let rows = report
            .lines()
            .filter(|l| l.starts_with(&format!("| {method} |")))
            .count();
        assert_eq!(rows, 10, "{method}: {report}");
    }
    let name = "work_precision_integrators";
    let png = dir.join(format!("{name}.png"));
    let decoder = png::Decoder::new(std::io::BufReader::new(fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size()];
    let frame = reader.next_frame(&mut pixels).unwrap();
    assert_eq!(
        (frame.width, frame.height),
        (Size::COLUMN_PNG.width, Size::COLUMN_PNG.panel_height)
    );
    for colour in &PALETTE[..methods.len()] {
        let rgb = [colour.0, colour.1, colour.2];
        let drawn = pixels.chunks(3).filter(|p| *p == rgb).count();
        assert!(drawn > 100, "{colour:?} drawn on {drawn} pixels");
    }
    for suffix in ["", "_screen"] {
        let text = fs::read_to_string(dir.join(format!("{name}{suffix}.svg"))).unwrap();
        let document = roxmltree::Document::parse(&text).unwrap();
        for method in methods {
            let entries = document
                .descendants()
                .filter(|node| {
                    node.has_tag_name("text") && node.text().map(str::trim) == Some(method)
                })
                .count();
            assert_eq!(entries, 1, "{method}{suffix}");
        }
    }
}
