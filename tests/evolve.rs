//! The evolution of `h(u, t)` (physics.md §4) against invariants: the
//! linearized operator conserves number, momentum and energy event by event;
//! the grid keeps the special particle's drift and variance rates exactly;
//! the evolved `h` keeps the invariants and relaxes to the equilibrium they
//! fix; and two independent methods (the exact convolution of the
//! translation-invariant kernel, the master equation on a grid) agree at
//! early times within their uncertainties.

use ternary::binning::Bins;
use ternary::evolve::convolution::{self, kernel_moments};
use ternary::evolve::grid::VelocityGrid;
use ternary::evolve::operator::{Generators, balanced_generators, column_rates, kernel_generators};
use ternary::evolve::processes::GridEvolution;
use ternary::evolve::propagate::Generator;
use ternary::evolve::spectral::Dissipative;
use ternary::evolve::spectrum::spectrum;
use ternary::kernel::{Draws, Event, Target, contributions, histograms, moments};
use ternary::physics::potential::Potential;
use ternary::physics::sampling::{LaunchProposal, OffsetIntegration, OffsetProposal, SamplingPlan};
use ternary::physics::scene::{EngineSettings, Method};
use ternary::stats::{Entries, Estimate, jackknife, replicate_means};

const KICK_FLOOR: f64 = 1e-10;

/// `randomizations` x 4096 scenes of the `n = 6` gas with a launch mixture of
/// spread `spread` (0: thermal launches only).
fn events(seed: u64, randomizations: u32, spread: f64) -> Vec<Event> {
    let plan = SamplingPlan {
        seed,
        randomizations,
        opposite_points: 3584,
        same_side_points: 512,
        proposal: OffsetProposal::default(),
        quasi_random: true,
        launch: LaunchProposal {
            spread,
            ..LaunchProposal::THERMAL
        },
        offsets: OffsetIntegration::Sampled,
    };
    let engine = EngineSettings::new(Method::Dprkn12, 1e-12, 100_000);
    plan.integrate_all(&Potential::inverse_power(6.0), &engine, |_| ())
        .iter()
        .map(Event::from_record)
        .collect()
}

fn generators(events: &[Event], grid: &VelocityGrid) -> Vec<Generators> {
    generators_with_floor(events, grid, KICK_FLOOR)
}

fn generators_with_floor(events: &[Event], grid: &VelocityGrid, floor: f64) -> Vec<Generators> {
    kernel_generators(events, &Draws::count(events), grid, floor, |_| ())
}

/// `a_6`: the self variance rate at u' = 0 within 0.1 (`Gamma` in `rho^2 l v_th`).
fn gamma(events: &[Event]) -> f64 {
    let sums = moments(events, &Target::dilute(0.0), &[0.1], &Draws::count(events));
    let values: Vec<f64> = sums.iter().map(|r| r[0].self_variance).collect();
    Estimate::from_replicates(&values).mean
}

fn mean(replicates: &[Generators], part: fn(&Generators) -> &Generator) -> Generator {
    let picked: Vec<Generator> = replicates.iter().map(|g| part(g).clone()).collect();
    Generator::sum(&picked).scaled(1.0 / picked.len() as f64)
}

/// Number, momentum and energy: every column of the full generator has zero
/// moments `sum_i M_ij u_i^p` for p = 0, 1, 2 up to the engine's errors: each
/// scene conserves them to ~1e-13 v_th per velocity (docs/benchmarks.md), so
/// a column's moment p is bounded by `1e-12 W (1 + |u'|)^p` with `W` the
/// column's total scene weight. The grid reaches 8 v_th, where no launch ever
/// arrives, so the ends' reflection plays no part. No kick floor here:
/// snapping one particle's tiny change to zero would break the conservation
/// it is meant to test.
#[test]
fn full_generator_conserves_number_momentum_and_energy() {
    let events = events(11, 4, 2.0);
    let draws = Draws::count(&events);
    let grid = VelocityGrid::covering(8.0, 0.1);
    let replicates = generators_with_floor(&events, &grid, 0.0);
    for j in grid.node_of(-4.0).unwrap()..=grid.node_of(4.0).unwrap() {
        let u_prime = grid.velocity(j);
        let mut weights = vec![0.0; draws.replicates()];
        for event in &events {
            for c in contributions(event, &Target::dilute(u_prime)) {
                weights[event.randomization as usize] += c.weight * draws.scale(event);
            }
        }
        for (g, weight) in replicates.iter().zip(weights) {
            let moments = grid.moments(&g.full.column(j), 0.0, f64::INFINITY);
            for (p, moment) in moments.iter().enumerate() {
                let bound = 1e-12 * weight * (1.0 + u_prime.abs()).powi(p as i32);
                assert!(
                    moment.abs() <= bound,
                    "u' = {u_prime}: moment {p} = {moment:e} > {bound:e}"
                );
            }
            let number: f64 = g.tagged.column(j).iter().sum();
            assert!(number.abs() <= 1e-12 * weight);
        }
    }
}

