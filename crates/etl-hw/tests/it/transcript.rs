//! Byte transcripts of the client, as embedded-hal-mock does for I2C drivers: a scripted
//! transport records exactly the bytes the client writes and answers each write with
//! canned bytes. The bytes come from the facts sheet
//! (`docs/PROTOCOL.md`, sections 2-4 and 4.10) and the codec
//! vectors; CRCs the sheet does not print are computed with the sheet's own script
//! (section 3, transcribed below), never with the codec under test.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use etl_core::lens::{LensError, LensErrorKind};
use etl_hw::client::{LensClient, OpenOptions, Transport, Unsolicited};
use etl_hw::codec::Reply;
use etl_hw::HwError;

/// The facts sheet's `crc16_arc` (section 3), transcribed.
fn crc16_arc(data: &[u8]) -> u16 {
    let mut crc = 0u16;
    for &b in data {
        crc ^= u16::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xA001 } else { crc >> 1 };
        }
    }
    crc
}

/// The sheet's `frame`: payload + CRC, low byte first (a command).
fn frame(payload: &[u8]) -> Vec<u8> {
    let c = crc16_arc(payload);
    [payload, &[(c & 0xFF) as u8, (c >> 8) as u8]].concat()
}

/// A reply: payload + CRC + CRLF.
fn reply(payload: &[u8]) -> Vec<u8> {
    [frame(payload), b"\r\n".to_vec()].concat()
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}

/// One command the client must write and the bytes the device answers it with.
type Exchange = (Vec<u8>, Vec<u8>);

/// The scripted link: every write is logged as one frame and releases the next canned
/// answer; a read with nothing to give blocks for its timeout, as a serial port does.
struct Script {
    answers: VecDeque<Vec<u8>>,
    input: Vec<u8>,
    written: Arc<Mutex<Vec<Vec<u8>>>>,
}

impl Transport for Script {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.written.lock().unwrap().push(bytes.to_vec());
        let answer = self.answers.pop_front().unwrap_or_default();
        self.input.extend_from_slice(&answer);
        Ok(())
    }

    fn bytes_waiting(&mut self) -> std::io::Result<usize> {
        Ok(self.input.len())
    }

    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        if self.input.is_empty() {
            std::thread::sleep(timeout);
            return Ok(0);
        }
        let n = buf.len().min(self.input.len());
        buf[..n].copy_from_slice(&self.input[..n]);
        self.input.drain(..n);
        Ok(n)
    }

    fn discard_input(&mut self) -> std::io::Result<()> {
        self.input.clear();
        Ok(())
    }

    fn name(&self) -> String {
        "script".into()
    }
}

/// The script of `exchanges` and the log of what the client wrote.
fn script(exchanges: &[Exchange]) -> (Script, Arc<Mutex<Vec<Vec<u8>>>>) {
    let written = Arc::new(Mutex::new(Vec::new()));
    let answers = exchanges.iter().map(|(_, answer)| answer.clone()).collect();
    (Script { answers, input: Vec::new(), written: Arc::clone(&written) }, written)
}

fn outs(exchanges: &[Exchange]) -> Vec<Vec<u8>> {
    exchanges.iter().map(|(out, _)| out.clone()).collect()
}

/// Max current 292.84 mA (29284 = 0x7264), limits +-4095 (0x0FFF, 0xF001), firmware `C`.
fn calibration_reads() -> Vec<Exchange> {
    vec![
        (hex("43 72 4D 41 00 00 71 80"), reply(b"CMA\x72\x64")),
        (frame(b"CrUA\x00\x00"), reply(b"CUA\x0F\xFF")),
        (frame(b"CrLA\x00\x00"), reply(b"CLA\xF0\x01")),
        (hex("48 00 36"), reply(b"HC")),
    ]
}

const TIMEOUT: Duration = Duration::from_millis(60);

fn options() -> OpenOptions {
    OpenOptions { timeout: TIMEOUT, ..OpenOptions::default() }
}

