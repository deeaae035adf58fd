//! Gap models for two-dimensional bodies beyond the paper's first order:
//! the **second-order** near-disk gap and the **exact** gap of convex
//! outlines (see `docs/explanation/gap-models.md`, "The ladder of gap
//! models").
//!
//! ## A gap as a function of `(r, A_i, A_j)`
//!
//! Near-disk gaps depend on the separation only through `r = |r_ij|` and
//! the two angles `A_i = θ_i − θ_ij`, `A_j = θ_j − θ_ij − π` between each
//! body's orientation and the line of centres. [`Partials`] holds such a
//! gap with its partial derivatives in these three variables, and
//! [`Partials::chain`] turns them into derivatives with respect to the
//! generalised coordinates: with `u = r_ij/r`, `t = (−u_y, u_x)`,
//! `∂r/∂r_j = u`, `∂²r/∂r_j² = t tᵀ/r`, `∂A/∂r_j = −t/r`,
//! `∂²A/∂r_j² = (u tᵀ + t uᵀ)/r²` and `∂A_i/∂θ_i = 1`,
//!
//! ```text
//! ∂h/∂r_j   = h_r u − (h_i + h_j) t/r,        ∂h/∂θ_i = h_i,
//! ∂²h/∂r_j² = h_rr u uᵀ + h_r t tᵀ/r + (h_i + h_j)(u tᵀ + t uᵀ)/r²
//!             − (h_ri + h_rj)(u tᵀ + t uᵀ)/r + (h_ii + 2h_ij + h_jj) t tᵀ/r²,
//! ∂²h/∂r_j∂θ_i = h_ri u − (h_ii + h_ij) t/r,   ∂²h/∂θ_i∂θ_j = h_ij.
//! ```
//!
//! ## Second order
//!
//! For outlines `R(φ) = R⁰[1 + Δ F(θ − φ)]`, with `F, F', F'', F'''` taken
//! at `A_i` (body `i`) and `A_j` (body `j`) and `G = R_i⁰ F_i' + R_j⁰ F_j'`,
//!
//! ```text
//! h₂ = r − R_i⁰ − R_j⁰ − Δ (R_i⁰ F_i + R_j⁰ F_j)
//!        + (Δ²/2) [G²/r − R_i⁰ F_i'² − R_j⁰ F_j'²]  + O(Δ³):
//! ```
//!
//! the first line is the paper's gap; the second is what the closest points
//! gain by leaving the line of centres (each body's support function
//! `H(ψ) = R⁰[1 + ΔF + Δ²F'²/2] + O(Δ³)` exceeds its radius, and the
//! common normal turns by `δψ = −ΔG/r`). [`second_order`] gives its
//! partials.
//!
//! ## Exact gap of convex outlines
//!
//! A convex body is described by its support function `H(β)` (the largest
//! projection of the outline on the direction `e(β)`, body frame). The
//! separating-axis theorem makes the signed distance of two convex bodies
//!
//! ```text
//! h = max_ψ g(ψ),    g(ψ) = r_ij·e(ψ) − H_i(ψ − θ_i) − H_j(ψ + π − θ_j)
//! ```
//!
//! (positive: the distance; negative: minus the depth of penetration along
//! the common normal). At the maximum `ψ*` the normal `n = e(ψ*)` is the
//! common normal of the two outlines. By the envelope theorem
//!
//! ```text
//! ∂h/∂r_j = n,   ∂h/∂θ_i = H_i'(ψ* − θ_i),   ∂h/∂θ_j = H_j'(ψ* + π − θ_j),
//! ```
//!
//! and with `k = −g''(ψ*) = h + ρ_i + ρ_j` (`ρ = H + H''`, the radius of
//! curvature at the contact point) and `n⊥ = e'(ψ*)`,
//!
//! ```text
//! ∂²h/∂r_j² = n⊥ n⊥ᵀ / k,        ∂²h/∂r_j∂θ_i = H_i'' n⊥ / k,
//! ∂²h/∂θ_i² = −H_i'' + H_i''²/k,  ∂²h/∂θ_i∂θ_j = H_i'' H_j'' / k.
//! ```
//!
//! [`exact`] finds `ψ*` by a safeguarded Newton iteration from the line of
//! centres; [`polar_support`] gives `H, H', H''` of any star-shaped convex
//! outline `R(φ)` from the boundary point whose normal points along `β`.
//!
//! ## The joint iteration
//!
//! [`exact_unit`] on [`polar_support_unit`] supports nests two Newton
//! iterations: at every iterate `ψ` both support searches run to
//! convergence, although only the last one's supports need it.
//! [`exact_joint`] runs one Newton iteration on the normal angle `ψ` and
//! both support points' polar angles `φ_i`, `φ_j` at once. With the height
//! of body `k`'s boundary point `φ` along its body-frame direction `β`,
//! `h(φ, β) = R(φ) cos δ`, `δ = φ − β` (`H(β) = max_φ h`), the gap is the
//! saddle value
//!
//! ```text
//! h = max_ψ min_{φ_i, φ_j} L,    L = r_ij·e(ψ) − h_i(φ_i, ψ − θ_i) − h_j(φ_j, ψ + π − θ_j),
//! ```
//!
//! stationary where `∂L/∂ψ = r_ij·e'(ψ) − R_i sin δ_i − R_j sin δ_j = 0`
//! and `q_k = R_k sin δ_k − R_k' cos δ_k = 0` (each support condition).
//! With `q_φ = ∂q/∂φ = 2R' sin δ + (R − R'') cos δ` and
//! `m = −∂q/∂β = R cos δ + R' sin δ` at the current point, Newton's step
//! on the three angles, the support steps eliminated
//! (`δφ_k = (m_k δψ − q_k)/q_φk`), is
//!
//! ```text
//! δψ = [∂L/∂ψ + Σ_k m_k q_k/q_φk] / k,     k = L + Σ_k m_k²/q_φk,
//! ```
//!
//! and at converged supports `m²/q_φ = ρ`, so that `k = h + ρ_i + ρ_j` and
//! `δψ` is the nested solve's outer step. One step costs one outline
//! evaluation per body, where the nested solve's step runs both support
//! searches (two or more evaluations each, and its line searches).
//!
//! A saddle point has no merit function, so the iteration is guarded
//! instead: it fails where `q_φ ≤ 0` (away from a support point of a
//! convex outline) or `k ≤ 0` (an overlap deeper than the radii of
//! curvature), where a step is longer than 0.3 rad (far from the optimum,
//! where it could run to another stationary point of `g` than the nested
//! solve's ascent reaches) or than the one before (no quadratic
//! convergence), or after 30 steps. The
//! caller then runs the nested solve.
//!
//! **Converged** means, for the Hessian: the last Newton step was below
//! [`JOINT_TOLERANCE`] = 10⁻⁸ rad on all three angles. Convergence being
//! quadratic, the distance left to the stationary point is `~C s²` after a
//! step `s`, with `C = O(n³Δ)` the ratio of the system's second to first
//! derivatives: `≲ C·10⁻¹⁶` rad in each angle, round-off, so that
//! `|g'(ψ)| = |∂L/∂ψ|` at converged supports is `≲ k·C·10⁻¹⁶` and `h` is
//! exact to round-off (`L` is stationary). The jets, `H''` included, are
//! computed at the final point.
//!
//! The contacts need `H` and `H'` alone, and end earlier: after a Newton
//! step `δ₁` below [`JOINT_FINISH`] = 10⁻⁵ rad, that step is corrected to
//! second order (Chebyshev: `J δ₂ = −½ F''[δ₁, δ₁]`, with `F` the three
//! conditions above, `J` their Jacobian, eliminated as for `δ₁`, and
//! `F''` from `R … R‴` at the same point), which leaves `~C²|δ₁|³ ≲
//! C²·10⁻¹⁵` rad, and `H`, `H'` are moved along `δ₁ + δ₂` to second order
//! (`O(|δ|³)` left): no further outline evaluation, and `|g'|`, `|q|`
//! below 10⁻¹⁴ at the result (tests: `shapes/fourier/tests/warm.rs`).
//!
//! Either way the result is that of the stationary point to round-off
//! **whatever the start**: from the first-order guesses, or from the point
//! where the same pair's previous solve ended (a *warm start*,
//! [`crate::profiled::Profiled`]'s contacts in the engine, which then take
//! one step on most pairs). It is not the nested solve's result bit for
//! bit: that one stops after a step below 10⁻⁷ rad on ψ (`~C·10⁻¹⁴` rad
//! left).

