//! The bilinear kernel behind [`super::remap`], written so that the compiler vectorises
//! what can be vectorised, without `unsafe` or intrinsics.
//!
//! A child of [`super`] rather than its sibling: it reads the parent's [`Sample`] and
//! [`SourceImage`], and the parent runs it (siblings importing each other would be a
//! cycle).
//!
//! Output pixels go through in blocks of [`BLOCK`], each in three passes over small arrays
//! on the stack:
//! 1. positions ([`Positions::locate`], a branch-free vector loop): every pixel's fractions
//!    (a, b) and its offset in the image, 0 for a pixel whose 2 x 2 neighbourhood is not
//!    wholly inside (so that the gather never branches on it);
//! 2. gather: the four taps of every pixel (scalar loads, one bounds check per pair of
//!    taps);
//! 3. blend: the bilinear formula of [`super::remap`] in f32, a branch-free vector loop;
//!
//! and the block's pixels whose neighbourhood is not wholly inside, if any, are done again
//! one by one with the border ([`fix_edges`]). Splitting the gathers (which no x86-64
//! baseline instruction vectorises) from the arithmetic (which SSE2 does 4 to 16 lanes at a
//! time) is what makes it fast (docs/PERFORMANCE-HISTORY.md, "Undistortion"). The numbers are those
//! of the one-pass scalar loop it replaces, bit for bit: the same f32 operations in the
//! same order.

use super::{Sample, SourceImage};

/// Output pixels per block: small enough that the block's arrays (at most 6 KB, for three
/// f32 channels) stay in L1, large enough that the vector loops run long.
pub(crate) const BLOCK: usize = 64;

/// Largest side of an image the vector path reads, px (2^15 - 1): a source pixel then fits
/// i16, so that the offsets y w + x are products of 16-bit numbers. [`super::remap`]
/// resamples larger images one pixel at a time ([`remap_pixel`]).
pub(crate) const MAX_VECTOR_SIDE_PX: usize = (1 << 15) - 1;

/// 1.5 * 2^23: adding it to |v| <= 2^22 leaves an f32 whose last mantissa bit is worth 1,
/// so the sum rounds v to an integer, and that integer is the difference of the bit
/// patterns. Rounding this way, rather than by a float-to-int cast (whose saturating
/// semantics keep the loop scalar), vectorises.
pub(crate) const ROUNDER: f32 = 12_582_912.0;

/// What the position pass needs of the source image.
#[derive(Clone, Copy)]
pub(crate) struct Geometry {
    /// width - 1, height - 1 as f32 (exact): a position (x, y) has its four taps inside
    /// when 0 <= x < w1 and 0 <= y < h1.
    w1: f32,
    h1: f32,
    /// The width (at most [`MAX_VECTOR_SIDE_PX`]).
    width: i16,
}

impl Geometry {
    /// Whether the four taps of the map entry (x, y) are inside the image (the vector
    /// path's pixels). `&`, not `&&`: no branch, so a loop calling it vectorises; NaN fails
    /// every comparison.
    #[inline(always)]
    fn inside(&self, x: f32, y: f32) -> bool {
        (x >= 0.0) & (y >= 0.0) & (x < self.w1) & (y < self.h1)
    }

    /// The geometry of `src`, or None when a side exceeds [`MAX_VECTOR_SIDE_PX`].
    pub(crate) fn of<T: Sample>(src: &SourceImage<'_, T>) -> Option<Self> {
        let (w, h) = (src.width(), src.height());
        let width = i16::try_from(w).ok().filter(|_| h <= MAX_VECTOR_SIDE_PX)?;
        // Sides are at least 1 and below 2^15: exact in f32.
        Some(Geometry { w1: (w - 1) as f32, h1: (h - 1) as f32, width })
    }
}

/// Where the pixels of one block read the image: pixel i interpolates at fractions
/// (a[i], b[i]) from the pixel at offset `off[i]` = y0 * width + x0 (x0, y0 the floors of
/// its map entries) when its 2 x 2 neighbourhood is inside the image, else `off[i]` is 0
/// and `edges` is set.
pub struct Positions {
    a: [f32; BLOCK],
    b: [f32; BLOCK],
    off: [u32; BLOCK],
    edges: bool,
    geometry: Geometry,
}

impl Positions {
    pub(crate) const fn new(geometry: Geometry) -> Self {
        Positions { a: [0.0; BLOCK], b: [0.0; BLOCK], off: [0; BLOCK], edges: false, geometry }
    }

