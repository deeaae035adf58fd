//! Contacts of smooth **non-convex** star-shaped outlines: several per pair
//! (see `docs/explanation/non-convex-gap.md`).
//!
//! ## Arcs
//!
//! A polar outline `R(φ)` (body frame) has the outward normal angle
//! `ν(φ) = φ − atan(R'/R)`, with `ν' = N/(R² + R'²)`,
//! `N = R² + 2R'² − R R''`. Its inflection points (the zeros of `N`) cut it
//! into **arcs** ([`OutlineArc`]) on which `ν` is monotonic: increasing on a
//! *convex* arc (`N > 0`), decreasing on a *concave* one. On an arc the
//! point with the normal `β` is unique; its height along `e(β)` is the arc's
//! support function `H_A(β) = R cos δ` (`δ = φ − β`), with
//! `H_A' = R sin δ` and `H_A'' = ρ − H_A`, `ρ = (R² + R'²)^{3/2}/N` the
//! signed radius of curvature (negative on a concave arc): the formulas of
//! the convex support function ([`crate::gap2d::polar_support`]) restricted
//! to the arc.
//!
//! ## Contacts
//!
//! For an arc `A` of body `i` and an arc `B` of body `j`, on the normal
//! angles `ψ` that both arcs reach (`ψ − θ_i` in `A`'s range, `ψ + π − θ_j`
//! in `B`'s),
//!
//! ```text
//! g_AB(ψ) = r_ij·e(ψ) − H_A(ψ − θ_i) − H_B(ψ + π − θ_j),   k = −g_AB'' = g_AB + ρ_A + ρ_B.
//! ```
//!
//! A stationary point `g_AB'(ψ*) = 0` is a common normal of the two arcs,
//! and `h = g_AB(ψ*)` the signed distance along it. It is a **contact**
//! when its support points lie in the arcs (half-open in `φ`, so that a
//! point at an inflection belongs to one arc) and `k ρ_A ρ_B > 0`: a
//! maximum of `g_AB` for two convex arcs, a minimum for a convex arc
//! against a concave one. At `h = 0` this is the condition that the
//! outlines touch without crossing (the signed curvatures add up to a
//! positive one). Two concave arcs have no contact: at `h ≤ 0` they
//! cross, and they meet the rule only at `h > |ρ_A| + |ρ_B|`.
//!
//! By the envelope theorem the derivatives are those of the convex exact
//! gap ([`crate::gap2d`]) with the arc's jets; the second derivatives divide
//! by `k`, of either sign ([`crate::gap2d::ExactGap::hessian_signed`]).
//!
//! ## Saddles
//!
//! The other stationary points (`k ρ_A ρ_B < 0`, on any two arcs) are the
//! local minima of the depth along the overlap. A contact is born or dies
//! where it merges with one of them: inside an arc pair at `k = 0` (a
//! fold), or at an end of the normal range shared by two arc pairs (an
//! inflection point). At `h < 0` its energy would go with it. So the
//! overlapping saddles (`h_s < 0`) are paired with contacts by the elder
//! rule of persistence: along body `i`'s outline (the stationary points
//! of the pair in order of the support point's polar angle), each contact
//! starts a component of the overlap; the saddles, deepest first, join
//! the components of their two neighbours (contacts deeper than them),
//! and the component whose deepest contact is the shallower ends there,
//! that contact taking the saddle. A contact with a saddle reports
//! `h = −√(h_c² − h_s²)` ([`ArcContact`]), so that with the harmonic
//! potential the pair's energy is `Σ h_c²/2 − Σ h_s²/2` over its contacts
//! and paired saddles, whichever contact a saddle goes to: smooth where
//! two contacts of one saddle change order in depth, continuous where a
//! contact merges with its saddle (`h = 0`) and where a saddle leaves the
//! overlap (`h_s = 0`, where `h = h_c`).
//!
//! ## The search
//!
//! Arc pairs whose bounding circles are farther apart than
//! `max(max_gap, 0) + reach` are skipped: their contacts have `h` above
//! the cut or an overlap deeper than `reach` (the near-disks take the
//! depth of two lobes, `Δ (max P − min P)(R_i⁰ + R_j⁰)`). Of the angles
//! `ψ` both arcs of a remaining pair reach, only those within
//! `asin(ρ/|D|)` of the line joining the circles' centres (`D`, radii
//! adding up to `ρ`) can hold a stationary point, since `g_AB'` is the
//! component along `e(ψ)⊥` of the line joining the two support points;
//! pieces of the range outside that window are skipped. On each
//! remaining piece `g_AB'` is sampled on the angles `ψ` both arcs reach, on
//! a grid that resolves their ends: every end is the end of an arc's normal
//! range, where `ν` is stationary (an inflection point) and the support
//! point moves as the square root of the distance in `ψ`, so the grid is
//! uniform in `u` with `ψ = lo + (hi − lo)(3u² − 2u³)`, in which it moves
//! smoothly (at least 4 cells, and one per 0.1 rad; one per 0.025 rad for
//! a concave arc against a convex one). Every sign change is
//! refined by Newton's method safeguarded by bisection, stopped after a
//! step below 10⁻⁹ rad. A cell where `g_AB'` keeps its sign while `g_AB''`
//! turns it towards zero (a tip touching both flanks of a valley puts two
//! stationary points in one cell) is searched for the extremum of `g_AB'`;
//! where `g_AB'` changes sign there, both stationary points are refined.
//! Before that, a cell where the cubic through `g_AB'` and its slope at
//! the ends turns twice inside, near zero at both turns (within a quarter
//! of the smaller end value, or past it), is halved, down to cells of
//! 10⁻⁶ rad: two extrema of `g_AB'` there may hide two stationary points
//! besides those the ends show (three within 0.1 rad, or a contact beside
//! a fold where a contact and a saddle are born). The samples take each
//! support point at its start from the arc's table
//! ([`OutlineArc::table`], computed once per shape), unsolved; a sample
//! whose `g_AB'` is within the error of that start of zero, the ends of
//! each cell that shows a stationary point and the refinement solve them
//! (Newton on the support point's polar angle), so the stationary points
//! are those of the solved outline, and where the solved ends of a cell
//! disagree with its samples the piece is scanned again with every
//! support point solved.
//! [`scan_stationary`] finds the stationary points by brute force, the
//! check of this search.

use crate::gap2d::{ExactGap, SupportJet};
use jamkit_core::math::{Unit, Vector, cmul, turn_unit, unit_of_angle};
use jamkit_core::{Contact, GapHessian};
use std::f64::consts::{PI, TAU};

/// A polar outline `φ ↦ (R, R', R'')` (body frame, unit size) at
/// `e^{iφ}`.
pub trait PolarOutline: Fn(Unit) -> (f64, f64, f64) {}
impl<F: Fn(Unit) -> (f64, f64, f64)> PolarOutline for F {}

/// One arc of an outline between consecutive inflection points, or the
/// whole of a convex outline.
#[derive(Clone, Debug, PartialEq)]
pub struct OutlineArc {
    /// Polar angles of its ends, `φ₀ < φ₁ ≤ φ₀ + 2π` (body frame).
    pub phi: (f64, f64),
    /// Normal angles `ν(φ₀)`, `ν(φ₁)`, continuous along the arc.
    pub nu: (f64, f64),
    /// Convex (`ν` increasing) or concave (`ν` decreasing).
    pub convex: bool,
    /// Centre of a circle containing the arc (body frame, unit size).
    pub centre: (f64, f64),
    /// Its radius.
    pub radius: f64,
    /// The polar angles `φ_k` (with `e^{iφ_k}` and the slope `dφ/dν =
    /// (R² + R'²)/N` there) where the normal angle is `ν₀ + (ν₁ − ν₀) k/K`,
    /// `k = 0 … K` ([`TABLE_CELLS`] = K): each normal's support point lies
    /// between two of them, where [`arc_support`] starts.
    pub table: Vec<(f64, Unit, f64)>,
}

