//! The stability suite, reduced so that each case runs in
//! seconds: every hard case ends converged inside its window with finite
//! values, or with an error whose message names what happened; never a
//! NaN, a panic or a hang (every reduced run caps `max_steps` and
//! `max_density_steps`). The full-size files are `experiments/stress/*.ron`;
//! their measured outcomes are in `docs/reports/stress.md`.

use crate::common;
use common::run_into;
use jamkit_core::Pair;
use jamkit_core::{Packing, Potential, Shape, Vector};
use jamkit_engine::{Objective, Scene};
use jamkit_experiment::Experiment;
use jamkit_experiment::runner::RunReport;
use jamkit_fourier::{Angle, FourierParams, NearDisk};
use jamkit_sphere::Sphere;
use rand::SeedableRng;
use std::f64::consts::PI;
use std::path::Path;

/// Caps every reduced run so that nothing can hang.
const CAPS: [&str; 2] = [
    "minimizer.max_steps=200000",
    "protocol.max_density_steps=5000",
];

/// Load `experiments/stress/<case>.ron` with `sets` and the caps applied,
/// and run it on one thread.
fn run_case(case: &str, sets: &[&str]) -> RunReport {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("experiments/stress")
        .join(format!("{case}.ron"));
    let e = Experiment::from_file(&path).unwrap();
    // The caps first, so that a case may tighten them.
    let sets: Vec<String> = CAPS
        .iter()
        .chain(sets.iter())
        .map(|s| s.to_string())
        .collect();
    let e = jamkit_experiment::overrides::apply(&e, &sets).unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_into(&e, dir.path(), 1)
}

/// Every sample converged with V/N inside the paper's window (1e-16, 2e-16),
/// a finite φ in `phi_range` and a finite pressure.
fn assert_jammed(report: &RunReport, samples: usize, phi_range: (f64, f64)) {
    assert!(report.failures.is_empty(), "{:?}", report.failures);
    assert_eq!(report.packings.len(), samples);
    for p in &report.packings {
        let e = p.energy_per_particle;
        assert!(e > 1e-16 && e < 2e-16, "{}: V/N = {e}", p.id);
        assert!(
            p.phi > phi_range.0 && p.phi < phi_range.1,
            "{}: phi = {}",
            p.id,
            p.phi
        );
        let pressure = p.measures.pressure.unwrap();
        assert!(
            pressure.is_finite() && pressure > 0.0,
            "{}: P = {pressure}",
            p.id
        );
        assert!(p.positions.iter().flatten().all(|x| x.is_finite()));
        assert!(p.orientations.iter().flatten().all(|x| x.is_finite()));
    }
}

/// Every sample failed, each with a message containing `needle`.
fn assert_all_fail_with(report: &RunReport, samples: usize, needle: &str) {
    assert!(
        report.packings.is_empty(),
        "{} packings",
        report.packings.len()
    );
    assert_eq!(report.failures.len(), samples);
    for f in &report.failures {
        let msg = f.to_string();
        assert!(msg.contains(needle), "expected '{needle}' in: {msg}");
        assert!(!msg.contains("NaN"), "{msg}");
    }
}

#[test]
fn tiny_delta_1e_6_jams() {
    let r = run_case("tiny_delta_1e-6", &["particles=16", "samples=1"]);
    assert_jammed(&r, 1, (0.75, 0.90));
}

#[test]
fn tiny_delta_1e_8_jams() {
    let r = run_case("tiny_delta_1e-8", &["particles=16", "samples=1"]);
    assert_jammed(&r, 1, (0.75, 0.90));
}

/// The same tiny-Δ near-disks with block masses (`minimizer.masses`),
/// whose rotations are held by a stiffness `∼ Δ²` far below the stress
/// part `∼ |h| Δ` of their Hessian: without the preconditioner's floor
/// `κ m_a` both stalled at the step cap (docs/explanation/minimizers.md,
/// "Block masses").
#[test]
fn tiny_deltas_jam_with_block_masses() {
    for case in ["tiny_delta_1e-6", "tiny_delta_1e-8"] {
        let r = run_case(
            case,
            &["particles=16", "samples=1", "minimizer.masses=Blocks(())"],
        );
        assert_jammed(&r, 1, (0.75, 0.90));
    }
}

