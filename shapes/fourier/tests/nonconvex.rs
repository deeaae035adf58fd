//! The exact gap of non-convex near-disks (`gap: "Exact"` beyond
//! Δ(n + 1/n) = 1): several contacts per pair, from the outline's arcs
//! between inflection points (`jamkit_planar::arcs`).
//!
//! What is checked: the derivatives against finite differences on random
//! pairs with two, three and more overlapping contacts; the energy along
//! paths on which contacts come and go; the convex exact gap recovered by
//! the arc search on a convex outline; and every contact against an
//! independent check on fine polygons (point in polygon, distance to the
//! polygon).

use jamkit_core::{Contact, GapHessian, Pair, Rotation2, Shape, Vector};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_planar::arcs::split_arcs;
use jamkit_planar::gap2d::GapModel;
use jamkit_planar::profiled::ExactSolve;
use std::f64::consts::TAU;

#[path = "support/polygon.rs"]
mod polygon;
use polygon::{Polygon, support_points};

#[path = "support/random.rs"]
mod random;
use random::Uniform;

fn fourier(n: u32, delta: f64, gap: GapModel) -> NearDisk {
    NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap,
    })
    .unwrap()
}

/// A pair: sizes, angles, separation.
#[derive(Clone, Copy, Debug)]
struct Config {
    size: [f64; 2],
    theta: [f64; 2],
    r: [f64; 2],
}

impl Config {
    fn pair(&self) -> Pair<2, Rotation2> {
        Pair::new(
            self.size[0],
            Rotation2::new(self.theta[0]),
            self.size[1],
            Rotation2::new(self.theta[1]),
            Vector::<2>::new(self.r[0], self.r[1]),
        )
    }

    /// Moved by `eps` along coordinate `c` (0, 1: r_j; 2: θ_i; 3: θ_j).
    fn moved(&self, c: usize, eps: f64) -> Self {
        let mut m = *self;
        match c {
            0 | 1 => m.r[c] += eps,
            2 => m.theta[0] += eps,
            _ => m.theta[1] += eps,
        }
        m
    }

    /// A random pair of sizes 1 and 1.4 (either way round) at random
    /// angles, the centres `(R_i + R_j)(1 + spread·(2u − 1) Δ/n)` apart:
    /// lobes interlocked or about to.
    fn random(rng: &mut Uniform, n: u32, delta: f64, spread: f64) -> Self {
        let size = if rng.next() < 0.5 {
            [1.0, 1.4]
        } else {
            [1.4, 1.0]
        };
        let a = TAU * rng.next();
        let d = (size[0] + size[1]) * (1.0 + spread * (2.0 * rng.next() - 1.0) * delta / n as f64);
        Self {
            size,
            theta: [TAU * rng.next(), TAU * rng.next()],
            r: [d * a.cos(), d * a.sin()],
        }
    }
}

impl Config {
    /// A body of size 1 at a random angle in the valley of a body of size
    /// 8 (the valley's bottom towards `a = π/2n` at `θ_i = 0`), up to
    /// 3 lobe heights deep: it touches the wide valley with several teeth.
    fn in_valley(rng: &mut Uniform, n: u32, delta: f64) -> Self {
        let a = std::f64::consts::PI / (2.0 * n as f64) + 0.3 * (2.0 * rng.next() - 1.0) / n as f64;
        let d = 8.0 * (1.0 - delta / n as f64) + 1.0 - 3.0 * delta / n as f64 * rng.next();
        Self {
            size: [8.0, 1.0],
            theta: [0.0, TAU * rng.next()],
            r: [d * a.cos(), d * a.sin()],
        }
    }
}

fn contacts(s: &NearDisk, c: &Config, max_gap: f64) -> Vec<Contact<2>> {
    let mut out = Vec::new();
    s.contacts(&c.pair(), max_gap, |k| out.push(k));
    out
}

fn hessians(s: &NearDisk, c: &Config, max_gap: f64) -> Vec<GapHessian<2>> {
    let mut out = Vec::new();
    s.gap_hessians(&c.pair(), max_gap, |k| out.push(k)).unwrap();
    out
}

/// The first derivatives of a contact in the order of [`Config::moved`].
fn gradient(c: &Contact<2>) -> [f64; 4] {
    [c.grad_r[0], c.grad_r[1], c.grad_rot_i[0], c.grad_rot_j[0]]
}

/// The second derivatives in the same order.
fn second(h: &GapHessian<2>) -> [[f64; 4]; 4] {
    let rows = [
        [h.rr[(0, 0)], h.rr[(0, 1)], h.r_qi[0][0], h.r_qj[0][0]],
        [h.rr[(1, 0)], h.rr[(1, 1)], h.r_qi[0][1], h.r_qj[0][1]],
        [0.0, 0.0, h.qi_qi[0][0], h.qi_qj[0][0]],
        [0.0, 0.0, h.qi_qj[0][0], h.qj_qj[0][0]],
    ];
    let mut m = rows;
    m[2][0] = rows[0][2];
    m[2][1] = rows[1][2];
    m[3][0] = rows[0][3];
    m[3][1] = rows[1][3];
    m
}

/// The contact of `list` whose normal is nearest `of`'s, if within `tol`.
fn matching<'a>(list: &'a [Contact<2>], of: &Contact<2>, tol: f64) -> Option<&'a Contact<2>> {
    list.iter()
        .map(|c| ((c.grad_r - of.grad_r).norm(), c))
        .filter(|(d, _)| *d < tol)
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| c)
}

