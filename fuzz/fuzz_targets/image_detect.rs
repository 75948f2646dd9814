#![no_main]
//! Fuzz target `image_detect`: see `bodies::image_detect`.

#[path = "../src/bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::image_detect(data));
