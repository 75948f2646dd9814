//! `etlcal.thermal/1`: a fitted temperature-compensation surface (section 5.2.2) with the
//! ranges it was fitted over, and its input table (CSV `temperature_c,e_in_ma,e_t_ma`).

use std::fmt::Write as _;
use std::path::Path;

use etl_core::thermal::{ThermalCalibration, ThermalSurface};
use serde::{Deserialize, Serialize};

use super::{read_json, write_atomic, write_json};
use crate::{Error, Result};

/// The `"format"` value of a thermal file.
pub const THERMAL_FORMAT: &str = "etlcal.thermal/1";

/// The header line of the thermal input table.
pub const THERMAL_TABLE_HEADER: &str = "temperature_c,e_in_ma,e_t_ma";

/// The content of an `etlcal.thermal/1` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalFile {
    /// Always [`THERMAL_FORMAT`].
    pub format: String,
    /// c_0..c_9 of E_T for 1, T, E, T^2, T E, E^2, T^3, T^2 E, T E^2, E^3 (mA, degC).
    pub coefficients: [f64; 10],
    /// RMS of the fit residuals, mA.
    pub rms_ma: f64,
    /// [min, max] temperature of the fitted samples, degC.
    pub t_range_c: [f64; 2],
    /// [min, max] driver current of the fitted samples, mA.
    pub e_in_range_ma: [f64; 2],
}

impl ThermalFile {
    /// The file for a fitted calibration and its RMS.
    pub fn new(cal: &ThermalCalibration, rms_ma: f64) -> Self {
        ThermalFile {
            format: THERMAL_FORMAT.to_owned(),
            coefficients: cal.surface.coefficients,
            rms_ma,
            t_range_c: cal.t_range_c,
            e_in_range_ma: cal.e_in_range_ma,
        }
    }

    /// The paper's surface over the paper's procedure ranges (RMS 0.2106 mA, section 5.2.2).
    pub fn paper() -> Self {
        Self::new(&ThermalCalibration::PAPER, 0.2106)
    }

    /// The core's view of the file.
    pub fn calibration(&self) -> ThermalCalibration {
        ThermalCalibration {
            surface: ThermalSurface { coefficients: self.coefficients },
            t_range_c: self.t_range_c,
            e_in_range_ma: self.e_in_range_ma,
        }
    }

    /// Checks the numbers (finite, ordered ranges, RMS >= 0); `path` names the file in
    /// the message.
    pub fn validate(&self, path: &Path) -> Result<()> {
        let bad = |message: String| Err(Error::Parse { path: path.to_owned(), message });
        if let Err(e) = self.calibration().validate() {
            return bad(e.to_string());
        }
        if !(self.rms_ma.is_finite() && self.rms_ma >= 0.0) {
            return bad(format!("rms_ma = {} must be a finite number >= 0", self.rms_ma));
        }
        Ok(())
    }

    /// Reads and validates a thermal file.
    pub fn load(path: &Path) -> Result<Self> {
        let f: ThermalFile = read_json(path, THERMAL_FORMAT)?;
        f.validate(path)?;
        Ok(f)
    }

    /// Validates and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate(path)?;
        write_json(path, self)
    }
}

/// One row of the thermal input table: E_T measured at (T, E_in).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalSample {
    /// Lens temperature, degC.
    pub temperature_c: f64,
    /// Driver current before compensation, mA.
    pub e_in_ma: f64,
    /// The compensating current E_T (refocused E_in - original E_in), mA.
    pub e_t_ma: f64,
}

/// Parses the thermal table: a header line [`THERMAL_TABLE_HEADER`] (spaces around fields
/// allowed), then one row of three finite numbers per line; blank lines are skipped.
/// Errors name the file and the line.
pub fn parse_thermal_table(text: &str, path: &Path) -> Result<Vec<ThermalSample>> {
    let err = |line: usize, message: String| Error::Parse {
        path: path.to_owned(),
        message: format!("line {line}: {message}"),
    };
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_start_matches('\u{feff}').trim()));
    let header = lines.by_ref().find(|(_, l)| !l.is_empty());
    match header {
        Some((n, h)) => {
            let fields: Vec<&str> = h.split(',').map(str::trim).collect();
            if fields.join(",") != THERMAL_TABLE_HEADER {
                return Err(err(n, format!("header must be \"{THERMAL_TABLE_HEADER}\", found \"{}\"", excerpt(h))));
            }
        }
        None => return Err(err(1, format!("empty table (expected the header \"{THERMAL_TABLE_HEADER}\")"))),
    }
    let names = ["temperature_c", "e_in_ma", "e_t_ma"];
    let mut rows = Vec::new();
    for (n, line) in lines {
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != 3 {
            return Err(err(n, format!("expected 3 comma-separated numbers, found {} fields", fields.len())));
        }
        let mut v = [0.0; 3];
        for (k, (field, name)) in fields.iter().zip(names).enumerate() {
            let x: f64 =
                field.parse().map_err(|_| err(n, format!("{name} = \"{}\" is not a number", excerpt(field))))?;
            if !x.is_finite() {
                return Err(err(n, format!("{name} = {} is not a finite number", excerpt(field))));
            }
            v[k] = x;
        }
        rows.push(ThermalSample { temperature_c: v[0], e_in_ma: v[1], e_t_ma: v[2] });
    }
    if rows.is_empty() {
        return Err(Error::Parse { path: path.to_owned(), message: "the table has a header but no data rows".into() });
    }
    Ok(rows)
}