use jamkit_core::math::{Matrix, Unit, Vector, cmul, turn_unit, unit_of_angle};
use jamkit_core::{Contact, GapHessian};

/// Which gap a family uses, and its parser: in `jamkit_core::gap_model`,
/// shared with the 3D `harmonic` family (re-exported here, where the 2D
/// families have always found it).
pub use jamkit_core::gap_model::{GapModel, deserialize_gap};

/// A gap `h(r, A_i, A_j)` with its partial derivatives (index 0: body `i`,
/// 1: body `j`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partials {
    /// `h`.
    pub h: f64,
    /// `∂h/∂r`.
    pub h_r: f64,
    /// `∂h/∂A_i`, `∂h/∂A_j`.
    pub h_a: [f64; 2],
    /// `∂²h/∂r²`.
    pub h_rr: f64,
    /// `∂²h/∂r∂A_i`, `∂²h/∂r∂A_j`.
    pub h_ra: [f64; 2],
    /// `∂²h/∂A_a∂A_b`.
    pub h_aa: [[f64; 2]; 2],
}

/// `u = r_ij/r` and `1/r`; coincident centres take `θ_ij = 0` and drop the
/// terms that diverge as `1/r` (such a pair overlaps deeply and any
/// direction pushes it apart), as the first-order gap does.
#[inline(always)]
pub(crate) fn direction(r_ij: &Vector<2>) -> (f64, Vector<2>, f64) {
    let r = r_ij.norm();
    if r > 0.0 {
        (r, r_ij * (1.0 / r), 1.0 / r)
    } else {
        (r, Vector::<2>::new(1.0, 0.0), 0.0)
    }
}

impl Partials {
    /// The contact (gap and first derivatives) at separation `r_ij`.
    #[inline(always)]
    pub fn contact(&self, r_ij: &Vector<2>) -> Contact<2> {
        let (_, u, inv_r) = direction(r_ij);
        let t = Vector::<2>::new(-u[1], u[0]);
        Contact {
            gap: self.h,
            grad_r: u * self.h_r - t * ((self.h_a[0] + self.h_a[1]) * inv_r),
            grad_rot_i: [self.h_a[0], 0.0, 0.0],
            grad_rot_j: [self.h_a[1], 0.0, 0.0],
        }
    }

    /// The gap with first and second derivatives in the generalised
    /// coordinates (chain rule of the module documentation).
    pub fn chain(&self, r_ij: &Vector<2>) -> GapHessian<2> {
        let (_, u, inv_r) = direction(r_ij);
        let t = Vector::<2>::new(-u[1], u[0]);
        let sym = u * t.transpose() + t * u.transpose();
        let (sa, sra) = (self.h_a[0] + self.h_a[1], self.h_ra[0] + self.h_ra[1]);
        let saa = self.h_aa[0][0] + 2.0 * self.h_aa[0][1] + self.h_aa[1][1];
        let rr = u * u.transpose() * self.h_rr
            + t * t.transpose() * (self.h_r * inv_r + saa * inv_r * inv_r)
            + sym * (sa * inv_r * inv_r - sra * inv_r);
        let rr: Matrix<2> = if inv_r > 0.0 {
            rr
        } else {
            Matrix::<2>::zeros()
        };
        let mut g = GapHessian::translational(self.h, Vector::<2>::zeros(), rr);
        g.contact = self.contact(r_ij);
        g.r_qi[0] = u * self.h_ra[0] - t * ((self.h_aa[0][0] + self.h_aa[0][1]) * inv_r);
        g.r_qj[0] = u * self.h_ra[1] - t * ((self.h_aa[1][1] + self.h_aa[0][1]) * inv_r);
        g.qi_qi[0][0] = self.h_aa[0][0];
        g.qj_qj[0][0] = self.h_aa[1][1];
        g.qi_qj[0][0] = self.h_aa[0][1];
        g
    }
}

/// A profile and its first three derivatives at one angle:
/// `[F, F', F'', F''']`.
pub type Jet3 = [f64; 4];

/// The second-order near-disk gap (module documentation) with its partials,
/// for bodies of sizes `size_i`, `size_j`, amplitude `delta`, profiles `p_i`
/// at `A_i` and `p_j` at `A_j`, at distance `r`. At `r = 0` the `G²/r` term
/// is dropped.
#[inline(always)]
pub fn second_order(
    r: f64,
    size_i: f64,
    size_j: f64,
    delta: f64,
    p_i: Jet3,
    p_j: Jet3,
) -> Partials {
    let inv_r = if r > 0.0 { 1.0 / r } else { 0.0 };
    let (ri, rj) = (size_i, size_j);
    let [f_i, s_i, c_i, d_i] = p_i;
    let [f_j, s_j, c_j, d_j] = p_j;
    let g = ri * s_i + rj * s_j;
    let d2 = delta * delta;
    let h = r - ri - rj - delta * (ri * f_i + rj * f_j)
        + 0.5 * d2 * (g * g * inv_r - ri * s_i * s_i - rj * s_j * s_j);
    let ha = |rk: f64, s: f64, c: f64| -delta * rk * s + d2 * (g * rk * c * inv_r - rk * s * c);
    let haa = |rk: f64, s: f64, c: f64, d: f64| {
        -delta * rk * c
            + d2 * (rk * rk * c * c * inv_r + g * rk * d * inv_r - rk * c * c - rk * s * d)
    };
    let hij = d2 * ri * c_i * rj * c_j * inv_r;
    Partials {
        h,
        h_r: 1.0 - 0.5 * d2 * g * g * inv_r * inv_r,
        h_a: [ha(ri, s_i, c_i), ha(rj, s_j, c_j)],
        h_rr: d2 * g * g * inv_r * inv_r * inv_r,
        h_ra: [
            -d2 * g * ri * c_i * inv_r * inv_r,
            -d2 * g * rj * c_j * inv_r * inv_r,
        ],
        h_aa: [[haa(ri, s_i, c_i, d_i), hij], [hij, haa(rj, s_j, c_j, d_j)]],
    }
}