/// The cells of an arc's table of support points ([`OutlineArc::table`]).
pub const TABLE_CELLS: usize = 64;

impl OutlineArc {
    /// The normal angles the arc reaches, `(lowest, highest)`.
    pub fn normal_range(&self) -> (f64, f64) {
        if self.convex {
            self.nu
        } else {
            (self.nu.1, self.nu.0)
        }
    }
}

/// `R² + 2R'² − R R''`: positive where the outline is convex.
#[inline]
pub fn curvature_numerator((r, r1, r2): (f64, f64, f64)) -> f64 {
    r * r + 2.0 * r1 * r1 - r * r2
}

#[inline]
fn normal_angle(phi: f64, (r, r1, _): (f64, f64, f64)) -> f64 {
    phi - (r1 / r).atan()
}

/// Cut the outline at its inflection points (sign changes of `N` on
/// `samples` angles, refined by bisection to round-off) into arcs, in order
/// of `φ`. A convex outline is one arc, `φ ∈ [0, 2π]`.
pub fn split_arcs<F: PolarOutline>(outline: &F, samples: usize) -> Vec<OutlineArc> {
    let at = |phi: f64| outline(unit_of_angle(phi));
    let n_of = |phi: f64| curvature_numerator(at(phi));
    let mut zeros = Vec::new();
    let step = TAU / samples as f64;
    let mut prev = n_of(0.0);
    for k in 1..=samples {
        let phi = step * k as f64;
        let cur = n_of(phi);
        if (prev > 0.0) != (cur > 0.0) {
            let (mut lo, mut hi) = (phi - step, phi);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if (n_of(mid) > 0.0) == (prev > 0.0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            zeros.push(0.5 * (lo + hi));
        }
        prev = cur;
    }
    let ends: Vec<(f64, f64)> = if zeros.is_empty() {
        vec![(0.0, TAU)]
    } else {
        let m = zeros.len();
        (0..m)
            .map(|k| {
                let a = zeros[k];
                let b = if k + 1 < m {
                    zeros[k + 1]
                } else {
                    zeros[0] + TAU
                };
                (a, b)
            })
            .collect()
    };
    ends.into_iter()
        .map(|(a, b)| {
            let convex = n_of(0.5 * (a + b)) > 0.0;
            let (nu_a, nu_b) = (normal_angle(a, at(a)), normal_angle(b, at(b)));
            // Bounding circle: the box of 512 points of the arc, padded by
            // what the points between samples can add (half a spacing
            // times the largest speed |dp/dφ| = √(R² + R'²) seen, doubled).
            let m = 512;
            let pts: Vec<(f64, f64, f64)> = (0..=m)
                .map(|s| {
                    let phi = a + (b - a) * s as f64 / m as f64;
                    let (r, r1, _) = at(phi);
                    (r * phi.cos(), r * phi.sin(), (r * r + r1 * r1).sqrt())
                })
                .collect();
            let fold = |f: fn(f64, f64) -> f64, g: fn(&(f64, f64, f64)) -> f64, init: f64| {
                pts.iter().map(g).fold(init, f)
            };
            let (x0, x1) = (
                fold(f64::min, |p| p.0, f64::INFINITY),
                fold(f64::max, |p| p.0, f64::NEG_INFINITY),
            );
            let (y0, y1) = (
                fold(f64::min, |p| p.1, f64::INFINITY),
                fold(f64::max, |p| p.1, f64::NEG_INFINITY),
            );
            let speed = fold(f64::max, |p| p.2, 0.0);
            let centre = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
            let far = pts
                .iter()
                .map(|p| (p.0 - centre.0).hypot(p.1 - centre.1))
                .fold(0.0, f64::max);
            let radius = far + (b - a) / m as f64 * speed + 1e-12;
            // ν is monotonic on the arc: each table entry by bisection.
            let sign = if convex { 1.0 } else { -1.0 };
            let table = (0..=TABLE_CELLS)
                .map(|k| {
                    let phi = if k == 0 {
                        a
                    } else if k == TABLE_CELLS {
                        b
                    } else {
                        let nu = nu_a + (nu_b - nu_a) * k as f64 / TABLE_CELLS as f64;
                        let (mut lo, mut hi) = (a, b);
                        for _ in 0..80 {
                            let mid = 0.5 * (lo + hi);
                            if sign * (normal_angle(mid, at(mid)) - nu) > 0.0 {
                                hi = mid;
                            } else {
                                lo = mid;
                            }
                        }
                        0.5 * (lo + hi)
                    };
                    let (r, r1, r2) = at(phi);
                    let slope = (r * r + r1 * r1) / curvature_numerator((r, r1, r2));
                    (phi, unit_of_angle(phi), slope)
                })
                .collect();
            OutlineArc {
                phi: (a, b),
                nu: (nu_a, nu_b),
                convex,
                centre,
                radius,
                table,
            }
        })
        .collect()
}

/// The point of `arc` whose outward normal has the angle `beta` (body
/// frame, within the arc's normal range; outside it, the nearer end): its
/// polar angle `φ` and the arc's support jet `(H, H', H'')` there (unit
/// size). [`arc_support_unit`] with `e^{iβ}` from `beta`.
pub fn arc_support<F: PolarOutline>(arc: &OutlineArc, beta: f64, outline: &F) -> (f64, SupportJet) {
    arc_support_unit(arc, beta, unit_of_angle(beta), outline)
}

/// [`arc_support`] given `e_beta = e^{iβ}` too. The root of
/// `q(φ) = R sin δ − R' cos δ = |p| sin(ν(φ) − β)` (`δ = φ − β`,
/// `q' = N cos δ / R`) between the two entries of the arc's table whose
/// normals enclose `β`, by Newton's method safeguarded by bisection, from
/// the cubic Hermite interpolation of `φ(ν)` in the table (values and
/// slopes; from the square root's in the end cells, where `ν − ν₀` grows
/// as `(φ − φ₀)²` at an inflection point and the slope is infinite),
/// stopped after a Newton step below 10⁻⁹ rad (what is left is ~C·10⁻¹⁸)
/// or a bracket below 10⁻¹⁴ rad. `e^{iφ}` follows the steps by
/// [`turn_unit`]: no trigonometric call.
pub fn arc_support_unit<F: PolarOutline>(
    arc: &OutlineArc,
    beta: f64,
    e_beta: Unit,
    outline: &F,
) -> (f64, SupportJet) {
    let (phi, jet, _) = support_point(arc, beta, e_beta, outline, true);
    (phi, jet)
}

/// [`arc_support_unit`], solved (`solve`) or at the table's interpolated
/// start, with the length `|q/q'|` of the Newton step that would follow
/// there: what the start is off by in `φ`, to second order (0 when
/// solved or at an entry of the table).
fn support_point<F: PolarOutline>(
    arc: &OutlineArc,
    beta: f64,
    e_beta: Unit,
    outline: &F,
    solve: bool,
) -> (f64, SupportJet, f64) {
    let sign = if arc.convex { 1.0 } else { -1.0 };
    let m = arc.table.len() - 1;
    let t = ((beta - arc.nu.0) / (arc.nu.1 - arc.nu.0)).clamp(0.0, 1.0) * m as f64;
    let k = (t as usize).min(m - 1);
    let (lo0, hi0) = (arc.table[k].0, arc.table[k + 1].0);
    let frac = t - k as f64;
    let (mut phi, mut e) = if frac <= 0.0 {
        (arc.table[k].0, arc.table[k].1)
    } else if frac >= 1.0 {
        (arc.table[k + 1].0, arc.table[k + 1].1)
    } else {
        let phi = if k == 0 {
            lo0 + (hi0 - lo0) * frac.sqrt()
        } else if k + 1 == m {
            lo0 + (hi0 - lo0) * (1.0 - (1.0 - frac).sqrt())
        } else {
            // Hermite basis on the cell, whose width in ν is `dnu`.
            let dnu = (arc.nu.1 - arc.nu.0) / m as f64;
            let (t, t2) = (frac, frac * frac);
            let t3 = t2 * t;
            let cubic = (2.0 * t3 - 3.0 * t2 + 1.0) * lo0
                + (t3 - 2.0 * t2 + t) * dnu * arc.table[k].2
                + (3.0 * t2 - 2.0 * t3) * hi0
                + (t3 - t2) * dnu * arc.table[k + 1].2;
            cubic.clamp(lo0, hi0)
        };
        (phi, turn_unit(arc.table[k].1, phi - lo0))
    };
    let (mut lo, mut hi) = (lo0, hi0);
    let back = (e_beta.0, -e_beta.1);
    let mut o = outline(e);
    let mut d = cmul(e, back);
    let inside = frac > 0.0 && frac < 1.0;
    let mut off = 0.0;
    if inside && !solve {
        let (r, r1, r2) = o;
        let q = r * d.1 - r1 * d.0;
        let dq = sign * (2.0 * r1 * d.1 + (r - r2) * d.0);
        off = if dq > 0.0 {
            (q / dq).abs()
        } else {
            f64::INFINITY
        };
    } else if inside {
        for _ in 0..100 {
            let (r, r1, r2) = o;
            let q = sign * (r * d.1 - r1 * d.0);
            if q > 0.0 {
                hi = phi;
            } else {
                lo = phi;
            }
            let dq = sign * (2.0 * r1 * d.1 + (r - r2) * d.0);
            let newton = phi - q / dq;
            // Closed: a step below the spacing of floats lands on `phi`,
            // which is an end of the bracket.
            let is_newton = dq > 0.0 && newton >= lo && newton <= hi;
            let next = if is_newton { newton } else { 0.5 * (lo + hi) };
            let step = next - phi;
            phi = next;
            e = turn_unit(e, step);
            o = outline(e);
            d = cmul(e, back);
            // After a Newton step below 1e-9 what is left is ~C·1e-18.
            if (is_newton && step.abs() < 1e-9) || hi - lo < 1e-14 {
                break;
            }
        }
    }
    let (r, r1, _) = o;
    let q = r * r + r1 * r1;
    // At an end of the arc (an inflection point) `N` is zero to round-off,
    // of either sign: it takes the arc's, so that `ρ` is the limit from
    // inside the arc (±∞ at the ends: as large as round-off in `N` allows).
    let n = curvature_numerator(o);
    let n = if sign * n > 0.0 {
        n
    } else {
        sign * f64::EPSILON * q
    };
    let rho = q * q.sqrt() / n;
    let h = r * d.0;
    (
        phi,
        SupportJet {
            h,
            d1: r * d.1,
            d2: rho - h,
        },
        off,
    )
}

/// A contact of two arcs ([`arc_contacts`]): the common normal where the
/// depth of the overlap is locally largest (`exact`), and the saddle it
/// meets, if any: the neighbouring stationary point of the same arc pair
/// where the depth is locally smallest, overlapping (`h_s < 0`) and
/// shallower than the contact. With a saddle the contact's gap is
///
/// ```text
/// h = −√(h_c² − h_s²)   (h_c ≤ h_s < 0),
/// ```
///
/// which is `h_c` when the saddle reaches `h_s = 0` (first derivatives
/// too) and 0 where the two merge (a fold, `h_s = h_c`), so that a contact
/// leaving at a fold takes no energy with it; with the harmonic potential
/// its energy is `h_c²/2 − h_s²/2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcContact {
    /// The contact's common normal and support jets (sizes included).
    pub exact: ExactGap,
    /// The saddle paired with it.
    pub saddle: Option<ExactGap>,
}

