//! The Hessian of the energy in all generalised coordinates.
//!
//! With `V = Σ_c v(h_c)` over contacts, the paper's Eq. (25) splits the
//! Hessian into a stiffness and a stress part,
//!
//! ```text
//! H_ab = ∂²V/∂q_a∂q_b = K_ab + T_ab,
//! K_ab = Σ_c v''(h_c) ∂h_c/∂q_a ∂h_c/∂q_b,     T_ab = Σ_c v'(h_c) ∂²h_c/∂q_a∂q_b,
//! ```
//!
//! where `q` runs over the translations and rotational coordinates of every
//! body. At the jamming point `v'(h) → 0` and `H → K`, the paper's choice.
//!
//! Each contact touches two bodies, so `H` is block-sparse: it is assembled
//! here as a list of entries (both triangles, duplicates summed), from the
//! second derivatives of every gap that the family provides
//! ([`Shape::gap_hessians`]). The coordinates are the ones FIRE sees, in the
//! same order (`D` translations then the rotational coordinates of body 0,
//! then body 1, …).
//!
//! Rattlers never couple: the contacts a rattler makes are left out (at
//! the end of a minimisation they carry no force, but a harmonic contact
//! at `h = −10⁻¹³` still has `v'' = 1`). Kept, a rattler's rows are zero and
//! it adds `f = D + rot_dof` zero modes, as the paper counts them (its
//! `D(ω)` is normalised by all `3N` coordinates); removed, its rows and
//! columns are left out. Without a rattler mask (an empty slice) every
//! contact counts, and the matrix is exactly `∂²V/∂q∂q`. The Hessian is **not**
//! mass-weighted, as in the paper: its eigenvalues are `λ = ω²` with unit
//! masses and unit moments of inertia.

use crate::scene::Scene;
use jamkit_core::{GapHessian, Potential, Result, Shape};

/// What to assemble.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HessianOptions {
    /// Only the stiffness part `K` (the paper's choice at φ_J).
    pub stiffness_only: bool,
    /// Leave out the rows and columns of rattlers, and their contacts.
    pub remove_rattlers: bool,
}

/// A symmetric Hessian as a list of entries (both triangles).
#[derive(Clone, Debug, PartialEq)]
pub struct Hessian {
    /// Number of rows (= columns).
    pub size: usize,
    /// Body of each row.
    pub body: Vec<u32>,
    /// Whether each row is a rotational coordinate.
    pub rotational: Vec<bool>,
    /// `(row, column, value)`; an index pair may repeat (the values add).
    pub entries: Vec<(u32, u32, f64)>,
}

impl Hessian {
    /// Assemble the Hessian of `scene`; `rattler` marks the rattlers (empty:
    /// none), whose contacts are dropped and, with
    /// `options.remove_rattlers`, whose rows too.
    pub fn of_scene<const D: usize, S: Shape<D>>(
        scene: &mut Scene<D, S>,
        rattler: &[bool],
        options: HessianOptions,
    ) -> Result<Self> {
        let n = scene.packing().len();
        let k = scene.packing().shape.rot_dof();
        let potential = scene.potential();
        Self::of_contacts::<D>(n, k, potential, rattler, options, |visit| {
            scene.for_each_gap_hessian(0.0, |i, j, c| visit(i, j, c))
        })
    }

    /// Assemble the Hessian of `n` bodies with `k` rotational coordinates
    /// each from the contacts that `contacts` hands to its visitor (as
    /// `(i, j, gap Hessian)`), with the rattler rules of [`Self::of_scene`]:
    /// for packings held other than by a [`Scene`] (a sheared cell).
    pub fn of_contacts<const D: usize>(
        n: usize,
        k: usize,
        potential: Potential,
        rattler: &[bool],
        options: HessianOptions,
        contacts: impl FnOnce(&mut dyn FnMut(usize, usize, &GapHessian<D>)) -> Result<()>,
    ) -> Result<Self> {
        let stride = D + k;
        let rattles = |i: usize| rattler.get(i).copied().unwrap_or(false);
        let kept = |i: usize| !(options.remove_rattlers && rattles(i));
        // Row of each kept body's first coordinate.
        let mut first_row = vec![u32::MAX; n];
        let mut body = Vec::new();
        let mut rotational = Vec::new();
        for i in (0..n).filter(|&i| kept(i)) {
            first_row[i] = body.len() as u32;
            for a in 0..stride {
                body.push(i as u32);
                rotational.push(a >= D);
            }
        }
        let mut entries = Vec::new();
        contacts(&mut |i, j, c| {
            if !rattles(i) && !rattles(j) {
                add_contact::<D>(
                    &mut entries,
                    [first_row[i], first_row[j]],
                    k,
                    potential,
                    c,
                    options.stiffness_only,
                );
            }
        })?;
        Ok(Self {
            size: body.len(),
            body,
            rotational,
            entries,
        })
    }

    /// The Hessian as a dense column-major matrix (`size × size`).
    pub fn dense(&self) -> faer::Mat<f64> {
        let mut m = faer::Mat::<f64>::zeros(self.size, self.size);
        for &(r, c, v) in &self.entries {
            m[(r as usize, c as usize)] += v;
        }
        m
    }

    /// `H x`.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.size];
        for &(r, c, v) in &self.entries {
            y[r as usize] += v * x[c as usize];
        }
        y
    }
}

