//! Elastic moduli above jamming: the stress tensor, the strain derivatives
//! of the energy, and the shear and bulk moduli by linear response, with a
//! check by deformation.
//!
//! **Strain.** A homogeneous strain deforms the periodic cell by
//! `F = I + γ E` and carries every separation with it, `r_ij → F r_ij`
//! (the centres move affinely; the bodies' orientations do not: rigid
//! bodies are not deformed, their rotation is part of the non-affine
//! relaxation). Here `E = e_a e_bᵀ` (`a ≠ b`) is a simple shear of the
//! `(a, b)` plane (`x_a += γ x_b`) and `E = I` an isotropic dilation. A
//! gap depends on the centres only through `r_ij`, so with
//! `g = ∂h/∂r_j`, `K_rr = ∂²h/∂r_j∂r_j` and `t = E r_ij` (the
//! [`GapHessian`] contract):
//!
//! ```text
//! ∂h/∂γ = g·t,      ∂²h/∂γ² = tᵀ K_rr t,
//! ∂²h/∂γ∂r_j = K_rr t = −∂²h/∂γ∂r_i,     ∂²h/∂γ∂q_i[a] = r_qi[a]·t,
//! ```
//!
//! and for `U = Σ_c v(h_c)`
//!
//! ```text
//! U_γ  = Σ_c v' g·t,
//! A    = ∂²U/∂γ²   = Σ_c [v'' (g·t)² + v' tᵀ K_rr t]          (affine),
//! Ξ_j  = ∂²U/∂γ∂r_j = Σ_c [v'' (g·t) g + v' K_rr t]  (−Ξ_i),
//! Ξ_qi = Σ_c [v'' (g·t) ∂h/∂q_i + v' r_qi·t]                     (non-affine force field).
//! ```
//!
//! **Stress.** `σ_ab = (1/V) Σ_c v'(h_c) g_a r_b` (`V` the box volume), so
//! that `V σ_ab = U_γ` for `E = e_a e_bᵀ` and the pressure is
//! `p = −tr σ / D` ([`jamkit_engine::Scene::pressure`]).
//!
//! **Moduli.** Relaxing the coordinates `q` (translations and rotations) at
//! fixed strain, `U_min(γ)` has second derivative `A − Ξᵀ H⁺ Ξ` at a
//! minimum, with `H` the full Hessian (stiffness and stress parts, rattlers
//! removed) and `H⁺` its pseudo-inverse on the modes with `ω = √λ` above
//! `omega_zero` (the zero modes as [`crate::spectrum`] counts them: the `D`
//! global translations, and any others, which are reported). Then
//!
//! ```text
//! G_ab = (A − Ξᵀ H⁺ Ξ) / V        (simple shear of the (a, b) plane; = dσ_ab/dγ),
//! B    = (A − Ξᵀ H⁺ Ξ) / (D² V) + (D − 1) p / D     (E = I; = −V dp/dV),
//! ```
//!
//! and `G` is the mean of `G_ab` over the `D(D−1)/2` planes. `G_ab` is the
//! slope of the shear stress under simple shear (`V σ_ab = dU_min/dγ`
//! along the relaxed path, volume constant); the bulk modulus takes the
//! change of volume into account (`V = V₀(1+γ)^D`). With `v'` terms left
//! out (`A`, `Ξ` and `H` at zero force) these are the O'Hern et al. (2003)
//! moduli; at a pressure `p` the stress terms shift `G` by `O(p)`.
//!
//! **Check by deformation.** [`Strained`] is the packing in a deformed
//! periodic cell (Lees–Edwards for a simple shear): the pairs of the
//! unstrained packing with their image vectors fixed, separations
//! `F r_ij + u_j − u_i`. It is an [`Objective`], so the engine's minimiser
//! relaxes it at fixed strain; [`by_deformation`] measures
//! `G_ab = (σ_ab(+γ) − σ_ab(−γ)) / 2γ` and `B = −(p(+γ) − p(−γ)) / (2Dγ)`.
//! (The periodic box of the engine is orthorhombic and cannot be sheared,
//! hence the fixed image vectors; they stay exact while no body moves by
//! more than the pair margin, which is checked.)

use crate::hessian::{Hessian, HessianOptions, add_contact};
use crate::pinverse::SparseInverse;
use crate::spectrum::ZeroModes;
use jamkit_core::Pair;
pub use jamkit_core::records::{Moduli, ModuliParams, ModuliSolver};
use jamkit_core::{Error, Matrix, Packing, PeriodicBox, Potential, Result, Shape, Vector};
use jamkit_engine::{Fire, FireParams, Objective, Scene};
use serde::{Deserialize, Serialize};

/// `E` of a simple shear of the `(a, b)` plane: `x_a += γ x_b`.
pub fn simple_shear<const D: usize>(a: usize, b: usize) -> Matrix<D> {
    let mut e = Matrix::<D>::zeros();
    e[(a, b)] = 1.0;
    e
}

/// The shear planes `(a, b)`, `a < b`: `(0, 1)` in 2D; `(0, 1)`, `(0, 2)`,
/// `(1, 2)` in 3D.
pub fn shear_planes<const D: usize>() -> Vec<(usize, usize)> {
    (0..D)
        .flat_map(|a| (a + 1..D).map(move |b| (a, b)))
        .collect()
}

/// The stress tensor `σ_ab = (1/V) Σ_c v'(h_c) g_a r_b` of a scene (every
/// contact; rattlers carry no force).
pub fn stress_tensor<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>) -> Matrix<D> {
    let potential = scene.potential();
    let mut sum = Matrix::<D>::zeros();
    scene.for_each_contact(0.0, |_, _, r, c| {
        sum += c.grad_r * r.transpose() * potential.derivative(c.gap);
    });
    sum / scene.packing().bbox.volume()
}

/// The strain derivatives of the energy for one strain `E`.
#[derive(Clone, Debug, PartialEq)]
pub struct StrainDerivatives {
    /// `U_γ = ∂U/∂γ`.
    pub first: f64,
    /// `A = ∂²U/∂γ²` at fixed coordinates (the affine term, times `V`).
    pub affine: f64,
    /// `Ξ = ∂²U/∂γ∂q`, one entry per row of the Hessian it goes with.
    pub xi: Vec<f64>,
}

/// One contact's share of the strain derivatives: `(U_γ, A)` and the
/// local `Ξ` in the pair's coordinates `(r_i, q_i, r_j, q_j)`.
fn contact_strain<const D: usize>(
    potential: Potential,
    c: &jamkit_core::GapHessian<D>,
    r: &Vector<D>,
    e: &Matrix<D>,
    k: usize,
    local: &mut [f64],
) -> (f64, f64) {
    let h = c.contact.gap;
    let (dv, ddv) = (potential.derivative(h), potential.second_derivative(h));
    local.fill(0.0);
    if dv == 0.0 && ddv == 0.0 {
        return (0.0, 0.0);
    }
    let g = &c.contact.grad_r;
    let t = e * r;
    let s = g.dot(&t);
    let kt = c.rr * t;
    let xr = g * (ddv * s) + kt * dv;
    let stride = D + k;
    for a in 0..D {
        local[a] = -xr[a];
        local[stride + a] = xr[a];
    }
    for a in 0..k {
        local[D + a] = ddv * s * c.contact.grad_rot_i[a] + dv * c.r_qi[a].dot(&t);
        local[stride + D + a] = ddv * s * c.contact.grad_rot_j[a] + dv * c.r_qj[a].dot(&t);
    }
    (dv * s, ddv * s * s + dv * t.dot(&kt))
}

/// The strain derivatives of `scene` for the strain `E = e`, with `Ξ` laid
/// out as the rows of `hessian` (built by [`Hessian::of_scene`] with the
/// same `rattler` mask): contacts of rattlers are left out, as there.
pub fn strain_derivatives<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattler: &[bool],
    hessian: &Hessian,
    e: &Matrix<D>,
) -> Result<StrainDerivatives> {
    strain_derivatives_of(scene, rattler, hessian, e)
}