/// `k = h + ρ_i + ρ_j` of a contact (from its Hessian: `∂²h/∂r_j²` is
/// `n⊥n⊥ᵀ/k`).
fn curvature_k(h: &GapHessian<2>) -> f64 {
    1.0 / h.rr.trace()
}

/// Random pairs of non-convex near-disks (n = 8, Δ = 0.3; n = 16,
/// Δ = 0.2; n = 3, Δ = 0.8; n = 4, Δ = 0.7), lobes interlocked or about
/// to, a third of them a small body in the valley of one 8 times larger:
/// gradients and second derivatives of every contact with h ≤ 1 against
/// central differences (step 1e-6: truncation ~1e-12 × third derivative,
/// round-off ~1e-10; tolerance 2e-6 on the gradient, 2e-4 relative to the
/// largest second derivative of the contact, which grows as 1/k).
/// Contacts within 0.05 of a fold (|k| < 0.05, where two stationary points
/// are about to merge) are not differentiated. Among the pairs, some have
/// two and some three contacts, and some overlap at two and at three.
/// (Four never occur here: the normals at a pair's contact points are
/// nearly parallel, so the points lie within about one lobe of the line of
/// centres.)
#[test]
fn derivatives_match_finite_differences_with_several_contacts() {
    let mut rng = Uniform::new(11);
    let (mut by_count, mut overlapping) = ([0usize; 6], [0usize; 6]);
    let mut checked = 0;
    for &(n, delta) in &[(8u32, 0.3), (16, 0.2), (3, 0.8), (4, 0.7)] {
        let s = fourier(n, delta, GapModel::Exact);
        assert!(!s.is_convex());
        for k in 0..60 {
            let c = if k % 3 == 0 {
                Config::in_valley(&mut rng, n, delta)
            } else {
                Config::random(&mut rng, n, delta, 2.0)
            };
            let cut = 1.0;
            let list = hessians(&s, &c, cut);
            let plain = contacts(&s, &c, cut);
            // `contacts` and `gap_hessians` visit the same contacts.
            assert_eq!(list.len(), plain.len());
            for (a, b) in list.iter().zip(&plain) {
                assert_eq!(a.contact, *b);
            }
            by_count[list.len().min(5)] += 1;
            overlapping[list.iter().filter(|h| h.contact.gap < 0.0).count().min(5)] += 1;
            let eps = 1e-6;
            for h in &list {
                if curvature_k(h).abs() < 0.05 || h.contact.gap > cut - 1e-3 {
                    continue;
                }
                let g = gradient(&h.contact);
                let m = second(h);
                for k in 0..4 {
                    let (p, q) = (c.moved(k, eps), c.moved(k, -eps));
                    // At the same cut: the saddles a contact is paired with
                    // are found among the arc pairs within it.
                    let (hp, hq) = (hessians(&s, &p, cut), hessians(&s, &q, cut));
                    let lp: Vec<_> = hp.iter().map(|x| x.contact).collect();
                    let lq: Vec<_> = hq.iter().map(|x| x.contact).collect();
                    let (Some(a), Some(b)) = (
                        matching(&lp, &h.contact, 1e-3),
                        matching(&lq, &h.contact, 1e-3),
                    ) else {
                        panic!("{c:?}: contact {h:?} lost under a move of {eps} along {k}");
                    };
                    let fd = (a.gap - b.gap) / (2.0 * eps);
                    assert!(
                        (fd - g[k]).abs() < 2e-6,
                        "n = {n}, {c:?}, coordinate {k}: {fd} against {}",
                        g[k]
                    );
                    let (ga, gb) = (gradient(a), gradient(b));
                    let scale = 1.0 + m.iter().flatten().fold(0.0f64, |x, y| x.max(y.abs()));
                    for l in 0..4 {
                        let fd2 = (ga[l] - gb[l]) / (2.0 * eps);
                        assert!(
                            (fd2 - m[l][k]).abs() < 2e-4 * scale,
                            "n = {n}, {c:?}, ∂²h/∂{l}∂{k}: {fd2} against {} (k = {})",
                            m[l][k],
                            curvature_k(h)
                        );
                    }
                }
                checked += 1;
            }
        }
    }
    eprintln!(
        "{checked} contacts checked; pairs by contacts {by_count:?}, by overlapping contacts {overlapping:?}"
    );
    assert!(checked > 200, "{checked} contacts checked");
    assert!(
        by_count[2] > 0 && by_count[3] > 0 && overlapping[2] > 0 && overlapping[3] > 0,
        "pairs by number of contacts: {by_count:?}, overlapping {overlapping:?}"
    );
}

