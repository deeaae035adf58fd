//! # Two-lobed near-disks: the `lobed` family
//!
//! The worked example of `docs/adding-a-shape.md`. A body of size `R⁰` and
//! orientation `θ_i` has the polar outline (lab direction `φ`)
//!
//! ```text
//! R_i(φ) = R⁰ [1 + Δ G(θ_i − φ)],
//! G(φ)   = (e^{−2κ sin²φ} − m) / (1 − m),    m = ⟨e^{−2κ sin²φ}⟩ = e^{−κ} I₀(κ),
//! ```
//!
//! two circular Gaussian (von Mises) bumps of angular width `≈ 1/(2√κ)` at
//! `φ = 0` and `φ = π`, shifted to zero mean and scaled so that
//! `max G = G(0) = 1`: a peanut whose two lobes point along `θ_i`, with
//! `min G = G(π/2) = (e^{−2κ} − m)/(1 − m) ∈ (−1, 0)` at the waist.
//! As `κ → 0`, `G → cos 2φ`; a large `κ` puts two sharp tips on a nearly
//! round body. `G` is even and π-periodic.
//!
//! Two bodies interact through the first-order gap (the paper's Eq. (8)
//! with `G` in place of `F`),
//!
//! ```text
//! h_ij = |r_ij| − R_i⁰ − R_j⁰ − Δ [R_i⁰ G(A_i) + R_j⁰ G(A_j)],
//! A_i = θ_i − θ_ij,   A_j = θ_j − θ_ij − π,   θ_ij = atan2(y_j − y_i, x_j − x_i),
//! ```
//!
//! exact to `O(Δ)`. With `u = r_ij/|r_ij|`, `t = (−u_y, u_x)` and
//! `∂θ_ij/∂r_j = t/|r_ij|`, its derivatives are
//!
//! ```text
//! ∂h/∂r_j = u + Δ [R_i⁰ G'(A_i) + R_j⁰ G'(A_j)] t / |r_ij|   (= −∂h/∂r_i),
//! ∂h/∂θ_i = −Δ R_i⁰ G'(A_i),     ∂h/∂θ_j = −Δ R_j⁰ G'(A_j),
//! G'(φ)   = −2κ sin(2φ) e^{−2κ sin²φ} / (1 − m).
//! ```
//!
//! The area is exact, not first-order:
//!
//! ```text
//! S = ½ ∫ R² dφ = π (R⁰)² [1 + Δ² ⟨G²⟩],   ⟨G²⟩ = (e^{−2κ} I₀(2κ) − m²) / (1 − m)².
//! ```
//!
//! NOTE: the pair loop calls one `exp` per body and no `atan2`, `sin` or
//! `cos`: `e^{iA_i} = e^{iθ_i} e^{−iθ_ij}` is a complex product of the
//! cached `e^{iθ_i}` and the unit vector `u`, and `G` needs only `sin A` and
//! `cos A`. The `−π` in `A_j` flips the sign of both, which `G` (π-periodic)
//! does not see.

use jamkit_core::{
    Contact, Dims, Family, FamilyInfo, GapHessian, Outline, ParamSpec, RotVec, Shape, ShapeVisitor,
    SharedOutline, Vector,
};
use jamkit_planar::first_order::{Profile, gap_hessian};
use rand::{Rng, RngExt};
use serde::Deserialize;
use std::f64::consts::PI;

/// The `lobed` family's self-description.
pub const INFO: FamilyInfo = FamilyInfo {
    name: "lobed",
    about: "two-lobed near-disks R(θ) = R0 [1 + Δ G(θ)], G a zero-mean pair of Gaussian bumps of sharpness κ, first-order gap (2D)",
    dims: Dims::Only(&[2]),
    params: &[
        ParamSpec {
            name: "delta",
            about: "Δ ≥ 0, the amplitude: the lobes reach R0 (1 + Δ)",
            is_list: false,
            default: None,
        },
        ParamSpec {
            name: "kappa",
            about: "κ in [0.1, 20], the sharpness of the lobes (width ≈ 1/(2√κ) rad; κ → 0 is cos 2θ)",
            is_list: false,
            default: Some("1.0"),
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia I of the angle θ; None: I = Δ (the paper's choice)",
            is_list: false,
            default: Some("None"),
        },
    ],
};

/// Parameters of `lobed`, as read from an experiment file. Defaults are
/// filled in from [`INFO`] by the experiment layer before parsing.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LobedParams {
    /// Amplitude `Δ`.
    pub delta: f64,
    /// Sharpness `κ` of the lobes.
    pub kappa: f64,
    /// Moment of inertia (`None`: `Δ`). Also read from a bare number, which
    /// is what `--set params.inertia=0.5` produces.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub inertia: Option<f64>,
}

