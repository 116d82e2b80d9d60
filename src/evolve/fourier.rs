//! The discrete Fourier transform of a power-of-two length by the radix-2
//! Cooley-Tukey algorithm (iterative, decimation in time), with every
//! twiddle factor from `libm`: one fixed sequence of floating-point
//! operations, so the result is the same on every x86-64 CPU. (rustfft picks
//! SSE or AVX code at run time and takes its twiddles from the system's sin
//! and cos, whose FMA variants the CPU decides: its spectra, and the
//! early-evolution tables built on them, differed between machines.)
//!
//! Conventions as usual: forward `X_k = sum_j x_j e^{-2 pi i j k / n}`,
//! inverse with `e^{+2 pi i j k / n}` and no `1/n`.

use std::ops::{Add, Mul, Sub};

/// A complex number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex {
    /// `re + i im`.
    pub const fn new(re: f64, im: f64) -> Complex {
        Complex { re, im }
    }

    /// The complex conjugate.
    fn conj(self) -> Complex {
        Complex::new(self.re, -self.im)
    }

    /// `e^z = e^re (cos im + i sin im)`, from `libm`.
    pub fn exp(self) -> Complex {
        let (sin, cos) = libm::sincos(self.im);
        let modulus = libm::exp(self.re);
        Complex::new(modulus * cos, modulus * sin)
    }
}

impl Add for Complex {
    type Output = Complex;
    fn add(self, other: Complex) -> Complex {
        Complex::new(self.re + other.re, self.im + other.im)
    }
}

impl Sub for Complex {
    type Output = Complex;
    fn sub(self, other: Complex) -> Complex {
        Complex::new(self.re - other.re, self.im - other.im)
    }
}

impl Mul for Complex {
    type Output = Complex;
    fn mul(self, other: Complex) -> Complex {
        Complex::new(
            self.re * other.re - self.im * other.im,
            self.re * other.im + self.im * other.re,
        )
    }
}

impl Mul<f64> for Complex {
    type Output = Complex;
    fn mul(self, factor: f64) -> Complex {
        Complex::new(self.re * factor, self.im * factor)
    }
}

/// Transforms of one power-of-two length, with its twiddle factors.
pub struct Fourier {
    /// The length `n`.
    size: usize,
    /// `e^{-2 pi i k / n}` for `k < n / 2`.
    twiddles: Vec<Complex>,
}

impl Fourier {
    /// The transforms of length `size`, a power of two.
    pub fn new(size: usize) -> Fourier {
        assert!(
            size.is_power_of_two(),
            "FFT length {size} is not a power of two"
        );
        let twiddles = (0..size / 2)
            .map(|k| {
                let (cos, sin) = unit_root(k, size);
                Complex::new(cos, -sin)
            })
            .collect();
        Fourier { size, twiddles }
    }

    /// The forward transform of `data` in place.
    pub fn forward(&self, data: &mut [Complex]) {
        self.transform(data, false);
    }

    /// The inverse transform of `data` in place (not divided by `n`).
    pub fn inverse(&self, data: &mut [Complex]) {
        self.transform(data, true);
    }

    fn transform(&self, data: &mut [Complex], inverse: bool) {
        let size = self.size;
        assert_eq!(
            data.len(),
            size,
            "data of another length than the transform's"
        );
        let bits = size.trailing_zeros();
        for i in 0..size {
            let j = i
                .reverse_bits()
                .checked_shr(usize::BITS - bits)
                .unwrap_or(0);
            if i < j {
                data.swap(i, j);
            }
        }
        let mut half = 1;
        while half < size {
            let stride = size / (2 * half);
            for start in (0..size).step_by(2 * half) {
                for k in 0..half {
                    let twiddle = self.twiddles[k * stride];
                    let twiddle = if inverse { twiddle.conj() } else { twiddle };
                    let even = data[start + k];
                    let odd = data[start + k + half] * twiddle;
                    data[start + k] = even + odd;
                    data[start + k + half] = even - odd;
                }
            }
            half *= 2;
        }
    }
}

/// `(cos, sin)` of `2 pi k / n` for `k <= n / 2`: `sincos` only for angles up
/// to `pi / 4`, the rest by the exact reflections `pi - a` and `pi / 2 - a`,
/// so every factor is as accurate as the sine of a small angle.
fn unit_root(k: usize, n: usize) -> (f64, f64) {
    if 4 * k > n {
        let (cos, sin) = unit_root(n / 2 - k, n);
        return (-cos, sin);
    }
    if 8 * k > n {
        let (cos, sin) = unit_root(n / 4 - k, n);
        return (sin, cos);
    }
    let (sin, cos) = libm::sincos(2.0 * std::f64::consts::PI * k as f64 / n as f64);
    (cos, sin)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transform by its definition, `O(n^2)`.
    fn direct(data: &[Complex], sign: f64) -> Vec<Complex> {
        let n = data.len();
        (0..n)
            .map(|k| {
                data.iter()
                    .enumerate()
                    .fold(Complex::new(0.0, 0.0), |sum, (j, &x)| {
                        let angle =
                            sign * 2.0 * std::f64::consts::PI * ((j * k) % n) as f64 / n as f64;
                        let (sin, cos) = libm::sincos(angle);
                        sum + x * Complex::new(cos, sin)
                    })
            })
            .collect()
    }

    fn sample(n: usize) -> Vec<Complex> {
        (0..n)
            .map(|j| {
                let x = j as f64;
                Complex::new(libm::sin(0.37 * x * x) + 0.1, libm::cos(1.3 * x) * 0.5)
            })
            .collect()
    }

    /// Agreement with the definition, to rounding (`~ log2(n) eps` relative
    /// to the largest coefficient).
    #[test]
    fn the_fast_transform_is_the_definition() {
        for n in [1, 2, 4, 8, 64, 256] {
            let data = sample(n);
            let fourier = Fourier::new(n);
            for (sign, inverse) in [(-1.0, false), (1.0, true)] {
                let mut fast = data.clone();
                if inverse {
                    fourier.inverse(&mut fast);
                } else {
                    fourier.forward(&mut fast);
                }
                let exact = direct(&data, sign);
                let scale = exact
                    .iter()
                    .map(|c| c.re.abs().max(c.im.abs()))
                    .fold(1.0, f64::max);
                for (a, b) in fast.iter().zip(&exact) {
                    assert!((a.re - b.re).abs() < 1e-13 * scale, "n = {n}: {a:?} {b:?}");
                    assert!((a.im - b.im).abs() < 1e-13 * scale, "n = {n}: {a:?} {b:?}");
                }
            }
        }
    }

    /// Inverse after forward gives `n` times the data (Parseval's
    /// normalization), and a delta transforms to a constant.
    #[test]
    fn inverse_undoes_forward_and_a_delta_is_flat() {
        let n = 1024;
        let data = sample(n);
        let fourier = Fourier::new(n);
        let mut round = data.clone();
        fourier.forward(&mut round);
        fourier.inverse(&mut round);
        for (a, b) in round.iter().zip(&data) {
            assert!((a.re / n as f64 - b.re).abs() < 1e-13);
            assert!((a.im / n as f64 - b.im).abs() < 1e-13);
        }
        let mut delta = vec![Complex::new(0.0, 0.0); n];
        delta[0] = Complex::new(1.0, 0.0);
        fourier.forward(&mut delta);
        assert!(delta.iter().all(|c| *c == Complex::new(1.0, 0.0)));
    }
}
