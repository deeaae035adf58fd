//! The **exact gap of two convex bodies in 3D** from their support
//! functions: the 3D counterpart of `jamkit_planar::gap2d::exact`, shared
//! by the 3D families with an exact gap (`ellipsoid`; any smooth convex
//! body whose support function is known, e.g. an exact gap for `harmonic`).
//!
//! ## The gap
//!
//! A convex body with centre `c` is described by its support function
//! `s(u) = max_{x ∈ body} u·(x − c)`, extended to all of `ℝ³` as a function
//! positively homogeneous of degree 1 (`s(λx) = λ s(x)`). Its gradient
//! `p(u) = ∇s(u)` is the *support point*, the boundary point (relative to
//! the centre) whose outward normal is `u`, and `S(u) = ∇∇s(u)` is the
//! matrix of the radii of curvature there (`S u = 0`; on the tangent plane
//! its eigenvalues are the principal radii of curvature). The
//! separating-axis theorem makes the signed distance of two convex bodies
//! at separation `r = r_j − r_i`
//!
//! ```text
//! h = max_{|u| = 1} g(u),     g(u) = u·r − s_i(u) − s_j(−u):
//! ```
//!
//! positive, the distance of the two surfaces; negative, minus the depth
//! of penetration along the common normal `n = u*` (the shortest
//! translation of body `j` along `n` that separates the bodies is `−h`).
//! At the optimum `r − p_i(n) + p_j(−n) = h n`: the support points of the
//! two bodies face each other along `n`.
//!
//! ## Finding the normal
//!
//! Write `G(x) = x·r − s_i(x) − s_j(−x)`, homogeneous of degree 1, so that
//! `u·∇G(u) = g(u)` (Euler). On the unit sphere its Riemannian gradient and
//! Hessian are
//!
//! ```text
//! t = ∇G − g u = r − p_i(u) + p_j(−u) − g u,
//! K = −(S_i(u) + S_j(−u) + g P),      P = 1 − u uᵀ,
//! ```
//!
//! and `W = −K = S_i + S_j + g P` is positive definite on the tangent plane
//! at a non-degenerate maximum (in 2D it is the number
//! `k = h + ρ_i + ρ_j` of `gap2d`). [`exact`] runs a safeguarded Newton
//! iteration from the line of centres: the Newton step solves `W δ = t` in
//! the tangent plane (as `(W + u uᵀ) δ = t`, one 3 × 3 Cholesky
//! factorisation: `W u = 0` and `t ⊥ u`), taken where `W` is positive
//! definite, else a gradient step of 0.1 along `t`; steps are capped at
//! 0.3, applied on the sphere as `u → (u + δ)/|u + δ|`, and halved
//! until `g` does not decrease, except Newton steps below 10⁻⁶ rad, which
//! are taken as they are (there the gain in `g`, `~|t||δ|/2`, is lost in
//! round-off and the descent test would only halve a correct step).
//! Converged after a Newton step below 10⁻⁷ (as `gap2d`): what is left,
//! `~C·10⁻¹⁴` with `C = O(1)` the ratio of third to second derivatives of
//! `g`, moves `h` by `~10⁻²⁸` (`g` is stationary) and the normal by
//! `~10⁻¹⁴`. Since `h ≥ g(r̂)`, a pair whose `g` at the line of
//! centres already exceeds `max_gap` is skipped after one evaluation.
//!
//! NOTE: for *overlapping* bodies the iteration finds the local maximum of
//! `g` nearest the line of centres. For the overlaps of a jamming run
//! (`|h|` far below the radii of curvature) `g` has one maximum; two long
//! bodies crossed at their centres can have several.
//!
//! ## Derivatives
//!
//! `h` depends on `r_j` only through `r`, so by the envelope theorem
//! `∂h/∂r_j = n`. A body's rotational coordinates `ω_p` turn it about the
//! axes `e_p` (`Q → exp(Σ ω_p e_p) Q`, with `e_p` the world axes, or the
//! body's own axes `Q x̂, Q ŷ` for a body symmetric about its `z` axis: the
//! same rotation at zero increment). Turning body `i` by `ω` reads its
//! support function at `exp(−ω) u`, so with `p_i = p_i(n)`, `p_j = p_j(−n)`
//!
//! ```text
//! ∂h/∂ω_ip = e_p · (n × p_i),      ∂h/∂ω_jp = −e_p · (n × p_j),
//! ```
//!
//! the torques of the contact force about each centre. The second
//! derivatives follow by differentiating the optimum implicitly: with
//! `θ` any of the coordinates, `G_θ` the derivative of `g` at fixed `u`,
//! `b_θ = ∂_θ ∇G` at fixed `u`, and `W⁺` the inverse of `W` on the
//! tangent plane (`W⁺ = (W + n nᵀ)⁻¹ − n nᵀ`),
//!
//! ```text
//! ∂²h/∂θ∂θ' = G_θθ' + b_θᵀ W⁺ b_θ',
//! b_r = 1 (so ∂²h/∂r_j² = W⁺),
//! b_ωip = −e_p × p_i + S_i (e_p × n),     b_ωjp = e_p × p_j + S_j (e_p × n),
//! G_ωω(body, v = ±n) = −[(e_p × v)ᵀ S (e_q × v) + ½((p·e_q)(e_p·v) + (p·e_p)(e_q·v)) − (p·v)(e_p·e_q)],
//! ```
//!
//! with `v = n` for body `i`, `v = −n` for body `j`, and `G_rω = 0`,
//! `G_ω_iω_j = 0` (the two bodies mix only through the moving normal).
//! Where `W` is not positive definite (bodies overlapping by more than
//! their radii of curvature: never in a jamming run) the `W⁺` terms are
//! dropped, as `gap2d` does with `1/k`.
//!
//! ## The support function of a star-shaped surface
//!
//! A body whose surface is `x(y) = ρ(y) y` over the unit sphere (body
//! frame, `ρ > 0`: star-shaped about its centre), like the `harmonic`
//! family's `ρ = R⁰(1 + ΔF)`, has no closed-form support function;
//! [`radial_support`] finds it. Write `ρ̃(x) = ρ(x/|x|)` (constant along
//! rays) with `g = ∇ρ̃` (tangent to the sphere) and `H = ∇∇ρ̃` at the unit
//! vector `y`, `P = 1 − y yᵀ`, `c = u·y`. For a direction `u` the support
//! point maximises the height `φ(y) = u·x(y) = ρ(y) c` over the sphere; its
//! Riemannian gradient and Hessian (the derivatives of the degree-0
//! extension `ρ̃(x) u·x/|x|`, tangential block) are
//!
//! ```text
//! t = c g + ρ P u,
//! ∇_S∇_S φ = −A,     A = ρ c P − c P H P − (g (Pu)ᵀ + (Pu) gᵀ).
//! ```
//!
//! `t = 0` says that the surface normal `N ∝ ρ y − ∇_S ρ` (that of a radial
//! graph) is along `u`. `A` is the surface's second fundamental form
//! written in the sphere's coordinates: `∂²(u·x)/∂a∂b = u·x_ab` where the
//! first derivatives vanish, and `u·x_ab = −II_ab` with `u` the outward
//! unit normal. The search is Newton's method on the sphere from `y₀`
//! (`u` itself, the sphere's answer): solve `A δ = t` in the tangent plane
//! (`(A + y yᵀ) δ = t` by Cholesky), step `y → (y + δ)/|y + δ|`, capped at
//! 0.3 and halved until `φ` does not decrease; a gradient step `0.1 t/|t|`
//! where `A` is not positive definite (far from the maximum). Converged
//! after a Newton step below 10⁻⁷, taken without the descent test: the
//! error left, `~C·10⁻¹⁴` with `C = O(1)` the ratio of third to second
//! derivatives of `φ`, moves `s` by `~10⁻²⁸` (`φ` is stationary) and the
//! support point by `~10⁻¹⁴`.
//!
//! At the optimum `y*`, `s(u) = ρ c`, and by the envelope theorem
//! (`s(u) = max_y u·x(y)`) its gradient is the support point itself,
//! `∇s = p = ρ(y*) y*`. Its Hessian follows by differentiating the
//! optimum: `t(y*(u), u) = 0` with `∂t/∂u = g yᵀ + ρ P` (`t` is linear in
//! `u`) gives `dy* = A⁺ (g yᵀ + ρ P) du`, and `dx = (ρ 1 + y gᵀ) dy` on
//! tangent vectors, so with `B = ρ P + y gᵀ` (the differential of the map
//! `y ↦ x(y)`, tangent plane of the sphere to tangent plane of the
//! surface, which is `u⊥`)
//!
//! ```text
//! ∇∇s(u) = B A⁺ Bᵀ,     A⁺ = (A + y yᵀ)⁻¹ − y yᵀ.
//! ```
//!
//! This is the inverse of the Weingarten map. With the first fundamental
//! form `I = BᵀB` and the second `II = A` in the sphere's coordinates, the
//! Weingarten map is `L = I⁻¹ II`; on `u⊥`, in the surface's own tangent
//! coordinates `dx = B dy`, `B A⁻¹ Bᵀ` has the eigenvalues of
//! `(BᵀB) A⁻¹ = I II⁻¹ = L⁻¹`, the principal radii of curvature. It is
//! symmetric, `∇∇s u = B A⁺ t = 0` at the optimum (`Bᵀ u = t`), and positive
//! on `u⊥` exactly where `A` is: where the surface is strictly convex. On a
//! non-convex surface the search may stop at a local maximum of the
//! height (the convex hull's support function is the global one): callers
//! check convexity first.
//!
//! ## The joint iteration
//!
//! [`exact_with`] on supports found by [`radial_search`] nests two Newton
//! iterations: at every point `u` of the outer one, both support searches
//! run to convergence, although only the last point's supports need that
//! accuracy. [`exact_joint`] instead runs one Newton iteration on the
//! normal and both support points at once. Since
//! `s_i(u) = max_y u·x_i(y)`, the gap is the saddle value
//!
//! ```text
//! h = max_u min_{y_i, y_j} L,     L(u, y_i, y_j) = u·d,     d = r − x_i(y_i) + x_j(y_j)
//! ```
//!
//! (`x` the world-frame surface point `R ρ(y) y`, `y` the body-frame unit
//! vector). Its stationarity conditions are the outer and both inner ones:
//! `P d = 0` (the support points face each other along `u`) and `t_i = 0`,
//! `t_j = 0` (each surface's normal at its point is `±u`, `t` as in the
//! support search, body `j` read in the direction `−u`). With `A`, `B`
//! and `t` of each body at its current `y`, Newton's step on the three
//! unit vectors (tangent steps `δu`, `δy_i`, `δy_j`) solves
//!
//! ```text
//! ⎡ −(u·d) P    −P R_i B_i    P R_j B_j ⎤ ⎡ δu  ⎤     ⎡ −P d ⎤
//! ⎢ −B_iᵀR_iᵀ P    A_i           0      ⎥ ⎢ δy_i⎥  =  ⎢  t_i ⎥
//! ⎣  B_jᵀR_jᵀ P     0           A_j     ⎦ ⎣ δy_j⎦     ⎣  t_j ⎦
//! ```
//!
//! (`∂t/∂u = Bᵀ`; the `y` blocks are the searches' own Hessians, the `u`
//! block that of the linear function `u·d` on the sphere). Eliminating
//! the support steps, `δy_i = A_i⁺ t_i + A_i⁺B_iᵀR_iᵀ δu` and
//! `δy_j = A_j⁺ t_j − A_j⁺B_jᵀR_jᵀ δu`, leaves on the tangent plane of `u`
//!
//! ```text
//! W δu = P (d − R_i B_i A_i⁺ t_i + R_j B_j A_j⁺ t_j),     W = (u·d) P + P (S̃_i + S̃_j) P,
//! S̃ = R B A⁺ Bᵀ Rᵀ:
//! ```
//!
//! the outer step of the nested solve, with each support point replaced
//! by its linearisation after one step of its own search, and `S̃` the
//! support Hessian's formula read at the current `y` (at converged
//! supports it is the nested solve's step exactly). One step costs a
//! radial jet and a 3 × 3 inverse by cofactors per body (for `A⁺ t`
//! and `A⁺ Bᵀ`, four right-hand sides) and one of `W + u uᵀ` for the
//! step (one division each, no square root), where the nested
//! solve runs both searches to convergence (2–3 steps each, with their
//! line searches) and factorises `A` twice more for the support Hessians.
//!
//! The iteration starts as the nested solve does, with both supports
//! searched to convergence at the line of centres, so that the same
//! pairs are skipped (`g(r̂) > max_gap`) bit for bit. It has no merit
//! function (a saddle point), so it is guarded instead: it stops with a
//! failure where `A_i`, `A_j` or `W` is not positive definite (a surface
//! not convex at its point, or bodies overlapping by more than their
//! radii of curvature), where a step is longer than the one before (no
//! quadratic convergence) or after 30 steps; steps are cut to length 0.3.
//! [`exact_joint`] then runs the nested solve and counts it
//! ([`joint_fallbacks`]). Converged after a step below 10⁻⁷ on all three
//! unit vectors, the same tolerance as the nested solve's: the error left
//! is `~10⁻¹⁴` in the normal and the support points and `~10⁻²⁸` in `h`
//! (`L` is stationary). The result carries the supports at the final
//! point (the support Hessian `R B A⁺ Bᵀ Rᵀ` there with `hessians`), so
//! [`ExactGap3::contact`] and [`ExactGap3::hessian`] serve both solvers.
//! It is not the nested solve's result bit for bit: the two stop at
//! different points within ~10⁻¹⁴ of the optimum.
//!
//! ## The warm start
//!
//! In a minimisation a pair's optimum moves little from one evaluation to
//! the next. [`exact_joint_warm`] runs the same joint iteration from where
//! the pair's last solve ended ([`JointStart`], kept as a
//! `jamkit_core::PairMemo`: the normal relative to the line of centres
//! and each support unit vector relative to its body's direction, so a
//! pair that moved or turned as a whole starts at its optimum; written
//! from where the iteration ended, without normalising, and read back
//! with one square root before the three normalisations), skipping
//! the cold start's two support searches at the line of centres. Same
//! steps and safeguards; it ends at a looser tolerance, since what a step
//! leaves shrinks with the step itself: Newton's iteration leaves
//! `K len²` after a step of length `len` (`K` below 1 for the bodies
//! tested), and `L` is stationary, so `h` keeps only the square of that.
//! A warm iteration ends after a step below [`WARM_TOL`] = 10⁻⁵ (≤ 10⁻¹⁰
//! left in the normal and the support points, ≤ 10⁻²⁰ in `h`), read at the
//! step's end as the cold one is; and after a step below [`TAYLOR_TOL`] =
//! 10⁻⁶, without support Hessians, it ends without reading the radial
//! functions again: the support points moved along the step to first
//! order (≤ 10⁻¹²) and `h` the stationary value of the quadratic model,
//! `L + ½ ∇L·δ` (`O(len³)`: ≤ 10⁻¹⁸). After a FIRE step most pairs take
//! one step. The guarantee holds whatever the start, so the error a
//! result carries is set by how far its own last step went, not by how
//! far the pair moved: a pair that stops moving is solved to round-off.
//! A result is accepted only with its normal in the cap `n·r̂ ≥ 1/2`, where
//! it is the maximum the cold solve reaches (conditions on
//! [`exact_joint_warm`]), else the caller solves cold. A pair is then
//! known to be apart only from its converged gap (`h > max_gap`), not from
//! `g(r̂)`, so a pair with `g(r̂) ≤ max_gap < h` is reported by the cold
//! solve and skipped by the warm one (both as a family's contacts allow).
//!
//! [`QuadraticSupport`] is the support function of an ellipsoid,
//! `s(x) = √(xᵀ M x)`, the body the `ellipsoid` family is made of and the
//! one the tests here use.