/// Opens a client over the script `calibration_reads() + then`, runs `body` on it and
/// asserts that the client wrote exactly the script's commands.
fn run(then: &[Exchange], body: impl FnOnce(&LensClient<Script>)) {
    let exchanges = [calibration_reads(), then.to_vec()].concat();
    let (link, written) = script(&exchanges);
    let client = LensClient::from_transport(link, options()).unwrap();
    body(&client);
    assert_eq!(*written.lock().unwrap(), outs(&exchanges));
}

/// mA of a current code with the 292.84 mA calibration (section 4.1: code x I_max / 4095).
fn ma(code: i16) -> f64 {
    f64::from(code) * 292.84 / 4095.0
}

#[test]
fn the_transcribed_crc_reproduces_the_facts_sheet() {
    assert_eq!(crc16_arc(b"123456789"), 0xBB3D);
    assert_eq!(frame(b"CrMA\x00\x00"), hex("43 72 4D 41 00 00 71 80"));
    assert_eq!(frame(b"TCA"), hex("54 43 41 B0 D0"));
    assert_eq!(reply(b"TCA\x01\xB2"), hex("54 43 41 01 B2 F5 B9 0D 0A"));
}

#[test]
fn handshake_then_the_calibration_reads() {
    let exchanges = [vec![(hex("53 74 61 72 74"), hex("52 65 61 64 79 0D 0A"))], calibration_reads()].concat();
    let (link, written) = script(&exchanges);
    let client = LensClient::from_transport(link, OpenOptions { handshake: true, ..options() }).unwrap();
    assert_eq!(*written.lock().unwrap(), outs(&exchanges));
    assert_eq!(client.max_current_ma(), 292.84);
    let [lo, hi] = client.limits_ma();
    assert!((lo + 292.84).abs() < 1e-12 && (hi - 292.84).abs() < 1e-12, "{lo} {hi}");
    assert_eq!(client.path(), std::path::Path::new("script"));
}

/// `Ar 00 00` (facts sheet section 4.1).
fn ar() -> Vec<u8> {
    hex("41 72 00 00 B4 27")
}

/// The `A` reply of current code `code`.
fn a_reply(code: i16) -> Vec<u8> {
    reply(&[b"A".as_slice(), &code.to_be_bytes()].concat())
}

#[test]
fn set_current_writes_aw_then_confirms_it_with_ar() {
    let then = [
        (hex("41 77 05 76 26 90"), vec![]), // 100 mA -> code 1398
        (ar(), a_reply(1398)),
        (hex("41 77 FD 45 25 45"), vec![]), // -50 mA -> code -699
        (ar(), a_reply(-699)),
        (frame(b"Aw\x0F\xFF"), vec![]), // 1000 mA: clamped to the upper limit 4095
        (ar(), a_reply(4095)),
    ];
    run(&then, |client| {
        let r = client.set_current_ma(100.0).unwrap();
        assert_eq!((r.code, r.clamped), (1398, false));
        assert!((r.commanded_ma - ma(1398)).abs() < 1e-12, "{r:?}");
        let r = client.set_current_ma(-50.0).unwrap();
        assert_eq!((r.code, r.clamped), (-699, false));
        assert!((r.commanded_ma - ma(-699)).abs() < 1e-12, "{r:?}");
        let r = client.set_current_ma(1000.0).unwrap();
        assert_eq!((r.code, r.clamped), (4095, true));
        assert!((r.commanded_ma - 292.84).abs() < 1e-12, "{r:?}");
    });
}

