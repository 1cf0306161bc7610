//! JSON values read only as far as the keypoint reader looks into them, without building the
//! document: a syntax check that allocates nothing ([`check`]), objects whose values stay text
//! ([`Object`]), a list's first item ([`first`]) and its items one at a time ([`each_item`]),
//! each read as a number, a name and a point ([`Item`]).

use posecoach_core::Vec3;
use serde::de::{self, DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use serde_json::value::RawValue;
use std::borrow::{Borrow, Cow};
use std::fmt;
use std::ops::Deref;

/// An object's keys, in order, each with its value's text (a key given twice keeps its first
/// place and its last value, as `serde_json`'s own map does).
pub type Object<'a> = indexmap::IndexMap<Key<'a>, &'a RawValue>;

/// An object's key, borrowed from the text where it holds no escape.
#[derive(Debug, PartialEq, Eq, Hash)]
pub struct Key<'a>(Cow<'a, str>);

impl Deref for Key<'_> {
    type Target = str;
    fn deref(&self) -> &str {
        &self.0
    }
}

impl Borrow<str> for Key<'_> {
    fn borrow(&self) -> &str {
        &self.0
    }
}

impl<'de> Deserialize<'de> for Key<'de> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> Visitor<'de> for Visit {
            type Value = Key<'de>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a key")
            }
            fn visit_borrowed_str<E>(self, v: &'de str) -> Result<Key<'de>, E> {
                Ok(Key(Cow::Borrowed(v)))
            }
            fn visit_str<E>(self, v: &str) -> Result<Key<'de>, E> {
                Ok(Key(Cow::Owned(v.to_string())))
            }
        }
        deserializer.deserialize_str(Visit)
    }
}

/// Keys a point's confidence is found under, the first present taken.
pub const CONFIDENCE_KEYS: [&str; 5] = [
    "visibility",
    "presence",
    "score",
    "confidence",
    "likelihood",
];

/// Keys a point's name is found under, the first holding a string taken.
pub const NAME_KEYS: [&str; 4] = ["name", "label", "type", "joint"];

/// What a JSON value's text starts as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `{`.
    Object,
    /// `[`.
    Array,
    /// `null`.
    Null,
    /// A number, a string or a boolean.
    Scalar,
}

/// What `value` is, from its first character (a raw value's text starts at the value).
pub fn kind(value: &RawValue) -> Kind {
    match value.get().as_bytes().first() {
        Some(b'{') => Kind::Object,
        Some(b'[') => Kind::Array,
        Some(b'n') => Kind::Null,
        _ => Kind::Scalar,
    }
}

/// Checks that `bytes` are a stream of JSON values as `serde_json` parses them into values
/// (numbers in range, strings valid UTF-8 with valid escapes), without keeping any.
///
/// # Errors
/// The parser's error for the first fault, naming its line and column.
pub fn check(bytes: &[u8]) -> Result<(), serde_json::Error> {
    serde_json::Deserializer::from_slice(bytes)
        .into_iter::<Checked>()
        .try_for_each(|value| value.map(|_| ()))
}

/// Any JSON value, parsed in full and dropped.
struct Checked;

impl<'de> Deserialize<'de> for Checked {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(Checked)
    }
}

impl<'de> Visitor<'de> for Checked {
    type Value = Checked;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<Checked, E> {
        Ok(Checked)
    }
    fn visit_i64<E>(self, _: i64) -> Result<Checked, E> {
        Ok(Checked)
    }
    fn visit_u64<E>(self, _: u64) -> Result<Checked, E> {
        Ok(Checked)
    }
    fn visit_f64<E>(self, _: f64) -> Result<Checked, E> {
        Ok(Checked)
    }
    fn visit_str<E>(self, _: &str) -> Result<Checked, E> {
        Ok(Checked)
    }
    fn visit_unit<E>(self) -> Result<Checked, E> {
        Ok(Checked)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Checked, A::Error> {
        while seq.next_element::<Checked>()?.is_some() {}
        Ok(Checked)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Checked, A::Error> {
        while map.next_entry::<Checked, Checked>()?.is_some() {}
        Ok(Checked)
    }
}

/// The object `value` holds, if it holds one.
pub fn object(value: &RawValue) -> Option<Object<'_>> {
    match kind(value) {
        Kind::Object => serde_json::from_str(value.get()).ok(),
        _ => None,
    }
}

/// The items of the array `value` holds, as text, if it holds one.
pub fn items(value: &RawValue) -> Option<Vec<&RawValue>> {
    match kind(value) {
        Kind::Array => serde_json::from_str(value.get()).ok(),
        _ => None,
    }
}

/// The first item of the array `value` holds, if it holds one with an item.
pub fn first(value: &RawValue) -> Option<&RawValue> {
    match kind(value) {
        Kind::Array => serde_json::from_str::<First>(value.get()).ok()?.0,
        _ => None,
    }
}

/// An array's first item, the others passed over.
struct First<'a>(Option<&'a RawValue>);

