//! `--set KEY=VALUE`: edit any field of an experiment from the command line.
//!
//! `KEY` is a dotted path (`particles`, `protocol.eps`, `params.delta`,
//! `minimizer.dt_max`); `VALUE` is RON (`256`, `[64, 128]`, `1e-4`,
//! `Fire2`, `"name"`), and a bare word that is not RON is taken as a string.
//! A path may skip an enum's variant name: `protocol.eps` reaches the `eps`
//! of `protocol: Jam(...)`.
//!
//! The experiment is turned into a JSON tree, edited, and read back through
//! the same typed schema, so an override is checked exactly like the file.

use crate::error::ExperimentError;
use crate::schema::Experiment;
use serde_json::Value;

/// Apply `KEY=VALUE` overrides in order.
pub fn apply(experiment: &Experiment, sets: &[String]) -> Result<Experiment, ExperimentError> {
    if sets.is_empty() {
        return Ok(experiment.clone());
    }
    let mut tree = serde_json::to_value(experiment).map_err(|e| ExperimentError::Override {
        key: String::new(),
        message: e.to_string(),
    })?;
    for set in sets {
        let (key, value) = set
            .split_once('=')
            .ok_or_else(|| ExperimentError::Override {
                key: set.clone(),
                message: "expected KEY=VALUE".into(),
            })?;
        let value = parse_value(value.trim());
        assign(&mut tree, key.trim(), value)?;
    }
    serde_json::from_value(tree).map_err(|e| ExperimentError::Override {
        key: sets.join(" "),
        message: format!("the result is not a valid experiment: {e}"),
    })
}

/// RON text to a JSON value. `ron::Value` forgets enum variant names, so
/// `Variant(...)` is read as `{"Variant": (...)}` here; a bare word that RON
/// rejects becomes a string (a unit variant such as `Fire2`, or a name).
fn parse_value(text: &str) -> Value {
    let ident_len = text.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(text.len());
    let (ident, rest) = text.split_at(ident_len);
    if ident.starts_with(|c: char| c.is_ascii_uppercase()) && rest.starts_with('(') && rest.ends_with(')') {
        let inner = parse_value(rest);
        let mut obj = serde_json::Map::new();
        obj.insert(ident.to_string(), inner);
        return Value::Object(obj);
    }
    ron::from_str::<ron::Value>(text)
        .ok()
        .and_then(|v| serde_json::to_value(v).ok())
        .unwrap_or_else(|| Value::String(text.to_string()))
}

fn assign(tree: &mut Value, key: &str, value: Value) -> Result<(), ExperimentError> {
    let err = |message: String| ExperimentError::Override {
        key: key.to_string(),
        message,
    };
    let parts: Vec<&str> = key.split('.').collect();
    let mut node = tree;
    for (depth, part) in parts.iter().enumerate() {
        let last = depth + 1 == parts.len();
        let known = known_fields(node);
        node = descend(node, part, last)
            .ok_or_else(|| err(format!("no field `{part}` here (known: {known})")))?;
    }
    *node = value;
    Ok(())
}

/// The child `part` of `node`, looking through an enum variant's name (a
/// one-key object whose key starts with a capital letter). The last step may
/// create a field (a new entry of `params`); a misspelt struct field created
/// this way is then rejected, with the list of known fields, when the tree is
/// read back through the schema.
fn descend<'a>(node: &'a mut Value, part: &str, last: bool) -> Option<&'a mut Value> {
    let variant = node
        .as_object()
        .filter(|obj| obj.len() == 1 && !obj.contains_key(part))
        .and_then(|obj| obj.keys().next().cloned())
        .filter(|k| k.starts_with(|c: char| c.is_ascii_uppercase()));
    let obj = match variant {
        Some(tag) => node.get_mut(&tag)?.as_object_mut()?,
        None => node.as_object_mut()?,
    };
    if obj.contains_key(part) || last {
        return Some(obj.entry(part.to_string()).or_insert(Value::Null));
    }
    None
}

fn known_fields(node: &Value) -> String {
    match node {
        Value::Object(m) => {
            let mut keys: Vec<&str> = m.keys().map(String::as_str).collect();
            if let (1, Some(Value::Object(inner))) = (m.len(), m.values().next()) {
                keys.extend(inner.keys().map(String::as_str));
            }
            keys.join(", ")
        }
        _ => "none: this value has no fields".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Experiment {
        Experiment::from_ron(r#"(name: "t", family: "sphere", particles: 16)"#, "t").unwrap()
    }

    #[test]
    fn sets_top_level_nested_and_enum_fields() {
        let e = apply(
            &base(),
            &[
                "particles=[8, 16]".into(),
                "protocol.eps=1e-4".into(),
                "minimizer.variant=Fire2".into(),
                "samples=3".into(),
            ],
        )
        .unwrap();
        assert_eq!(e.particles.values(), vec![8, 16]);
        assert_eq!(e.samples, 3);
        assert_eq!(e.minimizer.variant, jamkit_engine::FireVariant::Fire2);
        match e.protocol {
            crate::schema::Protocol::Jam { eps, .. } => assert_eq!(eps, 1e-4),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn unknown_key_is_named() {
        let err = apply(&base(), &["protocol.epz=1".into()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("epz") && err.contains("eps"), "{err}");
        let err = apply(&base(), &["output.nothing.deeper=1".into()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("nothing") && err.contains("packings"), "{err}");
        let err = apply(&base(), &["particles=-3".into()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("not a valid experiment"), "{err}");
    }
}
