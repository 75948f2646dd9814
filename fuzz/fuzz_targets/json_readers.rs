#![no_main]
//! Fuzz target `json_readers`: see `bodies::json_readers`.

#[path = "../src/bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::json_readers(data));
