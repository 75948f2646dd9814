// Included by the fuzz target `lens_reply` and by etl-hw's test `fuzz_corpus`: one body of
// checks, so that the committed corpus is replayed exactly as it was fuzzed.

/// Every reply header a command expects (`Command::reply_header`), and one that none does.
const EXPECTED: &[&[u8]] = &[
    b"Ready", b"A", b"CMA", b"CUA", b"CLA", b"MDA", b"MSA", b"MQA", b"MTA", b"MAA", b"MCA", b"MMA", b"PD",
    b"PT", b"TCA", b"TA", b"H", b"F", b"J", b"V", b"IR", b"X", b"S", b"GAA", b"Q",
];

/// Decodes `data` every way the client does; panics (a fuzzing crash) when a decoder
/// panics or breaks its contract: a decoded frame lies within the input, re-encodes to a
/// frame that decodes to itself, and a scan finds frames inside the buffer.
#[allow(dead_code)]
fn check(data: &[u8]) {
    use etl_hw::codec::{scan_reply, Command, Reply, Scan};
    if let Ok((reply, used)) = Reply::decode(data) {
        assert!(used > 0 && used <= data.len(), "decode used {used} of {} bytes", data.len());
        let bytes = reply.encode();
        assert_eq!(Reply::decode(&bytes), Ok((reply, bytes.len())), "re-encoded {reply:?}");
    }
    if let Ok(len) = Reply::frame_len(data) {
        assert!(len > 0, "zero-length frame");
    }
    for expected in EXPECTED {
        match scan_reply(data, expected) {
            Scan::Found { start, end, reply } => {
                assert!(start < end && end <= data.len(), "{start}..{end} of {}", data.len());
                assert_eq!(Reply::decode(&data[start..]).map(|(r, n)| (r, start + n)), Ok((reply, end)));
            }
            Scan::Corrupted { end } => assert!(end <= data.len(), "corrupted frame ends at {end}"),
            Scan::NeedMore => {}
        }
    }
    if let Ok((command, used)) = Command::decode(data) {
        assert!(used > 0 && used <= data.len());
        let _ = command.encode();
    }
}
