//! One test per class of bad input (the table in the README's "Bad input" section): each
//! asserts the library's typed error and runs the CLI binary, asserting its exit code
//! (2 bad input, 1 output or internal failure), a stderr message naming the problem, and that
//! nothing panicked.

use medial_blocks::geometry::{Triangulation, TriangulationError};
use medial_blocks::grid::{GridError, MAX_CELLS_PER_SIDE, MAX_TOTAL_NODES};
use medial_blocks::input::{parse_holes_csv, parse_holes_csv_with_limit, parse_triple, CsvError};
use medial_blocks::output::Format;
use medial_blocks::{mesh, Circle, Domain, DomainError, MeshError, Options};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the CLI; returns the exit code and stderr.
fn cli(args: &[&str], cwd: &Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run the CLI");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "the CLI panicked: {err}");
    (out.status.code().unwrap_or(-1), err)
}

/// Runs the CLI and asserts the exit code and that stderr contains every needle.
fn expect(args: &[&str], cwd: &Path, code: i32, needles: &[&str]) {
    let (c, err) = cli(args, cwd);
    assert_eq!(c, code, "{args:?}: exit code {c}, stderr {err:?}");
    if code == 0 {
        return;
    }
    assert!(err.starts_with("error: "), "{args:?}: stderr {err:?}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: stderr {err:?} lacks {n:?}");
    }
    // Every error is one line, clap's usage errors too.
    assert_eq!(err.lines().count(), 1, "one line of error: {err:?}");
}

struct Scratch {
    dir: tempfile::TempDir,
}

impl Scratch {
    fn new() -> Self {
        Scratch {
            dir: tempfile::tempdir().expect("temporary directory"),
        }
    }
    fn path(&self) -> &Path {
        self.dir.path()
    }
    fn file(&self, name: &str, content: impl AsRef<[u8]>) -> PathBuf {
        let p = self.path().join(name);
        std::fs::write(&p, content).expect("write input");
        p
    }
    /// `mesh NAME -o out --format json -q` plus `extra`, run in the scratch directory.
    fn mesh(&self, name: &str, content: &str, extra: &[&str], code: i32, needles: &[&str]) {
        self.file(name, content);
        let mut args = vec!["mesh", name, "-o", "out", "--format", "json", "-q"];
        args.extend_from_slice(extra);
        expect(&args, self.path(), code, needles);
        if code != 0 {
            assert!(
                !self.path().join("out/report.json").exists(),
                "a failed run wrote a report"
            );
        }
    }
}

fn json_domain(bounding: &str, holes: &[&str]) -> String {
    format!(
        "{{\"bounding\": {bounding}, \"holes\": [{}]}}",
        holes.join(", ")
    )
}

fn c(x: f64, y: f64, r: f64) -> String {
    format!("{{\"center\": [{x:?}, {y:?}], \"radius\": {r:?}}}")
}

const B10: &str = "{\"center\": [0, 0], \"radius\": 10}";

// 1. A number that overflows to infinity in JSON (JSON has no NaN or Infinity literal).
#[test]
fn json_overflowing_number() {
    let text = json_domain("{\"center\": [0, 0], \"radius\": 1e999}", &[]);
    let e = Domain::from_json_str(&text).unwrap_err();
    assert!(
        matches!(&e, DomainError::Json(m) if m.contains("number out of range")),
        "{e:?}"
    );
    Scratch::new().mesh(
        "d.json",
        &text,
        &[],
        2,
        &["d.json", "number out of range", "must be finite"],
    );
}

// 2. A NaN or Infinity literal in JSON: not JSON.
#[test]
fn json_nan_literal() {
    let text = json_domain(B10, &["{\"center\": [NaN, 0], \"radius\": 1}"]);
    let e = Domain::from_json_str(&text).unwrap_err();
    assert!(
        matches!(&e, DomainError::Json(m) if m.contains("line 1")),
        "{e:?}"
    );
    Scratch::new().mesh("d.json", &text, &[], 2, &["invalid domain JSON", "column"]);
}

// 3. Non-finite numbers through CSV (`nan`, `inf` parse as numbers, then validation names them).
#[test]
fn csv_non_finite() {
    let holes = parse_holes_csv("1,2,0.5\nnan,0,1\n").unwrap();
    let e = Domain::bounded(Circle::new(0.0, 0.0, 10.0), holes).unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::NonFinite {
                circle: 1,
                field: "center x",
                ..
            }
        ),
        "{e:?}"
    );
    let s = Scratch::new();
    s.mesh(
        "h.csv",
        "1,2,0.5\nnan,0,1\n",
        &["--bounding", "0,0,10"],
        2,
        &["hole 1", "non-finite center x"],
    );
    s.mesh(
        "h.csv",
        "1,2,inf\n",
        &["--bounding", "0,0,10"],
        2,
        &["hole 0", "non-finite radius"],
    );
    s.mesh(
        "h.csv",
        "1,2,0.5\n",
        &["--bounding", "0,0,1e999"],
        2,
        &["bounding circle", "non-finite radius"],
    );
}

// 4. Negative radius.
#[test]
fn negative_radius() {
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![Circle::new(0.0, 0.0, 1.0), Circle::new(5.0, 0.0, -1.0)],
    )
    .unwrap_err();
    assert_eq!(
        e,
        DomainError::NonPositiveRadius {
            circle: 1,
            radius: -1.0
        }
    );
    let text = json_domain(B10, &[&c(0.0, 0.0, 1.0), &c(5.0, 0.0, -1.0)]);
    Scratch::new().mesh(
        "d.json",
        &text,
        &[],
        2,
        &["hole 1", "radius -1", "must be positive"],
    );
}

// 5. Zero radius, of a hole or of the bounding circle.
#[test]
fn zero_radius() {
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![Circle::new(0.0, 0.0, 0.0)],
    )
    .unwrap_err();
    assert_eq!(
        e,
        DomainError::NonPositiveRadius {
            circle: 0,
            radius: 0.0
        }
    );
    let e = Domain::bounded(Circle::new(0.0, 0.0, 0.0), vec![]).unwrap_err();
    assert_eq!(
        e,
        DomainError::NonPositiveRadius {
            circle: -1,
            radius: 0.0
        }
    );
    let s = Scratch::new();
    s.mesh(
        "d.json",
        &json_domain(B10, &[&c(0.0, 0.0, 0.0)]),
        &[],
        2,
        &["hole 0", "radius 0"],
    );
    s.mesh(
        "d.json",
        &json_domain("{\"center\": [0, 0], \"radius\": 0}", &[]),
        &[],
        2,
        &["the bounding circle", "radius 0"],
    );
}

// 6. A hole outside the bounding circle.
#[test]
fn hole_outside_bounding_circle() {
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![Circle::new(0.0, 0.0, 1.0), Circle::new(20.0, 0.0, 1.0)],
    )
    .unwrap_err();
    assert!(
        matches!(e, DomainError::HoleNotInside { hole: 1, gap, .. } if gap < 0.0),
        "{e:?}"
    );
    let text = json_domain(B10, &[&c(0.0, 0.0, 1.0), &c(20.0, 0.0, 1.0)]);
    Scratch::new().mesh(
        "d.json",
        &text,
        &[],
        2,
        &["hole 1 is not strictly inside the bounding circle"],
    );
}

// 7. A hole touching the bounding circle (exactly, or within the gap tolerance).
#[test]
fn hole_touching_bounding_circle() {
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![Circle::new(8.0, 0.0, 2.0)],
    )
    .unwrap_err();
    assert!(
        matches!(e, DomainError::HoleNotInside { hole: 0, gap, .. } if gap == 0.0),
        "{e:?}"
    );
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![Circle::new(8.0, 0.0, 2.0 - 1e-12)],
    )
    .unwrap_err();
    assert!(
        matches!(e, DomainError::HoleNotInside { hole: 0, .. }),
        "{e:?}"
    );
    Scratch::new().mesh(
        "h.csv",
        "x,y,r\n8,0,2\n",
        &["--bounding", "0,0,10"],
        2,
        &["hole 0 is not strictly inside", "gap"],
    );
}

