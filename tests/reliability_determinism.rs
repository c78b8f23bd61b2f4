//! The same input gives byte-identical files on every run (and with any thread count, when the
//! CLI has `--threads`): the CLI runs twice on a few layouts with `--format all` and every file
//! is compared byte for byte.
//!
//! To add a variant (a new flag that must not change the output), add it to `variants()`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn cli(args: &[&str], cwd: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run the CLI")
}

/// Every file under `dir` (relative path -> bytes).
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for e in std::fs::read_dir(dir.join(&rel))
            .expect("read output")
            .flatten()
        {
            let p = rel.join(e.file_name());
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                stack.push(p);
            } else {
                out.insert(p.clone(), std::fs::read(dir.join(&p)).expect("read file"));
            }
        }
    }
    out
}

/// Extra arguments that must not change any output byte, compared against the first.
fn variants(cwd: &Path) -> Vec<Vec<&'static str>> {
    let mut v = vec![vec![], vec![]];
    let help = cli(&["mesh", "--help"], cwd);
    if String::from_utf8_lossy(&help.stdout).contains("--threads") {
        v.push(vec!["--threads", "1"]);
        v.push(vec!["--threads", "2"]);
    }
    v
}

/// One input: an optional (file name, content) (`None`: the built-in example) and extra
/// arguments.
type Input = (Option<(&'static str, String)>, Vec<&'static str>);

/// The inputs.
fn inputs() -> Vec<Input> {
    let ngon: Vec<String> = (0..6)
        .map(|k| {
            let a = std::f64::consts::PI * f64::from(k) / 3.0;
            format!(
                "{{\"center\": [{:?}, {:?}], \"radius\": 0.4}}",
                a.cos(),
                a.sin()
            )
        })
        .collect();
    let ngon = format!(
        "{{\"bounding\": {{\"center\": [0, 0], \"radius\": 2}}, \"holes\": [{}]}}",
        ngon.join(", ")
    );
    let mut csv = String::from("x,y,r\n");
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut holes: Vec<(f64, f64, f64)> = Vec::new();
    while holes.len() < 25 {
        let (x, y, r) = (rnd() * 16.0 - 8.0, rnd() * 16.0 - 8.0, 0.2 + rnd() * 0.6);
        let inside = 10.0 - (x * x + y * y).sqrt() - r > 0.1;
        if inside
            && holes
                .iter()
                .all(|&(a, b, q)| ((a - x).powi(2) + (b - y).powi(2)).sqrt() - q - r > 0.1)
        {
            holes.push((x, y, r));
            csv.push_str(&format!("{x:?},{y:?},{r:?}\n"));
        }
    }
    vec![
        (None, vec!["--cells", "8"]),
        (Some(("ngon.json", ngon)), vec!["--cells", "6"]),
        (
            Some(("random.csv", csv)),
            vec!["--bounding", "0,0,10", "--cells", "4"],
        ),
        (
            Some((
                "disk.json",
                "{\"bounding\": {\"center\": [1, 2], \"radius\": 3}, \"holes\": []}".into(),
            )),
            vec![],
        ),
    ]
}

#[test]
fn same_input_same_bytes() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let variants = variants(cwd);
    for (k, (input, extra)) in inputs().into_iter().enumerate() {
        let mut base = vec!["mesh".to_string()];
        if let Some((name, content)) = &input {
            std::fs::write(cwd.join(name), content).unwrap();
            base.push(name.to_string());
        }
        base.extend(["--format", "all", "-q"].map(String::from));
        base.extend(extra.iter().map(|s| s.to_string()));
        let mut first: Option<BTreeMap<PathBuf, Vec<u8>>> = None;
        for (v, var) in variants.iter().enumerate() {
            let dir = format!("out_{k}_{v}");
            let mut args: Vec<&str> = base.iter().map(String::as_str).collect();
            args.extend(["-o", dir.as_str()]);
            args.extend(var.iter().copied());
            let o = cli(&args, cwd);
            assert!(
                o.status.success(),
                "{args:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let got = files(&cwd.join(&dir));
            assert!(got.len() >= 10, "{args:?}: only {} files", got.len());
            match &first {
                None => first = Some(got),
                Some(f) => {
                    assert_eq!(
                        f.keys().collect::<Vec<_>>(),
                        got.keys().collect::<Vec<_>>(),
                        "{args:?}: different file sets"
                    );
                    for (p, bytes) in f {
                        assert!(
                            got[p] == *bytes,
                            "{args:?}: {} differs from the first run",
                            p.display()
                        );
                    }
                }
            }
        }
    }
}
