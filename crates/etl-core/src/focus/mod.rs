//! Sharpness measures and autofocus, without allocation, over a borrowed grayscale view;
//! and the focus law of a calibrated camera ([`FocusLaw`]: distance in focus <-> current).
//!
//! The measures ([`tenengrad()`], [`laplacian_variance`], [`brenner()`],
//! [`normalised_variance`]) take an [`ImageView`] of 8- or 16-bit pixels with any row
//! stride (a region of interest of a camera frame is measured in place) and return a
//! number that is larger when the image is sharper, in the image's own grey-level scale.
//! [`autofocus()`] finds the lens current that maximises any such measure with a small,
//! fixed number of frames. CPBD, the perceptual measure the paper's temperature procedure
//! maximises, needs buffers and lives in `etl-calib` (`sharpness::cpbd`).
//!
//! Which measure to focus with (measured on the synthetic camera over noise realisations,
//! docs/RESULTS.md, "Sharpness and autofocus"): [`tenengrad()`]. It falls as 1/blur, so it
//! still ranks images several pixels out of focus, and its peak was found within 0.3 mA
//! of the true best focus in every search, at read noise 2 and 8 grey levels. [`brenner()`]
//! does as well; [`normalised_variance`] is as accurate with the flattest peak;
//! [`laplacian_variance`] falls as blur^-3 into the noise floor and misled one noisy
//! search in eight. CPBD cannot drive a search: far from focus it sees only noise edges,
//! which it calls sharp.
//!
//! ```
//! use etl_core::focus::{autofocus, tenengrad, AutofocusOptions, ImageView};
//! // A toy "camera": a vertical edge whose width grows with the distance from 150 mA.
//! let mut frame = [0u8; 32 * 8];
//! let mut grab = |e_ma: f64| {
//!     let width = 1.0 + (e_ma - 150.0).abs() / 10.0;
//!     for (i, p) in frame.iter_mut().enumerate() {
//!         let x = (i % 32) as f64 - 15.5;
//!         *p = (127.5 + 127.5 * (x / width).tanh()) as u8;
//!     }
//!     tenengrad(&ImageView::packed(&frame, 32, 8)?)
//! };
//! let r = autofocus(&mut grab, &AutofocusOptions::default()).unwrap();
//! assert!((r.best_ma - 150.0).abs() < 1.0 && r.evaluations <= 15);
//! ```

pub mod autofocus;
pub mod brenner;
pub mod image;
pub mod laplacian;
pub mod law;
pub mod normvar;
pub mod tenengrad;

pub use autofocus::{autofocus, AutofocusOptions, AutofocusResult};
pub use brenner::brenner;
pub use image::{ImageView, Pixel, MAX_SIDE_PX};
pub use laplacian::laplacian_variance;
pub use law::{FocusLaw, FocusSample, FOCUS_LAW_MIN_CURRENTS, FOCUS_LAW_RANGE_MARGIN};
pub use normvar::normalised_variance;
pub use tenengrad::tenengrad;

#[cfg(test)]
mod tests {
    // Tests of the sharpness measures against direct floating-point formulas and hand-computed
    // values, and of the autofocus search on functions with a known peak.

    use super::*;
    use crate::Error;

    /// A deterministic pseudo-random 8-bit image (xorshift), `w` x `h`, packed.
    fn noise_image(w: usize, h: usize, seed: u64) -> [[u8; 40]; 30] {
        let mut s = seed | 1;
        let mut img = [[0u8; 40]; 30];
        for row in img.iter_mut().take(h) {
            for p in row.iter_mut().take(w) {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                *p = (s >> 24) as u8;
            }
        }
        img
    }

    fn at(img: &[[u8; 40]; 30], x: usize, y: usize) -> f64 {
        img[y][x] as f64
    }

