//! The names of instances in a bundle: each parameter value cut to
//! [`NAME_DIGITS`] significant digits, unique across the bundle.

use std::collections::{BTreeMap, BTreeSet};

/// Significant digits of a parameter value in a bundle path.
const NAME_DIGITS: usize = 6;

/// A parameter value, short: the shorter of its shortest round-trip form
/// (when that has at most `NAME_DIGITS` significant digits) and its
/// `NAME_DIGITS`-digit exponent form without trailing zeros: `0`, `-0.25`,
/// `5.38226e-5`, `1e-20`.
fn short_number(value: f64) -> String {
    let exponent = format!("{value:.*e}", NAME_DIGITS - 1);
    let (mantissa, power) = exponent.split_once('e').unwrap_or((&exponent, "0"));
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    let rounded = format!("{mantissa}e{power}");
    let plain = value.to_string();
    let significant = plain
        .trim_start_matches(['-', '0', '.'])
        .chars()
        .filter(char::is_ascii_digit)
        .count();
    if significant <= NAME_DIGITS && plain.len() <= rounded.len() {
        plain
    } else {
        rounded
    }
}

/// An instance name with each `<label><number>` part between underscores
/// (`rho0.00005382255169036728`, `lj-0.1052`) cut by `short_number`.
fn short_instance(instance: &str) -> String {
    let short_part = |part: &str| {
        let at = part
            .find(|c: char| c.is_ascii_digit() || matches!(c, '-' | '.'))
            .unwrap_or(part.len());
        let (label, number) = part.split_at(at);
        match number.parse::<f64>() {
            Ok(value) if value.is_finite() => format!("{label}{}", short_number(value)),
            _ => part.to_string(),
        }
    };
    instance
        .split('_')
        .map(short_part)
        .collect::<Vec<_>>()
        .join("_")
}

/// The bundle name of each of the plan's `instances`: its `short_instance`,
/// or its full name where two instances' short names coincide. It does not
/// depend on the selection, so a name is the same in every bundle of a study.
pub(super) fn bundle_names<'a>(
    instances: impl Iterator<Item = &'a str>,
) -> BTreeMap<&'a str, String> {
    let instances: BTreeSet<&str> = instances.collect();
    let mut sharing: BTreeMap<String, usize> = BTreeMap::new();
    for instance in &instances {
        *sharing.entry(short_instance(instance)).or_default() += 1;
    }
    instances
        .into_iter()
        .map(|instance| {
            let short = short_instance(instance);
            let name = if sharing[&short] == 1 {
                short
            } else {
                instance.to_string()
            };
            (instance, name)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_parameter_value_is_cut_to_six_significant_digits() {
        assert_eq!(
            short_instance("lj-0.1052_u0_rho0.00005382255169036728"),
            "lj-0.1052_u0_rho5.38226e-5"
        );
        assert_eq!(
            short_instance("ipp-6_u-0.25_rho0.0010324090855340624"),
            "ipp-6_u-0.25_rho1.03241e-3"
        );
        assert_eq!(short_instance("ipp-6_u-3_rho0"), "ipp-6_u-3_rho0");
        assert_eq!(short_instance("study"), "study");
        assert_eq!(short_number(1e-20), "1e-20");
        assert_eq!(short_number(2.0e-5), "2e-5");
    }

    #[test]
    fn bundle_names_are_unique_even_where_short_names_coincide() {
        let instances = [
            "ipp-6_u0_rho0.00005382255169036728",
            "ipp-6_u0_rho0.00005382255169036729",
            "ipp-6_u0_rho0.0007300234653397379",
            "ipp-6_u0_rho0",
        ];
        let names = bundle_names(instances.into_iter());
        let distinct: BTreeSet<&String> = names.values().collect();
        assert_eq!(distinct.len(), instances.len(), "{names:?}");
        assert_eq!(names[instances[0]], instances[0], "coinciding: full names");
        assert_eq!(names[instances[1]], instances[1]);
        assert_eq!(names[instances[2]], "ipp-6_u0_rho7.30023e-4");
        assert_eq!(names[instances[3]], "ipp-6_u0_rho0");
    }
}