/// A support function and its first two derivatives at one direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SupportJet {
    /// `H(β)`.
    pub h: f64,
    /// `H'(β)`.
    pub d1: f64,
    /// `H''(β)`; `H + H''` is the radius of curvature at the support point.
    pub d2: f64,
}

/// The support function of a star-shaped **convex** outline given in polar
/// form by `outline(φ) = (R, R', R'')` (body frame), in the direction `β`.
///
/// The support point is the boundary point whose outward normal points
/// along `β`: its polar angle `φ` solves `ν(φ) = φ − atan(R'/R) = β`, i.e.
/// with `δ = φ − β`, `q(φ) = R sin δ − R' cos δ = 0`, found by Newton's
/// method (`q' = 2R' sin δ + (R − R'') cos δ = (cos δ/R)(R² + 2R'² − R R'')`
/// is positive on a convex outline). Then
/// `H = R cos δ`, `H' = R sin δ`, `H'' = ρ − H`,
/// `ρ = (R² + R'²)^{3/2} / (R² + 2R'² − R R'')`.
///
/// NOTE: on a non-convex outline `ν` is not monotonic, the support point
/// jumps and `ρ` changes sign; callers refuse such outlines.
pub fn polar_support<F: Fn(f64) -> (f64, f64, f64)>(beta: f64, outline: F) -> SupportJet {
    let e = unit_of_angle(beta);
    polar_support_unit(e, e, |p: Unit| outline(p.1.atan2(p.0))).0
}

/// [`polar_support`] with directions as unit complex numbers (no
/// trigonometric call): `e_beta = e^{iβ}`, Newton started from the support
/// point `p0 = e^{iφ₀}`, `outline(e^{iφ}) = (R, R', R'')`. Returns the
/// [`SupportPoint`] too, so that a caller asking for nearby directions can
/// start the next search there.
#[inline]
pub fn polar_support_unit<F: Fn(Unit) -> (f64, f64, f64)>(
    e_beta: Unit,
    p0: Unit,
    outline: F,
) -> (SupportJet, SupportPoint) {
    let back = (e_beta.0, -e_beta.1);
    let mut p = p0;
    let (mut r, mut r1, mut r2) = outline(p);
    let mut d = cmul(p, back);
    for _ in 0..30 {
        let q = r * d.1 - r1 * d.0;
        let dq = 2.0 * r1 * d.1 + (r - r2) * d.0;
        let step = if dq > 0.0 {
            (q / dq).clamp(-0.5, 0.5)
        } else {
            // Far from the root (δ beyond ±π/2): turn towards β.
            0.5 * d.1.signum()
        };
        p = turn_unit(p, -step);
        (r, r1, r2) = outline(p);
        d = cmul(p, back);
        // Quadratic convergence: after a step s the error is ~C s² with
        // C = |q''/2q'| ≲ n³Δ; at s < 1e-7 that is ≲ 1e-13 in φ, which moves
        // H by ~1e-26 (H is stationary in φ) and H' by ~1e-13.
        if step.abs() < 1e-7 {
            break;
        }
    }
    let q = r * r + r1 * r1;
    let k = r * r + 2.0 * r1 * r1 - r * r2;
    let rho = q * q.sqrt() / k;
    let h = r * d.0;
    (
        SupportJet {
            h,
            d1: r * d.1,
            d2: rho - h,
        },
        SupportPoint {
            p,
            dphi_dbeta: q / k,
        },
    )
}

/// Where a support search ended: the support point `e^{iφ}` and how fast it
/// moves with the direction, `dφ/dβ = 1/ν' = (R² + R'²)/(R² + 2R'² − R R'')`,
/// so that the next search, for a nearby direction `β + dβ`, can start at
/// `φ + dβ dφ/dβ` (error O(dβ²)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupportPoint {
    /// `e^{iφ}`.
    pub p: Unit,
    /// `dφ/dβ` there.
    pub dphi_dbeta: f64,
}

/// The exact gap of two convex bodies at the optimum normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactGap {
    /// The common normal `n = e^{iψ*}` (from `i` towards `j`).
    pub normal: Unit,
    /// The signed distance `h = g(ψ*)`.
    pub gap: f64,
    /// Body `i`'s support function at `ψ* − θ_i`.
    pub jet_i: SupportJet,
    /// Body `j`'s support function at `ψ* + π − θ_j`.
    pub jet_j: SupportJet,
    /// Newton iterations taken (each evaluates both support functions).
    pub iterations: u32,
    /// False when the iteration stopped at its cap (the last iterate is
    /// returned; never observed on convex outlines).
    pub converged: bool,
}

/// The exact signed distance `h = max_ψ g(ψ)` of two convex bodies with
/// orientations `theta_i`, `theta_j` and body-frame support functions
/// `sup_i`, `sup_j` of the angle (module documentation), started from the
/// line of centres. See [`exact_unit`], which this wraps.
pub fn exact<S: Fn(f64) -> SupportJet, T: Fn(f64) -> SupportJet>(
    r_ij: &Vector<2>,
    theta_i: f64,
    sup_i: S,
    theta_j: f64,
    sup_j: T,
) -> ExactGap {
    let w0 = if r_ij.norm() > 0.0 {
        (r_ij[0] / r_ij.norm(), r_ij[1] / r_ij.norm())
    } else {
        (1.0, 0.0)
    };
    exact_unit(
        r_ij,
        w0,
        unit_of_angle(theta_i),
        |e: Unit| sup_i(e.1.atan2(e.0)),
        unit_of_angle(theta_j),
        |e: Unit| sup_j(e.1.atan2(e.0)),
    )
}

