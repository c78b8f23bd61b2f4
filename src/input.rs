//! CSV input parsers used by the CLI (and fuzzed by `fuzz/fuzz_targets/parse_csv.rs`):
//! holes `x,y,r` for `mesh`, points `x,y` for `triangulate`, and the `X,Y,R` triple of
//! `--bounding`.
//!
//! Rules shared by both files: lines are trimmed; blank lines are skipped; fields are split on
//! `,` and trimmed. Numbers are read with Rust's `f64` parser, so `nan`, `inf` and `1e999`
//! (infinity) are *numbers* here: they are refused later, with the hole or point named, by
//! [`crate::Domain`] validation or the triangulation. Every error names its 1-based line.
//! Nothing here panics, and the number of stored rows is capped (the cap is checked before a
//! row is stored, so an absurd file is refused without a matching allocation).

use crate::domain::Circle;
use crate::geometry::Point;

/// Why a CSV text was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CsvError {
    /// The text is empty or only whitespace.
    #[error("the CSV file is empty")]
    Empty,
    /// There is no data row (only a header, blank or comment lines).
    #[error("no {what} in the CSV file (only a header, blank or comment lines)")]
    NoRows { what: &'static str },
    /// A row has the wrong number of fields.
    #[error("line {line}: expected {expected} comma-separated numbers `{columns}`, found {found}")]
    WrongColumnCount {
        line: usize,
        expected: usize,
        found: usize,
        columns: &'static str,
    },
    /// A field is not a number.
    #[error("line {line}: '{field}' is not a number")]
    NotANumber { line: usize, field: String },
    /// More data rows than the limit.
    #[error("line {line}: more than {max} rows, the limit")]
    TooManyRows { line: usize, max: usize },
}

impl CsvError {
    /// The 1-based line the error is on, if any.
    pub fn line(&self) -> Option<usize> {
        match self {
            CsvError::WrongColumnCount { line, .. }
            | CsvError::NotANumber { line, .. }
            | CsvError::TooManyRows { line, .. } => Some(*line),
            CsvError::Empty | CsvError::NoRows { .. } => None,
        }
    }
}

/// Parse exactly `N` comma-separated numbers from one line (`line` is used in errors).
fn numbers<const N: usize>(
    text: &str,
    line: usize,
    columns: &'static str,
) -> Result<[f64; N], CsvError> {
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    if fields.len() != N {
        return Err(CsvError::WrongColumnCount {
            line,
            expected: N,
            found: fields.len(),
            columns,
        });
    }
    let mut out = [0.0; N];
    for (v, f) in out.iter_mut().zip(&fields) {
        *v = f.parse::<f64>().map_err(|_| CsvError::NotANumber {
            line,
            field: truncate(f),
        })?;
    }
    Ok(out)
}

/// A field for an error message: at most 40 characters, control characters escaped (a NUL
/// byte or a stray carriage return would otherwise be invisible: `'0.5\u{0}'`, not `'0.5'`).
fn truncate(f: &str) -> String {
    let mut s = String::new();
    for c in f.chars().take(40) {
        if c.is_control() {
            s.extend(c.escape_default());
        } else {
            s.push(c);
        }
    }
    if f.chars().count() > 40 {
        s.push_str("...");
    }
    s
}

/// `text` without a leading byte order mark (`U+FEFF`, which some editors write at the start
/// of CSV and JSON files). Every reader of this crate starts with it, so a BOM neither hides
/// the first row (it made `\u{feff}1,0,0.5` look like a header) nor breaks the JSON parser.
pub fn without_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// Whether the first line of a CSV file is a header: it has at least two comma-separated
/// fields and none of them is a number, quoted or not. So `x,y,r` is a header, while a data
/// row whose first field does not parse (`0x1,0,0.5`) or a row on another separator
/// (`1<TAB>0<TAB>0.5`, one field) is read as a row and refused with its line: a one-row file
/// used to lose its only row that way and mesh the empty disk.
fn is_header(line: &str) -> bool {
    let mut fields = line.split(',').map(|f| f.trim().trim_matches('"').trim());
    line.contains(',') && fields.all(|f| f.parse::<f64>().is_err())
}

/// The `X,Y,R` triple of `--bounding` (not validated beyond being three numbers).
pub fn parse_triple(text: &str) -> Result<[f64; 3], String> {
    numbers::<3>(text, 1, "X,Y,R").map_err(|e| match e {
        CsvError::WrongColumnCount { found, .. } => {
            format!("expected 3 comma-separated numbers X,Y,R, found {found}")
        }
        CsvError::NotANumber { field, .. } => format!("'{field}' is not a number"),
        other => other.to_string(),
    })
}