    /// Locates up to [`BLOCK`] map entries (the shorter of `map_x`, `map_y`). Returns the
    /// number of entries.
    #[inline(always)]
    pub(crate) fn locate(&mut self, map_x: &[f32], map_y: &[f32]) -> usize {
        let (g, mut edges) = (self.geometry, false);
        let n = if let (Some(mx), Some(my)) = (map_x.first_chunk::<BLOCK>(), map_y.first_chunk::<BLOCK>()) {
            // A whole block: a loop of known length over arrays, which vectorises.
            for i in 0..BLOCK {
                edges |= self.set(i, mx[i], my[i], g);
            }
            BLOCK
        } else {
            let n = map_x.len().min(map_y.len()).min(BLOCK);
            for (i, (&x, &y)) in map_x.iter().zip(map_y).take(n).enumerate() {
                edges |= self.set(i, x, y, g);
            }
            n
        };
        self.edges = edges;
        n
    }

    /// Pixel i (< [`BLOCK`]) at the map entry (x, y). Returns whether its neighbourhood is
    /// not wholly inside the image.
    #[inline(always)]
    fn set(&mut self, i: usize, x: f32, y: f32, g: Geometry) -> bool {
        let inside = g.inside(x, y);
        // Clamped into [0, 2^15) (NaN to 0: `max` returns the other operand), so that the
        // rounding below is exact; inside, the clamp changes nothing.
        let (xc, yc) = (x.max(0.0).min(g.w1), y.max(0.0).min(g.h1));
        let (x0, y0) = (floor(xc), floor(yc));
        // Inside, x0 <= w - 2 and y0 <= h - 2 fit i16 and y0 w + x0 < 2^30.
        let off = i32::from(y0 as i16) * i32::from(g.width) + i32::from(x0 as i16);
        if let (Some(a), Some(b), Some(o)) = (self.a.get_mut(i), self.b.get_mut(i), self.off.get_mut(i)) {
            // The fractions as the scalar formula has them: x - x0, exact in f32.
            (*a, *b) = (xc - x0 as f32, yc - y0 as f32);
            *o = if inside { off as u32 } else { 0 };
        }
        !inside
    }
}

/// floor(v) for 0 <= v < 2^22, branch-free and vectorisable: v rounded to an integer
/// (to even on halves), less one where that rounded up.
#[inline(always)]
fn floor(v: f32) -> i32 {
    let r = (v + ROUNDER).to_bits() as i32 - ROUNDER.to_bits() as i32;
    r - i32::from(r as f32 > v)
}

/// The four taps of every pixel of a block, one array per tap, and each sample's fractions
/// (so that the blend reads them as vectors); reused from block to block.
pub struct Taps<T, const C: usize> {
    t00: [[T; C]; BLOCK],
    t01: [[T; C]; BLOCK],
    t10: [[T; C]; BLOCK],
    t11: [[T; C]; BLOCK],
    a: [[f32; C]; BLOCK],
    b: [[f32; C]; BLOCK],
}

impl<T: Sample, const C: usize> Taps<T, C> {
    pub(crate) fn new(fill: T) -> Self {
        let t = [[fill; C]; BLOCK];
        Taps { t00: t, t01: t, t10: t, t11: t, a: [[0.0; C]; BLOCK], b: [[0.0; C]; BLOCK] }
    }
}

/// The bilinear formula of [`super::remap`]: the same f32 operations in the same order as
/// the scalar code, so the same numbers.
#[inline(always)]
fn interpolate(s00: f32, s01: f32, s10: f32, s11: f32, a: f32, b: f32) -> f32 {
    let top = s00 + a * (s01 - s00);
    let bottom = s10 + a * (s11 - s10);
    top + b * (bottom - top)
}