/// The stiffness part of each body's own diagonal block of the Hessian,
///
/// ```text
/// K_bb = Σ_{c ∋ b} v''(h_c) ∇_b h_c ∇_b h_cᵀ,
/// ```
///
/// with `∇_b h_c` the derivatives of contact `c`'s gap in body `b`'s
/// `f = D + rot_dof` coordinates (`−∂h/∂r_j` then `∂h/∂q_i` for the first
/// body of a pair, `∂h/∂r_j` then `∂h/∂q_j` for the second). Written into
/// `blocks` as `N` row-major `f × f` blocks. It needs only the gaps' first
/// derivatives, so every family has it; the preconditioned FIRE
/// ([`crate::precon`]) uses it as its mass.
pub fn stiffness_blocks<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    blocks: &mut Vec<f64>,
) {
    let k = scene.packing().shape.rot_dof();
    let f = D + k;
    let n = scene.packing().len();
    blocks.clear();
    blocks.resize(n * f * f, 0.0);
    let potential = scene.potential();
    scene.for_each_contact(0.0, |i, j, _, c| {
        let ddv = potential.second_derivative(c.gap);
        if ddv == 0.0 {
            return;
        }
        for (body, sign, rot) in [(i, -1.0, &c.grad_rot_i), (j, 1.0, &c.grad_rot_j)] {
            let mut g = [0.0; 6];
            for a in 0..D {
                g[a] = sign * c.grad_r[a];
            }
            g[D..f].copy_from_slice(&rot[..k]);
            let block = &mut blocks[body * f * f..(body + 1) * f * f];
            for a in 0..f {
                for b in 0..f {
                    block[a * f + b] += ddv * g[a] * g[b];
                }
            }
        }
    });
}

/// Add one contact's `v'' ∇h ∇hᵀ (+ v' ∇²h)` to the entries. Local
/// coordinates of the pair: `(r_i, q_i, r_j, q_j)`, with `∂h/∂r_i = −∂h/∂r_j`;
/// `first_row` holds the rows of body `i`'s and body `j`'s first
/// coordinates and `k` the rotational coordinates per body. Public for
/// objectives other than [`Scene`] that assemble the same Hessian (the
/// strained packings of `jamkit_observe::moduli`).
pub fn add_contact<const D: usize>(
    entries: &mut Vec<(u32, u32, f64)>,
    first_row: [u32; 2],
    k: usize,
    potential: Potential,
    c: &GapHessian<D>,
    stiffness_only: bool,
) {
    let h = c.contact.gap;
    let (dv, ddv) = (potential.derivative(h), potential.second_derivative(h));
    if dv == 0.0 && ddv == 0.0 {
        return;
    }
    let s = D + k;
    // Local gradient g (length 2s) and local Hessian L (2s × 2s).
    let mut g = vec![0.0; 2 * s];
    let mut l = vec![vec![0.0; 2 * s]; 2 * s];
    let (ri, qi, rj, qj) = (0, D, s, s + D);
    for a in 0..D {
        g[ri + a] = -c.contact.grad_r[a];
        g[rj + a] = c.contact.grad_r[a];
    }
    g[qi..qi + k].copy_from_slice(&c.contact.grad_rot_i[..k]);
    g[qj..qj + k].copy_from_slice(&c.contact.grad_rot_j[..k]);
    if !stiffness_only && dv != 0.0 {
        for a in 0..D {
            for b in 0..D {
                let v = c.rr[(a, b)];
                l[ri + a][ri + b] = v;
                l[rj + a][rj + b] = v;
                l[ri + a][rj + b] = -v;
                l[rj + a][ri + b] = -v;
            }
        }
        for a in 0..k {
            for b in 0..D {
                let (ui, uj) = (c.r_qi[a][b], c.r_qj[a][b]);
                l[rj + b][qi + a] = ui;
                l[ri + b][qi + a] = -ui;
                l[rj + b][qj + a] = uj;
                l[ri + b][qj + a] = -uj;
                l[qi + a][rj + b] = ui;
                l[qi + a][ri + b] = -ui;
                l[qj + a][rj + b] = uj;
                l[qj + a][ri + b] = -uj;
            }
            for b in 0..k {
                l[qi + a][qi + b] = c.qi_qi[a][b];
                l[qj + a][qj + b] = c.qj_qj[a][b];
                l[qi + a][qj + b] = c.qi_qj[a][b];
                l[qj + b][qi + a] = c.qi_qj[a][b];
            }
        }
    }
    let row = |local: usize| first_row[local / s] + (local % s) as u32;
    for x in 0..2 * s {
        for y in 0..2 * s {
            let v = ddv * g[x] * g[y] + dv * l[x][y];
            if v != 0.0 {
                entries.push((row(x), row(y), v));
            }
        }
    }
}

/// The Hessian by central differences of the analytic gradient,
/// `(∇V(q + ε e_b) − ∇V(q − ε e_b)) / 2ε`, symmetrised, as rows (every
/// body kept). Rotations go through the family's `rotate`, so this checks
/// [`Hessian::of_scene`] in the same coordinates; for non-commuting 3D
/// rotations the symmetric part is the second derivative in the increments.
pub fn finite_difference<const D: usize, S: Shape<D>>(
    scene: &Scene<D, S>,
    step: f64,
) -> Vec<Vec<f64>> {
    use crate::objective::Objective;
    let n = scene.dof();
    let mut columns = Vec::with_capacity(n);
    let mut dq = vec![0.0; n];
    let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
    for b in 0..n {
        for (sign, out) in [(1.0, &mut plus), (-1.0, &mut minus)] {
            let mut moved = scene.clone();
            dq[b] = sign * step;
            moved.displace(&dq);
            moved.energy_gradient(out);
        }
        dq[b] = 0.0;
        columns.push(
            plus.iter()
                .zip(&minus)
                .map(|(p, m)| (p - m) / (2.0 * step))
                .collect::<Vec<f64>>(),
        );
    }
    (0..n)
        .map(|a| {
            (0..n)
                .map(|b| 0.5 * (columns[b][a] + columns[a][b]))
                .collect()
        })
        .collect()
}
