//! The extrapolated jamming searches (`protocol.search: Extrapolated`, and
//! `Adaptive`, the default): the slope they extrapolate with is the
//! derivative of the relaxed energy (finite differences), one leap lands
//! where `V/N ∝ (φ − φ_J)²` says, the searches end in the paper's window,
//! and `Adaptive` is the default, with the paper's `Bisection` left out of
//! recorded settings.

use jamkit_core::{Potential, Shape};
use jamkit_engine::{
    Fire, FireParams, JamParams, JamSearch, Objective, Scene, energy_slope, extrapolated_step, jam,
};
use jamkit_experiment::{Experiment, Plan};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_sphere::Sphere;

use crate::common;
use common::compressed;

/// Two packings of 16 disks (seed 3) with `fields` added to the file
/// (each starting with a comma): the run directories of the resume tests.
fn old_disks(fields: &str) -> Experiment {
    let text = format!(
        r#"(name: "old", family: "sphere", dim: 2, particles: 16, samples: 2, seed: 3{fields})"#
    );
    Experiment::from_ron(&text, "inline").unwrap()
}

/// The recorded settings of an experiment's first packing.
fn settings(e: &Experiment) -> serde_json::Value {
    Plan::new(e).unwrap().jobs[0].settings.clone()
}

/// `new`'s run refuses `old`'s packings, made with `key` off where today's
/// default is on (they record none), naming `key`, both values and the fix
/// (`--set set=false`), and resumes them with that fix.
fn refused_then_resumed_as_off(old: &Experiment, new: &Experiment, key: &str, set: &str) {
    common::refused_then_resumed(
        old,
        new,
        &[
            key,
            "true",
            "false (not written; the default before true",
            &format!("--set {set}=false"),
        ],
    );
}

