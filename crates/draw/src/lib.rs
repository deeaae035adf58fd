//! # Pictures of packings and shapes
//!
//! `jamkit-draw` turns a 2D packing file (`packings/<id>.json`) into an SVG
//! or PNG picture of every body's true outline in the periodic box, a 3D
//! one into a shaded orthographic ray-cast of the box seen along `z`
//! ([`scene3d`], [`render3d`]), and draws polar plots
//! `R(θ)/R⁰ = 1 + Δ F(θ)` of near-disk shapes (shaded bodies in 3D). It backs
//! the `jamkit draw` and `jamkit draw-shape` commands (`docs/how-to/draw.md`).
//!
//! The crate is split in two layers:
//!
//! * geometry, free of any plotting: [`geometry`] (outlines of the
//!   families, periodic images, clipping to the box), [`packing`] (a
//!   packing file as bodies with outlines), [`scene3d`] (a 3D packing file
//!   as bodies, and the ray-cast), [`shapes`] (the curves of a shape plot)
//!   and [`colors`] (fill colours by size);
//! * plotting with `plotters`: [`render`] (SVG and PNG output) and
//!   [`render3d`] (shading, the 3D pictures, the ray-cast embedded in SVG
//!   as a PNG image).
//!
//! Packing pictures carry text only in their colour key; shape panels have titles, axes and
//! legends, drawn (in PNG) and measured (in SVG) with the bundled DejaVu
//! Sans ([`fonts`]).

pub mod colors;
pub mod fonts;
pub mod geometry;
pub mod packing;
pub mod render;
pub mod render3d;
pub mod scene3d;
pub mod shapes;

use std::path::PathBuf;

/// Everything that can go wrong while drawing; each message names the fix.
#[derive(Debug, thiserror::Error)]
pub enum DrawError {
    /// A file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error (shown in the message, not chained).
        error: std::io::Error,
    },
    /// A packing file is not valid JSON of the expected form.
    #[error("{path}: not a packing file: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What the JSON reader said.
        message: String,
    },
    /// The packing is neither two- nor three-dimensional (or not the
    /// dimension a reader expects).
    #[error("dim = {0}: only 2D and 3D packings can be drawn")]
    Dimension(usize),
    /// A family this crate does not know how to draw in this dimension.
    #[error(
        "family `{0}` in dim {1}: cannot draw it (drawn are 2D shapes with an outline, 3D balls, 3D shapes with a surface, and bodies made of spheres; see `jamkit shapes`)"
    )]
    UnknownFamily(String, usize),
    /// The family's parameters do not describe a valid shape.
    #[error("params (family `{family}`): {message}")]
    Params {
        /// Family name.
        family: String,
        /// What is wrong.
        message: String,
    },
    /// The arrays of a packing file do not fit together (lengths, finiteness).
    #[error("{0}")]
    Inconsistent(String),
    /// An output file name whose extension is not `.svg` or `.png`.
    #[error("{path}: {message}")]
    Format {
        /// The output file.
        path: PathBuf,
        /// Which extensions are accepted.
        message: String,
    },
    /// An image size outside the accepted range.
    #[error(
        "--size = {0}: must lie in {min}..={max} pixels",
        min = render::MIN_SIZE,
        max = render::MAX_SIZE
    )]
    Size(u32),
    /// The plotting library failed.
    #[error("drawing {path}: {message}")]
    Render {
        /// The output file (empty when drawing to a string).
        path: PathBuf,
        /// The library's message.
        message: String,
    },
}

/// How a registered family is drawn in `dim`: the family's shape, built
/// from `params` as an experiment file gives them (defaults filled in),
/// handed to `drawing` (a visitor that asks the shape for its drawing
/// capability, `None` when it has none). Every error names the family.
pub(crate) fn drawing_of<V, T>(
    family: &str,
    dim: usize,
    params: &jamkit_registry::ParamMap,
    drawing: V,
) -> Result<T, DrawError>
where
    V: jamkit_registry::SceneVisitor<Output = Option<T>>,
{
    use jamkit_registry as registry;
    let bad = |e: jamkit_core::Error| params_error(family, e);
    let info = registry::family_info(family).map_err(bad)?;
    if !registry::supports_dim(&info, dim) {
        return Err(DrawError::UnknownFamily(family.to_string(), dim));
    }
    let params = registry::with_defaults(&info, params);
    registry::dispatch(family, dim, &params, drawing)
        .map_err(bad)?
        .ok_or_else(|| DrawError::UnknownFamily(family.to_string(), dim))
}

/// [`drawing_of`] from the parameters a packing file stores (JSON).
pub(crate) fn drawing_from_json<V, T>(
    family: &str,
    dim: usize,
    params: &serde_json::Value,
    drawing: V,
) -> Result<T, DrawError>
where
    V: jamkit_registry::SceneVisitor<Output = Option<T>>,
{
    let params = jamkit_registry::params_from_json(params).map_err(|e| params_error(family, e))?;
    drawing_of(family, dim, &params, drawing)
}

/// A family's parameters refused, named.
fn params_error(family: &str, e: jamkit_core::Error) -> DrawError {
    DrawError::Params {
        family: family.to_string(),
        message: e.to_string(),
    }
}

pub use geometry::{Outline, Point};
pub use packing::{Body, Packing2d, Piece};
pub use render::{Format, draw_packing, draw_shapes, packing_svg, shapes_svg};
pub use render3d::{draw_bodies, draw_packing_3d, packing_3d_svg};
pub use scene3d::Packing3d;
pub use shapes::{ShapeCurve, ShapePanel};
