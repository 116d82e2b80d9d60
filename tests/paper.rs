//! The paper table: every row's relative difference and z-score recomputed
//! here from its published value and ours, and ours read back from the
//! artifacts it comes from (moments at the paper's truncation, the
//! detailed-balance pair from scenes drawn for it, the compared rings' final time, the scaling ratio
//! from the gases table and from MD, the N2 gas).

use std::fs;
use std::path::{Path, PathBuf};

use arrow::array::RecordBatch;
use ternary::binning::Bins;
use ternary::contract;
use ternary::kernel::{Target, histograms};
use ternary::pipeline::table::read_parquet;
use ternary::pipeline::{Input, InstanceId};
use ternary::stages::kernel::collision_events;
use ternary::stats::Estimate;

mod common;

use common::{REDUCED_STUDY, stdout, ternary, workspace, write_config};

/// The table `name` of the artifact a ref names (`<stage>/<instance>`).
fn table(store: &Path, stage: &str, instance: &str, name: &str) -> RecordBatch {
    let reference: serde_json::Value = serde_json::from_str(
        &fs::read_to_string(store.join(format!("refs/{stage}/{instance}.json"))).unwrap(),
    )
    .unwrap();
    let dir: PathBuf = store
        .join("artifacts")
        .join(stage)
        .join(reference["key"].as_str().unwrap());
    read_parquet(&dir.join(format!("{name}.parquet")))
        .unwrap()
        .0
}

/// The `[[md.system]]` parameters of a ring, from its md artifact.
fn md_params(store: &Path, ring: &str) -> serde_json::Value {
    let reference: serde_json::Value = serde_json::from_str(
        &fs::read_to_string(store.join(format!("refs/md/{ring}.json"))).unwrap(),
    )
    .unwrap();
    let manifest = store
        .join("artifacts/md")
        .join(reference["key"].as_str().unwrap())
        .join("manifest.json");
    let manifest: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(manifest).unwrap()).unwrap();
    manifest["params"].clone()
}

/// The self variance rate (mean, stderr) of a moments table at truncation `x`.
fn rate_at(moments: &RecordBatch, x: f64) -> (f64, f64) {
    use contract::moments::{SELF_VARIANCE, TRUNCATION};
    let row = TRUNCATION
        .read(moments)
        .unwrap()
        .iter()
        .position(|t| (t - x).abs() <= 1e-12 * x)
        .unwrap_or_else(|| panic!("no truncation {x}"));
    let rate = SELF_VARIANCE.read(moments).unwrap()[row];
    (rate.mean, rate.stderr)
}

fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

