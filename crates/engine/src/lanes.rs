//! The energy and gradient of families with `FastContacts::LANES`, several
//! pairs at a time.
//!
//! The generic pass (`Scene::pair_sum`) takes one pair at a time: a branch
//! on the bounding test (mispredicted for a good share of the pairs near
//! jamming), the family's contact, a push into a buffer, and a second branch
//! per contact to sum it. For a family with at most one contact per pair
//! that can compute its contacts several pairs at a time
//! (`FastContacts::contacts_lanes`, e.g. the first-order near-disks), this kernel
//! works like the balls' one (`balls`), in two phases over chunks of the
//! neighbour list:
//!
//! 1. **Pair terms** of the whole chunk with no branch: separation (minimum
//!    image), the family's contacts (one call of `FastContacts::contacts_lanes`
//!    for the chunk), `v(h)`, `f = v'(h) ∂h/∂r_j` and the torques
//!    `v'(h) ∂h/∂q_i`, `v'(h) ∂h/∂q_j`, zero for pairs without a contact.
//!    Each step is one loop over the chunk's pairs (*lanes*) on plain
//!    arrays, which the compiler vectorises: the AVX2 copy (`simd`)
//!    computes four pairs per instruction.
//! 2. **Sums**, one pair at a time in list order: `V += v`, `g_j += (f, τ_j)`,
//!    and `g_i += (−f, τ_i)` in registers, added to `g_i` when `i`'s
//!    partners end.
//!
//! NOTE: the arithmetic of each pair and the order of every sum are those of
//! the generic pass (`FastContacts::contacts_lanes` promises `Shape::contacts`'
//! bits; `v' · x = x · v'` exactly), so the results are the same bits: pairs
//! without a contact add exact zeros, and `x + 0 = x − 0 = x` for every sum
//! here (none of them is ever `−0`: they start at `+0`, and `+0 + −0 = +0`).
//!
//! NOTE: a whole chunk per call, not four pairs: asking the family for four
//! pairs per call (its dispatch on gap model and modes every four pairs,
//! half-scalar complex products) makes near-disk packings only 12 % faster
//! than the generic pass; with a whole chunk per call and one fused loop
//! per phase they are 45 % faster (docs/reports/performance.md, "Where the
//! time of a packing goes").

use jamkit_core::{
    BodyOrientation, ContactLanes, FastContacts, MAX_ROT, Packing, PairLanes, Potential, RotVec,
    Shape,
};
use jamkit_core::{PeriodicBox, Vector};

/// Pairs per chunk: the pair terms of a chunk stay in L1 between the phases.
const CHUNK: usize = 64;

/// The pair terms of one chunk, one entry per pair.
struct Terms<const D: usize> {
    energy: [f64; CHUNK],
    force: [[f64; CHUNK]; D],
    torque_i: [[f64; CHUNK]; MAX_ROT],
    torque_j: [[f64; CHUNK]; MAX_ROT],
}

/// The bodies and the list, as the kernel reads them.
pub(crate) struct Lanes<'a, const D: usize, S: Shape<D>> {
    pub packing: &'a Packing<D, S>,
    /// `[b_i, b_j]` per pair, in list order.
    pub pair_reach: &'a [[f64; 2]],
    pub owners: &'a [u32],
    pub partners: &'a [u32],
    pub potential: Potential,
}