/// Quadratic deposition keeps the first two moments of every kick: the
/// tagged generator's column rates are the special particle's drift and
/// variance rates computed from the unbinned kicks, to rounding.
#[test]
fn tagged_columns_carry_the_exact_drift_and_variance_rates() {
    let events = events(12, 2, 2.0);
    let grid = VelocityGrid::covering(3.0, 0.05);
    let replicates = generators(&events, &grid);
    let draws = Draws::count(&events);
    for u_prime in [0.0, 1.0, -1.5] {
        let sums = moments(&events, &Target::dilute(u_prime), &[f64::INFINITY], &draws);
        let node = grid.node_of(u_prime).unwrap();
        for (g, sum) in replicates.iter().zip(&sums) {
            let (drift, variance) = column_rates(&g.tagged, &grid);
            let expected = [sum[0].self_drift, sum[0].self_variance];
            for (got, want) in [drift[node], variance[node]].iter().zip(expected) {
                assert!(
                    (got - want).abs() <= 1e-10 * want.abs().max(1e-6),
                    "u' = {u_prime}: {got:e} vs {want:e}"
                );
            }
        }
    }
}

/// The full generator, projected onto detailed balance and dissipation
/// ([`Dissipative`]), evolves `h_full` with number 1, momentum u' = 0 and
/// energy 0 at all times (exactly, though the ends reflect), and `h_full`
/// approaches `f0 (3 - u^2) / 2`, the equilibrium those fix. The raw tagged
/// generator (a Markov generator: stable as it is) takes the special
/// particle's velocity to `f0`. The raw full estimate at this sample size has
/// growing modes: the projection removes them.
#[test]
fn evolution_keeps_the_invariants_and_relaxes_to_equilibrium() {
    let events = events(13, 16, 2.0);
    let grid = VelocityGrid::covering(3.0, 0.1);
    let replicates = generators(&events, &grid);
    let a = gamma(&events);
    let mut h0 = vec![0.0; grid.len()];
    h0[grid.node_of(0.0).unwrap()] = 1.0;
    let times: Vec<f64> = [0.1, 1.0, 10.0].iter().map(|t| t / a).collect();
    let distance =
        |h: &[f64], eq: &[f64]| -> f64 { h.iter().zip(eq).map(|(x, y)| (x - y).abs()).sum() };
    let raw = mean(&replicates, |g| &g.full);
    assert!(
        raw.exponential(times[2]).norm_1() > 1e3,
        "no growing mode to remove"
    );
    let u = grid.velocities();
    let invariants = [
        vec![1.0; grid.len()],
        u.clone(),
        u.iter().map(|x| x * x).collect(),
    ];
    let projected = Dissipative::project(&raw, &grid.maxwellian(), &invariants).unwrap();
    let full = projected.propagate(&h0, &times);
    for h in &full {
        let [number, momentum, energy] = grid.moments(h, 0.0, f64::INFINITY);
        assert!((number - 1.0).abs() < 1e-12, "{number}");
        assert!(
            momentum.abs() < 1e-12 && energy.abs() < 1e-12,
            "{momentum} {energy}"
        );
    }
    // From a delta at u' = 0.5 the momentum u' and the energy u'^2 stay as well.
    let mut shifted = vec![0.0; grid.len()];
    shifted[grid.node_of(0.5).unwrap()] = 1.0;
    for h in projected.propagate(&shifted, &times) {
        let [number, momentum, energy] = grid.moments(&h, 0.0, f64::INFINITY);
        let errors = [number - 1.0, momentum - 0.5, energy - 0.25];
        assert!(errors.iter().all(|e| e.abs() < 1e-12), "{errors:?}");
    }
    let equilibrium = grid.conserving_equilibrium(0.0);
    let full_distances: Vec<f64> = full.iter().map(|h| distance(h, &equilibrium)).collect();
    let tagged = mean(&replicates, |g| &g.tagged).propagate(&h0, &times);
    let tagged_distances: Vec<f64> = tagged
        .iter()
        .map(|h| distance(h, &grid.maxwellian()))
        .collect();
    // The tagged velocity goes from a delta (distance ~2) to within a few
    // percent of f0 by t = 1/Gamma. Later, at this sample size (6.5e4 scenes),
    // its stationary state comes out ~30% too broad (the rare heavy weights of
    // the launch mixture at |u'| >= 1 are undersampled), and the full
    // estimate violates detailed balance by ~30%, its noise modes (clipped to
    // rate 0) keeping h_full ~0.3 from equilibrium. At the default study's
    // 1.2e6 scenes neither happens (distances 0.05 and 0.0035 at 8/Gamma,
    // docs/benchmarks.md; the 0.0035 was the continuum limit's miss on the
    // grid, which conserving_equilibrium now takes from the grid's own sums).
    // Here only the approach is asserted.
    assert!(
        tagged_distances[0] > 1.0 && tagged_distances[1] < 0.1,
        "{tagged_distances:?}"
    );
    assert!(
        full_distances[1] < 0.5 * full_distances[0],
        "{full_distances:?}"
    );
    assert!(projected.largest_clipped > 0.0 && projected.asymmetry > 0.1);
}

