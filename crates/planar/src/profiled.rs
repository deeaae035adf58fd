//! A near-disk family is its profile: [`Profiled<P>`] is the whole `Shape`
//! of a 2D near-disk with the paper's first-order gap, for any profile `P`.
//!
//! A body of size `R⁰` and orientation `θ_i` has the polar outline (lab
//! direction `φ`)
//!
//! ```text
//! R_i(φ) = R⁰ [1 + Δ P(θ_i − φ)],
//! ```
//!
//! and two bodies interact through the first-order gap (Ikeda, Eq. (8) with
//! `P` in place of `sin(nφ)/n`)
//!
//! ```text
//! h_ij = |r_ij| − R_i⁰ − R_j⁰ − Δ [R_i⁰ P(A_i) + R_j⁰ P(A_j)],
//! A_i = θ_i − θ_ij,   A_j = θ_j − θ_ij − π,
//! ∂h/∂r_j = u + Δ [R_i⁰ P'(A_i) + R_j⁰ P'(A_j)] t / |r_ij|   (= −∂h/∂r_i),
//! ∂h/∂θ_i = −Δ R_i⁰ P'(A_i),     ∂h/∂θ_j = −Δ R_j⁰ P'(A_j),
//! ```
//!
//! with `u = r_ij/|r_ij|` and `t = (−u_y, u_x)`; the second derivatives are
//! [`first_order::gap_hessian`]'s. The area is `½∫R² dφ = π (R⁰)² [1 +
//! 2Δ⟨P⟩ + Δ²⟨P²⟩]`, exact for the outline, not first order.
//!
//! A profile ([`NearDiskProfile`]) gives `P`, `P'` and `P''` from `cos A`
//! and `sin A`, its range and its moments; everything else (parameter
//! checks for `Δ` and the inertia, the bounding radius, orientations,
//! contacts, Hessians, the outline for drawing, the convexity warning)
//! is written once here. A new near-disk family is a profile, its
//! parameters and its registration: `shapes/lobed` is the example
//! (docs/tutorials/new-shape-rust.md).
//!
//! NOTE: the pair loop calls no `atan2`, `sin` or `cos`: `e^{iA_i} =
//! e^{iθ_i} e^{−iθ_ij}` is a complex product of the cached `e^{iθ_i}`
//! ([`Angle`]) and the unit vector `u`. For body `j` the `−π` of `A_j`
//! flips the signs of both `cos A_j` and `sin A_j`; a profile that declares
//! itself symmetric under a half turn (`P(A + π) = P(A)`, as for every even
//! mode) gets the unflipped pair, which it cannot tell apart.

use crate::first_order::{Profile, gap_hessian};
use crate::gap2d::direction;
use jamkit_core::{
    Angle, Contact, Error, GapHessian, Look, NoFastPath, Outline, Pair, Policy, RotVec, Shape,
    Vector,
};
use std::f64::consts::PI;
use std::fmt::Debug;

/// The profile `P` of a near-disk family, `R(φ)/R⁰ = 1 + Δ P(φ)`.
pub trait NearDiskProfile: Clone + Debug + PartialEq + Send + Sync + 'static {
    /// The family's registered name.
    const FAMILY: &'static str;
    /// Whether `P(A + π) = P(A)` for every `A` (then body `j`'s angle may
    /// drop the `−π`; see the module notes).
    const HALF_TURN_SYMMETRIC: bool;

    /// `P(A)` and `P'(A)` from `cos A` and `sin A` (the pair loop's path).
    fn value_slope(&self, cos: f64, sin: f64) -> (f64, f64);

    /// `P''(A)` from `cos A` and `sin A` (the Hessian's path).
    fn curvature(&self, cos: f64, sin: f64) -> f64;

    /// `(min P, max P)` over the circle. The maximum sets the bounding
    /// radius `R⁰(1 + Δ max P)`: one too small loses contacts, so give an
    /// exact bound (or a safe one).
    fn range(&self) -> (f64, f64);

    /// `(⟨P⟩, ⟨P²⟩)` over the circle, for the area. By default the
    /// trapezoid rule on 4096 angles (spectrally accurate for a smooth
    /// periodic `P`); a profile with closed forms overrides it.
    fn moments(&self) -> (f64, f64) {
        let m = 4096;
        let (mut s1, mut s2) = (0.0, 0.0);
        for k in 0..m {
            let (sin, cos) = (2.0 * PI * k as f64 / m as f64).sin_cos();
            let p = self.value_slope(cos, sin).0;
            s1 += p;
            s2 += p * p;
        }
        (s1 / m as f64, s2 / m as f64)
    }

    /// The profile's own parameters, for messages (e.g. `κ = 2`).
    fn describe(&self) -> String;
}

