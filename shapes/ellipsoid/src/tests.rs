//! Pair-level checks of the `ellipsoid` family: every first and second
//! derivative against finite differences, `h_ij = h_ji`, invariance under
//! a global rotation, the gap against a brute-force scan of directions and
//! against the distance of the two surfaces computed from points, the
//! sphere limit, the skip test, the drawing surface, the parameters.

use super::*;
use approx::assert_relative_eq;
use jamkit_core::{Pair, ShapeExt};

fn spheroid(alpha: f64) -> Ellipsoid {
    Ellipsoid::spheroid(alpha).unwrap()
}

fn triaxial(axes: [f64; 3]) -> Ellipsoid {
    Ellipsoid::triaxial(axes).unwrap()
}

/// Prolate, oblate, near the sphere, long, flat and triaxial.
fn shapes() -> Vec<Ellipsoid> {
    vec![
        spheroid(1.5),
        spheroid(0.6),
        spheroid(1.05),
        spheroid(3.0),
        spheroid(1.0 / 3.0),
        triaxial([1.0, 1.4, 2.2]),
    ]
}

fn orientations() -> Vec<Quaternion> {
    vec![
        Quaternion::IDENTITY,
        Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap(),
        Quaternion::normalized(-0.7, 0.1, 0.4, 0.2).unwrap(),
    ]
}

const SIZES: (f64, f64) = (0.5, 0.7);

/// Directions of the line of centres: along body `i`'s `z` axis (tip to
/// tip when both are identity: aligned axes), 10⁻³ off it, along its `x`
/// axis, and generic; each at a distance where the gap is about `δ`
/// (from `g` at the line of centres, a lower bound on `h`), overlapping
/// (`δ = −0.03`) and apart (`δ = 0.04`).
fn separations(s: &Ellipsoid, o_i: &Quaternion, o_j: &Quaternion) -> Vec<Vector<3>> {
    let dirs = [
        o_i.apply(&Vector::<3>::z()),
        o_i.apply(&Vector::<3>::new(1e-3, -2e-3, 1.0)).normalize(),
        o_i.apply(&Vector::<3>::x()),
        Vector::<3>::new(0.5, -0.7, 0.6).normalize(),
        Vector::<3>::new(-0.9, 0.3, 0.45).normalize(),
    ];
    let (si, sj) = (s.support(SIZES.0, o_i), s.support(SIZES.1, o_j));
    let mut out = Vec::new();
    for d in dirs {
        let reach = si.jet(&d).h + sj.jet(&-d).h;
        for delta in [-0.03, 0.04] {
            out.push(d * (reach + delta));
        }
    }
    out
}

fn contact(s: &Ellipsoid, o_i: &Quaternion, o_j: &Quaternion, r: &Vector<3>) -> Contact<3> {
    let c = s.pair_contacts(&Pair::new(SIZES.0, *o_i, SIZES.1, *o_j, *r), f64::INFINITY);
    assert_eq!(c.len(), 1);
    c[0]
}

/// Every first derivative of one contact against central differences of
/// its gap (ε = 1e-6: truncation ε²|h'''|/6 ≲ 1e-10 for these radii of
/// curvature ≥ 0.1, round-off 1e-16/ε ~ 1e-10; bound 1e-8), and every
/// second derivative (positions, all rotations, both bodies and mixed)
/// against second central differences of the gap (ε = 1e-4: truncation
/// ε²|h''''|/12 ≲ 1e-6 with `h''''` up to ~10² at the flat bodies' rims,
/// round-off 4·1e-16/ε² ~ 4e-8; bound 1e-5 absolute on entries up to ~10).
/// Prolate, oblate, near-sphere, long, flat and triaxial bodies, at three
/// orientations each, aligned (tip to tip), 10⁻³ off aligned, side on and
/// generic, overlapping and apart: 1080 pairs.
#[test]
fn pair_derivatives_match_finite_differences() {
    let mut largest: f64 = 0.0;
    for s in shapes() {
        for o_i in orientations() {
            for o_j in orientations().iter().rev() {
                for r in separations(&s, &o_i, o_j) {
                    let d = jamkit_kit::pair_derivatives(&s, SIZES, &o_i, o_j, &r, 1e-6, 1e-4);
                    largest = largest.max(d.largest_second());
                    assert!(
                        d.grad_error() < 1e-8 && d.hess_error() < 1e-5,
                        "{s:?} at r = {r:?}, o_i = {o_i:?}: {d:?}"
                    );
                }
            }
        }
    }
    // The second derivatives are not all small (the test has teeth).
    assert!(largest > 1.0, "largest second derivative {largest}");
}