// 8. Overlapping holes.
#[test]
fn overlapping_holes() {
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![
            Circle::new(-5.0, 0.0, 1.0),
            Circle::new(0.0, 0.0, 1.0),
            Circle::new(1.5, 0.0, 1.0),
        ],
    )
    .unwrap_err();
    assert!(
        matches!(e, DomainError::HolesOverlap { first: 1, second: 2, gap, .. } if gap < 0.0),
        "{e:?}"
    );
    let text = json_domain(
        B10,
        &[&c(-5.0, 0.0, 1.0), &c(0.0, 0.0, 1.0), &c(1.5, 0.0, 1.0)],
    );
    Scratch::new().mesh("d.json", &text, &[], 2, &["holes 1 and 2 overlap"]);
}

// 9. Touching holes (gap zero, or within the tolerance 1e-9 R).
#[test]
fn touching_holes() {
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![Circle::new(0.0, 0.0, 1.0), Circle::new(2.0, 0.0, 1.0)],
    )
    .unwrap_err();
    assert!(
        matches!(e, DomainError::HolesOverlap { first: 0, second: 1, gap, .. } if gap == 0.0),
        "{e:?}"
    );
    let text = json_domain(B10, &[&c(0.0, 0.0, 1.0), &c(2.0 + 1e-9, 0.0, 1.0)]);
    let e = Domain::from_json_str(&text).unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::HolesOverlap {
                first: 0,
                second: 1,
                ..
            }
        ),
        "{e:?}"
    );
    Scratch::new().mesh(
        "d.json",
        &text,
        &[],
        2,
        &["holes 0 and 1 overlap or touch", "must exceed"],
    );
}

// 10. Duplicate holes.
#[test]
fn duplicate_holes() {
    let e = Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![
            Circle::new(3.0, 0.0, 1.0),
            Circle::new(-3.0, 0.0, 1.0),
            Circle::new(3.0, 0.0, 1.0),
        ],
    )
    .unwrap_err();
    assert_eq!(
        e,
        DomainError::DuplicateHole {
            first: 0,
            second: 2
        }
    );
    Scratch::new().mesh(
        "h.csv",
        "3,0,1\n-3,0,1\n3,0,1\n",
        &["--bounding", "0,0,10"],
        2,
        &["hole 2 is a duplicate of hole 0"],
    );
}

// 11. Empty input where holes are required: an empty file. (An empty `holes` array, or a CSV
// with only a header, is allowed: the disk template.)
#[test]
fn empty_files() {
    assert_eq!(parse_holes_csv(""), Err(CsvError::Empty));
    assert_eq!(parse_holes_csv("x,y,r\n"), Ok(vec![]));
    let e = Domain::from_json_str("").unwrap_err();
    assert!(matches!(e, DomainError::Json(_)), "{e:?}");
    let s = Scratch::new();
    s.mesh("d.json", "", &[], 2, &["d.json", "the file is empty"]);
    s.mesh(
        "h.csv",
        " \n\n",
        &["--bounding", "0,0,10"],
        2,
        &["h.csv", "the CSV file is empty"],
    );
    // Allowed: no holes at all is a disk.
    s.mesh("d.json", &json_domain(B10, &[]), &[], 0, &[]);
}

// 12. An absurd number of holes: refused by count before the holes are stored.
#[test]
fn absurd_hole_count() {
    let holes: Vec<String> = (0..1000).map(|k| c(f64::from(k), 0.0, 0.1)).collect();
    let text = json_domain(
        "{\"center\": [0, 0], \"radius\": 10000}",
        &holes.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    assert_eq!(
        Domain::from_json_str_with_limit(&text, 10),
        Err(DomainError::TooManyHoles {
            count: 1000,
            max: 10
        })
    );
    assert_eq!(
        Domain::bounded_with_limit(
            Circle::new(0.0, 0.0, 10.0),
            vec![Circle::new(0.0, 0.0, 1.0); 3],
            2
        ),
        Err(DomainError::TooManyHoles { count: 3, max: 2 })
    );
    assert!(matches!(
        parse_holes_csv_with_limit("0,0,1\n0,0,1\n0,0,1\n", 2),
        Err(CsvError::TooManyRows { line: 3, max: 2 })
    ));
    // Through the CLI: one row more than Domain::MAX_HOLES (a 6 MB CSV).
    let s = Scratch::new();
    let rows = Domain::MAX_HOLES + 1;
    s.file("h.csv", "0,0,1\n".repeat(rows));
    expect(
        &["mesh", "h.csv", "--bounding", "0,0,10", "-o", "out", "-q"],
        s.path(),
        2,
        &[
            &format!("line {rows}"),
            &format!("more than {} rows", Domain::MAX_HOLES),
        ],
    );
}

// 13. Absurd --cells: refused before any grid allocation.
#[test]
fn absurd_cells() {
    let d = Domain::hexagon_example();
    // Exact mode refuses it the same way, before allocating.
    let e = mesh(
        &d,
        &Options {
            cells: 1_000_000_000,
            ..Options::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, MeshError::Grid(GridError::TooManyCellsPerSide { .. })),
        "{e:?}"
    );
    let e = mesh(
        &d,
        &Options {
            cells: 1_000_000_000,
            ..Options::paper()
        },
    )
    .unwrap_err();
    assert_eq!(
        e,
        MeshError::Grid(GridError::TooManyCellsPerSide {
            cells: 1_000_000_000,
            limit: MAX_CELLS_PER_SIDE
        })
    );
    let e = mesh(
        &d,
        &Options {
            cells: MAX_CELLS_PER_SIDE,
            ..Options::paper()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, MeshError::Grid(GridError::TooManyNodes { nodes, limit }) if nodes > limit && limit == MAX_TOTAL_NODES),
        "{e:?}"
    );
    let s = Scratch::new();
    expect(
        &["mesh", "-o", "out", "-q", "--cells", "1000000000"],
        s.path(),
        2,
        &["1000000000 cells along a block side", "limit of 100000"],
    );
    expect(
        &["mesh", "-o", "out", "-q", "--cells", "100000"],
        s.path(),
        2,
        &[&format!("nodes, more than the limit of {MAX_TOTAL_NODES}")],
    );
    expect(
        &[
            "mesh",
            "-o",
            "out",
            "-q",
            "--cells",
            "99999999999999999999999",
        ],
        s.path(),
        2,
        &["--cells"],
    );
}

// 14. --cells 0 (and negative).
#[test]
fn zero_cells() {
    let e = mesh(
        &Domain::hexagon_example(),
        &Options {
            cells: 0,
            ..Options::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, MeshError::Options(_)), "{e:?}");
    let s = Scratch::new();
    expect(
        &["mesh", "-o", "out", "-q", "--cells", "0"],
        s.path(),
        2,
        &["--cells must be at least 1"],
    );
    expect(
        &["mesh", "-o", "out", "-q", "--cells", "-3"],
        s.path(),
        2,
        &["invalid value '-3' for '--cells <CELLS>'"],
    );
}

// 15. Absurd coordinates (beyond 1e100, so squares stay finite).
#[test]
fn absurd_coordinates() {
    let e = Domain::bounded(Circle::new(1e300, 0.0, 10.0), vec![]).unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::OutOfRange {
                circle: -1,
                field: "center x",
                ..
            }
        ),
        "{e:?}"
    );
    let text = json_domain(
        "{\"center\": [0, 0], \"radius\": 1e200}",
        &[&c(0.0, 1e150, 1.0)],
    );
    assert!(matches!(
        Domain::from_json_str(&text),
        Err(DomainError::OutOfRange {
            circle: -1,
            field: "radius",
            ..
        })
    ));
    Scratch::new().mesh(
        "d.json",
        &text,
        &[],
        2,
        &[
            "the bounding circle has radius = 1e200",
            "beyond the supported magnitude 1e100",
        ],
    );
}

