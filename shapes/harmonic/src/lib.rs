//! # Near-spheres with spherical-harmonic modes: the `harmonic` family (3D)
//!
//! The paper's model (Ikeda, near-disks `R(θ) = R⁰[1 + Δ sin(nθ)/n]`)
//! carried to three dimensions. A body of size `R⁰` and orientation `Q`
//! (a unit quaternion, the rotation from body to world frame) has the
//! radius
//!
//! ```text
//! R(û) = R⁰ [1 + Δ F(Qᵀ û)],     F = Σ_k c_k Ŷ_{l_k m_k},     l_k ≥ 2,
//! ```
//!
//! in the world direction `û`, where `Ŷ_lm` is the real spherical harmonic
//! of degree `l` and order `m` ([`solid`]: `m > 0` the `cos mφ` one, `m < 0`
//! the `sin |m|φ` one, `m = 0` the zonal `P_l(cos θ)`) scaled by a positive
//! factor so that **its largest slope on the sphere is 1**:
//! `max |∇_S Ŷ_lm| = 1`. This is the role `sin(nθ)/n` plays in 2D (its
//! slope `cos nθ` peaks at 1): the paper's `Δ` is the largest tilt of the
//! surface away from the sphere's, mode by mode. For example
//! `Ŷ_20 = (3 cos²θ − 1)/3` (prolate along the body `z` axis for `Δ > 0`:
//! poles at `1 + 2Δ/3`, waist at `1 − Δ/3`) and `Ŷ_22 = sin²θ cos 2φ / 2`.
//! `l = 1` is left out: to first order it is a shift of the centre.
//!
//! **Gap.** The paper's first-order gap (Ikeda, Eq. (8)) in 3D: each body's
//! radius along the line of centres,
//!
//! ```text
//! h_ij = r − R_i⁰ − R_j⁰ − Δ [R_i⁰ F(Q_iᵀ r̂) + R_j⁰ F(−Q_jᵀ r̂)],   r = |r_ij|, r̂ = r_ij / r,
//! ```
//!
//! exact to `O(Δ)` for convex bodies (the closest points leave the line of
//! centres at the next order). Write `G̃(x) = F(Qᵀ x/|x|)`, a function of
//! `x ∈ ℝ³` constant along rays. With `F = Σ_l P_l` split by degree (`P_l`
//! homogeneous of degree `l`, so `G̃ = Σ_l |x|^{−l} P_l(Qᵀx)`) and
//! `y = Qᵀ x/|x|`,
//!
//! ```text
//! ∇G̃ = Q Σ_l [∇P_l − l P_l y] / |x|,
//! ∇∇G̃ = Q Σ_l [∇∇P_l − l (∇P_l yᵀ + y ∇P_lᵀ) − l P_l 1 + l (l+2) P_l y yᵀ] Qᵀ / |x|².
//! ```
//!
//! A small rotation `ω` (world frame) of the body turns `Q` into
//! `exp(ω) Q`, so `G̃` is read at `exp(−ω) x`; along the rotation axes
//! `e_p`, with `t_p = −e_p × x`, `g = ∇G̃`, `H = ∇∇G̃`:
//!
//! ```text
//! ∂G̃/∂ω_p = g · t_p,     ∂²G̃/∂x∂ω_p = e_p × g + H t_p,
//! ∂²G̃/∂ω_p∂ω_q = t_pᵀ H t_q + ½[(g·e_q)(e_p·x) + (g·e_p)(e_q·x)] − (g·x)(e_p·e_q),
//! ```
//!
//! where `g·x = 0` (`G̃` is constant along rays), so the last term is
//! dropped.
//!
//! Body `i` enters with `x = r_ij`, body `j` with `x = −r_ij` (so the odd
//! derivatives in `r` change sign), each multiplied by `−Δ R⁰`; the gap of
//! a sphere adds `∂h/∂r_j = r̂` and `(1 − r̂ r̂ᵀ)/r`. The two bodies'
//! rotations do not mix (`∂²h/∂ω_i∂ω_j = 0`).
//!
//! **Exact gap** (`gap: "Exact"`; the default `"FirstOrder"` is the gap
//! above, bit for bit). The signed distance of two convex bodies along
//! their common normal, `h = max_u [u·r_ij − s_i(u) − s_j(−u)]`, with its
//! gradient and Hessian in positions and rotations by
//! [`jamkit_gap3d::exact`], from each body's support function: the
//! body-frame surface `x(y) = ρ(y) y`, `ρ = R⁰(1 + ΔF)`, has its support
//! point in the direction `u` where its normal is `u`, found by Newton's
//! method on the sphere ([`jamkit_gap3d::radial_support`], whose
//! documentation derives `s`, `∇s = ρ(y*) y*` and
//! `∇∇s = B A⁺ Bᵀ`, the inverse Weingarten map), each search started where
//! the body's previous one in the same gap ended ([`Harmonic::support`]
//! gives it for one direction). It needs a convex body:
//! [`Harmonic::new`] refuses `Exact`, naming `params.gap`, when the
//! convexity condition of [`Harmonic::is_convex`] fails anywhere on
//! [`CONVEXITY_GRID`] × 2·[`CONVEXITY_GRID`] directions, and refuses
//! `"SecondOrder"` (there is none in 3D).
//!
//! **Exact solver** (`exact_solver`, read with `gap: "Exact"` only).
//! `"Nested"` is the iteration above, cold. `"Joint"`, the default, runs
//! [`jamkit_gap3d::exact_joint`]: one Newton iteration on the normal and
//! both support points at once, on the same radial jets, falling back to
//! the nested solve where it fails (counted by
//! [`jamkit_gap3d::joint_fallbacks`]), and the engine's energy pass starts
//! each listed pair's solve where its last one ended
//! ([`Harmonic::exact_gap_warm`], [`jamkit_gap3d::exact_joint_warm`]): the
//! same optimum, in one or two steps after a small move, to a tolerance
//! set by the last step (≤ 10⁻¹⁰ in the normal and the support points,
//! ≤ 10⁻²⁰ in the gap; [`jamkit_gap3d::WARM_TOL`]), after a screen that
//! skips pairs certainly apart ([`Harmonic::gap_lower_bound`]); where `F`
//! is a quadratic form (every mode `l = 2`) it reads the radial jets in
//! closed form. The results agree with the nested solve's to ~10⁻¹⁰, not
//! bit for bit, so a packing made with `"Joint"` is a different (equally
//! valid) packing. A packing file records
//! `exact_solver` only where it is `"Joint"` and the gap exact, so files
//! of `"Nested"` packings are those written before the parameter existed
//! ([`jamkit_core::Added`]), and a file or run that records none reads
//! back as `"Nested"`.
//!
//! **Rotational coordinates.** Three (`ω` in the world frame, the nmer
//! convention: `Q → exp(ω) Q`), or two when `F` is axisymmetric (every mode
//! with a non-zero coefficient has `m = 0`): then the rotation about the
//! body axis moves nothing, and the two coordinates turn the axis about
//! `Q x̂` and `Q ŷ` (`Q → Q exp((dq₀, dq₁, 0))`, body frame). At `Δ = 0` the
//! registry runs the `sphere` family (no rotational coordinates, the same
//! random stream, hence the same packing bit for bit).
//!
//! **Volume** exact: `V = (4π/3)(R⁰)³ [1 + 3Δ⟨F⟩ + 3Δ²⟨F²⟩ + Δ³⟨F³⟩]`
//! with exact sphere averages of the polynomials (`⟨F⟩ = 0`).
//!
//! **Asphericity** `A = S³/(36π V²)` (1 for a sphere), to second order:
//! `A = 1 + (3/2) Δ² Σ_l (l − 1)(l + 2) ⟨P_l²⟩ + O(Δ³)` (the surface
//! `S = 4π(R⁰)²[1 + Δ²⟨F²⟩ + Δ²⟨|∇_S F|²⟩/2]` and
//! `⟨|∇_S P_l|²⟩ = l(l+1)⟨P_l²⟩`); [`Harmonic::asphericity`] integrates
//! it numerically at any `Δ`. For one mode `Ŷ_20`: `⟨Ŷ_20²⟩ = 4/45`, so
//! `A = 1 + (8/15) Δ²`.
//!
//! **Inertia.** Mass 1; every rotational coordinate has the moment of
//! inertia `I = Δ` by default, the paper's 2D choice carried over (the
//! minima do not depend on it, only FIRE's route); `inertia: x` sets it.
//!
//! **Rattlers and isostaticity.** The paper's convention carried to 3D: a
//! body with fewer than `d + 1 = 4` contacts is a rattler. Near-spheres jam
//! hypostatic, like near-disks: the isostatic count uses the body's real
//! coordinates, `f = 3 + rot_dof` (6, or 5 for an axisymmetric `F`).

pub mod solid;

use jamkit_core::Error;
use jamkit_core::gap_model::GapModel;
use jamkit_core::{
    Added, Contact, Dims, Family, FamilyInfo, GapHessian, Look, MAX_ROT, Matrix, NoFastPath, Pair,
    PairMemo, ParamSpec, Policy, Quaternion, RotVec, Shape, ShapeVisitor, Vector,
};
/// How the exact gap is solved (`exact_solver`).
pub use jamkit_gap3d::ExactSolver;
use jamkit_gap3d::{self as gap3d, ExactGap3, RadialSupport, SupportAt};
use serde::Deserialize;
use solid::{LMAX, Poly};
use std::cell::Cell;
use std::f64::consts::PI;

