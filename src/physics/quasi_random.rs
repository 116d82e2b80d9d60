//! Randomized quasi-Monte Carlo point sets for sampling scenes (numerics.md,
//! "Sampling scenes"), and the standard normal CDF and quantile that map their
//! coordinates onto Gaussian proposals.
//!
//! A scene is three uniform coordinates (arrival offset and two launch speeds)
//! pushed through exact inverse CDFs. [`ScrambledSobol`] supplies them as the
//! first three dimensions of Sobol's sequence under Owen's nested uniform
//! scrambling. Every scrambled point is uniform on the unit cube, so estimates
//! are unbiased and independent randomizations give an honest error bar from
//! their spread; the net structure survives the scrambling, so for smooth
//! integrands the standard deviation over randomizations of an average over
//! `N = 2^m` points falls like `N^-3/2 (log N)^((s-1)/2)` instead of
//! `N^-1/2` (Owen 1997); the scene integrands are not smooth and numerics.md
//! measured `N^-0.73` on them.
//!
//! What this is not: a pseudo-random generator (the points of one
//! randomization are strongly dependent by design; only distinct
//! randomizations are independent of each other), a Sobol' sequence in more
//! than three dimensions or beyond `2^32` points, or a general library of
//! special functions.
//!
//! References:
//! * I. M. Sobol', "On the distribution of points in a cube and the approximate
//!   evaluation of integrals", USSR Comput. Math. Math. Phys. 7 (1967) 86-112.
//! * P. Bratley and B. L. Fox, "Algorithm 659: Implementing Sobol's
//!   quasirandom sequence generator", ACM TOMS 14 (1988) 88-100.
//! * S. Joe and F. Y. Kuo, "Constructing Sobol sequences with better
//!   two-dimensional projections", SIAM J. Sci. Comput. 30 (2008) 2635-2654;
//!   direction numbers from their file `new-joe-kuo-6.21201`.
//! * A. B. Owen, "Randomly permuted (t,m,s)-nets and (t,s)-sequences", in
//!   Monte Carlo and Quasi-Monte Carlo Methods in Scientific Computing,
//!   Lecture Notes in Statistics 106 (1995) 299-317; "Scrambled net variance
//!   for integrals of smooth functions", Ann. Statist. 25 (1997) 1541-1562;
//!   "Scrambling Sobol' and Niederreiter-Xing points", J. Complexity 14 (1998)
//!   466-489.
//! * G. L. Steele, D. Lea and C. H. Flood, "Fast splittable pseudorandom number
//!   generators", OOPSLA 2014 (SplitMix64), with D. Stafford's "Mix13"
//!   finalizer ("Better bit mixing", 2011).
//! * M. J. Wichura, "Algorithm AS 241: The percentage points of the normal
//!   distribution", Applied Statistics 37 (1988) 477-484.
//! * W. J. Cody, "Rational Chebyshev approximations for the error function",
//!   Math. Comp. 23 (1969) 631-637, as packaged in function `ANORM` of
//!   "Algorithm 715: SPECFUN", ACM TOMS 19 (1993) 22-32.

/// Number of coordinates of a point: arrival offset and two launch speeds.
const DIMENSIONS: usize = 3;

/// Bits of each coordinate. Indices run up to `2^32 - 1`, and the first
/// `2^32` points are distinct in every coordinate.
const PRECISION_BITS: usize = 32;

/// Width `2^-32` of the finest dyadic cell a coordinate resolves.
const CELL_WIDTH: f64 = 1.0 / (1_u64 << PRECISION_BITS) as f64;

/// One row `d s a m_1 ... m_s` of Joe & Kuo's table: the primitive polynomial
/// `x^s + a_1 x^(s-1) + ... + a_(s-1) x + 1` over GF(2) and the initial odd
/// integers `m_k < 2^k`.
struct JoeKuoRow {
    /// Degree `s` of the primitive polynomial.
    degree: usize,
    /// Bits `a_1 ... a_(s-1)` of the inner coefficients, `a_1` most significant.
    inner_coefficients: u32,
    /// Initial `m_1, ..., m_s`.
    initial: &'static [u32],
}

/// Rows `d = 2` and `d = 3` of `new-joe-kuo-6.21201`. Dimension 1 is not in
/// the table: it has `m_k = 1` for every `k` (van der Corput in base 2).
const JOE_KUO_ROWS: [JoeKuoRow; DIMENSIONS - 1] = [
    JoeKuoRow {
        degree: 1,
        inner_coefficients: 0,
        initial: &[1],
    },
    JoeKuoRow {
        degree: 2,
        inner_coefficients: 1,
        initial: &[1, 3],
    },
];

/// Direction numbers `v_k = m_k 2^(32-k)`, `k = 1..=32` stored at `k - 1`,
/// one array per dimension.
const DIRECTION_NUMBERS: [[u32; PRECISION_BITS]; DIMENSIONS] = [
    van_der_corput_directions(),
    joe_kuo_directions(&JOE_KUO_ROWS[0]),
    joe_kuo_directions(&JOE_KUO_ROWS[1]),
];