/// Random pairs of n = 8 (Δ = 0.3) and n = 16 (Δ = 0.2) near contact
/// against polygons of 8192 vertices (edges of ~8e-4 R⁰; a chord leaves the
/// outline by ≲ 1e-6 R⁰ at the sharpest tip): the pair overlaps as
/// polygons exactly when the model has a contact with h < 0, and the
/// deepest vertex of either polygon inside the other is as deep as the
/// model's deepest contact, to 2e-5 R⁰ (pairs whose deepest point is
/// within 2e-5 of touching are not judged). Every overlapping contact's
/// support points are a distance |h| apart along the normal, each inside
/// the other polygon at distance |h| from its edge (same tolerance).
#[test]
fn contacts_agree_with_fine_polygons() {
    let mut rng = Uniform::new(5);
    let mut judged = [0usize; 2];
    for &(n, delta) in &[(8u32, 0.3), (16, 0.2)] {
        let s = fourier(n, delta, GapModel::Exact);
        for _ in 0..150 {
            let c = Config::random(&mut rng, n, delta, 1.2);
            let mut found = Vec::new();
            s.profiled()
                .arc_contacts(&c.pair(), 0.0, None, &mut |e| found.push(e.exact));
            let pi = Polygon::new(&s, c.size[0], c.theta[0], [0.0, 0.0], 8192);
            let pj = Polygon::new(&s, c.size[1], c.theta[1], c.r, 8192);
            let depth = pi.depth_of(&pj).max(pj.depth_of(&pi));
            let model = found.iter().map(|e| -e.gap).fold(0.0, f64::max);
            for e in found.iter().filter(|e| e.gap < -2e-5) {
                let (a, b) = support_points(e, c.r);
                let (cs, sn) = e.normal;
                // The normal is converged to ~1e-13 rad; near an inflection
                // point a support point moves by ρ δψ with ρ up to ~1e3.
                assert!((b[0] - a[0] - e.gap * cs).abs() < 1e-9, "{c:?}: {e:?}");
                assert!((b[1] - a[1] - e.gap * sn).abs() < 1e-9, "{c:?}: {e:?}");
                assert!(pj.contains(a) && pi.contains(b), "{c:?}: {e:?}");
                assert!((pj.distance(a) + e.gap).abs() < 2e-5, "{c:?}: {e:?}");
                assert!((pi.distance(b) + e.gap).abs() < 2e-5, "{c:?}: {e:?}");
            }
            if depth.max(model) < 2e-5 {
                continue;
            }
            judged[usize::from(depth > 0.0)] += 1;
            assert!(
                (depth - model).abs() < 2e-5,
                "n = {n}, {c:?}: polygons {depth}, model {model} from {found:?}"
            );
        }
    }
    assert!(judged[1] > 150, "{judged:?} (apart, overlapping)");
}

/// At `path(t)`: the harmonic energy Σ_{h<0} h²/2 of the pair's contacts,
/// its derivative along the path (the contacts' gradients against the
/// path's velocity by central differences of step 10⁻⁶), and the number of
/// contacts.
fn harmonic_along(s: &NearDisk, path: &dyn Fn(f64) -> Config, t: f64) -> (f64, f64, usize) {
    let list = contacts(s, &path(t), 0.0);
    let e: f64 = list.iter().map(|k| 0.5 * k.gap * k.gap).sum();
    let (p, q) = (path(t + 1e-6), path(t - 1e-6));
    let v = [
        (p.r[0] - q.r[0]) / 2e-6,
        (p.r[1] - q.r[1]) / 2e-6,
        (p.theta[0] - q.theta[0]) / 2e-6,
        (p.theta[1] - q.theta[1]) / 2e-6,
    ];
    let de: f64 = list
        .iter()
        .map(|k| {
            let g = gradient(k);
            k.gap * (0..4).map(|a| g[a] * v[a]).sum::<f64>()
        })
        .sum();
    (e, de, list.len())
}

/// Along paths on which contacts appear and leave, the harmonic energy
/// Σ_{h<0} h²/2 changes step by step by no more than its derivative
/// allows: |E(t + dt) − E(t)| ≤ 1.5 max|dE/dt| dt + 1e-15 at the two ends
/// of the step (dE/dt from the contacts' gradients and the path's velocity;
/// a contact born or lost at h < 0 would jump by h²/2). On each path the
/// number of overlapping contacts changes, and it reaches two. The paths:
/// a body of size 1 rolled (turned and carried) over a quarter turn of a
/// body of size 4 along its outline, a tenth of a lobe of the small one
/// deep; two bodies of size 1 and 1.4 slid past each other, turning, a
/// tenth of a lobe deep. (Paths through a fold at h < 0:
/// [`energy_is_continuous_through_a_fold`].)
#[test]
fn energy_is_continuous_as_contacts_come_and_go() {
    for &(n, delta) in &[(8u32, 0.3), (16, 0.2)] {
        let s = fourier(n, delta, GapModel::Exact);
        let lobe = delta / n as f64;
        let rolled = |t: f64| {
            let a = 0.5 * std::f64::consts::PI * t;
            // The big body's radius towards the small one, plus the small
            // one's, less half a lobe.
            let d = 4.0 * s.relative_radius(0.2 - a) + 1.0 - 0.1 * lobe;
            Config {
                size: [4.0, 1.0],
                theta: [0.2, 0.7 + 5.0 * a],
                r: [d * a.cos(), d * a.sin()],
            }
        };
        let slid = |t: f64| Config {
            size: [1.0, 1.4],
            theta: [0.3, 1.0 + 0.5 * t],
            r: [2.4 * (1.0 - 0.1 * lobe), 0.8 * t - 0.4],
        };
        let paths: [&dyn Fn(f64) -> Config; 2] = [&rolled, &slid];
        let mut two = false;
        for path in paths {
            let energy = |t: f64| harmonic_along(&s, path, t);
            let steps = 4000;
            let dt = 1.0 / steps as f64;
            let mut prev = energy(0.0);
            let mut counts = vec![prev.2];
            for k in 1..=steps {
                let cur = energy(k as f64 * dt);
                let bound = 1.5 * prev.1.abs().max(cur.1.abs()) * dt + 1e-15;
                assert!(
                    (cur.0 - prev.0).abs() <= bound,
                    "n = {n}, t = {}: E {} → {} ({} → {} contacts), bound {bound}",
                    k as f64 * dt,
                    prev.0,
                    cur.0,
                    prev.2,
                    cur.2
                );
                counts.push(cur.2);
                prev = cur;
            }
            counts.dedup();
            eprintln!("n = {n}: counts {counts:?}");
            assert!(counts.len() > 2, "n = {n}: contact counts {counts:?}");
            two |= counts.contains(&2);
        }
        assert!(two, "n = {n}: never two overlapping contacts");
    }
}

