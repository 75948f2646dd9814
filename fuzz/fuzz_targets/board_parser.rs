#![no_main]
//! Fuzz target `board_parser`: see `bodies::board_parser`.

#[path = "../src/bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::board_parser(data));