/// `h_ij = h_ji`: swapping the bodies and reversing `r_ij` gives the same
/// gap (1e-14), `∂h/∂r_j` reversed and the rotational derivatives swapped
/// (1e-12: the Newton iterations from `r̂` and `−r̂` stop at normals equal
/// to ~1e-16, and the torques are products of order-1 numbers).
#[test]
fn gap_is_symmetric() {
    for s in shapes() {
        let os = orientations();
        for r in separations(&s, &os[1], &os[2]) {
            // The sizes swap with the bodies.
            jamkit_kit::check_swapped(&s, SIZES, &os[1], &os[2], &r, 1e-14, 1e-12);
        }
    }
}

/// Turning the whole pair by one rotation `U` (centres and both
/// orientations, `Q → U Q`) leaves the gap unchanged (1e-14) and turns
/// `∂h/∂r_j` by `U` (1e-12); the world-frame torques of a triaxial body
/// turn by `U`, the body-frame ones of a spheroid do not change.
#[test]
fn pair_is_invariant_under_a_global_rotation() {
    let turns = [
        Quaternion::normalized(0.4, 0.7, -0.3, 0.5).unwrap(),
        Quaternion::normalized(-0.1, 0.2, 0.9, -0.4).unwrap(),
    ];
    for s in shapes() {
        let os = orientations();
        for r in separations(&s, &os[2], &os[1]) {
            let a = contact(&s, &os[2], &os[1], &r);
            for turn in turns {
                let (ti, tj) = (turn.mul(&os[2]), turn.mul(&os[1]));
                let b = contact(&s, &ti, &tj, &turn.apply(&r));
                assert_relative_eq!(a.gap, b.gap, epsilon = 1e-14);
                assert_relative_eq!(turn.apply(&a.grad_r), b.grad_r, epsilon = 1e-12);
                for (qa, qb) in [(a.grad_rot_i, b.grad_rot_i), (a.grad_rot_j, b.grad_rot_j)] {
                    if s.is_axisymmetric() {
                        for p in 0..3 {
                            assert_relative_eq!(qa[p], qb[p], epsilon = 1e-12);
                        }
                    } else {
                        let ta = turn.apply(&Vector::<3>::new(qa[0], qa[1], qa[2]));
                        assert_relative_eq!(
                            ta,
                            Vector::<3>::new(qb[0], qb[1], qb[2]),
                            epsilon = 1e-12
                        );
                    }
                }
            }
        }
    }
}

/// `g(u) = u·r − s_i(u) − s_j(−u)` written out from the semi-axes in the
/// body frames (`s(u) = |diag(a, b, c) Qᵀ u|`), not from the pair code's
/// quadratic form.
fn g_written_out(
    s: &Ellipsoid,
    o_i: &Quaternion,
    o_j: &Quaternion,
    r: &Vector<3>,
    u: &Vector<3>,
) -> f64 {
    let sup = |size: f64, o: &Quaternion, v: &Vector<3>| {
        let y = o.conjugate().apply(v);
        let ax = s.semi_axes(size);
        Vector::<3>::new(ax[0] * y[0], ax[1] * y[1], ax[2] * y[2]).norm()
    };
    u.dot(r) - sup(SIZES.0, o_i, u) - sup(SIZES.1, o_j, &-u)
}

