//! Reading YAML values by hand where a derived type cannot say what went wrong: a value as a
//! message shows it, and a value checked inside the parser's call for its key (so that the
//! message carries the key's path and line).

use crate::limits::excerpt;

/// A YAML value as a message shows it: a number or word as written (at most
/// [`crate::limits::ECHO_CHARS`] characters), else its kind.
pub fn shown(v: &serde_yaml::Value) -> String {
    use serde_yaml::Value;
    match v {
        Value::Null => "nothing".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("`{}`", excerpt(s)),
        Value::Sequence(_) => "a list".into(),
        Value::Mapping(_) => "a mapping".into(),
        Value::Tagged(t) => format!("a value tagged {}", t.tag),
    }
}

/// A value read whole and turned into a `T` by `check`, whose `Err` says in words what the
/// value should have been: refused inside the parser's call for the key, so that the message
/// carries the key's path and line ([`super::config::yaml_problem`]), as a derived type's
/// would (an untagged enum's says only that no variant matched).
pub fn checked_value<'de, D, T>(
    d: D,
    check: impl FnOnce(serde_yaml::Value) -> Result<T, String>,
) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
{
    d.deserialize_any(Checked(check))
}

struct Checked<F>(F);

impl<F> Checked<F> {
    fn check<T, E: serde::de::Error>(self, v: serde_yaml::Value) -> Result<T, E>
    where
        F: FnOnce(serde_yaml::Value) -> Result<T, String>,
    {
        (self.0)(v).map_err(E::custom)
    }
}

impl<'de, T, F: FnOnce(serde_yaml::Value) -> Result<T, String>> serde::de::Visitor<'de>
    for Checked<F>
{
    type Value = T;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a YAML value")
    }
    fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<T, E> {
        self.check(serde_yaml::Value::Bool(v))
    }
    fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<T, E> {
        self.check(serde_yaml::Value::Number(v.into()))
    }
    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<T, E> {
        self.check(serde_yaml::Value::Number(v.into()))
    }
    fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<T, E> {
        self.check(serde_yaml::Value::Number(v.into()))
    }
    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<T, E> {
        self.check(serde_yaml::Value::String(v.to_string()))
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<T, E> {
        self.check(serde_yaml::Value::Null)
    }
    fn visit_none<E: serde::de::Error>(self) -> Result<T, E> {
        self.check(serde_yaml::Value::Null)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<T, A::Error> {
        let mut items = Vec::new();
        while let Some(x) = seq.next_element()? {
            items.push(x);
        }
        self.check(serde_yaml::Value::Sequence(items))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<T, A::Error> {
        let mut m = serde_yaml::Mapping::new();
        while let Some((k, v)) = map.next_entry()? {
            m.insert(k, v);
        }
        self.check(serde_yaml::Value::Mapping(m))
    }
}
