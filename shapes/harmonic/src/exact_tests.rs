//! Pair-level checks of the `harmonic` family's exact gap (`gap: "Exact"`):
//! the support function's derivatives against finite differences and its
//! value against a scan of the surface; every first and second derivative
//! of the gap against finite differences; the gap against a scan of
//! directions; `h_ij = h_ji`; invariance under a global rotation; the
//! first-order gap's error against it, `O(Δ²)`; the parameter checks.

use super::tests::{mixed, orientations, single};
use super::*;
use approx::assert_relative_eq;
use jamkit_core::{Pair, ShapeExt};

const SIZES: (f64, f64) = (0.5, 0.7);

fn exact(h: Harmonic) -> Harmonic {
    h.with_gap(GapModel::Exact).unwrap()
}

/// Convex bodies: zonal `l = 2` (two rotational coordinates), tesseral
/// `l = 2`, `l = 3` and `l = 4`, and a mixed sum (up to `l = 5`).
fn shapes() -> Vec<Harmonic> {
    vec![
        exact(single(2, 0, 0.2)),
        exact(single(2, 2, 0.2)),
        exact(single(3, -1, 0.12)),
        exact(single(4, 3, 0.06)),
        exact(mixed(0.08)),
    ]
}

/// Directions of the line of centres: along body `i`'s `±z` axis (the
/// poles of the zonal modes), 10⁻³ off it, and generic; each at a distance
/// where the gap is about `δ` (from `g` at the line of centres, a lower
/// bound on `h`), overlapping (`δ = −0.03`) and apart (`δ = 0.04`).
fn separations(s: &Harmonic, o_i: &Quaternion, o_j: &Quaternion) -> Vec<Vector<3>> {
    let dirs = [
        o_i.apply(&Vector::<3>::z()),
        -o_i.apply(&Vector::<3>::z()),
        o_i.apply(&Vector::<3>::new(1e-3, -2e-3, 1.0)).normalize(),
        Vector::<3>::new(0.5, -0.7, 0.6).normalize(),
        Vector::<3>::new(-0.9, 0.3, 0.45).normalize(),
    ];
    let (ci, cj) = (o_i.columns(), o_j.columns());
    let mut out = Vec::new();
    for d in dirs {
        let reach = s.support(SIZES.0, &ci, &d).jet.h + s.support(SIZES.1, &cj, &-d).jet.h;
        for delta in [-0.03, 0.04] {
            out.push(d * (reach + delta));
        }
    }
    out
}

fn contact(s: &Harmonic, o_i: &Quaternion, o_j: &Quaternion, r: &Vector<3>) -> Contact<3> {
    let c = s.pair_contacts(&Pair::new(SIZES.0, *o_i, SIZES.1, *o_j, *r), f64::INFINITY);
    assert_eq!(c.len(), 1);
    c[0]
}

/// Directions for the support function: 24 spread over the sphere and
/// the body's poles.
fn directions() -> Vec<Vector<3>> {
    let mut out: Vec<Vector<3>> = (0..24)
        .map(|k| {
            let x = k as f64;
            Vector::<3>::new((x * 1.3).sin(), (x * 0.7).cos(), (x * 2.1).sin() + 0.1).normalize()
        })
        .collect();
    out.push(Vector::<3>::z());
    out.push(-Vector::<3>::z());
    out
}