/// A near-disk of profile `P`: `Δ`, the moment of inertia, and the area
/// constants computed once.
#[derive(Clone, Debug, PartialEq)]
pub struct Profiled<P> {
    profile: P,
    delta: f64,
    inertia: f64,
    /// `P`'s range and moments.
    range: (f64, f64),
    moments: (f64, f64),
}

impl<P: NearDiskProfile> Profiled<P> {
    /// The shape of amplitude `delta` and moment of inertia `inertia`
    /// (`None`: `I = Δ`, the paper's choice, or 1 for the disk `Δ = 0`,
    /// whose turning changes nothing), checked: `Δ ≥ 0` finite, `I`
    /// positive and finite, and `R(φ) > 0` everywhere. Errors name
    /// `params.delta` or `params.inertia`.
    pub fn new(profile: P, delta: f64, inertia: Option<f64>) -> jamkit_core::Result<Self> {
        if !(delta.is_finite() && delta >= 0.0) {
            return Err(Error::invalid(
                "params.delta",
                delta,
                "must be a finite number ≥ 0",
            ));
        }
        let inertia = inertia.unwrap_or(if delta > 0.0 { delta } else { 1.0 });
        if !(inertia > 0.0 && inertia.is_finite()) {
            return Err(Error::invalid(
                "params.inertia",
                inertia,
                "must be positive and finite",
            ));
        }
        let range = profile.range();
        let moments = profile.moments();
        let shape = Self {
            profile,
            delta,
            inertia,
            range,
            moments,
        };
        let min_r = shape.min_relative_radius();
        if !(min_r > 0.0) {
            return Err(Error::invalid(
                "params.delta",
                delta,
                format!(
                    "is so large that R(θ) ≤ 0 somewhere (min R/R0 = {min_r:.4}); need Δ < {:.4} at {}",
                    -1.0 / range.0,
                    shape.profile.describe()
                ),
            ));
        }
        Ok(shape)
    }

    /// The profile.
    pub fn profile(&self) -> &P {
        &self.profile
    }

    /// `Δ`.
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// `R(φ)/R⁰ = 1 + Δ P(φ)` in the body frame.
    pub fn relative_radius(&self, phi: f64) -> f64 {
        let (sin, cos) = phi.sin_cos();
        1.0 + self.delta * self.profile.value_slope(cos, sin).0
    }

    /// `min R/R⁰ = 1 + Δ min P`.
    pub fn min_relative_radius(&self) -> f64 {
        1.0 + self.delta * self.range.0
    }

    /// True when the outline is convex: the polar curvature numerator
    /// `r² + 2r'² − r r''` stays positive (sampled on 8192 angles).
    pub fn is_convex(&self) -> bool {
        let d = self.delta;
        (0..8192).all(|k| {
            let (sin, cos) = (2.0 * PI * k as f64 / 8192.0).sin_cos();
            let (p, dp) = self.profile.value_slope(cos, sin);
            let (r, dr, ddr) = (1.0 + d * p, d * dp, d * self.profile.curvature(cos, sin));
            r * r + 2.0 * dr * dr - r * ddr > 0.0
        })
    }

    /// Area in units of `(R⁰)²`: `π [1 + 2Δ⟨P⟩ + Δ²⟨P²⟩]`.
    pub fn relative_area(&self) -> f64 {
        let d = self.delta;
        let (mean, mean_square) = self.moments;
        // NOTE: written so that a zero-mean profile gives `π (1 + Δ²⟨P²⟩)`
        // to the bit (`1 + 0 = 1`).
        PI * (1.0 + 2.0 * d * mean + d * d * mean_square)
    }