impl ArcContact {
    /// The gap: `h_c`, or with a saddle `−√(h_c² − h_s²)` (0 where
    /// rounding puts the saddle deeper).
    pub fn gap(&self) -> f64 {
        match self.saddle {
            None => self.exact.gap,
            Some(s) => Self::merged(self.exact.gap, s.gap).map_or(0.0, |root| -root),
        }
    }

    /// `√(h_c² − h_s²)` of a contact with a saddle, or `None` where the two
    /// have merged to rounding (gap 0, and so no force: the derivatives of
    /// `h_c` stand in for the gap's).
    fn merged(c: f64, a: f64) -> Option<f64> {
        let q = c * c - a * a;
        (q > 0.0).then(|| q.sqrt())
    }

    /// The gap and its first derivatives.
    pub fn contact(&self) -> Contact<2> {
        let c = self.exact.contact();
        let Some(s) = self.saddle else {
            return c;
        };
        let a = s.contact();
        let (hc, ha) = (c.gap, a.gap);
        let Some(root) = Self::merged(hc, ha) else {
            return Contact { gap: 0.0, ..c };
        };
        let (fc, fa) = (-hc / root, ha / root);
        Contact {
            gap: -root,
            grad_r: c.grad_r * fc + a.grad_r * fa,
            grad_rot_i: [fc * c.grad_rot_i[0] + fa * a.grad_rot_i[0], 0.0, 0.0],
            grad_rot_j: [fc * c.grad_rot_j[0] + fa * a.grad_rot_j[0], 0.0, 0.0],
        }
    }

    /// The gap with its second derivatives: those of `h_c` and `h_s`
    /// ([`ExactGap::hessian_signed`]) by the chain rule.
    pub fn hessian(&self) -> GapHessian<2> {
        let hc = self.exact.hessian_signed();
        let Some(s) = self.saddle else {
            return hc;
        };
        let ha = s.hessian_signed();
        let (c, a) = (hc.contact.gap, ha.contact.gap);
        let Some(root) = Self::merged(c, a) else {
            let mut g = hc;
            g.contact.gap = 0.0;
            return g;
        };
        let cube = root * root * root;
        let (fc, fa) = (-c / root, a / root);
        let (fcc, faa, fca) = (a * a / cube, c * c / cube, -c * a / cube);
        let (mc, ma) = (as_matrix(&hc), as_matrix(&ha));
        let (gc, ga) = (as_gradient(&hc.contact), as_gradient(&ha.contact));
        let mut m = [[0.0; 4]; 4];
        for (k, row) in m.iter_mut().enumerate() {
            for (l, x) in row.iter_mut().enumerate() {
                *x = fc * mc[k][l]
                    + fa * ma[k][l]
                    + fcc * gc[k] * gc[l]
                    + faa * ga[k] * ga[l]
                    + fca * (gc[k] * ga[l] + ga[k] * gc[l]);
            }
        }
        let mut g = hc;
        g.contact = self.contact();
        for k in 0..2 {
            for l in 0..2 {
                g.rr[(k, l)] = m[k][l];
            }
            g.r_qi[0][k] = m[k][2];
            g.r_qj[0][k] = m[k][3];
        }
        g.qi_qi[0][0] = m[2][2];
        g.qj_qj[0][0] = m[3][3];
        g.qi_qj[0][0] = m[2][3];
        g
    }
}

/// `(∂h/∂r_j, ∂h/∂θ_i, ∂h/∂θ_j)` as one vector.
fn as_gradient(c: &Contact<2>) -> [f64; 4] {
    [c.grad_r[0], c.grad_r[1], c.grad_rot_i[0], c.grad_rot_j[0]]
}

/// The second derivatives in the order of [`as_gradient`].
fn as_matrix(h: &GapHessian<2>) -> [[f64; 4]; 4] {
    let (rq_i, rq_j) = (h.r_qi[0], h.r_qj[0]);
    [
        [h.rr[(0, 0)], h.rr[(0, 1)], rq_i[0], rq_j[0]],
        [h.rr[(1, 0)], h.rr[(1, 1)], rq_i[1], rq_j[1]],
        [rq_i[0], rq_i[1], h.qi_qi[0][0], h.qi_qj[0][0]],
        [rq_j[0], rq_j[1], h.qi_qj[0][0], h.qj_qj[0][0]],
    ]
}