use jamkit_core::{Contact, GapHessian, MAX_ROT, MEMO_LEN, Matrix, RotVec, Vector};

/// A support function at one direction `u` (world frame) with its first
/// two derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupportJet3 {
    /// `s(u)`.
    pub h: f64,
    /// `∇s(u)`: the support point relative to the centre.
    pub point: Vector<3>,
    /// `∇∇s(u)` (symmetric, `S u = 0`): the radii of curvature at the
    /// support point.
    pub hess: Matrix<3>,
}

/// The support function `s(x) = √(xᵀ M x)` of the ellipsoid
/// `{y : yᵀ M⁻¹ y ≤ 1}` (`M = Q diag(a², b², c²) Qᵀ` for semi-axes
/// `a, b, c` along the columns of `Q`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadraticSupport {
    /// `M`, symmetric positive definite.
    pub form: Matrix<3>,
}

impl QuadraticSupport {
    /// The ellipsoid with semi-axes `semi[k]` along the unit vectors
    /// `axes[k]` (orthonormal): `M = Σ_k semi[k]² axes[k] axes[k]ᵀ`.
    #[inline(always)]
    pub fn new(axes: &[Vector<3>; 3], semi: [f64; 3]) -> Self {
        let mut form = Matrix::<3>::zeros();
        for k in 0..3 {
            form += axes[k] * axes[k].transpose() * (semi[k] * semi[k]);
        }
        Self { form }
    }

    /// `s(u)`, `∇s = M u / s` and `∇∇s = M/s − (M u)(M u)ᵀ/s³` (at a unit
    /// `u`; `∇∇s u = 0`).
    #[inline(always)]
    pub fn jet(&self, u: &Vector<3>) -> SupportJet3 {
        let mu = self.form * u;
        let h = u.dot(&mu).sqrt();
        let inv = 1.0 / h;
        let point = mu * inv;
        SupportJet3 {
            h,
            point,
            hess: (self.form - point * point.transpose()) * inv,
        }
    }
}

/// The exact gap of two convex bodies at the optimum normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactGap3 {
    /// The common normal `n` (unit, from `i` towards `j`).
    pub normal: Vector<3>,
    /// The signed distance `h = g(n)`.
    pub gap: f64,
    /// Body `i`'s support jet at `n` (its `hess` zero from [`exact_with`]
    /// without `hessians`).
    pub jet_i: SupportJet3,
    /// Body `j`'s support jet at `−n` (likewise).
    pub jet_j: SupportJet3,
    /// Iterations taken (each evaluates both support functions at least
    /// once).
    pub iterations: u32,
    /// False when the iteration stopped at its cap (the last iterate is
    /// returned).
    pub converged: bool,
}

/// A support function read at one direction `u`: its value and support
/// point at once, its Hessian `∇∇s(u)` on request. [`exact`] asks for the
/// Hessian only at the points its Newton steps start from (and, with
/// `hessians`, at the optimum), not at rejected line-search points, at a
/// pair it skips, or at the last point of a search for a contact; for a
/// support found by a search ([`RadialFound`]) the Hessian is the costly
/// part (a 3 × 3 inverse and two products).
pub trait SupportAt {
    /// `s(u)`.
    fn value(&self) -> f64;
    /// `∇s(u)`, the support point relative to the centre.
    fn point(&self) -> Vector<3>;
    /// `∇∇s(u)`.
    fn hess(&self) -> Matrix<3>;
}

impl SupportAt for SupportJet3 {
    #[inline(always)]
    fn value(&self) -> f64 {
        self.h
    }
    #[inline(always)]
    fn point(&self) -> Vector<3> {
        self.point
    }
    #[inline(always)]
    fn hess(&self) -> Matrix<3> {
        self.hess
    }
}

/// One evaluation of `g` and its tangent gradient at a unit `u`, with the
/// two supports (whose Hessians give `W` when a Newton step needs it).
#[derive(Clone, Copy, Debug)]
struct Eval<I, J> {
    g: f64,
    t: Vector<3>,
    ji: I,
    jj: J,
}

/// `u` moved by the tangent vector `δ` and projected back onto the sphere,
/// `(u + δ)/|u + δ|`: a second-order retraction (it follows the great
/// circle through `u` along `δ`, by the angle `atan|δ| = |δ| − |δ|³/3 + …`),
/// enough for Newton's quadratic convergence, with no trigonometric call.
#[inline(always)]
fn along_sphere(u: &Vector<3>, d: &Vector<3>) -> Vector<3> {
    (u + d).normalize()
}

/// The step of both searches on the sphere ([`exact`], [`radial_support`]):
/// the Newton step `newton` when there is one, else a gradient step of
/// length 0.1 along the tangent ascent direction `t`; either cut to length
/// 0.3. Gives the step, whether it is Newton's, and its length before the
/// cut; `None` when there is no Newton step and `t = 0` (a stationary
/// point: converged).
#[inline(always)]
fn safeguarded_step(newton: Option<Vector<3>>, t: &Vector<3>) -> Option<(Vector<3>, bool, f64)> {
    let (mut step, is_newton) = match newton {
        Some(d) => (d, true),
        None => {
            let n = t.norm();
            if n == 0.0 {
                return None;
            }
            (t * (0.1 / n), false)
        }
    };
    let len = step.norm();
    if len > 0.3 {
        step *= 0.3 / len;
    }
    Some((step, is_newton, len))
}

/// The support jet of `s`, its Hessian zero unless `hessians`.
#[inline(always)]
fn jet_of<S: SupportAt>(s: &S, hessians: bool) -> SupportJet3 {
    SupportJet3 {
        h: s.value(),
        point: s.point(),
        hess: if hessians {
            s.hess()
        } else {
            Matrix::<3>::zeros()
        },
    }
}

/// The exact signed distance `h = max_{|u|=1} [u·r_ij − s_i(u) − s_j(−u)]`
/// (module documentation), with `sup_i(u)` and `sup_j(v)` the two bodies'
/// world-frame supports (the solver asks body `j` at `v = −u`), started
/// from the line of centres (`x̂` at coincident centres). `None` when `g`
/// at the line of centres already exceeds `max_gap` (then `h > max_gap`).
/// The result's support jets carry their Hessians: [`exact_with`] with
/// `hessians = true`.
#[inline]
pub fn exact<A, B, I, J>(r_ij: &Vector<3>, sup_i: A, sup_j: B, max_gap: f64) -> Option<ExactGap3>
where
    A: Fn(&Vector<3>) -> I,
    B: Fn(&Vector<3>) -> J,
    I: SupportAt,
    J: SupportAt,
{
    exact_with(r_ij, sup_i, sup_j, max_gap, true)
}

/// [`exact`], with the two support Hessians at the optimum computed only
/// when `hessians` (else the result's `jet_i.hess` and `jet_j.hess` are
/// zero): [`ExactGap3::contact`] does not read them, [`ExactGap3::hessian`]
/// does. Everything else, the normal, the gap and the support points, is
/// the same bit for bit either way.
#[inline]
pub fn exact_with<A, B, I, J>(
    r_ij: &Vector<3>,
    sup_i: A,
    sup_j: B,
    max_gap: f64,
    hessians: bool,
) -> Option<ExactGap3>
where
    A: Fn(&Vector<3>) -> I,
    B: Fn(&Vector<3>) -> J,
    I: SupportAt,
    J: SupportAt,
{
    exact_warm(r_ij, sup_i, sup_j, None, max_gap, hessians)
}

/// `g(u)` and its tangent gradient `t` with the two supports read at `u`
/// and `−u`.
#[inline(always)]
fn evaluate<A, B, I, J>(r_ij: &Vector<3>, sup_i: &A, sup_j: &B, u: &Vector<3>) -> Eval<I, J>
where
    A: Fn(&Vector<3>) -> I,
    B: Fn(&Vector<3>) -> J,
    I: SupportAt,
    J: SupportAt,
{
    let ji = sup_i(u);
    let jj = sup_j(&-u);
    let g = u.dot(r_ij) - ji.value() - jj.value();
    let t = r_ij - ji.point() + jj.point() - u * g;
    Eval { g, t, ji, jj }
}