/// The exact gap with every direction a unit complex number: the first
/// guess of the normal `w0 = e^{iψ₀}`, the orientations `z = e^{iθ}`, and
/// support functions of the body-frame direction `e^{iβ}`.
///
/// Safeguarded Newton on `g'(ψ) = 0`: a Newton step is taken only where
/// `g'' < 0` (else a gradient step); steps larger than 10⁻³ rad are capped
/// at 0.3 rad and halved until `g` does not decrease; smaller Newton steps
/// are taken as they are (quadratic convergence; near the top `g` is flat
/// to round-off, and a test on its value would stop ψ ~1e-8 short).
/// Converged after a Newton step below 10⁻⁷ rad: what is left, ~C·10⁻¹⁴
/// with `C = |g'''/2g''| = O(1)`, moves `h` by ~10⁻²⁸ (`g` is stationary)
/// and the normal by ~10⁻¹⁴.
pub fn exact_unit<S: Fn(Unit) -> SupportJet, T: Fn(Unit) -> SupportJet>(
    r_ij: &Vector<2>,
    w0: Unit,
    z_i: Unit,
    sup_i: S,
    z_j: Unit,
    sup_j: T,
) -> ExactGap {
    let (zi_bar, zj_bar_neg) = ((z_i.0, -z_i.1), (-z_j.0, z_j.1));
    let eval = |w: Unit| {
        let (c, s) = w;
        let ji = sup_i(cmul(w, zi_bar));
        let jj = sup_j(cmul(w, zj_bar_neg));
        let along = r_ij[0] * c + r_ij[1] * s;
        let g = along - ji.h - jj.h;
        let g1 = -r_ij[0] * s + r_ij[1] * c - ji.d1 - jj.d1;
        let g2 = -along - ji.d2 - jj.d2;
        (g, g1, g2, ji, jj)
    };
    let mut w = w0;
    let mut cur = eval(w);
    let mut converged = false;
    let mut iterations = 0;
    while iterations < 60 {
        iterations += 1;
        let (g, g1, g2, _, _) = cur;
        let mut step = if g2 < 0.0 {
            -g1 / g2
        } else {
            0.1 * g1.signum()
        };
        step = step.clamp(-0.3, 0.3);
        if g2 < 0.0 && step.abs() < 1e-3 {
            w = turn_unit(w, step);
            cur = eval(w);
            if step.abs() < 1e-7 {
                converged = true;
                break;
            }
            continue;
        }
        let mut next_w = turn_unit(w, step);
        let mut next = eval(next_w);
        let mut halvings = 0;
        while next.0 < g && halvings < 40 {
            step *= 0.5;
            next_w = turn_unit(w, step);
            next = eval(next_w);
            halvings += 1;
        }
        if next.0 < g {
            // No ascent along this direction at round-off level: ψ is the
            // maximum to machine precision.
            converged = true;
            break;
        }
        w = next_w;
        cur = next;
    }
    let (g, _, _, jet_i, jet_j) = cur;
    ExactGap {
        normal: w,
        gap: g,
        jet_i,
        jet_j,
        iterations,
        converged,
    }
}

/// `z e^{iθ}` for a Newton step `θ` of any length up to about 1 rad, with
/// no trigonometric call: below 10⁻² rad `e^{iθ}` by its Taylor series to
/// `θ⁸` (exact in double precision), else `e^{iθ/8}` by its series to
/// `(θ/8)¹⁰` (truncation below 10⁻¹⁷ for |θ| ≤ 1) squared three times;
/// the coefficients are multiplied rather than divided (no division on the
/// iteration's critical path), and the result is renormalised (a few ulps).
#[inline(always)]
pub fn turn_step(z: Unit, theta: f64) -> Unit {
    let e = if theta.abs() < 1e-2 {
        small_turn(theta)
    } else {
        large_turn(theta)
    };
    renormalised(z, e)
}

/// [`turn_step`] with both branches computed and one chosen: the same
/// bits, with no branch (for many turns side by side).
#[inline(always)]
pub(crate) fn turn_select(z: Unit, theta: f64) -> Unit {
    let (small, large) = (small_turn(theta), large_turn(theta));
    let e = if theta.abs() < 1e-2 { small } else { large };
    renormalised(z, e)
}

/// `e^{iθ}` as `e^{iθ/8}` by its series to `(θ/8)¹⁰` squared three
/// times, [`turn_step`]'s branch from 10⁻² rad on.
#[inline(always)]
fn large_turn(theta: f64) -> Unit {
    let x = 0.125 * theta;
    let x2 = x * x;
    let s = x
        * (1.0
            - x2 * (1.0 / 6.0)
                * (1.0
                    - x2 * (1.0 / 20.0) * (1.0 - x2 * (1.0 / 42.0) * (1.0 - x2 * (1.0 / 72.0)))));
    let c = 1.0
        - x2 * 0.5
            * (1.0
                - x2 * (1.0 / 12.0)
                    * (1.0
                        - x2 * (1.0 / 30.0)
                            * (1.0 - x2 * (1.0 / 56.0) * (1.0 - x2 * (1.0 / 90.0)))));
    let mut e = (c, s);
    for _ in 0..3 {
        e = cmul(e, e);
    }
    e
}

/// `e^{iθ}` by its Taylor series to `θ⁸`, [`turn_step`]'s branch below
/// 10⁻² rad.
#[inline(always)]
fn small_turn(theta: f64) -> Unit {
    let x2 = theta * theta;
    let s =
        theta * (1.0 - x2 * (1.0 / 6.0) * (1.0 - x2 * (1.0 / 20.0) * (1.0 - x2 * (1.0 / 42.0))));
    let c = 1.0
        - x2 * 0.5
            * (1.0 - x2 * (1.0 / 12.0) * (1.0 - x2 * (1.0 / 30.0) * (1.0 - x2 * (1.0 / 56.0))));
    (c, s)
}

/// `z e`, renormalised to the unit circle by one Newton step ([`turn_step`]).
#[inline(always)]
fn renormalised(z: Unit, e: Unit) -> Unit {
    let (c, s) = cmul(z, e);
    let fix = 1.5 - 0.5 * (c * c + s * s);
    (c * fix, s * fix)
}

/// One body's part of a step of [`exact_joint`] at its support-point
/// guess `p = e^{iφ}` for the body-frame direction `e^{iβ}` (module
/// documentation, "The joint iteration").
#[derive(Clone, Copy, Debug)]
struct JointBody {
    /// `h(φ, β) = R cos δ`, the height of the boundary point along `β`.
    h: f64,
    /// `∂h/∂β = R sin δ`.
    h_beta: f64,
    /// The support condition `q = R sin δ − R' cos δ = −∂h/∂φ`.
    q: f64,
    /// `q_φ = 2R' sin δ + (R − R'') cos δ > 0` on a convex outline.
    q_phi: f64,
    /// `m = −∂q/∂β = R cos δ + R' sin δ`.
    m: f64,
    /// `(R, R', R'', R‴)` at the support-point guess.
    outline: (f64, f64, f64, f64),
    /// `e^{iδ} = p e^{−iβ}`.
    d: Unit,
}

impl JointBody {
    /// `(∂²q/∂φ∂β, ∂²q/∂φ², ∂²h_β/∂φ²)`, for [`exact_joint`]'s last step:
    /// `(R − R'') sin δ − 2R' cos δ`, `(3R'' − R) sin δ + (3R' − R‴) cos δ`
    /// and `(R'' − R) sin δ + 2R' cos δ` (the other second derivatives are
    /// `∂²q/∂β² = −q`, `∂²h_β/∂φ∂β = q`, `∂²h_β/∂β² = −h_β`).
    #[inline(always)]
    fn second(&self) -> (f64, f64, f64) {
        let ((r, r1, r2, r3), (c, s)) = (self.outline, self.d);
        (
            (r - r2) * s - 2.0 * r1 * c,
            (3.0 * r2 - r) * s + (3.0 * r1 - r3) * c,
            (r2 - r) * s + 2.0 * r1 * c,
        )
    }
}

