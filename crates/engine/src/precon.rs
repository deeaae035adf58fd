//! Block-preconditioned FIRE: each body's own block of the stiffness
//! matrix as its mass.
//!
//! FIRE integrates `M q̈ = −∂V/∂q`; its stable time step is set by the
//! stiffest vibration, `Δt < 2/ω_max` with `ω²` the eigenvalues of
//! `M⁻¹ H`, and it relaxes the softest mode on the time scale `1/ω_min`.
//! With the paper's masses (`m = 1`, `I = Δ` for near-disks) a near-disk's
//! rotation is held only by contacts whose gap changes as `Δ` times a
//! translation, so its stiffness is `O(Δ²)` and its frequency
//! `ω² ≈ Δ²/Δ = Δ` sits far below the translations': FIRE crawls along
//! these rotations, and non-spherical bodies jam far more slowly than
//! disks. A preconditioner replaces the masses by a matrix that looks
//! like the Hessian (Packwood et al., J. Chem. Phys. 144, 164109 (2016)),
//! so that `M⁻¹H` is close to the identity and every mode moves on one
//! time scale.
//!
//! Here `M` is block-diagonal, one `f × f` block per body (`f = D + rot_dof`,
//! its translations and rotations), built from the stiffness part of that
//! body's own block of the Hessian,
//!
//! ```text
//! K_bb = Σ_{c ∋ b} v''(h_c) ∇_b h_c ∇_b h_cᵀ,
//! M_b  = K_bb / s + c · diag_a( max(s_a / s, κ m_a) ),
//! ```
//!
//! where `∇_b h_c` holds the derivatives of the gap of contact `c` in body
//! `b`'s coordinates, `s_a` is the mean of `(K_bb)_aa` over the bodies
//! where it is not zero (the typical stiffness of a body's coordinate `a`),
//! `s` the mean of the translations' `s_a` (so that a body with typical
//! contacts keeps a translational mass near one and the family's `Δt_max`
//! keeps its meaning), `m_a` the coordinate's own mass, `c` =
//! [`PreconParams::floor`] and `κ` = [`PreconParams::least_mass`]. The floor
//! `c s_a / s` regularises: a body without contacts (a rattler, or below
//! jamming) moves with it, and a contact that forms between two refreshes
//! meets a body no lighter than a share `c` of a typical one, so its
//! frequency stays near `1/√c`. Only the stiffness part is used: it is
//! positive semi-definite, so `M_b` is positive definite, and it needs only
//! the first derivatives of the gaps every family provides.
//!
//! NOTE: the stress part `T = Σ v'(h) ∇²h` of the Hessian is left out of
//! `M`, and where a coordinate's stiffness is tiny it can dominate: a
//! near-disk's rotation has `K_θθ ∼ Δ²` but `T_θθ ∼ |h| Δ`, so at
//! `Δ = 10⁻⁶` with overlaps of `10⁻⁴` the rotation's `ω² = T/M` was
//! thousands and FIRE stalled (`tests/stress.rs`' tiny-Δ cases, forced to
//! block masses). The floor `κ m_a` (a share of the paper's own mass, whose
//! `T/m` plain FIRE integrates stably) bounds that: with `κ = 0.03`
//! they jam again, and 3D dimers lose little of the gain (634 k against
//! 555 k FIRE steps without the bound, 6 seeds of N = 128).
//!
//! FIRE's rules are unchanged in the metric of `M`: the Euler step is
//! `v ← v − Δt M⁻¹ g`, the mixing `v ← (1 − α) v + α (|v|_M / |g|_{M⁻¹}) M⁻¹(−g)`
//! with `|v|_M² = vᵀ M v` and `|g|_{M⁻¹}² = gᵀ M⁻¹ g`, and the power
//! `P = −g·v`. The blocks are rebuilt every [`PreconParams::refresh`] steps
//! and at the start of every minimisation. The stopping rules do not look
//! at `M`, so a minimisation ends in the same window of energy or force.

use crate::objective::Objective;
use jamkit_core::{Error, Result};
use serde::{Deserialize, Serialize};

