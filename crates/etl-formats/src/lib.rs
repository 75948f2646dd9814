//! etl-formats: every `etlcal.*` file format, its one validator, and its conversions to
//! etl-core types. This is the crate a vision service depends on: it reads a calibration
//! and gives the camera at any lens current and temperature, with nothing of the
//! calibration machinery (detection, solvers' drivers, plots, the command line).
//!
//! ```
//! use std::path::Path;
//! use etl_formats::{Calibration, Trust};
//!
//! # fn main() -> etl_formats::Result<()> {
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/service/calibration.json");
//! let cal = Calibration::load(Path::new(path))?; // refuses a file that fails its checks
//! // The camera at the lens's driver current and temperature: E_com = E_in - E_T(T, E_in)
//! // (Eq. 7-8) with the thermal calibration the file keeps; a temperature, current or
//! // E_com outside the calibrated ranges is refused unless extrapolation is asked for.
//! let (e_in_ma, temperature_c) = (150.0, 35.0);
//! let camera = cal.at(e_in_ma, temperature_c, Trust::Refuse)?;
//! assert!((camera.e_com_ma() - 143.485).abs() < 1e-3);
//! assert!(cal.at(150.0, 80.0, Trust::Refuse).is_err());
//!
//! // K at that setting, a world point's pixel, and a pixel without distortion.
//! let k = camera.intrinsics();
//! assert!(k.fx > 1000.0 && k.fy > 1000.0);
//! let pixel = camera.project([10.0, 8.0, 20.0])?;
//! let ideal = camera.undistort_point(pixel)?;
//! assert!((ideal[0] - pixel[0]).abs() < 5.0 && (ideal[1] - pixel[1]).abs() < 5.0);
//! # Ok(())
//! # }
//! ```
//!
//! File formats (docs/FORMATS.md): JSON with a `"format"` field naming format and version
//! (`etlcal.<name>/<version>`); lengths in mm, currents in mA, temperatures in degC.
//!
//! Readers refuse an unknown format or version with a message naming it. Unknown fields
//! are refused too (`deny_unknown_fields` on every format struct): a misspelt key would
//! otherwise silently fall back to a default, which for a calibration is worse than an
//! error. Each format has one `validate`, run by its reader and its writer (the command
//! line and Python alike). Writers are atomic: a temporary file in the same directory,
//! then a rename, so a failed run leaves earlier output whole.

use std::io::Write;
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;

pub mod a0;
pub mod board;
pub mod calibration;
mod checks;
pub mod dataset;
mod error;
pub mod export;
mod input_value;
mod json_path;
pub mod lens_dynamics;
pub mod lens_setting;
pub mod memory;
pub mod model_selection;
pub mod npy;
pub mod observations;
pub mod optics;
pub mod output;
pub mod plan;
pub mod rig;
pub mod rig_dataset;
pub mod thermal;

pub(crate) use checks::first_not_finite;
pub use checks::{check_image_size, check_range, compact, MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE_PX};
pub use error::{Error, ErrorKind, Result};
pub use input_value::InputValue;

pub use a0::A0File;
pub use board::{Board, Checkerboard};
pub use calibration::{Calibration, ThermalRef};
pub use dataset::Dataset;
pub use etl_core::model::{CameraModel, Distortion, Intrinsics};
pub use etl_core::runtime::{Camera, CameraAt, Extrapolated, SettingKind, Trust};
pub use etl_core::thermal::{Compensation, ThermalCalibration, ThermalSurface};
pub use lens_dynamics::LensDynamicsFile;
pub use observations::Observations;
pub use thermal::ThermalFile;

/// The largest JSON file the readers take: 1 GiB, more than a thousand times a large
/// rig's observations (10,000 views of a 9 x 7 board are about 60 MB). Anything larger is
/// refused before it is read, so that a wrong path (a disk image, a log) cannot take the
/// machine's memory.
pub const MAX_JSON_BYTES: u64 = 1 << 30;

