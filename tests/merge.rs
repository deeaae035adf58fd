//! `jamkit merge`: parts of a run made in separate directories gather into
//! one run with the tables of one plain run (timings aside); a missing
//! part, a conflicting duplicate and parts of different experiments are
//! refused with messages that say what is wrong.

use std::path::{Path, PathBuf};

use crate::common;
use common::{jamkit, quickstart, results_without_timing};

const SMALL: [&str; 6] = ["--set", "particles=32", "--set", "samples=5", "--jobs", "1"];

/// Run part `i` of `k` (or everything, `k = 0`) into `dir`.
fn run(dir: &Path, i: usize, k: usize, extra: &[&str]) {
    let file = quickstart();
    let shard = format!("{i}/{k}");
    let mut args = vec!["run", &file, "--out", dir.to_str().unwrap(), "--quiet"];
    args.extend(SMALL);
    if k > 0 {
        args.extend(["--shard", &shard]);
    }
    args.extend(extra);
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{args:?}: {err}");
}

fn merge(dirs: &[PathBuf], out: &Path) -> (i32, String, String) {
    let mut args = vec!["merge".to_string()];
    args.extend(dirs.iter().map(|d| d.to_str().unwrap().to_string()));
    args.extend(["-o".into(), out.to_str().unwrap().into()]);
    jamkit(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

#[test]
fn parts_in_separate_directories_merge_to_one_run() {
    let tmp = tempfile::tempdir().unwrap();
    let single = tmp.path().join("single");
    run(&single, 0, 0, &[]);
    for k in [1usize, 2, 3, 4] {
        let parts: Vec<PathBuf> = (1..=k)
            .map(|i| {
                let d = tmp.path().join(format!("k{k}_part{i}"));
                run(&d, i, k, &[]);
                assert!(!d.join("results.csv").exists(), "a part writes no table");
                d
            })
            .collect();
        let out = tmp.path().join(format!("merged{k}"));
        let (code, text, err) = merge(&parts, &out);
        assert_eq!(code, 0, "{err}");
        assert!(
            text.contains(&format!("5 packings from {k} parts")),
            "{text}"
        );
        assert_eq!(
            results_without_timing(&out),
            results_without_timing(&single),
            "K = {k}"
        );
        let summary = |d: &Path| std::fs::read_to_string(d.join("summary.csv")).unwrap();
        assert_eq!(
            summary(&out).lines().count(),
            summary(&single).lines().count()
        );
        // Into one of the parts: the same tables.
        let (code, _, err) = merge(&parts, &parts[0]);
        assert_eq!(code, 0, "{err}");
        assert_eq!(
            results_without_timing(&parts[0]),
            results_without_timing(&single)
        );
    }
}

#[test]
fn a_missing_part_is_refused_and_named() {
    let tmp = tempfile::tempdir().unwrap();
    let parts: Vec<PathBuf> = (1..=3)
        .map(|i| {
            let d = tmp.path().join(format!("p{i}"));
            run(&d, i, 3, &[]);
            d
        })
        .collect();
    let (code, _, err) = merge(&parts[..2], &tmp.path().join("out"));
    assert_ne!(code, 0);
    // Part 3 of 3 holds job j = 2 of the grid order (j mod 3 + 1 = 3): sample 3.
    assert!(
        err.contains("1 of the run's 5 packings are in none of the parts"),
        "{err}"
    );
    assert!(err.contains("sphere_d2_N32_s3"), "{err}");
    assert!(!tmp.path().join("out/results.csv").exists());
}

#[test]
fn a_conflicting_duplicate_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    run(&a, 1, 2, &[]);
    run(&b, 2, 2, &[]);
    // A copy of one of a's packings in b, with another φ.
    let name = "packings/sphere_d2_N32_s1.json";
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join(name)).unwrap()).unwrap();
    // The same file is fine: counted as a duplicate.
    std::fs::write(b.join(name), serde_json::to_string(&v).unwrap()).unwrap();
    let (code, text, err) = merge(&[a.clone(), b.clone()], &tmp.path().join("ok"));
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("1 found in more than one"), "{text}");
    v["phi"] = serde_json::json!(0.5);
    std::fs::write(b.join(name), serde_json::to_string(&v).unwrap()).unwrap();
    let (code, _, err) = merge(&[a, b], &tmp.path().join("out"));
    assert_ne!(code, 0);
    assert!(
        err.contains("packing sphere_d2_N32_s1 differs between"),
        "{err}"
    );
}

#[test]
fn parts_of_different_experiments_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    run(&a, 1, 2, &[]);
    run(&b, 2, 2, &["--set", "minimizer.force_tol=1e-24"]);
    let (code, _, err) = merge(&[a, b], &tmp.path().join("out"));
    assert_ne!(code, 0);
    assert!(err.contains("ran different experiments"), "{err}");
    assert!(err.contains("force_tol"), "{err}");
}

/// A part killed in the middle resumes: rerun, it reads back what it
/// finished, makes the rest, and the merged run is one plain run's.
#[test]
fn a_killed_part_resumes() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let file = quickstart();
    let tmp = tempfile::tempdir().unwrap();
    let big = [
        "--set",
        "particles=256",
        "--set",
        "samples=8",
        "--jobs",
        "1",
    ];
    let part = |dir: &Path, i: usize| -> Vec<String> {
        let shard = format!("{i}/2");
        let mut args = vec![
            "run",
            file.as_str(),
            "--out",
            dir.to_str().unwrap(),
            "--shard",
            &shard,
        ];
        args.extend(big);
        args.into_iter().map(String::from).collect()
    };
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_jamkit"))
        .args(part(&a, 1))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stderr.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(first.starts_with("[1/4] "), "{first}");
    let args = part(&a, 1);
    let (code, _, err) = jamkit(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    let read_back = err.matches("read back from an earlier run").count();
    assert!((1..4).contains(&read_back), "resumed, not redone: {err}");
    let args = part(&b, 2);
    let (code, _, err) = jamkit(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    let merged = tmp.path().join("merged");
    let (code, _, err) = merge(&[a, b], &merged);
    assert_eq!(code, 0, "{err}");
    let single = tmp.path().join("single");
    let mut args = vec![
        "run",
        file.as_str(),
        "--out",
        single.to_str().unwrap(),
        "--quiet",
    ];
    args.extend(big);
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        results_without_timing(&merged),
        results_without_timing(&single)
    );
}

/// The same sample made in two parts is the same packing, but its timings
/// (the packing's and its spectrum's `wall_s`) differ: merged, counted as
/// a duplicate, not refused.
#[test]
fn a_sample_made_twice_with_a_spectrum_merges() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let spectrum = ["--set", "observables=[Contacts, Spectrum(())]"];
    run(&a, 1, 2, &spectrum);
    run(&b, 2, 2, &spectrum);
    // Part 1 again into b: sample 1 made a second time, other timings.
    run(&b, 1, 2, &spectrum);
    let name = "packings/sphere_d2_N32_s1.json";
    let timing = |d: &Path| {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join(name)).unwrap()).unwrap();
        (
            v["measures"]["wall_s"].clone(),
            v["measures"]["spectrum"]["wall_s"].clone(),
        )
    };
    assert!(timing(&a).1.is_number(), "the packing has a spectrum");
    let out = tmp.path().join("out");
    let (code, text, err) = merge(&[a, b], &out);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("found in more than one"), "{text}");
    assert!(out.join("dos.csv").exists());
}