/// The `lobed` family's registration: the one line of
/// `crates/experiment/src/registry.rs` names this type.
pub struct LobedFamily;

impl Family for LobedFamily {
    const INFO: FamilyInfo = INFO;
    const EXAMPLE: &'static str = "(delta: 0.2, kappa: 2.0)";
    type Params = LobedParams;

    fn visit<V: ShapeVisitor>(
        p: &LobedParams,
        _dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        Ok(visitor.visit::<2, _>(Lobed::new(p)?))
    }
}

impl Outline for Lobed {
    fn relative_radius(&self, psi: f64) -> f64 {
        Lobed::relative_radius(self, psi)
    }
}

/// Smallest and largest `κ` accepted.
///
/// NOTE: `1 − m ≈ κ` for small `κ`, so `G = (g − m)/(1 − m)` loses about
/// `log₁₀(1/κ)` digits to cancellation; below 0.1 use the `fourier` family
/// with `n = 2`, which is the limit. Above 20 the lobes are narrower than
/// 0.11 rad and the neglected `O(Δ² G'²) ~ Δ² κ` terms of the gap grow.
pub const KAPPA_RANGE: (f64, f64) = (0.1, 20.0);

/// The `lobed` family: `Δ`, `κ`, the moment of inertia, and the constants
/// of `G` computed once at construction.
#[derive(Clone, Debug, PartialEq)]
pub struct Lobed {
    delta: f64,
    kappa: f64,
    inertia: f64,
    /// `m = ⟨e^{−2κ sin²φ}⟩ = e^{−κ} I₀(κ)`.
    mean: f64,
    /// `1/(1 − m)`.
    scale: f64,
    /// `⟨G²⟩`.
    mean_square: f64,
}

/// Orientation `θ` with `e^{iθ}` cached (`cos θ`, `sin θ`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angle {
    /// `θ`, kept in `[−π, π]`.
    pub theta: f64,
    cos: f64,
    sin: f64,
}

impl Angle {
    /// The orientation `θ`, wrapped into `[−π, π]`.
    pub fn new(theta: f64) -> Self {
        // NOTE: wrapping keeps sin/cos accurate for bodies that have turned
        // many times; θ and θ + 2π are the same orientation.
        let theta = theta - 2.0 * PI * (theta / (2.0 * PI)).round();
        let (sin, cos) = theta.sin_cos();
        Self { theta, cos, sin }
    }
}

/// `e^{−x} I₀(x)` by the power series `I₀(x) = Σ_k (x²/4)^k / (k!)²`.
///
/// All terms are positive, so the sum is accurate to a few ulps; for
/// `x ≤ 2 κ_max = 40` the largest term is below `e^{40} ≈ 2·10¹⁷` and the
/// series needs fewer than 100 terms.
fn scaled_bessel_i0(x: f64) -> f64 {
    let q = 0.25 * x * x;
    let (mut term, mut sum, mut k) = (1.0f64, 1.0f64, 1.0f64);
    while term > 1e-17 * sum {
        term *= q / (k * k);
        sum += term;
        k += 1.0;
    }
    sum * (-x).exp()
}

impl Lobed {
    /// Build the family, checking every parameter.
    pub fn new(p: &LobedParams) -> jamkit_core::Result<Self> {
        let err = |field: &str, value: f64, allowed: String| {
            jamkit_core::Error::invalid(field, value, allowed)
        };
        if !(p.delta.is_finite() && p.delta >= 0.0) {
            return Err(err(
                "params.delta",
                p.delta,
                "must be a finite number ≥ 0".into(),
            ));
        }
        let (lo, hi) = KAPPA_RANGE;
        if !(p.kappa >= lo && p.kappa <= hi) {
            return Err(err(
                "params.kappa",
                p.kappa,
                format!("must lie in [{lo}, {hi}] (for κ < {lo} use family `fourier` with n = 2)"),
            ));
        }
        let inertia = p.inertia.unwrap_or(p.delta);
        if !(inertia > 0.0 && inertia.is_finite()) {
            return Err(err(
                "params.inertia",
                inertia,
                "must be positive and finite (the default I = Δ needs Δ > 0)".into(),
            ));
        }
        let mean = scaled_bessel_i0(p.kappa);
        let scale = 1.0 / (1.0 - mean);
        let mean_g2 = scaled_bessel_i0(2.0 * p.kappa);
        let shape = Self {
            delta: p.delta,
            kappa: p.kappa,
            inertia,
            mean,
            scale,
            mean_square: (mean_g2 - mean * mean) * scale * scale,
        };
        let min_r = shape.min_relative_radius();
        if !(min_r > 0.0) {
            return Err(err(
                "params.delta",
                p.delta,
                format!(
                    "is so large that R(θ) ≤ 0 at the waist (min R/R0 = {min_r:.4}); need Δ < {:.4} at κ = {}",
                    -1.0 / shape.profile_min(),
                    p.kappa
                ),
            ));
        }
        Ok(shape)
    }