/// Reads `path` as JSON of format `expected` (e.g. `"etlcal.calibration/1"`).
///
/// The `"format"` field is checked before the rest is parsed, so a file of another
/// format or version gets a message naming both, not a confusing field error.
/// A path that is not a regular file (a FIFO, a device, a directory) is refused before it
/// is opened ([`output::check_input`]), and so is a file larger than [`MAX_JSON_BYTES`]
/// (before anything is allocated for it).
pub fn read_json<T: DeserializeOwned>(path: &Path, expected: &str) -> Result<T> {
    if let Some(m) = output::check_input(path)? {
        if m.len() > MAX_JSON_BYTES {
            return Err(Error::invalid_value(
                "input",
                path,
                format!(
                    "{}: {} bytes, more than the {MAX_JSON_BYTES} an etlcal JSON file may hold: refused before reading",
                    path.display(),
                    m.len()
                ),
            ));
        }
    }
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_owned(), source })?;
    parse_json(&text, path, expected)
}

/// Parses JSON text of format `expected`; `path` is used in messages only.
pub fn parse_json<T: DeserializeOwned>(text: &str, path: &Path, expected: &str) -> Result<T> {
    // Malformed JSON is located by the path of the value it breaks in (any shape will do).
    let parse_error = |e: serde_json::Error| Error::Parse { path: path.to_owned(), message: at_field(text, e) };
    // The tag first, then the typed value straight from the text: no serde_json::Value
    // tree, which allocates a map per point and was most of the time of reading an
    // observations file. Files etlcal writes lead with the tag, read without a scan.
    let tag = match leading_format_tag(text) {
        Some(tag) => tag,
        None => serde_json::from_str::<FormatTag>(text).map_err(parse_error)?.0,
    };
    let found = tag.as_deref().unwrap_or("missing");
    if found != expected {
        return Err(Error::Format { path: path.to_owned(), found: found.to_owned(), expected: expected.to_owned() });
    }
    serde_json::from_str(text).map_err(|e| Error::Parse { path: path.to_owned(), message: at_field(text, e) })
}

/// The message of `e`, an error of parsing `text`, led by the path of the field it stopped
/// at (`kf_x: invalid length 3, expected an array of length 4 at line 9 column 3`;
/// `views[2].points[0].pixel[1]: ...`), found from its position ([`json_path`]).
fn at_field(text: &str, e: serde_json::Error) -> String {
    match json_path::path_at(text, e.line(), e.column()) {
        Some(path) => format!("{path}: {e}"),
        None => e.to_string(),
    }
}

/// The tag of a document that opens with `{"format": "<string>"`, read without looking
/// further (the typed parse that follows checks the rest); `None` for any other opening.
fn leading_format_tag(text: &str) -> Option<Option<String>> {
    let json_ws: &[char] = &[' ', '\t', '\n', '\r'];
    let rest = text.trim_start_matches(json_ws).strip_prefix('{')?;
    let rest = rest.trim_start_matches(json_ws).strip_prefix("\"format\"")?;
    let rest = rest.trim_start_matches(json_ws).strip_prefix(':')?;
    // One value off a stream: the text after it (the rest of the object) is not read.
    match serde_json::Deserializer::from_str(rest).into_iter::<String>().next() {
        Some(Ok(tag)) => Some(Some(tag)),
        _ => None,
    }
}

/// The string `"format"` field of a JSON document, `None` if the document is not an
/// object or the field is missing or not a string; everything else is skipped unbuilt.
struct FormatTag(Option<String>);

impl<'de> serde::Deserialize<'de> for FormatTag {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(FormatTagVisitor)
    }
}

/// Whether an object key is `"format"`.
struct IsFormatKey(bool);

