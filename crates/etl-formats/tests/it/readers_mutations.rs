//! Property tests of every reader against mutations of a valid file (docs/RELIABILITY.md,
//! "Property tests"): a number made NaN, 1e999, 1e308 or negative, a key dropped or
//! renamed, an array shortened. Each gives an error of one line naming the field (the
//! mutated key or one holding it), or the value the file now says: never a value that
//! differs from the file but for the documented defaults of optional keys.

use super::support;

use std::path::Path;

use etl_formats::thermal::{parse_thermal_table, THERMAL_TABLE_HEADER};
use etl_formats::{A0File, Calibration, Dataset, Observations, ThermalFile};
use proptest::prelude::*;
use support::formats::{finite, Format};
use support::mutate::{apply, difference, keys_along, sites, Mutation};

/// Whether `message` names one of `keys` (`_` and spaces alike: "focus law" names
/// `focus_law`).
fn names_a_key(message: &str, keys: &[&str]) -> bool {
    let m = message.to_lowercase().replace('_', " ");
    keys.iter().any(|k| m.contains(&k.to_lowercase().replace('_', " ")))
}

/// Mutates `value`'s file at the `pick`-th place and reads it.
fn mutated_file_is_refused_or_read_as_written<F: Format>(
    dir: &Path,
    value: &F,
    pick: usize,
) -> Result<(), TestCaseError> {
    let json = serde_json::to_value(value).unwrap();
    let all = sites(&json);
    let (place, mutation) = &all[pick % all.len()];
    let (written, text) = apply(&json, place, *mutation);
    let path = dir.join(format!("{}.json", F::NAME));
    std::fs::write(&path, &text).unwrap();
    let at = support::mutate::pattern(place);
    match F::load(&path) {
        Ok(read) => {
            prop_assert!(
                !matches!(mutation, Mutation::NaN | Mutation::Overflow),
                "{} {at} {mutation:?}: read as {read:?}",
                F::NAME
            );
            let read = serde_json::to_value(&read).unwrap();
            let d = difference(&written, &read, &mut vec![], F::OPTIONAL);
            prop_assert!(d.is_none(), "{} {at} {mutation:?}: a value other than the file's: {}", F::NAME, d.unwrap());
        }
        Err(e) => {
            let line = e.to_string();
            prop_assert!(!line.contains('\n'), "{} {at} {mutation:?}: {line}", F::NAME);
            let keys = keys_along(place);
            prop_assert!(
                names_a_key(&line, &keys),
                "{} {at} {mutation:?}: the message names none of {keys:?}: {line}",
                F::NAME
            );
        }
    }
    Ok(())
}

fn config() -> ProptestConfig {
    ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() }
}

macro_rules! mutations {
    ($name:ident, $ty:ty) => {
        proptest! {
            #![proptest_config(config())]
            #[test]
            fn $name(value in <$ty as Format>::strategy(), pick in any::<usize>()) {
                let dir = tempfile::tempdir().unwrap();
                mutated_file_is_refused_or_read_as_written(dir.path(), &value, pick)?;
            }
        }
    };
}

mutations!(calibration_mutations_are_refused_naming_the_field_or_read_as_written, Calibration);
mutations!(observations_mutations_are_refused_naming_the_field_or_read_as_written, Observations);
mutations!(dataset_mutations_are_refused_naming_the_field_or_read_as_written, Dataset);
mutations!(a0_mutations_are_refused_naming_the_field_or_read_as_written, A0File);
mutations!(thermal_mutations_are_refused_naming_the_field_or_read_as_written, ThermalFile);
mutations!(board_mutations_are_refused_naming_the_field_or_read_as_written, etl_formats::dataset::Board);

/// The thermal table's columns, in order.
const COLUMNS: [&str; 3] = ["temperature_c", "e_in_ma", "e_t_ma"];

proptest! {
    #![proptest_config(config())]

    /// A field of the thermal table made NaN, 1e999 or text is refused naming its column
    /// and line; one dropped, naming the line; the header renamed, naming the header; a row
    /// dropped reads as the shorter table, as written.
    #[test]
    fn thermal_table_mutations_are_refused_naming_the_field_or_read_as_written(
        rows in prop::collection::vec(prop::array::uniform3(finite()), 1..8),
        row in any::<usize>(),
        column in 0..3usize,
        what in 0..5u8,
    ) {
        let row = row % rows.len();
        let mut lines: Vec<Vec<String>> = rows.iter().map(|r| r.iter().map(|x| x.to_string()).collect()).collect();
        match what {
            0 => lines[row][column] = "NaN".into(),
            1 => lines[row][column] = "1e999".into(),
            2 => lines[row][column] = "12x".into(),
            3 => { lines[row].remove(column); }
            _ => { lines.remove(row); }
        }
        let mut text = format!("{THERMAL_TABLE_HEADER}\n");
        for l in &lines {
            text += &(l.join(",") + "\n");
        }
        match parse_thermal_table(&text, Path::new("t.csv")) {
            Ok(read) => {
                prop_assert_eq!(what, 4);
                let want: Vec<[f64; 3]> = rows.iter().enumerate().filter(|(i, _)| *i != row).map(|(_, r)| *r).collect();
                let got: Vec<[f64; 3]> = read.iter().map(|r| [r.temperature_c, r.e_in_ma, r.e_t_ma]).collect();
                prop_assert_eq!(got, want);
            }
            Err(e) => {
                let line = e.to_string();
                prop_assert!(!line.contains('\n'), "{}", line);
                if what == 4 {
                    // The only row dropped.
                    prop_assert!(rows.len() == 1 && line.contains("the table has a header but no data rows"), "{}", line);
                    return Ok(());
                }
                prop_assert!(line.contains(&format!("line {}", row + 2)), "{}", line);
                if what < 3 {
                    prop_assert!(line.contains(COLUMNS[column]), "{}", line);
                } else {
                    prop_assert!(line.contains("expected 3 comma-separated numbers, found 2 fields"), "{}", line);
                }
            }
        }
    }

    #[test]
    fn a_renamed_thermal_table_header_is_refused_naming_the_header(column in 0..3usize) {
        let mut names = COLUMNS.map(str::to_owned);
        names[column] += "_renamed";
        let text = format!("{}\n27,40,0.5\n", names.join(","));
        let e = parse_thermal_table(&text, Path::new("t.csv")).unwrap_err().to_string();
        prop_assert!(e.contains("line 1: header must be \"temperature_c,e_in_ma,e_t_ma\""), "{}", e);
    }
}
