//! # Ellipses: the `ellipse` family (2D) with the exact gap
//!
//! A body of size `R⁰` is an ellipse of the **same area as the disk of
//! radius `R⁰`**, with aspect ratio `α = a/b ≥ 1`:
//!
//! ```text
//! a = R⁰ √α,   b = R⁰ / √α,   S = π a b = π (R⁰)²,
//! ```
//!
//! so that a size distribution and a packing fraction mean the same thing
//! as for disks, and `α = 1` is the disk of radius `R⁰` (the registry runs
//! it as the `sphere` family). Its orientation `θ` is the counter-clockwise
//! rotation of the body: the long axis points along `e(θ) = (cos θ, sin θ)`.
//!
//! ## Support function and gap
//!
//! In the body frame the support function (the largest projection of the
//! ellipse on the direction `e(β)`) is
//!
//! ```text
//! H(β)  = √q,    q = a² cos²β + b² sin²β,
//! H'(β) = (b² − a²) sin β cos β / H,
//! H''(β) = [(b² − a²)(cos²β − sin²β) − H'²] / H,    H + H'' = a²b²/H³ > 0,
//! ```
//!
//! and body `i` in the lab frame has `H_i(ψ − θ_i)`. Two bodies interact
//! through the **exact** gap, the signed distance along the common normal,
//! `h = max_ψ [r_ij·e(ψ) − H_i(ψ − θ_i) − H_j(ψ + π − θ_j)]`
//! ([`jamkit_core::gap2d::exact`]: positive, the distance of the two
//! outlines; negative, minus the depth of penetration along the normal),
//! with its gradient by the envelope theorem and its second derivatives
//! ([`jamkit_core::gap2d::ExactGap::hessian`]). There is no expansion in
//! `α − 1`: the gap is exact for every aspect ratio, to round-off.
//!
//! NOTE: for *overlapping* bodies `max_ψ` is taken by a safeguarded Newton
//! iteration from the line of centres, i.e. the local maximum nearest to
//! it. For the overlaps of a jamming run (`|h| ≪ b`) `g(ψ)` has one
//! maximum and this is the global one; two ellipses crossed at their
//! centres can have several.
//!
//! ## Inertia and asphericity
//!
//! The moment of inertia of `θ` defaults to that of a uniform ellipse of
//! unit mass, `I = (a² + b²)/4 = (R⁰)² (α + 1/α)/4` (the disk's `(R⁰)²/2`
//! at `α = 1`); `inertia` replaces it by one value for all sizes.
//! The asphericity `A = P²/(4πS)` (1 for a disk) uses the perimeter
//! `P = ∫₀^{2π} √(a² sin²t + b² cos²t) dt` by the trapezoid rule, which is
//! spectrally accurate for this smooth periodic integrand.

use jamkit_core::gap2d::{ExactGap, SupportJet, exact};
use jamkit_core::{Contact, Dims, FamilyInfo, GapHessian, ParamSpec, RotVec, Shape, Vector};
pub use jamkit_fourier::Angle;
use rand::{Rng, RngExt};
use serde::Deserialize;
use std::f64::consts::PI;

/// The `ellipse` family's self-description.
pub const INFO: FamilyInfo = FamilyInfo {
    name: "ellipse",
    about: "ellipses of aspect ratio α = a/b, a = R0 √α, b = R0/√α (the area of the disk R0), with the exact gap (2D)",
    dims: Dims::Only(&[2]),
    params: &[
        ParamSpec {
            name: "aspect",
            about: "α = a/b ≥ 1, finite; 1 gives disks (the sphere family)",
            is_list: false,
            default: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia I of the angle θ; None: I = (a² + b²)/4 (uniform ellipse of unit mass)",
            is_list: false,
            default: Some("None"),
        },
    ],
};

/// Parameters of `ellipse`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EllipseParams {
    /// Aspect ratio `α = a/b ≥ 1`.
    pub aspect: f64,
    /// Moment of inertia (`None`: `(a² + b²)/4`, size by size).
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub inertia: Option<f64>,
}