impl<'de> serde::Deserialize<'de> for IsFormatKey {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = IsFormatKey;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("an object key")
            }
            fn visit_str<E: serde::de::Error>(self, key: &str) -> std::result::Result<IsFormatKey, E> {
                Ok(IsFormatKey(key == "format"))
            }
        }
        d.deserialize_str(V)
    }
}

struct FormatTagVisitor;

impl<'de> serde::de::Visitor<'de> for FormatTagVisitor {
    type Value = FormatTag;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON document")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> std::result::Result<FormatTag, A::Error> {
        let mut found = None;
        while let Some(IsFormatKey(is_format)) = map.next_key()? {
            if is_format {
                // The last of repeated keys, as a serde_json::Value map would keep.
                found = map.next_value::<serde_json::Value>()?.as_str().map(str::to_owned);
            } else {
                map.next_value::<serde::de::IgnoredAny>()?;
            }
        }
        Ok(FormatTag(found))
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<FormatTag, A::Error> {
        while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {}
        Ok(FormatTag(None))
    }

    fn visit_bool<E: serde::de::Error>(self, _: bool) -> std::result::Result<FormatTag, E> {
        Ok(FormatTag(None))
    }

    fn visit_i64<E: serde::de::Error>(self, _: i64) -> std::result::Result<FormatTag, E> {
        Ok(FormatTag(None))
    }

    fn visit_u64<E: serde::de::Error>(self, _: u64) -> std::result::Result<FormatTag, E> {
        Ok(FormatTag(None))
    }

    fn visit_f64<E: serde::de::Error>(self, _: f64) -> std::result::Result<FormatTag, E> {
        Ok(FormatTag(None))
    }

    fn visit_str<E: serde::de::Error>(self, _: &str) -> std::result::Result<FormatTag, E> {
        Ok(FormatTag(None))
    }

    fn visit_unit<E: serde::de::Error>(self) -> std::result::Result<FormatTag, E> {
        Ok(FormatTag(None))
    }
}

/// Writes `value` as pretty JSON to `path` atomically (temp file + rename).
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut bytes =
        serde_json::to_vec_pretty(value).map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

/// Writes `bytes` to `path` atomically: a temporary file in the same directory is written,
/// flushed to disk and renamed over `path`. On any error `path` is untouched and the
/// temporary file removed. The parent directory must exist (it is not created: a
/// misspelt output directory is an error, not a surprise tree).
///
/// The policy of [`output`]: a symlink is written through (its target is replaced, the
/// link kept), an existing output must be a regular file and writable, and a replaced
/// file keeps its permission bits; temporaries of killed runs (`.NAME.tmpPID`) are removed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| Error::Output { path: path.to_owned(), source };
    let (target, dir, name) = output::resolve_output(path)?;
    if !dir.is_dir() {
        return Err(Error::Output {
            path: path.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "the output directory does not exist"),
        });
    }
    output::check_paths(&[], &[output::Output::File(&target)]).map_err(|e| match e {
        Error::Output { source, .. } => Error::Output { path: path.to_owned(), source },
        other => other,
    })?;
    if output::is_own_temp(&target) {
        // A file set's temporary, renamed by the set: a temporary of it would be one more
        // file a kill leaves behind.
        return output::write_synced(&target, bytes).map_err(io);
    }
    output::remove_stale_temps(&dir, &name);
    let tmp = output::temp_sibling(&dir, &name);
    let mode = output::kept_mode(&target);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        if let Some(mode) = mode {
            f.set_permissions(mode)?;
        }
        f.sync_all()?;
        std::fs::rename(&tmp, &target)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
}

