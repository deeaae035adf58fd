//! # Ellipsoids and spheroids: the `ellipsoid` family (3D) with the exact gap
//!
//! A body of size `R⁰` is an ellipsoid of the **same volume as the ball of
//! radius `R⁰`**, so that a size distribution and a packing fraction mean
//! the same thing as for spheres. Its semi-axes along the body axes
//! `x̂, ŷ, ẑ` are `R⁰ (ξ_x, ξ_y, ξ_z)` with `ξ_x ξ_y ξ_z = 1`, given either
//!
//! * as a **spheroid** of aspect ratio `α` (`alpha`), symmetric about the
//!   body `z` axis: `a = R⁰ α^{2/3}` along `ẑ`, `b = c = R⁰ α^{−1/3}`
//!   across it (`α > 1` prolate, `α < 1` oblate, `α = a/b`); or
//! * as **general ratios** `axes: [x, y, z]`, normalised to unit product:
//!   `ξ = (x, y, z) / (x y z)^{1/3}`. When exactly two are equal, the body
//!   frame is turned (a cyclic relabelling of the axes) so that the
//!   distinct one lies along `ẑ`, and the body is a spheroid.
//!
//! `α = 1` (or three equal ratios) is the ball of radius `R⁰`: the registry
//! runs it as the `sphere` family (no rotational coordinates, the same
//! random stream, hence the same packing bit for bit), as `ellipse` does at
//! `α = 1` and `harmonic` at `Δ = 0`. The orientation is a unit quaternion
//! `Q` ([`Quaternion`], the rotation from body to world frame).
//!
//! ## Support function and gap
//!
//! In the world frame the body is `{y : yᵀ M⁻¹ y ≤ 1}` about its centre,
//! with `M = Q diag(a², b², c²) Qᵀ`, and its support function (the largest
//! projection of the body on the direction `u`) is
//!
//! ```text
//! s(u) = √(uᵀ M u),    ∇s = M u / s  (the support point),
//! ∇∇s = M/s − (M u)(M u)ᵀ/s³          (its radii of curvature),
//! ```
//!
//! ([`jamkit_gap3d::QuadraticSupport`]). Two bodies interact through
//! the **exact** gap, the signed distance along the common normal,
//!
//! ```text
//! h = max_{|u| = 1} [u·r_ij − s_i(u) − s_j(−u)]
//! ```
//!
//! (positive: the distance of the two surfaces; negative: minus the depth of
//! penetration along the normal), found by a safeguarded Newton iteration
//! on the unit sphere from the line of centres, with its gradient by the
//! envelope theorem (`∂h/∂r_j = n`, the torques `n × p` of the support
//! points) and its second derivatives in positions and rotations by
//! implicit differentiation of the optimal normal: all in
//! [`jamkit_gap3d`], which any convex 3D body with a known support
//! function can reuse. There is no expansion in `α − 1`: the gap is exact
//! for every aspect ratio, to round-off. Since `h ≥ g(r̂)` at the line of
//! centres, a pair with `g(r̂) > max_gap` is skipped after one evaluation
//! (and one with `r` beyond the sum of the long semi-axes before any).
//!
//! ## Warm start
//!
//! With `warm_start: true`, the default of an experiment, the engine's
//! energy pass starts each listed pair's solve at the normal where its
//! last one ended ([`Ellipsoid::exact_gap_warm`],
//! [`jamkit_gap3d::exact_warm`]), kept relative to the line of centres in
//! body `i`'s frame. The result is the cold solve's optimum to the
//! solver's tolerance (normal ~10⁻¹⁴, gap ~10⁻²⁸), not its bits; pairs are
//! skipped exactly where the cold solve skips them. With `false` every
//! solve starts at the line of centres: the packings made before the
//! parameter existed, bit for bit, whose records have none (a missing key
//! reads as `false`; [`jamkit_core::Added`]).
//!
//! ## Rotational coordinates, inertia
//!
//! Three rotational coordinates for a triaxial body (`ω` in the world
//! frame, `Q → exp(ω) Q`, the convention of `nmer` and `harmonic`), two for
//! a spheroid: the rotation about its own axis moves nothing, and the two
//! coordinates turn it about its transverse axes `Q x̂`, `Q ŷ`
//! (`Q → Q exp((dq₀, dq₁, 0))`, as `harmonic` does for an axisymmetric `F`).
//!
//! Mass 1. The moment of inertia defaults to that of a uniform solid
//! ellipsoid of unit mass: about a principal axis `(b² + c²)/5` (and
//! cyclic). A spheroid's two coordinates turn it about its transverse
//! axes, so each gets its exact transverse moment `(a² + b²)/5`. A triaxial
//! body's world-frame coordinates see the inertia tensor
//! `Q diag(I_x, I_y, I_z) Qᵀ`, which FIRE (one mass per coordinate) cannot
//! carry; they get the mean principal moment `2(a² + b² + c²)/15` (the
//! ball's `2R²/5` at `α = 1`). The minima do not depend on the inertia,
//! only FIRE's route to them; `inertia: x` sets one value for all
//! coordinates and sizes.
//!
//! ## Rattlers and isostaticity
//!
//! The paper's convention carried to 3D, as for the other 3D families: a
//! body with fewer than `d + 1 = 4` contacts is a rattler, and the isostatic
//! count uses the body's real coordinates, `f = 3 + 2 = 5` for a spheroid
//! and `3 + 3 = 6` for a triaxial ellipsoid. Ellipsoids jam hypostatic
//! (Donev et al., Science 303, 990 (2004)): `z_J < 2f`.

