//! Self-description of shape families, for the registry and `jamkit shapes`.
//!
//! A family crate exports one [`FamilyInfo`]: its name, what it is, which
//! dimensions it supports and its parameters. Parameters are read from the
//! experiment file by serde into the family's own parameter struct; the
//! [`ParamSpec`]s say which are scalars and which are lists, so that the
//! experiment layer knows when a list in the file means "scan these values"
//! (a list given for a scalar, or a list of lists for a list parameter).

/// One parameter of a family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamSpec {
    /// Name in the experiment file.
    pub name: &'static str,
    /// What it means, with its allowed range.
    pub about: &'static str,
    /// True when the parameter itself is a list (e.g. Fourier modes).
    pub is_list: bool,
    /// Its default, in RON, or `None` when it must be given.
    pub default: Option<&'static str>,
}

/// Which dimensions a family supports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dims {
    /// Exactly these.
    Only(&'static [usize]),
    /// Any dimension the engine is compiled for.
    Any,
}

/// A family's description.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FamilyInfo {
    /// Registry name.
    pub name: &'static str,
    /// One line on what the bodies are.
    pub about: &'static str,
    /// Supported dimensions.
    pub dims: Dims,
    /// Parameters.
    pub params: &'static [ParamSpec],
}

impl FamilyInfo {
    /// The spec of parameter `name`, if the family has one.
    pub fn param(&self, name: &str) -> Option<&ParamSpec> {
        self.params.iter().find(|p| p.name == name)
    }
}

/// Read an optional parameter written either as `Some(x)`/`None` (RON) or
/// as a bare `x` (what `--set` and JSON produce, having no `Some`). Use as
/// `#[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]`.
pub fn lenient_option<'de, D, T>(deserializer: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: serde::Deserialize<'de>,
{
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Either<T> {
        Wrapped(Option<T>),
        Bare(T),
    }
    // NOTE: the untagged enum's own error ("did not match any variant of
    // untagged enum Either") says nothing to a user; the caller names the
    // field and what it allows.
    let either = <Either<T> as serde::Deserialize>::deserialize(deserializer).map_err(|_| {
        <D::Error as serde::de::Error>::custom(
            "a value of the wrong type (give the value itself, or None)",
        )
    })?;
    Ok(match either {
        Either::Wrapped(v) => v,
        Either::Bare(v) => Some(v),
    })
}
