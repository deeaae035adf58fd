//! The energy and gradient of balls (`FastContacts::BALL`), several pairs at a time.
//!
//! For balls every listed pair costs a square root and a division, and
//! one pair at a time these two set the pace of the whole step (their
//! throughput, and a mispredicted branch on the bounding test for one pair
//! in four near jamming). This kernel works in two phases over chunks of the
//! neighbour list:
//!
//! 1. **Pair forces**, `LANES` pairs at a time with no branch: separation
//!    (minimum image), `|r|`, gap `h = |r| − R_i − R_j`, `v(h)` and
//!    `f = v'(h) r/|r|`, zero for pairs whose balls are apart. Written as
//!    loops over lanes, the AVX2 copy (`simd`) does four square roots and
//!    four divisions per instruction.
//! 2. **Sums**, one pair at a time in list order: `V += v`, `g_j += f`,
//!    and `g_i −= f` in a register, added to `g_i` when `i`'s partners end.
//!
//! NOTE: the arithmetic of each pair and the order of every sum are those of
//! the generic pass (`Scene::pair_sum` with the `sphere` family's
//! `contacts`), so the results are the same bits: pairs whose balls are
//! apart add exact zeros, and `x + 0 = x − 0 = x` for every sum here (none
//! of them is ever `−0`: they start at `+0`, and `+0 + −0 = +0`).

use jamkit_core::{PeriodicBox, Potential, Vector};

/// Pairs per vector operation (four `f64` in an AVX2 register).
const LANES: usize = 4;
/// Pairs per chunk: the pair forces of a chunk stay in L1 between the phases.
const CHUNK: usize = 64;

/// The bodies and the list, as the kernel reads them.
pub(crate) struct Balls<'a, const D: usize> {
    pub bbox: &'a PeriodicBox<D>,
    pub positions: &'a [Vector<D>],
    /// `[b_i, b_j]` per pair, in list order: for balls the reach is the
    /// radius, so these are also `R_i` and `R_j`.
    pub pair_reach: &'a [[f64; 2]],
    pub owners: &'a [u32],
    pub partners: &'a [u32],
    pub potential: Potential,
}

impl<const D: usize> Balls<'_, D> {
    /// The energy, with its gradient (`D` coordinates per body) in `grad`.
    pub fn energy_gradient(&self, grad: &mut [f64]) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2 (checked at run time by `simd::avx2`).
            // Why: four square roots and divisions per instruction; same bits.
            return unsafe { self.energy_gradient_avx2(grad) };
        }
        self.energy_gradient_portable(grad)
    }

    /// [`Balls::energy_gradient_portable`] compiled with AVX2.
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
        let mut force = [[0.0; CHUNK]; D];
        let mut energy_of = [0.0; CHUNK];
        let mut energy = 0.0;
        // Body i's own gradient, kept until its last partner is done.
        let mut owner = usize::MAX;
        let mut g_owner = Vector::<D>::zeros();
        for start in (0..pairs).step_by(CHUNK) {
            let len = CHUNK.min(pairs - start);
            let full = len - len % LANES;
            for k in (0..full).step_by(LANES) {
                self.pair_forces::<LANES>(start, k, &mut force, &mut energy_of, v);
            }
            for k in full..len {
                self.pair_forces::<1>(start, k, &mut force, &mut energy_of, v);
            }
            (owner, g_owner, energy) = accumulate(
                &self.owners[start..start + len],
                &self.partners[start..start + len],
                &force,
                &energy_of[..len],
                grad,
                (owner, g_owner, energy),
            );
        }
        if owner != usize::MAX {
            add(grad, owner, &g_owner);
        }
        energy
    }

    /// `v(h)` and `f = v'(h) ∂h/∂r_j` of the `W` pairs from `first` on,
    /// zeros where the balls are apart.
    ///
    /// NOTE: written as straight loops over lanes on plain arrays, with no
    /// bounds check between them (indices are clamped to the last body, a
    /// no-op for a valid list), so that the vectoriser turns each loop into
    /// a few vector instructions.
    #[inline(always)]
    fn pair_forces<const W: usize>(
        &self,
        start: usize,
        k: usize,
        force: &mut [[f64; CHUNK]; D],
        energy: &mut [f64; CHUNK],
        v: impl Fn(f64) -> (f64, f64),
    ) {
        let first = start + k;
        let n = self.positions.len();
        let positions = &self.positions[..n];
        let (owners, partners, pair_reach) = (
            &self.owners[first..first + W],
            &self.partners[first..first + W],
            &self.pair_reach[first..first + W],
        );
        let mut d = [[0.0; W]; D];
        let (mut r2, mut cut2, mut size_i, mut size_j) = ([0.0; W], [0.0; W], [0.0; W], [0.0; W]);
        for l in 0..W {
            let i = (owners[l] as usize).min(n - 1);
            let j = (partners[l] as usize).min(n - 1);
            let dl = self.bbox.minimum_image(positions[j] - positions[i]);
            // The same sum, in the same order, as `Scene::pair_sum`'s.
            r2[l] = dl.norm_squared();
            for a in 0..D {
                d[a][l] = dl[a];
            }
            let [b_i, b_j] = pair_reach[l];
            let cut = b_i + b_j;
            cut2[l] = cut * cut;
            size_i[l] = b_i;
            size_j[l] = b_j;
        }
        let mut r = [0.0; W];
        for l in 0..W {
            r[l] = r2[l].sqrt();
        }
        let mut inv = [0.0; W];
        for l in 0..W {
            inv[l] = 1.0 / r[l];
        }
        let (mut e, mut dv) = ([0.0; W], [0.0; W]);
        for l in 0..W {
            (e[l], dv[l]) = v(r[l] - size_i[l] - size_j[l]);
        }
        // NOTE: as in `Scene::pair_sum`, a pair counts unless `r² ≥ cut²`
        // (so a NaN separation counts, and shows up in V).
        let mut apart = [false; W];
        for l in 0..W {
            apart[l] = r2[l] >= cut2[l];
        }
        let energy = &mut energy[k..k + W];
        for l in 0..W {
            energy[l] = if apart[l] { 0.0 } else { e[l] };
        }
        let mut unit = [[0.0; W]; D];
        for a in 0..D {
            for l in 0..W {
                unit[a][l] = d[a][l] * inv[l];
            }
        }
        // `sphere`'s unit vector at r = 0 (or NaN): the first axis. Rare, so
        // a branch of its own: a select on the quotient would make the
        // compiler branch around the division in every lane.
        if r.iter().any(|&x| !(x > 0.0)) {
            for l in 0..W {
                if !(r[l] > 0.0) {
                    for a in 0..D {
                        unit[a][l] = if a == 0 { 1.0 } else { 0.0 };
                    }
                }
            }
        }
        for a in 0..D {
            let force = &mut force[a][k..k + W];
            for l in 0..W {
                force[l] = if apart[l] { 0.0 } else { unit[a][l] * dv[l] };
            }
        }
    }
}

