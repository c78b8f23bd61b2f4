//! `output::replace_file` (issue 8): the name always points at a complete file, old or new,
//! whether it is exchanged with the old file (Linux, an existing regular file) or renamed;
//! what is not a regular file is treated as `rename` treats it; a second run of
//! `write_files` into the same directory gives the same files and leaves nothing behind.

use crate::common;

use medial_blocks::output::{replace_file, write_atomic, write_files, Format};
use std::path::Path;

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn replaces_an_existing_file_and_removes_the_old_one() {
    let dir = tempfile::tempdir().unwrap();
    let (new, target) = (dir.path().join("new"), dir.path().join("target"));
    std::fs::write(&target, b"old contents").unwrap();
    std::fs::write(&new, b"new").unwrap();
    replace_file(&new, &target).unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"new");
    assert_eq!(names(dir.path()), ["target"], "the old file is gone");
}

#[test]
fn renames_onto_a_missing_name() {
    let dir = tempfile::tempdir().unwrap();
    let (new, target) = (dir.path().join("new"), dir.path().join("target"));
    std::fs::write(&new, b"new").unwrap();
    replace_file(&new, &target).unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"new");
    assert_eq!(names(dir.path()), ["target"]);
}

/// A directory under the target name is not swapped away (and then deleted with the
/// temporary name): the call fails as `rename` does and both stay as they were.
#[test]
fn a_directory_in_the_way_is_an_error_and_is_kept() {
    let dir = tempfile::tempdir().unwrap();
    let (new, target) = (dir.path().join("new"), dir.path().join("target"));
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("inside"), b"keep me").unwrap();
    std::fs::write(&new, b"new").unwrap();
    assert!(replace_file(&new, &target).is_err());
    assert_eq!(std::fs::read(target.join("inside")).unwrap(), b"keep me");
    assert_eq!(std::fs::read(&new).unwrap(), b"new");
}

/// A symbolic link under the target name is replaced by the file, as `rename` does; the file
/// it pointed to is not touched.
#[cfg(unix)]
#[test]
fn a_symlink_is_replaced_not_followed() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("pointed"), b"pointed").unwrap();
    std::os::unix::fs::symlink(p.join("pointed"), p.join("target")).unwrap();
    std::fs::write(p.join("new"), b"new").unwrap();
    replace_file(&p.join("new"), &p.join("target")).unwrap();
    assert!(!std::fs::symlink_metadata(p.join("target"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read(p.join("target")).unwrap(), b"new");
    assert_eq!(std::fs::read(p.join("pointed")).unwrap(), b"pointed");
    assert_eq!(names(p), ["pointed", "target"]);
}

/// The old file keeps its other names (a hard link made by the user): only the target name
/// moves to the new file.
#[cfg(unix)]
#[test]
fn other_hard_links_keep_the_old_contents() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("target"), b"old").unwrap();
    std::fs::hard_link(p.join("target"), p.join("kept")).unwrap();
    write_atomic(&p.join("target"), |w| {
        use std::io::Write;
        w.write_all(b"new")
    })
    .unwrap();
    assert_eq!(std::fs::read(p.join("target")).unwrap(), b"new");
    assert_eq!(std::fs::read(p.join("kept")).unwrap(), b"old");
    assert_eq!(names(p), ["kept", "target"], "no temporary file left");
}

/// While one thread replaces a file again and again, another reads it: every read sees one
/// whole version, never a missing or partial file.
#[test]
fn readers_always_see_a_whole_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("target");
    let version = |k: u32| format!("version {k} ").repeat(2000).into_bytes();
    std::fs::write(&target, version(0)).unwrap();
    let stop = std::sync::atomic::AtomicBool::new(false);
    // Reads so far: the writer starts after the first one (on a loaded machine the reader
    // thread could otherwise start only after the last replacement, and read nothing).
    let started = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        let reader = s.spawn(|| {
            let mut reads = 0;
            while reads == 0 || !stop.load(std::sync::atomic::Ordering::Relaxed) {
                let got = std::fs::read(&target).expect("the name always exists");
                let k: u32 = std::str::from_utf8(&got[8..])
                    .unwrap()
                    .split(' ')
                    .next()
                    .unwrap()
                    .parse()
                    .unwrap();
                assert_eq!(got, version(k), "a whole version");
                reads += 1;
                started.store(reads, std::sync::atomic::Ordering::Relaxed);
            }
            reads
        });
        while started.load(std::sync::atomic::Ordering::Relaxed) == 0 && !reader.is_finished() {
            std::thread::yield_now();
        }
        for k in 1..=300 {
            write_atomic(&target, |w| {
                use std::io::Write;
                w.write_all(&version(k))
            })
            .unwrap();
        }
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        assert!(reader.join().unwrap() > 0);
    });
    assert_eq!(std::fs::read(&target).unwrap(), version(300));
    assert_eq!(names(dir.path()), ["target"]);
}

/// Two runs of every writer into the same directory: the second replaces every file with
/// the same bytes and leaves no temporary file or staging directory.
#[test]
fn writing_twice_into_one_directory_gives_the_same_files() {
    let domain = medial_blocks::layouts::hexagon();
    let mesh = medial_blocks::mesh(&domain, &medial_blocks::Options::default()).unwrap();
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    write_files(&mesh, a.path(), Format::ALL).unwrap();
    write_files(&mesh, b.path(), Format::ALL).unwrap();
    write_files(&mesh, b.path(), Format::ALL).unwrap();
    let (ta, tb) = (common::tree(a.path()), common::tree(b.path()));
    assert!(ta.len() > 10);
    assert_eq!(
        ta.len(),
        tb.len(),
        "no file more or less after a second run"
    );
    for (x, y) in ta.iter().zip(&tb) {
        assert_eq!(x.0, y.0);
        assert!(x.1 == y.1, "{} differs after a second run", x.0);
        assert!(!x.0.contains(".tmp") && !x.0.contains("staging"), "{}", x.0);
    }
}