#[inline(always)]
fn joint_body<F: Fn(Unit) -> (f64, f64, f64, f64)>(
    e_beta: Unit,
    p: Unit,
    outline: &F,
) -> JointBody {
    let (r, r1, r2, r3) = outline(p);
    let d = cmul(p, (e_beta.0, -e_beta.1));
    JointBody {
        h: r * d.0,
        h_beta: r * d.1,
        q: r * d.1 - r1 * d.0,
        q_phi: 2.0 * r1 * d.1 + (r - r2) * d.0,
        m: r * d.0 + r1 * d.1,
        outline: (r, r1, r2, r3),
        d,
    }
}

/// The support jet at the support point `p = e^{iφ}` for the direction
/// `e^{iβ}` ([`polar_support_unit`]'s formulas, without its search).
#[inline(always)]
fn jet_at<F: Fn(Unit) -> (f64, f64, f64, f64)>(e_beta: Unit, p: Unit, outline: &F) -> SupportJet {
    let (r, r1, r2, _) = outline(p);
    let d = cmul(p, (e_beta.0, -e_beta.1));
    let q = r * r + r1 * r1;
    let k = r * r + 2.0 * r1 * r1 - r * r2;
    let h = r * d.0;
    SupportJet {
        h,
        d1: r * d.1,
        d2: q * q.sqrt() / k - h,
    }
}

static JOINT_FALLBACKS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// How many times a caller of [`exact_joint`] fell back to the nested solve
/// in this process (all threads; counted by [`count_joint_fallback`]): a
/// diagnostic, for tests and benchmarks.
pub fn joint_fallbacks() -> u64 {
    JOINT_FALLBACKS.load(std::sync::atomic::Ordering::Relaxed)
}

/// Count one fall-back from [`exact_joint`] to the nested solve.
#[cold]
pub fn count_joint_fallback() {
    JOINT_FALLBACKS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
}

/// The iteration cap of [`exact_joint`] (it converges in 3–5 steps from the
/// line of centres where it converges at all).
const JOINT_CAP: u32 = 30;

/// The longest step [`exact_joint`] takes (rad) before it hands over to the
/// nested solve.
const JOINT_MAX_STEP: f64 = 0.3;

/// [`exact_joint`] has converged after a step below this on all three
/// angles (rad): the error left, `~C·10⁻¹⁶` with `C = O(n³Δ)` (quadratic
/// convergence), is round-off, whatever the start.
pub const JOINT_TOLERANCE: f64 = 1e-8;

/// Without `second`, [`exact_joint`] ends after a step below this (rad)
/// with the second-order correction of that step: what is left is
/// `~C²s³ ≲ C²·10⁻¹⁸` rad (cubic), round-off.
pub const JOINT_FINISH: f64 = 1e-5;

/// The exact gap of two convex bodies given by their body-frame polar
/// outlines `outline(e^{iφ}) = (R, R', R'')` (sizes included), by one
/// Newton iteration on the normal and both support points at once (module
/// documentation, "The joint iteration"), from the normal `w0` and the
/// support points `p_i`, `p_j` (`e^{iβ}` of each body's direction where no
/// better guess is known). `z_i`, `z_j` as in [`exact_unit`].
///
/// `None` where the iteration fails (`q_φ ≤ 0` or `k ≤ 0` at an iterate, a
/// step longer than 0.3 rad or than the one before, or 30 steps): the
/// caller then runs the nested solve, [`exact_unit`] on
/// [`polar_support_unit`] supports. With `second`: converged after a step
/// below [`JOINT_TOLERANCE`] on the normal and both support points (what
/// is left is round-off, `~C·10⁻¹⁶` rad in each angle; module
/// documentation), from any start, and the jets are those at the final
/// point. Without: ended after a step below [`JOINT_FINISH`] corrected to
/// second order, with `H` and `H'` moved along it to second order (module
/// documentation, round-off left, no outline evaluation), and `H''` NaN
/// (the contacts need `H` and `H'` alone). The outlines give
/// `(R, R', R'', R‴)` (`R‴` is read only without `second`).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn exact_joint<F: Fn(Unit) -> (f64, f64, f64, f64), G: Fn(Unit) -> (f64, f64, f64, f64)>(
    r_ij: &Vector<2>,
    w0: Unit,
    z_i: Unit,
    p_i: Unit,
    outline_i: F,
    z_j: Unit,
    p_j: Unit,
    outline_j: G,
    second: bool,
) -> Option<ExactGap> {
    let (zi_bar, zj_bar_neg) = ((z_i.0, -z_i.1), (-z_j.0, z_j.1));
    let (mut w, mut pi, mut pj) = (w0, p_i, p_j);
    let mut last = f64::INFINITY;
    let mut iterations = 0;
    loop {
        if iterations == JOINT_CAP {
            return None;
        }
        iterations += 1;
        let (ei, ej) = (cmul(w, zi_bar), cmul(w, zj_bar_neg));
        let bi = joint_body(ei, pi, &outline_i);
        let bj = joint_body(ej, pj, &outline_j);
        if !(bi.q_phi > 0.0 && bj.q_phi > 0.0) {
            return None;
        }
        let (inv_i, inv_j) = (1.0 / bi.q_phi, 1.0 / bj.q_phi);
        let (ai, aj) = (bi.m * inv_i, bj.m * inv_j);
        let along = r_ij[0] * w.0 + r_ij[1] * w.1;
        let l_psi = -r_ij[0] * w.1 + r_ij[1] * w.0 - bi.h_beta - bj.h_beta;
        let k = along - bi.h - bj.h + ai * bi.m + aj * bj.m;
        if !(k > 0.0) {
            return None;
        }
        let dpsi = (l_psi + ai * bi.q + aj * bj.q) / k;
        let dphi_i = ai * dpsi - bi.q * inv_i;
        let dphi_j = aj * dpsi - bj.q * inv_j;
        let len = dpsi.abs().max(dphi_i.abs()).max(dphi_j.abs());
        // No progress: a Newton step that does not shrink (it shrinks
        // quadratically near the optimum).
        // A step beyond 0.3 rad: far from the optimum, where a saddle
        // iteration can run to another stationary point of `g`; the nested
        // solve's ascent is safe there.
        if !len.is_finite() || len > last || len > JOINT_MAX_STEP {
            return None;
        }
        if !second && len < JOINT_FINISH {
            let step = [dpsi, dphi_i, dphi_j];
            return Some(
                finish(
                    r_ij,
                    w,
                    [&bi, &bj],
                    [ai, aj],
                    k,
                    step,
                    iterations,
                    turn_step,
                )
                .0,
            );
        }
        w = turn_step(w, dpsi);
        pi = turn_step(pi, dphi_i);
        pj = turn_step(pj, dphi_j);
        if len < JOINT_TOLERANCE {
            let (jet_i, jet_j) = if second {
                let (ei, ej) = (cmul(w, zi_bar), cmul(w, zj_bar_neg));
                (jet_at(ei, pi, &outline_i), jet_at(ej, pj, &outline_j))
            } else {
                // H = h(φ, β) and H' = ∂h/∂β moved along the last step to
                // first order (∂h/∂φ = −q, ∂h/∂β = h_β, ∂h_β/∂φ = m,
                // ∂h_β/∂β = −h): the step is below 10⁻⁸ rad, so what is
                // left, O(step²), is round-off.
                let moved = |b: &JointBody, dphi: f64| SupportJet {
                    h: b.h - b.q * dphi + b.h_beta * dpsi,
                    d1: b.h_beta + b.m * dphi - b.h * dpsi,
                    d2: f64::NAN,
                };
                (moved(&bi, dphi_i), moved(&bj, dphi_j))
            };
            return Some(ExactGap {
                normal: w,
                gap: r_ij[0] * w.0 + r_ij[1] * w.1 - jet_i.h - jet_j.h,
                jet_i,
                jet_j,
                iterations,
                converged: true,
            });
        }
        last = len;
    }
}

