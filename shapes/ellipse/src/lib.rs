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
//! ([`jamkit_planar::gap2d::exact`]: positive, the distance of the two
//! outlines; negative, minus the depth of penetration along the normal),
//! with its gradient by the envelope theorem and its second derivatives
//! ([`jamkit_planar::gap2d::ExactGap::hessian`]). There is no expansion in
//! `α − 1`: the gap is exact for every aspect ratio, to round-off.
//!
//! ## Implementation
//!
//! The lab-frame support function of body `i` is the square root of a
//! quadratic form in the normal `n = e(ψ)`:
//! `H_i² = nᵀ M_i n = p_i + m_i cos 2(ψ − θ_i)`, `p = (a² + b²)/2`,
//! `m = (a² − b²)/2` (and the same for `−n`, so body `j` needs no `π`).
//! [`Axis`] stores `cos 2θ` and `sin 2θ`, so a pair needs no trigonometry.
//! With `u = H²`, `u' = −2m sin 2β`, `u'' = −4m cos 2β`, `u''' = 8m sin 2β`
//! (`β = ψ − θ`),
//!
//! ```text
//! H' = u'/2H,   H'' = (u''/2 − H'²)/H,   H''' = (u'''/2 − 3H'H'')/H:
//! ```
//!
//! one square root and one division per body and evaluation.
//!
//! **Screen.** `h = max_ψ g ≥ g(ψ₀)` at the line of centres `ψ₀`, so a
//! pair with `g(ψ₀) > max_gap` is skipped; the test
//! `r − max_gap > H_i + H_j` is made on squares, without a square root.
//!
//! **Halley's iteration** on `g'(ψ) = 0` from the line of centres,
//!
//! ```text
//! δψ = −(g'/g'') / (1 − g' g'''/2g''²),   g''' = −r_ij·e(ψ)⊥ − H_i''' − H_j''',
//! ```
//!
//! converges cubically: 2–3 steps from the line of centres near contact
//! up to α = 1.5. It runs on a direction `v = L e(ψ)` of any length: `g`,
//! `H` and their derivatives are homogeneous of degree one in `v`, so the
//! step is the same, and the turn is `v + δψ v⊥` (by `atan δψ`, which keeps
//! the convergence cubic), with no square root; `v` is normalised once. It
//! stops after a step below 10⁻⁵ rad, where what is left is `~K·10⁻¹⁵` rad
//! (`K = |g'''²/4g''² − g''''/6g''| = O(1)`) and moves `h` by `~10⁻³⁰`, and
//! the gap and jets are evaluated at the final normal; the contacts, after
//! a last step below 10⁻⁶ rad, instead move `H` and `H'` there by their
//! Taylor series from the last iterate (`H'''` included; `≲ 10⁻¹⁶` left),
//! with no evaluation. Every iterate's `g` is a lower bound on `h`, so a
//! pair leaves as soon as one exceeds `max_gap`.
//!
//! **Warm start.** In the engine's energy pass
//! ([`Ellipse::exact_gap_warm`], `Shape::contacts_warm`) Halley's iteration
//! starts at the normal where the pair's last solve ended, kept in the
//! pair's memo relative to the line of centres: after a minimiser's step
//! most pairs take one step and no further evaluation. The result is the
//! same optimum to round-off, from any memo. The engine asks for these
//! solves a chunk of pairs at a time ([`Ellipse::exact_warm_lanes`], the
//! family's `FastContacts`): the screens and the first steps of many pairs
//! side by side, by the same functions as one pair at a time, hence the
//! same bits.
//!
//! Where a guard fails — `g'' ≥ 0`, Halley's denominator below `1/2`, a
//! step beyond 1 rad or not shorter than the one before, a step over
//! 10⁻³ rad that lowers `g`, or 12 steps — [`Ellipse::exact_gap_safeguarded`]
//! runs: the safeguarded Newton iteration of
//! [`jamkit_planar::gap2d::exact`] on the unit vector `n` (gradient steps
//! where `g'' ≥ 0`, steps capped at 0.3 rad and halved until `g` does not
//! decrease, except that Newton steps below 10⁻⁶ rad skip that test: it is
//! then decided by round-off), one `sin_cos` per step. That happens for
//! overlaps deeper than most of the short semi-axis, and at α ≳ 2 where
//! the normal turns far from the line of centres ([`fallbacks`] counts
//! them). Tests check both against `gap2d::exact` with the closed-form
//! `H(β)` and against each other to round-off, and the zero of the gap
//! against the Perram–Wertheim contact function.
//!
//! NOTE: for *overlapping* bodies `max_ψ` is taken by an iteration from
//! the line of centres, i.e. the local maximum nearest to it. For the
//! overlaps of a jamming run (`|h| ≪ b`) `g(ψ)` has one maximum and this
//! is the global one; two ellipses crossed at their centres can have
//! several.
//!
//! ## Inertia and asphericity
//!
//! The moment of inertia of `θ` defaults to that of a uniform ellipse of
//! unit mass, `I = (a² + b²)/4 = (R⁰)² (α + 1/α)/4` (the disk's `(R⁰)²/2`
//! at `α = 1`); `inertia` replaces it by one value for all sizes.
//! The asphericity `A = P²/(4πS)` (1 for a disk) uses the perimeter
//! `P = ∫₀^{2π} √(a² sin²t + b² cos²t) dt` by the trapezoid rule, which is
//! spectrally accurate for this smooth periodic integrand.

use jamkit_core::{
    Contact, Dims, Family, FamilyInfo, GapHessian, Look, MEMO_LEN, Outline, Pair, PairMemo,
    ParamSpec, Policy, RotVec, Shape, ShapeVisitor, Vector, Warm,
};
use jamkit_planar::gap2d::{ExactGap, SupportJet};
use serde::Deserialize;
use std::f64::consts::PI;

mod lanes;
pub use lanes::WARM_LANE_STEPS;

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
            added: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia I of the angle θ; None: I = (a² + b²)/4 (uniform ellipse of unit mass)",
            is_list: false,
            default: Some("None"),
            added: None,
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

/// The `ellipse` family's registration.
pub struct EllipseFamily;

impl Family for EllipseFamily {
    const INFO: FamilyInfo = INFO;
    const EXAMPLE: &'static str = "(aspect: 1.5)";
    type Params = EllipseParams;

    /// `α = 1` is the disk of radius `R⁰`: it runs as `sphere` (no
    /// rotational coordinates, same random stream, hence the same packing
    /// as `sphere` for the same seed), as near-disks with `Δ = 0`.
    fn visit<V: ShapeVisitor>(
        p: &EllipseParams,
        dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        let shape = Ellipse::new(p)?;
        if p.aspect == 1.0 {
            jamkit_sphere::visit_ball(dim, visitor)
        } else {
            Ok(visitor.visit::<2, _>(shape))
        }
    }
}