/// Holes from CSV text with at most [`crate::Domain::MAX_HOLES`] rows (see
/// [`parse_holes_csv_with_limit`]).
pub fn parse_holes_csv(text: &str) -> Result<Vec<Circle>, CsvError> {
    parse_holes_csv_with_limit(text, crate::Domain::MAX_HOLES)
}

/// Holes from CSV text: `x,y,r` per line; a leading byte order mark, blank lines and lines
/// starting with `#` are skipped; a first line of comma-separated fields none of which is a
/// number is a header. A text with a header and no row gives no holes (a disk domain); an empty text is
/// [`CsvError::Empty`].
pub fn parse_holes_csv_with_limit(text: &str, max_rows: usize) -> Result<Vec<Circle>, CsvError> {
    let text = without_bom(text);
    if text.trim().is_empty() {
        return Err(CsvError::Empty);
    }
    let mut holes = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if n == 0 && is_header(line) {
            continue;
        }
        if holes.len() >= max_rows {
            return Err(CsvError::TooManyRows {
                line: n + 1,
                max: max_rows,
            });
        }
        let [x, y, r] = numbers::<3>(line, n + 1, "x,y,r")?;
        holes.push(Circle::new(x, y, r));
    }
    Ok(holes)
}

/// Points from CSV text with no row limit beyond memory (see [`parse_points_csv_with_limit`]).
pub fn parse_points_csv(text: &str) -> Result<(Vec<Point>, Vec<usize>), CsvError> {
    parse_points_csv_with_limit(text, usize::MAX)
}

/// Points from CSV text, `x,y` per line, and the 1-based line number of each data row. A
/// leading byte order mark and blank lines are skipped; a first non-blank line of
/// comma-separated fields none of which is a number is a header. No data row is [`CsvError::NoRows`].
pub fn parse_points_csv_with_limit(
    text: &str,
    max_rows: usize,
) -> Result<(Vec<Point>, Vec<usize>), CsvError> {
    let mut points = Vec::new();
    let mut lines = Vec::new();
    let mut first = true;
    for (i, raw) in without_bom(text).lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        if first {
            first = false;
            if is_header(line) {
                continue;
            }
        }
        if points.len() >= max_rows {
            return Err(CsvError::TooManyRows {
                line: i + 1,
                max: max_rows,
            });
        }
        let [x, y] = numbers::<2>(line, i + 1, "x,y")?;
        points.push([x, y]);
        lines.push(i + 1);
    }
    if points.is_empty() {
        return Err(CsvError::NoRows { what: "points" });
    }
    Ok((points, lines))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holes_header_comments_and_errors() {
        let h = parse_holes_csv("x,y,r\n# c\n\n1, 2 ,0.5\n").unwrap();
        assert_eq!(h, vec![Circle::new(1.0, 2.0, 0.5)]);
        assert_eq!(parse_holes_csv("x,y,r\n").unwrap(), vec![]);
        assert_eq!(parse_holes_csv(" \n"), Err(CsvError::Empty));
        assert_eq!(
            parse_holes_csv("1,2,3\n1,x,3\n"),
            Err(CsvError::NotANumber {
                line: 2,
                field: "x".into()
            })
        );
        assert!(matches!(
            parse_holes_csv("1,2\n"),
            Err(CsvError::WrongColumnCount {
                line: 1,
                found: 2,
                ..
            })
        ));
        assert!(matches!(
            parse_holes_csv_with_limit("1,2,3\n4,5,6\n", 1),
            Err(CsvError::TooManyRows { line: 2, max: 1 })
        ));
    }

    #[test]
    fn points_header_blank_lines_and_spaces() {
        let (p, l) = parse_points_csv("x, y\n\n 1.5 , 2\n3,4  \n\n").unwrap();
        assert_eq!(p, vec![[1.5, 2.0], [3.0, 4.0]]);
        assert_eq!(l, vec![3, 4]);
        assert_eq!(parse_points_csv("1,2\n3,x\n").unwrap_err().line(), Some(2));
        assert_eq!(
            parse_points_csv("1,2\n3,4,5\n").unwrap_err().line(),
            Some(2)
        );
        assert!(parse_points_csv("\n\n").is_err());
        assert!(parse_points_csv("x,y\n").is_err());
    }

    #[test]
    fn triple() {
        assert_eq!(parse_triple(" 1, -2,3").unwrap(), [1.0, -2.0, 3.0]);
        assert!(parse_triple("1,2").unwrap_err().contains("found 2"));
        assert!(parse_triple("1,2,z").unwrap_err().contains("'z'"));
    }
}