/// Two independent methods: the variance of `h` at `t = 0.01 / Gamma` from the
/// exact convolution of the translation-invariant kernel (thermal launches,
/// fine bins) and from the tagged master equation on a grid (the launch
/// mixture, grid step 0.05) agree within their jackknife errors.
#[test]
fn convolution_and_master_equation_agree_at_early_times() {
    let thermal = events(14, 8, 0.0);
    let wide = events(15, 8, 2.0);
    let target = Target::dilute(0.0);
    let draws = Draws::count(&thermal);
    let a = gamma(&thermal);
    let t = 0.01 / a;
    let bins = Bins::for_window(0.2, 5e-5);
    let kernels: Vec<Vec<f64>> = histograms(&thermal, &target, &bins, &draws)
        .iter()
        .map(|h| h.total())
        .collect();
    let total: Vec<f64> = (0..bins.len())
        .map(|k| kernels.iter().map(|g| g[k]).sum())
        .collect();
    let count = kernels.len() as f64;
    let variance_of = |g: &[f64]| {
        let size = convolution::periodic_size(g, bins.width, t);
        let h = &convolution::evolve(g, size, &[t])[0];
        let half = (size / 2) as f64;
        let m = |p: i32| -> f64 {
            h.iter()
                .enumerate()
                .map(|(i, v)| v * ((i as f64 - half) * bins.width).powi(p))
                .sum()
        };
        m(2) / m(0) - (m(1) / m(0)).powi(2)
    };
    let full: Vec<f64> = total.iter().map(|s| s / count).collect();
    let loo: Vec<Vec<f64>> = kernels
        .iter()
        .map(|own| {
            vec![variance_of(
                &total
                    .iter()
                    .zip(own)
                    .map(|(s, o)| (s - o) / (count - 1.0))
                    .collect::<Vec<_>>(),
            )]
        })
        .collect();
    let fourier = jackknife(&[variance_of(&full)], &loo)[0];
    // A check of the FFT, not of physics: for a translation-invariant kernel
    // the variance is t kappa_2 identically, so this only confirms that the
    // Fourier evolution (padding, periodic wrap) reproduces the cumulant; the
    // physics check is the master equation below, an independent method.
    let closed = t * kernel_moments(&full, bins.width)[2];
    assert!(
        (fourier.mean - closed).abs() < 1e-9 * closed,
        "{} vs {closed}",
        fourier.mean
    );

    let grid = VelocityGrid::covering(4.0, 0.05);
    let replicates = generators(&wide, &grid);
    let tagged: Vec<Generator> = replicates.iter().map(|g| g.tagged.clone()).collect();
    let sum = Generator::sum(&tagged);
    let mut h0 = vec![0.0; grid.len()];
    h0[grid.node_of(0.0).unwrap()] = 1.0;
    let spread = |m: &Generator| grid.moments(&m.propagate(&h0, &[t])[0], 0.0, f64::INFINITY)[2];
    let grid_loo: Vec<Vec<f64>> = tagged
        .iter()
        .map(|own| vec![spread(&own.leave_out(&sum, tagged.len()))])
        .collect();
    let master = jackknife(
        &[spread(&sum.clone().scaled(1.0 / tagged.len() as f64))],
        &grid_loo,
    )[0];
    let sigma = libm::hypot(fourier.stderr, master.stderr);
    assert!(
        (fourier.mean - master.mean).abs() < 3.0 * sigma,
        "convolution {fourier:?} vs master equation {master:?}"
    );
    // The comparison has teeth: each error is a few percent at most.
    assert!(sigma < 0.05 * master.mean, "{sigma} vs {}", master.mean);
}

