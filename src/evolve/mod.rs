//! Evolution of the perturbation `h(u, t)` (physics.md §4): the exact
//! translation-invariant convolution semigroup for early times
//! ([`convolution`], rebinned with the moments against their closed forms in
//! [`early`]), the full `u'`-dependent master equation on a velocity
//! grid ([`operator`], [`grid`]) with its exact exponential ([`propagate`]),
//! and the Fokker-Planck equation of the same drift and variance rates (the
//! three processes and the projection's effect in [`processes`]); the
//! relaxation spectrum of the same generators ([`spectrum`]).
//! Uncertainties come from the jackknife over the Monte Carlo randomizations
//! (`stats::Replicated`): every quantity here is computed once on the mean
//! kernel and once with each randomization left out. Pure math: no IO.

pub mod convolution;
pub mod dirichlet;
pub mod early;
pub mod fourier;
pub mod grid;
pub mod operator;
pub mod processes;
pub mod propagate;
pub mod spectral;
pub mod spectrum;
