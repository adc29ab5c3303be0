//! The published peers' per-model confusion counts (`peers.csv`), for side-by-side tables.
//!
//! ```
//! let dir = tempfile::tempdir()?;
//! let path = dir.path().join("peers.csv");
//! std::fs::write(
//!     &path,
//!     "dataset,model,method,description,gt_positive,tp,fp,tn,fn\n\
//!      abc,0133,ca,CA covariance analysis,sharp,1,2,3,4\n",
//! )?;
//! let peers = bounded_data::peers::read(&path)?;
//! assert_eq!((peers[0].method.as_str(), peers[0].fn_), ("ca", 4));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::DataError;
use std::path::Path;

/// The header line of a peers table.
const HEADER: &str = "dataset,model,method,description,gt_positive,tp,fp,tn,fn";

/// One published result: a method's confusion counts on one model.
#[derive(Debug, Clone, PartialEq)]
pub struct PeerResult {
    /// Dataset name (`default`, `abc`).
    pub dataset: String,
    /// Model (cloud) name, the file stem of the evaluation cloud.
    pub model: String,
    /// Short method key (`tc`, `pced`, `ca`, ...).
    pub method: String,
    /// Human-readable method name.
    pub description: String,
    /// What the peer counted as positive (`sharp` or `sharp+smooth`).
    pub gt_positive: String,
    /// True positives.
    pub tp: u64,
    /// False positives.
    pub fp: u64,
    /// True negatives.
    pub tn: u64,
    /// False negatives.
    pub fn_: u64,
}

/// Reads `peers.csv` (columns dataset,model,method,description,gt_positive,tp,fp,tn,fn).
pub fn read(path: &Path) -> Result<Vec<PeerResult>, DataError> {
    let text = std::fs::read_to_string(path).map_err(|e| DataError::io(path, e))?;
    parse(&text).map_err(|what| DataError::malformed(path, what))
}

/// The rows of a peers table, or what is wrong, naming the line.
fn parse(text: &str) -> Result<Vec<PeerResult>, String> {
    let mut lines = text.lines().enumerate();
    if lines
        .next()
        .is_none_or(|(_, header)| header.trim() != HEADER)
    {
        return Err(format!("line 1: expected the header {HEADER}"));
    }
    let mut rows = Vec::new();
    for (n, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.trim().split(',').collect();
        if cols.len() != 9 {
            return Err(format!(
                "line {}: expected 9 columns, found {}",
                n + 1,
                cols.len()
            ));
        }
        let count = |i: usize| -> Result<u64, String> {
            cols[i].parse().map_err(|_| {
                format!(
                    "line {}: column {} is not a count: {:?}",
                    n + 1,
                    i + 1,
                    cols[i]
                )
            })
        };
        rows.push(PeerResult {
            dataset: cols[0].into(),
            model: cols[1].into(),
            method: cols[2].into(),
            description: cols[3].into(),
            gt_positive: cols[4].into(),
            tp: count(5)?,
            fp: count(6)?,
            tn: count(7)?,
            fn_: count(8)?,
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_rows_and_rejects_bad_counts() {
        let ok = "dataset,model,method,description,gt_positive,tp,fp,tn,fn\n\
                  abc,0133,ca,CA covariance analysis,sharp,1,2,3,4\n";
        let rows = parse(ok).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(
            (rows[0].tp, rows[0].fp, rows[0].tn, rows[0].fn_),
            (1, 2, 3, 4)
        );
        assert_eq!(rows[0].model, "0133");
        let bad = ok.replace(",4\n", ",x\n");
        let err = parse(&bad).unwrap_err();
        assert!(err.contains("line 2") && err.contains("column 9"), "{err}");
        assert!(
            parse("a,b\n")
                .unwrap_err()
                .contains("line 1: expected the header")
        );
        assert!(
            parse(&ok.replace(",4\n", "\n"))
                .unwrap_err()
                .contains("9 columns, found 8")
        );
    }

    #[test]
    fn read_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("peers.csv");
        let e = read(&path).unwrap_err();
        assert!(matches!(e, DataError::Io { .. }), "{e}");
        std::fs::write(&path, "dataset,model\n").unwrap();
        let e = read(&path).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: line 1", path.display())), "{e}");
    }
}
