//! Property tests: decode(encode(x)) = x for every command and reply with data, and the
//! decoders never panic on random bytes (the fuzz target).

use etl_hw::codec::{scan_reply, Command, Mode, Reply};
use proptest::prelude::*;

fn mode() -> impl Strategy<Value = Mode> {
    prop::sample::select(Mode::ALL.to_vec())
}

fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        any::<i16>().prop_map(|code| Command::SetCurrent { code }),
        // Legacy `A`: a valid code (|code| <= 4096) never starts with `w`/`r`.
        (-4096i16..=4096).prop_map(|code| Command::SetCurrentLegacy { code }),
        any::<i16>().prop_map(|code| Command::SetFocalPower { code }),
        any::<i16>().prop_map(|code| Command::SetSignalUpper { code }),
        any::<i16>().prop_map(|code| Command::SetSignalLower { code }),
        any::<u32>().prop_map(|millihertz| Command::SetFrequency { millihertz }),
        (any::<i16>(), any::<i16>()).prop_map(|(max_x16, min_x16)| Command::SetTemperatureLimits { max_x16, min_x16 }),
        mode().prop_map(Command::SetMode),
        prop::sample::select(vec![
            Command::Start,
            Command::GetCurrent,
            Command::ReadMaxCurrent,
            Command::ReadUpperLimit,
            Command::ReadLowerLimit,
            Command::ReadMode,
            Command::GetFocalPower,
            Command::Temperature,
            Command::TemperatureLegacy,
            Command::FirmwareType,
            Command::FirmwareBranch,
            Command::PartNumber,
            Command::FirmwareVersion,
            Command::DeviceId,
            Command::LensSerial,
            Command::Status,
            Command::AnalogInput,
        ]),
    ]
}

fn reply() -> impl Strategy<Value = Reply> {
    prop_oneof![
        any::<i16>().prop_map(|code| Reply::Current { code }),
        any::<i16>().prop_map(|centi_ma| Reply::MaxCurrent { centi_ma }),
        any::<i16>().prop_map(|code| Reply::UpperLimit { code }),
        any::<i16>().prop_map(|code| Reply::LowerLimit { code }),
        // `MwCA` is answered by ControlledMode, never by Mode(Controlled).
        mode().prop_filter("not controlled", |m| *m != Mode::Controlled).prop_map(Reply::Mode),
        (any::<u8>(), any::<i16>(), any::<i16>()).prop_map(|(status, max_fp, min_fp)| Reply::ControlledMode {
            status,
            max_fp,
            min_fp
        }),
        (any::<u8>(), any::<i16>(), any::<i16>()).prop_map(|(status, max_fp, min_fp)| Reply::TemperatureLimits {
            status,
            max_fp,
            min_fp
        }),
        any::<u8>().prop_map(|code| Reply::ActiveMode { code }),
        any::<i16>().prop_map(|code| Reply::FocalPower { code }),
        any::<i16>().prop_map(|raw| Reply::Temperature { raw }),
        (any::<u8>(), any::<i16>()).prop_map(|(status, raw)| Reply::TemperatureLegacy { status, raw }),
        any::<u8>().prop_map(Reply::FirmwareType),
        any::<u8>().prop_map(Reply::FirmwareBranch),
        any::<[u8; 3]>().prop_map(Reply::PartNumber),
        (any::<u8>(), any::<u8>(), any::<u16>(), any::<u16>())
            .prop_map(|(major, minor, build, revision)| Reply::FirmwareVersion { major, minor, build, revision }),
        any::<[u8; 8]>().prop_map(Reply::DeviceId),
        any::<[u8; 8]>().prop_map(Reply::LensSerial),
        any::<[u8; 4]>().prop_map(Reply::Status),
        any::<u16>().prop_map(Reply::AnalogInput),
        any::<u8>().prop_map(Reply::Error),
        Just(Reply::Ready),
        Just(Reply::Nack),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn command_round_trip(c in command()) {
        let f = c.encode();
        prop_assert_eq!(Command::decode(&f), Ok((c, f.len())));
        // A stream of two commands decodes one at a time.
        let mut two = f.clone();
        two.extend_from_slice(&f);
        prop_assert_eq!(Command::decode(&two), Ok((c, f.len())));
    }

    #[test]
    fn reply_round_trip(r in reply(), garbage in prop::collection::vec(any::<u8>(), 0..8)) {
        let f = r.encode();
        prop_assert_eq!(Reply::decode(&f), Ok((r, f.len())));
        // Behind garbage the scanner still finds it (unless the garbage itself holds a
        // valid frame of the same header, which random bytes of this length cannot).
        let mut buf = garbage.clone();
        buf.extend_from_slice(&f);
        let header = &r.header()[..r.header().len().min(3)];
        match scan_reply(&buf, header) {
            etl_hw::codec::Scan::Found { reply, end, .. } => {
                if !matches!(reply, Reply::Error(_) | Reply::Nack) || matches!(r, Reply::Error(_) | Reply::Nack) {
                    prop_assert_eq!(end, buf.len());
                    prop_assert_eq!(reply, r);
                }
            }
            other => prop_assert!(false, "{:?} not found in {:02X?}: {:?}", r, buf, other),
        }
    }

    /// Fuzz: random bytes never panic any decoder.
    #[test]
    fn decoders_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..64), header in prop::sample::select(vec![&b"TCA"[..], b"A", b"MCA", b"Ready", b"V", b"IR"])) {
        let _ = Reply::decode(&bytes);
        let _ = Command::decode(&bytes);
        let _ = scan_reply(&bytes, header);
        let _ = Reply::frame_len(&bytes);
    }

    /// Fuzz with protocol-shaped input: valid headers followed by random bytes.
    #[test]
    fn decoders_never_panic_on_shaped_bytes(r in reply(), tail in prop::collection::vec(any::<u8>(), 0..16), cut in 0usize..20) {
        let mut f = r.encode();
        f.truncate(cut.min(f.len()));
        f.extend_from_slice(&tail);
        let _ = Reply::decode(&f);
        let _ = Command::decode(&f);
        let _ = scan_reply(&f, r.header());
    }
}
