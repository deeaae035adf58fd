//! The `ellipse` family (exact gap) in the engine: finite-difference checks
//! of each pair's gradient and Hessian (overlapping pairs and pairs across
//! θ_ij = ±π included), the conformance kit's checks of the assembled
//! forces, torques and Hessian and of rotation invariance, the aspect ratios of the Fig. 5 experiment, a small
//! jamming run, and bad input.

use jamkit_core::{Contact, GapHessian, Shape, Vector};
use jamkit_core::{Pair, ShapeExt};
use jamkit_ellipse::{Axis, Ellipse, EllipseParams};
use jamkit_experiment::{Experiment, overrides};
use jamkit_fourier::{FourierParams, NearDisk};
use rand::{RngExt, SeedableRng};
use std::f64::consts::PI;
use std::path::Path;

use crate::common;

fn ellipse(aspect: f64) -> Ellipse {
    Ellipse::new(&EllipseParams {
        aspect,
        inertia: None,
    })
    .unwrap()
}

/// Nearly round, the paper's range, elongated, needle-like.
const ASPECTS: [f64; 4] = [1.05, 1.3, 2.0, 4.0];

fn contact(s: &Ellipse, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> Contact<2> {
    s.pair_contacts(
        &Pair::new(ri, Axis::new(ti), rj, Axis::new(tj), d),
        f64::INFINITY,
    )[0]
}

fn hessian(s: &Ellipse, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> GapHessian<2> {
    let mut out = None;
    s.gap_hessians(
        &Pair::new(ri, Axis::new(ti), rj, Axis::new(tj), d),
        f64::INFINITY,
        |c| out = Some(c),
    )
    .unwrap();
    out.expect("max_gap = ∞ visits every pair")
}

/// Random pairs: sizes 0.5 or 0.7, random orientations, the line of
/// centres in a random direction, at a distance between 0.9 times the sum
/// of the short semi-axes and 1.15 times the sum of the long ones (so both
/// overlapping pairs, some deeply, and separated ones); plus pairs with
/// θ_ij within 1e-9 of ±π and orientations within 1e-9 of ±π.
fn pairs(s: &Ellipse, seed: u64) -> Vec<(f64, f64, f64, f64, Vector<2>)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for _ in 0..40 {
        let ri = if rng.random::<f64>() < 0.5 { 0.5 } else { 0.7 };
        let rj = if rng.random::<f64>() < 0.5 { 0.5 } else { 0.7 };
        let reach = s.bounding_radius(ri) + s.bounding_radius(rj);
        let short = s.semi_axes(ri).1 + s.semi_axes(rj).1;
        let r = 0.9 * short + (1.15 * reach - 0.9 * short) * rng.random::<f64>();
        let phi = 2.0 * PI * rng.random::<f64>() - PI;
        let ti = 2.0 * PI * rng.random::<f64>() - PI;
        let tj = 2.0 * PI * rng.random::<f64>() - PI;
        out.push((
            ri,
            ti,
            rj,
            tj,
            Vector::<2>::new(r * phi.cos(), r * phi.sin()),
        ));
    }
    let r = 0.95 * (s.bounding_radius(0.5) + s.bounding_radius(0.7));
    for dy in [1e-9, -1e-9, 0.0] {
        for (ti, tj) in [(PI - 1e-9, -PI + 1e-9), (0.4, PI), (-2.0, 1.1)] {
            out.push((0.5, ti, 0.7, tj, Vector::<2>::new(-r, dy)));
        }
    }
    out
}

/// Each pair's gradient (∂h/∂r_j, ∂h/∂θ_i, ∂h/∂θ_j) against central
/// differences of its gap, ε = 1e-6. The gap is the maximum of a smooth
/// function, computed to round-off (~1e-15 rad left in the normal), so
/// the round-off of the difference is ~1e-16/ε = 1e-10 and its truncation
/// ~ε² h''' ≲ 1e-10 (h''' ~ 1/k² with k = h + ρ_i + ρ_j ≳ 0.05 here):
/// a bound of 1e-7 on derivatives of order 0.1–1 catches any wrong term.
#[test]
fn pair_gradients_match_finite_differences() {
    let eps = 1e-6;
    for aspect in ASPECTS {
        let s = ellipse(aspect);
        let mut overlapping = 0;
        for (ri, ti, rj, tj, d) in pairs(&s, 7) {
            let c = contact(&s, ri, ti, rj, tj, d);
            overlapping += usize::from(c.gap < 0.0);
            let h = |ti: f64, tj: f64, d: Vector<2>| contact(&s, ri, ti, rj, tj, d).gap;
            let ex = Vector::<2>::new(eps, 0.0);
            let ey = Vector::<2>::new(0.0, eps);
            let fd = [
                (h(ti, tj, d + ex) - h(ti, tj, d - ex)) / (2.0 * eps),
                (h(ti, tj, d + ey) - h(ti, tj, d - ey)) / (2.0 * eps),
                (h(ti + eps, tj, d) - h(ti - eps, tj, d)) / (2.0 * eps),
                (h(ti, tj + eps, d) - h(ti, tj - eps, d)) / (2.0 * eps),
            ];
            let an = [c.grad_r[0], c.grad_r[1], c.grad_rot_i[0], c.grad_rot_j[0]];
            for (k, (a, f)) in an.iter().zip(&fd).enumerate() {
                assert!(
                    (a - f).abs() < 1e-7,
                    "α = {aspect}, pair {:?}, component {k}: {a} vs {f}",
                    (ri, ti, rj, tj, d)
                );
            }
        }
        assert!(overlapping >= 5, "α = {aspect}: too few overlapping pairs");
    }
}

/// Each pair's second derivatives (`gap_hessians`) against central
/// differences of the analytic gradient (`contacts`), ε = 1e-6: the
/// gradient is exact to ~1e-15 (it is `e(ψ*)` and `H'(ψ* − θ)`), so the
/// difference is good to ~1e-9 plus a truncation ~ε² ≲ 1e-10 relative to
/// the entries (~1/k ≲ 20). Bound: 1e-6 (1 + |entry|). `gap_hessians` must
/// also give the gap and gradient of `contacts` to 1e-14 (1 + |entry|):
/// `contacts` ends with a Taylor finish after a last step below 10⁻⁶ rad,
/// `gap_hessians` with one more evaluation at the optimum, and the two
/// agree to round-off, not bit for bit.
#[test]
fn pair_hessians_match_finite_differences() {
    let eps = 1e-6;
    for aspect in ASPECTS {
        let s = ellipse(aspect);
        for (ri, ti, rj, tj, d) in pairs(&s, 11) {
            let g = hessian(&s, ri, ti, rj, tj, d);
            let c = contact(&s, ri, ti, rj, tj, d);
            let pairs = [
                (g.contact.gap, c.gap),
                (g.contact.grad_r[0], c.grad_r[0]),
                (g.contact.grad_r[1], c.grad_r[1]),
                (g.contact.grad_rot_i[0], c.grad_rot_i[0]),
                (g.contact.grad_rot_j[0], c.grad_rot_j[0]),
            ];
            for (k, (a, b)) in pairs.into_iter().enumerate() {
                assert!(
                    (a - b).abs() <= 1e-14 * (1.0 + a.abs()),
                    "α = {aspect}, entry {k}: gap_hessians {a} against contacts {b}"
                );
            }
            let grad = |ti: f64, tj: f64, d: Vector<2>| {
                let c = contact(&s, ri, ti, rj, tj, d);
                [c.grad_r[0], c.grad_r[1], c.grad_rot_i[0], c.grad_rot_j[0]]
            };
            let diff = |p: [f64; 4], m: [f64; 4]| -> [f64; 4] {
                std::array::from_fn(|k| (p[k] - m[k]) / (2.0 * eps))
            };
            let ex = Vector::<2>::new(eps, 0.0);
            let ey = Vector::<2>::new(0.0, eps);
            // Columns: derivative with respect to x_j, y_j, θ_i, θ_j.
            let cols = [
                diff(grad(ti, tj, d + ex), grad(ti, tj, d - ex)),
                diff(grad(ti, tj, d + ey), grad(ti, tj, d - ey)),
                diff(grad(ti + eps, tj, d), grad(ti - eps, tj, d)),
                diff(grad(ti, tj + eps, d), grad(ti, tj - eps, d)),
            ];
            // The analytic matrix in the same order.
            let an = [
                [g.rr[(0, 0)], g.rr[(1, 0)], g.r_qi[0][0], g.r_qj[0][0]],
                [g.rr[(0, 1)], g.rr[(1, 1)], g.r_qi[0][1], g.r_qj[0][1]],
                [g.r_qi[0][0], g.r_qi[0][1], g.qi_qi[0][0], g.qi_qj[0][0]],
                [g.r_qj[0][0], g.r_qj[0][1], g.qi_qj[0][0], g.qj_qj[0][0]],
            ];
            for c in 0..4 {
                for r in 0..4 {
                    let (a, f) = (an[c][r], cols[c][r]);
                    assert!(
                        (a - f).abs() < 1e-6 * (1.0 + a.abs()),
                        "α = {aspect}, pair {:?}, entry ({r}, {c}): {a} vs {f}",
                        (ri, ti, rj, tj, d)
                    );
                }
            }
        }
    }
}

/// The conformance kit's assembled checks (`crates/kit`) over the range of
/// aspect ratios: forces and torques and the Hessian against finite
/// differences, `h_ij = h_ji`, rotation invariance.
#[test]
fn ellipses_pass_the_kit_checks() {
    for aspect in ASPECTS {
        let shape = ellipse(aspect);
        jamkit_kit::check_gradient::<2, _>(&shape);
        jamkit_kit::check_symmetry::<2, _>(&shape);
        assert!(jamkit_kit::check_rotation::<2, _>(&shape));
    }
    for aspect in [1.1, 2.0] {
        assert!(jamkit_kit::check_hessian::<2, _>(&ellipse(aspect)));
    }
}

/// The aspect ratios written in the Fig. 5 experiment files give each
/// ellipse the asphericity of the n = 2 near-disk at its Δ: recomputed
/// here, they agree with the file to 1e-9 (the file keeps 10 digits).
#[test]
fn fig05_aspect_ratios_match_the_near_disk_asphericity() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper");
    for (ellipses, disks) in [
        ("quick/fig05_ellipses.ron", "quick/fig05_near_disks.ron"),
        ("ellipses.ron", "ellipses_near_disks.ron"),
    ] {
        let list = |file: &str, key: &str| -> Vec<f64> {
            let e = Experiment::from_file(&root.join(file)).unwrap();
            let v = e.params.get(key).unwrap_or_else(|| panic!("{file}: {key}"));
            v.clone().into_rust::<Vec<f64>>().unwrap()
        };
        let aspects = list(ellipses, "aspect");
        let deltas = list(disks, "delta");
        assert_eq!(aspects.len(), deltas.len());
        for (alpha, delta) in aspects.iter().zip(&deltas) {
            let nd = NearDisk::fourier(&FourierParams {
                n: 2,
                delta: *delta,
                inertia: None,
                gap: Default::default(),
            })
            .unwrap();
            let expected = Ellipse::aspect_for_asphericity(nd.asphericity()).unwrap();
            assert!(
                (alpha - expected).abs() < 1e-9,
                "{ellipses}: Δ = {delta}: α = {alpha}, expected {expected}"
            );
        }
    }
}

