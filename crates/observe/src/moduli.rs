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
use crate::spectrum::ZeroModes;
use jamkit_core::{Error, Matrix, Packing, Potential, Result, Shape, Vector};
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
    let k = scene.packing().shape.rot_dof();
    let stride = D + k;
    let first_row = first_rows(hessian, scene.packing().len());
    let rattles = |i: usize| rattler.get(i).copied().unwrap_or(false);
    let potential = scene.potential();
    let mut out = StrainDerivatives {
        first: 0.0,
        affine: 0.0,
        xi: vec![0.0; hessian.size],
    };
    let mut local = vec![0.0; 2 * stride];
    let mut missing = None;
    // The separation of each visited pair: `for_each_gap_hessian` does not
    // pass it, so it is recomputed here as the scene's pair loop does.
    let positions = scene.packing().positions.clone();
    let bbox = scene.packing().bbox.clone();
    scene.for_each_gap_hessian(0.0, |i, j, c| {
        if rattles(i) || rattles(j) {
            return;
        }
        let r = bbox.minimum_image(positions[j] - positions[i]);
        let (first, affine) = contact_strain(potential, c, &r, e, k, &mut local);
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

/// How the moduli are computed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModuliParams {
    /// Modes with `ω = √λ` at or below this are zero modes, left out of
    /// `H⁺` (the same threshold as the spectrum's `dos.omega_zero`).
    pub omega_zero: f64,
}

impl Default for ModuliParams {
    fn default() -> Self {
        Self { omega_zero: 1e-5 }
    }
}

impl ModuliParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !(self.omega_zero > 0.0 && self.omega_zero.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.omega_zero"),
                self.omega_zero,
                "must be positive and finite",
            ));
        }
        Ok(())
    }
}

/// The elastic moduli of one packing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Moduli {
    /// `G`: the mean of `shear_planes`.
    pub shear: f64,
    /// `G_ab` for the planes `(0,1)` in 2D; `(0,1)`, `(0,2)`, `(1,2)` in 3D.
    pub shear_planes: Vec<f64>,
    /// `B = −V dp/dV`.
    pub bulk: f64,
    /// The affine parts `A/V` (mean over planes) of `G` …
    pub shear_affine: f64,
    /// … and `A/(D²V) + (D−1)p/D` of `B`.
    pub bulk_affine: f64,
    /// `p = −tr σ / D`.
    pub pressure: f64,
    /// Rows of the Hessian (rattlers removed).
    pub coordinates: usize,
    /// Zero modes (`ω ≤ omega_zero`, negative `λ` included, as the
    /// spectrum counts them); rattlers are removed, so `rattlers` is 0.
    pub zero_modes: ZeroModes,
    /// Modes with `λ < −omega_zero²`: the state is a saddle, not a minimum,
    /// and the moduli of the positive modes alone do not describe it.
    pub negative_modes: u64,
    /// The largest share of `|Ξ|²` (over the strains) on zero modes other
    /// than translations: a strain that such a floppy mode accommodates
    /// meets no resistance there, which `H⁺` leaves out.
    pub floppy_share: f64,
    /// For the plane of the smallest `G_ab`, the share of its non-affine
    /// term `Ξᵀ H⁺ Ξ` carried by the softest mode above the zero modes
    /// (`λ_1`, the smallest `λ > omega_zero²`). `G_ab` without that mode
    /// is `G_ab + soft_share · (non-affine term)/V`: even a small share can
    /// be what makes a small `G_ab` negative (docs/elasticity.md,
    /// "Negative G"). `None` in packing files written before it was
    /// measured, and with no mode above the zero modes.
    #[serde(default)]
    pub soft_share: Option<f64>,
}

impl Moduli {
    /// The smallest plane modulus `G_ab` (`G` in 2D): negative when the
    /// packing, stable at fixed box, is unstable to the shear of that plane.
    pub fn shear_min(&self) -> f64 {
        self.shear_planes
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }
}

/// The linear-response moduli of a relaxed scene; `rattler` marks the
/// rattlers, whose rows and contacts are removed.
pub fn measure<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
) -> Result<Moduli> {
    params.validate("moduli")?;
    let options = HessianOptions {
        stiffness_only: false,
        remove_rattlers: true,
    };
    let hessian = Hessian::of_scene(scene, rattler, options)?;
    let n = hessian.size;
    let volume = scene.packing().bbox.volume();
    let lambda_zero = params.omega_zero * params.omega_zero;
    let (values, vectors) = if n == 0 {
        (Vec::new(), faer::Mat::<f64>::zeros(0, 0))
    } else {
        let evd = hessian
            .dense()
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
        let values: Vec<f64> = (0..n).map(|m| evd.S()[m]).collect();
        (values, evd.U().to_owned())
    };
    // The softest mode above the zero modes (eigenvalues ascend).
    let softest = values.iter().position(|&l| l > lambda_zero);
    // `U_min'' = A − Σ_{λ > λ0} (u·Ξ)²/λ`, the share of `|Ξ|²` on the
    // zero modes (translations carry none: Ξ sums to zero over bodies) and
    // the share of the non-affine term on the softest mode.
    let relaxed = |d: &StrainDerivatives| -> (f64, f64, Option<f64>) {
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
    };
    let mut floppy_share: f64 = 0.0;
    let planes = shear_planes::<D>();
    let mut per_plane = Vec::new();
    let mut shear_affine = 0.0;
    let mut soft_share = None;
    for &(a, b) in &planes {
        let d = strain_derivatives(scene, rattler, &hessian, &simple_shear::<D>(a, b))?;
        let (c, share, soft) = relaxed(&d);
        floppy_share = floppy_share.max(share);
        if per_plane.iter().all(|&g| c / volume < g) {
            soft_share = soft;
        }
        per_plane.push(c / volume);
        shear_affine += d.affine / volume / planes.len() as f64;
    }
    let d = strain_derivatives(scene, rattler, &hessian, &Matrix::<D>::identity())?;
    let (c, share, _) = relaxed(&d);
    floppy_share = floppy_share.max(share);
    let dd = (D * D) as f64;
    // `U_γ = Σ v' g·r = −D V p` for `E = I`.
    let pressure = -d.first / (D as f64 * volume);
    let stress_term = (D as f64 - 1.0) * pressure / D as f64;
    let total = values.iter().filter(|&&l| l <= lambda_zero).count() as u64;
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
        negative_modes: values.iter().filter(|&&l| l < -lambda_zero).count() as u64,
        floppy_share,
        soft_share,
    })
}