/// One body as [`arc_contacts`] sees it: its arcs and outline (unit size),
/// size and orientation angle.
pub struct ArcBody<'a, F> {
    /// The arcs of its outline ([`split_arcs`]).
    pub arcs: &'a [OutlineArc],
    /// Its outline at unit size.
    pub outline: &'a F,
    /// `R⁰`.
    pub size: f64,
    /// `θ`.
    pub theta: f64,
}

/// Visit every contact (module documentation) of bodies `i` and `j` at
/// separation `r_ij` whose gap is at most `max_gap`, as an [`ExactGap`]
/// (sizes included): every one with `−reach ≤ h ≤ max_gap` and perhaps
/// deeper ones (arc pairs whose bounding circles are more than
/// `max(max_gap, 0) + reach` apart are skipped).
pub fn arc_contacts<F: PolarOutline, G: PolarOutline, V: FnMut(ArcContact)>(
    i: &ArcBody<'_, F>,
    j: &ArcBody<'_, G>,
    r_ij: &Vector<2>,
    max_gap: f64,
    reach: f64,
    visit: V,
) {
    contacts_by(i, j, r_ij, max_gap, reach, Scan::DEFAULT, visit);
}

/// How [`piece`] scans: its starting cells and whether its samples are
/// solved support points or the tables' starts.
#[derive(Clone, Copy, Debug)]
struct Scan {
    /// The widest starting cell on arcs both convex or both concave, rad.
    cell: f64,
    /// The widest starting cell on a concave arc against a convex one, rad.
    concave_cell: f64,
    /// Every sample solved (else the tables' starts, see [`piece`]).
    solved: bool,
}

impl Scan {
    const DEFAULT: Scan = Scan {
        cell: CELL,
        concave_cell: CONCAVE_CELL,
        solved: false,
    };
}

/// [`arc_contacts`] with the scan `scan`.
fn contacts_by<F: PolarOutline, G: PolarOutline, V: FnMut(ArcContact)>(
    i: &ArcBody<'_, F>,
    j: &ArcBody<'_, G>,
    r_ij: &Vector<2>,
    max_gap: f64,
    reach: f64,
    scan: Scan,
    mut visit: V,
) {
    let mut found: Vec<Stationary> = Vec::new();
    let cut = max_gap.max(0.0) + reach;
    let (zi, zj) = (unit_of_angle(i.theta), unit_of_angle(j.theta));
    let place = |z: Unit, c: (f64, f64), size: f64| {
        (
            size * (z.0 * c.0 - z.1 * c.1),
            size * (z.1 * c.0 + z.0 * c.1),
        )
    };
    // First each arc against the other body's bounding circle (its
    // arcs' farthest reach), then the pairs of arcs that pass: body j's
    // arcs that pass, with their placed centres, once.
    let (bound_i, bound_j) = (bound_of(i), bound_of(j));
    let near_j: Vec<(&OutlineArc, (f64, f64))> = j
        .arcs
        .iter()
        .map(|arc_b| (arc_b, place(zj, arc_b.centre, j.size)))
        .filter(|(arc_b, cb)| {
            norm(r_ij[0] + cb.0, r_ij[1] + cb.1) - j.size * arc_b.radius <= bound_i + cut
        })
        .collect();
    for arc_a in i.arcs {
        let ca = place(zi, arc_a.centre, i.size);
        if norm(r_ij[0] - ca.0, r_ij[1] - ca.1) - i.size * arc_a.radius > bound_j + cut {
            continue;
        }
        for &(arc_b, cb) in &near_j {
            let between = (r_ij[0] + cb.0 - ca.0, r_ij[1] + cb.1 - ca.1);
            let radii = i.size * arc_a.radius + j.size * arc_b.radius;
            if norm(between.0, between.1) - radii > cut {
                continue;
            }
            let window = NormalWindow::new(between, radii);
            pair_of_arcs(i, arc_a, j, arc_b, r_ij, &window, scan, &mut found);
        }
    }
    // The elder rule (module documentation): along body i's outline (by
    // the polar angle of the support point, around the circle) each
    // contact starts a component; the saddles, deepest first, join the
    // components of their neighbours that are contacts deeper than them,
    // and the deepest contact of the one whose deepest is the shallower
    // takes the saddle. A saddle with one such neighbour goes to it if it
    // has none; one whose neighbours are already joined goes to none.
    found.sort_by(|a, b| a.phi_i.total_cmp(&b.phi_i));
    let m = found.len();
    let gap = |k: usize| found[k].exact.gap;
    let mut saddle: Vec<Option<usize>> = vec![None; m];
    // Union-find over the stationary points; a component's root is its
    // deepest contact (the older root stays the root).
    let mut parent: Vec<usize> = (0..m).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    let mut saddles: Vec<usize> = (0..m).filter(|&k| !found[k].contact).collect();
    saddles.sort_by(|&a, &b| gap(a).total_cmp(&gap(b)));
    for s in saddles {
        let sides: Vec<usize> = [(s + m - 1) % m, (s + 1) % m]
            .into_iter()
            .filter(|&c| found[c].contact && gap(c) < gap(s))
            .collect();
        match sides[..] {
            [l, r] if l != r => {
                let (rl, rr) = (root(&mut parent, l), root(&mut parent, r));
                if rl == rr {
                    continue;
                }
                let (young, old) = if gap(rl) > gap(rr) {
                    (rl, rr)
                } else {
                    (rr, rl)
                };
                if saddle[young].is_none() {
                    saddle[young] = Some(s);
                }
                parent[young] = old;
            }
            [c] | [c, _] if saddle[c].is_none() => saddle[c] = Some(s),
            _ => {}
        }
    }
    for (c, f) in found.iter().enumerate() {
        if f.contact && f.exact.gap <= max_gap {
            visit(ArcContact {
                exact: f.exact,
                saddle: saddle[c].map(|s| found[s].exact),
            });
        }
    }
}

/// A stationary point of an arc pair: a contact, or an overlapping saddle.
struct Stationary {
    exact: ExactGap,
    /// The polar angle of its support point on body `i` (body frame, in
    /// `[0, 2π)`).
    phi_i: f64,
    contact: bool,
}