/// Settings of the block preconditioner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PreconParams {
    /// FIRE steps between two rebuilds of the blocks (and one at the start
    /// of every minimisation).
    pub refresh: u64,
    /// `c`: the share of each coordinate's typical stiffness added to the
    /// diagonal of every block.
    pub floor: f64,
    /// `κ`: that typical stiffness is taken no smaller than `κ` times the
    /// coordinate's own mass (see the module's note on the stress part).
    pub least_mass: f64,
    /// Use the blocks only in the minimisations of the jamming search that
    /// start from a decompressed jammed state (after a relaxed state above
    /// the window), and the bodies' own masses everywhere else: the
    /// compression that picks the basin runs with the paper's masses, the
    /// relaxations inside a jammed basin with the blocks. Not written out
    /// when off.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub jammed_only: bool,
}

impl Default for PreconParams {
    fn default() -> Self {
        Self {
            refresh: 100,
            floor: 0.25,
            least_mass: 0.03,
            jammed_only: false,
        }
    }
}

impl PreconParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if self.refresh == 0 {
            return Err(Error::invalid(
                format!("{prefix}.refresh"),
                0,
                "must be at least 1 (FIRE steps between rebuilds of the mass blocks)",
            ));
        }
        if !(self.least_mass > 0.0 && self.least_mass.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.least_mass"),
                self.least_mass,
                "must be positive and finite (share of the body's own mass a coordinate's floor keeps)",
            ));
        }
        if !(self.floor > 0.0 && self.floor.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.floor"),
                self.floor,
                "must be positive and finite (share of the body's own masses in its block)",
            ));
        }
        Ok(())
    }
}

/// The mass blocks `M_b` and their inverses, kept across minimisations.
#[derive(Clone, Debug, Default)]
pub(crate) struct BlockMasses {
    /// Coordinates per body, `f`.
    stride: usize,
    /// `M_b`, row-major, body after body (`N f²` numbers).
    mass: Vec<f64>,
    /// `M_b⁻¹`, the same layout.
    inverse: Vec<f64>,
    /// `s_a`, the mean diagonal stiffness of each coordinate of a body.
    class_scale: Vec<f64>,
}

impl BlockMasses {
    /// Rebuild the blocks from the stiffness of `obj`'s current state and
    /// its own inverse masses `inv_m`. Returns `false` (and builds nothing)
    /// when `obj` cannot give its stiffness blocks.
    pub(crate) fn rebuild<O: Objective>(
        &mut self,
        obj: &mut O,
        inv_m: &[f64],
        params: &PreconParams,
    ) -> bool {
        let n = inv_m.len();
        let bodies = obj.bodies().max(1);
        let f = n / bodies;
        self.stride = f;
        if !obj.stiffness_blocks(&mut self.mass) {
            return false;
        }
        debug_assert_eq!(self.mass.len(), bodies * f * f);
        let translations = obj.translations_per_body().min(f);
        // s_a: mean diagonal stiffness of coordinate a of a body, over the
        // bodies where it is non-zero; s: the translations' mean.
        self.class_scale.clear();
        self.class_scale.resize(f, 0.0);
        let mut counts = vec![0usize; f];
        for b in 0..bodies {
            for a in 0..f {
                let d = self.mass[b * f * f + a * f + a];
                if d > 0.0 {
                    self.class_scale[a] += d;
                    counts[a] += 1;
                }
            }
        }
        for (s_a, &c) in self.class_scale.iter_mut().zip(&counts) {
            if c > 0 {
                *s_a /= c as f64;
            }
        }
        let touching: usize = counts[..translations].iter().sum();
        let scale = if touching > 0 {
            (0..translations)
                .map(|a| self.class_scale[a] * counts[a] as f64)
                .sum::<f64>()
                / touching as f64
        } else {
            0.0
        };
        let stiffness = if scale > 0.0 { 1.0 / scale } else { 0.0 };
        self.inverse.resize(self.mass.len(), 0.0);
        for b in 0..bodies {
            let block = &mut self.mass[b * f * f..(b + 1) * f * f];
            for x in block.iter_mut() {
                *x *= stiffness;
            }
            for a in 0..f {
                let m = 1.0 / inv_m[b * f + a];
                // Without any contact, the plain masses.
                block[a * f + a] += if scale > 0.0 {
                    params.floor * (self.class_scale[a] / scale).max(params.least_mass * m)
                } else {
                    m
                };
            }
            let inverse = &mut self.inverse[b * f * f..(b + 1) * f * f];
            if !invert_spd(block, f, inverse) {
                // Cannot happen for K ⪰ 0 plus a positive floor, short of
                // overflow; fall back to the body's plain masses.
                block.fill(0.0);
                inverse.fill(0.0);
                for a in 0..f {
                    block[a * f + a] = 1.0 / inv_m[b * f + a];
                    inverse[a * f + a] = inv_m[b * f + a];
                }
            }
        }
        true
    }