/// An invalid parameter, named.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    /// Field path.
    pub field: String,
    /// Offending value.
    pub value: String,
    /// What is allowed.
    pub allowed: String,
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} = {}: {}", self.field, self.value, self.allowed)
    }
}

/// The ellipse family: the aspect ratio and the moment of inertia.
#[derive(Clone, Debug, PartialEq)]
pub struct Ellipse {
    aspect: f64,
    /// `√α`: `a = R⁰ √α`, `b = R⁰/√α`.
    root: f64,
    inertia: Option<f64>,
}

impl Ellipse {
    /// The family for these parameters, or the first invalid one.
    pub fn new(p: &EllipseParams) -> Result<Self, ParamError> {
        if !(p.aspect >= 1.0 && p.aspect.is_finite()) {
            return Err(ParamError {
                field: "params.aspect".into(),
                value: p.aspect.to_string(),
                allowed: "must be a finite number ≥ 1 (α = a/b, long over short semi-axis)".into(),
            });
        }
        if let Some(i) = p.inertia
            && !(i > 0.0 && i.is_finite())
        {
            return Err(ParamError {
                field: "params.inertia".into(),
                value: i.to_string(),
                allowed: "must be positive and finite, or None for (a² + b²)/4".into(),
            });
        }
        Ok(Self {
            aspect: p.aspect,
            root: p.aspect.sqrt(),
            inertia: p.inertia,
        })
    }

    /// `α = a/b`.
    pub fn aspect(&self) -> f64 {
        self.aspect
    }

    /// The semi-axes `(a, b)` of a body of size `size`.
    pub fn semi_axes(&self, size: f64) -> (f64, f64) {
        (size * self.root, size / self.root)
    }

    /// The body-frame support function `H(β)` of a body of size `size`,
    /// with `H'` and `H''` (module documentation).
    #[inline(always)]
    pub fn support(&self, size: f64) -> impl Fn(f64) -> SupportJet + use<> {
        let (a, b) = self.semi_axes(size);
        let (a2, b2) = (a * a, b * b);
        let d = b2 - a2;
        move |beta: f64| {
            let (s, c) = beta.sin_cos();
            let h = (a2 * c * c + b2 * s * s).sqrt();
            let d1 = d * s * c / h;
            SupportJet {
                h,
                d1,
                d2: (d * (c * c - s * s) - d1 * d1) / h,
            }
        }
    }

    /// The polar radius `R(ψ)/R⁰ = 1/√(α⁻¹ cos²ψ + α sin²ψ)` of the outline
    /// in the body-frame direction `ψ` (for drawing).
    pub fn relative_radius(&self, psi: f64) -> f64 {
        let (s, c) = psi.sin_cos();
        1.0 / (c * c / self.aspect + self.aspect * s * s).sqrt()
    }

    /// Asphericity `A = P²/(4πS)` (1 for a disk), `P` by the trapezoid
    /// rule on 4096 points of the parametric form (exact to round-off: the
    /// error of the trapezoid rule on a periodic analytic integrand falls
    /// geometrically with the number of points).
    pub fn asphericity(&self) -> f64 {
        asphericity_of(self.aspect)
    }