/// A step of FIRE in a compressed packing of n = 16, Δ = 0.1 (bodies of
/// size 0.7), stretched to `t ∈ [−1, 2]` (the step is `t ∈ [0, 1]`): a
/// tip's flank in the mouth of a valley, six hundredths of a lobe deep,
/// where the contact of arcs 20 (concave) and 11 (convex) meets the saddle
/// of the same arcs at `t ≈ 0.14`, `h ≈ −6.1·10⁻⁴`, and leaves (a fold).
fn fold_path(t: f64) -> Config {
    segment(
        [[-1.240604858, -2.812204518], [-1.240686550, -2.812325416]],
        [
            [-1.277477671288, 0.557135519072],
            [-1.277439931465, 0.557253542028],
        ],
        t,
    )
}

/// Two bodies of size 0.7 moved along a straight segment of their
/// coordinates, from `theta[0]`, `r[0]` at `t = 0` to `theta[1]`, `r[1]`
/// at `t = 1`.
fn segment(theta: [[f64; 2]; 2], r: [[f64; 2]; 2], t: f64) -> Config {
    between([0.7, 0.7], theta, r, t)
}

/// Through the fold of [`fold_path`] the harmonic energy Σ h²/2 changes
/// step by step (3000 steps) by no more than 1.5 times its largest
/// derivative at the two ends of the step, plus 10⁻¹⁸ (the energy is
/// ~4·10⁻⁷, its change per step ~10⁻¹³; the contact leaving with its own
/// h would jump by h²/2 ≈ 1.9·10⁻⁷). Along the path the pair goes from
/// two contacts, one with a saddle, to one.
#[test]
fn energy_is_continuous_through_a_fold() {
    let s = fourier(16, 0.1, GapModel::Exact);
    let energy = |t: f64| {
        let (e, de, count) = harmonic_along(&s, &fold_path, t);
        let mut saddles = 0;
        s.profiled()
            .arc_contacts(&fold_path(t).pair(), 0.0, None, &mut |e| {
                saddles += usize::from(e.saddle.is_some());
            });
        (e, de, count, saddles)
    };
    let steps = 3000;
    let dt = 3.0 / steps as f64;
    let mut prev = energy(-1.0);
    assert_eq!((prev.2, prev.3), (2, 1), "two contacts, one with a saddle");
    for k in 1..=steps {
        let t = -1.0 + k as f64 * dt;
        let cur = energy(t);
        let bound = 1.5 * prev.1.abs().max(cur.1.abs()) * dt + 1e-18;
        assert!(
            (cur.0 - prev.0).abs() <= bound,
            "t = {t}: E {} → {} ({} → {} contacts), bound {bound}",
            prev.0,
            cur.0,
            prev.2,
            cur.2
        );
        prev = cur;
    }
    assert_eq!((prev.2, prev.3), (1, 0), "one contact left");
}

/// A stretch of FIRE's path in a compressed packing of n = 16, Δ = 0.1
/// (bodies of size 0.7, `t ∈ [0, 1]`) on which two contacts of one pair
/// (arcs 27 and 30, 28 and 29), ~1.4·10⁻³ deep and 2·10⁻³ apart in depth at
/// the ends, with a saddle ~1.2·10⁻³ deep between them, become equally
/// deep (their order in depth changes).
fn crossing_path(t: f64) -> Config {
    segment(
        [[-1.344702222, 1.404168162], [-1.344737662, 1.404581621]],
        [
            [-0.676838869520, -1.216811736086],
            [-0.676914106312, -1.216800208051],
        ],
        t,
    )
}

/// Along [`crossing_path`] (1000 steps) the harmonic energy Σ h²/2
/// follows the trapezoid rule of its derivative step by step to 10⁻¹⁵:
/// the energy is `h₁²/2 + h₂²/2 − h_s²/2` whichever contact takes the
/// saddle, smooth, and the rule misses by the round-off of the gaps,
/// ~10⁻¹⁴ × |h| ~ 10⁻¹⁷ (E ~ 8·10⁻⁷, dE/dt ~ −3·10⁻⁸, dt³ E‴/12 far
/// below). A saddle whose share of the energy depends on which contact
/// takes it (as a prominence `h_c − h_s²/h_c` does) puts a kink where the
/// depths cross, and the step over it misses by ~10⁻¹¹.
#[test]
fn energy_is_smooth_where_two_contacts_of_a_saddle_are_equally_deep() {
    let s = fourier(16, 0.1, GapModel::Exact);
    let steps = 1000;
    let dt = 1.0 / steps as f64;
    let mut prev = harmonic_along(&s, &crossing_path, 0.0);
    assert_eq!(prev.2, 2, "two overlapping contacts");
    let mut worst: f64 = 0.0;
    for k in 1..=steps {
        let cur = harmonic_along(&s, &crossing_path, k as f64 * dt);
        assert_eq!(cur.2, 2, "two overlapping contacts at step {k}");
        let miss = (cur.0 - prev.0) - 0.5 * (cur.1 + prev.1) * dt;
        worst = worst.max(miss.abs());
        prev = cur;
    }
    eprintln!("largest miss of the trapezoid rule: {worst:e}");
    assert!(
        worst < 1e-15,
        "largest miss of the trapezoid rule {worst:e}"
    );
}

