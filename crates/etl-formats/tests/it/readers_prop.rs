//! Property tests of every reader (docs/RELIABILITY.md, "Property tests"): (a) any valid
//! value a writer writes reads back equal; (b) any bytes, and any JSON shaped like the
//! format, give a value or a typed one-line error, never a panic. The mutations of valid
//! files are in readers_mutations.rs; the lens codec's properties in crates/etl-hw.

use super::support;

use std::path::Path;

use etl_formats::thermal::{parse_thermal_table, write_thermal_table, ThermalSample, THERMAL_TABLE_HEADER};
use etl_formats::{A0File, Calibration, Dataset, ErrorKind, Observations, ThermalFile};
use proptest::prelude::*;
use serde_json::Value;
use support::formats::{finite, Format};

fn config() -> ProptestConfig {
    ProptestConfig { cases: 128, failure_persistence: None, ..ProptestConfig::default() }
}

/// Writes `value` with its writer and reads it back with its reader: equal, and the text
/// parsed again gives the same.
fn round_trip<F: Format>(dir: &Path, value: &F) -> Result<(), TestCaseError> {
    let path = dir.join(format!("{}.json", F::NAME));
    value.save(&path).map_err(|e| TestCaseError::fail(format!("a valid {} is refused: {e}", F::NAME)))?;
    let back = F::load(&path).map_err(|e| TestCaseError::fail(format!("{} written is not read: {e}", F::NAME)))?;
    prop_assert_eq!(&back, value);
    Ok(())
}

/// `result` of reading bad input: a value (which then round-trips) or a typed error of
/// one line.
fn typed_one_line<F: Format>(dir: &Path, result: etl_formats::Result<F>) -> Result<(), TestCaseError> {
    match result {
        Ok(value) => round_trip(dir, &value),
        Err(e) => {
            let line = e.to_string();
            prop_assert!(!line.contains('\n'), "{} error of several lines: {line}", F::NAME);
            prop_assert!(
                matches!(e.kind(), ErrorKind::Parse | ErrorKind::Format | ErrorKind::InvalidInput | ErrorKind::Io),
                "{} error of kind {:?}: {line}",
                F::NAME,
                e.kind()
            );
            Ok(())
        }
    }
}

/// Reads `bytes` as a file of format `F`.
fn load_bytes<F: Format>(dir: &Path, bytes: &[u8]) -> etl_formats::Result<F> {
    let path = dir.join(format!("in-{}.json", F::NAME));
    std::fs::write(&path, bytes).unwrap();
    F::load(&path)
}

/// Every key of a valid value of `F` (at any depth), to build JSON the reader goes into.
fn keys_of<F: Format>() -> Vec<String> {
    fn walk(v: &Value, out: &mut Vec<String>) {
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    out.push(k.clone());
                    walk(x, out);
                }
            }
            Value::Array(a) => a.iter().for_each(|x| walk(x, out)),
            _ => {}
        }
    }
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let mut keys = vec![];
    for _ in 0..16 {
        let value = F::strategy().new_tree(&mut runner).unwrap().current();
        walk(&serde_json::to_value(&value).unwrap(), &mut keys);
    }
    keys.sort();
    keys.dedup();
    keys
}

/// JSON documents shaped like `F`: objects with its `"format"` tag (mostly) and keys drawn
/// from its own, values of every kind nested a few levels.
fn json_like<F: Format>() -> BoxedStrategy<Value> {
    let keys = keys_of::<F>();
    let key = prop_oneof![4 => proptest::sample::select(keys), 1 => "[a-z_]{1,8}"];
    let number = prop_oneof![
        finite().prop_map(Value::from),
        any::<i64>().prop_map(Value::from),
        any::<u64>().prop_map(Value::from)
    ];
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        number,
        "[ -~]{0,12}".prop_map(Value::String)
    ];
    let tree = leaf.prop_recursive(4, 48, 6, move |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..6).prop_map(Value::Array),
            prop::collection::vec((key.clone(), inner), 0..8).prop_map(|kv| Value::Object(kv.into_iter().collect())),
        ]
    });
    (tree, prop_oneof![5 => Just(Some(F::TAG)), 1 => Just(None)])
        .prop_map(|(v, tag)| {
            let mut object = match v {
                Value::Object(m) => m,
                other => [("x".to_owned(), other)].into_iter().collect(),
            };
            if let Some(tag) = tag {
                object.insert("format".into(), Value::from(tag));
            }
            Value::Object(object)
        })
        .boxed()
}

