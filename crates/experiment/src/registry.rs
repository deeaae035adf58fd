//! The registry: every shape family jamkit knows, in one readable list.
//!
//! Adding a family means one entry in [`FAMILIES`] and one arm in
//! [`dispatch`]; nothing else in the engine changes. `dispatch` is the one
//! place where a family name from a file becomes a typed shape `S` in a
//! const dimension `D`, after which everything is statically dispatched.

use crate::error::ExperimentError;
use jamkit_core::{Dims, FamilyInfo, Shape};
use serde::de::DeserializeOwned;
use std::collections::BTreeMap;

/// Parameters of one grid point, by name.
pub type ParamMap = BTreeMap<String, ron::Value>;

/// Every registered family.
pub const FAMILIES: &[FamilyInfo] = &[
    jamkit_sphere::INFO,
    jamkit_fourier::FOURIER_INFO,
    jamkit_fourier::FOURIER_SUM_INFO,
    jamkit_lobed::INFO,
    jamkit_nmer::INFO,
    jamkit_ellipse::INFO,
];

/// Dimensions the engine is compiled for (families with `Dims::Any`).
pub const COMPILED_DIMS: &[usize] = &[2, 3, 4];

/// Something to do with a typed shape: run a sample, draw, analyse, …
pub trait SceneVisitor {
    /// What the visit returns.
    type Output;
    /// Called with the family's shape in dimension `D`.
    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Self::Output;
}

/// The family called `name`.
pub fn family_info(name: &str) -> Result<FamilyInfo, ExperimentError> {
    FAMILIES
        .iter()
        .copied()
        .find(|f| f.name == name)
        .ok_or_else(|| {
            let known: Vec<&str> = FAMILIES.iter().map(|f| f.name).collect();
            ExperimentError::invalid(
                "family",
                format!("\"{name}\""),
                format!("must be one of: {}", known.join(", ")),
            )
        })
}

/// Whether `info` can run in dimension `dim`.
pub fn supports_dim(info: &FamilyInfo, dim: usize) -> bool {
    match info.dims {
        Dims::Any => COMPILED_DIMS.contains(&dim),
        Dims::Only(dims) => dims.contains(&dim),
    }
}

/// "dim 2 or 3", for messages.
pub fn describe_dims(info: &FamilyInfo) -> String {
    let dims = match info.dims {
        Dims::Any => COMPILED_DIMS,
        Dims::Only(d) => d,
    };
    let list: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
    format!("dim {}", list.join(" or "))
}

/// Read a family's parameter struct from the grid point's values.
pub fn parse_params<T: DeserializeOwned>(
    family: &str,
    params: &ParamMap,
) -> Result<T, ExperimentError> {
    let read = |skip: Option<&str>| -> Result<T, ron::Error> {
        let map: ron::Map = params
            .iter()
            .filter(|(k, _)| Some(k.as_str()) != skip)
            .map(|(k, v)| (ron::Value::String(k.clone()), v.clone()))
            .collect();
        ron::Value::Map(map).into_rust()
    };
    read(None).map_err(|e| {
        let message = e.to_string();
        // NOTE: serde names no field when a value has the wrong type (an
        // optional parameter read leniently says only "did not match any
        // variant"); the field is the one whose removal makes that error go.
        let culprit = params
            .iter()
            .find(|(k, _)| read(Some(k)).map_or_else(|e| e.to_string() != message, |_| true));
        match culprit {
            Some((name, value)) => {
                let about = family_info(family)
                    .ok()
                    .and_then(|info| info.param(name).map(|p| p.about))
                    .unwrap_or("see `jamkit shapes`");
                ExperimentError::invalid(
                    format!("params.{name} (family `{family}`)"),
                    ron::to_string(value).unwrap_or_default(),
                    format!("{message}; {name}: {about}"),
                )
            }
            None => ExperimentError::invalid(
                format!("params (family `{family}`)"),
                ron::to_string(params).unwrap_or_default(),
                message,
            ),
        }
    })
}

