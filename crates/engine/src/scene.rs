//! A scene: a packing, a contact potential and a neighbour list.
//!
//! The energy is `V = Σ_contacts v(h_c)`, and its gradient in the generalised
//! coordinates follows from the chain rule on each contact's gap,
//!
//! ```text
//! ∂V/∂r_j = Σ_c v'(h_c) ∂h_c/∂r_j,   ∂V/∂r_i = −Σ_c v'(h_c) ∂h_c/∂r_j,
//! ∂V/∂q_i = Σ_c v'(h_c) ∂h_c/∂q_i,
//! ```
//!
//! computed with the energy in one pass over the neighbour list.
//!
//! On the generic pass (a family with none of the engine's fast kernels)
//! every listed pair has a [`PairMemo`] beside it, handed to
//! [`Shape::contacts_warm`]: a family with an iterative gap starts each
//! pair's solve where its last one ended. The memos belong to the scene's
//! pairs and follow them through rebuilds of the list by `(i, j)`
//! ([`NeighborList::carry_over`]; a pair new to the list starts at `None`),
//! so that a run is the same bits whatever the threads or shards.

use crate::neighbors::NeighborList;
use jamkit_core::{
    BodyOrientation, Contact, ContactLanes, FastContacts, GapHessian, Kernel, Packing, Pair,
    PairLanes, PairMemo, Potential, Shape, ShapeExt, Vector,
};

/// Pairs per chunk of the generic pass ([`Scene::pair_sum`]).
const CHUNK: usize = 64;

/// A packing ready to be relaxed.
#[derive(Clone, Debug)]
pub struct Scene<const D: usize, S: Shape<D>> {
    pub(crate) packing: Packing<D, S>,
    pub(crate) potential: Potential,
    pub(crate) neighbors: NeighborList<D>,
    reach: Vec<f64>,
    pub(crate) inverse_masses: Vec<f64>,
    pub(crate) evaluations: u64,
    /// Scratch: the contacts of one chunk of the list, `(pair, contact)`.
    found: Vec<(u32, Contact<D>)>,
    /// Scratch: `FastContacts::body_terms` of every body (the slots kernel).
    body_terms: Vec<f64>,
    /// Scratch: the slots kernel's buffers.
    slot_scratch: crate::slots::Scratch<D>,
    /// One memo per listed pair, in list order, on the generic pass
    /// ([`Shape::contacts_warm`]); empty on the fast kernels.
    memos: Vec<PairMemo>,
    /// Scratch: the memos of the list before a rebuild.
    memos_before: Vec<PairMemo>,
    /// Scratch: the family's, for [`FastContacts::contacts_warm_lanes`].
    warm_scratch: Vec<[f64; CHUNK]>,
    /// Centres and orientations of the last [`Objective::save`](crate::Objective::save).
    pub(crate) saved: (Vec<Vector<D>>, Vec<S::Orientation>),
}

impl<const D: usize, S: Shape<D>> Scene<D, S> {
    /// A scene with Verlet skin `skin` (in units of length; a few tenths of
    /// the smallest body size is a good choice).
    pub fn new(packing: Packing<D, S>, potential: Potential, skin: f64) -> Self {
        let reach = packing
            .sizes
            .iter()
            .map(|&s| packing.shape.bounding_radius(s))
            .collect();
        let inverse_masses = packing.inverse_masses();
        let mut scene = Self {
            packing,
            potential,
            neighbors: NeighborList::new(skin),
            reach,
            inverse_masses,
            evaluations: 0,
            found: Vec::new(),
            body_terms: Vec::new(),
            slot_scratch: Default::default(),
            memos: Vec::new(),
            memos_before: Vec::new(),
            warm_scratch: Vec::new(),
            saved: (Vec::new(), Vec::new()),
        };
        scene.rebuild_neighbors();
        scene
    }

    /// The packing.
    pub fn packing(&self) -> &Packing<D, S> {
        &self.packing
    }

    /// Give the packing back.
    pub fn into_packing(self) -> Packing<D, S> {
        self.packing
    }

    /// The potential.
    pub fn potential(&self) -> Potential {
        self.potential
    }

