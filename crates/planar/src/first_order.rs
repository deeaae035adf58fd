//! The paper's first-order gap between two near-disks, for any profile.
//!
//! A near-disk of size `R⁰` has the outline `R(φ) = R⁰ [1 + Δ P(θ − φ)]`
//! for some profile `P` (`sin(nφ)/n` for the paper's `fourier` family). To
//! first order in `Δ` the gap is (Ikeda, Eq. (8))
//!
//! ```text
//! h = r − R_i⁰ − R_j⁰ − Δ [R_i⁰ P(A_i) + R_j⁰ P(A_j)],
//! A_i = θ_i − θ_ij,   A_j = θ_j − θ_ij − π,
//! ```
//!
//! with `r = |r_ij|` and `θ_ij` the direction of `r_ij`. With `u = r_ij/r`,
//! `t = (−u_y, u_x)`, `∂A/∂r_j = −t/r`, `G = Δ[R_i⁰ P'(A_i) + R_j⁰ P'(A_j)]`,
//! `c_i = Δ R_i⁰ P''(A_i)` and `G₂ = c_i + c_j`:
//!
//! ```text
//! ∂h/∂r_j = u + G t / r,            ∂h/∂θ_i = −Δ R_i⁰ P'(A_i),
//! ∂²h/∂r_j∂r_j = t tᵀ (1/r − G₂/r²) − (G/r²)(u tᵀ + t uᵀ),
//! ∂²h/∂r_j∂θ_i = c_i t / r,         ∂²h/∂θ_i² = −c_i,     ∂²h/∂θ_i∂θ_j = 0
//! ```
//!
//! (the same for `j`). A family's fast `contacts` may compute the first
//! derivatives its own way; [`gap_hessian`] gives the second derivatives
//! from the profile's value, slope and curvature at the two angles.

use jamkit_core::math::{Matrix, Vector};
use jamkit_core::{Contact, GapHessian};

/// `P(A)`, `P'(A)` and `P''(A)` of one body at its angle `A` to the line of
/// centres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profile {
    /// `P(A)`.
    pub value: f64,
    /// `P'(A)`.
    pub slope: f64,
    /// `P''(A)`.
    pub curvature: f64,
}

/// The first-order gap of bodies `i` (size `size_i`, profile `p_i` at
/// `A_i`) and `j` at separation `r_ij`, with its first and second
/// derivatives (one rotational coordinate per body, the angle θ).
pub fn gap_hessian(
    r_ij: &Vector<2>,
    size_i: f64,
    size_j: f64,
    delta: f64,
    p_i: Profile,
    p_j: Profile,
) -> GapHessian<2> {
    let r = r_ij.norm();
    let gap = r - size_i - size_j - delta * (size_i * p_i.value + size_j * p_j.value);
    let (gi, gj) = (delta * size_i * p_i.slope, delta * size_j * p_j.slope);
    // NOTE: coincident centres have no direction; take θ_ij = 0 as the
    // families' `contacts` do, and zero curvature terms (they diverge as 1/r).
    let (u, inv_r) = if r > 0.0 {
        (r_ij / r, 1.0 / r)
    } else {
        (Vector::<2>::new(1.0, 0.0), 0.0)
    };
    let t = Vector::<2>::new(-u[1], u[0]);
    let g = gi + gj;
    let contact = Contact {
        gap,
        grad_r: u + t * (g * inv_r),
        grad_rot_i: [-gi, 0.0, 0.0],
        grad_rot_j: [-gj, 0.0, 0.0],
    };
    let (c_i, c_j) = (
        delta * size_i * p_i.curvature,
        delta * size_j * p_j.curvature,
    );
    let tt = t * t.transpose();
    let ut = u * t.transpose() + t * u.transpose();
    let rr = if r > 0.0 {
        tt * (inv_r - (c_i + c_j) * inv_r * inv_r) - ut * (g * inv_r * inv_r)
    } else {
        Matrix::<2>::zeros()
    };
    let mut h = GapHessian::translational(gap, contact.grad_r, rr);
    h.contact = contact;
    h.r_qi[0] = t * (c_i * inv_r);
    h.r_qj[0] = t * (c_j * inv_r);
    h.qi_qi[0][0] = -c_i;
    h.qj_qj[0][0] = -c_j;
    h
}
