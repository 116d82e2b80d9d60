//! The names ternary gives its store entries: keys, store ids, staging
//! directories, writers (`<pid>@<host>`) and temporary files; only entries
//! with these names are ever removed.

use std::fs;
use std::path::Path;

/// `true` for a lower-case hex SHA-256 (an artifact key).
pub fn is_key(name: &str) -> bool {
    name.len() == 64 && name.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}

/// `true` for a store id: 16 lower-case hex digits.
pub(super) fn is_store_id(text: &str) -> bool {
    text.len() == 16 && text.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}

/// `true` for the staging names [`Store::begin`] of the store `id` creates:
/// `<key>.<id>.<writer>` and `<key>.<id>.<writer>.old`, the writer
/// `<pid>@<host>`. Names without the id (another store's, a user's, or
/// ternary's before stores had ids) are not.
pub(super) fn is_staging_name(name: &str, id: &str) -> bool {
    let name = name.strip_suffix(".old").unwrap_or(name);
    let Some((key, rest)) = name.split_once('.') else {
        return false;
    };
    let Some(writer) = rest.strip_prefix(id).and_then(|w| w.strip_prefix('.')) else {
        return false;
    };
    is_key(key) && is_writer_name(writer)
}

/// `true` for a [`writer_name`]: `<pid>@<host>`.
pub(super) fn is_writer_name(text: &str) -> bool {
    text.split_once('@').is_some_and(|(pid, host)| {
        !pid.is_empty()
            && pid.bytes().all(|b| b.is_ascii_digit())
            && !host.is_empty()
            && host
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'.')
    })
}

/// `true` when the staging entry `name` (or a temporary file's name ending
/// in `.<pid>`) was made by a process that still runs on this host: a run in
/// progress, not debris of an interrupted one.
pub fn is_live_staging(name: &str) -> bool {
    let name = name.strip_suffix(".old").unwrap_or(name);
    let this_host = this_host();
    let (pid, host) = match name.rsplit_once('@') {
        Some((rest, host)) => (rest.rsplit('.').next().unwrap_or_default(), host),
        None => (
            name.rsplit('.').next().unwrap_or_default(),
            this_host.as_str(),
        ),
    };
    host == this_host
        && !pid.is_empty()
        && pid.bytes().all(|b| b.is_ascii_digit())
        && Path::new("/proc").join(pid).exists()
}

/// This host's name as [`writer_name`] writes it.
pub(super) fn this_host() -> String {
    let ours = writer_name();
    ours.split_once('@')
        .map_or("", |(_, host)| host)
        .to_string()
}

/// `true` for a temporary marker of any store: `.ternary-store.json.<id>.<pid>`.
pub(super) fn is_marker_temporary(name: &str) -> bool {
    name.strip_prefix(".ternary-store.json.")
        .and_then(|tag| tag.split_once('.'))
        .is_some_and(|(id, pid)| {
            is_store_id(id) && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
        })
}

/// `<pid>@<host>`: names this process among writers on many nodes sharing a store.
pub(super) fn writer_name() -> String {
    let host = fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let host: String = host
        .trim()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '.')
        .collect();
    let host = if host.is_empty() {
        "localhost".into()
    } else {
        host
    };
    format!("{}@{host}", std::process::id())
}

/// `true` for the temporary names [`write_atomically`] of the store `id`
/// creates for refs and the marker: `.<name>.json.<id>.<pid>`.
pub(super) fn is_json_temporary(name: &str, id: &str) -> bool {
    name.strip_prefix('.')
        .and_then(|rest| rest.rsplit_once(".json."))
        .and_then(|(file, tag)| Some((file, tag.strip_prefix(id)?.strip_prefix('.')?)))
        .is_some_and(|(file, pid)| {
            !file.is_empty() && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `verify` during a run called that run's staging "from interrupted
    /// runs": a staging entry of a running process on this host is live.
    #[test]
    fn a_running_writers_staging_is_live_and_a_dead_ones_is_not() {
        let key = "a".repeat(64);
        let live = format!("{key}.0123456789abcdef.{}", writer_name());
        assert!(is_live_staging(&live));
        assert!(is_live_staging(&format!("{live}.old")));
        let dead = (100_000..u32::MAX)
            .find(|pid| !Path::new("/proc").join(pid.to_string()).exists())
            .unwrap();
        let host = writer_name().split_once('@').unwrap().1.to_string();
        assert!(!is_live_staging(&format!(
            "{key}.0123456789abcdef.{dead}@{host}"
        )));
        let elsewhere = format!("{key}.0123456789abcdef.{}@another-host", std::process::id());
        assert!(!is_live_staging(&elsewhere));
    }

    #[test]
    fn only_ternary_names_are_staging_or_ref_debris() {
        let key = "a".repeat(64);
        let id = "0123456789abcdef";
        assert!(is_staging_name(
            &format!("{key}.{id}.123@node-7.cluster"),
            id
        ));
        assert!(is_staging_name(&format!("{key}.{id}.123@node-7.old"), id));
        assert!(!is_staging_name(&format!("{key}.{id}.123@node/7"), id));
        // Without this store's id: another store's, a user's, or from
        // before stores had ids.
        assert!(!is_staging_name(&format!("{key}.123@node-7"), id));
        assert!(!is_staging_name(&format!("{key}.123"), id));
        assert!(!is_staging_name(&format!("{key}.fedcba9876543210.1@n"), id));
        assert!(!is_staging_name("my_project", id));
        assert!(!is_staging_name(&format!("{key}.{id}.x1@n"), id));
        assert!(!is_staging_name(
            &format!("{}.{id}.123@n", "A".repeat(64)),
            id
        ));
        assert!(is_json_temporary(&format!(".ipp-6.json.{id}.77"), id));
        assert!(!is_json_temporary(".ipp-6.json.77", id));
        assert!(!is_json_temporary("ipp-6.json", id));
        assert!(!is_json_temporary(".notes.json.bak", id));
    }
}
