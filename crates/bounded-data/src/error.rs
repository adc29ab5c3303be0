use std::path::PathBuf;
use thiserror::Error;

/// Errors of reading, writing and generating point clouds.
///
/// Every variant names the file it concerns, so a command-line user sees which input is bad.
#[derive(Debug, Error)]
pub enum DataError {
    /// An I/O failure on a named file.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file's content does not follow its format.
    #[error("{path}: {what}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong, in words (with the line or byte offset where known).
        what: String,
    },
    /// The file extension names no supported format.
    #[error(
        "{path}: unknown point-cloud format (supported: .ply .pcd .xyz .txt .csv .las .laz .e57)"
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The positions read do not form a valid cloud (empty, NaN / infinite coordinates).
    #[error("{path}: {source}")]
    Geom {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: bounded_geom::GeomError,
    },
    /// The labels of a labelled cloud cannot be derived (unknown colour, bad class value).
    #[error("{path}: labels: {what}")]
    Labels {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the point and value.
        what: String,
    },
    /// A generator setting is out of range (noise level or outlier fraction negative,
    /// non-finite, or a fraction above 1).
    #[error("generator: {what}")]
    Generator {
        /// Which setting and value, and the range it must lie in.
        what: String,
    },
    /// A write request is inconsistent (e.g. fewer classes than points).
    #[error("{path}: cannot write: {what}")]
    InvalidOutput {
        /// The file that was to be written.
        path: PathBuf,
        /// What is inconsistent.
        what: String,
    },
}

impl DataError {
    /// A [`DataError::Malformed`] for `path`.
    pub(crate) fn malformed(path: &std::path::Path, what: impl Into<String>) -> Self {
        Self::Malformed {
            path: path.to_path_buf(),
            what: what.into(),
        }
    }

    /// A [`DataError::Io`] for `path`.
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

impl From<bounded_geom::atomic::WriteError> for DataError {
    fn from(e: bounded_geom::atomic::WriteError) -> Self {
        Self::Io {
            path: e.path,
            source: e.source,
        }
    }
}

/// Longest text, in characters, that an error message quotes from a file.
const MAX_QUOTED: usize = 60;

/// `text` from a file, in single quotes for an error message: control and other
/// non-printable characters escaped as in Rust source (`\u{1b}`, `\0`, `\t`), and cut after
/// [`MAX_QUOTED`] characters (marked `...`), so that a crafted file can neither send
/// terminal escape sequences nor flood the terminal. Every reader quotes file text through it.
pub(crate) fn quoted(text: &str) -> String {
    let mut out = String::from("'");
    for (k, c) in text.chars().enumerate() {
        if k == MAX_QUOTED {
            out.push_str("...");
            break;
        }
        match c {
            // Quotes and backslashes are printable: kept as they are, easier to read.
            '\'' | '"' | '\\' => out.push(c),
            _ => out.extend(c.escape_debug()),
        }
    }
    out.push('\'');
    out
}

#[cfg(test)]
mod tests {
    use super::quoted;

    #[test]
    fn quoting_escapes_control_characters_and_caps_the_length() {
        assert_eq!(quoted("x y"), "'x y'");
        assert_eq!(quoted("a\u{1b}[2Jb\u{7}\0\t"), r"'a\u{1b}[2Jb\u{7}\0\t'");
        // Invisible format characters (a right-to-left override) too; printable text stays.
        assert_eq!(quoted("\u{202e}é'\""), r#"'\u{202e}é'"'"#);
        let long = "z".repeat(100);
        assert_eq!(quoted(&long), format!("'{}...'", "z".repeat(60)));
    }

    #[test]
    fn readers_echo_no_raw_control_bytes_and_no_long_lines() {
        use std::path::Path;
        let evil = format!("\x1b]0;owned\x07\x1b[2J\0{}", "A".repeat(5000));
        let ply = format!("ply\nformat ascii 1.0\n{evil}\nend_header\n");
        let pcd = format!("FIELDS x y z\nSIZE 4 4 4\nTYPE {evil} F F\nPOINTS 1\nDATA ascii\n");
        let messages = [
            crate::ply::read_from(ply.as_bytes(), Path::new("e.ply")).unwrap_err(),
            crate::pcd::read_from(pcd.as_bytes(), Path::new("e.pcd")).unwrap_err(),
            crate::xyz::read_from(
                format!("1 2 3\n1 2 {evil}\n").as_bytes(),
                Path::new("e.xyz"),
            )
            .unwrap_err(),
            crate::xyz::read_from(
                format!("a b c {evil}\n1 2 3\n").as_bytes(),
                Path::new("e.xyz"),
            )
            .unwrap_err(),
        ]
        .map(|e| e.to_string());
        for m in messages {
            assert!(!m.chars().any(|c| c.is_control()), "{m:?}");
            assert!(m.contains(r"\u{1b}]0;owned\u{7}"), "{m}");
            assert!(m.len() < 300, "{m}");
        }
    }
}