    /// `out = M⁻¹ x` (the preconditioner of L-BFGS, [`crate::lbfgs`]),
    /// with the block size as a constant where it is one of the families'.
    #[inline(always)]
    pub(crate) fn apply_inverse(&self, x: &[f64], out: &mut [f64]) {
        match self.stride {
            2 => self.apply_inverse_of::<2>(x, out),
            3 => self.apply_inverse_of::<3>(x, out),
            6 => self.apply_inverse_of::<6>(x, out),
            f => {
                for ((xb, ob), inv) in x
                    .chunks_exact(f)
                    .zip(out.chunks_exact_mut(f))
                    .zip(self.inverse.chunks_exact(f * f))
                {
                    for a in 0..f {
                        ob[a] = (0..f).map(|c| inv[a * f + c] * xb[c]).sum();
                    }
                }
            }
        }
    }

    #[inline(always)]
    fn apply_inverse_of<const F: usize>(&self, x: &[f64], out: &mut [f64]) {
        for ((xb, ob), inv) in x
            .chunks_exact(F)
            .zip(out.chunks_exact_mut(F))
            .zip(self.inverse.chunks_exact(F * F))
        {
            for a in 0..F {
                let mut sum = 0.0;
                for c in 0..F {
                    sum += inv[a * F + c] * xb[c];
                }
                ob[a] = sum;
            }
        }
    }

    /// `w = M⁻¹ g`, and `[Σ g², Σ g v, vᵀ M v, gᵀ M⁻¹ g]` in one pass over
    /// the bodies (fixed order: deterministic).
    pub(crate) fn sums(&self, g: &[f64], v: &[f64], w: &mut [f64]) -> [f64; 4] {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2 (checked at run time); same code, same bits.
            return unsafe { self.sums_avx2(g, v, w) };
        }
        self.sums_sized(g, v, w)
    }

    /// [`BlockMasses::sums_sized`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    unsafe fn sums_avx2(&self, g: &[f64], v: &[f64], w: &mut [f64]) -> [f64; 4] {
        self.sums_sized(g, v, w)
    }

    /// The block size as a constant, so that each body's two small
    /// matrix–vector products unroll: disks 2, near-disks and spheres 3,
    /// 3D rigid bodies 6.
    #[inline(always)]
    fn sums_sized(&self, g: &[f64], v: &[f64], w: &mut [f64]) -> [f64; 4] {
        match self.stride {
            2 => self.sums_of::<2>(g, v, w),
            3 => self.sums_of::<3>(g, v, w),
            4 => self.sums_of::<4>(g, v, w),
            5 => self.sums_of::<5>(g, v, w),
            6 => self.sums_of::<6>(g, v, w),
            // Blocks of one coordinate (one-dimensional spheres) or more
            // than six (no family has more): the general loop.
            _ => self.sums_general(g, v, w),
        }
    }

    /// Any block size.
    fn sums_general(&self, g: &[f64], v: &[f64], w: &mut [f64]) -> [f64; 4] {
        let f = self.stride;
        let (mut gg, mut gv, mut vv, mut gw) = (0.0, 0.0, 0.0, 0.0);
        for b in 0..g.len() / f.max(1) {
            let m = &self.mass[b * f * f..(b + 1) * f * f];
            let inv = &self.inverse[b * f * f..(b + 1) * f * f];
            for a in 0..f {
                let (mut mv, mut ig) = (0.0, 0.0);
                for c in 0..f {
                    mv += m[a * f + c] * v[b * f + c];
                    ig += inv[a * f + c] * g[b * f + c];
                }
                w[b * f + a] = ig;
                gg += g[b * f + a] * g[b * f + a];
                gv += g[b * f + a] * v[b * f + a];
                vv += v[b * f + a] * mv;
                gw += g[b * f + a] * ig;
            }
        }
        [gg, gv, vv, gw]
    }

    /// NOTE: four independent partial sums per quantity (body `b` adds into
    /// lane `b mod 4`), as in FIRE's own `step_sums`: one accumulator would
    /// serialise every body on the adder's latency. The order is fixed, so
    /// the result is deterministic.
    #[inline(always)]
    fn sums_of<const F: usize>(&self, g: &[f64], v: &[f64], w: &mut [f64]) -> [f64; 4] {
        const LANES: usize = 4;
        let mut acc = [[0.0; LANES]; 4];
        for (b, ((gb, vb), wb)) in g
            .chunks_exact(F)
            .zip(v.chunks_exact(F))
            .zip(w.chunks_exact_mut(F))
            .enumerate()
        {
            let m = &self.mass[b * F * F..(b + 1) * F * F];
            let inv = &self.inverse[b * F * F..(b + 1) * F * F];
            let (mut gg, mut gv, mut vv, mut gw) = (0.0, 0.0, 0.0, 0.0);
            for a in 0..F {
                let (mut mv, mut ig) = (0.0, 0.0);
                for c in 0..F {
                    mv += m[a * F + c] * vb[c];
                    ig += inv[a * F + c] * gb[c];
                }
                wb[a] = ig;
                gg += gb[a] * gb[a];
                gv += gb[a] * vb[a];
                vv += vb[a] * mv;
                gw += gb[a] * ig;
            }
            let l = b % LANES;
            acc[0][l] += gg;
            acc[1][l] += gv;
            acc[2][l] += vv;
            acc[3][l] += gw;
        }
        acc.map(|l| (l[0] + l[1]) + (l[2] + l[3]))
    }
}