/// The setting of a camera in words, as messages name it: `"E_com 148.900 mA"` (to the
/// uA), or `"focal power 12.5000 dpt"` (to 1e-4 dpt, the driver's resolution is 5e-3)
/// for a focal-power calibration's camera.
pub fn setting_label(c: &CameraAt) -> String {
    match c.setting_kind() {
        SettingKind::Current => format!("E_com {:.3} mA", c.e_com_ma()),
        SettingKind::FocalPower => format!("focal power {:.4} dpt", c.focal_power_dpt()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize, serde::Deserialize, Debug, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Doc {
        format: String,
        x: f64,
    }

    #[test]
    fn round_trip_and_format_checks() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.json");
        let d = Doc { format: "etlcal.test/1".into(), x: 1.5 };
        write_json(&p, &d).unwrap();
        assert_eq!(read_json::<Doc>(&p, "etlcal.test/1").unwrap(), d);
        let e = read_json::<Doc>(&p, "etlcal.test/2").unwrap_err().to_string();
        assert!(e.contains("etlcal.test/1") && e.contains("etlcal.test/2"), "{e}");
        std::fs::write(&p, r#"{"format": "etlcal.test/1", "x": 1, "y": 2}"#).unwrap();
        let e = read_json::<Doc>(&p, "etlcal.test/1").unwrap_err().to_string();
        assert!(e.contains("unknown field"), "{e}");
    }

    #[test]
    fn the_format_tag_is_read_from_objects_only() {
        let p = Path::new("t.json");
        let format_of = |text: &str| match parse_json::<Doc>(text, p, "etlcal.test/1") {
            Err(Error::Format { found, .. }) => found,
            other => panic!("{text}: {other:?}"),
        };
        // Not an object, or no string "format": "missing", as before any field is read.
        for text in
            ["[1, {\"format\": \"x\"}]", "3", "\"etlcal.test/1\"", "null", "{\"format\": 1, \"x\": 2}", "{\"x\": 2}"]
        {
            assert_eq!(format_of(text), "missing", "{text}");
        }
        // The tag is found wherever it is, escapes and nesting included.
        assert_eq!(format_of(r#"{"x": {"format": "inner"}, "form\u0061t": "etlcal.test/9"}"#), "etlcal.test/9");
        // Malformed JSON and a bad field are parse errors naming the place.
        for (text, needle) in [
            ("{\"format\": \"etlcal.test/1\", \"x\": }", "line 1"),
            ("{\"format\": \"etlcal.test/1\"}", "missing field `x`"),
        ] {
            match parse_json::<Doc>(text, p, "etlcal.test/1") {
                Err(Error::Parse { message, .. }) => assert!(message.contains(needle), "{message}"),
                other => panic!("{text}: {other:?}"),
            }
        }
        // A leading tag of another format is named before the rest is read, even if the
        // rest is broken; a leading tag of this format leaves the rest to the typed parse.
        assert_eq!(format_of(" \n{ \"format\" :\"etlcal.test/2\", \"x\": "), "etlcal.test/2");
        assert!(matches!(
            parse_json::<Doc>("{\"format\": \"etlcal.test/1\", \"x\": 1", p, "etlcal.test/1"),
            Err(Error::Parse { .. })
        ));
        let d: Doc = parse_json(r#"{"x": 2, "format": "etlcal.test/1"}"#, p, "etlcal.test/1").unwrap();
        assert_eq!(d, Doc { format: "etlcal.test/1".into(), x: 2.0 });
    }

    #[test]
    fn missing_directory_is_an_error_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("missing").join("a.json");
        assert!(write_json(&p, &Doc { format: "f".into(), x: 0.0 }).is_err());
        assert!(!dir.path().join("missing").exists());
    }

    #[test]
    fn failed_write_leaves_the_old_file_whole() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.json");
        std::fs::write(&p, "old").unwrap();
        // A directory where the temp file would go makes the write fail.
        let tmp = dir.path().join(format!(".a.json.tmp{}", std::process::id()));
        std::fs::create_dir(&tmp).unwrap();
        assert!(write_atomic(&p, b"new").is_err());
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old");
    }
}

/// The README's Rust example, compiled and run with the doctests (its other code blocks
/// are marked `sh` and `python`, which rustdoc leaves alone; the Python one runs in
/// `crates/etl-py/tests/test_readme.py`).
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