/// What the moduli need of a packing, whether held by a [`Scene`] (the
/// engine's orthorhombic box) or by a [`Strained`] cell: its contacts with
/// their separations and gap Hessians.
trait Cell<const D: usize> {
    /// Number of bodies.
    fn body_count(&self) -> usize;
    /// Rotational coordinates per body.
    fn rot_coordinates(&self) -> usize;
    /// The pair potential.
    fn pair_potential(&self) -> Potential;
    /// The cell's volume.
    fn cell_volume(&self) -> f64;
    /// Visit every contact as `(i, j, r_ij, gap Hessian)`.
    fn visit_gap_hessians(
        &mut self,
        visit: &mut dyn FnMut(usize, usize, &Vector<D>, &jamkit_core::GapHessian<D>),
    ) -> Result<()>;
    /// The Hessian (stiffness and stress parts) with the rattlers' rows
    /// and contacts removed.
    fn full_hessian(&mut self, rattler: &[bool]) -> Result<Hessian>;
}

const FULL_HESSIAN: HessianOptions = HessianOptions {
    stiffness_only: false,
    remove_rattlers: true,
};

impl<const D: usize, S: Shape<D>> Cell<D> for Scene<D, S> {
    fn body_count(&self) -> usize {
        self.packing().len()
    }

    fn rot_coordinates(&self) -> usize {
        self.packing().shape.rot_dof()
    }

    fn pair_potential(&self) -> Potential {
        self.potential()
    }

    fn cell_volume(&self) -> f64 {
        self.packing().bbox.volume()
    }

    fn visit_gap_hessians(
        &mut self,
        visit: &mut dyn FnMut(usize, usize, &Vector<D>, &jamkit_core::GapHessian<D>),
    ) -> Result<()> {
        // The separation of each visited pair: `for_each_gap_hessian` does
        // not pass it, so it is recomputed here as the scene's pair loop
        // does.
        let positions = self.packing().positions.clone();
        let bbox = self.packing().bbox.clone();
        self.for_each_gap_hessian(0.0, |i, j, c| {
            let r = bbox.minimum_image(positions[j] - positions[i]);
            visit(i, j, &r, c);
        })
    }

    fn full_hessian(&mut self, rattler: &[bool]) -> Result<Hessian> {
        Hessian::of_scene(self, rattler, FULL_HESSIAN)
    }
}

fn strain_derivatives_of<const D: usize, C: Cell<D>>(
    cell: &mut C,
    rattler: &[bool],
    hessian: &Hessian,
    e: &Matrix<D>,
) -> Result<StrainDerivatives> {
    let k = cell.rot_coordinates();
    let stride = D + k;
    let first_row = first_rows(hessian, cell.body_count());
    let rattles = |i: usize| rattler.get(i).copied().unwrap_or(false);
    let potential = cell.pair_potential();
    let mut out = StrainDerivatives {
        first: 0.0,
        affine: 0.0,
        xi: vec![0.0; hessian.size],
    };
    let mut local = vec![0.0; 2 * stride];
    let mut missing = None;
    cell.visit_gap_hessians(&mut |i, j, r, c| {
        if rattles(i) || rattles(j) {
            return;
        }
        let (first, affine) = contact_strain(potential, c, r, e, k, &mut local);
        out.first += first;
        out.affine += affine;
        for (side, body) in [i, j].into_iter().enumerate() {
            let row = first_row[body];
            if row == u32::MAX {
                missing = Some(body);
                continue;
            }
            for a in 0..stride {
                out.xi[row as usize + a] += local[side * stride + a];
            }
        }
    })?;
    if let Some(body) = missing {
        return Err(Error::Unsupported(format!(
            "body {body} has contacts but no rows in the Hessian: the rattler mask of the strain derivatives differs from the Hessian's"
        )));
    }
    Ok(out)
}

/// The row of each body's first coordinate in `hessian` (`u32::MAX` for a
/// body whose rows were removed).
fn first_rows(hessian: &Hessian, bodies: usize) -> Vec<u32> {
    let mut first = vec![u32::MAX; bodies];
    for (row, &b) in hessian.body.iter().enumerate().rev() {
        if let Some(f) = first.get_mut(b as usize) {
            *f = row as u32;
        }
    }
    first
}

/// Relative residual to which Lanczos finds the softest mode for
/// [`measure`] (its eigenvector gives `soft_share`).
const LANCZOS_TOL: f64 = 1e-9;
/// The same in each strain step of [`stabilise`], where only its
/// eigenvalue is needed (to know that no mode but the translations is at
/// or below `ω_zero²`).
const LANCZOS_TOL_STEP: f64 = 1e-4;

/// The linear-response moduli of a relaxed scene; `rattler` marks the
/// rattlers, whose rows and contacts are removed.
pub fn measure<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
) -> Result<Moduli> {
    measure_cell(scene, rattler, params)
}

/// The linear-response moduli of a relaxed [`Strained`] cell (the same
/// definitions as [`measure`], in the deformed cell: `V` its volume, the
/// strains applied on top of its deformation); `rattler` as there.
pub fn measure_strained<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
) -> Result<Moduli> {
    measure_cell(cell, rattler, params)
}

/// `H⁺` of a Hessian: its modes, or a sparse factorisation.
enum PseudoInverse {
    /// Eigenvalues (ascending) and eigenvectors.
    Dense(Vec<f64>, faer::Mat<f64>),
    /// `crate::pinverse`.
    Sparse(SparseInverse),
}

impl PseudoInverse {
    /// By `solver`; with the reason when `Sparse` fell back to the dense
    /// modes.
    fn of(
        hessian: &Hessian,
        dim: usize,
        lambda_zero: f64,
        solver: ModuliSolver,
        tol: f64,
    ) -> Result<(Self, Option<String>)> {
        let fallback = match solver {
            ModuliSolver::Dense => None,
            ModuliSolver::Sparse => match SparseInverse::new(hessian, dim, lambda_zero, tol) {
                Ok(inverse) => return Ok((Self::Sparse(inverse), None)),
                Err(reason) => Some(reason),
            },
        };
        let (values, vectors) = modes(hessian)?;
        Ok((Self::Dense(values, vectors), fallback))
    }
}

/// The eigenvalues and eigenvectors of a Hessian (ascending).
fn modes(hessian: &Hessian) -> Result<(Vec<f64>, faer::Mat<f64>)> {
    let n = hessian.size;
    if n == 0 {
        return Ok((Vec::new(), faer::Mat::<f64>::zeros(0, 0)));
    }
    let evd = hessian
        .dense()
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
    let values: Vec<f64> = (0..n).map(|m| evd.S()[m]).collect();
    Ok((values, evd.U().to_owned()))
}

fn measure_cell<const D: usize, C: Cell<D>>(
    scene: &mut C,
    rattler: &[bool],
    params: &ModuliParams,
) -> Result<Moduli> {
    params.validate("moduli")?;
    let hessian = scene.full_hessian(rattler)?;
    let n = hessian.size;
    let volume = scene.cell_volume();
    let lambda_zero = params.omega_zero * params.omega_zero;
    let (inverse, dense_fallback) =
        PseudoInverse::of(&hessian, D, lambda_zero, params.solver, LANCZOS_TOL)?;
    let relaxed = |d: &StrainDerivatives| match &inverse {
        PseudoInverse::Dense(values, vectors) => relaxed_dense(values, vectors, lambda_zero, d),
        PseudoInverse::Sparse(s) => relaxed_sparse(s, d),
    };
    let mut floppy_share: f64 = 0.0;
    let planes = shear_planes::<D>();
    let mut per_plane = Vec::new();
    let mut shear_affine = 0.0;
    let mut soft_share = None;
    for &(a, b) in &planes {
        let d = strain_derivatives_of(scene, rattler, &hessian, &simple_shear::<D>(a, b))?;
        let (c, share, soft) = relaxed(&d);
        floppy_share = floppy_share.max(share);
        if per_plane.iter().all(|&g| c / volume < g) {
            soft_share = soft;
        }
        per_plane.push(c / volume);
        shear_affine += d.affine / volume / planes.len() as f64;
    }
    let d = strain_derivatives_of(scene, rattler, &hessian, &Matrix::<D>::identity())?;
    let (c, share, _) = relaxed(&d);
    floppy_share = floppy_share.max(share);
    let dd = (D * D) as f64;
    // `U_γ = Σ v' g·r = −D V p` for `E = I`.
    let pressure = -d.first / (D as f64 * volume);
    let stress_term = (D as f64 - 1.0) * pressure / D as f64;
    // The sparse path is taken only when the translations are the only
    // zero modes and no mode is negative (`crate::pinverse`).
    let (total, negative_modes) = match &inverse {
        PseudoInverse::Dense(values, _) => (
            values.iter().filter(|&&l| l <= lambda_zero).count() as u64,
            values.iter().filter(|&&l| l < -lambda_zero).count() as u64,
        ),
        PseudoInverse::Sparse(_) => (D as u64, 0),
    };
    let translations = if n == 0 { 0 } else { D as u64 };
    Ok(Moduli {
        shear: per_plane.iter().sum::<f64>() / planes.len().max(1) as f64,
        shear_planes: per_plane,
        bulk: c / (dd * volume) + stress_term,
        shear_affine,
        bulk_affine: d.affine / (dd * volume) + stress_term,
        pressure,
        coordinates: n,
        zero_modes: ZeroModes {
            total,
            translations,
            rattlers: 0,
            extra: total as i64 - translations as i64,
        },
        negative_modes,
        floppy_share,
        soft_share,
        dense_fallback,
    })
}

