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
//! Nothing here knows the experiment's fields: any type with a serde
//! schema is edited the same way (the scan of an experiment file,
//! `Experiment::scanned`, applies its settings through [`apply_values`]).

use crate::error::ExperimentError;
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::Value;

/// Apply `KEY=VALUE` overrides in order.
pub fn apply<T>(experiment: &T, sets: &[String]) -> Result<T, ExperimentError>
where
    T: Clone + Serialize + DeserializeOwned,
{
    let values = sets
        .iter()
        .map(|set| {
            let (key, value) = set
                .split_once('=')
                .ok_or_else(|| ExperimentError::Override {
                    key: set.clone(),
                    message: "expected KEY=VALUE".into(),
                })?;
            Ok((key.trim().to_string(), parse_value(value.trim())))
        })
        .collect::<Result<Vec<_>, ExperimentError>>()?;
    edit(experiment, &values, || sets.join(" "))
}

/// Set each `KEY` (a dotted path, as in [`apply`]) to its value (in serde's
/// JSON form), in order, and read the result back through the schema.
pub fn apply_values<T>(experiment: &T, sets: &[(String, Value)]) -> Result<T, ExperimentError>
where
    T: Clone + Serialize + DeserializeOwned,
{
    edit(experiment, sets, || {
        sets.iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    })
}

/// [`apply_values`], `text` naming the overrides in an error.
fn edit<T>(
    experiment: &T,
    sets: &[(String, Value)],
    text: impl Fn() -> String,
) -> Result<T, ExperimentError>
where
    T: Clone + Serialize + DeserializeOwned,
{
    if sets.is_empty() {
        return Ok(experiment.clone());
    }
    let mut tree = serde_json::to_value(experiment).map_err(|e| ExperimentError::Override {
        key: String::new(),
        message: e.to_string(),
    })?;
    for (key, value) in sets {
        assign(&mut tree, key, value.clone())?;
    }
    serde_json::from_value(tree).map_err(|e| ExperimentError::Override {
        key: text(),
        message: format!("the result is not a valid experiment: {e}"),
    })
}

/// RON text to a JSON value in serde's externally tagged form: `Name` is
/// the string `"Name"` (a unit variant), `Name(a: 1)` is `{"Name": {"a": 1}}`,
/// `Name(x)` is `{"Name": x}`, `Some(x)` is `x`, `None` is `null`. A value
/// that does not parse is taken as a plain string (`--set name=trial`).
fn parse_value(text: &str) -> Value {
    let mut p = RonText {
        s: text.as_bytes(),
        at: 0,
    };
    match p.value() {
        Some(v) if p.at_end() => v,
        _ => Value::String(text.to_string()),
    }
}

/// A small recursive-descent reader of RON values (enough for overrides).
struct RonText<'a> {
    s: &'a [u8],
    at: usize,
}

