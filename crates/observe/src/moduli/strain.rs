//! The stress tensor and the strain derivatives of the energy (module
//! documentation of [`super`]).

use crate::hessian::{Hessian, HessianOptions};
use jamkit_core::{Error, Matrix, Potential, Result, Shape, Vector};
use jamkit_engine::Scene;
pub use jamkit_engine::cell::{shear_planes, simple_shear};

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
pub(super) fn contact_strain<const D: usize>(
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
pub(super) trait Cell<const D: usize> {
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

pub(super) const FULL_HESSIAN: HessianOptions = HessianOptions {
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

pub(super) fn strain_derivatives_of<const D: usize, C: Cell<D>>(
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
pub(super) fn first_rows(hessian: &Hessian, bodies: usize) -> Vec<u32> {
    let mut first = vec![u32::MAX; bodies];
    for (row, &b) in hessian.body.iter().enumerate().rev() {
        if let Some(f) = first.get_mut(b as usize) {
            *f = row as u32;
        }
    }
    first
}