/// `(U_min'', share of |Ξ|² on the zero modes, share of the non-affine
/// term on the softest mode)` from the dense modes: `U_min'' = A −
/// Σ_{λ > λ0} (u·Ξ)²/λ`, where translations carry none of `Ξ` (it sums to
/// zero over bodies).
fn relaxed_dense(
    values: &[f64],
    vectors: &faer::Mat<f64>,
    lambda_zero: f64,
    d: &StrainDerivatives,
) -> (f64, f64, Option<f64>) {
    let n = values.len();
    // The softest mode above the zero modes (eigenvalues ascend).
    let softest = values.iter().position(|&l| l > lambda_zero);
    let mut non_affine = 0.0;
    let (mut on_zero, mut total) = (0.0, 0.0);
    let mut on_softest = 0.0;
    for m in 0..n {
        let c: f64 = (0..n).map(|r| vectors[(r, m)] * d.xi[r]).sum();
        total += c * c;
        if values[m] > lambda_zero {
            non_affine += c * c / values[m];
            if Some(m) == softest {
                on_softest = c * c / values[m];
            }
        } else {
            on_zero += c * c;
        }
    }
    let share = if total > 0.0 { on_zero / total } else { 0.0 };
    let soft = (softest.is_some() && non_affine > 0.0).then(|| on_softest / non_affine);
    (d.affine - non_affine, share, soft)
}

/// The same as [`relaxed_dense`] by the sparse solve: `Ξ`'s component
/// along the translations (the only zero modes here) is projected out and
/// is the share, `Ξᵀ H⁺ Ξ = Ξ_P · x` with `H x = Ξ_P`, and the softest
/// mode is Lanczos's.
fn relaxed_sparse(inverse: &SparseInverse, d: &StrainDerivatives) -> (f64, f64, Option<f64>) {
    let total: f64 = d.xi.iter().map(|x| x * x).sum();
    let mut xi = d.xi.clone();
    let on_zero = inverse.project(&mut xi);
    let x = inverse.solve(&xi);
    let non_affine: f64 = xi.iter().zip(&x).map(|(a, b)| a * b).sum();
    let c: f64 = inverse.softest.iter().zip(&xi).map(|(a, b)| a * b).sum();
    let on_softest = c * c / inverse.lambda_min;
    let share = if total > 0.0 { on_zero / total } else { 0.0 };
    let soft = (non_affine > 0.0).then(|| on_softest / non_affine);
    (d.affine - non_affine, share, soft)
}

/// A packing in a homogeneously deformed periodic cell, with the pairs and
/// image vectors of the undeformed one fixed: the separation of pair `ij`
/// is `F R_ij + u_j − u_i`, `R_ij` its minimum image when it was built and
/// `u` the displacements since. An [`Objective`] in the same coordinates
/// as the [`Scene`] it was built from (translations then rotations, body
/// by body), with the same Hessian, so the engine's minimisers relax it.
///
/// Like the engine's neighbour list, the pairs are listed again while a
/// minimiser moves the bodies: as soon as some body has moved by a quarter
/// of the margin since the last listing ([`Objective::displace`]). Without
/// it a rearrangement (a plastic event under strain) would run on the fixed
/// list, where unlisted neighbours do not repel: bodies slide through each
/// other and the listed energy falls to zero (3D spheres, N = 128,
/// δφ = 10⁻¹: bodies moved by up to 1.9; `tests/moduli.rs`,
/// `dense_3d_spheres_stabilise`).
#[derive(Clone, Debug)]
pub struct Strained<const D: usize, S: Shape<D>> {
    shape: S,
    potential: Potential,
    sizes: Vec<f64>,
    orientations: Vec<S::Orientation>,
    geometry: Geometry<D>,
    /// The geometry and orientations at the last [`Objective::save`].
    saved: Option<Box<(Geometry<D>, Vec<S::Orientation>)>>,
    bbox: PeriodicBox<D>,
    inverse_masses: Vec<f64>,
    margin: f64,
    phi: f64,
}

/// The cell and the bodies' centres of a [`Strained`] packing (what a
/// listing of the pairs changes).
#[derive(Clone, Debug)]
struct Geometry<const D: usize> {
    displacement: Vec<Vector<D>>,
    pairs: Vec<(u32, u32, Vector<D>)>,
    deformation: Matrix<D>,
    volume: f64,
    /// The centres as of the last listing (or as built), for listing the
    /// pairs again.
    positions: Vec<Vector<D>>,
    /// The deformation folded in by [`Strained::rebase`]: the cell is
    /// `lattice · diag(L)` of the box it was built from.
    lattice: Matrix<D>,
}