/// A packing in a homogeneously deformed periodic cell, with the pairs and
/// image vectors of the undeformed one fixed: the separation of pair `ij`
/// is `F R_ij + u_j − u_i`, `R_ij` its minimum image when it was built and
/// `u` the displacements since. An [`Objective`] in the same coordinates
/// as the [`Scene`] it was built from (translations then rotations, body
/// by body), with the same Hessian, so the engine's minimisers relax it.
#[derive(Clone, Debug)]
pub struct Strained<const D: usize, S: Shape<D>> {
    shape: S,
    potential: Potential,
    sizes: Vec<f64>,
    orientations: Vec<S::Orientation>,
    displacement: Vec<Vector<D>>,
    saved: (Vec<Vector<D>>, Vec<S::Orientation>),
    pairs: Vec<(u32, u32, Vector<D>)>,
    deformation: Matrix<D>,
    volume: f64,
    inverse_masses: Vec<f64>,
    margin: f64,
    phi: f64,
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
            displacement: vec![Vector::<D>::zeros(); p.len()],
            saved: (Vec::new(), Vec::new()),
            pairs,
            deformation: Matrix::<D>::identity(),
            volume: p.bbox.volume(),
            inverse_masses: p.inverse_masses(),
            margin,
            phi: p.phi(),
        })
    }

    /// Deform the cell to `F = I + γ E` (the displacements are kept).
    pub fn set_strain(&mut self, gamma: f64, e: &Matrix<D>) {
        self.deformation = Matrix::<D>::identity() + e * gamma;
    }

    /// The cell's volume, `V₀ det F`.
    pub fn volume(&self) -> f64 {
        self.volume * determinant(&self.deformation)
    }

    /// The largest displacement of a centre since the pairs were listed.
    pub fn max_displacement(&self) -> f64 {
        self.displacement
            .iter()
            .map(|u| u.norm())
            .fold(0.0, f64::max)
    }

    /// Fail when some body moved so far that a pair missing from the list
    /// could touch (or an image vector could have changed).
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

    /// Visit every contact of the strained cell as `(i, j, r0, r, contact)`:
    /// `r0` the pair's separation in the cell as built, `r` the strained
    /// one.
    fn visit<F>(&self, mut visit: F)
    where
        F: FnMut(usize, usize, &Vector<D>, &Vector<D>, &jamkit_core::Contact<D>),
    {
        for &(i, j, r0) in &self.pairs {
            let (i, j) = (i as usize, j as usize);
            let r = self.deformation * r0 + self.displacement[j] - self.displacement[i];
            self.shape.contacts(
                self.sizes[i],
                &self.orientations[i],
                self.sizes[j],
                &self.orientations[j],
                &r,
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

    fn displace(&mut self, dq: &[f64]) {
        let stride = D + self.shape.rot_dof();
        for (i, chunk) in dq.chunks_exact(stride).enumerate() {
            for a in 0..D {
                self.displacement[i][a] += chunk[a];
            }
            if stride > D {
                self.shape.rotate(&mut self.orientations[i], &chunk[D..]);
            }
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
        for &(i, j, r0) in &self.pairs {
            let (iu, ju) = (i as usize, j as usize);
            let r = self.deformation * r0 + self.displacement[ju] - self.displacement[iu];
            let outcome = self.shape.gap_hessians(
                self.sizes[iu],
                &self.orientations[iu],
                self.sizes[ju],
                &self.orientations[ju],
                &r,
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

    fn save(&mut self) {
        self.saved.0.clone_from(&self.displacement);
        self.saved.1.clone_from(&self.orientations);
    }

    fn restore(&mut self) {
        self.displacement.clone_from(&self.saved.0);
        self.orientations.clone_from(&self.saved.1);
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
/// small) and `max_i (∂V/∂q_i)² < 10⁻²⁶`.
pub fn deformation_minimizer() -> FireParams {
    FireParams {
        energy_tol: 1e-300,
        force_tol: 1e-26,
        force_criterion: jamkit_engine::ForceCriterion::Max,
        newton: Some(jamkit_engine::NewtonParams {
            after: 100,
            ..Default::default()
        }),
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
    let mut base = Strained::new(scene, margin)?;
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
