//! The ladder of near-disk gap models (`gap: FirstOrder | SecondOrder |
//! Exact`): finite-difference gradients and Hessians, independent checks of
//! the exact gap, and the order of each model's error
//! (`docs/explanation/gap-models.md`, "The ladder of gap models").

use jamkit_core::{Packing, Potential, Shape, SizeDistribution, Vector};
use jamkit_core::{Pair, ShapeExt};
use jamkit_engine::{Scene, check::gradient_error};
use jamkit_fourier::{Angle, FourierParams, FourierSumParams, Mode, NearDisk};
use jamkit_planar::gap2d::GapModel;
use rand::{RngExt, SeedableRng};
use std::f64::consts::PI;

use crate::common;

fn fourier(n: u32, delta: f64, gap: GapModel) -> NearDisk {
    NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap,
    })
    .unwrap()
}

/// Three modes with phases (n = 2, 3, 7), Δ = 0.1 (still convex; at 0.2
/// the n = 7 mode makes it non-convex): the hard case.
fn multi_mode(gap: GapModel) -> NearDisk {
    let m = |n, a, b| Mode { n, a, b };
    NearDisk::fourier_sum(&FourierSumParams {
        modes: vec![m(2, 0.4, 0.3), m(3, 0.2, -1.0), m(7, 0.05, 2.0)],
        delta: 0.1,
        inertia: None,
        gap,
    })
    .unwrap()
}

fn shapes(gap: GapModel) -> Vec<NearDisk> {
    let mut v: Vec<NearDisk> = (2..=5).map(|n| fourier(n, 0.15, gap)).collect();
    v.push(multi_mode(gap));
    v
}

fn dense(shape: NearDisk, n: usize, seed: u64) -> Scene<2, NearDisk> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let packing = Packing::<2, NearDisk>::random(shape, sizes, 0.9, &mut rng).unwrap();
    Scene::new(packing, Potential::Harmonic, 0.2)
}

