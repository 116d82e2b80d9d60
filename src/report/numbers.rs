//! Numbers as the command line prints them: `value ± error` to the digits
//! the error justifies, never more than an `f64` holds; bare values to six
//! significant digits; zeros without a sign.

/// Significant digits of a value printed without an error to round it to.
const BARE_DIGITS: i32 = 6;

/// Significant digits of a value above which its error is written in the
/// concise form `1.23456789(12)` rather than as `± 0.00000012`.
const CONCISE_DIGITS: i32 = 8;

/// Significant digits an `f64` reproduces whatever its value (`DBL_DIG`):
/// how a value is printed whose error is zero or below `RESOLVED_ERROR`.
const F64_DIGITS: i32 = 15;

/// Smallest error, relative to its value, that a two-digit error can state:
/// below it the error is a few units in the last place of an `f64` (2.2e-16
/// relative), rounding and not a measurement, and its digits would push the
/// value past 17 significant digits.
const RESOLVED_ERROR: f64 = 1e-15;

/// Decimal exponents printed in fixed notation: magnitudes `1e-4` to `1e6`.
const FIXED_EXPONENTS: std::ops::RangeInclusive<i32> = -4..=5;

/// How a `value ± error` is written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Notation {
    /// `(m ± e)e<exponent>` instead of fixed decimals.
    pub scientific: bool,
    /// `m(ee)`, the error in units of the value's last digit.
    pub concise: bool,
}

impl Notation {
    /// A notation that writes both `self`'s and `other`'s numbers in one form.
    pub fn covering(self, other: Notation) -> Notation {
        Notation {
            scientific: self.scientific || other.scientific,
            concise: self.concise || other.concise,
        }
    }
}

/// A finite `value ± error` with an error an `f64` resolves, rounded: the
/// decimal exponent of the error's second significant digit, the error's
/// two digits, and the decimal exponent of the larger of value and error.
struct Rounded {
    last: i32,
    digits: f64,
    magnitude: i32,
}

impl Rounded {
    /// `None` when the error is not a finite number above `RESOLVED_ERROR`
    /// of the value: those are written without digits of the error.
    fn of(value: f64, error: f64) -> Option<Rounded> {
        let error = error.abs();
        if !value.is_finite() || !error.is_finite() || error <= RESOLVED_ERROR * value.abs() {
            return None;
        }
        // After rounding to two digits, 9.96 becomes 10: one place up.
        let mut last = libm::log10(error).floor() as i32 - 1;
        if (error / 10f64.powi(last)).round() >= 100.0 {
            last += 1;
        }
        let digits = (error / 10f64.powi(last)).round();
        let magnitude = libm::log10(value.abs().max(digits * 10f64.powi(last))).floor() as i32;
        Some(Rounded {
            last,
            digits,
            magnitude,
        })
    }

    /// The notation the number takes alone.
    fn notation(&self) -> Notation {
        Notation {
            scientific: !FIXED_EXPONENTS.contains(&self.magnitude),
            concise: self.magnitude - self.last + 1 > CONCISE_DIGITS,
        }
    }
}

/// The notation [`with_error`] gives `value ± error` alone (the default one
/// when it has no digits of an error to write).
pub fn natural_notation(value: f64, error: f64) -> Notation {
    Rounded::of(value, error).map_or_else(Notation::default, |rounded| rounded.notation())
}

/// `value ± error` to the digits the error justifies: the error with two
/// significant digits, the value to the same decimal place; in fixed
/// notation for magnitudes from `1e-4` to `1e6`, otherwise as
/// `(m ± e)e<exponent>`. A value known to more than `CONCISE_DIGITS`
/// digits is written `m(ee)`, the error in units of the last digit. A value
/// that is not a number (NaN, infinite) prints `undefined`, which says why;
/// an exact zero (zero error) prints `0`, another value with a zero error
/// `F64_DIGITS` digits and `(exact)`, one with an error below
/// `RESOLVED_ERROR` of it the same digits and that bound, one with a
/// missing error `(no error estimate)`.
pub fn with_error(value: f64, error: f64, undefined: &str) -> String {
    written(value, error, undefined, natural_notation(value, error))
}

