//! The gap models a family with an approximate gap may offer: the
//! paper's first order, its second-order correction (2D near-disks only)
//! and the exact signed distance of convex bodies, with the parser of the
//! family parameter `gap` shared by the 2D (`jamkit_planar::gap2d`) and 3D
//! (`harmonic`) families.

/// Which gap a family uses (`fourier`, `fourier_sum`, `harmonic`; the
/// 3D `harmonic` family has no `SecondOrder` and refuses it).
///
/// In experiment files it is written as a string, `gap: "Exact"`
/// (`"FirstOrder"`, `"SecondOrder"`, `"Exact"`; case, `_` and `-` are
/// ignored): family parameters pass through RON's untyped values, which
/// keep strings but drop the names of bare identifiers. Read it with
/// [`deserialize_gap`], which turns a bare name into a clear error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GapModel {
    /// The paper's first-order gap, exact to `O(Δ)`.
    #[default]
    FirstOrder,
    /// The first-order gap with its `O(Δ²)` correction.
    SecondOrder,
    /// The true signed distance along the common normal (convex outlines).
    Exact,
}

impl std::str::FromStr for GapModel {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let key: String = text
            .chars()
            .filter(|c| !matches!(c, '_' | '-' | ' '))
            .collect::<String>()
            .to_ascii_lowercase();
        match key.as_str() {
            "firstorder" | "first" => Ok(GapModel::FirstOrder),
            "secondorder" | "second" => Ok(GapModel::SecondOrder),
            "exact" => Ok(GapModel::Exact),
            _ => Err(format!(
                "unknown gap model {text:?}: allowed are \"FirstOrder\", \"SecondOrder\", \"Exact\""
            )),
        }
    }
}

/// Deserialize a family's `gap` parameter: a string naming the model, or
/// `None`/absent for the paper's `FirstOrder`. A bare RON identifier
/// (`gap: Exact`) reaches a family as a unit value without its name, and
/// is refused with a message saying how to write it.
pub fn deserialize_gap<'de, D: serde::Deserializer<'de>>(d: D) -> Result<GapModel, D::Error> {
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Raw {
        Name(String),
        // Before `Wrapped`: a unit value would read as `None`.
        Unit(()),
        Wrapped(Option<String>),
    }
    use serde::Deserialize;
    use serde::de::Error;
    match Raw::deserialize(d)? {
        Raw::Name(s) | Raw::Wrapped(Some(s)) => s.parse().map_err(D::Error::custom),
        Raw::Wrapped(None) => Ok(GapModel::FirstOrder),
        Raw::Unit(()) => Err(D::Error::custom(
            "write the gap model as a string, e.g. gap: \"Exact\" (allowed: \"FirstOrder\", \"SecondOrder\", \"Exact\")",
        )),
    }
}

impl GapModel {
    /// The name used in experiment files.
    pub fn name(self) -> &'static str {
        match self {
            GapModel::FirstOrder => "FirstOrder",
            GapModel::SecondOrder => "SecondOrder",
            GapModel::Exact => "Exact",
        }
    }
}
