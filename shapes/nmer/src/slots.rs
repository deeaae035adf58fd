//! The contacts of many body pairs at a time, sphere pair by sphere pair
//! (the engine's *slots* path, `Shape::slot_contacts_lanes`).
//!
//! [`Shape::contacts`](jamkit_core::Shape::contacts) takes one body pair at
//! a time: the rotation matrices of both bodies, their world-frame sphere
//! offsets and rotation axes, then the `k × k` sphere pairs one after the
//! other, each behind a branch on its gap. Here the offsets (and, for a
//! linear 3D body, the rotation axes) are computed once per body and energy
//! evaluation ([`Nmer::write_body_terms`]); a chunk of `W` body pairs
//! gathers them, and each sphere pair `(a, b)` (*slot* `a k + b`) is one
//! loop over the chunk's lanes with no branch: `v = r_ij − d_a + d_b`,
//! `|v|`, the gap, `n = v (1/|v|)` and the torques, which the compiler
//! vectorises (four lanes per AVX2 instruction in the engine's AVX2 copy).
//!
//! NOTE: every number is computed by the same operations, in the same
//! order, as in `contacts` (the offsets by the same `world_of`/`world`, the
//! lanes' vectors by the same `nalgebra` calls), so it is the same bits;
//! a lane is `found` exactly where `contacts` visits the sphere pair (the
//! bounding test `|r_ij| − (R⁰_i + R⁰_j) b > 0`, then `h > 0`, both false).

use crate::Nmer;
use crate::orientation::{Angle, Quaternion};
use jamkit_core::{ContactLanes, MAX_ROT, MAX_SLOTS, RotVec, SlotPairs, Vector};

/// The most spheres per body on the slots path: `k² ≤ MAX_SLOTS`.
const SLOT_SPHERES: usize = 4;
const _: () = assert!(SLOT_SPHERES * SLOT_SPHERES <= MAX_SLOTS);

impl<const D: usize> Nmer<D> {
    /// Sphere pairs per body pair on the slots path: `k²` for up to
    /// [`SLOT_SPHERES`] spheres, else 0 (the generic pass).
    pub(crate) fn slots(&self) -> usize {
        let k = self.spheres();
        if k <= SLOT_SPHERES { k * k } else { 0 }
    }

    /// Numbers per body: `R⁰`, the `k` world offsets, then `extra`.
    pub(crate) fn terms_len(&self, extra: usize) -> usize {
        1 + D * self.spheres() + extra
    }

    /// [`Nmer::slot_lanes`] with room for 2 spheres (dimers) or
    /// [`SLOT_SPHERES`] (same arithmetic, so the same bits).
    #[inline(always)]
    fn by_room<const W: usize>(
        &self,
        &(terms, per_body): &(&[f64], usize),
        pairs: &SlotPairs<D, W>,
        out: &mut [ContactLanes<D, W>],
        torques: impl Fn(usize, &Vector<D>, &Vector<D>, &Vector<D>) -> (RotVec, RotVec),
    ) {
        if self.spheres() <= 2 {
            self.slot_lanes::<2, W>((terms, per_body), pairs, out, torques)
        } else {
            self.slot_lanes::<SLOT_SPHERES, W>((terms, per_body), pairs, out, torques)
        }
    }

    /// `R⁰` and the world offsets `d` into the front of `out`.
    fn write_offsets(&self, size: f64, d: &[Vector<D>], out: &mut [f64]) {
        out[0] = size;
        for (a, d) in d[..self.spheres()].iter().enumerate() {
            out[1 + D * a..1 + D * (a + 1)].copy_from_slice(d.as_slice());
        }
    }