use jamkit_core::Error;
use jamkit_core::{
    Added, Contact, Dims, Family, FamilyInfo, GapHessian, Look, MAX_ROT, MEMO_LEN, NoFastPath,
    Pair, PairMemo, ParamSpec, Policy, Quaternion, RotVec, Shape, ShapeVisitor, Vector,
};
use jamkit_gap3d::{self as gap3d, ExactGap3, QuadraticSupport, WORLD_AXES};
use serde::Deserialize;
use std::f64::consts::PI;

/// The largest ratio of the longest to the shortest semi-axis accepted
/// (the range the tests cover).
pub const MAX_RATIO: f64 = 10.0;

/// The family's self-description.
pub const INFO: FamilyInfo = FamilyInfo {
    name: "ellipsoid",
    about: "ellipsoids of the volume of the ball R0: spheroids of aspect ratio α (a = R0 α^(2/3) along the axis, b = R0 α^(−1/3)) or semi-axes in given ratios, with the exact gap (3D)",
    dims: Dims::Only(&[3]),
    params: &[
        ParamSpec {
            name: "alpha",
            about: "spheroid aspect ratio α = a/b > 0 (α > 1 prolate, α < 1 oblate, 1 the sphere family), longest over shortest axis ≤ 10; give alpha or axes",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "axes",
            about: "semi-axis ratios [x, y, z], each > 0, longest over shortest ≤ 10, normalised to unit product; two equal: a spheroid (the distinct axis becomes body z)",
            is_list: true,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia of every rotational coordinate; None: a uniform solid ellipsoid of unit mass ((a² + b²)/5 for a spheroid, 2(a² + b² + c²)/15 triaxial)",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "warm_start",
            about: "true: the engine's energy pass starts each listed pair's gap solve at the normal where its last one ended; false: every solve starts at the line of centres (the same optimum to 1e-14, not the same bits); a packing that records none was made with false",
            is_list: false,
            default: Some("true"),
            added: Some(Added {
                before: "false",
                read_with: None,
            }),
        },
    ],
};

/// Parameters of `ellipsoid`, as read from an experiment file. Exactly one
/// of `alpha` and `axes` is given.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EllipsoidParams {
    /// The aspect ratio `α = a/b` of a spheroid.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub alpha: Option<f64>,
    /// Semi-axis ratios `[x, y, z]`.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub axes: Option<[f64; 3]>,
    /// Moment of inertia (`None`: a uniform solid ellipsoid of unit mass).
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub inertia: Option<f64>,
    /// Start each listed pair's solve where its last one ended. An
    /// experiment that does not give it runs `true` (the default the
    /// experiment layer fills in); `None` or a missing key reads as `false`,
    /// what a packing that records none was made with.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub warm_start: Option<bool>,
}

/// The `ellipsoid` family's registration.
pub struct EllipsoidFamily;

impl Family for EllipsoidFamily {
    const INFO: FamilyInfo = INFO;
    const EXAMPLE: &'static str = "(alpha: 1.5)";
    type Params = EllipsoidParams;

