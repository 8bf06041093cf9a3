//! A manifest's `motion.animation`: which of the glTF file's animations play along the path.

use aabench_renderer::scene::number;
use serde::Deserialize;

/// Which of the glTF file's animations play (by `name` or by `index`, each one or a list, or
/// `all`: one of them), on one clock from `start_s` seconds into it: frame f of the measured
/// window shows them at `start_s + f · time_step_s`, and the still is their pose at
/// `start_s`, unless the warm-up before the window would begin before their first key: then
/// the window starts that much later ([`super::Timeline`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationPick {
    #[serde(default, deserialize_with = "names")]
    pub name: Option<Vec<String>>,
    #[serde(default, deserialize_with = "indices")]
    pub index: Option<Vec<usize>>,
    /// Every animation of the file.
    pub all: Option<bool>,
    #[serde(default)]
    pub start_s: f64,
}

/// What an [`AnimationPick`] names, once checked ([`AnimationPick::check`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Picked<'a> {
    Names(&'a [String]),
    Indices(&'a [usize]),
    All,
}

impl AnimationPick {
    /// Checks that it names one way (and no name or index twice) and a start within bounds.
    /// On failure, the field (under `animation`) and why.
    pub fn check(&self) -> Result<(), (String, String)> {
        let fail = |field: &str, message: String| Err((field.to_string(), message));
        let given = [self.name.is_some(), self.index.is_some(), self.all.is_some()];
        match given {
            [true, true, _] => return fail("index", "give names or indices, not both".into()),
            [_, true, true] | [true, _, true] => {
                return fail("all", "give `all`, or names or indices, not both".into());
            }
            [false, false, false] => {
                return fail(
                    "name",
                    "give the animation's name (or a list), its index, or `\"all\": true`".into(),
                );
            }
            _ => {}
        }
        if self.all == Some(false) {
            return fail(
                "all",
                "false picks nothing: leave the animation out, or pick by name or index".into(),
            );
        }
        let listed = |field: &str, items: Vec<String>| {
            if items.is_empty() {
                return fail(field, "the list is empty: pick at least one animation".into());
            }
            match (1..items.len()).find(|&i| items[..i].contains(&items[i])) {
                Some(i) => fail(field, format!("{} is listed twice", items[i])),
                None => Ok(()),
            }
        };
        match self.picked() {
            Picked::Names(names) => listed("name", names.iter().map(|n| format!("{n:?}")).collect())?,
            Picked::Indices(indices) => listed("index", indices.iter().map(|i| i.to_string()).collect())?,
            Picked::All => {}
        }
        if !(self.start_s.is_finite() && (0.0..=MAX_ANIMATION_START_S).contains(&self.start_s)) {
            return fail(
                "start_s",
                format!("{} must be within [0, {MAX_ANIMATION_START_S}] seconds", number(self.start_s)),
            );
        }
        Ok(())
    }

    /// What it names: its names, its indices, or every animation.
    pub fn picked(&self) -> Picked<'_> {
        match (&self.name, &self.index) {
            (Some(names), _) => Picked::Names(names),
            (None, Some(indices)) => Picked::Indices(indices),
            (None, None) => Picked::All,
        }
    }
}

/// `"walk"` or `["walk", "wave"]`.
fn names<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<Option<Vec<String>>, D::Error> {
    one_or_many(deserializer, "an animation's name, or a list of names")
}

/// `0` or `[0, 3]`.
fn indices<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<Option<Vec<usize>>, D::Error> {
    one_or_many(deserializer, "an animation's index (a whole number from 0), or a list of them")
}

/// One value or a list of them, with `expected` as what the message says it wants where it
/// is neither. A visitor rather than an untagged enum, so that the error points at the value.
fn one_or_many<'de, D, T>(deserializer: D, expected: &'static str) -> Result<Option<Vec<T>>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let visitor = OneOrMany::<T> { expected, list: true, read: std::marker::PhantomData };
    deserializer.deserialize_any(visitor).map(Some)
}

/// Reads a string or a whole number as one `T`, or where `list` a list of them.
struct OneOrMany<T> {
    expected: &'static str,
    list: bool,
    read: std::marker::PhantomData<T>,
}

impl<'de, T: Deserialize<'de>> OneOrMany<T> {
    /// `value` as a `T`; where it is not one, an error that says what was expected.
    fn one<E, V>(&self, value: V, unexpected: serde::de::Unexpected) -> Result<T, E>
    where
        E: serde::de::Error,
        V: serde::de::IntoDeserializer<'de, E>,
    {
        T::deserialize(value.into_deserializer()).map_err(|_: E| E::invalid_type(unexpected, self))
    }
}

impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for OneOrMany<T> {
    type Value = Vec<T>;

    fn expecting(&self, formatter: &mut std::fmt::Formatter) -> std::fmt::Result {
        formatter.write_str(self.expected)
    }

    fn visit_str<E: serde::de::Error>(self, value: &str) -> Result<Vec<T>, E> {
        self.one(value, serde::de::Unexpected::Str(value)).map(|one| vec![one])
    }

    fn visit_u64<E: serde::de::Error>(self, value: u64) -> Result<Vec<T>, E> {
        self.one(value, serde::de::Unexpected::Unsigned(value)).map(|one| vec![one])
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<T>, A::Error> {
        if !self.list {
            return Err(serde::de::Error::invalid_type(serde::de::Unexpected::Seq, &self));
        }
        let element =
            || OneOrMany::<T> { expected: self.expected, list: false, read: std::marker::PhantomData };
        let mut values = Vec::new();
        while let Some(one) = seq.next_element_seed(element())? {
            values.extend(one);
        }
        Ok(values)
    }
}

impl<'de, T: Deserialize<'de>> serde::de::DeserializeSeed<'de> for OneOrMany<T> {
    type Value = Vec<T>;

    fn deserialize<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<Vec<T>, D::Error> {
        deserializer.deserialize_any(self)
    }
}

/// The latest start an animation may be given, in seconds (a day: past it, an f32 keyframe time
/// no longer resolves a frame).
pub const MAX_ANIMATION_START_S: f64 = 86_400.0;
