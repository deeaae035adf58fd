//! The registry: every shape family jamkit knows (its own crate, so that
//! drawing a packing does not pull in the runner).
//!
//! A family registers itself once, in its own crate, by implementing
//! [`jamkit_core::Family`]: its info, its typed parameters, and how they
//! become a shape in a dimension (with the degenerate cases, `Δ = 0` → the
//! disk); its manifest names the types under
//! `[package.metadata.jamkit] families`. Adding a family crate to jamkit is
//! one line, its dependency in this crate's `Cargo.toml`: the build script
//! reads the family types from the crate's manifest into the `families!`
//! list ([`FAMILIES`] is the list it makes). The runner, `jamkit draw`,
//! `draw-shape`, `report` and `jamkit shapes` all go through [`dispatch`],
//! the one place where a family name from a file becomes a typed shape `S`
//! in a const dimension `D`, after which everything is statically
//! dispatched.

use jamkit_core::{Dims, Error, Family, FamilyInfo};
use serde::de::DeserializeOwned;
use std::collections::BTreeMap;

pub use jamkit_core::ShapeVisitor as SceneVisitor;

/// Parameters of one grid point, by name.
pub type ParamMap = BTreeMap<String, ron::Value>;

/// The list of families: each line names a type implementing
/// [`jamkit_core::Family`]. It defines [`FAMILIES`], [`EXAMPLES`] and the
/// dispatch by name.
macro_rules! families {
    ($($family:ty),+ $(,)?) => {
        /// Every registered family.
        pub const FAMILIES: &[FamilyInfo] = &[$(<$family as Family>::INFO),+];

        /// Every registered family's example parameters (RON), in the order
        /// of [`FAMILIES`].
        pub const EXAMPLES: &[&str] = &[$(<$family as Family>::EXAMPLE),+];

        fn dispatch_by_name<V: SceneVisitor>(
            family: &str,
            dim: usize,
            params: &ParamMap,
            visitor: V,
        ) -> Result<V::Output, Error> {
            $(
                if family == <$family as Family>::INFO.name {
                    let p: <$family as Family>::Params = parse_params(family, params)?;
                    return <$family as Family>::visit(&p, dim, visitor);
                }
            )+
            Err(unknown_family(family))
        }
    };
}

// The families of the crates this crate depends on under `shapes/`, as
// their manifests list them (build.rs).
include!(concat!(env!("OUT_DIR"), "/families.rs"));

/// Dimensions the engine is compiled for (families with `Dims::Any`).
pub const COMPILED_DIMS: &[usize] = &[2, 3, 4];

/// The family called `name`.
pub fn family_info(name: &str) -> Result<FamilyInfo, Error> {
    FAMILIES
        .iter()
        .copied()
        .find(|f| f.name == name)
        .ok_or_else(|| unknown_family(name))
}

fn unknown_family(name: &str) -> Error {
    let known: Vec<&str> = FAMILIES.iter().map(|f| f.name).collect();
    Error::invalid(
        "family",
        format!("\"{name}\""),
        format!("must be one of: {}", known.join(", ")),
    )
}

/// `params` with the defaults of `info` filled in for the parameters it
/// does not give (a `None` default is left out: serde fills it).
pub fn with_defaults(info: &FamilyInfo, params: &ParamMap) -> ParamMap {
    let mut out = params.clone();
    for spec in info.params {
        if let Some(default) = spec.default
            && !out.contains_key(spec.name)
            && default != "None"
        {
            let value = ron::from_str(default).expect("family defaults are valid RON");
            out.insert(spec.name.to_string(), value);
        }
    }
    out
}

/// A parameter map written in RON, as a struct `(n: 3, delta: 0.2)` or as a
/// map `{"n": 3, "delta": 0.2}` (the form of experiment files).
pub fn params_from_ron(text: &str) -> Result<ParamMap, String> {
    let value: ron::Value = ron::from_str(text).map_err(|e| e.to_string())?;
    if value == ron::Value::Unit {
        // `()`: the empty struct.
        return Ok(ParamMap::new());
    }
    value
        .into_rust()
        .map_err(|e| format!("not a parameter map: {e}"))
}

