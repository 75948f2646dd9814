//! CPBD, the cumulative probability of blur detection (Narvekar and Karam, IEEE TIP
//! 20(9):2678-2683, 2011), exactly as the reference package `cpbd` 1.0.7 computes it
//! (docs/CPBD.md, sections A.2 to A.5).
//!
//! 64 x 64 blocks (the remainder of the image is ignored) with at least 9 Canny edge
//! pixels are edge blocks; in them, every width of a "vertical" Sobel edge measured along
//! its row counts as detected-sharp when it is at most the block's just-noticeable width
//! (5 px when the block's contrast is at most 50 grey levels, else 3 px). CPBD is the
//! fraction of such widths, accumulated as the package does: a 101-bin histogram of
//! `round(100 P_blur)`, normalised, summed over bins 0..=63 with NumPy's pairwise sum.
//! The result equals the package's bit for bit on every fixture (tests/sharpness.rs).
//!
//! The package computes full-image maps (Canny, Sobel strength, angles, widths) and then
//! pools them; here everything is computed block by block in parallel, and only as far
//! as the pooling needs it, with the same floating-point operations where floats are
//! involved, so the counts and hence the result are the same:
//! * the Sobel threshold needs the mean strength of the whole image, an exact integer
//!   sum (`strength_threshold`, `marziliano.rs`);
//! * the edge-block test stops classifying a block's Canny pixels as soon as it has 9
//!   strong ones (`hysteresis.rs`, `canny.rs`), usually within the block's first rows;
//! * widths are measured only in edge blocks, and each side of a width only as far as
//!   the block's just-noticeable width (`marziliano.rs`).
//!
//! What CPBD does not see: horizontal edges (widths are measured along rows only) and,
//! on a checkerboard, blur beyond about 1 px (all widths exceed 3 px), where it falls to
//! 0. Use a gradient measure for a coarse focus search.

use rayon::prelude::*;

use super::canny::{Bleed, Scratch as CannyScratch};
use super::hysteresis::{decide, Classes, Decision};
use super::marziliano::{any_nonzero_angle, block_widths, strength_threshold, BlockWidths};
use etl_formats::{Error, Result};

/// Block side, px.
pub const BLOCK_PX: usize = 64;
/// A block is an edge block if its Canny edge count exceeds this fraction of its pixels.
pub const EDGE_BLOCK_FRACTION: f64 = 0.002;
/// Block contrast (max - min grey level) up to which the just-noticeable width is 5 px.
pub const JNB_CONTRAST_SPLIT: u8 = 50;

/// Histogram bins of `round(100 (1 - exp(-(w / w_jnb)^3.6)))` for the widths that land
/// in bins 0..=63, as `(w_jnb, [(width, bin)])`; wider widths land in bins 85 and up.
/// Values printed by NumPy 2.4 from the package's own expression (checked in the tests).
const SHARP_BINS_JNB3: [(u8, usize); 2] = [(2, 21), (3, 63)];
const SHARP_BINS_JNB5: [(u8, usize); 4] = [(2, 4), (3, 15), (4, 36), (5, 63)];

/// CPBD of an 8-bit grayscale image given as `height` rows of `width` grey levels
/// (row-major, packed), in [0, 1]; larger is sharper.
///
/// Preconditions: at least one 64 x 64 block (`width, height >= 64`) and
/// `data.len() == width * height`. The reference package returns 0 for smaller images
/// (it has no block to pool); here that is an error because 0 would read as "blurred".
/// A constant image has no edge and gives 0, like the package.
///
/// Errors: [`Error::InvalidInput`] for a wrong length or an image smaller than a block.
///
/// ```
/// use etl_image::sharpness::cpbd::cpbd;
/// // A busy synthetic texture, every edge 1-2 px wide: the reference package gives 1.0.
/// let (w, h) = (128, 64);
/// let img: Vec<u8> = (0..w * h)
///     .map(|k| {
///         let (x, y) = (k % w, k / w);
///         ((x * 37 + y * 91 + (x * y) % 7) % 256) as u8
///     })
///     .collect();
/// assert_eq!(cpbd(&img, w, h).unwrap(), 1.0);
/// // A hard-edged checkerboard gives 0 in the reference as here: CPBD is no focus
/// // measure for a coarse search on a board (see the module docs).
/// let board: Vec<u8> = (0..w * h).map(|k| if ((k % w) / 16 + (k / w) / 16) % 2 == 0 { 200 } else { 40 }).collect();
/// assert_eq!(cpbd(&board, w, h).unwrap(), 0.0);
/// ```
pub fn cpbd(data: &[u8], width: usize, height: usize) -> Result<f64> {
    if width.checked_mul(height) != Some(data.len()) {
        return Err(Error::invalid_value(
            "data",
            data.len(),
            format!("image data holds {} values, not width {width} x height {height}", data.len()),
        ));
    }
    if width < BLOCK_PX || height < BLOCK_PX {
        return Err(Error::invalid_value(
            "image",
            [width, height],
            format!("CPBD needs at least one 64 x 64 block; the image is {width} x {height} px"),
        ));
    }
    if !any_nonzero_angle(data, width, height) {
        // The package measures no width at all (compute.py L88): CPBD 0.
        return Ok(0.0);
    }
    Ok(pool(data, width, height))
}

/// Per-thread working memory of the block loop.
#[derive(Default)]
struct Scratch {
    canny: CannyScratch,
    classes: Vec<u8>,
    strength: Vec<i32>,
}

