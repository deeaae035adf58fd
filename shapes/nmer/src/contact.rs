//! Sphere–sphere contacts between two rigid bodies, and the `Shape` impls.
//!
//! Every sphere `a` of body `i` and sphere `b` of body `j` is a contact with
//! the gap `h = |v| − R⁰_i ρ_a − R⁰_j ρ_b`, `v = r_ij + d_b − d_a`
//! (`d` the world-frame offsets, `n = v/|v|`). A small rotation `ω` of body
//! `i` moves `d_a` to `exp(ω) d_a = d_a + ω × d_a + ½ ω × (ω × d_a) + …`,
//! so along a rotation axis `e_p`:
//!
//! ```text
//! ∂v/∂q_{i,p} = t_{i,p} = −e_p × d_a,          ∂v/∂q_{j,p} = t_{j,p} = e_p × d_b,
//! ∂h/∂q = n · t,    ∂h/∂r_j = n,
//! ```
//!
//! and, with `P = (1 − n nᵀ)/|v|` the curvature of `|v|`, the second
//! derivatives of `h(exp(Σ_p q_p e_p) ∘ o)` at `q = 0` (symmetric in `p, q`):
//!
//! ```text
//! ∂²h/∂r_j∂r_j = P,     ∂²h/∂r_j∂q_{i,p} = P t_{i,p},     ∂²h/∂r_j∂q_{j,p} = P t_{j,p},
//! ∂²h/∂q_{i,p}∂q_{j,q} = t_{i,p}ᵀ P t_{j,q},
//! ∂²h/∂q_{i,p}∂q_{i,q} = t_{i,p}ᵀ P t_{i,q} − ½ n·[e_p × (e_q × d_a) + e_q × (e_p × d_a)],
//! ∂²h/∂q_{j,p}∂q_{j,q} = t_{j,p}ᵀ P t_{j,q} + ½ n·[e_p × (e_q × d_b) + e_q × (e_p × d_b)],
//! e_p × (e_q × d) = e_q (e_p·d) − d (e_p·e_q).
//! ```
//!
//! In 2D `e = ẑ`, `t_i = −ẑ × d_a`, and the curvature terms are `+n·d_a`
//! and `−n·d_b`. The axes `e_p` are the world axes for a 3D body with three
//! rotational coordinates and `R(o) x̂, R(o) ŷ` for a linear one (see
//! [`crate::orientation`]).
//!
//! A pair is skipped when `|r_ij|` exceeds the two bounding radii plus
//! `max_gap`; otherwise every sphere pair with `h ≤ max_gap` is visited
//! (its exact gap costs no more than a bound on it).

use crate::orientation::{Angle, Quaternion};
use crate::{MAX_SPHERES, Nmer};
use jamkit_core::{
    Contact, ContactLanes, FastContacts, GapHessian, MAX_ROT, Matrix, Pair, Policy, RotVec, Shape,
    SlotPairs, Vector,
};

/// FIRE's largest time step for bodies made of spheres in 3D. Two bodies
/// touch at up to four points, nearly parallel, so jammed dimers vibrate
/// faster than spheres: `ω_max² ≈ 12` in 3D (α = 1.1–1.5) against 6.2 for
/// spheres, and the default 0.5 sits at 0.87 of the stability limit
/// `2/ω_max`, where FIRE stalled for 10⁵–10⁶ steps in single
/// minimisations (2 of 3 packings of 256 dimers at α = 1.5; 1.5·10⁶ steps
/// for one of 128 at α = 1.1). 0.35 puts it at 0.6 of the limit, where
/// the default keeps spheres. 2D keeps the default: there dimers have
/// `ω_max² ≈ 10`, 0.5 is 0.80 of the limit, and 30 of 30 packings jammed
/// with fewer steps than with 0.35 (docs/reports/sanity.md;
/// docs/explanation/minimizers.md, "FIRE").
pub const FIRE_DT_MAX: f64 = 0.35;