    /// Number of energy/gradient evaluations so far.
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    /// Fail when some body could meet its own periodic image, or a pair
    /// could interact through two images: the minimum-image convention needs
    /// every listed range `b_i + b_j + skin` below half the shortest edge.
    pub fn check_box(&self) -> jamkit_core::Result<()> {
        let max_reach = self.reach.iter().copied().fold(0.0, f64::max);
        let range = 2.0 * max_reach + self.neighbors.skin();
        let edge = self.packing.bbox.min_edge();
        if 2.0 * range > edge {
            return Err(jamkit_core::Error::BoxTooSmall {
                edge,
                range,
                phi: self.phi(),
            });
        }
        Ok(())
    }

    /// Number of pairs in the neighbour list.
    pub fn neighbor_pairs(&self) -> usize {
        self.neighbors.pair_count()
    }

    /// Number of neighbour-list builds so far.
    pub fn neighbor_builds(&self) -> u64 {
        self.neighbors.builds()
    }

    /// Packing fraction.
    pub fn phi(&self) -> f64 {
        self.packing.phi()
    }

    /// Rescale affinely to packing fraction `phi`.
    pub fn set_phi(&mut self, phi: f64) {
        self.packing.set_phi(phi);
        // Affine rescaling moves far bodies by more than the skin allows.
        self.rebuild_neighbors();
    }

    pub(crate) fn rebuild_neighbors(&mut self) {
        self.packing.wrap_positions();
        self.neighbors
            .build(&self.packing.bbox, &self.packing.positions, &self.reach);
        if self.packing.shape.kernel() == Kernel::Pairs {
            std::mem::swap(&mut self.memos, &mut self.memos_before);
            self.neighbors
                .carry_over(&self.memos_before, &mut self.memos);
        }
    }

    fn refresh_neighbors(&mut self) {
        if self.neighbors.needs_rebuild(&self.packing.positions) {
            self.rebuild_neighbors();
        }
    }

    /// Visit every pair whose bounding balls come within `extra` of each
    /// other, with its separation `r_ij` (minimum image) and every contact
    /// the family reports for it (`i < j`). `extra` up to the skin uses the
    /// neighbour list; beyond, all pairs.
    pub fn for_each_contact<F: FnMut(usize, usize, &Vector<D>, &Contact<D>)>(
        &mut self,
        extra: f64,
        mut visit: F,
    ) {
        self.for_each_pair(extra, |p, i, j, d| {
            p.shape.contacts(
                &Pair::new(
                    p.sizes[i],
                    p.orientations[i],
                    p.sizes[j],
                    p.orientations[j],
                    *d,
                ),
                extra,
                |c| visit(i, j, d, &c),
            );
        });
    }

    /// Like [`Scene::for_each_contact`], with the second derivatives of each
    /// gap (for the Hessian). Fails when the family provides none.
    pub fn for_each_gap_hessian<F: FnMut(usize, usize, &GapHessian<D>)>(
        &mut self,
        extra: f64,
        mut visit: F,
    ) -> jamkit_core::Result<()> {
        let mut result = Ok(());
        self.for_each_pair(extra, |p, i, j, d| {
            if result.is_ok() {
                result = p.shape.gap_hessians(
                    &Pair::new(
                        p.sizes[i],
                        p.orientations[i],
                        p.sizes[j],
                        p.orientations[j],
                        *d,
                    ),
                    extra,
                    |c| visit(i, j, &c),
                );
            }
        });
        result
    }

    /// Visit every pair `i < j` whose bounding balls come within `extra` of
    /// each other, with its separation `r_ij` (minimum image). `extra` up to
    /// the skin uses the neighbour list; beyond, all pairs.
    fn for_each_pair<F: FnMut(&Packing<D, S>, usize, usize, &Vector<D>)>(
        &mut self,
        extra: f64,
        mut visit: F,
    ) {
        self.refresh_neighbors();
        let p = &self.packing;
        let n = p.len();
        let mut pair = |i: usize, j: usize| {
            let d = p.bbox.minimum_image(p.positions[j] - p.positions[i]);
            let cut = self.reach[i] + self.reach[j] + extra;
            if d.norm_squared() < cut * cut {
                visit(p, i, j, &d);
            }
        };
        if extra <= self.neighbors.skin() {
            for i in 0..n {
                for &j in self.neighbors.partners(i) {
                    pair(i, j as usize);
                }
            }
        } else {
            for i in 0..n {
                for j in i + 1..n {
                    pair(i, j);
                }
            }
        }
    }

