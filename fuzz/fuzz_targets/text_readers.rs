#![no_main]
//! Fuzz target `text_readers`: see `bodies::text_readers`.

#[path = "../src/bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::text_readers(data));
