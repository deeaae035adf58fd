//! `jamkit plot`: figures of any run. Scanned quantities are found, one
//! figure per observable and scanned quantity is written (SVG and PNG),
//! series are labelled by the other coordinates, unmeasured observables are
//! skipped and said so, and a directory without packings is refused.

use crate::common;
use jamkit_experiment::Experiment;

#[test]
fn a_dimer_scan_plots_every_observable_against_each_scanned_quantity() {
    let run = tempfile::tempdir().unwrap();
    let text = r#"(name: "dimers", family: "nmer", dim: 2,
        params: {"alpha": [1.2, 1.5]}, particles: [16, 24], samples: 2, seed: 3,
        observables: [Contacts, Pressure, Spectrum()])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    common::run_ok(&e, run.path(), 2);
    let out = tempfile::tempdir().unwrap();
    let p = jamkit_report::runplot::plot(&[run.path().to_path_buf()], out.path()).unwrap();
    assert_eq!(p.scanned, ["alpha", "particles"]);
    for x in ["alpha", "particles"] {
        for y in ["phi_j", "z_j", "rattlers", "pressure"] {
            let stem = out.path().join(format!("{y}_vs_{x}"));
            assert!(p.figures.contains(&stem), "{y}_vs_{x}: {:?}", p.figures);
            let png = std::fs::read(stem.with_extension("png")).unwrap();
            assert_eq!(&png[1..4], b"PNG");
        }
    }
    // φ_J against α: one series per N, labelled with it.
    let svg = std::fs::read_to_string(out.path().join("phi_j_vs_alpha.svg")).unwrap();
    assert!(
        svg.contains("N = 16") && svg.contains("N = 24"),
        "series labels"
    );
    assert!(p.figures.contains(&out.path().join("dos")));
    assert!(p.index.contains("Z(h) (no Gaps measured)"), "{}", p.index);
    let index = std::fs::read_to_string(out.path().join("index.md")).unwrap();
    assert_eq!(index, p.index);
}

#[test]
fn runs_of_one_file_at_several_pressures_plot_the_moduli_against_the_target() {
    // The same file run at two target pressures into two directories: the
    // packing ids are the same, the settings differ, so both runs are
    // points (not one taken for a copy of the other), and G, B are drawn
    // against the target pressure.
    let text = r#"(name: "el", family: "sphere", dim: 2, particles: 16, samples: 2, seed: 1,
        protocol: Pressure(pressure: 1e-2), observables: [Contacts, Pressure, Moduli()])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    let runs = [tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap()];
    common::run_ok(&e, runs[0].path(), 2);
    let e = jamkit_experiment::overrides::apply(&e, &["protocol.pressure=1e-1".into()]).unwrap();
    common::run_ok(&e, runs[1].path(), 2);
    let out = tempfile::tempdir().unwrap();
    let dirs: Vec<_> = runs.iter().map(|d| d.path().to_path_buf()).collect();
    let p = jamkit_report::runplot::plot(&dirs, out.path()).unwrap();
    assert_eq!(p.scanned, ["target_pressure"]);
    for y in ["shear_modulus", "bulk_modulus", "pressure"] {
        let stem = out.path().join(format!("{y}_vs_target_pressure"));
        assert!(p.figures.contains(&stem), "{y}: {:?}", p.figures);
    }
    assert!(p.index.contains("2 points, 4 packings"), "{}", p.index);
}

#[test]
fn plot_refuses_a_directory_without_packings() {
    let empty = tempfile::tempdir().unwrap();
    std::fs::create_dir(empty.path().join("packings")).unwrap();
    let out = tempfile::tempdir().unwrap();
    let err = jamkit_report::runplot::plot(&[empty.path().to_path_buf()], out.path())
        .unwrap_err()
        .to_string();
    assert!(err.contains("no packing files"), "{err}");
}

