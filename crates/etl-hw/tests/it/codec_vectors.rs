//! The facts sheet's frames (section 3 worked examples and script output, section 4
//! tables), byte for byte.

use etl_hw::codec::scaling::{current_code, current_ma, temperature_c, FirmwareType};
use etl_hw::codec::{crc16_arc, scan_reply, Command, DecodeError, Mode, Reply, Scan};

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}

#[test]
fn crc_check_value() {
    assert_eq!(crc16_arc(b"123456789"), 0xBB3D);
}

#[test]
fn command_frames_match_the_facts_sheet() {
    let cases: &[(Command, &str)] = &[
        (Command::Start, "53 74 61 72 74"),
        (Command::SetCurrent { code: 1202 }, "41 77 04 B2 26 93"),
        (Command::SetCurrent { code: current_code(100.0, 292.84) }, "41 77 05 76 26 90"),
        (Command::SetCurrent { code: current_code(-50.0, 292.84) }, "41 77 FD 45 25 45"),
        (Command::GetCurrent, "41 72 00 00 B4 27"),
        (Command::Temperature, "54 43 41 B0 D0"),
        (Command::TemperatureLegacy, "54 41 FE F0"),
        (Command::SetMode(Mode::Current), "4D 77 44 41 54 46"),
        (Command::SetMode(Mode::Controlled), "4D 77 43 41 56 76"),
        (Command::ReadMode, "4D 4D 41 65 77"),
        (Command::SetFocalPower { code: 2000 }, "50 77 44 41 07 D0 00 00 31 FD"),
        (Command::ReadMaxCurrent, "43 72 4D 41 00 00 71 80"),
        (Command::SetCurrentLegacy { code: 1202 }, "41 04 B2 D2 A1"),
        (Command::FirmwareType, "48 00 36"),
        (Command::FirmwareBranch, "46 81 F2"),
        (Command::PartNumber, "4A 81 F7"),
        (Command::FirmwareVersion, "56 80 3E"),
        (Command::LensSerial, "58 01 FA"),
        (Command::Status, "53 72 BC D5"),
        (Command::AnalogInput, "47 41 41 40 75"),
        (Command::SetTemperatureLimits { max_x16: 45 * 16, min_x16: 20 * 16 }, "50 77 54 41 02 D0 01 40 33 C1"),
        (Command::SetTemperatureLimits { max_x16: 35 * 16, min_x16: 20 * 16 }, "50 77 54 41 02 30 01 40 32 37"),
        (Command::SetFrequency { millihertz: 100_000 }, "50 77 46 41 00 01 86 A0 03 4A"),
    ];
    for (cmd, frame) in cases {
        assert_eq!(cmd.encode(), hex(frame), "{cmd:?}");
        let (back, used) = Command::decode(&hex(frame)).unwrap();
        assert_eq!((back, used), (*cmd, hex(frame).len()), "{frame}");
    }
    // 12 Hz -> 00 00 2E E0 (MAN16).
    assert_eq!(&Command::SetFrequency { millihertz: 12_000 }.encode()[4..8], &[0x00, 0x00, 0x2E, 0xE0]);
    // IR + 8 zeros is 12 bytes.
    assert_eq!(Command::DeviceId.encode().len(), 12);
}

#[test]
fn reply_frames_match_the_facts_sheet() {
    let cases: &[(Reply, &str)] = &[
        (Reply::Ready, "52 65 61 64 79 0D 0A"),
        (Reply::Temperature { raw: 434 }, "54 43 41 01 B2 F5 B9 0D 0A"),
        (Reply::Mode(Mode::Current), "4D 44 41 63 27 0D 0A"),
        (Reply::Mode(Mode::Sinusoidal), "4D 53 41 6C D7 0D 0A"),
        // "A 05 7A": the true CRC is 0xA7D2 (the vendor sheet prints D2 FF).
        (Reply::Current { code: 0x057A }, "41 05 7A D2 A7 0D 0A"),
        (Reply::Nack, "4E 0D 0A"),
    ];
    for (reply, frame) in cases {
        assert_eq!(reply.encode(), hex(frame), "{reply:?}");
        assert_eq!(Reply::decode(&hex(frame)).unwrap(), (*reply, hex(frame).len()));
    }
    assert_eq!(temperature_c(434), Some(27.125));
}