// 16. Malformed JSON (not JSON at all, trailing garbage).
#[test]
fn malformed_json() {
    for text in [
        "{bounding: 1}",
        "[1, 2, 3]",
        "{\"bounding\": {\"center\": [0, 0], \"radius\": 1}, \"holes\": []} x",
    ] {
        let e = Domain::from_json_str(text).unwrap_err();
        assert!(matches!(e, DomainError::Json(_)), "{text}: {e:?}");
    }
    Scratch::new().mesh(
        "d.json",
        "{bounding: 1}",
        &[],
        2,
        &["d.json: invalid domain JSON: key must be a string at line 1 column 2"],
    );
}

// 17. Truncated JSON.
#[test]
fn truncated_json() {
    let full = json_domain(B10, &[&c(1.0, 1.0, 1.0)]);
    for cut in 1..full.len() {
        let e = Domain::from_json_str(&full[..cut]).unwrap_err();
        assert!(matches!(e, DomainError::Json(_)), "{cut}: {e:?}");
    }
    Scratch::new().mesh(
        "d.json",
        &full[..full.len() - 5],
        &[],
        2,
        &["invalid domain JSON: EOF while parsing"],
    );
}

// 18. Wrong types.
#[test]
fn wrong_types() {
    let text = json_domain(B10, &["{\"center\": [0, 0], \"radius\": \"1\"}"]);
    let e = Domain::from_json_str(&text).unwrap_err();
    assert!(
        matches!(&e, DomainError::Json(m) if m.contains("invalid type: string")),
        "{e:?}"
    );
    let s = Scratch::new();
    s.mesh(
        "d.json",
        &text,
        &[],
        2,
        &["invalid type: string \"1\", expected f64"],
    );
    s.mesh(
        "d.json",
        &json_domain(B10, &["{\"center\": [0, 0, 0], \"radius\": 1}"]),
        &[],
        2,
        &["invalid length 3, expected a centre [x, y] of two numbers"],
    );
    s.mesh(
        "d.json",
        "{\"bounding\": {\"center\": [0, 0], \"radius\": 10}, \"holes\": {}}",
        &[],
        2,
        &["invalid type: map, expected an array of circles"],
    );
}

// 19. Unknown fields (at the top level and inside a circle).
#[test]
fn unknown_fields() {
    let text = json_domain(B10, &["{\"center\": [0, 0], \"radius\": 1, \"mass\": 2}"]);
    let e = Domain::from_json_str(&text).unwrap_err();
    assert!(
        matches!(&e, DomainError::Json(m) if m.contains("unknown field `mass`")),
        "{e:?}"
    );
    let s = Scratch::new();
    s.mesh(
        "d.json",
        &text,
        &[],
        2,
        &["unknown field `mass`, expected `center` or `radius`"],
    );
    s.mesh(
        "d.json",
        "{\"bounding\": {\"center\": [0, 0], \"radius\": 10}, \"holes\": [], \"periodic\": true}",
        &[],
        2,
        &["unknown field `periodic`"],
    );
}

// 20. Missing fields.
#[test]
fn missing_fields() {
    let text = json_domain(B10, &["{\"center\": [0, 0]}"]);
    let e = Domain::from_json_str(&text).unwrap_err();
    assert!(
        matches!(&e, DomainError::Json(m) if m.contains("missing field `radius`")),
        "{e:?}"
    );
    let s = Scratch::new();
    s.mesh("d.json", &text, &[], 2, &["missing field `radius`"]);
    s.mesh(
        "d.json",
        "{\"holes\": []}",
        &[],
        2,
        &["missing field `bounding`"],
    );
}

// 21. A nonexistent, unreadable (a directory) or non-UTF-8 input file.
#[test]
fn unreadable_input() {
    let s = Scratch::new();
    expect(
        &["mesh", "nope.json", "-o", "out"],
        s.path(),
        2,
        &["cannot read nope.json"],
    );
    std::fs::create_dir(s.path().join("dir.json")).unwrap();
    expect(
        &["mesh", "dir.json", "-o", "out"],
        s.path(),
        2,
        &["cannot read dir.json"],
    );
    s.file("bin.json", [0xff, 0xfe, 0x00, 0x7b]);
    expect(
        &["mesh", "bin.json", "-o", "out"],
        s.path(),
        2,
        &["cannot read bin.json", "UTF-8"],
    );
    expect(
        &["triangulate", "nope.csv"],
        s.path(),
        2,
        &["nope.csv: cannot read"],
    );
}

// 22. CSV with a bad number.
#[test]
fn csv_bad_number() {
    assert_eq!(
        parse_holes_csv("1,2,0.5\n3,4x,1\n"),
        Err(CsvError::NotANumber {
            line: 2,
            field: "4x".into()
        })
    );
    Scratch::new().mesh(
        "h.csv",
        "1,2,0.5\n3,4x,1\n",
        &["--bounding", "0,0,10"],
        2,
        &["h.csv: line 2: '4x' is not a number"],
    );
}

// 23. CSV with the wrong column count.
#[test]
fn csv_wrong_column_count() {
    assert_eq!(
        parse_holes_csv("x,y,r\n1,2,0.5\n3,4\n"),
        Err(CsvError::WrongColumnCount {
            line: 3,
            expected: 3,
            found: 2,
            columns: "x,y,r"
        })
    );
    Scratch::new().mesh(
        "h.csv",
        "x,y,r\n1,2,0.5\n3,4\n",
        &["--bounding", "0,0,10"],
        2,
        &["line 3: expected 3 comma-separated numbers `x,y,r`, found 2"],
    );
}

// 24. CSV of holes without --bounding, or a bad --bounding, or --bounding with JSON.
#[test]
fn csv_bounding_problems() {
    assert!(parse_triple("0,0").unwrap_err().contains("found 2"));
    let s = Scratch::new();
    s.mesh(
        "h.csv",
        "1,2,0.5\n",
        &[],
        2,
        &["needs the bounding circle --bounding X,Y,R"],
    );
    s.mesh(
        "h.csv",
        "1,2,0.5\n",
        &["--bounding", "0,0"],
        2,
        &["--bounding: expected 3 comma-separated numbers X,Y,R, found 2"],
    );
    s.mesh(
        "h.csv",
        "1,2,0.5\n",
        &["--bounding", "0,zero,10"],
        2,
        &["--bounding: 'zero' is not a number"],
    );
    s.mesh(
        "d.json",
        &json_domain(B10, &[]),
        &["--bounding", "0,0,10"],
        2,
        &["--bounding is for CSV input"],
    );
}

// 25. Unknown --format.
#[test]
fn unknown_format() {
    assert!(Format::parse_list("vtk,stl")
        .unwrap_err()
        .contains("unknown format 'stl'"));
    assert!(Format::parse_list(",").is_err());
    let s = Scratch::new();
    expect(
        &["mesh", "-o", "out", "--format", "vtk,stl"],
        s.path(),
        2,
        &["--format: unknown format 'stl' (choose from vtk"],
    );
    expect(
        &["mesh", "-o", "out", "--format", ""],
        s.path(),
        2,
        &["--format: no format named"],
    );
    assert!(!s.path().join("out").exists(), "nothing written");
}

// 26. An output directory that cannot be written (a path under a regular file).
#[test]
fn unwritable_output_directory() {
    let s = Scratch::new();
    s.file("plain", "not a directory");
    expect(
        &["mesh", "-o", "plain/out", "-q"],
        s.path(),
        1,
        &["cannot write into plain/out"],
    );
    expect(
        &["triangulate", "-o", "plain/t.json"],
        s.path(),
        1,
        &["cannot create plain/t.json"],
    );
}