/// The last step of [`exact_joint`] without `second`, from the bodies
/// `b` at the normal `w`, after its Newton step `δ₁ = (δψ, δφ_i, δφ_j)`
/// below [`JOINT_FINISH`]: the step corrected to second order (Chebyshev),
/// `δ = δ₁ + δ₂` with `J δ₂ = −½ F''[δ₁, δ₁]` (`F` the three stationarity
/// conditions, `J` their Jacobian, eliminated as for `δ₁`: `a_k = m_k/q_φk`,
/// `k`), which leaves `~C²|δ₁|³` rad; then the normal turned by `δψ`, and
/// `H = h` and `H' = h_β` of each body moved along `δ` to second order
/// (their derivatives in `φ` and `β` from `R … R‴`; what is left,
/// `O(|δ|³)`, is round-off). No outline evaluation; `H''` is NaN. The
/// normal turns by `turn` ([`turn_step`]); the turn's angle is returned
/// with the result.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn finish(
    r_ij: &Vector<2>,
    w: Unit,
    b: [&JointBody; 2],
    a: [f64; 2],
    k: f64,
    [dpsi, dphi_i, dphi_j]: [f64; 3],
    iterations: u32,
    turn: impl Fn(Unit, f64) -> Unit,
) -> (ExactGap, f64) {
    let dphi = [dphi_i, dphi_j];
    let rt = -r_ij[0] * w.1 + r_ij[1] * w.0;
    // ½ F''[δ₁, δ₁]: ψ's condition `r·e'(ψ) − Σ h_β`, each body's `q`.
    let mut half = [0.0; 3];
    half[0] = -0.5 * rt * dpsi * dpsi;
    let mut seconds = [(0.0, 0.0, 0.0); 2];
    for s in 0..2 {
        let (q_pb, q_pp, hb_pp) = b[s].second();
        seconds[s] = (q_pb, q_pp, hb_pp);
        let (x, y) = (dpsi, dphi[s]);
        half[0] -= 0.5 * (-b[s].h_beta * x * x + 2.0 * b[s].q * x * y + hb_pp * y * y);
        half[1 + s] = 0.5 * (-b[s].q * x * x + 2.0 * q_pb * x * y + q_pp * y * y);
    }
    let dpsi2 = (half[0] + a[0] * half[1] + a[1] * half[2]) / k;
    let step = [
        dpsi + dpsi2,
        dphi_i + (a[0] * dpsi2 - half[1] / b[0].q_phi),
        dphi_j + (a[1] * dpsi2 - half[2] / b[1].q_phi),
    ];
    let normal = turn(w, step[0]);
    let x = step[0];
    let moved = |s: usize| {
        let (bs, y, hb_pp) = (b[s], step[1 + s], seconds[s].2);
        SupportJet {
            h: bs.h - bs.q * y
                + bs.h_beta * x
                + 0.5 * (-bs.q_phi * y * y + 2.0 * bs.m * x * y - bs.h * x * x),
            d1: bs.h_beta + bs.m * y - bs.h * x
                + 0.5 * (hb_pp * y * y + 2.0 * bs.q * x * y - bs.h_beta * x * x),
            d2: f64::NAN,
        }
    };
    let (jet_i, jet_j) = (moved(0), moved(1));
    let e = ExactGap {
        normal,
        gap: r_ij[0] * normal.0 + r_ij[1] * normal.1 - jet_i.h - jet_j.h,
        jet_i,
        jet_j,
        iterations,
        converged: true,
    };
    (e, x)
}

/// One step of [`exact_joint`] without `second` from the normal `w` and
/// the support points `p_i`, `p_j`, after a step of length `last` (∞ for
/// the first), with no branch (for many pairs side by side,
/// [`crate::profiled::Profiled`]'s warm lanes).
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointStep {
    /// The result of [`exact_joint`]'s finish after this step (arbitrary
    /// unless `finished`).
    pub gap: ExactGap,
    /// [`exact_joint`] returns `gap` after this step, bit for bit: its
    /// safeguards pass, the step is below [`JOINT_FINISH`], and the
    /// normal turns by less than 10⁻² ([`turn_step`]'s Taylor branch).
    pub finished: bool,
    /// [`exact_joint`] takes this step and goes on: its safeguards pass,
    /// and the step is not below [`JOINT_FINISH`].
    pub go_on: bool,
    /// The Newton step on the normal and the two support points.
    pub step: [f64; 3],
    /// Its length (the largest of the three).
    pub len: f64,
}

/// [`JointStep`] (the same operations in the same order as
/// [`exact_joint`]'s step).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn joint_step<
    F: Fn(Unit) -> (f64, f64, f64, f64),
    G: Fn(Unit) -> (f64, f64, f64, f64),
