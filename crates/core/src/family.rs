//! Self-description of shape families, for the registry and `jamkit shapes`.
//!
//! A family crate exports one [`FamilyInfo`]: its name, what it is, which
//! dimensions it supports and its parameters. Parameters are read from the
//! experiment file by serde into the family's own parameter struct; the
//! [`ParamSpec`]s say which are scalars and which are lists, so that the
//! experiment layer knows when a list in the file means "scan these values"
//! (a list given for a scalar, or a list of lists for a list parameter).
//!
//! A family registers itself once, through one implementation of [`Family`]:
//! its [`FamilyInfo`], its typed parameters, and how those parameters become
//! a shape in a given dimension ([`Family::visit`], where the degenerate
//! cases live: a near-disk with `Δ = 0` is the disk, a dimer with `α = 1`
//! the sphere). Everything that needs a shape from a name (the runner,
//! `jamkit draw`, `draw-shape`, `report`) asks the registry, an explicit
//! list of these implementations, and is handed the typed shape through a
//! [`ShapeVisitor`], after which all is statically dispatched. The
//! parameter table ([`FamilyInfo::params`]) is written beside the serde
//! struct it describes; the registry's tests check that the two name the
//! same fields and agree on which are required.

use crate::Shape;
use serde::de::DeserializeOwned;
use std::fmt::Debug;

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
    /// `Some` for a parameter added after packings were written without
    /// it ([`Added`]); `None`: the packing records it as the point has it
    /// (`null` for `"None"`).
    pub added: Option<Added>,
}

/// How a parameter added to a family after packings were written without
/// it keeps those packings as they were (their ids, `params` and
/// `settings`, hence the resumption of the runs that wrote them).
///
/// The family reads the parameter with the default the experiment layer
/// fills in ([`ParamSpec::default`]) when an experiment file leaves it out;
/// the packing's record leaves it out where it holds [`Added::before`] (what
/// the packings written without it had) or `None`, and, when the file does not give
/// it, where [`Added::read_with`] says the family does not read it. So the
/// family's own reading of a missing key and of `None` (its serde default,
/// used when a packing's record is read back) must be `before`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Added {
    /// The value, in RON, that the packings written before the parameter
    /// existed had.
    pub before: &'static str,
    /// `(other, value)`: the family reads the parameter only where the
    /// parameter `other` has `value` (RON; strings compared without case),
    /// e.g. an exact-gap solver only with `gap: "Exact"`.
    pub read_with: Option<(&'static str, &'static str)>,
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

/// Something to do with a typed shape: run a sample, draw it, analyse it.
///
/// The registry calls [`ShapeVisitor::visit`] once per job, with the
/// family's shape in the dimension the job asks for.
pub trait ShapeVisitor {
    /// What the visit returns.
    type Output;
    /// Called with the family's shape in dimension `D`.
    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Self::Output;
}

/// A shape family's one registration: everything the registry needs to turn
/// `(name, dim, params)` into a typed shape.
///
/// Per-family defaults that depend on the parameters or the dimension (the
/// rotational inertia, FIRE's largest time step and masses) travel with the
/// shape ([`Shape::rot_inertia`], [`Shape::policy`]).
pub trait Family {
    /// Name, description, dimensions and parameters (`jamkit shapes`).
    const INFO: FamilyInfo;
    /// A small valid parameter set in RON (`"(n: 2, delta: 0.1)"`): the
    /// default panel of `jamkit draw-shape` and the example the docs' and
    /// tests' checks run.
    const EXAMPLE: &'static str;
    /// The typed parameters, read by serde from the experiment file.
    type Params: DeserializeOwned;
    /// Build the shape of `params` in dimension `dim` (one of
    /// [`FamilyInfo::dims`], checked by the caller) and hand it to
    /// `visitor`. A parameter out of range is
    /// [`Error::InvalidParameter`](crate::Error::InvalidParameter), never a
    /// panic.
    fn visit<V: ShapeVisitor>(
        params: &Self::Params,
        dim: usize,
        visitor: V,
    ) -> crate::Result<V::Output>;
}

impl FamilyInfo {
    /// The spec of parameter `name`, if the family has one.
    pub fn param(&self, name: &str) -> Option<&ParamSpec> {
        self.params.iter().find(|p| p.name == name)
    }
}

/// Read a named choice: a string handed to `parse` (whose error is the
/// message), or `None`/absent for `default`. A bare RON identifier
/// (`gap: Exact`) reaches a family as a unit value without its name and is
/// refused with `unit_message`, which should say how to write it. Shared by
/// the named family parameters (`gap`, `exact_solver`).
pub fn deserialize_named<'de, D, T>(
    deserializer: D,
    default: T,
    parse: impl FnOnce(&str) -> Result<T, String>,
    unit_message: impl FnOnce() -> String,
) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
{
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Raw {
        Name(String),
        // Before `Wrapped`: a unit value would read as `None`.
        Unit(()),
        Wrapped(Option<String>),
    }
    use serde::de::Error;
    match <Raw as serde::Deserialize>::deserialize(deserializer)? {
        Raw::Name(s) | Raw::Wrapped(Some(s)) => parse(&s).map_err(D::Error::custom),
        Raw::Wrapped(None) => Ok(default),
        Raw::Unit(()) => Err(D::Error::custom(unit_message())),
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
