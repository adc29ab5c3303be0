//! The published peers' per-model confusion counts (`peers.csv`), for side-by-side tables.

use anyhow::{Context, Result, bail};
use std::path::Path;

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
pub fn read(path: &Path) -> Result<Vec<PeerResult>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the peers table", path.display()))?;
    parse(&text).with_context(|| format!("{}: malformed peers table", path.display()))
}

fn parse(text: &str) -> Result<Vec<PeerResult>> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, header))
            if header.trim() == "dataset,model,method,description,gt_positive,tp,fp,tn,fn" => {}
        _ => bail!(
            "line 1: expected the header dataset,model,method,description,gt_positive,tp,fp,tn,fn"
        ),
    }
    let mut rows = Vec::new();
    for (n, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.trim().split(',').collect();
        if cols.len() != 9 {
            bail!("line {}: expected 9 columns, found {}", n + 1, cols.len());
        }
        let count = |i: usize| -> Result<u64> {
            cols[i].parse().with_context(|| {
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
        let err = format!("{:#}", parse(&bad).unwrap_err());
        assert!(err.contains("line 2") && err.contains("column 9"), "{err}");
        assert!(parse("a,b\n").is_err());
    }
}
