//! The paper table: every row's relative difference and z-score recomputed
//! here from its published value and ours, and ours read back from the
//! artifacts it comes from (Table I: moments at the paper's truncation, the
//! shape fit, the scan's largest kick; the detailed-balance pair from scenes
//! drawn for it, the compared rings' final time, the scaling ratio from the
//! gases table and from MD, the N2 gas).

use std::fs;
use std::path::Path;

use arrow_array::RecordBatch;
use ternary::binning::Bins;
use ternary::contract;
use ternary::contract::readers::collision_events;
use ternary::kernel::model::Part;
use ternary::kernel::{Target, histograms};
use ternary::pipeline::{Input, InstanceId};
use ternary::stats::Estimate;

mod common;

use common::{REDUCED_STUDY, stderr, stdout, table, ternary, workspace, write_config};

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
    // The untruncated row's truncation is null: infinity here.
    let row = TRUNCATION
        .optional(moments)
        .unwrap()
        .into_iter()
        .map(|t| t.unwrap_or(f64::INFINITY))
        .position(|t| t == x || (x.is_finite() && (t - x).abs() <= 1e-12 * x))
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
    // The summary shows Table I as the paper prints it: a line per n.
    let summary = stdout(&run);
    let line = |n: &str| {
        summary
            .lines()
            .skip_while(|l| !l.contains("Table I: published | ours (z)"))
            .find(|l| l.split_whitespace().next() == Some(n))
            .unwrap_or_else(|| panic!("no Table I line for n = {n}: {summary}"))
            .to_string()
    };
    assert!(line("6").contains("0.000258 | ") && line("6").contains("0.182 | "));
    assert!(line("2").contains("0 | 0 (+0.0)"), "{}", line("2"));
    let store = dir.join("data");
    let paper = table(&store, "paper", "study", "paper");
    let quantities = QUANTITY.read(&paper).unwrap();
    let published = PUBLISHED.read(&paper).unwrap();
    let ours = OURS.read(&paper).unwrap();
    let converged = OURS_CONVERGED.read(&paper).unwrap();
    let converged_state = CONVERGED.read(&paper).unwrap();
    let relative = RELATIVE_DIFFERENCE.read(&paper).unwrap();
    let z = Z.read(&paper).unwrap();
    let notes = NOTE.read(&paper).unwrap();
    let (cells_n, cells_column) = (
        TABLE_I_N.read(&paper).unwrap(),
        TABLE_I_COLUMN.read(&paper).unwrap(),
    );
    // Table I of the study's n = 2 and 6: a_n, |u1f,max| for both, the
    // shape for n = 6 (blank for n = 2); then the six other rows.
    let table_i: Vec<(f64, &str)> = (0..quantities.len())
        .filter(|&k| cells_n[k].is_finite())
        .map(|k| (cells_n[k], cells_column[k].as_str()))
        .collect();
    assert_eq!(
        table_i,
        [
            (2.0, "a_n"),
            (6.0, "a_n"),
            (6.0, "alpha"),
            (6.0, "beta"),
            (6.0, "sigma"),
            (2.0, "|u1f,max|"),
            (6.0, "|u1f,max|")
        ]
    );
    assert_eq!(quantities.len(), 15, "{quantities:?}");
    // Exact predictions: the scaling rows (8^(1/2 - 1/6) = 2) and a_2 = 0.
    let exact = |k: usize| published[k].stderr == 0.0;
    let by_construction = |q: &str| q.ends_with("scaled kernel (dilute)");
    for k in 0..quantities.len() {
        let (p, o) = (published[k], ours[k]);
        let expected_z = if by_construction(&quantities[k]) {
            f64::NAN
        } else if o.mean == p.mean {
            0.0
        } else {
            (o.mean - p.mean) / (o.stderr * o.stderr + p.stderr * p.stderr).sqrt()
        };
        assert!(
            close(z[k], expected_z) || (z[k].is_nan() && expected_z.is_nan()),
            "{}: z {} != {expected_z}",
            quantities[k],
            z[k]
        );
        if p.mean != 0.0 {
            assert!(
                close(relative[k], o.mean / p.mean - 1.0),
                "{}",
                quantities[k]
            );
        }
        assert!(
            (o.stderr > 0.0 || exact(k)) && (p.stderr > 0.0 || exact(k)),
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
    // a_n and the Lennard-Jones rate: the moments at X = 0.04 and where
    // they have converged: untruncated (kicks reach past the window's edge;
    // the window's rate is in the note).
    for (start, instance) in [
        ("a_2", "ipp-2_u0_rho0"),
        ("a_6", "ipp-6_u0_rho0"),
        ("a: self", "lj-0.1_u0_rho0"),
    ] {
        let moments = table(&store, "moments", instance, "moments");
        let k = row(start);
        assert_eq!(
            (ours[k].mean, ours[k].stderr),
            rate_at(&moments, 0.04),
            "{start}"
        );
        let untruncated = rate_at(&moments, f64::INFINITY);
        assert_eq!((converged[k].mean, converged[k].stderr), untruncated);
        assert_eq!(converged_state[k], "differs");
        let (window, _) = rate_at(&moments, 0.1);
        assert!(
            notes[k].contains(&format!("X = 0.1, the window's edge, gives {window:.4e}")),
            "{window:.4e}: {}",
            notes[k]
        );
    }
    // The integrable n = 2: no kick, a_2 = 0 exactly (z = 0).
    assert_eq!(ours[row("a_2")].mean, 0.0);
    // The shape of n = 6: the fit under the paper's protocol (up to its
    // truncation 0.04) with the statistical error and the half-spread over
    // every protocol of the fit table combined; converged: the study's fit.
    {
        use contract::fit::{ALPHA, BETA, PROTOCOL, RANGE_MAX, SIGMA};
        let fit = table(&store, "fit", "ipp-6_u0_rho0", "fit");
        let protocols = PROTOCOL.read(&fit).unwrap();
        let paper = protocols.iter().position(|p| p == "paper").unwrap();
        assert_eq!(protocols[0], "study");
        assert_eq!(RANGE_MAX.read(&fit).unwrap()[paper], 0.04);
        for (start, pair, summary_pair) in [
            ("alpha", ALPHA, contract::table::ALPHA),
            ("beta", BETA, contract::table::BETA),
            ("sigma", SIGMA, contract::table::SIGMA),
        ] {
            let k = row(&format!("{start}: shape fit, n = 6"));
            let values = pair.read(&fit).unwrap();
            let means: Vec<f64> = values.iter().map(|e| e.mean).collect();
            let spread = 0.5
                * (means.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                    - means.iter().copied().fold(f64::INFINITY, f64::min));
            assert!(protocols.len() >= 10 && spread > 0.0);
            assert_eq!(ours[k].mean, values[paper].mean);
            assert_eq!(ours[k].stderr, libm::hypot(values[paper].stderr, spread));
            assert_eq!(converged[k].mean, values[0].mean);
            assert_eq!(converged_state[k], "differs");
            // The summary table carries the study's fit with both errors.
            let summary = table(&store, "table", "study", "table");
            let potentials = contract::table::POTENTIAL.read(&summary).unwrap();
            let n6 = potentials.iter().position(|p| p == "ipp-6").unwrap();
            let summarized = summary_pair.read(&summary).unwrap()[n6];
            assert_eq!(summarized.mean, values[0].mean);
            assert_eq!(summarized.stderr, libm::hypot(values[0].stderr, spread));
            // The goodness of both fits beside them: chi2/dof with p-values.
            for row in [paper, 0] {
                let dof = contract::fit::BINS.read(&fit).unwrap()[row] - 3;
                let per_dof = contract::fit::CHI2_PER_DOF.read(&fit).unwrap()[row];
                assert!(
                    notes[k].contains(&format!(
                        "chi2/dof = {per_dof:.1} with {dof} degrees of freedom, p = "
                    )),
                    "{}",
                    notes[k]
                );
            }
        }
    }
    // |u1f,max| of the symmetric launch (u2 = 1, u3 = -1) from the scan.
    for n in [2, 6] {
        use contract::scan::peak::{U1_FINAL_MAX_ABS, U2};
        let peaks = table(&store, "scan", &format!("ipp-{n}"), "peak");
        let u2 = U2.read(&peaks).unwrap();
        let u3 = contract::scan::U3.read(&peaks).unwrap();
        let symmetric = (0..u2.len())
            .position(|j| u2[j] == 1.0 && u3[j] == -1.0)
            .unwrap();
        let expected = U1_FINAL_MAX_ABS.read(&peaks).unwrap()[symmetric];
        let k = row(&format!("|u1f,max|, n = {n}"));
        assert_eq!(
            (ours[k].mean, ours[k].stderr),
            (expected.mean, expected.stderr)
        );
    }
    // n = 2 is integrable: the scan's largest kick is rounding, far below
    // the paper's bound of 1e-7.
    assert!(ours[row("|u1f,max|, n = 2")].mean < 1e-10);
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
        let note = &notes[k];
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
        let k = row("Gamma(2 rho, 800 meV) / Gamma(2 rho, 100 meV), n = 6, scaled kernel");
        // At each ring's own rho l (the launch rule's finite-density
        // factor), in the note: "give <ratio> +- <error>".
        let (at_density, error) = notes[k]
            .split_once(" give ")
            .and_then(|(_, rest)| rest.split_once(" (paired"))
            .and_then(|(numbers, _)| numbers.split_once(" +- "))
            .map(|(m, e)| (m.parse::<f64>().unwrap(), e.parse::<f64>().unwrap()))
            .unwrap_or_else(|| panic!("{}", notes[k]));
        // The gases table rounds a_n times rho^2 l v_th once more; the note
        // prints seven decimals.
        assert!(
            (at_density - dense_hot.mean / dense_cold.mean).abs() < 1e-7,
            "{at_density} against the gases table's {dense_hot:?} / {dense_cold:?}"
        );
        // Both rates come from one set of scenes: positively correlated, so
        // the paired error lies below the independent propagation.
        let independent = dense_hot.mean / dense_cold.mean
            * libm::hypot(
                dense_hot.stderr / dense_hot.mean,
                dense_cold.stderr / dense_cold.mean,
            );
        assert!(error < independent, "{error} vs {independent}");
        // Ours is the dilute ratio: by construction, no z.
        assert!(z[k].is_nan() && converged_state[k] == "same");
        // Dilute: the same a_6 in both, so exactly the scaling, 8^(1/3).
        let dilute = of(&GAMMA, hot).mean / of(&GAMMA, cold).mean;
        assert!(close(ours[k].mean, dilute) && ours[k].stderr == 0.0);
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
    // The exponents of Gamma ~ rho^p T^q from the thermal MD rates V(t_f)/t_f
    // of ring6 (rho, T), ring6_dense (2 rho, T), ring6_dense_hot (2 rho, 8 T):
    // three rates fix them, p from the first two, q from the last two.
    {
        use contract::compare::finite_size::{RING, THERMAL_MD_VARIANCE};
        let rings = table(&store, "compare", "study", "finite_size");
        let names = RING.read(&rings).unwrap();
        let rate = |ring: &str| {
            let v = THERMAL_MD_VARIANCE.read(&rings).unwrap()
                [names.iter().position(|n| n == ring).unwrap()];
            let time = md_params(&store, ring)["final_time_ns"].as_f64().unwrap();
            (v.mean / time, v.stderr / v.mean)
        };
        let gas = |ring: &str, key: &str| md_params(&store, ring)["gas"][key].as_f64().unwrap();
        let exponent = |a: &str, b: &str, key: &str| {
            let ((rate_a, relative_a), (rate_b, relative_b)) = (rate(a), rate(b));
            let lever = libm::log(gas(b, key) / gas(a, key));
            (
                libm::log(rate_b / rate_a) / lever,
                libm::hypot(relative_a, relative_b) / lever.abs(),
            )
        };
        for (quantity, (value, error), published) in [
            ("p in Gamma", exponent("ring6", cold, "density_per_um"), 2.0),
            ("q in Gamma", exponent(cold, hot, "kt_ev"), 1.0 / 3.0),
        ] {
            let k = row(quantity);
            assert!(
                (ours[k].mean - value).abs() < 1e-9 && (ours[k].stderr / error - 1.0).abs() < 1e-9,
                "{quantity}: {:?} against {value} +- {error}",
                ours[k]
            );
            assert!(
                (z[k] - (value - published) / error).abs() < 1e-6,
                "{}",
                z[k]
            );
            assert!(notes[k].contains("no chi-square"), "{}", notes[k]);
        }
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
        rate_reproduces_the_nitrogen_row(&config, &store, (ours[k], converged[k]));
    }
    recombination_agrees_between_scene_sets(&store);
    the_study_table_holds_what_its_suppliers_computed(&store);
    pulls_recompute_from_their_sources(&store, &summary);
    kernel_models_fit_their_kernels(&store);
    kernel_command_evaluates_the_stored_model(&config, &store);
    held_out_kernels_recompute_from_the_models(&store);
}

/// `ternary kernel` prints the stored model of a computed kernel, on either
/// side, to the digits of its error (recomputed here from the knots), and
/// refuses a potential or `u'` the study did not compute, naming it.
fn kernel_command_evaluates_the_stored_model(config: &Path, store: &Path) {
    use contract::fit::model::{CUTOFF_SCALE, LN_G, SIDE, T};
    use ternary::kernel::model::NaturalSpline;
    let printed = stdout(&ternary(
        config,
        &["kernel", "--n", "6", "--du", "1e-3", "--du", "-2e-3"],
    ));
    let knots = table(store, "fit", "ipp-6_u0_rho0", "kernel_model");
    let (sides, t, ln_g, scale) = (
        SIDE.read(&knots).unwrap(),
        T.read(&knots).unwrap(),
        LN_G.read(&knots).unwrap(),
        CUTOFF_SCALE.read(&knots).unwrap(),
    );
    let total = contract::fit::part_rows(&knots, Part::Total).unwrap();
    for (du, side) in [(1e-3, "above"), (-2e-3, "below")] {
        let rows: Vec<usize> = total
            .iter()
            .copied()
            .filter(|&k| sides[k] == side)
            .collect();
        let spline = NaturalSpline::through(
            &rows.iter().map(|&k| t[k]).collect::<Vec<f64>>(),
            &rows.iter().map(|&k| ln_g[k].mean).collect::<Vec<f64>>(),
        );
        let x = f64::abs(du);
        let expected = libm::exp(spline.value(libm::log(x) + x / scale[rows[0]]));
        let line = printed
            .lines()
            .find(|l| l.split_whitespace().next() == Some(&format!("{du}")))
            .unwrap_or_else(|| panic!("no line for {du}: {printed}"));
        let words: Vec<&str> = line.split_whitespace().collect();
        let (value, error): (f64, f64) = (words[1].parse().unwrap(), words[3].parse().unwrap());
        assert!(error > 0.0 && error < value, "{line}");
        assert!(
            (value - expected).abs() <= 0.5 * error,
            "{line}: model {expected}"
        );
    }
    parts_add_up(config);
    for (args, named) in [
        (&["kernel", "--n", "7", "--du", "1e-3"][..], "ipp-7"),
        (
            &["kernel", "--n", "6", "--u-prime", "-1.5", "--du", "1e-3"][..],
            "--u-prime -1.5",
        ),
    ] {
        let refused = ternary(config, args);
        assert!(
            !refused.status.success() && stderr(&refused).contains(named),
            "{}",
            stderr(&refused)
        );
    }
}

/// `ternary kernel --part`: the self and bath parts the command prints add
/// up to the whole it prints, within the last digit of each, for a computed
/// kernel (u' = 0.5, where the bath part is not the mirror of anything) and
/// an interpolated one (u' = 0.1, between the computed ones), each with a
/// positive error.
fn parts_add_up(config: &Path) {
    for u_prime in ["0.5", "0.1"] {
        let value = |part: &str, du: &str| -> (f64, f64) {
            let printed = stdout(&ternary(
                config,
                &[
                    "kernel",
                    "--n",
                    "6",
                    "--u-prime",
                    u_prime,
                    "--du",
                    du,
                    "--part",
                    part,
                ],
            ));
            let line = printed
                .lines()
                .find(|l| l.split_whitespace().next() == Some(du))
                .unwrap_or_else(|| panic!("no line for {du}: {printed}"));
            printed_estimate(line)
        };
        for du in ["0.001", "-0.02"] {
            let (whole, whole_error) = value("total", du);
            let (own, own_error) = value("self", du);
            let (bath, bath_error) = value("bath", du);
            assert!(whole_error > 0.0 && own_error > 0.0 && bath_error > 0.0);
            // Each printed to two digits of its error: the sum within them.
            let digits = 0.05 * (whole_error + own_error + bath_error);
            assert!(
                (own + bath - whole).abs() <= digits,
                "u' {u_prime}, du {du}: {own} + {bath} != {whole}"
            );
        }
    }
}

/// The value and error of a `ternary kernel` row (`du`, then `a ± b` or
/// `(a ± b)eN`, then the relative error in %).
fn printed_estimate(line: &str) -> (f64, f64) {
    let words: Vec<&str> = line.split_whitespace().skip(1).collect();
    let end = words.iter().position(|w| w.ends_with('%')).unwrap();
    let text = words[..end].join(" ");
    let (numbers, scale) = match text.split_once(")e") {
        Some((inside, exponent)) => (
            inside.trim_start_matches('('),
            libm::pow(10.0, exponent.parse().unwrap()),
        ),
        None => (text.as_str(), 1.0),
    };
    let (value, error) = numbers
        .split_once(" ± ")
        .unwrap_or_else(|| panic!("{line}"));
    (
        scale * value.parse::<f64>().unwrap(),
        scale * error.parse::<f64>().unwrap(),
    )
}

/// Every kernel of the reduced study but the vanishing n = 2 one has a
/// model of the whole and of its self part that pass their own tests
/// (chi2 within 0.7..1.5 of its expectation under flipped randomizations,
/// p > 0.01), and the stored knots of each reproduce its stored chi2 from
/// `kernel_log` alone (`G`, `G_self`): the spline through `(t, ln_G)` in
/// `t = ln|du| + |du| / cutoff_scale`, straight beyond the end knots,
/// averaged over each group (a 400-point midpoint rule here), against the
/// group means with the variance of each pooled with its neighbours'.
fn kernel_models_fit_their_kernels(store: &Path) {
    use contract::fit::model_fit::*;
    let mut refs: Vec<String> = fs::read_dir(store.join("refs/fit"))
        .unwrap()
        .map(|entry| {
            entry
                .unwrap()
                .path()
                .file_stem()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    refs.sort();
    assert_eq!(refs.len(), 24, "{refs:?}");
    for instance in refs {
        let fit = table(store, "fit", &instance, "kernel_model_fit");
        let groups = table(store, "fit", &instance, "kernel_model_groups");
        for part in Part::MODELLED {
            let row = contract::fit::goodness_row(&fit, part).unwrap();
            let status = &STATUS.read(&fit).unwrap()[row];
            let name = format!("{instance} {}", part.name());
            if instance.starts_with("ipp-2") {
                assert!(
                    status.contains("fewer than three groups"),
                    "{name}: {status}"
                );
                continue;
            }
            assert_eq!(status, "fitted", "{name}");
            let (chi2, expected) = (
                CHI2.read(&fit).unwrap()[row],
                CHI2_EXPECTED.read(&fit).unwrap()[row],
            );
            let p = P_VALUE.read(&fit).unwrap()[row];
            assert!(
                (0.7..=1.5).contains(&(chi2 / expected)) && p > 0.01,
                "{name}: chi2 {chi2}, expected {expected}, p {p}"
            );
            assert_eq!(CONVERGED.read(&fit).unwrap()[row], 1, "{name}");
            let mirrored = MIRRORED.read(&fit).unwrap()[row] == 1;
            let residuals = contract::fit::model_groups::RESIDUAL.read(&groups).unwrap();
            let summed: f64 = contract::fit::part_rows(&groups, part)
                .unwrap()
                .iter()
                .map(|&k| residuals[k] * residuals[k])
                .sum();
            assert!(
                (summed / chi2 - 1.0).abs() < 1e-12,
                "{name}: residuals {summed} != {chi2}"
            );
            let recomputed = model_chi2(store, &instance, part, mirrored);
            assert!(
                (recomputed / chi2 - 1.0).abs() < 1e-6,
                "{name}: {recomputed} != {chi2}"
            );
        }
    }
}

/// The `interpolation` stage of the reduced study (u' = 0, 0.5, -0.25 and
/// their mirror images: five u' nodes) holds out each kernel at u' = 0 and
/// predicts it from the models at u' = -0.5 and 0.25 (mirror images of 0.5
/// and -0.25: their sides swapped), -0.25 and 0.5. Every prediction is recomputed
/// here from the stored knots (a 400-point midpoint rule for the group
/// means, the Lagrange polynomial in u' through their logarithms), and so
/// is its own error estimate (the same without the farthest node); the
/// held-out model is the one its fit stored, every z comes from its
/// columns, and each summary row from its groups.
fn held_out_kernels_recompute_from_the_models(store: &Path) {
    use contract::interpolation::{groups, summary};
    let rows = table(store, "interpolation", "kernels", "kernel_interpolation");
    let (potential, u_prime, density, nodes) = (
        contract::POTENTIAL.read(&rows).unwrap(),
        groups::U_PRIME.read(&rows).unwrap(),
        groups::RHO_L.read(&rows).unwrap(),
        groups::NODES.read(&rows).unwrap(),
    );
    let (du, inner, outer) = (
        groups::DU.read(&rows).unwrap(),
        groups::DU_INNER.read(&rows).unwrap(),
        groups::DU_OUTER.read(&rows).unwrap(),
    );
    let (g, model, predicted, z) = (
        groups::G.read(&rows).unwrap(),
        groups::G_MODEL.read(&rows).unwrap(),
        groups::G_PREDICTED.read(&rows).unwrap(),
        groups::Z.read(&rows).unwrap(),
    );
    let (ln_ratio, correction) = (
        groups::LN_RATIO.read(&rows).unwrap(),
        groups::CORRECTION.read(&rows).unwrap(),
    );
    let coordinate = groups::COORDINATE.read(&rows).unwrap();
    assert!(coordinate.iter().all(|c| c == "u'"), "{coordinate:?}");
    assert!(u_prime.iter().all(|&u| u == 0.0), "{u_prime:?}");
    let held: std::collections::BTreeSet<(String, String)> = (0..potential.len())
        .map(|k| (potential[k].clone(), density[k].to_string()))
        .collect();
    // ipp-6, lj-0.1, lj-0.1052 at both densities (ipp-2 has no model).
    assert_eq!(held.len(), 6, "{held:?}");
    let lagrange = |at: f64, points: &[(f64, f64)]| -> f64 {
        points
            .iter()
            .enumerate()
            .map(|(i, (xi, yi))| {
                let others = points.iter().enumerate().filter(|(j, _)| *j != i);
                yi * others
                    .map(|(_, (xj, _))| (at - xj) / (xi - xj))
                    .product::<f64>()
            })
            .sum()
    };
    for k in 0..potential.len() {
        assert_eq!(
            nodes[k],
            "u' = -0.5 (mirror image), -0.25, 0.25 (mirror image), 0.5"
        );
        let (a, b) = (inner[k].abs(), outer[k].abs());
        assert!(a < du[k].abs() && du[k].abs() < b, "{k}");
        let instance = |u: f64| format!("{}_u{u}_rho{}", potential[k], density[k]);
        // A mirror image's group above u' is its stored kernel's below.
        let side = |mirrored: bool| {
            if (du[k] > 0.0) != mirrored {
                "above"
            } else {
                "below"
            }
        };
        let points: Vec<(f64, f64)> = [
            (-0.5, 0.5, true),
            (-0.25, -0.25, false),
            (0.25, -0.25, true),
            (0.5, 0.5, false),
        ]
        .iter()
        .map(|&(node, stored, mirrored)| {
            let mean = stored_group_mean(store, &instance(stored), side(mirrored), a, b);
            (node, libm::log(mean))
        })
        .collect();
        let expected = libm::exp(lagrange(0.0, &points));
        assert!(
            (predicted[k].mean / expected - 1.0).abs() < 1e-4,
            "{}: {} != {expected}",
            instance(0.0),
            predicted[k].mean
        );
        // The held-out kernel's own model, as its fit stored it.
        let fitted = table(store, "fit", &instance(0.0), "kernel_model_groups");
        let middles = contract::fit::model_groups::DU.read(&fitted).unwrap();
        let row = contract::fit::part_rows(&fitted, Part::Total)
            .unwrap()
            .into_iter()
            .find(|&r| middles[r] == du[k])
            .unwrap();
        let stored = contract::fit::model_groups::G_MODEL.read(&fitted).unwrap()[row];
        assert!((model[k].mean / stored - 1.0).abs() < 1e-12, "{k}");
        // One degree lower: without the farthest node, -0.5 (the first of
        // the two as far).
        let lower = libm::exp(lagrange(0.0, &points[1..]));
        let expected_correction = libm::log(expected / lower);
        assert!((correction[k] - expected_correction).abs() < 1e-4, "{k}");
        let ratio = libm::log(model[k].mean / predicted[k].mean);
        assert!((ln_ratio[k].mean - ratio).abs() < 1e-12, "{k}");
        let stated = libm::hypot(correction[k], predicted[k].stderr / predicted[k].mean);
        assert!((z[k] - ratio / stated).abs() < 1e-9, "{k}");
        assert!(
            g[k].mean > 3.0 * g[k].stderr,
            "an unresolved group compared"
        );
    }
    let summaries = table(
        store,
        "interpolation",
        "kernels",
        "kernel_interpolation_summary",
    );
    let (s_potential, s_density, counts, largest, beyond) = (
        contract::POTENTIAL.read(&summaries).unwrap(),
        summary::RHO_L.read(&summaries).unwrap(),
        summary::GROUPS.read(&summaries).unwrap(),
        summary::LARGEST_ABS_Z.read(&summaries).unwrap(),
        summary::BEYOND_TWO.read(&summaries).unwrap(),
    );
    assert_eq!(s_potential.len(), held.len());
    for s in 0..s_potential.len() {
        let own: Vec<f64> = (0..potential.len())
            .filter(|&k| potential[k] == s_potential[s] && density[k] == s_density[s])
            .map(|k| z[k].abs())
            .collect();
        assert!(own.len() >= 10, "{}: {} groups", s_potential[s], own.len());
        assert_eq!(counts[s] as usize, own.len());
        assert_eq!(largest[s], own.iter().copied().fold(0.0, f64::max));
        assert_eq!(beyond[s] as usize, own.iter().filter(|&&z| z > 2.0).count());
    }
    coordinates_sum_their_kernels(store, &summaries);
}

/// The interpolation's per-coordinate table is its held-out kernels'
/// summary rows summed: kernels, groups, groups beyond 2 and the largest
/// |z| with the kernel it belongs to.
fn coordinates_sum_their_kernels(store: &Path, summaries: &RecordBatch) {
    use contract::interpolation::{coordinates, summary};
    let along = table(
        store,
        "interpolation",
        "kernels",
        "kernel_interpolation_coordinates",
    );
    let coordinate = summary::COORDINATE.read(summaries).unwrap();
    let potential = contract::POTENTIAL.read(summaries).unwrap();
    let groups = summary::GROUPS.read(summaries).unwrap();
    let beyond = summary::BEYOND_TWO.read(summaries).unwrap();
    let largest = summary::LARGEST_ABS_Z.read(summaries).unwrap();
    let names = coordinates::COORDINATE.read(&along).unwrap();
    assert!(!names.is_empty());
    let sums = (
        coordinates::HELD_OUT.read(&along).unwrap(),
        coordinates::GROUPS.read(&along).unwrap(),
        coordinates::BEYOND_TWO.read(&along).unwrap(),
        coordinates::LARGEST_ABS_Z.read(&along).unwrap(),
        coordinates::LARGEST_POTENTIAL.read(&along).unwrap(),
    );
    for (c, name) in names.iter().enumerate() {
        let rows: Vec<usize> = (0..coordinate.len())
            .filter(|&k| &coordinate[k] == name)
            .collect();
        let sum = |of: &[u32]| rows.iter().map(|&k| of[k]).sum::<u32>();
        assert_eq!(sums.0[c] as usize, rows.len(), "{name}");
        assert_eq!(sums.1[c], sum(&groups), "{name}");
        assert_eq!(sums.2[c], sum(&beyond), "{name}");
        let worst = rows
            .iter()
            .copied()
            .fold(rows[0], |w, k| if largest[k] > largest[w] { k } else { w });
        assert_eq!(sums.3[c], largest[worst], "{name}");
        assert_eq!(sums.4[c], potential[worst], "{name}");
    }
}

/// The mean of a stored model's `side` over `[a, b]` (`0 < a < b`): the
/// spline through its knots in `t = ln x + x / cutoff_scale`, exponentiated,
/// by a 400-point midpoint rule.
fn stored_group_mean(store: &Path, instance: &str, side: &str, a: f64, b: f64) -> f64 {
    use contract::fit::model::*;
    use ternary::kernel::model::NaturalSpline;
    let knots = table(store, "fit", instance, "kernel_model");
    let (sides, t, values, scales) = (
        SIDE.read(&knots).unwrap(),
        T.read(&knots).unwrap(),
        LN_G.read(&knots).unwrap(),
        CUTOFF_SCALE.read(&knots).unwrap(),
    );
    let rows: Vec<usize> = contract::fit::part_rows(&knots, Part::Total)
        .unwrap()
        .into_iter()
        .filter(|&k| sides[k] == side)
        .collect();
    let spline = NaturalSpline::through(
        &rows.iter().map(|&k| t[k]).collect::<Vec<f64>>(),
        &rows.iter().map(|&k| values[k].mean).collect::<Vec<f64>>(),
    );
    let scale = scales[rows[0]];
    (0..400)
        .map(|j| {
            let x = a + (f64::from(j) + 0.5) * (b - a) / 400.0;
            libm::exp(spline.value(libm::log(x) + x / scale))
        })
        .sum::<f64>()
        / 400.0
}

/// The chi2 of a kernel's stored model of `part` against its `kernel_log`
/// groups ([`kernel_models_fit_their_kernels`]).
fn model_chi2(store: &Path, instance: &str, part: Part, mirrored: bool) -> f64 {
    use contract::fit::model::*;
    use contract::kernel::log::{DU_INNER, DU_OUTER};
    use ternary::kernel::model::NaturalSpline;
    let knots = table(store, "fit", instance, "kernel_model");
    let log = table(store, "kernel", instance, "kernel_log");
    let (sides, t, values, scales) = (
        SIDE.read(&knots).unwrap(),
        T.read(&knots).unwrap(),
        LN_G.read(&knots).unwrap(),
        CUTOFF_SCALE.read(&knots).unwrap(),
    );
    let (inner, outer) = (DU_INNER.read(&log).unwrap(), DU_OUTER.read(&log).unwrap());
    let g = match part {
        Part::Total => contract::kernel::G,
        Part::SelfPart => contract::kernel::G_SELF,
    }
    .read(&log)
    .unwrap();
    let modelled = contract::fit::part_rows(&knots, part).unwrap();
    let mut chi2 = 0.0;
    for (side, sign) in [("below", -1.0), ("above", 1.0)] {
        if mirrored && side == "below" {
            continue;
        }
        let rows: Vec<usize> = modelled
            .iter()
            .copied()
            .filter(|&k| sides[k] == side)
            .collect();
        let t_side: Vec<f64> = rows.iter().map(|&k| t[k]).collect();
        let ln_g: Vec<f64> = rows.iter().map(|&k| values[k].mean).collect();
        let (spline, scale) = (NaturalSpline::through(&t_side, &ln_g), scales[rows[0]]);
        let model = |x: f64| libm::exp(spline.value(libm::log(x) + x / scale));
        let mut groups: Vec<usize> = (0..g.len()).filter(|&k| sign * inner[k] > 0.0).collect();
        groups.sort_by(|&a, &b| (sign * inner[a]).total_cmp(&(sign * inner[b])));
        // Groups without spread around them carry no error: dropped, then
        // the rest pooled anew.
        let pooled = |groups: &[usize]| -> Vec<f64> {
            let variance: Vec<f64> = groups.iter().map(|&k| g[k].stderr * g[k].stderr).collect();
            (0..variance.len())
                .map(|i| {
                    let window = &variance[i.saturating_sub(1)..(i + 2).min(variance.len())];
                    window.iter().sum::<f64>() / window.len() as f64
                })
                .collect()
        };
        let spread = pooled(&groups);
        groups = (0..groups.len())
            .filter(|&i| spread[i] > 0.0)
            .map(|i| groups[i])
            .collect();
        for (&k, pooled) in groups.iter().zip(pooled(&groups)) {
            let (a, b) = (sign * inner[k], sign * outer[k]);
            let mean = (0..400)
                .map(|j| model(a + (f64::from(j) + 0.5) * (b - a) / 400.0))
                .sum::<f64>()
                / 400.0;
            chi2 += (g[k].mean - mean).powi(2) / pooled;
        }
    }
    chi2
}

/// The `pulls` table holds every cross-check of the study, each pull
/// recomputed here from the tables it compares: the recombination rate of
/// each potential with a well three ways (`moments`, the sweep's and the
/// dissociation's `recombination` tables) and every sweep's joint
/// detailed-balance test that is evidence, against exactly 0. The summary
/// is their count, mean, spread and largest, and its verdict the rule of
/// `calibration` (the reduced study has too few pulls for one); the run
/// prints it.
fn pulls_recompute_from_their_sources(store: &Path, printed: &str) {
    use contract::pulls::{checks, summary};
    let pulls = table(store, "pulls", "study", "pulls");
    let subjects = checks::SUBJECT.read(&pulls).unwrap();
    let firsts = checks::FIRST.read(&pulls).unwrap();
    let seconds = checks::SECOND.read(&pulls).unwrap();
    let values = checks::PULL.read(&pulls).unwrap();
    let checks = checks::CHECK.read(&pulls).unwrap();
    let mut expected: Vec<(String, Estimate, Estimate)> = Vec::new();
    let rates = |stage: &str, instance: &str, at: Option<f64>| {
        use contract::sweep::recombination::{RATE_COLUMN, U_PRIME};
        let table = table(store, stage, instance, "recombination");
        let row = U_PRIME
            .optional(&table)
            .unwrap()
            .iter()
            .position(|u| *u == at)
            .unwrap();
        RATE_COLUMN.read(&table).unwrap()[row]
    };
    for lj in ["lj-0.1", "lj-0.1052"] {
        let moments = table(store, "moments", &format!("{lj}_u0_rho0"), "moments");
        let kernel = contract::moments::RECOMBINATION_RATE
            .read(&moments)
            .unwrap()[0];
        let balanced = |at| rates("dissociation", lj, at);
        expected.push((lj.to_string(), kernel, balanced(Some(0.0))));
        expected.push((
            lj.to_string(),
            rates("sweep", lj, Some(0.0)),
            balanced(Some(0.0)),
        ));
        expected.push((lj.to_string(), rates("sweep", lj, None), balanced(None)));
    }
    let mut sweeps: Vec<String> = fs::read_dir(store.join("refs/sweep"))
        .unwrap()
        .map(|entry| {
            entry
                .unwrap()
                .file_name()
                .to_string_lossy()
                .replace(".json", "")
        })
        .collect();
    sweeps.sort();
    let order = |id: &str| {
        let potentials = ["ipp-2", "ipp-6", "lj-0.1", "lj-0.1052"];
        potentials
            .iter()
            .position(|p| *p == id)
            .unwrap_or_else(|| panic!("{id}"))
    };
    sweeps.sort_by_key(|id| order(id));
    for sweep in &sweeps {
        use contract::sweep::balance_tests::*;
        let tests = table(store, "sweep", sweep, "balance_tests");
        let separations = SEPARATION.read(&tests).unwrap();
        let shares = JOINT_LARGEST_SHARE.read(&tests).unwrap();
        for (k, imbalance) in JOINT_IMBALANCE
            .read(&tests)
            .unwrap()
            .into_iter()
            .enumerate()
        {
            if shares[k] <= 0.5 {
                let subject = format!("{sweep}, separation {}", separations[k]);
                expected.push((
                    subject,
                    imbalance,
                    Estimate {
                        mean: 0.0,
                        stderr: 0.0,
                    },
                ));
            }
        }
    }
    assert_eq!(subjects.len(), expected.len(), "{subjects:?}");
    assert!(
        checks[..6].iter().all(|c| c.contains("recombination")),
        "{checks:?}"
    );
    for (k, (subject, first, second)) in expected.iter().enumerate() {
        assert_eq!(
            (&subjects[k], firsts[k], seconds[k]),
            (subject, *first, *second)
        );
        let pull = (first.mean - second.mean) / libm::hypot(first.stderr, second.stderr);
        assert!(pull.to_bits() == values[k].to_bits() || pull.is_nan() && values[k].is_nan());
    }
    // The recombination rate three ways agrees at both theta within 3
    // combined errors (the default study: within 2 at all 13 theta,
    // docs/lennard-jones.md; the reduced study's sweep has far fewer
    // scenes: its largest, sweep against balance at theta = 0.1, is -2.4).
    for (k, pull) in values[..6].iter().enumerate() {
        assert!(pull.abs() < 3.0, "{}: {} = {pull}", subjects[k], checks[k]);
    }
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let count = finite.len() as f64;
    let mean = finite.iter().sum::<f64>() / count;
    let spread = (finite.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (count - 1.0)).sqrt();
    let worst = finite
        .iter()
        .copied()
        .fold(0.0, |w: f64, v| if v.abs() > w.abs() { v } else { w });
    let row = table(store, "pulls", "study", "pulls_summary");
    assert_eq!(summary::PULLS.read(&row).unwrap()[0] as usize, finite.len());
    let recorded = summary::MEAN.read(&row).unwrap()[0];
    assert!(close(recorded.mean, mean) && close(recorded.stderr, spread / count.sqrt()));
    assert!(close(summary::SPREAD.read(&row).unwrap()[0], spread));
    assert_eq!(summary::WORST_PULL.read(&row).unwrap()[0], worst);
    assert_eq!(
        summary::VERDICT.read(&row).unwrap()[0],
        format!("too few pulls to tell ({} < 50)", finite.len())
    );
    assert!(printed.contains("cross-checks: pulls"), "{printed}");
}

/// `ternary rate` on the study's store: N2 at the `N2_10K` gas's theta =
/// 0.1052 (T = 0.1052 x 95.05 K), one atom per 10 um, is that table row
/// itself and gives the paper row's 1/Gamma under both definitions (`paper`:
/// `(ours, converged)` in s); the atom's mass scales 1/Gamma by
/// sqrt(m_N / m_N2); 10 K (theta = 0.105208) lies above the reduced
/// study's table [0.1, 0.1052] and is refused, as is the 4 eps reading
/// (theta = 0.026).
fn rate_reproduces_the_nitrogen_row(config: &Path, store: &Path, paper: (Estimate, Estimate)) {
    use ternary::physics::species;
    use ternary::physics::units::{Mass, PhysicalGas};
    use ternary::rates::{gas_rates, time_of};
    let study = ternary::config::Study::load(config).unwrap();
    let opened = ternary::pipeline::store::Store::open_existing(store).unwrap();
    let sourced =
        ternary::report::theta_table(&study, &opened, &ternary::plan::plan(&study)).unwrap();
    assert_eq!(sourced.table.thetas, [0.1, 0.1052]);
    let n2 = species::species("N2").unwrap();
    let temperature = 0.1052 * n2.eps_over_k;
    let gas = |mass_amu: f64| {
        PhysicalGas::from_kelvin(
            n2.eps_over_k,
            n2.sigma_angstrom,
            temperature,
            Mass::AtomicMassUnits(mass_amu),
            0.1,
        )
    };
    let molecule = gas_rates(&sourced.table, &gas(28.0134)).unwrap();
    // The exact row: the table's own a_n, its own error, no interpolation.
    let rows = table(store, "table", "study", "table");
    let k = contract::table::POTENTIAL
        .row_of(&rows, "lj-0.1052")
        .unwrap();
    let a_n = contract::table::A_N.read(&rows).unwrap()[k];
    let constant = molecule.thermalization;
    assert_eq!(
        (constant.value, constant.statistical, constant.interpolation),
        (a_n.mean, a_n.stderr, 0.0)
    );
    // 1/Gamma from the formula, worked here: l = sigma theta^(-1/6),
    // v_th = sqrt(kT/m), Gamma = a rho^2 l v_th.
    let kt_joule = temperature * 1.380_649e-23;
    let v_th = (kt_joule / (28.0134 * 1.660_539_066_60e-27)).sqrt() * 1e6; // um/s
    let l = 3.698e-4 * libm::pow(0.1052, -1.0 / 6.0); // um
    let formula = 1.0 / (a_n.mean * 0.01 * l * v_th);
    // A bound pair lives 1 / (k_d rho v_th), k_d the table row's own.
    let k_d = contract::dissociation::study::DISSOCIATION_RATE
        .read(&rows)
        .unwrap()[k];
    let dissociation = molecule.dissociation;
    assert_eq!(
        (dissociation.value, dissociation.statistical),
        (k_d.mean, k_d.stderr)
    );
    let life = time_of(molecule.per_pair_per_second(dissociation).estimate()).mean;
    let expected_life = 1.0 / (k_d.mean * 0.1 * v_th);
    assert!((life / expected_life - 1.0).abs() < 1e-8, "{life} s");
    let time = |rate| time_of(molecule.per_second(rate).estimate());
    // The gas's eps_ev in pipeline.toml has 9 digits: agreement to 1e-8.
    for (ours, expected) in [
        (time(constant).mean, formula),
        (time(constant).mean, paper.1.mean),
        (time(constant).stderr, paper.1.stderr),
        (time(molecule.paper_thermalization).mean, paper.0.mean),
        (time(molecule.paper_thermalization).stderr, paper.0.stderr),
    ] {
        assert!((ours / expected - 1.0).abs() < 1e-8, "{ours} != {expected}");
    }
    // The paper's example, about 10 s (one significant digit: +- 5 s).
    let published = ternary::paper::published::NITROGEN;
    let paper_time = time(molecule.paper_thermalization).mean;
    assert!(
        (paper_time - published.value).abs() <= published.uncertainty,
        "{paper_time} s"
    );
    // The atom's mass: v_th grows by sqrt(2), 1/Gamma shrinks by it.
    let atom = gas_rates(&sourced.table, &gas(14.0067)).unwrap();
    let ratio = time_of(atom.per_second(atom.thermalization).estimate()).mean / time(constant).mean;
    assert!(
        (ratio - (14.0067f64 / 28.0134).sqrt()).abs() < 1e-12,
        "{ratio}"
    );
    // The command line prints the same row, with its sources.
    let temperature = format!("{temperature}");
    let rate = |temperature: &str, extra: &[&str]| {
        let mut args = vec!["rate", "--species", "N2", "--spacing-um", "10"];
        args.extend_from_slice(&["--temperature", temperature]);
        args.extend_from_slice(extra);
        ternary(config, &args)
    };
    let printed = rate(&temperature, &[]);
    assert!(printed.status.success(), "{}", stderr(&printed));
    let text = stdout(&printed);
    assert!(text.contains("theta = kT/eps = 0.105200"), "{text}");
    assert!(text.contains("from: table[study] "), "{text}");
    assert!(text.contains("1/Gamma = "), "{text}");
    assert!(text.contains("  life    = "), "{text}");
    for (extra, outside) in [
        (&[][..], "0.10520"),
        (&["--reading", "four-eps"][..], "0.0263"),
    ] {
        let refused = rate("10", extra);
        assert!(!refused.status.success());
        let message = stderr(&refused);
        assert!(
            message.contains(&format!("theta = kT/eps = {outside}"))
                && message
                    .contains("outside the study's Lennard-Jones table, theta in [0.1, 0.1052]"),
            "{message}"
        );
    }
}

/// The recombination rate at `u' = 0` from the kernel's scenes (`moments`)
/// and from the sweep's own scene set (another launch proposal and seed):
/// independent estimates of one number, within errors; zero without a well,
/// its thermal average too.
/// Every study-table column another stage supplies holds, bit for bit, that
/// stage's value for the row's potential, and is null where the study runs
/// no such instance (the gaps without a spectrum, `k_d` without a well).
fn the_study_table_holds_what_its_suppliers_computed(store: &Path) {
    let rows = table(store, "table", "study", "table");
    let potentials = contract::table::POTENTIAL.read(&rows).unwrap();
    let (mut read, mut null) = (0, 0);
    for column in contract::STUDY_COLUMNS.iter().copied().flatten() {
        let values = column.column.read(&rows).unwrap();
        for (k, potential) in potentials.iter().enumerate() {
            let stage = column.source.stage;
            if store
                .join(format!("refs/{stage}/{potential}.json"))
                .exists()
            {
                let source = table(store, stage, potential, column.source.name);
                let expected = column.read(&source).unwrap();
                assert_eq!(
                    (values[k].mean.to_bits(), values[k].stderr.to_bits()),
                    (expected.mean.to_bits(), expected.stderr.to_bits()),
                    "{} of {potential}",
                    column.column.value.name
                );
                read += 1;
            } else {
                assert!(values[k].mean.is_nan(), "{potential}");
                null += 1;
            }
        }
    }
    assert!(read > 0 && null > 0, "{read} read, {null} null");
}

fn recombination_agrees_between_scene_sets(store: &Path) {
    use contract::sweep::recombination::{RATE_COLUMN, U_PRIME};
    let sweep_rate = |potential: &str| {
        let sweep = table(store, "sweep", potential, "recombination");
        let at = U_PRIME.optional(&sweep).unwrap();
        let rates = RATE_COLUMN.read(&sweep).unwrap();
        let at_rest = at.iter().position(|u| *u == Some(0.0)).expect("u' = 0");
        let thermal = at.iter().position(Option::is_none).expect("thermal row");
        (rates[at_rest], rates[thermal])
    };
    let moments = table(store, "moments", "lj-0.1_u0_rho0", "moments");
    let kernel = contract::moments::RECOMBINATION_RATE
        .read(&moments)
        .unwrap()[0];
    let (sweep, thermal) = sweep_rate("lj-0.1");
    let z = (kernel.mean - sweep.mean) / libm::hypot(kernel.stderr, sweep.stderr);
    assert!(z.abs() < 4.0, "kernel {kernel:?}, sweep {sweep:?}");
    // Together (inverse-variance weighted) they resolve a rate above zero:
    // the agreement is between two measurements of something.
    let weights = [kernel.stderr.powi(-2), sweep.stderr.powi(-2)];
    let pooled = (weights[0] * kernel.mean + weights[1] * sweep.mean) / (weights[0] + weights[1]);
    let pooled_error = (weights[0] + weights[1]).sqrt().recip();
    assert!(pooled > 3.0 * pooled_error, "{pooled} +- {pooled_error}");
    assert!(thermal.mean > 0.0, "{thermal:?}");
    // Detailed balance: the thermal recombination rate against the one the
    // dissociation stage predicts, 3 K_b k_d (tests/kernel.rs holds the
    // test with power; the reduced study's sweep resolves R only to ~50%).
    let dissociation = table(store, "dissociation", "lj-0.1", "dissociation");
    let balanced = contract::dissociation::BALANCED_RECOMBINATION
        .read(&dissociation)
        .unwrap()[0];
    assert!(balanced.mean > 10.0 * balanced.stderr, "{balanced:?}");
    let z = (thermal.mean - balanced.mean) / libm::hypot(thermal.stderr, balanced.stderr);
    assert!(
        z.abs() < 4.0,
        "recombination {thermal:?}, 3 K_b k_d {balanced:?}"
    );
    let (none, thermal_none) = sweep_rate("ipp-6");
    assert_eq!((none.mean, thermal_none.mean), (0.0, 0.0));
    binding_energies_of_recombination(store);
}

/// The bound pairs of recombination: every recombined scene of the sweep's
/// Lennard-Jones scenes (`theta = 0.1`) records an internal energy inside
/// the well, `(-D, 0)`, every other scene none; the distribution of the
/// binding energy `B` (`binding`) is nowhere negative and, times the bin
/// widths, sums to the thermal recombination rate (the same per-replicate
/// sum split by `B`: equal to rounding); the mean `B` lies within half a
/// bin of the histogram's (every pair lies within half a bin of its bin's
/// centre). Without a well (`ipp-6`) no scene records one, the
/// distribution has no bins and the mean no value.
fn binding_energies_of_recombination(store: &Path) {
    use contract::sweep::binding::{BINDING_HIGH, BINDING_LOW, RATE_DENSITY};
    use contract::sweep::recombination::{MEAN_BINDING, RATE_COLUMN, U_PRIME};
    // U/kT = theta x^-12 - x^-6 bottoms out at -1 / (4 theta).
    let depth = 0.25 / 0.1;
    let energies = |collisions: &str| {
        let events = table(store, "collisions", collisions, "events");
        let outcome = contract::collisions::OUTCOME.read(&events).unwrap();
        let energy = contract::collisions::BINDING_ENERGY
            .optional(&events)
            .unwrap();
        outcome.into_iter().zip(energy).collect::<Vec<_>>()
    };
    let scenes = energies("lj-0.1_sweep");
    for (outcome, energy) in &scenes {
        let recombined = outcome == "recombined";
        let inside = energy.is_some_and(|e| -depth < e && e < 0.0);
        assert!(
            recombined == inside && recombined == energy.is_some(),
            "{outcome}: {energy:?}"
        );
    }
    assert!(scenes.iter().any(|(_, energy)| energy.is_some()));
    assert!(energies("ipp-6_sweep").iter().all(|(_, e)| e.is_none()));
    let thermal = |potential: &str| {
        let recombination = table(store, "sweep", potential, "recombination");
        let at = U_PRIME.optional(&recombination).unwrap();
        let row = at.iter().position(Option::is_none).expect("thermal row");
        let rate = RATE_COLUMN.read(&recombination).unwrap()[row];
        (rate, MEAN_BINDING.read(&recombination).unwrap()[row])
    };
    let (rate, mean) = thermal("lj-0.1");
    let binding = table(store, "sweep", "lj-0.1", "binding");
    let low = BINDING_LOW.read(&binding).unwrap();
    let high = BINDING_HIGH.read(&binding).unwrap();
    let density = RATE_DENSITY.read(&binding).unwrap();
    assert_eq!((low[0], high[high.len() - 1]), (0.0, depth));
    let bins = || low.iter().zip(&high).zip(&density);
    assert!(bins().all(|(_, d)| d.mean >= 0.0), "{density:?}");
    let integral: f64 = bins().map(|((a, b), d)| d.mean * (b - a)).sum();
    assert!(close(integral, rate.mean), "{integral} vs {rate:?}");
    let centred: f64 = bins()
        .map(|((a, b), d)| 0.5 * (a + b) * d.mean * (b - a))
        .sum();
    let half_bin = 0.5 * (high[0] - low[0]);
    assert!(
        (mean.mean - centred / integral).abs() <= half_bin,
        "{mean:?}"
    );
    assert!(
        0.0 < mean.mean && mean.mean < depth && mean.stderr > 0.0,
        "{mean:?}"
    );
    let (none, mean_none) = thermal("ipp-6");
    assert_eq!(none.mean, 0.0);
    assert!(mean_none.mean.is_nan());
    assert_eq!(table(store, "sweep", "ipp-6", "binding").num_rows(), 0);
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
