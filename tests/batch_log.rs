//! What a run tells in a batch job (stderr not a terminal): one line per
//! finished packing, nothing with `--quiet`, and a `results.csv` that holds
//! the packings finished so far when the run is killed.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use crate::common;
use common::{jamkit, quickstart};

/// Without a terminal, each finished packing writes a line with its id,
/// φ, z, FIRE steps and the run's ETA; the count matches the samples, and
/// a rerun says the packings were read back.
#[test]
fn a_batch_run_writes_one_line_per_packing() {
    let file = quickstart();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let args = [
        "run",
        &file,
        "--out",
        out.to_str().unwrap(),
        "--set",
        "particles=32",
        "--set",
        "samples=3",
        "--jobs",
        "1",
    ];
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with('[')).collect();
    assert_eq!(lines.len(), 3, "{err}");
    for (k, line) in lines.iter().enumerate() {
        let id = format!("sphere_d2_N32_s{}", k + 1);
        assert!(line.starts_with(&format!("[{}/3] ", k + 1)), "{line}");
        assert!(line.contains(&id), "{line}");
        assert!(
            line.contains("φ 0.8") && line.contains("FIRE steps"),
            "{line}"
        );
        assert!(line.contains("ETA"), "{line}");
    }
    assert!(lines[2].ends_with("ETA done"), "{}", lines[2]);
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        err.matches("read back from an earlier run").count(),
        3,
        "{err}"
    );
}

#[test]
fn quiet_writes_nothing_on_stderr() {
    let file = quickstart();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let (code, text, err) = jamkit(&[
        "run",
        &file,
        "--out",
        out.to_str().unwrap(),
        "--set",
        "particles=32",
        "--set",
        "samples=2",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty(), "{err}");
    assert!(text.contains("2 packings"), "{text}");
}

/// Killed after its first packing, a run leaves a `results.csv` with that
/// packing's row (before, the table appeared only at the end).
#[test]
fn a_killed_run_leaves_the_rows_it_finished() {
    let file = quickstart();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let mut child = Command::new(env!("CARGO_BIN_EXE_jamkit"))
        .args([
            "run",
            &file,
            "--out",
            out.to_str().unwrap(),
            "--set",
            "particles=512",
            "--set",
            "samples=20",
            "--jobs",
            "1",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = child.stderr.take().unwrap();
    let mut first = String::new();
    BufReader::new(err).read_line(&mut first).unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(first.starts_with("[1/20] sphere_d2_N512_s1"), "{first}");
    let table = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    // The header, the first packing, and at most the ones that finished
    // between the line and the kill; never all twenty.
    assert!(rows.len() >= 2 && rows.len() < 21, "{table}");
    assert!(rows[0].starts_with("id,"), "{table}");
    assert!(rows[1].starts_with("sphere_d2_N512_s1,"), "{table}");
    assert!(!out.join("summary.csv").exists());
}