/// A small jamming run: N = 32 at α = 1.2, 3 seeds, the paper's protocol.
/// Every packing ends in the energy window with sane φ_J (0.8 < φ_J <
/// 0.92), and the mean φ_J is above that of disks (α = 1, run as
/// `sphere`) from the same seeds: at large N ellipses of α ≈ 1.2 jam at
/// φ_J ≈ 0.87–0.89 against 0.84 for disks, a gap several times the
/// sample-to-sample spread of N = 32 packings (≈ 0.01).
#[test]
fn small_ellipse_packings_jam_denser_than_disks() {
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper/quick/fig05_ellipses.ron");
    let e = Experiment::from_file(&file).unwrap();
    let e = overrides::apply(
        &e,
        &[
            "particles=32".into(),
            "samples=3".into(),
            "params.aspect=[1.0, 1.2]".into(),
        ],
    )
    .unwrap();
    e.validate().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&e, dir.path(), 2);
    assert_eq!(report.packings.len(), 6);
    let mut mean = [0.0; 2];
    for p in &report.packings {
        let round = p.params.get("aspect").and_then(|v| v.as_f64()) == Some(1.0);
        assert_eq!(p.family, "ellipse");
        common::assert_in_window(p);
        let phi = p.phi;
        assert!(phi > 0.8 && phi < 0.92, "{}: φ_J = {phi}", p.id);
        // α = 1 runs as disks: no angles stored.
        assert_eq!(p.orientations.is_empty(), round, "{}", p.id);
        mean[usize::from(!round)] += phi / 3.0;
    }
    assert!(
        mean[1] > mean[0] + 0.01,
        "φ_J: disks {}, ellipses {}",
        mean[0],
        mean[1]
    );
}