/// The safeguarded Newton ascent of [`exact_with`] from the unit vector
/// `u`, where `eval` gave `cur`.
#[inline(always)]
fn ascend<E, I, J>(eval: &E, mut u: Vector<3>, mut cur: Eval<I, J>, hessians: bool) -> ExactGap3
where
    E: Fn(&Vector<3>) -> Eval<I, J>,
    I: SupportAt,
    J: SupportAt,
{
    // W = S_i + S_j + g P at the point a Newton step starts from.
    let w = |e: &Eval<I, J>, u: &Vector<3>| {
        let p = Matrix::<3>::identity() - u * u.transpose();
        e.ji.hess() + e.jj.hess() + p * e.g
    };
    let mut converged = false;
    let mut iterations = 0;
    while iterations < 60 {
        iterations += 1;
        // The tangent component only (t ⊥ u up to round-off).
        let t = cur.t - u * u.dot(&cur.t);
        let newton = (w(&cur, &u) + u * u.transpose())
            .cholesky()
            .map(|c| c.solve(&t))
            .map(|d| d - u * u.dot(&d));
        let Some((mut step, is_newton, len)) = safeguarded_step(newton, &t) else {
            converged = true;
            break;
        };
        if is_newton && len < 1e-6 {
            u = along_sphere(&u, &step);
            cur = eval(&u);
            if len < 1e-7 {
                converged = true;
                break;
            }
            continue;
        }
        // NOTE: this halving line search and `radial_support`'s are written
        // out each: one generic helper for both made ellipsoid packings 15 %
        // slower (same bits).
        let mut next_u = along_sphere(&u, &step);
        let mut next = eval(&next_u);
        let mut halvings = 0;
        while next.g < cur.g && halvings < 40 {
            step *= 0.5;
            next_u = along_sphere(&u, &step);
            next = eval(&next_u);
            halvings += 1;
        }
        if next.g < cur.g {
            // No ascent along this direction at round-off level: u is the
            // maximum to machine precision.
            converged = true;
            break;
        }
        u = next_u;
        cur = next;
    }
    ExactGap3 {
        normal: u,
        gap: cur.g,
        jet_i: jet_of(&cur.ji, hessians),
        jet_j: jet_of(&cur.jj, hessians),
        iterations,
        converged,
    }
}

/// [`exact_with`] started at the unit vector `start` (where given)
/// instead of the line of centres: the warm start of a pair whose last
/// solve ended near there (its normal kept by [`normal_offset`], read back
/// by [`normal_from_offset`]). The result is the cold solve's optimum to
/// the iteration's tolerance, or the cold solve's result bit for bit:
///
/// * `None` exactly where [`exact_with`] gives `None` (`g(r̂) > max_gap`,
///   read first);
/// * the ascent from `start` is accepted when `start` and its end lie in
///   the cap `n·r̂ ≥ 1/2` about the line of centres, `g(start) ≥ g(r̂)`
///   and it converged. The ascent never lowers `g`, so it ends at a local
///   maximum above `g(r̂)`. Where `h > 0` that is the maximum: `G` is
///   concave and homogeneous of degree 1, so at a local maximum `u` on the
///   sphere with `g(u) > 0` no point of the unit ball does better near it
///   (`G(t v) = t G(v)`), and a local maximum of a concave function on a
///   convex set is the global one. For the shallow overlaps of a jamming
///   run (`|h|` far below the radii of curvature) `g` has one maximum on
///   the cap (module documentation, NOTE);
/// * otherwise (and with no `start`) the cold ascent from `r̂`, bit for
///   bit [`exact_with`].
#[inline]
pub fn exact_warm<A: Fn(&Vector<3>) -> I, B: Fn(&Vector<3>) -> J, I: SupportAt, J: SupportAt>(
    r_ij: &Vector<3>,
    sup_i: A,
    sup_j: B,
    start: Option<&Vector<3>>,
    max_gap: f64,
    hessians: bool,
) -> Option<ExactGap3> {
    let eval = |u: &Vector<3>| evaluate(r_ij, &sup_i, &sup_j, u);
    let cap = Cap::new(r_ij);
    let cold = eval(&cap.r_hat);
    if cold.g > max_gap {
        return None;
    }
    if let Some(start) = start.filter(|s| cap.contains(s)) {
        let warm = eval(start);
        if warm.g >= cold.g {
            let e = ascend(&eval, *start, warm, hessians);
            if e.converged && cap.contains(&e.normal) && e.gap >= cold.g {
                return Some(e);
            }
        }
    }
    Some(ascend(&eval, cap.r_hat, cold, hessians))
}

/// What a pair keeps of its last normal `n` for a warm start
/// ([`exact_warm`], [`JointStart`]): `Q_iᵀ(n − r̂)`, the normal relative to
/// the line of centres in body `i`'s frame (`columns_i` the columns of
/// `Q_i`), so that a pair that moved or turned as a whole starts where its
/// optimum moved to.
#[inline]
pub fn normal_offset(
    normal: &Vector<3>,
    r_ij: &Vector<3>,
    columns_i: &[Vector<3>; 3],
) -> Vector<3> {
    in_frame(columns_i, &(normal - unit_or_x(r_ij)))
}

/// The start [`normal_offset`] encoded, read at the separation `r_ij` and
/// orientation `columns_i`: `n₀ ∝ r̂ + Q_i a`; `None` where that vanishes.
#[inline]
pub fn normal_from_offset(
    a: &Vector<3>,
    r_ij: &Vector<3>,
    columns_i: &[Vector<3>; 3],
) -> Option<Vector<3>> {
    let [c0, c1, c2] = columns_i;
    unit(unit_or_x(r_ij) + (c0 * a[0] + c1 * a[1] + c2 * a[2]))
}

/// `Qᵀ v` for the rotation with the columns `c`.
#[inline(always)]
fn in_frame(c: &[Vector<3>; 3], v: &Vector<3>) -> Vector<3> {
    Vector::<3>::new(c[0].dot(v), c[1].dot(v), c[2].dot(v))
}

/// `x/|x|`, `None` where `|x|` is zero or not finite.
#[inline(always)]
fn unit(x: Vector<3>) -> Option<Vector<3>> {
    let n = x.norm();
    (n > 0.0 && n.is_finite()).then(|| x / n)
}

/// An upper bound on the support function of a star-shaped body
/// `x(y) = ρ(y) y` in the direction `u` (unit) from its radial function in
/// that direction alone: `s(u) ≤ ρ(u) + π² G² / (16 ρ_min)`, with `G` a
/// bound on the surface slope `|∇_S ρ|` and `0 < ρ_min ≤ ρ(u)`.
///
/// At the angle `θ` from `u`, `ρ(y) ≤ ρ(u) + G θ` (along the great
/// circle) and, for `θ ≤ π/2`, `cos θ = 1 − 2 sin²(θ/2) ≤ 1 − 4θ²/π²`
/// (`sin x ≥ (2√2/π) x` for `x ≤ π/4`), so
/// `u·x(y) = ρ(y) cos θ ≤ ρ(u) + Gθ − 4ρ(u)θ²/π²`, whose largest value over
/// `θ` is `ρ(u) + π²G²/(16 ρ(u))`; for `θ > π/2`, `u·x(y) < 0 < ρ(u)`.
/// With it `g(u) ≥ u·r − ρ_i(u) − ρ_j(−u) − (the two margins)` bounds the gap
/// `h ≥ g(u)` from below at any `u`, from two radial values.
#[inline(always)]
pub fn radial_support_bound(rho_u: f64, slope: f64, rho_min: f64) -> f64 {
    rho_u + std::f64::consts::PI * std::f64::consts::PI * slope * slope / (16.0 * rho_min)
}

/// Where a [`radial_support`] search ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadialSupport {
    /// `s(u)`, `∇s` (the support point) and `∇∇s` (module documentation).
    pub jet: SupportJet3,
    /// The unit vector `y*` of the support point `p = ρ(y*) y*`.
    pub y: Vector<3>,
    /// Newton or gradient steps taken.
    pub iterations: u32,
    /// False when the search stopped at its cap (the last iterate is used).
    pub converged: bool,
}

/// The radial function and the height at one unit vector `y` of a
/// [`radial_support`] search.
#[derive(Clone, Copy, Debug, PartialEq)]
struct At {
    y: Vector<3>,
    rho: f64,
    g: Vector<3>,
    h: Matrix<3>,
    phi: f64,
}

/// `t` and `A` (module documentation) at a point of the search for the
/// direction `u`.
#[inline(always)]
fn tangent(u: &Vector<3>, a: &At) -> (Vector<3>, Matrix<3>) {
    let y = a.y;
    let c = u.dot(&y);
    let p = Matrix::<3>::identity() - y * y.transpose();
    let pu = u - y * c;
    let g = a.g - y * y.dot(&a.g);
    let t = g * c + pu * a.rho;
    let gp = g * pu.transpose();
    let big = p * (a.rho * c) - p * a.h * p * c - (gp + gp.transpose());
    (t, big)
}

/// Where a [`radial_search`] ended: the support value and point at once,
/// the Hessian `∇∇s = B A⁺ Bᵀ` on request ([`RadialFound::hess`]), all in
/// the frame of the radial function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadialFound {
    u: Vector<3>,
    at: At,
    /// Newton or gradient steps taken.
    pub iterations: u32,
    /// False when the search stopped at its cap (the last iterate is used).
    pub converged: bool,
}

impl RadialFound {
    /// `s(u)`.
    #[inline(always)]
    pub fn value(&self) -> f64 {
        self.at.phi
    }

    /// The support point `ρ(y*) y*`.
    #[inline(always)]
    pub fn point(&self) -> Vector<3> {
        self.at.y * self.at.rho
    }

    /// The unit vector `y*` of the support point.
    #[inline(always)]
    pub fn y(&self) -> Vector<3> {
        self.at.y
    }

    /// `∇∇s(u) = B A⁺ Bᵀ` (module documentation), symmetrised.
    #[inline(always)]
    pub fn hess(&self) -> Matrix<3> {
        let cur = &self.at;
        let y = cur.y;
        let (_, big) = tangent(&self.u, cur);
        let yy = y * y.transpose();
        let inv = match (big + yy).cholesky() {
            Some(c) => c.inverse() - yy,
            None => Matrix::<3>::zeros(),
        };
        let g = cur.g - y * y.dot(&cur.g);
        let b = (Matrix::<3>::identity() - yy) * cur.rho + y * g.transpose();
        let hess = b * inv * b.transpose();
        (hess + hess.transpose()) * 0.5
    }

    /// The whole [`RadialSupport`].
    #[inline(always)]
    pub fn support(&self) -> RadialSupport {
        RadialSupport {
            jet: SupportJet3 {
                h: self.value(),
                point: self.point(),
                hess: self.hess(),
            },
            y: self.at.y,
            iterations: self.iterations,
            converged: self.converged,
        }
    }
}

/// The support jet of the star-shaped surface `x(y) = ρ(y) y` in the
/// direction `u` (unit; the frame of `radial`), from the surface point
/// whose outward normal is `u` (module documentation), searched from the
/// unit vector `start`. `radial(y)` gives `ρ`, `∇ρ̃` and `∇∇ρ̃` at the unit
/// vector `y`, with `ρ̃(x) = ρ(x/|x|)` constant along rays.
#[inline]
pub fn radial_support<F>(u: &Vector<3>, start: &Vector<3>, radial: F) -> RadialSupport
where
    F: Radial,
{
    radial_search(u, start, radial).support()
}

