#![no_main]
//! Fuzz target `charuco_detect`: see `bodies::charuco_detect`.

#[path = "../src/bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::charuco_detect(data));
