//! FIRE's time step against the stability limit of the packings it makes,
//! and what a failed minimisation leaves behind.

use crate::common;

use common::{run_into, run_ok};
use jamkit_core::Shape;
use jamkit_engine::{Objective, Scene};
use jamkit_experiment::Experiment;
use jamkit_experiment::reload::{PackingVisitor, reload};
use jamkit_experiment::runner::failed_path;
use jamkit_format::PackingFile;
use jamkit_observe::hessian::{Hessian, HessianOptions};
use jamkit_observe::spectrum::omega_max_sq;

fn experiment(family: &str, dim: usize, params: &str, extra: &str) -> Experiment {
    let text = format!(
        r#"(name: "steps", dim: {dim}, family: "{family}", params: {{ {params} }},
            sizes: Binary(small: 0.5, large: 0.7), particles: 64, samples: 1,
            protocol: Jam(phi_start: 0.1, eps: 1e-3, energy_low: 1e-16, energy_high: 2e-16),
            rattlers: (min_contacts: None), observables: [Contacts] {extra})"#
    );
    Experiment::from_ron(&text, "inline").unwrap()
}

/// `ω_max²`, the largest eigenvalue of `M^{-1/2} H M^{-1/2}` (translations of
/// unit mass, rotations of the family's inertia): the stiffest vibration
/// FIRE's Euler step must follow.
struct OmegaMaxSq;

impl PackingVisitor for OmegaMaxSq {
    type Output = f64;
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> f64 {
        let h = Hessian::of_scene(&mut scene, &[], HessianOptions::default()).unwrap();
        omega_max_sq(&h, scene.inverse_masses()).unwrap()
    }
}

/// The default `dt_max` (the family's, recorded in the packing's settings)
/// sits at most at 0.82 of the semi-implicit Euler step's stability limit
/// `2/ω_max` on a jammed packing of each kind. 0.82 separates what was
/// measured (docs/reports/sanity.md): FIRE stalled for 10⁵–10⁶ steps in
/// single minimisations at 0.86–0.87 (3D dimers with `dt_max` 0.5) and
/// converged on every packing at 0.58–0.62 (disks, spheres), 0.79–0.80
/// (2D dimers, 30 of 30 at N = 512) and 0.6 (3D dimers with 0.35, 30 of
/// 30). The 3D
/// dimers' own `ω_max` is why they take a smaller step: with 0.5 they
/// would sit above 0.83 of their limit.
#[test]
fn default_time_steps_sit_well_below_the_stability_limit() {
    let cases = [
        ("sphere", 2, "", 0.5),
        ("sphere", 3, "", 0.5),
        ("nmer", 2, r#""alpha": 1.5"#, 0.5),
        ("nmer", 3, r#""alpha": 1.5"#, 0.35),
    ];
    for (family, dim, params, expected_dt) in cases {
        let e = experiment(family, dim, params, "");
        let dir = tempfile::tempdir().unwrap();
        let report = run_ok(&e, dir.path(), 1);
        let p = &report.packings[0];
        let dt_max = p.settings["minimizer"]["dt_max"].as_f64().unwrap();
        assert_eq!(dt_max, expected_dt, "{family} {dim}D: recorded dt_max");
        let omega_sq = reload(p, OmegaMaxSq).unwrap();
        let ratio = dt_max * omega_sq.sqrt() / 2.0;
        assert!(
            ratio <= 0.82,
            "{family} {dim}D: dt_max = {dt_max} is {ratio:.3} of 2/ω_max (ω_max² = {omega_sq:.3})"
        );
        if family == "nmer" && dim == 3 {
            let old = 0.5 * omega_sq.sqrt() / 2.0;
            assert!(
                old > 0.83,
                "3D dimers: 0.5 would be {old:.3} of 2/ω_max (ω_max² = {omega_sq:.3}); expected the stiff multi-contact modes"
            );
        }
    }
}

/// A sample whose minimisation hits the step cap leaves the configuration
/// it stopped at in `<id>.failed.json` (loadable, flagged with the error,
/// every body's centre there), the error says where it is, and a rerun
/// that succeeds removes it.
#[test]
fn a_failed_sample_keeps_its_configuration_until_a_rerun_succeeds() {
    let dir = tempfile::tempdir().unwrap();
    let capped = experiment("nmer", 2, r#""alpha": 1.5"#, ", minimizer: (max_steps: 50)");
    let report = run_into(&capped, dir.path(), 1);
    assert_eq!(report.failures.len(), 1);
    let message = report.failures[0].to_string();
    let path = failed_path(&dir.path().join("packings"), "nmer_d2_N64_alpha1.5_s1");
    assert!(
        message.contains(&path.display().to_string()),
        "the error names the saved file: {message}"
    );
    let failed = PackingFile::load_checked(&path).unwrap();
    assert!(failed.measures.flag.contains("did not converge"));
    assert_eq!(failed.positions.len(), 64);
    assert_eq!(failed.orientations.len(), 64);
    assert!(failed.phi > 0.1 - 1e-12, "φ = {}", failed.phi);
    // The saved configuration is a scene again.
    assert!(reload(&failed, OmegaMaxSq).unwrap().is_finite());

    let full = experiment("nmer", 2, r#""alpha": 1.5"#, "");
    run_ok(&full, dir.path(), 1);
    assert!(
        !path.exists(),
        "a successful rerun removes the stale failed state"
    );
}

/// A jamming search that gives up (here: too few density changes allowed)
/// also leaves the configuration it reached, flagged with the error.
#[test]
fn a_failed_jamming_search_keeps_its_configuration() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"(name: "steps", family: "sphere", particles: 32, samples: 1,
        protocol: Jam(phi_start: 0.1, eps: 1e-3, energy_low: 1e-16, energy_high: 2e-16, max_density_steps: 5))"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    let report = run_into(&e, dir.path(), 1);
    assert_eq!(report.failures.len(), 1);
    let message = report.failures[0].to_string();
    assert!(message.contains("jamming search failed"), "{message}");
    let path = failed_path(&dir.path().join("packings"), "sphere_d2_N32_s1");
    assert!(message.contains(&path.display().to_string()), "{message}");
    let failed = PackingFile::load_checked(&path).unwrap();
    assert!(failed.measures.flag.contains("jamming search failed"));
    assert_eq!(failed.positions.len(), 32);
    // Five compressions of ε = 10⁻³ from φ = 0.1 (none reversed: V = 0).
    assert!((failed.phi - 0.105).abs() < 1e-9, "φ = {}", failed.phi);
}