    /// Energy `V` and its gradient `∂V/∂q` (written into `grad`, length `dof`).
    pub fn energy_gradient(&mut self, grad: &mut [f64]) -> f64 {
        self.refresh_neighbors();
        self.evaluations += 1;
        if <S::Fast as FastContacts<D, S>>::BALL {
            let p = &self.packing;
            let (owners, partners) = self.neighbors.pairs();
            return crate::balls::Balls {
                bbox: &p.bbox,
                positions: &p.positions,
                pair_reach: self.neighbors.pair_reach(),
                owners,
                partners,
                potential: self.potential,
            }
            .energy_gradient(grad);
        }
        if S::Fast::contact_slots(&self.packing.shape) > 0 {
            let p = &self.packing;
            let len = S::Fast::body_terms_len(&p.shape);
            self.body_terms.resize(p.len() * len, 0.0);
            for (b, (&size, o)) in p.sizes.iter().zip(&p.orientations).enumerate() {
                S::Fast::body_terms(
                    &p.shape,
                    size,
                    o,
                    &mut self.body_terms[b * len..(b + 1) * len],
                );
            }
            let (owners, partners) = self.neighbors.pairs();
            return crate::slots::Slots {
                packing: p,
                terms: &self.body_terms,
                pair_reach: self.neighbors.pair_reach(),
                owners,
                partners,
                potential: self.potential,
            }
            .energy_gradient(grad, &mut self.slot_scratch);
        }
        if <S::Fast as FastContacts<D, S>>::LANES && S::Fast::use_lanes(&self.packing.shape) {
            let p = &self.packing;
            let (owners, partners) = self.neighbors.pairs();
            return crate::lanes::Lanes {
                packing: p,
                pair_reach: self.neighbors.pair_reach(),
                owners,
                partners,
                potential: self.potential,
            }
            .energy_gradient(grad);
        }
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2 (checked at run time by `simd::avx2`).
            // Why: the AVX2 copy of the same code gives the same bits and,
            // with FIRE's, −10 % per disk step (docs/reports/performance.md).
            return unsafe { self.pair_sum_avx2(grad) };
        }
        let mut found = std::mem::take(&mut self.found);
        let mut memos = std::mem::take(&mut self.memos);
        let mut scratch = std::mem::take(&mut self.warm_scratch);
        let lanes = self.warm_lanes().then_some(&mut scratch);
        let e = self.pair_sum(grad, &mut found, &mut memos, lanes);
        self.found = found;
        self.memos = memos;
        self.warm_scratch = scratch;
        e
    }

    /// Whether the generic pass asks the family for its warm contacts a
    /// chunk at a time ([`FastContacts::use_warm_lanes`]).
    fn warm_lanes(&self) -> bool {
        S::Fast::use_warm_lanes(&self.packing.shape)
    }

    /// The energy and gradient by the generic pass (one pair at a time
    /// through `Shape::contacts`) even where a faster kernel exists: tests
    /// compare the kernels with it, bit for bit.
    #[doc(hidden)]
    pub fn energy_gradient_generic(&mut self, grad: &mut [f64]) -> f64 {
        self.refresh_neighbors();
        let mut found = Vec::new();
        let mut memos = std::mem::take(&mut self.memos);
        memos.resize(self.neighbors.pair_count(), None);
        let e = self.pair_sum(grad, &mut found, &mut memos, None);
        if self.packing.shape.kernel() == Kernel::Pairs {
            self.memos = memos;
        }
        e
    }

    /// [`Scene::pair_sum`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn pair_sum_avx2(&mut self, grad: &mut [f64]) -> f64 {
        let mut found = std::mem::take(&mut self.found);
        let mut memos = std::mem::take(&mut self.memos);
        let mut scratch = std::mem::take(&mut self.warm_scratch);
        let lanes = self.warm_lanes().then_some(&mut scratch);
        let e = self.pair_sum(grad, &mut found, &mut memos, lanes);
        self.found = found;
        self.memos = memos;
        self.warm_scratch = scratch;
        e
    }

    /// The energy, with its gradient written into `grad`, over a fresh
    /// neighbour list.
    ///
    /// Two phases per chunk of the list: the family's contacts of every pair
    /// whose bounding balls overlap, into a buffer; then the sums in list
    /// order, `V += v(h)`, `g_j += v' ∂h/∂q_j`, and `g_i += v' ∂h/∂q_i` in
    /// registers until `i`'s partners end (added to `g_i` then). Each pair's
    /// contacts come from [`Shape::contacts_warm`] with its memo in `memos`
    /// (one per listed pair); with `lanes` (the family's scratch), the
    /// pairs whose bounding balls overlap go to the family a chunk of them
    /// at a time, with their memos ([`FastContacts::contacts_warm_lanes`]:
    /// the same contacts bit for bit, summed in the same order).
    ///
    /// NOTE: one pass that summed inside the family's callback kept `V` and
    /// `g_i` on the stack (a store-to-load latency per pair) and made the
    /// pairs wait for each other; apart, the contacts of many pairs are
    /// computed side by side. Every sum has the same terms in the same order
    /// as in that one pass, so the results are the same bits (bodies with no
    /// contact add nothing, where the one pass added exact zeros).
    #[inline(always)]
    fn pair_sum(
        &self,
        grad: &mut [f64],
        found: &mut Vec<(u32, Contact<D>)>,
        memos: &mut [PairMemo],
        lanes: Option<&mut Vec<[f64; CHUNK]>>,
    ) -> f64 {
        grad.fill(0.0);
        let p = &self.packing;
        let (positions, sizes, orientations, reach) = (
            &p.positions[..],
            &p.sizes[..],
            &p.orientations[..],
            &self.reach[..],
        );
        let k = p.shape.rot_dof();
        let stride = D + k;
        let potential = self.potential;
        let (owners, partners) = self.neighbors.pairs();
        let memos = &mut memos[..partners.len()];
        let mut energy = 0.0;
        let mut owner = usize::MAX;
        let mut gi_r = Vector::<D>::zeros();
        let mut gi_q = [0.0; jamkit_core::MAX_ROT];
        // With `lanes`: a batch of pairs within reach and their places in
        // the list.
        let mut batch = PairLanes::<D, S::Orientation, CHUNK>::filled(S::Orientation::reference());
        let mut batch_at = [0u32; CHUNK];
        let mut batch_out = ContactLanes::<D, CHUNK>::default();
        if let Some(scratch) = lanes {
            // Batches of `CHUNK` pairs within reach (the last one shorter),
            // in list order.
            let mut next = 0;
            while next < partners.len() {
                let mut len = 0;
                while next < partners.len() && len < CHUNK {
                    let pair = next;
                    next += 1;
                    let (i, j) = (owners[pair] as usize, partners[pair] as usize);
                    let d = p.bbox.minimum_image(positions[j] - positions[i]);
                    let cut = reach[i] + reach[j];
                    let r2 = d.norm_squared();
                    if r2 >= cut * cut {
                        continue;
                    }
                    (batch.size_i[len], batch.size_j[len]) = (sizes[i], sizes[j]);
                    (batch.reach_i[len], batch.reach_j[len]) = (reach[i], reach[j]);
                    (batch.o_i[len], batch.o_j[len]) = (orientations[i], orientations[j]);
                    for a in 0..D {
                        batch.r_ij[a][len] = d[a];
                    }
                    batch.r2[len] = r2;
                    batch_at[len] = pair as u32;
                    len += 1;
                }
                S::Fast::contacts_warm_lanes(
                    &p.shape,
                    &batch,
                    len,
                    0.0,
                    memos,
                    &batch_at,
                    scratch,
                    &mut batch_out,
                );
                (energy, owner, gi_r, gi_q) = sum_contacts(
                    (0..len).filter_map(|l| batch_out.get(l).map(|c| (batch_at[l], c))),
                    (owners, partners),
                    potential,
                    (k, grad),
                    (energy, owner, gi_r, gi_q),
                );
            }
            if owner != usize::MAX {
                add_body(grad, owner, stride, &gi_r, &gi_q);
            }
            return energy;
        }
        for start in (0..partners.len()).step_by(CHUNK) {
            let end = (start + CHUNK).min(partners.len());
            found.clear();
            for pair in start..end {
                let (i, j) = (owners[pair] as usize, partners[pair] as usize);
                let d = p.bbox.minimum_image(positions[j] - positions[i]);
                // Bounding balls apart: no contact, and no square root.
                let cut = reach[i] + reach[j];
                if d.norm_squared() >= cut * cut {
                    continue;
                }
                p.shape.contacts_warm(
                    &Pair::new(sizes[i], orientations[i], sizes[j], orientations[j], d),
                    0.0,
                    &mut memos[pair],
                    |c| found.push((pair as u32, c)),
                );
            }
            (energy, owner, gi_r, gi_q) = sum_contacts(
                found.iter().copied(),
                (owners, partners),
                potential,
                (k, grad),
                (energy, owner, gi_r, gi_q),
            );
        }
        if owner != usize::MAX {
            add_body(grad, owner, stride, &gi_r, &gi_q);
        }
        energy
    }

    /// Energy `V` alone.
    pub fn energy(&mut self) -> f64 {
        let mut e = 0.0;
        let potential = self.potential;
        self.for_each_contact(0.0, |_, _, _, c| e += potential.energy(c.gap));
        e
    }

    /// Pressure from the virial of the contact forces,
    /// `P = −(1 / (D V_box)) Σ_c v'(h_c) (r_ij · ∂h_c/∂r_j)`.
    pub fn pressure(&mut self) -> f64 {
        let potential = self.potential;
        let mut virial = 0.0;
        self.for_each_contact(0.0, |_, _, d, c| {
            virial += potential.derivative(c.gap) * d.dot(&c.grad_r);
        });
        -virial / (D as f64 * self.packing.bbox.volume())
    }
}

