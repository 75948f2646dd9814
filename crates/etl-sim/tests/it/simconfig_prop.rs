//! Property tests of the `etlcal.simconfig/1` reader (docs/RELIABILITY.md, "Property
//! tests"), as the formats crate has for its files: a valid configuration written reads
//! back equal; any bytes, and any JSON shaped like a configuration, give a configuration
//! that validates or an error of one line, never a panic.

use etl_sim::simulate::{NoiseModel, SettingRig, SimConfig, SimRig, CONFIG_FORMAT};
use proptest::prelude::*;
use serde_json::Value;

fn config() -> ProptestConfig {
    ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() }
}

/// Noise levels within the reader's practical ranges.
fn noise() -> impl Strategy<Value = NoiseModel> {
    (0.0..10.0f64, 0.0..10.0f64, 0.0..50.0f64, 0.0..100.0f64, 0.0..1.0f64, 0.0..1000.0f64)
        .prop_map(|(xy_mm, z_mm, e_ma, px, kf0_rel, pp_px)| NoiseModel { xy_mm, z_mm, e_ma, px, kf0_rel, pp_px })
}

/// Valid configurations: either rig, a setting rig on the paper's only.
fn valid() -> impl Strategy<Value = SimConfig> {
    let setting = (prop::collection::vec(-290.0..290.0f64, 1..8), 1..40usize, 0.01..5.0f64, 0.1..20.0f64, 0.0..30.0f64)
        .prop_map(|(e_com_ma, views_per_setting, blur_px, aperture_mm, max_tilt_deg)| SettingRig {
            e_com_ma,
            views_per_setting,
            blur_px,
            aperture_mm,
            max_tilt_deg,
        });
    (any::<u64>(), any::<bool>(), noise(), prop::option::of(setting)).prop_map(|(seed, strong, noise, setting)| {
        let rig = if strong && setting.is_none() { SimRig::Strong } else { SimRig::Paper };
        SimConfig { format: CONFIG_FORMAT.into(), seed, rig, noise, setting_rig: setting }
    })
}

/// `bytes` written to a file and read: a valid configuration, or one line of error.
fn read_bytes(bytes: &[u8]) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sim.json");
    std::fs::write(&path, bytes).unwrap();
    match SimConfig::load(&path) {
        Ok(c) => prop_assert!(c.validate().is_ok()),
        Err(e) => prop_assert!(!e.to_string().contains('\n'), "{e}"),
    }
    Ok(())
}

/// JSON objects with the configuration's keys (and others) holding any JSON values.
fn json_like() -> impl Strategy<Value = Value> {
    let key = prop::sample::select(vec![
        "format",
        "seed",
        "rig",
        "noise",
        "setting_rig",
        "xy_mm",
        "px",
        "e_com_ma",
        "views_per_setting",
        "blur_px",
        "other",
    ])
    .prop_map(str::to_owned);
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::from),
        any::<i64>().prop_map(Value::from),
        any::<f64>().prop_map(|x| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)),
        prop::sample::select(vec![CONFIG_FORMAT, "paper", "strong", ""]).prop_map(Value::from),
    ];
    let tree = leaf.prop_recursive(3, 24, 6, move |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..5).prop_map(Value::Array),
            prop::collection::btree_map(key.clone(), inner, 0..6).prop_map(|m| Value::Object(m.into_iter().collect())),
        ]
    });
    tree.prop_map(|v| match v {
        Value::Object(mut m) => {
            m.insert("format".into(), Value::from(CONFIG_FORMAT));
            Value::Object(m)
        }
        other => other,
    })
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn a_written_configuration_reads_back_equal(c in valid()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sim.json");
        std::fs::write(&path, serde_json::to_vec_pretty(&c).unwrap()).unwrap();
        prop_assert_eq!(SimConfig::load(&path).unwrap(), c);
    }

    #[test]
    fn any_bytes_give_a_configuration_or_a_one_line_error(bytes in prop::collection::vec(any::<u8>(), 0..256)) {
        read_bytes(&bytes)?;
    }

    #[test]
    fn json_shaped_like_a_configuration_gives_one_or_a_one_line_error(doc in json_like()) {
        read_bytes(&serde_json::to_vec(&doc).unwrap())?;
    }
}