impl Outline for Ellipse {
    fn relative_radius(&self, psi: f64) -> f64 {
        Ellipse::relative_radius(self, psi)
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
    pub fn new(p: &EllipseParams) -> jamkit_core::Result<Self> {
        if !(p.aspect >= 1.0 && p.aspect.is_finite()) {
            return Err(jamkit_core::Error::invalid(
                "params.aspect",
                p.aspect.to_string(),
                "must be a finite number ≥ 1 (α = a/b, long over short semi-axis)",
            ));
        }
        if let Some(i) = p.inertia
            && !(i > 0.0 && i.is_finite())
        {
            return Err(jamkit_core::Error::invalid(
                "params.inertia",
                i.to_string(),
                "must be positive and finite, or None for (a² + b²)/4",
            ));
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

    /// The quadratic form of a body of size `size` and orientation `o`.
    #[inline(always)]
    fn form(&self, size: f64, o: &Axis) -> Form {
        let r2 = size * size;
        Form {
            p: 0.5 * r2 * (self.aspect + 1.0 / self.aspect),
            m: 0.5 * r2 * (self.aspect - 1.0 / self.aspect),
            c2: o.unit().0,
            s2: o.unit().1,
        }
    }

    /// The exact gap of two bodies (module documentation), or `None` when
    /// it certainly exceeds `max_gap`: Halley's iteration from the line of
    /// centres, with [`Ellipse::exact_gap_safeguarded`] where its guards
    /// fail.
    #[inline(always)]
    pub fn exact_gap(
        &self,
        size_i: f64,
        o_i: &Axis,
        size_j: f64,
        o_j: &Axis,
        r_ij: &Vector<2>,
        max_gap: f64,
    ) -> Option<Solution> {
        self.solve(
            &Pair::new(size_i, *o_i, size_j, *o_j, *r_ij),
            max_gap,
            None,
            true,
        )
    }

    /// [`Ellipse::exact_gap`] as the engine's pair loop finds it
    /// ([`Shape::contacts_warm`]): Halley's iteration started at the normal
    /// where this pair's last solve ended (`memo`: that normal relative to
    /// the line of centres, `n ū` as a complex number in its first two
    /// entries, times the distance `r` of that solve), else, or where a guard fails, the cold solve of
    /// [`Ellipse::exact_gap`]; `memo` gets the normal of this solve. The
    /// screens are the cold solve's, and the result is the same optimum to
    /// round-off (Halley stops after a step below 10⁻⁵ rad, `~K·10⁻¹⁵` rad
    /// from it, whatever the start). A pair that turned as a whole starts
    /// at its optimum, and one that moved a little converges in one step.
    #[inline(always)]
    pub fn exact_gap_warm(
        &self,
        pair: &Pair<2, Axis>,
        max_gap: f64,
        memo: &mut PairMemo,
    ) -> Option<Solution> {
        self.solve(pair, max_gap, Some(memo), false)
    }

    /// The solve of [`Ellipse::exact_gap`] (`memo` `None`, `second`) and
    /// of [`Ellipse::exact_gap_warm`] (`memo` given): the screens, Halley's
    /// iteration from the memo's normal where there is one, else or where
    /// a guard fails [`Ellipse::cold`]; the memo, where given, gets the
    /// normal found.
    #[inline(always)]
    fn solve(
        &self,
        pair: &Pair<2, Axis>,
        max_gap: f64,
        memo: Option<&mut PairMemo>,
        second: bool,
    ) -> Option<Solution> {
        let r_ij = &pair.r_ij;
        let (fi, fj, r) = self.screen(pair, max_gap)?;
        let (x, y) = (r_ij[0], r_ij[1]);
        let warm = match memo.as_deref() {
            // The line of centres `r_ij` turned by the memo's `n ū` (both
            // of any length).
            Some(Some([a0, a1, ..])) => match halley(
                &fi,
                &fj,
                (x, y),
                (x * *a0 - y * *a1, y * *a0 + x * *a1),
                max_gap,
                second,
            ) {
                Fast::Done(s) => Some(Some(s)),
                Fast::Apart => Some(None),
                Fast::Failed => None,
            },
            _ => None,
        };
        let found = match warm {
            Some(found) => found,
            None => self.cold(&fi, &fj, pair, r, max_gap, second),
        };
        if let (Some(memo), Some(s)) = (memo, &found) {
            *memo = Some(remember((s.normal[0], s.normal[1]), (x, y)));
        }
        found
    }

    /// The bounding circles' screen: `None` for a pair whose gap
    /// `h ≥ |r_ij| − a_i − a_j` certainly exceeds `max_gap`, else both
    /// bodies' quadratic forms and `r = |r_ij|`.
    #[inline(always)]
    fn bounded(&self, pair: &Pair<2, Axis>, max_gap: f64) -> Option<(Form, Form, f64)> {
        let r = pair.r_ij.norm();
        if r - self.bounding_radius(pair.size_i) - self.bounding_radius(pair.size_j) > max_gap {
            return None;
        }
        Some((
            self.form(pair.size_i, &pair.o_i),
            self.form(pair.size_j, &pair.o_j),
            r,
        ))
    }

    /// The two screens of [`Ellipse::exact_gap`]: `None` for a pair whose
    /// gap certainly exceeds `max_gap`, else both bodies' quadratic forms
    /// and `r = |r_ij|`.
    #[inline(always)]
    fn screen(&self, pair: &Pair<2, Axis>, max_gap: f64) -> Option<(Form, Form, f64)> {
        let (fi, fj, r) = self.bounded(pair, max_gap)?;
        if screened_out(&fi, &fj, (pair.r_ij[0], pair.r_ij[1]), r, max_gap) {
            return None;
        }
        Some((fi, fj, r))
    }

    /// Halley's iteration from the line of centres, and the safeguarded
    /// iteration where its guards fail (the solve of
    /// [`Ellipse::exact_gap`] after its screens); Halley's jets at its
    /// final normal with `second`, else moved to it ([`halley`]).
    #[inline(always)]
    fn cold(
        &self,
        fi: &Form,
        fj: &Form,
        pair: &Pair<2, Axis>,
        r: f64,
        max_gap: f64,
        second: bool,
    ) -> Option<Solution> {
        let (x, y) = (pair.r_ij[0], pair.r_ij[1]);
        let v0 = if r > 0.0 { (x, y) } else { (1.0, 0.0) };
        match halley(fi, fj, (x, y), v0, max_gap, second) {
            Fast::Done(s) => Some(s),
            Fast::Apart => None,
            Fast::Failed => {
                count_fallback();
                self.exact_gap_safeguarded(pair, max_gap)
            }
        }
    }

    /// The exact gap by a safeguarded Newton iteration on `n = e(ψ)` from
    /// the line of centres (module documentation), or `None` when `g` at
    /// the line of centres exceeds `max_gap`: what [`Ellipse::exact_gap`]
    /// runs where Halley's iteration fails its guards.
    pub fn exact_gap_safeguarded(&self, pair: &Pair<2, Axis>, max_gap: f64) -> Option<Solution> {
        let (fi, fj, r) = self.bounded(pair, max_gap)?;
        let (x, y) = (pair.r_ij[0], pair.r_ij[1]);
        let eval = |n: (f64, f64)| {
            let w = (n.0 * n.0 - n.1 * n.1, 2.0 * n.0 * n.1);
            let (ji, jj) = (fi.jet(w), fj.jet(w));
            let rn = x * n.0 + y * n.1;
            let rt = -x * n.1 + y * n.0;
            Eval {
                g: rn - ji.h - jj.h,
                g1: rt - ji.d1 - jj.d1,
                g2: -rn - ji.d2 - jj.d2,
                ji,
                jj,
            }
        };
        let turn = |n: (f64, f64), step: f64| {
            let (s, c) = step.sin_cos();
            (n.0 * c - n.1 * s, n.1 * c + n.0 * s)
        };
        let mut n = if r > 0.0 { (x / r, y / r) } else { (1.0, 0.0) };
        let mut cur = eval(n);
        // h = max g ≥ g(line of centres).
        if cur.g > max_gap {
            return None;
        }
        // The iteration of `gap2d::exact`, on n = e(ψ).
        let mut converged = false;
        let mut iterations = 0;
        while iterations < 60 {
            iterations += 1;
            let g = cur.g;
            let mut step = if cur.g2 < 0.0 {
                -cur.g1 / cur.g2
            } else {
                0.1 * cur.g1.signum()
            };
            step = step.clamp(-0.3, 0.3);
            if step.abs() < 1e-14 {
                n = turn(n, step);
                cur = eval(n);
                converged = true;
                break;
            }
            // NOTE: a Newton step below 1e-6 rad (g'' < 0) is taken as it
            // is: there the iteration converges quadratically, and the gain
            // in g (~g'·step/2 ≲ 1e-13 |g|) can be lost in round-off, so the
            // descent test would only halve a correct step, again and again.
            if step.abs() < 1e-6 && cur.g2 < 0.0 {
                n = turn(n, step);
                cur = eval(n);
                continue;
            }
            let mut next = eval(turn(n, step));
            let mut halvings = 0;
            while next.g < g && halvings < 40 {
                step *= 0.5;
                next = eval(turn(n, step));
                halvings += 1;
            }
            if next.g < g {
                converged = true;
                break;
            }
            n = turn(n, step);
            cur = next;
        }
        Some(Solution {
            normal: Vector::<2>::new(n.0, n.1),
            gap: cur.g,
            jet_i: cur.ji,
            jet_j: cur.jj,
            iterations,
            converged,
        })
    }
}

/// `H² = p + m cos 2(ψ − θ)` of one body.
#[derive(Clone, Copy, Debug)]
struct Form {
    p: f64,
    m: f64,
    c2: f64,
    s2: f64,
}

impl Form {
    /// `u(v) = vᵀ M v = |v|² H²` of the direction `v` of any length
    /// (`H² = p + m cos 2(ψ − θ)`).
    #[inline(always)]
    fn square(&self, v: (f64, f64)) -> f64 {
        let l2 = v.0 * v.0 + v.1 * v.1;
        let w = (v.0 * v.0 - v.1 * v.1, 2.0 * v.0 * v.1);
        self.p * l2 + self.m * (w.0 * self.c2 + w.1 * self.s2)
    }

    /// `H, H', H''` and `H'''` at the direction `v = L e(ψ)` of any length
    /// `L`, each times `L` (homogeneous of degree one), from `w = v²`
    /// (`L² (cos 2ψ, sin 2ψ)`, as a complex number) and `l2 = L²`:
    /// `u = H² = p + m cos 2β`, `u' = −2m sin 2β`, `u'' = −4m cos 2β`,
    /// `u''' = 8m sin 2β` (`β = ψ − θ`), `H' = u'/2H`,
    /// `H'' = (u''/2 − H'²)/H`, `H''' = (u'''/2 − 3H'H'')/H`.
    #[inline(always)]
    fn jet3(&self, w: (f64, f64), l2: f64) -> (SupportJet, f64) {
        let cc = w.0 * self.c2 + w.1 * self.s2;
        let ss = w.1 * self.c2 - w.0 * self.s2;
        let h = (self.p * l2 + self.m * cc).sqrt();
        let inv = 1.0 / h;
        let d1 = -self.m * ss * inv;
        let d2 = (-2.0 * self.m * cc - d1 * d1) * inv;
        let d3 = (4.0 * self.m * ss - 3.0 * d1 * d2) * inv;
        (SupportJet { h, d1, d2 }, d3)
    }

    /// `H, H', H''` at the normal whose `(cos 2ψ, sin 2ψ)` is `w`.
    #[inline(always)]
    fn jet(&self, w: (f64, f64)) -> SupportJet {
        // cos 2(ψ − θ) and sin 2(ψ − θ).
        let cc = w.0 * self.c2 + w.1 * self.s2;
        let ss = w.1 * self.c2 - w.0 * self.s2;
        let h = (self.p + self.m * cc).sqrt();
        let d1 = -self.m * ss / h;
        SupportJet {
            h,
            d1,
            d2: (-2.0 * self.m * cc - d1 * d1) / h,
        }
    }
}

/// Halley's iteration stops after a step below this (rad): what is left
/// is `~K·10⁻¹⁵` rad, `K = |g'''²/4g''² − g''''/6g''| = O(1)` (cubic
/// convergence), which moves `h` by `~10⁻³⁰` (`g` is stationary).
const HALLEY_TOL: f64 = 1e-5;

/// Without `second`, [`halley`] moves the jets of its last iterate to the
/// final normal by their Taylor series after a last step below this (rad),
/// rather than evaluate them there.
const TAYLOR_FINISH: f64 = 1e-6;

/// The longest step of Halley's iteration (rad) before it hands over to
/// the safeguarded iteration.
const HALLEY_MAX_STEP: f64 = 1.0;

/// Halley's iteration gives up after this many steps (it takes 2–4 from
/// the line of centres where it converges at all).
const HALLEY_CAP: u32 = 12;

/// How [`halley`] ended.
enum Fast {
    /// Converged.
    Done(Solution),
    /// `g > max_gap` at an iterate: `h > max_gap`.
    Apart,
    /// A guard failed: run the safeguarded iteration.
    Failed,
}

/// Halley's iteration on `g'(ψ) = 0` (module documentation) from the
/// direction `v0` (the separation itself: any length will do), for the
/// bodies `fi`, `fj` at separation `(x, y)`.
///
/// The iteration runs on a direction `v = L n` of any length `L > 0`:
/// `g`, `H` and their derivatives in `ψ` are homogeneous of degree one in
/// `v`, so the step (a ratio of them) is the same, and a turn by the step
/// `s` is `v + s v⊥` (the angle `atan s = s − s³/3 + …`, which leaves the
/// convergence cubic). `v` is normalised once, at the end, where the gap
/// and the jets are evaluated; without `second`, after a last step below
/// [`TAYLOR_FINISH`], `H` and `H'` are instead those of the last iterate
/// moved along that step by their Taylor series (`H''` is NaN: the
/// contacts need `H` and `H'` alone), which saves an evaluation.
#[inline(always)]
fn halley(
    fi: &Form,
    fj: &Form,
    (x, y): (f64, f64),
    v0: (f64, f64),
    max_gap: f64,
    second: bool,
) -> Fast {
    let mut v = v0;
    let l2 = square(v);
    let (mut cur, mut g3, mut thirds) = evaluate(fi, fj, (x, y), v, l2);
    let mut len_v = l2.sqrt();
    let mut last = f64::INFINITY;
    for iterations in 1..=HALLEY_CAP {
        let s = halley_step(&cur, g3, v, len_v, last, max_gap);
        if s.apart {
            return Fast::Apart;
        }
        if !s.ok {
            return Fast::Failed;
        }
        v = s.v;
        let l2 = square(v);
        let len_next = l2.sqrt();
        if s.len < HALLEY_TOL {
            let n = unit(v, len_next);
            if !second && s.len < TAYLOR_FINISH {
                let (gap, ji, jj) = taylor(&cur, thirds, s.step, len_v, n, (x, y));
                if gap > max_gap {
                    return Fast::Apart;
                }
                return Fast::Done(Solution {
                    normal: Vector::<2>::new(n.0, n.1),
                    gap,
                    jet_i: ji,
                    jet_j: jj,
                    iterations,
                    converged: true,
                });
            }
            let (end, ..) = evaluate(fi, fj, (x, y), n, 1.0);
            if end.g > max_gap {
                return Fast::Apart;
            }
            return Fast::Done(Solution {
                normal: Vector::<2>::new(n.0, n.1),
                gap: end.g,
                jet_i: end.ji,
                jet_j: end.jj,
                iterations,
                converged: true,
            });
        }
        let next;
        (next, g3, thirds) = evaluate(fi, fj, (x, y), v, l2);
        if overshoots(s.len, next.g, cur.g, len_v, len_next) {
            return Fast::Failed;
        }
        (cur, len_v, last) = (next, len_next, s.len);
    }
    Fast::Failed
}

/// The screen at the line of centres ([`Ellipse::exact_gap`]'s second):
/// `h ≥ g(ψ₀) = r − H_i − H_j` there, so the pair at separation `(x, y)`
/// (`r = |r_ij|`) is skipped when `t = r − max_gap > H_i + H_j`, i.e.
/// `t r > √U_i + √U_j` with `U = r² H² = u(r_ij)` (the quadratic form at
/// the separation itself), tested on squares.
#[inline(always)]
fn screened_out(fi: &Form, fj: &Form, (x, y): (f64, f64), r: f64, max_gap: f64) -> bool {
    let t = r - max_gap;
    let (ui, uj) = (fi.square((x, y)), fj.square((x, y)));
    let tr = t * r;
    let excess = tr * tr - ui - uj;
    (t > 0.0) & (excess > 0.0) & (excess * excess > 4.0 * ui * uj)
}

/// `|v|²`.
#[inline(always)]
fn square(v: (f64, f64)) -> f64 {
    v.0 * v.0 + v.1 * v.1
}

/// `v/|v|`, given `|v|` (`length`).
#[inline(always)]
fn unit(v: (f64, f64), length: f64) -> (f64, f64) {
    let inv = 1.0 / length;
    (v.0 * inv, v.1 * inv)
}

/// `g, g', g''` with both jets at the direction `v` (`|v|² = l2`), and
/// `g'''` with each body's `H'''` (for the Taylor finish), all scaled by
/// `|v|`, for the bodies `fi`, `fj` at separation `(x, y)`.
#[inline(always)]
fn evaluate(
    fi: &Form,
    fj: &Form,
    (x, y): (f64, f64),
    v: (f64, f64),
    l2: f64,
) -> (Eval, f64, (f64, f64)) {
    let w = (v.0 * v.0 - v.1 * v.1, 2.0 * v.0 * v.1);
    let ((ji, ti), (jj, tj)) = (fi.jet3(w, l2), fj.jet3(w, l2));
    let rn = x * v.0 + y * v.1;
    let rt = -x * v.1 + y * v.0;
    (
        Eval {
            g: rn - ji.h - jj.h,
            g1: rt - ji.d1 - jj.d1,
            g2: -rn - ji.d2 - jj.d2,
            ji,
            jj,
        },
        -rt - ti - tj,
        (ti, tj),
    )
}

/// One step of [`halley`] from the iterate `v` (`|v| = len_v`) where `g`
/// and its derivatives are `cur` and `g3`, after a step of length `last`.
#[derive(Clone, Copy, Debug)]
struct HalleyStep {
    /// `g > max_gap` there (`h = max g ≥ g(ψ)` for every `ψ`): apart.
    apart: bool,
    /// The guards hold: `g'' < 0`, Halley's denominator above `1/2` (near
    /// the optimum it is 1), and the step at most [`HALLEY_MAX_STEP`] and
    /// shorter than the one before (else the safeguarded ascent runs).
    ok: bool,
    /// `s = −(g'/g'') / (1 − g'g'''/2g''²)`.
    step: f64,
    /// `|s|`.
    len: f64,
    /// `v` turned by the step, `v + s v⊥`.
    v: (f64, f64),
}

/// [`HalleyStep`] from `cur` and `g3` at `v`.
#[inline(always)]
fn halley_step(
    cur: &Eval,
    g3: f64,
    v: (f64, f64),
    len_v: f64,
    last: f64,
    max_gap: f64,
) -> HalleyStep {
    // g(v) = |v| g(ψ).
    let apart = cur.g > max_gap * len_v;
    let (g1, g2) = (cur.g1, cur.g2);
    let den = 2.0 * g2 * g2 - g1 * g3;
    let step = -2.0 * g1 * g2 / den;
    let len = step.abs();
    let ok = (g2 < 0.0) & (den > g2 * g2) & (len <= HALLEY_MAX_STEP) & (len < last);
    HalleyStep {
        apart,
        ok,
        step,
        len,
        v: (v.0 - step * v.1, v.1 + step * v.0),
    }
}

/// The finish of [`halley`] without `second` after a last step `step`
/// below [`TAYLOR_FINISH`]: the gap and `H`, `H'` at the final normal `n`,
/// moved from the last iterate (`cur`, each body's `H'''` in `thirds`,
/// scaled by `|v| = len_v`) by the turn `a = atan(step)` along their
/// Taylor series (to `a³` and `a²`; what is left, `≲ |H''''|a³/6 ≲ 10⁻¹⁶`
/// for `|H''''| ≲ 100`, is round-off): no evaluation. `H''` is NaN (the
/// contacts need `H` and `H'` alone).
#[inline(always)]
fn taylor(
    cur: &Eval,
    thirds: (f64, f64),
    step: f64,
    len_v: f64,
    n: (f64, f64),
    (x, y): (f64, f64),
) -> (f64, SupportJet, SupportJet) {
    let a = step * (1.0 - step * step * (1.0 / 3.0));
    let inv_l = 1.0 / len_v;
    let moved = |j: &SupportJet, t: f64| SupportJet {
        h: (j.h + a * (j.d1 + a * (0.5 * j.d2 + a * (1.0 / 6.0) * t))) * inv_l,
        d1: (j.d1 + a * (j.d2 + a * 0.5 * t)) * inv_l,
        d2: f64::NAN,
    };
    let (ji, jj) = (moved(&cur.ji, thirds.0), moved(&cur.jj, thirds.1));
    (x * n.0 + y * n.1 - ji.h - jj.h, ji, jj)
}

/// Whether a step of [`halley`] of length `len ≥ 10⁻³` from `g = cur`
/// (at `|v| = len_v`) to `g = next` (at `|v| = len_next`, both scaled by
/// `|v|`) lowered `g`: it ran past the maximum the safeguarded ascent
/// reaches (a large step must climb).
#[inline(always)]
fn overshoots(len: f64, next: f64, cur: f64, len_v: f64, len_next: f64) -> bool {
    (len >= 1e-3) & (next * len_v < cur * len_next)
}

/// The memo of a solve that ended at the normal `n` for the separation
/// `(x, y)`: `n r̄_ij`, the normal relative to the line of centres, times
/// `r` (any length will do, and no division).
#[inline(always)]
fn remember(n: (f64, f64), (x, y): (f64, f64)) -> [f64; MEMO_LEN] {
    let mut m = [0.0; MEMO_LEN];
    m[0] = n.0 * x + n.1 * y;
    m[1] = n.1 * x - n.0 * y;
    m
}

static FALLBACKS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// How many pairs [`Ellipse::exact_gap`] handed over to
/// [`Ellipse::exact_gap_safeguarded`] in this process (all threads): a
/// diagnostic, for tests and benchmarks.
pub fn fallbacks() -> u64 {
    FALLBACKS.load(std::sync::atomic::Ordering::Relaxed)
}

#[cold]
fn count_fallback() {
    FALLBACKS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
}

/// One evaluation of `g(ψ)`, `g'`, `g''` with both bodies' jets.
#[derive(Clone, Copy, Debug)]
struct Eval {
    g: f64,
    g1: f64,
    g2: f64,
    ji: SupportJet,
    jj: SupportJet,
}

/// The exact gap of a pair at the optimum normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution {
    /// The common normal `n = e(ψ*)`, from `i` towards `j`.
    pub normal: Vector<2>,
    /// The signed distance `h`.
    pub gap: f64,
    /// Body `i`'s `H, H', H''` at `ψ* − θ_i`.
    pub jet_i: SupportJet,
    /// Body `j`'s at `ψ* + π − θ_j`.
    pub jet_j: SupportJet,
    /// Iterations taken (each evaluates both support functions once, but
    /// for the safeguarded iteration's halvings).
    pub iterations: u32,
    /// False when the iteration stopped at its cap.
    pub converged: bool,
}

impl Solution {
    /// The contact: `∂h/∂r_j = n`, `∂h/∂θ = H'`.
    #[inline(always)]
    pub fn contact(&self) -> Contact<2> {
        Contact {
            gap: self.gap,
            grad_r: self.normal,
            grad_rot_i: [self.jet_i.d1, 0.0, 0.0],
            grad_rot_j: [self.jet_j.d1, 0.0, 0.0],
        }
    }

    /// The gap with its second derivatives
    /// ([`jamkit_planar::gap2d::ExactGap::hessian`]), with the same contact
    /// as [`Solution::contact`], bit for bit.
    pub fn hessian(&self) -> GapHessian<2> {
        let e = ExactGap {
            normal: (self.normal[0], self.normal[1]),
            gap: self.gap,
            jet_i: self.jet_i,
            jet_j: self.jet_j,
            iterations: self.iterations,
            converged: self.converged,
        };
        let mut g = e.hessian();
        g.contact = self.contact();
        g
    }
}

/// An orientation: the angle `θ` of the long axis in `(−π, π]`, with
/// `cos 2θ` and `sin 2θ` cached (all the pair loop needs: an ellipse is
/// symmetric under `θ → θ + π`).
pub type Axis = jamkit_core::Angle<2>;

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
    type Orientation = Axis;
    type Fast = Self;

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

    #[inline]
    fn rotate(&self, o: &mut Axis, dq: &[f64]) {
        *o = o.turned(dq[0]);
    }

    /// Rattlers below `d + 1 = 3` contacts, as for near-disks; ellipses jam
    /// hypostatic (Donev et al. 2007).
    fn policy(&self) -> Policy {
        Policy {
            expects_isostatic: false,
            ..Policy::new(2)
        }
    }

    /// The outline for drawing, and the semi-axes per unit size for export,
    /// `(√α, 1/√α, 1/√α)`, the third (out of the plane) taken as the short
    /// one.
    fn look(&self) -> Look {
        Look {
            outline: Some(std::sync::Arc::new(self.clone())),
            ellipsoid_axes: Some([self.root, 1.0 / self.root, 1.0 / self.root]),
            ..Look::default()
        }
    }

    #[inline]
    fn contacts<F: FnMut(Contact<2>)>(&self, pair: &Pair<2, Axis>, max_gap: f64, mut visit: F) {
        if let Some(s) = self.solve(pair, max_gap, None, false) {
            visit(s.contact());
        }
    }

    /// [`Ellipse::exact_gap_warm`]: the exact gap started where the
    /// pair's last solve ended.
    #[inline(always)]
    fn contact_warm(&self, pair: &Pair<2, Axis>, max_gap: f64, memo: &mut PairMemo) -> Warm<2> {
        Warm::Solved(
            self.exact_gap_warm(pair, max_gap, memo)
                .map(|s| s.contact()),
        )
    }

    fn gap_hessians<V: FnMut(GapHessian<2>)>(
        &self,
        pair: &Pair<2, Axis>,
        max_gap: f64,
        mut visit: V,
    ) -> jamkit_core::Result<()> {
        if let Some(s) = self.solve(pair, max_gap, None, true) {
            visit(s.hessian());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::{Pair, ShapeExt};
    use std::f64::consts::FRAC_PI_2;

    fn ellipse(aspect: f64) -> Ellipse {
        Ellipse::new(&EllipseParams {
            aspect,
            inertia: None,
        })
        .unwrap()
    }

    fn contact(s: &Ellipse, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> Contact<2> {
        s.pair_contacts(
            &Pair::new(ri, Axis::new(ti), rj, Axis::new(tj), d),
            f64::INFINITY,
        )[0]
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
            let beta = -3.0 + 0.161 * k as f64;
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

    /// A deterministic uniform stream in `[0, 1)` for the random pairs.
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        move || rng.random::<f64>()
    }

    /// `H'''` of [`Form::jet3`] against central differences of its `H''`
    /// (ε = 1e-5: truncation ~ε²H'''' ≲ 1e-10, round-off ~1e-16/ε ≈ 1e-11;
    /// tolerance 1e-8); its `H, H', H''` equal [`Form::jet`]'s to round-off
    /// (1e-15: a multiplication by `1/H` against a division), and at the
    /// direction `L e(ψ)` all four are `L` times those at `e(ψ)` (1e-14
    /// relative: a few ulps of `L e(ψ)` squared), as is `√u`
    /// ([`Form::square`]).
    #[test]
    fn third_derivative_matches_finite_differences() {
        let s = ellipse(2.5);
        let f = s.form(0.7, &Axis::new(0.4));
        let eps = 1e-5;
        let w = |psi: f64| ((2.0 * psi).cos(), (2.0 * psi).sin());
        for k in 0..40 {
            let psi = -3.0 + 0.161 * k as f64;
            let (c, d3) = f.jet3(w(psi), 1.0);
            let (m, _) = f.jet3(w(psi - eps), 1.0);
            let (p, _) = f.jet3(w(psi + eps), 1.0);
            assert_relative_eq!(d3, (p.d2 - m.d2) / (2.0 * eps), epsilon = 1e-8);
            let old = f.jet(w(psi));
            assert_relative_eq!(c.h, old.h, epsilon = 1e-15);
            assert_relative_eq!(c.d1, old.d1, epsilon = 1e-15);
            assert_relative_eq!(c.d2, old.d2, epsilon = 1e-15);
            let l = 1.7;
            let v = (l * psi.cos(), l * psi.sin());
            let (sc, sd3) = f.jet3((v.0 * v.0 - v.1 * v.1, 2.0 * v.0 * v.1), l * l);
            for (a, b) in [(sc.h, c.h), (sc.d1, c.d1), (sc.d2, c.d2), (sd3, d3)] {
                assert_relative_eq!(a, l * b, epsilon = 1e-14, max_relative = 1e-14);
            }
            assert_relative_eq!(f.square(v).sqrt(), l * c.h, max_relative = 1e-14);
        }
    }

    /// Halley's iteration against the safeguarded iteration on random
    /// pairs, α from 1.001 to 3, sizes 0.5 to 0.7, separations from deep
    /// overlap (a third of the short axes) to apart, and near contact
    /// (|h| < 10⁻³): both converge to round-off, so gaps agree to 1e-13 and
    /// normals and `H'` to 1e-12 (round-off of the last step scaled by
    /// `1/k`, `k = −g''`), `H''` to 1e-11. Halley takes at most 5 steps
    /// and hands over to the safeguarded iteration on no pair with α ≤ 1.5
    /// and on few with α = 3 (deep overlaps only).
    #[test]
    fn halley_matches_the_safeguarded_iteration() {
        let mut rnd = uniform(11);
        for aspect in [1.001, 1.1, 1.5, 3.0] {
            let s = ellipse(aspect);
            let (mut handed_over, mut near, mut most) = (0, 0, 0);
            for k in 0..2000 {
                let (ri, rj) = (0.5 + 0.2 * rnd(), 0.5 + 0.2 * rnd());
                let (oi, oj) = (Axis::new(6.3 * rnd()), Axis::new(6.3 * rnd()));
                let phi = 6.3 * rnd();
                let u = Vector::<2>::new(phi.cos(), phi.sin());
                let (lo, hi) = (
                    0.67 * (ri + rj) / s.root,
                    s.bounding_radius(ri) + s.bounding_radius(rj),
                );
                let mut d = u * (lo + (hi - lo) * rnd());
                if k % 2 == 1 {
                    // Near contact: move along the line of centres by
                    // minus the gap, twice (h changes by ~the move).
                    for _ in 0..2 {
                        let h = s
                            .exact_gap_safeguarded(&Pair::new(ri, oi, rj, oj, d), f64::INFINITY)
                            .unwrap()
                            .gap;
                        d -= u * (h - 1e-3 * (2.0 * rnd() - 1.0));
                    }
                }
                let safe = s
                    .exact_gap_safeguarded(&Pair::new(ri, oi, rj, oj, d), f64::INFINITY)
                    .unwrap();
                near += usize::from(safe.gap.abs() < 1e-3);
                let fast = match halley(
                    &s.form(ri, &oi),
                    &s.form(rj, &oj),
                    (d[0], d[1]),
                    (d[0], d[1]),
                    f64::INFINITY,
                    true,
                ) {
                    Fast::Done(m) => m,
                    Fast::Apart => unreachable!("max_gap = ∞"),
                    Fast::Failed => {
                        handed_over += 1;
                        // Up to α = 1.5 only overlaps deeper than 0.4,
                        // most of the short semi-axes (0.41 to 0.57).
                        assert!(aspect > 1.5 || safe.gap < -0.4, "{safe:?}");
                        continue;
                    }
                };
                most = most.max(fast.iterations);
                let got = s.exact_gap(ri, &oi, rj, &oj, &d, f64::INFINITY).unwrap();
                assert_eq!(got, fast);
                assert!(safe.converged, "{safe:?}");
                assert_relative_eq!(got.gap, safe.gap, epsilon = 1e-13);
                assert_relative_eq!(got.normal, safe.normal, epsilon = 1e-12);
                for (a, b) in [(got.jet_i, safe.jet_i), (got.jet_j, safe.jet_j)] {
                    assert_relative_eq!(a.h, b.h, epsilon = 1e-12);
                    assert_relative_eq!(a.d1, b.d1, epsilon = 1e-12);
                    assert_relative_eq!(a.d2, b.d2, epsilon = 1e-11);
                }
            }
            assert!(near > 400, "α = {aspect}: {near} pairs near contact");
            assert!(most <= 5, "α = {aspect}: {most} steps");
            // At α = 3 the normal turns by up to ~1.3 rad from the line of
            // centres even near contact, beyond the reach of the first
            // steps on about a third of these pairs.
            assert!(handed_over < 2000 / 100 * 35, "α = {aspect}: {handed_over}");
        }
    }

    /// The warm start (`contacts_warm`, whose `H` and `H'` are moved to
    /// the final normal by their Taylor series) finds the optimum of the
    /// cold solve with the jets evaluated there (`exact_gap`) to round-off:
    /// the gap to 2·10⁻¹⁵, the normal to 10⁻¹⁴ (Halley stops `~K·10⁻¹⁵`
    /// rad from the optimum, from either start; the Taylor series leave
    /// `≲ 10⁻¹⁵`) and `H'` to `10⁻¹⁴ α²` (it moves by `H''` times the
    /// normal's difference, and `|H''|` reaches `α²` times the minor
    /// semi-axis), with no memo, for pairs near contact moved
    /// by 10⁻⁶ … 10⁻² after the solve that left the memo, and from a memo
    /// of another pair; after a move of 10⁻⁶ the warm solve takes one step
    /// where the cold one takes two or more.
    #[test]
    fn warm_start_finds_the_cold_optimum() {
        let mut rnd = uniform(5);
        for aspect in [1.1, 1.5, 3.0] {
            let s = ellipse(aspect);
            let tol_d1 = 1e-14 * aspect * aspect;
            let (mut one_step, mut tiny, mut stranger_ok) = (0, 0, 0);
            let mut stranger: PairMemo = None;
            for _ in 0..500 {
                let (ri, rj) = (0.5 + 0.2 * rnd(), 0.5 + 0.2 * rnd());
                let (ti, tj) = (6.3 * rnd(), 6.3 * rnd());
                let phi = 6.3 * rnd();
                let u = Vector::<2>::new(phi.cos(), phi.sin());
                let mut d = u * (ri + rj);
                for _ in 0..2 {
                    let h = s
                        .exact_gap_safeguarded(
                            &Pair::new(ri, Axis::new(ti), rj, Axis::new(tj), d),
                            1.0,
                        )
                        .unwrap()
                        .gap;
                    d -= u * (h - 1e-3 * (2.0 * rnd() - 1.0));
                }
                let pair = Pair::new(ri, Axis::new(ti), rj, Axis::new(tj), d);
                let mut memo: PairMemo = None;
                let first = s.exact_gap_warm(&pair, 1.0, &mut memo).unwrap();
                let cold = s.exact_gap(ri, &pair.o_i, rj, &pair.o_j, &d, 1.0).unwrap();
                assert_eq!(first.iterations, cold.iterations);
                assert_relative_eq!(first.gap, cold.gap, epsilon = 2e-15);
                assert_relative_eq!(first.jet_i.d1, cold.jet_i.d1, epsilon = 1e-14);
                assert_relative_eq!(first.jet_j.d1, cold.jet_j.d1, epsilon = 1e-14);
                assert!(memo.is_some());
                let moves = [1e-6, 1e-4, 1e-2];
                let step = moves[(3.0 * rnd()) as usize % 3];
                let mut kick = |x: f64| x + step * (2.0 * rnd() - 1.0);
                let moved = Pair::new(
                    ri,
                    Axis::new(kick(ti)),
                    rj,
                    Axis::new(kick(tj)),
                    Vector::<2>::new(kick(d[0]), kick(d[1])),
                );
                let cold = s
                    .exact_gap(ri, &moved.o_i, rj, &moved.o_j, &moved.r_ij, 1.0)
                    .unwrap();
                for (mut m, from_stranger) in [(memo, false), (stranger, true)] {
                    let Some(warm) = s.exact_gap_warm(&moved, 1.0, &mut m) else {
                        panic!("{moved:?}")
                    };
                    assert_relative_eq!(warm.gap, cold.gap, epsilon = 2e-15);
                    assert_relative_eq!(warm.normal, cold.normal, epsilon = 1e-14);
                    assert_relative_eq!(warm.jet_i.d1, cold.jet_i.d1, epsilon = tol_d1);
                    assert_relative_eq!(warm.jet_j.d1, cold.jet_j.d1, epsilon = tol_d1);
                    if from_stranger {
                        stranger_ok += 1;
                    } else if step == 1e-6 && cold.iterations >= 2 {
                        tiny += 1;
                        one_step += usize::from(warm.iterations == 1);
                    }
                }
                stranger = memo;
            }
            assert!(stranger_ok == 500);
            assert!(tiny > 100, "α = {aspect}: {tiny} pairs moved by 1e-6");
            assert!(
                one_step * 10 >= tiny * 9,
                "α = {aspect}: {one_step} of {tiny}"
            );
        }
    }

    /// `Shape::contacts_warm` goes through `Shape::contact_warm` to the
    /// warm solve: from an empty memo it visits `Shape::contacts`' contact
    /// bit for bit and records the memo; a pair apart (past the screens)
    /// gives none and leaves the memo as it was.
    #[test]
    fn contacts_warm_is_contacts_from_an_empty_memo() {
        let mut rnd = uniform(9);
        let s = ellipse(1.5);
        let (mut touching, mut apart) = (0, 0);
        for _ in 0..400 {
            let (ri, rj) = (0.5 + 0.2 * rnd(), 0.5 + 0.2 * rnd());
            let phi = 6.3 * rnd();
            let d = Vector::<2>::new(phi.cos(), phi.sin()) * ((ri + rj) * (0.8 + 0.6 * rnd()));
            let pair = Pair::new(ri, Axis::new(6.3 * rnd()), rj, Axis::new(6.3 * rnd()), d);
            let (mut cold, mut warm) = (Vec::new(), Vec::new());
            s.contacts(&pair, 0.0, |c| cold.push(c));
            let mut memo: PairMemo = None;
            s.contacts_warm(&pair, 0.0, &mut memo, |c| warm.push(c));
            assert_eq!(warm, cold);
            assert!(matches!(
                s.contact_warm(&pair, 0.0, &mut memo.clone()),
                Warm::Solved(c) if c.is_some() != cold.is_empty()
            ));
            assert_eq!(memo.is_some(), !cold.is_empty());
            if cold.is_empty() {
                apart += 1;
            } else {
                touching += 1;
            }
        }
        assert!(touching > 50 && apart > 50, "{touching} {apart}");
    }

    /// An independent check of where the gap vanishes: the Perram–Wertheim
    /// contact function `F = max_λ λ(1 − λ) rᵀ C(λ)⁻¹ r`,
    /// `C(λ) = (1 − λ) M_i + λ M_j` (`M = R diag(a², b²) Rᵀ`, so that
    /// `H(n)² = nᵀ M n`), is the square of the factor `μ` by which both
    /// ellipses, scaled about their centres, just touch. So the gap of the
    /// scaled pair vanishes (to 1e-12: `λ` by golden section to ~1e-9, `F`
    /// stationary in it) and the gap has the sign of `F − 1`.
    #[test]
    fn gap_vanishes_at_the_perram_wertheim_contact() {
        let mut rnd = uniform(5);
        for aspect in [1.1, 1.5, 3.0] {
            let s = ellipse(aspect);
            for _ in 0..300 {
                let (ri, rj) = (0.5 + 0.2 * rnd(), 0.5 + 0.2 * rnd());
                let (ti, tj, phi) = (6.3 * rnd(), 6.3 * rnd(), 6.3 * rnd());
                let reach = s.bounding_radius(ri) + s.bounding_radius(rj);
                let d = Vector::<2>::new(phi.cos(), phi.sin()) * (reach * (0.5 + 0.6 * rnd()));
                let form = |size: f64, theta: f64| {
                    let (a, b) = s.semi_axes(size);
                    let (sn, cs) = theta.sin_cos();
                    // R diag(a², b²) Rᵀ.
                    [
                        a * a * cs * cs + b * b * sn * sn,
                        (a * a - b * b) * cs * sn,
                        a * a * sn * sn + b * b * cs * cs,
                    ]
                };
                let (mi, mj) = (form(ri, ti), form(rj, tj));
                let f = |l: f64| {
                    let c = [0, 1, 2].map(|k| (1.0 - l) * mi[k] + l * mj[k]);
                    let det = c[0] * c[2] - c[1] * c[1];
                    let q =
                        (c[2] * d[0] * d[0] - 2.0 * c[1] * d[0] * d[1] + c[0] * d[1] * d[1]) / det;
                    l * (1.0 - l) * q
                };
                let (mut lo, mut hi) = (0.0, 1.0);
                let g = 0.5 * (5f64.sqrt() - 1.0);
                for _ in 0..100 {
                    let (x1, x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
                    if f(x1) < f(x2) {
                        lo = x1;
                    } else {
                        hi = x2;
                    }
                }
                let mu = f(0.5 * (lo + hi)).sqrt();
                let (oi, oj) = (Axis::new(ti), Axis::new(tj));
                let touching = s
                    .exact_gap(mu * ri, &oi, mu * rj, &oj, &d, f64::INFINITY)
                    .unwrap();
                assert!(touching.gap.abs() < 1e-12, "{touching:?}");
                let h = s
                    .exact_gap(ri, &oi, rj, &oj, &d, f64::INFINITY)
                    .unwrap()
                    .gap;
                if (mu - 1.0).abs() > 1e-9 {
                    assert_eq!(h > 0.0, mu > 1.0, "h = {h}, μ = {mu}");
                }
            }
        }
    }

    /// The iteration on `n` agrees with `gap2d::exact` run on the
    /// closed-form `H(β)` ([`Ellipse::support`]): gap to 1e-13, the normal
    /// and jets to 1e-12 (both converge to round-off), for separated,
    /// touching and overlapping pairs in all directions; ours converges within 8 iterations for α ≤ 2
    /// (30 at α = 5, where deep overlaps take gradient steps first).
    #[test]
    fn matches_the_generic_exact_gap() {
        let mut generic_capped = 0;
        for aspect in [1.01, 1.3, 2.0, 5.0] {
            let s = ellipse(aspect);
            for k in 0..200 {
                let x = k as f64;
                let (ri, rj) = (0.5 + 0.2 * (x * 0.37).sin().abs(), 0.6);
                let (ti, tj) = (3.1 * (x * 1.3).sin(), 3.1 * (x * 0.7).cos());
                let phi = x * 2.399;
                let reach = s.bounding_radius(ri) + s.bounding_radius(rj);
                let r = reach * (0.75 + 0.5 * (x * 0.113).sin().abs());
                let d = Vector::<2>::new(r * phi.cos(), r * phi.sin());
                let e = jamkit_planar::gap2d::exact(&d, ti, s.support(ri), tj, s.support(rj));
                let m = s
                    .exact_gap(ri, &Axis::new(ti), rj, &Axis::new(tj), &d, f64::INFINITY)
                    .unwrap();
                generic_capped += usize::from(!e.converged);
                assert!(
                    m.converged && m.iterations <= if aspect <= 2.0 { 8 } else { 30 },
                    "{m:?}"
                );
                assert_relative_eq!(m.gap, e.gap, epsilon = 1e-13);
                let tol = 1e-12;
                assert_relative_eq!(m.normal[0], e.normal.0, epsilon = tol);
                assert_relative_eq!(m.normal[1], e.normal.1, epsilon = tol);
                for (a, b) in [(m.jet_i, e.jet_i), (m.jet_j, e.jet_j)] {
                    assert_relative_eq!(a.h, b.h, epsilon = tol);
                    assert_relative_eq!(a.d1, b.d1, epsilon = tol);
                    assert_relative_eq!(a.d2, b.d2, epsilon = 10.0 * tol);
                }
            }
        }
        // Since `gap2d::exact` takes small Newton steps untested it
        // converges on every pair too.
        assert_eq!(generic_capped, 0, "gap2d::exact hit its iteration cap");
    }

    /// The skip test is safe: a pair skipped for `max_gap` has a gap above
    /// it (`g` at the line of centres is a lower bound on `h`).
    #[test]
    fn skipped_pairs_are_farther_than_max_gap() {
        let s = ellipse(1.8);
        let mut skipped = 0;
        for k in 0..400 {
            let x = k as f64;
            let (ti, tj) = (3.1 * (x * 1.3).sin(), 3.1 * (x * 0.7).cos());
            let r = 1.0 + 1.5 * (x * 0.113).sin().abs();
            let d = Vector::<2>::new(r * (x * 2.4).cos(), r * (x * 2.4).sin());
            let full = gap(&s, 0.5, ti, 0.7, tj, d);
            match s.exact_gap(0.5, &Axis::new(ti), 0.7, &Axis::new(tj), &d, 0.0) {
                None => {
                    skipped += 1;
                    assert!(full > 0.0);
                }
                // The contacts' jets are moved to the optimum by their
                // Taylor series where `exact_gap` evaluates them: the same
                // gap to round-off.
                Some(m) => assert_relative_eq!(m.gap, full, epsilon = 1e-15),
            }
        }
        assert!(skipped > 50);
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
            assert_eq!(e.field(), Some("params.aspect"));
            assert!(e.allowed().unwrap().contains("≥ 1"), "{e}");
        }
        for inertia in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = Ellipse::new(&EllipseParams {
                aspect: 1.5,
                inertia: Some(inertia),
            })
            .unwrap_err();
            assert_eq!(e.field(), Some("params.inertia"));
        }
        // Defaults: I = (a² + b²)/4, per size.
        let s = ellipse(2.0);
        assert_relative_eq!(s.rot_inertia(0.5)[0], 0.25 * 0.25 * 2.5, epsilon = 1e-15);
    }
}