/// A zero-vibration shaped step from 0 to 100 mA: the current read, 60 % of the step
/// (code 839: 60 mA x 4095 / 292.84 = 839.0), then the target (code 1398) no earlier than
/// the shaper's delay after the first write; each write confirmed by its read-back. A
/// shaper that is no step shape is refused before a byte is written.
#[test]
fn a_shaped_step_writes_the_fraction_then_the_target_after_the_delay() {
    let then = [
        (ar(), a_reply(0)),
        (frame(b"Aw\x03\x47"), vec![]),
        (ar(), a_reply(839)),
        (hex("41 77 05 76 26 90"), vec![]),
        (ar(), a_reply(1398)),
    ];
    let shaper = etl_core::physics::shaping::ZvShaper { first_fraction: 0.6, delay_s: 0.008 };
    run(&then, |client| {
        let start = Instant::now();
        let s = client.set_current_shaped_ma(100.0, &shaper).unwrap();
        assert!(start.elapsed() >= Duration::from_millis(8));
        assert_eq!((s.from_ma, s.first.code, s.target.code), (0.0, 839, 1398));
        assert!(s.delay_s >= 0.008 && s.late_s == (s.delay_s - 0.008).max(0.0), "{s:?}");
        for bad in [0.0, 1.5, f64::NAN] {
            let z = etl_core::physics::shaping::ZvShaper { first_fraction: bad, delay_s: 0.004 };
            assert!(matches!(client.set_current_shaped_ma(100.0, &z), Err(HwError::Core(_))), "{bad}");
        }
        let z = etl_core::physics::shaping::ZvShaper { first_fraction: 0.6, delay_s: -1.0 };
        assert!(client.set_current_shaped_ma(100.0, &z).is_err());
    });
}

#[test]
fn a_current_command_the_driver_rejects_is_an_error_naming_aw() {
    // E 02 answers the `Aw`; the read-back's `A` (the old code 0) follows it and is consumed,
    // so the next query gets its own answer.
    let then = [(hex("41 77 05 76 26 90"), reply(b"E\x02")), (ar(), a_reply(0)), (ar(), a_reply(0))];
    run(&then, |client| {
        let e = client.set_current_ma(100.0).unwrap_err();
        assert!(matches!(e, HwError::Device { command: "Aw", id: 2 }), "{e:?}");
        assert_eq!(e.to_string(), "lens driver answered Aw with error 2: command not available in this firmware type");
        assert_eq!(e.kind(), LensErrorKind::Refused);
        assert_eq!(client.current_ma().unwrap(), 0.0);
        assert!(client.take_unsolicited().is_empty());
    });
}

#[test]
fn a_current_read_back_other_than_the_one_sent_is_not_applied() {
    let then = [(hex("41 77 05 76 26 90"), vec![]), (ar(), a_reply(7))];
    run(&then, |client| {
        let e = client.set_current_ma(100.0).unwrap_err();
        assert!(matches!(e, HwError::CurrentNotApplied { command: "Aw", sent_code: 1398, read_code: 7 }), "{e:?}");
        assert_eq!(e.to_string(), "lens driver did not apply Aw: sent current code 1398, read back 7");
    });
}

#[test]
fn after_a_timeout_a_late_reply_is_discarded_before_the_next_answer() {
    // The first `Ar` gets no answer in time; its late reply (code 999) comes in front of the
    // probe's `H` reply, so it is dropped, and the next `Ar` gets the lens's real code 1398.
    let then = [(ar(), vec![]), (hex("48 00 36"), [a_reply(999), reply(b"HC")].concat()), (ar(), a_reply(1398))];
    run(&then, |client| {
        assert!(matches!(client.current_ma(), Err(HwError::Timeout { command: "Ar", .. })));
        let got = client.current_ma().unwrap();
        assert!((got - ma(1398)).abs() < 1e-12, "{got}: the late reply was taken as the answer");
    });
}

#[test]
fn until_the_probe_is_answered_nothing_else_is_sent() {
    // No answer to `TCA`, none to the probe `H`: the second query is not sent and fails;
    // the third is preceded by a probe again, answered this time.
    let probe = hex("48 00 36");
    let tca = hex("54 43 41 B0 D0");
    let then = [
        (tca.clone(), vec![]),
        (probe.clone(), vec![]),
        (probe, reply(b"HC")),
        (tca, hex("54 43 41 01 B2 F5 B9 0D 0A")),
    ];
    run(&then, |client| {
        assert!(matches!(client.temperature_c(), Err(HwError::Timeout { command: "TCA", .. })));
        let e = client.temperature_c().unwrap_err();
        assert!(matches!(e, HwError::Desynchronised { command: "TCA", .. }), "{e:?}");
        assert_eq!(e.kind(), LensErrorKind::Timeout);
        assert_eq!(client.temperature_c().unwrap(), 27.125);
    });
}