/// Resamples one block: `dst` takes its first `n * C` samples (`n` <= [`BLOCK`] the pixels
/// the caller located from `map_x`, `map_y`; a shorter `dst` leaves the rest unwritten).
/// Precondition (callers): `src` of C channels, `pos` located with the geometry of `src`.
#[inline(always)]
pub(crate) fn remap_block<T: Sample, const C: usize>(
    src: &SourceImage<'_, T>,
    pos: &Positions,
    maps: (&[f32], &[f32]),
    border: T,
    taps: &mut Taps<T, C>,
    dst: &mut [T],
) {
    let data = src.data();
    let below = data.get(src.width() * C..).unwrap_or(&[]);
    // Every pixel of the block, also past `n` (stale positions, never written out): a loop
    // of known length, so every array index is provably inside.
    for i in 0..BLOCK {
        let o = pos.off[i] as usize * C;
        // Rows y0 and y0 + 1 from x0: runs of 2 C samples at o in `data` and in `below`.
        // Each `get` is one check (o < 2^32 C cannot overflow); a run's length, 2 C, then
        // proves the split.
        let run = |s: &[T]| s.get(o..o + 2 * C).and_then(split_pair).unwrap_or(([border; C], [border; C]));
        let ((s00, s01), (s10, s11)) = (run(data), run(below));
        [taps.t00[i], taps.t01[i], taps.t10[i], taps.t11[i]] = [s00, s01, s10, s11];
        (taps.a[i], taps.b[i]) = ([pos.a[i]; C], [pos.b[i]; C]);
    }
    let m = maps.0.len().min(BLOCK) * C;
    let (t00, t01) = (taps.t00.as_flattened(), taps.t01.as_flattened());
    let (t10, t11) = (taps.t10.as_flattened(), taps.t11.as_flattened());
    let weights = taps.a.as_flattened().iter().zip(taps.b.as_flattened());
    let samples = dst.iter_mut().zip(t00).zip(t01).zip(t10).zip(t11).zip(weights).take(m);
    for (((((o, &s00), &s01), &s10), &s11), (&a, &b)) in samples {
        *o = T::from_f32(interpolate(s00.to_f32(), s01.to_f32(), s10.to_f32(), s11.to_f32(), a, b));
    }
    if pos.edges {
        fix_edges::<T, C>(src, pos.geometry, maps, border, dst);
    }
}

/// [`remap_block`] for one channel of u8, the common case: the gather loads each pixel's
/// two pairs of taps as two u16, and the blend unpacks them in the vector loop. The same
/// values.
#[inline(always)]
pub(crate) fn remap_block_grey_u8(
    src: &SourceImage<'_, u8>,
    pos: &Positions,
    maps: (&[f32], &[f32]),
    border: u8,
    dst: &mut [u8],
) {
    let data = src.data();
    // The row below starts w samples on: the same offset in `below` is the bottom pair,
    // and both checks (one compare each: o < 2^32 cannot overflow) look alike.
    let below = data.get(src.width()..).unwrap_or(&[]);
    let pair =
        |s: &[u8], o: usize| s.get(o..o + 2).and_then(|p| p.first_chunk::<2>()).map_or(0, |&p| u16::from_le_bytes(p));
    let (mut top, mut bottom) = ([0u16; BLOCK], [0u16; BLOCK]);
    for i in 0..BLOCK {
        let o = pos.off[i] as usize;
        (top[i], bottom[i]) = (pair(data, o), pair(below, o));
    }
    let n = maps.0.len().min(BLOCK);
    let blend = |t: u16, b: u16, i: usize| -> u8 {
        let s = [t & 0xff, t >> 8, b & 0xff, b >> 8].map(f32::from);
        let (a, b) = (pos.a.get(i).copied().unwrap_or(0.0), pos.b.get(i).copied().unwrap_or(0.0));
        u8::from_f32(interpolate(s[0], s[1], s[2], s[3], a, b))
    };
    match dst.first_chunk_mut::<BLOCK>() {
        // A whole block: a loop of known length, vectorised without a scalar tail.
        Some(out) if n >= BLOCK => {
            for i in 0..BLOCK {
                out[i] = blend(top[i], bottom[i], i);
            }
        }
        _ => {
            for (i, ((o, &t), &b)) in dst.iter_mut().zip(&top).zip(&bottom).take(n).enumerate() {
                *o = blend(t, b, i);
            }
        }
    }
    if pos.edges {
        fix_edges::<u8, 1>(src, pos.geometry, maps, border, dst);
    }
}

/// A run of 2 C samples as the pixels (x0, x0 + 1) of one row.
#[inline(always)]
fn split_pair<T: Copy, const C: usize>(run: &[T]) -> Option<([T; C], [T; C])> {
    let (a, rest) = run.split_first_chunk::<C>()?;
    Some((*a, *rest.first_chunk::<C>()?))
}

/// The pixels among the first `n` of a block (`n` the shorter map's length, at most
/// [`BLOCK`]) whose neighbourhood is not wholly inside the image, again, one by one.
#[inline(never)]
fn fix_edges<T: Sample, const C: usize>(
    src: &SourceImage<'_, T>,
    g: Geometry,
    (map_x, map_y): (&[f32], &[f32]),
    border: T,
    dst: &mut [T],
) {
    for ((&x, &y), out) in map_x.iter().zip(map_y).zip(dst.chunks_exact_mut(C)).take(BLOCK) {
        if !g.inside(x, y) {
            remap_pixel::<T, C>(src, x, y, border, out);
        }
    }
}