#[inline(always)]
fn norm(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// The radius of a circle about the body's centre that holds all its arcs.
fn bound_of<F>(b: &ArcBody<'_, F>) -> f64 {
    b.size
        * b.arcs
            .iter()
            .map(|a| norm(a.centre.0, a.centre.1) + a.radius)
            .fold(0.0, f64::max)
}

/// The contacts of one pair of arcs.
#[allow(clippy::too_many_arguments)]
fn pair_of_arcs<F: PolarOutline, G: PolarOutline>(
    i: &ArcBody<'_, F>,
    arc_a: &OutlineArc,
    j: &ArcBody<'_, G>,
    arc_b: &OutlineArc,
    r_ij: &Vector<2>,
    window: &NormalWindow,
    scan: Scan,
    found: &mut Vec<Stationary>,
) {
    let (na, nb) = (arc_a.normal_range(), arc_b.normal_range());
    let (a_lo, a_len) = (i.theta + na.0, na.1 - na.0);
    let b_lo0 = j.theta - PI + nb.0;
    let b_len = nb.1 - nb.0;
    // Shift B's range by whole turns so that it starts at or after
    // a_lo − b_len, then visit every overlap with A's.
    let turns = ((a_lo - b_len - b_lo0) / TAU).ceil();
    let mut shift = turns * TAU;
    while b_lo0 + shift < a_lo + a_len {
        let lo = a_lo.max(b_lo0 + shift);
        let hi = (a_lo + a_len).min(b_lo0 + shift + b_len);
        if hi > lo && window.meets(lo, hi) {
            piece(i, arc_a, j, arc_b, shift, (lo, hi), r_ij, scan, found);
        }
        shift += TAU;
    }
}

/// The normals `ψ` at which two arcs can have a stationary point. With the
/// support points `x_A(ψ)`, `x_B(ψ)` (lab frame), `g_AB' = e(ψ)⊥·(x_B − x_A)`:
/// zero only where the line joining the support points is along `e(ψ)`.
/// The arcs lie in circles of centres `C_A`, `C_B` and radii adding up to
/// `ρ`, so a stationary point needs `|e(ψ)⊥·D| ≤ ρ`, `D = C_B − C_A`:
/// `ψ` within `asin(ρ/|D|)` of the direction of `D` or of its opposite.
/// A piece of the normal range outside this holds no stationary point,
/// so leaving it out changes no result.
struct NormalWindow {
    /// The direction of `D`, less the half-width (`None`: every `ψ`).
    start: Option<f64>,
    /// The width, `2 asin(ρ/|D|)` with a margin.
    width: f64,
}

impl NormalWindow {
    fn new(between: (f64, f64), radii: f64) -> Self {
        // The margin covers the round-off of `g_AB'` (of order 1e-16 of
        // the sizes) many times over.
        let (distance, radii) = (norm(between.0, between.1), radii + 1e-9);
        if distance <= radii {
            return NormalWindow {
                start: None,
                width: PI,
            };
        }
        let half = (radii / distance).asin() + 1e-9;
        NormalWindow {
            start: Some(between.1.atan2(between.0) - half),
            width: 2.0 * half,
        }
    }

    /// Whether `[lo, hi]` meets the window or its half-turn.
    fn meets(&self, lo: f64, hi: f64) -> bool {
        match self.start {
            None => true,
            Some(start) => {
                let t = (lo - start).rem_euclid(PI);
                t <= self.width || t + (hi - lo) >= PI
            }
        }
    }
}

/// `g`, `g'`, `g''` of an arc pair at `ψ`, the jets (sizes included) and
/// the support points' polar angles; whether they are solved, and if not
/// (the scan's samples), `off`: a bound of how far `g'` is from the solved
/// value.
struct Eval {
    g: f64,
    g1: f64,
    g2: f64,
    jets: (SupportJet, SupportJet),
    rho_sign: f64,
    phis: (f64, f64),
    solved: bool,
    off: f64,
}

/// A cell of the scan of a piece whose ends (`ψ`, `g'`, `g''`, solved)
/// show a root of `g'` (`g'` changes sign) or may hide two (`turn`: `g'`
/// of one sign, `g''` turning it towards the other).
struct Cell {
    ends: [(f64, f64, f64, bool); 2],
    turn: bool,
}

/// The stationary points of arcs `A` (body `i`) and `B` (body `j`) on the
/// normals `ψ ∈ [lo, hi]` both reach (`ψ + π − θ_j − shift` in `B`'s
/// range).
///
/// The scan samples `g'` with the support points at the arcs' table
/// starts, unsolved, which is off by the length of the Newton step that
/// would follow, to second order: a sample whose `g'` is within four times
/// that of zero is solved. The cells that show roots are then taken with
/// solved ends: each root is refined on solved values (the same as from a
/// scan of solved points wherever the cells are the same). Where a cell's
/// solved ends do not show what its unsolved ones did, the piece is scanned
/// again with every point solved.
#[allow(clippy::too_many_arguments)]
fn piece<F: PolarOutline, G: PolarOutline>(
    i: &ArcBody<'_, F>,
    arc_a: &OutlineArc,
    j: &ArcBody<'_, G>,
    arc_b: &OutlineArc,
    shift: f64,
    (lo, hi): (f64, f64),
    r_ij: &Vector<2>,
    scan: Scan,
    found: &mut Vec<Stationary>,
) {
    let (zi, zj) = (unit_of_angle(i.theta), unit_of_angle(j.theta));
    let eval_by = |psi: f64, solve: bool| {
        let (s, c) = psi.sin_cos();
        // e^{i(ψ − θ_i)} and e^{i(ψ + π − θ_j)}.
        let e_a = cmul((c, s), (zi.0, -zi.1));
        let e_b = cmul((-c, -s), (zj.0, -zj.1));
        let (pa, ja, off_a) = support_point(arc_a, psi - i.theta, e_a, i.outline, solve);
        let (pb, jb, off_b) =
            support_point(arc_b, psi - shift + PI - j.theta, e_b, j.outline, solve);
        let along = r_ij[0] * c + r_ij[1] * s;
        let scale = |jet: SupportJet, size: f64| SupportJet {
            h: size * jet.h,
            d1: size * jet.d1,
            d2: size * jet.d2,
        };
        let (ja_s, jb_s) = (scale(ja, i.size), scale(jb, j.size));
        // `H' = R sin δ` at a point off by `ε` in `φ` is off by at most
        // `|p| ε` (`|p|² = H² + H'²`).
        let off = if solve {
            0.0
        } else {
            norm(ja_s.h, ja_s.d1) * off_a + norm(jb_s.h, jb_s.d1) * off_b
        };
        Eval {
            g: along - ja_s.h - jb_s.h,
            g1: -r_ij[0] * s + r_ij[1] * c - ja_s.d1 - jb_s.d1,
            g2: -along - ja_s.d2 - jb_s.d2,
            jets: (ja_s, jb_s),
            rho_sign: (ja.h + ja.d2).signum() * (jb.h + jb.d2).signum(),
            phis: (pa, pb),
            solved: solve,
            off,
        }
    };
    let exact = |psi: f64| eval_by(psi, true);
    let rough = |psi: f64| {
        let e = eval_by(psi, false);
        if e.g1.abs() <= 4.0 * e.off {
            exact(psi)
        } else {
            e
        }
    };
    // Both ends of a piece are ends of an arc's normal range, where the
    // support point moves as the square root of the distance in ψ (ν is
    // stationary at an inflection point): the grid is uniform in u with
    // ψ = lo + (hi − lo)(3u² − 2u³), in which it moves smoothly.
    let width = if arc_a.convex == arc_b.convex {
        scan.cell
    } else {
        scan.concave_cell
    };
    let cells = ((hi - lo) / width).ceil().max(4.0) as usize;
    let inside = |phi: f64, arc: &OutlineArc| phi >= arc.phi.0 && phi < arc.phi.1;
    // The contacts (those above `max_gap` too: they are neighbours in the
    // pairing of saddles) and the saddles (`k ρ_A ρ_B < 0`) with `h < 0`.
    let root = |kept: &mut Vec<Stationary>, x0: f64, f0: f64, x1: f64, f1: f64| {
        if let Some((psi, steps, e)) = refine(&exact, (x0, f0), (x1, f1))
            && inside(e.phis.0, arc_a)
            && inside(e.phis.1, arc_b)
        {
            // Two concave arcs give saddles only (their other stationary
            // points lie at h > |ρ_A| + |ρ_B|).
            let contact = -e.g2 * e.rho_sign > 0.0;
            let keep = if contact {
                arc_a.convex || arc_b.convex
            } else {
                e.g < 0.0
            };
            if keep {
                let (s, c) = psi.sin_cos();
                kept.push(Stationary {
                    exact: ExactGap {
                        normal: (c, s),
                        gap: e.g,
                        jet_i: e.jets.0,
                        jet_j: e.jets.1,
                        iterations: steps,
                        converged: true,
                    },
                    phi_i: e.phis.0.rem_euclid(TAU),
                    contact,
                });
            }
        }
    };
    for solved in [scan.solved, true] {
        let shown = if solved {
            scan_cells(&exact, (lo, hi), cells)
        } else {
            scan_cells(&rough, (lo, hi), cells)
        };
        let mut kept = Vec::new();
        let mut redo = false;
        for cell in shown {
            let [a, b] = cell.ends.map(|(psi, g1, g2, was_solved)| {
                if was_solved {
                    (psi, g1, g2)
                } else {
                    let e = exact(psi);
                    (psi, e.g1, e.g2)
                }
            });
            let (pa, pb) = (a.1 > 0.0, b.1 > 0.0);
            if !cell.turn && pa != pb {
                root(&mut kept, a.0, a.1, b.0, b.1);
            } else if cell.turn && pa == pb && (a.2 > 0.0) != (b.2 > 0.0) && (a.2 > 0.0) != pa {
                if let Some((xm, fm)) = crossing(&exact, (a.0, a.2), (b.0, b.2), pa) {
                    root(&mut kept, a.0, a.1, xm, fm);
                    root(&mut kept, xm, fm, b.0, b.1);
                }
            } else {
                redo = true;
                break;
            }
        }
        if !redo {
            found.append(&mut kept);
            return;
        }
    }
}

/// The cells of a piece `[lo, hi]` (`cells` of them in `u`, halved where
/// the cubic test asks) that show or may hide roots of `g'`, with `g'` and
/// `g''` from `eval`.
fn scan_cells<E: Fn(f64) -> Eval>(eval: &E, (lo, hi): (f64, f64), cells: usize) -> Vec<Cell> {
    let at = |u: f64| {
        if u >= 1.0 {
            hi
        } else {
            lo + (hi - lo) * u * u * (3.0 - 2.0 * u)
        }
    };
    // dψ/du.
    let rate = |u: f64| (hi - lo) * 6.0 * u * (1.0 - u);
    let end = |psi: f64, e: &Eval| (psi, e.g1, e.g2, e.solved);
    // A cell: where the cubic through `g'` and its slope in `u` at the ends
    // turns twice inside, near zero at both turns, two extrema may hide two
    // roots besides those the ends show: the cell is halved in `u` (down to
    // [`MIN_CELL`] in ψ). Else a root of `g'` where it changes sign; two
    // where it has the same sign at both ends and one extremum inside turns
    // it towards the other sign (then `g''` changes sign).
    let mut shown = Vec::new();
    let mut stack = Vec::new();
    let mut left = eval(lo);
    for k in 1..=cells {
        let u1 = k as f64 / cells as f64;
        stack.push(((k - 1) as f64 / cells as f64, u1, eval(at(u1))));
        while let Some((ua, ub, right)) = stack.pop() {
            let (a, b, start) = (at(ua), at(ub), &left);
            if b - a > MIN_CELL
                && may_cross(
                    ub - ua,
                    (start.g1, start.g2 * rate(ua)),
                    (right.g1, right.g2 * rate(ub)),
                )
            {
                let um = 0.5 * (ua + ub);
                stack.push((um, ub, right));
                stack.push((ua, um, eval(at(um))));
                continue;
            }
            let turn = (start.g2 > 0.0) != (right.g2 > 0.0) && (start.g2 > 0.0) != (start.g1 > 0.0);
            if (start.g1 > 0.0) != (right.g1 > 0.0) || turn {
                shown.push(Cell {
                    ends: [end(a, start), end(b, &right)],
                    turn: (start.g1 > 0.0) == (right.g1 > 0.0),
                });
            }
            left = right;
        }
    }
    shown
}

/// The widest cell of ψ the scan of a piece starts from, in radians, on
/// pairs of arcs both convex or both concave (and at least 4 cells a
/// piece). The cubic test halves cells where two stationary points may
/// hide; the starting width sets how fine the scan is before that.
const CELL: f64 = 0.1;

/// The widest cell of ψ on a concave arc against a convex one, in
/// radians: narrower, since a tip in a valley of about its own curvature
/// has `g''` near zero over a range of ψ and several stationary points
/// close together.
const CONCAVE_CELL: f64 = 0.025;

/// The narrowest cell [`piece`] halves, in radians of ψ.
const MIN_CELL: f64 = 1e-6;

/// Whether the cubic through `g'` and its slope at the two ends of a cell
/// of width `w` in `u` (`(g', dg'/du)` at each end) may hide two roots of
/// `g'` besides those its end values show: it turns twice inside (its
/// slope, a quadratic in `t ∈ (0, 1)`, has two roots there), and at both
/// turns it lies on the side of zero that two more roots need or within a
/// quarter of the smaller end value of it. With `g'` of one sign at both
/// ends that is one turn (either, the one towards zero) near or past
/// zero; with a sign change, the first turn past the far end's sign or
/// near zero, and the second back on the near end's side or near zero (a
/// contact beside a fold). In `u` the slope stays finite at a piece's
/// ends, where `g''` of `ψ` does not.
fn may_cross(w: f64, (p0, d0): (f64, f64), (p1, d1): (f64, f64)) -> bool {
    let (m0, m1) = (w * d0, w * d1);
    let a = 6.0 * (p0 - p1) + 3.0 * (m0 + m1);
    let b = 6.0 * (p1 - p0) - 4.0 * m0 - 2.0 * m1;
    let disc = b * b - 4.0 * a * m0;
    if a == 0.0 || !(disc > 0.0) {
        return false;
    }
    let root = disc.sqrt();
    let (t1, t2) = {
        let (x, y) = ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a));
        (x.min(y), x.max(y))
    };
    if !(t1 > 0.0 && t2 < 1.0) {
        return false;
    }
    let near = 0.25 * p0.abs().min(p1.abs());
    let cubic = |t: f64| {
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * p0
            + (t3 - 2.0 * t2 + t) * m0
            + (3.0 * t2 - 2.0 * t3) * p1
            + (t3 - t2) * m1
    };
    // How far `c` lies on the side of `p`'s sign (negative: past zero).
    let beyond = |c: f64, p: f64| if p > 0.0 { c } else { -c };
    let (c1, c2) = (cubic(t1), cubic(t2));
    if (p0 > 0.0) == (p1 > 0.0) {
        beyond(c1, p0) < near || beyond(c2, p0) < near
    } else {
        beyond(c1, p0) < near && beyond(c2, p1) < near
    }
}