    /// The aspect ratio `α ≥ 1` whose asphericity is `target` (bisection
    /// to round-off; `A(α)` increases with `α`), or `None` when
    /// `target < 1` or is not finite.
    pub fn aspect_for_asphericity(target: f64) -> Option<f64> {
        if !(target >= 1.0 && target.is_finite()) {
            return None;
        }
        let (mut lo, mut hi) = (1.0f64, 2.0f64);
        while asphericity_of(hi) < target {
            hi *= 2.0;
            if hi > 1e12 {
                return None;
            }
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if asphericity_of(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }

    /// The exact gap of two bodies (module documentation).
    #[inline(always)]
    fn gap(
        &self,
        size_i: f64,
        o_i: &Angle,
        size_j: f64,
        o_j: &Angle,
        r_ij: &Vector<2>,
    ) -> ExactGap {
        exact(
            r_ij,
            o_i.theta(),
            self.support(size_i),
            o_j.theta(),
            self.support(size_j),
        )
    }
}

/// `A = P²/(4πS)` of an ellipse of aspect ratio `alpha` (semi-axes `√α`,
/// `1/√α`, so `S = π`).
fn asphericity_of(alpha: f64) -> f64 {
    let (a2, b2) = (alpha, 1.0 / alpha);
    let m = 4096;
    let perimeter = (0..m)
        .map(|k| {
            let (s, c) = (2.0 * PI * k as f64 / m as f64).sin_cos();
            (a2 * s * s + b2 * c * c).sqrt()
        })
        .sum::<f64>()
        * 2.0
        * PI
        / m as f64;
    perimeter * perimeter / (4.0 * PI * PI)
}

impl Shape<2> for Ellipse {
    type Orientation = Angle;

    fn family(&self) -> &'static str {
        INFO.name
    }

    fn rot_dof(&self) -> usize {
        1
    }

    /// `π a b = π (R⁰)²`: the area of the disk of radius `R⁰`.
    fn volume(&self, size: f64) -> f64 {
        PI * size * size
    }

    /// The long semi-axis `a = R⁰ √α`.
    fn bounding_radius(&self, size: f64) -> f64 {
        size * self.root
    }

    fn rot_inertia(&self, size: f64) -> RotVec {
        let i = self.inertia.unwrap_or_else(|| {
            let (a, b) = self.semi_axes(size);
            0.25 * (a * a + b * b)
        });
        [i, 1.0, 1.0]
    }

    fn reference_orientation(&self) -> Angle {
        Angle::new(0.0)
    }

    fn random_orientation<R: Rng + ?Sized>(&self, rng: &mut R) -> Angle {
        Angle::new(2.0 * PI * rng.random::<f64>() - PI)
    }

    #[inline]
    fn rotate(&self, o: &mut Angle, dq: &[f64]) {
        *o = o.turned(dq[0]);
    }

    fn orientation_coords(&self, o: &Angle) -> Vec<f64> {
        vec![o.theta()]
    }

    fn orientation_from_coords(&self, coords: &[f64]) -> Option<Angle> {
        match coords {
            [theta] if theta.is_finite() => Some(Angle::new(*theta)),
            _ => None,
        }
    }

    /// `d + 1 = 3`, as for near-disks.
    fn rattler_threshold(&self) -> usize {
        3
    }

    /// Ellipses jam hypostatic (Donev et al. 2007).
    fn expects_isostatic(&self) -> bool {
        false
    }

    #[inline]
    fn contacts<F: FnMut(Contact<2>)>(
        &self,
        size_i: f64,
        o_i: &Angle,
        size_j: f64,
        o_j: &Angle,
        r_ij: &Vector<2>,
        max_gap: f64,
        mut visit: F,
    ) {
        // h ≥ |r| − a_i − a_j: skip pairs that are certainly apart.
        if r_ij.norm() - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return;
        }
        visit(self.gap(size_i, o_i, size_j, o_j, r_ij).contact());
    }

    fn gap_hessians<V: FnMut(GapHessian<2>)>(
        &self,
        size_i: f64,
        o_i: &Angle,
        size_j: f64,
        o_j: &Angle,
        r_ij: &Vector<2>,
        max_gap: f64,
        mut visit: V,
    ) -> jamkit_core::Result<()> {
        if r_ij.norm() - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return Ok(());
        }
        visit(self.gap(size_i, o_i, size_j, o_j, r_ij).hessian());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::FRAC_PI_2;

    fn ellipse(aspect: f64) -> Ellipse {
        Ellipse::new(&EllipseParams {
            aspect,
            inertia: None,
        })
        .unwrap()
    }