/// What a block contributes to the pooling.
enum Block {
    /// Measured: the block's just-noticeable width and its width counts.
    Measured(usize, BlockWidths),
    /// Not an edge block; its classes.
    Skipped(Vec<u8>),
    /// Depends on the hysteresis; its classes.
    Undecided(Vec<u8>),
}

/// The package's `_calculate_sharpness_metric` (SPEC.md A.5, compute.py L149-194), block
/// by block in parallel: the edge-block test ([`decide`], then the hysteresis for the
/// few blocks it leaves open), the contrast, the widths; the histogram is a sum of
/// integer counts, so the order the blocks finish in does not matter.
fn pool(data: &[u8], w: usize, h: usize) -> f64 {
    let min_edges_f = (BLOCK_PX * BLOCK_PX) as f64 * EDGE_BLOCK_FRACTION;
    // The package tests `count > 8.192`: the least integer count that passes.
    let min_edges = min_edges_f.floor() as usize + 1;
    let thresh2 = strength_threshold(data, w, h);
    let bleed = Bleed::new(w, h);
    let (bw, bh) = (w / BLOCK_PX, h / BLOCK_PX);
    let measure = |bi: usize, bj: usize, strength: &mut Vec<i32>| {
        let (rows, cols) = (bi * BLOCK_PX..(bi + 1) * BLOCK_PX, bj * BLOCK_PX..(bj + 1) * BLOCK_PX);
        let jnb = if contrast(data, w, &rows, &cols) <= JNB_CONTRAST_SPLIT { 5 } else { 3 };
        (jnb, block_widths(data, w, h, (rows, cols), thresh2, jnb, strength))
    };
    let blocks: Vec<Block> = (0..bw * bh)
        .into_par_iter()
        .map_init(Scratch::default, |s, k| {
            let (bi, bj) = (k / bw, k % bw);
            match decide(data, w, h, &bleed, (bi, bj), min_edges, &mut s.canny, &mut s.classes) {
                Decision::Edge => {
                    let (jnb, widths) = measure(bi, bj, &mut s.strength);
                    Block::Measured(jnb, widths)
                }
                // Kept: the hysteresis of an open block may reach into it.
                Decision::NotEdge(classes) => Block::Skipped(classes),
                Decision::Undecided(classes) => Block::Undecided(classes),
            }
        })
        .collect();

    let mut hist = [0u64; 64];
    let mut total: u64 = 0;
    let mut add = |jnb: usize, widths: &BlockWidths| {
        total += widths.total;
        let bins: &[(u8, usize)] = if jnb == 5 { &SHARP_BINS_JNB5 } else { &SHARP_BINS_JNB3 };
        for &(wd, bin) in bins {
            hist[bin] += widths.by_width[wd as usize];
        }
    };
    let mut open = Vec::new();
    let mut classes = Classes::new(data, w, h, &bleed);
    for (k, b) in blocks.into_iter().enumerate() {
        match b {
            Block::Measured(jnb, widths) => add(jnb, &widths),
            Block::Skipped(c) => classes.insert((k / bw, k % bw), c),
            Block::Undecided(c) => {
                classes.insert((k / bw, k % bw), c);
                open.push(k);
            }
        }
    }
    let mut strength = Vec::new();
    for k in open {
        let (bi, bj) = (k / bw, k % bw);
        if classes.edges_in_block((bi, bj)) >= min_edges {
            let (jnb, widths) = measure(bi, bj, &mut strength);
            add(jnb, &widths);
        }
    }
    if total == 0 {
        return 0.0;
    }
    let p: Vec<f64> = hist.iter().map(|&c| c as f64 / total as f64).collect();
    numpy_sum_64(&p)
}

/// `int(max - min)` of the block's grey levels (compute.py L203-205).
fn contrast(data: &[u8], w: usize, rows: &std::ops::Range<usize>, cols: &std::ops::Range<usize>) -> u8 {
    let (mut lo, mut hi) = (u8::MAX, u8::MIN);
    for r in rows.clone() {
        for &v in &data[r * w..][cols.clone()] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    hi.saturating_sub(lo)
}

/// NumPy's pairwise float64 sum of exactly 64 values (`pairwise_sum` with 8 accumulators
/// for n <= 128), so that the rounding matches `np.sum(hist[:64])`.
fn numpy_sum_64(a: &[f64]) -> f64 {
    let mut r = [0.0f64; 8];
    r.copy_from_slice(&a[..8]);
    for chunk in a[8..].chunks_exact(8) {
        for (acc, v) in r.iter_mut().zip(chunk) {
            *acc += v;
        }
    }
    ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sharp_bins_follow_the_package_expression() {
        let bin = |wd: f64, jnb: f64| (100.0 * (1.0 - (-(wd / jnb).abs().powf(3.6)).exp())).round_ties_even() as usize;
        for (jnb, table) in [(3.0, &SHARP_BINS_JNB3[..]), (5.0, &SHARP_BINS_JNB5[..])] {
            for &(wd, b) in table {
                assert_eq!(bin(wd as f64, jnb), b);
            }
            // The first width beyond the table is past bin 63.
            assert!(bin(table.len() as f64 + 2.0, jnb) > 63);
        }
    }

    #[test]
    fn pairwise_sum_order() {
        // 1 + 64 tiny values: sequential summation would absorb them, pairwise keeps some.
        let mut a = [1e-17f64; 64];
        a[0] = 1.0;
        let seq: f64 = a.iter().sum();
        assert_eq!(seq, 1.0);
        assert!(numpy_sum_64(&a) > 1.0);
    }
}
