//! The natural cubic spline of `ln G` in the warped distance from `u'`, the
//! kernel model's one curve (issue 59).

/// A natural cubic spline through `(knots[k], values[k])`: cubic between
/// knots, twice continuously differentiable, `S'' = 0` at the end knots, and
/// continued as the straight line of its end slope beyond them (which keeps
/// it twice differentiable there). Dimensionless in `t`; `values` in
/// whatever units the caller's `y` has.
#[derive(Clone, Debug, PartialEq)]
pub struct NaturalSpline {
    knots: Vec<f64>,
    values: Vec<f64>,
    /// `S''` at each knot.
    curvature: Vec<f64>,
}

impl NaturalSpline {
    /// The spline through the points; `knots` strictly ascending, at least two.
    /// The curvatures solve `h_(k-1) M_(k-1) / 6 + (h_(k-1) + h_k) M_k / 3 +
    /// h_k M_(k+1) / 6 = secant_k - secant_(k-1)` with `M_0 = M_(K-1) = 0`
    /// (de Boor, A Practical Guide to Splines, ch. IV).
    pub fn through(knots: &[f64], values: &[f64]) -> NaturalSpline {
        assert!(
            knots.len() >= 2 && values.len() == knots.len(),
            "a spline needs at least two knots and one value per knot"
        );
        let last = knots.len() - 1;
        let step = |k: usize| knots[k + 1] - knots[k];
        let secant = |k: usize| (values[k + 1] - values[k]) / step(k);
        let mut rows = vec![[0.0, 1.0, 0.0, 0.0]];
        rows.extend((1..last).map(|k| {
            let (left, right) = (step(k - 1), step(k));
            [
                left / 6.0,
                (left + right) / 3.0,
                right / 6.0,
                secant(k) - secant(k - 1),
            ]
        }));
        rows.push([0.0, 1.0, 0.0, 0.0]);
        NaturalSpline {
            knots: knots.to_vec(),
            values: values.to_vec(),
            curvature: crate::linalg::solve_tridiagonal(rows),
        }
    }

    /// `S(t)`.
    pub fn value(&self, t: f64) -> f64 {
        let (knots, values, m) = (&self.knots, &self.values, &self.curvature);
        let last = knots.len() - 1;
        if t < knots[0] {
            return values[0] + self.end_slope(0) * (t - knots[0]);
        }
        if t > knots[last] {
            return values[last] + self.end_slope(last) * (t - knots[last]);
        }
        let k = knots.partition_point(|&knot| knot <= t).clamp(1, last) - 1;
        let h = knots[k + 1] - knots[k];
        let a = (knots[k + 1] - t) / h;
        let b = 1.0 - a;
        a * values[k]
            + b * values[k + 1]
            + ((a * a * a - a) * m[k] + (b * b * b - b) * m[k + 1]) * h * h / 6.0
    }

    /// `S'` at the first (`0`) or the last end knot.
    fn end_slope(&self, end: usize) -> f64 {
        let (knots, values, m) = (&self.knots, &self.values, &self.curvature);
        if end == 0 {
            let h = knots[1] - knots[0];
            (values[1] - values[0]) / h - h * (2.0 * m[0] + m[1]) / 6.0
        } else {
            let h = knots[end] - knots[end - 1];
            (values[end] - values[end - 1]) / h + h * (m[end - 1] + 2.0 * m[end]) / 6.0
        }
    }
}

/// The warped distance from `u'` in which `ln G` is a spline: `t(x) = ln x +
/// x / x_c` (`x = |u - u'|` and the cut-off scale `x_c` in `v_th`). Near `u'`
/// it is `ln x`, where `G` is a power law `x^-beta`, a straight line in
/// `t`; far out it is `x / x_c`, where the cut-off `exp(-x^2 / 2 sigma^2)`
/// is a parabola in `t`: both are what a cubic spline holds exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Warp {
    /// `x_c` (`v_th`).
    pub cutoff_scale: f64,
}

impl Warp {
    /// `t(x)` for `x > 0`.
    pub fn t(self, x: f64) -> f64 {
        libm::log(x) + x / self.cutoff_scale
    }

    /// The `x > 0` with `t(x) = t`: Newton's method in `u = ln x` on `u +
    /// e^u / x_c - t`, increasing and convex in `u`, from `u = t` (at or
    /// above the root), from where it descends to the root without
    /// overshooting.
    pub fn x(self, t: f64) -> f64 {
        let mut u = t;
        for _ in 0..200 {
            let scaled = libm::exp(u) / self.cutoff_scale;
            let step = (u + scaled - t) / (1.0 + scaled);
            u -= step;
            if step.abs() <= 1e-15 * u.abs().max(1.0) {
                break;
            }
        }
        libm::exp(u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Through its knots, linear beyond them, `S'' = 0` at the ends, and
    /// exact for a straight line.
    #[test]
    fn natural_spline_interpolates_and_continues_straight() {
        let knots = [0.0, 0.7, 1.5, 3.0, 4.1];
        let values = [1.0, -2.0, 0.5, 3.0, 2.0];
        let spline = NaturalSpline::through(&knots, &values);
        for (t, v) in knots.iter().zip(values) {
            assert!((spline.value(*t) - v).abs() < 1e-14);
        }
        let second = |t: f64, h: f64| {
            (spline.value(t + h) - 2.0 * spline.value(t) + spline.value(t - h)) / (h * h)
        };
        assert!(
            second(4.1 + 1.0, 0.5).abs() < 1e-9,
            "straight beyond the end"
        );
        assert!(second(-1.0, 0.5).abs() < 1e-9, "straight before the start");
        assert!(second(0.0, 1e-4).abs() < 1e-3, "S'' = 0 at the first knot");
        let line = NaturalSpline::through(&knots, &knots.map(|t| 2.0 - 0.5 * t));
        for t in [-2.0, 0.3, 2.2, 6.0] {
            assert!((line.value(t) - (2.0 - 0.5 * t)).abs() < 1e-13);
        }
    }

    /// The spline is linear in its values: the sum of two splines is the
    /// spline of the summed values (what makes the cardinal basis).
    #[test]
    fn natural_spline_is_linear_in_its_values() {
        let knots = [0.0, 1.0, 2.5, 3.0];
        let (a, b) = ([1.0, 2.0, -1.0, 0.0], [0.5, -3.0, 2.0, 1.0]);
        let sum: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
        let (sa, sb, ss) = (
            NaturalSpline::through(&knots, &a),
            NaturalSpline::through(&knots, &b),
            NaturalSpline::through(&knots, &sum),
        );
        for t in [-1.0, 0.5, 2.7, 5.0] {
            assert!((sa.value(t) + sb.value(t) - ss.value(t)).abs() < 1e-13);
        }
    }

    /// `x(t(x)) = x` from `1e-6` to 10 scales.
    #[test]
    fn warp_inverts() {
        let warp = Warp {
            cutoff_scale: 0.005,
        };
        for x in [1e-6, 3e-5, 1e-3, 0.005, 0.02, 0.05] {
            let back = warp.x(warp.t(x));
            assert!((back - x).abs() <= 1e-13 * x, "{x} -> {back}");
        }
    }
}
