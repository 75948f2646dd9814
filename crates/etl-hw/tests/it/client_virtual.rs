//! The client against the virtual lens over a real pseudo-terminal: every command.
#![cfg(unix)] // the pseudo-terminal virtual lens

use std::time::Duration;

use etl_core::lens::Lens;
use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::codec::scaling::FirmwareType;
use etl_hw::codec::{Command, Mode, Reply};
use etl_hw::virtual_lens::{VirtualLens, VirtualLensConfig};
use etl_hw::HwError;
use proptest::prelude::*;

fn spawn(config: VirtualLensConfig) -> (VirtualLens, LensClient) {
    let device = VirtualLens::spawn(config).unwrap();
    let client =
        LensClient::open(device.path(), OpenOptions { timeout: Duration::from_millis(300), ..Default::default() })
            .unwrap();
    (device, client)
}

/// Waits until the device has processed what was written (fire-and-forget commands have
/// no reply to wait for): a query round trip.
fn sync(client: &LensClient) {
    client.current_ma().unwrap();
}

#[test]
fn identify_reads_everything() {
    let (_device, client) =
        spawn(VirtualLensConfig { upper_limit_code: 3000, lower_limit_code: -1000, ..Default::default() });
    let info = client.identify().unwrap();
    assert_eq!(info.firmware_type, FirmwareType::Other(b'C'));
    assert_eq!(info.firmware_version, "3.8.1.5");
    assert_eq!(info.lens_serial, "ETLV0001");
    assert_eq!(info.max_current_ma, 292.84);
    assert!((info.upper_limit_ma - 3000.0 * 292.84 / 4095.0).abs() < 1e-9);
    assert!((info.lower_limit_ma + 1000.0 * 292.84 / 4095.0).abs() < 1e-9);
    assert_eq!(info.status, [0, 0, 0, 0b100]); // no temperature limits yet
    for cmd in [Command::FirmwareBranch, Command::PartNumber, Command::DeviceId, Command::AnalogInput] {
        assert!(client.transact(cmd).unwrap().is_some(), "{cmd:?}");
    }
    assert_eq!(client.transact(Command::DeviceId).unwrap(), Some(Reply::DeviceId(*b"LD4VIRT1")));
}

#[test]
fn set_and_get_current_and_temperature() {
    let (device, client) = spawn(VirtualLensConfig { initial_temperature_c: Some(31.3), ..Default::default() });
    let r = client.set_current_ma(123.4).unwrap();
    assert!(!r.clamped);
    assert!((r.commanded_ma - 123.4).abs() <= 0.5 * 292.84 / 4095.0 + 1e-12);
    let back = client.current_ma().unwrap();
    assert_eq!(back, r.commanded_ma);
    assert_eq!(device.state().e_in_ma, r.commanded_ma);
    let t = client.temperature_c().unwrap();
    assert!((t - 31.3).abs() <= 1.0 / 32.0 + 0.01, "{t}");
    // Negative currents are valid.
    client.set_current_ma(-50.0).unwrap();
    assert!((client.current_ma().unwrap() + 50.0).abs() < 0.04);
}

#[test]
fn handshake_zeroes_the_current_and_reconnect_without_it_keeps_it() {
    let device = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
    {
        let c = LensClient::open(device.path(), OpenOptions::default()).unwrap();
        c.set_current_ma(150.0).unwrap();
        sync(&c);
    }
    // Without Start the lens keeps its current.
    let c = LensClient::open(device.path(), OpenOptions::default()).unwrap();
    assert!((c.current_ma().unwrap() - 150.0).abs() < 0.04);
    drop(c);
    // With Start it is zeroed.
    let c = LensClient::open(device.path(), OpenOptions { handshake: true, ..Default::default() }).unwrap();
    assert_eq!(c.current_ma().unwrap(), 0.0);
    assert_eq!(device.received().handshakes, 1);
}