#[test]
fn paper_rows_recompute_from_their_sources() {
    use contract::paper::*;
    let dir = workspace("paper");
    let config = write_config(&dir, REDUCED_STUDY);
    let run = ternary(&config, &["run"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        stdout(&run).contains("the paper (Phys. Rev. E 110, 014114)"),
        "{}",
        stdout(&run)
    );
    let store = dir.join("data");
    let paper = table(&store, "paper", "study", "paper");
    let quantities = QUANTITY.read(&paper).unwrap();
    let published = PUBLISHED.read(&paper).unwrap();
    let ours = OURS.read(&paper).unwrap();
    let converged = OURS_CONVERGED.read(&paper).unwrap();
    let relative = RELATIVE_DIFFERENCE.read(&paper).unwrap();
    let z = Z.read(&paper).unwrap();
    assert_eq!(quantities.len(), 7, "{quantities:?}");
    // The scaling rows compare with an exact prediction, 8^(1/2 - 1/6) = 2.
    let exact = |q: &str| q.starts_with("Gamma(2 rho, 800 meV)");
    for k in 0..quantities.len() {
        let (p, o) = (published[k], ours[k]);
        let expected_z = (o.mean - p.mean) / (o.stderr * o.stderr + p.stderr * p.stderr).sqrt();
        assert!(
            close(z[k], expected_z),
            "{}: z {} != {expected_z}",
            quantities[k],
            z[k]
        );
        assert!(
            close(relative[k], o.mean / p.mean - 1.0),
            "{}",
            quantities[k]
        );
        let published_error = if exact(&quantities[k]) {
            p.mean == 2.0 && p.stderr == 0.0
        } else {
            p.stderr > 0.0
        };
        assert!(
            o.stderr > 0.0 && published_error,
            "{}: errors on both sides (none for an exact prediction)",
            quantities[k]
        );
    }
    let row = |start: &str| {
        quantities
            .iter()
            .position(|q| q.starts_with(start))
            .unwrap_or_else(|| panic!("no row `{start}` in {quantities:?}"))
    };
    // a_6 and the Lennard-Jones rate: the moments at X = 0.04 and at the window edge.
    for (start, instance) in [("a_6", "ipp-6_u0_rho0"), ("a: self", "lj-0.1_u0_rho0")] {
        let moments = table(&store, "moments", instance, "moments");
        let k = row(start);
        assert_eq!(
            (ours[k].mean, ours[k].stderr),
            rate_at(&moments, 0.04),
            "{start}"
        );
        assert_eq!(
            (converged[k].mean, converged[k].stderr),
            rate_at(&moments, 0.1),
            "{start}"
        );
    }
    // The detailed-balance pair: from launches drawn for u' = -3, recomputed
    // here from the full histograms of those scenes; the sweep's own row
    // (its launch mixture) in the note.
    {
        use contract::sweep::detailed_balance::{A, B, RATIO};
        let events = table(&store, "collisions", "ipp-6_u-3", "events");
        let input = Input {
            id: InstanceId::new("collisions", "ipp-6_u-3"),
            tables: [("events".to_string(), events)].into(),
        };
        let (events, draws, _) = collision_events(&input).unwrap();
        let (a, b, width) = (-3.0, -2.96, 0.005);
        let bins = Bins::for_window(2.0 * (b - a) + 4.0 * width, width);
        let steps = ((b - a) / width).round() as usize;
        let self_kernel = |from: f64, k: usize| -> Vec<f64> {
            histograms(&events, &Target::dilute(from), &bins, &draws)
                .iter()
                .map(|h| h.self_part[k] / width)
                .collect()
        };
        let expected = Estimate::paired_ratio(
            &self_kernel(a, bins.half_bins + steps),
            &self_kernel(b, bins.half_bins - steps),
        );
        let k = row("G(-3.00");
        assert!(
            close(ours[k].mean, expected.mean) && close(ours[k].stderr, expected.stderr),
            "{:?} vs {expected:?}",
            ours[k]
        );
        assert!(converged[k].mean.is_nan(), "one definition");
        // Drawn for u' = -3: the thermal launches overtake the special
        // particle at relative speeds near +3.
        let launches = table(&store, "launches", "ipp-6_u-3", "launches");
        let u2 = contract::launches::U2.read(&launches).unwrap();
        let mean = u2.iter().sum::<f64>() / u2.len() as f64;
        assert!(mean > 2.5, "mean launch speed {mean}");
        let balance = table(&store, "sweep", "ipp-6", "detailed_balance");
        let (first, second) = (A.read(&balance).unwrap(), B.read(&balance).unwrap());
        let pair = (0..first.len())
            .position(|j| first[j] == a && (second[j] - b).abs() < 1e-9)
            .unwrap();
        let grid = RATIO.read(&balance).unwrap()[pair];
        let note = &NOTE.read(&paper).unwrap()[k];
        assert!(
            note.contains(&format!("{:.3} +- {:.3}", grid.mean, grid.stderr)),
            "{note}"
        );
    }
    // Gamma t_f = a_6(0.04) rho^2 l v_th t_f of the compared rings.
    {
        use contract::compare::finite_size::SCALED_TIME;
        let rings = table(&store, "compare", "study", "finite_size");
        let time = SCALED_TIME.read(&rings).unwrap()[0];
        let (a, a_error) = rate_at(&table(&store, "moments", "ipp-6_u0_rho0", "moments"), 0.04);
        let k = row("Gamma t_f");
        assert!(close(ours[k].mean, a * time) && close(ours[k].stderr, a_error * time));
    }
    // Gamma(2 rho, 8 T) / Gamma(2 rho, T): ring6_dense_hot over ring6_dense.
    let (cold, hot) = ("ring6_dense", "ring6_dense_hot");
    {
        use contract::gases::{GAMMA, GAMMA_AT_DENSITY, GAS};
        let gases = table(&store, "gases", "study", "gases");
        let names = GAS.read(&gases).unwrap();
        let of = |column: &contract::Pair, gas: &str| {
            column.read(&gases).unwrap()[names.iter().position(|n| n == gas).unwrap()]
        };
        let (dense_cold, dense_hot) = (of(&GAMMA_AT_DENSITY, cold), of(&GAMMA_AT_DENSITY, hot));
        let k = row("Gamma(2 rho, 800 meV) / Gamma(2 rho, 100 meV), n = 6, kernels");
        // The gases table rounds a_n times rho^2 l v_th once more than the paper stage.
        assert!(
            (ours[k].mean / (dense_hot.mean / dense_cold.mean) - 1.0).abs() < 1e-12,
            "{:?} against the gases table's {dense_hot:?} / {dense_cold:?}",
            ours[k]
        );
        // Both rates come from one set of scenes: positively correlated, so
        // the paired error lies below the independent propagation.
        let independent = dense_hot.mean / dense_cold.mean
            * libm::hypot(
                dense_hot.stderr / dense_hot.mean,
                dense_cold.stderr / dense_cold.mean,
            );
        assert!(
            ours[k].stderr < independent,
            "{:?} vs {independent}",
            ours[k]
        );
        // Dilute: the same a_6 in both, so exactly the scaling, 8^(1/3).
        let dilute = of(&GAMMA, hot).mean / of(&GAMMA, cold).mean;
        assert!(close(converged[k].mean, dilute) && converged[k].stderr == 0.0);
        assert!((dilute - 2.0).abs() < 1e-12, "{dilute}");
    }
    {
        use contract::compare::finite_size::{MD_VARIANCE, RING};
        let rings = table(&store, "compare", "study", "finite_size");
        let names = RING.read(&rings).unwrap();
        let variance = |ring: &str| {
            MD_VARIANCE.read(&rings).unwrap()[names.iter().position(|n| n == ring).unwrap()]
        };
        let time = |ring: &str| md_params(&store, ring)["final_time_ns"].as_f64().unwrap();
        let (v_cold, v_hot) = (variance(cold), variance(hot));
        let ratio = (v_hot.mean / time(hot)) / (v_cold.mean / time(cold));
        let error = ratio * libm::hypot(v_hot.stderr / v_hot.mean, v_cold.stderr / v_cold.mean);
        let k = row("Gamma(2 rho, 800 meV) / Gamma(2 rho, 100 meV), n = 6, MD");
        assert!(close(ours[k].mean, ratio) && close(ours[k].stderr, error));
        assert!(converged[k].mean.is_nan(), "one definition");
    }
    // 1/Gamma of N2 in seconds, Gamma = a(0.04) rho^2 l v_th from the gas's own units.
    {
        use contract::gases::{DENSITY, GAS, LENGTH_UNIT, THERMAL_SPEED};
        let gases = table(&store, "gases", "study", "gases");
        let g = GAS
            .read(&gases)
            .unwrap()
            .iter()
            .position(|n| n == "N2_10K")
            .unwrap();
        let rho = DENSITY.read(&gases).unwrap()[g];
        let l = LENGTH_UNIT.read(&gases).unwrap()[g];
        let v = THERMAL_SPEED.read(&gases).unwrap()[g];
        let (a, _) = rate_at(
            &table(&store, "moments", "lj-0.1052_u0_rho0", "moments"),
            0.04,
        );
        let seconds = 1e-9 / (a * rho * rho * l * v);
        let k = row("1/Gamma of 1D N2");
        assert!(
            (ours[k].mean / seconds - 1.0).abs() < 1e-12,
            "{} s != {seconds} s",
            ours[k].mean
        );
    }
}

/// Every ring at `u' = 0.5`: valid, so the study runs (before: 15 instances,
/// then "paper[study]: no compared ring", no figures). The paper row that
/// compares a ring at `u' = 0` says "no ring"; the finite-size figure, which
/// has no ring to draw, is not planned.
#[test]
fn a_study_without_a_ring_at_rest_runs_and_says_no_ring() {
    let dir = workspace("paper-no-ring");
    let study = REDUCED_STUDY.replace("[[md.system]]\n", "[[md.system]]\nu_prime = 0.5\n");
    assert!(study.matches("u_prime = 0.5").count() >= 2);
    let config = write_config(&dir, &study);
    let run = ternary(&config, &["run"]);
    let text = stdout(&run);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let row = text
        .lines()
        .find(|line| line.contains("Gamma t_f of the MD rings"))
        .expect("the ring row");
    assert!(row.contains(" - "), "{row}");
    assert!(text.contains("no ring: no [[md.system]]"), "{text}");
    assert!(
        !dir.join("data/artifacts/figures")
            .join("finite_size")
            .exists()
    );
    assert!(!text.contains("figures[finite_size]"), "{text}");
}