/// World-frame offsets `d_a = R⁰ R(o) s_a` of one body's spheres, room for
/// `M` of them (the first `min(k, M)` filled).
///
/// NOTE: `M` is 2 for dimers, 4 up to four spheres, else `MAX_SPHERES`
/// (`by_spheres!`): with room for 16 always, zeroing and moving the
/// two 16-vector arrays of every pair took a third of a 3D dimer step.
type Offsets<const D: usize, const M: usize> = [Vector<D>; M];

/// Run `$body` with the const `$m` the room [`Offsets`] needs for `$shape`'s
/// spheres: 2, 4 or `MAX_SPHERES` (same arithmetic, so the same bits).
macro_rules! by_spheres {
    ($shape:expr, $m:ident => $body:block) => {
        match $shape.spheres() {
            0..=2 => {
                const $m: usize = 2;
                $body
            }
            3..=4 => {
                const $m: usize = 4;
                $body
            }
            _ => {
                const $m: usize = MAX_SPHERES;
                $body
            }
        }
    };
}

impl<const D: usize> Nmer<D> {
    /// True when the bounding spheres put the pair farther apart than
    /// `max_gap` (then no sphere pair is visited).
    #[inline(always)]
    fn apart(&self, size_i: f64, size_j: f64, r_ij: &Vector<D>, max_gap: f64) -> bool {
        r_ij.norm() - (size_i + size_j) * self.unit_reach > max_gap
    }

    /// Visit every sphere pair `(a, b)` with `h ≤ max_gap`, giving `a`, `b`,
    /// the gap, `n` and `|v|`, from the world offsets `d_i`, `d_j` (the
    /// first [`Nmer::spheres`] of them).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn sphere_pairs(
        &self,
        size_i: f64,
        d_i: &[Vector<D>],
        size_j: f64,
        d_j: &[Vector<D>],
        r_ij: &Vector<D>,
        max_gap: f64,
        mut f: impl FnMut(usize, usize, f64, Vector<D>, f64),
    ) {
        let k = self.spheres();
        let (d_i, d_j, radii) = (&d_i[..k], &d_j[..k], &self.radii);
        for (a, (da, ra)) in d_i.iter().zip(radii).enumerate() {
            let base = r_ij - da;
            let reach_a = size_i * ra;
            for (b, (db, rb)) in d_j.iter().zip(radii).enumerate() {
                let v = base + db;
                let dist = v.norm();
                let gap = dist - reach_a - size_j * rb;
                if gap > max_gap {
                    continue;
                }
                // NOTE: coincident sphere centres have no direction; a
                // fixed unit vector keeps the run deterministic (such a
                // pair overlaps deeply and any direction pushes it apart).
                let n = if dist > 0.0 {
                    v * (1.0 / dist)
                } else {
                    Vector::<D>::from_fn(|c, _| if c == 0 { 1.0 } else { 0.0 })
                };
                f(a, b, gap, n, dist);
            }
        }
    }

    /// The spheres (centre, radius) at the world offsets `d`
    /// ([`Shape::sphere_decomposition`]).
    fn spheres_at(&self, size: f64, d: &[Vector<D>]) -> Option<Vec<(Vector<D>, f64)>> {
        Some(
            (0..self.spheres())
                .map(|a| (d[a], self.radii[a] * size))
                .collect(),
        )
    }
}

/// `a_x b_y − a_y b_x`.
#[inline(always)]
fn cross2(a: &Vector<2>, b: &Vector<2>) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// `(1 − n nᵀ)/|v|`, zero at coincident centres (infinite curvature; such a
/// pair has no defined Hessian).
fn curvature<const D: usize>(n: &Vector<D>, dist: f64) -> Matrix<D> {
    if dist > 0.0 {
        (Matrix::<D>::identity() - n * n.transpose()) / dist
    } else {
        Matrix::<D>::zeros()
    }
}