#[test]
fn limits_clamp_and_nan_is_refused() {
    let (device, client) =
        spawn(VirtualLensConfig { upper_limit_code: 2800, lower_limit_code: 0, ..Default::default() });
    let [lo, hi] = client.limits_ma();
    assert_eq!(lo, 0.0);
    let r = client.set_current_ma(250.0).unwrap();
    assert!(r.clamped && r.code == 2800 && r.commanded_ma == hi);
    let r = client.set_current_ma(-10.0).unwrap();
    assert!(r.clamped && r.code == 0);
    assert!(matches!(client.set_current_ma(f64::NAN), Err(HwError::Core(etl_core::Error::NotFinite { .. }))));
    assert!(matches!(client.set_current_ma(f64::INFINITY), Err(HwError::Core(_))));
    sync(&client);
    assert_eq!(device.received().current_codes, vec![2800, 0]);
}

#[test]
fn modes_and_controlled_focal_power() {
    let (device, client) = spawn(VirtualLensConfig { initial_temperature_c: Some(30.0), ..Default::default() });
    client.set_mode(Mode::Sinusoidal).unwrap();
    assert_eq!(client.mode().unwrap(), Some(Mode::Sinusoidal));
    client.set_mode(Mode::Current).unwrap();
    assert_eq!(client.mode().unwrap(), Some(Mode::Current));
    // Controlled mode needs temperature limits first: the client refuses before sending,
    // and the driver itself refuses a bare `MwCA` with status bit 2.
    let e = client.enter_controlled_mode().unwrap_err();
    assert!(e.to_string().contains("send the temperature window (PwTA) before"), "{e}");
    match client.transact(etl_hw::codec::Command::SetMode(Mode::Controlled)).unwrap() {
        Some(etl_hw::codec::Reply::ControlledMode { status, .. }) => assert_eq!(status, 0b100),
        other => panic!("{other:?}"),
    }
    assert_eq!(client.mode().unwrap(), Some(Mode::Current));
    assert!(client.set_focal_power_dpt(12.0).is_err());
    assert!(client.set_temperature_limits_c(20.0, 40.0).is_err()); // min >= max
    let lim = client.set_temperature_limits_c(40.0, 20.0).unwrap();
    assert_eq!(lim.status, 0);
    let range = client.enter_controlled_mode().unwrap();
    assert!(range.min_dpt < 9.0 && range.max_dpt > 19.0, "{range:?}");
    assert_eq!(client.mode().unwrap(), Some(Mode::Controlled));
    let sent = client.set_focal_power_dpt(12.5).unwrap();
    assert_eq!(sent, 12.5);
    let got = client.focal_power_dpt().unwrap();
    assert!((got - 12.5).abs() < 0.01, "{got}");
    assert!((device.state().focal_power_dpt - 12.5).abs() < 0.01);
    assert!(client.set_focal_power_dpt(f64::NAN).is_err());
    // Outside the reported range: refused with the range, nothing sent, the power kept.
    let commands = device.received().commands;
    let e = client.set_focal_power_dpt(range.max_dpt + 0.5).unwrap_err();
    assert!(matches!(e, HwError::Core(etl_core::Error::OutOfRange { what: "focal power (dpt)", .. })), "{e:?}");
    assert!(!e.to_string().contains('\n'), "{e}");
    assert_eq!(device.received().commands, commands);
    assert!((client.focal_power_dpt().unwrap() - 12.5).abs() < 0.01);
}

#[test]
fn firmware_type_a_focal_power_encoding() {
    let (_device, client) = spawn(VirtualLensConfig { firmware_type: b'A', ..Default::default() });
    let range = client.enter_focal_power_mode(45.0, 20.0).unwrap();
    assert!(range.status_flags().is_empty(), "{:?}", range.status_flags());
    assert_eq!(client.temperature_window_c(), Some((20.0, 45.0)));
    client.set_focal_power_dpt(10.0).unwrap();
    assert!((client.focal_power_dpt().unwrap() - 10.0).abs() < 0.01);
}

