//! Good and bad experiment files (`tests/inputs/{good,bad}/*.ron`).
//!
//! Every good file validates and expands to a grid. Every bad file starts
//! with a line `// error: <text>`, and loading it must fail with a message
//! that contains `<text>`: the message names the field, the value and what
//! is allowed.

use jamkit_experiment::{Experiment, ExperimentError, Plan};
use std::path::{Path, PathBuf};

fn files(dir: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/inputs")
        .join(dir);
    let mut out: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    out.sort();
    assert!(!out.is_empty(), "no files in {}", dir.display());
    out
}

fn load(path: &Path) -> Result<(Experiment, usize), ExperimentError> {
    let e = Experiment::from_file(path)?;
    e.validate()?;
    let points = Plan::new(&e)?.points.len();
    Ok((e, points))
}

#[test]
fn good_files_validate() {
    for path in files("good") {
        let (_, points) = load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(points >= 1);
    }
}

#[test]
fn bad_files_fail_with_their_message() {
    for path in files("bad") {
        let text = std::fs::read_to_string(&path).unwrap();
        let expected = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("// error: "))
            .unwrap_or_else(|| panic!("{}: first line must be `// error: …`", path.display()));
        match load(&path) {
            Ok(_) => panic!(
                "{}: accepted, expected error containing {expected:?}",
                path.display()
            ),
            Err(e) => assert!(
                e.to_string().contains(expected),
                "{}:\n  got:      {e}\n  expected: {expected}",
                path.display()
            ),
        }
    }
}

/// The shipped experiments are valid too.
#[test]
fn shipped_experiments_validate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut stack = vec![root];
    let mut count = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "ron") {
                load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                count += 1;
            }
        }
    }
    assert!(count >= 3);
}
