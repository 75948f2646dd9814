//! File formats (DESIGN.md): JSON with a `"format"` field naming format and version
//! (`etlcal.<name>/<version>`); lengths in mm, currents in mA, temperatures in degC.
//!
//! Readers refuse an unknown format or version with a message naming it. Unknown fields
//! are refused too (`deny_unknown_fields` on every format struct): a misspelt key would
//! otherwise silently fall back to a default, which for a calibration is worse than an
//! error. Writers are atomic: a temporary file in the same directory, then a rename, so a
//! failed run leaves earlier output whole.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::error::{Error, Result};

pub mod a0;
pub mod calibration;
pub mod dataset;
pub mod observations;
pub mod thermal;

/// Reads `path` as JSON of format `expected` (e.g. `"etlcal.calibration/1"`).
///
/// The `"format"` field is checked before the rest is parsed, so a file of another
/// format or version gets a message naming both, not a confusing field error.
pub fn read_json<T: DeserializeOwned>(path: &Path, expected: &str) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_owned(), source })?;
    parse_json(&text, path, expected)
}

/// Parses JSON text of format `expected`; `path` is used in messages only.
pub fn parse_json<T: DeserializeOwned>(text: &str, path: &Path, expected: &str) -> Result<T> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })?;
    let found = value.get("format").and_then(|f| f.as_str()).unwrap_or("missing");
    if found != expected {
        return Err(Error::Format { path: path.to_owned(), found: found.to_owned(), expected: expected.to_owned() });
    }
    serde_json::from_value(value).map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })
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
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| Error::Io { path: path.to_owned(), source };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(Error::Io {
            path: path.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "the output directory does not exist"),
        });
    }
    let name = path.file_name().ok_or_else(|| Error::InvalidInput(format!("{}: not a file path", path.display())))?;
    let tmp = dir.join(format!(".{}.tmp{}", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
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