/// An operator with a planted spectrum on `grid`: `M = D^(1/2) S D^(-1/2)`,
/// `S = sum_k lambda_k w_k w_k^T` with `w_k` orthonormal and orthogonal to the
/// invariant directions `f0^(1/2) {1, u, u^2}` (which `S` annihilates), plus
/// `asymmetry` times a fixed matrix that breaks detailed balance and every
/// invariant. Returns the generator and the modes `w_k`.
fn planted_operator(
    grid: &VelocityGrid,
    spectrum: impl Fn(usize) -> f64,
    asymmetry: f64,
) -> (Generator, Vec<Vec<f64>>) {
    let root: Vec<f64> = grid.maxwellian().iter().map(|f| f.sqrt()).collect();
    let n = root.len();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let invariants = invariants(grid).into_iter().map(|p| {
        p.iter()
            .zip(&root)
            .map(|(x, r)| x * r)
            .collect::<Vec<f64>>()
    });
    let units = (0..n).map(|i| {
        (0..n)
            .map(|j| if i == j { 1.0 } else { 0.0 })
            .collect::<Vec<f64>>()
    });
    for mut q in invariants.chain(units) {
        for _pass in 0..2 {
            for b in &basis {
                let dot: f64 = q.iter().zip(b).map(|(x, y)| x * y).sum();
                q.iter_mut().zip(b).for_each(|(x, y)| *x -= dot * y);
            }
        }
        let norm = q.iter().map(|x: &f64| x * x).sum::<f64>().sqrt();
        if norm > 1e-6 {
            basis.push(q.iter().map(|x| x / norm).collect());
        }
    }
    let modes = basis.split_off(3);
    let columns: Vec<Vec<f64>> = (0..n)
        .map(|j| {
            (0..n)
                .map(|i| {
                    let s: f64 = modes
                        .iter()
                        .enumerate()
                        .map(|(k, w)| spectrum(k) * w[i] * w[j])
                        .sum();
                    s * root[i] / root[j] + asymmetry * libm::sin((i + 2 * j) as f64)
                })
                .collect()
        })
        .collect();
    (Generator::from_columns(&columns), modes)
}

/// Number, momentum and energy at the nodes: `1, u, u^2`.
fn invariants(grid: &VelocityGrid) -> Vec<Vec<f64>> {
    let u = grid.velocities();
    vec![
        vec![1.0; u.len()],
        u.clone(),
        u.iter().map(|x| x * x).collect(),
    ]
}

/// A delta at `u = 0` (node masses).
fn delta_at_zero(grid: &VelocityGrid) -> Vec<f64> {
    let mut h0 = vec![0.0; grid.len()];
    h0[grid.node_of(0.0).unwrap()] = 1.0;
    h0
}