fn gap_of(s: &NearDisk, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> f64 {
    s.pair_contacts(
        &Pair::new(ri, Angle::new(ti), rj, Angle::new(tj), d),
        f64::INFINITY,
    )[0]
    .gap
}

/// Forces and torques against central differences, for SecondOrder and
/// Exact. ε = 1e-7: the random dense start has pairs at small `r` where the
/// second-order term `Δ²G²/2r` has large third derivatives, and at ε = 1e-6
/// the truncation error reached 3e-6 of the gradient scale (it fell as ε²,
/// so it is truncation, not a wrong term); at 1e-7 it is ~3e-8 and the
/// round-off ~1e-16 V/ε ~ 1e-9. A wrong term would miss by ≫ 1e-6.
#[test]
fn second_order_and_exact_gradients_match_finite_differences() {
    for gap in [GapModel::SecondOrder, GapModel::Exact] {
        for shape in shapes(gap) {
            for seed in 1..=2 {
                let scene = dense(shape.clone(), 40, seed);
                let (err, scale) = gradient_error(&scene, 1e-7);
                assert!(scale > 1e-2);
                assert!(
                    err < 1e-6 * scale,
                    "{gap:?} {shape:?} seed {seed}: {err:e} vs {scale:e}"
                );
            }
        }
    }
}

/// The analytic Hessian against central differences of the analytic
/// gradient, by the conformance kit (1e-6 relative to the largest entry;
/// the reason is in `crates/kit`).
#[test]
fn second_order_and_exact_hessians_match_finite_differences() {
    for gap in [GapModel::SecondOrder, GapModel::Exact] {
        for shape in shapes(gap) {
            assert!(
                jamkit_kit::check_hessian_at::<2, _>(&shape, 24, 1),
                "{gap:?}"
            );
        }
    }
}

/// A pair with θ_ij within 1e-9 of ±π (the branch cut of atan2, where the
/// exact gap's Newton iteration starts): the gradient is right on both sides.
#[test]
fn exact_gradient_is_smooth_across_theta_ij_equal_pi() {
    for shape in [
        fourier(3, 0.2, GapModel::Exact),
        multi_mode(GapModel::Exact),
    ] {
        for dy in [1e-9, -1e-9, 0.0] {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
            let mut p =
                Packing::<2, NearDisk>::random(shape.clone(), vec![0.5, 0.7], 0.05, &mut rng)
                    .unwrap();
            let c = *p.bbox.edges() * 0.5;
            p.positions[0] = c;
            p.positions[1] = c + Vector::<2>::new(-1.1, dy);
            let scene = Scene::new(p, Potential::Harmonic, 0.2);
            let (err, scale) = gradient_error(&scene, 1e-7);
            assert!(scale > 1e-3, "the pair must overlap");
            assert!(err < 1e-6 * scale, "dy = {dy}: {err:e} vs {scale:e}");
        }
    }
}

/// The outline of body `i` (size `ri`, angle `ti`) in the lab direction `φ`.
fn radius(s: &NearDisk, ri: f64, ti: f64, phi: f64) -> f64 {
    ri * s.relative_radius(ti - phi)
}

/// The exact gap checked without its own machinery: the support function
/// by brute force (the largest projection of 5·10⁴ outline points, low by
/// at most ~R(δφ)²/2 ≈ 10⁻⁸), and the maximum over the normal direction by a
/// scan (the exact gap must be at least every scanned `g(ψ)` and at most
/// their maximum plus the scan's resolution).
#[test]
fn exact_gap_is_the_max_over_normals_of_the_brute_force_support_gap() {
    let s = multi_mode(GapModel::Exact);
    let m = 50_000;
    let support = |ri: f64, ti: f64, psi: f64| {
        (0..m)
            .map(|k| {
                let phi = 2.0 * PI * k as f64 / m as f64;
                radius(&s, ri, ti, phi) * (phi - psi).cos()
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for _ in 0..4 {
        let (ti, tj) = (
            rng.random::<f64>() * 2.0 * PI,
            rng.random::<f64>() * 2.0 * PI,
        );
        let a = rng.random::<f64>() * 2.0 * PI;
        let dist = 1.2 + 0.2 * (rng.random::<f64>() - 0.5);
        let d = Vector::<2>::new(dist * a.cos(), dist * a.sin());
        let h = gap_of(&s, 0.5, ti, 0.7, tj, d);
        let g = |psi: f64| {
            d[0] * psi.cos() + d[1] * psi.sin() - support(0.5, ti, psi) - support(0.7, tj, psi + PI)
        };
        // g is smooth with |g''| ≲ 2: a scan with step 5e-3 around the line
        // of centres (±0.3 rad) finds its maximum to ~|g''|(2.5e-3)² ≈ 1e-5.
        let best = (-60..=60)
            .map(|k| g(a + 5e-3 * k as f64))
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(h >= best - 3e-8, "exact {h} below the scan's max {best}");
        assert!(h <= best + 2e-5, "exact {h} above the scan's max {best}");
    }
}

/// Order of each model: over random pairs near contact, the largest error
/// of `h` against `Exact` scales as Δ² (FirstOrder) and Δ³ (SecondOrder).
/// Fitted log–log slopes over Δ = 10⁻³ … 10⁻¹ must lie within 0.25 of 2
/// and 3 (the leading coefficients vary with the pairs sampled, so the
/// slope is not exact; a wrong order would miss by ≥ 1).
#[test]
fn first_order_error_scales_as_delta_squared_and_second_order_as_delta_cubed() {
    for n in [2, 3, 5] {
        let deltas = [1e-3, 3e-3, 1e-2, 3e-2, 1e-1];
        let mut errs = [[0.0f64; 5]; 2];
        for (k, &delta) in deltas.iter().enumerate() {
            let exact = fourier(n, delta, GapModel::Exact);
            let models = [
                fourier(n, delta, GapModel::FirstOrder),
                fourier(n, delta, GapModel::SecondOrder),
            ];
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
            for _ in 0..200 {
                let (ti, tj) = (
                    rng.random::<f64>() * 2.0 * PI,
                    rng.random::<f64>() * 2.0 * PI,
                );
                let a = rng.random::<f64>() * 2.0 * PI;
                // Near contact: within ±Δ·R of touching.
                let dist = 1.2 + 0.5 * delta * (rng.random::<f64>() - 0.5);
                let d = Vector::<2>::new(dist * a.cos(), dist * a.sin());
                let he = gap_of(&exact, 0.5, ti, 0.7, tj, d);
                for (e, m) in errs.iter_mut().zip(&models) {
                    e[k] = e[k].max((gap_of(m, 0.5, ti, 0.7, tj, d) - he).abs());
                }
            }
        }
        for (order, e) in [(2.0, errs[0]), (3.0, errs[1])] {
            let slope = fit_slope(&deltas, &e);
            println!("n = {n}: order {order}: errors {e:?}, fitted slope {slope:.3}");
            assert!(
                (slope - order).abs() < 0.25,
                "n = {n}: slope {slope} for order {order}: {e:?}"
            );
        }
    }
}

/// Least-squares slope of log y against log x.
fn fit_slope(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let n = x.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// `h_ij = h_ji` and invariance under a global rotation, for both new
/// models (round-off: 1e-14 on gaps of order 1).
#[test]
fn new_models_are_symmetric_and_rotation_invariant() {
    for gap in [GapModel::SecondOrder, GapModel::Exact] {
        let s = multi_mode(gap);
        let d = Vector::<2>::new(0.8, -0.9);
        let h = gap_of(&s, 0.5, 0.3, 0.7, -1.2, d);
        assert!((h - gap_of(&s, 0.7, -1.2, 0.5, 0.3, -d)).abs() < 1e-14);
        for alpha in [0.4, 2.0, PI, -2.5] {
            let (sa, ca) = f64::sin_cos(alpha);
            let dr = Vector::<2>::new(ca * d[0] - sa * d[1], sa * d[0] + ca * d[1]);
            let hr = gap_of(&s, 0.5, 0.3 + alpha, 0.7, -1.2 + alpha, dr);
            assert!((h - hr).abs() < 1e-14, "{gap:?} α = {alpha}: {h} vs {hr}");
        }
    }
}

/// On a non-convex outline the exact gap takes the outline's arcs between
/// inflection points (several contacts per pair) and flags nothing; the
/// approximate models, which assume one contact per pair, warn; on a
/// convex outline `Exact` has no arcs (the convex exact gap).
#[test]
fn exact_gap_of_non_convex_outlines_has_arcs_and_no_warning() {
    let p = |gap, delta| FourierParams {
        n: 5,
        delta,
        inertia: None,
        gap,
    };
    let s = NearDisk::fourier(&p(GapModel::Exact, 0.5)).unwrap();
    assert_eq!(s.profiled().arcs().map(|a| a.len()), Some(10));
    assert!(s.policy().warnings.is_empty(), "{:?}", s.policy().warnings);
    let s = NearDisk::fourier(&p(GapModel::SecondOrder, 0.5)).unwrap();
    assert!(!s.policy().warnings.is_empty());
    let s = NearDisk::fourier(&p(GapModel::Exact, 0.1)).unwrap();
    assert!(s.is_convex() && s.profiled().arcs().is_none());
}

/// The exact gap skips pairs whose first-order gap `h₁` exceeds the cut by
/// more than the slack `(R_i⁰ + R_j⁰) Δ² F'²_max / (1 − Δ F_max)`; that is
/// only right if `h ≥ h₁ − slack` always holds. Checked on 4000 random
/// pairs per shape at the most aspherical convex Δ of each n, over all
/// distances from deep overlap to apart.
#[test]
fn exact_gap_never_falls_below_the_first_order_bound() {
    let cases = [(2, 0.3), (3, 0.3), (4, 0.2), (5, 0.15)];
    for (n, delta) in cases {
        let exact = fourier(n, delta, GapModel::Exact);
        let first = fourier(n, delta, GapModel::FirstOrder);
        let (f_max, df_max) = (1.0 / n as f64, 1.0);
        let slack = delta * delta * df_max * df_max / (1.0 - delta * f_max);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(n as u64);
        let mut tightest = f64::INFINITY;
        for _ in 0..4000 {
            let (ti, tj) = (
                rng.random::<f64>() * 2.0 * PI,
                rng.random::<f64>() * 2.0 * PI,
            );
            let a = rng.random::<f64>() * 2.0 * PI;
            let dist = 0.9 + 0.6 * rng.random::<f64>();
            let d = Vector::<2>::new(dist * a.cos(), dist * a.sin());
            let he = gap_of(&exact, 0.5, ti, 0.7, tj, d);
            let h1 = gap_of(&first, 0.5, ti, 0.7, tj, d);
            let margin = he - (h1 - slack);
            assert!(margin >= 0.0, "n = {n}, Δ = {delta}: h = {he}, h₁ = {h1}");
            tightest = tightest.min(margin / slack);
        }
        println!("n = {n}, Δ = {delta}: closest approach {tightest:.3} of the slack");
        // The bound is not vacuous: some pair comes within 80 % of it.
        assert!(
            tightest < 0.8,
            "n = {n}: the bound is never approached ({tightest})"
        );
    }
}

/// Every model jams end to end from an experiment file (the gap written as
/// a string), and a rerun measures new observables on the saved packings,
/// which reload with their gap model: nothing is jammed again. At Δ = 0.1
/// the models' gaps differ by ~Δ² ≈ 1e-2 of a radius near contact, so the
/// packings differ, but each φ_J lies within 0.01 of the first-order one
/// (N = 16: sample-to-sample spread ~5e-3).
#[test]
fn every_model_jams_from_an_experiment_file_and_reloads() {
    let experiment = |observables: &str| {
        let text = format!(
            r#"(name: "gm", family: "fourier", particles: 16, seed: 5,
                params: {{"n": 2, "delta": 0.1, "gap": ["FirstOrder", "SecondOrder", "Exact"]}},
                observables: {observables})"#
        );
        jamkit_experiment::Experiment::from_ron(&text, "inline").unwrap()
    };
    let dir = tempfile::tempdir().unwrap();
    let first = common::run_ok(&experiment("[Contacts]"), dir.path(), 2);
    assert_eq!(first.packings.len(), 3);
    let phi: Vec<f64> = first.packings.iter().map(|p| p.phi).collect();
    for p in &phi {
        assert!((p - phi[0]).abs() < 0.01, "{phi:?}");
    }
    let second = common::run_ok(&experiment("[Contacts, Spectrum()]"), dir.path(), 2);
    assert_eq!(second.reused, 3);
    for (a, b) in first.packings.iter().zip(&second.packings) {
        assert_eq!(a.phi.to_bits(), b.phi.to_bits());
        assert!(b.measures.spectrum.is_some());
    }
}

/// The joint iteration (what contacts and Hessians use) against the nested
/// solve (the check), on pairs near contact (gap from −0.05 to +0.05 of
/// the sizes, as in a packing near jamming) and on the pairs of a dense,
/// overlapping random start, for n = 2 … 5 at Δ = 0.15 and the three-mode
/// profile. Both stop within ~1e-14 rad of the optimum: gaps agree to
/// 1e-14, normals and `H'` (torques) to 1e-12 (round-off of the last
/// Newton step over `k`). Near contact, from the first-order guesses, the
/// joint iteration converges on its own for every pair (no hand-over to
/// the nested solve).
#[test]
fn joint_iteration_agrees_with_the_nested_solve() {
    use jamkit_planar::profiled::ExactSolve;
    let close = |a: &jamkit_planar::gap2d::ExactGap, b: &jamkit_planar::gap2d::ExactGap| {
        (a.gap - b.gap).abs() < 1e-14
            && (a.normal.0 - b.normal.0).abs() < 1e-12
            && (a.normal.1 - b.normal.1).abs() < 1e-12
            && (a.jet_i.d1 - b.jet_i.d1).abs() < 1e-12
            && (a.jet_j.d1 - b.jet_j.d1).abs() < 1e-12
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for s in shapes(GapModel::Exact) {
        let p = s.profiled();
        for _ in 0..200 {
            let (ti, tj, a) = (
                rng.random::<f64>() * 2.0 * PI,
                rng.random::<f64>() * 2.0 * PI,
                rng.random::<f64>() * 2.0 * PI,
            );
            let u = Vector::<2>::new(a.cos(), a.sin());
            let mut pair = Pair::new(0.5, Angle::new(ti), 0.7, Angle::new(tj), u);
            let h = p
                .exact_solve(&pair, f64::INFINITY, ExactSolve::Nested)
                .unwrap()
                .gap;
            pair.r_ij = u * (1.0 - h + 0.12 * (rng.random::<f64>() - 0.5));
            let nested = p
                .exact_solve(&pair, f64::INFINITY, ExactSolve::Nested)
                .unwrap();
            let joint = p
                .exact_solve(&pair, f64::INFINITY, ExactSolve::JointAlone)
                .expect("the joint iteration converges near contact");
            assert!(close(&joint, &nested), "{joint:?} against {nested:?}");
        }
        let scene = dense(s.clone(), 32, 3);
        let pk = scene.packing();
        let mut pairs = 0;
        for i in 0..pk.sizes.len() {
            for j in i + 1..pk.sizes.len() {
                let d = pk.bbox.minimum_image(pk.positions[j] - pk.positions[i]);
                let pair = Pair::new(
                    pk.sizes[i],
                    pk.orientations[i],
                    pk.sizes[j],
                    pk.orientations[j],
                    d,
                );
                // Pairs the contacts would skip (certainly apart) are
                // skipped by both.
                let Some(nested) = p.exact_solve(&pair, 0.0, ExactSolve::Nested) else {
                    continue;
                };
                let joint = p.exact_solve(&pair, 0.0, ExactSolve::Joint).unwrap();
                assert!(close(&joint, &nested), "{joint:?} against {nested:?}");
                pairs += 1;
            }
        }
        assert!(pairs > 32, "only {pairs} pairs");
    }
}

/// Overlapping pairs down to coincident centres (r from 0 to 1.05 × the
/// sum of the sizes), where `g(ψ)` may have several maxima: the contacts'
/// solve (the joint iteration where its reach admits the pair, the nested
/// solve elsewhere) finds the nested solve's maximum, to 1e-14 in the gap.
/// Δ = 0.3 (n = 2) and the n = 5 mode at Δ = 0.15, where the joint
/// iteration run on every pair would stop at another maximum on some
/// pairs below r ≈ 0.11 × the sizes.
#[test]
fn the_contacts_solve_finds_the_nested_maximum_under_deep_overlaps() {
    use jamkit_planar::profiled::ExactSolve;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
    for s in [
        fourier(2, 0.3, GapModel::Exact),
        fourier(5, 0.15, GapModel::Exact),
    ] {
        let p = s.profiled();
        for _ in 0..20_000 {
            let (ti, tj, a) = (
                rng.random::<f64>() * 2.0 * PI,
                rng.random::<f64>() * 2.0 * PI,
                rng.random::<f64>() * 2.0 * PI,
            );
            let r = 1.2 * 1.05 * rng.random::<f64>();
            let d = Vector::<2>::new(a.cos(), a.sin()) * r;
            let pair = Pair::new(0.5, Angle::new(ti), 0.7, Angle::new(tj), d);
            let nested = p.exact_solve(&pair, 0.0, ExactSolve::Nested);
            let joint = p.exact_solve(&pair, 0.0, ExactSolve::Joint);
            match (nested, joint) {
                (Some(x), Some(y)) => {
                    assert!(
                        (x.gap - y.gap).abs() < 1e-14,
                        "r = {r}: {y:?} against {x:?}"
                    )
                }
                (None, None) => {}
                other => panic!("one solve skipped the pair: {other:?}"),
            }
        }
    }
}

/// The energy pass starts each pair's exact gap where its last solve
/// ended (`Shape::contacts_warm`, a memo per listed pair): after 40 steps
/// down the gradient (bodies moved by ~0.1 in all, neighbour lists
/// rebuilt, memos carried over), the energy and gradient equal those of a
/// fresh scene of the same packing (every pair cold) to 1e-13 relative
/// (both solves stop within round-off of the same optimum; the sums add a
/// few ulps per pair), and two clones stepped alike stay the same bits.
#[test]
fn warm_energy_pass_matches_a_cold_one() {
    use jamkit_engine::Objective;
    for shape in shapes(GapModel::Exact) {
        let mut scene = dense(shape, 40, 3);
        let mut grad = vec![0.0; scene.dof()];
        for _ in 0..40 {
            scene.energy_gradient(&mut grad);
            let big = grad.iter().fold(0.0f64, |m, g| m.max(g.abs()));
            let dq: Vec<f64> = grad.iter().map(|g| -3e-3 * g / big).collect();
            scene.displace(&dq);
        }
        let mut twin = scene.clone();
        let e_warm = scene.energy_gradient(&mut grad);
        let mut twin_grad = vec![0.0; scene.dof()];
        assert_eq!(
            e_warm.to_bits(),
            twin.energy_gradient(&mut twin_grad).to_bits()
        );
        assert_eq!(grad, twin_grad);
        assert!(scene.neighbor_builds() > 1, "{}", scene.neighbor_builds());
        let mut fresh = Scene::new(scene.packing().clone(), Potential::Harmonic, 0.2);
        let mut cold = vec![0.0; scene.dof()];
        let e_cold = fresh.energy_gradient(&mut cold);
        assert!(e_warm > 0.0);
        assert!(
            (e_warm - e_cold).abs() <= 1e-13 * e_cold,
            "{e_warm} {e_cold}"
        );
        let scale = cold.iter().fold(0.0f64, |m, g| m.max(g.abs()));
        for (w, c) in grad.iter().zip(&cold) {
            assert!((w - c).abs() <= 1e-13 * scale, "{w} {c}");
        }
    }
}

/// An exact-gap run gives the same packings bit for bit on one thread and
/// on two (each pair's memo belongs to the pair, not to a thread).
#[test]
fn exact_runs_do_not_depend_on_the_threads() {
    let text = r#"(name: "warm", family: "fourier", particles: 16, samples: 2, seed: 3,
        params: {"n": 2, "delta": 0.2, "gap": "Exact"}, observables: [Contacts])"#;
    let e = jamkit_experiment::Experiment::from_ron(text, "inline").unwrap();
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let ra = common::run_ok(&e, a.path(), 1);
    let rb = common::run_ok(&e, b.path(), 2);
    assert_eq!(ra.packings.len(), 2);
    for (p, q) in ra.packings.iter().zip(&rb.packings) {
        assert_eq!(p.id, q.id);
        let bits =
            |v: &Vec<Vec<f64>>| -> Vec<u64> { v.iter().flatten().map(|x| x.to_bits()).collect() };
        assert_eq!(bits(&p.positions), bits(&q.positions));
        assert_eq!(bits(&p.orientations), bits(&q.orientations));
    }
}