impl<const D: usize, S: Shape<D>> Lanes<'_, D, S> {
    /// The energy, with its gradient (`D + rot_dof` coordinates per body)
    /// in `grad`.
    pub fn energy_gradient(&self, grad: &mut [f64]) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2 (checked at run time by `simd::avx2`).
            // Why: four pairs per instruction; same bits.
            return unsafe { self.energy_gradient_avx2(grad) };
        }
        self.energy_gradient_portable(grad)
    }

    /// [`Lanes::energy_gradient_portable`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn energy_gradient_avx2(&self, grad: &mut [f64]) -> f64 {
        self.energy_gradient_portable(grad)
    }

    #[inline(always)]
    fn energy_gradient_portable(&self, grad: &mut [f64]) -> f64 {
        match self.potential {
            Potential::Harmonic => self.sum(grad, |h| Potential::Harmonic.energy_and_derivative(h)),
            Potential::Hertzian => self.sum(grad, |h| Potential::Hertzian.energy_and_derivative(h)),
        }
    }

    #[inline(always)]
    fn sum(&self, grad: &mut [f64], v: impl Fn(f64) -> (f64, f64) + Copy) -> f64 {
        grad.fill(0.0);
        let pairs = self.partners.len();
        let k = self.packing.shape.rot_dof();
        let mut terms = Terms {
            energy: [0.0; CHUNK],
            force: [[0.0; CHUNK]; D],
            torque_i: [[0.0; CHUNK]; MAX_ROT],
            torque_j: [[0.0; CHUNK]; MAX_ROT],
        };
        // The chunk's pairs and contacts: every call fills them anew.
        let mut lanes = PairLanes::<D, S::Orientation, CHUNK>::filled(S::Orientation::reference());
        let mut contacts = ContactLanes::<D, CHUNK>::default();
        let mut energy = 0.0;
        // Body i's own gradient, kept until its last partner is done.
        let mut state = (usize::MAX, Vector::<D>::zeros(), [0.0; MAX_ROT]);
        for start in (0..pairs).step_by(CHUNK) {
            let len = CHUNK.min(pairs - start);
            self.pair_terms(start, k, &mut lanes, &mut contacts, &mut terms, v);
            (state, energy) = accumulate(
                &self.owners[start..start + len],
                &self.partners[start..start + len],
                &terms,
                (k, grad),
                (state, energy),
            );
        }
        let (owner, g_r, g_q) = state;
        if owner != usize::MAX {
            add(grad, owner, k, &g_r, &g_q);
        }
        energy
    }

    /// `v(h)`, `f = v'(h) ∂h/∂r_j` and the torques of the chunk of pairs
    /// from `start` on, zeros where a pair has no contact. A short last
    /// chunk repeats the last pair of the list in its spare lanes (whose
    /// terms `accumulate` never reads).
    ///
    /// NOTE: the lanes are a whole chunk: every step is a loop of `CHUNK`
    /// iterations over plain arrays, with indices clamped to the last body
    /// and pair (a no-op for a valid list) so that no bounds check sits in
    /// them, and the compiler vectorises each loop as a whole (four pairs
    /// per AVX2 instruction), the family's contacts included; one call of
    /// the family per chunk.
    #[inline(always)]
    fn pair_terms(
        &self,
        start: usize,
        k: usize,
        lanes: &mut PairLanes<D, S::Orientation, CHUNK>,
        c: &mut ContactLanes<D, CHUNK>,
        terms: &mut Terms<D>,
        v: impl Fn(f64) -> (f64, f64),
    ) {
        const W: usize = CHUNK;
        let p = self.packing;
        let n = p.positions.len();
        let (positions, sizes, orientations) =
            (&p.positions[..n], &p.sizes[..n], &p.orientations[..n]);
        let bbox: &PeriodicBox<D> = &p.bbox;
        let last = self.partners.len() - 1;
        let (owners, partners, pair_reach) = (
            &self.owners[..=last],
            &self.partners[..=last],
            &self.pair_reach[..=last],
        );
        let pair: [usize; W] = std::array::from_fn(|l| (start + l).min(last));
        let lanes = &mut *lanes;
        for l in 0..W {
            let i = (owners[pair[l]] as usize).min(n - 1);
            let j = (partners[pair[l]] as usize).min(n - 1);
            let raw = positions[j] - positions[i];
            for a in 0..D {
                lanes.r_ij[a][l] = raw[a];
            }
            lanes.o_i[l] = orientations[i];
            lanes.o_j[l] = orientations[j];
            lanes.size_i[l] = sizes[i];
            lanes.size_j[l] = sizes[j];
            [lanes.reach_i[l], lanes.reach_j[l]] = pair_reach[pair[l]];
        }
        // Minimum image, `r²` and the bounding test's `(b_i + b_j)²`, the
        // same operations in the same order as `Scene::pair_sum`'s, apart
        // from the gathers above so that this loop is vectorised.
        let mut cut2 = [0.0; W];
        for l in 0..W {
            let d = bbox.minimum_image(lanes.separation(l));
            lanes.r2[l] = d.norm_squared();
            for a in 0..D {
                lanes.r_ij[a][l] = d[a];
            }
            let cut = lanes.reach_i[l] + lanes.reach_j[l];
            cut2[l] = cut * cut;
        }
        S::Fast::contacts_lanes(&p.shape, lanes, c);
        // NOTE: as in `Scene::pair_sum`, a pair counts unless `r² ≥ cut²`
        // (so a NaN separation counts, and shows up in V).
        let (mut counts, mut dv) = ([false; W], [0.0; W]);
        for l in 0..W {
            counts[l] = !(lanes.r2[l] >= cut2[l]) && c.found[l];
            let e;
            (e, dv[l]) = v(c.gap[l]);
            terms.energy[l] = if counts[l] { e } else { 0.0 };
            for a in 0..D {
                terms.force[a][l] = if counts[l] {
                    c.grad_r[a][l] * dv[l]
                } else {
                    0.0
                };
            }
        }
        for a in 0..k.min(MAX_ROT) {
            for l in 0..W {
                terms.torque_i[a][l] = if counts[l] {
                    dv[l] * c.grad_rot_i[a][l]
                } else {
                    0.0
                };
            }
            for l in 0..W {
                terms.torque_j[a][l] = if counts[l] {
                    dv[l] * c.grad_rot_j[a][l]
                } else {
                    0.0
                };
            }
        }
    }
}