/// `v_k = 2^(32-k)`: the coordinate is the bit reversal of the index.
const fn van_der_corput_directions() -> [u32; PRECISION_BITS] {
    let mut directions = [0; PRECISION_BITS];
    let mut k = 0;
    while k < PRECISION_BITS {
        directions[k] = 1 << (PRECISION_BITS - 1 - k);
        k += 1;
    }
    directions
}

/// Sobol's recurrence in the form of Bratley & Fox (1988), for `k > s`:
/// `v_k = v_(k-s) ^ (v_(k-s) >> s) ^ a_1 v_(k-1) ^ ... ^ a_(s-1) v_(k-s+1)`,
/// which is `m_k = 2 a_1 m_(k-1) ^ ... ^ 2^(s-1) a_(s-1) m_(k-s+1) ^ 2^s m_(k-s) ^ m_(k-s)`
/// scaled by `2^(32-k)`.
const fn joe_kuo_directions(row: &JoeKuoRow) -> [u32; PRECISION_BITS] {
    let s = row.degree;
    let mut directions = [0; PRECISION_BITS];
    let mut k = 0;
    while k < PRECISION_BITS {
        directions[k] = if k < s {
            row.initial[k] << (PRECISION_BITS - 1 - k)
        } else {
            let mut direction = directions[k - s] ^ (directions[k - s] >> s);
            let mut j = 1;
            while j < s {
                if (row.inner_coefficients >> (s - 1 - j)) & 1 == 1 {
                    direction ^= directions[k - j];
                }
                j += 1;
            }
            direction
        };
        k += 1;
    }
    directions
}

/// Unscrambled Sobol' coordinate of point `index` in natural (not Gray-code)
/// order: the XOR of `v_(k+1)` over the set bits `k` of `index`.
fn sobol_coordinate(directions: &[u32; PRECISION_BITS], index: u32) -> u32 {
    let mut coordinate = 0;
    let mut remaining = index;
    while remaining != 0 {
        coordinate ^= directions[remaining.trailing_zeros() as usize];
        remaining &= remaining - 1;
    }
    coordinate
}

/// Unscrambled Sobol' point `index` as 32-bit binary fractions.
fn sobol_point(index: u32) -> [u32; DIMENSIONS] {
    DIRECTION_NUMBERS.map(|directions| sobol_coordinate(&directions, index))
}

/// Weyl increment of SplitMix64, `2^64 / golden ratio`, rounded to odd.
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// Stafford's Mix13, the output function of SplitMix64: a bijection of `u64`
/// whose every output bit depends on every input bit.
fn mix64(state: u64) -> u64 {
    let mut z = state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Levels of the scramble tree served by one 64-bit hash: a subtree of depth
/// 6 has 63 nodes.
const LEVELS_PER_HASH: usize = 6;

/// Owen's nested uniform scramble of one 32-bit coordinate `x = 0.x_1 x_2 ...`
/// (Owen 1995, base 2): output digit `y_b = x_b ^ pi(x_1 ... x_(b-1))`, with
/// one independent fair bit `pi` per node of the binary tree of dyadic
/// intervals, the node at depth `b - 1` being the prefix `x_1 ... x_(b-1)`.
///
/// This is the definition itself, not the Laine-Karras hash approximation of
/// Burley (2020). The tree is cut into subtrees of depth 6 with roots at
/// depths `r = 0, 6, ..., 30`; the root with prefix `x_1 ... x_r` is numbered
/// `2^r + x_1 ... x_r` (heap order, unique over all depths), and the 63 node
/// bits of its subtree are bits 1..=63 of `mix64(seed ^ root * GOLDEN_GAMMA)`,
/// the node at local depth `j` with local prefix `p` owning bit `2^j + p`. For a uniformly random seed the bits of one
/// subtree are exactly independent (`mix64` is a bijection); distinct subtrees
/// rely on the mixing of `mix64`. Six hashes per coordinate instead of 32.
fn nested_uniform_scramble(coordinate: u32, seed: u64) -> u32 {
    let mut flips = 0;
    for start in (0..PRECISION_BITS).step_by(LEVELS_PER_HASH) {
        let root = (1 << start) | (u64::from(coordinate) >> (PRECISION_BITS - start));
        let node_bits = mix64(seed ^ root.wrapping_mul(GOLDEN_GAMMA));
        let digits = (coordinate << start) >> (PRECISION_BITS - LEVELS_PER_HASH);
        for local_depth in 0..LEVELS_PER_HASH.min(PRECISION_BITS - start) {
            let node = (1 << local_depth) | (digits >> (LEVELS_PER_HASH - local_depth));
            let flip = (node_bits >> node) as u32 & 1;
            flips |= flip << (PRECISION_BITS - 1 - start - local_depth);
        }
    }
    coordinate ^ flips
}

/// Midpoint of the dyadic cell of width `2^-32` holding the binary fraction
/// `bits`: `(bits + 1/2) 2^-32`, exact in `f64`, in `[2^-33, 1 - 2^-33]`.
fn cell_midpoint(bits: u32) -> f64 {
    (f64::from(bits) + 0.5) * CELL_WIDTH
}

/// Sobol' points in three dimensions (Joe & Kuo 2008 direction numbers;
/// dimension 1 is van der Corput in base 2), 32-bit precision, randomized by
/// Owen's nested uniform scrambling with an independent scramble per
/// dimension.
///
/// Use the first `N = 2^m` indices of a randomization: those points form a
/// scrambled `(1, m, 3)`-net (dimensions 1 and 2 alone a `(0, m, 2)`-net), and
/// only complete nets get the fast convergence; other `N` stay unbiased.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScrambledSobol {
    /// Seed of the scramble tree of each dimension.
    dimension_seeds: [u64; DIMENSIONS],
}