    /// `Δ`.
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// `κ`.
    pub fn kappa(&self) -> f64 {
        self.kappa
    }

    /// `G(A)` and `G'(A)` from `cos A` and `sin A` (the pair loop's path).
    #[inline(always)]
    fn profile_from_phase(&self, cos: f64, sin: f64) -> (f64, f64) {
        // e^{−2κ sin²A}; sin 2A = 2 sin A cos A.
        let g = (-2.0 * self.kappa * sin * sin).exp();
        (
            (g - self.mean) * self.scale,
            -4.0 * self.kappa * sin * cos * g * self.scale,
        )
    }

    /// `G(φ)` and `G'(φ)` (slow path, for geometry and tests).
    pub fn profile(&self, phi: f64) -> (f64, f64) {
        let (sin, cos) = phi.sin_cos();
        self.profile_from_phase(cos, sin)
    }

    /// `G''(φ) = 4κ (κ sin²2φ − cos 2φ) e^{−2κ sin²φ} / (1 − m)`.
    pub fn profile_second(&self, phi: f64) -> f64 {
        let g = (-2.0 * self.kappa * phi.sin().powi(2)).exp();
        let (s2, c2) = (2.0 * phi).sin_cos();
        4.0 * self.kappa * (self.kappa * s2 * s2 - c2) * g * self.scale
    }

    /// `min G = G(π/2) = (e^{−2κ} − m)/(1 − m)`.
    pub fn profile_min(&self) -> f64 {
        ((-2.0 * self.kappa).exp() - self.mean) * self.scale
    }

    /// `R(φ)/R⁰ = 1 + Δ G(φ)` in the body frame.
    pub fn relative_radius(&self, phi: f64) -> f64 {
        1.0 + self.delta * self.profile(phi).0
    }

    /// `min R/R⁰ = 1 + Δ min G`, at the waist.
    pub fn min_relative_radius(&self) -> f64 {
        1.0 + self.delta * self.profile_min()
    }

    /// True when the outline is convex: the polar curvature numerator
    /// `r² + 2r'² − r r''` stays positive (sampled on 4096 angles of one
    /// period, `[0, π)`; the narrowest lobe, κ = 20, spans ~140 of them).
    pub fn is_convex(&self) -> bool {
        (0..4096).all(|k| {
            let phi = PI * k as f64 / 4096.0;
            let (g, dg) = self.profile(phi);
            let (r, dr, ddr) = (
                1.0 + self.delta * g,
                self.delta * dg,
                self.delta * self.profile_second(phi),
            );
            r * r + 2.0 * dr * dr - r * ddr > 0.0
        })
    }

    /// Area in units of `(R⁰)²`: `π [1 + Δ² ⟨G²⟩]`.
    pub fn relative_area(&self) -> f64 {
        PI * (1.0 + self.delta * self.delta * self.mean_square)
    }
}

impl Shape<2> for Lobed {
    type Orientation = Angle;

