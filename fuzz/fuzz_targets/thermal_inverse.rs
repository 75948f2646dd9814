#![no_main]
//! Fuzz target `thermal_inverse`: see `bodies::thermal_inverse`.

#[path = "../src/bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::thermal_inverse(data));