/// The support jet of every body, at three orientations and 26
/// directions: `p·u = s` and `∇∇s u = 0` (1e-13, round-off); `∇s = p`
/// against central differences of the degree-1 extension
/// `s(v) = |v| s(v/|v|)` (ε = 1e-6: truncation ε²|s'''| ~ 1e-12,
/// round-off 1e-16/ε ~ 1e-10; bound 1e-8); `∇∇s` against central
/// differences of `p` (same ε; `p` is converged to ~1e-15, so round-off
/// ~1e-9; bound 1e-7); the principal radii of curvature (the eigenvalues
/// of `∇∇s` on `u⊥`) positive.
#[test]
fn support_derivatives_match_finite_differences() {
    for s in shapes() {
        for o in orientations() {
            let c = o.columns();
            let sup = |v: &Vector<3>| s.support(SIZES.0, &c, &v.normalize()).jet;
            for u in directions().iter().map(|d| o.apply(d)) {
                let got = s.support(SIZES.0, &c, &u);
                assert!(got.converged && got.iterations <= 8, "{got:?}");
                let j = got.jet;
                assert_relative_eq!(j.point.dot(&u), j.h, epsilon = 1e-13);
                assert!((j.hess * u).norm() < 1e-13, "{:?}", j.hess * u);
                let e = 1e-6;
                for a in 0..3 {
                    let mut d = Vector::<3>::zeros();
                    d[a] = e;
                    let (up, um) = (u + d, u - d);
                    let fd = (up.norm() * sup(&up).h - um.norm() * sup(&um).h) / (2.0 * e);
                    assert!((fd - j.point[a]).abs() < 1e-8, "{s:?}: ∂s/∂u[{a}]");
                    let col = (sup(&up).point - sup(&um).point) / (2.0 * e);
                    for b in 0..3 {
                        assert!(
                            (col[b] - j.hess[(b, a)]).abs() < 1e-7,
                            "{s:?}: ∂²s/∂u[{b}]∂u[{a}] {} vs fd {}",
                            j.hess[(b, a)],
                            col[b]
                        );
                    }
                }
                let eig = (j.hess + u * u.transpose()).symmetric_eigenvalues();
                assert!(eig.min() > 0.0, "{s:?}: radii {eig:?}");
            }
        }
    }
}

/// The largest of `f` on the unit sphere by scanning: 4000 directions on
/// a Fibonacci lattice (spacing ~0.056), then 9 × 9 grids in the tangent
/// plane about the best so far, re-centred and halved from a half-width
/// of 0.06 down to 10⁻⁸. No derivative is used.
fn scan_max(f: impl Fn(&Vector<3>) -> f64) -> (f64, Vector<3>) {
    let n = 4000;
    let golden = PI * (3.0 - 5f64.sqrt());
    let mut best = (f64::NEG_INFINITY, Vector::<3>::z());
    for k in 0..n {
        let z = 1.0 - (2.0 * k as f64 + 1.0) / n as f64;
        let s = (1.0 - z * z).sqrt();
        let (sp, cp) = (golden * k as f64).sin_cos();
        let u = Vector::<3>::new(s * cp, s * sp, z);
        let v = f(&u);
        if v > best.0 {
            best = (v, u);
        }
    }
    let mut w = 0.06;
    while w > 1e-8 {
        let c = best.1;
        let e1 = c.cross(&Vector::<3>::new(0.3, -0.4, 0.8)).normalize();
        let e2 = c.cross(&e1);
        for a in -4..=4 {
            for b in -4..=4 {
                let u = (c + e1 * (w * a as f64 / 4.0) + e2 * (w * b as f64 / 4.0)).normalize();
                let v = f(&u);
                if v > best.0 {
                    best = (v, u);
                }
            }
        }
        w *= 0.5;
    }
    best
}

/// The support function against a scan of the surface points
/// `x(y) = R⁰(1 + ΔF(y)) y` (only `F` itself, no derivative):
/// `s(u) = max_y u·x(y)` agrees to 1e-12 (the scan ends on a grid of
/// spacing ~10⁻⁸, where `u·x` is off its maximum by ~10⁻¹⁶), and the exact
/// gap against a scan of directions of `u·r − s_i(u) − s_j(−u)`: the same
/// maximum to 1e-12 and the same normal to 1e-5 (the maximum is flat:
/// `g` moves by ~10⁻¹⁰ over 10⁻⁵). Separations overlapping and apart,
/// along the poles and generic.
#[test]
fn exact_gap_matches_a_scan() {
    let os = orientations();
    for s in shapes() {
        let (o_i, o_j) = (os[1], os[2]);
        let (ci, cj) = (o_i.columns(), o_j.columns());
        for u in directions().iter().step_by(5) {
            let u = o_i.apply(u);
            let (scan, _) =
                scan_max(|y| SIZES.0 * (1.0 + s.delta * s.f(&o_i.apply_inverse(y))) * u.dot(y));
            let got = s.support(SIZES.0, &ci, &u).jet.h;
            assert!(
                (got - scan).abs() < 1e-12,
                "{s:?}: s = {got} vs scan {scan}"
            );
        }
        for r in separations(&s, &o_i, &o_j) {
            let e = s
                .exact_gap(SIZES.0, &o_i, SIZES.1, &o_j, &r, f64::INFINITY)
                .unwrap();
            assert!(e.converged);
            let (scan, n) = scan_max(|u| {
                u.dot(&r) - s.support(SIZES.0, &ci, u).jet.h - s.support(SIZES.1, &cj, &-u).jet.h
            });
            assert!(
                (e.gap - scan).abs() < 1e-12,
                "{s:?}: h = {} vs scan {scan} at r = {r:?}",
                e.gap
            );
            assert!((e.normal - n).norm() < 1e-5, "{:?} vs {n:?}", e.normal);
        }
    }
}