/// The family's self-description.
pub const INFO: FamilyInfo = FamilyInfo {
    name: "harmonic",
    about: "near-spheres R(û) = R0 [1 + Δ F(Qᵀû)], F a sum of real spherical harmonics Y_lm (l ≥ 2) each scaled to largest slope 1, with the paper's first-order gap or the exact gap of convex bodies (3D)",
    dims: Dims::Only(&[3]),
    params: &[
        ParamSpec {
            name: "l",
            about: "degree of a single mode Ŷ_lm, an integer in [2, 8]; give l (with m) or modes",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "m",
            about: "order of the single mode, an integer in [−l, l] (m > 0: cos mφ, m < 0: sin |m|φ); None: 0",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "modes",
            about: "list of (l: integer in [2, 8], m: integer in [−l, l], c: coefficient), each (l, m) once: F = Σ c Ŷ_lm",
            is_list: true,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "delta",
            about: "Δ ≥ 0, the amplitude; 0 gives spheres (the sphere family)",
            is_list: false,
            default: None,
            added: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia of every rotational coordinate; None: I = Δ (the paper's 2D choice)",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "gap",
            about: "gap model, a string: \"FirstOrder\" (the paper's, error O(Δ²)) or \"Exact\" (signed distance along the common normal from the support functions; convex bodies only); None: FirstOrder",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "exact_solver",
            about: "how the exact gap is solved, a string: \"Joint\" (one Newton iteration on the normal and both support points, each listed pair started where its last solve ended, the nested solve where it fails) or \"Nested\" (a Newton iteration on the normal, both support searches converged at each of its steps, from the line of centres); the same optimum to 1e-14, not the same bits; read with gap \"Exact\" only; a packing that records none was made with \"Nested\"",
            is_list: false,
            default: Some("\"Joint\""),
            added: Some(Added {
                before: "\"Nested\"",
                read_with: Some(("gap", "\"Exact\"")),
            }),
        },
    ],
};

/// How finely [`Harmonic::new`] samples the surface (`n × 2n` directions)
/// before it accepts the exact gap.
pub const CONVEXITY_GRID: usize = 64;

/// One mode `c Ŷ_lm`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mode {
    /// Degree `l ≥ 2`.
    pub l: u32,
    /// Order `m`, `|m| ≤ l`.
    pub m: i32,
    /// Coefficient.
    pub c: f64,
}

/// Parameters of `harmonic`, as read from an experiment file. Exactly one
/// of `l` (a single mode `Ŷ_lm`, coefficient 1) and `modes` is given.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HarmonicParams {
    /// Degree of the single mode.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub l: Option<u32>,
    /// Order of the single mode (`None`: 0).
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub m: Option<i32>,
    /// The modes of a sum.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub modes: Option<Vec<Mode>>,
    /// Amplitude `Δ`.
    pub delta: f64,
    /// Moment of inertia (`None`: `Δ`).
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub inertia: Option<f64>,
    /// The gap model (default: the paper's first order).
    #[serde(
        default,
        deserialize_with = "jamkit_core::gap_model::deserialize_first_or_exact"
    )]
    pub gap: GapModel,
    /// How the exact gap is solved; read with `gap: "Exact"` only. An
    /// experiment that does not give it runs `Joint` (the default the
    /// experiment layer fills in); a missing key reads as `Nested`, what a
    /// packing that records none was made with ([`jamkit_core::Added`]).
    #[serde(default, deserialize_with = "deserialize_exact_solver")]
    pub exact_solver: ExactSolver,
}

/// Read `exact_solver`: a string, `"Nested"` or `"Joint"` (case ignored),
/// or `None`/absent for `Nested` (a packing's record). A bare RON identifier reaches a family
/// without its name and is refused with how to write it.
fn deserialize_exact_solver<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<ExactSolver, D::Error> {
    jamkit_core::family::deserialize_named(
        d,
        ExactSolver::Nested,
        |s| {
            s.parse()
                .map_err(|e: String| format!("params.exact_solver: {e}"))
        },
        || {
            "params.exact_solver: write the solver as a string, exact_solver: \"Joint\" (allowed: \"Nested\", \"Joint\")".to_string()
        },
    )
}

/// The `harmonic` family's registration.
pub struct HarmonicFamily;

impl Family for HarmonicFamily {
    const INFO: FamilyInfo = INFO;
    const EXAMPLE: &'static str =
        "(modes: [(l: 2, m: 0, c: 1.0), (l: 3, m: 2, c: 0.5)], delta: 0.15)";
    type Params = HarmonicParams;

    /// `Δ = 0`: spheres, run as the `sphere` family (no rotational
    /// coordinates, the same random stream: the same packing for the same
    /// seed). The parameters are checked first.
    fn visit<V: ShapeVisitor>(
        p: &HarmonicParams,
        dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        let shape = Harmonic::new(p)?;
        match (dim, p.delta == 0.0) {
            (3, true) => jamkit_sphere::visit_ball(3, visitor),
            (3, false) => Ok(visitor.visit::<3, _>(shape)),
            _ => Err(Error::invalid(
                "dim",
                dim,
                "harmonic bodies exist in dim 3 only",
            )),
        }
    }
}

/// Near-spheres `R(û) = R⁰[1 + Δ F(Qᵀû)]` (crate documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Harmonic {
    delta: f64,
    modes: Vec<Mode>,
    /// `F` split by degree: `(l, P_l)`, each `P_l` homogeneous of degree `l`
    /// with the coefficients and slope normalisations folded in.
    by_degree: Vec<(u32, Poly)>,
    /// Every mode with a non-zero coefficient has `m = 0`.
    axisymmetric: bool,
    /// A certain upper bound on `|F|` on the sphere.
    f_bound: f64,
    /// `M` with `F(y) = yᵀ M y` on the sphere, where every mode has
    /// `l = 2` (`F` is then a quadratic form): the joint solve's radial
    /// jets in closed form ([`Harmonic::joint_jet`]).
    quadratic: Option<Matrix<3>>,
    /// `Σ|c|`, slightly raised: a bound on the slope `|∇_S F|` (each mode
    /// is scaled to slope `|c|`).
    f_slope: f64,
    /// `⟨P_l²⟩` for each degree (same order as `by_degree`).
    mean_squares: Vec<f64>,
    /// `V / (R⁰)³`.
    unit_volume: f64,
    inertia: f64,
    gap: GapModel,
    exact_solver: ExactSolver,
}

/// The value and derivatives of one body's term `G̃(x) = F(Qᵀx/|x|)` and
/// of its dependence on the body's rotation (crate documentation), at
/// `x` and zero rotation.
#[derive(Clone, Copy, Debug)]
struct BodyJet {
    /// `∇_x∇_x G̃`.
    hess: Matrix<3>,
    /// `∂²G̃/∂x∂q_p`.
    x_rot: [Vector<3>; MAX_ROT],
    /// `∂²G̃/∂q_p∂q_q`.
    rot_rot: [RotVec; MAX_ROT],
}

/// A body's support found in its own frame ([`gap3d::RadialFound`]), read
/// in the world frame: value and support point at once, the Hessian
/// `R ∇∇s Rᵀ` when [`gap3d::exact_with`] asks for it.
#[derive(Clone, Copy, Debug)]
struct WorldSupport {
    body: gap3d::RadialFound,
    columns: [Vector<3>; 3],
    point: Vector<3>,
}

impl gap3d::SupportAt for WorldSupport {
    #[inline(always)]
    fn value(&self) -> f64 {
        self.body.value()
    }
    #[inline(always)]
    fn point(&self) -> Vector<3> {
        self.point
    }
    #[inline(always)]
    fn hess(&self) -> Matrix<3> {
        let rot = Matrix::<3>::from_columns(&self.columns);
        rot * self.body.hess() * rot.transpose()
    }
}