/// A family's parameters as a packing file stores them (JSON) back as a
/// parameter map. JSON `null` arrives as RON's unit `()`; in a packing file
/// it is always an absent optional (`None`), never a bare RON name.
pub fn params_from_json(params: &serde_json::Value) -> Result<ParamMap, Error> {
    let mut map: ParamMap = serde_json::from_value(params.clone()).map_err(|e| {
        Error::invalid(
            "params",
            params.to_string(),
            format!("not a family parameter map: {e}"),
        )
    })?;
    for v in map.values_mut() {
        if *v == ron::Value::Unit {
            *v = ron::Value::Option(None);
        }
    }
    Ok(map)
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
pub fn parse_params<T: DeserializeOwned>(family: &str, params: &ParamMap) -> Result<T, Error> {
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
                Error::invalid(
                    format!("params.{name} (family `{family}`)"),
                    ron::to_string(value).unwrap_or_default(),
                    format!("{message}; {name}: {about}"),
                )
            }
            None => Error::invalid(
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
) -> Result<V::Output, Error> {
    let info = family_info(family)?;
    if !supports_dim(&info, dim) {
        return Err(Error::invalid(
            "dim",
            dim,
            format!("family `{family}` supports {}", describe_dims(&info)),
        ));
    }
    dispatch_by_name(family, dim, params, visitor)
}

/// The asphericity `A = P²/(4πS)` (1 for a disk) of the body of a 2D
/// family that defines it, its shape built from `params` as for a run:
/// `fourier` and `fourier_sum` (near-disks) and `ellipse`, each by its own
/// computation. `Ok(None)` for the other families; an unknown family or
/// parameters the family refuses are errors.
pub fn asphericity(family: &str, params: &ParamMap) -> Result<Option<f64>, Error> {
    family_info(family)?;
    let a = match family {
        "fourier" => {
            jamkit_fourier::NearDisk::fourier(&parse_params(family, params)?)?.asphericity()
        }
        "fourier_sum" => {
            jamkit_fourier::NearDisk::fourier_sum(&parse_params(family, params)?)?.asphericity()
        }
        "ellipse" => jamkit_ellipse::Ellipse::new(&parse_params(family, params)?)?.asphericity(),
        _ => return Ok(None),
    };
    Ok(Some(a))
}

/// The families' reference page, `docs/reference/families.md`, as
/// `jamkit shapes --markdown` prints it: every registered family with its
/// dimensions, an example parameter set and a table of its parameters.
/// Generated from [`FAMILIES`] and [`EXAMPLES`], so that it lists exactly
/// what the registry holds (`tests/reference.rs` checks the committed page).
pub fn reference_markdown() -> String {
    let mut md = String::from(
        "# Shape families\n\n\
         <!-- Generated by `jamkit shapes --markdown > docs/reference/families.md`; do not edit. -->\n\n\
         Every registered family, as `jamkit shapes` lists it. An experiment file\n\
         names one with `family: \"NAME\"` and gives its parameters in `params`\n\
         (`params: {\"delta\": 0.1}`); a list where a single value is expected\n\
         scans it (docs/how-to/sweep.md). A parameter without a default must be\n\
         given. The geometry and gap of each family: docs/explanation/gap-models.md.\n\n",
    );
    md.push_str("| family | dimensions | bodies |\n|---|---|---|\n");
    for f in FAMILIES {
        md.push_str(&format!(
            "| [`{}`](#{}) | {} | {} |\n",
            f.name,
            f.name,
            describe_dims(f).trim_start_matches("dim "),
            f.about.replace('|', "\\|")
        ));
    }
    for (f, example) in FAMILIES.iter().zip(EXAMPLES) {
        md.push_str(&format!(
            "\n## {}\n\n{}.\n\nDimensions: {}. Example parameters (the default panel of \
             `jamkit draw-shape {}`): `{}`.\n\n",
            f.name,
            f.about,
            describe_dims(f).trim_start_matches("dim "),
            f.name,
            example
        ));
        if f.params.is_empty() {
            md.push_str("No parameters.\n");
            continue;
        }
        md.push_str("| parameter | default | meaning |\n|---|---|---|\n");
        for p in f.params {
            let default = p
                .default
                .map_or("required".to_string(), |d| format!("`{d}`"));
            let list = if p.is_list { " (a list)" } else { "" };
            md.push_str(&format!(
                "| `{}` | {} | {}{} |\n",
                p.name,
                default,
                p.about.replace('|', "\\|"),
                list
            ));
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Builds the shape and does nothing with it.
    struct Build;

    impl SceneVisitor for Build {
        type Output = ();
        fn visit<const D: usize, S: jamkit_core::Shape<D>>(self, _shape: S) {}
    }

    fn example(f: &FamilyInfo) -> ParamMap {
        let at = FAMILIES.iter().position(|g| g.name == f.name).unwrap();
        with_defaults(f, &params_from_ron(EXAMPLES[at]).unwrap())
    }

    fn first_dim(f: &FamilyInfo) -> usize {
        *COMPILED_DIMS.iter().find(|&&d| supports_dim(f, d)).unwrap()
    }

    /// The names serde's "unknown field" message lists as expected: the
    /// backquoted names between `, expected` and the end of serde's part
    /// of the message (`instead`, or the `;` after which the registry
    /// adds its own words).
    fn serde_fields(message: &str) -> Vec<String> {
        let Some((_, rest)) = message.split_once(", expected") else {
            return Vec::new();
        };
        let end = rest.find(';').unwrap_or(rest.len());
        let rest = &rest[..end];
        if rest.contains("no fields") {
            return Vec::new();
        }
        rest.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    }

    /// Each family's parameter table (`FamilyInfo::params`, what `jamkit
    /// shapes` and the reference page print) names exactly the fields of
    /// the serde type the experiment file is read into: a field added to
    /// one and not the other fails here.
    #[test]
    fn every_parameter_table_names_the_fields_of_its_serde_type() {
        for f in FAMILIES {
            let mut params = example(f);
            params.insert("not_a_parameter".into(), ron::Value::Bool(true));
            let message = dispatch(f.name, first_dim(f), &params, Build)
                .unwrap_err()
                .to_string();
            assert!(message.contains("not_a_parameter"), "{}: {message}", f.name);
            let mut fields = serde_fields(&message);
            let mut listed: Vec<String> = f.params.iter().map(|p| p.name.to_string()).collect();
            fields.sort();
            listed.sort();
            assert_eq!(
                fields, listed,
                "{}: serde's fields against the table ({message})",
                f.name
            );
        }
    }

    /// A parameter the table calls required is required by serde, and one
    /// with a default may be left out as far as serde is concerned (a
    /// family may still refuse the combination, as `nmer` does without
    /// either `alpha` or `spheres`, but not with serde's "missing field"):
    /// the table's default is what the family gets.
    #[test]
    fn every_parameter_table_says_what_is_required_and_what_has_a_default() {
        for f in FAMILIES {
            for p in f.params {
                let at = FAMILIES.iter().position(|g| g.name == f.name).unwrap();
                let mut params = params_from_ron(EXAMPLES[at]).unwrap();
                params.remove(p.name);
                let built = dispatch(f.name, first_dim(f), &with_defaults(f, &params), Build);
                let message = built.err().map(|e| e.to_string());
                match p.default {
                    None => {
                        let e =
                            message.unwrap_or_else(|| panic!("{}.{} is required", f.name, p.name));
                        assert!(
                            e.contains("missing field") && e.contains(p.name),
                            "{}.{}: {e}",
                            f.name,
                            p.name
                        );
                    }
                    Some(d) => {
                        if let Some(e) = message {
                            assert!(
                                !e.contains("missing field"),
                                "{}.{} with its default {d}: {e}",
                                f.name,
                                p.name
                            );
                        }
                    }
                }
            }
        }
    }

    fn params(json: serde_json::Value) -> ParamMap {
        params_from_json(&json).unwrap()
    }

    #[test]
    fn asphericity_is_the_familys_own_computation() {
        let near_disk = jamkit_fourier::NearDisk::fourier(&jamkit_fourier::FourierParams {
            n: 2,
            delta: 0.3,
            inertia: Some(1.0),
            gap: Default::default(),
        })
        .unwrap();
        let a = asphericity(
            "fourier",
            &params(serde_json::json!({"n": 2, "delta": 0.3, "inertia": 1.0})),
        )
        .unwrap()
        .unwrap();
        assert_eq!(a.to_bits(), near_disk.asphericity().to_bits());
        assert!(a > 1.0);
        let ellipse = jamkit_ellipse::Ellipse::new(&jamkit_ellipse::EllipseParams {
            aspect: 1.5,
            inertia: None,
        })
        .unwrap();
        let a = asphericity("ellipse", &params(serde_json::json!({"aspect": 1.5})))
            .unwrap()
            .unwrap();
        assert_eq!(a.to_bits(), ellipse.asphericity().to_bits());
        let sum = asphericity(
            "fourier_sum",
            &params_from_ron("(delta: 0.1, modes: [(n: 3, a: 1.0)])").unwrap(),
        )
        .unwrap()
        .unwrap();
        assert!(sum > 1.0, "{sum}");
    }

    #[test]
    fn asphericity_of_other_families_is_none_and_bad_input_an_error() {
        assert_eq!(asphericity("sphere", &ParamMap::new()).unwrap(), None);
        let err = asphericity("blob", &ParamMap::new())
            .unwrap_err()
            .to_string();
        assert!(err.contains("must be one of"), "{err}");
        let err = asphericity("ellipse", &params(serde_json::json!({"aspect": 0.5})))
            .unwrap_err()
            .to_string();
        assert!(err.contains("aspect"), "{err}");
        let err = asphericity("fourier", &params(serde_json::json!({"n": 2})))
            .unwrap_err()
            .to_string();
        assert!(err.contains("delta"), "{err}");
    }
}
