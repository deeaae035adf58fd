//! `jamkit bench accuracy` and `jamkit bench pair`: the pair benchmark
//! (files, rows, the fitted orders 2 and 3 of the gap models), and the
//! gap-model and tolerance runs, which run `experiments/accuracy/*.ron`
//! through the runner and compare what it recorded: the comparison holds the runner's numbers, the reference rows
//! differ from themselves by exactly 0, a rerun reads the packings back,
//! and `jamkit run` of the same file with the same overrides makes the same
//! packings.

use crate::common;
use common::jamkit;
use std::path::Path;

/// A CSV with a header, as `(header, rows)`; every row as long as the header.
fn table(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            let r: Vec<String> = l.split(',').map(String::from).collect();
            assert_eq!(r.len(), header.len(), "{}: {l}", path.display());
            r
        })
        .collect();
    (header, rows)
}

fn rows(path: &Path) -> Vec<Vec<String>> {
    table(path).1
}

/// The cell of `row` under `column`.
fn cell<'a>(header: &[String], row: &'a [String], column: &str) -> &'a str {
    let k = header
        .iter()
        .position(|h| h == column)
        .unwrap_or_else(|| panic!("no column {column} in {header:?}"));
    &row[k]
}

/// `jamkit bench accuracy --quick`, tables into `dir/out`, runs into
/// `dir/runs`, with `extra` arguments.
fn quick_bench(dir: &Path, extra: &[&str]) -> (i32, String, String) {
    let (out, runs) = (dir.join("out"), dir.join("runs"));
    let mut args = vec![
        "bench",
        "accuracy",
        "--quick",
        "-o",
        out.to_str().unwrap(),
        "--runs",
        runs.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    jamkit(&args)
}

#[test]
fn quick_accuracy_bench_writes_tables_figures_and_the_orders_of_the_models() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let runs = dir.path().join("runs");
    let (code, stdout, err) = quick_bench(dir.path(), &[]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "pairs.csv",
        "slopes.csv",
        "packings.csv",
        "tolerances.csv",
        "tables.md",
        "errors_vs_delta.png",
        "errors_vs_delta.svg",
        "speed_vs_error.png",
        "speed_vs_error.svg",
        "tolerances.png",
        "tolerances.svg",
    ] {
        let p = out.join(f);
        assert!(
            std::fs::metadata(&p).is_ok_and(|m| m.len() > 100),
            "{f} missing or empty"
        );
    }

    // Pairs: 3 models × n = 2…5 × 6 values of Δ. Exact is not measured
    // exactly where the outline is non-convex (n = 4, 5 at Δ = 0.3), and there the
    // other models have a time but no error.
    let pairs = rows(&out.join("pairs.csv"));
    assert_eq!(pairs.len(), 3 * 4 * 6);
    for r in &pairs {
        let (model, n, delta, convex) = (&r[0], &r[1], &r[2], &r[3]);
        let non_convex = delta == "0.3" && (n == "4" || n == "5");
        assert_eq!(convex == "false", non_convex, "{r:?}");
        let timed = r[4].parse::<f64>().is_ok_and(|t| t > 0.0);
        assert_eq!(timed, !(non_convex && model == "Exact"), "{r:?}");
        let has_error = r[5].parse::<f64>().is_ok_and(|e| e > 0.0);
        assert_eq!(has_error, !non_convex && model != "Exact", "{r:?}");
    }
    // SecondOrder is more accurate than FirstOrder wherever both are measured.
    for f in pairs
        .iter()
        .filter(|r| r[0] == "FirstOrder" && !r[5].is_empty())
    {
        let s = pairs
            .iter()
            .find(|r| r[0] == "SecondOrder" && r[1] == f[1] && r[2] == f[2])
            .unwrap();
        let (ef, es): (f64, f64) = (f[5].parse().unwrap(), s[5].parse().unwrap());
        assert!(es < ef, "n = {}, Δ = {}: {es} ≥ {ef}", f[1], f[2]);
    }

    // Slopes: one per approximate model and n, near the orders 2 and 3.
    let slopes = rows(&out.join("slopes.csv"));
    assert_eq!(slopes.len(), 8);
    for r in &slopes {
        let slope: f64 = r[2].parse().unwrap();
        let order = if r[0] == "FirstOrder" { 2.0 } else { 3.0 };
        assert!((slope - order).abs() < 0.3, "{r:?}");
        let printed: f64 = stdout
            .lines()
            .find_map(|l| l.strip_prefix(&format!("slope {} n = {}: ", r[0], r[1])))
            .and_then(|rest| rest.split_whitespace().next()?.parse().ok())
            .unwrap_or_else(|| panic!("no printed slope for {r:?}: {stdout}"));
        assert!((printed - slope).abs() < 1e-3, "{printed} vs {r:?}");
    }

    // Packings (quick: Δ = 0.1, seed 1): one per model, each converged
    // with a packing fraction a near-disk packing can have, all compared
    // with Exact; Exact's own differences are exactly 0.
    let (head, packs) = table(&out.join("packings.csv"));
    assert_eq!(packs.len(), 3);
    for r in &packs {
        assert_eq!(cell(&head, r, "reference"), "Exact", "{r:?}");
        assert!(cell(&head, r, "error").is_empty(), "failed: {r:?}");
        let phi: f64 = cell(&head, r, "phi_j").parse().unwrap();
        assert!(phi > 0.7 && phi < 0.95, "{r:?}");
        let dphi: f64 = cell(&head, r, "d_phi_j").parse().unwrap();
        if cell(&head, r, "model") == "Exact" {
            assert_eq!(dphi, 0.0, "{r:?}");
        } else {
            assert!(dphi != 0.0, "another gap, the same φ_J bit for bit? {r:?}");
        }
    }

    // Tolerances: 2 windows × 6 force tolerances × 2 seeds, all converged,
    // one run whose scan is the ladder; the tables name the reference setting.
    let (head, tols) = table(&out.join("tolerances.csv"));
    assert_eq!(tols.len(), 2 * 6 * 2);
    assert!(
        tols.iter().all(|r| r.last().unwrap().is_empty()),
        "{tols:?}"
    );
    for r in tols.iter().filter(|r| r[0] == "1e-16" && r[2] == "1e-28") {
        assert_eq!(cell(&head, r, "d_phi_j"), "0e0", "the reference: {r:?}");
        assert_eq!(cell(&head, r, "d_n_c"), "0", "the reference: {r:?}");
    }
    let (rhead, results) = table(&runs.join("tolerances/results.csv"));
    assert_eq!(results.len(), 2 * 6 * 2);
    assert!(
        results
            .iter()
            .any(|r| cell(&rhead, r, "id").contains("_energy_low1e-14_force_tol1e-22_s2")),
        "{results:?}"
    );
    // One column per scanned setting, after the parameters, holding what
    // the id says: `…_energy_high2e-14_energy_low1e-14_force_tol1e-22_s2`.
    let at = |name: &str| rhead.iter().position(|h| h == name);
    assert!(at("gap") < at("protocol.energy_high") && at("minimizer.force_tol") < at("protocol"));
    for r in &results {
        let id = cell(&rhead, r, "id");
        let tail = format!(
            "_energy_high{}_energy_low{}_force_tol{}_s{}",
            cell(&rhead, r, "protocol.energy_high"),
            cell(&rhead, r, "protocol.energy_low"),
            cell(&rhead, r, "minimizer.force_tol"),
            cell(&rhead, r, "seed"),
        );
        assert!(id.ends_with(&tail), "{id} against {tail}");
    }
    // A file without a scan has no such columns.
    let (ghead, _) = table(&runs.join("gap_models/results.csv"));
    assert!(!ghead.iter().any(|h| h.contains('.')), "{ghead:?}");
    // `jamkit report --accuracy` of the same run: the same comparison.
    let again = dir.path().join("again");
    let (code, _, err) = jamkit(&[
        "report",
        "--accuracy",
        "tolerances",
        runs.join("tolerances").to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        std::fs::read_to_string(again.join("tolerances.csv")).unwrap(),
        std::fs::read_to_string(out.join("tolerances.csv")).unwrap()
    );
    assert!(again.join("tolerances.svg").exists() && again.join("accuracy.md").exists());
    let md = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(md.contains("## Pair evaluations") && md.contains("## Tolerances"));
    assert!(
        md.contains("| 1e-16…2e-16 | 1e-28 | 2/2 | ") && md.contains("| ref. |"),
        "{md}"
    );

    // A rerun reads every packing back from the runs: the same numbers.
    let before = std::fs::read_to_string(out.join("packings.csv")).unwrap();
    let (code, _, err) = quick_bench(dir.path(), &[]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("read back from an earlier run"), "{err}");
    let after = std::fs::read_to_string(out.join("packings.csv")).unwrap();
    assert_eq!(before, after);
}

/// `jamkit bench pair` is the pair benchmark on its own: the same files
/// and rows as `bench accuracy` writes, and a `pairs.md` that says where
/// it was measured.
#[test]
fn the_pair_benchmark_runs_on_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pair");
    let (code, stdout, err) = jamkit(&["bench", "pair", "--quick", "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(rows(&out.join("pairs.csv")).len(), 3 * 4 * 6);
    assert_eq!(rows(&out.join("slopes.csv")).len(), 8);
    assert_eq!(stdout.matches("slope ").count(), 8, "{stdout}");
    for f in ["errors_vs_delta.svg", "speed_vs_error.png"] {
        assert!(out.join(f).exists(), "{f}");
    }
    let md = std::fs::read_to_string(out.join("pairs.md")).unwrap();
    assert!(
        md.starts_with("Generated by `jamkit bench pair --quick` at commit ")
            && md.contains("## Pair evaluations"),
        "{md}"
    );
    // And no run directory: it times a function, it runs no experiment.
    assert!(!out.join("results.csv").exists() && !out.join("packings").exists());
}

/// A small comparison: FirstOrder against SecondOrder (no Exact), N = 12,
/// two seeds, through the command line; the comparison is the runner's
/// numbers, and `jamkit run` of the file with the same overrides makes the
/// same packings.
#[test]
fn gap_models_without_exact_compare_with_second_order_from_the_runners_records() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let runs = dir.path().join("runs");
    let sets = [
        "particles=12",
        "samples=2",
        "params.delta=0.05",
        "params.gap=[\"FirstOrder\", \"SecondOrder\"]",
    ];
    let mut args = Vec::new();
    for s in &sets {
        args.extend(["--set-gap-models", s]);
    }
    let (code, _, err) = quick_bench(dir.path(), &args);
    assert_eq!(code, 0, "{err}");

    let (head, packs) = table(&out.join("packings.csv"));
    for column in [
        "model",
        "delta",
        "particles",
        "reference",
        "seed",
        "phi_j",
        "z_j",
        "n_c",
        "rattlers",
        "d_phi_j",
        "d_z_j",
        "d_n_c",
        "d_rattlers",
        "error",
    ] {
        assert!(head.iter().any(|h| h == column), "{column}: {head:?}");
    }
    assert_eq!(packs.len(), 4, "2 models × 2 seeds: {packs:?}");
    // The runner's own table of the same packings.
    let (rhead, results) = table(&runs.join("gap_models/results.csv"));
    assert_eq!(results.len(), 4);
    let phi_of = |model: &str, seed: &str| -> f64 {
        let r = results
            .iter()
            .find(|r| cell(&rhead, r, "gap") == model && cell(&rhead, r, "seed") == seed)
            .unwrap_or_else(|| panic!("no {model} seed {seed} in results.csv"));
        cell(&rhead, r, "phi_j").parse().unwrap()
    };
    for r in &packs {
        let (model, seed) = (cell(&head, r, "model"), cell(&head, r, "seed"));
        assert_eq!(cell(&head, r, "reference"), "SecondOrder", "{r:?}");
        assert_eq!(cell(&head, r, "particles"), "12");
        assert!(cell(&head, r, "error").is_empty(), "failed: {r:?}");
        let phi: f64 = cell(&head, r, "phi_j").parse().unwrap();
        assert!((phi - phi_of(model, seed)).abs() < 1e-9, "{r:?}");
        let dphi: f64 = cell(&head, r, "d_phi_j").parse().unwrap();
        let expected = phi_of(model, seed) - phi_of("SecondOrder", seed);
        assert_eq!(dphi, expected, "{r:?}");
        if model == "SecondOrder" {
            for d in ["d_phi_j", "d_z_j", "d_n_c", "d_rattlers"] {
                assert_eq!(cell(&head, r, d).parse::<f64>().unwrap(), 0.0, "{d}: {r:?}");
            }
        }
    }
    let md = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(md.contains("| 0.05 | SecondOrder | 2/2 |"), "{md}");
    assert!(md.contains("| 0.05 | FirstOrder | 2/2 |"), "{md}");

    // `jamkit run` of the file itself, same overrides: the same packings.
    let direct = dir.path().join("direct");
    let mut args = vec![
        "run",
        "experiments/accuracy/gap_models.ron",
        "--out",
        direct.to_str().unwrap(),
        "--quiet",
    ];
    for s in &sets {
        args.extend(["--set", s]);
    }
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
    let (dhead, direct) = table(&direct.join("results.csv"));
    for (a, b) in results.iter().zip(&direct) {
        for column in ["id", "phi_j", "n_contacts", "fire_steps"] {
            assert_eq!(cell(&rhead, a, column), cell(&dhead, b, column), "{column}");
        }
    }
}

#[test]
fn bad_accuracy_options_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    for (args, names) in [
        (vec!["--set-gap-models", "particles=1"], "particles = 1"),
        (vec!["--set-gap-models", "params.delta=0.9"], "params.gap"),
        (vec!["--set-gap-models", "params.delta=nan"], "params.delta"),
        (
            vec!["--set-gap-models", "particles=[8, 10]"],
            "params.delta and params.gap",
        ),
        (
            vec!["--set-gap-models", "observables=[Pressure]"],
            "observables",
        ),
        (
            vec!["--set-tolerances", "params.delta=[0.1, 0.2]"],
            "--set-tolerances",
        ),
        (
            vec![
                "--set-tolerances",
                "scan=[]",
                "--set-tolerances",
                "protocol=Phi(phi: 0.5)",
            ],
            "protocol = phi",
        ),
        // The file's scan reaches the window of `Jam` only.
        (
            vec!["--set-tolerances", "protocol=Phi(phi: 0.5)"],
            "energy_low",
        ),
        (vec!["--jobs", "0"], "--jobs 0"),
    ] {
        let (code, _, err) = quick_bench(dir.path(), &args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && !err.contains("panicked") && err.contains(names),
            "{args:?}: {err}"
        );
    }
    assert!(
        !dir.path().join("runs").exists(),
        "a refused plan ran something"
    );
}