#[test]
fn read_current() {
    // The sheet's `A 05 7A` with its true CRC 0xA7D2 (section 3): code 1402.
    let then = [(hex("41 72 00 00 B4 27"), hex("41 05 7A D2 A7 0D 0A"))];
    run(&then, |client| {
        let got = client.current_ma().unwrap();
        assert!((got - ma(1402)).abs() < 1e-12, "{got}");
        assert!((got - 100.25926).abs() < 1e-5, "{got}");
    });
}

#[test]
fn read_temperature() {
    // 434 / 16 = 27.125 degC (section 3 worked example).
    let then = [(hex("54 43 41 B0 D0"), hex("54 43 41 01 B2 F5 B9 0D 0A"))];
    run(&then, |client| assert_eq!(client.temperature_c().unwrap(), 27.125));
}

#[test]
fn old_firmware_refuses_tca_and_the_client_falls_back_to_ta() {
    // E 03 "command not recognised", then `TA` (`54 41 FE F0`) answered `TA 00 01 B2`
    // (section 4.5); the second reading goes to `TA` directly.
    let ta = (hex("54 41 FE F0"), reply(b"TA\x00\x01\xB2"));
    let then = [(hex("54 43 41 B0 D0"), reply(b"E\x03")), ta.clone(), ta];
    run(&then, |client| {
        assert_eq!(client.temperature_c().unwrap(), 27.125);
        assert_eq!(client.temperature_c().unwrap(), 27.125);
    });
}

#[test]
fn a_device_error_reply_is_refused_with_its_id() {
    // E 04: lens not compatible with firmware (section 4.10).
    let then = [(hex("41 72 00 00 B4 27"), reply(b"E\x04"))];
    run(&then, |client| {
        let e = client.current_ma().unwrap_err();
        assert!(matches!(e, HwError::Device { command: "Ar", id: 4 }), "{e:?}");
        assert_eq!(e.kind(), LensErrorKind::Refused);
        assert_eq!(e.to_string(), "lens driver answered Ar with error 4: lens not compatible with firmware");
    });
}

#[test]
fn a_reply_failing_its_crc_is_reported_at_once_and_the_next_query_works() {
    // The worked TCA reply with the CRC's high byte B9 -> B8.
    let then = [
        (hex("54 43 41 B0 D0"), hex("54 43 41 01 B2 F5 B8 0D 0A")),
        (hex("54 43 41 B0 D0"), hex("54 43 41 01 B2 F5 B9 0D 0A")),
    ];
    run(&then, |client| {
        let t0 = Instant::now();
        let e = client.temperature_c().unwrap_err();
        assert!(t0.elapsed() < TIMEOUT, "a CRC failure does not wait for the timeout");
        assert!(matches!(e, HwError::Crc { command: "TCA" }), "{e:?}");
        assert_eq!(e.kind(), LensErrorKind::Protocol);
        assert_eq!(client.temperature_c().unwrap(), 27.125);
    });
}

#[test]
fn a_nack_is_a_protocol_error() {
    let then = [(hex("54 43 41 B0 D0"), hex("4E 0D 0A"))];
    run(&then, |client| {
        let e = client.temperature_c().unwrap_err();
        assert!(matches!(e, HwError::Nack { command: "TCA" }), "{e:?}");
        assert_eq!(e.kind(), LensErrorKind::Protocol);
    });
}

#[test]
fn silence_times_out_after_the_configured_time() {
    let then = [(hex("54 43 41 B0 D0"), vec![])];
    run(&then, |client| {
        let t0 = Instant::now();
        let e = client.temperature_c().unwrap_err();
        let waited = t0.elapsed();
        assert!(matches!(e, HwError::Timeout { command: "TCA", timeout: TIMEOUT }), "{e:?}");
        assert_eq!(e.kind(), LensErrorKind::Timeout);
        assert!(waited >= TIMEOUT && waited < 10 * TIMEOUT, "{waited:?}");
    });
}

