//! The `ellipsoid` family (3D, exact support-function gap) in the engine:
//! the conformance kit over prolate, oblate, near-spherical and triaxial
//! bodies; the energy's invariance under a general rotation of a cluster
//! (the kit turns about the z axis only, and skips bodies with two
//! rotational coordinates); α = 1 as the sphere family, bit for bit; the
//! rattler convention and the isostatic count with the body's real
//! coordinates; the shipped example experiment. The pair-level checks
//! (every first and second derivative against finite differences,
//! h_ij = h_ji, the brute-force scan of directions, the distance of the
//! surfaces, the sphere limit) are the crate's unit tests.

use crate::common;

use jamkit_core::Shape;
use jamkit_ellipsoid::{Ellipsoid, EllipsoidParams};
use jamkit_experiment::{Experiment, overrides};
use std::path::Path;

fn spheroid(alpha: f64) -> Ellipsoid {
    Ellipsoid::spheroid(alpha).unwrap()
}

fn triaxial(axes: [f64; 3]) -> Ellipsoid {
    Ellipsoid::triaxial(axes).unwrap()
}

/// The kit's forces and torques, Hessian (central differences of the
/// analytic gradient on dense overlapping configurations, φ = 0.9) and
/// `h_ij = h_ji` (tolerances and their reasons in `crates/kit`) for the
/// bodies the conformance test (`tests/conformance.rs`: α = 1.5, 1.2, 0.5
/// and a triaxial body, with the whole kit) leaves out: nearly round
/// (α = 1.05), long (α = 3), flat (α = 1/3) and strongly triaxial.
#[test]
fn spheroids_and_triaxial_bodies_pass_the_kit() {
    for shape in [
        spheroid(1.05),
        spheroid(3.0),
        spheroid(1.0 / 3.0),
        triaxial([0.5, 1.0, 2.0]),
    ] {
        jamkit_kit::check_gradient::<3, _>(&shape);
        assert!(jamkit_kit::check_hessian::<3, _>(&shape));
        jamkit_kit::check_symmetry::<3, _>(&shape);
    }
}

/// A compact overlapping cluster turned by a rotation about a skew axis
/// (centres about the middle, every orientation `Q → U Q`) keeps its
/// energy to 1e-12 relative (only the order of round-off changes):
/// prolate, oblate and triaxial bodies.
#[test]
fn energy_is_invariant_under_a_general_rotation() {
    for shape in [spheroid(1.8), spheroid(0.5), triaxial([1.0, 1.4, 2.2])] {
        common::check_general_rotation(shape);
    }
}

/// α = 1 (and three equal ratios) is the sphere family: the same packings
/// for the same seeds, bit for bit, with no orientations.
#[test]
fn alpha_one_reproduces_the_sphere_packing() {
    let text = |family: &str| {
        format!(r#"(name: "z", dim: 3, family: {family}, particles: 32, samples: 2, seed: 4)"#)
    };
    let spheres = common::run_inline(&text(r#""sphere""#));
    assert_eq!(spheres.len(), 2);
    for params in [r#"{"alpha": 1.0}"#, r#"{"axes": [1.5, 1.5, 1.5]}"#] {
        let round = common::run_inline(&text(&format!(r#""ellipsoid", params: {params}"#)));
        common::assert_sphere_packings(&spheres, &round);
    }
}

/// The rattler convention and the isostatic count, recomputed from the
/// packing file alone: contacts are the pairs with a negative exact gap
/// (minimum image), bodies with fewer than d + 1 = 4 contacts are removed
/// until none is left, and the remaining set must be the file's
/// non-rattlers with its contact count; the margin is `N_c − (f N_nr − 3)`
/// with `f = 3 + 2` for a spheroid and `3 + 3` for a triaxial body, and it
/// is negative (ellipsoids this close to the sphere jam hypostatic).
/// Packings of N = 64, one seed each.
#[test]
fn rattlers_and_the_isostatic_count_use_the_real_coordinates() {
    for (params, f) in [
        (r#"{"alpha": 1.3}"#, 5),
        (r#"{"axes": [1.0, 1.15, 1.3]}"#, 6),
    ] {
        let (p, map) = common::packing_with_params_3d("ellipsoid", params);
        let shape: EllipsoidParams = jamkit_registry::parse_params("ellipsoid", &map).unwrap();
        let shape = Ellipsoid::new(&shape).unwrap();
        assert_eq!(Shape::<3>::rot_dof(&shape) + 3, f);
        let margin = common::check_counts_from_file(&shape, &p);
        assert!(margin < 0, "{params}: iso margin {margin}");
    }
}

/// `experiments/examples/ellipsoid.ron` (prolate α = 1.5 and oblate
/// α = 0.6, N = 64), one sample per α, jams every packing into the paper's
/// window 1e-16 < V/N < 2e-16, above the random close packing of spheres
/// (φ_J ≈ 0.64 at this N: ellipsoids pack denser, Donev et al. 2004).
#[test]
fn example_experiment_jams() {
    let report = common::run_file("experiments/examples/ellipsoid.ron", &["samples=1"], 2);
    assert_eq!(report.packings.len(), 2, "one packing per α");
    for p in &report.packings {
        common::assert_in_window(p);
        assert!(p.phi > 0.65 && p.phi < 0.75, "{}: φ = {}", p.id, p.phi);
    }
}

/// `--set params.alpha=…` reaches the family, and a value out of range is
/// refused with the field named.
#[test]
fn parameters_can_be_set_from_the_command_line() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/examples/ellipsoid.ron");
    let e = Experiment::from_file(&file).unwrap();
    for set in [
        "params.alpha=2.5",
        "params.inertia=0.5",
        "params.inertia=Some(0.5)",
    ] {
        let e = overrides::apply(&e, &[set.into()]).unwrap();
        e.validate().unwrap();
        jamkit_experiment::Plan::new(&e).unwrap_or_else(|err| panic!("{set}: {err}"));
    }
    let bad = overrides::apply(&e, &["params.alpha=0.0".into()]).unwrap();
    let err = jamkit_experiment::Plan::new(&bad)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("params.alpha"), "{err}");
}