/// Bad parameters are refused with the field, the value and what is
/// allowed, never a panic.
#[test]
fn bad_parameters_are_refused_with_the_field_named() {
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper/quick/fig05_ellipses.ron");
    let e = Experiment::from_file(&file).unwrap();
    for (set, field) in [
        ("params.aspect=0.8", "params.aspect"),
        ("params.aspect=-1.0", "params.aspect"),
        ("params.inertia=0.0", "params.inertia"),
        ("params.inertia=-2.0", "params.inertia"),
    ] {
        let e = overrides::apply(&e, &[set.into()]).unwrap();
        let err = match e.validate() {
            Err(err) => err.to_string(),
            Ok(()) => jamkit_experiment::Plan::new(&e).err().unwrap().to_string(),
        };
        assert!(err.contains(field), "{set}: {err}");
    }
    let e = overrides::apply(&e, &["params.shape=2".into()]).unwrap();
    let err = match e.validate() {
        Err(err) => err.to_string(),
        Ok(()) => jamkit_experiment::Plan::new(&e).err().unwrap().to_string(),
    };
    assert!(err.contains("shape"), "{err}");
}

/// Same seed, same packing bits (the run does not depend on the threads).
#[test]
fn runs_are_deterministic() {
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/paper/quick/fig05_ellipses.ron");
    let e = Experiment::from_file(&file).unwrap();
    let e = overrides::apply(
        &e,
        &[
            "particles=16".into(),
            "samples=2".into(),
            "params.aspect=[1.5]".into(),
        ],
    )
    .unwrap();
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let ra = common::run_ok(&e, a.path(), 1);
    let rb = common::run_ok(&e, b.path(), 2);
    for (p, q) in ra.packings.iter().zip(&rb.packings) {
        assert_eq!(p.id, q.id);
        let bits =
            |v: &Vec<Vec<f64>>| -> Vec<u64> { v.iter().flatten().map(|x| x.to_bits()).collect() };
        assert_eq!(bits(&p.positions), bits(&q.positions));
        assert_eq!(bits(&p.orientations), bits(&q.orientations));
    }
}

/// The scene's warm lanes (`FastContacts::contacts_warm_lanes`) give the
/// generic pass's energy and gradient bit for bit along a path of moves
/// and jumps (`common::assert_lanes_match_the_generic_pass`): α = 1.1,
/// 1.5 and 3.
#[test]
fn warm_lanes_match_the_generic_pass_bit_for_bit() {
    for aspect in [1.1, 1.5, 3.0] {
        common::assert_lanes_match_the_generic_pass(ellipse(aspect), &format!("α = {aspect}"));
    }
}