/// Every first and second derivative of the exact gap (positions, both
/// bodies' rotations, mixed) against finite differences
/// ([`jamkit_kit::pair_derivatives`]: ε = 1e-6 for the gradient,
/// truncation ε²|h'''| ~ 1e-11, round-off ~1e-10 with the normal
/// converged to ~1e-15, bound 1e-8; second central differences with
/// ε = 1e-4, truncation ε²|h''''|/12 ≲ 1e-7, round-off 4·1e-16/ε² ~ 4e-8,
/// bound 1e-5 on entries up to ~1). At the poles `±Q_i e_z`, next to them
/// and generic, overlapping and apart, three orientations per body.
/// Both solvers of the exact gap (`exact_solver`).
#[test]
fn exact_pair_derivatives_match_finite_differences() {
    let mut largest: f64 = 0.0;
    let joint = shapes()
        .into_iter()
        .map(|s| s.with_exact_solver(ExactSolver::Joint));
    for s in shapes().into_iter().chain(joint) {
        for o_i in orientations() {
            for o_j in orientations().iter().rev() {
                for r in separations(&s, &o_i, o_j) {
                    let d = jamkit_kit::pair_derivatives(&s, SIZES, &o_i, o_j, &r, 1e-6, 1e-4);
                    largest = largest.max(d.largest_second());
                    assert!(
                        d.grad_error() < 1e-8 && d.hess_error() < 1e-5,
                        "{s:?} at r = {r:?}, o_i = {o_i:?}: grad error {}, hess error {}",
                        d.grad_error(),
                        d.hess_error()
                    );
                }
            }
        }
    }
    assert!(largest > 0.5, "largest second derivative {largest}");
}

/// `h_ij = h_ji`: swapping the bodies (and sizes) and reversing `r_ij`
/// gives the same gap (1e-14), `∂h/∂r_j` reversed and the rotational
/// derivatives swapped (1e-12: the searches from `r̂` and `−r̂` stop at
/// normals equal to round-off).
#[test]
fn exact_gap_is_symmetric() {
    let os = orientations();
    for s in shapes() {
        for r in separations(&s, &os[1], &os[2]) {
            jamkit_kit::check_swapped(&s, SIZES, &os[1], &os[2], &r, 1e-14, 1e-12);
        }
    }
}

/// Turning the whole pair by one rotation `U` (centres and both
/// orientations, `Q → U Q`) leaves the exact gap unchanged (1e-14) and
/// turns `∂h/∂r_j` by `U` (1e-12); the world-frame torques turn by `U`,
/// the body-frame ones of an axisymmetric `F` do not change.
#[test]
fn exact_gap_is_invariant_under_a_global_rotation() {
    let turn = Quaternion::normalized(0.4, 0.7, -0.3, 0.5).unwrap();
    let os = orientations();
    for s in shapes() {
        for r in separations(&s, &os[2], &os[1]) {
            let a = contact(&s, &os[2], &os[1], &r);
            let (ti, tj) = (turn.mul(&os[2]), turn.mul(&os[1]));
            let b = contact(&s, &ti, &tj, &turn.apply(&r));
            assert_relative_eq!(a.gap, b.gap, epsilon = 1e-14);
            assert_relative_eq!(turn.apply(&a.grad_r), b.grad_r, epsilon = 1e-12);
            for (qa, qb) in [(a.grad_rot_i, b.grad_rot_i), (a.grad_rot_j, b.grad_rot_j)] {
                let qa = Vector::<3>::new(qa[0], qa[1], qa[2]);
                let qb = Vector::<3>::new(qb[0], qb[1], qb[2]);
                if s.is_axisymmetric() {
                    assert_relative_eq!(qa, qb, epsilon = 1e-12);
                } else {
                    assert_relative_eq!(turn.apply(&qa), qb, epsilon = 1e-12);
                }
            }
        }
    }
}