>(
    r_ij: &Vector<2>,
    w: Unit,
    z_i: Unit,
    p_i: Unit,
    outline_i: F,
    z_j: Unit,
    p_j: Unit,
    outline_j: G,
    last: f64,
) -> JointStep {
    let (zi_bar, zj_bar_neg) = ((z_i.0, -z_i.1), (-z_j.0, z_j.1));
    let (ei, ej) = (cmul(w, zi_bar), cmul(w, zj_bar_neg));
    let bi = joint_body(ei, p_i, &outline_i);
    let bj = joint_body(ej, p_j, &outline_j);
    let (inv_i, inv_j) = (1.0 / bi.q_phi, 1.0 / bj.q_phi);
    let (ai, aj) = (bi.m * inv_i, bj.m * inv_j);
    let along = r_ij[0] * w.0 + r_ij[1] * w.1;
    let l_psi = -r_ij[0] * w.1 + r_ij[1] * w.0 - bi.h_beta - bj.h_beta;
    let k = along - bi.h - bj.h + ai * bi.m + aj * bj.m;
    let dpsi = (l_psi + ai * bi.q + aj * bj.q) / k;
    let dphi_i = ai * dpsi - bi.q * inv_i;
    let dphi_j = aj * dpsi - bj.q * inv_j;
    let len = dpsi.abs().max(dphi_i.abs()).max(dphi_j.abs());
    let step = [dpsi, dphi_i, dphi_j];
    let (gap, turn) = finish(r_ij, w, [&bi, &bj], [ai, aj], k, step, 1, |z, t| {
        renormalised(z, small_turn(t))
    });
    let safe = (bi.q_phi > 0.0)
        & (bj.q_phi > 0.0)
        & (k > 0.0)
        & len.is_finite()
        & !(len > last)
        & !(len > JOINT_MAX_STEP);
    let below = len < JOINT_FINISH;
    JointStep {
        gap,
        finished: safe & below & (turn.abs() < 1e-2),
        go_on: safe & !below,
        step,
        len,
    }
}

impl ExactGap {
    /// The contact: `∂h/∂r_j = n`, `∂h/∂θ = H'`.
    pub fn contact(&self) -> Contact<2> {
        let (c, s) = self.normal;
        Contact {
            gap: self.gap,
            grad_r: Vector::<2>::new(c, s),
            grad_rot_i: [self.jet_i.d1, 0.0, 0.0],
            grad_rot_j: [self.jet_j.d1, 0.0, 0.0],
        }
    }

    /// The gap with its second derivatives (module documentation).
    pub fn hessian(&self) -> GapHessian<2> {
        let (c, s) = self.normal;
        let nt = Vector::<2>::new(-s, c);
        let (hi, hj) = (self.jet_i.d2, self.jet_j.d2);
        let k = self.gap + self.jet_i.h + hi + self.jet_j.h + hj;
        // NOTE: k = h + ρ_i + ρ_j > 0 unless the bodies overlap by more
        // than the sum of their curvature radii; guard the division.
        let inv_k = if k > 0.0 { 1.0 / k } else { 0.0 };
        let contact = self.contact();
        let mut g =
            GapHessian::translational(self.gap, contact.grad_r, nt * nt.transpose() * inv_k);
        g.contact = contact;
        g.r_qi[0] = nt * (hi * inv_k);
        g.r_qj[0] = nt * (hj * inv_k);
        g.qi_qi[0][0] = -hi + hi * hi * inv_k;
        g.qj_qj[0][0] = -hj + hj * hj * inv_k;
        g.qi_qj[0][0] = hi * hj * inv_k;
        g
    }