/// Invert a small symmetric positive definite matrix (row-major `f × f`)
/// by Cholesky; `false` when it is not positive definite.
fn invert_spd(a: &[f64], f: usize, out: &mut [f64]) -> bool {
    // L with A = L Lᵀ, in the lower triangle of `l`.
    let mut l = [0.0; 36];
    debug_assert!(f <= 6);
    for i in 0..f {
        for j in 0..=i {
            let mut s = a[i * f + j];
            for k in 0..j {
                s -= l[i * 6 + k] * l[j * 6 + k];
            }
            if i == j {
                if !(s > 0.0) {
                    return false;
                }
                l[i * 6 + i] = s.sqrt();
            } else {
                l[i * 6 + j] = s / l[j * 6 + j];
            }
        }
    }
    // Columns of A⁻¹: solve L y = e_c, then Lᵀ x = y.
    for c in 0..f {
        let mut y = [0.0; 6];
        for i in 0..f {
            let mut s = if i == c { 1.0 } else { 0.0 };
            for k in 0..i {
                s -= l[i * 6 + k] * y[k];
            }
            y[i] = s / l[i * 6 + i];
        }
        for i in (0..f).rev() {
            let mut s = y[i];
            for k in i + 1..f {
                s -= l[k * 6 + i] * out[k * f + c];
            }
            out[i * f + c] = s / l[i * 6 + i];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_of_a_small_spd_matrix() {
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        let mut inv = [0.0; 9];
        assert!(invert_spd(&a, 3, &mut inv));
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[i * 3 + k] * inv[k * 3 + j]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((p - want).abs() < 1e-14, "({i},{j}): {p}");
            }
        }
        // Not positive definite.
        assert!(!invert_spd(&[1.0, 2.0, 2.0, 1.0], 2, &mut [0.0; 4]));
    }

    #[test]
    fn bad_settings_are_named() {
        let e = PreconParams {
            refresh: 0,
            ..Default::default()
        }
        .validate("minimizer.precondition")
        .unwrap_err();
        assert!(
            e.to_string().contains("minimizer.precondition.refresh"),
            "{e}"
        );
        let e = PreconParams {
            floor: -1.0,
            ..Default::default()
        }
        .validate("p")
        .unwrap_err();
        assert!(e.to_string().contains("p.floor"), "{e}");
    }
}