impl Harmonic {
    /// Build and check the shape. Refused with the field named: both or
    /// neither of `l` and `modes`; `m` without `l`; `l` outside `[2, 8]`;
    /// `|m| > l`; a coefficient not finite; an `(l, m)` given twice; no
    /// modes; `Δ` negative or not finite, or so large that `R` may reach 0
    /// (`Δ Σ|c| max|Ŷ| ≥ 1`); an inertia not positive and finite (the
    /// default `I = Δ` needs `Δ > 0`; at `Δ = 0` it is 1 and unused).
    pub fn new(p: &HarmonicParams) -> jamkit_core::Result<Self> {
        if !(p.delta.is_finite() && p.delta >= 0.0) {
            return Err(Error::invalid(
                "params.delta",
                p.delta,
                "must be a finite number ≥ 0",
            ));
        }
        let modes = match (&p.l, &p.modes) {
            (Some(_), Some(_)) => {
                return Err(Error::invalid(
                    "params.l",
                    "given together with params.modes",
                    "give either l (and m) for one mode, or modes: [(l, m, c), ...], not both",
                ));
            }
            (None, None) => {
                return Err(Error::invalid(
                    "params",
                    "neither l nor modes",
                    "give l (a single mode Ŷ_lm, with m, default 0) or modes: [(l: 2, m: 0, c: 1.0), ...]",
                ));
            }
            (Some(l), None) => vec![Mode {
                l: *l,
                m: p.m.unwrap_or(0),
                c: 1.0,
            }],
            (None, Some(list)) => {
                if let Some(m) = p.m {
                    return Err(Error::invalid(
                        "params.m",
                        m,
                        "belongs with l (a single mode); with modes give m inside each mode",
                    ));
                }
                list.clone()
            }
        };
        if modes.is_empty() {
            return Err(Error::invalid(
                "params.modes",
                "[]",
                "must list at least one mode (l, m, c)",
            ));
        }
        let single = p.l.is_some();
        for (k, md) in modes.iter().enumerate() {
            let (fl, fm) = if single {
                ("params.l".to_string(), "params.m".to_string())
            } else {
                (
                    format!("params.modes[{k}].l"),
                    format!("params.modes[{k}].m"),
                )
            };
            if !(2..=LMAX).contains(&md.l) {
                return Err(Error::invalid(
                    fl,
                    md.l,
                    format!(
                        "must be an integer in [2, {LMAX}] (l = 0 is the size, l = 1 a shift of the centre)"
                    ),
                ));
            }
            if md.m.unsigned_abs() > md.l {
                return Err(Error::invalid(
                    fm,
                    md.m,
                    format!("must be an integer in [−l, l] = [−{0}, {0}]", md.l),
                ));
            }
            if !md.c.is_finite() {
                return Err(Error::invalid(
                    format!("params.modes[{k}].c"),
                    md.c,
                    "must be finite",
                ));
            }
            if modes[..k].iter().any(|o| (o.l, o.m) == (md.l, md.m)) {
                return Err(Error::invalid(
                    format!("params.modes[{k}]"),
                    format!("(l: {}, m: {})", md.l, md.m),
                    "is given twice: list each (l, m) once (add the coefficients)",
                ));
            }
        }
        let mut by_degree: Vec<(u32, Poly)> = Vec::new();
        let mut f_bound = 0.0;
        // The scan's largest slope is each mode's to ~10⁻¹³ (relative);
        // 10⁻⁹ more covers it.
        let f_slope = modes.iter().map(|md| md.c.abs()).sum::<f64>() * (1.0 + 1e-9);
        for md in &modes {
            let raw = Poly::solid_harmonic(md.l, md.m);
            let (slope, bound) = raw.max_slope_and_bound(md.m);
            let scaled = raw.scaled(md.c / slope);
            f_bound += md.c.abs() * bound / slope;
            match by_degree.iter_mut().find(|(l, _)| *l == md.l) {
                Some((_, p)) => *p = p.add(&scaled),
                None => by_degree.push((md.l, scaled)),
            }
        }
        by_degree.sort_by_key(|(l, _)| *l);
        if p.delta * f_bound >= 1.0 {
            return Err(Error::invalid(
                "params.delta",
                p.delta,
                format!(
                    "is so large that R may reach 0: Δ Σ|c| max|Ŷ| = {:.4} must be < 1 (Δ < {:.4})",
                    p.delta * f_bound,
                    1.0 / f_bound
                ),
            ));
        }
        let inertia = p
            .inertia
            .unwrap_or(if p.delta > 0.0 { p.delta } else { 1.0 });
        if !(inertia > 0.0 && inertia.is_finite()) {
            return Err(Error::invalid(
                "params.inertia",
                inertia,
                "must be positive and finite (the default I = Δ needs Δ > 0)",
            ));
        }
        let f: Poly = by_degree
            .iter()
            .fold(Poly::default(), |acc, (_, p)| acc.add(p));
        let f2 = f.mul(&f);
        let (m1, m2, m3) = (f.sphere_mean(), f2.sphere_mean(), f2.mul(&f).sphere_mean());
        let d = p.delta;
        let unit_volume = 4.0 * PI / 3.0 * (1.0 + 3.0 * d * m1 + 3.0 * d * d * m2 + d * d * d * m3);
        let mean_squares = by_degree
            .iter()
            .map(|(_, p)| p.mul(p).sphere_mean())
            .collect();
        let quadratic = match by_degree.as_slice() {
            [(2, p)] => {
                let mut m = Matrix::<3>::zeros();
                for (c, e) in p.terms() {
                    let axes: Vec<usize> = (0..3).flat_map(|a| (0..e[a]).map(move |_| a)).collect();
                    let (a, b) = (axes[0], axes[1]);
                    if a == b {
                        m[(a, a)] += c;
                    } else {
                        m[(a, b)] += 0.5 * c;
                        m[(b, a)] += 0.5 * c;
                    }
                }
                Some(m)
            }
            _ => None,
        };
        let shape = Self {
            quadratic,
            delta: d,
            axisymmetric: modes.iter().all(|md| md.m == 0 || md.c == 0.0),
            modes,
            by_degree,
            f_bound,
            f_slope,
            mean_squares,
            unit_volume,
            inertia,
            gap: GapModel::FirstOrder,
            exact_solver: p.exact_solver,
        };
        shape.with_gap(p.gap)
    }

    /// The single mode `Y_l^m` of amplitude `delta`, with the default
    /// inertia and the first-order gap.
    pub fn single(l: u32, m: i32, delta: f64) -> jamkit_core::Result<Self> {
        Self::new(&HarmonicParams {
            l: Some(l),
            m: Some(m),
            modes: None,
            delta,
            inertia: None,
            gap: GapModel::FirstOrder,
            exact_solver: ExactSolver::Nested,
        })
    }

    /// The same body with the gap model `gap`. Refused with the field
    /// named: `SecondOrder` (no second-order gap in 3D), and `Exact` for a
    /// body that is not convex on the [`CONVEXITY_GRID`] sample of
    /// directions ([`Harmonic::is_convex`]).
    pub fn with_gap(mut self, gap: GapModel) -> jamkit_core::Result<Self> {
        if gap == GapModel::SecondOrder {
            return Err(Error::invalid(
                "params.gap",
                "SecondOrder",
                "\"FirstOrder\" (default) or \"Exact\": harmonic has no second-order gap",
            ));
        }
        if gap == GapModel::Exact && !self.is_convex(CONVEXITY_GRID) {
            return Err(Error::invalid(
                "params.gap",
                "Exact",
                format!(
                    "needs a convex body, and Δ = {} makes this one non-convex (its curvature changes sign on a {} × {} grid of directions; the common normal is then not unique); use \"FirstOrder\" or a smaller Δ",
                    self.delta,
                    CONVEXITY_GRID,
                    2 * CONVEXITY_GRID
                ),
            ));
        }
        self.gap = gap;
        Ok(self)
    }

    /// The gap model.
    pub fn gap_model(&self) -> GapModel {
        self.gap
    }

    /// The same body with the exact gap solved by `solver` (read only with
    /// the exact gap).
    pub fn with_exact_solver(mut self, solver: ExactSolver) -> Self {
        self.exact_solver = solver;
        self
    }

    /// How the exact gap is solved.
    pub fn exact_solver(&self) -> ExactSolver {
        self.exact_solver
    }

    /// `Δ`.
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// The modes.
    pub fn modes(&self) -> &[Mode] {
        &self.modes
    }

    /// Whether `F` is axisymmetric (two rotational coordinates).
    pub fn is_axisymmetric(&self) -> bool {
        self.axisymmetric
    }

    /// A certain upper bound on `|F|` on the unit sphere.
    pub fn f_bound(&self) -> f64 {
        self.f_bound
    }

    /// `F(y)` at the body-frame unit vector `y`.
    pub fn f(&self, y: &Vector<3>) -> f64 {
        self.by_degree.iter().map(|(_, p)| p.value(y)).sum()
    }

    /// A lower bound on the exact gap `h` of a pair (sizes `size_i`,
    /// `size_j`, rotations with the columns `ci`, `cj`, separation `r_ij`)
    /// from the radial functions at any unit vector `n` alone:
    /// `h ≥ g(n) ≥ n·r_ij − ρ_i(n) − ρ_j(−n) − m_i − m_j`, with the margins
    /// `m = π² G² / (16 ρ_min)` of [`gap3d::radial_support_bound`]
    /// (`G = R⁰ Δ Σ|c|`, `ρ_min = R⁰(1 − Δ f_bound)`).
    pub fn gap_lower_bound(
        &self,
        size_i: f64,
        ci: &[Vector<3>; 3],
        size_j: f64,
        cj: &[Vector<3>; 3],
        r_ij: &Vector<3>,
        n: &Vector<3>,
    ) -> f64 {
        let support = |size: f64, c: &[Vector<3>; 3], v: &Vector<3>| {
            let y = Vector::<3>::new(c[0].dot(v), c[1].dot(v), c[2].dot(v));
            let rho = size * (1.0 + self.delta * self.f_fast(&y));
            gap3d::radial_support_bound(
                rho,
                size * self.delta * self.f_slope,
                size * (1.0 - self.delta * self.f_bound),
            )
        };
        n.dot(r_ij) - support(size_i, ci, n) - support(size_j, cj, &-n)
    }

    /// The tangential gradient `∇_S F` at the body-frame unit vector `y`.
    pub fn surface_gradient(&self, y: &Vector<3>) -> Vector<3> {
        let g: Vector<3> = self.by_degree.iter().map(|(_, p)| p.jet(y, false).1).sum();
        g - y * y.dot(&g)
    }

    /// `R(û)/R⁰` for a body with orientation `o`, in the world direction `u`
    /// (a unit vector).
    pub fn relative_radius(&self, o: &Quaternion, u: &Vector<3>) -> f64 {
        1.0 + self.delta * self.f(&o.apply_inverse(u))
    }

