//! The `harmonic` family (3D near-spheres with spherical-harmonic modes)
//! in the engine: the conformance kit over single modes (axisymmetric or
//! not, low and high degree) and a mixed sum; the energy's invariance
//! under a general rotation of a cluster (the kit turns about the z axis
//! only, and skips bodies with two rotational coordinates); Δ = 0 as the
//! sphere family, bit for bit; the rattler convention and the isostatic
//! count with the body's real coordinates; the shipped experiment.
//! The pair-level checks (every first and second derivative against finite
//! differences near ±Q e_z and generic, h_ij = h_ji, the printed formula,
//! volume, asphericity) are the crate's unit tests.

use crate::common;

use jamkit_core::Shape;
use jamkit_core::gap_model::GapModel;
use jamkit_harmonic::{ExactSolver, Harmonic, HarmonicParams, Mode};

fn single(l: u32, m: i32, delta: f64) -> Harmonic {
    Harmonic::single(l, m, delta).unwrap()
}

fn mixed(delta: f64) -> Harmonic {
    Harmonic::new(&HarmonicParams {
        l: None,
        m: None,
        modes: Some(vec![
            Mode { l: 2, m: 0, c: 1.0 },
            Mode {
                l: 2,
                m: 1,
                c: -0.3,
            },
            Mode {
                l: 4,
                m: -2,
                c: 0.5,
            },
            Mode { l: 6, m: 3, c: 0.2 },
        ]),
        delta,
        inertia: None,
        gap: Default::default(),
        exact_solver: Default::default(),
    })
    .unwrap()
}

/// The kit's forces and torques, Hessian (central differences of the
/// analytic gradient on dense overlapping configurations) and
/// `h_ij = h_ji` (tolerances and their reasons in `crates/kit`) for
/// single modes l = 2…6, zonal (two rotational coordinates) and not
/// (three), and a mixed sum; the whole kit (with a jamming run and the
/// rotation about z) for one non-axisymmetric mode.
#[test]
fn modes_and_sums_pass_the_kit() {
    for shape in [
        single(2, 0, 0.2),
        single(2, 2, 0.2),
        single(3, -1, 0.15),
        single(4, 0, 0.1),
        single(6, -5, 0.1),
        mixed(0.15),
    ] {
        jamkit_kit::check_gradient::<3, _>(&shape);
        assert!(jamkit_kit::check_hessian::<3, _>(&shape));
        jamkit_kit::check_symmetry::<3, _>(&shape);
    }
    let done = jamkit_kit::check_family::<3, _>(single(3, 2, 0.2));
    for check in ["gradient", "hessian", "symmetry", "rotation", "jamming"] {
        assert!(done.ran.contains(&check), "{check}: {done:?}");
    }
}