/// The search of [`radial_support`], its Hessian left for later
/// ([`RadialFound::hess`]; the same bits).
#[inline]
pub fn radial_search<F>(u: &Vector<3>, start: &Vector<3>, radial: F) -> RadialFound
where
    F: Radial,
{
    let at = |y: Vector<3>| {
        let (rho, g, h) = radial(&y);
        At {
            phi: rho * u.dot(&y),
            y,
            rho,
            g,
            h,
        }
    };
    let mut cur = at(start.normalize());
    let mut iterations = 0;
    let mut converged = false;
    while iterations < 60 {
        iterations += 1;
        let y = cur.y;
        let (t, big) = tangent(u, &cur);
        let newton = (big + y * y.transpose())
            .cholesky()
            .map(|c| c.solve(&t))
            .map(|d| d - y * y.dot(&d))
            .filter(|d| d.dot(&t) > 0.0);
        let Some((mut step, is_newton, len)) = safeguarded_step(newton, &t) else {
            converged = true;
            break;
        };
        if is_newton && len < 1e-7 {
            cur = at(along_sphere(&y, &step));
            converged = true;
            break;
        }
        let mut next = at(along_sphere(&y, &step));
        let mut halvings = 0;
        while next.phi < cur.phi && halvings < 40 {
            step *= 0.5;
            next = at(along_sphere(&y, &step));
            halvings += 1;
        }
        if next.phi < cur.phi {
            converged = true;
            break;
        }
        cur = next;
    }
    RadialFound {
        u: *u,
        at: cur,
        iterations,
        converged,
    }
}

/// How the exact gap of two star-shaped bodies is solved (the `harmonic`
/// family's `exact_solver`): the same optimum either way, to the solvers'
/// tolerance, not the same bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ExactSolver {
    /// [`exact_with`] on supports found by [`radial_search`]: at every
    /// evaluation of the normal, both support searches run to convergence.
    #[default]
    Nested,
    /// [`exact_joint`]: one Newton iteration on the normal and both
    /// support points at once, the nested solve where it fails.
    Joint,
}

impl ExactSolver {
    /// Both solvers.
    pub const ALL: [ExactSolver; 2] = [ExactSolver::Nested, ExactSolver::Joint];

    /// The name used in experiment files.
    pub fn name(self) -> &'static str {
        match self {
            ExactSolver::Nested => "Nested",
            ExactSolver::Joint => "Joint",
        }
    }
}

impl std::str::FromStr for ExactSolver {
    type Err = String;

    /// `"Nested"` or `"Joint"`, case ignored; the error names both.
    fn from_str(text: &str) -> Result<Self, String> {
        ExactSolver::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| {
                format!("unknown exact solver {text:?}: allowed are \"Nested\", \"Joint\"")
            })
    }
}

/// A radial function in a body's frame: `ρ`, `∇ρ̃` and `∇∇ρ̃` at a unit
/// vector `y`, with `ρ̃(x) = ρ(x/|x|)` constant along rays (what
/// [`radial_support`] and [`RadialBody`] read).
pub trait Radial: Fn(&Vector<3>) -> (f64, Vector<3>, Matrix<3>) {}

impl<T: Fn(&Vector<3>) -> (f64, Vector<3>, Matrix<3>)> Radial for T {}

/// A star-shaped body `x(y) = ρ(y) y` placed in the world, as
/// [`exact_joint`] reads it: the columns of its rotation (body to world)
/// and its radial function in the body frame (`ρ`, `∇ρ̃`, `∇∇ρ̃` at a unit
/// vector, as [`radial_support`] takes it).
#[derive(Clone, Copy)]
pub struct RadialBody<'a, F> {
    /// The columns of the rotation `R` (body to world).
    pub columns: &'a [Vector<3>; 3],
    /// The radial function.
    pub radial: F,
}

impl<F> RadialBody<'_, F>
where
    F: Radial,
{
    /// `Rᵀ v`.
    #[inline(always)]
    fn to_body(&self, v: &Vector<3>) -> Vector<3> {
        let [c0, c1, c2] = self.columns;
        Vector::<3>::new(c0.dot(v), c1.dot(v), c2.dot(v))
    }

    /// `R b`.
    #[inline(always)]
    fn to_world(&self, b: &Vector<3>) -> Vector<3> {
        let [c0, c1, c2] = self.columns;
        c0 * b[0] + c1 * b[1] + c2 * b[2]
    }

    /// The radial function at the body-frame unit vector `y`, its height
    /// in the body-frame direction `ub`.
    #[inline(always)]
    fn at(&self, y: Vector<3>, ub: &Vector<3>) -> At {
        let (rho, g, h) = (self.radial)(&y);
        At {
            phi: rho * ub.dot(&y),
            y,
            rho,
            g,
            h,
        }
    }

    /// The support value, world support point and (with `hessian`) world
    /// support Hessian `R ∇∇s Rᵀ` of the support found at `at` for the
    /// body-frame direction `ub`.
    #[inline(always)]
    fn jet(&self, ub: &Vector<3>, at: At, hessian: bool) -> SupportJet3 {
        let found = RadialFound {
            u: *ub,
            at,
            iterations: 0,
            converged: true,
        };
        let hess = if hessian {
            let rot = Matrix::<3>::from_columns(self.columns);
            rot * found.hess() * rot.transpose()
        } else {
            Matrix::<3>::zeros()
        };
        SupportJet3 {
            h: found.value(),
            point: self.to_world(&found.point()),
            hess,
        }
    }
}

/// One body's part of a step of [`exact_joint`], at its current unit
/// vector `y` and direction (module documentation, "The joint
/// iteration"), all but `n` in the world frame.
struct Linearised {
    /// The support search's own Newton step `A⁺ t` (body frame).
    n: Vector<3>,
    /// `A⁺ Bᵀ Rᵀ`: how the support's `y` follows a turn of the direction
    /// (world tangent vector to body tangent vector).
    follow: Matrix<3>,
    /// `R B`: the surface point's differential (body tangent to world).
    b: Matrix<3>,
    /// `R ρ y`, the surface point.
    x: Vector<3>,
    /// The support search's gradient `t` (body frame).
    t: Vector<3>,
    /// `ρ u·y`, its height.
    phi: f64,
}

/// The inverse of a symmetric 3 × 3 matrix (its lower triangle read) by
/// cofactors, `None` unless it is positive definite (Sylvester: the
/// leading principal minors positive). The joint iteration's four
/// right-hand sides per body cost less this way than through a Cholesky
/// factorisation's triangular solves.
#[inline(always)]
fn spd_inverse(m: &Matrix<3>) -> Option<Matrix<3>> {
    let (a, b, c) = (m[(0, 0)], m[(1, 0)], m[(2, 0)]);
    let (d, e, f) = (m[(1, 1)], m[(2, 1)], m[(2, 2)]);
    let c00 = d * f - e * e;
    let c01 = c * e - b * f;
    let c02 = b * e - c * d;
    let minor = a * d - b * b;
    let det = a * c00 + b * c01 + c * c02;
    if !(a > 0.0 && minor > 0.0 && det > 0.0) {
        return None;
    }
    let c11 = a * f - c * c;
    let c12 = b * c - a * e;
    let inv = 1.0 / det;
    Some(Matrix::<3>::new(c00, c01, c02, c01, c11, c12, c02, c12, minor) * inv)
}

/// `None` where `A` is not positive definite (the surface is not convex
/// there, or `y` is far from the support point). `t` and `A` as in
/// [`tangent`], `P H P` by rank-one updates; with `A⁺ = (A + y yᵀ)⁻¹ − y yᵀ`
/// (`A y = 0`) and `Bᵀ = ρ P + g yᵀ`, the search's step is `A⁺ t`, and
/// `A⁺ Bᵀ = ρ A⁺ + (A⁺ g) yᵀ`, `R B = ρ R + (R y)(g − ρ y)ᵀ`.
#[inline(always)]
fn linearise<F>(body: &RadialBody<'_, F>, ub: &Vector<3>, at: &At) -> Option<Linearised>
where
    F: Radial,
{
    let y = at.y;
    let rho = at.rho;
    let c = ub.dot(&y);
    let pu = ub - y * c;
    let g = at.g - y * y.dot(&at.g);
    let t = g * c + pu * rho;
    let hy = at.h * y;
    let yy = y * y.transpose();
    let php = at.h - y * hy.transpose() - hy * y.transpose() + yy * y.dot(&hy);
    let gp = g * pu.transpose();
    let big = (Matrix::<3>::identity() - yy) * (rho * c) - php * c - (gp + gp.transpose());
    let a_plus = spd_inverse(&(big + yy))? - yy;
    let rot = Matrix::<3>::from_columns(body.columns);
    let ry = body.to_world(&y);
    Some(Linearised {
        n: a_plus * t,
        follow: (a_plus * rho + (a_plus * g) * y.transpose()) * rot.transpose(),
        b: rot * rho + ry * (g - y * rho).transpose(),
        x: ry * rho,
        t,
        phi: rho * c,
    })
}

/// The last step of a converged cold joint iteration ([`exact_joint`])
/// is below this (the nested solve's tolerance): ~10⁻¹⁴ left in the
/// normal and the support points, ~10⁻²⁸ in `h`.
pub const JOINT_TOL: f64 = 1e-7;

/// The last step of a converged warm joint iteration
/// ([`exact_joint_warm`]) is below this: what is left is at most
/// `K len²` in the normal and the support points (quadratic convergence,
/// `K` of the order of the ratio of third to second derivatives of `L`;
/// 0.54 at most on the ellipsoids of the tests, near-spherical and
/// elongated: ≤ 10⁻¹⁰) and `O(len⁴)` in `h` (`L` is stationary: ≤ 10⁻²⁰).
pub const WARM_TOL: f64 = 1e-5;

/// A warm joint iteration without support Hessians ([`exact_joint_warm`])
/// whose step is below this ends without reading the radial functions
/// again: the normal `u + δu` (`K len²` from the optimum, as after any
/// step), each support point moved along the step to first order,
/// `x + R B δy` (`O(len²)`: ≤ 10⁻¹²), and `h` the stationary value of the
/// quadratic model of `L`, `L + ½ ∇L·δ` (`O(len³)`: ≤ 10⁻¹⁸, below the
/// round-off of `h`). Each support value is `±u·x` at the moved point
/// (`O(len²)`; the gap is the model's).
pub const TAYLOR_TOL: f64 = 1e-6;

/// The iteration cap of [`exact_joint`] (it converges in 3–6 steps where it
/// converges at all).
const JOINT_CAP: u32 = 30;

static JOINT_FALLBACKS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// How many times [`exact_joint`] fell back to the nested solve in this
/// process (all threads): a diagnostic, for benchmarks.
pub fn joint_fallbacks() -> u64 {
    JOINT_FALLBACKS.load(std::sync::atomic::Ordering::Relaxed)
}

/// The exact gap of two star-shaped convex bodies by one Newton iteration
/// on the normal and both support points at once (module documentation,
/// "The joint iteration"), or by `nested` (the nested solve, [`exact_with`] on
/// [`radial_search`] supports, counted by [`joint_fallbacks`]) where that
/// iteration fails. The same first evaluation as the nested solve (both
/// supports searched to convergence at the line of centres), so the same
/// pairs are skipped (`None`: `g(r̂) > max_gap`); the result is the nested
/// one's to the solvers' tolerance (normal and support points ~10⁻¹⁴, gap
/// ~10⁻²⁸ from the optimum), with the support Hessians at the optimum
/// when `hessians`, so that [`ExactGap3::contact`] and
/// [`ExactGap3::hessian`] serve both.
#[inline]
pub fn exact_joint<F, G, N>(
    r_ij: &Vector<3>,
    body_i: &RadialBody<'_, F>,
    body_j: &RadialBody<'_, G>,
    max_gap: f64,
    hessians: bool,
    nested: N,
) -> Option<ExactGap3>
where
    F: Radial,
    G: Radial,
    N: FnOnce() -> Option<ExactGap3>,
{
    match exact_joint_alone(r_ij, body_i, body_j, max_gap, hessians) {
        Joint::Found(e, _) => Some(e),
        Joint::Apart => None,
        Joint::Failed => {
            JOINT_FALLBACKS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            nested()
        }
    }
}

/// How [`exact_joint_alone`] ended.
// NOTE: `Found` is large (two support jets), the others empty; boxing it
// would allocate on every gap in the hot path, and the value is only
// returned and matched at once, never stored.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
pub enum Joint {
    /// Converged (a Newton step below [`JOINT_TOL`] on the normal and both
    /// support points; [`WARM_TOL`] or [`TAYLOR_TOL`] from a warm start),
    /// with where the iteration ended: its normal and support unit vectors
    /// (after a step below [`TAYLOR_TOL`], `y + δy`, unit to `O(len²)`),
    /// the next warm start ([`JointStart::memo`]).
    Found(ExactGap3, JointStart),
    /// `g(r̂) > max_gap` (cold: the pair is skipped, as by the nested
    /// solve), or a converged gap above `max_gap` ([`exact_joint_warm`]).
    Apart,
    /// `A` or `W` not positive definite at an iterate, a Newton step that
    /// did not shrink, or the iteration cap: [`exact_joint`] then runs the
    /// nested solve.
    Failed,
}

/// The joint iteration of [`exact_joint`] without the fallback.
pub fn exact_joint_alone<F, G>(
    r_ij: &Vector<3>,
    body_i: &RadialBody<'_, F>,
    body_j: &RadialBody<'_, G>,
    max_gap: f64,
    hessians: bool,
) -> Joint
where
    F: Radial,
    G: Radial,
{
    let u = unit_or_x(r_ij);
    // The nested solve's first evaluation, the same bits: both supports
    // searched to convergence at the line of centres, each from the
    // direction itself.
    let (ub_i, ub_j) = (body_i.to_body(&u), body_j.to_body(&-u));
    let fi = radial_search(&ub_i, &ub_i, &body_i.radial);
    let fj = radial_search(&ub_j, &ub_j, &body_j.radial);
    if u.dot(r_ij) - fi.value() - fj.value() > max_gap {
        return Joint::Apart;
    }
    match joint_iterate(
        r_ij, body_i, body_j, u, fi.at, fj.at, hessians, JOINT_TOL, 0.0,
    ) {
        Some((e, end)) => Joint::Found(e, end),
        None => Joint::Failed,
    }
}

/// Where a warm-started joint iteration begins ([`exact_joint_warm`]): the
/// normal and the two support points' unit vectors (each in its body's
/// frame), as a pair's last solve left them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointStart {
    /// The normal (world frame, unit).
    pub normal: Vector<3>,
    /// Body `i`'s support unit vector `y_i` (its frame; unit, or unit to
    /// `O(len²)` where a joint iteration ended from its linearisation,
    /// [`Joint::Found`]).
    pub y_i: Vector<3>,
    /// Body `j`'s support unit vector `y_j` (likewise).
    pub y_j: Vector<3>,
}