impl RonText<'_> {
    fn skip_ws(&mut self) {
        while self.at < self.s.len() && self.s[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
    }

    fn at_end(&mut self) -> bool {
        self.skip_ws();
        self.at == self.s.len()
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip_ws();
        self.s.get(self.at).copied()
    }

    fn eat(&mut self, c: u8) -> bool {
        if self.peek() == Some(c) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn ident(&mut self) -> Option<String> {
        self.skip_ws();
        let start = self.at;
        while self.at < self.s.len()
            && (self.s[self.at].is_ascii_alphanumeric() || self.s[self.at] == b'_')
        {
            self.at += 1;
        }
        (self.at > start && !self.s[start].is_ascii_digit())
            .then(|| String::from_utf8_lossy(&self.s[start..self.at]).into_owned())
    }

    fn value(&mut self) -> Option<Value> {
        match self.peek()? {
            b'"' => self.string().map(Value::String),
            b'[' => {
                self.at += 1;
                let mut items = Vec::new();
                while !self.eat(b']') {
                    items.push(self.value()?);
                    if !self.eat(b',') && self.peek() != Some(b']') {
                        return None;
                    }
                }
                Some(Value::Array(items))
            }
            b'{' => {
                self.at += 1;
                let mut map = serde_json::Map::new();
                while !self.eat(b'}') {
                    let key = match self.value()? {
                        Value::String(k) => k,
                        other => other.to_string(),
                    };
                    if !self.eat(b':') {
                        return None;
                    }
                    map.insert(key, self.value()?);
                    if !self.eat(b',') && self.peek() != Some(b'}') {
                        return None;
                    }
                }
                Some(Value::Object(map))
            }
            b'(' => self.parenthesised(),
            c if c == b'-' || c == b'+' || c == b'.' || c.is_ascii_digit() => self.number(),
            _ => {
                let name = self.ident()?;
                match name.as_str() {
                    "true" => return Some(Value::Bool(true)),
                    "false" => return Some(Value::Bool(false)),
                    "None" => return Some(Value::Null),
                    _ => {}
                }
                if self.peek() != Some(b'(') {
                    return Some(Value::String(name));
                }
                // `Name()` is a struct variant with every field defaulted
                // (`Spectrum()`, `Gaps()`), not an empty tuple.
                let inner = match self.parenthesised()? {
                    Value::Array(items) if items.is_empty() => Value::Object(Default::default()),
                    inner => inner,
                };
                if name == "Some" {
                    return Some(inner);
                }
                let mut tagged = serde_json::Map::new();
                tagged.insert(name, inner);
                Some(Value::Object(tagged))
            }
        }
    }

    /// `(a: 1, b: 2)` → object; `(x)` → x; `(x, y)` → array.
    fn parenthesised(&mut self) -> Option<Value> {
        if !self.eat(b'(') {
            return None;
        }
        let mut fields = serde_json::Map::new();
        let mut items = Vec::new();
        while !self.eat(b')') {
            let save = self.at;
            match (self.ident(), self.eat(b':')) {
                (Some(key), true) => {
                    fields.insert(key, self.value()?);
                }
                _ => {
                    self.at = save;
                    items.push(self.value()?);
                }
            }
            if !self.eat(b',') && self.peek() != Some(b')') {
                return None;
            }
        }
        match (fields.is_empty(), items.len()) {
            (false, 0) => Some(Value::Object(fields)),
            (true, 1) => items.pop(),
            (true, _) => Some(Value::Array(items)),
            (false, _) => None,
        }
    }

    fn string(&mut self) -> Option<String> {
        self.at += 1;
        let mut out = String::new();
        while self.at < self.s.len() {
            let c = self.s[self.at];
            self.at += 1;
            match c {
                b'"' => return Some(out),
                b'\\' => {
                    out.push(*self.s.get(self.at)? as char);
                    self.at += 1;
                }
                _ => out.push(c as char),
            }
        }
        None
    }

    fn number(&mut self) -> Option<Value> {
        let start = self.at;
        while self.at < self.s.len()
            && matches!(
                self.s[self.at],
                b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E' | b'_'
            )
        {
            self.at += 1;
        }
        let text: String = String::from_utf8_lossy(&self.s[start..self.at]).replace('_', "");
        if let Ok(i) = text.parse::<i64>() {
            return Some(Value::from(i));
        }
        text.parse::<f64>()
            .ok()
            .and_then(serde_json::Number::from_f64)
            .map(Value::Number)
    }
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
    use serde::Deserialize;

    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Settings {
        n: u32,
        shape: Shape,
    }

    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    enum Shape {
        Disk,
        Ellipse { aspect: f64 },
    }

    #[test]
    fn any_serde_type_is_edited_and_read_back_through_its_schema() {
        let base = Settings {
            n: 4,
            shape: Shape::Disk,
        };
        let sets = ["n=8".to_string(), "shape=Ellipse(aspect: 1.5)".to_string()];
        let edited = apply(&base, &sets).unwrap();
        assert_eq!(edited.n, 8);
        assert_eq!(edited.shape, Shape::Ellipse { aspect: 1.5 });
        // A variant's field is reached through the variant's name.
        let again = apply(&edited, &["shape.aspect=2.0".to_string()]).unwrap();
        assert_eq!(again.shape, Shape::Ellipse { aspect: 2.0 });
        // A new last field is refused by the schema, a path through a
        // field that is not there by the editing, each naming the fields.
        let err = apply(&base, &["m=1".to_string()]).unwrap_err().to_string();
        assert!(
            err.contains("unknown field `m`") && err.contains("`shape`"),
            "{err}"
        );
        let err = apply(&base, &["m.k=1".to_string()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("no field `m` here (known: n, shape)"), "{err}");
        let err = apply(&base, &["n=-1".to_string()]).unwrap_err().to_string();
        assert!(err.contains("not a valid experiment"), "{err}");
        assert_eq!(apply(&base, &[]).unwrap(), base);
    }
}