    /// `α = 1` (or three equal ratios) is the ball of radius `R⁰`: it runs
    /// as `sphere` (no rotational coordinates, the same random stream: the
    /// same packing for the same seed). The parameters are checked first.
    fn visit<V: ShapeVisitor>(
        p: &EllipsoidParams,
        dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        let shape = Ellipsoid::new(p)?;
        match (dim, shape.is_ball()) {
            (3, true) => jamkit_sphere::visit_ball(3, visitor),
            (3, false) => Ok(visitor.visit::<3, _>(shape)),
            _ => Err(Error::invalid("dim", dim, "ellipsoids exist in dim 3 only")),
        }
    }
}

/// Ellipsoids of the volume of the ball `R⁰` (crate documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Ellipsoid {
    /// `ξ = (ξ_x, ξ_y, ξ_z)`, unit product: semi-axes `R⁰ ξ` along the
    /// body axes.
    ratios: [f64; 3],
    /// `ξ_x = ξ_y` (a spheroid about body `z`): two rotational coordinates.
    axial: bool,
    /// All three equal: the ball.
    ball: bool,
    inertia: Option<f64>,
    /// Warm starts in the energy pass ([`Ellipsoid::exact_gap_warm`]).
    warm_start: bool,
}

impl Ellipsoid {
    /// Build and check the shape. Refused with the field named: both or
    /// neither of `alpha` and `axes`; `α` or a ratio not positive and
    /// finite; longest over shortest semi-axis above [`MAX_RATIO`]; an
    /// inertia not positive and finite.
    pub fn new(p: &EllipsoidParams) -> jamkit_core::Result<Self> {
        let (ratios, ball) = match (p.alpha, p.axes) {
            (Some(_), Some(_)) => {
                return Err(Error::invalid(
                    "params.alpha",
                    "given together with params.axes",
                    "give either alpha (a spheroid) or axes: [x, y, z] (general ratios), not both",
                ));
            }
            (None, None) => {
                return Err(Error::invalid(
                    "params",
                    "neither alpha nor axes",
                    "give alpha (a spheroid of aspect ratio α = a/b, e.g. alpha: 1.5) or axes: [x, y, z] (semi-axis ratios)",
                ));
            }
            (Some(alpha), None) => {
                if !(alpha > 0.0 && alpha.is_finite()) {
                    return Err(Error::invalid(
                        "params.alpha",
                        alpha,
                        "must be a finite number > 0 (α = a/b: > 1 prolate, < 1 oblate, 1 a sphere)",
                    ));
                }
                if alpha.max(1.0 / alpha) > MAX_RATIO {
                    return Err(Error::invalid(
                        "params.alpha",
                        alpha,
                        format!(
                            "must lie in [1/{MAX_RATIO}, {MAX_RATIO}]: longest over shortest semi-axis ≤ {MAX_RATIO}, the range the exact gap is tested on"
                        ),
                    ));
                }
                let b = alpha.powf(-1.0 / 3.0);
                ([b, b, alpha.powf(2.0 / 3.0)], alpha == 1.0)
            }
            (None, Some(v)) => {
                for (k, x) in v.iter().enumerate() {
                    if !(*x > 0.0 && x.is_finite()) {
                        return Err(Error::invalid(
                            format!("params.axes[{k}]"),
                            x,
                            "must be a finite number > 0 (a semi-axis ratio)",
                        ));
                    }
                }
                let (lo, hi) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
                if hi / lo > MAX_RATIO {
                    return Err(Error::invalid(
                        "params.axes",
                        format!("[{}, {}, {}]", v[0], v[1], v[2]),
                        format!(
                            "longest over shortest semi-axis must be ≤ {MAX_RATIO}, the range the exact gap is tested on (here {:.4})",
                            hi / lo
                        ),
                    ));
                }
                let norm = (v[0] * v[1] * v[2]).cbrt();
                let [x, y, z] = v.map(|x| x / norm);
                // Exactly two equal: the distinct axis along body z (a
                // cyclic relabelling).
                let ratios = if v[1] == v[2] && v[0] != v[1] {
                    [y, z, x]
                } else if v[0] == v[2] && v[0] != v[1] {
                    [z, x, y]
                } else {
                    [x, y, z]
                };
                (ratios, v[0] == v[1] && v[1] == v[2])
            }
        };
        if let Some(i) = p.inertia
            && !(i > 0.0 && i.is_finite())
        {
            return Err(Error::invalid(
                "params.inertia",
                i,
                "must be positive and finite, or None for a uniform solid ellipsoid of unit mass",
            ));
        }
        Ok(Self {
            axial: ratios[0] == ratios[1],
            ratios,
            ball,
            inertia: p.inertia,
            warm_start: p.warm_start.unwrap_or(false),
        })
    }

