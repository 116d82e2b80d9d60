//! Checking an artifact before it is trusted: its manifest, its listing
//! and its files' hashes.

use std::fs::{self, File};
use std::io;
use std::path::Path;

use super::*;
use crate::pipeline::key::{hex, sha256_hex, stage_key};
use crate::pipeline::table::content_sha256_of_file;

/// Problems of a manifest as a document: it must name this artifact, its key
/// must follow from its stage, code fingerprint, parameters and inputs, and it must
/// list plain, unique file names (exactly `outputs` when given).
pub(super) fn manifest_problems(
    manifest: &Manifest,
    stage: &str,
    key: &str,
    outputs: Option<&[String]>,
) -> Vec<String> {
    let mut problems = Vec::new();
    if manifest
        .manifest_sha256
        .as_ref()
        .is_some_and(|seal| *seal != manifest.seal())
    {
        problems.push("the manifest was edited (its manifest_sha256 no longer matches)".into());
    }
    if manifest.key != key || manifest.stage != stage {
        problems.push(format!(
            "manifest names {}/{}",
            manifest.stage, manifest.key
        ));
    }
    if manifest.code.fingerprint.is_empty() {
        problems.push(
            "written by an earlier ternary, before keys followed the code: no current key names it (`ternary gc` removes it)"
                .to_string(),
        );
    } else if stage_key(
        &manifest.stage,
        &manifest.code.fingerprint,
        &manifest.params,
        &manifest.inputs,
    ) != manifest.key
    {
        problems.push(
            "the manifest's code fingerprint, parameters or inputs do not give its key".to_string(),
        );
    }
    let mut names: Vec<&str> = manifest.files.iter().map(|f| f.name.as_str()).collect();
    if names.is_empty() {
        problems.push("the manifest lists no file".to_string());
    }
    if let Some(name) = names
        .iter()
        .find(|name| name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.'))
    {
        problems.push(format!(
            "the manifest lists `{name}`, not a plain file name"
        ));
    }
    names.sort_unstable();
    if names.windows(2).any(|pair| pair[0] == pair[1]) {
        problems.push("the manifest lists a file twice".to_string());
    }
    if let Some(problem) = outputs.and_then(|outputs| listing_problem(manifest, outputs)) {
        problems.push(problem);
    }
    problems
}

/// Whether `manifest` lists exactly the files `outputs` (the files its stage
/// instance writes), and if not, how they differ.
pub fn listing_problem(manifest: &Manifest, outputs: &[String]) -> Option<String> {
    let mut names: Vec<&str> = manifest.files.iter().map(|f| f.name.as_str()).collect();
    names.sort_unstable();
    let mut expected: Vec<&str> = outputs.iter().map(String::as_str).collect();
    expected.sort_unstable();
    (names != expected).then(|| {
        format!(
            "the manifest lists [{}] but the stage writes [{}]",
            names.join(", "),
            expected.join(", ")
        )
    })
}

/// Problems of one listed file, checked to `depth`.
pub(super) fn file_problems(dir: &Path, file: &FileRecord, depth: Depth) -> Vec<String> {
    let path = dir.join(&file.name);
    let name = &file.name;
    let size = match fs::metadata(&path) {
        Ok(meta) => meta.len(),
        Err(error) => return vec![format!("{name}: {error}")],
    };
    if size != file.bytes {
        return vec![format!(
            "{name}: {size} bytes but the manifest records {}",
            file.bytes
        )];
    }
    let mismatch = |sha: String| {
        vec![format!(
            "{name}: sha256 {sha} but the manifest records {}",
            file.sha256
        )]
    };
    match depth {
        Depth::Sizes => {}
        Depth::Hashes => match sha256_of_file(&path) {
            Err(error) => return vec![format!("{name}: {error}")],
            Ok(sha) if sha != file.sha256 => return mismatch(sha),
            Ok(_) => {}
        },
        Depth::Contents => {
            let bytes = match fs::read(&path) {
                Ok(bytes) => bytes,
                Err(error) => return vec![format!("{name}: {error}")],
            };
            let sha = sha256_hex(&bytes);
            if sha != file.sha256 {
                return mismatch(sha);
            }
            return content_problems(file, bytes);
        }
    }
    Vec::new()
}

/// Lower-case hex SHA-256 of a file, read in 1 MiB pieces.
fn sha256_of_file(path: &Path) -> io::Result<String> {
    use sha2::{Digest, Sha256};
    use std::io::Read;
    let mut file = File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        let read = file.read(&mut buffer)?;
        if read == 0 {
            break;
        }
        hasher.update(&buffer[..read]);
    }
    Ok(hex(&hasher.finalize()))
}

/// Problems of a file's table content against its recorded content hash.
fn content_problems(file: &FileRecord, bytes: Vec<u8>) -> Vec<String> {
    let name = &file.name;
    match content_sha256_of_file(name, bytes) {
        Err(error) => vec![format!("{name}: {}", error_chain(&error))],
        Ok(content) if content != file.content_sha256 => vec![format!(
            "{name}: content sha256 {content} but the manifest records {}",
            file.content_sha256
        )],
        Ok(_) => Vec::new(),
    }
}