    /// The slots of `W` pairs into `out` (`k²` entries) from `terms`
    /// (`per_body` numbers a body, [`Nmer::write_offsets`] first), the
    /// torques of each lane by `torques(l, n, d_a, d_b)` (`∂h/∂q_i`,
    /// `∂h/∂q_j`).
    ///
    #[inline(always)]
    fn slot_lanes<const M: usize, const W: usize>(
        &self,
        (terms, per_body): (&[f64], usize),
        pairs: &SlotPairs<D, W>,
        out: &mut [ContactLanes<D, W>],
        torques: impl Fn(usize, &Vector<D>, &Vector<D>, &Vector<D>) -> (RotVec, RotVec),
    ) {
        let k = self.spheres().min(M);
        let len = self.terms_len(0);
        let (mut size_i, mut size_j) = ([0.0; W], [0.0; W]);
        let mut d_i = [[[0.0; W]; D]; M];
        let mut d_j = [[[0.0; W]; D]; M];
        for l in 0..W {
            let t_i = &terms[pairs.body_i[l] * per_body..][..len];
            let t_j = &terms[pairs.body_j[l] * per_body..][..len];
            size_i[l] = t_i[0];
            size_j[l] = t_j[0];
            for a in 0..k {
                for c in 0..D {
                    d_i[a][c][l] = t_i[1 + D * a + c];
                    d_j[a][c][l] = t_j[1 + D * a + c];
                }
            }
        }
        // `Nmer::apart` with `max_gap = 0`; `r2.sqrt()` is `r_ij.norm()`.
        let mut near = [false; W];
        for l in 0..W {
            near[l] = !(pairs.r2[l].sqrt() - (size_i[l] + size_j[l]) * self.unit_reach > 0.0);
        }
        for a in 0..k {
            for b in 0..k {
                let ContactLanes {
                    found,
                    gap,
                    grad_r: n,
                    grad_rot_i,
                    grad_rot_j,
                } = &mut out[a * k + b];
                let (d_a, d_b) = (&d_i[a], &d_j[b]);
                let reach = (&size_i, self.radii[a], &size_j, self.radii[b]);
                sphere_pair(pairs, (d_a, d_b), reach, &near, (gap, found, n));
                for l in 0..W {
                    let lane = |d: &[[f64; W]; D]| Vector::<D>::from_fn(|c, _| d[c][l]);
                    let (t_i, t_j) = torques(l, &lane(n), &lane(d_a), &lane(d_b));
                    for p in 0..MAX_ROT {
                        grad_rot_i[p][l] = t_i[p];
                        grad_rot_j[p][l] = t_j[p];
                    }
                }
            }
        }
    }
}

/// Slot `(a, b)` of `W` pairs: `v = r_ij − d_a + d_b`, the gap
/// `|v| − R⁰_i ρ_a − R⁰_j ρ_b`, whether `contacts` visits it, and
/// `n = v (1/|v|)` (the first axis at `|v| = 0`).
///
/// NOTE: the loop writes local arrays, copied out after it: writing into
/// the caller's `ContactLanes` the compiler vectorised it behind run-time
/// overlap checks, which failed, and it ran scalar.
/// `n` is fixed at `|v| = 0` in a branch of its own: a select on the
/// quotient made the compiler branch around the division in every lane.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn sphere_pair<const D: usize, const W: usize>(
    pairs: &SlotPairs<D, W>,
    (d_a, d_b): (&[[f64; W]; D], &[[f64; W]; D]),
    (size_i, r_a, size_j, r_b): (&[f64; W], f64, &[f64; W], f64),
    near: &[bool; W],
    (gap, found, n): (&mut [f64; W], &mut [bool; W], &mut [[f64; W]; D]),
) {
    let lane = |d: &[[f64; W]; D], l: usize| Vector::<D>::from_fn(|c, _| d[c][l]);
    // Local arrays, copied out after the loop (see the note).
    let (mut dist, mut h, mut visit, mut unit) = ([0.0; W], [0.0; W], [false; W], [[0.0; W]; D]);
    for l in 0..W {
        let base = pairs.separation(l) - lane(d_a, l);
        let v = base + lane(d_b, l);
        dist[l] = v.norm();
        let reach_a = size_i[l] * r_a;
        h[l] = dist[l] - reach_a - size_j[l] * r_b;
        visit[l] = near[l] & !(h[l] > 0.0);
        let quotient = v * (1.0 / dist[l]);
        for c in 0..D {
            unit[c][l] = quotient[c];
        }
    }
    (*gap, *found, *n) = (h, visit, unit);
    if dist.iter().any(|&x| !(x > 0.0)) {
        for l in 0..W {
            if !(dist[l] > 0.0) {
                for c in 0..D {
                    n[c][l] = if c == 0 { 1.0 } else { 0.0 };
                }
            }
        }
    }
}