#[test]
fn reply_lengths_follow_the_tables() {
    let lens: &[(Reply, usize)] = &[
        (Reply::Current { code: 1 }, 7),
        (Reply::MaxCurrent { centi_ma: 29284 }, 9),
        (Reply::UpperLimit { code: 4095 }, 9),
        (Reply::LowerLimit { code: -4095 }, 9),
        (Reply::Mode(Mode::Triangular), 7),
        (Reply::ControlledMode { status: 0, max_fp: 1, min_fp: -1 }, 12),
        (Reply::ActiveMode { code: 1 }, 8),
        (Reply::FocalPower { code: 1 }, 8),
        (Reply::TemperatureLimits { status: 0, max_fp: 1, min_fp: 2 }, 11),
        (Reply::Temperature { raw: 1 }, 9),
        (Reply::TemperatureLegacy { status: 0, raw: 434 }, 9),
        (Reply::FirmwareType(b'A'), 6),
        (Reply::FirmwareVersion { major: 1, minor: 2, build: 3, revision: 4 }, 11),
        (Reply::DeviceId(*b"12345678"), 14),
        (Reply::LensSerial(*b"00000000"), 13),
        (Reply::Status([0, 0, 0, 4]), 9),
        (Reply::Error(1), 6),
    ];
    for (r, n) in lens {
        assert_eq!(r.encode().len(), *n, "{r:?}");
    }
    // The legacy TA example: 54 41 00 01 B2 ... = 434 -> 27.125 degC.
    let ta = Reply::TemperatureLegacy { status: 0, raw: 434 }.encode();
    assert_eq!(&ta[..5], &hex("54 41 00 01 B2")[..]);
}

#[test]
fn scaling_conventions() {
    assert_eq!(current_code(50.0, 293.0), 699); // MAN16's example
    assert_eq!(current_code(292.84, 292.84), 4095);
    assert_eq!(current_code(f64::NAN, 292.84), 0);
    assert_eq!(current_code(1e12, 292.84), i16::MAX); // saturates, callers clamp first
    assert!((current_ma(1398, 292.84) - 99.9735).abs() < 1e-3);
    assert_eq!(temperature_c(4095), None); // no sensor
    assert_eq!(temperature_c(-16 * 41), None); // below -40 degC
    assert_eq!(temperature_c(-16), Some(-1.0));
    // Focal power: type A has +5 dpt offset (0 dpt -> 1000, 3 -> 1600, 5 -> 2000).
    let a = FirmwareType::from_letter(b'A');
    assert_eq!([a.fp_code(0.0), a.fp_code(3.0), a.fp_code(5.0)], [1000, 1600, 2000]);
    let c = FirmwareType::from_letter(b'C');
    assert_eq!([c.fp_code(0.0), c.fp_code(3.0)], [0, 600]);
    assert_eq!(a.fp_dpt(1600), 3.0);
    assert_eq!(c.fp_dpt(-300), -1.5);
}

#[test]
fn binary_payload_with_crlf_is_not_cut() {
    // 16.125 degC: the facts sheet lists it among replies with 0A/0D inside.
    let f = Reply::Temperature { raw: (16.125f64 * 16.0) as i16 }.encode();
    assert!(f[..f.len() - 2].iter().any(|&b| b == 0x0A || b == 0x0D), "{f:02X?}");
    assert_eq!(Reply::decode(&f).unwrap().0, Reply::Temperature { raw: 258 });
}

#[test]
fn decode_errors_are_named() {
    let mut f = Reply::Temperature { raw: 434 }.encode();
    assert_eq!(Reply::decode(&f[..4]), Err(DecodeError::Incomplete));
    f[4] ^= 1;
    assert_eq!(Reply::decode(&f), Err(DecodeError::Crc { len: 9 }));
    let mut g = Reply::Temperature { raw: 434 }.encode();
    g[8] = b'x';
    assert_eq!(Reply::decode(&g), Err(DecodeError::Malformed { len: 9 }));
    assert_eq!(Reply::decode(b"zz"), Err(DecodeError::Unknown));
    assert_eq!(Command::decode(b"zz"), Err(DecodeError::Unknown));
    assert_eq!(Command::decode(b"T"), Err(DecodeError::Incomplete));
    assert_eq!(Command::decode(b"Sta"), Err(DecodeError::Incomplete));
    let mut c = Command::GetCurrent.encode();
    c[5] ^= 0xFF;
    assert_eq!(Command::decode(&c), Err(DecodeError::Crc { len: 6 }));
    // Dummy bytes must be zero.
    let mut d = b"Ar\x00\x01".to_vec();
    let crc = crc16_arc(&d);
    d.extend_from_slice(&crc.to_le_bytes());
    assert_eq!(Command::decode(&d), Err(DecodeError::Malformed { len: 6 }));
}