/// With every eigenvalue negative (the invariant modes' zero aside, to
/// rounding: 1e-12 of the largest rate clips nothing measurable) the
/// eigen-decomposition's propagation agrees with the exponential by scaling
/// and squaring (two independent methods) to rounding relative to the
/// largest entry.
#[test]
fn a_dissipative_operator_propagates_as_its_exponential() {
    let grid = VelocityGrid::covering(3.0, 0.5);
    let (generator, _) = planted_operator(&grid, |k| -0.1 * (k + 1) as f64, 0.0);
    let projected =
        Dissipative::project(&generator, &grid.maxwellian(), &invariants(&grid)).unwrap();
    assert!(
        projected.largest_clipped < 1e-12,
        "{}",
        projected.largest_clipped
    );
    let h0 = delta_at_zero(&grid);
    let times = [1.0, 10.0, 100.0];
    let exact = generator.propagate(&h0, &times);
    for (got, want) in projected.propagate(&h0, &times).iter().zip(&exact) {
        let scale = want.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
        let error = got
            .iter()
            .zip(want)
            .fold(0.0, |m: f64, (a, b)| m.max((a - b).abs()));
        assert!(error <= 1e-12 * scale, "{error:e} of {scale:e}");
    }
}

/// One positive eigenvalue `lambda` planted in mode `w`: propagation sets it
/// to zero, so the mode's coefficient `w . f0^(-1/2) h` keeps its start
/// value `c` at every time while every other mode decays as planted: to
/// rounding relative to the largest coefficient (the eigenvectors come from
/// Jacobi rotations accurate to ~1e-15).
#[test]
fn a_planted_positive_eigenvalue_is_frozen() {
    let grid = VelocityGrid::covering(3.0, 0.5);
    let (lambda, planted) = (0.02, 4);
    let spectrum = |k: usize| {
        if k == planted {
            lambda
        } else {
            -0.1 * (k + 1) as f64
        }
    };
    let (generator, modes) = planted_operator(&grid, spectrum, 0.0);
    let projected =
        Dissipative::project(&generator, &grid.maxwellian(), &invariants(&grid)).unwrap();
    assert!((projected.largest_clipped - lambda).abs() < 1e-14);
    let h0 = delta_at_zero(&grid);
    let root: Vec<f64> = grid.maxwellian().iter().map(|f| f.sqrt()).collect();
    let coefficient = |w: &[f64], h: &[f64]| -> f64 {
        w.iter()
            .zip(h)
            .zip(&root)
            .map(|((w, h), r)| w * h / r)
            .sum()
    };
    let times = [0.5, 10.0, 200.0];
    let largest = modes
        .iter()
        .fold(0.0, |m: f64, w| m.max(coefficient(w, &h0).abs()));
    assert!(coefficient(&modes[planted], &h0).abs() > 0.1 * largest);
    for (h, t) in projected.propagate(&h0, &times).iter().zip(times) {
        for (k, w) in modes.iter().enumerate() {
            let c = coefficient(w, &h0);
            let gain = if k == planted {
                1.0
            } else {
                libm::exp(spectrum(k) * t)
            };
            let got = coefficient(w, h);
            assert!(
                (got - c * gain).abs() <= 1e-12 * largest,
                "mode {k}, t {t}: {got} vs {}",
                c * gain
            );
        }
    }
}

