//! The spectrum and the gaps through the experiment runner and the
//! command line: files written, normalisations, resume with other
//! observables, and `jamkit spectrum` on a saved packing.

use crate::common;
use jamkit_experiment::Experiment;
use std::path::Path;

fn experiment(observables: &str) -> Experiment {
    let text = format!(
        r#"(name: "obs", family: "fourier", params: {{"n": 2, "delta": 0.1}}, particles: 32, samples: 2, seed: 3,
            observables: {observables})"#
    );
    Experiment::from_ron(&text, "inline").unwrap()
}

/// Rows of a CSV file as maps from the header's names.
fn csv(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

fn num(row: &std::collections::HashMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?}", row[key]))
}

/// D(ω) integrates to the fraction of modes above the zero threshold
/// (exactly, up to round-off: it is counts over N_dof and the bin width),
/// Z(h) rises from 0 to exactly 1 at h_cut, and every packing has its
/// eigenvalue table with one row per coordinate.
#[test]
fn spectrum_and_gaps_are_written_and_normalised() {
    let dir = tempfile::tempdir().unwrap();
    let e = experiment("[Contacts, Spectrum(eigenvalues: true), Gaps()]");
    let report = common::run_ok(&e, dir.path(), 2);
    let results = csv(&dir.path().join("results.csv"));
    assert_eq!(results.len(), 2);
    let mut zero = 0.0;
    for r in &results {
        zero += num(r, "zero_modes");
        // Hypostatic near-disks: N_f − N_c + 1 zero modes (tests/spectrum.rs),
        // so some beyond the translations and rattlers.
        assert!(num(r, "zero_extra") > 0.0);
        assert!(num(r, "gaps") > 0.0);
        let id = &r["id"];
        let table =
            std::fs::read_to_string(dir.path().join(format!("eigenvalues/{id}.csv"))).unwrap();
        assert_eq!(table.lines().count(), 1 + 3 * 32, "{id}");
        assert_eq!(r["softest_participation"], "", "no eigenvectors asked for");
    }
    let dos = csv(&dir.path().join("dos.csv"));
    let integral: f64 = dos
        .iter()
        .map(|r| num(r, "dos") * (num(r, "omega_hi") - num(r, "omega_lo")))
        .sum();
    let modes = 2.0 * 3.0 * 32.0;
    let outside: f64 = report
        .packings
        .iter()
        .map(|p| p.measures.spectrum.as_ref().unwrap().histogram.outside as f64)
        .sum();
    assert!(
        (integral - (modes - zero - outside) / modes).abs() < 1e-12,
        "∫D = {integral}"
    );
    let gaps = csv(&dir.path().join("gaps.csv"));
    let z: Vec<f64> = gaps.iter().map(|r| num(r, "z")).collect();
    assert!(z.windows(2).all(|w| w[1] >= w[0]), "Z(h) must not decrease");
    assert_eq!(*z.last().unwrap(), 1.0);
    assert!(z[0] < 0.01, "almost no gaps below 1e-12: Z = {}", z[0]);
}

/// With `modes: true`, the softest-mode columns of `results.csv` repeat the
/// row of `eigenvalues/<id>.csv` of the first mode above `omega_zero`
/// (below it lie the translations and the quartic modes of the hypostatic
/// near-disks, so it is not the first row).
#[test]
fn softest_mode_columns_repeat_the_first_non_zero_mode() {
    let dir = tempfile::tempdir().unwrap();
    common::run_ok(
        &experiment("[Contacts, Spectrum(modes: true)]"),
        dir.path(),
        2,
    );
    for r in &csv(&dir.path().join("results.csv")) {
        let id = &r["id"];
        let modes = csv(&dir.path().join(format!("eigenvalues/{id}.csv")));
        let first = modes.iter().position(|m| num(m, "omega") > 1e-5).unwrap();
        assert!(first > 2, "{id}: zero modes below the softest");
        let m = &modes[first];
        assert_eq!(r["softest_omega"], m["omega"], "{id}");
        assert_eq!(r["softest_participation"], m["participation"], "{id}");
        assert_eq!(r["softest_rotational_share"], m["rotational_share"], "{id}");
        let pr = num(r, "softest_participation");
        assert!((1.0 / 32.0..=1.0).contains(&pr), "{id}: PR = {pr}");
    }
}