// 27. triangulate: too few distinct points.
#[test]
fn triangulate_too_few_points() {
    assert_eq!(
        Triangulation::new(&[[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]]).err(),
        Some(TriangulationError::TooFewPoints { distinct: 2 })
    );
    let s = Scratch::new();
    s.file("p.csv", "0,0\n1,1\n0,0\n");
    expect(
        &["triangulate", "p.csv"],
        s.path(),
        2,
        &["p.csv: need at least 3 distinct points, got 2"],
    );
    s.file("e.csv", "x,y\n");
    expect(
        &["triangulate", "e.csv"],
        s.path(),
        2,
        &["e.csv: no points"],
    );
}

// 28. triangulate: all points collinear.
#[test]
fn triangulate_collinear() {
    let pts: Vec<[f64; 2]> = (0..5).map(|k| [f64::from(k), 2.0 * f64::from(k)]).collect();
    assert_eq!(
        Triangulation::new(&pts).err(),
        Some(TriangulationError::AllCollinear { distinct: 5 })
    );
    let s = Scratch::new();
    s.file("p.csv", "0,0\n1,2\n2,4\n3,6\n4,8\n");
    expect(
        &["triangulate", "p.csv"],
        s.path(),
        2,
        &["all 5 distinct points are collinear"],
    );
}

// 29. triangulate: a non-finite point, a bad number, a wrong column count.
#[test]
fn triangulate_bad_rows() {
    assert_eq!(
        Triangulation::new(&[[0.0, 0.0], [f64::NAN, 1.0], [1.0, 0.0]]).err(),
        Some(TriangulationError::NonFinite { index: 1 })
    );
    let s = Scratch::new();
    s.file("p.csv", "x,y\n0,0\ninf,1\n1,0\n");
    expect(
        &["triangulate", "p.csv"],
        s.path(),
        2,
        &["p.csv:3: non-finite coordinate"],
    );
    s.file("p.csv", "0,0\n1,zz\n");
    expect(
        &["triangulate", "p.csv"],
        s.path(),
        2,
        &["p.csv:2: `zz` is not a number"],
    );
    s.file("p.csv", "0,0\n1,2,3\n");
    expect(
        &["triangulate", "p.csv"],
        s.path(),
        2,
        &["p.csv:2: expected 2 columns `x,y`, found 3"],
    );
}

// 30. A valid domain very tight for boundary sampling (holes within 1e-8 R of the bounding
// circle): adaptive sampling meshes it now (tests/fuzz_replay_mesh.rs,
// near_touching_bounding_circle_is_meshed); a refusal, if it ever comes back, must be typed,
// never a panic or a bad mesh.
#[test]
fn too_tight_for_sampling() {
    let r = 0.44;
    let holes: Vec<Circle> = (0..5)
        .map(|k| {
            let a = 2.0 * std::f64::consts::PI * f64::from(k) / 5.0;
            Circle::new(a.cos(), a.sin(), r)
        })
        .collect();
    let big = (1.0 + r) * (1.0 + 1e-8);
    let d = Domain::bounded(Circle::new(0.0, 0.0, big), holes.clone()).unwrap();
    match mesh(&d, &Options::default()) {
        Err(MeshError::Sampling { circle: -1, .. }) => {}
        // Sampling may learn to cope: then the mesh must pass every check.
        Ok(m) => medial_blocks::fuzzing::check_mesh(&d, &m).unwrap(),
        Err(e) => panic!("unexpected error {e:?}"),
    }
    let text = json_domain(
        &c(0.0, 0.0, big),
        &holes
            .iter()
            .map(|h| c(h.center[0], h.center[1], h.radius))
            .collect::<Vec<_>>()
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    let s = Scratch::new();
    s.file("d.json", &text);
    let (code, err) = cli(
        &["mesh", "d.json", "-o", "out", "-q", "--format", "json"],
        s.path(),
    );
    assert!(
        code == 0 || (code == 2 && err.contains("boundary sampling of circle -1 did not converge")),
        "{code}: {err}"
    );
}

// 32. A circle too small for the magnitude of its coordinates (radius below 16 units in the
// last place: its samples cannot be distinct). Prefer meshing: a radius just above
// the limit is accepted.
#[test]
fn radius_below_precision() {
    let bounding = Circle::new(1e6, 0.0, 10.0);
    let min_radius = Domain::min_radius_for(&bounding);
    assert!(min_radius > 3e-9 && min_radius < 4e-9, "{min_radius}");
    let e = Domain::bounded(bounding, vec![Circle::new(1e6, 0.0, 1e-9)]).unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::RadiusBelowPrecision { circle: 0, radius, magnitude, .. }
                if radius == 1e-9 && magnitude == 1e6 + 10.0
        ),
        "{e:?}"
    );
    // The same hole near the origin is fine, and so is a radius at the limit.
    Domain::bounded(
        Circle::new(0.0, 0.0, 10.0),
        vec![Circle::new(0.0, 0.0, 1e-8)],
    )
    .unwrap();
    Domain::bounded(bounding, vec![Circle::new(1e6, 0.0, min_radius)]).unwrap();
    // The bounding circle too.
    let e = Domain::bounded(Circle::new(1e6, 0.0, 1e-9), vec![]).unwrap_err();
    assert!(
        matches!(e, DomainError::RadiusBelowPrecision { circle: -1, .. }),
        "{e:?}"
    );
    let text = json_domain(
        "{\"center\": [1e6, 0], \"radius\": 10}",
        &[&c(1e6, 0.0, 1e-9)],
    );
    Scratch::new().mesh(
        "d.json",
        &text,
        &[],
        2,
        &[
            "hole 0 has radius 1e-9, which is too small for coordinates of magnitude 1.00001e6",
            "units in the last place",
            "translate the layout nearer the origin or scale it up",
        ],
    );
    // Periodic domains: the bound is the extent of the tiling the mesher samples (8 L).
    let e = medial_blocks::PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.5, 0.5, 1e-14)])
        .unwrap_err();
    assert!(
        matches!(e, DomainError::RadiusBelowPrecision { circle: 0, magnitude, .. } if magnitude == 8.0),
        "{e:?}"
    );
}

// 33. Two circles farther apart than the tolerance (1e-9 R) but closer than double precision
// resolves at the magnitude of their coordinates (3 units in the last place): a small domain
// far from the origin.
#[test]
fn gap_below_precision() {
    let bounding = Circle::new(1e6, 0.0, 0.1);
    let a = Circle::new(1e6 - 0.05, 0.0, 0.04);
    let d = medial_blocks::domain::dist(a.center, [1e6 + 0.04, 0.0]);
    let b = Circle::new(1e6 + 0.04, 0.0, d - 0.04 - 3e-10);
    let gap = medial_blocks::domain::gap(&a, &b);
    let unit = f64::EPSILON * (1e6 + 0.1);
    assert!(gap > 1e-9 * 0.1 && gap < 3.0 * unit, "{gap:e}");
    assert_eq!(Domain::min_gap_for(&bounding), 3.0 * unit);
    let e = Domain::bounded(bounding, vec![a, b]).unwrap_err();
    assert!(
        matches!(e, DomainError::GapBelowPrecision { first: 0, second: 1, gap: g, .. } if g == gap),
        "{e:?}"
    );
    // A hole as close to the bounding circle.
    let h = Circle::new(1e6 + 0.05, 0.0, 0.05 - 2e-10);
    let e = Domain::bounded(bounding, vec![h]).unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::GapBelowPrecision {
                first: -1,
                second: 0,
                ..
            }
        ),
        "{e:?}"
    );
    // The same pair at the origin is a valid (near-touching) domain.
    Domain::bounded(
        Circle::new(0.0, 0.0, 0.1),
        vec![
            Circle::new(-0.05, 0.0, 0.04),
            Circle::new(0.04, 0.0, 0.05 - 0.04 - 3e-10 + 0.04),
        ],
    )
    .unwrap();
    let text = json_domain(
        &c(1e6, 0.0, 0.1),
        &[
            &c(a.center[0], 0.0, a.radius),
            &c(b.center[0], 0.0, b.radius),
        ],
    );
    Scratch::new().mesh(
        "d.json",
        &text,
        &[],
        2,
        &[
            "holes 0 and 1 are only",
            "apart, which is too close for coordinates of magnitude 1.0000001e6",
            "needs a gap of at least",
            "translate the layout nearer the origin or scale it up",
        ],
    );
}

