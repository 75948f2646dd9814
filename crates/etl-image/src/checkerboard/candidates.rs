//! Which saddles are checkerboard corners: the ring test, and the directions of the two
//! edges crossing there.
//!
//! On a circle around an X-junction the intensity is light, dark, light, dark: exactly four
//! crossings of its mean, in two nearly opposite pairs (each pair is one straight edge
//! through the corner). Points on an edge (two crossings), L-corners of a single square
//! (two), T-junctions and texture (crossings not in opposite pairs) are rejected here.

use std::f32::consts::PI;

use super::response::Saddle;
use crate::grey::Plane;

/// A corner candidate at the detection level.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Corner {
    pub p: [f32; 2],
    /// Directions (radians, modulo pi) of the two edges through the corner.
    pub line: [f32; 2],
}

const RING_SAMPLES: usize = 32;
/// Minimum light-to-dark range on the ring, grey levels.
const MIN_RING_CONTRAST: f32 = 4.0;
/// How far from opposite the two crossings of one edge may be (perspective, noise), rad.
const OPPOSITE_TOL: f32 = 0.6;
/// Smallest angle between the two edges, rad (a board seen at up to ~75 degrees).
const MIN_EDGE_ANGLE: f32 = 0.35;

/// The difference of two directions modulo pi, in [0, pi/2].
pub(crate) fn line_diff(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(PI);
    d.min(PI - d)
}

/// Keeps the saddles that pass the ring test at one of `radii` (detection-level px; several
/// because printed squares often do not quite touch at their corners, and a small ring then
/// misses one of the dark squares, while a large ring reaches past small squares).
///
/// Only the `max_saddles` strongest saddles are tested (the sharp staircase of edges seen at
/// the detection level gives many weak ones, all rejected by the ring test).
pub(crate) fn corners(s: &Plane, saddles: &[Saddle], radii: &[f32], max_saddles: usize) -> Vec<Corner> {
    let rings: Vec<(f32, Vec<[f32; 2]>)> = radii
        .iter()
        .map(|&radius| {
            let ring = (0..RING_SAMPLES)
                .map(|k| {
                    let a = 2.0 * PI * k as f32 / RING_SAMPLES as f32;
                    [radius * a.cos(), radius * a.sin()]
                })
                .collect();
            (radius, ring)
        })
        .collect();
    let mut out = Vec::new();
    let mut v = [0.0f32; RING_SAMPLES];
    for sd in saddles.iter().take(max_saddles) {
        for (radius, ring) in &rings {
            if !s.contains(sd.p, radius + 1.0) {
                continue;
            }
            for (val, o) in v.iter_mut().zip(ring) {
                // Inside: `contains` above keeps radius + 1 px from every border.
                *val = s.bilinear_inside(sd.p[0] + o[0], sd.p[1] + o[1]);
            }
            if let Some(line) = ring_lines(&v) {
                out.push(Corner { p: sd.p, line });
                break;
            }
        }
    }
    out
}

fn ring_lines(v: &[f32; RING_SAMPLES]) -> Option<[f32; 2]> {
    let (mut lo, mut hi, mut sum) = (f32::MAX, f32::MIN, 0.0);
    for &x in v {
        lo = lo.min(x);
        hi = hi.max(x);
        sum += x;
    }
    if hi - lo < MIN_RING_CONTRAST {
        return None;
    }
    let mean = sum / RING_SAMPLES as f32;
    let mut cross = [0.0f32; 4];
    let mut n = 0;
    let mut last = 0usize;
    let mut first = usize::MAX;
    for k in 0..RING_SAMPLES {
        let a = v[k] - mean;
        let b = v[(k + 1) % RING_SAMPLES] - mean;
        if (a > 0.0) != (b > 0.0) {
            if n == 4 {
                return None;
            }
            cross[n] = 2.0 * PI * (k as f32 + a / (a - b)) / RING_SAMPLES as f32;
            if first == usize::MAX {
                first = k;
            } else if k - last < 3 {
                // A sector narrower than ~30 degrees: noise or texture, not a square.
                return None;
            }
            last = k;
            n += 1;
        }
    }
    if n != 4 || first + RING_SAMPLES - last < 3 {
        return None;
    }
    let mut line = [0.0f32; 2];
    for e in 0..2 {
        let d = cross[e + 2] - cross[e];
        if (d - PI).abs() > OPPOSITE_TOL {
            return None;
        }
        // Mean direction of the two half-edges, modulo pi.
        let a = cross[e];
        let b = cross[e + 2] - PI;
        line[e] = (0.5 * (a + b)).rem_euclid(PI);
    }
    (line_diff(line[0], line[1]) >= MIN_EDGE_ANGLE).then_some(line)
}