/// What [`sum_contacts`] carries from one chunk to the next: `V`, the body
/// whose partners are under way, and its gradient so far.
type PairSums<const D: usize> = (f64, usize, Vector<D>, jamkit_core::RotVec);

/// The second phase of [`Scene::pair_sum`] over one chunk's contacts.
///
/// NOTE: never inlined: inside the first phase's code, `V` and `g_i` went
/// through the stack again.
#[inline(never)]
fn sum_contacts<const D: usize>(
    found: impl Iterator<Item = (u32, Contact<D>)>,
    (owners, partners): (&[u32], &[u32]),
    potential: Potential,
    (k, grad): (usize, &mut [f64]),
    (mut energy, mut owner, mut gi_r, mut gi_q): PairSums<D>,
) -> PairSums<D> {
    let stride = D + k;
    for (pair, c) in found {
        let (i, j) = (
            owners[pair as usize] as usize,
            partners[pair as usize] as usize,
        );
        if i != owner {
            if owner != usize::MAX {
                add_body(grad, owner, stride, &gi_r, &gi_q);
            }
            owner = i;
            gi_r = Vector::<D>::zeros();
            gi_q = [0.0; jamkit_core::MAX_ROT];
        }
        // NOTE: no test on the sign of the gap here: a pair out of
        // contact adds exact zeros (v' = 0), which is cheaper than a
        // mispredicted branch, and the sums are the same.
        let (v, dv) = potential.energy_and_derivative(c.gap);
        energy += v;
        let f = c.grad_r * dv;
        gi_r -= f;
        let gj = &mut grad[j * stride..(j + 1) * stride];
        for a in 0..D {
            gj[a] += f[a];
        }
        for a in 0..k {
            gi_q[a] += dv * c.grad_rot_i[a];
            gj[D + a] += dv * c.grad_rot_j[a];
        }
    }
    (energy, owner, gi_r, gi_q)
}

/// `grad[body] += (g_r, g_q)`, the body's own share of the pair sums.
#[inline(always)]
fn add_body<const D: usize>(
    grad: &mut [f64],
    body: usize,
    stride: usize,
    g_r: &Vector<D>,
    g_q: &jamkit_core::RotVec,
) {
    let g = &mut grad[body * stride..(body + 1) * stride];
    for a in 0..D {
        g[a] += g_r[a];
    }
    for a in D..stride {
        g[a] += g_q[a - D];
    }
}