/// Assemble a [`GapHessian`] from the contact, the tangents `t = ∂v/∂q`
/// and the curvature terms `n · ∂²v/∂q∂q` of both bodies.
fn assemble<const D: usize>(
    contact: Contact<D>,
    curv: &Matrix<D>,
    t_i: &[Vector<D>],
    t_j: &[Vector<D>],
    second_i: &[RotVec; MAX_ROT],
    second_j: &[RotVec; MAX_ROT],
) -> GapHessian<D> {
    let mut h = GapHessian::translational(contact.gap, contact.grad_r, *curv);
    h.contact = contact;
    for p in 0..t_i.len() {
        h.r_qi[p] = curv * t_i[p];
        h.r_qj[p] = curv * t_j[p];
    }
    for p in 0..t_i.len() {
        for q in 0..t_i.len() {
            h.qi_qj[p][q] = t_i[p].dot(&h.r_qj[q]);
        }
        // NOTE: the diagonal blocks are filled from one triangle so that
        // they are symmetric bit for bit, not only to round-off.
        for q in p..t_i.len() {
            h.qi_qi[p][q] = t_i[p].dot(&h.r_qi[q]) + second_i[p][q];
            h.qj_qj[p][q] = t_j[p].dot(&h.r_qj[q]) + second_j[p][q];
            h.qi_qi[q][p] = h.qi_qi[p][q];
            h.qj_qj[q][p] = h.qj_qj[p][q];
        }
    }
    h
}

impl Nmer<2> {
    pub(crate) fn world<const M: usize>(&self, size: f64, o: &Angle) -> Offsets<2, M> {
        let mut d = [Vector::<2>::zeros(); M];
        for (out, s) in d.iter_mut().zip(&self.offsets) {
            *out = o.apply(s) * size;
        }
        d
    }

    /// The contact of sphere `a` of body `i` (offset `d_a`) with sphere `b`
    /// of body `j` (offset `d_b`): gap, `n` and `∂h/∂q = n · t`.
    #[inline(always)]
    pub(crate) fn contact(gap: f64, n: Vector<2>, d_a: &Vector<2>, d_b: &Vector<2>) -> Contact<2> {
        Contact {
            gap,
            grad_r: n,
            grad_rot_i: [-cross2(d_a, &n), 0.0, 0.0],
            grad_rot_j: [cross2(d_b, &n), 0.0, 0.0],
        }
    }
}

impl Shape<2> for Nmer<2> {
    type Orientation = Angle;
    type Fast = Self;

