//! `[publication]`: how an exported dataset describes and credits itself
//! (`ternary export` writes it into `datapackage.json`, `CITATION.cff` and
//! `.zenodo.json`). No stage reads it: it changes no artifact.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check};

/// `[publication]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct PublicationConfig {
    /// Dataset name: lower-case letters, digits, `-`, `_` and `.` (a Data Package `name`).
    pub name: String,
    /// Title of the dataset.
    pub title: String,
    /// What the dataset holds, in a few sentences.
    pub description: String,
    /// Version of the dataset (not of the tool).
    pub version: String,
    /// SPDX licence identifier.
    pub license: String,
    /// Keywords.
    pub keywords: Vec<String>,
    /// Release date `YYYY-MM-DD`; when absent, no file carries a date.
    pub date: Option<String>,
    /// Authors, in order (`[[publication.authors]]`).
    pub authors: Vec<AuthorConfig>,
}

impl Default for PublicationConfig {
    fn default() -> Self {
        PublicationConfig {
            name: "ternary-study".into(),
            title: "Three-body thermalization of a dilute one-dimensional gas".into(),
            description: "Collision kernels, thermalization rates, Boltzmann evolution and ring \
                          molecular dynamics computed by ternary."
                .into(),
            version: "1.0.0".into(),
            license: "CC-BY-4.0".into(),
            keywords: vec![
                "three-body collisions".into(),
                "thermalization".into(),
                "one-dimensional gas".into(),
                "Boltzmann equation".into(),
            ],
            date: None,
            authors: Vec::new(),
        }
    }
}

/// `[[publication.authors]]`: a person (`given_names`, `family_names`) or an
/// organization (`name`).
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct AuthorConfig {
    /// Given names of a person.
    pub given_names: Option<String>,
    /// Family names of a person.
    pub family_names: Option<String>,
    /// Name of an organization (instead of a person's names).
    pub name: Option<String>,
    /// ORCID iD, `0000-0000-0000-0000` (the last digit may be `X`).
    pub orcid: Option<String>,
    /// Affiliation.
    pub affiliation: Option<String>,
}

impl AuthorConfig {
    /// `Family, Given` for a person, the name for an organization.
    pub fn display_name(&self) -> String {
        match (&self.family_names, &self.given_names, &self.name) {
            (Some(family), Some(given), _) => format!("{family}, {given}"),
            (Some(family), None, _) => family.clone(),
            (_, _, Some(name)) => name.clone(),
            _ => String::new(),
        }
    }
}

impl PublicationConfig {
    /// Checks the name, licence, date, ORCID iDs and that each author is a
    /// person or an organization.
    pub(super) fn validate(&self) -> Result<(), Invalid> {
        check(
            !self.name.is_empty()
                && self
                    .name
                    .bytes()
                    .all(|b| matches!(b, b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.')),
            "publication.name",
            format!(
                "`{}` must be lower-case letters, digits, `-`, `_` or `.`",
                self.name
            ),
        )?;
        check(
            license_url(&self.license).is_some(),
            "publication.license",
            format!(
                "`{}` is not an SPDX id of a data licence ternary knows: {}",
                self.license,
                LICENSES.map(|(id, _)| id).join(", ")
            ),
        )?;
        for (key, value) in [("title", &self.title), ("version", &self.version)] {
            check(
                !value.trim().is_empty(),
                format!("publication.{key}"),
                "is empty",
            )?;
        }
        check(
            self.date.as_deref().is_none_or(is_date),
            "publication.date",
            "must be a date YYYY-MM-DD",
        )?;
        for (k, author) in self.authors.iter().enumerate() {
            let person = author.family_names.is_some();
            check(
                person != author.name.is_some(),
                format!("publication.authors[{k}]"),
                "give family_names (and given_names) for a person, or name for an organization",
            )?;
            check(
                author.orcid.as_deref().is_none_or(is_orcid),
                format!("publication.authors[{k}].orcid"),
                "must be an ORCID iD 0000-0000-0000-000X",
            )?;
        }
        Ok(())
    }
}

/// The SPDX licence ids a dataset may carry, with their canonical URLs: the
/// open licences data repositories (Zenodo, the Data Package standard) offer
/// for data, and the common ones for code.
pub const LICENSES: [(&str, &str); 15] = [
    ("CC-BY-4.0", "https://creativecommons.org/licenses/by/4.0/"),
    (
        "CC-BY-SA-4.0",
        "https://creativecommons.org/licenses/by-sa/4.0/",
    ),
    (
        "CC-BY-NC-4.0",
        "https://creativecommons.org/licenses/by-nc/4.0/",
    ),
    (
        "CC-BY-NC-SA-4.0",
        "https://creativecommons.org/licenses/by-nc-sa/4.0/",
    ),
    (
        "CC-BY-ND-4.0",
        "https://creativecommons.org/licenses/by-nd/4.0/",
    ),
    (
        "CC-BY-NC-ND-4.0",
        "https://creativecommons.org/licenses/by-nc-nd/4.0/",
    ),
    (
        "CC0-1.0",
        "https://creativecommons.org/publicdomain/zero/1.0/",
    ),
    ("ODC-By-1.0", "https://opendatacommons.org/licenses/by/1-0/"),
    ("ODbL-1.0", "https://opendatacommons.org/licenses/odbl/1-0/"),
    ("PDDL-1.0", "https://opendatacommons.org/licenses/pddl/1-0/"),
    ("MIT", "https://opensource.org/license/mit"),
    ("Apache-2.0", "https://www.apache.org/licenses/LICENSE-2.0"),
    (
        "BSD-3-Clause",
        "https://opensource.org/license/bsd-3-clause",
    ),
    (
        "GPL-3.0-or-later",
        "https://www.gnu.org/licenses/gpl-3.0.html",
    ),
    ("MPL-2.0", "https://www.mozilla.org/en-US/MPL/2.0/"),
];

/// The URL of the licence `id` (SPDX ids match without regard to case), or
/// `None` for an id not in [`LICENSES`].
pub fn license_url(id: &str) -> Option<&'static str> {
    LICENSES
        .iter()
        .find(|(known, _)| known.eq_ignore_ascii_case(id))
        .map(|(_, url)| *url)
}

/// `YYYY-MM-DD` with a plausible month and day.
fn is_date(text: &str) -> bool {
    let parts: Vec<&str> = text.split('-').collect();
    let number = |part: &str, digits: usize, range: std::ops::RangeInclusive<u32>| {
        part.len() == digits && part.parse::<u32>().is_ok_and(|n| range.contains(&n))
    };
    parts.len() == 3
        && number(parts[0], 4, 1000..=9999)
        && number(parts[1], 2, 1..=12)
        && number(parts[2], 2, 1..=31)
}

/// Four groups of four digits (the last character may be `X`).
fn is_orcid(text: &str) -> bool {
    let groups: Vec<&str> = text.split('-').collect();
    groups.len() == 4
        && groups.iter().enumerate().all(|(g, group)| {
            group.len() == 4
                && group
                    .chars()
                    .enumerate()
                    .all(|(c, ch)| ch.is_ascii_digit() || (g == 3 && c == 3 && ch == 'X'))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_and_orcids_are_recognized() {
        assert!(is_date("2024-07-15"));
        assert!(!is_date("2024-13-01"));
        assert!(!is_date("15.07.2024"));
        assert!(is_orcid("0000-0002-1825-0097"));
        assert!(is_orcid("0000-0002-1694-233X"));
        assert!(!is_orcid("0000-0002-1825-009"));
        assert!(!is_orcid("https://orcid.org/0000-0002-1825-0097"));
    }
}
