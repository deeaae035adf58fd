//! Runs sharing an output directory: a packing whose lock another process
//! holds is left to it (and no tables are written until a later run gathers
//! it), two identical runs at once make every packing exactly once, and
//! the gathered tables are those of one plain run (timings aside).

use std::process::{Command, Stdio};

use crate::common;
use common::{jamkit, quickstart, results_without_timing};

fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .unwrap()
        .trim()
        .to_string()
}

#[test]
fn a_held_lock_leaves_its_packing_to_the_holder() {
    let file = quickstart();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let small = ["--set", "particles=32", "--set", "samples=3", "--jobs", "1"];
    let args = [&["run", &file, "--out", out.to_str().unwrap()][..], &small].concat();
    // A live holder of sample 2's lock: this test process.
    std::fs::create_dir_all(out.join("packings")).unwrap();
    let lock = out.join("packings/sphere_d2_N32_s2.lock");
    std::fs::write(&lock, format!("host={} pid={}", host(), std::process::id())).unwrap();
    let (code, text, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("sphere_d2_N32_s2: in flight elsewhere"),
        "{err}"
    );
    assert!(
        text.contains("1 more are being made by other processes"),
        "{text}"
    );
    assert!(!out.join("packings/sphere_d2_N32_s2.json").exists());
    assert!(
        !out.join("summary.csv").exists(),
        "no tables while a packing is missing"
    );
    assert!(lock.exists(), "another process's lock is not removed");
    // The holder is gone: a rerun makes it and gathers everything.
    std::fs::remove_file(&lock).unwrap();
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        err.matches("read back from an earlier run").count(),
        2,
        "{err}"
    );
    assert!(out.join("summary.csv").exists());
    let single = tmp.path().join("single");
    let (code, _, err) = jamkit(
        &[
            &["run", &file, "--out", single.to_str().unwrap()][..],
            &small,
        ]
        .concat(),
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        results_without_timing(&out),
        results_without_timing(&single)
    );
    let left: Vec<_> = std::fs::read_dir(out.join("packings"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "lock"))
        .collect();
    assert!(left.is_empty(), "locks left behind: {left:?}");
}

#[test]
fn two_identical_runs_at_once_make_each_packing_once() {
    let file = quickstart();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("shared");
    let samples = 8;
    let args: Vec<String> = [
        "run",
        &file,
        "--out",
        out.to_str().unwrap(),
        "--set",
        "particles=128",
        "--set",
        &format!("samples={samples}"),
        "--jobs",
        "1",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let spawn = || {
        Command::new(env!("CARGO_BIN_EXE_jamkit"))
            .args(&args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn(), spawn());
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert!(a.status.success() && b.status.success());
    let logs = [a.stderr, b.stderr].map(|e| String::from_utf8_lossy(&e).to_string());
    let made: usize = logs.iter().map(|l| l.matches("FIRE steps").count()).sum();
    assert_eq!(made, samples, "every packing made once: {logs:?}");
    // A third run gathers the tables; they are one plain run's.
    let (code, _, err) = jamkit(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    assert_eq!(err.matches("read back").count(), samples, "{err}");
    let single = tmp.path().join("single");
    let mut one = args.clone();
    one[3] = single.to_str().unwrap().to_string();
    let (code, _, err) = jamkit(&one.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        results_without_timing(&out),
        results_without_timing(&single)
    );
}
