//! Small-N jamming end to end, in 2D and 3D, through the experiment runner.

use crate::common;
use common::run_into;
use jamkit_experiment::Experiment;
use jamkit_format::PackingFile;

fn experiment(dim: usize, particles: usize, samples: usize) -> Experiment {
    let text = format!(
        r#"(name: "small", dim: {dim}, family: "sphere", particles: {particles}, samples: {samples}, seed: 11)"#
    );
    Experiment::from_ron(&text, "inline").unwrap()
}

/// Every packing ends inside the paper's window, with a rigid contact
/// network: N_c ≥ d (N_nr − 1) + 1 (isostatic plus one, periodic box).
/// The packing fraction of such small systems spreads widely, so only a
/// generous physical range is asserted (random close packing is 0.84 in 2D,
/// 0.64 in 3D; finite N shifts and spreads it by a few percent).
fn check_jammed(dim: usize, particles: usize, phi_range: (f64, f64)) {
    let dir = tempfile::tempdir().unwrap();
    let report = run_into(&experiment(dim, particles, 3), dir.path(), 2);
    assert!(report.failures.is_empty(), "{:?}", report.failures);
    assert_eq!(report.packings.len(), 3);
    for p in &report.packings {
        common::assert_in_window(p);
        assert!(
            p.phi > phi_range.0 && p.phi < phi_range.1,
            "{}: phi = {}",
            p.id,
            p.phi
        );
        let margin = p.measures.iso_margin.unwrap();
        assert!(margin >= 1, "{}: iso margin {margin}", p.id);
        assert_eq!(p.positions.len(), particles);
        assert_eq!(p.rattler.len(), particles);
        assert!(p.measures.flag.is_empty());
    }
}

#[test]
fn disks_jam_end_to_end_2d() {
    check_jammed(2, 64, (0.78, 0.88));
}

#[test]
fn spheres_jam_end_to_end_3d() {
    check_jammed(3, 64, (0.58, 0.70));
}

