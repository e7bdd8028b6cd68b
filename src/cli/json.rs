//! JSON output without silent nulls: JSON has no infinity and no NaN, and `serde_json` writes
//! both as `null`, which reads like "absent". [`to_string_pretty`] writes an infinite number as
//! the string `"inf"` or `"-inf"` (the documented marker: a bound that is off, a round-off
//! level beyond the largest double) and refuses NaN, naming the key where it was found: a
//! quantity that could not be computed is an error, never a value.
//!
//! ```
//! #[derive(serde::Serialize)]
//! struct Report {
//!     bound: f64,
//!     residual: f64,
//! }
//!
//! let text = dpc::cli::json::to_string_pretty(&Report { bound: f64::INFINITY, residual: 1e-15 });
//! assert!(text.unwrap().contains(r#""bound": "inf""#));
//! let err = dpc::cli::json::to_string_pretty(&Report { bound: 1.0, residual: f64::NAN });
//! assert_eq!(err.unwrap_err().to_string(), "`residual` is NaN: it could not be computed");
//! ```

use std::cell::RefCell;
use std::fmt::Display;

use serde::ser::{self, Serialize, Serializer};
use thiserror::Error;

/// Why a value could not be written as JSON.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum JsonError {
    /// A number is NaN.
    #[error("`{key}` is NaN: it could not be computed")]
    NaN {
        /// The dotted key (`law.theorem_3_1_residual`, `final_error.theta`, `poles[2]`).
        key: String,
    },
    /// The serialiser failed otherwise.
    #[error("{0}")]
    Other(String),
}

/// Read back a number that [`to_string_pretty`] wrote: a JSON number, or `"inf"` / `"-inf"`.
///
/// # Errors
/// The deserialiser's error for anything else.
pub fn number_or_inf<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Number {
        Finite(f64),
        Marker(String),
    }
    match <Number as serde::Deserialize>::deserialize(d)? {
        Number::Finite(x) => Ok(x),
        Number::Marker(m) if m == "inf" => Ok(f64::INFINITY),
        Number::Marker(m) if m == "-inf" => Ok(f64::NEG_INFINITY),
        Number::Marker(m) => Err(serde::de::Error::custom(format!(
            "expected a number, \"inf\" or \"-inf\", found \"{m}\""
        ))),
    }
}

/// `value` as pretty-printed JSON, infinities as `"inf"` / `"-inf"`.
///
/// # Errors
/// [`JsonError::NaN`] naming the first NaN found.
pub fn to_string_pretty<T: Serialize + ?Sized>(value: &T) -> Result<String, JsonError> {
    let path = RefCell::new(Vec::new());
    let nan = RefCell::new(None);
    let mut out = Vec::new();
    let mut json = serde_json::Serializer::pretty(&mut out);
    let result = value.serialize(Finite {
        inner: &mut json,
        path: &path,
        nan: &nan,
    });
    if let Some(key) = nan.into_inner() {
        return Err(JsonError::NaN { key });
    }
    result.map_err(|e| JsonError::Other(e.to_string()))?;
    String::from_utf8(out).map_err(|e| JsonError::Other(e.to_string()))
}

/// A serializer that passes everything to `inner` except non-finite floats.
struct Finite<'a, S> {
    inner: S,
    path: &'a RefCell<Vec<String>>,
    nan: &'a RefCell<Option<String>>,
}

/// A value to be serialised through [`Finite`].
struct Wrap<'a, T: ?Sized> {
    value: &'a T,
    path: &'a RefCell<Vec<String>>,
    nan: &'a RefCell<Option<String>>,
}

impl<T: Serialize + ?Sized> Serialize for Wrap<'_, T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.value.serialize(Finite {
            inner: serializer,
            path: self.path,
            nan: self.nan,
        })
    }
}

/// Compound serializers ([`ser::SerializeSeq`] and the like) of `inner`, wrapping each
/// element and tracking the key path.
struct Compound<'a, C> {
    inner: C,
    path: &'a RefCell<Vec<String>>,
    nan: &'a RefCell<Option<String>>,
    index: usize,
}

impl<'a, S> Finite<'a, S> {
    fn float<E: ser::Error>(&self, v: f64) -> Result<Option<&'static str>, E> {
        if v.is_nan() {
            let key = key_text(&self.path.borrow());
            self.nan.borrow_mut().get_or_insert(key.clone());
            return Err(E::custom(format!("`{key}` is NaN")));
        }
        Ok(if v == f64::INFINITY {
            Some("inf")
        } else if v == f64::NEG_INFINITY {
            Some("-inf")
        } else {
            None
        })
    }
}

fn key_text(path: &[String]) -> String {
    let mut out = String::new();
    for part in path {
        if part.starts_with('[') || out.is_empty() {
            out.push_str(part);
        } else {
            out.push('.');
            out.push_str(part);
        }
    }
    out
}