/// The gradient and the second derivatives of a contact with a saddle
/// ([`fold_path`] at `t ∈ [−1, 0]`, 2·10⁻⁵ to 2·10⁻⁴ from the fold)
/// against central differences (step 10⁻⁸: truncation ~10⁻¹⁶ × third
/// derivatives up to ~10⁶ near the fold, round-off ~10⁻⁸ on the second
/// derivatives): tolerance 10⁻⁷ on the gradient, 10⁻⁵ relative to the
/// largest second derivative, each times `κ = h_c/h`. The gap
/// `h = −√(h_c² − h_s²)` carries the round-off of `h_c` and `h_s`
/// (~10⁻¹⁶) multiplied by `κ` (57 and more on this path, where the two
/// are within 10⁻⁷ of each other), and so do its differences: from steps
/// of 3·10⁻⁹, 10⁻⁸ and 3·10⁻⁸ the first derivative at `t = −1` scatters
/// by 1.5·10⁻⁶ about the analytic one, not as a truncation error would.
#[test]
fn a_contact_with_a_saddle_matches_finite_differences() {
    let s = fourier(16, 0.1, GapModel::Exact);
    let (mut checked, mut worst_kappa) = (0, 0.0f64);
    for k in 0..=10 {
        let c = fold_path(-1.0 + 0.1 * k as f64);
        let mut with_saddle = Vec::new();
        s.profiled().arc_contacts(&c.pair(), 0.0, None, &mut |e| {
            if e.saddle.is_some() {
                with_saddle.push((e.hessian(), e.exact.gap / e.gap()));
            }
        });
        assert_eq!(with_saddle.len(), 1, "{c:?}");
        let (h, kappa) = with_saddle[0];
        worst_kappa = worst_kappa.max(kappa);
        let (g, m) = (gradient(&h.contact), second(&h));
        let scale = m.iter().flatten().fold(0.0f64, |x, y| x.max(y.abs()));
        let eps = 1e-8;
        for a in 0..4 {
            let (lp, lq) = (
                contacts(&s, &c.moved(a, eps), 0.0),
                contacts(&s, &c.moved(a, -eps), 0.0),
            );
            let (Some(p), Some(q)) = (
                matching(&lp, &h.contact, 1e-2),
                matching(&lq, &h.contact, 1e-2),
            ) else {
                panic!("{c:?}: contact lost under a move of {eps} along {a}");
            };
            let fd = (p.gap - q.gap) / (2.0 * eps);
            assert!(
                (fd - g[a]).abs() < 1e-7 * kappa,
                "{c:?}, {a}: {fd} against {}",
                g[a]
            );
            let (gp, gq) = (gradient(p), gradient(q));
            for b in 0..4 {
                let fd2 = (gp[b] - gq[b]) / (2.0 * eps);
                assert!(
                    (fd2 - m[b][a]).abs() < 1e-5 * kappa * scale,
                    "{c:?}, ∂²h/∂{b}∂{a}: {fd2} against {}",
                    m[b][a]
                );
            }
        }
        checked += 1;
    }
    assert_eq!(checked, 11);
    assert!(worst_kappa > 10.0, "{worst_kappa}: no point near the fold");
}

/// On a convex outline (n = 3, Δ = 0.2; n = 16, Δ = 0.04) the arc search,
/// with the whole outline as its one arc and no cut, finds as its contact
/// of largest h the convex exact gap's (nested solve), to round-off (any
/// other is a local maximum of g on the far sides, deeper than a radius,
/// which `arc_contacts`' bounding circles leave out): gap 1e-13, normal and
/// torques 1e-10, second derivatives 1e-7 relative (the two solvers stop
/// within ~1e-14 rad of the optimum by different routes). And `Exact` on a
/// convex outline keeps the convex code path (no arcs).
#[test]
fn convex_outlines_give_the_convex_exact_gap() {
    let mut rng = Uniform::new(3);
    for &(n, delta) in &[(3u32, 0.2), (16, 0.04)] {
        let s = fourier(n, delta, GapModel::Exact);
        assert!(s.is_convex() && s.profiled().arcs().is_none());
        let p = s.profiled();
        let whole = split_arcs(&|u| p.unit_outline(u), 8192);
        assert_eq!(whole.len(), 1);
        for _ in 0..200 {
            let c = Config::random(&mut rng, n, delta, 3.0);
            let pair = c.pair();
            let convex = p
                .exact_solve(&pair, f64::INFINITY, ExactSolve::Nested)
                .unwrap();
            let mut found = Vec::new();
            let mut saddle = None;
            p.arc_contacts(&pair, f64::INFINITY, Some(&whole), &mut |e| {
                if saddle.is_none_or(|(h, _)| e.exact.gap > h) {
                    saddle = Some((e.exact.gap, e.saddle));
                }
                found.push(e.exact)
            });
            // The contact of largest h has no saddle.
            assert_eq!(saddle.map(|s| s.1), Some(None), "{c:?}");
            found.sort_by(|a, b| b.gap.total_cmp(&a.gap));
            // Others are maxima of g on the far sides, through both bodies.
            assert!(found.len() == 1 || found[1].gap < -1.0, "{c:?}: {found:?}");
            let a = found[0];
            assert!((a.gap - convex.gap).abs() < 1e-13, "{a:?} {convex:?}");
            let (ca, cb) = (a.contact(), convex.contact());
            for (x, y) in gradient(&ca).iter().zip(gradient(&cb)) {
                assert!((x - y).abs() < 1e-10, "{ca:?} {cb:?}");
            }
            let (ha, hb) = (second(&a.hessian_signed()), second(&convex.hessian()));
            for (x, y) in ha.iter().flatten().zip(hb.iter().flatten()) {
                assert!((x - y).abs() < 1e-7 * (1.0 + y.abs()), "{ha:?} {hb:?}");
            }
        }
    }
}