/// `jamkit report` on a run that is not the paper's near-disks (the
/// README's quickstart) draws the run's own figures instead of failing.
#[test]
fn report_on_the_quickstart_draws_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let fig = dir.path().join("fig");
    let (code, _, err) = common::jamkit(&[
        "run",
        &common::quickstart(),
        "--out",
        run.to_str().unwrap(),
        "--set",
        "samples=2",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) =
        common::jamkit(&["report", run.to_str().unwrap(), "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("drew the runs' own instead"), "{out}");
    let index = std::fs::read_to_string(fig.join("index.md")).unwrap();
    assert!(index.contains("phi_j_vs_"), "{index}");
    assert!(fig.join("dos.png").exists() || index.contains("no Spectrum measured"));
}

#[test]
fn z_above_jam_goes_on_a_log_axis_without_its_exact_zeros() {
    // Disks compressed by δφ = 1e-7 above their own jamming point gain no
    // contact (z − z_J = 0 exactly at N = 64); at 1e-4 and 1e-1 they do,
    // a factor ~30 apart: the figure is log-scaled with the zero left off,
    // and its caption says so (a log axis cannot show 0).
    let text = r#"(name: "zaj", family: "sphere", particles: 64, samples: 1, seed: 1,
        protocol: AboveJam(delta_phi: [1e-7, 1e-4, 1e-1]), observables: [Contacts, Pressure])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    let run = tempfile::tempdir().unwrap();
    let report = common::run_ok(&e, run.path(), 1);
    let dz: Vec<f64> = report
        .packings
        .iter()
        .map(|p| p.measures.z_j.unwrap() - p.measures.jam_point.as_ref().unwrap().z.unwrap())
        .collect();
    assert_eq!(dz.iter().filter(|&&d| d == 0.0).count(), 1, "{dz:?}");
    let out = tempfile::tempdir().unwrap();
    let p = jamkit_report::runplot::plot(&[run.path().to_path_buf()], out.path()).unwrap();
    assert!(
        p.index
            .contains("(1 point with a mean of exactly 0 left off the log axis)"),
        "{}",
        p.index
    );
}

#[test]
fn the_stabilised_cells_z_is_plotted_where_it_was_measured() {
    // Disks (N = 64) at δφ = 1e-4 and 1e-1 above their own jamming point,
    // shear-stabilised: `z − z_J` of the stabilised cell is drawn beside
    // the fixed box's, and each cell, stable to shear, has the margin a
    // disk packing needs for it (at least d(d+1)/2 = 3; tests/moduli.rs,
    // `SHEAR_STABLE_MARGIN_2D`). A run without the option has no such
    // figure.
    let text = r#"(name: "zst", family: "sphere", particles: 64, samples: 1, seed: 1,
        protocol: AboveJam(delta_phi: [1e-4, 1e-1], shear_stabilised: true),
        observables: [Contacts, Pressure, Moduli()])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    let run = tempfile::tempdir().unwrap();
    let report = common::run_ok(&e, run.path(), 1);
    assert_eq!(report.packings.len(), 2);
    for p in &report.packings {
        let s = p.measures.moduli.as_ref().unwrap().stabilisation.as_ref();
        let cell = s.unwrap().contacts.as_ref().expect("stabilised contacts");
        assert!(cell.iso_margin >= 3, "{}: {cell:?}", p.id);
    }
    let out = tempfile::tempdir().unwrap();
    let p = jamkit_report::runplot::plot(&[run.path().to_path_buf()], out.path()).unwrap();
    for y in ["z_above_jam", "z_stab_above_jam"] {
        let stem = out.path().join(format!("{y}_vs_delta_phi"));
        assert!(p.figures.contains(&stem), "{y}: {:?}", p.figures);
    }
    let plain = r#"(name: "zpl", family: "sphere", particles: 64, samples: 1, seed: 1,
        protocol: AboveJam(delta_phi: [1e-4, 1e-1]), observables: [Contacts, Pressure])"#;
    let e = Experiment::from_ron(plain, "inline").unwrap();
    let run = tempfile::tempdir().unwrap();
    common::run_ok(&e, run.path(), 1);
    let out = tempfile::tempdir().unwrap();
    let p = jamkit_report::runplot::plot(&[run.path().to_path_buf()], out.path()).unwrap();
    assert!(
        !p.figures
            .iter()
            .any(|f| f.ends_with("z_stab_above_jam_vs_delta_phi"))
    );
}