/// An estimate that breaks detailed balance and every invariant, with
/// several positive eigenvalues after the projection: propagation freezes
/// those modes (`h` stays O(1) away from where the decaying modes alone
/// would take it) but keeps number, momentum and second moment of the start
/// to rounding (the clipped modes are orthogonal to the invariants).
#[test]
fn clipping_keeps_number_momentum_and_energy() {
    let grid = VelocityGrid::covering(3.0, 0.25);
    let spectrum = |k: usize| {
        if k.is_multiple_of(3) {
            0.01
        } else {
            -0.05 * (k + 1) as f64
        }
    };
    let (generator, _) = planted_operator(&grid, spectrum, 0.003);
    let projected =
        Dissipative::project(&generator, &grid.maxwellian(), &invariants(&grid)).unwrap();
    assert!(projected.largest_clipped > 0.005);
    let h0 = delta_at_zero(&grid);
    let start = grid.moments(&h0, 0.0, f64::INFINITY);
    let equilibrium = grid.conserving_equilibrium(0.0);
    // Rounding of the invariant p's moment: each eigenvector is orthogonal to
    // the invariant direction D^(1/2) p to n EPSILON ||D^(1/2) p||_2
    // (Jacobi), and h superposes them with coefficients c_k whose sum of
    // sizes is at most sqrt(n) ||D^(-1/2) h0||_2 = sqrt(n / f0_start).
    let root: Vec<f64> = grid.maxwellian().iter().map(|f| f.sqrt()).collect();
    let centre = grid.node_of(0.0).unwrap();
    let n = grid.len() as f64;
    let rounding: Vec<f64> = invariants(&grid)
        .iter()
        .map(|p| {
            let direction: f64 = p.iter().zip(&root).map(|(p, r)| (p * r).powi(2)).sum();
            n * f64::EPSILON * direction.sqrt() * (n.sqrt() / root[centre])
        })
        .collect();
    for h in projected.propagate(&h0, &[10.0, 100.0, 1000.0]) {
        let frozen: f64 = h.iter().zip(&equilibrium).map(|(x, e)| (x - e).abs()).sum();
        assert!(frozen > 0.1, "no frozen mode to test: {frozen}");
        let moments = grid.moments(&h, 0.0, f64::INFINITY);
        for ((m, s), r) in moments.iter().zip(&start).zip(&rounding) {
            assert!(
                (m - s).abs() <= *r,
                "{moments:?} against {start:?}: {rounding:?}"
            );
        }
    }
}

/// The late relaxation two independent ways (issue 55, item 3): the decay
/// rate of the relative entropy along the evolution from `delta(u)` by the
/// generators of one set of scenes (seed 21), against the slowest even mode
/// (the slowest one `delta(u)` excites) of the spectrum of the generators of
/// an independent set (seed 22), for the special particle and for the full
/// operator: within three combined jackknife errors, each rate to 10%. Both
/// sets are Dirichlet forms (`balanced_generators`, as `evolve` and
/// `spectrum` build them); the evolution's rate is the most precise one in
/// the second half of the schedule, where the slowest excited mode dominates.
#[test]
fn the_late_decay_agrees_with_the_spectrum_of_independent_scenes() {
    let grid = VelocityGrid::covering(3.0, 0.1);
    let centre = grid.node_of(0.0).unwrap();
    let (evolved, analysed) = (events(21, 16, 2.0), events(22, 16, 2.0));
    let balanced = |events: &[Event]| {
        balanced_generators(
            events,
            &Draws::count(events),
            &grid,
            KICK_FLOOR,
            centre,
            |_| (),
        )
        .0
    };
    let gamma = gamma(&evolved);
    let schedule = [0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0];
    let times: Vec<f64> = schedule.iter().map(|t| t / gamma).collect();
    let evolution = GridEvolution::new(&balanced(&evolved), &grid, centre, 0.0, &times).unwrap();
    let independent = balanced(&analysed);
    let f0 = grid.maxwellian();
    let number = vec![vec![1.0; grid.len()]];
    type Part = fn(&Generators) -> &Generator;
    let parts: [(&str, Part, Vec<Vec<f64>>); 2] = [
        ("full", |g| &g.full, invariants(&grid)),
        ("tagged", |g| &g.tagged, number),
    ];
    for (process, (name, part, conserved)) in parts.into_iter().enumerate() {
        let picked: Vec<Generator> = independent.iter().map(|g| part(g).clone()).collect();
        let slowest_even = replicate_means(&picked).scalar(|m| {
            let found = spectrum(m, &f0, &conserved, 0).unwrap();
            let even = found.parities.iter().position(|&p| p > 0.0).unwrap();
            found.rates[even]
        });
        let evolving = &evolution.processes[process];
        let late = (schedule.len() / 2..schedule.len())
            .map(|k| evolving.entropy_decay(&grid, k, times[k] - times[k - 1]))
            .min_by(|a, b| a.stderr.total_cmp(&b.stderr))
            .unwrap();
        let z = (late.mean - slowest_even.mean) / libm::hypot(late.stderr, slowest_even.stderr);
        assert!(
            z.abs() < 3.0
                && late.stderr < 0.1 * late.mean
                && slowest_even.stderr < 0.1 * slowest_even.mean,
            "{name}: entropy decays at {late:?}, independent slowest even mode {slowest_even:?}, z = {z}"
        );
    }
}
