#![no_main]
//! Fuzz target `calibrate_observations`: see `bodies::calibrate_observations`.

#[path = "../src/bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::calibrate_observations(data));