impl ScrambledSobol {
    /// Independent randomization number `randomization` of the point set,
    /// derived deterministically from `seed` (same inputs, same points on any
    /// machine or thread). The dimension seeds are the first three SplitMix64
    /// outputs from the state `mix64(mix64(seed + gamma) ^ randomization)`.
    pub fn new(seed: u64, randomization: u64) -> ScrambledSobol {
        let state = mix64(mix64(seed.wrapping_add(GOLDEN_GAMMA)) ^ randomization);
        ScrambledSobol {
            dimension_seeds: std::array::from_fn(|dimension| {
                mix64(state.wrapping_add(GOLDEN_GAMMA.wrapping_mul(dimension as u64 + 1)))
            }),
        }
    }

    /// Point `index` (0-based; any index, any order, `O(32)` per coordinate)
    /// as three coordinates in the open interval `(0, 1)`.
    ///
    /// Each coordinate is the midpoint of the scrambled `2^-32` cell, so it
    /// lies in `[2^-33, 1 - 2^-33]` and is never exactly 0 or 1: inverse CDFs
    /// are always finite, and their tails are cut at probability `2^-33`
    /// (e.g. `|standard_normal_quantile| <= 6.33`). Over randomizations each
    /// coordinate is uniform on the `2^32` midpoints, whose mean is exactly 1/2.
    pub fn point(&self, index: u32) -> [f64; DIMENSIONS] {
        let sobol = sobol_point(index);
        std::array::from_fn(|dimension| {
            cell_midpoint(nested_uniform_scramble(
                sobol[dimension],
                self.dimension_seeds[dimension],
            ))
        })
    }
}

/// `sum_k coefficients[k] x^k` by Horner's rule (ascending powers).
fn polynomial<const N: usize>(coefficients: &[f64; N], x: f64) -> f64 {
    coefficients.iter().rev().fold(0.0, |sum, &c| sum * x + c)
}

/// AS 241 switches from the central to the tail approximations at
/// `|p - 1/2| = 0.425`; the central one is in `r = 0.425^2 - (p - 1/2)^2`.
const QUANTILE_CENTRAL_SPLIT: f64 = 0.425;
const QUANTILE_CENTRAL_SHIFT: f64 = 0.180625;

/// In the tails AS 241 works in `r = sqrt(-ln min(p, 1 - p))`: the
/// intermediate approximation in `r - 1.6` for `r <= 5`, the far tail in
/// `r - 5` (beyond `p ~ 1.4e-11`).
const QUANTILE_TAIL_SPLIT: f64 = 5.0;
const QUANTILE_INTERMEDIATE_SHIFT: f64 = 1.6;

/// PPND16 coefficients, ascending powers, digits as published (Wichura 1988):
/// `A0..A7` and `1, B1..B7`, central region.
#[allow(clippy::excessive_precision, reason = "digits as published")]
const PPND16_A: [f64; 8] = [
    3.3871328727963666080e0,
    1.3314166789178437745e2,
    1.9715909503065514427e3,
    1.3731693765509461125e4,
    4.5921953931549871457e4,
    6.7265770927008700853e4,
    3.3430575583588128105e4,
    2.5090809287301226727e3,
];
#[allow(clippy::excessive_precision, reason = "digits as published")]
const PPND16_B: [f64; 8] = [
    1.0,
    4.2313330701600911252e1,
    6.8718700749205790830e2,
    5.3941960214247511077e3,
    2.1213794301586595867e4,
    3.9307895800092710610e4,
    2.8729085735721942674e4,
    5.2264952788528545610e3,
];
/// PPND16 `C0..C7` and `1, D1..D7`, intermediate tail (`r <= 5`).
#[allow(clippy::excessive_precision, reason = "digits as published")]
const PPND16_C: [f64; 8] = [
    1.42343711074968357734e0,
    4.63033784615654529590e0,
    5.76949722146069140550e0,
    3.64784832476320460504e0,
    1.27045825245236838258e0,
    2.41780725177450611770e-1,
    2.27238449892691845833e-2,
    7.74545014278341407640e-4,
];
#[allow(clippy::excessive_precision, reason = "digits as published")]
const PPND16_D: [f64; 8] = [
    1.0,
    2.05319162663775882187e0,
    1.67638483018380384940e0,
    6.89767334985100004550e-1,
    1.48103976427480074590e-1,
    1.51986665636164571966e-2,
    5.47593808499534494600e-4,
    1.05075007164441684324e-9,
];
/// PPND16 `E0..E7` and `1, F1..F7`, far tail (`r > 5`).
#[allow(clippy::excessive_precision, reason = "digits as published")]
const PPND16_E: [f64; 8] = [
    6.65790464350110377720e0,
    5.46378491116411436990e0,
    1.78482653991729133580e0,
    2.96560571828504891230e-1,
    2.65321895265761230930e-2,
    1.24266094738807843860e-3,
    2.71155556874348757815e-5,
    2.01033439929228813265e-7,
];
#[allow(clippy::excessive_precision, reason = "digits as published")]
const PPND16_F: [f64; 8] = [
    1.0,
    5.99832206555887937690e-1,
    1.36929880922735805310e-1,
    1.48753612908506148525e-2,
    7.86869131145613259100e-4,
    1.84631831751005468180e-5,
    1.42151175831644588870e-7,
    2.04426310338993978564e-15,
];