impl JointStart {
    /// What a pair keeps of the solve that ended at `e` (a [`jamkit_core::PairMemo`]'s
    /// numbers; [`JointStart::memo`] of the normal and the support unit
    /// vectors `y = Qᵀ p / |p|`, from the support points: a star-shaped
    /// body's support point is `ρ(y) y`), for bodies whose rotations have
    /// the columns `columns_i`, `columns_j`, at the separation `r_ij`. For a
    /// result of the cold solve; the joint iteration gives its own end
    /// ([`Joint::Found`]).
    pub fn remember(
        e: &ExactGap3,
        r_ij: &Vector<3>,
        columns_i: &[Vector<3>; 3],
        columns_j: &[Vector<3>; 3],
    ) -> [f64; MEMO_LEN] {
        let end = Self {
            normal: e.normal,
            y_i: in_frame(columns_i, &e.jet_i.point).normalize(),
            y_j: in_frame(columns_j, &e.jet_j.point).normalize(),
        };
        end.memo(r_ij, columns_i, columns_j)
    }

    /// The nine numbers of a [`jamkit_core::PairMemo`] for this start, at the
    /// separation `r_ij` and orientations `columns_i`, `columns_j`: the
    /// normal relative to the line of centres, `Q_iᵀ(|r| n − r)` (body `i`'s
    /// frame, scaled by the separation), and each support unit vector
    /// relative to its body's direction, `y_i − Q_iᵀ n` and `y_j + Q_jᵀ n`
    /// (body frames). So a pair that moved or turned as a whole starts
    /// where its optimum moved to ([`JointStart::recall`]). No
    /// normalisation: the numbers are differences of what the solve left.
    #[inline]
    pub fn memo(
        &self,
        r_ij: &Vector<3>,
        columns_i: &[Vector<3>; 3],
        columns_j: &[Vector<3>; 3],
    ) -> [f64; MEMO_LEN] {
        let n = &self.normal;
        let a = in_frame(columns_i, &(n * r_ij.norm() - r_ij));
        let di = self.y_i - in_frame(columns_i, n);
        let dj = self.y_j + in_frame(columns_j, n);
        [a[0], a[1], a[2], di[0], di[1], di[2], dj[0], dj[1], dj[2]]
    }

    /// The start [`JointStart::memo`] encoded, read at the separation
    /// `r_ij` and orientations `columns_i`, `columns_j`: `n₀ = m/|m|` with
    /// `m = r + Q_i Q_iᵀ(|r| n − r)`, `y_i ∝ Q_iᵀ n₀ + (y_i − Q_iᵀ n)`,
    /// `y_j ∝ −Q_jᵀ n₀ + (y_j + Q_jᵀ n)`, the last two formed from `m`
    /// times `|m|` (the same directions), so that the three
    /// normalisations wait on one square root, not on each other. `None`
    /// where a vector to normalise vanishes.
    #[inline]
    pub fn recall(
        memo: &[f64; MEMO_LEN],
        r_ij: &Vector<3>,
        columns_i: &[Vector<3>; 3],
        columns_j: &[Vector<3>; 3],
    ) -> Option<Self> {
        let v = |k: usize| Vector::<3>::new(memo[k], memo[k + 1], memo[k + 2]);
        let [c0, c1, c2] = columns_i;
        let m = r_ij + (c0 * memo[0] + c1 * memo[1] + c2 * memo[2]);
        let len = m.norm();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        Some(Self {
            normal: m / len,
            y_i: unit(in_frame(columns_i, &m) + v(3) * len)?,
            y_j: unit(v(6) * len - in_frame(columns_j, &m))?,
        })
    }
}

/// The cap `n·r̂ ≥ 1/2` about the line of centres, in which a warm
/// start's result is accepted ([`exact_warm`], [`exact_joint_warm`]);
/// empty at coincident centres.
#[derive(Clone, Copy)]
struct Cap {
    /// `r̂` ([`unit_or_x`]).
    r_hat: Vector<3>,
    /// `r > 0`.
    some: bool,
}

impl Cap {
    #[inline(always)]
    fn new(r_ij: &Vector<3>) -> Self {
        Self {
            r_hat: unit_or_x(r_ij),
            some: r_ij.norm() > 0.0,
        }
    }

    #[inline(always)]
    fn contains(&self, n: &Vector<3>) -> bool {
        self.some && n.dot(&self.r_hat) >= 0.5
    }
}

/// `r/|r|`, or `x̂` at `r = 0` (the solvers' start at coincident centres).
#[inline(always)]
fn unit_or_x(r: &Vector<3>) -> Vector<3> {
    let n = r.norm();
    if n > 0.0 { r / n } else { Vector::<3>::x() }
}

/// The joint iteration of [`exact_joint`] started at `start` instead of
/// the line of centres: the warm start of a pair whose last solve ended
/// near there ([`JointStart`]). The same iteration and safeguards as the
/// cold one, ended after a step below [`WARM_TOL`] (≤ 10⁻¹⁰ left in the
/// normal and both support points, ≤ 10⁻²⁰ in `h`) or, without
/// `hessians`, below [`TAYLOR_TOL`] from the linearisation (module
/// documentation, "The warm start"), whatever the start. The result is
/// accepted only where its normal (and the start's) lies in the cap
/// `n·r̂ ≥ 1/2` about the line of centres. There it is the maximum the
/// cold solve's ascent from `r̂` reaches when (a) the two support
/// functions' spreads over the sphere, `max s − min s`, add up to less
/// than `r/2` (then `g < g(r̂)` outside the cap, which the ascent never
/// leaves) and (b) `W` is positive definite on the cap (`g` is concave
/// along its great circles: one stationary point there). Near-spheres
/// near contact meet both: spreads `O(Δ R⁰)` against `r ≈ 2R⁰`, and
/// `W = S_i + S_j + g P` with radii of curvature `≈ R⁰` and `g ≥ −r/2 − O(Δ R⁰)`
/// on the cap. `Found` with a gap at most `max_gap`; `Apart` for a
/// converged gap above it (`h` is the maximum, so the pair is certainly
/// apart); `Failed` where the iteration fails or leaves the cap: the
/// caller then runs the cold solve.
pub fn exact_joint_warm<F, G>(
    r_ij: &Vector<3>,
    body_i: &RadialBody<'_, F>,
    body_j: &RadialBody<'_, G>,
    start: &JointStart,
    max_gap: f64,
    hessians: bool,
) -> Joint
where
    F: Radial,
    G: Radial,
{
    // The cap as `n·r ≥ |r|/2`: no division.
    let half = 0.5 * r_ij.norm();
    let in_cap = |n: &Vector<3>| half > 0.0 && n.dot(r_ij) >= half;
    if !in_cap(&start.normal) {
        return Joint::Failed;
    }
    let u = start.normal;
    let (ub_i, ub_j) = (body_i.to_body(&u), body_j.to_body(&-u));
    let (at_i, at_j) = (body_i.at(start.y_i, &ub_i), body_j.at(start.y_j, &ub_j));
    match joint_iterate(
        r_ij, body_i, body_j, u, at_i, at_j, hessians, WARM_TOL, TAYLOR_TOL,
    ) {
        Some((e, end)) if in_cap(&e.normal) => {
            if e.gap > max_gap {
                Joint::Apart
            } else {
                Joint::Found(e, end)
            }
        }
        _ => Joint::Failed,
    }
}