/// Phase 2 over one chunk: `V += v`, `g_j += f`, `g_i −= f` (in a register
/// until `i`'s partners end), in list order. `state`: the body whose
/// partners are under way, its gradient so far, and `V` so far.
///
/// NOTE: a function of its own, never inlined: inside the vector code, `V`
/// and `g_i` went through the stack (a store-to-load latency per pair).
#[inline(never)]
fn accumulate<const D: usize>(
    owners: &[u32],
    partners: &[u32],
    force: &[[f64; CHUNK]; D],
    energy_of: &[f64],
    grad: &mut [f64],
    state: (usize, Vector<D>, f64),
) -> (usize, Vector<D>, f64) {
    let (mut owner, mut g_owner, mut energy) = state;
    for (k, ((&i, &j), &e)) in owners.iter().zip(partners).zip(energy_of).enumerate() {
        let (i, j) = (i as usize, j as usize);
        energy += e;
        if i != owner {
            if owner != usize::MAX {
                add(grad, owner, &g_owner);
            }
            owner = i;
            g_owner = Vector::<D>::zeros();
        }
        let f = Vector::<D>::from_fn(|a, _| force[a][k]);
        g_owner -= f;
        add(grad, j, &f);
    }
    (owner, g_owner, energy)
}

/// `grad[body] += g`.
#[inline(always)]
fn add<const D: usize>(grad: &mut [f64], body: usize, g: &Vector<D>) {
    let slot = &mut grad[body * D..(body + 1) * D];
    for a in 0..D {
        slot[a] += g[a];
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::Scene;
    use jamkit_core::{Packing, Potential, SizeDistribution};
    use jamkit_sphere::Sphere;
    use rand::SeedableRng;

    fn check<const D: usize>(n: usize, phi: f64, potential: Potential) {
        for seed in 1..=3 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let sizes = SizeDistribution::default().sample(n, &mut rng);
            let packing = Packing::<D, Sphere>::random(Sphere, sizes, phi, &mut rng).unwrap();
            let mut scene = Scene::new(packing, potential, 0.2);
            let (mut fast, mut generic) = (vec![0.0; n * D], vec![0.0; n * D]);
            let e_fast = scene.energy_gradient(&mut fast);
            let e_generic = scene.energy_gradient_generic(&mut generic);
            assert!(e_fast > 0.0);
            assert_eq!(e_fast.to_bits(), e_generic.to_bits(), "{D}D {potential:?}");
            let bits = |g: &[f64]| g.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&generic), "{D}D {potential:?}");
        }
    }

    /// The balls' kernel gives the generic pass's energy and gradient bit
    /// for bit (list lengths not multiples of the lane or chunk width).
    #[test]
    fn balls_kernel_matches_the_generic_pass_bit_for_bit() {
        for potential in [Potential::Harmonic, Potential::Hertzian] {
            check::<2>(301, 0.85, potential);
            check::<2>(70, 0.3, potential);
            check::<3>(203, 0.6, potential);
        }
    }
}
