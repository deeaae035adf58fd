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
//! Beyond the first-order gap: a profile that also gives the third
//! derivative ([`NearDiskProfile::jet3`]) may run with the second-order or
//! the exact gap ([`GapModel`], [`Profiled::with_gap`]; see
//! [`crate::gap2d`]). The orientation type is a parameter
//! ([`PlanarOrientation`]): [`Angle<1>`] by default, [`Rotation2`] for a
//! family whose packings were made with it (`fourier`). A family with a
//! kernel of its own for many pairs at once wraps `Profiled` in a type of
//! its own that names it as its `Shape::Fast` (`fourier` does).
//!
//! NOTE: the pair loop calls no `atan2`, `sin` or `cos`: `e^{iA_i} =
//! e^{iθ_i} e^{−iθ_ij}` is a complex product of the cached `e^{iθ_i}`
//! ([`PlanarOrientation::unit`]) and the unit vector `u`. For body `j` the
//! `−π` of `A_j` flips the signs of both `cos A_j` and `sin A_j`; a profile
//! that declares itself symmetric under a half turn (`P(A + π) = P(A)`, as
//! for every even mode) gets the unflipped pair, which it cannot tell
//! apart.

use crate::arcs::{self, OutlineArc};
use crate::first_order::{Profile, gap_hessian};
use crate::gap2d::{self, GapModel, Jet3, SupportJet, direction};
use jamkit_core::math::{Unit, cmul, turn_unit};
use jamkit_core::{
    Angle, BodyOrientation, Contact, ContactLanes, Error, GapHessian, Look, MAX_ROT, MEMO_LEN,
    NoFastPath, Outline, Pair, PairLanes, PairMemo, Policy, RotVec, Rotation2, Shape, Vector, Warm,
    contacts_warm_one_by_one,
};
use std::f64::consts::PI;
use std::fmt::Debug;
use std::marker::PhantomData;

/// A planar orientation as the near-disks use it: `e^{iθ}` for the pair
/// loop, and a turn by `dθ` for the rotational coordinate.
pub trait PlanarOrientation: BodyOrientation {
    /// `e^{iθ} = (cos θ, sin θ)`.
    fn unit(&self) -> Unit;
    /// Turned by `dθ`.
    fn turned(self, dtheta: f64) -> Self;
}

/// `θ` accumulated, `e^{iθ}` by `sin_cos` after every turn
/// ([`Angle::turned`]); the file's `[θ]` reads back to the bit.
impl PlanarOrientation for Angle<1> {
    #[inline(always)]
    fn unit(&self) -> Unit {
        Angle::unit(self)
    }
    #[inline]
    fn turned(self, dtheta: f64) -> Self {
        Angle::turned(self, dtheta)
    }
}

/// `e^{iθ}` turned by the Taylor series of `e^{i dθ}`
/// ([`Rotation2::turned`]).
impl PlanarOrientation for Rotation2 {
    #[inline(always)]
    fn unit(&self) -> Unit {
        Rotation2::unit(self)
    }
    #[inline]
    fn turned(self, dtheta: f64) -> Self {
        Rotation2::turned(self, dtheta)
    }
}

/// The profile `P` of a near-disk family, `R(φ)/R⁰ = 1 + Δ P(φ)`.
pub trait NearDiskProfile: Clone + Debug + PartialEq + Send + Sync + 'static {
    /// The family's registered name.
    const FAMILY: &'static str;
    /// Whether `P(A + π) = P(A)` for every `A` (then body `j`'s angle may
    /// drop the `−π`; see the module notes).
    const HALF_TURN_SYMMETRIC: bool;
    /// Whether the Hessian's phases take the line of centres as `r_ij / r`
    /// (true) or, as the pair loop does, as `r_ij · (1/r)` (false, the
    /// default). The two differ in the last bit for about a fifth of
    /// pairs; `fourier`'s packings were made with the division.
    const HESSIAN_DIVIDES: bool = false;

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

    /// `[P, P', P'', P‴]` from `cos A` and `sin A`, for the second-order
    /// and the exact gap; `None` (the default): the profile has the
    /// first-order gap only.
    fn jet3(&self, _cos: f64, _sin: f64) -> Option<Jet3> {
        None
    }

    /// A bound on `|P'|` over the circle, for the exact gap's skip of far
    /// pairs; `None` (the default): every pair goes to the iteration.
    fn slope_bound(&self) -> Option<f64> {
        None
    }
}

/// How [`Profiled::exact_solve`] finds the exact gap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExactSolve {
    /// The joint iteration ([`gap2d::exact_joint`]) from first-order
    /// guesses of the normal and the support points, and the nested solve
    /// where it fails: what contacts and Hessians use.
    Joint,
    /// The joint iteration alone (`None` where it fails or is not run:
    /// pairs closer than its reach), for tests.
    JointAlone,
    /// The nested solve alone ([`gap2d::exact_unit`] on
    /// [`gap2d::polar_support_unit`] supports from the line of centres), a
    /// check: it agrees with the joint iteration to the solvers' tolerance,
    /// not to the bit.
    Nested,
}

/// A near-disk of profile `P` and orientation type `O`: `Δ`, the moment of
/// inertia, the gap model, and the area constants computed once.
#[derive(Clone, Debug, PartialEq)]
pub struct Profiled<P, O = Angle<1>> {
    profile: P,
    delta: f64,
    inertia: f64,
    /// `P`'s range and moments.
    range: (f64, f64),
    moments: (f64, f64),
    gap: GapModel,
    /// Per unit size, how far the exact gap can fall below the first-order
    /// one (`Δ² P'²_max / (1 − Δ P_max)`, ∞ where that bound is not proven).
    exact_slack: f64,
    /// Per unit size, the centre distance above which the joint iteration
    /// runs: `2 max(max(H − ρ), max R − min R)` over the outline
    /// ([`Profiled::exact_solve`]).
    joint_reach: f64,
    /// The outline's arcs between inflection points, for the exact gap of
    /// a non-convex outline ([`crate::arcs`]); `None` otherwise.
    arcs: Option<std::sync::Arc<Vec<OutlineArc>>>,
    orientation: PhantomData<O>,
}

