//! A packing file back in memory: its family, box, bodies and potential as
//! a typed [`Scene`], so that a saved packing can be analysed later (its
//! spectrum, its gaps) without being made again.
//!
//! The file holds the family's parameters, the box edges, every centre,
//! size and orientation, and the settings it was made with (potential,
//! Verlet skin). Orientations come back through the family's
//! `BodyOrientation::from_coords`, so they agree with the ones in memory only to
//! the last bit or two (an angle is stored, not its cosine and sine); the
//! runner therefore measures a new packing on the scene rebuilt here from
//! its file (`sample::measure_saved`), so that a re-measure is bit for bit.

use crate::error::ExperimentError;
use crate::schema::EngineParams;
use jamkit_core::BodyOrientation;
use jamkit_core::{Packing, PeriodicBox, Potential, Shape, Vector};
use jamkit_engine::Scene;
use jamkit_format::PackingFile;
use jamkit_registry::{self as registry, SceneVisitor};

/// How far the packing fraction of a reloaded packing may differ from the
/// one its file records, relative. The file records φ computed from the
/// same box edges, sizes and family volume, and its numbers read back to
/// the same bits, so the two agree to the rounding of the volume sum (a
/// few ulps, `~10⁻¹⁵`, for a file from `jamkit analyze`, which sums the
/// volumes by its own formula; exactly for a file jamkit made). `10⁻⁹`
/// leaves six orders of magnitude for that rounding, and a file that
/// passes holds its φ to far better than a jamming search resolves it.
pub const PHI_TOLERANCE: f64 = 1e-9;

/// Something to do with a reloaded scene.
pub trait PackingVisitor {
    /// What the visit returns.
    type Output;
    /// Called with the scene of the packing file.
    fn visit<const D: usize, S: Shape<D>>(self, scene: Scene<D, S>) -> Self::Output;
}

/// Rebuild the scene of `file` and hand it to `visitor`: the family's
/// shape built from the parameters the file records.
pub fn reload<V: PackingVisitor>(
    file: &PackingFile,
    visitor: V,
) -> Result<V::Output, ExperimentError> {
    let params = registry::params_from_json(&file.params).map_err(|e| {
        ExperimentError::invalid(
            format!("packing {}: params", file.id),
            "…",
            format!("not a family parameter map: {e}"),
        )
    })?;
    let builder = Builder { file, visitor };
    registry::dispatch(&file.family, file.dim, &params, builder)?
}

struct Builder<'a, V> {
    file: &'a PackingFile,
    visitor: V,
}

impl<V: PackingVisitor> SceneVisitor for Builder<'_, V> {
    type Output = Result<V::Output, ExperimentError>;

    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Self::Output {
        Ok(self.visitor.visit(scene_of(shape, self.file)?))
    }
}

/// The scene of `file` on `shape` (the shape of the family and parameters
/// the file records): its box, bodies, potential and Verlet skin, checked
/// against the φ the file records.
pub(crate) fn scene_of<const D: usize, S: Shape<D>>(
    shape: S,
    f: &PackingFile,
) -> Result<Scene<D, S>, ExperimentError> {
    let bad = |field: &str, allowed: String| {
        ExperimentError::invalid(format!("packing {}: {field}", f.id), "…", allowed)
    };
    if f.positions.len() != f.particles || f.radii.len() != f.particles {
        return Err(bad(
            "positions",
            format!(
                "the file holds no configuration for its {} bodies (was it written with output.packings = false?)",
                f.particles
            ),
        ));
    }
    let setting = |key: &str| f.settings.get(key).cloned().unwrap_or_default();
    let potential: Potential = serde_json::from_value(setting("potential")).unwrap_or_default();
    let engine: EngineParams = serde_json::from_value(setting("engine")).unwrap_or_default();
    let vector = |xs: &[f64], what: &str| -> Result<Vector<D>, ExperimentError> {
        if xs.len() != D || xs.iter().any(|x| !x.is_finite()) {
            return Err(bad(what, format!("must hold {D} finite numbers per entry")));
        }
        Ok(Vector::<D>::from_column_slice(xs))
    };
    let bbox = PeriodicBox::new(vector(&f.box_edges, "box")?);
    let positions = f
        .positions
        .iter()
        .map(|r| vector(r, "positions"))
        .collect::<Result<Vec<_>, _>>()?;
    let orientations = if shape.rot_dof() == 0 {
        vec![S::Orientation::reference(); f.particles]
    } else {
        if f.orientations.len() != f.particles {
            return Err(bad(
                "orientations",
                format!("must hold one entry per body ({})", f.particles),
            ));
        }
        f.orientations
            .iter()
            .map(|o| {
                S::Orientation::from_coords(o).ok_or_else(|| {
                    bad(
                        "orientations",
                        format!("{o:?} is not an orientation of family `{}`", f.family),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?
    };
    let min_reach = f
        .radii
        .iter()
        .map(|&s| shape.bounding_radius(s))
        .fold(f64::INFINITY, f64::min);
    let packing = Packing {
        shape,
        bbox,
        positions,
        orientations,
        sizes: f.radii.clone(),
    };
    // The box, the sizes and the family's volume give the φ the file
    // records: a box or a size changed after the file was written (by
    // hand, or a corrupted copy) is refused before anything is
    // computed on it.
    let phi = packing.phi();
    if !((phi - f.phi).abs() <= PHI_TOLERANCE * f.phi.abs()) {
        return Err(ExperimentError::invalid(
            format!("packing {}: phi", f.id),
            f.phi,
            format!(
                "the file's box {:?}, sizes and family `{}` give phi = {phi:e} (relative difference {:.1e}, more than {PHI_TOLERANCE:e}): its box or its sizes are not the ones it was written with",
                f.box_edges,
                f.family,
                (phi - f.phi).abs() / f.phi.abs()
            ),
        ));
    }
    Ok(Scene::new(packing, potential, engine.skin * min_reach))
}