/// At most the first 40 characters of a field quoted in a message (a 10 MB field must not
/// become a 10 MB error line), with `...` when cut.
fn excerpt(field: &str) -> String {
    match field.char_indices().nth(40) {
        Some((at, _)) => format!("{}...", &field[..at]),
        None => field.to_owned(),
    }
}

/// Reads the thermal table from `path` (see [`parse_thermal_table`]); a path that is not
/// a regular file is refused before it is opened.
pub fn read_thermal_table(path: &Path) -> Result<Vec<ThermalSample>> {
    crate::output::check_input(path)?;
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_owned(), source })?;
    parse_thermal_table(&text, path)
}

/// Writes the thermal table atomically, numbers printed so that they read back exactly.
pub fn write_thermal_table(path: &Path, rows: &[ThermalSample]) -> Result<()> {
    let mut text = String::from(THERMAL_TABLE_HEADER);
    text.push('\n');
    for (i, r) in rows.iter().enumerate() {
        let numbers =
            [("temperature_c", Some(r.temperature_c)), ("e_in_ma", Some(r.e_in_ma)), ("e_t_ma", Some(r.e_t_ma))];
        if let Some((key, x)) = crate::first_not_finite(numbers) {
            let message = format!("{}: thermal table rows must be finite", path.display());
            return Err(Error::invalid_value(format!("rows[{i}].{key}"), x, message));
        }
        // `{}` on f64 prints the shortest string that parses back to the same number.
        let _ = writeln!(text, "{},{},{}", r.temperature_c, r.e_in_ma, r.e_t_ma);
    }
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_huge_field_is_cut_in_the_message() {
        let text = format!("{THERMAL_TABLE_HEADER}\n30,{},1\n", "9".repeat(1_000_000) + "x");
        let e = parse_thermal_table(&text, Path::new("t.csv")).unwrap_err().to_string();
        assert!(e.len() < 150 && e.contains("e_in_ma = \"9999") && e.contains("...\" is not a number"), "{e}");
    }

    use super::*;

    #[test]
    fn table_round_trip_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let rows = vec![
            ThermalSample { temperature_c: 27.0, e_in_ma: 40.0, e_t_ma: 0.1 + 0.2 },
            ThermalSample { temperature_c: 36.5, e_in_ma: 240.0, e_t_ma: -3.25e-3 },
        ];
        write_thermal_table(&p, &rows).unwrap();
        assert_eq!(read_thermal_table(&p).unwrap(), rows);
        let path = Path::new("x.csv");
        let ok = parse_thermal_table("\u{feff}temperature_c, e_in_ma ,e_t_ma\r\n\n27,40,0.5\r\n", path).unwrap();
        assert_eq!(ok.len(), 1);
        for (text, needle) in [
            ("", "empty table"),
            ("t,e,et\n1,2,3\n", "header must be"),
            ("temperature_c,e_in_ma,e_t_ma\n", "no data rows"),
            ("temperature_c,e_in_ma,e_t_ma\n27,40\n", "line 2: expected 3"),
            ("temperature_c,e_in_ma,e_t_ma\n27,40,abc\n", "line 2: e_t_ma = \"abc\""),
            ("temperature_c,e_in_ma,e_t_ma\n27,40,1\nNaN,40,1\n", "line 3: temperature_c = NaN is not a finite"),
        ] {
            let e = parse_thermal_table(text, path).unwrap_err().to_string();
            assert!(e.contains(needle), "{e}");
        }
    }

    #[test]
    fn thermal_file_round_trip_and_validation() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("thermal.json");
        let f = ThermalFile::paper();
        f.save(&p).unwrap();
        let back = ThermalFile::load(&p).unwrap();
        assert_eq!(back, f);
        assert_eq!(back.calibration(), ThermalCalibration::PAPER);
        let bad = ThermalFile { t_range_c: [37.0, 27.0], ..f.clone() };
        assert!(bad.save(&dir.path().join("bad.json")).is_err());
        assert!(!dir.path().join("bad.json").exists());
        std::fs::write(&p, r#"{"format": "etlcal.thermal/1", "coefficients": [0,0,0,0,0,0,0,0,0,0], "rms_ma": 0, "t_range_c": [1, 2], "e_in_range_ma": [1, 2], "extra": 1}"#).unwrap();
        assert!(ThermalFile::load(&p).unwrap_err().to_string().contains("unknown field"));
        std::fs::write(&p, r#"{"format": "etlcal.thermal/1", "coefficients": [0,0,0], "rms_ma": 0, "t_range_c": [1, 2], "e_in_range_ma": [1, 2]}"#).unwrap();
        assert!(ThermalFile::load(&p).is_err());
    }
}
