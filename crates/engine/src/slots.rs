//! The energy and gradient of families with contact slots
//! (`FastContacts::contact_slots`, bodies made of spheres: up to `k²` contacts per
//! pair, sphere `a` of one body against sphere `b` of the other), several
//! pairs at a time.
//!
//! The generic pass (`Scene::pair_sum`) takes one pair at a time: a branch
//! on the bounding test, the family's contacts (for `nmer`: both rotation
//! matrices, both bodies' rotated sphere offsets, then `k²` sphere pairs
//! one by one, each behind a branch on its gap), a push of each contact
//! into a buffer, and a branch per contact to sum it. This kernel works
//! like the near-disks' one (`lanes`), in phases over chunks of the
//! neighbour list, after the family's terms of every body (the rotated
//! offsets) are computed once per evaluation (`FastContacts::body_terms`):
//!
//! 0. **Bounding pre-pass** over each chunk of the list with no branch and
//!    no square root: separation (minimum image), `r²`, and the pairs whose
//!    bounding balls overlap (`r² < (b_i + b_j)²`, the generic pass's own
//!    test) appended in list order to a queue; the slots below take the
//!    queue a full chunk at a time. In a jammed 3D dimer packing a quarter
//!    of the listed pairs fail that test (docs/reports/performance.md,
//!    "Where the time of a packing goes").
//! 1. **Slots** of a chunk of queued pairs with no branch: the family's
//!    contacts slot by slot (one call of
//!    `FastContacts::slot_contacts_lanes` for the chunk, one loop over the chunk's
//!    pairs per slot; the AVX2 copy (`simd`) computes four lanes per
//!    instruction); then the contacts that count, compacted with no branch
//!    in the generic pass's order (pair by pair, each pair's slots in
//!    order), with `v(h)`, `f = v'(h) ∂h/∂r_j` and the torques.
//! 2. **Sums**, one contact at a time in that order: `V += v`,
//!    `g_j += (f, τ_j)`, and `g_i += (−f, τ_i)` in registers, added to `g_i`
//!    when `i`'s partners end.
//!
//! NOTE: the arithmetic of each contact and the order of every sum are
//! those of the generic pass (`FastContacts::slot_contacts_lanes` promises
//! `Shape::contacts`' bits, which visits the slots in order; `v' · x =
//! x · v'` exactly), so the results are the same bits: slots without a
//! contact add nothing, as in the generic pass, and neither do the pairs
//! the pre-pass leaves out (the generic pass skips them by the same test;
//! the queue keeps list order).

use crate::lanes::add;
use jamkit_core::{ContactLanes, MAX_ROT, MAX_SLOTS, Packing, PeriodicBox, Potential, RotVec};
use jamkit_core::{FastContacts, Shape, SlotPairs, Vector};

/// Pairs per chunk: with `k²` slots of contacts a pair, a chunk's terms
/// stay in L1 between the phases (3D dimers: 4 × 5 kB).
const CHUNK: usize = 32;

/// The bodies and the list, as the kernel reads them.
pub(crate) struct Slots<'a, const D: usize, S: Shape<D>> {
    pub packing: &'a Packing<D, S>,
    /// `FastContacts::body_terms` of every body, `FastContacts::body_terms_len` a body.
    pub terms: &'a [f64],
    /// `[b_i, b_j]` per pair, in list order.
    pub pair_reach: &'a [[f64; 2]],
    pub owners: &'a [u32],
    pub partners: &'a [u32],
    pub potential: Potential,
}

/// The kernel's buffers, kept by the scene from one evaluation to the next
/// (made anew, zeroing them took 5 % of a 3D dimer run).
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch<const D: usize> {
    /// Each slot's contacts in a chunk (`FastContacts::contact_slots` of them).
    contacts: Vec<ContactLanes<D, CHUNK>>,
    /// The chunk's contacts that count, as (pair in the chunk, slot).
    found: Vec<(u16, u16)>,
    /// Their terms.
    terms: Vec<Term<D>>,
}