/// The joint iteration from the normal `u` and the supports' radial jets
/// `at_i`, `at_j` (read at `u` and `−u`), ended after a step below `tol`
/// (taken, both supports read at its end), or, without `hessians`, after
/// a step below `taylor` (taken, the supports moved along it to first
/// order and `h` from the second-order model, no further radial jet):
/// `None` where it fails (module documentation). With the result, where
/// it ended ([`Joint::Found`]). The step's `3 × 3` system is solved by
/// [`spd_inverse`] (one division, positive definiteness from the leading
/// minors), the step lengths compared squared: no square root but the
/// retractions'.
#[inline]
#[allow(clippy::too_many_arguments)]
fn joint_iterate<F, G>(
    r_ij: &Vector<3>,
    body_i: &RadialBody<'_, F>,
    body_j: &RadialBody<'_, G>,
    mut u: Vector<3>,
    mut at_i: At,
    mut at_j: At,
    hessians: bool,
    tol: f64,
    taylor: f64,
) -> Option<(ExactGap3, JointStart)>
where
    F: Radial,
    G: Radial,
{
    let (mut yi, mut yj) = (at_i.y, at_j.y);
    let (tol2, taylor2) = (tol * tol, taylor * taylor);
    let mut last2 = f64::INFINITY;
    let mut iterations = 0;
    loop {
        if iterations == JOINT_CAP {
            return None;
        }
        iterations += 1;
        let (ub_i, ub_j) = (body_i.to_body(&u), body_j.to_body(&-u));
        let li = linearise(body_i, &ub_i, &at_i)?;
        let lj = linearise(body_j, &ub_j, &at_j)?;
        let uu = u * u.transpose();
        let p = Matrix::<3>::identity() - uu;
        let g = u.dot(r_ij) - li.phi - lj.phi;
        // `P S P` by rank-one updates, `S = S̃_i + S̃_j`.
        let s = li.b * li.follow + lj.b * lj.follow;
        let (su, us) = (s * u, s.tr_mul(&u));
        let w = p * g + s - u * us.transpose() - su * u.transpose() + uu * u.dot(&su);
        let rhs = p * (r_ij - li.x + lj.x - li.b * li.n + lj.b * lj.n);
        let du = spd_inverse(&(w + uu))? * rhs;
        let du = du - u * u.dot(&du);
        let dyi = li.n + li.follow * du;
        let dyj = lj.n - lj.follow * du;
        let (dyi, dyj) = (dyi - yi * yi.dot(&dyi), dyj - yj * yj.dot(&dyj));
        let len2 = du
            .norm_squared()
            .max(dyi.norm_squared())
            .max(dyj.norm_squared());
        // No progress: a Newton step that does not shrink (it shrinks
        // quadratically near the optimum).
        if !len2.is_finite() || len2 > last2 {
            return None;
        }
        if len2 < taylor2 && !hessians {
            // `h = L + ½ ∇L·δ` (the quadratic model's stationary value),
            // `∇L·δ = d·δu − t_i·δy_i − t_j·δy_j`, and the surface points
            // moved by `R B δy`.
            let d = r_ij - li.x + lj.x;
            let gap = g + 0.5 * (d.dot(&du) - li.t.dot(&dyi) - lj.t.dot(&dyj));
            let u = along_sphere(&u, &du);
            let (x_i, x_j) = (li.x + li.b * dyi, lj.x + lj.b * dyj);
            let jet = |h: f64, point: Vector<3>| SupportJet3 {
                h,
                point,
                hess: Matrix::<3>::zeros(),
            };
            let end = JointStart {
                normal: u,
                y_i: yi + dyi,
                y_j: yj + dyj,
            };
            let e = ExactGap3 {
                normal: u,
                gap,
                jet_i: jet(u.dot(&x_i), x_i),
                jet_j: jet(-u.dot(&x_j), x_j),
                iterations,
                converged: true,
            };
            return Some((e, end));
        }
        let cut = if len2 > 0.09 { 0.3 / len2.sqrt() } else { 1.0 };
        u = along_sphere(&u, &(du * cut));
        yi = along_sphere(&yi, &(dyi * cut));
        yj = along_sphere(&yj, &(dyj * cut));
        let (ub_i, ub_j) = (body_i.to_body(&u), body_j.to_body(&-u));
        at_i = body_i.at(yi, &ub_i);
        at_j = body_j.at(yj, &ub_j);
        if len2 < tol2 {
            let jet_i = body_i.jet(&ub_i, at_i, hessians);
            let jet_j = body_j.jet(&ub_j, at_j, hessians);
            let e = ExactGap3 {
                normal: u,
                gap: u.dot(r_ij) - jet_i.h - jet_j.h,
                jet_i,
                jet_j,
                iterations,
                converged: true,
            };
            let end = JointStart {
                normal: u,
                y_i: yi,
                y_j: yj,
            };
            return Some((e, end));
        }
        last2 = len2;
    }
}

/// `∂²s(exp(−Σω e) v)/∂ω_p∂ω_q` at `ω = 0` for the support jet `jet` at
/// `v` (module documentation).
#[inline]
fn rotation_second(jet: &SupportJet3, v: &Vector<3>, e_p: &Vector<3>, e_q: &Vector<3>) -> f64 {
    let (tp, tq) = (e_p.cross(v), e_q.cross(v));
    let p = &jet.point;
    tp.dot(&(jet.hess * tq)) + 0.5 * (p.dot(e_q) * e_p.dot(v) + p.dot(e_p) * e_q.dot(v))
        - p.dot(v) * e_p.dot(e_q)
}

impl ExactGap3 {
    /// The contact: `∂h/∂r_j = n`, `∂h/∂ω_ip = e_p·(n × p_i)`,
    /// `∂h/∂ω_jp = −e_p·(n × p_j)`, for the first `m` of each body's
    /// rotation axes `axes_i`, `axes_j`.
    #[inline(always)]
    pub fn contact(
        &self,
        axes_i: &[Vector<3>; 3],
        axes_j: &[Vector<3>; 3],
        m: usize,
    ) -> Contact<3> {
        let n = &self.normal;
        let (ti, tj) = (n.cross(&self.jet_i.point), n.cross(&self.jet_j.point));
        let mut grad_rot_i: RotVec = [0.0; MAX_ROT];
        let mut grad_rot_j: RotVec = [0.0; MAX_ROT];
        for p in 0..m {
            grad_rot_i[p] = axes_i[p].dot(&ti);
            grad_rot_j[p] = -axes_j[p].dot(&tj);
        }
        Contact {
            gap: self.gap,
            grad_r: *n,
            grad_rot_i,
            grad_rot_j,
        }
    }

    /// `W = S_i(n) + S_j(−n) + h P` and its inverse on the tangent plane,
    /// `W⁺` (zero where `W` is not positive definite there).
    pub fn tangent_inverse(&self) -> Matrix<3> {
        let n = &self.normal;
        let nn = n * n.transpose();
        let w = self.jet_i.hess + self.jet_j.hess + (Matrix::<3>::identity() - nn) * self.gap;
        match (w + nn).cholesky() {
            Some(c) => {
                let inv = c.inverse() - nn;
                // Symmetrise: the two triangles agree to round-off.
                (inv + inv.transpose()) * 0.5
            }
            None => Matrix::<3>::zeros(),
        }
    }

    /// The gap with its first and second derivatives (module
    /// documentation), with the same contact as [`ExactGap3::contact`], bit
    /// for bit.
    pub fn hessian(
        &self,
        axes_i: &[Vector<3>; 3],
        axes_j: &[Vector<3>; 3],
        m: usize,
    ) -> GapHessian<3> {
        let n = self.normal;
        let contact = self.contact(axes_i, axes_j, m);
        let winv = self.tangent_inverse();
        let mut out = GapHessian::translational(self.gap, n, winv);
        out.contact = contact;
        let (pi, pj) = (self.jet_i.point, self.jet_j.point);
        let b_i: [Vector<3>; 3] = std::array::from_fn(|p| {
            let e = axes_i[p];
            -e.cross(&pi) + self.jet_i.hess * e.cross(&n)
        });
        let b_j: [Vector<3>; 3] = std::array::from_fn(|p| {
            let e = axes_j[p];
            e.cross(&pj) + self.jet_j.hess * e.cross(&n)
        });
        for p in 0..m {
            out.r_qi[p] = winv * b_i[p];
            out.r_qj[p] = winv * b_j[p];
        }
        for p in 0..m {
            for q in 0..m {
                out.qi_qi[p][q] = -rotation_second(&self.jet_i, &n, &axes_i[p], &axes_i[q])
                    + b_i[p].dot(&(winv * b_i[q]));
                out.qj_qj[p][q] = -rotation_second(&self.jet_j, &-n, &axes_j[p], &axes_j[q])
                    + b_j[p].dot(&(winv * b_j[q]));
                out.qi_qj[p][q] = b_i[p].dot(&(winv * b_j[q]));
            }
        }
        // Symmetrise the rotational blocks (the formulas are symmetric; the
        // products round differently).
        for p in 0..m {
            for q in p + 1..m {
                let a = 0.5 * (out.qi_qi[p][q] + out.qi_qi[q][p]);
                out.qi_qi[p][q] = a;
                out.qi_qi[q][p] = a;
                let b = 0.5 * (out.qj_qj[p][q] + out.qj_qj[q][p]);
                out.qj_qj[p][q] = b;
                out.qj_qj[q][p] = b;
            }
        }
        out
    }
}