/// Inverse `Phi^-1(p)` of the standard normal CDF (probit), Wichura's AS 241
/// (PPND16), relative error about `1e-16` over `(0, 1)`:
/// `q R_AB(0.180625 - q^2)` with `q = p - 1/2` for `|q| <= 0.425`, otherwise
/// `sign(q) R(r - shift)` with `r = sqrt(-ln min(p, 1 - p))` and the rational
/// functions `R_CD` (`r <= 5`) or `R_EF`.
///
/// `probit(1/2) = 0` exactly, and `probit(1 - p) = -probit(p)` exactly
/// whenever `1 - p` is exact in floating point. `p = 0` gives `-inf`, `p = 1`
/// gives `+inf`, and `p` outside `[0, 1]` or NaN gives NaN. Note that `1 - p`
/// rounds for `p < 1/2`, so pass the lower tail probability itself where it is
/// known rather than its complement.
pub fn standard_normal_quantile(p: f64) -> f64 {
    let q = p - 0.5;
    if q.abs() <= QUANTILE_CENTRAL_SPLIT {
        let r = QUANTILE_CENTRAL_SHIFT - q * q;
        return q * polynomial(&PPND16_A, r) / polynomial(&PPND16_B, r);
    }
    if !(p > 0.0 && p < 1.0) {
        return if p == 0.0 {
            f64::NEG_INFINITY
        } else if p == 1.0 {
            f64::INFINITY
        } else {
            f64::NAN
        };
    }
    let tail = if q < 0.0 { p } else { 1.0 - p };
    let r = (-libm::log(tail)).sqrt();
    let magnitude = if r <= QUANTILE_TAIL_SPLIT {
        let s = r - QUANTILE_INTERMEDIATE_SHIFT;
        polynomial(&PPND16_C, s) / polynomial(&PPND16_D, s)
    } else {
        let s = r - QUANTILE_TAIL_SPLIT;
        polynomial(&PPND16_E, s) / polynomial(&PPND16_F, s)
    };
    if q < 0.0 { -magnitude } else { magnitude }
}

/// Cody's ANORM uses the central approximation for `|x| <= 0.66291` and the
/// asymptotic one beyond `sqrt(32)`.
const CDF_CENTRAL_SPLIT: f64 = 0.66291;
const CDF_ASYMPTOTIC_SPLIT: f64 = 5.656854248;

/// Beyond `|x| = 40`, `Phi(-|x|) < 4e-350` rounds to zero.
const CDF_ZERO_BEYOND: f64 = 40.0;

/// `1 / sqrt(2 pi)`, the limit of `y Phi(-y) exp(y^2/2)` as `y -> inf`
/// (ANORM's `SQRPI`).
#[allow(clippy::excessive_precision, reason = "digits as published")]
const FRAC_1_SQRT_2PI: f64 = 3.9894228040143267794e-1;