    fn contact(s: &Ellipse, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> Contact<2> {
        let mut out = None;
        s.contacts(
            ri,
            &Angle::new(ti),
            rj,
            &Angle::new(tj),
            &d,
            f64::INFINITY,
            |c| out = Some(c),
        );
        out.unwrap()
    }

    fn gap(s: &Ellipse, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> f64 {
        contact(s, ri, ti, rj, tj, d).gap
    }

    /// `H'` and `H''` of the closed-form support function against central
    /// differences of `H` (ε = 1e-5: truncation ~ε²H''' ≲ 1e-9, round-off
    /// ~1e-16/ε² ≈ 1e-6 for H''; tolerances 1e-8 and 1e-5).
    #[test]
    fn support_derivatives_match_finite_differences() {
        let s = ellipse(2.5);
        let h = s.support(0.7);
        let eps = 1e-5;
        for k in 0..40 {
            let beta = -3.14 + 0.161 * k as f64;
            let (m, c, p) = (h(beta - eps), h(beta), h(beta + eps));
            assert_relative_eq!(c.d1, (p.h - m.h) / (2.0 * eps), epsilon = 1e-8);
            assert_relative_eq!(c.d2, (p.d1 - m.d1) / (2.0 * eps), epsilon = 1e-8);
            assert_relative_eq!(c.d2, (p.h - 2.0 * c.h + m.h) / (eps * eps), epsilon = 1e-5);
            // ρ = H + H'' = a²b²/H³ (a = 0.7·√2.5, b = 0.7/√2.5).
            let ab = 0.49;
            assert_relative_eq!(c.h + c.d2, ab * ab / c.h.powi(3), max_relative = 1e-12);
        }
    }

    /// Aligned pairs: long axes along the line of centres `r − 2a`, across
    /// it `r − 2b`, one of each `r − a − b` (to round-off, 1e-14), for
    /// sizes 0.5 and 0.7 (`a_k = R_k √α`, `b_k = R_k/√α`), in any direction
    /// of the line of centres.
    #[test]
    fn aligned_ellipses_have_known_gaps() {
        let s = ellipse(1.8);
        let (ai, bi) = s.semi_axes(0.5);
        let (aj, bj) = s.semi_axes(0.7);
        for phi in [0.0, 0.4, -2.0, PI] {
            let u = Vector::<2>::new(phi.cos(), phi.sin());
            let d = u * 1.9;
            let g = |ti: f64, tj: f64| gap(&s, 0.5, phi + ti, 0.7, phi + tj, d);
            assert_relative_eq!(g(0.0, 0.0), 1.9 - ai - aj, epsilon = 1e-14);
            assert_relative_eq!(g(0.0, PI), 1.9 - ai - aj, epsilon = 1e-14);
            assert_relative_eq!(g(FRAC_PI_2, FRAC_PI_2), 1.9 - bi - bj, epsilon = 1e-14);
            assert_relative_eq!(g(0.0, FRAC_PI_2), 1.9 - ai - bj, epsilon = 1e-14);
            assert_relative_eq!(g(FRAC_PI_2, 0.0), 1.9 - bi - aj, epsilon = 1e-14);
            // Overlapping tip to tip by less than the tips' radii of
            // curvature b²/a (≈ 0.2 here): the axis is still the common
            // normal and h = r − a_i − a_j < 0. (Deeper, the bodies slip
            // sideways more cheaply: the axis becomes a minimum of g.)
            let dd = u * (ai + aj - 0.05);
            assert_relative_eq!(gap(&s, 0.5, phi, 0.7, phi, dd), -0.05, epsilon = 1e-14);
        }
    }

    /// The gap is the distance of the outlines: minimising over points of
    /// both parametrised outlines (a dense grid, then Newton-free local
    /// refinement) gives the same value for separated bodies, to 1e-9.
    #[test]
    fn gap_is_the_distance_between_outlines() {
        let s = ellipse(2.0);
        let cases = [
            (0.5, 0.3, 0.7, -1.2, Vector::<2>::new(1.6, 0.9)),
            (0.7, 2.9, 0.5, -3.0, Vector::<2>::new(-1.3, -1.4)),
            (0.5, 1.5, 0.5, 1.6, Vector::<2>::new(0.2, 1.6)),
            (0.5, 0.1, 0.5, 0.4, Vector::<2>::new(1.5, 0.1)),
        ];
        for (ri, ti, rj, tj, d) in cases {
            let point = |size: f64, theta: f64, t: f64, centre: Vector<2>| {
                let (a, b) = s.semi_axes(size);
                let (st, ct) = theta.sin_cos();
                let (x, y) = (a * t.cos(), b * t.sin());
                centre + Vector::<2>::new(ct * x - st * y, st * x + ct * y)
            };
            let dist = |u: f64, v: f64| {
                (point(rj, tj, v, d) - point(ri, ti, u, Vector::<2>::zeros())).norm()
            };
            // Grid, then coordinate-wise golden refinement.
            let m = 720;
            let mut best = (f64::INFINITY, 0.0, 0.0);
            for p in 0..m {
                for q in 0..m {
                    let (u, v) = (
                        2.0 * PI * p as f64 / m as f64,
                        2.0 * PI * q as f64 / m as f64,
                    );
                    let x = dist(u, v);
                    if x < best.0 {
                        best = (x, u, v);
                    }
                }
            }
            let (mut u, mut v, mut step) = (best.1, best.2, 2.0 * PI / m as f64);
            for _ in 0..200 {
                for (du, dv) in [(step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)] {
                    if dist(u + du, v + dv) < dist(u, v) {
                        u += du;
                        v += dv;
                    }
                }
                step *= 0.9;
            }
            let h = gap(&s, ri, ti, rj, tj, d);
            assert!(h > 0.05, "the case {d:?} must be separated: h = {h}");
            assert_relative_eq!(h, dist(u, v), epsilon = 1e-9);
        }
    }

    /// `h_ij = h_ji` (swap bodies, reverse the separation), and the
    /// gradients swap accordingly, to round-off.
    #[test]
    fn gap_is_symmetric() {
        let s = ellipse(1.6);
        for (d, ti, tj) in [
            (Vector::<2>::new(0.8, -0.9), 0.3, -1.2),
            (Vector::<2>::new(-0.7, 0.05), 3.1, -3.1),
            (Vector::<2>::new(0.6, 0.2), 2.0, 0.7),
        ] {
            let a = contact(&s, 0.5, ti, 0.7, tj, d);
            let b = contact(&s, 0.7, tj, 0.5, ti, -d);
            assert_relative_eq!(a.gap, b.gap, epsilon = 1e-14);
            assert_relative_eq!(a.grad_r, -b.grad_r, epsilon = 1e-12);
            assert_relative_eq!(a.grad_rot_i[0], b.grad_rot_j[0], epsilon = 1e-12);
            assert_relative_eq!(a.grad_rot_j[0], b.grad_rot_i[0], epsilon = 1e-12);
        }
    }

    /// As α → 1⁺ the gap tends to the disk gap `r − R_i − R_j`, linearly in
    /// `α − 1` (`a, b = R⁰(1 ± (α−1)/2 + …)`, so the deviation is at most
    /// `(R_i + R_j)(α − 1)/2` to first order).
    #[test]
    fn nearly_round_ellipses_tend_to_disks() {
        let d = Vector::<2>::new(0.9, 0.75);
        let disk = d.norm() - 1.2;
        for eps in [1e-2, 1e-4, 1e-6, 1e-8] {
            let s = ellipse(1.0 + eps);
            for (ti, tj) in [(0.3, -1.1), (2.0, 2.5), (-3.1, 3.1)] {
                let h = gap(&s, 0.5, ti, 0.7, tj, d);
                assert!(
                    (h - disk).abs() <= 0.6 * eps * (1.0 + 1e-3) + 1e-15,
                    "ε = {eps}: {h} vs {disk}"
                );
            }
        }
        // α = 1 exactly is the disk to round-off.
        assert_relative_eq!(
            gap(&ellipse(1.0), 0.5, 0.3, 0.7, 2.0, d),
            disk,
            epsilon = 1e-15
        );
    }

    /// A = P²/(4πS) against the Gauss–Kummer AGM formula for the perimeter,
    /// `P = 2π [a² − Σ_{n≥0} 2^{n−1} c_n²] / M(a, b)`, exact to round-off
    /// (quadratic convergence); agreement to 1e-13 relative.
    #[test]
    fn asphericity_matches_the_agm_perimeter() {
        let agm_perimeter = |a: f64, b: f64| {
            let (mut x, mut y) = (a, b);
            let mut c2 = a * a - b * b;
            let mut sum = 0.5 * c2;
            let mut pow = 0.5;
            for _ in 0..10 {
                let (nx, ny) = (0.5 * (x + y), (x * y).sqrt());
                c2 = (0.5 * (x - y)).powi(2);
                pow *= 2.0;
                sum += pow * c2;
                (x, y) = (nx, ny);
            }
            2.0 * PI * (a * a - sum) / x
        };
        for alpha in [1.0f64, 1.001, 1.2, 2.0, 5.0, 20.0] {
            let (a, b) = (alpha.sqrt(), 1.0 / alpha.sqrt());
            let p = agm_perimeter(a, b);
            let expected = p * p / (4.0 * PI * PI * a * b);
            assert_relative_eq!(ellipse(alpha).asphericity(), expected, max_relative = 1e-13);
        }
        // Small α − 1 = ε: A − 1 = 3ε²/8 + O(ε³), as for the n = 2
        // near-disk with Δ = ε (`R ≈ R⁰[1 + (ε/2) cos 2ψ]`).
        let eps = 1e-3;
        assert_relative_eq!(
            ellipse(1.0 + eps).asphericity() - 1.0,
            3.0 * eps * eps / 8.0,
            max_relative = 1e-2
        );
    }

    /// `aspect_for_asphericity` inverts `asphericity` (to 1e-12 in α).
    #[test]
    fn aspect_for_asphericity_inverts() {
        for alpha in [1.0, 1.01, 1.3, 3.0] {
            let a = ellipse(alpha).asphericity();
            let back = Ellipse::aspect_for_asphericity(a).unwrap();
            assert_relative_eq!(back, alpha, max_relative = 1e-6);
            assert_relative_eq!(ellipse(back).asphericity(), a, max_relative = 1e-14);
        }
        assert_eq!(Ellipse::aspect_for_asphericity(0.5), None);
        assert_eq!(Ellipse::aspect_for_asphericity(f64::NAN), None);
    }

    /// The polar radius lies on the outline: `(x/a)² + (y/b)² = 1`.
    #[test]
    fn relative_radius_is_on_the_outline() {
        let s = ellipse(2.2);
        let (a, b) = s.semi_axes(1.0);
        for k in 0..50 {
            let psi = -PI + 0.13 * k as f64;
            let r = s.relative_radius(psi);
            let (x, y) = (r * psi.cos(), r * psi.sin());
            assert_relative_eq!((x / a).powi(2) + (y / b).powi(2), 1.0, epsilon = 1e-14);
        }
    }

    #[test]
    fn bad_parameters_are_rejected_with_the_field_named() {
        for aspect in [0.9, 0.0, -2.0, f64::NAN, f64::INFINITY] {
            let e = Ellipse::new(&EllipseParams {
                aspect,
                inertia: None,
            })
            .unwrap_err();
            assert_eq!(e.field, "params.aspect");
            assert!(e.allowed.contains("≥ 1"), "{e}");
        }
        for inertia in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = Ellipse::new(&EllipseParams {
                aspect: 1.5,
                inertia: Some(inertia),
            })
            .unwrap_err();
            assert_eq!(e.field, "params.inertia");
        }
        // Defaults: I = (a² + b²)/4, per size.
        let s = ellipse(2.0);
        assert_relative_eq!(s.rot_inertia(0.5)[0], 0.25 * 0.25 * 2.5, epsilon = 1e-15);
    }
}
