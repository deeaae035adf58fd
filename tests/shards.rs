//! `jamkit run --shard I/K`: parts of an experiment's samples run as separate
//! processes into one directory, then gathered by a run without `--shard`,
//! give the packings and tables of one plain run, bit for bit (timings
//! aside), for any K.

use std::path::Path;

use crate::common;
use common::{jamkit, results_without_timing};

#[test]
fn any_number_of_shards_gathers_to_one_run() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron");
    let file = file.to_str().unwrap();
    let small = ["--set", "particles=32", "--set", "samples=5", "--jobs", "1"];
    let tmp = tempfile::tempdir().unwrap();
    let run = |out: &Path, extra: &[&str]| {
        let args = [
            &["run", file, "--out", out.to_str().unwrap()][..],
            &small,
            extra,
        ]
        .concat();
        let (code, text, err) = jamkit(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
        text
    };
    let single = tmp.path().join("single");
    run(&single, &[]);
    let reference = results_without_timing(&single);
    assert_eq!(reference.len(), 6, "header and five packings");
    for k in 1..=4usize {
        let dir = tmp.path().join(format!("k{k}"));
        for i in 1..=k {
            let text = run(&dir, &["--shard", &format!("{i}/{k}")]);
            assert!(text.contains(&format!("shard {i}/{k}")), "{text}");
            // A part writes packings, never a table of its own packings only.
            assert!(!dir.join("results.csv").exists(), "K = {k}, part {i}");
        }
        assert_eq!(
            std::fs::read_dir(dir.join("packings")).unwrap().count(),
            5,
            "K = {k}: every sample once"
        );
        let text = run(&dir, &[]);
        assert!(text.contains("5 packings (5 reused"), "K = {k}: {text}");
        assert_eq!(results_without_timing(&dir), reference, "K = {k}");
    }
}

/// Four parts started at once into one directory (as the tasks of a job
/// array on a shared file system) write disjoint packing files and the same
/// `experiment.ron`, each atomically; the gathering run equals one run.
#[test]
fn parts_running_at_once_share_a_directory() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron");
    let tmp = tempfile::tempdir().unwrap();
    let args = |out: &Path| {
        vec![
            "run".to_string(),
            file.to_str().unwrap().to_string(),
            "--out".to_string(),
            out.to_str().unwrap().to_string(),
            "--set".to_string(),
            "particles=32".to_string(),
            "--set".to_string(),
            "samples=6".to_string(),
            "--jobs".to_string(),
            "1".to_string(),
        ]
    };
    let shared = tmp.path().join("shared");
    let children: Vec<_> = (1..=4)
        .map(|i| {
            std::process::Command::new(env!("CARGO_BIN_EXE_jamkit"))
                .args(args(&shared))
                .args(["--shard", &format!("{i}/4")])
                .current_dir(env!("CARGO_MANIFEST_DIR"))
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for child in children {
        let out = child.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let single = tmp.path().join("single");
    for dir in [&shared, &single] {
        let a = args(dir);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        let (code, _, err) = jamkit(&a);
        assert_eq!(code, 0, "{err}");
    }
    assert_eq!(
        results_without_timing(&shared),
        results_without_timing(&single)
    );
}

#[test]
fn bad_shards_are_named() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron");
    let tmp = tempfile::tempdir().unwrap();
    for bad in ["0/3", "4/3", "1/0", "x", "2", "1/-2"] {
        let (code, _, err) = jamkit(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            tmp.path().to_str().unwrap(),
            "--shard",
            bad,
        ]);
        assert_eq!(code, 1, "{bad}");
        assert!(
            err.contains(&format!("--shard = {bad}")) && err.contains("1 ≤ I ≤ K"),
            "{bad}: {err}"
        );
        assert!(!err.contains("panicked"), "{bad}: {err}");
    }
}