/// The arcs of a non-convex outline alternate convex and concave, cover the
/// circle once, and meet at inflection points (R² + 2R'² − RR'' = 0 to
/// round-off); the normal angle turns by 2π in all. n = 8 at Δ = 0.3 has
/// two inflection points per lobe: 16 arcs.
#[test]
fn arcs_alternate_and_cover_the_outline() {
    let s = fourier(8, 0.3, GapModel::Exact);
    let p = s.profiled();
    let arcs = p.arcs().unwrap();
    assert_eq!(arcs.len(), 16);
    let mut turn = 0.0;
    for (k, a) in arcs.iter().enumerate() {
        let next = &arcs[(k + 1) % arcs.len()];
        assert_ne!(a.convex, next.convex);
        assert!(
            (next.phi.0 - a.phi.1)
                .rem_euclid(TAU)
                .min(TAU - (next.phi.0 - a.phi.1).rem_euclid(TAU))
                < 1e-15
        );
        let (c, sn) = (a.phi.0.cos(), a.phi.0.sin());
        let (r, r1, r2) = p.unit_outline((c, sn));
        assert!((r * r + 2.0 * r1 * r1 - r * r2).abs() < 1e-12);
        turn += a.nu.1 - a.nu.0;
    }
    assert!((turn - TAU).abs() < 1e-12, "{turn}");
}

/// A tip of a body of size 0.7 touching both flanks of a valley of a body
/// of size 0.5 (n = 8, Δ = 0.2, a pair of a jammed packing): g_AB of the
/// tip's arc against the valley's has two minima (contacts, h ≈ −3.7e-7
/// and −6.6e-6) 0.044 rad apart with a maximum between, within one grid
/// cell. Both contacts are found here and under moves of ±1e-10 and
/// ±1e-8 of the separation, with gaps that change by less than the move.
#[test]
fn a_tip_touching_both_flanks_of_a_valley_has_two_contacts() {
    let s = fourier(8, 0.2, GapModel::Exact);
    let ti = (-0.8543071985876032f64).atan2(-0.5197684200116448);
    let tj = (0.5218473607348512f64).atan2(-0.8530388807633976);
    let at = |dy: f64| {
        let c = Config {
            size: [0.5, 0.7],
            theta: [ti, tj],
            r: [1.0070352858441112, 0.6195969739110416 + dy],
        };
        let mut gaps: Vec<f64> = contacts(&s, &c, 0.0).iter().map(|k| k.gap).collect();
        gaps.sort_by(f64::total_cmp);
        gaps
    };
    let here = at(0.0);
    assert_eq!(here.len(), 2, "{here:?}");
    assert!(
        (here[0] + 6.57e-6).abs() < 1e-8 && (here[1] + 3.71e-7).abs() < 1e-9,
        "{here:?}"
    );
    for dy in [1e-10, -1e-10, 1e-8, -1e-8] {
        let moved = at(dy);
        assert_eq!(moved.len(), 2, "{dy}: {moved:?}");
        for (a, b) in here.iter().zip(&moved) {
            assert!(
                (a - b).abs() <= dy.abs(),
                "{dy}: {here:?} against {moved:?}"
            );
        }
    }
}

