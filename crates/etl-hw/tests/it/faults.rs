//! Faults against the virtual lens: a reply that never comes, a corrupted reply, garbage
//! before a reply, error frames, a NACK, the port vanishing and a reconnect.
#![cfg(unix)] // the pseudo-terminal virtual lens

use std::time::{Duration, Instant};

use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::codec::Reply;
use etl_hw::virtual_lens::{Faults, VirtualLens, VirtualLensConfig};
use etl_hw::HwError;

fn spawn(config: VirtualLensConfig, timeout_ms: u64) -> (VirtualLens, LensClient) {
    let device = VirtualLens::spawn(config).unwrap();
    let client = LensClient::open(
        device.path(),
        OpenOptions { timeout: Duration::from_millis(timeout_ms), ..Default::default() },
    )
    .unwrap();
    (device, client)
}

#[test]
fn a_reply_that_never_comes_times_out_in_the_configured_time() {
    let (device, client) = spawn(VirtualLensConfig::default(), 150);
    device.with_faults(|f| f.silence_next = 1);
    let t0 = Instant::now();
    let r = client.temperature_c();
    let waited = t0.elapsed();
    assert!(matches!(r, Err(HwError::Timeout { command: "TCA", .. })), "{r:?}");
    assert!(waited >= Duration::from_millis(150) && waited < Duration::from_millis(1500), "{waited:?}");
    // The next query works.
    assert!(client.temperature_c().is_ok());
}

#[test]
fn a_slow_reply_within_the_timeout_is_fine_and_beyond_it_is_not() {
    let (device, client) = spawn(VirtualLensConfig::default(), 200);
    device.with_faults(|f| f.reply_delay = Duration::from_millis(60));
    assert!(client.current_ma().is_ok());
    device.with_faults(|f| f.reply_delay = Duration::from_millis(400));
    assert!(matches!(client.current_ma(), Err(HwError::Timeout { .. })));
    device.set_faults(Faults::default());
    // The late reply arrives before the next query; the resynchronisation discards it.
    std::thread::sleep(Duration::from_millis(300));
    assert!(client.current_ma().is_ok());
}

#[test]
fn a_corrupted_reply_is_a_crc_error_then_retry_succeeds() {
    let (device, client) = spawn(VirtualLensConfig { initial_temperature_c: Some(29.0), ..Default::default() }, 3000);
    device.with_faults(|f| f.corrupt_next = 1);
    let t0 = Instant::now();
    assert!(matches!(client.temperature_c(), Err(HwError::Crc { command: "TCA" })));
    assert!(t0.elapsed() < Duration::from_millis(1500), "CRC errors are reported without waiting for the timeout");
    assert_eq!(client.temperature_c().unwrap(), 29.0);
}

#[test]
fn garbage_before_a_reply_is_skipped() {
    let (device, client) = spawn(VirtualLensConfig { initial_temperature_c: Some(26.5), ..Default::default() }, 300);
    // Bytes that look like parts of frames, CR/LF included.
    device.with_faults(|f| f.garbage_before_next = b"\x00TC\r\nA\x05Rea\xff".to_vec());
    assert_eq!(client.temperature_c().unwrap(), 26.5);
    device.with_faults(|f| f.garbage_before_next = vec![0x41; 40]);
    assert!(client.current_ma().is_ok());
}

#[test]
fn error_frames_in_reply_and_unsolicited() {
    let (device, client) = spawn(VirtualLensConfig::default(), 300);
    device.with_faults(|f| f.error_frame_next = Some(2));
    assert!(matches!(client.current_ma(), Err(HwError::Device { command: "Ar", id: 2 })));
    // A rejected current command is an error of the call that sent it, naming `Aw`.
    device.with_faults(|f| f.error_frame_next = Some(1));
    let e = client.set_current_ma(50.0).unwrap_err();
    assert!(matches!(e, HwError::Device { command: "Aw", id: 1 }), "{e:?}");
    assert_eq!(client.current_ma().unwrap(), 0.0); // the write was not executed
    assert!(client.take_unsolicited().is_empty());
    // After another fire-and-forget write (`PwDA`) the error frame is unsolicited: drained
    // before the next command and reported.
    let range = client.enter_focal_power_mode(60.0, 10.0).unwrap();
    device.with_faults(|f| f.error_frame_next = Some(1));
    client.set_focal_power_dpt(range.min_dpt).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    assert!(client.mode().is_ok());
    let u = client.take_unsolicited();
    assert_eq!(u.len(), 1);
    assert_eq!((u[0].reply, u[0].after), (Reply::Error(1), "PwDA"));
    assert!(client.take_unsolicited().is_empty());
}

#[test]
fn command_crc_errors_give_e1_or_nack() {
    let (device, client) = spawn(VirtualLensConfig::default(), 300);
    device.with_faults(|f| f.crc_error_next = 1);
    assert!(matches!(client.temperature_c(), Err(HwError::Device { id: 1, .. })));
    let (device2, client2) = spawn(VirtualLensConfig { nack_on_crc: true, ..Default::default() }, 300);
    device2.with_faults(|f| f.crc_error_next = 1);
    assert!(matches!(client2.temperature_c(), Err(HwError::Nack { command: "TCA" })));
    assert!(client2.temperature_c().is_ok());
    assert_eq!(device.received().crc_errors + device2.received().crc_errors, 2);
}

#[test]
fn lost_command_bytes_time_out_then_recover() {
    let (device, client) = spawn(VirtualLensConfig::default(), 150);
    device.with_faults(|f| f.drop_rx_bytes_next = 2);
    // "TCA" + CRC loses its first two bytes: the device sees garbage, answers E 03.
    let r = client.temperature_c();
    assert!(matches!(r, Err(HwError::Device { id: 3, .. }) | Err(HwError::Timeout { .. })), "{r:?}");
    std::thread::sleep(Duration::from_millis(80));
    assert!(client.temperature_c().is_ok());
}

#[test]
fn the_port_vanishing_is_an_error_and_reconnect_keeps_the_current() {
    let (device, client) = spawn(VirtualLensConfig::default(), 200);
    client.set_current_ma(175.0).unwrap();
    let before = client.current_ma().unwrap();
    device.disconnect();
    let t0 = Instant::now();
    let r = client.current_ma();
    assert!(matches!(r, Err(HwError::Io { .. }) | Err(HwError::Timeout { .. })), "{r:?}");
    assert!(t0.elapsed() < Duration::from_millis(1500));
    // Reconnecting while the device is gone fails cleanly.
    assert!(client.reconnect().is_err());
    device.reconnect().unwrap();
    client.reconnect().unwrap();
    assert_eq!(client.current_ma().unwrap(), before);
    assert_eq!(device.received().handshakes, 0);
    assert!((device.state().e_in_ma - 175.0).abs() < 0.04);
}