/// One output pixel of [`super::remap`] at the map entry (x, y), by the scalar formula:
/// each of the four taps outside the image reads `border`; a position wholly outside, NaN
/// or infinite gives `border`. For the pixels the vector path leaves out (near or beyond
/// the edges, and every pixel of an image wider or taller than [`MAX_VECTOR_SIDE_PX`]).
#[inline(never)]
pub(crate) fn remap_pixel<T: Sample, const C: usize>(
    src: &SourceImage<'_, T>,
    x: f32,
    y: f32,
    border: T,
    out: &mut [T],
) {
    let (w, h, data) = (src.width(), src.height(), src.data());
    // Sides are at most 2^20: exact in f32. A position in (-1, w) x (-1, h) has at least
    // one tap inside.
    if !(x > -1.0 && y > -1.0 && x < w as f32 && y < h as f32) {
        out.fill(border);
        return;
    }
    let (xf, yf) = (libm::floorf(x), libm::floorf(y));
    let (a, b) = (x - xf, y - yf);
    // xf, yf in [-1, w - 1], [-1, h - 1]: the casts are exact.
    let (x0, y0) = (xf as isize, yf as isize);
    let tap = |xi: isize, yi: isize, c: usize| -> f32 {
        if xi < 0 || yi < 0 || xi as usize >= w || yi as usize >= h {
            border.to_f32()
        } else {
            data.get((yi as usize * w + xi as usize) * C + c).map_or(border.to_f32(), |s| s.to_f32())
        }
    };
    for (c, o) in out.iter_mut().enumerate() {
        let (s00, s01) = (tap(x0, y0, c), tap(x0 + 1, y0, c));
        let (s10, s11) = (tap(x0, y0 + 1, c), tap(x0 + 1, y0 + 1, c));
        *o = T::from_f32(interpolate(s00, s01, s10, s11, a, b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::undistort::remap;
    use core::fmt::Debug;
    use rand::{Rng, SeedableRng};

    const W: usize = 23;
    const H: usize = 17;
    /// Three whole blocks and a partial one.
    const N: usize = 3 * BLOCK + 5;

    /// Map entries over [-3, W + 2] x [-3, H + 2] (inside, across every edge, wholly
    /// outside), one in eight NaN or infinite, one in eight on a whole pixel (the edges of
    /// the inside test fall there).
    fn random_maps(rng: &mut impl Rng) -> ([f32; N], [f32; N]) {
        let mut draw = |side: usize| -> f32 {
            match rng.random_range(0..16) {
                0 => f32::NAN,
                1 => [f32::INFINITY, f32::NEG_INFINITY, 1e30][rng.random_range(0..3)],
                2 | 3 => rng.random_range(-2..=side as i32 + 1) as f32,
                _ => rng.random_range(-3.0..side as f32 + 2.0),
            }
        };
        (core::array::from_fn(|_| draw(W)), core::array::from_fn(|_| draw(H)))
    }

    /// `remap` (the blocks) against [`remap_pixel`] (the one-pixel formula, which is the
    /// scalar loop this kernel replaced) for every pixel, and every prefix length around
    /// a block's end.
    fn agree<T: Sample + Debug, const C: usize>(
        data: &[T],
        mx: &[f32; N],
        my: &[f32; N],
        border: T,
        same: fn(T, T) -> bool,
    ) {
        let src = SourceImage::new(data, W, H, C).unwrap();
        let mut got = [border; N * 3];
        remap(&src, mx, my, border, &mut got[..N * C]).unwrap();
        for i in 0..N {
            let mut want = [border; C];
            remap_pixel::<T, C>(&src, mx[i], my[i], border, &mut want);
            for c in 0..C {
                let g = got[i * C + c];
                assert!(same(g, want[c]), "pixel {i} ({}, {}) channel {c}: {g:?} vs {:?}", mx[i], my[i], want[c]);
            }
        }
        for n in [0, 1, BLOCK - 1, BLOCK, BLOCK + 1, N - 1] {
            let mut part = [border; N * 3];
            remap(&src, &mx[..n], &my[..n], border, &mut part[..n * C]).unwrap();
            assert!(part[..n * C].iter().zip(&got).all(|(&a, &b)| same(a, b)), "prefix of {n}");
        }
    }

    #[test]
    fn blocks_give_the_one_pixel_formulas_numbers_for_every_type_and_position() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        let img8: [u8; W * H * 3] = core::array::from_fn(|_| rng.random());
        let img16: [u16; W * H * 3] = core::array::from_fn(|_| rng.random());
        let imgf: [f32; W * H * 3] = core::array::from_fn(|_| rng.random_range(-1e3..1e3));
        let exact = |a: f32, b: f32| a.to_bits() == b.to_bits();
        for _ in 0..40 {
            let (mx, my) = random_maps(&mut rng);
            agree::<u8, 1>(&img8[..W * H], &mx, &my, 7, |a, b| a == b);
            agree::<u8, 3>(&img8, &mx, &my, 7, |a, b| a == b);
            agree::<u16, 1>(&img16[..W * H], &mx, &my, 7, |a, b| a == b);
            agree::<u16, 3>(&img16, &mx, &my, 9, |a, b| a == b);
            agree::<f32, 1>(&imgf[..W * H], &mx, &my, -5.0, exact);
            agree::<f32, 3>(&imgf, &mx, &my, f32::NAN, exact);
        }
    }

    #[test]
    fn an_image_too_wide_for_the_vector_path_gets_the_same_numbers() {
        const WIDE: usize = MAX_VECTOR_SIDE_PX + 1;
        let img: [u8; WIDE * 2] = core::array::from_fn(|i| (i % 251) as u8);
        let src = SourceImage::new(&img, WIDE, 2, 1).unwrap();
        assert!(Geometry::of(&src).is_none());
        let mx = [0.5, 32766.25, 32767.5, 100.75, f32::NAN, -0.5];
        let my = [0.5, 0.0, 0.25, 0.75, 0.0, 1.0];
        let mut got = [0u8; 6];
        remap(&src, &mx, &my, 3, &mut got).unwrap();
        for i in 0..6 {
            let mut want = [0u8; 1];
            remap_pixel::<u8, 1>(&src, mx[i], my[i], 3, &mut want);
            assert_eq!(got[i], want[0], "{i}");
        }
        // (100.75, 0.75): 0.25 of row 0 and 0.75 of row 1 around columns 100, 101.
        let s = |x: usize, y: usize| f32::from(img[y * WIDE + x]);
        let top = s(100, 0) + 0.75 * (s(101, 0) - s(100, 0));
        let bottom = s(100, 1) + 0.75 * (s(101, 1) - s(100, 1));
        assert_eq!(got[3], (top + 0.75 * (bottom - top) + 0.5) as u8);
        assert_eq!(got[4], 3);
    }

    #[test]
    fn floor_is_the_floor_on_its_range() {
        for v in [0.0f32, 0.25, 0.5, 0.999_999_9, 1.0, 1.5, 2.5, 3.0, 1934.999, 32766.5, 4_194_303.0] {
            assert_eq!(floor(v), libm::floorf(v) as i32, "{v}");
        }
    }

    #[test]
    fn positions_give_fractions_offsets_and_edges() {
        let img = [0u8; 20 * 10];
        let src = SourceImage::new(&img, 20, 10, 1).unwrap();
        let g = Geometry::of(&src).unwrap();
        let mut p = Positions::new(g);
        let mx = [-0.25, 3.5, f32::NAN, 18.99, 2.0, 19.0];
        let my = [2.0, 1.0, 0.0, 3.0, 8.5, 1.0];
        assert_eq!(p.locate(&mx, &my), 6);
        let inside: [bool; 6] = core::array::from_fn(|i| g.inside(mx[i], my[i]));
        assert_eq!(inside, [false, true, false, true, true, false]);
        assert_eq!((p.off[0], p.off[2], p.off[5]), (0, 0, 0));
        assert_eq!((p.a[1], p.b[1], p.off[1]), (0.5, 0.0, 23));
        // x0 = 18 = w - 2 is the last inside column, y0 = 8 = h - 2 the last inside row;
        // x = 19 = w - 1 is not inside (its right taps are outside).
        assert_eq!(p.off[3], 78);
        assert!((p.a[3] - 0.99).abs() < 1e-5);
        assert_eq!((p.a[4], p.b[4], p.off[4]), (0.0, 0.5, 162));
        assert!(p.edges);
        assert_eq!(p.locate(&mx[1..2], &my[1..2]), 1);
        assert!(!p.edges);
        let wide = [0u8; 32768];
        assert!(Geometry::of(&SourceImage::new(&wide, 32768, 1, 1).unwrap()).is_none());
        assert!(Geometry::of(&SourceImage::new(&wide, 32767, 1, 1).unwrap()).is_some());
    }
}