impl<const D: usize, S: Shape<D>> Strained<D, S> {
    /// The packing of `scene`, undeformed, with every pair whose bounding
    /// balls come within `margin` of each other.
    pub fn new(scene: &Scene<D, S>, margin: f64) -> Result<Self> {
        if !(margin > 0.0 && margin.is_finite()) {
            return Err(Error::invalid(
                "margin",
                margin,
                "must be positive and finite",
            ));
        }
        scene.check_box()?;
        let p: &Packing<D, S> = scene.packing();
        if 2.0 * (2.0 * max_reach(p) + margin) > p.bbox.min_edge() {
            return Err(Error::invalid(
                "margin",
                margin,
                format!(
                    "must leave every pair range below half the box edge {}",
                    p.bbox.min_edge()
                ),
            ));
        }
        let reach: Vec<f64> = p
            .sizes
            .iter()
            .map(|&s| p.shape.bounding_radius(s))
            .collect();
        let mut pairs = Vec::new();
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let r = p.bbox.minimum_image(p.positions[j] - p.positions[i]);
                let cut = reach[i] + reach[j] + margin;
                if r.norm_squared() < cut * cut {
                    pairs.push((i as u32, j as u32, r));
                }
            }
        }
        Ok(Self {
            shape: p.shape.clone(),
            potential: scene.potential(),
            sizes: p.sizes.clone(),
            orientations: p.orientations.clone(),
            geometry: Geometry {
                displacement: vec![Vector::<D>::zeros(); p.len()],
                pairs,
                deformation: Matrix::<D>::identity(),
                volume: p.bbox.volume(),
                positions: p.positions.clone(),
                lattice: Matrix::<D>::identity(),
            },
            saved: None,
            bbox: p.bbox.clone(),
            inverse_masses: p.inverse_masses(),
            margin,
            phi: p.phi(),
        })
    }

    /// Deform the cell to `F = I + γ E` (the displacements are kept),
    /// `F` relative to the cell as built or as last [`Self::rebase`]d.
    pub fn set_strain(&mut self, gamma: f64, e: &Matrix<D>) {
        self.geometry.deformation = Matrix::<D>::identity() + e * gamma;
    }

    /// Deform the cell by `F` (relative as for [`Self::set_strain`]).
    pub fn set_deformation(&mut self, f: Matrix<D>) {
        self.geometry.deformation = f;
    }

    /// The cell's deformation from the box it was built from,
    /// `F · lattice` (the cell is `F · lattice · diag(L)`).
    pub fn total_deformation(&self) -> Matrix<D> {
        self.geometry.deformation * self.geometry.lattice
    }

    /// Make the current cell and configuration the reference: each pair
    /// vector becomes its current separation `F R_ij + u_j − u_i`, each
    /// centre `F x_i + u_i`, the deformation is folded into the lattice
    /// and the displacements are zeroed. Energy, forces and stress are
    /// unchanged (up to round-off); strains set afterwards act on the
    /// current cell.
    pub fn rebase(&mut self) {
        let f = self.geometry.deformation;
        for (i, j, r) in &mut self.geometry.pairs {
            *r = f * *r + self.geometry.displacement[*j as usize]
                - self.geometry.displacement[*i as usize];
        }
        for (x, u) in self
            .geometry
            .positions
            .iter_mut()
            .zip(&mut self.geometry.displacement)
        {
            *x = f * *x + *u;
            *u = Vector::<D>::zeros();
        }
        self.geometry.lattice = f * self.geometry.lattice;
        self.geometry.volume *= determinant(&f);
        self.geometry.deformation = Matrix::<D>::identity();
    }

    /// [`Self::rebase`], then list the pairs again in the deformed cell:
    /// each pair's image is the minimum image in the coordinates of the
    /// undeformed box, `r = M ⌊M⁻¹ (x_j − x_i)⌉_L` with `M` the lattice.
    /// Exact while the lattice is near `I`: refused when an entry of
    /// `M − I` exceeds 0.2 or the pair range no longer fits in the sheared
    /// cell.
    pub fn relist(&mut self) -> Result<()> {
        self.rebase();
        let m = self.geometry.lattice;
        let strain = (m - Matrix::<D>::identity()).abs().max();
        if !(strain <= 0.2) {
            return Err(Error::invalid(
                "strain",
                strain,
                "the cell's strain (largest entry of F − I) must stay at or below 0.2 for its pair list",
            ));
        }
        let reach: Vec<f64> = (self.sizes.iter())
            .map(|&s| self.shape.bounding_radius(s))
            .collect();
        let widest = reach.iter().copied().fold(0.0, f64::max);
        // A sheared cell is narrower than its box by at most `D · strain`
        // of an edge.
        let width = self.bbox.min_edge() * (1.0 - D as f64 * strain);
        if 2.0 * (2.0 * widest + self.margin) > width {
            return Err(Error::invalid(
                "strain",
                strain,
                format!(
                    "the sheared cell (narrowest width about {width}) must stay wider than twice the pair range {}",
                    2.0 * widest + self.margin
                ),
            ));
        }
        if !self.list_pairs() {
            return Err(Error::invalid(
                "strain",
                strain,
                "the cell's deformation must be invertible",
            ));
        }
        Ok(())
    }

    /// List the pairs of the rebased cell (the listing of [`Self::relist`],
    /// without its checks of the lattice); `false` when the lattice is
    /// singular (the list is then left as it was).
    fn list_pairs(&mut self) -> bool {
        let m = self.geometry.lattice;
        let Some(inv) = inverse(&m) else {
            return false;
        };
        let reach: Vec<f64> = (self.sizes.iter())
            .map(|&s| self.shape.bounding_radius(s))
            .collect();
        let reduced: Vec<Vector<D>> = self.geometry.positions.iter().map(|x| inv * x).collect();
        self.geometry.pairs.clear();
        for i in 0..reduced.len() {
            for j in i + 1..reduced.len() {
                let r = m * self.bbox.minimum_image(reduced[j] - reduced[i]);
                let cut = reach[i] + reach[j] + self.margin;
                if r.norm_squared() < cut * cut {
                    self.geometry.pairs.push((i as u32, j as u32, r));
                }
            }
        }
        true
    }

    /// The energy of the cell.
    pub fn energy(&self) -> f64 {
        let mut grad = vec![0.0; Objective::dof(self)];
        self.energy_and_gradient(&mut grad)
    }

    /// Every contact (`h < 0`) of the cell, in its deformed shape.
    pub fn contacts(&self) -> crate::contacts::ContactNetwork {
        let mut network = crate::contacts::ContactNetwork {
            bodies: self.sizes.len(),
            contacts: Vec::new(),
        };
        self.visit(|i, j, _, _, c| {
            if c.gap < 0.0 {
                network.contacts.push((i as u32, j as u32));
            }
        });
        network
    }

    /// Rattlers of the cell: bodies with fewer than `threshold` contacts
    /// (`h < 0`), removed iteratively ([`crate::contacts::find_rattlers`]).
    pub fn rattlers(&self, threshold: usize) -> Vec<bool> {
        crate::contacts::find_rattlers(&self.contacts(), threshold)
    }

    /// The contact numbers of the cell with the rattlers `rattler` (by
    /// count, as [`Self::rattlers`]; `f = D + rot_dof` coordinates per
    /// non-rattler): what [`crate::summarize`] gives for a packing in its
    /// fixed box, here in the deformed cell.
    pub fn contact_count(&self, rattler: &[bool]) -> crate::ContactCount {
        let f = (D + self.shape.rot_dof()) as i64;
        let kept = rattler.iter().filter(|&&r| !r).count() as i64;
        crate::ContactCount::of(&self.contacts(), rattler, f * kept, D)
    }

    /// The cell's volume, `V₀ det F`.
    pub fn volume(&self) -> f64 {
        self.geometry.volume * determinant(&self.geometry.deformation)
    }

    /// The bodies' centres in the deformed cell, `F x_i + u_i` (not wrapped
    /// into the cell: a body's centre minus its position in the box it was
    /// built from, mapped by [`Self::total_deformation`], is its non-affine
    /// displacement).
    pub fn centres(&self) -> Vec<Vector<D>> {
        let g = &self.geometry;
        (g.positions.iter().zip(&g.displacement))
            .map(|(x, u)| g.deformation * x + u)
            .collect()
    }

    /// The largest displacement of a centre since the pairs were listed.
    pub fn max_displacement(&self) -> f64 {
        self.geometry
            .displacement
            .iter()
            .map(|u| u.norm())
            .fold(0.0, f64::max)
    }

    /// Fail when some body moved so far since the pairs were listed that a
    /// pair missing from the list could touch (or an image vector could
    /// have changed). A minimiser step that moves a body further than a
    /// quarter of the margin before the list catches up only bends the
    /// path: the list made then is complete for the state it ends in as
    /// long as this check holds.
    pub fn check_pairs(&self) -> Result<()> {
        let moved = self.max_displacement();
        if 2.0 * moved >= self.margin {
            return Err(Error::Unsupported(format!(
                "a body moved by {moved:e} in the strained cell, more than half the pair margin {:e}: the strain is too large for a fixed pair list",
                self.margin
            )));
        }
        Ok(())
    }

    /// The strained separation of pair `(i, j)` whose separation in the
    /// cell as built is `r0`: `F r0 + u_j − u_i`.
    fn separation(&self, i: usize, j: usize, r0: &Vector<D>) -> Vector<D> {
        self.geometry.deformation * r0 + self.geometry.displacement[j]
            - self.geometry.displacement[i]
    }

    /// Visit every contact of the strained cell as `(i, j, r0, r, contact)`:
    /// `r0` the pair's separation in the cell as built, `r` the strained
    /// one.
    fn visit<F>(&self, mut visit: F)
    where
        F: FnMut(usize, usize, &Vector<D>, &Vector<D>, &jamkit_core::Contact<D>),
    {
        for &(i, j, r0) in &self.geometry.pairs {
            let (i, j) = (i as usize, j as usize);
            let r = self.separation(i, j, &r0);
            self.shape.contacts(
                &Pair::new(
                    self.sizes[i],
                    self.orientations[i],
                    self.sizes[j],
                    self.orientations[j],
                    r,
                ),
                0.0,
                |c| visit(i, j, &r0, &r, &c),
            );
        }
    }

    /// The stress tensor `σ_ab = (1/V) Σ_c v' g_a r_b` in the deformed cell.
    pub fn stress(&self) -> Matrix<D> {
        let mut sum = Matrix::<D>::zeros();
        self.visit(|_, _, _, r, c| {
            sum += c.grad_r * r.transpose() * self.potential.derivative(c.gap);
        });
        sum / self.volume()
    }

    /// `∂U/∂γ = Σ_c v' g·(E R_ij)` at the current cell and coordinates, for
    /// a strain `F → F + dγ E F₀` about the cell as built (`F₀ = I`): the
    /// derivative of the energy along the line `F = I + γ E` at fixed `u`
    /// and `q` (for finite-difference checks of [`strain_derivatives`]).
    pub fn strain_derivative(&self, e: &Matrix<D>) -> f64 {
        let mut sum = 0.0;
        self.visit(|_, _, r0, _, c| {
            sum += self.potential.derivative(c.gap) * c.grad_r.dot(&(e * r0));
        });
        sum
    }

    /// `p = −tr σ / D`.
    pub fn pressure(&self) -> f64 {
        -self.stress().trace() / D as f64
    }

    /// The energy and its gradient in the coordinates `(u, q)`.
    pub fn energy_and_gradient(&self, grad: &mut [f64]) -> f64 {
        let k = self.shape.rot_dof();
        let stride = D + k;
        grad.fill(0.0);
        let mut energy = 0.0;
        self.visit(|i, j, _, _, c| {
            let (v, dv) = self.potential.energy_and_derivative(c.gap);
            energy += v;
            for a in 0..D {
                grad[i * stride + a] -= dv * c.grad_r[a];
                grad[j * stride + a] += dv * c.grad_r[a];
            }
            for a in 0..k {
                grad[i * stride + D + a] += dv * c.grad_rot_i[a];
                grad[j * stride + D + a] += dv * c.grad_rot_j[a];
            }
        });
        energy
    }
}

