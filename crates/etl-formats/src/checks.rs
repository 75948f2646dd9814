//! The checks every reader shares: numbers in a range, finite numbers, image sizes, and
//! the compact form in which messages print numbers.

use crate::{Error, Result};

/// A number as messages print it: [`etl_core::Compact`] (scientific notation outside
/// [1e-4, 1e5), so that 1e308 is `1e308`, not 309 digits; shortest round-trip digits inside).
pub fn compact(x: f64) -> String {
    etl_core::Compact(x).to_string()
}

/// `value` if it is in `range` (inclusive; NaN never is), else [`Error::InvalidInput`]
/// about `what` (a flag or a key) with the value (compact), whose message names both and
/// the range: `--aperture-mm NaN mm is outside [0, 50] mm`.
pub fn check_range(what: &str, value: f64, range: [f64; 2], unit: &str) -> Result<f64> {
    if (range[0]..=range[1]).contains(&value) {
        return Ok(value);
    }
    let [lo, hi] = range.map(compact);
    Err(Error::invalid_value(what, value, format!("{what} {} {unit} is outside [{lo}, {hi}] {unit}", compact(value))))
}

/// The first `(key, value)` whose value is given and not finite (NaN or infinite), so that
/// a validator's error names it ([`Error::invalid_value`]).
pub(crate) fn first_not_finite<'a>(
    numbers: impl IntoIterator<Item = (&'a str, Option<f64>)>,
) -> Option<(&'a str, f64)> {
    numbers.into_iter().find_map(|(key, x)| x.filter(|x| !x.is_finite()).map(|x| (key, x)))
}

/// The largest image side, px, and the most pixels an image may have: 65536 px and
/// 2^28 px (268 Mpx, a 16384 x 16384 sensor), beyond any camera etlcal calibrates; larger
/// is refused before anything is allocated for it.
pub const MAX_IMAGE_SIDE_PX: u32 = 65_536;
/// See [`MAX_IMAGE_SIDE_PX`].
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;
/// Checks `image_size` against [`MAX_IMAGE_SIDE_PX`] and [`MAX_IMAGE_PIXELS`] (`what`
/// names it: the error's `what` and the message's first word).
pub fn check_image_size(image_size: [u32; 2], what: &str) -> Result<()> {
    let [w, h] = image_size;
    if !(1..=MAX_IMAGE_SIDE_PX).contains(&w) || !(1..=MAX_IMAGE_SIDE_PX).contains(&h) {
        return Err(Error::invalid_value(
            what,
            image_size,
            format!("{what} [{w}, {h}] px: each side must be in [1, {MAX_IMAGE_SIDE_PX}] px"),
        ));
    }
    if u64::from(w) * u64::from(h) > MAX_IMAGE_PIXELS {
        return Err(Error::invalid_value(
            what,
            image_size,
            format!("{what} [{w}, {h}] px: more than {MAX_IMAGE_PIXELS} pixels (the documented limit)"),
        ));
    }
    Ok(())
}