/// [`with_error`] in `notation` (one form for a column of numbers).
pub fn written(value: f64, error: f64, undefined: &str, notation: Notation) -> String {
    if !value.is_finite() {
        return undefined.to_string();
    }
    let Some(Rounded {
        last,
        digits,
        magnitude,
    }) = Rounded::of(value, error)
    else {
        return unresolved(value, error);
    };
    let rounded = digits * 10f64.powi(last);
    let (scale, exponent, decimals) = if notation.scientific {
        (
            10f64.powi(magnitude),
            format!("e{magnitude}"),
            magnitude - last,
        )
    } else {
        (1.0, String::new(), -last)
    };
    // Errors of 100 and more round the value to tens, hundreds, ...
    let value = if decimals < 0 {
        (value / 10f64.powi(last)).round() * 10f64.powi(last)
    } else {
        value
    };
    let decimals = decimals.max(0) as usize;
    let shown = fixed(value / scale, decimals);
    match (notation.concise, notation.scientific) {
        (true, _) => format!("{shown}({digits}){exponent}"),
        (false, false) => format!("{shown} ± {}", fixed(rounded, decimals)),
        (false, true) => format!("({shown} ± {}){exponent}", fixed(rounded / scale, decimals)),
    }
}

/// A finite `value` whose `error` has no digits to write: missing, zero, or
/// below `RESOLVED_ERROR` of the value.
fn unresolved(value: f64, error: f64) -> String {
    let shown = significant_to(value, F64_DIGITS);
    if !error.is_finite() {
        format!("{} (no error estimate)", significant(value))
    } else if error != 0.0 {
        format!("{shown} (error < {RESOLVED_ERROR:e} of it)")
    } else if value == 0.0 {
        shown
    } else if let Some((numerator, denominator)) = repeating_fraction(value) {
        format!("{numerator}/{denominator} (exact)")
    } else {
        format!("{shown} (exact)")
    }
}

/// The greatest common divisor of `a` and `b` (Euclid).
fn gcd(a: u64, b: u32) -> u64 {
    let (mut a, mut b) = (a, u64::from(b));
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Denominators up to which an exact value is recognised as a fraction.
const LARGEST_DENOMINATOR: u32 = 12;

/// `value` as `numerator / denominator` when it is such a fraction in
/// lowest terms to rounding (a few units in the last place) with a
/// denominator up to [`LARGEST_DENOMINATOR`] whose decimals repeat (a prime
/// factor other than 2 and 5: `1/3`, not `1/4`, which `0.25` writes exactly;
/// never an integer).
fn repeating_fraction(value: f64) -> Option<(i64, u32)> {
    let terminates = |mut q: u32| {
        for p in [2, 5] {
            while q.is_multiple_of(p) {
                q /= p;
            }
        }
        q == 1
    };
    (2..=LARGEST_DENOMINATOR)
        .filter(|&q| !terminates(q))
        .find_map(|q| {
            let numerator = (value * f64::from(q)).round();
            let close =
                (numerator / f64::from(q) - value).abs() <= 4.0 * f64::EPSILON * value.abs();
            let lowest = close && numerator.abs() < 1e15 && gcd(numerator.abs() as u64, q) == 1;
            lowest.then_some((numerator as i64, q))
        })
}

/// `x` with `decimals` decimals; a value that rounds to zero has no sign.
pub fn fixed(x: f64, decimals: usize) -> String {
    let text = format!("{x:.decimals$}");
    match text.strip_prefix('-') {
        Some(unsigned) if unsigned.chars().all(|c| c == '0' || c == '.') => unsigned.to_string(),
        _ => text,
    }
}

/// `x` to [`BARE_DIGITS`] significant digits ([`significant_to`]).
pub fn significant(x: f64) -> String {
    significant_to(x, BARE_DIGITS)
}

/// `x` to `digits` significant digits without trailing zeros, in fixed
/// notation for magnitudes from `1e-4` to `1e6`; zero as `0`.
pub fn significant_to(x: f64, digits: i32) -> String {
    if x == 0.0 {
        return "0".to_string();
    }
    let trim = |text: &str| -> String {
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            text.to_string()
        }
    };
    // The exponent after rounding to `digits` (9.9999996 becomes 10).
    let text = format!("{x:.*e}", (digits - 1) as usize);
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let magnitude: i32 = exponent.parse().unwrap_or(0);
    if FIXED_EXPONENTS.contains(&magnitude) {
        trim(&fixed(x, (digits - 1 - magnitude).max(0) as usize))
    } else {
        format!("{}e{exponent}", trim(mantissa))
    }
}

