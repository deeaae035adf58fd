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
    /// The true signed distance along the common normal (of each contact,
    /// for the 2D near-disks' non-convex outlines).
    Exact,
}

impl std::str::FromStr for GapModel {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        GapModel::parse_among(text, &GapModel::ALL)
    }
}

impl GapModel {
    /// Every model, in the order of their accuracy.
    pub const ALL: [GapModel; 3] = [GapModel::FirstOrder, GapModel::SecondOrder, GapModel::Exact];

    /// Read a model's name (case, `_`, `-` and spaces ignored; `first`,
    /// `second` for short) among the `allowed` ones; the error names what
    /// is allowed.
    pub fn parse_among(text: &str, allowed: &[GapModel]) -> Result<GapModel, String> {
        let key: String = text
            .chars()
            .filter(|c| !matches!(c, '_' | '-' | ' '))
            .collect::<String>()
            .to_ascii_lowercase();
        let model = match key.as_str() {
            "firstorder" | "first" => Some(GapModel::FirstOrder),
            "secondorder" | "second" => Some(GapModel::SecondOrder),
            "exact" => Some(GapModel::Exact),
            _ => None,
        };
        match model {
            Some(m) if allowed.contains(&m) => Ok(m),
            Some(m) => Err(format!(
                "gap model {:?} is not offered by this family: allowed are {}",
                m.name(),
                GapModel::names(allowed)
            )),
            None => Err(format!(
                "unknown gap model {text:?}: allowed are {}",
                GapModel::names(allowed)
            )),
        }
    }

    /// `"FirstOrder", "Exact"`: the names of `models` for messages.
    fn names(models: &[GapModel]) -> String {
        let names: Vec<String> = models.iter().map(|m| format!("{:?}", m.name())).collect();
        names.join(", ")
    }
}

/// Deserialize a family's `gap` parameter: a string naming the model, or
/// `None`/absent for the paper's `FirstOrder`. A bare RON identifier
/// (`gap: Exact`) reaches a family as a unit value without its name, and
/// is refused with a message saying how to write it.
pub fn deserialize_gap<'de, D: serde::Deserializer<'de>>(d: D) -> Result<GapModel, D::Error> {
    deserialize_among(d, &GapModel::ALL)
}

/// [`deserialize_gap`] for a family without the second-order gap (the 3D
/// `harmonic`): `"FirstOrder"` or `"Exact"`, and the error says so.
pub fn deserialize_first_or_exact<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<GapModel, D::Error> {
    deserialize_among(d, &[GapModel::FirstOrder, GapModel::Exact])
}

fn deserialize_among<'de, D: serde::Deserializer<'de>>(
    d: D,
    allowed: &[GapModel],
) -> Result<GapModel, D::Error> {
    crate::family::deserialize_named(
        d,
        GapModel::FirstOrder,
        |s| GapModel::parse_among(s, allowed),
        || {
            format!(
                "write the gap model as a string, e.g. gap: \"Exact\" (allowed: {})",
                GapModel::names(allowed)
            )
        },
    )
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

#[cfg(test)]
mod tests {
    use super::GapModel;

    #[test]
    fn names_are_read_loosely_and_refused_with_what_is_allowed() {
        assert_eq!("second_order".parse(), Ok(GapModel::SecondOrder));
        assert_eq!("Exact".parse(), Ok(GapModel::Exact));
        let planar = &GapModel::ALL;
        let solid = &[GapModel::FirstOrder, GapModel::Exact];
        assert_eq!(
            GapModel::parse_among("first-order", solid),
            Ok(GapModel::FirstOrder)
        );
        let e = GapModel::parse_among("Exactly", planar).unwrap_err();
        assert_eq!(
            e,
            r#"unknown gap model "Exactly": allowed are "FirstOrder", "SecondOrder", "Exact""#
        );
        let e = GapModel::parse_among("second", solid).unwrap_err();
        assert_eq!(
            e,
            r#"gap model "SecondOrder" is not offered by this family: allowed are "FirstOrder", "Exact""#
        );
    }
}