impl<const D: usize, S: Shape<D>> Slots<'_, D, S> {
    /// The energy, with its gradient (`D + rot_dof` coordinates per body)
    /// in `grad`.
    pub fn energy_gradient(&self, grad: &mut [f64], scratch: &mut Scratch<D>) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2 (checked at run time by `simd::avx2`).
            // Why: four lanes per instruction; same bits.
            return unsafe { self.energy_gradient_avx2(grad, scratch) };
        }
        self.energy_gradient_portable(grad, scratch)
    }

    /// [`Slots::energy_gradient_portable`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn energy_gradient_avx2(&self, grad: &mut [f64], scratch: &mut Scratch<D>) -> f64 {
        self.energy_gradient_portable(grad, scratch)
    }

    #[inline(always)]
    fn energy_gradient_portable(&self, grad: &mut [f64], scratch: &mut Scratch<D>) -> f64 {
        match self.potential {
            Potential::Harmonic => self.sum(grad, scratch, |h| {
                Potential::Harmonic.energy_and_derivative(h)
            }),
            Potential::Hertzian => self.sum(grad, scratch, |h| {
                Potential::Hertzian.energy_and_derivative(h)
            }),
        }
    }

    #[inline(always)]
    fn sum(
        &self,
        grad: &mut [f64],
        scratch: &mut Scratch<D>,
        v: impl Fn(f64) -> (f64, f64) + Copy,
    ) -> f64 {
        grad.fill(0.0);
        let pairs = self.partners.len();
        if pairs == 0 {
            return 0.0;
        }
        let k = self.packing.shape.rot_dof();
        let slots = S::Fast::contact_slots(&self.packing.shape).min(MAX_SLOTS);
        let Scratch {
            contacts,
            found,
            terms,
        } = scratch;
        contacts.resize(slots, ContactLanes::default());
        found.resize(CHUNK * slots, (0, 0));
        terms.resize(CHUNK * slots, Term::default());
        let mut lanes = SlotPairs::<D, CHUNK> {
            body_i: [0; CHUNK],
            body_j: [0; CHUNK],
            r_ij: [[0.0; CHUNK]; D],
            r2: [0.0; CHUNK],
        };
        let mut picked = Picked::<D>::default();
        let mut energy = 0.0;
        // Body i's own gradient, kept until its last partner is done.
        let mut state = (usize::MAX, Vector::<D>::zeros(), [0.0; MAX_ROT]);
        let (owners, partners) = (&self.owners[..pairs], &self.partners[..pairs]);
        // NOTE: written out twice rather than as a closure: a closure is
        // not compiled with the AVX2 of `energy_gradient_avx2`.
        for start in (0..pairs).step_by(CHUNK) {
            self.pick(start, &mut picked);
            if picked.len >= CHUNK {
                let m = self.slot_terms(&picked, CHUNK, k, &mut lanes, contacts, (found, terms), v);
                (state, energy) =
                    accumulate(owners, partners, &terms[..m], (k, grad), (state, energy));
                picked.drop_front();
            }
        }
        if picked.len > 0 {
            let len = picked.len;
            let m = self.slot_terms(&picked, len, k, &mut lanes, contacts, (found, terms), v);
            (state, energy) = accumulate(owners, partners, &terms[..m], (k, grad), (state, energy));
        }
        let (owner, g_r, g_q) = state;
        if owner != usize::MAX {
            add(grad, owner, k, &g_r, &g_q);
        }
        energy
    }

    /// The bounding pre-pass over the chunk of list pairs from `start` on:
    /// the separation (minimum image) and `r²` of every pair, with no
    /// branch and no square root, and the pairs whose bounding balls
    /// overlap (`r² < (b_i + b_j)²`, the generic pass's test) appended to
    /// `picked` in list order, with no branch.
    ///
    /// NOTE: as in `Scene::pair_sum`, a pair is taken unless `r² ≥ cut²`
    /// (so a NaN separation is taken, and shows up in V).
    #[inline(always)]
    fn pick(&self, start: usize, picked: &mut Picked<D>) {
        const W: usize = CHUNK;
        let p = self.packing;
        let n = p.positions.len();
        let positions = &p.positions[..n];
        let bbox: &PeriodicBox<D> = &p.bbox;
        let last = self.partners.len() - 1;
        let (owners, partners, pair_reach) = (
            &self.owners[..=last],
            &self.partners[..=last],
            &self.pair_reach[..=last],
        );
        let mut r_ij = [[0.0; W]; D];
        let mut r2 = [0.0; W];
        let mut cut2 = [0.0; W];
        for l in 0..W {
            let pair = (start + l).min(last);
            let i = (owners[pair] as usize).min(n - 1);
            let j = (partners[pair] as usize).min(n - 1);
            let raw = positions[j] - positions[i];
            for a in 0..D {
                r_ij[a][l] = raw[a];
            }
            let [b_i, b_j] = pair_reach[pair];
            let cut = b_i + b_j;
            cut2[l] = cut * cut;
        }
        // Minimum image and `r²`, the same operations in the same order as
        // `Scene::pair_sum`'s, apart from the gathers above so that this
        // loop is vectorised.
        for l in 0..W {
            let d = bbox.minimum_image(Vector::<D>::from_fn(|a, _| r_ij[a][l]));
            r2[l] = d.norm_squared();
            for a in 0..D {
                r_ij[a][l] = d[a];
            }
        }
        let len = W.min(self.partners.len() - start);
        for l in 0..len {
            let at = picked.len;
            picked.pair[at] = (start + l) as u32;
            for a in 0..D {
                picked.r_ij[a][at] = r_ij[a][l];
            }
            picked.r2[at] = r2[l];
            picked.len += usize::from(!(r2[l] >= cut2[l]));
        }
    }

    /// The terms of the contacts of the first `len` picked pairs, pair by
    /// pair and each pair's slots in order, into `terms`; returns how many.
    /// A short chunk repeats the last picked pair in its spare lanes (never
    /// counted: only `len` pairs are compacted).
    ///
    /// NOTE: the family's slots are computed in every lane (vectorised);
    /// `v(h)` and the sums take only the contacts that count (about one a
    /// pair in a jammed 3D dimer packing against `k² = 4` slots): summing
    /// every slot with zeros left the kernel 1.5× slower than the generic
    /// pass.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn slot_terms(
        &self,
        picked: &Picked<D>,
        len: usize,
        k: usize,
        lanes: &mut SlotPairs<D, CHUNK>,
        contacts: &mut [ContactLanes<D, CHUNK>],
        (found, terms): (&mut [(u16, u16)], &mut [Term<D>]),
        v: impl Fn(f64) -> (f64, f64),
    ) -> usize {
        let n = self.packing.positions.len();
        let last = self.partners.len() - 1;
        let (owners, partners) = (&self.owners[..=last], &self.partners[..=last]);
        for l in 0..CHUNK {
            let at = l.min(len - 1);
            let pair = (picked.pair[at] as usize).min(last);
            lanes.body_i[l] = (owners[pair] as usize).min(n - 1);
            lanes.body_j[l] = (partners[pair] as usize).min(n - 1);
            for a in 0..D {
                lanes.r_ij[a][l] = picked.r_ij[a][at];
            }
            lanes.r2[l] = picked.r2[at];
        }
        S::Fast::slot_contacts_lanes(&self.packing.shape, self.terms, lanes, contacts);
        // The contacts that count, pair by pair and each pair's slots in
        // order (the generic pass's order), with no branch.
        let mut m = 0;
        for at in 0..len {
            for (s, c) in contacts.iter().enumerate() {
                found[m] = (at as u16, s as u16);
                m += usize::from(c.found[at]);
            }
        }
        for (t, &(at, s)) in terms.iter_mut().zip(&found[..m]) {
            let (at, c) = (at as usize, &contacts[s as usize]);
            let (e, dv) = v(c.gap[at]);
            t.energy = e;
            t.pair = picked.pair[at];
            for a in 0..D {
                t.force[a] = c.grad_r[a][at] * dv;
            }
            for a in 0..k.min(MAX_ROT) {
                t.torque_i[a] = dv * c.grad_rot_i[a][at];
                t.torque_j[a] = dv * c.grad_rot_j[a][at];
            }
        }
        m
    }
}