fn unit(theta: f64, phi: f64) -> Vector<3> {
    Vector::<3>::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// The maximum of `g` over directions by brute force: the best of a
/// Fibonacci lattice of 40 000 directions (spacing ~0.018 rad), then a
/// pattern search in `(θ, φ)` about it, with steps shrinking from the
/// lattice spacing to 1e-12. The chart is turned by a fixed generic
/// rotation, so that no maximum of the cases sits at its poles.
fn brute_force_max(g: impl Fn(&Vector<3>) -> f64) -> (f64, Vector<3>) {
    let chart = Quaternion::normalized(0.2, 0.9, -0.4, 0.3).unwrap();
    let unit = |t: f64, p: f64| chart.apply(&unit(t, p));
    let f = |v: &Vector<3>| g(v);
    let n = 40_000;
    let golden = PI * (3.0 - 5f64.sqrt());
    let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
    for k in 0..n {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
        let (theta, phi) = (z.acos(), golden * k as f64);
        let v = f(&unit(theta, phi));
        if v > best.0 {
            best = (v, theta, phi);
        }
    }
    let (mut t, mut p) = (best.1, best.2);
    let mut step = 0.02;
    while step > 1e-12 {
        let mut moved = false;
        for (dt, dp) in [(step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)] {
            if f(&unit(t + dt, p + dp)) > f(&unit(t, p)) {
                t += dt;
                p += dp;
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    (f(&unit(t, p)), unit(t, p))
}

/// The exact gap is the maximum of `g` over all directions: a brute-force
/// scan of `g` written out from the semi-axes agrees to 1e-12 in the gap
/// (both reach the top of a smooth maximum: an angle error ε costs ~ε²)
/// and 1e-5 in the normal (the pattern search pins the angle only to
/// ~√(1e-16/curvature)), for separated and overlapping pairs of prolate,
/// oblate and triaxial bodies at generic orientations.
#[test]
fn gap_is_the_maximum_over_all_directions() {
    let (mut cases, mut overlapping) = (0, 0);
    for s in [spheroid(2.0), spheroid(0.5), triaxial([1.0, 1.4, 2.2])] {
        let os = orientations();
        for (o_i, o_j) in [(os[1], os[2]), (os[2], os[0]), (os[0], os[1])] {
            for r in separations(&s, &o_i, &o_j).into_iter().skip(2) {
                for scale in [0.98, 1.0, 1.05] {
                    let r = r * scale;
                    let e = s
                        .exact_gap(SIZES.0, &o_i, SIZES.1, &o_j, &r, f64::INFINITY)
                        .unwrap();
                    assert!(e.converged, "{e:?}");
                    let (best, u) = brute_force_max(|u| g_written_out(&s, &o_i, &o_j, &r, u));
                    assert_relative_eq!(e.gap, best, epsilon = 1e-12);
                    assert!((e.normal - u).norm() < 1e-5, "{:?} vs {u:?}", e.normal);
                    cases += 1;
                    overlapping += usize::from(e.gap < 0.0);
                }
            }
        }
    }
    assert_eq!(cases, 3 * 3 * 8 * 3);
    assert!(
        overlapping >= 25 && cases - overlapping >= 25,
        "{overlapping} of {cases}"
    );
}

/// The point of body `i`'s surface with polar angles `(t, p)` of the
/// parametrisation `Q diag(a, b, c) (sin t cos p, sin t sin p, cos t)`.
fn surface_point(
    s: &Ellipsoid,
    size: f64,
    o: &Quaternion,
    centre: &Vector<3>,
    t: f64,
    p: f64,
) -> Vector<3> {
    let ax = s.semi_axes(size);
    let y = unit(t, p);
    centre + o.apply(&Vector::<3>::new(ax[0] * y[0], ax[1] * y[1], ax[2] * y[2]))
}

/// The distance of two surfaces from points alone: the closest pair on a
/// 36⁴ grid of the two parametrisations, then a pattern search on the four
/// angles with steps shrinking to 1e-13.
fn surface_distance(s: &Ellipsoid, o_i: &Quaternion, o_j: &Quaternion, r: &Vector<3>) -> f64 {
    let zero = Vector::<3>::zeros();
    let dist = |x: &[f64; 4]| {
        (surface_point(s, SIZES.1, o_j, r, x[2], x[3])
            - surface_point(s, SIZES.0, o_i, &zero, x[0], x[1]))
        .norm()
    };
    let m = 36;
    let angle = |k: usize, full: f64| full * (k as f64 + 0.5) / m as f64;
    let mut best = (f64::INFINITY, [0.0; 4]);
    for a in 0..m {
        for b in 0..m {
            for c in 0..m {
                for d in 0..m {
                    let x = [
                        angle(a, PI),
                        angle(b, 2.0 * PI),
                        angle(c, PI),
                        angle(d, 2.0 * PI),
                    ];
                    let v = dist(&x);
                    if v < best.0 {
                        best = (v, x);
                    }
                }
            }
        }
    }
    let mut x = best.1;
    let mut step = 0.1;
    while step > 1e-13 {
        let mut moved = false;
        for k in 0..4 {
            for sign in [1.0, -1.0] {
                let mut y = x;
                y[k] += sign * step;
                if dist(&y) < dist(&x) {
                    x = y;
                    moved = true;
                }
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    dist(&x)
}

/// The separating-axis gap is the distance of the two surfaces, computed
/// independently from points of their parametrisations (1e-9: the
/// pattern search's closest points are on the surfaces exactly, and it
/// pins the distance to round-off of a smooth minimum). For overlapping
/// pairs, moving body `j` out along the normal by `−h + 0.01` leaves the
/// surfaces exactly 0.01 apart (the depth of penetration along `n` is
/// `−h`; at `u = n` the gap grows by 0.01, elsewhere by less).
#[test]
fn gap_is_the_distance_of_the_surfaces() {
    let os = orientations();
    for s in [spheroid(2.0), spheroid(0.5), triaxial([1.0, 1.4, 2.2])] {
        for (o_i, o_j, r) in [
            (os[1], os[2], Vector::<3>::new(1.0, -0.9, 0.7)),
            (os[2], os[0], Vector::<3>::new(-0.4, 0.3, 1.4)),
            (os[0], os[1], Vector::<3>::new(0.9, 0.9, -0.1)),
        ] {
            let e = s
                .exact_gap(SIZES.0, &o_i, SIZES.1, &o_j, &r, f64::INFINITY)
                .unwrap();
            let (r, h) = if e.gap > 0.0 {
                (r, e.gap)
            } else {
                (r + e.normal * (0.01 - e.gap), 0.01)
            };
            let d = surface_distance(&s, &o_i, &o_j, &r);
            assert_relative_eq!(d, h, epsilon = 1e-9);
        }
    }
}

/// The sphere limit: `α = 1` gives `r − R_i − R_j` to round-off at any
/// orientation; `α = 1 + ε` stays within `(R_i + R_j)(2ε/3)(1 + ε)` of it
/// (`a = R α^{2/3} ≈ R(1 + 2ε/3)`, `b ≈ R(1 − ε/3)`), prolate and oblate.
#[test]
fn nearly_round_bodies_tend_to_spheres() {
    let d = Vector::<3>::new(0.9, 0.75, -0.3);
    let ball = d.norm() - 1.2;
    let os = orientations();
    let round = spheroid(1.0);
    assert!(round.is_ball());
    let h = contact(&round, &os[1], &os[2], &d).gap;
    assert_relative_eq!(h, ball, epsilon = 1e-15);
    for eps in [1e-2, 1e-4, 1e-6, 1e-8] {
        for alpha in [1.0 + eps, 1.0 / (1.0 + eps)] {
            let s = spheroid(alpha);
            for (o_i, o_j) in [(os[0], os[1]), (os[1], os[2]), (os[2], os[2])] {
                let h = contact(&s, &o_i, &o_j, &d).gap;
                assert!(
                    (h - ball).abs() <= 1.2 * 2.0 * eps / 3.0 * (1.0 + eps) + 1e-15,
                    "ε = {eps}: {h} vs {ball}"
                );
            }
        }
    }
}

/// The skip test is safe: a pair skipped for `max_gap` has a gap above it
/// (`g` at the line of centres is a lower bound on `h`), and a pair not
/// skipped has the same gap as with `max_gap = ∞`, bit for bit.
#[test]
fn skipped_pairs_are_farther_than_max_gap() {
    let s = triaxial([1.0, 0.6, 2.0]);
    let mut skipped = 0;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    use rand::SeedableRng;
    for k in 0..400 {
        let (o_i, o_j) = (Quaternion::random(&mut rng), Quaternion::random(&mut rng));
        let x = k as f64;
        let dir = unit(x * 0.7, x * 2.4);
        let r = dir * (0.9 + 1.2 * (x * 0.113).sin().abs());
        let full = contact(&s, &o_i, &o_j, &r).gap;
        for max_gap in [0.0, 0.05] {
            match s.exact_gap(SIZES.0, &o_i, SIZES.1, &o_j, &r, max_gap) {
                None => {
                    skipped += 1;
                    assert!(full > max_gap);
                }
                Some(e) => assert_eq!(e.gap, full),
            }
        }
    }
    assert!(skipped > 100, "{skipped}");
}

/// The Newton iteration converges on random pairs of every body the
/// family accepts, from long (α = 10) to flat (α = 1/10), apart and
/// overlapping by up to 10 % of the small semi-axis, within the iteration
/// counts observed (a regression bound: 12 up to α = 3, 30 beyond).
#[test]
fn newton_converges_quickly() {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for alpha in [1.01, 1.5, 3.0, 1.0 / 3.0, 10.0, 0.1] {
        let s = spheroid(alpha);
        let short = s.ratios().iter().fold(f64::INFINITY, |a, b| a.min(*b)) * SIZES.0;
        let mut worst = 0;
        for _ in 0..300 {
            let (o_i, o_j) = (Quaternion::random(&mut rng), Quaternion::random(&mut rng));
            let dir = Quaternion::random(&mut rng).apply(&Vector::<3>::x());
            let (si, sj) = (s.support(SIZES.0, &o_i), s.support(SIZES.1, &o_j));
            let reach = si.jet(&dir).h + sj.jet(&-dir).h;
            let r = dir * (reach + short * rng.random_range(-0.1..0.3));
            let e = s
                .exact_gap(SIZES.0, &o_i, SIZES.1, &o_j, &r, f64::INFINITY)
                .unwrap();
            assert!(e.converged, "α = {alpha}: {e:?}");
            worst = worst.max(e.iterations);
        }
        let bound = if (1.0 / 3.0..=3.0).contains(&alpha) {
            12
        } else {
            30
        };
        assert!(worst <= bound, "α = {alpha}: {worst} iterations");
    }
}

/// Aligned pairs: tip to tip `r − a_i − a_j`, side by side
/// `r − b_i − b_j`, tip to side `r − a_i − b_j`, separated and overlapping
/// by less than the tips' radius of curvature, in a turned frame (1e-14).
#[test]
fn aligned_spheroids_have_known_gaps() {
    let s = spheroid(1.8);
    let [bi, _, ai] = s.semi_axes(SIZES.0);
    let [bj, _, aj] = s.semi_axes(SIZES.1);
    let turn = Quaternion::normalized(0.4, 0.7, -0.3, 0.5).unwrap();
    let side = turn.mul(&Quaternion::exp(&Vector::<3>::new(PI / 2.0, 0.0, 0.0)));
    let z = turn.apply(&Vector::<3>::z());
    for (o_i, o_j, reach) in [
        (turn, turn, ai + aj),
        (side, side, bi + bj),
        (turn, side, ai + bj),
    ] {
        for delta in [0.2, -0.02] {
            let h = contact(&s, &o_i, &o_j, &(z * (reach + delta))).gap;
            assert_relative_eq!(h, delta, epsilon = 1e-14);
        }
    }
}

/// The drawing surface is the shape: its rotation of the stored
/// quaternion is `Q`, `ρ(y) y` lies on the ellipsoid
/// (`Σ (ρ y_k/ξ_k)² = 1`, 1e-14), the bounds are the extreme semi-axes
/// and hold on a sample, a non-unit quaternion is refused.
#[test]
fn the_drawing_surface_is_the_shape() {
    use rand::SeedableRng;
    let s = triaxial([1.0, 1.4, 2.2]);
    let surface = Shape::<3>::look(&s).surface.unwrap();
    let (lo, hi) = surface.relative_radius_bounds();
    let ratios = s.ratios();
    assert_relative_eq!(lo, ratios[0], epsilon = 1e-15);
    assert_relative_eq!(hi, ratios[2], epsilon = 1e-15);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for _ in 0..50 {
        let q = Quaternion::random(&mut rng);
        let m = surface.rotation(&q.coords()).unwrap();
        let c = q.columns();
        for (k, col) in c.iter().enumerate() {
            for r in 0..3 {
                assert_relative_eq!(m[r][k], col[r], epsilon = 1e-12);
            }
        }
        let y = Quaternion::random(&mut rng).columns()[0];
        let rho = surface.relative_radius([y[0], y[1], y[2]]);
        let on: f64 = (0..3).map(|k| (rho * y[k] / ratios[k]).powi(2)).sum();
        assert_relative_eq!(on, 1.0, epsilon = 1e-14);
        assert!(lo <= rho && rho <= hi);
    }
    assert!(surface.rotation(&[2.0, 0.0, 0.0, 0.0]).is_none());
}

/// The semi-axes: `alpha` gives `(α^{−1/3}, α^{−1/3}, α^{2/3})` with unit
/// product; `axes` are normalised to unit product, and two equal ratios
/// put the distinct axis along body `z` (a spheroid, two coordinates);
/// three equal ratios are the ball. The volume is the ball's.
#[test]
fn axes_are_normalised_and_spheroids_found() {
    let s = spheroid(2.0);
    let r = s.ratios();
    assert_relative_eq!(r[2] / r[0], 2.0, epsilon = 1e-14);
    assert_relative_eq!(r[0] * r[1] * r[2], 1.0, epsilon = 1e-14);
    assert!(s.is_axisymmetric() && Shape::<3>::rot_dof(&s) == 2);
    let t = triaxial([2.0, 3.0, 4.0]);
    assert_relative_eq!(
        t.ratios()[0] * t.ratios()[1] * t.ratios()[2],
        1.0,
        epsilon = 1e-14
    );
    assert_relative_eq!(t.ratios()[2] / t.ratios()[0], 2.0, epsilon = 1e-14);
    assert_eq!(Shape::<3>::rot_dof(&t), 3);
    for axes in [[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]] {
        let e = triaxial(axes);
        assert!(e.is_axisymmetric(), "{axes:?}");
        assert_relative_eq!(e.ratios()[2] / e.ratios()[0], 2.0, epsilon = 1e-14);
        // The same body as alpha = 2.
        assert_relative_eq!(e.ratios()[0], r[0], epsilon = 1e-14);
    }
    assert!(triaxial([1.5, 1.5, 1.5]).is_ball());
    assert!(!triaxial([1.5, 1.5, 1.6]).is_ball());
    assert_relative_eq!(
        Shape::<3>::volume(&t, 0.7),
        4.0 * PI / 3.0 * 0.343,
        epsilon = 1e-15
    );
}

/// The default inertia is that of a uniform solid ellipsoid of unit mass:
/// a spheroid's transverse moment `(a² + b²)/5`, a triaxial body's mean
/// principal moment `2(a² + b² + c²)/15`; the sphere's `2R²/5` at α → 1;
/// `inertia` overrides it for every coordinate.
#[test]
fn default_inertia_is_the_solid_ellipsoids() {
    let s = spheroid(2.0);
    let [b, _, a] = s.semi_axes(0.6);
    assert_relative_eq!(
        s.rot_inertia(0.6)[0],
        (a * a + b * b) / 5.0,
        epsilon = 1e-15
    );
    assert_relative_eq!(
        s.rot_inertia(0.6)[1],
        (a * a + b * b) / 5.0,
        epsilon = 1e-15
    );
    let t = triaxial([1.0, 2.0, 3.0]);
    let [x, y, z] = t.semi_axes(0.6);
    assert_relative_eq!(
        t.rot_inertia(0.6)[2],
        2.0 * (x * x + y * y + z * z) / 15.0,
        epsilon = 1e-15
    );
    assert_relative_eq!(
        spheroid(1.0 + 1e-9).rot_inertia(0.5)[0],
        0.1,
        epsilon = 1e-9
    );
    let fixed = Ellipsoid::new(&EllipsoidParams {
        alpha: Some(2.0),
        axes: None,
        inertia: Some(0.3),
        warm_start: None,
    })
    .unwrap();
    assert_eq!(fixed.rot_inertia(0.6), [0.3; 3]);
}

#[test]
fn bad_parameters_are_refused_with_the_field_named() {
    let p = |alpha: Option<f64>, axes: Option<[f64; 3]>, inertia: Option<f64>| EllipsoidParams {
        alpha,
        axes,
        inertia,
        warm_start: None,
    };
    let cases = [
        (p(Some(0.0), None, None), "params.alpha", "> 0"),
        (p(Some(-1.5), None, None), "params.alpha", "> 0"),
        (p(Some(f64::NAN), None, None), "params.alpha", "> 0"),
        (p(Some(f64::INFINITY), None, None), "params.alpha", "> 0"),
        (p(Some(12.0), None, None), "params.alpha", "≤ 10"),
        (p(Some(0.05), None, None), "params.alpha", "≤ 10"),
        (p(None, None, None), "params", "alpha"),
        (
            p(Some(2.0), Some([1.0, 1.0, 2.0]), None),
            "params.alpha",
            "not both",
        ),
        (
            p(None, Some([1.0, 0.0, 2.0]), None),
            "params.axes[1]",
            "> 0",
        ),
        (
            p(None, Some([1.0, 2.0, f64::NAN]), None),
            "params.axes[2]",
            "> 0",
        ),
        (p(None, Some([1.0, 2.0, 11.0]), None), "params.axes", "≤ 10"),
        (p(Some(2.0), None, Some(0.0)), "params.inertia", "positive"),
        (
            p(Some(2.0), None, Some(f64::NAN)),
            "params.inertia",
            "positive",
        ),
    ];
    for (params, field, allowed) in cases {
        let e = Ellipsoid::new(&params)
            .err()
            .unwrap_or_else(|| panic!("{params:?} accepted"));
        assert_eq!(e.field(), Some(field), "{params:?}: {e}");
        assert!(e.allowed().unwrap().contains(allowed), "{params:?}: {e}");
    }
    // The limits themselves are accepted.
    assert!(Ellipsoid::spheroid(10.0).is_ok() && Ellipsoid::spheroid(0.1).is_ok());
}

/// The asphericity against the spheroids' closed-form surfaces (1e-12
/// relative at 96 nodes, geometric convergence; 48 leave 3e-12 at α = 0.2), prolate
/// `S = 2πb²[1 + (a/(b e)) arcsin e]`, `e² = 1 − b²/a²`, and oblate
/// `S = 2πb²[1 + ((1 − e²)/e) artanh e]`, `e² = 1 − a²/b²`; near the
/// sphere `A − 1 = (8/15)ε² + O(ε³)` (1 % at ε = 10⁻³, where the next order
/// is ~ε relative); a triaxial body's `A` does not depend on the order of
/// its axes (1e-13).
#[test]
fn asphericity_matches_the_closed_forms() {
    for alpha in [1.2, 2.0, 5.0, 0.8, 0.5, 0.2] {
        let s = spheroid(alpha);
        let [b, _, a] = s.ratios();
        let area = if a > b {
            let e = (1.0 - b * b / (a * a)).sqrt();
            2.0 * PI * b * b * (1.0 + a / (b * e) * e.asin())
        } else {
            let e = (1.0 - a * a / (b * b)).sqrt();
            2.0 * PI * b * b * (1.0 + (1.0 - e * e) / e * e.atanh())
        };
        let expected = area.powi(3) / (36.0 * PI * (4.0 * PI / 3.0).powi(2));
        assert_relative_eq!(s.asphericity(96), expected, max_relative = 1e-12);
        assert!(expected > 1.0);
    }
    let eps = 1e-3;
    for alpha in [1.0 + eps, 1.0 / (1.0 + eps)] {
        assert_relative_eq!(
            spheroid(alpha).asphericity(48) - 1.0,
            8.0 / 15.0 * eps * eps,
            max_relative = 1e-2
        );
    }
    let a = triaxial([1.0, 1.4, 2.2]).asphericity(48);
    let b = triaxial([2.2, 1.0, 1.4]).asphericity(48);
    assert_relative_eq!(a, b, max_relative = 1e-13);
    assert_relative_eq!(spheroid(1.0).asphericity(8), 1.0, max_relative = 1e-14);
}