#[test]
fn scan_skips_garbage_and_reports_corruption() {
    let good = Reply::Temperature { raw: 434 }.encode();
    let mut buf = b"\x00\xffTC\r\nA".to_vec();
    buf.extend_from_slice(&good);
    match scan_reply(&buf, b"TCA") {
        Scan::Found { reply, start, end } => {
            assert_eq!(reply, Reply::Temperature { raw: 434 });
            assert_eq!((start, end), (7, 7 + 9));
        }
        other => panic!("{other:?}"),
    }
    let mut bad = good.clone();
    bad[6] ^= 0x5A;
    assert_eq!(scan_reply(&bad, b"TCA"), Scan::Corrupted { end: 9 });
    assert_eq!(scan_reply(&good[..5], b"TCA"), Scan::NeedMore);
    let e = Reply::Error(3).encode();
    assert!(matches!(scan_reply(&e, b"TCA"), Scan::Found { reply: Reply::Error(3), .. }));
    // A valid frame of another command is not taken for the reply.
    assert_eq!(scan_reply(&Reply::Current { code: 5 }.encode(), b"TCA"), Scan::NeedMore);
}

#[test]
fn reply_headers_follow_the_facts_sheet() {
    // Sections 2 and 4: the header each command's reply starts with; fire-and-forget
    // commands have none (only an error frame can come back).
    let cases: &[(Command, Option<&str>)] = &[
        (Command::Start, Some("Ready")),
        (Command::SetCurrent { code: 1 }, None),
        (Command::SetCurrentLegacy { code: 1 }, None),
        (Command::GetCurrent, Some("A")),
        (Command::ReadMaxCurrent, Some("CMA")),
        (Command::ReadUpperLimit, Some("CUA")),
        (Command::ReadLowerLimit, Some("CLA")),
        (Command::SetMode(Mode::Current), Some("MDA")),
        (Command::SetMode(Mode::Sinusoidal), Some("MSA")),
        (Command::SetMode(Mode::Rectangular), Some("MQA")),
        (Command::SetMode(Mode::Triangular), Some("MTA")),
        (Command::SetMode(Mode::Analog), Some("MAA")),
        (Command::SetMode(Mode::Controlled), Some("MCA")),
        (Command::ReadMode, Some("MMA")),
        (Command::SetFocalPower { code: 1 }, None),
        (Command::GetFocalPower, Some("PD")),
        (Command::SetTemperatureLimits { max_x16: 2, min_x16: 1 }, Some("PT")),
        (Command::SetSignalUpper { code: 1 }, None),
        (Command::SetSignalLower { code: 1 }, None),
        (Command::SetFrequency { millihertz: 1 }, None),
        (Command::Temperature, Some("TCA")),
        (Command::TemperatureLegacy, Some("TA")),
        (Command::FirmwareType, Some("H")),
        (Command::FirmwareBranch, Some("F")),
        (Command::PartNumber, Some("J")),
        (Command::FirmwareVersion, Some("V")),
        (Command::DeviceId, Some("IR")),
        (Command::LensSerial, Some("X")),
        (Command::Status, Some("S")),
        (Command::AnalogInput, Some("GAA")),
    ];
    for (cmd, header) in cases {
        assert_eq!(cmd.reply_header(), *header, "{cmd:?}");
        assert_eq!(cmd.has_reply(), header.is_some(), "{cmd:?}");
    }
    // The codec's replies start with the header their command expects.
    assert_eq!(Reply::MaxCurrent { centi_ma: 1 }.header(), b"CMA");
    assert_eq!(Reply::ControlledMode { status: 0, max_fp: 0, min_fp: 0 }.header(), b"MCA");
    assert_eq!(Reply::Status([0; 4]).header(), b"S");
}
