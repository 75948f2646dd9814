//! The client against the virtual lens's device model in-process ([`VirtualTransport`]):
//! the same protocol and faults as through the pseudo-terminal, on every platform.

use std::time::{Duration, Instant};

use etl_core::lens::{LensError, LensErrorKind};
use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::virtual_lens::{ThermalModel, VirtualDevice, VirtualLensConfig, VirtualTransport};
use etl_hw::HwError;

const TIMEOUT: Duration = Duration::from_millis(80);

fn open(config: VirtualLensConfig) -> (VirtualDevice, LensClient<VirtualTransport>) {
    let device = VirtualDevice::new(config).unwrap();
    let options = OpenOptions { timeout: TIMEOUT, handshake: true, ..OpenOptions::default() };
    let client = LensClient::from_transport(device.transport(), options).unwrap();
    (device, client)
}

#[test]
fn current_and_temperature_reach_the_model() {
    let (device, client) = open(VirtualLensConfig {
        upper_limit_code: 3000,
        lower_limit_code: -1000,
        // Ambient 31.3 degC and no coil heating: the lens stays at 31.3 degC.
        thermal: ThermalModel { ambient_c: 31.3, coil_resistance_ohm: 0.0, ..Default::default() },
        ..Default::default()
    });
    assert_eq!(device.received().handshakes, 1);
    assert!((client.limits_ma()[1] - 3000.0 * 292.84 / 4095.0).abs() < 1e-12);
    let r = client.set_current_ma(123.4).unwrap();
    // 123.4 mA -> code round(123.4 x 4095 / 292.84) = 1726.
    assert_eq!((r.code, r.clamped), (1726, false));
    assert_eq!(device.state().current_code, 1726);
    assert_eq!(client.current_ma().unwrap(), 1726.0 * 292.84 / 4095.0);
    // The sensor reports 1/16 degC steps: 31.3 -> 501/16 = 31.3125.
    assert_eq!(client.temperature_c().unwrap(), 31.3125);
    let r = client.set_current_ma(250.0).unwrap();
    assert_eq!((r.code, r.clamped), (3000, true));
    assert_eq!(device.received().current_codes, vec![1726, 3000]);
    assert_eq!(client.identify().unwrap().lens_serial, "ETLV0001");
}

#[test]
fn faults_of_the_model_reach_the_client() {
    let (device, client) = open(VirtualLensConfig::default());
    device.with_faults(|f| f.silence_next = 1);
    let t0 = Instant::now();
    let e = client.temperature_c().unwrap_err();
    assert!(matches!(e, HwError::Timeout { command: "TCA", .. }), "{e:?}");
    assert!(t0.elapsed() >= TIMEOUT);
    // The next call resynchronises first (the probe `H` takes the next reply).
    assert!(client.temperature_c().is_ok());
    device.with_faults(|f| f.corrupt_next = 1);
    assert!(matches!(client.temperature_c(), Err(HwError::Crc { command: "TCA" })));
    // A reply later than the timeout is a timeout; one within it is fine.
    device.with_faults(|f| f.reply_delay = 2 * TIMEOUT);
    assert_eq!(client.current_ma().unwrap_err().kind(), LensErrorKind::Timeout);
    device.with_faults(|f| f.reply_delay = TIMEOUT / 4);
    // The late reply comes in front of the probe's, within the probe's wait.
    std::thread::sleep(TIMEOUT);
    assert_eq!(client.current_ma().unwrap(), 0.0);
    device.with_faults(|f| f.error_frame_next = Some(2));
    assert!(matches!(client.current_ma(), Err(HwError::Device { command: "Ar", id: 2 })));
}

#[test]
fn a_late_reply_never_answers_a_later_question() {
    // The reply to a timed-out `Ar` (50 mA) comes while the next `Ar` waits; meanwhile the
    // lens was set to 150 mA behind the client's back. The answer must be 150, not 50.
    let (mut device, client) = open(VirtualLensConfig::default());
    client.set_current_ma(50.0).unwrap();
    device.with_faults(|f| f.reply_delay = TIMEOUT + Duration::from_millis(60));
    assert!(matches!(client.current_ma(), Err(HwError::Timeout { command: "Ar", .. })));
    device.with_faults(|f| f.reply_delay = Duration::ZERO);
    let commanded = etl_core::lens::Lens::set_current_ma(&mut device, 150.0).unwrap();
    let got = client.current_ma().unwrap();
    assert!((got - commanded).abs() < 1e-9 && (got - 150.0).abs() < 0.04, "{got} mA: a late reply was taken");
}