    /// The spheroid of aspect ratio `alpha` with the default inertia.
    pub fn spheroid(alpha: f64) -> jamkit_core::Result<Self> {
        Self::new(&EllipsoidParams {
            alpha: Some(alpha),
            axes: None,
            inertia: None,
            warm_start: None,
        })
    }

    /// The ellipsoid with semi-axis ratios `axes` (body `x, y, z`) and the
    /// default inertia.
    pub fn triaxial(axes: [f64; 3]) -> jamkit_core::Result<Self> {
        Self::new(&EllipsoidParams {
            alpha: None,
            axes: Some(axes),
            inertia: None,
            warm_start: None,
        })
    }

    /// The ratios `ξ` (unit product) of the semi-axes along body `x, y, z`.
    pub fn ratios(&self) -> [f64; 3] {
        self.ratios
    }

    /// The semi-axes `R⁰ ξ` of a body of size `size`.
    pub fn semi_axes(&self, size: f64) -> [f64; 3] {
        self.ratios.map(|x| x * size)
    }

    /// Whether the body is a spheroid about body `z` (two rotational
    /// coordinates).
    pub fn is_axisymmetric(&self) -> bool {
        self.axial
    }

    /// Whether the body is the ball (run as the `sphere` family).
    pub fn is_ball(&self) -> bool {
        self.ball
    }

    /// The largest semi-axis over `R⁰`.
    fn longest(&self) -> f64 {
        self.ratios[0].max(self.ratios[1]).max(self.ratios[2])
    }

    /// The support function of a body of size `size` and orientation `o`.
    #[inline(always)]
    pub fn support(&self, size: f64, o: &Quaternion) -> QuadraticSupport {
        QuadraticSupport::new(&o.columns(), self.semi_axes(size))
    }

    /// The rotation axes `e_p` of a body: the world axes, or `Q x̂, Q ŷ`
    /// for a spheroid.
    #[inline(always)]
    fn axes(&self, o: &Quaternion) -> [Vector<3>; 3] {
        if self.axial { o.columns() } else { WORLD_AXES }
    }

    /// The same shape with warm starts in the engine's energy pass on or
    /// off (the `warm_start` parameter).
    pub fn with_warm_start(mut self, warm_start: bool) -> Self {
        self.warm_start = warm_start;
        self
    }