#[test]
fn old_firmware_falls_back_to_ta_and_legacy_a() {
    let device = VirtualLens::spawn(VirtualLensConfig {
        legacy_firmware: true,
        initial_temperature_c: Some(28.0),
        ..Default::default()
    })
    .unwrap();
    let client =
        LensClient::open(device.path(), OpenOptions { legacy_set_current: true, ..Default::default() }).unwrap();
    assert_eq!(client.temperature_c().unwrap(), 28.0);
    assert_eq!(client.temperature_c().unwrap(), 28.0); // second call goes to TA directly
    client.set_current_ma(80.0).unwrap();
    assert!((client.current_ma().unwrap() - 80.0).abs() < 0.04);
    assert!(client.take_unsolicited().is_empty());
}

#[test]
fn no_sensor_is_an_error() {
    let (_device, client) = spawn(VirtualLensConfig { has_sensor: false, ..Default::default() });
    assert!(matches!(client.temperature_c(), Err(HwError::NoSensor { raw: 4095 })));
}

#[test]
fn open_fails_cleanly_on_a_missing_port() {
    let r = LensClient::open("/nonexistent/ttyACM9", OpenOptions::default());
    assert!(matches!(r, Err(HwError::Open { .. })));
}

#[test]
fn the_lens_trait_works_through_the_client() {
    let (device, mut client) = spawn(VirtualLensConfig::default());
    fn drive<L: Lens>(lens: &mut L) -> f64 {
        lens.set_current_ma(1e9).unwrap()
    }
    let sent = drive(&mut client);
    assert_eq!(sent, 292.84);
    assert_eq!(Lens::current_ma(&mut client).unwrap(), 292.84);
    assert!((Lens::temperature_c(&mut client).unwrap() - device.state().sensor_c).abs() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// No sequence of set-current calls, NaN and huge values included, puts a current
    /// outside the limits on the wire (the device records every code it receives).
    #[test]
    fn nothing_outside_the_limits_reaches_the_wire(
        lower in -4095i16..=0,
        upper in 0i16..=4095,
        requests in prop::collection::vec(
            prop_oneof![
                -400.0f64..400.0,
                Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY),
                Just(1e300), Just(-1e300), Just(f64::MAX), Just(f64::MIN_POSITIVE),
                any::<f64>(),
            ],
            1..30,
        ),
    ) {
        let (device, client) = spawn(VirtualLensConfig { upper_limit_code: upper, lower_limit_code: lower, ..Default::default() });
        for &ma in &requests {
            let r = client.set_current_ma(ma);
            prop_assert_eq!(r.is_err(), !ma.is_finite());
        }
        sync(&client);
        let codes = device.received().current_codes;
        prop_assert_eq!(codes.len(), requests.iter().filter(|x| x.is_finite()).count());
        for c in codes {
            prop_assert!(c >= lower && c <= upper, "code {} outside [{}, {}]", c, lower, upper);
        }
    }
}

#[test]
fn virtual_lens_refuses_bad_configurations() {
    let bad = [
        VirtualLensConfig { time_scale: 0.0, ..Default::default() },
        VirtualLensConfig { time_scale: f64::NAN, ..Default::default() },
        VirtualLensConfig { sensor_period_s: -0.1, ..Default::default() },
        VirtualLensConfig { upper_limit_code: -5, lower_limit_code: 5, ..Default::default() },
        VirtualLensConfig { upper_limit_code: 5000, ..Default::default() },
        VirtualLensConfig { max_current_centi_ma: 0, ..Default::default() },
        VirtualLensConfig { initial_temperature_c: Some(f64::INFINITY), ..Default::default() },
        VirtualLensConfig {
            thermal: etl_hw::virtual_lens::ThermalModel { tau_s: 0.0, ..Default::default() },
            ..Default::default()
        },
    ];
    for c in bad {
        assert!(matches!(VirtualLens::spawn(c.clone()), Err(HwError::Core(_))), "{c:?}");
    }
}

#[test]
fn the_port_path_is_removed_when_the_lens_is_dropped() {
    let device = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
    let path = device.path().to_owned();
    assert!(path.exists());
    drop(device);
    assert!(!path.exists());
}