// 34. A per-circle option naming a circle the domain does not have (it used to be ignored
// without a word).
#[test]
fn circle_option_naming_no_circle() {
    use medial_blocks::exact_mode::Clustering;
    use medial_blocks::{mesh_periodic, PeriodicDomain};
    let d = Domain::hexagon_example(); // circles -1..=6
    let clustering = Clustering {
        first: None,
        growth: 1.2,
    };
    let refused = |e: MeshError, flag: &str, id: i32| {
        assert!(
            matches!(&e, MeshError::Options(m)
                if m.contains(&format!("{flag} names circle {id},"))
                    && m.contains("not a circle of the domain")),
            "{e:?}"
        );
    };
    for mode in [medial_blocks::Mode::Exact, medial_blocks::Mode::Paper] {
        for id in [7, 99, -2] {
            let o = Options {
                mode,
                wall_cells: vec![(id, 3)],
                ..Options::default()
            };
            refused(mesh(&d, &o).unwrap_err(), "--wall-cells", id);
            let o = Options {
                mode,
                circle_clustering: vec![(id, clustering)],
                ..Options::default()
            };
            refused(mesh(&d, &o).unwrap_err(), "--circle-clustering", id);
        }
    }
    // The first and the last circle are accepted, and a fixed count is obeyed (the oracle
    // that the check does not refuse what the mesher uses).
    for id in [-1, 6] {
        let o = Options {
            wall_cells: vec![(id, 3)],
            ..Options::default()
        };
        mesh(&d, &o).unwrap();
    }
    // The disk: only the bounding circle.
    let disk = Domain::bounded(Circle::new(0.0, 0.0, 1.0), vec![]).unwrap();
    let o = Options {
        wall_cells: vec![(0, 3)],
        ..Options::default()
    };
    refused(mesh(&disk, &o).unwrap_err(), "--wall-cells", 0);
    // A periodic domain has no bounding circle.
    let pd = PeriodicDomain::new(
        [1.0, 1.0],
        vec![Circle::new(0.3, 0.3, 0.1), Circle::new(0.7, 0.6, 0.15)],
    )
    .unwrap();
    for id in [-1, 2] {
        let o = Options {
            wall_cells: vec![(id, 3)],
            ..Options::default()
        };
        refused(mesh_periodic(&pd, &o).unwrap_err(), "--wall-cells", id);
    }
    let s = Scratch::new();
    expect(
        &["mesh", "-o", "out", "-q", "--circle-clustering", "99:0.01"],
        s.path(),
        2,
        &[
            "--circle-clustering names circle 99",
            "its circles are -1 (the bounding circle) to 6",
        ],
    );
    expect(
        &["mesh", "-o", "out", "-q", "--wall-cells", "7:4"],
        s.path(),
        2,
        &["--wall-cells names circle 7"],
    );
    assert!(!s.path().join("out/report.json").exists());
}

// 35. An absurd number of smoothing sweeps: refused before any work (it ran for minutes).
#[test]
fn absurd_smoothing_sweeps() {
    use medial_blocks::exact_mode::MAX_SMOOTH_SWEEPS;
    use medial_blocks::{mesh_periodic, PeriodicDomain};
    let o = Options {
        smooth: MAX_SMOOTH_SWEEPS + 1,
        ..Options::default()
    };
    let e = mesh(&Domain::hexagon_example(), &o).unwrap_err();
    assert!(
        matches!(&e, MeshError::Options(m) if m.contains("--smooth 1001 is more than the limit of 1000")),
        "{e:?}"
    );
    let pd = PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.3, 0.3, 0.1)]).unwrap();
    assert!(matches!(mesh_periodic(&pd, &o), Err(MeshError::Options(_))));
    let s = Scratch::new();
    let started = std::time::Instant::now();
    expect(
        &["mesh", "-o", "out", "-q", "--smooth", "100000"],
        s.path(),
        2,
        &["--smooth 100000 is more than the limit of 1000 sweeps"],
    );
    // Not a timing assertion on the mesher: the refusal must come before any meshing, and a
    // run of 100 000 sweeps took minutes.
    assert!(started.elapsed().as_secs() < 60);
}

// 36. Negative values of numeric flags reach the option checks (clap used to take `-1` for a
// flag and answer with a usage block), and clap's own errors are one line.
#[test]
fn negative_flag_values_and_usage_errors() {
    let s = Scratch::new();
    for (flag, value, needle) in [
        (
            "--first-height-rel",
            "-1",
            "--first-height-rel -1 is out of range: expected a finite number > 0",
        ),
        (
            "--first-height",
            "-0.5",
            "--first-height -0.5 is out of range: expected a finite number > 0",
        ),
        (
            "--growth",
            "-2",
            "--growth -2 is out of range: expected 1 <= G <= 10",
        ),
        (
            "--transition",
            "-1",
            "the background spacing must be finite and positive, got -1",
        ),
        (
            "--collapse-fraction",
            "-1",
            "--collapse-fraction -1 is out of range: expected 0 <= F <= 1",
        ),
        (
            "--refine-ratio",
            "-1",
            "--refine-ratio -1 is out of range: expected a finite R >= 0.5773502691896258",
        ),
        (
            "--cell-size",
            "-1",
            "--cell-size -1 is out of range: expected a finite number > 0",
        ),
        (
            "--smooth",
            "-1",
            "invalid value '-1' for '--smooth <SMOOTH>'",
        ),
        (
            "--block-cells",
            "-4",
            "invalid value '-4' for '--block-cells <N>'",
        ),
        ("--threads", "-1", "invalid value '-1' for '--threads <N>'"),
    ] {
        expect(
            &["mesh", "-o", "out", "-q", flag, value],
            s.path(),
            2,
            &[needle],
        );
    }
    for (args, needle) in [
        (
            &["mesh", "-q", "--block-cells", "4", "--cells", "4"][..],
            "the argument '--block-cells <N>' cannot be used with '--cells <CELLS>'",
        ),
        (
            &["mesh", "-q", "--transition-rect=-1,-1,1,1"][..],
            "the following required arguments were not provided: --transition <TRANSITION>",
        ),
        (
            &["mesh", "-q", "--bogus"][..],
            "unexpected argument '--bogus' found",
        ),
        (&["frob"][..], "unrecognized subcommand 'frob'"),
        (
            &["mesh", "h.csv", "--periodic", "-1,1", "--bounding", "0,0,1"][..],
            "cannot be used with",
        ),
    ] {
        expect(args, s.path(), 2, &[needle, "(see --help)"]);
    }
    // A negative period reaches the domain check.
    s.file("h.csv", "0.5,0.5,0.1\n");
    expect(
        &["mesh", "h.csv", "-o", "out", "-q", "--periodic", "-1,1"],
        s.path(),
        2,
        &["the period Lx is -1, but it must be finite, positive and at most 1.25e99"],
    );
    // Help and version still print in full and succeed.
    let out = Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(["mesh", "--help"])
        .output()
        .expect("run the CLI");
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("Usage: medial-blocks mesh"));
}