/// ANORM's `A` and `B`, rearranged to ascending powers of `x^2` (Cody's
/// `A(5)` is the leading coefficient): `Phi(x) = 1/2 + x A(x^2) / B(x^2)`.
#[allow(clippy::excessive_precision, reason = "digits as published")]
const ANORM_A: [f64; 5] = [
    1.8154981253343561249e04,
    1.0676894854603709582e03,
    1.6102823106855587881e02,
    2.2352520354606839287e00,
    6.5682337918207449113e-2,
];
#[allow(clippy::excessive_precision, reason = "digits as published")]
const ANORM_B: [f64; 5] = [
    4.5507789335026729956e04,
    1.0260932208618978205e04,
    9.7609855173777669322e02,
    4.7202581904688241870e01,
    1.0,
];
/// ANORM's `C` and `D` in ascending powers of `y = |x|` (Cody's `C(9)`
/// leads): `Phi(-y) = exp(-y^2/2) C(y) / D(y)` for `0.66291 < y <= sqrt(32)`.
#[allow(clippy::excessive_precision, reason = "digits as published")]
const ANORM_C: [f64; 9] = [
    9.8427148383839780218e03,
    1.1602651437647350124e04,
    6.8481904505362823326e03,
    2.4945375852903726711e03,
    5.9727027639480026226e02,
    9.3506656132177855979e01,
    8.8831497943883759412e00,
    3.9894151208813466764e-1,
    1.0765576773720192317e-8,
];
#[allow(clippy::excessive_precision, reason = "digits as published")]
const ANORM_D: [f64; 9] = [
    1.9685429676859990727e04,
    3.8912003286093271411e04,
    3.4900952721145977266e04,
    1.8615571640885098091e04,
    6.4855582982667607550e03,
    1.5193775994075548050e03,
    2.3538790178262499861e02,
    2.2266688044328115691e01,
    1.0,
];
/// ANORM's `P` and `Q` in ascending powers of `z = 1/y^2` (Cody's `P(6)`
/// leads): `Phi(-y) = exp(-y^2/2) [1/sqrt(2 pi) - z P(z) / Q(z)] / y` for
/// `y > sqrt(32)`.
#[allow(clippy::excessive_precision, reason = "digits as published")]
const ANORM_P: [f64; 6] = [
    2.9112874951168792e-5,
    1.421619193227893466e-3,
    2.2235277870649807e-2,
    1.274011611602473639e-1,
    2.1589853405795699e-1,
    2.307344176494017303e-2,
];
#[allow(clippy::excessive_precision, reason = "digits as published")]
const ANORM_Q: [f64; 6] = [
    7.29751555083966205e-5,
    3.78239633202758244e-3,
    6.59881378689285515e-2,
    4.68238212480865118e-1,
    1.28426009614491121e00,
    1.0,
];

/// `exp(-y^2/2)` without the error of rounding `y^2`: with `t = trunc(16 y)/16`
/// (so `t^2` is exact), `exp(-t^2/2) exp(-(y - t)(y + t)/2)` (Cody's ANORM).
fn gaussian_factor(y: f64) -> f64 {
    let coarse = (16.0 * y).trunc() / 16.0;
    let remainder = (y - coarse) * (y + coarse);
    libm::exp(-0.5 * coarse * coarse) * libm::exp(-0.5 * remainder)
}

/// Lower tail `Phi(-y)` for `y > 0.66291`, relative error of a few ulps
/// where it does not underflow.
fn normal_lower_tail(y: f64) -> f64 {
    if y > CDF_ZERO_BEYOND {
        return 0.0;
    }
    let scaled = if y <= CDF_ASYMPTOTIC_SPLIT {
        polynomial(&ANORM_C, y) / polynomial(&ANORM_D, y)
    } else {
        let z = 1.0 / (y * y);
        (FRAC_1_SQRT_2PI - z * polynomial(&ANORM_P, z) / polynomial(&ANORM_Q, z)) / y
    };
    scaled * gaussian_factor(y)
}