impl<'de> Deserialize<'de> for First<'de> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> Visitor<'de> for Visit {
            type Value = First<'de>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an array")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<First<'de>, A::Error> {
                let first = seq.next_element()?;
                while seq.next_element::<IgnoredAny>()?.is_some() {}
                Ok(First(first))
            }
        }
        deserializer.deserialize_seq(Visit)
    }
}

/// A number as a keypoint file writes one: `None` for any other value.
pub fn number(value: &RawValue) -> Option<f64> {
    serde_json::from_str::<Number>(value.get()).ok()?.0
}

/// A value that may be a number.
#[derive(Clone, Copy, Default)]
struct Number(Option<f64>);

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> Visitor<'de> for Visit {
            type Value = Number;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("any JSON value")
            }
            fn visit_i64<E>(self, v: i64) -> Result<Number, E> {
                Ok(Number(Some(v as f64)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Number, E> {
                Ok(Number(Some(v as f64)))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Number, E> {
                Ok(Number(Some(v)))
            }
            fn visit_bool<E>(self, _: bool) -> Result<Number, E> {
                Ok(Number(None))
            }
            fn visit_str<E>(self, _: &str) -> Result<Number, E> {
                Ok(Number(None))
            }
            fn visit_unit<E>(self) -> Result<Number, E> {
                Ok(Number(None))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Number, A::Error> {
                IgnoredAny.visit_seq(seq).map(|_| Number(None))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Number, A::Error> {
                IgnoredAny.visit_map(map).map(|_| Number(None))
            }
        }
        deserializer.deserialize_any(Visit)
    }
}

/// A value that may be a string.
struct Text(Option<String>);

impl<'de> Deserialize<'de> for Text {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> Visitor<'de> for Visit {
            type Value = Text;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("any JSON value")
            }
            fn visit_str<E>(self, v: &str) -> Result<Text, E> {
                Ok(Text(Some(v.to_string())))
            }
            fn visit_i64<E>(self, _: i64) -> Result<Text, E> {
                Ok(Text(None))
            }
            fn visit_u64<E>(self, _: u64) -> Result<Text, E> {
                Ok(Text(None))
            }
            fn visit_f64<E>(self, _: f64) -> Result<Text, E> {
                Ok(Text(None))
            }
            fn visit_bool<E>(self, _: bool) -> Result<Text, E> {
                Ok(Text(None))
            }
            fn visit_unit<E>(self) -> Result<Text, E> {
                Ok(Text(None))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Text, A::Error> {
                IgnoredAny.visit_seq(seq).map(|_| Text(None))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Text, A::Error> {
                IgnoredAny.visit_map(map).map(|_| Text(None))
            }
        }
        deserializer.deserialize_any(Visit)
    }
}

/// A point's position and confidence (1 where it states none); `None` for `null`; `Err` for a
/// value that is no point.
pub type Point = Result<Option<(Vec3, f64)>, ()>;

/// A landmark list's item, or a named landmark's value, as far as the reader looks into it.
pub struct Item {
    /// The number it is, if it is one (a flat list's coordinate).
    pub number: Option<f64>,
    /// The name it gives itself ([`NAME_KEYS`]).
    pub name: Option<String>,
    /// The point it is: `[x, y, z]`, `[x, y, z, confidence]`, `{"x", "y", "z"}` with a
    /// confidence under one of [`CONFIDENCE_KEYS`], or `null`.
    pub point: Point,
}

impl Item {
    fn other() -> Item {
        Item {
            number: None,
            name: None,
            point: Err(()),
        }
    }
}

/// The point of a position's numbers and a confidence, if it has one: each must be a finite
/// number.
pub fn point(xyz: [Option<f64>; 3], confidence: Option<Option<f64>>) -> Point {
    let finite = |v: Option<f64>| v.filter(|v| v.is_finite()).ok_or(());
    let [x, y, z] = [finite(xyz[0])?, finite(xyz[1])?, finite(xyz[2])?];
    let confidence = match confidence {
        None => 1.0,
        Some(c) => finite(c)?,
    };
    Ok(Some((Vec3::new(x as f32, y as f32, z as f32), confidence)))
}

/// The point `value` is.
pub fn point_of(value: &RawValue) -> Point {
    serde_json::from_str::<Item>(value.get()).map_or(Err(()), |item| item.point)
}

impl<'de> Deserialize<'de> for Item {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(ItemVisitor)
    }
}

struct ItemVisitor;

/// A key of a point object the reader looks at.
enum Field {
    Axis(usize),
    Confidence(usize),
    Name(usize),
    Other,
}

impl<'de> Deserialize<'de> for Field {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> Visitor<'de> for Visit {
            type Value = Field;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a key")
            }
            fn visit_str<E>(self, v: &str) -> Result<Field, E> {
                let at = |keys: &[&str]| keys.iter().position(|k| *k == v);
                Ok(match v {
                    "x" => Field::Axis(0),
                    "y" => Field::Axis(1),
                    "z" => Field::Axis(2),
                    _ => at(&CONFIDENCE_KEYS)
                        .map(Field::Confidence)
                        .or_else(|| at(&NAME_KEYS).map(Field::Name))
                        .unwrap_or(Field::Other),
                })
            }
        }
        deserializer.deserialize_str(Visit)
    }
}