    /// `V/(R⁰)³`, exact.
    pub fn unit_volume(&self) -> f64 {
        self.unit_volume
    }

    /// `⟨F²⟩`, the sphere average (exact).
    pub fn mean_square(&self) -> f64 {
        self.mean_squares.iter().sum()
    }

    /// Whether the body is convex, sampled on the Gauss–Legendre ×
    /// trapezoid grid of `n × 2n` directions. A star-shaped surface
    /// `ρ(ŷ) ŷ` (`ρ = 1 + ΔF`) is convex where the tangential matrix
    /// `ρ² 1 + 2 ∇_Sρ ∇_Sρᵀ − ρ ∇_S∇_Sρ` is positive definite (the 3D form
    /// of the planar `r² + 2r'² − r r'' > 0`; for an axisymmetric body its
    /// two eigenvalues are the meridian's condition and the parallels'
    /// `ρ(ρ − ρ' cot θ) > 0`). `∇_S∇_S F` is the tangential block of the
    /// Hessian of `F(x/|x|)`, constant along rays.
    pub fn is_convex(&self, n: usize) -> bool {
        let (nodes, _) = gauss_legendre(n);
        let frame = [Vector::<3>::x(), Vector::<3>::y(), Vector::<3>::z()];
        nodes.iter().all(|z| {
            let s = (1.0 - z * z).sqrt();
            (0..2 * n).all(|k| {
                let phi = PI * k as f64 / n as f64;
                let (sp, cp) = phi.sin_cos();
                let y = Vector::<3>::new(s * cp, s * sp, *z);
                let e1 = Vector::<3>::new(z * cp, z * sp, -s);
                let e2 = Vector::<3>::new(-sp, cp, 0.0);
                let (f, g, _) = self.value_grad(&frame, &y, 1.0);
                let h = self.body_jet(&frame, &frame, 0, &y, 1.0).hess;
                let rho = 1.0 + self.delta * f;
                let (g1, g2) = (self.delta * g.dot(&e1), self.delta * g.dot(&e2));
                let m11 = rho * rho + 2.0 * g1 * g1 - rho * self.delta * e1.dot(&(h * e1));
                let m22 = rho * rho + 2.0 * g2 * g2 - rho * self.delta * e2.dot(&(h * e2));
                let m12 = 2.0 * g1 * g2 - rho * self.delta * e1.dot(&(h * e2));
                m11 > 0.0 && m11 * m22 - m12 * m12 > 0.0
            })
        })
    }

    /// The asphericity `A = S³/(36π V²)` to second order in `Δ`:
    /// `1 + (3/2) Δ² Σ_l (l − 1)(l + 2) ⟨P_l²⟩`.
    pub fn asphericity_second_order(&self) -> f64 {
        let s: f64 = self
            .by_degree
            .iter()
            .zip(&self.mean_squares)
            .map(|((l, _), m)| ((*l as f64) - 1.0) * (*l as f64 + 2.0) * m)
            .sum();
        1.0 + 1.5 * self.delta * self.delta * s
    }

    /// The asphericity `A = S³/(36π V²)` at this `Δ`, with the surface
    /// `S = ∫ R √(R² + |∇_S R|²) dΩ` by Gauss–Legendre quadrature in
    /// `cos θ` (`n` nodes) and the trapezoid rule in `φ` (`2n` points),
    /// both spectrally accurate for this smooth integrand, and the exact
    /// volume.
    pub fn asphericity(&self, n: usize) -> f64 {
        let (nodes, weights) = gauss_legendre(n);
        let mut area = 0.0;
        for (z, w) in nodes.iter().zip(&weights) {
            let s = (1.0 - z * z).sqrt();
            for k in 0..2 * n {
                let phi = PI * k as f64 / n as f64;
                let y = Vector::<3>::new(s * phi.cos(), s * phi.sin(), *z);
                let r = 1.0 + self.delta * self.f(&y);
                let g = self.delta * self.surface_gradient(&y).norm();
                area += w * (PI / n as f64) * r * (r * r + g * g).sqrt();
            }
        }
        area.powi(3) / (36.0 * PI * self.unit_volume * self.unit_volume)
    }

    /// `G̃(x) = F(Qᵀx/|x|)` and `∇G̃` in the world frame (crate
    /// documentation), with `columns` those of `R(Q)`; also the body-frame
    /// direction `y = Qᵀx/|x|`. The first-derivative path of the pair loop;
    /// [`Harmonic::body_jet`] adds the second derivatives to the same bits.
    #[inline(always)]
    fn value_grad(
        &self,
        columns: &[Vector<3>; 3],
        x: &Vector<3>,
        inv_r: f64,
    ) -> (f64, Vector<3>, Vector<3>) {
        let [c0, c1, c2] = columns;
        let u = x * inv_r;
        let y = Vector::<3>::new(c0.dot(&u), c1.dot(&u), c2.dot(&u));
        let mut value = 0.0;
        let mut gb = Vector::<3>::zeros();
        for (l, p) in &self.by_degree {
            let (v, g) = p.value_grad(&y);
            value += v;
            gb += g - y * (*l as f64 * v);
        }
        let grad = (c0 * gb[0] + c1 * gb[1] + c2 * gb[2]) * inv_r;
        (value, grad, y)
    }

    /// `G̃(x) = F(Qᵀx/|x|)` and all its derivatives (crate documentation),
    /// with `axes` the rotation axes `e_p` and `m` the number of rotational
    /// coordinates.
    fn body_jet(
        &self,
        columns: &[Vector<3>; 3],
        axes: &[Vector<3>; 3],
        m: usize,
        x: &Vector<3>,
        inv_r: f64,
    ) -> BodyJet {
        let (_, grad, y) = self.value_grad(columns, x, inv_r);
        let (_, _, hb) = self.unit_jet(&y);
        let mut jet = BodyJet {
            hess: Matrix::<3>::zeros(),
            x_rot: [Vector::<3>::zeros(); MAX_ROT],
            rot_rot: [[0.0; MAX_ROT]; MAX_ROT],
        };
        let rot_m = Matrix::<3>::from_columns(columns);
        let hess = rot_m * hb * rot_m.transpose() * (inv_r * inv_r);
        jet.hess = hess;
        let t: [Vector<3>; 3] = std::array::from_fn(|p| x.cross(&axes[p]));
        for p in 0..m {
            jet.x_rot[p] = axes[p].cross(&grad) + hess * t[p];
        }
        for p in 0..m {
            for q in p..m {
                let w = t[p].dot(&(hess * t[q]))
                    + 0.5
                        * (grad.dot(&axes[q]) * axes[p].dot(x)
                            + grad.dot(&axes[p]) * axes[q].dot(x));
                jet.rot_rot[p][q] = w;
                jet.rot_rot[q][p] = w;
            }
        }
        jet
    }

    /// `F̃`, `∇F̃` and `∇∇F̃` at the body-frame unit vector `y`, with
    /// `F̃(x) = F(x/|x|)` (crate documentation, `Q = 1`, `|x| = 1`).
    #[inline(always)]
    fn unit_jet(&self, y: &Vector<3>) -> (f64, Vector<3>, Matrix<3>) {
        let mut value = 0.0;
        let mut grad = Vector::<3>::zeros();
        let mut hb = Matrix::<3>::zeros();
        for (l, p) in &self.by_degree {
            let lf = *l as f64;
            let (v, g, h) = p.jet(y, true);
            value += v;
            grad += g - y * (lf * v);
            let gy = g * y.transpose();
            hb += h - (gy + gy.transpose()) * lf - Matrix::<3>::identity() * (lf * v)
                + y * y.transpose() * (lf * (lf + 2.0) * v);
        }
        (value, grad, hb)
    }

    /// [`Harmonic::radial_jet`] as the joint solve reads it: where `F` is
    /// the quadratic form `yᵀ M y` (every mode `l = 2`), in closed form,
    /// `F̃ = v = yᵀMy`, `∇F̃ = 2(My − v y)`,
    /// `∇∇F̃ = 2M − 4(My yᵀ + y (My)ᵀ) − 2v 1 + 8v y yᵀ` (the degree-`l`
    /// formula of [`Harmonic::unit_jet`] with `∇P = 2My`, `∇∇P = 2M`); the
    /// same numbers to round-off, not the same bits, so only the `"Joint"`
    /// solver reads it (`"Nested"` keeps its packings bit for bit).
    #[inline(always)]
    fn joint_jet(&self, size: f64, y: &Vector<3>) -> (f64, Vector<3>, Matrix<3>) {
        let Some(m) = &self.quadratic else {
            return self.radial_jet(size, y);
        };
        let my = m * y;
        let v = y.dot(&my);
        let grad = (my - y * v) * 2.0;
        let mixed = my * y.transpose();
        let hess =
            m * 2.0 - (mixed + mixed.transpose()) * 4.0 - Matrix::<3>::identity() * (2.0 * v)
                + y * y.transpose() * (8.0 * v);
        let a = size * self.delta;
        (size + a * v, grad * a, hess * a)
    }

    /// `F(y)` at the body-frame unit vector `y`, from the quadratic form
    /// where there is one.
    #[inline(always)]
    fn f_fast(&self, y: &Vector<3>) -> f64 {
        match &self.quadratic {
            Some(m) => y.dot(&(m * y)),
            None => self.f(y),
        }
    }

