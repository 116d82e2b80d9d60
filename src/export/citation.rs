//! The citation metadata written from `[publication]`: `CITATION.cff`
//! (Citation File Format 1.2.0) and `.zenodo.json` (Zenodo deposit).

use std::fmt::Write as _;

use serde_json::{Value, json};

use super::{PAPER_ARXIV, PAPER_CITATION, PAPER_DOI};
use crate::config::{AuthorConfig, PublicationConfig};

/// `https://orcid.org/<id>`.
pub(super) fn orcid_url(orcid: &str) -> String {
    format!("https://orcid.org/{orcid}")
}

/// A YAML string (double-quoted, escaped): safe for any text.
fn yaml(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_default()
}

pub(super) fn citation_cff(publication: &PublicationConfig) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "cff-version: 1.2.0");
    let _ = writeln!(
        out,
        "message: {}",
        yaml(&format!(
            "If you use this dataset, please cite it as below. It reproduces and extends \
             {PAPER_CITATION}, doi:{PAPER_DOI}, arXiv:{PAPER_ARXIV}."
        ))
    );
    let _ = writeln!(out, "type: dataset");
    let _ = writeln!(out, "title: {}", yaml(&publication.title));
    let _ = writeln!(out, "version: {}", yaml(&publication.version));
    if let Some(date) = &publication.date {
        let _ = writeln!(out, "date-released: {}", yaml(date));
    }
    let _ = writeln!(out, "license: {}", yaml(&publication.license));
    let _ = writeln!(out, "abstract: {}", yaml(&publication.description));
    let _ = writeln!(out, "authors:");
    for author in &publication.authors {
        cff_author(&mut out, author);
    }
    if !publication.keywords.is_empty() {
        let _ = writeln!(out, "keywords:");
        for keyword in &publication.keywords {
            let _ = writeln!(out, "  - {}", yaml(keyword));
        }
    }
    out
}

fn cff_author(out: &mut String, author: &AuthorConfig) {
    let mut lines = Vec::new();
    if let Some(family) = &author.family_names {
        lines.push(format!("family-names: {}", yaml(family)));
    }
    if let Some(given) = &author.given_names {
        lines.push(format!("given-names: {}", yaml(given)));
    }
    if let Some(name) = &author.name {
        lines.push(format!("name: {}", yaml(name)));
    }
    if let Some(orcid) = &author.orcid {
        lines.push(format!("orcid: {}", yaml(&orcid_url(orcid))));
    }
    if let Some(affiliation) = &author.affiliation {
        lines.push(format!("affiliation: {}", yaml(affiliation)));
    }
    for (k, line) in lines.iter().enumerate() {
        let _ = writeln!(out, "  {} {line}", if k == 0 { "-" } else { " " });
    }
}

pub(super) fn zenodo(publication: &PublicationConfig) -> Value {
    let creators: Vec<Value> = publication
        .authors
        .iter()
        .map(|author| {
            let mut value = json!({ "name": author.display_name() });
            if let Some(affiliation) = &author.affiliation {
                value["affiliation"] = json!(affiliation);
            }
            if let Some(orcid) = &author.orcid {
                value["orcid"] = json!(orcid);
            }
            value
        })
        .collect();
    let mut value = json!({
        "upload_type": "dataset",
        "title": publication.title,
        "description": publication.description,
        "version": publication.version,
        "license": publication.license.to_lowercase(),
        "creators": creators,
        "keywords": publication.keywords,
        "related_identifiers": [
            { "identifier": PAPER_DOI, "relation": "references", "scheme": "doi" },
            { "identifier": format!("arXiv:{PAPER_ARXIV}"), "relation": "references", "scheme": "arxiv" },
        ],
    });
    if let Some(date) = &publication.date {
        value["publication_date"] = json!(date);
    }
    value
}