    fn family(&self) -> &'static str {
        INFO.name
    }

    fn rot_dof(&self) -> usize {
        1
    }

    fn volume(&self, size: f64) -> f64 {
        self.relative_area() * size * size
    }

    /// `R⁰ (1 + Δ)`: the lobe tips, since `max G = 1`.
    fn bounding_radius(&self, size: f64) -> f64 {
        size * (1.0 + self.delta)
    }

    fn rot_inertia(&self, _size: f64) -> RotVec {
        [self.inertia, 1.0, 1.0]
    }

    fn outline(&self) -> Option<SharedOutline> {
        Some(std::sync::Arc::new(self.clone()))
    }

    fn reference_orientation(&self) -> Angle {
        Angle::new(0.0)
    }

    fn random_orientation<R: Rng + ?Sized>(&self, rng: &mut R) -> Angle {
        Angle::new(2.0 * PI * rng.random::<f64>() - PI)
    }

    fn rotate(&self, o: &mut Angle, dq: &[f64]) {
        *o = Angle::new(o.theta + dq[0]);
    }

    fn orientation_coords(&self, o: &Angle) -> Vec<f64> {
        vec![o.theta]
    }

    fn orientation_from_coords(&self, coords: &[f64]) -> Option<Angle> {
        match coords {
            [theta] if theta.is_finite() => Some(Angle::new(*theta)),
            _ => None,
        }
    }

    /// Three, as for the paper's near-disks (`d + 1`).
    fn rattler_threshold(&self) -> usize {
        3
    }

    /// Near-disks jam hypostatic.
    fn expects_isostatic(&self) -> bool {
        false
    }

    fn warnings(&self) -> Vec<String> {
        if self.is_convex() {
            Vec::new()
        } else {
            vec![format!(
                "non-convex outline (Δ = {}, κ = {}): the first-order gap assumes convex bodies with one contact per pair",
                self.delta, self.kappa
            )]
        }
    }

    #[inline(always)]
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
        let r = r_ij.norm();
        // G ≤ 1, so h ≥ |r| − b_i − b_j: skip pairs that are certainly apart.
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return;
        }
        // NOTE: coincident centres have no direction θ_ij; take θ_ij = 0
        // (deterministic; such a pair overlaps deeply and any direction
        // pushes it apart).
        let (u, inv_r) = if r > 0.0 {
            (r_ij * (1.0 / r), 1.0 / r)
        } else {
            (Vector::<2>::new(1.0, 0.0), 0.0)
        };
        // e^{iA} = e^{iθ} e^{−iθ_ij}: cos A = cos θ u_x + sin θ u_y,
        // sin A = sin θ u_x − cos θ u_y. For body j the −π of A_j is dropped
        // (G is π-periodic).
        let phase = |o: &Angle| (o.cos * u[0] + o.sin * u[1], o.sin * u[0] - o.cos * u[1]);
        let (ci, si) = phase(o_i);
        let (cj, sj) = phase(o_j);
        let (g_i, dg_i) = self.profile_from_phase(ci, si);
        let (g_j, dg_j) = self.profile_from_phase(cj, sj);
        let d = self.delta;
        let gap = r - size_i - size_j - d * (size_i * g_i + size_j * g_j);
        let tangent = Vector::<2>::new(-u[1], u[0]);
        let grad_r = u + tangent * (d * (size_i * dg_i + size_j * dg_j) * inv_r);
        visit(Contact {
            gap,
            grad_r,
            grad_rot_i: [-d * size_i * dg_i, 0.0, 0.0],
            grad_rot_j: [-d * size_j * dg_j, 0.0, 0.0],
        });
    }

    /// The same gap with its second derivatives, for the Hessian: the
    /// first-order gap is the paper's for any profile, so
    /// [`jamkit_planar::first_order::gap_hessian`] does the work once it has
    /// `G`, `G'` and `G''` at the two angles (this path is not hot, so `A`
    /// comes from `atan2`).
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
        let r = r_ij.norm();
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return Ok(());
        }
        let u = if r > 0.0 {
            r_ij * (1.0 / r)
        } else {
            Vector::<2>::new(1.0, 0.0)
        };
        // NOTE: as in `contacts`, A_j = θ_j − θ_ij − π, whose −π flips the
        // signs of cos A_j and sin A_j. G, G' and G'' are π-periodic and do
        // not see it, so both bodies use A = θ − θ_ij here. A profile that
        // is not π-periodic must pass (−cos, −sin) for body j (and
        // atan2(−sin, −cos) for its curvature), or its Hessian is wrong.
        let profile = |o: &Angle| {
            let (cos, sin) = (o.cos * u[0] + o.sin * u[1], o.sin * u[0] - o.cos * u[1]);
            let (value, slope) = self.profile_from_phase(cos, sin);
            Profile {
                value,
                slope,
                curvature: self.profile_second(sin.atan2(cos)),
            }
        };
        visit(gap_hessian(
            r_ij,
            size_i,
            size_j,
            self.delta,
            profile(o_i),
            profile(o_j),
        ));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn lobed(delta: f64, kappa: f64) -> Lobed {
        Lobed::new(&LobedParams {
            delta,
            kappa,
            inertia: None,
        })
        .unwrap()
    }

    fn contact(s: &Lobed, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> Contact<2> {
        s.pair_contacts(ri, &Angle::new(ti), rj, &Angle::new(tj), &d, f64::INFINITY)[0]
    }

    /// `G` written directly from its definition, with `exp` and `sin`.
    fn g_direct(kappa: f64, phi: f64) -> f64 {
        let m = (0..20000)
            .map(|k| (-2.0 * kappa * (PI * k as f64 / 20000.0).sin().powi(2)).exp())
            .sum::<f64>()
            / 20000.0;
        ((-2.0 * kappa * phi.sin().powi(2)).exp() - m) / (1.0 - m)
    }

    /// The pair loop's gap equals the printed formula written with atan2,
    /// sin and exp (and the normalisation m by quadrature, not the Bessel
    /// series), to round-off: 1e-13 on gaps of order 1.
    #[test]
    fn gap_matches_the_printed_formula() {
        for kappa in [0.3, 1.0, 6.0] {
            let s = lobed(0.2, kappa);
            for &(x, y, ti, tj) in &[
                (1.1, 0.3, 0.4, -2.0),
                (-0.9, -0.8, 3.1, 1.0),
                (0.2, -1.3, -3.1, 3.0),
                (-1.2, 1e-12, 0.0, PI),
            ] {
                let d = Vector::<2>::new(x, y);
                let tij = y.atan2(x);
                let expected = d.norm()
                    - 0.5
                    - 0.7
                    - 0.2
                        * (0.5 * g_direct(kappa, ti - tij) + 0.7 * g_direct(kappa, tj - tij - PI));
                let h = contact(&s, 0.5, ti, 0.7, tj, d).gap;
                assert_relative_eq!(h, expected, epsilon = 1e-13);
            }
        }
    }

    /// h_ij = h_ji, and the derivatives swap: ∂h/∂r_j ↦ −∂h/∂r_j,
    /// ∂h/∂θ_i ↔ ∂h/∂θ_j.
    #[test]
    fn gap_is_symmetric() {
        let s = lobed(0.3, 2.0);
        let d = Vector::<2>::new(0.8, -0.9);
        let a = contact(&s, 0.5, 0.3, 0.7, -1.2, d);
        let b = contact(&s, 0.7, -1.2, 0.5, 0.3, -d);
        assert_relative_eq!(a.gap, b.gap, epsilon = 1e-14);
        assert_relative_eq!(a.grad_r, -b.grad_r, epsilon = 1e-14);
        assert_relative_eq!(a.grad_rot_i[0], b.grad_rot_j[0], epsilon = 1e-14);
        assert_relative_eq!(a.grad_rot_j[0], b.grad_rot_i[0], epsilon = 1e-14);
    }

    /// The pair's own derivatives against central differences of its gap
    /// (ε = 1e-6: truncation ε²|h'''| ≲ 1e-10 at κ = 6, round-off 1e-16/ε).
    #[test]
    fn pair_derivatives_match_finite_differences() {
        let eps = 1e-6;
        for kappa in [0.3, 1.0, 6.0] {
            let s = lobed(0.2, kappa);
            let (ti, tj, d) = (0.7, -2.2, Vector::<2>::new(-0.9, 0.6));
            let c = contact(&s, 0.5, ti, 0.7, tj, d);
            let h = |ti: f64, tj: f64, d: Vector<2>| contact(&s, 0.5, ti, 0.7, tj, d).gap;
            let num_ti = (h(ti + eps, tj, d) - h(ti - eps, tj, d)) / (2.0 * eps);
            let num_tj = (h(ti, tj + eps, d) - h(ti, tj - eps, d)) / (2.0 * eps);
            assert_relative_eq!(c.grad_rot_i[0], num_ti, epsilon = 1e-8);
            assert_relative_eq!(c.grad_rot_j[0], num_tj, epsilon = 1e-8);
            for a in 0..2 {
                let mut e = Vector::<2>::zeros();
                e[a] = eps;
                let num = (h(ti, tj, d + e) - h(ti, tj, d - e)) / (2.0 * eps);
                assert_relative_eq!(c.grad_r[a], num, epsilon = 1e-8);
            }
        }
    }

    /// G has zero mean and its maximum 1 at φ = 0 (checks m, hence the
    /// Bessel series); G' and G'' match central differences of G.
    #[test]
    fn profile_is_normalised_and_its_derivatives_are_right() {
        for kappa in [0.1, 1.0, 5.0, 20.0] {
            let s = lobed(0.1, kappa);
            let m = 4096;
            let mean: f64 = (0..m)
                .map(|k| s.profile(2.0 * PI * k as f64 / m as f64).0)
                .sum::<f64>()
                / m as f64;
            assert!(mean.abs() < 1e-13, "κ = {kappa}: ⟨G⟩ = {mean:e}");
            assert_relative_eq!(s.profile(0.0).0, 1.0, epsilon = 1e-14);
            assert_relative_eq!(s.profile(PI / 2.0).0, s.profile_min(), epsilon = 1e-14);
            let eps = 1e-5;
            for phi in [0.2, 1.0, 2.5, -0.7] {
                let num1 = (s.profile(phi + eps).0 - s.profile(phi - eps).0) / (2.0 * eps);
                let num2 = (s.profile(phi + eps).1 - s.profile(phi - eps).1) / (2.0 * eps);
                let scale = 1.0 + kappa * kappa;
                assert_relative_eq!(s.profile(phi).1, num1, epsilon = 1e-7 * scale);
                assert_relative_eq!(s.profile_second(phi), num2, epsilon = 1e-7 * scale);
            }
        }
    }

    /// Area: the closed form against the trapezoid rule for ½∫R² on 4096
    /// points, spectrally accurate for this analytic periodic integrand
    /// (its Fourier coefficients fall off like I_k(2κ), negligible beyond
    /// k ≈ 100 even at κ = 20), so they agree to 1e-12.
    #[test]
    fn area_matches_quadrature() {
        for (delta, kappa) in [(0.3, 0.1), (0.5, 1.0), (0.2, 5.0), (0.4, 20.0)] {
            let s = lobed(delta, kappa);
            let m = 4096;
            let quad: f64 = (0..m)
                .map(|k| 0.5 * s.relative_radius(2.0 * PI * k as f64 / m as f64).powi(2))
                .sum::<f64>()
                * 2.0
                * PI
                / m as f64;
            assert_relative_eq!(s.relative_area(), quad, max_relative = 1e-12);
            assert_relative_eq!(
                Shape::<2>::volume(&s, 0.7),
                quad * 0.49,
                max_relative = 1e-12
            );
        }
    }

    #[test]
    fn rotation_wraps_and_coords_round_trip() {
        let s = lobed(0.1, 1.0);
        let mut o = Angle::new(3.0);
        s.rotate(&mut o, &[0.5]);
        assert_relative_eq!(o.theta, 3.5 - 2.0 * PI, epsilon = 1e-15);
        let back = s
            .orientation_from_coords(&s.orientation_coords(&o))
            .unwrap();
        assert_eq!(back, o);
        assert!(s.orientation_from_coords(&[f64::NAN]).is_none());
        assert!(s.orientation_from_coords(&[]).is_none());
    }

    #[test]
    fn nonsense_parameters_are_rejected_and_large_delta_is_non_convex() {
        let try_new = |delta, kappa, inertia| {
            Lobed::new(&LobedParams {
                delta,
                kappa,
                inertia,
            })
        };
        assert_eq!(
            try_new(-0.1, 1.0, None).unwrap_err().field(),
            Some("params.delta")
        );
        assert_eq!(
            try_new(f64::NAN, 1.0, None).unwrap_err().field(),
            Some("params.delta")
        );
        assert_eq!(
            try_new(0.1, 0.0, None).unwrap_err().field(),
            Some("params.kappa")
        );
        assert_eq!(
            try_new(0.1, 50.0, None).unwrap_err().field(),
            Some("params.kappa")
        );
        assert_eq!(
            try_new(0.0, 1.0, None).unwrap_err().field(),
            Some("params.inertia")
        );
        assert!(try_new(0.0, 1.0, Some(1.0)).is_ok());
        // κ = 1: min G ≈ −0.619, so R > 0 needs Δ < 1.62.
        assert_eq!(
            try_new(1.7, 1.0, None).unwrap_err().field(),
            Some("params.delta")
        );
        assert!(lobed(0.2, 1.0).is_convex());
        assert!(Shape::<2>::warnings(&lobed(0.2, 1.0)).is_empty());
        // The waist turns concave near Δ ≈ 0.61 at κ = 1.
        assert!(!lobed(1.0, 1.0).is_convex());
        assert_eq!(Shape::<2>::warnings(&lobed(1.0, 1.0)).len(), 1);
    }
}
