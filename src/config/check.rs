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
pub(super) fn compact(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) || !x.is_finite() {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

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