macro_rules! format_properties {
    ($module:ident, $ty:ty) => {
        mod $module {
            use super::*;

            proptest! {
                #![proptest_config(config())]

                #[test]
                fn a_written_value_reads_back_equal(value in <$ty as Format>::strategy()) {
                    let dir = tempfile::tempdir().unwrap();
                    round_trip(dir.path(), &value)?;
                }

                #[test]
                fn any_bytes_give_a_value_or_a_typed_one_line_error(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
                    let dir = tempfile::tempdir().unwrap();
                    typed_one_line(dir.path(), load_bytes::<$ty>(dir.path(), &bytes))?;
                }

                #[test]
                fn json_shaped_like_the_format_gives_a_value_or_a_typed_one_line_error(doc in json_like::<$ty>()) {
                    let dir = tempfile::tempdir().unwrap();
                    let text = serde_json::to_vec_pretty(&doc).unwrap();
                    typed_one_line(dir.path(), load_bytes::<$ty>(dir.path(), &text))?;
                }

                /// A valid file cut anywhere is refused (a torn write is never taken for a
                /// shorter value).
                #[test]
                fn a_valid_file_cut_short_is_refused(value in <$ty as Format>::strategy(), cut in 0.0..1.0f64) {
                    let dir = tempfile::tempdir().unwrap();
                    let text = serde_json::to_vec_pretty(&value).unwrap();
                    let at = ((text.len() - 1) as f64 * cut) as usize;
                    let e = load_bytes::<$ty>(dir.path(), &text[..at]).unwrap_err();
                    prop_assert!(!e.to_string().contains('\n'), "{e}");
                }
            }
        }
    };
}

format_properties!(calibration, Calibration);
format_properties!(observations, Observations);
format_properties!(dataset, Dataset);
format_properties!(a0, A0File);
format_properties!(thermal, ThermalFile);
format_properties!(board, etl_formats::dataset::Board);

/// Rows of the thermal table: any finite numbers.
fn table_rows() -> impl Strategy<Value = Vec<ThermalSample>> {
    prop::collection::vec(
        (finite(), finite(), finite()).prop_map(|(temperature_c, e_in_ma, e_t_ma)| ThermalSample {
            temperature_c,
            e_in_ma,
            e_t_ma,
        }),
        1..20,
    )
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn thermal_table_rows_read_back_equal(rows in table_rows()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        write_thermal_table(&path, &rows).unwrap();
        prop_assert_eq!(etl_formats::thermal::read_thermal_table(&path).unwrap(), rows);
    }

    #[test]
    fn thermal_table_text_gives_rows_or_a_one_line_error(text in "[0-9a-z_,.eE+\\- \\n\\r]{0,200}", header in any::<bool>()) {
        let text = if header { format!("{THERMAL_TABLE_HEADER}\n{text}") } else { text };
        match parse_thermal_table(&text, Path::new("t.csv")) {
            Ok(rows) => prop_assert!(rows.iter().all(|r| r.temperature_c.is_finite() && r.e_in_ma.is_finite() && r.e_t_ma.is_finite())),
            Err(e) => {
                prop_assert_eq!(e.kind(), ErrorKind::Parse);
                prop_assert!(!e.to_string().contains('\n'), "{}", e);
            }
        }
    }

    #[test]
    fn thermal_table_bytes_give_rows_or_a_one_line_error(bytes in prop::collection::vec(any::<u8>(), 0..256)) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        std::fs::write(&path, &bytes).unwrap();
        if let Err(e) = etl_formats::thermal::read_thermal_table(&path) {
            prop_assert!(matches!(e.kind(), ErrorKind::Parse | ErrorKind::Io), "{:?}: {}", e.kind(), e);
            prop_assert!(!e.to_string().contains('\n'), "{}", e);
        }
    }
}
