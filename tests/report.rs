//! `jamkit report` on a small run made here: every figure written as a
//! non-empty SVG and PNG, every fitted exponent finite, the summary table
//! present, and clear errors for directories without near-disk packings.

use crate::common;
use jamkit_experiment::Experiment;
use std::path::Path;

fn small_run(dir: &Path) {
    let text = r#"(name: "rep", family: "fourier",
        params: {"n": 2, "delta": [0.003, 0.01, 0.03, 0.1, 0.3]}, particles: [16, 32], samples: 2, seed: 5,
        observables: [Contacts, Spectrum(), Gaps(h_min: 1e-8, points_per_decade: 4)])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    common::run_ok(&e, dir, 2);
}

#[test]
fn report_writes_figures_fits_and_summary() {
    let runs = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    small_run(runs.path());
    let options = jamkit_report::Options {
        resamples: 50,
        ..Default::default()
    };
    let r = jamkit_report::report(&[runs.path().to_path_buf()], out.path(), &options).unwrap();
    // φ_J, f_r, δz_J, finite size (two N), collapse, Z(h) and its collapse,
    // D(ω), ω₁/ω_*: at least eight figures from this run.
    assert!(r.figures.len() >= 8, "{:?}", r.figures);
    for stem in &r.figures {
        let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
        assert!(
            svg.contains("<svg") && svg.len() > 2000,
            "{}",
            stem.display()
        );
        let png = std::fs::read(stem.with_extension("png")).unwrap();
        assert_eq!(&png[1..4], b"PNG", "{}", stem.display());
        assert!(png.len() > 5000, "{}: {} bytes", stem.display(), png.len());
    }
    // ω₁ is defined at every Δ ≤ 0.1 (three points), so it is fitted.
    assert!(r.fits.iter().any(|f| f.quantity == "ω₁"), "{:?}", r.fits);
    for f in &r.fits {
        assert!(
            f.fit.exponent.is_finite() && f.fit.error.is_finite() && f.fit.error >= 0.0,
            "{f:?}"
        );
        assert!(f.fit.points >= 3);
    }
    // Fits over four Δ or more are refitted without each end point: one
    // point fewer, a range inside the full one, and the table says so.
    let varied: Vec<_> = r.fits.iter().filter(|f| f.fit.points >= 4).collect();
    assert!(!varied.is_empty(), "{:?}", r.fits);
    for f in varied {
        assert_eq!(f.range_variants.len(), 2, "{f:?}");
        for (_, v) in &f.range_variants {
            assert_eq!(v.points, f.fit.points - 1, "{f:?}");
            assert!(v.range.0 >= f.fit.range.0 && v.range.1 <= f.fit.range.1);
            assert!(v.range != f.fit.range);
        }
    }
    let md = std::fs::read_to_string(out.path().join("report.md")).unwrap();
    assert!(md.contains("## How the exponents move with the fit range"));
    assert_eq!(md, r.markdown);
    assert!(md.contains("| paper's claim | our measurement | agrees? |"));
    assert!(md.contains("ω₁ ∝ Δ"));
}

/// Runs of the exact gap alone (as `experiments/rough/large_n.ron`) get
/// the paper's figures of that gap model, and the summary says which.
#[test]
fn report_of_exact_gap_runs_draws_their_figures() {
    let runs = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    for (n, delta) in [(2, "[0.01, 0.3]"), (16, "[0.01, 0.05]")] {
        let text = format!(
            r#"(name: "exact", family: "fourier",
            params: {{"n": {n}, "delta": {delta}, "gap": "Exact"}}, particles: 16, samples: 1,
            observables: [Contacts])"#
        );
        let e = Experiment::from_ron(&text, "inline").unwrap();
        common::run_ok(&e, runs.path(), 2);
    }
    let r = jamkit_report::report(
        &[runs.path().to_path_buf()],
        out.path(),
        &jamkit_report::Options::default(),
    )
    .unwrap();
    assert!(
        r.markdown
            .contains("the figures are those of the `Exact` gap model"),
        "{}",
        r.markdown
    );
    assert!(out.path().join("fig07_phi_j.png").exists());
}

#[test]
fn report_refuses_directories_without_near_disks() {
    let empty = tempfile::tempdir().unwrap();
    std::fs::create_dir(empty.path().join("packings")).unwrap();
    let out = tempfile::tempdir().unwrap();
    let err = jamkit_report::report(
        &[empty.path().to_path_buf()],
        out.path(),
        &jamkit_report::Options::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("no packings of the `fourier` family"), "{err}");
    let missing = jamkit_report::report(
        &[empty.path().join("nowhere")],
        out.path(),
        &jamkit_report::Options::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.len() > 10 && missing.contains("nowhere"), "{missing}");
}

/// Near-spheres with one mode `l` (3D `harmonic`) get the same figures and
/// claims, named by `l`; a call mixing them with near-disks is refused.
#[test]
fn report_of_near_spheres_names_the_mode_l_and_refuses_mixing() {
    let runs = tempfile::tempdir().unwrap();
    let text = r#"(name: "rep3", dim: 3, family: "harmonic",
        params: {"l": 2, "m": 0, "delta": [0.03, 0.1, 0.3]}, particles: 64, samples: 1, seed: 5,
        observables: [Contacts, Spectrum()])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    common::run_ok(&e, runs.path(), 2);
    let out = tempfile::tempdir().unwrap();
    let options = jamkit_report::Options {
        resamples: 20,
        ..Default::default()
    };
    let r = jamkit_report::report(&[runs.path().to_path_buf()], out.path(), &options).unwrap();
    let names: Vec<String> = r
        .figures
        .iter()
        .map(|s| s.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().any(|n| n == "fig12_dos_l2"), "{names:?}");
    assert!(names.iter().all(|n| !n.ends_with("_n2")), "{names:?}");
    let md = &r.markdown;
    assert!(md.contains("| l | N | Δ values |"), "{md}");
    assert!(md.contains("| 2 | 64 | 3e-2, 1e-1, 3e-1 | 1–1 |"), "{md}");
    assert!(md.contains("φ_J rises with Δ for every l"), "{md}");
    // δz_J is measured against the spheres' z_iso = 2d = 6 in 3D: near-spheres
    // at Δ = 0.3 jam far above it (z_J ≈ 9 at N = 128, docs/reports/paper-3d.md).
    assert!(md.contains("l = 2: "), "{md}");

    let disks = tempfile::tempdir().unwrap();
    let text = r#"(name: "rep2", family: "fourier", params: {"n": 2, "delta": 0.1},
        particles: 16, samples: 1, seed: 5, observables: [Contacts])"#;
    common::run_ok(
        &Experiment::from_ron(text, "inline").unwrap(),
        disks.path(),
        1,
    );
    let err = jamkit_report::report(
        &[runs.path().to_path_buf(), disks.path().to_path_buf()],
        out.path(),
        &options,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("more than one kind (2D, n; 3D, l)"), "{err}");
}