    /// The exact gap of two bodies (crate documentation), or `None` when it
    /// certainly exceeds `max_gap`.
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
        let pair = Pair::new(size_i, *o_i, size_j, *o_j, *r_ij);
        let (_, si, sj) = self.supports(&pair, max_gap)?;
        gap3d::exact(r_ij, |u| si.jet(u), |u| sj.jet(u), max_gap)
    }

    /// The exact gap as the engine's pair loop finds it with `warm_start`
    /// ([`Shape::contacts_warm`]): the ascent started at the normal where
    /// the pair's last solve ended, kept in `memo` relative to the line of
    /// centres in body `i`'s frame ([`gap3d::normal_offset`]), so that a
    /// pair that moved or turned as a whole starts at its optimum;
    /// [`gap3d::exact_warm`] accepts it or solves cold. `memo` gets where
    /// this solve ended. The result is [`Ellipsoid::exact_gap`]'s optimum
    /// to the solver's tolerance (normal ~10⁻¹⁴, gap ~10⁻²⁸), whatever the
    /// memo holds, and `None` exactly where that is; with an empty memo it
    /// is [`Ellipsoid::exact_gap`]'s result bit for bit.
    #[inline]
    pub fn exact_gap_warm(
        &self,
        pair: &Pair<3, Quaternion>,
        max_gap: f64,
        memo: &mut PairMemo,
    ) -> Option<ExactGap3> {
        let r_ij = &pair.r_ij;
        let (ci, si, sj) = self.supports(pair, max_gap)?;
        let start = memo.as_ref().and_then(|m| {
            gap3d::normal_from_offset(&Vector::<3>::new(m[0], m[1], m[2]), r_ij, &ci)
        });
        let found = gap3d::exact_warm(
            r_ij,
            |u| si.jet(u),
            |u| sj.jet(u),
            start.as_ref(),
            max_gap,
            true,
        );
        if let Some(e) = &found {
            let a = gap3d::normal_offset(&e.normal, r_ij, &ci);
            let mut m = [0.0; MEMO_LEN];
            m[..3].copy_from_slice(a.as_slice());
            *memo = Some(m);
        }
        found
    }

    /// Body `i`'s rotation columns and the two bodies' support functions,
    /// or `None` when a bound shows the gap exceeds `max_gap`:
    /// `h ≥ r − (longest semi-axes)` before any work, and `h ≥ g(r̂)`
    /// before the quadratic forms are built.
    #[inline(always)]
    fn supports(
        &self,
        pair: &Pair<3, Quaternion>,
        max_gap: f64,
    ) -> Option<([Vector<3>; 3], QuadraticSupport, QuadraticSupport)> {
        let (size_i, size_j, r_ij) = (pair.size_i, pair.size_j, &pair.r_ij);
        // h ≥ r − (longest semi-axes): skip pairs certainly apart.
        let r = r_ij.norm();
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return None;
        }
        let (ci, cj) = (pair.o_i.columns(), pair.o_j.columns());
        // h ≥ g(r̂) = r − s_i(r̂) − s_j(−r̂), with s(u) = |diag(a, b, c) Qᵀ u|:
        // skip before building the quadratic forms (`gap3d::exact` makes
        // the same test again, on the forms, for pairs that get there).
        if r > 0.0 {
            let u = r_ij / r;
            let reach = |size: f64, c: &[Vector<3>; 3]| {
                (0..3)
                    .map(|k| (size * self.ratios[k] * c[k].dot(&u)).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            if r - reach(size_i, &ci) - reach(size_j, &cj) > max_gap {
                return None;
            }
        }
        Some((
            ci,
            QuadraticSupport::new(&ci, self.semi_axes(size_i)),
            QuadraticSupport::new(&cj, self.semi_axes(size_j)),
        ))
    }

    /// The asphericity `A = S³/(36π V²)` (1 for a ball), with the surface
    /// `S = ∫∫ √(b²c²(1 − z²)cos²φ + a²c²(1 − z²)sin²φ + a²b²z²) dz dφ` of
    /// the parametrisation `(a sin θ cos φ, b sin θ sin φ, c cos θ)`,
    /// `z = cos θ`, by Gauss–Legendre quadrature in `z` (`n` nodes) and the
    /// trapezoid rule in `φ` (`2n` points): the integrand is analytic and
    /// periodic in `φ`, so both converge geometrically (tests compare the
    /// spheroids' closed forms). For a spheroid `α = 1 + ε`,
    /// `A − 1 = (8/15) ε² + O(ε³)`, the value of the `harmonic` body `Ŷ_20`
    /// at `Δ = ε`: to first order in `ε` they are the same body,
    /// `R = R⁰[1 + ε (3 cos²θ − 1)/3]`.
    pub fn asphericity(&self, n: usize) -> f64 {
        let [a, b, c] = self.ratios;
        let (nodes, weights) = jamkit_core::math::gauss_legendre(n);
        let mut area = 0.0;
        for (z, w) in nodes.iter().zip(&weights) {
            let s2 = 1.0 - z * z;
            for k in 0..2 * n {
                let (sp, cp) = (PI * k as f64 / n as f64).sin_cos();
                let q = b * b * c * c * s2 * cp * cp
                    + a * a * c * c * s2 * sp * sp
                    + a * a * b * b * z * z;
                area += w * (PI / n as f64) * q.sqrt();
            }
        }
        let volume = 4.0 * PI / 3.0;
        area.powi(3) / (36.0 * PI * volume * volume)
    }

    /// `R(u)/R⁰` along the body-frame unit vector `y`:
    /// `1/√(Σ_k y_k²/ξ_k²)`.
    pub fn relative_radius(&self, y: &Vector<3>) -> f64 {
        let q: f64 = (0..3).map(|k| (y[k] / self.ratios[k]).powi(2)).sum();
        1.0 / q.sqrt()
    }
}