/// Same seeds, different thread counts: identical packings, bit for bit.
/// A second run into the same directory computes nothing and returns the
/// same records.
#[test]
fn packings_are_reproducible_and_runs_resume() {
    let e = experiment(2, 32, 3);
    let one = tempfile::tempdir().unwrap();
    let two = tempfile::tempdir().unwrap();
    let a = run_into(&e, one.path(), 1);
    let b = run_into(&e, two.path(), 2);
    assert_eq!(a.reused, 0);
    for (x, y) in a.packings.iter().zip(&b.packings) {
        assert_eq!(x.positions, y.positions);
        assert_eq!(x.phi.to_bits(), y.phi.to_bits());
        assert_eq!(x.box_edges, y.box_edges);
    }
    let again = run_into(&e, one.path(), 2);
    assert_eq!(again.reused, 3);
    assert_eq!(again.packings, a.packings);
    let csv = std::fs::read_to_string(one.path().join("results.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for column in [
        "family",
        "dim",
        "particles",
        "seed",
        "phi_j",
        "energy_per_particle",
        "n_contacts",
        "n_rattlers",
        "z_j",
        "iso_margin",
        "fire_steps",
        "wall_s",
    ] {
        assert!(
            header.split(',').any(|c| c == column),
            "missing column {column}"
        );
    }
    assert_eq!(csv.lines().count(), 4);
    let summary = std::fs::read_to_string(one.path().join("summary.csv")).unwrap();
    assert_eq!(summary.lines().count(), 2);
    // Changed settings are neither served from the old files nor mixed
    // with them: the run is refused, naming the setting.
    let changed = jamkit_experiment::overrides::apply(&e, &["protocol.eps=2e-3".into()]).unwrap();
    let options = common::options(two.path(), 2);
    let refused = jamkit_experiment::runner::run(&changed, &options).unwrap_err();
    let message = refused.to_string();
    assert!(
        message.contains("protocol.Jam.eps = 0.002") && message.contains("another --out"),
        "{message}"
    );
    // Nothing was touched: the same settings still read every packing back.
    assert_eq!(run_into(&e, two.path(), 2).reused, 3);
    for p in &a.packings {
        for x in &p.positions {
            assert!(
                x.iter()
                    .zip(&p.box_edges)
                    .all(|(c, l)| (0.0..*l).contains(c)),
                "centre outside the box"
            );
        }
    }
    // A damaged packing file is recomputed, not trusted.
    let damaged = one
        .path()
        .join("packings")
        .join(format!("{}.json", a.packings[0].id));
    std::fs::write(&damaged, "{ truncated").unwrap();
    let repaired = run_into(&e, one.path(), 1);
    assert_eq!(repaired.reused, 2);
    assert_eq!(
        PackingFile::load(&damaged).unwrap().positions,
        a.packings[0].positions
    );
}

/// Compression to a packing fraction and to a pressure end where asked.
#[test]
fn phi_and_pressure_protocols_reach_their_targets() {
    let dir = tempfile::tempdir().unwrap();
    let mut e = experiment(2, 64, 1);
    e = jamkit_experiment::overrides::apply(&e, &["protocol=Phi(phi: 0.9, eps: 0.01)".into()])
        .unwrap();
    let r = run_into(&e, dir.path(), 1);
    assert!(
        (r.packings[0].phi - 0.9).abs() < 1e-12,
        "phi {}",
        r.packings[0].phi
    );
    assert!(
        r.packings[0].energy_per_particle > 1e-6,
        "0.9 is above jamming: energy must remain"
    );
    let dir = tempfile::tempdir().unwrap();
    e = jamkit_experiment::overrides::apply(
        &e,
        &["protocol=Pressure(pressure: 1e-3, tol: 1e-2)".into()],
    )
    .unwrap();
    let r = run_into(&e, dir.path(), 1);
    let p = r.packings[0].measures.pressure.unwrap();
    assert!((p - 1e-3).abs() < 1e-2 * 1e-3, "pressure {p}");
}

/// A search that cannot finish within its caps ends with an error that
/// names the sample and the cap, and the run reports it instead of hanging.
#[test]
fn exhausted_search_is_a_clear_error() {
    let first_failure = |set: &str| {
        let dir = tempfile::tempdir().unwrap();
        let e = jamkit_experiment::overrides::apply(&experiment(2, 16, 1), &[set.into()]).unwrap();
        let report = run_into(&e, dir.path(), 1);
        assert!(report.packings.is_empty());
        report.failures[0].to_string()
    };
    let msg = first_failure("protocol.max_density_steps=5");
    assert!(
        msg.contains("sample sphere_d2_N16_s11") && msg.contains("max_density_steps = 5"),
        "{msg}"
    );
    let msg = first_failure("minimizer.max_steps=3");
    assert!(msg.contains("FIRE did not converge in 3 steps"), "{msg}");
}

/// `dim: [2, 3]` runs both dimensions in one output directory: packings
/// with `dim` 2 and 3, the 2D one first (`dim` is the outermost axis), one
/// summary row per dimension. Each packing records its own `dim` as a
/// plain number in its settings, so the 2D packing is the one a scalar
/// `dim: 2` file makes, and a later scalar run reuses it.
#[test]
fn a_dim_list_runs_both_dimensions() {
    let both = Experiment::from_ron(
        r#"(name: "dims", dim: [2, 3], family: "sphere", particles: 64, samples: 1, seed: 11)"#,
        "inline",
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let report = run_into(&both, dir.path(), 2);
    assert!(report.failures.is_empty(), "{:?}", report.failures);
    let got: Vec<(usize, &str, usize)> = report
        .packings
        .iter()
        .map(|p| (p.dim, p.id.as_str(), p.positions[0].len()))
        .collect();
    assert_eq!(
        got,
        vec![(2, "sphere_d2_N64_s11", 2), (3, "sphere_d3_N64_s11", 3)]
    );
    for p in &report.packings {
        assert_eq!(p.settings["dim"], serde_json::json!(p.dim), "{}", p.id);
        let on_disk =
            PackingFile::load(&dir.path().join("packings").join(format!("{}.json", p.id))).unwrap();
        assert_eq!(on_disk.dim, p.dim);
    }
    let summary = std::fs::read_to_string(dir.path().join("summary.csv")).unwrap();
    assert_eq!(summary.lines().count(), 3, "{summary}");
    // The scalar file's run of 2D: the same packing, served from the files
    // the list run wrote.
    let two = jamkit_experiment::overrides::apply(&both, &["dim=2".into()]).unwrap();
    let again = run_into(&two, dir.path(), 1);
    assert_eq!(again.reused, 1);
    assert_eq!(again.packings.len(), 1);
    assert_eq!(again.packings[0], report.packings[0]);
    let fresh = tempfile::tempdir().unwrap();
    let alone = run_into(&two, fresh.path(), 1);
    assert_eq!(alone.reused, 0);
    assert_eq!(alone.packings[0].positions, report.packings[0].positions);
    assert_eq!(alone.packings[0].settings, report.packings[0].settings);
}
