//! The far-kernel benchmark: the launch proposal's slow stratum against
//! none, on the offset quadrature. A launch pair with a slow launch (speed
//! `v`) has an offset integral growing like `1 / v`; under the launch density
//! alone (`~ v` near 0) its weight has unbounded variance, which the far bins'
//! bath part (`0.01 <= |du| <= 0.05`, fed by slow bath particles) inherits:
//! errors that do not fall with more pairs, and randomizations far in the
//! tails. Each share runs at `pairs` and `4 pairs` per randomization: with a
//! finite variance the errors halve.

use std::fmt::Write as _;

use ternary::kernel::Target;
use ternary::physics::sampling::OffsetIntegration;

use super::sampler::{KernelBenchOptions, KernelRun, Variant, plan_for, run_sampler};

/// Shares of the slow component compared (0: the launch density alone).
const SHARES: [f64; 4] = [0.0, 1.0 / 64.0, 1.0 / 32.0, 1.0 / 16.0];

/// One row of the table.
fn row(share: f64, pairs: u32, run: &KernelRun) -> String {
    format!(
        "| {} | {pairs} | {} | {:.1} | {:.5e} | {:.2e} | {:.6e} | {:.2e} | {:.2e} | {:.3} | {:.4} | {:.2} |\n",
        share_label(share),
        run.scenes,
        run.seconds,
        run.a_n.mean,
        run.a_n.stderr / run.a_n.mean,
        run.a_n_window.mean,
        run.a_n_window.stderr / run.a_n_window.mean,
        run.near_bins,
        run.far_bins,
        run.far_groups,
        run.tail_z,
    )
}

/// `0` or `1/k`.
fn share_label(share: f64) -> String {
    if share == 0.0 {
        "0 (launch density)".into()
    } else {
        format!("1/{}", (1.0 / share).round())
    }
}

/// The comparison: every share at `pairs` and `4 pairs` per randomization,
/// the strata split once by a pilot without the slow component.
pub fn far_kernel(options: &KernelBenchOptions) -> String {
    let potential = options.potential;
    let study = &options.study;
    let base = Variant {
        name: "offset quadrature",
        proposal: study.proposal,
        same_side_fraction: 0.15,
        quasi_random: true,
        offsets: OffsetIntegration::Quadrature(study.quadrature),
        slow_share: 0.0,
    };
    let probe = plan_for(&base, options.seed, options.randomizations, options.points);
    let fraction = ternary::kernel::pilot_same_side_fraction(
        &probe,
        &potential,
        &study.engine,
        &[Target::dilute(0.0)],
        1024,
    )
    .unwrap_or(base.same_side_fraction);
    let mut out = format!(
        "### Far kernel: {}, {} randomizations, seed {}, same-side share {fraction:.3} (one pilot)\n\n",
        potential.id(),
        options.randomizations,
        options.seed
    );
    out.push_str("Slow share: the share of each launch coordinate in the slow stratum (speeds uniform below 0.1). Errors relative; near bins 1e-4..2e-3, far fine bins and far groups (1/20 decade) 0.01..0.05, medians; tail z: the largest |z| of a randomization's sum over |du| in [0.01, 0.02), [0.02, 0.03), [0.03, 0.05) (Gaussian: ~2.5; at most (R - 1)/sqrt(R)).\n\n");
    out.push_str("| slow share | pairs per randomization | scenes | seconds | a_n untruncated | rel. error | a_n in the window | rel. error | near bins | far fine bins | far groups | tail z |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let mut halving = String::new();
    for share in SHARES {
        let variant = Variant {
            same_side_fraction: fraction,
            slow_share: share,
            ..base
        };
        let runs: Vec<KernelRun> = [options.points, 4 * options.points]
            .into_iter()
            .map(|pairs| {
                let plan = plan_for(&variant, options.seed, options.randomizations, pairs);
                let run = run_sampler(&potential, &plan, study);
                out.push_str(&row(share, pairs, &run));
                run
            })
            .collect();
        let ratio = |error: fn(&KernelRun) -> f64| error(&runs[0]) / error(&runs[1]);
        let _ = writeln!(
            halving,
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            share_label(share),
            ratio(|r| r.a_n.stderr),
            ratio(|r| r.a_n_window.stderr),
            ratio(|r| r.near_bins),
            ratio(|r| r.far_groups),
            runs[1].seconds / runs[0].seconds,
        );
    }
    out.push_str("\nError at `pairs` over error at `4 pairs` (2 for a finite variance and plain Monte Carlo, more for quasi-random points), and the time ratio:\n\n| slow share | a_n untruncated | a_n in the window | near bins | far groups | time |\n|---|---|---|---|---|---|\n");
    out.push_str(&halving);
    out
}