macro_rules! forward {
    ($($method:ident($ty:ty)),* $(,)?) => {
        $(fn $method(self, v: $ty) -> Result<Self::Ok, Self::Error> {
            self.inner.$method(v)
        })*
    };
}

impl<'a, S: Serializer> Serializer for Finite<'a, S> {
    type Ok = S::Ok;
    type Error = S::Error;
    type SerializeSeq = Compound<'a, S::SerializeSeq>;
    type SerializeTuple = Compound<'a, S::SerializeTuple>;
    type SerializeTupleStruct = Compound<'a, S::SerializeTupleStruct>;
    type SerializeTupleVariant = Compound<'a, S::SerializeTupleVariant>;
    type SerializeMap = Compound<'a, S::SerializeMap>;
    type SerializeStruct = Compound<'a, S::SerializeStruct>;
    type SerializeStructVariant = Compound<'a, S::SerializeStructVariant>;

    forward!(
        serialize_bool(bool),
        serialize_i8(i8),
        serialize_i16(i16),
        serialize_i32(i32),
        serialize_i64(i64),
        serialize_i128(i128),
        serialize_u8(u8),
        serialize_u16(u16),
        serialize_u32(u32),
        serialize_u64(u64),
        serialize_u128(u128),
        serialize_char(char),
        serialize_str(&str),
        serialize_bytes(&[u8]),
    );

    fn serialize_f32(self, v: f32) -> Result<Self::Ok, Self::Error> {
        match self.float(f64::from(v))? {
            Some(marker) => self.inner.serialize_str(marker),
            None => self.inner.serialize_f32(v),
        }
    }

    fn serialize_f64(self, v: f64) -> Result<Self::Ok, Self::Error> {
        match self.float(v)? {
            Some(marker) => self.inner.serialize_str(marker),
            None => self.inner.serialize_f64(v),
        }
    }

    fn serialize_none(self) -> Result<Self::Ok, Self::Error> {
        self.inner.serialize_none()
    }

    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<Self::Ok, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        self.inner.serialize_some(&Wrap { value, path, nan })
    }

    fn serialize_unit(self) -> Result<Self::Ok, Self::Error> {
        self.inner.serialize_unit()
    }

    fn serialize_unit_struct(self, name: &'static str) -> Result<Self::Ok, Self::Error> {
        self.inner.serialize_unit_struct(name)
    }

    fn serialize_unit_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
    ) -> Result<Self::Ok, Self::Error> {
        self.inner.serialize_unit_variant(name, index, variant)
    }

    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        value: &T,
    ) -> Result<Self::Ok, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        self.inner
            .serialize_newtype_struct(name, &Wrap { value, path, nan })
    }

    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<Self::Ok, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        self.inner
            .serialize_newtype_variant(name, index, variant, &Wrap { value, path, nan })
    }

    fn serialize_seq(self, len: Option<usize>) -> Result<Self::SerializeSeq, Self::Error> {
        let c = self.inner.serialize_seq(len)?;
        Ok(Compound {
            inner: c,
            path: self.path,
            nan: self.nan,
            index: 0,
        })
    }

    fn serialize_tuple(self, len: usize) -> Result<Self::SerializeTuple, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        let c = self.inner.serialize_tuple(len)?;
        Ok(Compound {
            inner: c,
            path,
            nan,
            index: 0,
        })
    }

    fn serialize_tuple_struct(
        self,
        name: &'static str,
        len: usize,
    ) -> Result<Self::SerializeTupleStruct, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        let c = self.inner.serialize_tuple_struct(name, len)?;
        Ok(Compound {
            inner: c,
            path,
            nan,
            index: 0,
        })
    }

    fn serialize_tuple_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<Self::SerializeTupleVariant, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        let c = self
            .inner
            .serialize_tuple_variant(name, index, variant, len)?;
        Ok(Compound {
            inner: c,
            path,
            nan,
            index: 0,
        })
    }

    fn serialize_map(self, len: Option<usize>) -> Result<Self::SerializeMap, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        let c = self.inner.serialize_map(len)?;
        Ok(Compound {
            inner: c,
            path,
            nan,
            index: 0,
        })
    }

    fn serialize_struct(
        self,
        name: &'static str,
        len: usize,
    ) -> Result<Self::SerializeStruct, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        let c = self.inner.serialize_struct(name, len)?;
        Ok(Compound {
            inner: c,
            path,
            nan,
            index: 0,
        })
    }

    fn serialize_struct_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<Self::SerializeStructVariant, Self::Error> {
        let (path, nan) = (self.path, self.nan);
        let c = self
            .inner
            .serialize_struct_variant(name, index, variant, len)?;
        Ok(Compound {
            inner: c,
            path,
            nan,
            index: 0,
        })
    }

    fn collect_str<T: Display + ?Sized>(self, value: &T) -> Result<Self::Ok, Self::Error> {
        self.inner.collect_str(value)
    }

    fn is_human_readable(&self) -> bool {
        self.inner.is_human_readable()
    }
}

