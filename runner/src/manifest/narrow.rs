//! The manifest's 32-bit float settings, read as the numbers written. serde_json reads a
//! number into an f32 by rounding its f64, which turns a number past f32's range (1e39) into
//! infinity, and the range check after it would then quote `inf` where the file says 1e39.
//! These read the f64 and refuse what an f32 cannot hold, quoting the number as written; the
//! path to the field comes with the error.

use serde::{Deserialize, Deserializer};

use aabench_renderer::scene::number;

/// An f32 setting.
pub fn f32<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f32, D::Error> {
    narrow(f64::deserialize(deserializer)?)
}

/// An optional f32 setting (give it `#[serde(default)]` too).
pub fn option<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<f32>, D::Error> {
    Option::<f64>::deserialize(deserializer)?.map(narrow).transpose()
}

/// Three f32 components (a colour).
pub fn triple<'de, D: Deserializer<'de>>(deserializer: D) -> Result<[f32; 3], D::Error> {
    let [a, b, c] = <[f64; 3]>::deserialize(deserializer)?;
    Ok([narrow(a)?, narrow(b)?, narrow(c)?])
}

fn narrow<E: serde::de::Error>(value: f64) -> Result<f32, E> {
    let narrowed = value as f32;
    if value.is_finite() && !narrowed.is_finite() {
        return Err(E::custom(format!(
            "{} is past the largest number this setting holds (a 32-bit float: ±3.4e38)",
            number(value)
        )));
    }
    Ok(narrowed)
}