#[test]
fn an_error_frame_after_a_focal_power_write_is_drained_as_unsolicited() {
    // `PwDA` has no reply; the E 01 it provoked waits on the line until the next command.
    let then = [
        (hex("50 77 54 41 02 D0 01 40 33 C1"), reply(b"PT\x00\x0B\xB8\x07\xD0")),
        (hex("4D 77 43 41 56 76"), reply(b"MCA\x00\x0B\xB8\x07\xD0")),
        (frame(b"PwDA\x09\xC4\x00\x00"), reply(b"E\x01")), // 12.5 dpt -> code 2500
        (ar(), a_reply(1398)),
    ];
    run(&then, |client| {
        client.enter_focal_power_mode(45.0, 20.0).unwrap();
        client.set_focal_power_dpt(12.5).unwrap();
        assert!((client.current_ma().unwrap() - ma(1398)).abs() < 1e-12);
        assert_eq!(client.take_unsolicited(), vec![Unsolicited { reply: Reply::Error(1), after: "PwDA" }]);
    });
}

#[test]
fn impossible_calibrations_are_typed_protocol_errors() {
    // A max current of 0 stops the open at the first read.
    let zero = [(hex("43 72 4D 41 00 00 71 80"), reply(b"CMA\x00\x00"))];
    let (link, written) = script(&zero);
    let e = LensClient::from_transport(link, options()).err().unwrap();
    assert!(matches!(e, HwError::BadMaxCurrent { centi_ma: 0 }), "{e:?}");
    assert_eq!(e.kind(), LensErrorKind::Protocol);
    assert_eq!(e.to_string(), "protocol error: the driver reports a max current of 0 mA (must be > 0)");
    assert_eq!(*written.lock().unwrap(), outs(&zero));
    // Lower 5 > upper -5 (0xFFFB): refused before the firmware type is read.
    let mut inverted = calibration_reads();
    inverted[1].1 = reply(b"CUA\xFF\xFB");
    inverted[2].1 = reply(b"CLA\x00\x05");
    inverted.truncate(3);
    let (link, written) = script(&inverted);
    let e = LensClient::from_transport(link, options()).err().unwrap();
    assert!(matches!(e, HwError::InvertedLimits { lower: 5, upper: -5 }), "{e:?}");
    assert_eq!(e.to_string(), "protocol error: driver limits are inverted: lower 5 > upper -5");
    assert_eq!(*written.lock().unwrap(), outs(&inverted));
}

#[test]
fn controlled_mode_the_driver_refuses_is_a_refusal() {
    // A window accepted, then `MwCA` (`4D 77 43 41 56 76`) answered `MCA` + status 0b100 +
    // max FP + min FP all the same (a driver that lost the limits).
    let then = [
        (hex("50 77 54 41 02 D0 01 40 33 C1"), reply(b"PT\x00\x0B\xB8\x07\xD0")),
        (hex("4D 77 43 41 56 76"), reply(b"MCA\x04\x0B\xB8\x07\xD0")),
    ];
    run(&then, |client| {
        let e = client.enter_focal_power_mode(45.0, 20.0).unwrap_err();
        assert!(matches!(e, HwError::ControlledModeRefused { status: 0b100 }), "{e:?}");
        assert_eq!(e.kind(), LensErrorKind::Refused);
    });
}