impl<P: NearDiskProfile> Profiled<P> {
    /// The shape of amplitude `delta` and moment of inertia `inertia`
    /// (`None`: `I = Δ`, the paper's choice, or 1 for the disk `Δ = 0`,
    /// whose turning changes nothing), checked: `Δ ≥ 0` finite, `I`
    /// positive and finite, and `R(φ) > 0` everywhere. Errors name
    /// `params.delta` or `params.inertia`. The first-order gap, orientations
    /// [`Angle<1>`].
    pub fn new(profile: P, delta: f64, inertia: Option<f64>) -> jamkit_core::Result<Self> {
        Self::with_orientation(profile, delta, inertia)
    }
}

impl<P: NearDiskProfile, O: PlanarOrientation> Profiled<P, O> {
    /// [`Profiled::new`] with orientations of type `O`.
    pub fn with_orientation(
        profile: P,
        delta: f64,
        inertia: Option<f64>,
    ) -> jamkit_core::Result<Self> {
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
            gap: GapModel::FirstOrder,
            exact_slack: f64::INFINITY,
            joint_reach: f64::INFINITY,
            arcs: None,
            orientation: PhantomData,
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

    /// The same shape with the gap model `gap`. The second-order and the
    /// exact gap need the profile's [`NearDiskProfile::jet3`]; errors name
    /// `params.gap`. On a non-convex outline the exact gap is the arcs'
    /// ([`crate::arcs`]: several contacts per pair) with the inscribed
    /// disks' core ([`Profiled::core_contact`]), on a convex one the
    /// convex exact gap.
    pub fn with_gap(mut self, gap: GapModel) -> jamkit_core::Result<Self> {
        if gap != GapModel::FirstOrder && self.profile.jet3(1.0, 0.0).is_none() {
            return Err(Error::invalid(
                "params.gap",
                format!("{gap:?}"),
                format!(
                    "must be FirstOrder: the profile ({}) gives no third derivative",
                    self.profile.describe()
                ),
            ));
        }
        self.arcs = None;
        if gap == GapModel::Exact && !self.is_convex() {
            let arcs = arcs::split_arcs(&|p: Unit| self.unit_outline(p), 8192);
            if arcs.len() < 2 {
                return Err(Error::invalid(
                    "params.gap",
                    "Exact",
                    format!(
                        "found no inflection point on the non-convex outline at Δ = {} ({}) on 8192 angles: the outline is too finely wrinkled for the exact gap",
                        self.delta,
                        self.profile.describe()
                    ),
                ));
            }
            self.arcs = Some(std::sync::Arc::new(arcs));
        }
        let (d, f_max) = (self.delta, self.range.1);
        // The bound needs R_max/R_min = (1 + ΔP)/(1 − ΔP) < 1.85.
        self.exact_slack = match self.profile.slope_bound() {
            Some(df_max) if d * f_max < 0.25 => d * d * df_max * df_max / (1.0 - d * f_max),
            _ => f64::INFINITY,
        };
        self.joint_reach = self.joint_reach();
        self.gap = gap;
        Ok(self)
    }

    /// `2 max(c, s)` per unit size, with `c = max(H − ρ)` (how far below
    /// `−H` the support function's `H''` = ρ − H can reach) and
    /// `s = Δ (max P − min P)` (the spread of `R`), on 8192 points of the
    /// outline (support point `R(φ)`, normal angle `φ − atan(R'/R)`).
    fn joint_reach(&self) -> f64 {
        let d = self.delta;
        let c = (0..8192)
            .map(|k| {
                let (sin, cos) = (2.0 * PI * k as f64 / 8192.0).sin_cos();
                let (p, dp) = self.profile.value_slope(cos, sin);
                let (r, dr, ddr) = (1.0 + d * p, d * dp, d * self.profile.curvature(cos, sin));
                let q = r * r + dr * dr;
                let rho = q * q.sqrt() / (r * r + 2.0 * dr * dr - r * ddr);
                r * r / q.sqrt() - rho
            })
            .fold(0.0, f64::max);
        2.0 * c.max(d * (self.range.1 - self.range.0))
    }

    /// The gap model.
    pub fn gap_model(&self) -> GapModel {
        self.gap
    }

    /// The arcs of a non-convex outline with the exact gap ([`crate::arcs`]),
    /// `None` for every other shape.
    pub fn arcs(&self) -> Option<&[OutlineArc]> {
        self.arcs.as_deref().map(|a| a.as_slice())
    }

    /// The body-frame outline at unit size, `(R, R', R'')` at `e^{iφ}`:
    /// `R(φ) = 1 + Δ P(−φ)` (needs the profile's third-order jet).
    pub fn unit_outline(&self, p: Unit) -> (f64, f64, f64) {
        let d = self.delta;
        let [f, df, ddf, _] = self.jet3((p.0, -p.1));
        (1.0 + d * f, -d * df, d * ddf)
    }

    /// Every exact contact of a pair of non-convex bodies with gap at most
    /// `max_gap` ([`arcs::arc_contacts`]: all of them with overlaps up to
    /// the depth of two lobes, `Δ (max P − min P)(R_i⁰ + R_j⁰)`; called only when
    /// [`Profiled::arcs`] is set), or, given `arcs`, those of these arcs
    /// (e.g. the whole outline as one arc, for tests).
    pub fn arc_contacts(
        &self,
        pair: &Pair<2, O>,
        max_gap: f64,
        arcs: Option<&[OutlineArc]>,
        visit: &mut dyn FnMut(arcs::ArcContact),
    ) {
        let Some(arcs) = arcs.or(self.arcs()) else {
            return;
        };
        let outline = |p: Unit| self.unit_outline(p);
        let theta = |o: &O| {
            let (c, s) = o.unit();
            s.atan2(c)
        };
        let body = |size: f64, o: &O| arcs::ArcBody {
            arcs,
            outline: &outline,
            size,
            theta: theta(o),
        };
        arcs::arc_contacts(
            &body(pair.size_i, &pair.o_i),
            &body(pair.size_j, &pair.o_j),
            &pair.r_ij,
            max_gap,
            self.delta * (self.range.1 - self.range.0) * (pair.size_i + pair.size_j),
            visit,
        );
    }

    /// The contact of the two bodies' inscribed disks (radii
    /// `R⁰ (1 + Δ min P)`) while they overlap, as an [`gap2d::ExactGap`]
    /// along the line of centres (`h = r − a − b`, support jets `(a, 0, 0)`
    /// and `(b, 0, 0)`, so `k = r`): the exact gap's core for a non-convex
    /// outline (`docs/explanation/non-convex-gap.md#core`). `None` when the
    /// disks do not overlap.
    pub fn core_contact(&self, pair: &Pair<2, O>) -> Option<gap2d::ExactGap> {
        let m = self.min_relative_radius();
        let (a, b) = (pair.size_i * m, pair.size_j * m);
        let r = pair.r_ij.norm();
        let gap = r - a - b;
        if !(gap < 0.0) {
            return None;
        }
        let normal = if r > 0.0 {
            (pair.r_ij[0] / r, pair.r_ij[1] / r)
        } else {
            (1.0, 0.0)
        };
        let jet = |h: f64| SupportJet {
            h,
            d1: 0.0,
            d2: 0.0,
        };
        Some(gap2d::ExactGap {
            normal,
            gap,
            jet_i: jet(a),
            jet_j: jet(b),
            iterations: 0,
            converged: true,
        })
    }

    /// [`Shape::contacts`] beyond the bounding test for a non-convex exact
    /// gap (the arcs' contacts and the core's): out of line, so that the
    /// other models' pair loop keeps one call site of `visit`.
    #[cold]
    #[inline(never)]
    fn several_contacts(&self, pair: &Pair<2, O>, max_gap: f64, visit: &mut dyn FnMut(Contact<2>)) {
        self.arc_contacts(pair, max_gap, None, &mut |e| visit(e.contact()));
        if let Some(e) = self.core_contact(pair) {
            visit(e.contact());
        }
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
    /// symmetric under a half turn): bit for bit the complex products
    /// `e^{iθ_i} ū` and `−e^{iθ_j} ū`.
    #[inline(always)]
    pub fn phases(&self, o_i: &O, o_j: &O, u: &Vector<2>) -> [(f64, f64); 2] {
        // e^{iA} = e^{iθ} e^{−iθ_ij}: cos A = cos θ u_x + sin θ u_y,
        // sin A = sin θ u_x − cos θ u_y.
        let phase = |o: &O| {
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

    /// The first-order contact ([`Shape::contacts`] without the bounding
    /// test).
    #[inline(always)]
    pub fn first_order(&self, pair: &Pair<2, O>) -> Contact<2> {
        self.first_order_at(pair, direction(&pair.r_ij))
    }

    /// [`Profiled::first_order`] given `(|r_ij|, r_ij/|r_ij|, 1/|r_ij|)`
    /// ([`direction`]).
    #[inline(always)]
    fn first_order_at(
        &self,
        pair: &Pair<2, O>,
        (r, u, inv_r): (f64, Vector<2>, f64),
    ) -> Contact<2> {
        let (size_i, size_j) = (pair.size_i, pair.size_j);
        let [(ci, si), (cj, sj)] = self.phases(&pair.o_i, &pair.o_j, &u);
        let (p_i, dp_i) = self.profile.value_slope(ci, si);
        let (p_j, dp_j) = self.profile.value_slope(cj, sj);
        let d = self.delta;
        let gap = r - size_i - size_j - d * (size_i * p_i + size_j * p_j);
        let tangent = Vector::<2>::new(-u[1], u[0]);
        let grad_r = u + tangent * (d * (size_i * dp_i + size_j * dp_j) * inv_r);
        Contact {
            gap,
            grad_r,
            grad_rot_i: [-d * size_i * dp_i, 0.0, 0.0],
            grad_rot_j: [-d * size_j * dp_j, 0.0, 0.0],
        }
    }

    /// `[P, P', P'', P‴]` at a phase (called only for the gap models that
    /// [`Profiled::with_gap`] admitted, which checked the profile has it).
    #[inline(always)]
    fn jet3(&self, (cos, sin): (f64, f64)) -> Jet3 {
        self.profile
            .jet3(cos, sin)
            .expect("with_gap admits the higher gap models only with a third derivative")
    }

    /// The contact of the second-order or the exact gap (the exact one
    /// started from `memo` where given, [`Profiled::exact_solve_warm`]).
    ///
    /// NOTE: kept out of line and cold: inlined into the pair loop, these
    /// paths made `fourier`'s first-order packings 17 % slower (n = 2,
    /// Δ = 0.1, N = 256, same bits).
    #[cold]
    #[inline(never)]
    fn beyond_first_order(&self, pair: &Pair<2, O>, r: f64, max_gap: f64) -> Option<Contact<2>> {
        match self.gap {
            GapModel::SecondOrder => Some(self.second_order(pair).contact(&pair.r_ij)),
            _ => self
                .exact_in(pair, r, max_gap, ExactSolve::Joint, None, false)
                .map(|e| e.contact()),
        }
    }

    /// The exact contact of [`Shape::contact_warm`]
    /// ([`Profiled::exact_solve_warm`]) past the bounding test at `r =
    /// |r_ij|`: out of line as [`Profiled::beyond_first_order`], though not
    /// cold (the pair loop of the exact gap calls it for every pair).
    #[inline(never)]
    fn exact_warm(
        &self,
        pair: &Pair<2, O>,
        r: f64,
        max_gap: f64,
        memo: &mut PairMemo,
    ) -> Option<Contact<2>> {
        self.exact_in(pair, r, max_gap, ExactSolve::Joint, Some(memo), false)
            .map(|e| e.contact())
    }

    /// The warm exact contacts of the first `len` of `W` pairs
    /// ([`FastContacts::contacts_warm_lanes`](jamkit_core::FastContacts::contacts_warm_lanes)):
    /// lane `l` gets [`Shape::contacts_warm`]'s contact with memo
    /// `memos[at[l]]` and leaves in it what that call leaves, bit for bit.
    /// `value_slope` maps `e^{iA}` to `(P, P')` and `jet` to
    /// `[P, P', P'', P‴]`, bit for bit the profile's; `scratch` is any
    /// vector (it grows to 38 arrays).
    ///
    /// A pass over the lanes with no branch computes the bounding test, the
    /// first-order screen and the joint iteration's first step from the
    /// memo (`gap2d::joint_step`), each the same operations in the same
    /// order as [`Profiled::exact_solve_warm`]; the pairs that go on take
    /// their further steps side by side, gathered into the first lanes, up
    /// to [`WARM_LANE_STEPS`] steps in all. The pairs that these steps do
    /// not settle (no memo, a failed safeguard, pairs within the joint
    /// iteration's reach, a normal out of its cone) go through
    /// [`Profiled::exact_solve_warm`] one at a time, from the start.
    ///
    /// NOTE: each pass is straight-line code over plain arrays, so that the
    /// compiler vectorises it (four lanes per AVX2 instruction, square
    /// roots and divisions included); the scalar solve of a pair is a
    /// chain of dependent operations that leaves most of the core idle.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn exact_warm_lanes<const W: usize>(
        &self,
        pairs: &PairLanes<2, O, W>,
        (len, max_gap): (usize, f64),
        (memos, at): (&mut [PairMemo], &[u32; W]),
        scratch: &mut Vec<[f64; W]>,
        out: &mut ContactLanes<2, W>,
        value_slope: impl Fn(Unit) -> (f64, f64),
        jet: impl Fn(Unit) -> Jet3,
    ) {
        if self.gap != GapModel::Exact || self.arcs.is_some() {
            return contacts_warm_one_by_one(self, pairs, len, max_gap, memos, at, out);
        }
        let len = len.min(W);
        // Per lane: the memo's first six numbers, then those of the
        // result (`M..`); where a going-on pair stands and the pair
        // (`GO..`, see below); the results of the further steps (`FOUND..`).
        const M: usize = 0;
        const GO: usize = 6;
        const FOUND: usize = 27;
        if scratch.len() < SCRATCH {
            scratch.resize(SCRATCH, [0.0; W]);
        }
        let s: &mut [[f64; W]; SCRATCH] = (&mut scratch[..SCRATCH])
            .try_into()
            .expect("SCRATCH arrays make an array of SCRATCH");
        let mut has = [false; W];
        for l in 0..len {
            has[l] = match &memos[at[l] as usize] {
                Some(v) => {
                    for k in 0..6 {
                        s[M + k][l] = v[k];
                    }
                    true
                }
                None => false,
            };
        }
        let (d, slack, reach) = (self.delta, self.exact_slack, self.joint_reach);
        // (R, R', R'', R‴) of a body of size `size`, as `exact_in`'s.
        let sized = |size: f64| {
            let jet = &jet;
            move |p: Unit| {
                let [f, df, ddf, dddf] = jet((p.0, -p.1));
                (
                    size * (1.0 + d * f),
                    size * (-d * df),
                    size * (d * ddf),
                    size * (-d * dddf),
                )
            }
        };
        // Per lane: 0 no contact, 1 solved here, 2 to the scalar solve,
        // 3 going on.
        let mut state = [0u8; W];
        for l in 0..W {
            let (x, y) = (pairs.r_ij[0][l], pairs.r_ij[1][l]);
            let (size_i, size_j) = (pairs.size_i[l], pairs.size_j[l]);
            let r = pairs.r2[l].sqrt();
            // `contact_warm`'s bounding test.
            let apart = r - pairs.reach_i[l] - pairs.reach_j[l] > max_gap;
            // `exact_in`: the line of centres and the first-order screen
            // (`first_order_at` and `phases`).
            let positive = r > 0.0;
            let inv = 1.0 / r;
            let inv_r = if positive { inv } else { 0.0 };
            let (lx, ly) = if positive {
                (x * inv_r, y * inv_r)
            } else {
                (1.0, 0.0)
            };
            let (z_i, z_j) = (pairs.o_i[l].unit(), pairs.o_j[l].unit());
            let phase = |(c, s): Unit| (c * lx + s * ly, s * lx - c * ly);
            let (cj, sj) = phase(z_j);
            let a_j = if P::HALF_TURN_SYMMETRIC {
                (cj, sj)
            } else {
                (-cj, -sj)
            };
            let ((p_i, _), (p_j, _)) = (value_slope(phase(z_i)), value_slope(a_j));
            let gap1 = r - size_i - size_j - d * (size_i * p_i + size_j * p_j);
            let far = gap1 - slack * (size_i + size_j) > max_gap;
            // The warm joint iteration's start and first step.
            let u = if positive { (x / r, y / r) } else { (1.0, 0.0) };
            let within = r > reach * (size_i + size_j);
            let w0 = cmul(u, (s[M][l], s[M + 1][l]));
            let (zi_bar, zj_bar_neg) = ((z_i.0, -z_i.1), (-z_j.0, z_j.1));
            let e_i = cmul(cmul(w0, zi_bar), (s[M + 2][l], s[M + 3][l]));
            let e_j = cmul(cmul(w0, zj_bar_neg), (s[M + 4][l], s[M + 5][l]));
            let js = gap2d::joint_step(
                &Vector::<2>::new(x, y),
                w0,
                z_i,
                e_i,
                sized(size_i),
                z_j,
                e_j,
                sized(size_j),
                f64::INFINITY,
            );
            let e = js.gap;
            let cone = e.normal.0 * x + e.normal.1 * y >= 0.5 * r;
            let warm = within & has[l];
            let solved = !(apart | far) & warm & js.finished & cone;
            state[l] = if apart | far {
                0
            } else if solved {
                1
            } else if warm & js.go_on {
                3
            } else {
                2
            };
            out.found[l] = solved;
            out.gap[l] = e.gap;
            out.grad_r[0][l] = e.normal.0;
            out.grad_r[1][l] = e.normal.1;
            out.grad_rot_i[0][l] = e.jet_i.d1;
            out.grad_rot_j[0][l] = e.jet_j.d1;
            for a in 1..MAX_ROT {
                out.grad_rot_i[a][l] = 0.0;
                out.grad_rot_j[a][l] = 0.0;
            }
            let kept = remember(&e, u);
            for k in 0..6 {
                s[M + k][l] = kept[k];
            }
            // Where the pair stands after the step.
            let now = [
                w0.0, w0.1, e_i.0, e_i.1, e_j.0, e_j.1, js.step[0], js.step[1], js.step[2], js.len,
                u.0, u.1,
            ];
            for (k, x) in now.into_iter().enumerate() {
                s[GO + k][l] = x;
            }
        }
        // The going-on lanes, gathered into the first `count` (their
        // lanes in `origin`), with their pairs: `GO + 12..` hold `x`, `y`,
        // `r`, `R⁰_i`, `R⁰_j`, `e^{iθ_i}`, `e^{iθ_j}`.
        let mut origin = [0usize; W];
        let mut count = 0;
        for l in 0..len {
            if state[l] == 3 {
                for a in &mut s[GO..GO + 12] {
                    a[count] = a[l];
                }
                let (z_i, z_j) = (pairs.o_i[l].unit(), pairs.o_j[l].unit());
                let pair = [
                    pairs.r_ij[0][l],
                    pairs.r_ij[1][l],
                    pairs.r2[l].sqrt(),
                    pairs.size_i[l],
                    pairs.size_j[l],
                    z_i.0,
                    z_i.1,
                    z_j.0,
                    z_j.1,
                ];
                for (k, x) in pair.into_iter().enumerate() {
                    s[GO + 12 + k][count] = x;
                }
                origin[count] = l;
                count += 1;
            }
        }
        let mut steps = 1;
        while count > 0 && steps < WARM_LANE_STEPS {
            steps += 1;
            let mut now = [0u8; W];
            // Blocks of `B` lanes, copied out so that the pass over a block
            // has a constant length (whole vectors, no bounds).
            const B: usize = 8;
            for base in (0..count.min(W)).step_by(B) {
                let g: [[f64; B]; 21] = std::array::from_fn(|k| {
                    std::array::from_fn(|t| s[GO + k][(base + t).min(W - 1)])
                });
                let mut stands = [[0.0; B]; 10];
                let mut found = [[0.0; B]; 11];
                let mut settled = [0u8; B];
                for t in 0..B {
                    let g = |k: usize| g[k][t];
                    let w = gap2d::turn_select((g(0), g(1)), g(6));
                    let p_i = gap2d::turn_select((g(2), g(3)), g(7));
                    let p_j = gap2d::turn_select((g(4), g(5)), g(8));
                    let (x, y, r) = (g(12), g(13), g(14));
                    let js = gap2d::joint_step(
                        &Vector::<2>::new(x, y),
                        w,
                        (g(17), g(18)),
                        p_i,
                        sized(g(15)),
                        (g(19), g(20)),
                        p_j,
                        sized(g(16)),
                        g(9),
                    );
                    let e = js.gap;
                    let cone = e.normal.0 * x + e.normal.1 * y >= 0.5 * r;
                    let kept = remember(&e, (g(10), g(11)));
                    settled[t] = if js.finished & cone {
                        1
                    } else if js.go_on {
                        3
                    } else {
                        2
                    };
                    let now = [
                        w.0, w.1, p_i.0, p_i.1, p_j.0, p_j.1, js.step[0], js.step[1], js.step[2],
                        js.len,
                    ];
                    for (a, x) in stands.iter_mut().zip(now) {
                        a[t] = x;
                    }
                    let result = [e.gap, e.normal.0, e.normal.1, e.jet_i.d1, e.jet_j.d1];
                    for (a, x) in found.iter_mut().zip(result.into_iter().chain(kept)) {
                        a[t] = x;
                    }
                }
                for t in 0..B.min(count - base) {
                    for (k, a) in stands.iter().enumerate() {
                        s[GO + k][base + t] = a[t];
                    }
                    for (k, a) in found.iter().enumerate() {
                        s[FOUND + k][base + t] = a[t];
                    }
                    now[base + t] = settled[t];
                }
            }
            let mut next_count = 0;
            for t in 0..count.min(W) {
                let l = origin[t];
                state[l] = now[t];
                match now[t] {
                    1 => {
                        out.found[l] = true;
                        out.gap[l] = s[FOUND][t];
                        out.grad_r[0][l] = s[FOUND + 1][t];
                        out.grad_r[1][l] = s[FOUND + 2][t];
                        out.grad_rot_i[0][l] = s[FOUND + 3][t];
                        out.grad_rot_j[0][l] = s[FOUND + 4][t];
                        for k in 0..6 {
                            s[M + k][l] = s[FOUND + 5 + k][t];
                        }
                    }
                    3 => {
                        for a in &mut s[GO..FOUND] {
                            a[next_count] = a[t];
                        }
                        origin[next_count] = l;
                        next_count += 1;
                    }
                    _ => {}
                }
            }
            count = next_count;
        }
        for &l in &origin[..count] {
            state[l] = 2;
        }
        for l in 0..len {
            let memo = &mut memos[at[l] as usize];
            match state[l] {
                1 => {
                    *memo = Some(std::array::from_fn(
                        |k| {
                            if k < 6 { s[M + k][l] } else { 0.0 }
                        },
                    ));
                }
                2 => {
                    out.found[l] = false;
                    let pair = pairs.pair(l);
                    let r = pairs.r2[l].sqrt();
                    if let Some(c) = self.exact_warm(&pair, r, max_gap, memo) {
                        out.set(l, &c);
                    }
                }
                _ => {}
            }
        }
    }

    /// The second-order gap's partials (see [`crate::gap2d`]).
    fn second_order(&self, pair: &Pair<2, O>) -> gap2d::Partials {
        let (r, u, _) = direction(&pair.r_ij);
        let [a_i, a_j] = self.phases(&pair.o_i, &pair.o_j, &u);
        gap2d::second_order(
            r,
            pair.size_i,
            pair.size_j,
            self.delta,
            self.jet3(a_i),
            self.jet3(a_j),
        )
    }

    /// The exact gap of a pair, or `None` when it certainly exceeds
    /// `max_gap` (or, with [`ExactSolve::JointAlone`], where the joint
    /// iteration fails), by the solver `solve` ([`ExactSolve`]), started
    /// cold (from the first-order guesses below): the solve of
    /// [`Shape::contacts`] and [`Shape::gap_hessians`]. In the body frame
    /// the outline is `R(φ)/R⁰ = 1 + Δ P(−φ)`, and orientation `θ` turns it
    /// counter-clockwise by `θ`.
    ///
    /// Two uses of the first-order gap `h₁` (cheap):
    /// * a bound: `h ≥ h₁ − (s_i + s_j)`, with `s = R⁰ Δ² P'²_max / (1 − Δ P_max)`
    ///   (the support function exceeds the radius `R(ψ)` by at most
    ///   `(6/11) L²/R_min`, `L = max|R'|`, when `R_max < 1.85 R_min`; see
    ///   `docs/explanation/gap-models.md`, "Exact"), so far pairs skip the
    ///   iteration;
    /// * the first guess of the normal, `ψ₀ = θ_ij + Δ(R_i⁰P_i' + R_j⁰P_j')/r`,
    ///   exact to `O(Δ²)`.
    ///
    /// Called only for a shape whose gap model is `Exact` (else the
    /// profile's third derivative may be missing).
    pub fn exact_solve(
        &self,
        pair: &Pair<2, O>,
        max_gap: f64,
        solve: ExactSolve,
    ) -> Option<gap2d::ExactGap> {
        self.exact_in(pair, pair.r_ij.norm(), max_gap, solve, None, true)
    }

    /// The exact gap as the engine's pair loop finds it
    /// ([`Shape::contacts_warm`]): the joint iteration started where the
    /// pair's last solve ended (`memo`: the normal relative to the line of
    /// centres and each support point relative to its body's direction, as
    /// unit complex numbers), else, or where that fails, the cold solve of
    /// [`Profiled::exact_solve`] with [`ExactSolve::Joint`]; `memo` gets
    /// where this solve ended. The far-pair bound and the joint iteration's
    /// reach and safeguards are the cold solve's, and its result is the
    /// same optimum to round-off ([`gap2d::JOINT_FINISH`]), whatever the
    /// memo holds. Where the joint iteration converges `H''` is not
    /// computed (NaN): the contacts do not need it.
    pub fn exact_solve_warm(
        &self,
        pair: &Pair<2, O>,
        max_gap: f64,
        memo: &mut PairMemo,
    ) -> Option<gap2d::ExactGap> {
        self.exact_in(
            pair,
            pair.r_ij.norm(),
            max_gap,
            ExactSolve::Joint,
            Some(memo),
            false,
        )
    }

    /// [`Profiled::exact_solve`] at `r = |r_ij|` with a memo (warm start
    /// and record, for [`ExactSolve::Joint`]) and `H''` only with `second`.
    #[inline(always)]
    fn exact_in(
        &self,
        pair: &Pair<2, O>,
        r: f64,
        max_gap: f64,
        solve: ExactSolve,
        memo: Option<&mut PairMemo>,
        second: bool,
    ) -> Option<gap2d::ExactGap> {
        let (size_i, size_j, r_ij) = (pair.size_i, pair.size_j, &pair.r_ij);
        let inv_r = if r > 0.0 { 1.0 / r } else { 0.0 };
        let line = if r > 0.0 {
            r_ij * inv_r
        } else {
            Vector::<2>::new(1.0, 0.0)
        };
        let first = self.first_order_at(pair, (r, line, inv_r));
        if first.gap - self.exact_slack * (size_i + size_j) > max_gap {
            return None;
        }
        // ψ₀ as the turn `dψ` of the line of centres `u`: by `turn_step` for
        // the joint iteration, by `turn_unit` for the nested solve (asked
        // only where the warm start is missing or fails).
        let u = if r > 0.0 {
            (r_ij[0] / r, r_ij[1] / r)
        } else {
            (1.0, 0.0)
        };
        let dpsi = || {
            if r > 0.0 {
                -(first.grad_rot_i[0] + first.grad_rot_j[0]) / r
            } else {
                0.0
            }
        };
        let d = self.delta;
        // R(φ)/R⁰ = 1 + Δ P(−φ) at p = e^{iφ}: e^{−iφ} = p̄.
        let outline = |p: Unit| {
            let [f, df, ddf, _] = self.jet3((p.0, -p.1));
            (1.0 + d * f, -d * df, d * ddf)
        };
        let (z_i, z_j) = (pair.o_i.unit(), pair.o_j.unit());
        let (zi_bar, zj_bar_neg) = ((z_i.0, -z_i.1), (-z_j.0, z_j.1));
        // The joint iteration only where it finds the nested solve's
        // optimum: with `r > 2 Σ R⁰ max(c, s)` ([`Profiled::joint_reach`]),
        // `g'' = −r cos(ψ − θ_ij) − H_i'' − H_j'' < 0` wherever
        // `cos(ψ − θ_ij) ≥ 1/2`, and `g` there exceeds every value outside
        // (`≤ r/2 − Σ R⁰ min R`): one maximum in that cone, the global one,
        // which the nested solve's ascent from `ψ₀` reaches. A joint result
        // outside the cone goes to the nested solve, wherever it started.
        if solve == ExactSolve::JointAlone && r <= self.joint_reach * (size_i + size_j) {
            return None;
        }
        let found = if solve != ExactSolve::Nested && r > self.joint_reach * (size_i + size_j) {
            // (R, R', R'', R‴) of a body of size `size`.
            let sized = |size: f64| {
                move |p: Unit| {
                    let [f, df, ddf, dddf] = self.jet3((p.0, -p.1));
                    (
                        size * (1.0 + d * f),
                        size * (-d * df),
                        size * (d * ddf),
                        size * (-d * dddf),
                    )
                }
            };
            let joint = |w0: Unit, e_i: Unit, e_j: Unit| {
                gap2d::exact_joint(
                    r_ij,
                    w0,
                    z_i,
                    e_i,
                    sized(size_i),
                    z_j,
                    e_j,
                    sized(size_j),
                    second,
                )
                .filter(|e| e.normal.0 * r_ij[0] + e.normal.1 * r_ij[1] >= 0.5 * r)
            };
            // Warm: the normal and the support points where the last solve
            // of this pair left them, relative to the line of centres and to
            // each body's direction (a pair that turned as a whole starts at
            // its optimum).
            let warm = match memo.as_deref() {
                Some(Some([a0, a1, di0, di1, dj0, dj1, ..])) => {
                    let w0 = cmul(u, (*a0, *a1));
                    joint(
                        w0,
                        cmul(cmul(w0, zi_bar), (*di0, *di1)),
                        cmul(cmul(w0, zj_bar_neg), (*dj0, *dj1)),
                    )
                }
                _ => None,
            };
            let joint = warm.or_else(|| {
                let w0 = gap2d::turn_step(u, dpsi());
                // From each support point's first-order offset from its
                // direction, δ = atan(R'/R) ≈ R'/R⁰ = ∂h₁/∂θ / R⁰ (error O(Δ²)).
                let (e_i, e_j) = (
                    gap2d::turn_step(cmul(w0, zi_bar), first.grad_rot_i[0] / size_i),
                    gap2d::turn_step(cmul(w0, zj_bar_neg), first.grad_rot_j[0] / size_j),
                );
                joint(w0, e_i, e_j)
            });
            if joint.is_none() && solve == ExactSolve::Joint {
                gap2d::count_joint_fallback();
            }
            joint
        } else {
            None
        };
        if solve == ExactSolve::JointAlone {
            return found;
        }
        let found = found.unwrap_or_else(|| self.nested(pair, u, dpsi(), z_i, z_j, &outline));
        if let Some(memo) = memo {
            *memo = Some(remember(&found, u));
        }
        Some(found)
    }

    /// The nested solve ([`gap2d::exact_unit`] on
    /// [`gap2d::polar_support_unit`] supports) from the normal `u e^{i dψ}`.
    fn nested<F: Fn(Unit) -> (f64, f64, f64) + Copy>(
        &self,
        pair: &Pair<2, O>,
        u: Unit,
        dpsi: f64,
        z_i: Unit,
        z_j: Unit,
        outline: &F,
    ) -> gap2d::ExactGap {
        // Each body's support search starts where its previous one ended,
        // turned by the change of direction: after the first Newton step on
        // ψ the support point moves by ~1e-4 rad and one inner step suffices.
        let support = |size: f64| {
            let last = std::cell::Cell::new(None::<(Unit, gap2d::SupportPoint)>);
            move |e: Unit| {
                let p0 = match last.get() {
                    Some((e_prev, sp)) => {
                        // dβ = arg(e ē_prev), small: sin dβ ≈ dβ to O(dβ³).
                        let turn = cmul(e, (e_prev.0, -e_prev.1));
                        turn_unit(sp.p, turn.1 * sp.dphi_dbeta)
                    }
                    None => e,
                };
                let (j, sp) = gap2d::polar_support_unit(e, p0, *outline);
                last.set(Some((e, sp)));
                SupportJet {
                    h: size * j.h,
                    d1: size * j.d1,
                    d2: size * j.d2,
                }
            }
        };
        gap2d::exact_unit(
            &pair.r_ij,
            turn_unit(u, dpsi),
            z_i,
            support(pair.size_i),
            z_j,
            support(pair.size_j),
        )
    }
}

/// The most joint steps [`Profiled::exact_warm_lanes`] takes side by side
/// (a pair that needs more goes through the scalar solve); from a memo
/// most pairs take one step, and almost all of the rest two or three.
pub const WARM_LANE_STEPS: u32 = 6;

/// The arrays of `W` numbers [`Profiled::exact_warm_lanes`] keeps in its
/// scratch.
const SCRATCH: usize = 38;

/// The memo of a solve that ended at `e` ([`Profiled::exact_solve_warm`]):
/// the normal relative to the line of centres, `n ū`, and each support
/// point relative to its body's direction, `e^{iδ} = (H, H')/|(H, H')|`
/// (`H = R cos δ`, `H' = R sin δ`).
#[inline(always)]
fn remember(e: &gap2d::ExactGap, u: Unit) -> [f64; MEMO_LEN] {
    let a = cmul(e.normal, (u.0, -u.1));
    let unit = |j: &SupportJet| {
        let inv = 1.0 / (j.h * j.h + j.d1 * j.d1).sqrt();
        (j.h * inv, j.d1 * inv)
    };
    let (di, dj) = (unit(&e.jet_i), unit(&e.jet_j));
    let mut m = [0.0; MEMO_LEN];
    m[..6].copy_from_slice(&[a.0, a.1, di.0, di.1, dj.0, dj.1]);
    m
}

impl<P: NearDiskProfile, O: PlanarOrientation> Outline for Profiled<P, O> {
    fn relative_radius(&self, psi: f64) -> f64 {
        Profiled::relative_radius(self, psi)
    }
}

impl<P: NearDiskProfile, O: PlanarOrientation> Shape<2> for Profiled<P, O> {
    type Orientation = O;
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

    #[inline]
    fn rotate(&self, o: &mut O, dq: &[f64]) {
        *o = o.turned(dq[0]);
    }

    /// Rattlers below three contacts, as for the paper's near-disks
    /// (`d + 1`); near-disks jam hypostatic; a warning where the outline is
    /// not convex and the gap is an approximate one (one contact per pair).
    /// A non-convex outline with the exact gap starts free of overlaps: two
    /// bodies dropped almost onto each other, lobes in lobes, overlap deeper
    /// than two lobes, where the arcs' contacts come and go with their
    /// energy, and can sit on such a jump, where FIRE stays (two bodies of
    /// n = 4, Δ = 0.3, R⁰ = 0.7, with centres 0.15 apart and nearly
    /// aligned, stopped a minimisation at φ = 0.1 with `V/N = 0.064`).
    fn policy(&self) -> Policy {
        let mut warnings = Vec::new();
        if self.arcs.is_none() && !self.is_convex() {
            warnings.push(format!(
                "non-convex outline (Δ = {}, {}): the first-order gap assumes convex bodies with one contact per pair",
                self.delta,
                self.profile.describe()
            ));
        }
        Policy {
            rattler_threshold: 3,
            expects_isostatic: false,
            overlap_free_start: self.arcs.is_some(),
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
    fn contacts<F: FnMut(Contact<2>)>(&self, pair: &Pair<2, O>, max_gap: f64, mut visit: F) {
        let r = pair.r_ij.norm();
        // P ≤ max P, so h ≥ |r| − b_i − b_j: skip pairs certainly apart.
        if r - self.bounding_radius(pair.size_i) - self.bounding_radius(pair.size_j) > max_gap {
            return;
        }
        // One call of `visit` for every gap model: a second call site (an
        // early return for the other models) cost `fourier`'s first-order
        // pair loop 6 %.
        let contact = if self.gap == GapModel::FirstOrder {
            Some(self.first_order(pair))
        } else if self.arcs.is_none() {
            self.beyond_first_order(pair, r, max_gap)
        } else {
            self.several_contacts(pair, max_gap, &mut visit);
            None
        };
        if let Some(c) = contact {
            visit(c);
        }
    }

    /// The convex exact gap started where the pair's last solve ended
    /// ([`Profiled::exact_solve_warm`]); none for the other gap models.
    #[inline(always)]
    fn contact_warm(&self, pair: &Pair<2, O>, max_gap: f64, memo: &mut PairMemo) -> Warm<2> {
        if self.gap != GapModel::Exact || self.arcs.is_some() {
            return Warm::Cold;
        }
        let r = pair.r_ij.norm();
        if r - self.bounding_radius(pair.size_i) - self.bounding_radius(pair.size_j) > max_gap {
            return Warm::Solved(None);
        }
        Warm::Solved(self.exact_warm(pair, r, max_gap, memo))
    }

    /// The same gap with its second derivatives
    /// ([`first_order::gap_hessian`](crate::first_order::gap_hessian)), or
    /// those of the second-order or the exact gap ([`crate::gap2d`]).
    fn gap_hessians<V: FnMut(GapHessian<2>)>(
        &self,
        pair: &Pair<2, O>,
        max_gap: f64,
        mut visit: V,
    ) -> jamkit_core::Result<()> {
        let (size_i, size_j, r_ij) = (pair.size_i, pair.size_j, &pair.r_ij);
        let (r, u, _) = direction(r_ij);
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return Ok(());
        }
        match self.gap {
            GapModel::FirstOrder => {}
            GapModel::SecondOrder => {
                visit(self.second_order(pair).chain(r_ij));
                return Ok(());
            }
            GapModel::Exact if self.arcs.is_some() => {
                self.arc_contacts(pair, max_gap, None, &mut |e| visit(e.hessian()));
                if let Some(e) = self.core_contact(pair) {
                    visit(e.hessian_signed());
                }
                return Ok(());
            }
            GapModel::Exact => {
                if let Some(e) = self.exact_solve(pair, max_gap, ExactSolve::Joint) {
                    visit(e.hessian());
                }
                return Ok(());
            }
        }
        let profile = |(cos, sin): (f64, f64)| {
            let (value, slope) = self.profile.value_slope(cos, sin);
            Profile {
                value,
                slope,
                curvature: self.profile.curvature(cos, sin),
            }
        };
        let u = if P::HESSIAN_DIVIDES && r > 0.0 {
            r_ij / r
        } else {
            u
        };
        let [a_i, a_j] = self.phases(&pair.o_i, &pair.o_j, &u);
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