/// The drawing surface of an `ellipsoid` body (`jamkit draw`):
/// `ρ(y) = 1/√(Σ y_k²/ξ_k²)` in the body frame, the rotation of the
/// quaternion `[w, x, y, z]` the packing file stores.
#[derive(Clone, Debug)]
pub struct EllipsoidSurface(Ellipsoid);

impl jamkit_core::Surface for EllipsoidSurface {
    fn relative_radius(&self, y: [f64; 3]) -> f64 {
        self.0.relative_radius(&Vector::<3>::new(y[0], y[1], y[2]))
    }

    /// The shortest and the longest semi-axis over `R⁰`.
    fn relative_radius_bounds(&self) -> (f64, f64) {
        let r = self.0.ratios;
        (r[0].min(r[1]).min(r[2]), self.0.longest())
    }
}

impl Shape<3> for Ellipsoid {
    type Orientation = Quaternion;
    type Fast = NoFastPath;

    fn family(&self) -> &'static str {
        INFO.name
    }

    /// 3, or 2 for a spheroid.
    fn rot_dof(&self) -> usize {
        if self.axial { 2 } else { 3 }
    }

    /// `(4π/3)(R⁰)³`: the volume of the ball of radius `R⁰`.
    fn volume(&self, size: f64) -> f64 {
        4.0 * PI / 3.0 * size * size * size
    }

    /// The longest semi-axis.
    fn bounding_radius(&self, size: f64) -> f64 {
        size * self.longest()
    }

    /// A uniform solid ellipsoid of unit mass (crate documentation), or the
    /// configured value.
    fn rot_inertia(&self, size: f64) -> RotVec {
        let i = self.inertia.unwrap_or_else(|| {
            let [a, b, c] = self.semi_axes(size).map(|x| x * x);
            if self.axial {
                // About a transverse axis: (a² + c²)/5 with a = b.
                (a + c) / 5.0
            } else {
                2.0 * (a + b + c) / 15.0
            }
        });
        [i; MAX_ROT]
    }

    /// `Q → exp(ω) Q` (world frame), or `Q → Q exp((dq₀, dq₁, 0))` (body
    /// frame) for a spheroid; renormalised.
    fn rotate(&self, o: &mut Quaternion, dq: &[f64]) {
        *o = o.stepped(dq, self.axial);
    }

    /// Rattlers below `d + 1 = 4` contacts, the paper's convention carried
    /// to 3D; ellipsoids jam hypostatic (Donev et al. 2004).
    fn policy(&self) -> Policy {
        Policy {
            expects_isostatic: false,
            ..Policy::new(3)
        }
    }

    /// The ellipsoid, for drawing ([`EllipsoidSurface`]), and its ratios `ξ`
    /// along the body axes for export (none for the ball).
    fn look(&self) -> Look {
        Look {
            surface: Some(std::sync::Arc::new(EllipsoidSurface(self.clone()))),
            ellipsoid_axes: (!self.ball).then_some(self.ratios),
            ..Look::default()
        }
    }

    #[inline]
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
        if let Some(e) = self.exact_gap(size_i, o_i, size_j, o_j, r_ij, max_gap) {
            visit(e.contact(&self.axes(o_i), &self.axes(o_j), self.rot_dof()));
        }
    }

    /// With `warm_start`, each listed pair's solve starts where its last
    /// one ended ([`Ellipsoid::exact_gap_warm`]); otherwise
    /// [`Shape::contacts`] (cold, bit for bit the packings made without
    /// the parameter).
    #[inline]
    fn contacts_warm<F: FnMut(Contact<3>)>(
        &self,
        pair: &Pair<3, Quaternion>,
        max_gap: f64,
        memo: &mut PairMemo,
        mut visit: F,
    ) {
        if !self.warm_start {
            return self.contacts(pair, max_gap, visit);
        }
        if let Some(e) = self.exact_gap_warm(pair, max_gap, memo) {
            visit(e.contact(&self.axes(&pair.o_i), &self.axes(&pair.o_j), self.rot_dof()));
        }
    }

    fn gap_hessians<V: FnMut(GapHessian<3>)>(
        &self,
        pair: &Pair<3, Quaternion>,
        max_gap: f64,
        mut visit: V,
    ) -> jamkit_core::Result<()> {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        if let Some(e) = self.exact_gap(size_i, o_i, size_j, o_j, r_ij, max_gap) {
            visit(e.hessian(&self.axes(o_i), &self.axes(o_j), self.rot_dof()));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod warm_tests;