/// Build the family's shape for one grid point and hand it to `visitor` in
/// the right dimension.
pub fn dispatch<V: SceneVisitor>(
    family: &str,
    dim: usize,
    params: &ParamMap,
    visitor: V,
) -> Result<V::Output, ExperimentError> {
    let info = family_info(family)?;
    if !supports_dim(&info, dim) {
        return Err(ExperimentError::invalid(
            "dim",
            dim,
            format!("family `{family}` supports {}", describe_dims(&info)),
        ));
    }
    // One arm per family; `any_dim!` expands a family that works in every
    // compiled dimension.
    macro_rules! any_dim {
        ($shape:expr) => {
            match dim {
                2 => Ok(visitor.visit::<2, _>($shape)),
                3 => Ok(visitor.visit::<3, _>($shape)),
                4 => Ok(visitor.visit::<4, _>($shape)),
                _ => unreachable!("checked by supports_dim"),
            }
        };
    }
    match family {
        "sphere" => {
            let _: NoParams = parse_params(family, params)?;
            any_dim!(jamkit_sphere::Sphere)
        }
        "fourier" => {
            let p: jamkit_fourier::FourierParams = parse_params(family, params)?;
            near_disk(visitor, p.delta, jamkit_fourier::NearDisk::fourier(&p))
        }
        "fourier_sum" => {
            let p: jamkit_fourier::FourierSumParams = parse_params(family, params)?;
            near_disk(visitor, p.delta, jamkit_fourier::NearDisk::fourier_sum(&p))
        }
        "lobed" => {
            let p: jamkit_lobed::LobedParams = parse_params(family, params)?;
            let shape = jamkit_lobed::Lobed::new(&p)
                .map_err(|e| ExperimentError::invalid(e.field, e.value, e.allowed))?;
            Ok(visitor.visit::<2, _>(shape))
        }
        "nmer" => {
            let p: jamkit_nmer::NmerParams = parse_params(family, params)?;
            let invalid =
                |e: jamkit_nmer::ParamError| ExperimentError::invalid(e.field, e.value, e.allowed);
            // α = 1: two coincident spheres are one sphere (same random
            // stream, hence the same packing as `sphere` for the same seed).
            match (dim, p.is_single_sphere()) {
                (2, true) => Ok(visitor.visit::<2, _>(jamkit_sphere::Sphere)),
                (3, true) => Ok(visitor.visit::<3, _>(jamkit_sphere::Sphere)),
                (2, false) => {
                    Ok(visitor.visit::<2, _>(jamkit_nmer::Nmer::<2>::new(&p).map_err(invalid)?))
                }
                (3, false) => {
                    Ok(visitor.visit::<3, _>(jamkit_nmer::Nmer::<3>::new(&p).map_err(invalid)?))
                }
                _ => unreachable!("checked by supports_dim"),
            }
        }
        "ellipse" => {
            let p: jamkit_ellipse::EllipseParams = parse_params(family, params)?;
            let shape = jamkit_ellipse::Ellipse::new(&p)
                .map_err(|e| ExperimentError::invalid(e.field, e.value, e.allowed))?;
            // α = 1 is the disk of radius R⁰: run it as `sphere` (no
            // rotational coordinates, same random stream, hence the same
            // packing as `sphere` for the same seed), as near-disks with Δ = 0.
            Ok(if p.aspect == 1.0 {
                visitor.visit::<2, _>(jamkit_sphere::Sphere)
            } else {
                visitor.visit::<2, _>(shape)
            })
        }
        other => unreachable!("family `{other}` is in FAMILIES but has no dispatch arm"),
    }
}

/// Near-disks with Δ = 0 are disks: they run as the sphere family, with no
/// rotational coordinates and the same random stream, hence the same
/// packing as `sphere` for the same seed.
fn near_disk<V: SceneVisitor>(
    visitor: V,
    delta: f64,
    shape: Result<jamkit_fourier::NearDisk, jamkit_fourier::ParamError>,
) -> Result<V::Output, ExperimentError> {
    let shape = shape.map_err(|e| ExperimentError::invalid(e.field, e.value, e.allowed))?;
    Ok(if delta == 0.0 {
        visitor.visit::<2, _>(jamkit_sphere::Sphere)
    } else {
        visitor.visit::<2, _>(shape)
    })
}

/// The parameters of a family that has none.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct NoParams {}