/// Standard normal CDF `Phi(x) = (1/sqrt(2 pi)) int_-inf^x exp(-t^2/2) dt`
/// by Cody's near-minimax rational approximations (ANORM, Cody 1969/1993):
/// relative error of a few ulps for `x <= 0` (down to the underflow of
/// `Phi(x)` near `x = -38.5`), absolute error of a few ulps for `x > 0`
/// (so `1 - Phi(x)` for large `x` should be computed as `Phi(-x)`).
/// `Phi(0) = 1/2` exactly; NaN gives NaN.
pub fn standard_normal_cdf(x: f64) -> f64 {
    let y = x.abs();
    if y <= CDF_CENTRAL_SPLIT {
        let z = x * x;
        return 0.5 + x * polynomial(&ANORM_A, z) / polynomial(&ANORM_B, z);
    }
    if x.is_nan() {
        return x;
    }
    let lower_tail = normal_lower_tail(y);
    if x < 0.0 {
        lower_tail
    } else {
        1.0 - lower_tail
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first eight points of Sobol's sequence in Gray-code order as
    /// published (e.g. Bratley & Fox 1988; Joe & Kuo 2008) for the first
    /// three dimensions.
    const PUBLISHED_FIRST_POINTS: [[f64; DIMENSIONS]; 8] = [
        [0.0, 0.0, 0.0],
        [0.5, 0.5, 0.5],
        [0.75, 0.25, 0.25],
        [0.25, 0.75, 0.75],
        [0.375, 0.375, 0.625],
        [0.875, 0.875, 0.125],
        [0.625, 0.125, 0.875],
        [0.125, 0.625, 0.375],
    ];

    /// Direct construction in natural order gives published point `n` at the
    /// index whose bits are the Gray code `n ^ (n >> 1)`; dimension 1 is the
    /// bit-reversed index (van der Corput).
    #[test]
    fn unscrambled_points_match_published_sobol_values() {
        for (n, published) in (0_u32..).zip(PUBLISHED_FIRST_POINTS) {
            let bits = sobol_point(n ^ (n >> 1));
            let point = bits.map(|b| f64::from(b) * CELL_WIDTH);
            assert_eq!(point, published, "point {n}");
        }
        for index in [1, 2, 3, 1000, 123_456_789, u32::MAX] {
            assert_eq!(sobol_point(index)[0], index.reverse_bits());
        }
    }

    /// Leading `count` bits of a coordinate, i.e. the index of its dyadic
    /// interval of width `2^-count`.
    fn leading_bits(coordinate: f64, count: u32) -> usize {
        (coordinate * f64::from(1_u32 << count)) as usize
    }

    /// Counts the first `2^m` points of `points` in the elementary boxes of
    /// widths `2^-widths[d]` along each dimension (`sum widths = m - t`) and
    /// checks that each holds exactly `2^t` points.
    fn assert_elementary_boxes_balanced(points: &[[f64; DIMENSIONS]], widths: [u32; DIMENSIONS]) {
        let cells: u32 = widths.iter().sum();
        let mut counts = vec![0_usize; 1 << cells];
        for point in points {
            let cell = (0..DIMENSIONS).fold(0, |cell, d| {
                (cell << widths[d]) | leading_bits(point[d], widths[d])
            });
            counts[cell] += 1;
        }
        let expected = points.len() >> cells;
        assert!(
            counts.iter().all(|&c| c == expected),
            "widths {widths:?}: {counts:?}"
        );
    }

    /// Owen scrambling preserves the `(t, m, s)`-net property of the first
    /// `2^m` points: each dimension alone is stratified into `2^m` intervals,
    /// dimensions 1 and 2 (a `(0, 2)`-sequence) into every elementary box of
    /// area `2^-m`, and all three (a `(1, 3)`-sequence: no `(0, 3)`-sequence
    /// exists in base 2) into every box of volume `2^(1-m)` with two points.
    #[test]
    fn scrambled_prefixes_are_nets() {
        for randomization in 0..3 {
            let sobol = ScrambledSobol::new(17, randomization);
            for m in 4..=10 {
                let points: Vec<_> = (0..1 << m).map(|i| sobol.point(i)).collect();
                for d in 0..DIMENSIONS {
                    let mut widths = [0; DIMENSIONS];
                    widths[d] = m;
                    assert_elementary_boxes_balanced(&points, widths);
                }
                for first in 0..=m {
                    assert_elementary_boxes_balanced(&points, [first, m - first, 0]);
                }
                for first in 0..m {
                    for second in 0..m - first {
                        assert_elementary_boxes_balanced(
                            &points,
                            [first, second, m - 1 - first - second],
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn randomizations_are_reproducible_and_distinct() {
        let indices = [0, 1, 2, 777, 1 << 20, u32::MAX];
        let points = |seed, randomization| {
            indices.map(|i| ScrambledSobol::new(seed, randomization).point(i))
        };
        assert_eq!(points(5, 3), points(5, 3));
        let reference = points(5, 3).concat();
        for (seed, randomization) in [(5, 4), (6, 3), (3, 5), (0, 0)] {
            let other = points(seed, randomization).concat();
            assert!(
                reference.iter().zip(&other).all(|(a, b)| a != b),
                "{seed} {randomization}"
            );
        }
    }

    #[test]
    fn coordinates_lie_strictly_inside_the_unit_interval() {
        assert_eq!(cell_midpoint(0), 0.5 * CELL_WIDTH);
        assert_eq!(cell_midpoint(u32::MAX), 1.0 - 0.5 * CELL_WIDTH);
        assert!(cell_midpoint(u32::MAX) < 1.0);
        let point = ScrambledSobol::new(1, 2).point(3);
        assert!(point.iter().all(|&u| u > 0.0 && u < 1.0));
    }

    /// The scramble is nested: two coordinates whose first `k` digits agree
    /// share the tree nodes down to depth `k`, so their first `k + 1` digits
    /// are flipped alike in every randomization, while every deeper node is
    /// distinct and flips independently (agreement about half the time, here
    /// within 5 standard deviations `5 sqrt(1/4 / 4096) = 0.039` of 1/2). A
    /// digital shift (the same flips for all coordinates) would agree always.
    #[test]
    fn scramble_flips_depend_on_the_whole_prefix() {
        let seeds: Vec<u64> = (0..4096).map(mix64).collect();
        for shared in [0, 1, 5, 6, 13, 30] {
            let (x, x_prime) = (0_u32, 1_u32 << (PRECISION_BITS - 1 - shared));
            let agreements: Vec<u32> = seeds
                .iter()
                .map(|&seed| {
                    !(nested_uniform_scramble(x, seed)
                        ^ x
                        ^ nested_uniform_scramble(x_prime, seed)
                        ^ x_prime)
                })
                .collect();
            for depth in 0..PRECISION_BITS {
                let digit = 1 << (PRECISION_BITS - 1 - depth);
                let agreeing = agreements.iter().filter(|&&a| a & digit != 0).count();
                if depth <= shared {
                    assert_eq!(agreeing, seeds.len(), "shared {shared}, depth {depth}");
                } else {
                    let fraction = agreeing as f64 / seeds.len() as f64;
                    assert!(
                        (fraction - 0.5).abs() < 0.039,
                        "shared {shared}, depth {depth}: {fraction}"
                    );
                }
            }
        }
    }

    /// Over randomizations a scrambled point is uniform: for points 0 and
    /// 1000, every group of four consecutive output digits (depths 1-4, ...,
    /// 29-32, each set by different tree nodes) is uniform on its 16 values.
    /// Pearson's chi-square with 15 degrees of freedom over 4096
    /// randomizations must stay below 60 (upper tail probability 2.5e-7).
    #[test]
    fn scrambled_points_are_uniform_over_randomizations() {
        let randomizations = 4096_u32;
        for index in [0, 1000] {
            let bits: Vec<_> = (0..randomizations)
                .map(|r| {
                    let point = ScrambledSobol::new(99, u64::from(r)).point(index);
                    point.map(|u| (u / CELL_WIDTH) as u32)
                })
                .collect();
            for d in 0..DIMENSIONS {
                for group in 0..PRECISION_BITS as u32 / 4 {
                    let mut counts = [0_u32; 16];
                    for point in &bits {
                        counts[((point[d] << (4 * group)) >> 28) as usize] += 1;
                    }
                    let expected = f64::from(randomizations) / 16.0;
                    let chi_square: f64 = counts
                        .iter()
                        .map(|&c| (f64::from(c) - expected).powi(2) / expected)
                        .sum();
                    assert!(
                        chi_square < 60.0,
                        "index {index} dim {d} group {group}: {chi_square}"
                    );
                }
            }
        }
    }

    /// `int exp(x + y + z) dx dy dz = (e - 1)^3` over the unit cube with
    /// R = 16 randomizations of N = 2^12 points. The spread of the R
    /// estimates gives the standard error; plain Monte Carlo with the same
    /// R N points has standard error `sqrt(Var f / (R N))`, `Var f =
    /// ((e^2 - 1)/2)^3 - (e - 1)^6`. Measured with seed 2024: RQMC standard
    /// error 9.0e-6 against 1.02e-2 for Monte Carlo, a ratio of 1.1e3 (seeds
    /// 1, 7, 99, 12345: 1176, 944, 966, 761; the ratio grows about like `N`).
    #[test]
    fn randomized_sobol_beats_monte_carlo_on_a_smooth_integrand() {
        let (randomizations, points) = (16_u32, 1_u32 << 12);
        let integrand = |[x, y, z]: [f64; 3]| libm::exp(x + y + z);
        let estimates: Vec<f64> = (0..randomizations)
            .map(|r| {
                let sobol = ScrambledSobol::new(2024, u64::from(r));
                (0..points).map(|i| integrand(sobol.point(i))).sum::<f64>() / f64::from(points)
            })
            .collect();
        let r = f64::from(randomizations);
        let mean = estimates.iter().sum::<f64>() / r;
        let sample_variance = estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (r - 1.0);
        let standard_error = (sample_variance / r).sqrt();
        let e = std::f64::consts::E;
        let exact = (e - 1.0).powi(3);
        let monte_carlo_error =
            ((((e * e - 1.0) / 2.0).powi(3) - exact * exact) / (r * f64::from(points))).sqrt();
        assert!(
            (mean - exact).abs() < 4.0 * standard_error,
            "{mean} vs {exact} +- {standard_error}"
        );
        assert!(
            monte_carlo_error > 30.0 * standard_error,
            "{monte_carlo_error} vs {standard_error}"
        );
    }

    /// `Phi^-1(p)` from mpmath at 50 digits (root of `ncdf(x) = p` at the
    /// double nearest each `p`), rounded to double.
    const QUANTILE_REFERENCE: [(f64, f64); 8] = [
        (1e-300, -37.0470962993612),
        (1e-10, -6.361340902404057),
        (0.001, -3.0902323061678136),
        (0.025, -1.9599639845400543),
        (0.3, -0.5244005127080408),
        (0.5, 0.0),
        (0.9, 1.2815515655446006),
        (1.0 - 1e-12, 7.0344869100478356),
    ];

    /// AS 241 is accurate to about 1e-16; a few more ulps come from the
    /// rounding of the rational function's evaluation.
    #[test]
    fn quantile_matches_high_precision_values() {
        for (p, exact) in QUANTILE_REFERENCE {
            let x = standard_normal_quantile(p);
            assert!(
                (x - exact).abs() <= 1e-15 * exact.abs(),
                "p = {p}: {x} vs {exact}"
            );
        }
        assert_eq!(standard_normal_quantile(0.5), 0.0);
    }

    #[test]
    fn quantile_is_odd_about_one_half() {
        for k in 1..1024 {
            // `p = k / 2048` and `1 - p` are both exact.
            let p = f64::from(k) / 2048.0;
            assert_eq!(
                standard_normal_quantile(1.0 - p),
                -standard_normal_quantile(p),
                "p = {p}"
            );
        }
        for k in 2..=53 {
            // `p = 2^-k` and `1 - p` are exact, down into the far tail.
            let p = 0.5_f64.powi(k);
            assert_eq!(
                standard_normal_quantile(1.0 - p),
                -standard_normal_quantile(p),
                "p = {p}"
            );
        }
    }

    #[test]
    fn quantile_at_and_outside_the_ends_of_the_domain() {
        assert_eq!(standard_normal_quantile(0.0), f64::NEG_INFINITY);
        assert_eq!(standard_normal_quantile(1.0), f64::INFINITY);
        for p in [-0.1, 1.5, f64::NAN] {
            assert!(standard_normal_quantile(p).is_nan());
        }
        assert!(standard_normal_cdf(f64::NAN).is_nan());
        assert_eq!(standard_normal_cdf(f64::NEG_INFINITY), 0.0);
        assert_eq!(standard_normal_cdf(f64::INFINITY), 1.0);
    }

    /// `Phi(x)` from mpmath at 30 digits, rounded to double.
    const CDF_REFERENCE: [(f64, f64); 8] = [
        (-37.0, 5.725571222524577e-300),
        (-20.0, 2.7536241186062337e-89),
        (-8.0, 6.220960574271784e-16),
        (-1.0, 0.15865525393145705),
        (-0.5, 0.3085375387259869),
        (0.3, 0.6179114221889527),
        (1.96, 0.9750021048517795),
        (3.0, 0.9986501019683699),
    ];

    /// Cody's approximations carry 18 digits; the evaluation (a few
    /// multiplications, divisions and `exp` calls) costs a few ulps.
    #[test]
    fn cdf_matches_high_precision_values() {
        for (x, exact) in CDF_REFERENCE {
            let phi = standard_normal_cdf(x);
            assert!(
                (phi - exact).abs() <= 1e-15 * exact,
                "x = {x}: {phi} vs {exact}"
            );
        }
        assert_eq!(standard_normal_cdf(0.0), 0.5);
    }

    /// `Phi(Phi^-1(p)) = p`. With `x = Phi^-1(p)` off by a relative `e1` and
    /// `Phi` by `e2`, the result is off by `e2 + (x phi(x) / Phi(x)) e1`, and
    /// `|x phi / Phi| <= 1 + x^2` for `x < 0`: the tolerance is
    /// `8 eps (1 + x^2)`, i.e. `1e-14` near the centre and proportionally
    /// more in the far tail, where rounding `x` itself costs `x^2 eps`.
    #[test]
    fn quantile_and_cdf_are_inverse() {
        let lower_tail = (1..=300).map(|k| libm::pow(10_f64, -f64::from(k)));
        let body = (1..1000).map(|k| f64::from(k) / 1000.0);
        for p in lower_tail.chain(body) {
            let x = standard_normal_quantile(p);
            let tolerance = 8.0 * f64::EPSILON * (1.0 + x * x);
            let roundtrip = standard_normal_cdf(x);
            assert!(
                (roundtrip - p).abs() <= tolerance * p,
                "p = {p}: x = {x}, Phi(x) = {roundtrip}"
            );
        }
    }

    /// Neither function jumps where it switches approximations: over the 41
    /// consecutive doubles centred on each split both are linear to far
    /// below an ulp, so every value must lie within 4 ulps of the chord
    /// through the two ends (a jump at the split of more than about 8 ulps
    /// would not).
    #[test]
    fn approximations_join_continuously() {
        let far_tail_split = libm::exp(-QUANTILE_TAIL_SPLIT * QUANTILE_TAIL_SPLIT);
        let quantile_splits = [
            0.5 - QUANTILE_CENTRAL_SPLIT,
            0.5 + QUANTILE_CENTRAL_SPLIT,
            far_tail_split,
        ];
        let cdf_splits = [
            -CDF_ASYMPTOTIC_SPLIT,
            -CDF_CENTRAL_SPLIT,
            CDF_CENTRAL_SPLIT,
            CDF_ASYMPTOTIC_SPLIT,
        ];
        let neighbourhoods = quantile_splits
            .map(|p| ulp_neighbourhood(p).map(standard_normal_quantile))
            .into_iter()
            .chain(cdf_splits.map(|x| ulp_neighbourhood(x).map(standard_normal_cdf)));
        for values in neighbourhoods {
            let (first, last) = (values[0], values[values.len() - 1]);
            let chord = |i: usize| first + (last - first) * i as f64 / (values.len() - 1) as f64;
            let continuous = values
                .iter()
                .enumerate()
                .all(|(i, &v)| (v - chord(i)).abs() <= 4.0 * f64::EPSILON * v.abs());
            assert!(continuous, "{values:?}");
        }
    }

    /// `center` and the 20 doubles on each side of it, ascending.
    fn ulp_neighbourhood(center: f64) -> [f64; 41] {
        let mut value = center;
        for _ in 0..20 {
            value = value.next_down();
        }
        std::array::from_fn(|_| {
            let current = value;
            value = value.next_up();
            current
        })
    }
}