/// The exact gap (`gap: "Exact"`, read through the registry) in the
/// engine: the kit's forces and torques, Hessian, `h_ij = h_ji`,
/// translation and rotation about z (tolerances in `crates/kit`) for a
/// zonal and a tesseral mode and a mixed sum, the last two also with
/// `exact_solver: "Joint"`, and the energy's invariance under a general
/// rotation. The kit's jamming run is left out: with the
/// exact gap it takes ~2 min on one core (~30× the first-order run);
/// the pair-level checks are the crate's unit tests (`exact_tests.rs`).
#[test]
fn the_exact_gap_passes_the_kit() {
    let parse = |json: &str| {
        let map = jamkit_registry::params_from_json(&serde_json::from_str(json).unwrap()).unwrap();
        let p: HarmonicParams = jamkit_registry::parse_params("harmonic", &map).unwrap();
        assert_eq!(p.gap, GapModel::Exact);
        Harmonic::new(&p).unwrap()
    };
    let joint = |h: Harmonic| {
        assert_eq!(h.exact_solver(), ExactSolver::Joint);
        h
    };
    for shape in [
        parse(r#"{"l": 2, "m": 0, "delta": 0.2, "gap": "Exact"}"#),
        parse(r#"{"l": 3, "m": 2, "delta": 0.1, "gap": "exact"}"#),
        parse(
            r#"{"modes": [{"l": 2, "m": 0, "c": 1.0}, {"l": 4, "m": -2, "c": 0.5}], "delta": 0.08, "gap": "Exact"}"#,
        ),
        joint(parse(
            r#"{"l": 3, "m": 2, "delta": 0.1, "gap": "Exact", "exact_solver": "Joint"}"#,
        )),
        joint(parse(
            r#"{"modes": [{"l": 2, "m": 0, "c": 1.0}, {"l": 4, "m": -2, "c": 0.5}], "delta": 0.08, "gap": "Exact", "exact_solver": "joint"}"#,
        )),
    ] {
        jamkit_kit::check_gradient::<3, _>(&shape);
        assert!(jamkit_kit::check_hessian::<3, _>(&shape));
        jamkit_kit::check_symmetry::<3, _>(&shape);
        jamkit_kit::check_translation::<3, _>(&shape);
        if !shape.is_axisymmetric() {
            assert!(jamkit_kit::check_rotation::<3, _>(&shape));
        }
        common::check_general_rotation(shape);
    }
}

/// A compact overlapping cluster turned by a rotation about a skew axis
/// (centres about the middle, every orientation `Q → U Q`) keeps its
/// energy to 1e-12 relative (only the order of round-off changes):
/// zonal, tesseral and mixed `F`.
#[test]
fn energy_is_invariant_under_a_general_rotation() {
    for shape in [single(2, 0, 0.25), single(3, 2, 0.2), mixed(0.2)] {
        common::check_general_rotation(shape);
    }
}

/// Δ = 0 is the sphere family: the same packings for the same seeds, bit
/// for bit, with no orientations.
#[test]
fn delta_zero_reproduces_the_sphere_packing() {
    let text = |family: &str| {
        format!(r#"(name: "z", dim: 3, family: {family}, particles: 32, samples: 2, seed: 4)"#)
    };
    let spheres = common::run_inline(&text(r#""sphere""#));
    let near = common::run_inline(&text(
        r#""harmonic", params: {"l": 3, "m": 1, "delta": 0.0}"#,
    ));
    assert_eq!(spheres.len(), 2);
    common::assert_sphere_packings(&spheres, &near);
}

/// The rattler convention and the isostatic count, recomputed from the
/// packing file alone: contacts are the pairs with a negative first-order
/// gap (minimum image), bodies with fewer than d + 1 = 4 contacts are
/// removed until none is left, and the remaining set must be the file's
/// non-rattlers with its contact count; the margin is
/// `N_c − (f N_nr − 3)` with `f = 3 + 2` for a zonal mode and `3 + 3`
/// otherwise. Packings of N = 64 at Δ = 0.2, one seed each.
#[test]
fn rattlers_and_the_isostatic_count_use_the_real_coordinates() {
    for (params, f) in [
        (r#"{"l": 2, "m": 0, "delta": 0.2}"#, 5),
        (r#"{"l": 2, "m": 2, "delta": 0.2}"#, 6),
    ] {
        let (p, map) = common::packing_with_params_3d("harmonic", params);
        let shape: HarmonicParams = jamkit_registry::parse_params("harmonic", &map).unwrap();
        let shape = Harmonic::new(&shape).unwrap();
        assert_eq!(Shape::<3>::rot_dof(&shape) + 3, f);
        common::check_counts_from_file(&shape, &p);
    }
}

/// `experiments/paper3d/quick.ron`, shrunk to N = 64 (32 bodies make the
/// box at Δ = 0.3 shorter than twice the interaction range, which the
/// runner refuses) and one sample per Δ,
/// jams every packing into the paper's window 1e-16 < V/N < 2e-16.
#[test]
fn quick_experiment_jams() {
    let report = common::run_file(
        "experiments/paper3d/quick.ron",
        &["particles=64", "samples=1"],
        2,
    );
    assert_eq!(report.packings.len(), 5, "one packing per Δ");
    for p in &report.packings {
        common::assert_in_window(p);
    }
}

/// `exact_solver` read through the registry: absent is `"Nested"` (what a
/// packing that records none was made with; an experiment's grid fills in
/// the default `"Joint"`), a string names the solver (case ignored); a wrong name
/// and a bare RON identifier (of the solver or of the gap) are refused
/// naming the field or what is allowed.
#[test]
fn the_exact_solver_is_read_and_checked() {
    let read = |text: &str| {
        let map = jamkit_registry::params_from_ron(text).unwrap();
        let p: HarmonicParams = jamkit_registry::parse_params("harmonic", &map).unwrap();
        Harmonic::new(&p).unwrap().exact_solver()
    };
    assert_eq!(
        read("(l: 2, delta: 0.1, gap: \"Exact\")"),
        ExactSolver::Nested
    );
    assert_eq!(
        read("(l: 2, delta: 0.1, gap: \"Exact\", exact_solver: \"joint\")"),
        ExactSolver::Joint
    );
    jamkit_kit::check_bad_params(
        "harmonic",
        3,
        &[
            (
                "(l: 2, delta: 0.1, gap: \"Exact\", exact_solver: \"Jointly\")",
                "\"Nested\", \"Joint\"",
            ),
            (
                "(l: 2, delta: 0.1, gap: \"Exact\", exact_solver: Joint)",
                "exact_solver",
            ),
            // The gap's bare identifier goes through the same reader.
            (
                "(l: 2, delta: 0.1, gap: Exact)",
                "write the gap model as a string",
            ),
        ],
    );
}

/// An experiment that does not give `exact_solver` runs the default
/// `"Joint"`, and its packing records it (label and `params`); one that
/// gives `"Nested"` records none, as packings written before the parameter
/// existed. Each record reads back as the solver that made it.
#[test]
fn packings_record_the_exact_solver_only_where_it_is_not_nested() {
    let run = |extra: &str| {
        common::run_inline(&format!(
            r#"(name: "s", dim: 3, family: "harmonic", params: {{"l": 2, "delta": 0.1, "gap": "Exact"{extra}}}, particles: 32, samples: 1, seed: 1, protocol: Phi(phi: 0.1), observables: [Contacts])"#
        ))
        .remove(0)
    };
    let solver = |p: &jamkit_format::PackingFile| {
        let map = jamkit_registry::params_from_json(&p.params).unwrap();
        let params: HarmonicParams = jamkit_registry::parse_params("harmonic", &map).unwrap();
        Harmonic::new(&params).unwrap().exact_solver()
    };
    let joint = run("");
    assert_eq!(joint.params["exact_solver"], "Joint");
    assert!(joint.id.contains("exact_solver_Joint"), "{}", joint.id);
    assert_eq!(solver(&joint), ExactSolver::Joint);
    let nested = run(r#", "exact_solver": "Nested""#);
    assert!(nested.params.get("exact_solver").is_none());
    assert!(!nested.id.contains("exact_solver"), "{}", nested.id);
    assert_eq!(solver(&nested), ExactSolver::Nested);
}