// 37. A domain smaller than `Domain::MIN_SCALE` (1e-100): a bounding radius or a period
// below it. Squares of its gaps underflow: a 1e-300 box used to report "holes 0 and 0
// overlap" (the hole against its own image), the hexagon at 1e-160 folded 5623 cells.
#[test]
fn domain_below_the_smallest_scale() {
    use medial_blocks::PeriodicDomain;
    let e = Domain::bounded(Circle::new(0.0, 0.0, 1e-101), vec![]).unwrap_err();
    assert_eq!(
        e,
        DomainError::DomainTooSmall {
            axis: None,
            value: 1e-101,
            min: Domain::MIN_SCALE
        }
    );
    for (size, axis) in [
        ([1e-300, 1e-300], 0),
        ([1.0, 1e-101], 1),
        ([1e-101, 1.0], 0),
    ] {
        let e = PeriodicDomain::new(size, vec![Circle::new(0.0, 0.0, 1e-302)]).unwrap_err();
        assert!(
            matches!(e, DomainError::DomainTooSmall { axis: Some(a), .. } if a == axis),
            "{size:?}: {e:?}"
        );
    }
    let s = Scratch::new();
    s.mesh(
        "p.json",
        "{\"periodic\":{\"size\":[1e-300,1e-300]},\"holes\":[{\"center\":[0,0],\"radius\":1e-301}]}",
        &[],
        2,
        &["the period Lx is 1e-300, below the smallest supported domain size 1e-100"],
    );
    s.mesh(
        "d.json",
        &json_domain(
            "{\"center\": [0, 0], \"radius\": 1e-200}",
            &[&c(0.0, 0.0, 5e-201)],
        ),
        &[],
        2,
        &["the bounding circle's radius is 1e-200, below the smallest supported domain size"],
    );
    // At the end of the range: the hexagon and a periodic box of size 1e-100 mesh as they do
    // at size 1 (the same blocks, no inverted cell, the same angles to rounding).
    let scale = |c: &Circle, k: f64| Circle::new(c.center[0] * k, c.center[1] * k, c.radius * k);
    let hex = Domain::hexagon_example();
    let k = Domain::MIN_SCALE / hex.bounding().radius;
    let tiny = Domain::bounded(
        scale(&hex.bounding(), k),
        hex.holes().iter().map(|h| scale(h, k)).collect(),
    )
    .unwrap();
    let o = Options {
        block_cells: Some(4),
        cells: 4,
        ..Options::default()
    };
    let (a, b) = (mesh(&hex, &o).unwrap(), mesh(&tiny, &o).unwrap());
    let (ra, rb) = (
        medial_blocks::output::report::Report::from_mesh(&a),
        medial_blocks::output::report::Report::from_mesh(&b),
    );
    assert_eq!((rb.blocks, rb.inverted_cells), (ra.blocks, 0));
    assert!((ra.min_angle_deg - rb.min_angle_deg).abs() < 1e-6);
    let box_of = |k: f64| {
        let holes = vec![
            Circle::new(0.3 * k, 0.4 * k, 0.2 * k),
            Circle::new(0.8 * k, 0.1 * k, 0.1 * k),
        ];
        let pd = PeriodicDomain::new([k, k], holes).unwrap();
        medial_blocks::output::report::Report::from_mesh(
            &medial_blocks::mesh_periodic(&pd, &o).unwrap(),
        )
    };
    let (ra, rb) = (box_of(1.0), box_of(Domain::MIN_SCALE));
    assert_eq!((rb.blocks, rb.inverted_cells), (ra.blocks, 0));
    assert!((ra.min_angle_deg - rb.min_angle_deg).abs() < 1e-6);
}

// 38. A periodic hole that does not fit in the box, along x only or y only, or only by the
// tolerance; and two holes that meet only through the periodic wrap.
#[test]
fn periodic_holes_that_do_not_fit_or_meet_across_the_edge() {
    use medial_blocks::PeriodicDomain;
    for (size, r, axis, period) in [
        ([1.0, 3.0], 0.5, 0, 1.0),
        ([3.0, 1.0], 0.5, 1, 1.0),
        ([1.0, 1.0], 0.6, 0, 1.0),
        ([2.0, 1.0], 0.5 - 1e-9, 1, 1.0),
        ([1.25e99, 1e99], 6e98, 1, 1e99),
    ] {
        let e = PeriodicDomain::new(size, vec![Circle::new(0.0, 0.0, r)]).unwrap_err();
        assert!(
            matches!(e, DomainError::HoleWiderThanPeriod { hole: 0, axis: a, period: p, .. }
                if a == axis && p == period),
            "{size:?} r {r}: {e:?}"
        );
    }
    // The largest box meshes (1e100 was accepted, then failed as an internal error).
    let big = PeriodicDomain::MAX_PERIOD;
    let pd = PeriodicDomain::new(
        [big, big],
        vec![
            Circle::new(0.3 * big, 0.4 * big, 0.2 * big),
            Circle::new(0.8 * big, 0.1 * big, 0.1 * big),
        ],
    )
    .unwrap();
    let o = Options {
        cells: 4,
        ..Options::default()
    };
    let m = medial_blocks::mesh_periodic(&pd, &o).unwrap();
    assert_eq!(
        medial_blocks::output::report::Report::from_mesh(&m).inverted_cells,
        0
    );
    assert!(matches!(
        PeriodicDomain::new(
            [big * (1.0 + f64::EPSILON), big],
            vec![Circle::new(0.0, 0.0, 1.0)]
        ),
        Err(DomainError::InvalidPeriod { axis: 0, .. })
    ));
    // Just inside the tolerance: it fits.
    let tol = PeriodicDomain::tolerance_for([2.0, 1.0]);
    assert!(PeriodicDomain::new([2.0, 1.0], vec![Circle::new(0.0, 0.0, 0.5 - tol)]).is_ok());
    // Two holes 0.3 wide whose centres are 0.6 apart only through the right edge (x = 0 and
    // 2.4 in a box 3 wide): hole 1 moved by -Lx meets hole 0.
    let e = PeriodicDomain::new(
        [3.0, 1.0],
        vec![Circle::new(0.0, 0.0, 0.3), Circle::new(2.4, 0.0, 0.3)],
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::HolesOverlap {
                first: 0,
                second: 1,
                shift: [-1, 0],
                ..
            }
        ),
        "{e:?}"
    );
    // Through the corner: hole 0 moved by (+Lx, +Ly) meets hole 1.
    let e = PeriodicDomain::new(
        [1.0, 1.0],
        vec![Circle::new(0.95, 0.95, 0.1), Circle::new(0.02, 0.02, 0.1)],
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::HolesOverlap {
                first: 0,
                second: 1,
                shift: [1, 1],
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e
        .to_string()
        .contains("across the periodic boundary (hole 1 moved by 1 Lx and 1 Ly)"));
    let s = Scratch::new();
    let p = |size: &str, holes: &str| {
        format!("{{\"periodic\":{{\"size\":{size}}},\"holes\":[{holes}]}}")
    };
    s.mesh(
        "x.json",
        &p("[1, 3]", &c(0.0, 0.0, 0.5)),
        &[],
        2,
        &["hole 0 has diameter 1, which does not fit in the period Lx = 1"],
    );
    s.mesh(
        "y.json",
        &p("[3, 1]", &c(0.0, 0.0, 0.5)),
        &[],
        2,
        &[
            "does not fit in the period Ly = 1",
            "its own periodic image",
        ],
    );
    s.mesh(
        "w.json",
        &p(
            "[3, 1]",
            &format!("{}, {}", c(0.0, 0.0, 0.3), c(2.4, 0.0, 0.3)),
        ),
        &[],
        2,
        &["holes 0 and 1 overlap or touch across the periodic boundary (hole 1 moved by -1 Lx)"],
    );
    s.mesh(
        "huge.json",
        &p("[1e300, 1e300]", &c(0.0, 0.0, 1.0)),
        &[],
        2,
        &["the period Lx is 1e300, but it must be finite, positive and at most 1.25e99"],
    );
}