    /// The measures written as plainly as possible in f64.
    fn reference(img: &[[u8; 40]; 30], w: usize, h: usize) -> [f64; 4] {
        let (mut ten, mut n) = (0.0, 0.0);
        let mut laps = [0.0f64; 40 * 30];
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let gx = at(img, x + 1, y - 1) + 2.0 * at(img, x + 1, y) + at(img, x + 1, y + 1)
                    - at(img, x - 1, y - 1)
                    - 2.0 * at(img, x - 1, y)
                    - at(img, x - 1, y + 1);
                let gy = at(img, x - 1, y + 1) + 2.0 * at(img, x, y + 1) + at(img, x + 1, y + 1)
                    - at(img, x - 1, y - 1)
                    - 2.0 * at(img, x, y - 1)
                    - at(img, x + 1, y - 1);
                ten += gx * gx + gy * gy;
                laps[n as usize] =
                    at(img, x - 1, y) + at(img, x + 1, y) + at(img, x, y - 1) + at(img, x, y + 1) - 4.0 * at(img, x, y);
                n += 1.0;
            }
        }
        let mean_lap = laps[..n as usize].iter().sum::<f64>() / n;
        let var_lap = laps[..n as usize].iter().map(|l| (l - mean_lap) * (l - mean_lap)).sum::<f64>() / n;
        let (mut bh, mut bv) = (0.0, 0.0);
        for y in 0..h {
            for x in 0..w {
                if x + 2 < w {
                    bh += (at(img, x + 2, y) - at(img, x, y)).powi(2);
                }
                if y + 2 < h {
                    bv += (at(img, x, y + 2) - at(img, x, y)).powi(2);
                }
            }
        }
        let bren = bh / (h * (w - 2)) as f64 + bv / ((h - 2) * w) as f64;
        let mut mu = 0.0;
        for y in 0..h {
            for x in 0..w {
                mu += at(img, x, y);
            }
        }
        mu /= (w * h) as f64;
        let mut var = 0.0;
        for y in 0..h {
            for x in 0..w {
                var += (at(img, x, y) - mu).powi(2);
            }
        }
        var /= (w * h) as f64;
        [ten / n, var_lap, bren, var / mu]
    }

    fn measures<T: Pixel>(v: &ImageView<'_, T>) -> [f64; 4] {
        [tenengrad(v).unwrap(), laplacian_variance(v).unwrap(), brenner(v).unwrap(), normalised_variance(v).unwrap()]
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn measures_match_direct_formulas_on_noise_with_stride() {
        for (w, h, seed) in [(40, 30, 1), (17, 9, 7), (3, 3, 11), (5, 28, 99)] {
            let img = noise_image(w, h, seed);
            let want = reference(&img, w, h);
            // A strided view over the 40-wide rows, and a packed copy.
            let flat: &[u8] = img.as_flattened();
            let strided = ImageView::new(flat, w, h, 40).unwrap();
            let mut packed = [0u8; 40 * 30];
            for y in 0..h {
                packed[y * w..y * w + w].copy_from_slice(&img[y][..w]);
            }
            let tight = ImageView::packed(&packed[..w * h], w, h).unwrap();
            for got in [measures(&strided), measures(&tight)] {
                for (g, r) in got.iter().zip(want) {
                    assert!(close(*g, r, 1e-12), "{w}x{h}: {g} vs {r}");
                }
            }
        }
    }

    #[test]
    fn sixteen_bit_scales_with_the_square_of_the_gain() {
        let img = noise_image(40, 30, 5);
        let eight = measures(&ImageView::new(img.as_flattened(), 40, 30, 40).unwrap());
        let mut wide = [0u16; 40 * 30];
        for (d, s) in wide.iter_mut().zip(img.as_flattened()) {
            *d = *s as u16 * 257;
        }
        let sixteen = measures(&ImageView::packed(&wide, 40, 30).unwrap());
        for k in 0..3 {
            assert!(close(sixteen[k], eight[k] * 257.0 * 257.0, 1e-12));
        }
        assert!(close(sixteen[3], eight[3] * 257.0, 1e-12));
        // Full-scale 16-bit values do not overflow the integer sums.
        let mut checker = [0u16; 40 * 30];
        for (i, p) in checker.iter_mut().enumerate() {
            *p = if (i % 40 + i / 40) % 2 == 0 { 65535 } else { 0 };
        }
        let v = ImageView::packed(&checker, 40, 30).unwrap();
        // Interior Sobel on a one-pixel checker is 0 in x and y (the +-1 columns are equal).
        assert_eq!(tenengrad(&v).unwrap(), 0.0);
        assert_eq!(laplacian_variance(&v).unwrap(), (4.0 * 65535.0f64).powi(2));
        assert_eq!(brenner(&v).unwrap(), 0.0);
        assert_eq!(normalised_variance(&v).unwrap(), 65535.0 / 2.0);
    }

    #[test]
    fn hand_computed_edge() {
        // Columns 0 0 0 9 9 9: Sobel |Gx| = 36 on columns 2 and 3 of the interior (1..=4),
        // Brenner pairs (x, x+2) differ by 9 for x = 1, 2.
        let mut px = [0u8; 6 * 4];
        for (i, p) in px.iter_mut().enumerate() {
            *p = if i % 6 >= 3 { 9 } else { 0 };
        }
        let v = ImageView::packed(&px, 6, 4).unwrap();
        assert_eq!(tenengrad(&v).unwrap(), 2.0 * 36.0 * 36.0 / 4.0);
        // Laplacian row: 0, 9, -9, 0 over the interior columns: mean 0, variance 81/2.
        assert_eq!(laplacian_variance(&v).unwrap(), 40.5);
        assert_eq!(brenner(&v).unwrap(), 2.0 * 81.0 / 4.0);
        assert_eq!(normalised_variance(&v).unwrap(), 20.25 / 4.5);
    }

    #[test]
    fn constant_images_are_zero_and_sharpness_falls_with_blur() {
        let px = [77u8; 64];
        let v = ImageView::packed(&px, 8, 8).unwrap();
        assert_eq!(measures(&v), [0.0; 4]);
        // A step, then the same step smeared over 3 px: every measure drops.
        let mut sharp = [0u8; 16 * 4];
        let mut soft = [0u8; 16 * 4];
        for i in 0..64 {
            let x = i % 16;
            sharp[i] = if x >= 8 { 200 } else { 20 };
            soft[i] = match x {
                0..=6 => 20,
                7 => 65,
                8 => 110,
                9 => 155,
                _ => 200,
            };
        }
        let a = measures(&ImageView::packed(&sharp, 16, 4).unwrap());
        let b = measures(&ImageView::packed(&soft, 16, 4).unwrap());
        for k in 0..3 {
            assert!(b[k] < a[k], "measure {k}: {} !< {}", b[k], a[k]);
        }
    }

    #[test]
    fn bad_views_and_images_are_refused() {
        let px = [1u8; 12];
        assert!(matches!(ImageView::packed(&px, 0, 3), Err(Error::OutOfRange { .. })));
        assert!(matches!(ImageView::packed(&px, 3, 0), Err(Error::OutOfRange { .. })));
        assert!(matches!(ImageView::packed(&px[..0], 1, 1), Err(Error::BufferTooSmall { needed: 1, got: 0, .. })));
        assert!(matches!(ImageView::new(&px, 4, 3, 3), Err(Error::InvalidArgument { .. })));
        assert!(matches!(ImageView::new(&px, 3, 3, 5), Err(Error::BufferTooSmall { needed: 13, got: 12, .. })));
        assert!(ImageView::new(&px, 2, 3, 5).is_ok());
        assert!(matches!(ImageView::new(&px, MAX_SIDE_PX + 1, 1, MAX_SIDE_PX + 1), Err(Error::OutOfRange { .. })));
        assert!(matches!(ImageView::new(&px, 1, 2, usize::MAX), Err(Error::BufferTooSmall { .. })));
        let tiny = ImageView::packed(&px, 6, 2).unwrap();
        for r in [tenengrad(&tiny), laplacian_variance(&tiny), brenner(&tiny)] {
            assert!(matches!(r, Err(Error::TooFew { needed: 3, got: 2, .. })));
        }
        assert_eq!(normalised_variance(&tiny).unwrap(), 0.0);
        let black = [0u16; 9];
        let v = ImageView::packed(&black, 3, 3).unwrap();
        assert!(matches!(normalised_variance(&v), Err(Error::Degenerate { .. })));
        assert_eq!(v.row(3), &[] as &[u16]);
    }

    fn peak(e_ma: f64, centre: f64, width: f64) -> f64 {
        // A defocused edge: sharpness ~ 1 / sqrt(blur^2 + floor^2), blur linear in the current.
        1.0 / libm::sqrt(1.0 + ((e_ma - centre) / width) * ((e_ma - centre) / width))
    }

    #[test]
    fn autofocus_finds_peaks_anywhere_in_the_range() {
        let opts = AutofocusOptions::default();
        let mut worst: f64 = 0.0;
        for i in 0..60 {
            let centre = 78.0 + 2.71 * i as f64;
            for width in [1.5, 4.0, 12.0] {
                let mut calls = 0;
                let r = autofocus(
                    |e| {
                        calls += 1;
                        assert!((opts.range_ma[0]..=opts.range_ma[1]).contains(&e));
                        Ok(peak(e, centre, width))
                    },
                    &opts,
                )
                .unwrap();
                assert_eq!(r.evaluations, calls);
                assert!(r.evaluations <= 15);
                assert!(r.bracket_ma[0] <= r.best_ma && r.best_ma <= r.bracket_ma[1]);
                worst = worst.max((r.best_ma - centre).abs());
            }
        }
        assert!(worst < 0.5, "worst error {worst} mA");
    }

    #[test]
    fn autofocus_on_a_parabola_converges_quickly_and_handles_the_range_ends() {
        let opts = AutofocusOptions { tolerance_ma: 0.01, ..AutofocusOptions::default() };
        let r = autofocus(|e| Ok(-(e - 123.4) * (e - 123.4)), &opts).unwrap();
        assert!(r.converged && (r.best_ma - 123.4).abs() < 0.02 && r.evaluations < 15, "{r:?}");
        // Peak beyond the upper end: the search ends at the end of the range.
        let r = autofocus(Ok, &opts).unwrap();
        assert!((r.best_ma - 240.0).abs() < 0.1, "{r:?}");
        let r = autofocus(|e| Ok(-e), &opts).unwrap();
        assert!((r.best_ma - 75.0).abs() < 0.1, "{r:?}");
        // A tight budget: no more evaluations than allowed, the best so far returned.
        let tight = AutofocusOptions { max_evaluations: 7, ..opts };
        let r = autofocus(|e| Ok(peak(e, 150.0, 3.0)), &tight).unwrap();
        assert_eq!(r.evaluations, 7);
        assert!(!r.converged);
    }

    #[test]
    fn autofocus_refuses_bad_options_and_passes_errors_through() {
        let f = |e: f64| Ok(e);
        let base = AutofocusOptions::default();
        let bad = [
            AutofocusOptions { range_ma: [10.0, 10.0], ..base },
            AutofocusOptions { range_ma: [f64::NAN, 10.0], ..base },
            AutofocusOptions { coarse_points: 2, ..base },
            AutofocusOptions { max_evaluations: 6, ..base },
            AutofocusOptions { tolerance_ma: 0.0, ..base },
            AutofocusOptions { tolerance_ma: f64::INFINITY, ..base },
        ];
        for o in bad {
            assert!(autofocus(f, &o).is_err(), "{o:?}");
        }
        // A range beyond the driver's currents (1e308 made every searched current NaN)
        // is refused before the measure is called once.
        for range_ma in [[-1e308, 1e308], [75.0, 300.0], [-300.0, 0.0]] {
            let mut calls = 0;
            let r = autofocus(
                |e| {
                    calls += 1;
                    Ok(e)
                },
                &AutofocusOptions { range_ma, ..base },
            );
            assert!(matches!(r, Err(Error::OutOfRange { min: -292.84, max: 292.84, .. })), "{range_ma:?}: {r:?}");
            assert_eq!(calls, 0, "{range_ma:?}");
        }
        let r = autofocus(|_| Err(Error::Degenerate { what: "camera" }), &base);
        assert_eq!(r, Err(Error::Degenerate { what: "camera" }));
        let r = autofocus(|e| Ok(if e > 200.0 { f64::NAN } else { 1.0 }), &base);
        assert!(matches!(r, Err(Error::NotFinite { .. })));
    }
}