impl Nmer<2> {
    /// `R⁰` and the world offsets of one body.
    pub(crate) fn write_body_terms(&self, size: f64, o: &Angle, out: &mut [f64]) {
        // NOTE: room for the spheres the path takes (`SLOT_SPHERES`), not
        // `MAX_SPHERES`: moving 16 offsets a body cost 4 % of a run.
        if self.spheres() <= 2 {
            self.write_offsets(size, &self.world::<2>(size, o), out);
        } else {
            self.write_offsets(size, &self.world::<SLOT_SPHERES>(size, o), out);
        }
    }

    /// [`Shape::slot_contacts_lanes`](jamkit_core::Shape::slot_contacts_lanes).
    #[inline(always)]
    pub(crate) fn slot_contacts<const W: usize>(
        &self,
        terms: &[f64],
        pairs: &SlotPairs<2, W>,
        out: &mut [ContactLanes<2, W>],
    ) {
        // The torques of `Nmer::<2>::contact`.
        let torques = |_: usize, n: &Vector<2>, d_a: &Vector<2>, d_b: &Vector<2>| {
            let c = Self::contact(0.0, *n, d_a, d_b);
            (c.grad_rot_i, c.grad_rot_j)
        };
        self.by_room(&(terms, self.terms_len(0)), pairs, out, torques)
    }
}

impl Nmer<3> {
    /// Numbers per body past the offsets: the rotation axes `e₀, e₁` of a
    /// linear body (the others' are the world axes).
    fn axes_len(&self) -> usize {
        if self.linear { 6 } else { 0 }
    }

    /// Numbers per body on the slots path.
    pub(crate) fn body_terms_len(&self) -> usize {
        self.terms_len(self.axes_len())
    }

    /// `R⁰`, the world offsets and (linear bodies) the rotation axes of one
    /// body, from one rotation matrix as in `contacts`.
    pub(crate) fn write_body_terms(&self, size: f64, o: &Quaternion, out: &mut [f64]) {
        let columns = o.columns();
        // Room as in 2D (see there).
        if self.spheres() <= 2 {
            self.write_offsets(size, &self.world_of::<2>(size, &columns), out);
        } else {
            self.write_offsets(size, &self.world_of::<SLOT_SPHERES>(size, &columns), out);
        }
        if self.linear {
            let e = self.axes(&columns);
            let at = self.terms_len(0);
            out[at..at + 3].copy_from_slice(e[0].as_slice());
            out[at + 3..at + 6].copy_from_slice(e[1].as_slice());
        }
    }

    /// [`Shape::slot_contacts_lanes`](jamkit_core::Shape::slot_contacts_lanes).
    #[inline(always)]
    pub(crate) fn slot_contacts<const W: usize>(
        &self,
        terms: &[f64],
        pairs: &SlotPairs<3, W>,
        out: &mut [ContactLanes<3, W>],
    ) {
        let per_body = self.body_terms_len();
        if self.linear {
            // The axes of both bodies, lane by lane (`e[body][p][c][l]`).
            let at = self.terms_len(0);
            let mut e = [[[[0.0; W]; 3]; 2]; 2];
            for l in 0..W {
                for (side, body) in [pairs.body_i[l], pairs.body_j[l]].into_iter().enumerate() {
                    let t = &terms[body * per_body + at..][..6];
                    for p in 0..2 {
                        for c in 0..3 {
                            e[side][p][c][l] = t[3 * p + c];
                        }
                    }
                }
            }
            let axis =
                |side: usize, p: usize, l: usize| Vector::<3>::from_fn(|c, _| e[side][p][c][l]);
            // The torques of `Nmer::<3>::contact` through `project`, linear.
            let torques = |l: usize, n: &Vector<3>, d_a: &Vector<3>, d_b: &Vector<3>| {
                let (t_i, t_j) = (-d_a.cross(n), d_b.cross(n));
                let project = |side: usize, t: &Vector<3>| {
                    [axis(side, 0, l).dot(t), axis(side, 1, l).dot(t), 0.0]
                };
                (project(0, &t_i), project(1, &t_j))
            };
            self.by_room(&(terms, per_body), pairs, out, torques)
        } else {
            // `project` of a body with three rotational coordinates: the
            // torque's world components.
            let torques = |_: usize, n: &Vector<3>, d_a: &Vector<3>, d_b: &Vector<3>| {
                let (t_i, t_j) = (-d_a.cross(n), d_b.cross(n));
                ([t_i[0], t_i[1], t_i[2]], [t_j[0], t_j[1], t_j[2]])
            };
            self.by_room(&(terms, per_body), pairs, out, torques)
        }
    }
}