/// Every jamming case of the suite with the extrapolated search
/// (`protocol.search`): the leaps end in the same window, with the same
/// ranges of φ.
#[test]
fn jamming_cases_jam_with_the_extrapolated_search() {
    let cases: [(&str, &[&str], (f64, f64)); 6] = [
        (
            "tiny_delta_1e-6",
            &["particles=16", "samples=1"],
            (0.75, 0.90),
        ),
        (
            "tiny_delta_1e-8",
            &["particles=16", "samples=1"],
            (0.75, 0.90),
        ),
        ("n12", &["particles=16", "samples=1"], (0.75, 0.90)),
        ("n16384", &["particles=256"], (0.80, 0.88)),
        (
            "size_ratio_10",
            &["particles=32", "samples=1"],
            (0.75, 0.95),
        ),
        (
            "phi_start_near_jamming",
            &["particles=32", "samples=1"],
            (0.78, 0.90),
        ),
    ];
    for (case, sets, range) in cases {
        let mut sets = sets.to_vec();
        sets.push("protocol.search=Extrapolated");
        let r = run_case(case, &sets);
        assert_jammed(&r, 1, range);
    }
}

#[test]
fn twelve_lobes_jam() {
    let n12 = NearDisk::fourier(&FourierParams {
        n: 12,
        delta: 0.006,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap();
    assert!(n12.is_convex(), "the file's Δ must keep n = 12 convex");
    let r = run_case("n12", &["particles=16", "samples=1"]);
    assert_jammed(&r, 1, (0.75, 0.90));
}

/// Four near-disks: the box at jamming is shorter than twice the
/// interaction range, and the engine says so.
#[test]
fn four_near_disks_fail_with_box_too_small() {
    let r = run_case("n4_particles", &["samples=2"]);
    assert_all_fail_with(&r, 2, "a body would meet its own periodic image");
    for f in &r.failures {
        assert!(f.to_string().contains("box edge"), "{f}");
    }
}

/// Reduced from N = 16384 to N = 256 for jamming; one energy and gradient
/// evaluation at the full N = 16384 near jamming is finite.
#[test]
fn many_disks_jam_and_full_size_evaluates() {
    let r = run_case("n16384", &["particles=256"]);
    assert_jammed(&r, 1, (0.80, 0.88));

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let sizes = (0..16384)
        .map(|k| if k < 8192 { 0.5 } else { 0.7 })
        .collect();
    let packing = Packing::<2, Sphere>::random(Sphere, sizes, 0.84, &mut rng).unwrap();
    let mut scene = Scene::new(packing, Potential::Harmonic, 0.4);
    scene.check_box().unwrap();
    let mut grad = vec![0.0; scene.dof()];
    let e = scene.energy_gradient(&mut grad);
    assert!(e.is_finite() && e > 0.0, "V = {e}");
    assert!(grad.iter().all(|g| g.is_finite()));
}

#[test]
fn size_ratio_10_jams() {
    let r = run_case("size_ratio_10", &["particles=32", "samples=1"]);
    assert_jammed(&r, 1, (0.75, 0.95));
}

#[test]
fn start_just_below_jamming_jams() {
    let r = run_case("phi_start_near_jamming", &["particles=32", "samples=1"]);
    assert_jammed(&r, 1, (0.78, 0.90));
}

#[test]
fn small_box_fails_with_box_too_small() {
    let r = run_case("small_box", &[]);
    assert_all_fail_with(&r, 1, "a body would meet its own periodic image");
    assert!(r.failures[0].to_string().contains("box edge"));
}

/// V/N in (1e-30, 2e-30): overlaps at the round-off of positions. FIRE
/// cannot push |∇V|² below ~1e-30 (round-off of the forces), so with
/// `force_tol = 1e-45` it runs to its cap and says so; the full file
/// (2·10⁶ steps) ends the same way (docs/reports/stress.md).
#[test]
fn window_near_precision_ends_with_a_clear_error() {
    let r = run_case(
        "window_near_precision",
        &["samples=1", "minimizer.max_steps=20000"],
    );
    assert_all_fail_with(&r, 1, "FIRE did not converge in 20000 steps");
}

/// Two bodies whose centres are closer than 1e-12 (and coincident): the
/// gap and its gradient are finite, and the same on every call.
#[test]
fn nearly_coincident_centres_give_finite_deterministic_contacts() {
    let disk = NearDisk::fourier(&FourierParams {
        n: 2,
        delta: 0.1,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap();
    for r in [Vector::<2>::new(0.0, 0.0), Vector::<2>::new(3e-13, -4e-13)] {
        let mut sphere_contacts = Vec::new();
        for _ in 0..2 {
            Shape::<2>::contacts(&Sphere, &Pair::new(0.5, (), 0.7, (), r), 0.0, |c| {
                sphere_contacts.push(c)
            });
        }
        assert_eq!(sphere_contacts.len(), 2);
        assert_eq!(sphere_contacts[0], sphere_contacts[1]);
        let c = &sphere_contacts[0];
        assert!(c.gap.is_finite() && c.grad_r.iter().all(|g| g.is_finite()));

        let (oi, oj) = (Angle::new(0.4), Angle::new(-1.3));
        let mut disk_contacts = Vec::new();
        for _ in 0..2 {
            disk.contacts(&Pair::new(0.5, oi, 0.7, oj, r), 0.0, |c| {
                disk_contacts.push(c)
            });
        }
        assert_eq!(disk_contacts.len(), 2);
        assert_eq!(disk_contacts[0], disk_contacts[1]);
        let c = &disk_contacts[0];
        assert!(c.gap.is_finite(), "gap {}", c.gap);
        assert!(c.grad_r.iter().all(|g| g.is_finite()), "{:?}", c.grad_r);
        assert!(
            c.grad_rot_i
                .iter()
                .chain(&c.grad_rot_j)
                .all(|g| g.is_finite())
        );
    }

    // The same through a scene: body 1 placed 1e-13 from body 0.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let sizes = (0..16).map(|k| if k < 8 { 0.5 } else { 0.7 }).collect();
    let mut packing = Packing::<2, NearDisk>::random(disk, sizes, 0.5, &mut rng).unwrap();
    packing.positions[1] = packing.positions[0] + Vector::<2>::new(1e-13, 0.0);
    let mut scene = Scene::new(packing, Potential::Harmonic, 0.4);
    let mut g1 = vec![0.0; scene.dof()];
    let mut g2 = vec![0.0; scene.dof()];
    let e1 = scene.energy_gradient(&mut g1);
    let e2 = scene.energy_gradient(&mut g2);
    assert!(e1.is_finite() && g1.iter().all(|g| g.is_finite()));
    assert_eq!((e1.to_bits(), &g1), (e2.to_bits(), &g2));
}

fn gap(disk: &NearDisk, oi: &Angle, oj: &Angle, r: &Vector<2>) -> f64 {
    let mut h = f64::NAN;
    disk.contacts(&Pair::new(0.5, *oi, 0.7, *oj, *r), f64::INFINITY, |c| {
        h = c.gap
    });
    h
}

/// Relative angles of exactly ±π, and orientations wound 10⁶ turns in one
/// call or in 10⁶ small turns, give the gap of the unwound orientation.
#[test]
fn wound_and_opposite_orientations_give_the_same_gap() {
    let disk = NearDisk::fourier(&FourierParams {
        n: 3,
        delta: 0.1,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap();
    let r = Vector::<2>::new(0.9, 0.5);
    let oi = Angle::new(0.3);
    let base = gap(&disk, &oi, &Angle::new(0.3 + PI), &r);
    assert!(base.is_finite());
    // Relative angle +π and −π: the same orientation, the same gap.
    let minus = gap(&disk, &oi, &Angle::new(0.3 - PI), &r);
    assert!((minus - base).abs() < 1e-12, "{minus} vs {base}");
    let exact = gap(&disk, &Angle::new(0.0), &Angle::new(PI), &r);
    let exact_minus = gap(&disk, &Angle::new(0.0), &Angle::new(-PI), &r);
    assert!(
        (exact - exact_minus).abs() < 1e-12,
        "{exact} vs {exact_minus}"
    );

    // Wound 10⁶ turns in one call. NOTE: 0.3 + 2π·10⁶ ≈ 6.3e6 is itself
    // stored only to half an ulp, 4.7e-10 rad, and 2π·10⁶ in the wrap is
    // rounded as much; the gap moves by at most Δ R n δθ ≈ 0.1·0.7·3·1e-9,
    // so agreement to 1e-9 is what double precision allows here.
    let wound = gap(&disk, &oi, &Angle::new(0.3 + PI + 2.0 * PI * 1e6), &r);
    assert!((wound - base).abs() < 1e-9, "{wound} vs {base}");

    // Wound by 10⁶ small turns of 2⁻¹⁰ (exact in binary) each: 976.5625 rad.
    let step = 1.0 / 1024.0;
    let mut turned = Angle::new(0.3);
    for _ in 0..1_000_000 {
        turned = turned.turned(step);
    }
    let direct = Angle::new(0.3 + 976.5625);
    let (a, b) = (gap(&disk, &turned, &oi, &r), gap(&disk, &direct, &oi, &r));
    assert!((a - b).abs() < 1e-12, "{a} vs {b}: {}", a - b);
}