/// `det m` by Gaussian elimination with partial pivoting (nalgebra's needs
/// bounds a generic `D` does not give).
fn determinant<const D: usize>(m: &Matrix<D>) -> f64 {
    let mut a = *m;
    let mut det = 1.0;
    for col in 0..D {
        let pivot = (col..D)
            .max_by(|&x, &y| a[(x, col)].abs().total_cmp(&a[(y, col)].abs()))
            .unwrap_or(col);
        if a[(pivot, col)] == 0.0 {
            return 0.0;
        }
        if pivot != col {
            a.swap_rows(pivot, col);
            det = -det;
        }
        det *= a[(col, col)];
        for row in col + 1..D {
            let f = a[(row, col)] / a[(col, col)];
            for c in col..D {
                a[(row, c)] -= f * a[(col, c)];
            }
        }
    }
    det
}

/// `m⁻¹` by Gauss–Jordan elimination with partial pivoting; `None` when
/// `m` is singular.
fn inverse<const D: usize>(m: &Matrix<D>) -> Option<Matrix<D>> {
    let mut a = *m;
    let mut inv = Matrix::<D>::identity();
    for col in 0..D {
        let pivot = (col..D).max_by(|&x, &y| a[(x, col)].abs().total_cmp(&a[(y, col)].abs()))?;
        if a[(pivot, col)] == 0.0 {
            return None;
        }
        a.swap_rows(pivot, col);
        inv.swap_rows(pivot, col);
        let d = a[(col, col)];
        for c in 0..D {
            a[(col, c)] /= d;
            inv[(col, c)] /= d;
        }
        for row in (0..D).filter(|&r| r != col) {
            let f = a[(row, col)];
            for c in 0..D {
                a[(row, c)] -= f * a[(col, c)];
                inv[(row, c)] -= f * inv[(col, c)];
            }
        }
    }
    Some(inv)
}

fn max_reach<const D: usize, S: Shape<D>>(p: &Packing<D, S>) -> f64 {
    p.sizes
        .iter()
        .map(|&s| p.shape.bounding_radius(s))
        .fold(0.0, f64::max)
}

impl<const D: usize, S: Shape<D>> Objective for Strained<D, S> {
    fn dof(&self) -> usize {
        self.sizes.len() * (D + self.shape.rot_dof())
    }

    fn bodies(&self) -> usize {
        self.sizes.len()
    }

    fn inverse_masses(&self) -> &[f64] {
        &self.inverse_masses
    }

    fn energy_gradient(&mut self, grad: &mut [f64]) -> f64 {
        self.energy_and_gradient(grad)
    }

    /// Move the bodies by `dq`; when some body has now moved by a quarter
    /// of the margin since the pairs were listed, [`Strained::rebase`] and
    /// list them again (energy and forces unchanged up to round-off).
    fn displace(&mut self, dq: &[f64]) {
        let stride = D + self.shape.rot_dof();
        for (i, chunk) in dq.chunks_exact(stride).enumerate() {
            for a in 0..D {
                self.geometry.displacement[i][a] += chunk[a];
            }
            if stride > D {
                self.shape.rotate(&mut self.orientations[i], &chunk[D..]);
            }
        }
        if 4.0 * self.max_displacement() >= self.margin {
            self.rebase();
            self.list_pairs();
        }
    }

    fn phi(&self) -> f64 {
        self.phi
    }

    fn translations_per_body(&self) -> usize {
        D
    }

    fn hessian_entries(&mut self, entries: &mut Vec<(u32, u32, f64)>) -> Result<bool> {
        let k = self.shape.rot_dof();
        let stride = (D + k) as u32;
        for &(i, j, r0) in &self.geometry.pairs {
            let (iu, ju) = (i as usize, j as usize);
            let r = self.separation(iu, ju, &r0);
            let outcome = self.shape.gap_hessians(
                &Pair::new(
                    self.sizes[iu],
                    self.orientations[iu],
                    self.sizes[ju],
                    self.orientations[ju],
                    r,
                ),
                0.0,
                |c| {
                    add_contact::<D>(
                        entries,
                        [i * stride, j * stride],
                        k,
                        self.potential,
                        &c,
                        false,
                    )
                },
            );
            match outcome {
                Ok(()) => {}
                Err(Error::Unsupported(_)) => return Ok(false),
                Err(e) => return Err(e),
            }
        }
        Ok(true)
    }

    /// Saves the geometry with the orientations: a listing of the pairs
    /// between save and restore changes the reference the displacements
    /// are measured from.
    fn save(&mut self) {
        match &mut self.saved {
            Some(saved) => {
                saved.0.clone_from(&self.geometry);
                saved.1.clone_from(&self.orientations);
            }
            None => {
                self.saved = Some(Box::new((self.geometry.clone(), self.orientations.clone())));
            }
        }
    }

    fn restore(&mut self) {
        if let Some(saved) = &self.saved {
            self.geometry.clone_from(&saved.0);
            self.orientations.clone_from(&saved.1);
        }
    }
}

/// The moduli measured by deformation.
#[derive(Clone, Debug, PartialEq)]
pub struct Deformation {
    /// `(σ_ab(+γ) − σ_ab(−γ)) / 2γ` for each shear plane.
    pub shear_planes: Vec<f64>,
    /// Their mean.
    pub shear: f64,
    /// `−(p(+γ) − p(−γ)) / (2Dγ)`.
    pub bulk: f64,
    /// The pressure of the relaxed, undeformed cell.
    pub pressure: f64,
    /// The largest displacement in any of the relaxed, deformed cells.
    pub max_displacement: f64,
}

