//! The paper table: every row's relative difference and z-score recomputed
//! here from its published value and ours, and ours read back from the
//! artifacts it comes from (moments at the paper's truncation, the sweep's
//! detailed-balance pair, the compared rings' final time, the N2 gas).

use std::fs;
use std::path::{Path, PathBuf};

use arrow::array::RecordBatch;
use ternary::contract;
use ternary::pipeline::table::read_parquet;

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
    assert_eq!(quantities.len(), 5, "{quantities:?}");
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
        assert!(
            o.stderr > 0.0 && p.stderr > 0.0,
            "{}: errors on both sides",
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
    // The detailed-balance pair of the sweep.
    {
        use contract::sweep::detailed_balance::{A, B, RATIO};
        let balance = table(&store, "sweep", "ipp-6", "detailed_balance");
        let (a, b) = (A.read(&balance).unwrap(), B.read(&balance).unwrap());
        let pair = (0..a.len())
            .position(|j| a[j] == -3.0 && (b[j] + 2.96).abs() < 1e-9)
            .unwrap();
        let k = row("G(-3.00");
        assert_eq!(ours[k].mean, RATIO.read(&balance).unwrap()[pair].mean);
        assert!(converged[k].mean.is_nan(), "one definition");
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
