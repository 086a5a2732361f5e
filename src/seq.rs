//! Image/file sequences on disk: a directory or a `dir/*.ext`-style glob (`*`, `?` and
//! `[...]` classes in the file name), sorted naturally (`frame2.svg` before `frame10.svg`).

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

/// One element of a file-name glob.
#[derive(Debug, PartialEq)]
enum Token {
    /// `*`: any run of characters, the empty one included.
    Star,
    /// `?`: any one character.
    Any,
    /// `[...]`: one character of the class (`[!...]` or `[^...]`: one not in it); ranges as
    /// `a-z`. A `]` right after the opening `[` (or `[!`) is one of its characters.
    Class { negated: bool, ranges: Vec<(char, char)> },
    /// Any other character, itself.
    Lit(char),
}

/// The tokens of a file-name glob. A `[` without its closing `]` is the character itself.
fn tokens(pattern: &str) -> Vec<Token> {
    let p: Vec<char> = pattern.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < p.len() {
        match p[i] {
            '*' => out.push(Token::Star),
            '?' => out.push(Token::Any),
            '[' => {
                let mut j = i + 1;
                let negated = j < p.len() && (p[j] == '!' || p[j] == '^');
                if negated {
                    j += 1;
                }
                let start = j;
                let mut ranges = Vec::new();
                while j < p.len() && (p[j] != ']' || j == start) {
                    if j + 2 < p.len() && p[j + 1] == '-' && p[j + 2] != ']' {
                        ranges.push((p[j], p[j + 2]));
                        j += 3;
                    } else {
                        ranges.push((p[j], p[j]));
                        j += 1;
                    }
                }
                if j < p.len() {
                    out.push(Token::Class { negated, ranges });
                    i = j + 1;
                    continue;
                }
                out.push(Token::Lit('['));
            }
            c => out.push(Token::Lit(c)),
        }
        i += 1;
    }
    out
}

impl Token {
    /// Whether this token, when it is not `*`, matches the character `c`.
    fn matches(&self, c: char) -> bool {
        match self {
            Token::Star => false,
            Token::Any => true,
            Token::Class { negated, ranges } => ranges.iter().any(|&(a, b)| (a..=b).contains(&c)) != *negated,
            Token::Lit(l) => *l == c,
        }
    }
}

/// Whether the file name `name` matches the glob `p` (its [`tokens`]): `*` (any run of
/// characters), `?` (one character) and `[...]` classes (`[0-9]`, `[abc]`, `[!0-9]`),
/// case-sensitively.
fn glob_match(p: &[Token], name: &str) -> bool {
    let n: Vec<char> = name.chars().collect();
    let (mut pi, mut ni, mut star, mut mark) = (0, 0, None, 0);
    while ni < n.len() {
        if pi < p.len() && p[pi].matches(n[ni]) {
            pi += 1;
            ni += 1;
        } else if pi < p.len() && p[pi] == Token::Star {
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
    p[pi..].iter().all(|t| *t == Token::Star)
}

/// The glob syntax [`is_glob`] and the sequence listings understand, for help texts and
/// messages.
pub const GLOB_SYNTAX: &str = "`*` (any run of characters), `?` (one character) and `[...]` (one of the characters: \
                               `[0-9]`, `[abc]`, `[!0-9]`), in the file name only";

/// True when `path` is a glob pattern: its file name has a `*`, a `?` or a `[...]` class.
pub fn is_glob(path: &Path) -> bool {
    path.file_name().map(|n| tokens(&n.to_string_lossy()).iter().any(|t| !matches!(t, Token::Lit(_)))).unwrap_or(false)
}

/// The folder and file-name pattern of the glob `input`; wildcards in a folder name are an
/// error.
fn split_glob(input: &Path) -> Result<(PathBuf, String)> {
    let dir = input.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if dir.components().any(|c| is_glob(Path::new(c.as_os_str()))) {
        return Err(Error::io(
            input,
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("wildcards are only supported in the file name, not in folder names (globs: {GLOB_SYNTAX})"),
            ),
        ));
    }
    Ok((dir.to_path_buf(), input.file_name().unwrap_or_default().to_string_lossy().into_owned()))
}

/// What a folder holds: its files (hidden ones left out, naturally sorted) and how many
/// folders.
pub struct Contents {
    /// The files, in natural order.
    pub files: Vec<PathBuf>,
    /// How many (not hidden) folders it holds.
    pub folders: usize,
}

impl Contents {
    /// Reads the folder `dir`.
    pub fn read(dir: &Path) -> Result<Contents> {
        let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
        let (mut files, mut folders) = (Vec::new(), 0);
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(dir, e))?;
            if entry.file_name().to_string_lossy().starts_with('.') {
                continue;
            }
            let path = entry.path();
            if path.is_file() {
                files.push(path);
            } else if path.is_dir() {
                folders += 1;
            }
        }
        sort_naturally(&mut files);
        Ok(Contents { files, folders })
    }

    /// What it holds, for a message: "0 files", "3 .txt files", "2 .json files, 1 .txt file and
    /// 1 folder".
    pub fn describe(&self) -> String {
        let mut parts = describe_files(&self.files);
        if self.folders > 0 {
            parts.push(plural(self.folders, "folder"));
        }
        match parts.len() {
            0 => "0 files".to_string(),
            1 => parts.remove(0),
            n => format!("{} and {}", parts[..n - 1].join(", "), parts[n - 1]),
        }
    }
}

/// "1 frame", "2 frames": `n` and `what`, with an `s` unless `n` is 1.
pub fn plural(n: usize, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}