/// The list pairs the pre-pass took and the slots have not yet: their
/// places in the list, separations and `r²`, in list order. Room for two
/// chunks: fewer than one is left after each chunk of slots, and one chunk
/// of the list adds at most one.
#[derive(Clone, Copy, Debug)]
struct Picked<const D: usize> {
    len: usize,
    pair: [u32; 2 * CHUNK],
    r_ij: [[f64; 2 * CHUNK]; D],
    r2: [f64; 2 * CHUNK],
}

impl<const D: usize> Default for Picked<D> {
    fn default() -> Self {
        Self {
            len: 0,
            pair: [0; 2 * CHUNK],
            r_ij: [[0.0; 2 * CHUNK]; D],
            r2: [0.0; 2 * CHUNK],
        }
    }
}

impl<const D: usize> Picked<D> {
    /// Forget the first chunk (its slots are done).
    #[inline(always)]
    fn drop_front(&mut self) {
        self.pair.copy_within(CHUNK.., 0);
        for r in &mut self.r_ij {
            r.copy_within(CHUNK.., 0);
        }
        self.r2.copy_within(CHUNK.., 0);
        self.len -= CHUNK;
    }
}

/// One contact's terms: `v(h)`, `f = v'(h) ∂h/∂r_j`, the torques, and its
/// pair's place in the list.
#[derive(Clone, Copy, Debug)]
struct Term<const D: usize> {
    pair: u32,
    energy: f64,
    force: [f64; D],
    torque_i: RotVec,
    torque_j: RotVec,
}

