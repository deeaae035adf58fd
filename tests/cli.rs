//! The `jamkit` binary: errors are messages with exit code 1, never panics.

use std::path::Path;

use crate::common;
use common::jamkit;

#[test]
fn bad_files_exit_with_a_message_and_no_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/inputs/bad");
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let (code, _, err) = jamkit(&["validate", path.to_str().unwrap()]);
        assert_eq!(code, 1, "{}", path.display());
        assert!(
            err.starts_with("error: ") && !err.contains("panicked"),
            "{}: {err}",
            path.display()
        );
    }
    let (code, _, err) = jamkit(&["run", "no/such/file.ron"]);
    assert_eq!(code, 1);
    assert!(err.contains("no/such/file.ron"), "{err}");
}

#[test]
fn overrides_reach_the_grid() {
    let (code, out, err) = jamkit(&[
        "validate",
        "experiments/quickstart.ron",
        "--set",
        "particles=[32, 64]",
        "--set",
        "samples=3",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("2 point(s) × 3 sample(s)")
            && out.contains("sphere_d2_N32")
            && out.contains("sphere_d2_N64"),
        "{out}"
    );
    let (code, _, err) = jamkit(&[
        "validate",
        "experiments/quickstart.ron",
        "--set",
        "protocol.epz=1",
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("epz"), "{err}");
}

/// `--set dim=…` takes one dimension or a list (the outermost axis of the
/// grid), and a bad entry of a list is named with its value.
#[test]
fn dim_overrides_scan_and_are_checked() {
    let (code, out, err) = jamkit(&[
        "validate",
        "experiments/sanity/dimers.ron",
        "--set",
        "dim=3",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("3 point(s) × 10 sample(s)")
            && out.contains("nmer_d3_N512_alpha1.5")
            && !out.contains("nmer_d2_"),
        "{out}"
    );
    let (code, out, err) = jamkit(&[
        "validate",
        "experiments/quickstart.ron",
        "--set",
        "dim=[3, 2]",
        "--set",
        "particles=[32, 64]",
    ]);
    assert_eq!(code, 0, "{err}");
    let labels: Vec<&str> = out.lines().skip(1).map(str::trim).collect();
    assert_eq!(
        labels,
        [
            "sphere_d3_N32",
            "sphere_d3_N64",
            "sphere_d2_N32",
            "sphere_d2_N64"
        ],
        "{out}"
    );
    let (code, _, err) = jamkit(&[
        "validate",
        "experiments/sanity/dimers.ron",
        "--set",
        "dim=[2, 5]",
    ]);
    assert_eq!(code, 1);
    assert!(
        err.contains("dim = 5") && err.contains("supports dim 2 or 3") && !err.contains("panicked"),
        "{err}"
    );
}

/// A family parameter of the wrong type is named, with its value and what
/// the family allows (serde alone names no field for an optional one).
#[test]
fn a_parameter_of_the_wrong_type_is_named() {
    for (file, set, field, allowed) in [
        (
            "experiments/sanity/dimers.ron",
            "params.inertia=heavy",
            "params.inertia",
            "moment of inertia",
        ),
        (
            "experiments/sanity/dimers.ron",
            "params.alpha=abc",
            "params.alpha",
            "aspect ratio",
        ),
        (
            "experiments/paper/phi_j.ron",
            "params.n=abc",
            "params.n",
            "mode number",
        ),
    ] {
        let (code, _, err) = jamkit(&["validate", file, "--set", set]);
        assert_eq!(code, 1, "{set}: {err}");
        assert!(
            err.contains(field) && err.contains(allowed) && !err.contains("untagged"),
            "{set}: {err}"
        );
    }
}

#[test]
fn shapes_lists_the_sphere_family() {
    let (code, out, _) = jamkit(&["shapes"]);
    assert_eq!(code, 0);
    assert!(out.contains("sphere"));
}

#[test]
fn run_writes_results_and_a_table() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().to_str().unwrap();
    let (code, out, err) = jamkit(&[
        "run",
        "experiments/quickstart.ron",
        "--out",
        out_dir,
        "--jobs",
        "2",
        "--set",
        "particles=16",
        "--set",
        "samples=2",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("sphere_d2_N16"), "{out}");
    for f in [
        "results.csv",
        "summary.csv",
        "experiment.ron",
        "packings/sphere_d2_N16_s1.json",
        "packings/sphere_d2_N16_s2.json",
    ] {
        assert!(dir.path().join(f).exists(), "{f} missing");
    }
}

/// Two experiment files run into one `--out` (as the paper profile's
/// Figs. 7–13 do): the directory's tables list every packing of both
/// files, a packing they share once, and every point of both; a run of
/// the second file alone still writes only its own.
#[test]
fn several_files_into_one_directory_tabulate_all_their_packings() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, particles: &str| {
        let path = dir.path().join(name);
        std::fs::write(
            &path,
            format!(
                r#"(name: "{name}", family: "sphere", particles: {particles}, samples: 2, seed: 1,
                   observables: [Contacts, Pressure])"#
            ),
        )
        .unwrap();
        path
    };
    // Both files make N = 16 (the same packings); only the first makes
    // N = 12 and only the second N = 20.
    let a = write("a.ron", "[12, 16]");
    let b = write("b.ron", "[16, 20]");
    let out = dir.path().join("both");
    let (code, stdout, err) = jamkit(&[
        "run",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("6 packings of the 2 files"), "{stdout}");
    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let ids: Vec<&str> = results
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(
        ids,
        [
            "sphere_d2_N12_s1",
            "sphere_d2_N12_s2",
            "sphere_d2_N16_s1",
            "sphere_d2_N16_s2",
            "sphere_d2_N20_s1",
            "sphere_d2_N20_s2"
        ]
    );
    let summary = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert_eq!(summary.lines().count(), 1 + 3, "{summary}");
    // One file alone: its own packings only (the shared directory keeps
    // the others' files, which a single run does not list).
    let (code, _, err) = jamkit(&[
        "run",
        b.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(results.lines().count(), 1 + 4, "{results}");
}