/// `x` as `format` shows it, or `undefined` when it is not a number.
pub fn or_why(x: f64, format: impl Fn(f64) -> String, undefined: &str) -> String {
    if x.is_finite() {
        format(x)
    } else {
        undefined.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two significant digits of the error, the value to the same place.
    #[test]
    fn values_are_rounded_to_the_error() {
        assert_eq!(
            with_error(3.1234e-4, 1.234e-6, "-"),
            "0.0003123 ± 0.0000012"
        );
        assert_eq!(with_error(1.23456, 0.0123, "-"), "1.235 ± 0.012");
        assert_eq!(with_error(12345.0, 234.0, "-"), "12350 ± 230");
    }

    /// A value known to more digits than fit a line gives its error in units
    /// of its last digit.
    #[test]
    fn precise_values_are_concise() {
        assert_eq!(
            with_error(-0.51370614225, 7.7e-10, "-"),
            "-0.51370614225(77)"
        );
        assert_eq!(
            with_error(3.0787446190007e7, 6.0e-2, "-"),
            "3.0787446190(60)e7"
        );
        assert_eq!(
            with_error(0.012345678, 1.2e-8, "-"),
            "0.012345678 ± 0.000000012"
        );
    }

    /// An error that rounds up to the next power of ten keeps two digits.
    #[test]
    fn an_error_rounding_up_keeps_two_digits() {
        assert_eq!(with_error(0.5, 0.00996, "-"), "0.500 ± 0.010");
    }

    /// Very small or large magnitudes share one exponent.
    #[test]
    fn small_and_large_magnitudes_share_an_exponent() {
        assert_eq!(with_error(2.5e-9, 1.2e-11, "-"), "(2.500 ± 0.012)e-9");
        assert_eq!(with_error(4.14864e6, 6.6e4, "-"), "(4.149 ± 0.066)e6");
        assert_eq!(with_error(-1.85e-17, 1.8e-15, "-"), "(0.0 ± 1.8)e-15");
    }

    /// A value that rounds to zero carries no sign, in any notation.
    #[test]
    fn a_value_rounding_to_zero_has_no_sign() {
        assert_eq!(with_error(-1e-9, 1e-3, "-"), "0.0000 ± 0.0010");
        assert_eq!(with_error(-4e-4, 0.02, "-"), "0.000 ± 0.020");
        assert_eq!(fixed(-0.0004, 3), "0.000");
        assert_eq!(fixed(-0.0, 1), "0.0");
        assert_eq!(significant(-0.0), "0");
    }

    /// An error below what an `f64` resolves adds no digits: the value gets
    /// the 15 an `f64` keeps, not 17 to 20 (the run summary printed
    /// `1.0000000000000000000(39)` and `0.00074437203303358(59)`).
    #[test]
    fn errors_below_f64_resolution_add_no_digits() {
        assert_eq!(with_error(1.0, 3.9e-19, "-"), "1 (error < 1e-15 of it)");
        assert_eq!(
            with_error(0.00074437203303358, 5.9e-19, "-"),
            "0.00074437203303358 (error < 1e-15 of it)"
        );
        // Just above the bound: 17 significant digits, no more.
        assert_eq!(
            with_error(1.2345678901234567, 2.4e-15, "-"),
            "1.2345678901234567(24)"
        );
    }

    /// Zero and missing errors, and values that are not numbers, say so; an
    /// exact zero is `0`.
    #[test]
    fn missing_numbers_say_why() {
        assert_eq!(with_error(0.0, 0.0, "-"), "0");
        assert_eq!(with_error(-0.0, 0.0, "-"), "0");
        assert_eq!(
            with_error(1.1637580872059066, 0.0, "-"),
            "1.16375808720591 (exact)"
        );
        assert_eq!(with_error(1.0 / 3.0, 0.0, "-"), "1/3 (exact)");
        assert_eq!(with_error(0.5 - 1.0 / 6.0, 0.0, "-"), "1/3 (exact)");
        assert_eq!(with_error(-5.0 / 12.0, 0.0, "-"), "-5/12 (exact)");
        assert_eq!(with_error(0.25, 0.0, "-"), "0.25 (exact)");
        assert_eq!(with_error(2.0, 0.0, "-"), "2 (exact)");
        assert_eq!(with_error(2.0, f64::NAN, "-"), "2 (no error estimate)");
        assert_eq!(with_error(f64::NAN, f64::NAN, "no fit"), "no fit");
        assert_eq!(with_error(f64::INFINITY, f64::NAN, "never"), "never");
        assert_eq!(significant(4.14864123e7), "4.14864e7");
        assert_eq!(significant(0.0154299), "0.0154299");
        assert_eq!(significant(9.9999996e5), "1e6");
    }

    /// A column's notation covers every cell: fixed cells of a column with a
    /// tiny value take its exponent form.
    #[test]
    fn a_column_shares_one_notation() {
        let column = natural_notation(1.178, 0.011).covering(natural_notation(3.69e-6, 7.0e-7));
        assert!(column.scientific && !column.concise);
        assert_eq!(written(1.178, 0.011, "-", column), "(1.178 ± 0.011)e0");
        assert_eq!(written(3.69e-6, 7.0e-7, "-", column), "(3.69 ± 0.70)e-6");
    }
}