impl<const D: usize> Default for Term<D> {
    fn default() -> Self {
        Self {
            pair: 0,
            energy: 0.0,
            force: [0.0; D],
            torque_i: [0.0; MAX_ROT],
            torque_j: [0.0; MAX_ROT],
        }
    }
}

/// Phase 2 over one chunk: for each contact in order, `V += v`,
/// `g_j += (f, τ_j)`, `g_i += (−f, τ_i)` (in registers until `i`'s partners
/// end). `state`: the body whose partners are under way and its gradient
/// so far; then `V`.
///
/// NOTE: a function of its own, never inlined (as `lanes::accumulate`).
#[inline(never)]
fn accumulate<const D: usize>(
    owners: &[u32],
    partners: &[u32],
    terms: &[Term<D>],
    (k, grad): (usize, &mut [f64]),
    (state, mut energy): ((usize, Vector<D>, RotVec), f64),
) -> ((usize, Vector<D>, RotVec), f64) {
    let (mut owner, mut g_r, mut g_q) = state;
    let stride = D + k;
    for t in terms {
        let (i, j) = (
            owners[t.pair as usize] as usize,
            partners[t.pair as usize] as usize,
        );
        if i != owner {
            if owner != usize::MAX {
                add(grad, owner, k, &g_r, &g_q);
            }
            owner = i;
            g_r = Vector::<D>::zeros();
            g_q = [0.0; MAX_ROT];
        }
        energy += t.energy;
        let f = Vector::<D>::from_fn(|a, _| t.force[a]);
        g_r -= f;
        let gj = &mut grad[j * stride..(j + 1) * stride];
        for a in 0..D {
            gj[a] += f[a];
        }
        for a in 0..k {
            g_q[a] += t.torque_i[a];
            gj[D + a] += t.torque_j[a];
        }
    }
    ((owner, g_r, g_q), energy)
}