    /// [`ExactGap::hessian`] for a stationary point of either kind: `k` of
    /// either sign (a contact of a concave arc, `crate::arcs`, has `k < 0`),
    /// and `H''` large near an inflection point, where
    /// `−H_i'' + H_i''²/k` is written `−H_i'' (h + H_i + ρ_j)/k` (no
    /// cancellation). Zero second derivatives at `k = 0`.
    pub fn hessian_signed(&self) -> GapHessian<2> {
        let (c, s) = self.normal;
        let nt = Vector::<2>::new(-s, c);
        let (hi, hj) = (self.jet_i.d2, self.jet_j.d2);
        let (rho_i, rho_j) = (self.jet_i.h + hi, self.jet_j.h + hj);
        let k = self.gap + rho_i + rho_j;
        let inv_k = if k != 0.0 && k.is_finite() {
            1.0 / k
        } else {
            0.0
        };
        let contact = self.contact();
        let mut g =
            GapHessian::translational(self.gap, contact.grad_r, nt * nt.transpose() * inv_k);
        g.contact = contact;
        g.r_qi[0] = nt * (hi * inv_k);
        g.r_qj[0] = nt * (hj * inv_k);
        g.qi_qi[0][0] = -hi * (self.gap + self.jet_i.h + rho_j) * inv_k;
        g.qj_qj[0][0] = -hj * (self.gap + self.jet_j.h + rho_i) * inv_k;
        g.qi_qj[0][0] = hi * hj * inv_k;
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn ellipse(a: f64, b: f64) -> impl Fn(f64) -> SupportJet {
        move |beta: f64| {
            let (s, c) = beta.sin_cos();
            let q = a * a * c * c + b * b * s * s;
            let h = q.sqrt();
            let dq = 2.0 * (b * b - a * a) * s * c;
            let ddq = 2.0 * (b * b - a * a) * (c * c - s * s);
            SupportJet {
                h,
                d1: dq / (2.0 * h),
                d2: ddq / (2.0 * h) - dq * dq / (4.0 * h * q),
            }
        }
    }

    /// Two disks: h = r − R_i − R_j exactly, normal along the line of centres.
    #[test]
    fn disks_give_the_disk_gap() {
        let disk = |r: f64| {
            move |_b: f64| SupportJet {
                h: r,
                d1: 0.0,
                d2: 0.0,
            }
        };
        let d = Vector::<2>::new(0.9, -0.7);
        let e = exact(&d, 0.3, disk(0.5), -1.0, disk(0.7));
        assert!(e.converged);
        assert_relative_eq!(e.gap, d.norm() - 1.2, epsilon = 1e-15);
    }

    /// Two ellipses side by side, long axes parallel to the line of
    /// centres: h = r − 2a; perpendicular: r − 2b; one of each: r − a − b.
    #[test]
    fn aligned_ellipses() {
        let (a, b) = (0.8, 0.4);
        let d = Vector::<2>::new(1.7, 0.0);
        let g = |ti: f64, tj: f64| exact(&d, ti, ellipse(a, b), tj, ellipse(a, b)).gap;
        let half = std::f64::consts::FRAC_PI_2;
        assert_relative_eq!(g(0.0, 0.0), 1.7 - 2.0 * a, epsilon = 1e-14);
        assert_relative_eq!(g(half, half), 1.7 - 2.0 * b, epsilon = 1e-14);
        assert_relative_eq!(g(0.0, half), 1.7 - a - b, epsilon = 1e-14);
    }

    /// The polar support of an ellipse `R(φ) = ab/√(b²cos²φ + a²sin²φ)`
    /// equals its closed-form support function (the inner Newton converges
    /// to round-off; 1e-12 on values of order 1).
    #[test]
    fn polar_support_of_an_ellipse() {
        let (a, b) = (0.9, 0.6);
        let outline = |phi: f64| {
            let (s, c) = phi.sin_cos();
            ellipse_outline(a, b)((c, s))
        };
        let exact_support = ellipse(a, b);
        for k in 0..24 {
            let beta = -3.1 + 0.27 * k as f64;
            let p = polar_support(beta, outline);
            let e = exact_support(beta);
            assert_relative_eq!(p.h, e.h, epsilon = 1e-12);
            assert_relative_eq!(p.d1, e.d1, epsilon = 1e-12);
            assert_relative_eq!(p.d2, e.d2, epsilon = 1e-10);
        }
    }

    /// The polar outline of an ellipse `R(φ) = ab/√(b²cos²φ + a²sin²φ)`
    /// at `p = e^{iφ}`, with `R'` and `R''`.
    fn ellipse_outline(a: f64, b: f64) -> impl Fn(Unit) -> (f64, f64, f64) + Copy {
        move |(c, s): Unit| {
            let q = b * b * c * c + a * a * s * s;
            let q1 = 2.0 * (a * a - b * b) * s * c;
            let q2 = 2.0 * (a * a - b * b) * (c * c - s * s);
            let r = a * b / q.sqrt();
            let r1 = -0.5 * r * q1 / q;
            let r2 = -0.5 * (r1 * q1 + r * q2) / q + 0.5 * r * q1 * q1 / (q * q);
            (r, r1, r2)
        }
    }

    /// `turn_step` is the turn by the angle to round-off (2e-15 on unit
    /// vectors; `unit_of_angle` itself is good to ~1 ulp) and stays on the
    /// unit circle, on both of its branches.
    #[test]
    fn turn_step_turns_by_the_angle() {
        let z = unit_of_angle(0.7);
        for k in 0..41 {
            let t = -1.0 + 0.05 * k as f64 + 1e-3;
            let (a, b) = (turn_step(z, t), unit_of_angle(0.7 + t));
            assert!(
                (a.0 - b.0).abs() < 2e-15 && (a.1 - b.1).abs() < 2e-15,
                "{t}"
            );
            assert!((a.0 * a.0 + a.1 * a.1 - 1.0).abs() < 1e-15);
        }
    }

    /// The joint iteration agrees with the nested solve on ellipses of
    /// aspect ratio up to 2 at random orientations and separations (from
    /// apart to overlapping by a tenth of the size): both stop within
    /// ~1e-14 rad of the optimum, so gaps agree to a few ulps (1e-14) and
    /// normals and `H'` to 1e-12 (round-off of the Newton steps scaled by
    /// `1/k`); `H''` to 1e-10 (it divides by the curvature numerator).
    #[test]
    fn joint_iteration_agrees_with_the_nested_solve() {
        let mut rnd = crate::uniform(7);
        let mut joint_steps = 0;
        for _ in 0..400 {
            let (ai, aj) = (1.0 + rnd(), 1.0 + rnd());
            let (si, sj) = (0.5 + 0.3 * rnd(), 0.5 + 0.3 * rnd());
            let (oi, oj) = (
                ellipse_outline(si * ai.sqrt(), si / ai.sqrt()),
                ellipse_outline(sj * aj.sqrt(), sj / aj.sqrt()),
            );
            let (ti, tj, a) = (6.3 * rnd(), 6.3 * rnd(), 6.3 * rnd());
            let d = Vector::<2>::new(a.cos(), a.sin()) * ((si + sj) * (0.9 + 0.4 * rnd()));
            let (zi, zj) = (unit_of_angle(ti), unit_of_angle(tj));
            let w0 = (a.cos(), a.sin());
            let nested = exact_unit(
                &d,
                w0,
                zi,
                |e: Unit| polar_support_unit(e, e, oi).0,
                zj,
                |e: Unit| polar_support_unit(e, e, oj).0,
            );
            // Support points searched at the line of centres.
            let (ei, ej) = (cmul(w0, (zi.0, -zi.1)), cmul(w0, (-zj.0, zj.1)));
            let (pi, pj) = (
                polar_support_unit(ei, ei, oi).1.p,
                polar_support_unit(ej, ej, oj).1.p,
            );
            // R‴ is not read with `second` (the jets at the final point).
            let (oi4, oj4) = (
                |p: Unit| {
                    let (r, r1, r2) = oi(p);
                    (r, r1, r2, f64::NAN)
                },
                |p: Unit| {
                    let (r, r1, r2) = oj(p);
                    (r, r1, r2, f64::NAN)
                },
            );
            let Some(joint) = exact_joint(&d, w0, zi, pi, oi4, zj, pj, oj4, true) else {
                continue;
            };
            joint_steps += 1;
            assert!(nested.converged);
            assert_relative_eq!(joint.gap, nested.gap, epsilon = 1e-14);
            assert_relative_eq!(joint.normal.0, nested.normal.0, epsilon = 1e-12);
            assert_relative_eq!(joint.normal.1, nested.normal.1, epsilon = 1e-12);
            assert_relative_eq!(joint.jet_i.d1, nested.jet_i.d1, epsilon = 1e-12);
            assert_relative_eq!(joint.jet_j.d1, nested.jet_j.d1, epsilon = 1e-12);
            assert_relative_eq!(joint.jet_i.d2, nested.jet_i.d2, epsilon = 1e-10);
            assert_relative_eq!(joint.jet_j.d2, nested.jet_j.d2, epsilon = 1e-10);
        }
        // From the line of centres on ellipses up to α = 2 (normals up to
        // ~0.5 rad away) it hands over to the nested solve on about 30 %
        // of these pairs (a first step beyond 0.3 rad), not on most; near
        // contact of near-disks it starts much closer (`Profiled`).
        assert!(joint_steps > 240, "{joint_steps} of 400 converged");
    }

    /// The chain rule reproduces the first-order gap's own derivatives.
    #[test]
    fn chain_rule_matches_first_order() {
        use crate::first_order::{Profile, gap_hessian};
        let (delta, ri, rj) = (0.2, 0.5, 0.7);
        let (n, ai, aj) = (3.0f64, 0.4f64, -1.3f64);
        let f = |a: f64| {
            [
                (n * a).sin() / n,
                (n * a).cos(),
                -n * (n * a).sin(),
                -n * n * (n * a).cos(),
            ]
        };
        let d = Vector::<2>::new(1.1, 0.4);
        let r = d.norm();
        let (pi, pj) = (f(ai), f(aj));
        let p = Partials {
            h: r - ri - rj - delta * (ri * pi[0] + rj * pj[0]),
            h_r: 1.0,
            h_a: [-delta * ri * pi[1], -delta * rj * pj[1]],
            h_rr: 0.0,
            h_ra: [0.0, 0.0],
            h_aa: [[-delta * ri * pi[2], 0.0], [0.0, -delta * rj * pj[2]]],
        };
        let prof = |x: [f64; 4]| Profile {
            value: x[0],
            slope: x[1],
            curvature: x[2],
        };
        let a = p.chain(&d);
        let b = gap_hessian(&d, ri, rj, delta, prof(pi), prof(pj));
        assert_relative_eq!(a.rr, b.rr, epsilon = 1e-14);
        assert_relative_eq!(a.contact.grad_r, b.contact.grad_r, epsilon = 1e-14);
        assert_relative_eq!(a.r_qi[0], b.r_qi[0], epsilon = 1e-14);
        assert_relative_eq!(a.r_qj[0], b.r_qj[0], epsilon = 1e-14);
    }
}