// 39. Every number in a message is readable: 1e300 prints as `1e300`, not 301 digits, and
// 0.5 as `0.5` (shortest round trip, exponent form only when large or tiny).
#[test]
fn numbers_in_messages_are_readable() {
    let s = Scratch::new();
    let cases = [
        (
            json_domain("{\"center\": [0, 0], \"radius\": 1e300}", &[]),
            "the bounding circle has radius = 1e300, beyond the supported magnitude 1e100",
        ),
        (
            json_domain(B10, &[&c(0.0, 0.0, 1.0), &c(1.5, 0.0, 1.0)]),
            "the gap between them is -0.5, it must exceed 1e-8",
        ),
        (
            json_domain(B10, &[&c(20.0, 0.0, 1.0)]),
            "its gap to the bounding circle is -11, it must exceed 1e-8",
        ),
        (
            json_domain(B10, &[&c(0.0, 0.0, -1e300)]),
            "hole 0 has radius -1e300, but a radius must be positive",
        ),
    ];
    for (text, needle) in &cases {
        s.mesh("d.json", text, &[], 2, &[needle]);
    }
    // No message of a domain with extreme numbers has a run of more than 17 digits.
    let longest_digit_run = |e: &str| {
        e.split(|ch: char| !ch.is_ascii_digit())
            .map(str::len)
            .max()
            .unwrap_or(0)
    };
    for text in [
        json_domain("{\"center\": [1e99, -1e99], \"radius\": 1e-300}", &[]),
        "{\"periodic\":{\"size\":[1e300,1e-300]},\"holes\":[]}".to_string(),
        json_domain(B10, &[&c(0.0, 0.0, 1e-300)]),
    ] {
        let e = medial_blocks::AnyDomain::from_json_str(&text)
            .unwrap_err()
            .to_string();
        assert!(longest_digit_run(&e) <= 17, "{e}");
    }
    // The Cartesian transition's messages too (a spacing of 1e-300 printed 300 zeros).
    use medial_blocks::transition::{mesh_with_transition, mesh_with_transition_rect, Rect};
    let hex = Domain::hexagon_example();
    let o = Options::default();
    let b = hex.bounding();
    let transition_cases = [
        (
            mesh_with_transition(&hex, &o, 1e-300).map(|_| ()),
            "a spacing of 1e-300 needs too many background intervals",
        ),
        (
            Rect::from_bounds([0.0, 0.0, 1.0, 1.0], 0.25, b.center, b.radius).map(|_| ()),
            "the rectangle [0, 1] x [0, 1] must enclose the bounding circle (centre (0, 0)",
        ),
        (
            Rect::from_bounds([1e300, 0.0, -1e300, 1.0], 0.25, b.center, b.radius).map(|_| ()),
            "with XMIN < XMAX and YMIN < YMAX, got 1e300,0,-1e300,1",
        ),
        (
            Rect::from_bounds([-5.0, -5.0, 5.0, 5.0], 2.5e-7, b.center, b.radius)
                .and_then(|r| mesh_with_transition_rect(&hex, &o, r))
                .map(|_| ()),
            "a spacing of 2.5e-7 needs too many background intervals",
        ),
    ];
    for (result, needle) in transition_cases {
        let e = result.expect_err(needle).to_string();
        assert!(e.contains(needle), "{e}");
        assert!(longest_digit_run(&e) <= 17, "{e}");
    }
}

// 40. Option values outside their ranges (`medial_blocks::ranges`): refused with the flag, the
// value and the range, in both modes and for periodic domains; the ends of each range mesh.
#[test]
fn option_values_outside_their_ranges() {
    use medial_blocks::exact_mode::{Clustering, FirstCell};
    use medial_blocks::ranges::{MAX_COLLAPSE_FRACTION, MAX_GROWTH, MIN_REFINE_RATIO};
    use medial_blocks::{mesh_periodic, Mode, PeriodicDomain};
    let hex = Domain::hexagon_example();
    let pd = PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.3, 0.3, 0.1)]).unwrap();
    let base = Options {
        cells: 3,
        ..Options::default()
    };
    let clustering = |growth, first| Clustering { first, growth };
    let bad: [(Options, &str); 8] = [
        (
            Options {
                refine_ratio: Some(0.5),
                ..base.clone()
            },
            "--refine-ratio 0.5 is out of range: expected a finite R >= 0.5773502691896258",
        ),
        (
            Options {
                refine_ratio: Some(f64::INFINITY),
                ..base.clone()
            },
            "--refine-ratio inf is out of range",
        ),
        (
            Options {
                collapse_fraction: 1e9,
                ..base.clone()
            },
            "--collapse-fraction 1e9 is out of range: expected 0 <= F <= 1",
        ),
        (
            Options {
                clustering: clustering(1e308, None),
                ..base.clone()
            },
            "--growth 1e308 is out of range: expected 1 <= G <= 10",
        ),
        (
            Options {
                clustering: clustering(1.2, Some(FirstCell::Absolute(f64::NAN))),
                ..base.clone()
            },
            "--first-height NaN is out of range: expected a finite number > 0",
        ),
        (
            Options {
                circle_clustering: vec![(0, clustering(0.9, Some(FirstCell::Relative(0.1))))],
                ..base.clone()
            },
            "--circle-clustering of circle 0: GROWTH 0.9 is out of range",
        ),
        (
            Options {
                cell_size: Some(0.0),
                ..base.clone()
            },
            "--cell-size 0 is out of range: expected a finite number > 0",
        ),
        (
            Options {
                mode: Mode::Paper,
                clustering: clustering(0.5, None),
                ..base.clone()
            },
            "--growth 0.5 is out of range",
        ),
    ];
    for (o, needle) in &bad {
        for e in [
            mesh(&hex, o).unwrap_err(),
            mesh_periodic(&pd, o).unwrap_err(),
        ] {
            assert!(
                matches!(&e, MeshError::Options(m) if m.contains(needle)),
                "{needle}: {e:?}"
            );
        }
    }
    // The ends of each range mesh (the library, both domain kinds).
    let ends = [
        Options {
            refine_ratio: Some(MIN_REFINE_RATIO),
            ..base.clone()
        },
        Options {
            refine_ratio: Some(f64::MAX),
            collapse_fraction: MAX_COLLAPSE_FRACTION,
            ..base.clone()
        },
        Options {
            collapse_fraction: 0.0,
            clustering: clustering(MAX_GROWTH, Some(FirstCell::Relative(1e-3))),
            ..base.clone()
        },
        Options {
            clustering: clustering(1.0, Some(FirstCell::Absolute(1e300))),
            cell_size: Some(f64::MAX),
            ..base.clone()
        },
    ];
    for o in &ends {
        assert!(mesh(&hex, o).is_ok(), "{o:?}");
        assert!(mesh_periodic(&pd, o).is_ok(), "{o:?}");
    }
    // The CLI: one line naming the flag, the value and the range, exit 2; the ends exit 0.
    let s = Scratch::new();
    for (flag, value, needle) in [
        (
            "--refine-ratio",
            "0.5",
            "--refine-ratio 0.5 is out of range",
        ),
        (
            "--refine-ratio",
            "0.5773502691896",
            "expected a finite R >= 0.5773502691896258",
        ),
        (
            "--growth",
            "1e308",
            "--growth 1e308 is out of range: expected 1 <= G <= 10",
        ),
        (
            "--growth",
            "10.000001",
            "--growth 10.000001 is out of range",
        ),
        (
            "--collapse-fraction",
            "1e9",
            "--collapse-fraction 1e9 is out of range",
        ),
        ("--collapse-fraction", "1.0000001", "expected 0 <= F <= 1"),
        (
            "--first-height-rel",
            "0",
            "--first-height-rel 0 is out of range",
        ),
        ("--cell-size", "inf", "--cell-size inf is out of range"),
        (
            "--circle-clustering",
            "2:0.01r:11",
            "circle 2: GROWTH 11 is out of range",
        ),
    ] {
        expect(
            &["mesh", "-o", "out", "-q", flag, value],
            s.path(),
            2,
            &[needle],
        );
    }
    for threads in ["0", "1025"] {
        expect(
            &["--threads", threads, "mesh", "-o", "out", "-q"],
            s.path(),
            2,
            &[&format!(
                "--threads {threads} is out of range: expected 1 <= N <= 1024"
            )],
        );
    }
    for args in [
        &["--refine-ratio", "0.5773502691896258", "--cells", "2"][..],
        &[
            "--growth",
            "10",
            "--first-height-rel",
            "0.001",
            "--cells",
            "2",
        ][..],
        &["--growth", "1", "--first-height", "1e300", "--cells", "2"][..],
        &["--collapse-fraction", "1", "--cells", "2"][..],
        &[
            "--collapse-fraction",
            "0",
            "--refine-ratio",
            "1e308",
            "--cells",
            "2",
        ][..],
        &["--cell-size", "1e308"][..],
        &["--threads", "1", "--cells", "2"][..],
    ] {
        let mut a = vec!["mesh", "-o", "out", "-q", "--format", "json"];
        a.extend_from_slice(args);
        expect(&a, s.path(), 0, &[]);
    }
    // --help states the ranges.
    let out = Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(["mesh", "--help"])
        .output()
        .expect("run the CLI");
    let help = String::from_utf8_lossy(&out.stdout);
    for range in [
        "1 to 10",
        "0 to 1",
        "0.5773502691896258",
        "1 to 100000",
        "0 to 1000",
        "finite, > 0",
    ] {
        assert!(help.contains(range), "--help lacks {range:?}");
    }
}