    fn family(&self) -> &'static str {
        crate::INFO.name
    }

    fn rot_dof(&self) -> usize {
        1
    }

    fn volume(&self, size: f64) -> f64 {
        self.unit_volume * size * size
    }

    fn bounding_radius(&self, size: f64) -> f64 {
        self.unit_reach * size
    }

    fn rot_inertia(&self, size: f64) -> RotVec {
        [self.moment_of_inertia(size); 3]
    }

    fn rotate(&self, o: &mut Angle, dq: &[f64]) {
        *o = o.turned_exact(dq[0]);
    }

    /// Rattlers below `f + 1 = 4` contacts (`f = 3`: two translations, one
    /// angle); bodies made of spheres interlock from an overlapping start,
    /// so the start is free of overlaps. FIRE's masses stay the bodies' own:
    /// in 2D the jammed-only blocks were not faster over the dimers
    /// measured. Their ensembles are the plain masses' (N = 128, α = 1.1
    /// and 1.5, 30 seeds), and at N = 512 they took 0.73× the CPU time at
    /// α = 1.1 but 1.05× the FIRE steps at α = 1.5 (seeds 1–6;
    /// docs/reports/minimizers.md, "Block masses only from jammed states").
    /// An experiment at small α may ask for them
    /// (`masses: Blocks((jammed_only: true))`).
    fn policy(&self) -> Policy {
        Policy {
            rattler_threshold: 4,
            overlap_free_start: true,
            ..Policy::new(2)
        }
    }

    fn sphere_decomposition(&self, size: f64, o: &Angle) -> Option<Vec<(Vector<2>, f64)>> {
        self.spheres_at(size, &self.world::<MAX_SPHERES>(size, o))
    }

    #[inline(always)]
    fn contacts<F: FnMut(Contact<2>)>(&self, pair: &Pair<2, Angle>, max_gap: f64, mut visit: F) {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        if self.apart(size_i, size_j, r_ij, max_gap) {
            return;
        }
        by_spheres!(self, M => {
            let (d_i, d_j) = (self.world::<M>(size_i, o_i), self.world::<M>(size_j, o_j));
            self.sphere_pairs(size_i, &d_i, size_j, &d_j, r_ij, max_gap, |a, b, gap, n, _| {
                visit(Self::contact(gap, n, &d_i[a], &d_j[b]))
            });
        })
    }

    fn gap_hessians<F: FnMut(GapHessian<2>)>(
        &self,
        pair: &Pair<2, Angle>,
        max_gap: f64,
        mut visit: F,
    ) -> jamkit_core::Result<()> {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        if self.apart(size_i, size_j, r_ij, max_gap) {
            return Ok(());
        }
        let (d_i, d_j) = (
            self.world::<MAX_SPHERES>(size_i, o_i),
            self.world::<MAX_SPHERES>(size_j, o_j),
        );
        let perp = |d: &Vector<2>| Vector::<2>::new(-d[1], d[0]);
        self.sphere_pairs(
            size_i,
            &d_i,
            size_j,
            &d_j,
            r_ij,
            max_gap,
            |a, b, gap, n, dist| {
                let contact = Self::contact(gap, n, &d_i[a], &d_j[b]);
                let mut second_i = [[0.0; MAX_ROT]; MAX_ROT];
                let mut second_j = [[0.0; MAX_ROT]; MAX_ROT];
                second_i[0][0] = n.dot(&d_i[a]);
                second_j[0][0] = -n.dot(&d_j[b]);
                visit(assemble(
                    contact,
                    &curvature(&n, dist),
                    &[-perp(&d_i[a])],
                    &[perp(&d_j[b])],
                    &second_i,
                    &second_j,
                ))
            },
        );
        Ok(())
    }
}

/// The engine's slots path: one slot per sphere pair.
impl FastContacts<2, Nmer<2>> for Nmer<2> {
    /// `k²` sphere pairs for up to four spheres a body (the engine's slots
    /// path, `crate::slots`), else 0.
    fn contact_slots(shape: &Self) -> usize {
        shape.slots()
    }

    fn body_terms_len(shape: &Self) -> usize {
        shape.terms_len(0)
    }

    fn body_terms(shape: &Self, size: f64, o: &Angle, out: &mut [f64]) {
        shape.write_body_terms(size, o, out)
    }

    #[inline(always)]
    fn slot_contacts_lanes<const W: usize>(
        shape: &Self,
        terms: &[f64],
        pairs: &SlotPairs<2, W>,
        out: &mut [ContactLanes<2, W>],
    ) {
        shape.slot_contacts(terms, pairs, out)
    }
}

impl Nmer<3> {
    fn world<const M: usize>(&self, size: f64, o: &Quaternion) -> Offsets<3, M> {
        self.world_of::<M>(size, &o.columns())
    }

    /// [`Nmer::world`] from the columns of `R(o)`.
    #[inline(always)]
    pub(crate) fn world_of<const M: usize>(
        &self,
        size: f64,
        columns: &[Vector<3>; 3],
    ) -> Offsets<3, M> {
        let [c0, c1, c2] = columns;
        let mut d = [Vector::<3>::zeros(); M];
        for (out, s) in d.iter_mut().zip(&self.offsets) {
            *out = (c0 * s[0] + c1 * s[1] + c2 * s[2]) * size;
        }
        d
    }

    /// The rotation axes `e_p` of the body's rotational coordinates, from
    /// the columns of `R(o)`: the world axes, or `R(o) x̂, R(o) ŷ` for a
    /// linear body.
    #[inline(always)]
    pub(crate) fn axes(&self, columns: &[Vector<3>; 3]) -> [Vector<3>; 3] {
        Quaternion::step_axes(columns, self.linear)
    }