    /// `ρ = R⁰(1 + ΔF)`, `∇ρ̃` and `∇∇ρ̃` at the body-frame unit vector `y`
    /// (`ρ̃(x) = ρ(x/|x|)`): the radial function
    /// [`gap3d::radial_support`] reads.
    #[inline(always)]
    fn radial_jet(&self, size: f64, y: &Vector<3>) -> (f64, Vector<3>, Matrix<3>) {
        let (value, grad, hess) = self.unit_jet(y);
        let a = size * self.delta;
        (size + a * value, grad * a, hess * a)
    }

    /// A body of size `size` whose rotation has the columns `columns`, as
    /// the joint iteration reads it ([`gap3d::exact_joint`]; radial jets
    /// by [`Harmonic::joint_jet`]).
    #[inline(always)]
    fn radial_body<'a>(
        &'a self,
        size: f64,
        columns: &'a [Vector<3>; 3],
    ) -> gap3d::RadialBody<'a, impl gap3d::Radial + 'a> {
        gap3d::RadialBody {
            columns,
            radial: move |y: &Vector<3>| self.joint_jet(size, y),
        }
    }

    /// The support function of a body of size `size` whose rotation has
    /// the columns `columns`, in the world direction `u` (unit), with its
    /// gradient (the support point) and Hessian, world frame: the search
    /// of [`gap3d::radial_support`] in the body frame, started at `Qᵀu`.
    /// Meaningful for a convex body (checked by [`Harmonic::new`] for the
    /// exact gap).
    pub fn support(&self, size: f64, columns: &[Vector<3>; 3], u: &Vector<3>) -> RadialSupport {
        self.support_from(size, columns, u, u)
    }

    /// [`Harmonic::support`] with the search started at the world-frame
    /// unit vector `start` (a warm start: where a search for a nearby
    /// direction ended).
    pub fn support_from(
        &self,
        size: f64,
        columns: &[Vector<3>; 3],
        u: &Vector<3>,
        start: &Vector<3>,
    ) -> RadialSupport {
        let found = self.search_from(size, columns, u, start);
        let rot = Matrix::<3>::from_columns(columns);
        RadialSupport {
            jet: gap3d::SupportJet3 {
                h: found.value(),
                point: found.point,
                hess: found.hess(),
            },
            y: rot * found.body.y(),
            iterations: found.body.iterations,
            converged: found.body.converged,
        }
    }

    /// The search of [`Harmonic::support_from`], its Hessian left for
    /// later ([`WorldSupport`]).
    #[inline(always)]
    fn search_from(
        &self,
        size: f64,
        columns: &[Vector<3>; 3],
        u: &Vector<3>,
        start: &Vector<3>,
    ) -> WorldSupport {
        let [c0, c1, c2] = columns;
        let body = |v: &Vector<3>| Vector::<3>::new(c0.dot(v), c1.dot(v), c2.dot(v));
        let ub = body(u);
        let found = gap3d::radial_search(&ub, &body(start), |y| self.radial_jet(size, y));
        let pb = found.point();
        WorldSupport {
            body: found,
            columns: *columns,
            point: c0 * pb[0] + c1 * pb[1] + c2 * pb[2],
        }
    }

    /// The support at `u`, the search started where the last one (`last`:
    /// its direction and support unit vector) ended, moved with the
    /// direction; `last` updated.
    #[inline(always)]
    fn warm_support(
        &self,
        size: f64,
        columns: &[Vector<3>; 3],
        u: &Vector<3>,
        last: &Cell<Option<(Vector<3>, Vector<3>)>>,
    ) -> WorldSupport {
        let start = match last.get() {
            Some((u0, y0)) => (y0 + (u - u0)).normalize(),
            None => *u,
        };
        let found = self.search_from(size, columns, u, &start);
        let rot = Matrix::<3>::from_columns(columns);
        last.set(Some((*u, rot * found.body.y())));
        found
    }

    /// The exact gap of two bodies (crate documentation), or `None` when it
    /// certainly exceeds `max_gap`, whatever the family's gap model.
    #[inline]
    pub fn exact_gap(
        &self,
        size_i: f64,
        o_i: &Quaternion,
        size_j: f64,
        o_j: &Quaternion,
        r_ij: &Vector<3>,
        max_gap: f64,
    ) -> Option<ExactGap3> {
        self.exact_gap_with(size_i, o_i, size_j, o_j, r_ij, max_gap, true)
    }

    /// [`Harmonic::exact_gap`], the support Hessians at the optimum
    /// computed only when `hessians` ([`gap3d::exact_with`]: the contact
    /// does not need them; the same bits otherwise).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn exact_gap_with(
        &self,
        size_i: f64,
        o_i: &Quaternion,
        size_j: f64,
        o_j: &Quaternion,
        r_ij: &Vector<3>,
        max_gap: f64,
        hessians: bool,
    ) -> Option<ExactGap3> {
        let r = r_ij.norm();
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return None;
        }
        let (ci, cj) = (o_i.columns(), o_j.columns());
        let nested = || {
            // Warm starts: each search begins where the body's last one
            // ended, moved with the direction (`y* − u` changes slowly, by
            // O(Δ|δu|)).
            let (last_i, last_j) = (Cell::new(None), Cell::new(None));
            gap3d::exact_with(
                r_ij,
                |u| self.warm_support(size_i, &ci, u, &last_i),
                |u| self.warm_support(size_j, &cj, u, &last_j),
                max_gap,
                hessians,
            )
        };
        match self.exact_solver {
            ExactSolver::Nested => nested(),
            ExactSolver::Joint => gap3d::exact_joint(
                r_ij,
                &self.radial_body(size_i, &ci),
                &self.radial_body(size_j, &cj),
                max_gap,
                hessians,
                nested,
            ),
        }
    }

    /// The exact gap as the engine's pair loop finds it
    /// ([`Shape::contacts_warm`]) with the `"Joint"` solver: the joint
    /// iteration started where the pair's last solve ended
    /// ([`gap3d::exact_joint_warm`] from the [`gap3d::JointStart`] that
    /// `memo` holds), else, or where that fails, the cold solve of
    /// [`Harmonic::exact_gap`]; `memo` gets where this solve ended, also
    /// for a pair the warm solve finds apart (`h > max_gap`, `None`). A pair
    /// that [`Harmonic::gap_lower_bound`] shows farther apart than
    /// `max_gap` (read at the memo's normal, or at the line of centres
    /// without a start) is skipped before any solve, its memo kept. The
    /// support Hessians at the optimum only with `hessians`. The result is
    /// the cold solve's optimum to the warm iteration's tolerance
    /// ([`gap3d::WARM_TOL`], [`gap3d::TAYLOR_TOL`]), whatever the memo
    /// holds (module documentation of `jamkit_gap3d`,
    /// [`gap3d::exact_joint_warm`]); with an empty memo it is the cold
    /// solve's bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub fn exact_gap_warm(
        &self,
        size_i: f64,
        o_i: &Quaternion,
        size_j: f64,
        o_j: &Quaternion,
        r_ij: &Vector<3>,
        max_gap: f64,
        memo: &mut PairMemo,
        hessians: bool,
    ) -> Option<ExactGap3> {
        let r = r_ij.norm();
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return None;
        }
        let (ci, cj) = (o_i.columns(), o_j.columns());
        let start = memo
            .as_ref()
            .and_then(|m| gap3d::JointStart::recall(m, r_ij, &ci, &cj));
        // Certainly apart (`h ≥ g(n) ≥` the bound, with room for
        // round-off) at the last normal, or at the line of centres without
        // a start (then `g(r̂)` exceeds `max_gap` too, and the cold solve
        // skips the pair at its first check): skipped, the memo kept.
        let screen = start.as_ref().map_or(r_ij / r, |s| s.normal);
        let bound = self.gap_lower_bound(size_i, &ci, size_j, &cj, r_ij, &screen);
        if bound - max_gap > 1e-12 * (size_i + size_j) {
            return None;
        }
        if let Some(start) = start {
            let warm = gap3d::exact_joint_warm(
                r_ij,
                &self.radial_body(size_i, &ci),
                &self.radial_body(size_j, &cj),
                &start,
                f64::INFINITY,
                hessians,
            );
            match warm {
                // A pair found apart keeps where it was found too, so that
                // its next solve (and screen) starts there.
                gap3d::Joint::Found(e, end) => {
                    *memo = Some(end.memo(r_ij, &ci, &cj));
                    return (e.gap <= max_gap).then_some(e);
                }
                gap3d::Joint::Apart => return None,
                // Not a start to try again: the cold solve writes its own.
                gap3d::Joint::Failed => *memo = None,
            }
        }
        let found = self.exact_gap_with(size_i, o_i, size_j, o_j, r_ij, max_gap, hessians);
        if let Some(e) = &found {
            *memo = Some(gap3d::JointStart::remember(e, r_ij, &ci, &cj));
        }
        found
    }

    /// `∂G̃/∂q_p = g · t_p = g · (x × e_p) = e_p · (g × x)`.
    #[inline(always)]
    fn torques(&self, axes: &[Vector<3>; 3], m: usize, grad: &Vector<3>, x: &Vector<3>) -> RotVec {
        let torque = grad.cross(x);
        let mut rot = [0.0; MAX_ROT];
        for p in 0..m {
            rot[p] = axes[p].dot(&torque);
        }
        rot
    }

    /// The rotation axes `e_p`: the world axes, or `Q x̂, Q ŷ` for an
    /// axisymmetric `F`.
    #[inline(always)]
    fn axes(&self, columns: &[Vector<3>; 3]) -> [Vector<3>; 3] {
        Quaternion::step_axes(columns, self.axisymmetric)
    }

    /// The separation, its inverse length (0 at coincident centres) and
    /// the unit vector, or `None` when the bounding test says the pair is
    /// certainly farther apart than `max_gap`.
    #[inline(always)]
    fn direction(
        &self,
        size_i: f64,
        size_j: f64,
        r_ij: &Vector<3>,
        max_gap: f64,
    ) -> Option<(f64, Vector<3>, f64, Vector<3>)> {
        let r = r_ij.norm();
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return None;
        }
        // NOTE: coincident centres have no direction: take x̂ and 1/r → 0
        // (such a pair overlaps deeply; any direction pushes it apart, and
        // a fixed one keeps the run deterministic).
        Some(if r > 0.0 {
            let inv_r = 1.0 / r;
            (r, *r_ij, inv_r, r_ij * inv_r)
        } else {
            (r, Vector::<3>::x(), 0.0, Vector::<3>::x())
        })
    }

    /// The first-order contact of a pair with its first derivatives.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn contact(
        &self,
        size_i: f64,
        c_i: &[Vector<3>; 3],
        size_j: f64,
        c_j: &[Vector<3>; 3],
        r: f64,
        x: &Vector<3>,
        inv_r: f64,
        u: &Vector<3>,
    ) -> Contact<3> {
        let m = Shape::<3>::rot_dof(self);
        let (f_i, g_i, _) = self.value_grad(c_i, x, inv_r);
        let (f_j, g_j, _) = self.value_grad(c_j, &(-x), inv_r);
        let (a_i, a_j) = (self.delta * size_i, self.delta * size_j);
        let gap = r - size_i - size_j - (a_i * f_i + a_j * f_j);
        let grad_r = u - g_i * a_i + g_j * a_j;
        let (t_i, t_j) = (
            self.torques(&self.axes(c_i), m, &g_i, x),
            self.torques(&self.axes(c_j), m, &g_j, &(-x)),
        );
        let mut grad_rot_i = [0.0; MAX_ROT];
        let mut grad_rot_j = [0.0; MAX_ROT];
        for p in 0..m {
            grad_rot_i[p] = -a_i * t_i[p];
            grad_rot_j[p] = -a_j * t_j[p];
        }
        Contact {
            gap,
            grad_r,
            grad_rot_i,
            grad_rot_j,
        }
    }
}