/// In a cell where `g'` has the sign `positive` at both ends and `g''`
/// changes sign from the opposite one to it (`g'` goes towards zero, then
/// back): a point where `g'` has the other sign, if the extremum of `g'`
/// between reaches it. The extremum is bracketed by the sign of `g''`
/// (regula falsi, Illinois), stopped when `g'` crosses or the bracket is
/// below 10⁻¹³ rad (a double root at most: a fold).
fn crossing<E: Fn(f64) -> Eval>(
    eval: &E,
    (mut a, mut fa): (f64, f64),
    (mut b, mut fb): (f64, f64),
    positive: bool,
) -> Option<(f64, f64)> {
    let mut side = 0;
    for _ in 0..100 {
        if b - a < 1e-13 {
            return None;
        }
        let x = (a * fb - b * fa) / (fb - fa);
        let x = if x > a && x < b { x } else { 0.5 * (a + b) };
        let e = eval(x);
        if (e.g1 > 0.0) != positive {
            return Some((x, e.g1));
        }
        if (e.g2 > 0.0) == (fa > 0.0) {
            a = x;
            fa = e.g2;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = x;
            fb = e.g2;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
    }
    None
}

/// The root of `g'` in `[x0, x1]`, given `g'` at both ends (of opposite
/// signs): Newton's method on `g'` from the secant's root, safeguarded by
/// bisection, stopped after a Newton step below 10⁻⁹ rad (what is left is
/// ~C·10⁻¹⁸) or a bracket below 10⁻¹⁴ rad; the root, the steps taken and
/// the evaluation there.
fn refine<E: Fn(f64) -> Eval>(
    eval: &E,
    (x0, f0): (f64, f64),
    (x1, f1): (f64, f64),
) -> Option<(f64, u32, Eval)> {
    let positive_left = f0 > 0.0;
    let (mut lo, mut hi) = (x0, x1);
    // The secant's root first.
    let mut x = x0 + (x1 - x0) * (f0 / (f0 - f1)).clamp(0.01, 0.99);
    let mut e = eval(x);
    for steps in 1..=200 {
        if (e.g1 > 0.0) == positive_left {
            lo = x;
        } else {
            hi = x;
        }
        let newton = x - e.g1 / e.g2;
        // Closed: a step below the spacing of floats lands on `x`, which is
        // an end of the bracket.
        let is_newton = newton.is_finite() && newton >= lo && newton <= hi;
        let next = if is_newton { newton } else { 0.5 * (lo + hi) };
        let step = (next - x).abs();
        x = next;
        e = eval(x);
        if (is_newton && step < 1e-9) || hi - lo < 1e-14 {
            return Some((x, steps, e));
        }
    }
    None
}

/// A stationary point found by [`scan_stationary`]: the arcs (indices in
/// each body's list), the normal angle `ψ`, the signed distance `h` and
/// whether it is a contact (`k ρ_A ρ_B > 0`) or a saddle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scanned {
    /// Body `i`'s arc.
    pub arc_i: usize,
    /// Body `j`'s arc.
    pub arc_j: usize,
    /// `ψ`.
    pub psi: f64,
    /// `g_AB(ψ)`.
    pub gap: f64,
    /// A contact, else a saddle.
    pub contact: bool,
}