/// Phase 2 over one chunk: `V += v`, `g_j += (f, τ_j)`, `g_i += (−f, τ_i)`
/// (in registers until `i`'s partners end), in list order. `state`: the
/// body whose partners are under way and its gradient so far; then `V`.
///
/// NOTE: a function of its own, never inlined: inside the vector code, `V`
/// and `g_i` went through the stack (a store-to-load latency per pair).
#[inline(never)]
fn accumulate<const D: usize>(
    owners: &[u32],
    partners: &[u32],
    terms: &Terms<D>,
    (k, grad): (usize, &mut [f64]),
    (state, mut energy): ((usize, Vector<D>, RotVec), f64),
) -> ((usize, Vector<D>, RotVec), f64) {
    let (mut owner, mut g_r, mut g_q) = state;
    let stride = D + k;
    for (at, (&i, &j)) in owners.iter().zip(partners).enumerate() {
        let (i, j) = (i as usize, j as usize);
        energy += terms.energy[at];
        if i != owner {
            if owner != usize::MAX {
                add(grad, owner, k, &g_r, &g_q);
            }
            owner = i;
            g_r = Vector::<D>::zeros();
            g_q = [0.0; MAX_ROT];
        }
        let f = Vector::<D>::from_fn(|a, _| terms.force[a][at]);
        g_r -= f;
        let gj = &mut grad[j * stride..(j + 1) * stride];
        for a in 0..D {
            gj[a] += f[a];
        }
        for a in 0..k {
            g_q[a] += terms.torque_i[a][at];
            gj[D + a] += terms.torque_j[a][at];
        }
    }
    ((owner, g_r, g_q), energy)
}

/// `grad[body] += (g_r, g_q)`.
#[inline(always)]
pub(crate) fn add<const D: usize>(
    grad: &mut [f64],
    body: usize,
    k: usize,
    g_r: &Vector<D>,
    g_q: &RotVec,
) {
    let g = &mut grad[body * (D + k)..(body + 1) * (D + k)];
    for a in 0..D {
        g[a] += g_r[a];
    }
    for a in 0..k {
        g[D + a] += g_q[a];
    }
}
