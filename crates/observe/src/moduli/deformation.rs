//! The check by deformation: the moduli as slopes of the stress of
//! [`Strained`] cells relaxed at `±γ`.

use jamkit_core::{Error, Matrix, Result, Shape};
use jamkit_engine::{Fire, FireParams, Scene};

use super::*;

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
    let fire = fire.for_family(cell.shape());
    fire.validate("minimizer")?;
    deformation_of(cell.clone(), gamma, &fire)
}

pub(super) fn deformation_of<const D: usize, S: Shape<D>>(
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