/// The lower-case extension of a file, if any.
pub fn extension(path: &Path) -> Option<String> {
    path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// Counts of files by extension, most first: "3 .svg files", "1 file without an extension".
pub fn describe_files(files: &[PathBuf]) -> Vec<String> {
    let mut counts: Vec<(Option<String>, usize)> = Vec::new();
    for f in files {
        let e = extension(f);
        match counts.iter_mut().find(|(x, _)| *x == e) {
            Some((_, n)) => *n += 1,
            None => counts.push((e, 1)),
        }
    }
    // Most first; files without an extension last among equals.
    counts.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| (a.0.is_none(), &a.0).cmp(&(b.0.is_none(), &b.0))));
    counts
        .into_iter()
        .map(|(e, n)| match e {
            Some(e) => plural(n, &format!(".{e} file")),
            None => format!("{} without an extension", plural(n, "file")),
        })
        .collect()
}

fn sort_naturally(files: &mut [PathBuf]) {
    files.sort_by(|a, b| {
        natural_cmp(
            &a.file_name().unwrap_or_default().to_string_lossy(),
            &b.file_name().unwrap_or_default().to_string_lossy(),
        )
    });
}

/// The files matching the glob `input` (`dir/f*.svg`), of any extension, in natural order
/// (hidden files only when the pattern starts with a dot). Matching no file is an error that
/// says what the folder holds.
pub fn glob_files(input: &Path) -> Result<Vec<PathBuf>> {
    let (dir, pattern) = split_glob(input)?;
    let glob = tokens(&pattern);
    let entries = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut files: Vec<PathBuf> = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(&dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') && !pattern.starts_with('.') {
            continue;
        }
        let path = entry.path();
        if path.is_file() && glob_match(&glob, &name) {
            files.push(path);
        }
    }
    if files.is_empty() {
        let holds = Contents::read(&dir)?.describe();
        return Err(Error::Empty {
            path: input.to_path_buf(),
            what: format!("matches no files ('{}' holds {holds})", dir.display()),
        });
    }
    sort_naturally(&mut files);
    Ok(files)
}

/// Lists the files of a sequence: every file in directory `input` whose extension is one of
/// `extensions` (case-insensitive), the files matching the glob `input` (`dir/*.svg`,
/// whatever their extension), or the file `input` itself when its extension is one of
/// `extensions` (a one-frame sequence; a file of another kind is an error that names it). The
/// result is sorted naturally; an empty sequence is an error that says what the folder holds
/// instead.
pub fn list_sequence(input: &Path, extensions: &[&str]) -> Result<Vec<PathBuf>> {
    if is_glob(input) && !input.exists() {
        return glob_files(input);
    }
    let is_one_of = |p: &Path| extension(p).is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)));
    if input.is_file() {
        if is_one_of(input) {
            return Ok(vec![input.to_path_buf()]);
        }
        let kind = describe_files(&[input.to_path_buf()]).remove(0).replacen("1 ", "a ", 1);
        let exts: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
        return Err(Error::Empty {
            path: input.to_path_buf(),
            what: format!(
                "is {kind}, not a sequence: expected a folder or glob of {} files, or one such file",
                exts.join("/")
            ),
        });
    }
    if !input.exists() {
        return Err(Error::io(input, std::io::Error::new(std::io::ErrorKind::NotFound, "no such file or directory")));
    }
    let contents = Contents::read(input)?;
    let files: Vec<PathBuf> = contents.files.iter().filter(|p| is_one_of(p)).cloned().collect();
    if files.is_empty() {
        return Err(Error::Empty {
            path: input.to_path_buf(),
            what: format!("no {} files found (it holds {})", extensions.join("/"), contents.describe()),
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
        let glob_match = |pattern: &str, name: &str| super::glob_match(&tokens(pattern), name);
        assert!(glob_match("*.svg", "frame001.svg"));
        assert!(glob_match("fr?me*.svg", "frame001.svg"));
        assert!(!glob_match("*.svg", "frame001.png"));
        // Classes: ranges, lists, negation, a `]` first, an unclosed `[` as itself.
        assert!(glob_match("f0[1-3].svg", "f02.svg"));
        assert!(!glob_match("f0[1-3].svg", "f04.svg"));
        assert!(!glob_match("f0[1-3].svg", "f0-.svg"));
        assert!(glob_match("f[ab]*", "fb9.png"));
        assert!(glob_match("f[!ab]?", "fc1") && !glob_match("f[!ab]?", "fa1") && !glob_match("f[^ab]?", "fa1"));
        assert!(glob_match("[]x].txt", "].txt") && glob_match("[]x].txt", "x.txt"));
        assert!(glob_match("a[b", "a[b") && !glob_match("a[b", "ab"));
        assert!(glob_match("*[0-9][0-9].svg", "frame12.svg") && !glob_match("*[0-9][0-9].svg", "frame1.svg"));
        assert!(is_glob(Path::new("seq/f0[1-3].svg")) && is_glob(Path::new("seq/*.svg")));
        assert!(!is_glob(Path::new("seq/f0[1.svg")) && !is_glob(Path::new("seq[1-3]/f.svg")));
    }

    #[test]
    fn contents_are_described_by_extension() {
        let c = |files: &[&str], folders| Contents { files: files.iter().map(PathBuf::from).collect(), folders };
        assert_eq!(c(&[], 0).describe(), "0 files");
        assert_eq!(c(&["a.txt", "b.TXT", "c.txt"], 0).describe(), "3 .txt files");
        assert_eq!(
            c(&["a.json", "b.txt", "c.json", "README"], 1).describe(),
            "2 .json files, 1 .txt file, 1 file without an extension and 1 folder"
        );
    }
}