    /// `(cos A, sin A)` of bodies `i` and `j` for the unit vector `u` of
    /// the line of centres (body `j`'s with the `−π` unless the profile is
    /// symmetric under a half turn).
    #[inline(always)]
    fn phases(&self, o_i: &Angle<1>, o_j: &Angle<1>, u: &Vector<2>) -> [(f64, f64); 2] {
        // e^{iA} = e^{iθ} e^{−iθ_ij}: cos A = cos θ u_x + sin θ u_y,
        // sin A = sin θ u_x − cos θ u_y.
        let phase = |o: &Angle<1>| {
            let (c, s) = o.unit();
            (c * u[0] + s * u[1], s * u[0] - c * u[1])
        };
        let (cj, sj) = phase(o_j);
        let j = if P::HALF_TURN_SYMMETRIC {
            (cj, sj)
        } else {
            (-cj, -sj)
        };
        [phase(o_i), j]
    }
}

impl<P: NearDiskProfile> Outline for Profiled<P> {
    fn relative_radius(&self, psi: f64) -> f64 {
        Profiled::relative_radius(self, psi)
    }
}

impl<P: NearDiskProfile> Shape<2> for Profiled<P> {
    type Orientation = Angle<1>;
    type Fast = NoFastPath;

    fn family(&self) -> &'static str {
        P::FAMILY
    }

    fn rot_dof(&self) -> usize {
        1
    }

    fn volume(&self, size: f64) -> f64 {
        self.relative_area() * size * size
    }

    /// `R⁰ (1 + Δ max P)`.
    fn bounding_radius(&self, size: f64) -> f64 {
        size * (1.0 + self.delta * self.range.1)
    }

    fn rot_inertia(&self, _size: f64) -> RotVec {
        [self.inertia, 1.0, 1.0]
    }

    fn rotate(&self, o: &mut Angle<1>, dq: &[f64]) {
        *o = o.turned(dq[0]);
    }

    /// Rattlers below three contacts, as for the paper's near-disks
    /// (`d + 1`); near-disks jam hypostatic; a warning where the outline is
    /// not convex.
    fn policy(&self) -> Policy {
        let mut warnings = Vec::new();
        if !self.is_convex() {
            warnings.push(format!(
                "non-convex outline (Δ = {}, {}): the first-order gap assumes convex bodies with one contact per pair",
                self.delta,
                self.profile.describe()
            ));
        }
        Policy {
            rattler_threshold: 3,
            expects_isostatic: false,
            warnings,
            ..Policy::new(2)
        }
    }

    fn look(&self) -> Look {
        Look {
            outline: Some(std::sync::Arc::new(self.clone())),
            ..Look::default()
        }
    }

    #[inline(always)]
    fn contacts<F: FnMut(Contact<2>)>(&self, pair: &Pair<2, Angle<1>>, max_gap: f64, mut visit: F) {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        let r = r_ij.norm();
        // P ≤ max P, so h ≥ |r| − b_i − b_j: skip pairs certainly apart.
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return;
        }
        let (_, u, inv_r) = direction(r_ij);
        let [(ci, si), (cj, sj)] = self.phases(o_i, o_j, &u);
        let (p_i, dp_i) = self.profile.value_slope(ci, si);
        let (p_j, dp_j) = self.profile.value_slope(cj, sj);
        let d = self.delta;
        let gap = r - size_i - size_j - d * (size_i * p_i + size_j * p_j);
        let tangent = Vector::<2>::new(-u[1], u[0]);
        let grad_r = u + tangent * (d * (size_i * dp_i + size_j * dp_j) * inv_r);
        visit(Contact {
            gap,
            grad_r,
            grad_rot_i: [-d * size_i * dp_i, 0.0, 0.0],
            grad_rot_j: [-d * size_j * dp_j, 0.0, 0.0],
        });
    }

    /// The same gap with its second derivatives
    /// ([`first_order::gap_hessian`](crate::first_order::gap_hessian)).
    fn gap_hessians<V: FnMut(GapHessian<2>)>(
        &self,
        pair: &Pair<2, Angle<1>>,
        max_gap: f64,
        mut visit: V,
    ) -> jamkit_core::Result<()> {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        let (r, u, _) = direction(r_ij);
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return Ok(());
        }
        let profile = |(cos, sin): (f64, f64)| {
            let (value, slope) = self.profile.value_slope(cos, sin);
            Profile {
                value,
                slope,
                curvature: self.profile.curvature(cos, sin),
            }
        };
        let [a_i, a_j] = self.phases(o_i, o_j, &u);
        visit(gap_hessian(
            r_ij,
            size_i,
            size_j,
            self.delta,
            profile(a_i),
            profile(a_j),
        ));
        Ok(())
    }
}