/// Overlaps of any depth keep a repulsive contact: random pairs of n = 8
/// (Δ = 0.2) and n = 16 (Δ = 0.1) of sizes 0.5 and 0.7 at random angles,
/// centres from 0 to R_i + R_j apart. Where the inscribed disks overlap
/// (`r < a + b`), the core contact is there with `h = r − a − b` along the
/// line of centres; wherever the polygons (8192 vertices) overlap by more
/// than 2e-5 R⁰ (their resolution, `contacts_agree_with_fine_polygons`),
/// the pair has a contact with `h < 0`. Beyond two lobes of overlap the
/// arcs alone lose their contacts (the common normals leave the arcs):
/// without the core such bodies pass through each other.
#[test]
fn deep_overlaps_keep_a_contact() {
    let mut rng = Uniform::new(9);
    let mut cores = 0;
    for &(n, delta) in &[(8u32, 0.2), (16, 0.1)] {
        let s = fourier(n, delta, GapModel::Exact);
        let core = s.profiled().min_relative_radius();
        for _ in 0..150 {
            let size = if rng.next() < 0.5 {
                [0.5, 0.7]
            } else {
                [0.7, 0.5]
            };
            let a = TAU * rng.next();
            let d = (size[0] + size[1]) * rng.next();
            let c = Config {
                size,
                theta: [TAU * rng.next(), TAU * rng.next()],
                r: [d * a.cos(), d * a.sin()],
            };
            let found = contacts(&s, &c, 0.0);
            let inscribed = d - core * (size[0] + size[1]);
            if inscribed < 0.0 {
                cores += 1;
                let (u, v) = (c.r[0] / d, c.r[1] / d);
                assert!(
                    found.iter().any(|k| (k.gap - inscribed).abs() < 1e-14
                        && (k.grad_r[0] - u).abs() < 1e-14
                        && (k.grad_r[1] - v).abs() < 1e-14
                        && k.grad_rot_i[0] == 0.0
                        && k.grad_rot_j[0] == 0.0),
                    "n = {n}, {c:?}: no core contact in {found:?}"
                );
            }
            let pi = Polygon::new(&s, c.size[0], c.theta[0], [0.0, 0.0], 8192);
            let pj = Polygon::new(&s, c.size[1], c.theta[1], c.r, 8192);
            let depth = pi.depth_of(&pj).max(pj.depth_of(&pi));
            if depth > 2e-5 {
                assert!(
                    found.iter().any(|k| k.gap < 0.0),
                    "n = {n}, {c:?}: polygons overlap by {depth}, no contact"
                );
            }
        }
    }
    assert!(cores > 200, "{cores} pairs with overlapping cores");
}

/// A step of FIRE in a compressed packing of n = 16, Δ = 0.2 (bodies of
/// sizes 0.5 and 0.7, N = 64 at φ = 0.834), stretched to `t ∈ [−1, 2]`:
/// arcs 0 (concave) and 31 (convex) meet at three stationary points within
/// 0.11 rad of the normal, a contact (h = −5.309·10⁻⁴), a saddle
/// (−5.288·10⁻⁴) and a deeper contact (−5.325·10⁻⁴), a dense scan of
/// `g'(ψ)` finds them all along the path.
fn three_points_path(t: f64) -> Config {
    between(
        [0.5, 0.7],
        [[-1.585540141, 1.923808048], [-1.585540236, 1.923807993]],
        [
            [0.189019904292, -1.182520975070],
            [0.189019971946, -1.182520977815],
        ],
        t,
    )
}

/// A step of FIRE in a compressed packing of n = 16, Δ = 0.3 (sizes 0.5
/// and 0.7, N = 64 at φ = 0.819), stretched to `t ∈ [−1, 2]`: on arcs 2
/// (concave) and 15 (convex) a contact (h = −3.87·10⁻⁶) lies 0.073 rad
/// from a fold, where a contact and a saddle at h ≈ −2.8·10⁻⁶ are born
/// together, within one cell of the search.
fn fold_beside_path(t: f64) -> Config {
    between(
        [0.5, 0.7],
        [[-1.568750719, -0.925789502], [-1.568750719, -0.925789501]],
        [
            [0.597090048892, -1.044717655326],
            [0.597090048301, -1.044717654658],
        ],
        t,
    )
}

/// Two bodies of sizes `size` moved along a straight segment of their
/// coordinates, from `theta[0]`, `r[0]` at `t = 0` to `theta[1]`, `r[1]`
/// at `t = 1`.
fn between(size: [f64; 2], theta: [[f64; 2]; 2], r: [[f64; 2]; 2], t: f64) -> Config {
    let at = |k: usize, v: &[[f64; 2]; 2]| v[0][k] + t * (v[1][k] - v[0][k]);
    Config {
        size,
        theta: [at(0, &theta), at(1, &theta)],
        r: [at(0, &r), at(1, &r)],
    }
}

/// Where three stationary points of one pair of arcs lie closer together
/// than the search's cells ([`three_points_path`]), all three are found
/// at every point of the path: two overlapping contacts throughout (the
/// shallower with the saddle) and the harmonic energy within the
/// trapezoid rule, step by step (3000 steps; the energy is ~1.4·10⁻⁷,
/// its change per step ~10⁻¹⁴, a missed contact and saddle jump by
/// ≈ 2·10⁻⁹), to 10⁻¹⁵.
#[test]
fn close_stationary_points_of_one_arc_pair_are_all_found() {
    let counts = trapezoid_along(16, 0.2, &three_points_path, 1e-15);
    assert_eq!(counts, vec![2], "two overlapping contacts throughout");
}

/// Where a contact and a fold share a cell ([`fold_beside_path`]), the
/// contact is found at every point of the path, and the contact born at
/// the fold with its saddle adds ~0 (`h = −√(h_c² − h_s²)`): the harmonic
/// energy (~7.5·10⁻¹²) keeps within the trapezoid rule step by step
/// (3000 steps) to 10⁻¹⁷ (the pair born at the fold adds its share as a
/// square root, ~10⁻¹⁹ off the rule), where the contact taken for the
/// fold's jumps by 3.5·10⁻¹².
#[test]
fn a_contact_beside_a_fold_in_one_cell_is_found() {
    trapezoid_along(16, 0.3, &fold_beside_path, 1e-17);
}