/// The minimiser settings [`by_deformation`] suggests: FIRE with the Newton
/// finish after 100 steps, an energy criterion that never stops it (above jamming `V/N` is not
/// small) and `max_i (∂V/∂q_i)² < 10⁻²⁶`. No L-BFGS, whatever the family
/// (`lbfgs: None`): the 3D dimers' L-BFGS default was measured on the
/// jamming search only; these relaxations of a strained packing and its
/// stabilisation keep the minimiser they were validated with.
pub fn deformation_minimizer() -> FireParams {
    FireParams {
        energy_tol: 1e-300,
        force_tol: 1e-26,
        force_criterion: jamkit_engine::ForceCriterion::Max,
        newton: Some(jamkit_engine::NewtonParams {
            after: 100,
            ..Default::default()
        }),
        lbfgs: jamkit_engine::LbfgsChoice::Off,
        ..FireParams::default()
    }
}

/// Shear and bulk moduli by deformation: the packing of `scene` relaxed in
/// its undeformed cell (as a [`Strained`] with pair margin `margin`), then
/// deformed by `±gamma` (each simple shear, then isotropically) and relaxed
/// again with `fire`; central differences of the stress.
pub fn by_deformation<const D: usize, S: Shape<D>>(
    scene: &Scene<D, S>,
    gamma: f64,
    margin: f64,
    fire: &FireParams,
) -> Result<Deformation> {
    if !(gamma > 0.0 && gamma < 0.01) {
        return Err(Error::invalid(
            "gamma",
            gamma,
            "must lie strictly between 0 and 0.01 (a small strain)",
        ));
    }
    let fire = fire.for_family(&scene.packing().shape);
    fire.validate("minimizer")?;
    deformation_of(Strained::new(scene, margin)?, gamma, &fire)
}

/// [`by_deformation`] of a [`Strained`] cell (e.g. a shear-stabilised
/// packing, [`stabilise`]): the strains `±gamma` act on top of its
/// current deformation.
pub fn by_deformation_strained<const D: usize, S: Shape<D>>(
    cell: &Strained<D, S>,
    gamma: f64,
    fire: &FireParams,
) -> Result<Deformation> {
    if !(gamma > 0.0 && gamma < 0.01) {
        return Err(Error::invalid(
            "gamma",
            gamma,
            "must lie strictly between 0 and 0.01 (a small strain)",
        ));
    }
    let fire = fire.for_family(&cell.shape);
    fire.validate("minimizer")?;
    deformation_of(cell.clone(), gamma, &fire)
}

fn deformation_of<const D: usize, S: Shape<D>>(
    mut base: Strained<D, S>,
    gamma: f64,
    fire: &FireParams,
) -> Result<Deformation> {
    base.rebase();
    Fire::new(fire.clone()).minimize(&mut base)?;
    let pressure = base.pressure();
    let mut max_displacement = base.max_displacement();
    let mut relaxed = |gamma: f64, e: &Matrix<D>| -> Result<Matrix<D>> {
        let mut s = base.clone();
        s.set_strain(gamma, e);
        Fire::new(fire.clone()).minimize(&mut s)?;
        s.check_pairs()?;
        max_displacement = max_displacement.max(s.max_displacement());
        Ok(s.stress())
    };
    let mut planes = Vec::new();
    for (a, b) in shear_planes::<D>() {
        let e = simple_shear::<D>(a, b);
        let plus = relaxed(gamma, &e)?[(a, b)];
        let minus = relaxed(-gamma, &e)?[(a, b)];
        planes.push((plus - minus) / (2.0 * gamma));
    }
    let iso = Matrix::<D>::identity();
    let p = |s: Matrix<D>| -s.trace() / D as f64;
    let (plus, minus) = (p(relaxed(gamma, &iso)?), p(relaxed(-gamma, &iso)?));
    let bulk = -(plus - minus) / (2.0 * D as f64 * gamma);
    Ok(Deformation {
        shear: planes.iter().sum::<f64>() / planes.len().max(1) as f64,
        shear_planes: planes,
        bulk,
        pressure,
        max_displacement,
    })
}

impl<const D: usize, S: Shape<D>> Cell<D> for Strained<D, S> {
    fn body_count(&self) -> usize {
        self.sizes.len()
    }

    fn rot_coordinates(&self) -> usize {
        self.shape.rot_dof()
    }

    fn pair_potential(&self) -> Potential {
        self.potential
    }

    fn cell_volume(&self) -> f64 {
        self.volume()
    }

    fn visit_gap_hessians(
        &mut self,
        visit: &mut dyn FnMut(usize, usize, &Vector<D>, &jamkit_core::GapHessian<D>),
    ) -> Result<()> {
        for &(i, j, r0) in &self.geometry.pairs {
            let (i, j) = (i as usize, j as usize);
            let r = self.separation(i, j, &r0);
            self.shape.gap_hessians(
                &Pair::new(
                    self.sizes[i],
                    self.orientations[i],
                    self.sizes[j],
                    self.orientations[j],
                    r,
                ),
                0.0,
                |c| visit(i, j, &r, &c),
            )?;
        }
        Ok(())
    }

    fn full_hessian(&mut self, rattler: &[bool]) -> Result<Hessian> {
        let (n, k, potential) = (self.body_count(), self.rot_coordinates(), self.potential);
        Hessian::of_contacts::<D>(n, k, potential, rattler, FULL_HESSIAN, |visit| {
            self.visit_gap_hessians(&mut |i, j, _, c| visit(i, j, c))
        })
    }
}

/// An orthonormal basis (under `A : B = Σ A_ab B_ab`) of the symmetric
/// traceless (deviatoric) strains: the `D(D−1)/2` shears
/// `(e_a e_bᵀ + e_b e_aᵀ)/√2`, `a < b`, then the `D − 1` normal ones
/// `diag(1, …, 1, −k, 0, …)/√(k + k²)`, `k = 1 … D−1` (2D: `diag(1, −1)/√2`;
/// 3D: `diag(1, −1, 0)/√2`, `diag(1, 1, −2)/√6`).
pub fn deviatoric_basis<const D: usize>() -> Vec<Matrix<D>> {
    let mut out = Vec::new();
    for (a, b) in shear_planes::<D>() {
        let mut e = Matrix::<D>::zeros();
        e[(a, b)] = std::f64::consts::FRAC_1_SQRT_2;
        e[(b, a)] = std::f64::consts::FRAC_1_SQRT_2;
        out.push(e);
    }
    for k in 1..D {
        let mut e = Matrix::<D>::zeros();
        let norm = ((k + k * k) as f64).sqrt();
        for a in 0..k {
            e[(a, a)] = 1.0 / norm;
        }
        e[(k, k)] = -(k as f64) / norm;
        out.push(e);
    }
    out
}

/// How [`stabilise`] relaxes the cell's shape.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StabiliseParams {
    /// Stop when every deviatoric stress component `|σ : E_k|` is below
    /// `tol · p` and the cell's deviatoric stiffness has no negative
    /// eigenvalue.
    pub tol: f64,
    /// Give up after this many strain steps.
    pub max_iterations: u32,
    /// The largest strain step (Frobenius norm of `δ`); near jamming the
    /// step is also capped at `10 p/μ_max` ([`stabilise`]).
    pub max_step: f64,
    /// The pair list's margin (as for [`by_deformation`]); the pairs are
    /// listed again before every step.
    pub margin: f64,
    /// How each step's stiffness applies `H⁺` (`solver`) and which modes
    /// it leaves out as zero modes (`omega_zero`). Not read from files:
    /// the runner sets them to the `Moduli` observable's, so that the
    /// stabilisation's steps and the moduli of the stabilised cell count
    /// zero modes alike.
    #[serde(skip)]
    pub moduli: ModuliParams,
}

impl Default for StabiliseParams {
    fn default() -> Self {
        Self {
            tol: 1e-6,
            max_iterations: 200,
            max_step: 1e-2,
            margin: 0.1,
            moduli: ModuliParams::default(),
        }
    }
}

impl StabiliseParams {
    /// Whether every field has its default (an experiment file then
    /// leaves the settings out, so packings made before they existed
    /// resume).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !(self.tol > 0.0 && self.tol < 1.0) {
            return Err(Error::invalid(
                format!("{prefix}.tol"),
                self.tol,
                "must lie in (0, 1)",
            ));
        }
        if self.max_iterations == 0 {
            return Err(Error::invalid(
                format!("{prefix}.max_iterations"),
                0,
                "must be at least 1",
            ));
        }
        if !(self.max_step > 0.0 && self.max_step <= 0.05) {
            return Err(Error::invalid(
                format!("{prefix}.max_step"),
                self.max_step,
                "must lie in (0, 0.05]",
            ));
        }
        if !(self.margin > 0.0 && self.margin.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.margin"),
                self.margin,
                "must be positive and finite",
            ));
        }
        self.moduli.validate("observables.Moduli")
    }
}