fn near_disk() -> NearDisk {
    NearDisk::fourier(&FourierParams {
        n: 2,
        delta: 0.1,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap()
}

/// `V/N` after relaxing at `phi`, starting from `scene`'s state.
fn relaxed_energy<const D: usize, S: Shape<D>>(scene: &Scene<D, S>, phi: f64) -> f64 {
    let mut s = scene.clone();
    s.set_phi(phi);
    let out = Fire::new(FireParams::paper()).minimize(&mut s).unwrap();
    out.energy / s.bodies() as f64
}

/// `energy_slope` of a relaxed, jammed state equals the central difference
/// of the relaxed `V/N` at `φ ± h`.
///
/// Tolerance 10⁻⁴ relative: the difference's own error is
/// `O((h / (φ − φ_J))²) ≈ 10⁻⁸` here, the minimisations' residual
/// (`Σ g² < 10⁻²⁵`) moves `V/N ~ 10⁻⁴` by far less; a slope that left out
/// the box's scaling or counted `V` instead of `V/N` would be off by O(1).
fn check_slope<const D: usize, S: Shape<D>>(shape: S, phi: f64) {
    let mut scene = compressed::<D, S>(shape, 32, 7, phi);
    Fire::new(FireParams::paper()).minimize(&mut scene).unwrap();
    let e = relaxed_energy(&scene, phi);
    assert!(e > 1e-6, "the state must be jammed: V/N = {e:e}");
    let slope = energy_slope(&mut scene);
    let h = 1e-6;
    let fd = (relaxed_energy(&scene, phi + h) - relaxed_energy(&scene, phi - h)) / (2.0 * h);
    let rel = (slope - fd).abs() / fd.abs();
    assert!(
        rel < 1e-4,
        "slope {slope:e} against FD {fd:e} (relative {rel:e})"
    );
}

#[test]
fn slope_is_the_derivative_of_the_relaxed_energy_disks() {
    check_slope::<2, _>(Sphere, 0.9);
}

#[test]
fn slope_is_the_derivative_of_the_relaxed_energy_3d_spheres() {
    check_slope::<3, _>(Sphere, 0.7);
}

#[test]
fn slope_is_the_derivative_of_the_relaxed_energy_near_disks() {
    check_slope::<2, _>(near_disk(), 0.92);
}

/// One leap from a slightly compressed packing (`V/N ≈ 10⁻¹⁰`) to
/// `V/N = 10⁻¹²` lands within 5 % of it, for the harmonic (`α = 2`) and
/// the Hertzian (`α = 5/2`) potential: the model's error is
/// `O(φ − φ_J) ≈ 10⁻⁵` relative and the contact network does not change
/// over so short a way; the other potential's exponent, or `V` for `V/N`,
/// would miss by 50 % or more.
fn check_leap(potential: Potential) {
    let mut scene = compressed::<2, _>(Sphere, 64, 3, 0.1);
    scene = Scene::new(scene.packing().clone(), potential, 0.2);
    let mut fire = Fire::new(FireParams::paper());
    let params = JamParams {
        energy_low: 1e-10,
        energy_high: 2e-10,
        ..JamParams::default()
    };
    jam(&mut scene, &mut fire, &params).unwrap();
    let phi = scene.phi();
    let e = relaxed_energy(&scene, phi);
    let target = 1e-12;
    let step = extrapolated_step(&mut scene, e, target).unwrap();
    let landed = relaxed_energy(&scene, phi + step);
    assert!(
        (landed / target - 1.0).abs() < 0.05,
        "{potential:?}: V/N {e:e} at φ = {phi}, step {step:e}: landed at {landed:e}, aimed at {target:e}"
    );
}

#[test]
fn one_leap_lands_where_the_model_says_harmonic() {
    check_leap(Potential::Harmonic);
}

#[test]
fn one_leap_lands_where_the_model_says_hertzian() {
    check_leap(Potential::Hertzian);
}

/// Both searches end in the paper's window, on disks and near-disks; the
/// extrapolated one with fewer minimisations in all (it replaces the
/// bisection's halvings above φ_J by one leap per two decades of `V/N`).
#[test]
fn extrapolated_search_ends_in_the_window_in_fewer_minimisations() {
    fn run<const D: usize, S: Shape<D>>(shape: S, seed: u64, search: JamSearch) -> (f64, f64, u64) {
        let mut scene = compressed::<D, S>(shape, 64, seed, 0.1);
        let mut fire = Fire::new(FireParams::default().for_family(&scene.packing().shape));
        let params = JamParams {
            search,
            ..JamParams::default()
        };
        let out = jam(&mut scene, &mut fire, &params).unwrap();
        (out.phi, out.energy_per_particle, out.work.minimizations)
    }
    let window = JamParams::default();
    let (mut paper, mut leaps) = (0, 0);
    for seed in 1..=4 {
        for (phi, e, m, search) in [
            {
                let (p, e, m) = run::<2, _>(Sphere, seed, JamSearch::Bisection);
                (p, e, m, "disks, bisection")
            },
            {
                let (p, e, m) = run::<2, _>(Sphere, seed, JamSearch::Extrapolated);
                (p, e, m, "disks, extrapolated")
            },
            {
                let (p, e, m) = run::<2, _>(near_disk(), seed, JamSearch::Bisection);
                (p, e, m, "near-disks, bisection")
            },
            {
                let (p, e, m) = run::<2, _>(near_disk(), seed, JamSearch::Extrapolated);
                (p, e, m, "near-disks, extrapolated")
            },
            {
                let (p, e, m) = run::<2, _>(near_disk(), seed, JamSearch::Adaptive);
                (p, e, m, "near-disks, adaptive")
            },
        ] {
            assert!(
                e > window.energy_low && e < window.energy_high,
                "{search}, seed {seed}: V/N = {e:e} at φ = {phi}"
            );
            if search.ends_with("bisection") {
                paper += m;
            } else if search.ends_with("extrapolated") {
                leaps += m;
            }
        }
    }
    assert!(
        leaps < paper,
        "minimisations: extrapolated {leaps}, bisection {paper}"
    );
}

/// `Adaptive` is the default (its ensembles are the bisection's:
/// docs/reports/minimizers.md, "The defaults against the paper's path").
/// `experiment.ron` always names the search, so a run
/// directory reads back as the search it was made with; a packing's
/// recorded settings leave out `search: Bisection`, as packings made before
/// the field existed (all bisection packings) record nothing, so that those
/// still resume under an explicit `Bisection`, and never under the default.
#[test]
fn adaptive_is_the_default_and_bisection_is_left_out_of_settings() {
    assert_eq!(JamParams::default().search, JamSearch::Adaptive);
    let protocol = |search: &str| {
        let text = format!(
            r#"(name: "s", family: "sphere", dim: 2, particles: 8, samples: 1, seed: 1{search})"#
        );
        let e = Experiment::from_ron(&text, "inline").unwrap();
        let settings = Plan::new(&e).unwrap().jobs[0].settings.clone();
        let written = ron::ser::to_string(&e).unwrap();
        (settings["protocol"]["Jam"].get("search").cloned(), written)
    };
    let (default, written) = protocol("");
    assert_eq!(default, Some(serde_json::json!("Adaptive")));
    assert!(written.contains("search:Adaptive"), "{written}");
    let (explicit, written) = protocol(", protocol: Jam(search: Adaptive)");
    assert_eq!(explicit, default);
    assert!(written.contains("search:Adaptive"), "{written}");
    let (extrapolated, written) = protocol(", protocol: Jam(search: Extrapolated)");
    assert_eq!(extrapolated, Some(serde_json::json!("Extrapolated")));
    assert!(written.contains("search:Extrapolated"), "{written}");
    let (bisection, written) = protocol(", protocol: Jam(search: Bisection)");
    assert_eq!(bisection, None, "bisection settings name no search");
    assert!(written.contains("search:Bisection"), "{written}");
    let back = Experiment::from_ron(&written, "experiment.ron").unwrap();
    assert_eq!(ron::ser::to_string(&back).unwrap(), written);
    let err = ron::from_str::<JamParams>("(search: Halving)").unwrap_err();
    assert!(err.to_string().contains("Halving"), "{err}");
}

/// A run directory of bisection packings (as every run made before the
/// extrapolated searches existed) is refused under the default, with
/// the search named and the fix said, and resumed under an explicit
/// `search: Bisection`. (The default search also brings the unjamming
/// forecast, which such packings lack; it is off on both sides here: the
/// search is the one difference, and the forecast has its own test.)
#[test]
fn bisection_packings_are_refused_under_the_default_and_resume_as_bisection() {
    let experiment = old_disks;
    common::refused_then_resumed(
        &experiment(", protocol: Jam(search: Bisection)"),
        &experiment(", minimizer: (unjam_forecast: false)"),
        &[
            "protocol.Jam.search",
            "\"Adaptive\"",
            "\"Bisection\" (not written",
            "add `search: Bisection`",
        ],
    );
}

/// A run directory of packings of the `Extrapolated` search (jamkit's
/// default before `Adaptive`) is refused under the default, with the
/// search named and the fix said, and resumed under an explicit
/// `search: Extrapolated`.
#[test]
fn extrapolated_packings_are_refused_under_the_default_and_resume_as_extrapolated() {
    let experiment = old_disks;
    common::refused_then_resumed(
        &experiment(", protocol: Jam(search: Extrapolated)"),
        &experiment(""),
        &[
            "protocol.Jam.search",
            "\"Adaptive\"",
            "\"Extrapolated\" (the default before \"Adaptive\"",
            "--set protocol.search=Extrapolated",
        ],
    );
}

/// A run directory of `AboveJam` packings made under `rejams: 0` (jamkit's
/// default before 2; they record no `rejams`) is refused under the
/// default, with the field named and the fix said, and resumed under an
/// explicit `rejams: 0`.
#[test]
fn above_jam_packings_without_rejams_are_refused_under_the_default_and_resume_as_zero() {
    let experiment = |rejams: &str| {
        let text = format!(
            r#"(name: "old", family: "sphere", dim: 2, particles: 16, samples: 1, seed: 3,
            protocol: AboveJam(delta_phi: 1e-2{rejams}))"#
        );
        Experiment::from_ron(&text, "inline").unwrap()
    };
    common::refused_then_resumed(
        &experiment(", rejams: 0"),
        &experiment(""),
        &[
            "protocol.AboveJam.rejams",
            "2",
            "0 (not written; the default before 2",
            "--set protocol.rejams=0",
        ],
    );
}

/// A run directory of jamming packings made without the unjamming
/// forecast (jamkit's default before it; they record no `unjam_forecast`)
/// is refused under the default, with the field named and the fix said,
/// and resumed under an explicit `unjam_forecast: false`. Where the
/// forecast does not act (the paper's bisection, `Phi`), the settings are
/// the same with it on and off, so such packings resume under the default.
#[test]
fn packings_without_the_unjamming_forecast_are_refused_where_it_acts_and_resume_as_off() {
    let experiment = |protocol: &str, minimizer: &str| {
        old_disks(&format!(", protocol: {protocol}, minimizer: ({minimizer})"))
    };
    refused_then_resumed_as_off(
        &experiment("Jam()", "unjam_forecast: false"),
        &experiment("Jam()", ""),
        "minimizer.unjam_forecast",
        "minimizer.unjam_forecast",
    );
    for protocol in ["Jam(search: Bisection)", "Phi(phi: 0.5)"] {
        assert_eq!(
            settings(&experiment(protocol, "unjam_forecast: false")),
            settings(&experiment(protocol, "")),
            "{protocol}"
        );
    }
    assert_ne!(
        settings(&experiment(
            "AboveJam(delta_phi: 1e-2)",
            "unjam_forecast: false"
        )),
        settings(&experiment("AboveJam(delta_phi: 1e-2)", ""))
    );
}

/// A run directory of packings made without the plateau escape (jamkit's
/// default before it; they record no `escape_plateaus`) is refused under
/// the default, with the field named and the fix said, and resumed under
/// an explicit `escape_plateaus: false`. Without the Newton finish (the
/// paper's path) it does not act, and the settings are the same with it on
/// and off.
#[test]
fn packings_without_the_plateau_escape_are_refused_where_it_acts_and_resume_as_off() {
    let experiment =
        |minimizer: &str, more: &str| old_disks(&format!(", minimizer: ({minimizer}){more}"));
    refused_then_resumed_as_off(
        &experiment("escape_plateaus: false", ""),
        &experiment("", ""),
        "minimizer.escape_plateaus",
        "minimizer.escape_plateaus",
    );
    assert_eq!(
        settings(&experiment("newton: None", "")),
        settings(&experiment("newton: None, escape_plateaus: false", ""))
    );
    assert_eq!(
        settings(&experiment("", ", paper_path: true")),
        settings(&experiment("escape_plateaus: false", ", paper_path: true"))
    );
    assert!(
        settings(&experiment("", ""))
            .to_string()
            .contains("escape_plateaus")
    );
}

/// A run directory of packings made without the check of `Δt_max` against
/// the stiffest mode (jamkit's default before it; they record no
/// `stable_dt`) is refused under the default, with the field named and the
/// fix said, and resumed under an explicit `stable_dt: false`;
/// `paper_path: true` records none, so the paper path's packings keep
/// their settings.
#[test]
fn packings_without_the_stable_dt_check_are_refused_under_the_default_and_resume_as_off() {
    let experiment =
        |minimizer: &str, more: &str| old_disks(&format!(", minimizer: ({minimizer}){more}"));
    refused_then_resumed_as_off(
        &experiment("stable_dt: false", ""),
        &experiment("", ""),
        "minimizer.stable_dt",
        "minimizer.stable_dt",
    );
    assert_eq!(
        settings(&experiment("", ", paper_path: true")),
        settings(&experiment("stable_dt: false", ", paper_path: true"))
    );
    assert!(
        settings(&experiment("", ""))
            .to_string()
            .contains("stable_dt")
    );
}

/// A run directory of jamming packings made without the saddle escape
/// (jamkit's default before it; they record no `escape_saddles`) is refused
/// under the default, with the field named and the fix said, and resumed
/// under an explicit `escape_saddles: false`; `paper_path: true` records no
/// escape either, so the paper path's packings keep their settings.
#[test]
fn packings_without_the_saddle_escape_are_refused_under_the_default_and_resume_as_off() {
    let experiment =
        |protocol: &str, more: &str| old_disks(&format!(", protocol: {protocol}{more}"));
    refused_then_resumed_as_off(
        &experiment("Jam(escape_saddles: false)", ""),
        &experiment("Jam()", ""),
        "protocol.Jam.escape_saddles",
        "protocol.escape_saddles",
    );
    assert_eq!(
        settings(&experiment("Jam()", ", paper_path: true")),
        settings(&experiment(
            "Jam(escape_saddles: false, search: Bisection)",
            ", paper_path: true"
        ))
    );
    assert!(
        !settings(&experiment("Jam()", ", paper_path: true"))
            .to_string()
            .contains("escape_saddles")
    );
    assert!(
        settings(&experiment("Jam()", ""))
            .to_string()
            .contains("escape_saddles")
    );
}