/// Every stationary point with `h < 0` of every pair of arcs of bodies `i`
/// and `j` with `ψ` in `[from, to]`, by brute force: on each range of `ψ`
/// that both arcs of a pair reach, `g_AB'` on `ψ = lo + (hi − lo)(3u² −
/// 2u³)` with `u` on a uniform grid, as many cells per range as its share
/// of `cells` over `[from, to]` (at least 64; the grid crowds the range's
/// ends, where the support points move as the square root of the distance
/// in `ψ`), each arc's support point by [`arc_support`], every sign change
/// bisected to the spacing of floats. Slow, and independent of
/// [`arc_contacts`]' table starts, cells, cubic test and pairing: the
/// check of its search, for tests and diagnostics. Deep stationary points
/// of arcs facing away from each other (`h` below `−reach` of
/// [`arc_contacts`]) are listed too.
pub fn scan_stationary<F: PolarOutline, G: PolarOutline>(
    i: &ArcBody<'_, F>,
    j: &ArcBody<'_, G>,
    r_ij: &Vector<2>,
    (from, to): (f64, f64),
    cells: usize,
) -> Vec<Scanned> {
    let mut out = Vec::new();
    for (a, arc_a) in i.arcs.iter().enumerate() {
        for (b, arc_b) in j.arcs.iter().enumerate() {
            let (na, nb) = (arc_a.normal_range(), arc_b.normal_range());
            // Arc a reaches ψ where ψ − θ_i lies in its range, arc b where
            // ψ + π − θ_j does (both modulo 2π): each range placed in ψ,
            // shifted by whole turns over [from, to].
            let placed = |start: f64, len: f64| {
                let first = ((from - len - start) / TAU).ceil() as i64;
                let last = ((to - start) / TAU).floor() as i64;
                (first..=last).map(move |k| (start + k as f64 * TAU, len))
            };
            for (sa, la) in placed(i.theta + na.0, na.1 - na.0) {
                for (sb, lb) in placed(j.theta - PI + nb.0, nb.1 - nb.0) {
                    let (lo, hi) = (from.max(sa).max(sb), to.min(sa + la).min(sb + lb));
                    if hi > lo {
                        let share = (hi - lo) / (to - from) * cells as f64;
                        stationary_by_brute_force(
                            i,
                            (a, arc_a),
                            j,
                            (b, arc_b),
                            r_ij,
                            (sa, sb),
                            (lo, hi),
                            share,
                            &mut out,
                        );
                    }
                }
            }
        }
    }
    out
}