/// What [`stabilise`] holds fixed besides the particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ensemble {
    /// The volume: the energy is minimised over the deviatoric strains.
    Volume,
    /// The pressure `p*`: the enthalpy `U + p* V` is minimised over every
    /// strain (the deviatoric ones and the dilation).
    Pressure(f64),
}

/// A shear-stabilised packing ([`stabilise`]).
#[derive(Clone, Debug)]
pub struct Stabilised<const D: usize, S: Shape<D>> {
    /// The packing in its relaxed, deformed cell (rebased: strains set on
    /// it act on top of the stabilising deformation).
    pub cell: Strained<D, S>,
    /// The cell's deformation `F` from the box it started in: `det F = 1`
    /// at fixed volume; at fixed pressure (the runner's) the dilation is
    /// free and `det F` is the cell's volume over the box's, not 1.
    pub deformation: Matrix<D>,
    /// `max_k |σ : E_k| / p` at the end.
    pub residual: f64,
    /// The same in the fixed box, relaxed in the cell before any strain.
    pub residual_before: f64,
    /// What was minimised (`U`, or `U + p* V` at fixed pressure) in the
    /// fixed box and at the end.
    pub objective_before: f64,
    /// See `objective_before`.
    pub objective_after: f64,
    /// Energy in the fixed box (relaxed in the cell) and at the end.
    pub energy_before: f64,
    /// See `energy_before`.
    pub energy_after: f64,
    /// Pressure in the fixed box and at the end.
    pub pressure_before: f64,
    /// See `pressure_before`.
    pub pressure_after: f64,
    /// Strain steps taken.
    pub iterations: u32,
    /// The smallest eigenvalue of the deviatoric stiffness `C` at the end.
    pub stiffness_min: f64,
    /// Rattlers of the final cell (by count).
    pub rattler: Vec<bool>,
    /// With `solver: Sparse`, the strain steps whose stiffness fell back to
    /// the dense eigendecomposition: the step (`0`: the stiffness of the
    /// relaxed fixed box) and why (`Moduli::dense_fallback`).
    pub dense_fallbacks: Vec<(u32, String)>,
}

/// The stiffness of a relaxed cell along the strains `basis`: the second
/// derivative per volume of its relaxed energy plus `P V` along
/// `F = I + Σ δ_k E_k`,
/// `C_kl = (A_kl − Ξ_kᵀ H⁺ Ξ_l) / V + P (tr E_k tr E_l − tr E_k E_l)`
/// (`A_kl` by polarisation of the affine terms). At fixed volume (the
/// deviatoric basis, `F` normalised to `det F = 1`) `P` is the cell's own
/// pressure `p` and the last term is `−p δ_kl`: the normalisation's
/// second-order isotropic strain `|δ|²/(2D)` meets `U_γ(I) = −D V p`. At
/// fixed pressure `P = p*`, the enthalpy's `p* V`.
fn deviatoric_stiffness<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
    basis: &[Matrix<D>],
    volume_pressure: f64,
) -> Result<(Vec<Vec<f64>>, Option<String>)> {
    let hessian = cell.full_hessian(rattler)?;
    let n = hessian.size;
    let lambda_zero = params.omega_zero * params.omega_zero;
    let (inverse, fallback) =
        PseudoInverse::of(&hessian, D, lambda_zero, params.solver, LANCZOS_TOL_STEP)?;
    let kk = basis.len();
    let mut single = Vec::new();
    for e in basis {
        single.push(strain_derivatives_of(cell, rattler, &hessian, e)?);
    }
    // `Ξ_kᵀ H⁺ Ξ_l`.
    let mut non_affine = vec![vec![0.0; kk]; kk];
    match &inverse {
        PseudoInverse::Dense(values, vectors) => {
            let coefficients = |xi: &[f64]| -> Vec<f64> {
                (0..n)
                    .map(|m| (0..n).map(|r| vectors[(r, m)] * xi[r]).sum())
                    .collect()
            };
            let c: Vec<Vec<f64>> = single.iter().map(|d| coefficients(&d.xi)).collect();
            for k in 0..kk {
                for l in k..kk {
                    non_affine[k][l] = (0..n)
                        .filter(|&m| values[m] > lambda_zero)
                        .map(|m| c[k][m] * c[l][m] / values[m])
                        .sum();
                }
            }
        }
        PseudoInverse::Sparse(s) => {
            let projected: Vec<Vec<f64>> = (single.iter())
                .map(|d| {
                    let mut xi = d.xi.clone();
                    s.project(&mut xi);
                    xi
                })
                .collect();
            let solved: Vec<Vec<f64>> = projected.iter().map(|xi| s.solve(xi)).collect();
            for k in 0..kk {
                for l in k..kk {
                    non_affine[k][l] = (projected[k].iter().zip(&solved[l]))
                        .map(|(a, b)| a * b)
                        .sum();
                }
            }
        }
    }
    let volume = cell.volume();
    let mut out = vec![vec![0.0; kk]; kk];
    for k in 0..kk {
        for l in k..kk {
            let affine = if k == l {
                single[k].affine
            } else {
                let both = strain_derivatives_of(cell, rattler, &hessian, &(basis[k] + basis[l]))?;
                0.5 * (both.affine - single[k].affine - single[l].affine)
            };
            // `P ∂²det(I + Σ δ E)/∂δ_k∂δ_l = P (tr E_k tr E_l − tr E_k E_l)`.
            let volume_term = volume_pressure
                * (basis[k].trace() * basis[l].trace() - (basis[k] * basis[l]).trace());
            let v = (affine - non_affine[k][l]) / volume + volume_term;
            out[k][l] = v;
            out[l][k] = v;
        }
    }
    Ok((out, fallback))
}

/// The stiffness `C_kl` of a relaxed cell along the strains `basis`, as
/// [`stabilise`] uses it in each step (`volume_pressure` the `P` there:
/// the cell's pressure at fixed volume, `p*` at fixed pressure), with the
/// reason when `params.solver` is `Sparse` and the dense path was taken.
pub fn stiffness_tensor<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
    basis: &[Matrix<D>],
    volume_pressure: f64,
) -> Result<(Vec<Vec<f64>>, Option<String>)> {
    params.validate("moduli")?;
    deviatoric_stiffness(cell, rattler, params, basis, volume_pressure)
}

/// Eigenvalues (ascending) and eigenvectors (columns) of a small symmetric
/// matrix.
fn symmetric_eigen(m: &[Vec<f64>]) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
    let n = m.len();
    let a = faer::Mat::<f64>::from_fn(n, n, |r, c| m[r][c]);
    let evd = a
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
    let values = (0..n).map(|k| evd.S()[k]).collect();
    let vectors = (0..n)
        .map(|k| (0..n).map(|r| evd.U()[(r, k)]).collect())
        .collect();
    Ok((values, vectors))
}

/// Relax a cell at fixed deformation (the cell lists its pairs again as
/// bodies move, [`Strained`]); fails when the last step moved a body too
/// far for its list ([`Strained::check_pairs`]).
fn relax_cell<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    fire: &FireParams,
) -> Result<()> {
    Fire::new(fire.clone()).minimize(cell)?;
    cell.check_pairs()
}

/// `V/N` at or below which a stabilised cell counts as unjammed (the
/// jamming window's upper edge, `protocol.energy_high`'s default).
const UNJAMMED: f64 = 2e-16;