/// Gauss–Legendre nodes and weights on `[−1, 1]` (in `jamkit_core::math`,
/// shared with the `ellipsoid` family's surface area).
pub use jamkit_core::math::gauss_legendre;

/// The drawing surface of a `harmonic` body (`jamkit draw`):
/// `ρ(y) = 1 + Δ F(y)` in the body frame, the rotation of the quaternion
/// `[w, x, y, z]` the packing file stores.
#[derive(Clone, Debug)]
pub struct HarmonicSurface(Harmonic);

impl jamkit_core::Surface for HarmonicSurface {
    fn relative_radius(&self, y: [f64; 3]) -> f64 {
        1.0 + self.0.delta * self.0.f(&Vector::<3>::new(y[0], y[1], y[2]))
    }

    /// `1 ∓ Δ max|F|` with the certain bound on `|F|` (positive: checked
    /// by [`Harmonic::new`]).
    fn relative_radius_bounds(&self) -> (f64, f64) {
        let b = self.0.delta * self.0.f_bound;
        (1.0 - b, 1.0 + b)
    }
}

impl Shape<3> for Harmonic {
    type Orientation = Quaternion;
    type Fast = NoFastPath;

    fn family(&self) -> &'static str {
        INFO.name
    }

    /// 3, or 2 for an axisymmetric `F`.
    fn rot_dof(&self) -> usize {
        if self.axisymmetric { 2 } else { 3 }
    }

    fn volume(&self, size: f64) -> f64 {
        self.unit_volume * size * size * size
    }

    /// `R⁰ (1 + Δ max|F|)` with the certain bound on `|F|`.
    fn bounding_radius(&self, size: f64) -> f64 {
        size * (1.0 + self.delta * self.f_bound)
    }

    fn rot_inertia(&self, _size: f64) -> RotVec {
        [self.inertia; MAX_ROT]
    }

    /// `Q → exp(ω) Q` (world frame), or `Q → Q exp((dq₀, dq₁, 0))` (body
    /// frame) for an axisymmetric `F`; renormalised.
    fn rotate(&self, o: &mut Quaternion, dq: &[f64]) {
        *o = o.stepped(dq, self.axisymmetric);
    }

    /// Rattlers below `d + 1 = 4` contacts, the paper's convention carried
    /// to 3D; near-spheres jam hypostatic, like the paper's near-disks; a
    /// warning where the body is not convex (sampled on 48 × 96
    /// directions): the first-order gap assumes convex bodies with one
    /// contact per pair.
    fn policy(&self) -> Policy {
        let mut warnings = Vec::new();
        if !self.is_convex(48) {
            warnings.push(format!(
                "non-convex body (Δ = {}): the first-order gap assumes convex bodies with one contact per pair",
                self.delta
            ));
        }
        Policy {
            rattler_threshold: 4,
            expects_isostatic: false,
            warnings,
            ..Policy::new(3)
        }
    }

    /// `1 + Δ F`, for drawing ([`HarmonicSurface`]).
    fn look(&self) -> Look {
        Look {
            surface: Some(std::sync::Arc::new(HarmonicSurface(self.clone()))),
            ..Look::default()
        }
    }

    #[inline(always)]
    fn contacts<F: FnMut(Contact<3>)>(
        &self,
        pair: &Pair<3, Quaternion>,
        max_gap: f64,
        mut visit: F,
    ) {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        if self.gap == GapModel::Exact {
            if let Some(e) = self.exact_gap_with(size_i, o_i, size_j, o_j, r_ij, max_gap, false) {
                let (c_i, c_j) = (o_i.columns(), o_j.columns());
                visit(e.contact(&self.axes(&c_i), &self.axes(&c_j), self.rot_dof()));
            }
            return;
        }
        if let Some((r, x, inv_r, u)) = self.direction(size_i, size_j, r_ij, max_gap) {
            let (c_i, c_j) = (o_i.columns(), o_j.columns());
            visit(self.contact(size_i, &c_i, size_j, &c_j, r, &x, inv_r, &u));
        }
    }

    /// With the exact gap and the `"Joint"` solver, each listed pair's
    /// solve starts where its last one ended ([`Harmonic::exact_gap_warm`]);
    /// otherwise [`Shape::contacts`] (the nested solve stays cold, bit for
    /// bit the packings made with it).
    #[inline(always)]
    fn contacts_warm<F: FnMut(Contact<3>)>(
        &self,
        pair: &Pair<3, Quaternion>,
        max_gap: f64,
        memo: &mut PairMemo,
        mut visit: F,
    ) {
        if self.gap == GapModel::Exact && self.exact_solver == ExactSolver::Joint {
            let (o_i, o_j) = (&pair.o_i, &pair.o_j);
            if let Some(e) = self.exact_gap_warm(
                pair.size_i,
                o_i,
                pair.size_j,
                o_j,
                &pair.r_ij,
                max_gap,
                memo,
                false,
            ) {
                let (c_i, c_j) = (o_i.columns(), o_j.columns());
                visit(e.contact(&self.axes(&c_i), &self.axes(&c_j), self.rot_dof()));
            }
            return;
        }
        self.contacts(pair, max_gap, visit)
    }

    /// Body `i`'s term enters with `x = r_ij`, body `j`'s with `x = −r_ij`
    /// (odd derivatives in `r_ij` change sign), each times `−Δ R⁰`; the
    /// sphere's `(1 − r̂ r̂ᵀ)/r` is added; the bodies' rotations do not mix.
    fn gap_hessians<F: FnMut(GapHessian<3>)>(
        &self,
        pair: &Pair<3, Quaternion>,
        max_gap: f64,
        mut visit: F,
    ) -> jamkit_core::Result<()> {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        if self.gap == GapModel::Exact {
            if let Some(e) = self.exact_gap(size_i, o_i, size_j, o_j, r_ij, max_gap) {
                let (c_i, c_j) = (o_i.columns(), o_j.columns());
                visit(e.hessian(&self.axes(&c_i), &self.axes(&c_j), self.rot_dof()));
            }
            return Ok(());
        }
        let Some((r, x, inv_r, u)) = self.direction(size_i, size_j, r_ij, max_gap) else {
            return Ok(());
        };
        let (c_i, c_j) = (o_i.columns(), o_j.columns());
        let contact = self.contact(size_i, &c_i, size_j, &c_j, r, &x, inv_r, &u);
        let m = Shape::<3>::rot_dof(self);
        let ji = self.body_jet(&c_i, &self.axes(&c_i), m, &x, inv_r);
        let jj = self.body_jet(&c_j, &self.axes(&c_j), m, &(-x), inv_r);
        let (a_i, a_j) = (self.delta * size_i, self.delta * size_j);
        let sphere = (Matrix::<3>::identity() - u * u.transpose()) * inv_r;
        let mut out = GapHessian::translational(
            contact.gap,
            contact.grad_r,
            sphere - ji.hess * a_i - jj.hess * a_j,
        );
        out.contact = contact;
        for p in 0..m {
            out.r_qi[p] = -ji.x_rot[p] * a_i;
            out.r_qj[p] = jj.x_rot[p] * a_j;
            for q in 0..m {
                out.qi_qi[p][q] = -a_i * ji.rot_rot[p][q];
                out.qj_qj[p][q] = -a_j * jj.rot_rot[p][q];
            }
        }
        visit(out);
        Ok(())
    }
}