#[test]
fn an_unexpected_reply_says_what_was_expected_and_what_came() {
    let e = HwError::UnexpectedReply { command: "Ar", expected: "A", got: Some(Reply::Status([0, 0, 0, 4])) };
    assert_eq!(e.to_string(), r#"protocol error: Ar expects a reply starting "A", got S frame Status([0, 0, 0, 4])"#);
    assert_eq!(e.kind(), LensErrorKind::Protocol);
    let none = HwError::UnexpectedReply { command: "Start", expected: "Ready", got: None };
    assert_eq!(none.to_string(), r#"protocol error: Start expects a reply starting "Ready", got no reply"#);
}

#[test]
fn timeouts_outside_their_range_are_refused_before_anything_is_sent() {
    for timeout in [Duration::ZERO, Duration::from_secs(61), Duration::MAX] {
        let (link, written) = script(&[]);
        let e = LensClient::from_transport(link, OpenOptions { timeout, ..options() }).err().unwrap();
        assert_eq!(e.to_string(), "invalid argument: reply timeout must lie in 1..=60000 ms");
        assert!(written.lock().unwrap().is_empty());
    }
}

/// Entering focal-power mode and setting 5.0 dpt, byte for byte, for each firmware type:
/// the temperature window first (`PwTA`, max then min: the sheet's 45/20 degC example
/// frame), then the mode switch (`MwCA`), then the fire-and-forget `PwDA` encoded for the
/// type: type A (dpt + 5) x 200 = 2000 (`07 D0`, the sheet's example), the others
/// dpt x 200 = 1000 (`03 E8`). The ranges the replies carry are encoded the same way.
#[test]
fn entering_focal_power_mode_and_setting_5_dpt_for_each_firmware_type() {
    for (letter, code, range) in [(b'A', b"\x07\xD0", b"\x0F\xA0\x03\xE8"), (b'C', b"\x03\xE8", b"\x0B\xB8\x00\xC8")] {
        let mut reads = calibration_reads();
        reads[3].1 = reply(&[b'H', letter]);
        let then = vec![
            (hex("50 77 54 41 02 D0 01 40 33 C1"), reply(&[&b"PT\x00"[..], range].concat())),
            (hex("4D 77 43 41 56 76"), reply(&[&b"MCA\x00"[..], range].concat())),
            (frame(&[&b"PwDA"[..], code, b"\x00\x00"].concat()), vec![]),
        ];
        let exchanges = [reads, then].concat();
        let (link, written) = script(&exchanges);
        let client = LensClient::from_transport(link, options()).unwrap();
        let r = client.enter_focal_power_mode(45.0, 20.0).unwrap();
        // Type A: 4000 -> 15 dpt, 1000 -> 0 dpt; type C: 3000 -> 15 dpt, 200 -> 1 dpt.
        assert_eq!((r.max_dpt, r.status), (15.0, 0), "type {}", letter as char);
        assert_eq!(client.set_focal_power_dpt(5.0).unwrap(), 5.0);
        assert_eq!(*written.lock().unwrap(), outs(&exchanges), "type {}", letter as char);
    }
}

/// The client refuses, in one line and without a byte on the line, a mode switch before
/// the temperature window, and a focal power outside the range the switch reported.
#[test]
fn a_mode_switch_without_the_window_and_a_power_outside_the_range_are_refused_unsent() {
    let then = [
        (hex("50 77 54 41 02 D0 01 40 33 C1"), reply(b"PT\x00\x0B\xB8\x07\xD0")),
        (hex("4D 77 43 41 56 76"), reply(b"MCA\x00\x0B\xB8\x07\xD0")),
    ];
    run(&then, |client| {
        let e = client.enter_controlled_mode().unwrap_err().to_string();
        assert!(e.contains("send the temperature window (PwTA) before switching to focal-power mode"), "{e}");
        assert!(client.set_focal_power_dpt(12.0).is_err());
        let range = client.enter_focal_power_mode(45.0, 20.0).unwrap();
        assert_eq!((range.min_dpt, range.max_dpt), (10.0, 15.0));
        for dpt in [9.99, 15.01, -1.0] {
            let e = client.set_focal_power_dpt(dpt).unwrap_err();
            assert!(!e.to_string().contains('\n') && e.to_string().contains("focal power (dpt)"), "{e}");
        }
    });
}

/// A window the driver refuses (its status bit 2 set) does not count as sent: the mode
/// switch is still refused by the client, and the status bits are named.
#[test]
fn a_refused_window_does_not_open_the_mode_switch() {
    let then = [(hex("50 77 54 41 02 D0 01 40 33 C1"), reply(b"PT\x14\x0B\xB8\x07\xD0"))];
    run(&then, |client| {
        let r = client.set_temperature_limits_c(45.0, 20.0).unwrap();
        assert_eq!(r.status_flags(), vec!["no temperature limits received", "focal-power inversion"]);
        assert_eq!(client.temperature_window_c(), None);
        assert!(client.enter_controlled_mode().is_err());
    });
}