/// Shear-stabilise a relaxed packing (Dagois-Bohy, Tighe, Simon, Henkes &
/// van Hecke, PRL 109, 095703, 2012): minimise its energy over the
/// coordinates **and** the cell's shape, at fixed volume (or its enthalpy
/// `U + p* V` at fixed pressure, the cell's volume free too), so that the
/// deviatoric stress vanishes (and `p = p*`) and the packing is stable to
/// every small deformation; then every shear modulus is `≥ 0`.
///
/// The cell is a [`Strained`] one (the engine's box is orthorhombic and
/// cannot be sheared); its deformation ranges over all `D(D+1)/2 − 1`
/// deviatoric strains ([`deviatoric_basis`]), and at fixed pressure also
/// over the dilation `E_0 = I/√D`. Alternating: relax the coordinates at
/// fixed cell; list the pairs again; from the generalised stress
/// `s_k = σ : E_k + p* tr E_k` and the stiffness `C` (`deviatoric_stiffness`)
/// take the step `δ = −Σ_m w_m (w_m·s)/μ_m` over the eigenpairs `(μ_m, w_m)`
/// of `C` with `μ_m > 0`, and the cap down the slope along those with
/// `μ_m ≤ 0`; cap `|δ|` at `min(max_step, max(10 p/μ_max, t))` (`μ_max`
/// the largest eigenvalue of `C`; `t` twice the last step's cap if it was
/// taken whole, else the step taken); deform the cell by
/// `F = I + Σ δ_k E_k` (at fixed volume divided by `det(…)^{1/D}`), relax,
/// and keep the step if the minimised function did not rise (by more than
/// 10⁻¹² relative round-off), else halve it (up to 20 times). Stops when
/// every `|s_k| < tol · p` (`p*` at fixed pressure) and `C` has no
/// negative eigenvalue. At fixed volume a packing can unjam (its energy
/// falls to zero: `V/N ≤ 2·10⁻¹⁶`), which is an error. `threshold`: the
/// rattler count rule.
pub fn stabilise<const D: usize, S: Shape<D>>(
    scene: &Scene<D, S>,
    threshold: usize,
    ensemble: Ensemble,
    params: &StabiliseParams,
    fire: &FireParams,
) -> Result<Stabilised<D, S>> {
    params.validate("stabilise")?;
    let fire = fire.for_family(&scene.packing().shape);
    fire.validate("minimizer")?;
    let mut basis = deviatoric_basis::<D>();
    let external = match ensemble {
        Ensemble::Volume => None,
        Ensemble::Pressure(p) => {
            if !(p > 0.0 && p.is_finite()) {
                return Err(Error::invalid(
                    "pressure",
                    p,
                    "the pressure of a stabilisation at fixed pressure must be positive and finite",
                ));
            }
            basis.insert(0, Matrix::<D>::identity() / (D as f64).sqrt());
            Some(p)
        }
    };
    let bodies = scene.packing().len().max(1) as f64;
    let mut cell = Strained::new(scene, params.margin)?;
    relax_cell(&mut cell, &fire)?;
    let objective = |c: &Strained<D, S>| c.energy() + external.map_or(0.0, |p| p * c.volume());
    let energy_before = cell.energy();
    let objective_before = objective(&cell);
    let pressure_before = cell.pressure();
    if !(pressure_before > 0.0) {
        return Err(Error::invalid(
            "pressure",
            pressure_before,
            "shear stabilisation needs a packing under positive pressure (jammed)",
        ));
    }
    let stress = |c: &Strained<D, S>| -> Vec<f64> {
        let sigma = c.stress();
        (basis.iter())
            .map(|e| sigma.component_mul(e).sum() + external.map_or(0.0, |p| p * e.trace()))
            .collect()
    };
    let largest = |s: &[f64]| s.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let residual_before = largest(&stress(&cell)) / external.unwrap_or(pressure_before);
    let mut value = objective_before;
    let mut iterations = 0;
    let mut trust = 0.0_f64;
    let mut dense_fallbacks = Vec::new();
    loop {
        cell.relist()?;
        let rattler = cell.rattlers(threshold);
        let s = stress(&cell);
        let pressure = cell.pressure();
        let reference = external.unwrap_or(pressure);
        let (stiffness, fell_back) =
            deviatoric_stiffness(&mut cell, &rattler, &params.moduli, &basis, reference)?;
        dense_fallbacks.extend(fell_back.map(|why| (iterations, why)));
        let (mu, w) = symmetric_eigen(&stiffness)?;
        let residual = largest(&s) / reference;
        let stiffness_min = mu.first().copied().unwrap_or(0.0);
        let per_body = cell.energy() / bodies;
        if external.is_none() && !(per_body > UNJAMMED && pressure > 0.0) {
            return Err(Error::JammingFailed {
                phi: cell.phi,
                steps: iterations as u64,
                reason: format!(
                    "the packing unjammed while its cell's shape relaxed at fixed volume (V/N = {per_body:.3e} after {iterations} strain steps, from {:.3e}): shear stabilisation at fixed volume lowered the energy to zero",
                    energy_before / bodies
                ),
            });
        }
        if residual < params.tol && stiffness_min >= 0.0 {
            let deformation = cell.total_deformation();
            return Ok(Stabilised {
                energy_after: cell.energy(),
                objective_after: objective(&cell),
                cell,
                deformation,
                residual,
                residual_before,
                objective_before,
                energy_before,
                pressure_before,
                pressure_after: pressure,
                iterations,
                stiffness_min,
                rattler,
                dense_fallbacks,
            });
        }
        if iterations >= params.max_iterations {
            return Err(Error::JammingFailed {
                phi: cell.phi,
                steps: iterations as u64,
                reason: format!(
                    "shear stabilisation did not converge in {} strain steps (stress residual {residual:.3e} p, tolerance {:e}; smallest stiffness {stiffness_min:.3e})",
                    params.max_iterations, params.tol
                ),
            });
        }
        // The strain cap: `max_step`, and near jamming `10 p/μ_max`, ten
        // times the strain that changes the overlaps by their own size
        // (`μ_max` the stiffest strain's modulus, ~B): a larger kick along
        // a soft or unstable strain rearranges (or unjams) the packing.
        // Grown by 2 after a step taken whole (a trust region), so that a
        // long way down a soft strain takes few steps.
        let stiffest = mu.last().copied().unwrap_or(0.0);
        let base = if stiffest > 0.0 {
            params.max_step.min(10.0 * reference / stiffest)
        } else {
            params.max_step
        };
        let cap = trust.max(base).min(params.max_step);
        let mut step = vec![0.0; basis.len()];
        for (m, wm) in w.iter().enumerate() {
            let along: f64 = wm.iter().zip(&s).map(|(a, b)| a * b).sum();
            let size = if mu[m] > 0.0 {
                -along / mu[m]
            } else {
                // Down the slope (or either way on a flat one) by the cap.
                -cap * if along > 0.0 { 1.0 } else { -1.0 }
            };
            for (x, wk) in step.iter_mut().zip(wm) {
                *x += size * wk;
            }
        }
        let norm = step.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > cap {
            step.iter_mut().for_each(|x| *x *= cap / norm);
        }
        let mut accepted = false;
        for halvings in 0..20 {
            let mut f = Matrix::<D>::identity();
            for (x, e) in step.iter().zip(&basis) {
                f += e * *x;
            }
            if external.is_none() {
                f /= determinant(&f).powf(1.0 / D as f64);
            }
            let mut trial = cell.clone();
            trial.set_deformation(f);
            // The pairs of the deformed cell before it relaxes (a strain
            // of `|δ|` moves a pair's separation by `|δ| r`).
            if trial.relist().is_ok() && relax_cell(&mut trial, &fire).is_ok() {
                let v = objective(&trial);
                if v <= value + 1e-12 * value.abs() {
                    cell = trial;
                    value = v;
                    accepted = true;
                    trust = if halvings == 0 {
                        2.0 * cap
                    } else {
                        cap * 0.5_f64.powi(halvings)
                    };
                    break;
                }
            }
            step.iter_mut().for_each(|x| *x *= 0.5);
        }
        if !accepted {
            return Err(Error::JammingFailed {
                phi: cell.phi,
                steps: iterations as u64,
                reason: format!(
                    "shear stabilisation found no strain step that lowers the energy (stress residual {residual:.3e} p, smallest stiffness {stiffness_min:.3e})"
                ),
            });
        }
        iterations += 1;
    }
}
