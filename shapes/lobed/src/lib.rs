//! # Two-lobed near-disks: the `lobed` family
//!
//! The worked example of `docs/tutorials/new-shape-rust.md`. A body of
//! size `R⁰` and orientation `θ_i` has the polar outline (lab direction
//! `φ`)
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
//! The family is its profile: [`LobedProfile`] gives `G`, `G'`, `G''`,
//! their range and moments, and `jamkit_planar::profiled::Profiled` does
//! the rest (parameter checks for `Δ` and the inertia, orientations, the
//! pair loop, the Hessian, the outline for drawing, the convexity warning).
//! `G` needs only `sin A` and `cos A`, so the pair loop calls one `exp` per
//! body and no `atan2`, `sin` or `cos`.

use jamkit_core::{Dims, Family, FamilyInfo, ParamSpec, ShapeVisitor};
use jamkit_planar::profiled::{NearDiskProfile, Profiled};
use serde::Deserialize;
#[cfg(test)]
use std::f64::consts::PI;

/// The `lobed` family's self-description.
pub const INFO: FamilyInfo = FamilyInfo {
    name: "lobed",
    about: "two-lobed near-disks of radius R0 [1 + Δ G(θ − φ)] towards the direction φ, θ the body's angle, G a zero-mean pair of Gaussian bumps of sharpness κ, first-order gap (2D)",
    dims: Dims::Only(&[2]),
    params: &[
        ParamSpec {
            name: "delta",
            about: "Δ ≥ 0, the amplitude: the lobes reach R0 (1 + Δ)",
            is_list: false,
            default: None,
            added: None,
        },
        ParamSpec {
            name: "kappa",
            about: "κ in [0.1, 20], the sharpness of the lobes (width ≈ 1/(2√κ) rad; κ → 0 is cos 2θ)",
            is_list: false,
            default: Some("1.0"),
            added: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia I of the angle θ; None: I = Δ (the paper's choice), 1 at Δ = 0",
            is_list: false,
            default: Some("None"),
            added: None,
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
/// `crates/registry/src/lib.rs` names this type.
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
        Ok(visitor.visit::<2, _>(lobed(p)?))
    }
}

/// Smallest and largest `κ` accepted.
///
/// NOTE: `1 − m ≈ κ` for small `κ`, so `G = (g − m)/(1 − m)` loses about
/// `log₁₀(1/κ)` digits to cancellation; below 0.1 use the `fourier` family
/// with `n = 2`, which is the limit. Above 20 the lobes are narrower than
/// 0.11 rad and the neglected `O(Δ² G'²) ~ Δ² κ` terms of the gap grow.
pub const KAPPA_RANGE: (f64, f64) = (0.1, 20.0);

/// The profile `G` of sharpness `κ`, with its constants computed once.
#[derive(Clone, Debug, PartialEq)]
pub struct LobedProfile {
    kappa: f64,
    /// `m = ⟨e^{−2κ sin²φ}⟩ = e^{−κ} I₀(κ)`.
    mean: f64,
    /// `1/(1 − m)`.
    scale: f64,
    /// `⟨G²⟩`.
    mean_square: f64,
}

/// The `lobed` shape: a near-disk of profile [`LobedProfile`].
pub type Lobed = Profiled<LobedProfile>;

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

/// The shape of `p`, every parameter checked (`κ` here, `Δ` and the
/// inertia by [`Profiled::new`]).
pub fn lobed(p: &LobedParams) -> jamkit_core::Result<Lobed> {
    Profiled::new(LobedProfile::new(p.kappa)?, p.delta, p.inertia)
}

impl LobedProfile {
    /// The profile of sharpness `kappa`, which must lie in [`KAPPA_RANGE`].
    pub fn new(kappa: f64) -> jamkit_core::Result<Self> {
        let (lo, hi) = KAPPA_RANGE;
        if !(kappa >= lo && kappa <= hi) {
            return Err(jamkit_core::Error::invalid(
                "params.kappa",
                kappa,
                format!("must lie in [{lo}, {hi}] (for κ < {lo} use family `fourier` with n = 2)"),
            ));
        }
        let mean = scaled_bessel_i0(kappa);
        let scale = 1.0 / (1.0 - mean);
        let mean_g2 = scaled_bessel_i0(2.0 * kappa);
        Ok(Self {
            kappa,
            mean,
            scale,
            mean_square: (mean_g2 - mean * mean) * scale * scale,
        })
    }

    /// `κ`.
    pub fn kappa(&self) -> f64 {
        self.kappa
    }

    /// `G(φ)` and `G'(φ)` (slow path, for geometry and tests).
    pub fn profile(&self, phi: f64) -> (f64, f64) {
        let (sin, cos) = phi.sin_cos();
        self.value_slope(cos, sin)
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
}

impl NearDiskProfile for LobedProfile {
    const FAMILY: &'static str = INFO.name;
    /// `G` depends on `sin² A` only.
    const HALF_TURN_SYMMETRIC: bool = true;

    /// `G(A)` and `G'(A)`: `e^{−2κ sin²A}`, and `sin 2A = 2 sin A cos A`.
    #[inline(always)]
    fn value_slope(&self, cos: f64, sin: f64) -> (f64, f64) {
        let g = (-2.0 * self.kappa * sin * sin).exp();
        (
            (g - self.mean) * self.scale,
            -4.0 * self.kappa * sin * cos * g * self.scale,
        )
    }

    /// `G''` at `A = atan2(sin, cos)` (not a hot path).
    fn curvature(&self, cos: f64, sin: f64) -> f64 {
        self.profile_second(sin.atan2(cos))
    }

    /// `max G = G(0) = 1`, `min G = G(π/2)`.
    fn range(&self) -> (f64, f64) {
        (self.profile_min(), 1.0)
    }

    /// `⟨G⟩ = 0` and `⟨G²⟩ = (e^{−2κ} I₀(2κ) − m²) / (1 − m)²`, exact.
    fn moments(&self) -> (f64, f64) {
        (0.0, self.mean_square)
    }

    fn describe(&self) -> String {
        format!("κ = {}", self.kappa)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::{Angle, BodyOrientation, Contact, Shape, Vector};
    use jamkit_core::{Pair, ShapeExt};

    fn shape(delta: f64, kappa: f64) -> Lobed {
        lobed(&LobedParams {
            delta,
            kappa,
            inertia: None,
        })
        .unwrap()
    }

    fn contact(s: &Lobed, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> Contact<2> {
        s.pair_contacts(
            &Pair::new(ri, Angle::<1>::new(ti), rj, Angle::<1>::new(tj), d),
            f64::INFINITY,
        )[0]
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
            let s = shape(0.2, kappa);
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
        let s = shape(0.3, 2.0);
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
            let s = shape(0.2, kappa);
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
            let s = shape(0.1, kappa);
            let m = 4096;
            let mean: f64 = (0..m)
                .map(|k| s.profile().profile(2.0 * PI * k as f64 / m as f64).0)
                .sum::<f64>()
                / m as f64;
            assert!(mean.abs() < 1e-13, "κ = {kappa}: ⟨G⟩ = {mean:e}");
            assert_relative_eq!(s.profile().profile(0.0).0, 1.0, epsilon = 1e-14);
            assert_relative_eq!(
                s.profile().profile(PI / 2.0).0,
                s.profile().profile_min(),
                epsilon = 1e-14
            );
            let eps = 1e-5;
            for phi in [0.2, 1.0, 2.5, -0.7] {
                let num1 = (s.profile().profile(phi + eps).0 - s.profile().profile(phi - eps).0)
                    / (2.0 * eps);
                let num2 = (s.profile().profile(phi + eps).1 - s.profile().profile(phi - eps).1)
                    / (2.0 * eps);
                let scale = 1.0 + kappa * kappa;
                assert_relative_eq!(s.profile().profile(phi).1, num1, epsilon = 1e-7 * scale);
                assert_relative_eq!(
                    s.profile().profile_second(phi),
                    num2,
                    epsilon = 1e-7 * scale
                );
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
            let s = shape(delta, kappa);
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
        let s = shape(0.1, 1.0);
        let mut o = Angle::new(3.0);
        s.rotate(&mut o, &[0.5]);
        assert_relative_eq!(o.theta(), 3.5 - 2.0 * PI, epsilon = 1e-15);
        let back = Angle::<1>::from_coords(&o.to_coords()).unwrap();
        assert_eq!(back, o);
        assert!(Angle::<1>::from_coords(&[f64::NAN]).is_none());
        assert!(Angle::<1>::from_coords(&[]).is_none());
    }

    #[test]
    fn nonsense_parameters_are_rejected_and_large_delta_is_non_convex() {
        let try_new = |delta, kappa, inertia| {
            lobed(&LobedParams {
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
            try_new(0.1, 1.0, Some(0.0)).unwrap_err().field(),
            Some("params.inertia")
        );
        // The disk Δ = 0 turns with I = 1 unless told otherwise.
        assert_eq!(
            Shape::<2>::rot_inertia(&try_new(0.0, 1.0, None).unwrap(), 1.0)[0],
            1.0
        );
        // κ = 1: min G ≈ −0.619, so R > 0 needs Δ < 1.62.
        assert_eq!(
            try_new(1.7, 1.0, None).unwrap_err().field(),
            Some("params.delta")
        );
        assert!(shape(0.2, 1.0).is_convex());
        assert!(Shape::<2>::policy(&shape(0.2, 1.0)).warnings.is_empty());
        // The waist turns concave near Δ ≈ 0.61 at κ = 1.
        assert!(!shape(1.0, 1.0).is_convex());
        assert_eq!(Shape::<2>::policy(&shape(1.0, 1.0)).warnings.len(), 1);
    }
}