/// [`scan_stationary`] on one range `[lo, hi]` of `ψ` that arcs `a` and
/// `b` both reach (`starts`: where their ranges, placed in `ψ`, begin).
#[allow(clippy::too_many_arguments)]
fn stationary_by_brute_force<F: PolarOutline, G: PolarOutline>(
    i: &ArcBody<'_, F>,
    (a, arc_a): (usize, &OutlineArc),
    j: &ArcBody<'_, G>,
    (b, arc_b): (usize, &OutlineArc),
    r_ij: &Vector<2>,
    starts: (f64, f64),
    (lo, hi): (f64, f64),
    share: f64,
    out: &mut Vec<Scanned>,
) {
    let (na, nb) = (arc_a.normal_range(), arc_b.normal_range());
    // (g, g', g'', sign of ρ_A ρ_B) at ψ, each normal held within its
    // arc's range against round-off.
    let eval = |psi: f64| {
        let beta_a = (na.0 + (psi - starts.0)).clamp(na.0, na.1);
        let beta_b = (nb.0 + (psi - starts.1)).clamp(nb.0, nb.1);
        let (_, ja) = arc_support(arc_a, beta_a, i.outline);
        let (_, jb) = arc_support(arc_b, beta_b, j.outline);
        let (s, c) = psi.sin_cos();
        let along = r_ij[0] * c + r_ij[1] * s;
        (
            along - i.size * ja.h - j.size * jb.h,
            -r_ij[0] * s + r_ij[1] * c - i.size * ja.d1 - j.size * jb.d1,
            -along - i.size * ja.d2 - j.size * jb.d2,
            (ja.h + ja.d2).signum() * (jb.h + jb.d2).signum(),
        )
    };
    let cells = share.ceil().max(64.0) as usize;
    let at = |k: usize| {
        let u = k as f64 / cells as f64;
        if k == cells {
            hi
        } else {
            lo + (hi - lo) * u * u * (3.0 - 2.0 * u)
        }
    };
    let mut last = (lo, eval(lo).1);
    for k in 1..=cells {
        let psi = at(k);
        let g1 = eval(psi).1;
        let (x0, f0) = std::mem::replace(&mut last, (psi, g1));
        if (f0 > 0.0) == (g1 > 0.0) {
            continue;
        }
        let (mut left, mut right) = (x0, psi);
        for _ in 0..64 {
            let m = 0.5 * (left + right);
            if (eval(m).1 > 0.0) == (f0 > 0.0) {
                left = m;
            } else {
                right = m;
            }
        }
        let psi = 0.5 * (left + right);
        let (gap, _, g2, rho) = eval(psi);
        if gap < 0.0 {
            out.push(Scanned {
                arc_i: a,
                arc_j: b,
                psi,
                gap,
                contact: -g2 * rho > 0.0,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::uniform;

    /// A pair of near-disks of n lobes of amplitude Δ as in a packing:
    /// sizes 0.5 and 0.5 or 0.7 (`[i, j]`), any angles, the centres from
    /// 2Δ/n closer to Δ/n farther than touching disks (relative) in any
    /// direction (`r_ij`): lobes interlocked or about to.
    fn packing_pair(
        next: &mut impl FnMut() -> f64,
        n: f64,
        delta: f64,
    ) -> ([f64; 2], [f64; 2], Vector<2>) {
        let sizes = [0.5, if next() < 0.5 { 0.5 } else { 0.7 }];
        let thetas = [TAU * next(), TAU * next()];
        let angle = TAU * next();
        let distance = (sizes[0] + sizes[1]) * (1.0 + delta / n * (3.0 * next() - 2.0));
        (
            sizes,
            thetas,
            Vector::<2>::new(distance * angle.cos(), distance * angle.sin()),
        )
    }

    /// The contacts (gaps up to 0.02) of two bodies of `outline`, split
    /// into `arcs`, of `sizes` and angles `thetas` at separation `r`, by
    /// `scan`; stationary points searched down to a depth of two lobes,
    /// `2Δ/n` of the sizes.
    fn scanned<F: PolarOutline>(
        (arcs, outline): (&[OutlineArc], &F),
        (n, delta): (f64, f64),
        sizes: [f64; 2],
        thetas: [f64; 2],
        r: &Vector<2>,
        scan: Scan,
    ) -> Vec<ArcContact> {
        let body = |k: usize| ArcBody {
            arcs,
            outline,
            size: sizes[k],
            theta: thetas[k],
        };
        let reach = delta * 2.0 / n * (sizes[0] + sizes[1]);
        let mut out = Vec::new();
        contacts_by(&body(0), &body(1), r, 0.02, reach, scan, |c| out.push(c));
        out
    }

    /// The unit outline `R = 1 + Δ sin(nφ)/n`: `(R, R', R'')` at `e^{iφ}`.
    fn near_disk(n: f64, delta: f64) -> impl Fn(Unit) -> (f64, f64, f64) {
        move |e: Unit| {
            let phi: f64 = e.1.atan2(e.0);
            let (s, c) = (n * phi).sin_cos();
            (1.0 + delta * s / n, delta * c, -n * delta * s)
        }
    }

    /// The scan on the tables' unsolved support points against the scan on
    /// solved ones: the same contacts (with the same saddles) to 10⁻¹² in
    /// `h` and `ψ`, on random overlapping and nearly touching pairs of
    /// near-disks `R = 1 + Δ sin(nφ)/n` beyond the convex limit (n = 4 …
    /// 32, Δ = 0.2, 0.3), and bit for bit wherever the two scans keep the
    /// same cells: on nearly all pairs.
    #[test]
    fn the_scan_on_tables_finds_the_contacts_of_the_solved_scan() {
        let mut next = uniform(0x2545_f491_4f6c_dd1d);
        let (mut pairs, mut same, mut contacts) = (0, 0, 0);
        for &(n, delta) in &[(4.0, 0.3), (8.0, 0.2), (8.0, 0.3), (16.0, 0.3), (32.0, 0.3)] {
            let outline = near_disk(n, delta);
            let arcs = split_arcs(&outline, 4096);
            for _ in 0..300 {
                let (sizes, thetas, r) = packing_pair(&mut next, n, delta);
                let list = |solved: bool| {
                    let scan = Scan {
                        solved,
                        ..Scan::DEFAULT
                    };
                    scanned((&arcs, &outline), (n, delta), sizes, thetas, &r, scan)
                };
                let (table, solved) = (list(false), list(true));
                assert_eq!(table.len(), solved.len(), "n {n}, Δ {delta}, r {r:?}");
                for (a, b) in table.iter().zip(&solved) {
                    assert!(
                        (a.exact.gap - b.exact.gap).abs() < 1e-12
                            && (a.exact.normal.0 - b.exact.normal.0).abs() < 1e-12
                            && (a.exact.normal.1 - b.exact.normal.1).abs() < 1e-12
                            && a.saddle.is_some() == b.saddle.is_some(),
                        "{a:?} against {b:?}"
                    );
                }
                pairs += 1;
                contacts += solved.len();
                same += usize::from(table == solved);
            }
        }
        eprintln!("{same} of {pairs} pairs the same bit for bit, {contacts} contacts");
        assert!(contacts > pairs, "{contacts} contacts on {pairs} pairs");
        assert!(
            same * 100 >= pairs * 99,
            "{same} of {pairs} the same bit for bit"
        );
    }

    /// `NormalWindow::meets` against a fine sampling of `[lo, hi]`: some
    /// sample with `|D| |sin(ψ − ψ_D)| ≤ ρ` where it says the piece meets
    /// the window, none (with a margin of 10⁻⁶ of ρ, wider than the
    /// sampling's step) where it says it does not. Pieces anywhere on the
    /// line of angles, of widths up to 4 rad, windows from 10⁻³ rad wide to
    /// the whole circle.
    #[test]
    fn the_normal_window_meets_exactly_the_pieces_that_reach_it() {
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut met, mut missed) = (0, 0);
        for _ in 0..2000 {
            let angle = TAU * (next() - 0.5);
            let distance = 0.5 + next();
            let radii = distance * (10f64).powf(-3.0 * next()) * 1.2;
            let between = (distance * angle.cos(), distance * angle.sin());
            let lo = 30.0 * (next() - 0.5);
            let hi = lo + 4.0 * next() * next();
            let window = NormalWindow::new(between, radii);
            let within = |psi: f64, slack: f64| {
                let (s, c) = psi.sin_cos();
                (between.0 * s - between.1 * c).abs() <= radii * (1.0 + slack)
            };
            let samples = 40_000;
            let psi = |k: usize| lo + (hi - lo) * k as f64 / samples as f64;
            if window.meets(lo, hi) {
                met += 1;
                assert!(
                    (0..=samples).any(|k| within(psi(k), 1e-6)),
                    "meets [{lo}, {hi}] but no sample is within the window ({between:?}, {radii})"
                );
            } else {
                missed += 1;
                assert!(
                    (0..=samples).all(|k| !within(psi(k), -1e-6)),
                    "misses [{lo}, {hi}] but a sample is within the window ({between:?}, {radii})"
                );
            }
        }
        assert!(met > 200 && missed > 200, "met {met}, missed {missed}");
    }

    /// The scan against one from cells of 0.005 rad on solved support
    /// points: the same contacts with the same saddles, on random
    /// overlapping and nearly touching pairs of near-disks beyond the
    /// convex limit (n = 4 … 32, Δ = 0.1 … 0.4) and small bodies deep in a
    /// large one's valley. The gaps agree to 10⁻¹², the normals to 10⁻⁸
    /// rad: each root is refined from its own cell until a step is below
    /// 10⁻⁹ rad, which near a fold (`g''` small) leaves ψ uncertain by
    /// about that step. Random pairs seldom put stationary points closer
    /// than a cell (even four cells a piece find these); the paths of
    /// `shapes/fourier/tests/nonconvex.rs` test those.
    #[test]
    fn the_scan_finds_the_contacts_of_a_fine_scan() {
        let mut next = uniform(0x6a09_e667_f3bc_c908);
        let fine = Scan {
            cell: 0.005,
            concave_cell: 0.005,
            solved: true,
        };
        let (mut pairs, mut contacts, mut saddles) = (0, 0, 0);
        let cases = [
            (4.0, 0.3),
            (4.0, 0.4),
            (8.0, 0.2),
            (8.0, 0.4),
            (16.0, 0.1),
            (16.0, 0.3),
            (32.0, 0.1),
            (32.0, 0.3),
        ];
        for &(n, delta) in &cases {
            let outline = near_disk(n, delta);
            let arcs = split_arcs(&outline, 4096);
            for k in 0..500 {
                // Half the pairs as in a packing, half a body of size 1/8
                // of the other in one of its valleys (bottom at
                // φ = −π/2n), up to three of its own lobe heights below
                // the bottom: teeth touching both flanks.
                let (sizes, thetas, r) = if k % 2 == 0 {
                    packing_pair(&mut next, n, delta)
                } else {
                    let angle = (-PI / 2.0 + 0.3 * (2.0 * next() - 1.0)) / n;
                    let d = 4.0 * (1.0 - delta / n) + 0.5 - 1.5 * delta / n * next();
                    let r = Vector::<2>::new(d * angle.cos(), d * angle.sin());
                    ([4.0, 0.5], [0.0, TAU * next()], r)
                };
                let list =
                    |scan: Scan| scanned((&arcs, &outline), (n, delta), sizes, thetas, &r, scan);
                let (coarse, fine) = (list(Scan::DEFAULT), list(fine));
                assert_eq!(coarse.len(), fine.len(), "n {n}, Δ {delta}, r {r:?}");
                for (a, b) in coarse.iter().zip(&fine) {
                    let saddles_agree = match (a.saddle, b.saddle) {
                        (Some(x), Some(y)) => (x.gap - y.gap).abs() < 1e-12,
                        (x, y) => x.is_none() && y.is_none(),
                    };
                    assert!(
                        (a.exact.gap - b.exact.gap).abs() < 1e-12
                            && (a.exact.normal.0 - b.exact.normal.0).abs() < 1e-8
                            && (a.exact.normal.1 - b.exact.normal.1).abs() < 1e-8
                            && saddles_agree,
                        "n {n}, Δ {delta}: {a:?} against {b:?}"
                    );
                    saddles += usize::from(b.saddle.is_some());
                }
                pairs += 1;
                contacts += fine.len();
            }
        }
        eprintln!("{pairs} pairs, {contacts} contacts, {saddles} with a saddle");
        assert!(
            contacts > pairs && saddles * 20 > pairs,
            "{contacts} contacts, {saddles} saddles on {pairs} pairs"
        );
    }
}