impl<'de> Visitor<'de> for ItemVisitor {
    type Value = Item;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_unit<E>(self) -> Result<Item, E> {
        Ok(Item {
            point: Ok(None),
            ..Item::other()
        })
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Item, E> {
        self.visit_f64(v as f64)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Item, E> {
        self.visit_f64(v as f64)
    }
    fn visit_f64<E>(self, v: f64) -> Result<Item, E> {
        Ok(Item {
            number: Some(v),
            ..Item::other()
        })
    }
    fn visit_bool<E>(self, _: bool) -> Result<Item, E> {
        Ok(Item::other())
    }
    fn visit_str<E>(self, _: &str) -> Result<Item, E> {
        Ok(Item::other())
    }
    /// `[x, y, z]` or `[x, y, z, confidence]`.
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Item, A::Error> {
        let mut values = [None; 4];
        let mut len = 0;
        while let Some(Number(v)) = seq.next_element()? {
            if let Some(slot) = values.get_mut(len) {
                *slot = v;
            }
            len += 1;
        }
        let [x, y, z, c] = values;
        let point = match len {
            3 => point([x, y, z], None),
            4 => point([x, y, z], Some(c)),
            _ => Err(()),
        };
        Ok(Item {
            point,
            ..Item::other()
        })
    }
    /// `{"x", "y", "z"}` with a confidence, or a named point; a key given twice keeps its last
    /// value.
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Item, A::Error> {
        let mut xyz = [None; 3];
        let mut confidences: [Option<Option<f64>>; 5] = [None; 5];
        let mut names: [Option<Option<String>>; 4] = Default::default();
        while let Some(field) = map.next_key::<Field>()? {
            match field {
                Field::Axis(a) => xyz[a] = map.next_value::<Number>()?.0,
                Field::Confidence(c) => confidences[c] = Some(map.next_value::<Number>()?.0),
                Field::Name(n) => names[n] = Some(map.next_value::<Text>()?.0),
                Field::Other => {
                    map.next_value::<IgnoredAny>()?;
                }
            }
        }
        Ok(Item {
            number: None,
            name: names.into_iter().flatten().flatten().next(),
            point: point(xyz, confidences.into_iter().flatten().next()),
        })
    }
}

/// Calls `each` on every item of the array `list` holds, in order, until it fails.
///
/// # Errors
/// The first of `each`'s errors; `syntax` of the parser's message for text that is not an
/// array (which the reader never gives, having checked it).
pub fn each_item<E>(
    list: &RawValue,
    each: impl FnMut(Item) -> Result<(), E>,
    syntax: impl FnOnce(String) -> E,
) -> Result<(), E> {
    let mut walk = Walk { each, failed: None };
    let mut parser = serde_json::Deserializer::from_str(list.get());
    match (&mut walk).deserialize(&mut parser) {
        Ok(()) => Ok(()),
        Err(e) => Err(walk.failed.take().unwrap_or_else(|| syntax(e.to_string()))),
    }
}

/// An array walked item by item; `failed` holds what stopped it.
struct Walk<F, E> {
    each: F,
    failed: Option<E>,
}

impl<'de, F: FnMut(Item) -> Result<(), E>, E> DeserializeSeed<'de> for &mut Walk<F, E> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
        deserializer.deserialize_seq(self)
    }
}

impl<'de, F: FnMut(Item) -> Result<(), E>, E> Visitor<'de> for &mut Walk<F, E> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an array")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while let Some(item) = seq.next_element::<Item>()? {
            if let Err(e) = (self.each)(item) {
                self.failed = Some(e);
                return Err(de::Error::custom("stopped"));
            }
        }
        Ok(())
    }
}
