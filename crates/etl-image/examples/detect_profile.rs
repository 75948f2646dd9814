//! Detection on one image, N times (default 1), for profilers and instruction counts:
//!
//! `RAYON_NUM_THREADS=1 valgrind --tool=callgrind target/release/examples/detect_profile IMAGE.png [N] [CxR]`
//!
//! The `detect` bench writes its views as `target/criterion/detect_view_blur_*.png`.
use etl_image::checkerboard::{detect_corners, Pattern};

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next() else {
        eprintln!("usage: detect_profile IMAGE.png [N] [CxR]");
        std::process::exit(2);
    };
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    let pattern: Pattern = match args.next().unwrap_or_else(|| "14x12".into()).parse() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let img = match image::open(&path) {
        Ok(i) => i.to_luma8(),
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    for _ in 0..n {
        match detect_corners(std::hint::black_box(&img), pattern) {
            Ok(d) => {
                std::hint::black_box(d);
            }
            Err(e) => {
                eprintln!("{path}: {e}");
                std::process::exit(1);
            }
        }
    }
}
