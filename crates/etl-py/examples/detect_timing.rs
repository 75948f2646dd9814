//! The Rust side of `benches/py_overhead.py`'s `detect_corners` rows, timed the way the
//! script times Python (best of 7 repeats of 5 calls; one image read once, detected again
//! and again, in a fresh process).
//!
//! `cargo run --release -p etl-py --example detect_timing -- IMAGE.png [--warm]`; prints
//! `best_ms median_ms`. `--warm` first allocates and frees 16 MiB: glibc then serves the
//! detector's large temporaries from its heap instead of fresh `mmap`s (whose first touch
//! page-faults), which is the state a criterion bench runs in after rendering its image.

use std::time::Instant;

use etl_image::checkerboard::{detect_corners, Pattern};

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next() else {
        eprintln!("usage: detect_timing IMAGE.png [--warm]");
        std::process::exit(2);
    };
    let warm = args.next().as_deref() == Some("--warm");
    if warm {
        drop(std::hint::black_box(vec![1u8; 16 << 20]));
    }
    let img = match image::open(&path) {
        Ok(i) => i.to_luma8(),
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    let pattern = match Pattern::new(14, 12) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    if let Err(e) = detect_corners(&img, pattern) {
        eprintln!("{path}: {e}");
        std::process::exit(1);
    }
    let mut per_call_ms = Vec::new();
    for _ in 0..7 {
        let t = Instant::now();
        for _ in 0..5 {
            let _ = std::hint::black_box(detect_corners(std::hint::black_box(&img), pattern));
        }
        per_call_ms.push(t.elapsed().as_secs_f64() * 1e3 / 5.0);
    }
    per_call_ms.sort_by(f64::total_cmp);
    println!("{:.3} {:.3}", per_call_ms[0], per_call_ms[3]);
}
