//! `paper_path: true`, the paper's path as one named setting: its packings
//! are those of the paper's fields set one by one (FIRE all the way with
//! plain masses and no L-BFGS, `Σ (∂V/∂q)²`, a fixed `Δt_max`, the plain
//! bisection, no saddle escape), bit for
//! bit and with the same recorded settings; it is not jamkit's default
//! path; and a file that contradicts it is refused, naming the field.

use jamkit_experiment::{Experiment, Plan, overrides};

use crate::common;

/// Near-disks (n = 2, Δ = 0.1, N = 32, one sample): a family whose
/// default masses and search differ from the paper's.
fn near_disks(sets: &[&str]) -> Experiment {
    let e = Experiment::from_ron(
        r#"(name: "p", family: "fourier", params: {"delta": 0.1}, particles: 32, seed: 3,
        observables: [Contacts])"#,
        "inline",
    )
    .unwrap();
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    overrides::apply(&e, &sets).unwrap()
}

#[test]
fn paper_path_is_the_paper_fields_set_one_by_one_bit_for_bit() {
    let named = near_disks(&["paper_path=true"]);
    let by_hand = near_disks(&[
        "minimizer.newton=None",
        "minimizer.masses=Plain",
        "minimizer.lbfgs=None",
        "minimizer.force_criterion=Sum",
        "protocol.search=Bisection",
        "protocol.escape_saddles=false",
        "minimizer.stable_dt=false",
    ]);
    let default = near_disks(&[]);
    let settings = |e: &Experiment| Plan::new(e).unwrap().jobs[0].settings.clone();
    assert_eq!(settings(&named), settings(&by_hand));
    assert_ne!(settings(&named), settings(&default));

    let (a_dir, b_dir) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let a = common::run_ok(&named, a_dir.path(), 1).packings.remove(0);
    let b = common::run_ok(&by_hand, b_dir.path(), 1).packings.remove(0);
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.orientations, b.orientations);
    assert_eq!(a.phi.to_bits(), b.phi.to_bits());
    assert_eq!(a.measures.fire_steps, b.measures.fire_steps);
    assert_eq!(a.settings, b.settings);

    // The effective experiment says what ran.
    let written = std::fs::read_to_string(a_dir.path().join("experiment.ron")).unwrap();
    for part in [
        "paper_path: true",
        "search: Bisection",
        "force_criterion: Sum",
        "newton: None",
        "lbfgs: None",
    ] {
        assert!(written.contains(part), "{part:?} missing from:\n{written}");
    }
}

#[test]
fn a_file_that_contradicts_the_paper_path_is_refused_naming_the_field() {
    for (sets, field) in [
        (
            &["paper_path=true", "minimizer.variant=Fire2"][..],
            "minimizer.variant",
        ),
        (
            &["paper_path=true", "minimizer.force_criterion=PerBody"][..],
            "minimizer.force_criterion",
        ),
        (
            &["paper_path=true", "protocol.search=Extrapolated"][..],
            "protocol.search",
        ),
        (
            &[
                "paper_path=true",
                r#"scan=[{"minimizer.newton": [None, Some(())]}]"#,
            ][..],
            "scan.minimizer.newton",
        ),
    ] {
        let e = near_disks(sets);
        let err = Plan::new(&e).err().unwrap().to_string();
        assert!(
            err.contains(field) && err.contains("paper_path"),
            "{sets:?}: {err}"
        );
    }
    // jamkit's default values and the paper's own are not contradictions.
    Plan::new(&near_disks(&[
        "paper_path=true",
        "minimizer.newton=None",
        "minimizer.force_criterion=Max",
        "protocol.search=Adaptive",
    ]))
    .unwrap();
}