    /// `∂h/∂q` from `∂h/∂ω`: the world components of `ω`, or its
    /// projections on `e₁, e₂` for a linear body.
    #[inline(always)]
    fn project(&self, axes: &[Vector<3>; 3], torque: Vector<3>) -> RotVec {
        if self.linear {
            [axes[0].dot(&torque), axes[1].dot(&torque), 0.0]
        } else {
            [torque[0], torque[1], torque[2]]
        }
    }

    /// The contact of sphere `a` of body `i` (offset `d_a`, rotation axes
    /// `e_i`) with sphere `b` of body `j` (`d_b`, `e_j`): gap, `n` and
    /// `∂h/∂q = n · t`.
    #[inline(always)]
    fn contact(
        &self,
        e_i: &[Vector<3>; 3],
        e_j: &[Vector<3>; 3],
        gap: f64,
        n: Vector<3>,
        d_a: &Vector<3>,
        d_b: &Vector<3>,
    ) -> Contact<3> {
        Contact {
            gap,
            grad_r: n,
            grad_rot_i: self.project(e_i, -d_a.cross(&n)),
            grad_rot_j: self.project(e_j, d_b.cross(&n)),
        }
    }
}

impl Shape<3> for Nmer<3> {
    type Orientation = Quaternion;
    type Fast = Self;

