//! Checks shared by the sections: a failed check names its key path.

use std::fmt;

use crate::physics::potential::Potential;
use crate::pipeline::path_names::{LONGEST_USER_NAME, name_problem};

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

/// `name` may become part of a file path (a ring's, a gas's, a launch's
/// name, a potential's id): the one rule of [`name_problem`].
pub(super) fn check_name(name: &str, key: impl Into<String>) -> Result<(), Invalid> {
    match name_problem(name, LONGEST_USER_NAME) {
        None => Ok(()),
        Some(problem) => Err((key.into(), problem)),
    }
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

/// `message` with every word (a run without spaces) of more than
/// [`LONGEST_WORD`] characters cut to its start and its length: a 1 MB string
/// given for a number is named, not printed.
pub(super) fn shortened(message: &str) -> String {
    message
        .split(' ')
        .map(|word| {
            let length = word.chars().count();
            if length > LONGEST_WORD {
                let start: String = word.chars().take(LONGEST_WORD / 2).collect();
                format!("{start}... ({length} characters)")
            } else {
                word.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Longest word a message shows whole.
const LONGEST_WORD: usize = 120;

/// Longest number a message shows as written (`0.000123456789012345`).
const LONGEST_PLAIN_NUMBER: usize = 24;

/// Most potentials of one study: every stage runs per potential, and the
/// plan grows with their number (a finer grid is a second study).
pub const MAX_POTENTIALS: usize = 128;

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
                    "`{id}` names no potential of [potentials]; known ids: {}",
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

    #[test]
    fn long_words_in_messages_are_cut() {
        let huge = format!(
            "invalid type: string \"{}\", expected f64",
            "a".repeat(100_000)
        );
        let short = shortened(&huge);
        assert!(short.len() < 200, "{short}");
        assert!(short.contains("(100003 characters)"), "{short}");
        let plain = "`gas[0].name`: is empty";
        assert_eq!(shortened(plain), plain);
    }
}
