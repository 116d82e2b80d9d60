//! The one rule for a name that becomes part of a file path (a ring's, a
//! gas's or a launch's name, a potential's id, an instance's name), and the
//! join that keeps such a path inside its root: a name is never a path.

use std::path::{Component, Path, PathBuf};

/// Longest name a user gives (a ring, a gas, a launch): instance names and
/// file names are built from it, and must stay well below the 255 bytes a
/// file name may have.
pub const LONGEST_USER_NAME: usize = 64;

/// Longest name of one path component ternary writes (an instance's ref
/// `<instance>.json` with its temporary-file tag must fit in 255 bytes).
pub const LONGEST_COMPONENT: usize = 200;

/// Why `name` cannot be one component of a path, or `None` when it can:
/// 1 to `longest` characters, each an ASCII letter, digit or one of `_-.+`,
/// the first not a dot (no `..`, no hidden file, no separator, no control
/// character).
pub fn name_problem(name: &str, longest: usize) -> Option<String> {
    if name.is_empty() {
        return Some("is empty".into());
    }
    let length = name.chars().count();
    if length > longest {
        return Some(format!(
            "is {length} characters long: a name has at most {longest}"
        ));
    }
    if name.starts_with('.') {
        return Some(format!(
            "`{}` starts with a dot: a name may not (it would be hidden, or a parent folder)",
            name.escape_default()
        ));
    }
    let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '+');
    name.chars().find(|c| !allowed(*c)).map(|c| {
        format!(
            "`{}` holds `{}`: a name may hold only letters, digits and `_-.+` (it names files)",
            name.escape_default(),
            c.escape_default()
        )
    })
}

/// `root` joined with the relative `path` when every component of `path`
/// is a plain name by [`name_problem`] (so the result lies inside `root`
/// whatever the names hold), else why not.
pub fn joined_inside(root: &Path, path: &str) -> Result<PathBuf, String> {
    let relative = Path::new(path);
    let mut joined = root.to_path_buf();
    for component in relative.components() {
        let Component::Normal(part) = component else {
            return Err(format!("`{path}` leaves {}", root.display()));
        };
        let part = part.to_string_lossy();
        if let Some(problem) = name_problem(&part, LONGEST_COMPONENT) {
            return Err(format!("`{}` in `{path}` {problem}", part.escape_default()));
        }
        joined.push(part.as_ref());
    }
    if joined == root {
        return Err(format!("`{path}` names no file inside {}", root.display()));
    }
    Ok(joined)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_names_pass_and_paths_do_not() {
        for good in ["ipp-6", "lj-0.1052_u-0.25_rho1e-5", "N41_R1600+x", "a.b"] {
            assert_eq!(name_problem(good, LONGEST_USER_NAME), None, "{good}");
        }
        for bad in [
            "",
            ".",
            "..",
            "../notes",
            "/dir/precious",
            "a/b",
            ".hidden",
            "a\nb",
            "a b",
            "é",
            "a\\b",
        ] {
            assert!(name_problem(bad, LONGEST_USER_NAME).is_some(), "{bad:?}");
        }
        let long = "a".repeat(LONGEST_USER_NAME + 1);
        assert!(name_problem(&long, LONGEST_USER_NAME).is_some());
        let message = name_problem("a\u{7}b", 64).unwrap();
        assert!(message.contains("\\u{7}"), "{message}");
    }

    #[test]
    fn a_join_stays_inside_its_root() {
        let root = Path::new("/store/refs");
        assert_eq!(
            joined_inside(root, "md/ring.json"),
            Ok(PathBuf::from("/store/refs/md/ring.json"))
        );
        for bad in [
            "../notes.json",
            "/etc/passwd",
            "md/../../x",
            "md/.x",
            "",
            ".",
        ] {
            assert!(joined_inside(root, bad).is_err(), "{bad:?}");
        }
    }
}