/// The least-squares slope of `ln y` against `ln x`.
fn log_slope(x: &[f64], y: &[f64]) -> f64 {
    let (lx, ly): (Vec<f64>, Vec<f64>) = (
        x.iter().map(|v| v.ln()).collect(),
        y.iter().map(|v| v.ln()).collect(),
    );
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// The first-order gap's error against the exact one scales as `Δ²`:
/// for `Ŷ_20`, `Ŷ_22` and the mixed sum, at two generic orientation pairs
/// and separations near contact (`r = R_i⁰ + R_j⁰`), the largest
/// `|h₁ − h|` over the configurations at Δ = 0.0025, 0.005, 0.01, 0.02
/// has a log–log slope within 0.05 of 2 (measured 1.99–2.02; a wrong
/// first-order term would give 1, a missing `Δ²` effect 3 or more).
#[test]
fn first_order_error_scales_as_delta_squared() {
    let os = orientations();
    let deltas = [0.0025, 0.005, 0.01, 0.02];
    let dirs = [
        Vector::<3>::new(0.5, -0.7, 0.6).normalize(),
        Vector::<3>::new(-0.9, 0.3, 0.45).normalize(),
    ];
    type Make = fn(f64) -> Harmonic;
    let makes: [(Make, &str); 3] = [
        (|d| single(2, 0, d), "Y20"),
        (|d| single(2, 2, d), "Y22"),
        (mixed, "mixed"),
    ];
    for (make, name) in makes {
        let errors: Vec<f64> = deltas
            .iter()
            .map(|&d| {
                let (first, ex) = (make(d), exact(make(d)));
                let mut worst: f64 = 0.0;
                for (o_i, o_j) in [(os[1], os[2]), (os[2], os[0])] {
                    for u in dirs {
                        let r = u * (SIZES.0 + SIZES.1);
                        let h1 = contact(&first, &o_i, &o_j, &r).gap;
                        let h = contact(&ex, &o_i, &o_j, &r).gap;
                        worst = worst.max((h1 - h).abs());
                    }
                }
                worst
            })
            .collect();
        let slope = log_slope(&deltas, &errors);
        eprintln!("first-order error {name}: {errors:?}, slope {slope:.4}");
        assert!(
            (slope - 2.0).abs() < 0.05,
            "{name}: slope {slope}, errors {errors:?}"
        );
    }
}

/// `gap: "SecondOrder"` is refused (no second-order gap in 3D) and
/// `gap: "Exact"` on a body that is not convex, both naming `params.gap`;
/// the default is the first-order gap.
#[test]
fn gap_parameter_is_checked() {
    let e = single(2, 0, 0.2)
        .with_gap(GapModel::SecondOrder)
        .unwrap_err()
        .to_string();
    assert!(e.contains("params.gap") && e.contains("SecondOrder"), "{e}");
    let bumpy = single(6, 3, 0.2);
    assert!(!bumpy.is_convex(CONVEXITY_GRID));
    let e = bumpy.with_gap(GapModel::Exact).unwrap_err().to_string();
    assert!(e.contains("params.gap") && e.contains("non-convex"), "{e}");
    assert_eq!(single(2, 0, 0.2).gap_model(), GapModel::FirstOrder);
    assert_eq!(exact(single(2, 0, 0.2)).gap_model(), GapModel::Exact);
}

/// The largest `Δ` (to 2⁻¹⁴ of the first non-convex step of 0.05) at
/// which `make(Δ)` is a valid convex body ([`Harmonic::is_convex`] on the
/// [`CONVEXITY_GRID`]).
fn convexity_limit(make: impl Fn(f64) -> Option<Harmonic>) -> f64 {
    let ok = |d: f64| make(d).is_some_and(|h| h.is_convex(CONVEXITY_GRID));
    let mut hi = 0.05;
    while ok(hi) {
        hi += 0.05;
    }
    let mut lo = hi - 0.05;
    for _ in 0..14 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// `exact_solver: "Joint"` against the nested solve: the bodies of the
/// other checks and `Ŷ_20`, `Ŷ_22`, `Ŷ_3,−1` and the mixed sum at 0.98 of
/// their convexity limit (Δ ≈ 0.28–0.5, far beyond a jamming run's), all
/// orientation pairs, along `±Q_i e_z`, 10⁻³ off it and generic,
/// overlapping and apart. The joint iteration converges without falling
/// back (`exact_joint_alone`), in at most 8 steps, and the gap, the normal,
/// the support points, the contact and every entry of the gap's Hessian
/// (positions and rotations) agree with the nested solve's to 1e-10
/// relative (both stop within ~10⁻¹⁴ of the same optimum; the Hessian
/// goes through two 3 × 3 inverses of matrices with entries ~0.1–1).
#[test]
fn joint_solver_agrees_with_the_nested_one() {
    let mut bodies = shapes();
    for (l, m) in [(2, 0), (2, 2), (3, -1)] {
        let limit = convexity_limit(|d| Harmonic::single(l, m, d).ok());
        bodies.push(exact(single(l, m, 0.98 * limit)));
    }
    let limit = convexity_limit(|d| Some(mixed(d)));
    bodies.push(exact(mixed(0.98 * limit)));
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-10 * a.abs().max(b.abs()).max(1.0);
    let (mut pairs, mut most) = (0, 0);
    for s in bodies {
        let joint = s.clone().with_exact_solver(ExactSolver::Joint);
        let m = s.rot_dof();
        for o_i in orientations() {
            for o_j in orientations().iter().rev() {
                let (ci, cj) = (o_i.columns(), o_j.columns());
                let (ai, aj) = (s.axes(&ci), s.axes(&cj));
                for r in separations(&s, &o_i, o_j) {
                    let alone = gap3d::exact_joint_alone(
                        &r,
                        &gap3d::RadialBody {
                            columns: &ci,
                            radial: |y: &Vector<3>| s.joint_jet(SIZES.0, y),
                        },
                        &gap3d::RadialBody {
                            columns: &cj,
                            radial: |y: &Vector<3>| s.joint_jet(SIZES.1, y),
                        },
                        f64::INFINITY,
                        true,
                    );
                    let gap3d::Joint::Found(alone, _) = alone else {
                        panic!("{s:?} at {r:?}: the joint iteration fell back");
                    };
                    most = most.max(alone.iterations);
                    let want = s
                        .exact_gap(SIZES.0, &o_i, SIZES.1, o_j, &r, f64::INFINITY)
                        .unwrap();
                    let got = joint
                        .exact_gap(SIZES.0, &o_i, SIZES.1, o_j, &r, f64::INFINITY)
                        .unwrap();
                    assert_eq!(got, alone);
                    let at = format!("{s:?} at r = {r:?}, o_i = {o_i:?}");
                    assert!(
                        close(got.gap, want.gap),
                        "{at}: h {} vs {}",
                        got.gap,
                        want.gap
                    );
                    assert!((got.normal - want.normal).norm() < 1e-10, "{at}");
                    assert!((got.jet_i.point - want.jet_i.point).norm() < 1e-10, "{at}");
                    assert!((got.jet_j.point - want.jet_j.point).norm() < 1e-10, "{at}");
                    let (hg, hw) = (got.hessian(&ai, &aj, m), want.hessian(&ai, &aj, m));
                    for p in 0..m {
                        assert!(close(hg.contact.grad_rot_i[p], hw.contact.grad_rot_i[p]));
                        assert!(close(hg.contact.grad_rot_j[p], hw.contact.grad_rot_j[p]));
                        for q in 0..m {
                            assert!(close(hg.qi_qi[p][q], hw.qi_qi[p][q]), "{at}");
                            assert!(close(hg.qj_qj[p][q], hw.qj_qj[p][q]), "{at}");
                            assert!(close(hg.qi_qj[p][q], hw.qi_qj[p][q]), "{at}");
                        }
                        for a in 0..3 {
                            assert!(close(hg.r_qi[p][a], hw.r_qi[p][a]), "{at}");
                            assert!(close(hg.r_qj[p][a], hw.r_qj[p][a]), "{at}");
                        }
                    }
                    for a in 0..3 {
                        for b in 0..3 {
                            assert!(close(hg.rr[(a, b)], hw.rr[(a, b)]), "{at}");
                        }
                    }
                    pairs += 1;
                }
            }
        }
    }
    eprintln!("joint against nested: {pairs} pairs, at most {most} joint steps");
    assert_eq!(pairs, 9 * 9 * 10);
    assert!(most <= 8, "{most} steps");
}
