//! `[potentials]`: the pair potentials of the study, one list per family
//! (`inverse_power = [2, 6]`, `lennard_jones = [0.1]`); each family says
//! how it is listed ([`FAMILIES`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::check::{Invalid, MAX_POTENTIALS, check, check_name, check_unique};
use crate::physics::potential::{FAMILIES, Potential};

/// `[potentials]`: per family key, one potential per listed value.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(transparent)]
pub struct PotentialsConfig(BTreeMap<String, Vec<toml::Value>>);

/// A listed TOML value as the family reads it (JSON), or why it cannot be
/// one: JSON has no NaN, infinity or date (serde_json would make the first
/// two `null`, and the message would say "null").
fn as_json(value: &toml::Value) -> Result<serde_json::Value, String> {
    match value {
        toml::Value::Float(x) if !x.is_finite() => Err(format!("{x} is not a finite number")),
        toml::Value::Datetime(date) => {
            Err(format!("{date} is a date, not a potential's parameter"))
        }
        other => serde_json::to_value(other).map_err(|e| e.to_string()),
    }
}

impl PotentialsConfig {
    /// Checks every value and returns the potentials, family by family in
    /// the order of [`FAMILIES`] (inverse power laws first), each family's
    /// in file order.
    pub(super) fn resolve(&self) -> Result<Vec<Potential>, Invalid> {
        if let Some(unknown) = self
            .0
            .keys()
            .find(|key| FAMILIES.iter().all(|family| family.key != key.as_str()))
        {
            let known: Vec<&str> = FAMILIES.iter().map(|family| family.key).collect();
            return Err((
                format!("potentials.{unknown}"),
                format!("is no potential family; known: {}", known.join(", ")),
            ));
        }
        let examples: Vec<String> = FAMILIES
            .iter()
            .map(|family| format!("`{}`", family.example))
            .collect();
        check(
            self.0.values().any(|values| !values.is_empty()),
            "potentials",
            format!("lists no potential: give {}", examples.join(" or ")),
        )?;
        let mut potentials = Vec::new();
        for family in &FAMILIES {
            let values = self.0.get(family.key).map_or(&[][..], Vec::as_slice);
            let key = |k: usize| format!("potentials.{}[{k}]", family.key);
            let listed = values
                .iter()
                .enumerate()
                .map(|(k, value)| {
                    as_json(value)
                        .and_then(family.potential)
                        .map_err(|e| (key(k), e))
                })
                .collect::<Result<Vec<Potential>, Invalid>>()?;
            let ids: Vec<String> = listed.iter().map(Potential::id).collect();
            for (k, id) in ids.iter().enumerate() {
                check_name(id, key(k))?;
            }
            check_unique(&ids, key)?;
            potentials.extend(listed);
        }
        check(
            potentials.len() <= MAX_POTENTIALS,
            "potentials",
            format!(
                "lists {} potentials, more than {MAX_POTENTIALS}: split the study",
                potentials.len()
            ),
        )?;
        Ok(potentials)
    }
}