/// The world axes, the rotation axes of a body whose three rotational
/// coordinates turn it in the world frame.
pub const WORLD_AXES: [Vector<3>; 3] = [
    Vector::<3>::new(1.0, 0.0, 0.0),
    Vector::<3>::new(0.0, 1.0, 0.0),
    Vector::<3>::new(0.0, 0.0, 1.0),
];

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::Quaternion;

    fn ellipsoid(q: &Quaternion, semi: [f64; 3]) -> QuadraticSupport {
        QuadraticSupport::new(&q.columns(), semi)
    }

    /// `∇s` and `∇∇s` of the quadratic support against central differences
    /// of `s` and `∇s` (ε = 1e-6: truncation ε²|s'''| ~ 1e-12, round-off
    /// 1e-16/ε ~ 1e-10; bound 1e-8), `S u = 0` and `p·u = s` to round-off.
    #[test]
    fn quadratic_support_derivatives() {
        let q = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let s = ellipsoid(&q, [0.4, 0.7, 1.3]);
        let e = 1e-6;
        for k in 0..20 {
            let x = k as f64;
            let u = Vector::<3>::new((x * 1.3).sin(), (x * 0.7).cos(), (x * 2.1).sin() + 0.1)
                .normalize();
            let j = s.jet(&u);
            assert_relative_eq!(j.point.dot(&u), j.h, epsilon = 1e-14);
            assert!((j.hess * u).norm() < 1e-14);
            for a in 0..3 {
                let mut d = Vector::<3>::zeros();
                d[a] = e;
                // Off the sphere: s is homogeneous, ∇s its gradient in ℝ³.
                let plus = |v: Vector<3>| v.dot(&(s.form * v)).sqrt();
                let fd = (plus(u + d) - plus(u - d)) / (2.0 * e);
                assert!((fd - j.point[a]).abs() < 1e-8);
                let grad = |v: Vector<3>| s.form * v / plus(v);
                let col = (grad(u + d) - grad(u - d)) / (2.0 * e);
                for b in 0..3 {
                    assert!((col[b] - j.hess[(b, a)]).abs() < 1e-8);
                }
            }
        }
    }

    /// `ρ(y) = (yᵀ M⁻¹ y)^{−1/2}`, the ellipsoid `{x : xᵀ M⁻¹ x ≤ 1}` as a
    /// radial function, with `∇ρ̃` and `∇∇ρ̃` written out (`q = yᵀAy`,
    /// `A = M⁻¹`): `g = q^{−1/2} y − q^{−3/2} A y` and
    /// `H = q^{−1/2} P − q^{−3/2}(y (Ay)ᵀ + (Ay) yᵀ + A) + 3 q^{−5/2} (Ay)(Ay)ᵀ`.
    fn ellipsoid_radial(
        form: &Matrix<3>,
    ) -> impl Fn(&Vector<3>) -> (f64, Vector<3>, Matrix<3>) + use<> {
        let a = form.try_inverse().unwrap();
        move |y: &Vector<3>| {
            let ay = a * y;
            let q = y.dot(&ay);
            let (q1, q3, q5) = (q.powf(-0.5), q.powf(-1.5), q.powf(-2.5));
            let p = Matrix::<3>::identity() - y * y.transpose();
            let cross = y * ay.transpose();
            let h =
                p * q1 - (cross + cross.transpose() + a) * q3 + ay * ay.transpose() * (3.0 * q5);
            (q1, y * q1 - ay * q3, h)
        }
    }

    /// The radial support search against the closed form of the same
    /// body: for ellipsoids of axis ratio up to 2 (far from the
    /// near-spheres it is built for, so the safeguards are exercised),
    /// turned, in 40 directions, started at `u`, `s`, `∇s` and `∇∇s` agree
    /// with [`QuadraticSupport::jet`] to 1e-12 (round-off of order-1
    /// numbers through a 3 × 3 inverse), converged in at most 12 steps.
    /// The search also finds the support point from a start far from it.
    #[test]
    fn radial_support_of_an_ellipsoid_is_its_support_function() {
        let q = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        for semi in [[0.4, 0.55, 0.8], [1.0, 1.05, 0.97]] {
            let e = ellipsoid(&q, semi);
            let radial = ellipsoid_radial(&e.form);
            for k in 0..40 {
                let x = k as f64;
                let u = Vector::<3>::new((x * 1.3).sin(), (x * 0.7).cos(), (x * 2.1).sin() + 0.1)
                    .normalize();
                let want = e.jet(&u);
                for start in [u, -u + Vector::<3>::new(0.3, 0.2, 0.1)] {
                    let got = radial_support(&u, &start, &radial);
                    assert!(got.converged, "{semi:?} {u:?}");
                    if start == u {
                        assert!(got.iterations <= 12, "{} steps", got.iterations);
                    }
                    assert_relative_eq!(got.jet.h, want.h, epsilon = 1e-12);
                    assert_relative_eq!(got.jet.point, want.point, epsilon = 1e-12);
                    assert_relative_eq!(got.jet.hess, want.hess, epsilon = 1e-12);
                }
            }
        }
    }

    /// Two balls (`M = R² 1`): `h = r − R_i − R_j`, normal along the line of
    /// centres, in one iteration, separated or overlapping.
    #[test]
    fn balls_give_the_sphere_gap() {
        let q = Quaternion::IDENTITY;
        let (a, b) = (ellipsoid(&q, [0.5; 3]), ellipsoid(&q, [0.7; 3]));
        for d in [
            Vector::<3>::new(0.9, -0.7, 0.3),
            Vector::<3>::new(0.3, 0.2, -0.4),
        ] {
            let e = exact(&d, |u| a.jet(u), |u| b.jet(u), f64::INFINITY).unwrap();
            assert!(e.converged);
            assert_relative_eq!(e.gap, d.norm() - 1.2, epsilon = 1e-15);
            assert_relative_eq!(e.normal, d.normalize(), epsilon = 1e-15);
        }
    }

    /// Aligned spheroids along the line of centres: tip to tip
    /// `r − a_i − a_j`, side by side `r − b_i − b_j`, separated and
    /// overlapping by less than the tips' radius of curvature (1e-14).
    #[test]
    fn aligned_spheroids() {
        let q = Quaternion::IDENTITY;
        let tip = ellipsoid(&q, [0.4, 0.4, 0.9]);
        let d = Vector::<3>::new(0.0, 0.0, 1.9);
        let e = exact(&d, |u| tip.jet(u), |u| tip.jet(u), f64::INFINITY).unwrap();
        assert_relative_eq!(e.gap, 0.1, epsilon = 1e-14);
        let d = Vector::<3>::new(0.0, 0.0, 1.75);
        let e = exact(&d, |u| tip.jet(u), |u| tip.jet(u), f64::INFINITY).unwrap();
        assert_relative_eq!(e.gap, -0.05, epsilon = 1e-14);
        let d = Vector::<3>::new(0.0, 0.95, 0.0);
        let e = exact(&d, |u| tip.jet(u), |u| tip.jet(u), f64::INFINITY).unwrap();
        assert_relative_eq!(e.gap, 0.15, epsilon = 1e-14);
    }

    /// An ellipsoid whose reference point is off its centre by `offset`
    /// (body frame): `s(u) = u·Q c + √(uᵀMu)`, a convex body *without*
    /// central symmetry (`s(−u) ≠ s(u)`), so that mixing up body `j`'s
    /// direction `−u` with `u` anywhere shows (for an ellipsoid about its
    /// centre `S(−u) = S(u)` and such a slip would pass).
    fn off_centre(
        q: &Quaternion,
        semi: [f64; 3],
        offset: Vector<3>,
    ) -> impl Fn(&Vector<3>) -> SupportJet3 {
        let e = ellipsoid(q, semi);
        let c = q.apply(&offset);
        move |u: &Vector<3>| {
            let j = e.jet(u);
            SupportJet3 {
                h: j.h + u.dot(&c),
                point: j.point + c,
                hess: j.hess,
            }
        }
    }

    /// The gap of two off-centre bodies at `r + z[0..3]`, body `i` turned
    /// by `exp(z[3..6])` and body `j` by `exp(z[6..9])` (world frame).
    fn off_centre_gap(z: &[f64]) -> ExactGap3 {
        let qi = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let qj = Quaternion::normalized(-0.7, 0.1, 0.4, 0.2).unwrap();
        let v = |k: usize| Vector::<3>::new(z[k], z[k + 1], z[k + 2]);
        let qi = Quaternion::exp(&v(3)).mul(&qi);
        let qj = Quaternion::exp(&v(6)).mul(&qj);
        let si = off_centre(&qi, [0.4, 0.55, 0.8], Vector::<3>::new(0.1, -0.05, 0.15));
        let sj = off_centre(&qj, [0.7, 0.5, 0.45], Vector::<3>::new(-0.12, 0.08, 0.05));
        let r = Vector::<3>::new(0.9, 0.7, -0.6) + v(0);
        exact(&r, si, sj, f64::INFINITY).unwrap()
    }

    /// The gradient in `z = (r_j, ω_i, ω_j)` (world axes, three each).
    fn off_centre_grad(g: &ExactGap3) -> [f64; 9] {
        let c = g.contact(&WORLD_AXES, &WORLD_AXES, 3);
        let mut v = [0.0; 9];
        for a in 0..3 {
            v[a] = c.grad_r[a];
            v[3 + a] = c.grad_rot_i[a];
            v[6 + a] = c.grad_rot_j[a];
        }
        v
    }

    /// The generic machinery on bodies without central symmetry, apart
    /// (`h > 0`) and overlapping (`h < 0`: the same bodies 0.45 closer):
    /// the optimum's geometry `r − p_i(n) + p_j(−n) = h n` (1e-12); the
    /// gradient (translation and both bodies' three world-frame rotations)
    /// against central differences of the gap (ε = 1e-6: truncation
    /// ~1e-12, round-off ~1e-10; bound 1e-8); every second derivative
    /// against central differences of the analytic gradient (ε = 1e-5:
    /// truncation ~1e-10, round-off ~1e-11; bound 1e-6). The gradient at
    /// `exp(ε e_b) Q` differentiated in `ε` is the Hessian of
    /// `h(exp(Σ z e) Q)` plus the commutator `½ (e_a × e_b)·∇_ω h` for two
    /// rotations of one body: the symmetric part is compared with the
    /// Hessian, the antisymmetric part with that term.
    #[test]
    fn bodies_without_central_symmetry() {
        for shift in [0.0, -0.45] {
            let dir = Vector::<3>::new(0.9, 0.7, -0.6).normalize() * shift;
            let at = |dz: &[f64; 9]| {
                let mut z = *dz;
                for a in 0..3 {
                    z[a] += dir[a];
                }
                off_centre_gap(&z)
            };
            let e = at(&[0.0; 9]);
            assert!(e.converged);
            assert_eq!(shift == 0.0, e.gap > 0.0, "h = {}", e.gap);
            let r = Vector::<3>::new(0.9, 0.7, -0.6) + dir;
            let closing = r - e.jet_i.point + e.jet_j.point - e.normal * e.gap;
            assert!(closing.norm() < 1e-12, "{closing:?}");
            let g0 = off_centre_grad(&e);
            let h = e.hessian(&WORLD_AXES, &WORLD_AXES, 3);
            assert_eq!(h.contact, e.contact(&WORLD_AXES, &WORLD_AXES, 3));
            let mut hm = [[0.0; 9]; 9];
            for a in 0..3 {
                for b in 0..3 {
                    hm[a][b] = h.rr[(a, b)];
                    hm[3 + a][3 + b] = h.qi_qi[a][b];
                    hm[6 + a][6 + b] = h.qj_qj[a][b];
                    hm[3 + a][6 + b] = h.qi_qj[a][b];
                    hm[6 + b][3 + a] = h.qi_qj[a][b];
                    hm[a][3 + b] = h.r_qi[b][a];
                    hm[3 + b][a] = h.r_qi[b][a];
                    hm[a][6 + b] = h.r_qj[b][a];
                    hm[6 + b][a] = h.r_qj[b][a];
                }
            }
            for a in 0..9 {
                let (mut p, mut m) = ([0.0; 9], [0.0; 9]);
                p[a] = 1e-6;
                m[a] = -1e-6;
                let fd = (at(&p).gap - at(&m).gap) / 2e-6;
                assert!(
                    (fd - g0[a]).abs() < 1e-8,
                    "∂h/∂z[{a}]: {} vs fd {fd}",
                    g0[a]
                );
            }
            let mut fd = [[0.0; 9]; 9];
            for b in 0..9 {
                let (mut p, mut m) = ([0.0; 9], [0.0; 9]);
                p[b] = 1e-5;
                m[b] = -1e-5;
                let (gp, gm) = (off_centre_grad(&at(&p)), off_centre_grad(&at(&m)));
                for a in 0..9 {
                    fd[a][b] = (gp[a] - gm[a]) / 2e-5;
                }
            }
            let body = |k: usize| k / 3;
            for a in 0..9 {
                for b in 0..9 {
                    let sym = 0.5 * (fd[a][b] + fd[b][a]);
                    assert!(
                        (sym - hm[a][b]).abs() < 1e-6,
                        "shift {shift}: ∂²h/∂z[{a}]∂z[{b}] {} vs fd {sym}",
                        hm[a][b]
                    );
                    let commutator = if body(a) == body(b) && body(a) > 0 {
                        let (ea, eb) = (WORLD_AXES[a % 3], WORLD_AXES[b % 3]);
                        let k = 3 * body(a);
                        let torque = Vector::<3>::new(g0[k], g0[k + 1], g0[k + 2]);
                        0.5 * ea.cross(&eb).dot(&torque)
                    } else {
                        0.0
                    };
                    let anti = 0.5 * (fd[a][b] - fd[b][a]);
                    assert!(
                        (anti - commutator).abs() < 1e-6,
                        "shift {shift}: antisymmetric part [{a}][{b}] {anti} vs {commutator}"
                    );
                }
            }
        }
    }

    /// A spheroid or ellipsoid of semi-axes `semi` turned by `q`, as a
    /// radial function in its own frame with its rotation's columns, and
    /// its closed-form support (world frame).
    fn radial_ellipsoid(
        q: &Quaternion,
        semi: [f64; 3],
    ) -> (
        [Vector<3>; 3],
        impl Fn(&Vector<3>) -> (f64, Vector<3>, Matrix<3>),
        QuadraticSupport,
    ) {
        let own = ellipsoid(&Quaternion::IDENTITY, semi);
        let form = own.form;
        (q.columns(), ellipsoid_radial(&form), ellipsoid(q, semi))
    }

    /// The joint iteration ([`exact_joint_alone`]) against the nested
    /// solve on the closed-form supports ([`exact`]) for spheroids
    /// (prolate and oblate, α up to 1.35) and a general ellipsoid, turned,
    /// along body `i`'s axis `±Q e_z`, 10⁻³ off it and generic, apart and
    /// overlapping: it converges without falling back, and the gap, the
    /// normal, the support points and every entry of the gap's Hessian
    /// agree to 1e-10 relative (both solvers stop within ~10⁻¹⁴ of the
    /// optimum; the Hessian goes through two 3 × 3 inverses). It takes
    /// at most 8 steps.
    #[test]
    fn joint_iteration_agrees_with_the_nested_solve_on_spheroids() {
        let qi = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let qj = Quaternion::normalized(-0.7, 0.1, 0.4, 0.2).unwrap();
        let pairs = [
            ([0.5, 0.5, 0.6], [0.6, 0.6, 0.5]),
            ([0.45, 0.45, 0.6], [0.7, 0.7, 0.52]),
            ([0.4, 0.55, 0.8], [0.7, 0.5, 0.45]),
        ];
        let mut checked = 0;
        for (semi_i, semi_j) in pairs {
            let (ci, ri, qsi) = radial_ellipsoid(&qi, semi_i);
            let (cj, rj, qsj) = radial_ellipsoid(&qj, semi_j);
            let (bi, bj) = (
                RadialBody {
                    columns: &ci,
                    radial: &ri,
                },
                RadialBody {
                    columns: &cj,
                    radial: &rj,
                },
            );
            let dirs = [
                qi.apply(&Vector::<3>::z()),
                -qi.apply(&Vector::<3>::z()),
                qi.apply(&Vector::<3>::new(1e-3, -2e-3, 1.0)).normalize(),
                Vector::<3>::new(0.5, -0.7, 0.6).normalize(),
                Vector::<3>::new(-0.9, 0.3, 0.45).normalize(),
            ];
            for d in dirs {
                let reach = qsi.jet(&d).h + qsj.jet(&-d).h;
                for delta in [-0.03, 0.04] {
                    let r = d * (reach + delta);
                    let want = exact(&r, |u| qsi.jet(u), |u| qsj.jet(u), f64::INFINITY).unwrap();
                    let Joint::Found(got, _) = exact_joint_alone(&r, &bi, &bj, f64::INFINITY, true)
                    else {
                        panic!("{semi_i:?} {semi_j:?} at {r:?}: the joint iteration failed");
                    };
                    assert!(got.iterations <= 8, "{} steps", got.iterations);
                    let close =
                        |a: f64, b: f64| (a - b).abs() <= 1e-10 * a.abs().max(b.abs()).max(1.0);
                    assert!(close(got.gap, want.gap), "h {} vs {}", got.gap, want.gap);
                    assert!((got.normal - want.normal).norm() < 1e-10);
                    assert!((got.jet_i.point - want.jet_i.point).norm() < 1e-10);
                    assert!((got.jet_j.point - want.jet_j.point).norm() < 1e-10);
                    let (hg, hw) = (
                        got.hessian(&WORLD_AXES, &WORLD_AXES, 3),
                        want.hessian(&WORLD_AXES, &WORLD_AXES, 3),
                    );
                    for a in 0..3 {
                        for b in 0..3 {
                            assert!(close(hg.rr[(a, b)], hw.rr[(a, b)]));
                            assert!(close(hg.qi_qi[a][b], hw.qi_qi[a][b]));
                            assert!(close(hg.qj_qj[a][b], hw.qj_qj[a][b]));
                            assert!(close(hg.qi_qj[a][b], hw.qi_qj[a][b]));
                            assert!(close(hg.r_qi[a][b], hw.r_qi[a][b]));
                            assert!(close(hg.r_qj[a][b], hw.r_qj[a][b]));
                        }
                    }
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 30);
    }

    /// The spheroids' semi-axes of the one-step tests: near-spheres
    /// (α ≤ 1.2) and more elongated ones (α up to 2).
    const ONE_STEP_PAIRS: [([f64; 3], [f64; 3]); 4] = [
        ([0.5, 0.5, 0.55], [0.6, 0.6, 0.57]),
        ([0.52, 0.55, 0.6], [0.66, 0.6, 0.7]),
        ([0.45, 0.45, 0.6], [0.7, 0.7, 0.52]),
        ([0.4, 0.55, 0.8], [0.7, 0.5, 0.45]),
    ];

    /// One joint step from a start off the optimum, as
    /// [`perturbed_starts`] takes it.
    struct OneStep {
        /// The nested solve's result on the closed-form supports.
        want: ExactGap3,
        /// Its support unit vectors `y_i`, `y_j` (body frames).
        y_want: [Vector<3>; 2],
        /// The joint iteration's result after its one step.
        got: ExactGap3,
        /// Its support unit vectors, from its support points.
        y_got: [Vector<3>; 2],
        /// The step's length: the largest move of the normal and the
        /// two support unit vectors.
        len: f64,
    }

    /// One step of [`joint_iterate`] (ended by `tol` or `taylor`, which
    /// must end it) from each start `ε` (in `eps`) off the optimum: for
    /// each pair of spheroids' semi-axes in `pairs` (rotated by two fixed
    /// quaternions), two directions and two separations (0.03 overlap,
    /// 0.02 apart), the normal and both support unit vectors of the
    /// nested solve's optimum turned by `ε` about three fixed axes; `f`
    /// gets each step.
    fn perturbed_starts(
        pairs: &[([f64; 3], [f64; 3])],
        eps: &[f64],
        tol: f64,
        taylor: f64,
        mut f: impl FnMut(&OneStep),
    ) {
        let qi = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let qj = Quaternion::normalized(-0.7, 0.1, 0.4, 0.2).unwrap();
        let turn = |v: &Vector<3>, axis: Vector<3>, eps: f64| {
            Quaternion::exp(&(axis.normalize() * eps)).apply(v)
        };
        let axes = [
            Vector::<3>::new(0.3, 0.8, -0.2),
            Vector::<3>::new(-0.6, 0.1, 0.7),
            Vector::<3>::new(0.2, -0.4, -0.9),
        ];
        for &(semi_i, semi_j) in pairs {
            let (ci, ri, qsi) = radial_ellipsoid(&qi, semi_i);
            let (cj, rj, qsj) = radial_ellipsoid(&qj, semi_j);
            let bi = RadialBody {
                columns: &ci,
                radial: &ri,
            };
            let bj = RadialBody {
                columns: &cj,
                radial: &rj,
            };
            for d in [
                Vector::<3>::new(0.5, -0.7, 0.6).normalize(),
                Vector::<3>::new(-0.9, 0.3, 0.45).normalize(),
            ] {
                let reach = qsi.jet(&d).h + qsj.jet(&-d).h;
                for delta in [-0.03, 0.02] {
                    let r = d * (reach + delta);
                    let want = exact(&r, |u| qsi.jet(u), |u| qsj.jet(u), f64::INFINITY).unwrap();
                    let yi_want = bi.to_body(&want.jet_i.point).normalize();
                    let yj_want = bj.to_body(&want.jet_j.point).normalize();
                    for &eps in eps {
                        let u0 = turn(&want.normal, axes[0], eps);
                        let yi0 = turn(&yi_want, axes[1], eps);
                        let yj0 = turn(&yj_want, axes[2], eps);
                        let (ub_i, ub_j) = (bi.to_body(&u0), bj.to_body(&-u0));
                        let (at_i, at_j) = (bi.at(yi0, &ub_i), bj.at(yj0, &ub_j));
                        let (got, _) =
                            joint_iterate(&r, &bi, &bj, u0, at_i, at_j, false, tol, taylor)
                                .expect("one step from near the optimum");
                        assert_eq!(got.iterations, 1);
                        let yi1 = bi.to_body(&got.jet_i.point).normalize();
                        let yj1 = bj.to_body(&got.jet_j.point).normalize();
                        let len = (got.normal - u0)
                            .norm()
                            .max((yi1 - yi0).norm())
                            .max((yj1 - yj0).norm());
                        f(&OneStep {
                            want,
                            y_want: [yi_want, yj_want],
                            got,
                            y_got: [yi1, yj1],
                            len,
                        });
                    }
                }
            }
        }
    }

    /// One joint step from a start `ε` off the optimum (normal and both
    /// support unit vectors turned by `ε` about fixed axes,
    /// `ε` = 10⁻² … 10⁻⁶) leaves at most `K len²` in each, `len` the
    /// step's length (the quadratic convergence [`WARM_TOL`] rests on):
    /// near-spheres (α ≤ 1.2) and the spheroids above, apart and
    /// overlapping, against the nested solve on the closed-form supports
    /// (~10⁻¹⁴ from the optimum, so only steps with `K len²` well above
    /// that are judged). `K` is measured below 1 (the largest printed);
    /// asserted ≤ 2.
    #[test]
    fn one_joint_step_leaves_at_most_k_len_squared() {
        let eps = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6];
        let (mut worst, mut judged): (f64, u32) = (0.0, 0);
        perturbed_starts(&ONE_STEP_PAIRS, &eps, f64::INFINITY, 0.0, |step| {
            let error = (step.got.normal - step.want.normal)
                .norm()
                .max((step.y_got[0] - step.y_want[0]).norm())
                .max((step.y_got[1] - step.y_want[1]).norm());
            if step.len * step.len > 1e-11 {
                worst = worst.max(error / (step.len * step.len));
                judged += 1;
            }
        });
        println!("largest K: {worst:.3} over {judged} steps");
        assert!(judged >= 40, "{judged} steps judged");
        assert!(worst <= 2.0, "K = {worst}");
    }

    /// The finish from the linearisation ([`TAYLOR_TOL`]): one step from a
    /// start `ε` off the optimum (as in the test above, `ε` = 10⁻² … 10⁻⁴),
    /// ended without reading the radial functions again, leaves at most
    /// `K₃ len³` in `h` (the quadratic model's stationary value) and
    /// `K₂ len²` in the normal and the support points (moved to first
    /// order), against the nested solve on the closed-form supports.
    /// Measured `K₃`, `K₂` are printed; asserted ≤ 5 and ≤ 2.
    #[test]
    fn the_taylor_finish_is_third_order_in_the_gap() {
        let pairs = [ONE_STEP_PAIRS[0], ONE_STEP_PAIRS[1], ONE_STEP_PAIRS[3]];
        let eps = [1e-2, 3e-3, 1e-3, 3e-4, 1e-4];
        let (mut k3, mut k2, mut judged): (f64, f64, u32) = (0.0, 0.0, 0);
        perturbed_starts(&pairs, &eps, 0.0, f64::INFINITY, |step| {
            let (got, want, len) = (&step.got, &step.want, step.len);
            let points = (got.normal - want.normal)
                .norm()
                .max((got.jet_i.point - want.jet_i.point).norm())
                .max((got.jet_j.point - want.jet_j.point).norm());
            k2 = k2.max(points / (len * len));
            k3 = k3.max((got.gap - want.gap).abs() / (len * len * len));
            judged += 1;
        });
        println!("largest K3 {k3:.3}, K2 {k2:.3} over {judged} steps");
        assert_eq!(judged, 60);
        assert!(k3 <= 5.0, "K3 = {k3}");
        assert!(k2 <= 2.0, "K2 = {k2}");
    }

    /// Where the joint iteration cannot work, it falls back: two flat
    /// oblate spheroids (semi-axes 1, 1, 0.2) side by side in one plane,
    /// overlapping rim to rim by 0.5, more than the rims' radius of
    /// curvature (0.04 across the plane), so that `W` is not positive
    /// definite at the line of centres. [`exact_joint_alone`] fails,
    /// [`exact_joint`] returns the nested solve's answer bit for bit and
    /// counts the fallback; that answer is the nested solve's on the
    /// closed-form supports (gap 1e-12, normal 1e-10).
    #[test]
    fn joint_iteration_falls_back_where_it_cannot_work() {
        let q = Quaternion::IDENTITY;
        let semi = [1.0, 1.0, 0.2];
        let (c, radial, closed) = radial_ellipsoid(&q, semi);
        let body = RadialBody {
            columns: &c,
            radial: &radial,
        };
        // Slightly off the plane, so that the side the normal turns to
        // is decided.
        let r = Vector::<3>::new(1.5, 0.0, 0.01);
        let nested = || {
            exact(
                &r,
                |u| radial_support(u, u, &radial).jet,
                |u| radial_support(u, u, &radial).jet,
                f64::INFINITY,
            )
        };
        assert!(matches!(
            exact_joint_alone(&r, &body, &body, f64::INFINITY, true),
            Joint::Failed
        ));
        let before = joint_fallbacks();
        let got = exact_joint(&r, &body, &body, f64::INFINITY, true, nested).unwrap();
        assert!(joint_fallbacks() > before);
        assert_eq!(got, nested().unwrap());
        let want = exact(&r, |u| closed.jet(u), |u| closed.jet(u), f64::INFINITY).unwrap();
        assert!(want.converged && got.converged);
        assert!(
            (got.gap - want.gap).abs() < 1e-12,
            "{} vs {}",
            got.gap,
            want.gap
        );
        assert!((got.normal - want.normal).norm() < 1e-10);
    }

    /// The solver's name is read with case ignored, and a wrong one is
    /// refused naming both allowed.
    #[test]
    fn exact_solver_names() {
        assert_eq!("joint".parse(), Ok(ExactSolver::Joint));
        assert_eq!("Nested".parse(), Ok(ExactSolver::Nested));
        let e = "Jointly".parse::<ExactSolver>().unwrap_err();
        assert!(
            e.contains("\"Nested\", \"Joint\"") && e.contains("Jointly"),
            "{e}"
        );
    }
}
