//! The text of `ternary pairs`: what equilibrium rings measured of their
//! bound pairs against what the dilute limit predicts, each with its z.

use std::fmt::Write as _;

use super::numbers::{significant_to, with_error};
use crate::physics::pair_kinetics::PairRelaxation;
use crate::stats::Estimate;

/// What the dilute limit predicts for a potential's pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairPrediction {
    /// `K_b`, `l`: exact (quadrature of the bound-pair density).
    pub bound_length: f64,
    /// `n_b / rho_f^2` of the exact equilibrium at the rings' density, `l`.
    pub dense_bound_length: f64,
    /// `k_d` from the dissociation scenes, `l` (`rho v_th` per pair).
    pub dissociation: Estimate,
}

/// `(a - b) / sqrt(s_a^2 + s_b^2)`.
fn z(a: Estimate, b: Estimate) -> f64 {
    (a.mean - b.mean) / libm::hypot(a.stderr, b.stderr)
}

/// The report: the rings (`ring`), the densities and the relaxation rate
/// measured, and one row per coefficient: measured, predicted, z.
pub fn pairs_text(ring: &str, measured: &PairRelaxation, predicted: &PairPrediction) -> String {
    let show = |e: Estimate| with_error(e.mean, e.stderr, "-");
    let exact = Estimate {
        mean: predicted.dense_bound_length,
        stderr: 0.0,
    };
    let m = measured;
    let expected_rate = predicted
        .dissociation
        .scaled(m.free_density.mean + 4.0 * m.bound_density.mean);
    let mut out = String::new();
    let _ = writeln!(out, "{ring}");
    let _ = writeln!(
        out,
        "free atoms rho_f l = {}, bound pairs n_b l = {}; N_b(t) relaxes at lambda = {} v_th/l (fitted over lags {}..{} l/v_th), predicted k_d (rho_f + 4 n_b) = {}",
        show(m.free_density),
        show(m.bound_density),
        show(m.relaxation_rate),
        m.fitted_lags[0],
        m.fitted_lags[1],
        show(expected_rate)
    );
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "{:<54} {:>20} {:>22} {:>6}",
        "coefficient (dilute limit)", "ring MD", "predicted", "z"
    );
    let formation = predicted.dissociation.scaled(predicted.bound_length);
    let rows = [
        (
            "n_b / rho_f^2 (K_b as rho -> 0), l",
            m.bound_length,
            exact,
            format!("{} (exact)", significant_to(exact.mean, 6)),
        ),
        (
            "k_d = lambda / (rho_f + 4 n_b), l",
            m.dissociation,
            predicted.dissociation,
            show(predicted.dissociation),
        ),
        (
            "K_b k_d = R/3 = k_d n_b / rho_f^2, l^2",
            m.formation,
            formation,
            show(formation),
        ),
    ];
    for (name, md, prediction, text) in rows {
        let _ = writeln!(
            out,
            "{name:<54} {:>20} {:>22} {:>6.2}",
            show(md),
            text,
            z(md, prediction)
        );
    }
    let local: Vec<String> = m
        .local_rates
        .iter()
        .map(|(lags, rate)| format!("{}-{}: {}", lags[0], lags[1], show(*rate)))
        .collect();
    let _ = writeln!(
        out,
        "\nlocal relaxation rate ln(C(a)/C(b))/(b - a) of N_b, lags a-b in l/v_th: {}",
        local.join(", ")
    );
    let _ = writeln!(
        out,
        "\nn_b, rho_f: time averages of the bound neighbour pairs (w^2/4 + U < 0) and the free atoms \
         per l. lambda: early slope of -ln C(tau), C the autocorrelation of the number of bound pairs \
         (later lags decay slower: pairs that break easily go first); the rate equation dn_b/dt = \
         K_b k_d rho_f^3 - k_d n_b rho_f at fixed N relaxes at k_d (rho_f + 4 n_b) (exchanges \
         A2 + A -> A + A2 leave N_b alone). The formation rate follows from stationarity. Predicted: \
         n_b / rho_f^2 exact for a 1D gas of nearest-neighbour pairs at the rings' density \
         (independent gaps of density exp(-U - p x), p from the mean gap; K_b = {} in the dilute \
         limit), k_d from the dissociation scenes ([dissociation]). Errors: jackknife over rings \
         (MD), over randomizations (scenes). k_d and K_b k_d are dilute-limit rates: expect \
         corrections of order rho l.",
        significant_to(predicted.bound_length, 6)
    );
    out
}
