//! Checks shared by the sections: a failed check names its key path.

use std::fmt;

use crate::physics::potential::Potential;

/// A validation failure: key path and message.
pub(super) type Invalid = (String, String);

/// `Ok` when `ok`, else the failure of `key` with `message`.
pub(super) fn check(
    ok: bool,
    key: impl Into<String>,
    message: impl Into<String>,
) -> Result<(), Invalid> {
    if ok {
        Ok(())
    } else {
        Err((key.into(), message.into()))
    }
}

/// Every value of a list appears once; `key(k)` names the repeat at `k`.
pub(super) fn check_unique<T: PartialEq + fmt::Display>(
    values: &[T],
    key: impl Fn(usize) -> String,
) -> Result<(), Invalid> {
    for (k, value) in values.iter().enumerate() {
        check(
            !values[..k].contains(value),
            key(k),
            format!("{value} is listed twice"),
        )?;
    }
    Ok(())
}

/// A list holds at most [`MAX_LIST`] values.
pub(super) fn check_length<T>(values: &[T], key: &str) -> Result<(), Invalid> {
    check(
        values.len() <= MAX_LIST,
        key,
        format!("lists {} values, more than {MAX_LIST}", values.len()),
    )
}

/// `value` is a finite number > 0.
pub(super) fn positive(value: f64) -> bool {
    value.is_finite() && value > 0.0
}

/// A number for a message: plain when of moderate size, else in exponent form
/// (`1e300`, not three hundred digits).
pub fn compact(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) || !x.is_finite() {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

/// `message` with every number of more than [`LONGEST_PLAIN_NUMBER`]
/// characters (how `f64`'s `Display` writes 1e300: three hundred digits) in
/// exponent form, as [`compact`] writes it.
pub(super) fn compact_numbers(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        out.push_str(&rest[..start]);
        let digits = &rest[start..];
        let end = digits
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(digits.len());
        let number = &digits[..end];
        match number.parse::<f64>() {
            Ok(value) if number.len() > LONGEST_PLAIN_NUMBER => out.push_str(&compact(value)),
            _ => out.push_str(number),
        }
        rest = &digits[end..];
    }
    out.push_str(rest);
    out
}

/// Longest number a message shows as written (`0.000123456789012345`).
const LONGEST_PLAIN_NUMBER: usize = 24;

/// Longest list of values (velocities, densities, times, settings).
pub const MAX_LIST: usize = 256;

/// The configured potential whose id is `id`, or the failure of `key` listing
/// the known ids.
pub(super) fn potential_named(
    id: &str,
    potentials: &[Potential],
    key: impl Into<String>,
) -> Result<Potential, Invalid> {
    potentials
        .iter()
        .copied()
        .find(|p| p.id() == id)
        .ok_or_else(|| {
            let known: Vec<String> = potentials.iter().map(Potential::id).collect();
            (
                key.into(),
                format!(
                    "`{id}` names no configured potential; known ids: {}",
                    known.join(", ")
                ),
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_in_messages_are_compacted() {
        let huge = format!("{} must be at most 12", 1e300);
        assert_eq!(compact_numbers(&huge), "1e300 must be at most 12");
        let tiny = format!("X = {} is outside (0, 0.1]", -1e-300);
        assert_eq!(compact_numbers(&tiny), "X = -1e-300 is outside (0, 0.1]");
        let plain = "scan.launch[3]: 0.000123456789 and 2e-4 at line 12";
        assert_eq!(compact_numbers(plain), plain);
    }
}