// 41. Text-file oddities: a byte order mark (CSV, JSON, JSON Lines) is skipped; a one-row CSV
// whose row does not parse (`0x1`, tabs, quotes) is refused with its line instead of being
// taken for a header (the file meshed the empty disk); invisible characters in a bad field
// are shown escaped; a periodic JSON with too many holes is refused by count.
#[test]
fn text_file_oddities() {
    let one = vec![Circle::new(1.0, 0.0, 0.5)];
    for text in [
        "\u{feff}1,0,0.5\n",
        "\u{feff}x,y,r\r\n1,0,0.5\r\n",
        "x,y,r\n+1,0,0.5",
        "\"x\",\"y\",\"r\"\n1,0,0.5\n",
    ] {
        assert_eq!(parse_holes_csv(text).unwrap(), one, "{text:?}");
    }
    for (text, field) in [
        ("0x1,0,0.5\n", "0x1"),
        ("\"1\",\"0\",\"0.5\"\n", "\"1\""),
        ("1,0,0.5\u{0}\n", "0.5\\u{0}"),
    ] {
        assert_eq!(
            parse_holes_csv(text),
            Err(CsvError::NotANumber {
                line: 1,
                field: field.into()
            }),
            "{text:?}"
        );
    }
    assert!(matches!(
        parse_holes_csv("1\t0\t0.5\n"),
        Err(CsvError::WrongColumnCount {
            line: 1,
            found: 1,
            ..
        })
    ));
    // Subnormal coordinates are numbers like any other.
    assert_eq!(
        parse_holes_csv("1e-310,0,0.5\n").unwrap(),
        vec![Circle::new(1e-310, 0.0, 0.5)]
    );
    let json = format!("\u{feff}{}", json_domain(B10, &[&c(1.0, 0.0, 0.5)]));
    assert_eq!(Domain::from_json_str(&json).unwrap().holes(), &one[..]);
    assert!(medial_blocks::AnyDomain::from_json_str(&json).is_ok());
    let periodic =
        "\u{feff}{\"periodic\":{\"size\":[3,3]},\"holes\":[{\"center\":[1,0],\"radius\":0.5}]}";
    assert!(medial_blocks::PeriodicDomain::from_json_str(periodic).is_ok());
    let s = Scratch::new();
    s.mesh("b.json", &json, &[], 0, &[]);
    Scratch::new().mesh(
        "b.csv",
        "\u{feff}1,0,0.5\n",
        &["--bounding", "0,0,3"],
        0,
        &[],
    );
    let s = Scratch::new();
    s.mesh(
        "h.csv",
        "0x1,0,0.5\n",
        &["--bounding", "0,0,3"],
        2,
        &["h.csv: line 1: '0x1' is not a number"],
    );
    s.mesh(
        "t.csv",
        "1\t0\t0.5\n",
        &["--bounding", "0,0,3"],
        2,
        &["line 1: expected 3 comma-separated numbers `x,y,r`, found 1"],
    );
    // The hole limit is counted, not stored, for periodic JSON too.
    let mut text = String::from("{\"periodic\":{\"size\":[1,1]},\"holes\":[");
    let hole = "{\"center\":[0.5,0.5],\"radius\":0.1}";
    for k in 0..=Domain::MAX_HOLES {
        if k > 0 {
            text.push(',');
        }
        text.push_str(hole);
    }
    text.push_str("]}");
    assert_eq!(
        medial_blocks::PeriodicDomain::from_json_str(&text),
        Err(DomainError::TooManyHoles {
            count: Domain::MAX_HOLES + 1,
            max: Domain::MAX_HOLES
        })
    );
}

// 42. A document that is not a JSON object (serde read `[1, 2]` as a struct and answered that
// the domain had both "periodic" and "bounding"), and a bad `mesh-sequence` flag: refused once
// before any frame, not once per frame with an output directory of failures.
#[test]
fn non_object_json_and_sequence_flags() {
    for (text, found) in [
        ("[1, 2]", "not an array"),
        ("\"x\"", "not a string"),
        ("1e5", "not a number or literal"),
        ("\u{feff} [", "not an array"),
    ] {
        let e = medial_blocks::AnyDomain::from_json_str(text).unwrap_err();
        assert!(
            matches!(&e, DomainError::Json(m) if m.starts_with("a domain is a JSON object") && m.ends_with(found)),
            "{text:?}: {e:?}"
        );
    }
    let s = Scratch::new();
    s.mesh(
        "a.json",
        "[1, 2]",
        &[],
        2,
        &["a domain is a JSON object", "not an array"],
    );
    let frame = json_domain(B10, &[&c(0.0, 0.0, 1.0), &c(3.0, 0.0, 1.0)]);
    s.file("f.jsonl", format!("{frame}\n[1, 2]\n{frame}\n"));
    let (code, err) = cli(
        &[
            "mesh-sequence",
            "f.jsonl",
            "-o",
            "seq",
            "-q",
            "--cells",
            "2",
        ],
        s.path(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("frame 1: error: line 2: invalid domain JSON: a domain is a JSON object"),
        "{err}"
    );
    assert!(err.contains("1 of 3 frames failed"), "{err}");
    for (cells, needle) in [
        ("0", "--cells must be at least 1"),
        (
            "100001",
            "100001 cells along a block side is more than the limit of 100000",
        ),
    ] {
        expect(
            &[
                "mesh-sequence",
                "f.jsonl",
                "-o",
                "bad",
                "-q",
                "--cells",
                cells,
            ],
            s.path(),
            2,
            &[needle],
        );
        assert!(
            !s.path().join("bad").exists(),
            "--cells {cells} wrote output"
        );
    }
}

/// Row 43: a periodic box whose empty regions would need more copies of the box than the
/// sample limit allows (one small hole in a box a million times longer than high) is refused
/// with `MeshError::Tiling`, naming the copies and the limit; elongated boxes within the
/// limits are meshed (`tests/periodic_elongated.rs`).
#[test]
fn periodic_box_too_elongated_for_the_limits() {
    let pd =
        medial_blocks::periodic::PeriodicDomain::new([1e6, 1.0], vec![Circle::new(0.3, 0.25, 0.2)])
            .unwrap();
    let e = medial_blocks::periodic::mesh_periodic(&pd, &Options::default()).unwrap_err();
    assert!(matches!(e, MeshError::Tiling(_)), "{e:?}");
    let s = Scratch::new();
    s.mesh(
        "long.json",
        r#"{"periodic": {"size": [1e6, 1]}, "holes": [{"center": [0.3, 0.25], "radius": 0.2}]}"#,
        &[],
        2,
        &[
            "periodic tiling: ",
            "copies of the box are needed",
            "more than the limit",
        ],
    );
}
