//! Whether the study's error bars are calibrated, judged by its own
//! cross-checks: every quantity the study computes two independent ways,
//! or holds against a value that must be exact, gives a pull `(a - b) /
//! sqrt(s_a^2 + s_b^2)`, distributed as N(0, 1) when both errors are right
//! and nothing is biased. Over many pulls, a mean far from 0 says a bias,
//! a spread below 1 overstated errors, above 1 understated ones. Pure
//! math: no IO.

use crate::stats::Estimate;

/// Fewest pulls a verdict is drawn from: the spread of 50 N(0, 1) draws
/// has a standard error of 0.1, so a spread outside [`SPREAD_RANGE`] is
/// three of them from 1.
pub const MIN_PULLS: usize = 50;

/// Largest mean pull of calibrated errors: three standard errors of the
/// mean of [`MIN_PULLS`] independent pulls (0.14 each), less where the
/// pulls are more.
pub const MAX_MEAN: f64 = 0.3;

/// Spread (sample standard deviation) of the pulls of calibrated errors.
pub const SPREAD_RANGE: [f64; 2] = [0.7, 1.3];

/// One cross-check: two estimates of one number (an exact value has a
/// standard error of 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Pull {
    /// What is compared, e.g. "thermal recombination: sweep's scenes against 3 K_b k_d".
    pub check: &'static str,
    /// Which instance it is compared for (a potential id, with a detail).
    pub subject: String,
    /// Unit of the two estimates.
    pub unit: &'static str,
    /// The first estimate.
    pub first: Estimate,
    /// The second estimate, or the exact value.
    pub second: Estimate,
}

impl Pull {
    /// `(a - b) / sqrt(s_a^2 + s_b^2)`; NaN without an error.
    pub fn value(&self) -> f64 {
        let combined = libm::hypot(self.first.stderr, self.second.stderr);
        if combined > 0.0 {
            (self.first.mean - self.second.mean) / combined
        } else {
            f64::NAN
        }
    }
}

/// The pulls' distribution against N(0, 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// Pulls with a value.
    pub count: usize,
    /// Their mean, with its standard error (spread / sqrt(count)).
    pub mean: Estimate,
    /// Their sample standard deviation.
    pub spread: f64,
    /// Index (into the pulls given) of the largest |pull|.
    pub worst: Option<usize>,
}

/// The calibration of `pulls` (those without a value left out).
pub fn calibration(pulls: &[Pull]) -> Calibration {
    let values: Vec<(usize, f64)> = pulls
        .iter()
        .map(Pull::value)
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .collect();
    let finite: Vec<f64> = values.iter().map(|(_, v)| *v).collect();
    let (mean, spread) = if finite.len() >= 2 {
        let mean = Estimate::from_replicates(&finite);
        (mean, mean.stderr * (finite.len() as f64).sqrt())
    } else {
        (
            Estimate {
                mean: f64::NAN,
                stderr: f64::NAN,
            },
            f64::NAN,
        )
    };
    let worst = values
        .iter()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(k, _)| *k);
    Calibration {
        count: finite.len(),
        mean,
        spread,
        worst,
    }
}

impl Calibration {
    /// "calibrated", or what is wrong: too few pulls to tell, a biased
    /// mean, overstated or understated errors.
    pub fn verdict(&self) -> String {
        let [low, high] = SPREAD_RANGE;
        let mut faults = Vec::new();
        if self.count < MIN_PULLS {
            return format!("too few pulls to tell ({} < {MIN_PULLS})", self.count);
        }
        if self.mean.mean.abs() >= MAX_MEAN {
            faults.push(format!("biased: |mean| >= {MAX_MEAN}"));
        }
        if self.spread < low {
            faults.push(format!("errors overstated: spread < {low}"));
        }
        if self.spread > high {
            faults.push(format!("errors understated: spread > {high}"));
        }
        if faults.is_empty() {
            "calibrated".to_string()
        } else {
            faults.join("; ")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    fn estimate(mean: f64, stderr: f64) -> Estimate {
        Estimate { mean, stderr }
    }

    /// Pulls of `count` pairs of one true value, each estimate's error
    /// quoted as `quoted` times its true error 1.
    fn pulls(count: usize, quoted: f64, bias: f64) -> Vec<Pull> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        (0..count)
            .map(|k| {
                let mut draw = || -> f64 { StandardNormal.sample(&mut rng) };
                Pull {
                    check: "test",
                    subject: k.to_string(),
                    unit: "1",
                    first: estimate(draw() + bias, quoted),
                    second: estimate(draw(), quoted),
                }
            })
            .collect()
    }

    /// The pull divides the difference by both errors in quadrature; an
    /// exact value (error 0) counts once; no error at all, no pull.
    #[test]
    fn a_pull_is_the_difference_over_the_combined_error() {
        let pull = |a: Estimate, b: Estimate| {
            Pull {
                check: "test",
                subject: String::new(),
                unit: "1",
                first: a,
                second: b,
            }
            .value()
        };
        assert_eq!(pull(estimate(9.0, 3.0), estimate(5.0, 4.0)), 0.8);
        assert_eq!(pull(estimate(1.0, 0.5), estimate(2.0, 0.0)), -2.0);
        assert!(pull(estimate(1.0, 0.0), estimate(2.0, 0.0)).is_nan());
    }

    /// Errors quoted right are calibrated; quoted twice too large they
    /// spread by one half (overstated), half as large by two (understated);
    /// a shift of one true error shows as a bias of 1/sqrt(2); the largest
    /// |pull| is found, and fewer than fifty pulls give no verdict.
    #[test]
    fn the_verdict_reads_the_mean_and_the_spread() {
        let right = calibration(&pulls(400, 1.0, 0.0));
        assert_eq!(right.verdict(), "calibrated", "{right:?}");
        assert_eq!(right.count, 400);
        let overstated = calibration(&pulls(400, 2.0, 0.0));
        assert!((overstated.spread - 0.5).abs() < 0.05, "{overstated:?}");
        assert_eq!(
            overstated.verdict(),
            "errors overstated: spread < 0.7",
            "{overstated:?}"
        );
        let understated = calibration(&pulls(400, 0.5, 0.0));
        assert!(understated.verdict().starts_with("errors understated"));
        let biased = calibration(&pulls(400, 1.0, 1.0));
        assert!((biased.mean.mean - libm::sqrt(0.5)).abs() < 3.0 * biased.mean.stderr);
        assert!(biased.verdict().starts_with("biased"), "{biased:?}");
        let drawn = pulls(400, 1.0, 0.0);
        let worst = drawn[right.worst.unwrap()].value().abs();
        assert!(drawn.iter().all(|p| p.value().abs() <= worst));
        assert!(
            calibration(&pulls(49, 1.0, 0.0))
                .verdict()
                .starts_with("too few pulls")
        );
    }
}