#[cfg(test)]
mod exact_tests;

#[cfg(test)]
mod warm_tests;

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::{Pair, ShapeExt};

    pub(crate) fn single(l: u32, m: i32, delta: f64) -> Harmonic {
        Harmonic::single(l, m, delta).unwrap()
    }

    /// The drawing surface agrees with the shape: its rotation of the
    /// stored quaternion is `Q` (columns `Q x̂, Q ŷ, Q ẑ`), and
    /// `ρ(Mᵀ û) = R(û)/R⁰` at generic orientations and directions of a
    /// mixed, non-axisymmetric `F`, to rounding; a non-unit quaternion is
    /// refused; the bounds hold `ρ` on a sample of directions.
    #[test]
    fn the_drawing_surface_is_the_shape() {
        use rand::SeedableRng;
        let h = mixed(0.2);
        let s = Shape::<3>::look(&h).surface.unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (lo, hi) = s.relative_radius_bounds();
        for _ in 0..50 {
            let q = Quaternion::random(&mut rng);
            let m = s.rotation(&q.coords()).unwrap();
            let c = q.columns();
            for (k, col) in c.iter().enumerate() {
                for r in 0..3 {
                    assert_relative_eq!(m[r][k], col[r], epsilon = 1e-12);
                }
            }
            let u = Quaternion::random(&mut rng).columns()[0];
            let y: [f64; 3] = std::array::from_fn(|a| (0..3).map(|r| m[r][a] * u[r]).sum());
            let rho = s.relative_radius(y);
            assert_relative_eq!(rho, h.relative_radius(&q, &u), epsilon = 1e-12);
            assert!(lo <= rho && rho <= hi, "{lo} ≤ {rho} ≤ {hi}");
        }
        assert!(s.rotation(&[2.0, 0.0, 0.0, 0.0]).is_none());
        assert!(s.rotation(&[1.0, 0.0, 0.0]).is_none());
    }

    pub(crate) fn mixed(delta: f64) -> Harmonic {
        Harmonic::new(&HarmonicParams {
            l: None,
            m: None,
            modes: Some(vec![
                Mode { l: 2, m: 0, c: 1.0 },
                Mode {
                    l: 2,
                    m: -1,
                    c: 0.4,
                },
                Mode { l: 3, m: 2, c: 0.5 },
                Mode {
                    l: 5,
                    m: -4,
                    c: -0.3,
                },
            ]),
            delta,
            inertia: None,
            gap: GapModel::FirstOrder,
            exact_solver: ExactSolver::Nested,
        })
        .unwrap()
    }

    fn unit(theta: f64, phi: f64) -> Vector<3> {
        Vector::<3>::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    /// The slope normalisation in closed form: `Ŷ_20 = (3z² − 1)/3` (the
    /// slope of `P_2(cos θ)` peaks at 3/2) and `Ŷ_22 = (x² − y²)/2` (the
    /// slope of `sin²θ cos 2φ` peaks at 2, along φ at the equator).
    #[test]
    fn normalisation_has_the_closed_forms_of_l_2() {
        let (y20, y22) = (single(2, 0, 0.1), single(2, 2, 0.1));
        for v in [
            unit(0.3, 1.1),
            unit(2.0, -0.4),
            Vector::<3>::z(),
            Vector::<3>::x(),
        ] {
            assert_relative_eq!(y20.f(&v), (3.0 * v[2] * v[2] - 1.0) / 3.0, epsilon = 1e-14);
            assert_relative_eq!(
                y22.f(&v),
                (v[0] * v[0] - v[1] * v[1]) / 2.0,
                epsilon = 1e-14
            );
        }
        assert!(y20.is_axisymmetric() && !y22.is_axisymmetric());
        assert_eq!(
            (Shape::<3>::rot_dof(&y20), Shape::<3>::rot_dof(&y22)),
            (2, 3)
        );
        // ⟨Ŷ_20²⟩ = (1/9)⟨9z⁴ − 6z² + 1⟩ = 4/45.
        assert_relative_eq!(y20.mean_square(), 4.0 / 45.0, epsilon = 1e-15);
    }

    /// Every single mode l = 2…8, every m: the largest slope of `F` on a
    /// 100 × 200 scan of the sphere is at most 1 (+1e-12 round-off) and at
    /// least 0.995 (the scan's step π/100 misses the peak by ~ step²);
    /// and `|F|` never exceeds the bound used for the bounding radius.
    #[test]
    fn every_single_mode_has_largest_slope_one() {
        for l in 2..=LMAX {
            for m in -(l as i32)..=l as i32 {
                let s = single(l, m, 0.1);
                let (mut slope, mut fmax) = (0.0f64, 0.0f64);
                for i in 0..=100 {
                    for j in 0..200 {
                        let v = unit(PI * i as f64 / 100.0, 2.0 * PI * j as f64 / 200.0);
                        slope = slope.max(s.surface_gradient(&v).norm());
                        fmax = fmax.max(s.f(&v).abs());
                    }
                }
                assert!(slope <= 1.0 + 1e-12 && slope > 0.995, "({l},{m}): {slope}");
                assert!(fmax <= s.f_bound(), "({l},{m}): {fmax} > {}", s.f_bound());
            }
        }
    }

    /// The exact volume against `(1/3)∫R³ dΩ` by Gauss–Legendre × trapezoid
    /// (64 × 128 nodes, exact for these polynomials of degree ≤ 15):
    /// 1e-13 relative.
    #[test]
    fn volume_matches_quadrature() {
        for s in [single(2, 0, 0.3), single(3, -2, 0.2), mixed(0.2)] {
            let (z, w) = gauss_legendre(64);
            let mut v = 0.0;
            for (zk, wk) in z.iter().zip(&w) {
                let rho = (1.0 - zk * zk).sqrt();
                for k in 0..128 {
                    let phi = PI * k as f64 / 64.0;
                    let u = Vector::<3>::new(rho * phi.cos(), rho * phi.sin(), *zk);
                    v += wk * (PI / 64.0) * (1.0 + s.delta * s.f(&u)).powi(3) / 3.0;
                }
            }
            assert_relative_eq!(s.unit_volume(), v, max_relative = 1e-13);
            assert!(s.unit_volume() > 4.0 * PI / 3.0);
        }
    }

    /// `A(Δ) = 1 + (3/2)Δ² Σ (l−1)(l+2)⟨P_l²⟩` is the small-Δ limit of the
    /// numerically integrated asphericity: the difference is of higher
    /// order (it shrinks at least 6× when Δ halves; second order would be
    /// 4×) and is below 5% of `A − 1` at Δ = 0.01.
    #[test]
    fn asphericity_to_second_order_is_the_small_delta_limit() {
        for (make, name) in [
            (single as fn(u32, i32, f64) -> Harmonic, "single"),
            (|_, _, d| mixed(d), "mixed"),
        ] {
            for (l, m) in [(2, 0), (3, 2), (4, -1)] {
                let err = |d: f64| {
                    let s = make(l, m, d);
                    (s.asphericity(48) - s.asphericity_second_order()).abs()
                };
                let (e1, e2) = (err(0.01), err(0.02));
                let a1 = make(l, m, 0.01).asphericity_second_order() - 1.0;
                assert!(e2 > 6.0 * e1, "{name} ({l},{m}): {e2} vs {e1}");
                assert!(e1 < 0.05 * a1, "{name} ({l},{m}): {e1} vs {a1}");
            }
        }
        // Ŷ_20: A = 1 + (8/15)Δ².
        assert_relative_eq!(
            single(2, 0, 0.1).asphericity_second_order(),
            1.0 + 8.0 / 15.0 * 0.01,
            epsilon = 1e-15
        );
    }

    pub(crate) fn orientations() -> Vec<Quaternion> {
        vec![
            Quaternion::IDENTITY,
            Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap(),
            Quaternion::normalized(-0.7, 0.1, 0.4, 0.2).unwrap(),
        ]
    }

    /// Separations along `±Q_i e_z` (the poles of the zonal modes, where
    /// their gradient vanishes), 10⁻³ off them, and generic.
    pub(crate) fn separations(o_i: &Quaternion) -> Vec<Vector<3>> {
        let pole = o_i.apply(&Vector::<3>::z());
        let tilt = o_i.apply(&Vector::<3>::new(1e-3, -2e-3, 1.0)).normalize();
        vec![
            pole * 1.1,
            -pole * 1.05,
            tilt * 1.08,
            -tilt * 1.12,
            Vector::<3>::new(0.5, -0.7, 0.6),
            Vector::<3>::new(-0.9, 0.3, 0.45),
        ]
    }

    fn shapes() -> Vec<Harmonic> {
        vec![
            single(2, 0, 0.2),
            single(2, 2, 0.2),
            single(4, -3, 0.15),
            single(6, 5, 0.1),
            mixed(0.15),
        ]
    }

    /// The pair loop's gap against the printed formula
    /// `r − R_i − R_j − Δ[R_i F(Q_iᵀ r̂) + R_j F(−Q_jᵀ r̂)]`, written with the
    /// conjugate quaternion's rotation (not the pair loop's transposed
    /// columns): 1e-14, round-off of the two ways of rotating.
    #[test]
    fn gap_matches_the_printed_formula() {
        for s in shapes() {
            for o_i in orientations() {
                for o_j in orientations() {
                    for r in separations(&o_i) {
                        let u = r.normalize();
                        let (ri, rj) = (0.5, 0.7);
                        let want = r.norm()
                            - ri
                            - rj
                            - s.delta
                                * (ri * s.f(&o_i.conjugate().apply(&u))
                                    + rj * s.f(&(-o_j.conjugate().apply(&u))));
                        let c = s.pair_contacts(&Pair::new(ri, o_i, rj, o_j, r), f64::INFINITY);
                        assert_eq!(c.len(), 1);
                        assert_relative_eq!(c[0].gap, want, epsilon = 1e-14);
                    }
                }
            }
        }
    }

    /// `h_ij = h_ji`: swapping the bodies and reversing `r_ij` gives the
    /// same gap, `∂h/∂r_j` reversed and the rotational derivatives swapped
    /// (1e-14: the same terms summed in another order).
    #[test]
    fn gap_is_symmetric() {
        for s in shapes() {
            let os = orientations();
            for r in separations(&os[1]) {
                jamkit_kit::check_swapped(&s, (0.5, 0.7), &os[1], &os[2], &r, 1e-14, 1e-14);
            }
        }
    }

    /// Every first derivative of one contact against central differences
    /// of its gap (ε = 1e-6: truncation ε²|h'''| ~ 1e-11, round-off
    /// 1e-16/ε ~ 1e-10; bound 1e-8), and every second derivative against
    /// second central differences of the gap (ε = 1e-4: truncation
    /// ε²|h''''| ~ 1e-7 for the l = 6 modes, round-off 1e-16/ε² ~ 1e-8;
    /// bound 1e-5 of the largest entry, ~1). Single modes, axisymmetric
    /// (two rotational coordinates) or not, and a mixed sum; at the poles
    /// `±Q_i e_z`, next to them and at generic separations.
    #[test]
    fn pair_derivatives_match_finite_differences() {
        for s in shapes() {
            for o_i in orientations() {
                for o_j in orientations().iter().rev() {
                    for r in separations(&o_i) {
                        let d =
                            jamkit_kit::pair_derivatives(&s, (0.5, 0.7), &o_i, o_j, &r, 1e-6, 1e-4);
                        assert!(
                            d.grad_error() < 1e-8 && d.hess_error() < 1e-5,
                            "{s:?} at r = {r:?}: {d:?}"
                        );
                    }
                }
            }
        }
    }

    /// Turning the whole pair by one rotation `U` (centres and both
    /// orientations, `Q → U Q`) leaves the gap unchanged and turns
    /// `∂h/∂r_j` by `U` (1e-14); with world-frame rotational coordinates the
    /// torques turn by `U` too, and with the body-frame ones of an
    /// axisymmetric `F` they do not change.
    #[test]
    fn pair_is_invariant_under_a_global_rotation() {
        let turn = Quaternion::normalized(0.4, 0.7, -0.3, 0.5).unwrap();
        for s in shapes() {
            let os = orientations();
            for r in separations(&os[2]) {
                let a = s.pair_contacts(&Pair::new(0.5, os[2], 0.7, os[1], r), f64::INFINITY)[0];
                let (ti, tj) = (turn.mul(&os[2]), turn.mul(&os[1]));
                let b =
                    s.pair_contacts(&Pair::new(0.5, ti, 0.7, tj, turn.apply(&r)), f64::INFINITY)[0];
                assert_relative_eq!(a.gap, b.gap, epsilon = 1e-14);
                assert_relative_eq!(turn.apply(&a.grad_r), b.grad_r, epsilon = 1e-14);
                let (qa, qb) = (a.grad_rot_i, b.grad_rot_i);
                if s.is_axisymmetric() {
                    for p in 0..3 {
                        assert_relative_eq!(qa[p], qb[p], epsilon = 1e-14);
                    }
                } else {
                    let ta = turn.apply(&Vector::<3>::new(qa[0], qa[1], qa[2]));
                    assert_relative_eq!(ta, Vector::<3>::new(qb[0], qb[1], qb[2]), epsilon = 1e-14);
                }
            }
        }
    }

    /// Convexity against the axisymmetric conditions written out for
    /// `Ŷ_20`, `ρ(θ) = 1 + Δ(3cos²θ − 1)/3`: the meridian's
    /// `ρ² + 2ρ'² − ρρ'' > 0` and the parallels' `ρ − ρ' cot θ > 0`, on
    /// 20 001 latitudes; the first Δ (step 10⁻³) where they fail is
    /// 3/7 ≈ 0.4286 (at the equator, `ρ = 1 − Δ/3`, `ρ'' = 2Δ`), and
    /// `is_convex` agrees 0.005 below and above it; a sum with l = 6 turns
    /// non-convex much earlier and gets the warning.
    #[test]
    fn convexity_matches_the_axisymmetric_conditions() {
        let written_out = |d: f64| {
            (0..=20_000).all(|k| {
                let t = PI * k as f64 / 20_000.0;
                let (st, ct) = t.sin_cos();
                let rho = 1.0 + d * (3.0 * ct * ct - 1.0) / 3.0;
                let d1 = -2.0 * d * st * ct;
                let d2 = -2.0 * d * (ct * ct - st * st);
                let meridian = rho * rho + 2.0 * d1 * d1 - rho * d2 > 0.0;
                let parallel = st < 1e-9 || rho * st - d1 * ct > 0.0;
                meridian && parallel
            })
        };
        let mut dc = 0.0;
        while written_out(dc + 1e-3) {
            dc += 1e-3;
        }
        assert!((dc - 3.0 / 7.0).abs() < 2e-3, "threshold {dc}");
        assert!(single(2, 0, dc - 0.005).is_convex(48));
        assert!(!single(2, 0, dc + 0.005).is_convex(48));
        assert!(Shape::<3>::policy(&single(2, 0, 0.3)).warnings.is_empty());
        let bumpy = single(6, 3, 0.2);
        assert!(!bumpy.is_convex(48));
        assert_eq!(Shape::<3>::policy(&bumpy).warnings.len(), 1);
    }

    /// Bad parameters are refused with the field named (the registry's
    /// path is checked in `tests/conformance.rs`).
    #[test]
    fn nonsense_parameters_are_refused_with_the_field_named() {
        let base = HarmonicParams {
            l: Some(2),
            m: None,
            modes: None,
            delta: 0.1,
            inertia: None,
            gap: GapModel::FirstOrder,
            exact_solver: ExactSolver::Nested,
        };
        let cases: Vec<(HarmonicParams, &str)> = vec![
            (
                HarmonicParams {
                    l: Some(1),
                    ..base.clone()
                },
                "params.l",
            ),
            (
                HarmonicParams {
                    l: Some(9),
                    ..base.clone()
                },
                "params.l",
            ),
            (
                HarmonicParams {
                    m: Some(3),
                    ..base.clone()
                },
                "params.m",
            ),
            (
                HarmonicParams {
                    delta: -0.1,
                    ..base.clone()
                },
                "params.delta",
            ),
            (
                HarmonicParams {
                    delta: f64::NAN,
                    ..base.clone()
                },
                "params.delta",
            ),
            (
                HarmonicParams {
                    delta: 1.6,
                    ..base.clone()
                },
                "params.delta",
            ),
            (
                HarmonicParams {
                    inertia: Some(0.0),
                    ..base.clone()
                },
                "params.inertia",
            ),
            (
                HarmonicParams {
                    modes: Some(vec![]),
                    ..base.clone()
                },
                "params.l",
            ),
            (
                HarmonicParams {
                    l: None,
                    modes: Some(vec![]),
                    ..base.clone()
                },
                "params.modes",
            ),
            (
                HarmonicParams {
                    l: None,
                    ..base.clone()
                },
                "params",
            ),
            (
                HarmonicParams {
                    l: None,
                    modes: Some(vec![
                        Mode { l: 3, m: 1, c: 1.0 },
                        Mode { l: 3, m: 1, c: 0.5 },
                    ]),
                    ..base.clone()
                },
                "params.modes[1]",
            ),
            (
                HarmonicParams {
                    l: None,
                    modes: Some(vec![Mode {
                        l: 3,
                        m: -4,
                        c: 1.0,
                    }]),
                    ..base.clone()
                },
                "params.modes[0].m",
            ),
            (
                HarmonicParams {
                    l: None,
                    modes: Some(vec![Mode {
                        l: 3,
                        m: 0,
                        c: f64::INFINITY,
                    }]),
                    ..base.clone()
                },
                "params.modes[0].c",
            ),
        ];
        for (p, field) in cases {
            let e = Harmonic::new(&p)
                .err()
                .unwrap_or_else(|| panic!("{p:?} accepted"))
                .to_string();
            assert!(e.contains(field), "{p:?}: {e} does not name {field}");
        }
        // Δ = 1.4 keeps R > 0 for Ŷ_20 (min F = −1/3, max 2/3: the bound
        // 2/3 + ε allows Δ < 1.5).
        assert!(Harmonic::new(&HarmonicParams { delta: 1.4, ..base }).is_ok());
    }
}