macro_rules! sequence {
    ($trait:ident, $method:ident) => {
        impl<C: ser::$trait> ser::$trait for Compound<'_, C> {
            type Ok = C::Ok;
            type Error = C::Error;

            fn $method<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Self::Error> {
                let key = format!("[{}]", self.index);
                self.index += 1;
                self.path.borrow_mut().push(key);
                let (path, nan) = (self.path, self.nan);
                let r = self.inner.$method(&Wrap { value, path, nan });
                self.path.borrow_mut().pop();
                r
            }

            fn end(self) -> Result<Self::Ok, Self::Error> {
                self.inner.end()
            }
        }
    };
}

sequence!(SerializeSeq, serialize_element);
sequence!(SerializeTuple, serialize_element);
sequence!(SerializeTupleStruct, serialize_field);
sequence!(SerializeTupleVariant, serialize_field);

/// The text of a map key, for the key path.
fn map_key<T: Serialize + ?Sized>(key: &T) -> String {
    match serde_json::to_value(key) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(other) => other.to_string(),
        Err(_) => "?".to_string(),
    }
}

impl<C: ser::SerializeMap> ser::SerializeMap for Compound<'_, C> {
    type Ok = C::Ok;
    type Error = C::Error;

    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), Self::Error> {
        // The key's text names the value that follows.
        self.path.borrow_mut().push(map_key(key));
        let (path, nan) = (self.path, self.nan);
        self.inner.serialize_key(&Wrap {
            value: key,
            path,
            nan,
        })
    }

    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Self::Error> {
        let (path, nan) = (self.path, self.nan);
        let r = self.inner.serialize_value(&Wrap { value, path, nan });
        self.path.borrow_mut().pop();
        r
    }

    fn end(self) -> Result<Self::Ok, Self::Error> {
        self.inner.end()
    }
}

macro_rules! fields {
    ($trait:ident) => {
        impl<C: ser::$trait> ser::$trait for Compound<'_, C> {
            type Ok = C::Ok;
            type Error = C::Error;

            fn serialize_field<T: Serialize + ?Sized>(
                &mut self,
                key: &'static str,
                value: &T,
            ) -> Result<(), Self::Error> {
                let wrapped = Wrap {
                    value,
                    path: self.path,
                    nan: self.nan,
                };
                let inner = &mut self.inner;
                self.path.borrow_mut().push(key.to_string());
                let r = inner.serialize_field(key, &wrapped);
                self.path.borrow_mut().pop();
                r
            }

            fn skip_field(&mut self, key: &'static str) -> Result<(), Self::Error> {
                self.inner.skip_field(key)
            }

            fn end(self) -> Result<Self::Ok, Self::Error> {
                self.inner.end()
            }
        }
    };
}

fields!(SerializeStruct);
fields!(SerializeStructVariant);

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[derive(serde::Serialize)]
    struct Inner {
        values: Vec<f64>,
        pair: Option<[f64; 2]>,
    }

    #[derive(serde::Serialize)]
    struct Outer {
        by_name: BTreeMap<String, f64>,
        inner: Inner,
    }

    #[test]
    fn infinities_are_markers_and_nan_is_an_error_naming_the_key() {
        let mut by_name = BTreeMap::new();
        by_name.insert("theta".to_string(), f64::NEG_INFINITY);
        let ok = Outer {
            by_name: by_name.clone(),
            inner: Inner {
                values: vec![1.0, f64::INFINITY],
                pair: Some([0.5, -2.0]),
            },
        };
        let text = to_string_pretty(&ok).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["by_name"]["theta"], "-inf");
        assert_eq!(v["inner"]["values"], serde_json::json!([1.0, "inf"]));
        assert_eq!(v["inner"]["pair"], serde_json::json!([0.5, -2.0]));
        assert!(!text.contains("null"), "{text}");

        let bad = Outer {
            by_name: by_name.clone(),
            inner: Inner {
                values: vec![1.0],
                pair: Some([0.5, f64::NAN]),
            },
        };
        let e = to_string_pretty(&bad).unwrap_err();
        assert_eq!(
            e,
            JsonError::NaN {
                key: "inner.pair[1]".into()
            }
        );
        by_name.insert("psi".to_string(), f64::NAN);
        let bad = Outer {
            by_name,
            inner: Inner {
                values: vec![],
                pair: None,
            },
        };
        assert_eq!(
            to_string_pretty(&bad).unwrap_err().to_string(),
            "`by_name.psi` is NaN: it could not be computed"
        );
    }
}
