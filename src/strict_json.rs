//! The JSON reading every loader shares: a leading UTF-8 byte-order mark is skipped (editors on
//! Windows write one) and an object with the same key twice is refused (serde_json alone keeps
//! the last value silently, so an edited file could say two things and mean one).

use std::collections::HashSet;
use std::fmt;

use serde::de::{DeserializeOwned, Deserializer, Error as _, MapAccess, SeqAccess, Visitor};

/// The UTF-8 byte-order mark.
const BOM: &str = "\u{feff}";

/// Parses `text` (a leading BOM skipped) as `T`. Errors (serde_json's, with line and column): not
/// JSON, not a `T`, or an object holding a key twice ("duplicate key \"name\"").
pub fn from_str<T: DeserializeOwned>(text: &str) -> Result<T, serde_json::Error> {
    let text = text.strip_prefix(BOM).unwrap_or(text);
    let mut de = serde_json::Deserializer::from_str(text);
    (&mut de).deserialize_any(UniqueKeys)?;
    de.end()?;
    serde_json::from_str(text)
}

/// [`from_str`] on bytes; invalid UTF-8 is an error.
pub fn from_slice<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, serde_json::Error> {
    let text = std::str::from_utf8(bytes).map_err(|e| serde_json::Error::custom(format!("not UTF-8: {e}")))?;
    from_str(text)
}

/// A visitor that walks a whole document without keeping it and fails on a repeated key.
struct UniqueKeys;

impl<'de> serde::Deserialize<'de> for UniqueKeys {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(UniqueKeys)
    }
}

impl<'de> Visitor<'de> for UniqueKeys {
    type Value = UniqueKeys;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<Self, E> {
        Ok(UniqueKeys)
    }
    fn visit_i64<E>(self, _: i64) -> Result<Self, E> {
        Ok(UniqueKeys)
    }
    fn visit_u64<E>(self, _: u64) -> Result<Self, E> {
        Ok(UniqueKeys)
    }
    fn visit_f64<E>(self, _: f64) -> Result<Self, E> {
        Ok(UniqueKeys)
    }
    fn visit_str<E>(self, _: &str) -> Result<Self, E> {
        Ok(UniqueKeys)
    }
    fn visit_unit<E>(self) -> Result<Self, E> {
        Ok(UniqueKeys)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self, A::Error> {
        while seq.next_element::<UniqueKeys>()?.is_some() {}
        Ok(UniqueKeys)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self, A::Error> {
        let mut keys = HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            if keys.contains(&key) {
                return Err(A::Error::custom(format!("duplicate key {key:?}")));
            }
            map.next_value::<UniqueKeys>()?;
            keys.insert(key);
        }
        Ok(UniqueKeys)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;

    #[test]
    fn duplicate_keys_are_refused_at_any_depth() {
        let e = from_str::<Value>(r#"{"a": 1, "a": 2}"#).unwrap_err().to_string();
        assert!(e.contains("duplicate key \"a\""), "{e}");
        let e = from_str::<Value>(r#"{"x": [{"b": {"c": 1, "c": 1}}]}"#).unwrap_err().to_string();
        assert!(e.contains("duplicate key \"c\"") && e.contains("line 1"), "{e}");
        // The same key in sibling objects is not a duplicate.
        let v: Value = from_str(r#"[{"a": 1}, {"a": 2}, {"b": {"a": 3}}]"#).unwrap();
        assert_eq!(v[1]["a"], 2);
    }

    #[test]
    fn a_bom_is_skipped_and_other_faults_still_refused() {
        let v: Value = from_str("\u{feff}{\"a\": [1, 2.5, true, null, \"s\"]}").unwrap();
        assert_eq!(v["a"][1], 2.5);
        let v: Value = from_slice(b"\xef\xbb\xbf{\"a\": 1}").unwrap();
        assert_eq!(v["a"], 1);
        assert!(from_str::<Value>("{\"a\": NaN}").is_err());
        assert!(from_str::<Value>("{\"a\": 1} x").is_err());
        assert!(from_str::<Value>("\u{feff}\u{feff}{}").is_err());
        assert!(from_slice::<Value>(b"{\"a\": \"\xff\"}").is_err());
    }
}
