//! The lens reply decoder on arbitrary bytes: `Reply::decode`, `Reply::frame_len`,
//! `scan_reply` for every reply header, `Command::decode`. The checks live in
//! `lens_reply_check.rs`, which `crates/etl-hw/tests/it/fuzz_corpus.rs` replays on the
//! committed corpus with stable `cargo test`.
#![no_main]

use libfuzzer_sys::fuzz_target;

include!("lens_reply_check.rs");

fuzz_target!(|data: &[u8]| check(data));