    fn family(&self) -> &'static str {
        crate::INFO.name
    }

    /// 2 for a linear body, 3 otherwise.
    fn rot_dof(&self) -> usize {
        if self.linear { 2 } else { 3 }
    }

    fn volume(&self, size: f64) -> f64 {
        self.unit_volume * size.powi(3)
    }

    fn bounding_radius(&self, size: f64) -> f64 {
        self.unit_reach * size
    }

    fn rot_inertia(&self, size: f64) -> RotVec {
        [self.moment_of_inertia(size); 3]
    }

    /// `o → exp(ω) ∘ o` with `ω = (dq₀, dq₁, dq₂)` in the world frame, or
    /// `o → o ∘ exp((dq₀, dq₁, 0))` (body frame) for a linear body; then
    /// renormalised.
    fn rotate(&self, o: &mut Quaternion, dq: &[f64]) {
        *o = o.stepped(dq, self.linear);
    }

    /// Rattlers below `f + 1` contacts with `f = 3 + rot_dof` (6 for a
    /// linear body, 7 otherwise); a start free of overlaps (bodies made of
    /// spheres interlock from an overlapping one); FIRE's step at most
    /// [`FIRE_DT_MAX`].
    ///
    /// FIRE's masses: with each body's stiffness block as its mass in the
    /// minimisations that start from a decompressed jammed state, 3D dimers
    /// (N = 128, α = 1.1 and 1.5, 30 seeds) jam into the same ensembles as
    /// with their own masses (φ_J, z_J, z_corr, rattlers within 1.03
    /// standard errors, KS p ≥ 0.95) in 1.07–1.23× fewer FIRE steps, none
    /// left hypostatic (4 of 30 at α = 1.1 with their own masses), and at
    /// N = 512, α = 1.1 in 0.72× the CPU time (docs/reports/minimizers.md,
    /// "Block masses only from jammed states").
    ///
    /// L-BFGS from the start in the block metric for dimers (bodies of two
    /// spheres): with it (and FIRE's jammed-only block masses where L-BFGS
    /// gives up), 3D dimers jam into the ensembles of FIRE with those
    /// masses (N = 512, 20 seeds each at α = 1.1 and 1.5: φ_J and z_J within
    /// 1.6 standard errors, KS p ≥ 0.14, the same spread of φ_J) in 2.2–3.1×
    /// less CPU time. Not for bodies of three or more spheres: bent trimers
    /// (N = 128, 40 seeds) kept the means but jammed with a wider spread of
    /// φ_J (s.d. 0.0050 against 0.0034, F-test p = 0.02);
    /// docs/reports/minimizers.md, "L-BFGS … the 3D dimer default".
    fn policy(&self) -> Policy {
        Policy {
            fire_dt_max: Some(FIRE_DT_MAX),
            jammed_block_masses: true,
            lbfgs_blocks: self.offsets.len() == 2,
            overlap_free_start: true,
            rattler_threshold: 3 + Shape::<3>::rot_dof(self) + 1,
            ..Policy::new(3)
        }
    }

    fn sphere_decomposition(&self, size: f64, o: &Quaternion) -> Option<Vec<(Vector<3>, f64)>> {
        self.spheres_at(size, &self.world::<MAX_SPHERES>(size, o))
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
        if self.apart(size_i, size_j, r_ij, max_gap) {
            return;
        }
        let (c_i, c_j) = (o_i.columns(), o_j.columns());
        let (e_i, e_j) = (self.axes(&c_i), self.axes(&c_j));
        by_spheres!(self, M => {
            let (d_i, d_j) = (self.world_of::<M>(size_i, &c_i), self.world_of::<M>(size_j, &c_j));
            self.sphere_pairs(size_i, &d_i, size_j, &d_j, r_ij, max_gap, |a, b, gap, n, _| {
                visit(self.contact(&e_i, &e_j, gap, n, &d_i[a], &d_j[b]))
            });
        })
    }

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
        if self.apart(size_i, size_j, r_ij, max_gap) {
            return Ok(());
        }
        let m = Shape::<3>::rot_dof(self);
        let (d_i, d_j) = (
            self.world::<MAX_SPHERES>(size_i, o_i),
            self.world::<MAX_SPHERES>(size_j, o_j),
        );
        let (e_i, e_j) = (self.axes(&o_i.columns()), self.axes(&o_j.columns()));
        // n · ½[e_p × (e_q × d) + e_q × (e_p × d)]
        //   = ½[(n·e_q)(e_p·d) + (n·e_p)(e_q·d)] − (n·d)(e_p·e_q).
        let curvature_terms = |e: &[Vector<3>; 3], d: &Vector<3>, n: &Vector<3>, sign: f64| {
            let mut out = [[0.0; MAX_ROT]; MAX_ROT];
            for p in 0..m {
                for q in 0..m {
                    let sym = 0.5 * (n.dot(&e[q]) * e[p].dot(d) + n.dot(&e[p]) * e[q].dot(d))
                        - n.dot(d) * e[p].dot(&e[q]);
                    out[p][q] = sign * sym;
                }
            }
            out
        };
        self.sphere_pairs(
            size_i,
            &d_i,
            size_j,
            &d_j,
            r_ij,
            max_gap,
            |a, b, gap, n, dist| {
                let contact = self.contact(&e_i, &e_j, gap, n, &d_i[a], &d_j[b]);
                let t_i: Vec<Vector<3>> = (0..m).map(|p| -e_i[p].cross(&d_i[a])).collect();
                let t_j: Vec<Vector<3>> = (0..m).map(|p| e_j[p].cross(&d_j[b])).collect();
                visit(assemble(
                    contact,
                    &curvature(&n, dist),
                    &t_i,
                    &t_j,
                    &curvature_terms(&e_i, &d_i[a], &n, -1.0),
                    &curvature_terms(&e_j, &d_j[b], &n, 1.0),
                ))
            },
        );
        Ok(())
    }
}

/// The engine's slots path: one slot per sphere pair.
impl FastContacts<3, Nmer<3>> for Nmer<3> {
    /// `k²` sphere pairs for up to four spheres a body (the engine's slots
    /// path, `crate::slots`), else 0.
    fn contact_slots(shape: &Self) -> usize {
        shape.slots()
    }

    fn body_terms_len(shape: &Self) -> usize {
        Nmer::<3>::body_terms_len(shape)
    }

    fn body_terms(shape: &Self, size: f64, o: &Quaternion, out: &mut [f64]) {
        shape.write_body_terms(size, o, out)
    }

    #[inline(always)]
    fn slot_contacts_lanes<const W: usize>(
        shape: &Self,
        terms: &[f64],
        pairs: &SlotPairs<3, W>,
        out: &mut [ContactLanes<3, W>],
    ) {
        shape.slot_contacts(terms, pairs, out)
    }
}