/// The two files are the documented study's physics: `jamkit run` of one
/// packing of each makes the packing of `docs/speed-vs-error/*.csv` (the
/// same FIRE steps, φ_J to its 9 printed digits, N_c and rattlers).
#[test]
fn the_files_make_the_documented_packings() {
    let dir = tempfile::tempdir().unwrap();
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/speed-vs-error");
    let (phead, packings) = table(&docs.join("packings.csv"));
    let (thead, tolerances) = table(&docs.join("tolerances.csv"));
    let documented = |head: &[String], rows: &[Vec<String>], key: &[(&str, &str)]| {
        rows.iter()
            .find(|r| key.iter().all(|(c, v)| cell(head, r, c) == *v))
            .unwrap_or_else(|| panic!("no documented row {key:?}"))
            .clone()
    };
    for (file, sets, head, row) in [
        (
            "gap_models",
            vec!["samples=1", "params.delta=0.01", "params.gap=FirstOrder"],
            &phead,
            documented(
                &phead,
                &packings,
                &[("model", "FirstOrder"), ("delta", "0.01"), ("seed", "1")],
            ),
        ),
        (
            "tolerances",
            vec!["samples=1", "scan=[]", "minimizer.force_tol=1e-20"],
            &thead,
            documented(
                &thead,
                &tolerances,
                &[
                    ("energy_low", "1e-16"),
                    ("force_tol", "1e-20"),
                    ("seed", "1"),
                ],
            ),
        ),
    ] {
        let out = dir.path().join(file);
        let path = format!("experiments/accuracy/{file}.ron");
        let mut args = vec!["run", &path, "--out", out.to_str().unwrap(), "--quiet"];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let (code, _, err) = jamkit(&args);
        assert_eq!(code, 0, "{err}");
        let (rhead, made) = table(&out.join("results.csv"));
        let made = &made[0];
        let phi: f64 = cell(&rhead, made, "phi_j").parse().unwrap();
        assert_eq!(format!("{phi:.9}"), cell(head, &row, "phi_j"), "{file}");
        for (ours, theirs) in [
            ("fire_steps", "fire_steps"),
            ("n_contacts", "n_c"),
            ("n_rattlers", "rattlers"),
        ] {
            assert_eq!(
                cell(&rhead, made, ours),
                cell(head, &row, theirs),
                "{file}: {ours}"
            );
        }
    }
}

#[test]
fn bad_accuracy_reports_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let empty = dir.path().join("empty");
    std::fs::create_dir_all(empty.join("packings")).unwrap();
    for (study, run, names) in [
        (
            "nonsense",
            &empty,
            "--accuracy nonsense: must be gap-models",
        ),
        ("tolerances", &empty, "no packing files"),
        ("gap-models", &dir.path().join("absent"), "absent"),
    ] {
        let (code, _, err) = jamkit(&[
            "report",
            "--accuracy",
            study,
            run.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 1, "{study}: {err}");
        assert!(
            err.starts_with("error: ") && !err.contains("panicked") && err.contains(names),
            "{study}: {err}"
        );
    }
}