/// The harmonic energy of n, Δ near-disks along `path` at `t ∈ [−1, 2]`
/// (3000 steps) against the trapezoid rule of its derivative: asserts
/// the largest miss below `tol`; the overlapping contact counts met.
fn trapezoid_along(n: u32, delta: f64, path: &dyn Fn(f64) -> Config, tol: f64) -> Vec<usize> {
    let s = fourier(n, delta, GapModel::Exact);
    let steps = 3000;
    let dt = 3.0 / steps as f64;
    let mut prev = harmonic_along(&s, path, -1.0);
    let mut counts = vec![prev.2];
    let mut worst: f64 = 0.0;
    for k in 1..=steps {
        let cur = harmonic_along(&s, path, -1.0 + k as f64 * dt);
        let miss = (cur.0 - prev.0) - 0.5 * (cur.1 + prev.1) * dt;
        worst = worst.max(miss.abs());
        counts.push(cur.2);
        prev = cur;
    }
    counts.sort_unstable();
    counts.dedup();
    eprintln!("largest miss of the trapezoid rule: {worst:e}, contact counts {counts:?}");
    assert!(worst < tol, "largest miss of the trapezoid rule {worst:e}");
    counts
}

/// The search of `arc_contacts` against brute force
/// ([`jamkit_planar::arcs::scan_stationary`] within 1.2 rad of the line
/// of centres, 6000 cells of ψ shared among the arc pairs' ranges, each
/// sign change of `g'` bisected to the spacing of floats) on random pairs
/// of n = 16 at Δ = 0.2 and 0.3, n = 8 at Δ = 0.3 and 0.4 and n = 32 at
/// Δ = 0.3, lobes interlocked up to a lobe and a half deep, and a small
/// body in the valley of a large one: the same overlapping contacts, gap
/// for gap to 10⁻⁹ (both refine to ~10⁻¹⁶), and every saddle it pairs is
/// one the scan finds. Stationary points deeper than half the search's
/// reach (arcs facing away) are left out of the comparison, and so are
/// pairs where the scan's cells cannot separate two stationary points of
/// one arc pair (closer than 10 cells in ψ: a contact at its fold).
#[test]
fn contacts_agree_with_a_brute_force_scan() {
    let mut rng = Uniform::new(17);
    for &(n, delta) in &[(16u32, 0.2), (8, 0.3), (16, 0.3), (32, 0.3), (8, 0.4)] {
        let s = fourier(n, delta, GapModel::Exact);
        let profiled = s.profiled();
        let arcs = profiled.arcs().expect("a non-convex outline");
        let outline = |u: (f64, f64)| profiled.unit_outline(u);
        let (cells, wide) = (6000, 1.2);
        let (mut compared, mut several, mut with_saddle) = (0, 0, 0);
        for k in 0..40 {
            let c = if k % 2 == 0 {
                Config::random(&mut rng, n, delta, 1.5)
            } else {
                Config::in_valley(&mut rng, n, delta)
            };
            let body = |k: usize| jamkit_planar::arcs::ArcBody {
                arcs,
                outline: &outline,
                size: c.size[k],
                theta: c.theta[k],
            };
            let reach = delta * (2.0 / n as f64) * (c.size[0] + c.size[1]);
            let r = Vector::<2>::new(c.r[0], c.r[1]);
            let line = c.r[1].atan2(c.r[0]);
            let scanned: Vec<_> = jamkit_planar::arcs::scan_stationary(
                &body(0),
                &body(1),
                &r,
                (line - wide, line + wide),
                cells,
            )
            .into_iter()
            .filter(|p| p.gap > -0.5 * reach)
            .collect();
            let unresolved = scanned.iter().enumerate().any(|(a, p)| {
                scanned[a + 1..].iter().any(|q| {
                    (p.arc_i, p.arc_j) == (q.arc_i, q.arc_j)
                        && (p.psi - q.psi).abs() < 10.0 * 2.0 * wide / cells as f64
                })
            });
            if unresolved {
                continue;
            }
            let mut found = Vec::new();
            let mut saddles = Vec::new();
            profiled.arc_contacts(&c.pair(), 0.0, None, &mut |ac| {
                if ac.exact.gap > -0.5 * reach {
                    found.push(ac.exact.gap);
                }
                saddles.extend(ac.saddle.map(|sd| sd.gap).filter(|&h| h > -0.5 * reach));
            });
            let mut want: Vec<f64> = scanned
                .iter()
                .filter(|p| p.contact)
                .map(|p| p.gap)
                .collect();
            found.sort_by(f64::total_cmp);
            want.sort_by(f64::total_cmp);
            assert_eq!(
                found.len(),
                want.len(),
                "n = {n}, {c:?}: {found:?} against {want:?}"
            );
            for (a, b) in found.iter().zip(&want) {
                assert!(
                    (a - b).abs() < 1e-9,
                    "n = {n}, {c:?}: {found:?} against {want:?}"
                );
            }
            for sd in &saddles {
                assert!(
                    scanned
                        .iter()
                        .any(|p| !p.contact && (p.gap - sd).abs() < 1e-9),
                    "n = {n}, {c:?}: saddle {sd} not among {scanned:?}"
                );
            }
            compared += 1;
            several += usize::from(found.len() > 1);
            with_saddle += usize::from(!saddles.is_empty());
        }
        eprintln!(
            "n = {n}: {compared} pairs compared, {several} with several contacts, {with_saddle} with saddles"
        );
        assert!(
            compared >= 30 && several >= 5,
            "n = {n}: {compared} pairs, {several} with several contacts"
        );
    }
}