/// A rerun that asks for other observables measures them on the saved
/// packings: nothing is jammed again (same FIRE steps, same φ), and the
/// records keep what was measured before, so experiments sharing an
/// output directory add up their observables.
#[test]
fn new_observables_are_measured_on_saved_packings() {
    let dir = tempfile::tempdir().unwrap();
    let first = common::run_ok(&experiment("[Contacts, Gaps()]"), dir.path(), 2);
    let second = common::run_ok(&experiment("[Contacts, Spectrum()]"), dir.path(), 2);
    assert_eq!(second.reused, 2);
    for (a, b) in first.packings.iter().zip(&second.packings) {
        assert_eq!(a.measures.fire_steps, b.measures.fire_steps);
        assert_eq!(a.phi.to_bits(), b.phi.to_bits());
        assert_eq!(a.measures.n_contacts, b.measures.n_contacts);
        assert!(a.measures.spectrum.is_none() && b.measures.spectrum.is_some());
        assert_eq!(a.measures.gaps, b.measures.gaps, "gaps kept");
    }
    assert!(dir.path().join("dos.csv").exists());
    // Asking for less than the files hold changes nothing.
    let third = common::run_ok(&experiment("[Contacts]"), dir.path(), 2);
    assert_eq!(third.packings, second.packings);
}

/// A re-measure of a saved near-disk packing (another observable added, so
/// the runner reads the packings back) gives the run's own measures bit
/// for bit: the run measures the configuration as its file records it.
/// Measured on the orientations in memory instead, `e^{iθ}` a bit or two
/// from what the stored `θ` gives back, these packings' fixed-box G would
/// come back 3e-12 and 1e-9 off (N = 32, Δ = 0.03, δφ = 1e-2, seeds 1
/// and 2).
#[test]
fn remeasured_near_disk_moduli_equal_the_run_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let above = |observables: &str| {
        let text = format!(
            r#"(name: "remeasure", family: "fourier", params: {{"n": 2, "delta": 0.03}},
                sizes: Binary(small: 0.5, large: 0.7), particles: 32, samples: 2, seed: 1,
                protocol: AboveJam(delta_phi: [1e-2]), observables: {observables})"#
        );
        Experiment::from_ron(&text, "inline").unwrap()
    };
    let run = common::run_ok(&above("[Contacts, Pressure, Moduli()]"), dir.path(), 1);
    let again = common::run_ok(
        &above("[Contacts, Pressure, Moduli(), Gaps()]"),
        dir.path(),
        1,
    );
    assert_eq!(again.reused, 2);
    for (a, b) in run.packings.iter().zip(&again.packings) {
        assert!(b.measures.gaps.is_some(), "{}: measured again", b.id);
        let (ma, mb) = (a.measures.moduli.as_ref(), b.measures.moduli.as_ref());
        let (ma, mb) = (&ma.unwrap().moduli, &mb.unwrap().moduli);
        assert_eq!(ma.shear.to_bits(), mb.shear.to_bits(), "{}: G", a.id);
        assert_eq!(ma.bulk.to_bits(), mb.bulk.to_bits(), "{}: B", a.id);
        // Every field (Debug writes each f64 to its last bit).
        assert_eq!(format!("{ma:?}"), format!("{mb:?}"), "{}", a.id);
        let (pa, pb) = (a.measures.pressure.unwrap(), b.measures.pressure.unwrap());
        assert_eq!(pa.to_bits(), pb.to_bits(), "{}: pressure", a.id);
        assert_eq!(a.measures.n_contacts, b.measures.n_contacts);
        assert_eq!(a.rattler, b.rattler);
    }
}

/// `jamkit spectrum` on a saved packing gives the eigenvalues the run
/// computed in memory (the same Hessian, K only, rattlers kept), up to the
/// round-off of storing orientations as angles: 1e-9 of λ_max.
#[test]
fn spectrum_command_reproduces_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(
        &experiment("[Contacts, Spectrum(eigenvalues: true)]"),
        dir.path(),
        2,
    );
    let id = &report.packings[0].id;
    let packing = dir.path().join(format!("packings/{id}.json"));
    let out = dir.path().join("spectrum.txt");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_jamkit"))
        .args([
            "spectrum",
            packing.to_str().unwrap(),
            "--stiffness-only",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let cli: Vec<f64> = std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    let run: Vec<f64> = csv(&dir.path().join(format!("eigenvalues/{id}.csv")))
        .iter()
        .map(|r| num(r, "lambda"))
        .collect();
    assert_eq!(cli.len(), run.len());
    assert!(cli.windows(2).all(|w| w[1] >= w[0]), "ascending");
    let max = run.last().unwrap().abs();
    for (a, b) in cli.iter().zip(&run) {
        assert!((a - b).abs() < 1e-9 * max, "{a} vs {b}");
    }
    // A file that is not a packing is an error with a message, not a panic.
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_jamkit"))
        .args(["spectrum", "Cargo.toml", "-o", "-"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(1));
    assert!(err.contains("not a jamkit packing file"), "{err}");
}
