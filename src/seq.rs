//! Image/file sequences on disk: a directory or a `dir/*.ext`-style glob, sorted naturally
//! (`frame2.svg` before `frame10.svg`).

use crate::error::{Error, Result};
use std::cmp::Ordering;
use std::path::{Path, PathBuf};

/// Compares two strings so that runs of digits compare by numeric value.
/// Letters compare case-insensitively; exact case only breaks ties.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    natural_cmp_folded(a, b).then_with(|| a.cmp(b))
}

fn natural_cmp_folded(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, _) => return Ordering::Less,
            (_, None) => return Ordering::Greater,
            (Some(ca), Some(cb)) if ca.is_ascii_digit() && cb.is_ascii_digit() => {
                let la = a.iter().take_while(|c| c.is_ascii_digit()).count();
                let lb = b.iter().take_while(|c| c.is_ascii_digit()).count();
                let (na, nb) = (&a[..la], &b[..lb]);
                let ta = na.iter().skip_while(|&&c| c == b'0').count();
                let tb = nb.iter().skip_while(|&&c| c == b'0').count();
                let ord = ta.cmp(&tb).then_with(|| na[la - ta..].cmp(&nb[lb - tb..])).then(la.cmp(&lb));
                if ord != Ordering::Equal {
                    return ord;
                }
                a = &a[la..];
                b = &b[lb..];
            }
            (Some(ca), Some(cb)) => {
                let ord = ca.to_ascii_lowercase().cmp(&cb.to_ascii_lowercase());
                if ord != Ordering::Equal {
                    return ord;
                }
                a = &a[1..];
                b = &b[1..];
            }
        }
    }
}

fn glob_match(pattern: &str, name: &str) -> bool {
    // Only `*` (any run) and `?` (one char) are supported, which covers frame globs.
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    let (mut pi, mut ni, mut star, mut mark) = (0, 0, None, 0);
    while ni < n.len() {
        if pi < p.len() && (p[pi] == '?' || p[pi] == n[ni]) {
            pi += 1;
            ni += 1;
        } else if pi < p.len() && p[pi] == '*' {
            star = Some(pi);
            mark = ni;
            pi += 1;
        } else if let Some(s) = star {
            pi = s + 1;
            mark += 1;
            ni = mark;
        } else {
            return false;
        }
    }
    p[pi..].iter().all(|&c| c == '*')
}

/// True when `path` is a glob pattern (its file name contains `*` or `?`).
pub fn is_glob(path: &Path) -> bool {
    path.file_name().map(|n| n.to_string_lossy().contains(['*', '?'])).unwrap_or(false)
}

/// Lists the files of a sequence: every file in directory `input` whose extension is one of
/// `extensions` (case-insensitive), or the files matching the glob `input` (`dir/*.svg`).
/// The result is sorted naturally; an empty sequence is an error.
pub fn list_sequence(input: &Path, extensions: &[&str]) -> Result<Vec<PathBuf>> {
    let (dir, pattern) = if is_glob(input) {
        let dir = input.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        (dir.to_path_buf(), Some(input.file_name().unwrap_or_default().to_string_lossy().into_owned()))
    } else {
        (input.to_path_buf(), None)
    };
    let entries = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut files: Vec<PathBuf> = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(&dir, e))?;
        let path = entry.path();
        if !path.is_file() {
            continue;
        }
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let ok = match &pattern {
            Some(p) => glob_match(p, &name),
            None => path.extension().map(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x))).unwrap_or(false),
        };
        if ok {
            files.push(path);
        }
    }
    files.sort_by(|a, b| {
        natural_cmp(
            &a.file_name().unwrap_or_default().to_string_lossy(),
            &b.file_name().unwrap_or_default().to_string_lossy(),
        )
    });
    if files.is_empty() {
        return Err(Error::Empty {
            path: input.to_path_buf(),
            what: format!("no {} files found", extensions.join("/")),
        });
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order() {
        let mut v = vec!["f10.svg", "f2.svg", "f1.svg", "F3.svg", "f02.svg"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, vec!["f1.svg", "f2.svg", "f02.svg", "F3.svg", "f10.svg"]);
    }

    #[test]
    fn globbing() {
        assert!(glob_match("*.svg", "frame001.svg"));
        assert!(glob_match("fr?me*.svg", "frame001.svg"));
        assert!(!glob_match("*.svg", "frame001.png"));
    }
}
