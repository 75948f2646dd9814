//! Which 64 x 64 blocks are CPBD edge blocks (SPEC.md A.2 "edge-block threshold" and
//! A.5, compute.py L197-200): blocks with more than 0.2 % of their pixels on
//! `skimage.feature.canny`'s edges, whose last step is the hysteresis (SPEC.md A.3.1):
//! the 8-connected groups of [`WEAK`] and [`STRONG`] pixels that contain a strong one.
//!
//! Only the count per block matters, which allows two shortcuts that leave it unchanged:
//! a block with enough strong pixels is an edge block whatever the hysteresis does
//! (strong pixels are always edges), so [`decide`] computes the classes a few rows at a
//! time and stops as soon as it has them, which on a textured or noisy image is after
//! the first rows; and a block with too few strong and weak pixels together is not one.
//! Only the blocks in between need the hysteresis, which [`Classes::edges_in_block`]
//! runs over their groups alone, computing the classes of further 64 x 64 tiles of the
//! image (including its unused right and bottom remainder) only when a group reaches
//! into them.

use std::ops::Range;

use super::canny::{classify, Bleed, Scratch, NONE, STRONG, WEAK};

/// Side of a block and of a tile of the class cache, px.
pub const TILE: usize = 64;

/// Rows of a block classified before each check of the strong count: small first, so
/// that a busy block stops early, then larger, so that a quiet one costs few repeated
/// halos.
const ROW_STEPS: [Range<usize>; 5] = [0..1, 1..4, 4..12, 12..32, 32..TILE];

/// The edge-block test of one block after [`decide`].
pub enum Decision {
    /// At least the minimum number of strong pixels.
    Edge,
    /// Fewer strong and weak pixels together than the minimum; the block's classes.
    NotEdge(Vec<u8>),
    /// Depends on the hysteresis; the block's classes.
    Undecided(Vec<u8>),
}

/// The rows and columns of tile (`ti`, `tj`) of a `w x h` image.
fn tile_span(ti: usize, tj: usize, w: usize, h: usize) -> (Range<usize>, Range<usize>) {
    (ti * TILE..((ti + 1) * TILE).min(h), tj * TILE..((tj + 1) * TILE).min(w))
}

/// The edge-block test of block (`bi`, `bj`) of a `w x h` image: an edge block has at
/// least `min_edges` Canny edge pixels. `classes` is working memory. Preconditions as
/// [`classify`].
#[allow(clippy::too_many_arguments)]
pub fn decide(
    image: &[u8],
    w: usize,
    h: usize,
    bleed: &Bleed,
    (bi, bj): (usize, usize),
    min_edges: usize,
    scratch: &mut Scratch,
    classes: &mut Vec<u8>,
) -> Decision {
    let (rows, cols) = tile_span(bi, bj, w, h);
    classes.clear();
    classes.resize(TILE * TILE, NONE);
    let (mut strong, mut weak) = (0, 0);
    for step in ROW_STEPS {
        let r = rows.start + step.start..(rows.start + step.end).min(rows.end);
        let (s, k) = classify(image, w, h, bleed, r, cols.clone(), &mut classes[step.start * TILE..], TILE, scratch);
        strong += s;
        weak += k;
        if strong >= min_edges {
            return Decision::Edge;
        }
    }
    if strong + weak < min_edges {
        Decision::NotEdge(classes.clone())
    } else {
        Decision::Undecided(classes.clone())
    }
}

/// Pixel classes of the whole image, tile by tile, computed when first needed.
pub struct Classes<'a> {
    image: &'a [u8],
    w: usize,
    h: usize,
    bleed: &'a Bleed,
    tiles_w: usize,
    tiles: Vec<Option<Vec<u8>>>,
    scratch: Scratch,
    /// Per pixel: 0 not visited, else `LINKED` or `UNLINKED` (of its group).
    visit: Vec<u8>,
}

const LINKED: u8 = 1;
const UNLINKED: u8 = 2;
const QUEUED: u8 = 3;

impl<'a> Classes<'a> {
    /// No tile computed yet. Preconditions as [`classify`].
    pub fn new(image: &'a [u8], w: usize, h: usize, bleed: &'a Bleed) -> Self {
        let tiles_w = w.div_ceil(TILE);
        let tiles = (0..tiles_w * h.div_ceil(TILE)).map(|_| None).collect();
        Classes { image, w, h, bleed, tiles_w, tiles, scratch: Scratch::default(), visit: Vec::new() }
    }

    /// Records the classes of tile (`ti`, `tj`) computed elsewhere (row stride [`TILE`]).
    pub fn insert(&mut self, (ti, tj): (usize, usize), classes: Vec<u8>) {
        if let Some(t) = self.tiles.get_mut(ti * self.tiles_w + tj) {
            *t = Some(classes);
        }
    }

    fn class(&mut self, r: usize, c: usize) -> u8 {
        let (ti, tj) = (r / TILE, c / TILE);
        let k = ti * self.tiles_w + tj;
        if self.tiles[k].is_none() {
            let (rows, cols) = tile_span(ti, tj, self.w, self.h);
            let mut t = vec![NONE; TILE * TILE];
            classify(self.image, self.w, self.h, self.bleed, rows, cols, &mut t, TILE, &mut self.scratch);
            self.tiles[k] = Some(t);
        }
        self.tiles[k].as_ref().map_or(NONE, |t| t[(r % TILE) * TILE + c % TILE])
    }

    /// The number of Canny edge pixels (strong, or weak and linked to a strong one through
    /// weak and strong 8-neighbours) in block (`bi`, `bj`).
    pub fn edges_in_block(&mut self, (bi, bj): (usize, usize)) -> usize {
        let (w, h) = (self.w, self.h);
        if self.visit.is_empty() {
            self.visit = vec![0u8; w * h];
        }
        let (rows, cols) = tile_span(bi, bj, w, h);
        let mut group: Vec<usize> = Vec::new();
        let mut stack: Vec<usize> = Vec::new();
        let mut edges = 0;
        for r in rows {
            for c in cols.clone() {
                match self.class(r, c) {
                    STRONG => edges += 1,
                    WEAK => {
                        let k0 = r * w + c;
                        if self.visit[k0] == 0 {
                            // Flood the group, then label it as a whole.
                            let mut linked = false;
                            group.clear();
                            self.visit[k0] = QUEUED;
                            stack.push(k0);
                            while let Some(k) = stack.pop() {
                                group.push(k);
                                let (r1, c1) = (k / w, k % w);
                                for r2 in r1.saturating_sub(1)..(r1 + 2).min(h) {
                                    for c2 in c1.saturating_sub(1)..(c1 + 2).min(w) {
                                        let k2 = r2 * w + c2;
                                        if self.visit[k2] != 0 {
                                            continue;
                                        }
                                        match self.class(r2, c2) {
                                            STRONG => linked = true,
                                            WEAK => {
                                                self.visit[k2] = QUEUED;
                                                stack.push(k2);
                                            }
                                            _ => {}
                                        }
                                    }
                                }
                            }
                            let label = if linked { LINKED } else { UNLINKED };
                            for &k in &group {
                                self.visit[k] = label;
                            }
                        }
                        if self.visit[k0] == LINKED {
                            edges += 1;
                        }
                    }
                    _ => {}
                }
            }
        }
        edges
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sharpness::canny::tests::fixture;

    /// A gentle ramp (1 grey level per 20 px across, per 33 down) with a sparse sprinkle
    /// of single-pixel bumps: the Gaussian tails around them give weak Canny pixels,
    /// which 8-bit images rarely have otherwise.
    fn ramp_image(w: usize, h: usize, seed: u64) -> Vec<u8> {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f64, (k / w) as f64);
                let bump = if next() % 50 == 0 { (next() % 7) as f64 - 3.0 } else { 0.0 };
                (100.0 + 0.05 * x + 0.03 * y + bump).round() as u8
            })
            .collect()
    }

    /// The edge map by a whole-image flood from every strong pixel.
    fn edges_by_flood(image: &[u8], w: usize, h: usize) -> (Vec<bool>, usize) {
        let bleed = Bleed::new(w, h);
        let mut class = vec![NONE; w * h];
        classify(image, w, h, &bleed, 0..h, 0..w, &mut class, w, &mut Scratch::default());
        let weak = class.iter().filter(|&&c| c == WEAK).count();
        let mut edge: Vec<bool> = class.iter().map(|&c| c == STRONG).collect();
        let mut stack: Vec<usize> = (0..w * h).filter(|&k| edge[k]).collect();
        while let Some(k) = stack.pop() {
            let (r, c) = (k / w, k % w);
            for r2 in r.saturating_sub(1)..(r + 2).min(h) {
                for c2 in c.saturating_sub(1)..(c + 2).min(w) {
                    let k2 = r2 * w + c2;
                    if class[k2] == WEAK && !edge[k2] {
                        edge[k2] = true;
                        stack.push(k2);
                    }
                }
            }
        }
        (edge, weak)
    }

    #[test]
    fn block_edge_counts_equal_a_whole_image_hysteresis() {
        let (w, h) = (256, 192);
        let ramp = ramp_image(w, h, 22);
        let (brick, bw, bh) = fixture("brick.png");
        for (img, w, h) in [(ramp, w, h), (brick, bw, bh)] {
            let (edges, weak) = edges_by_flood(&img, w, h);
            let bleed = Bleed::new(w, h);
            let mut classes = Classes::new(&img, w, h, &bleed);
            let mut weak_linked = 0;
            for bi in 0..h / TILE {
                for bj in 0..w / TILE {
                    let want = (bi * TILE..(bi + 1) * TILE)
                        .flat_map(|r| (bj * TILE..(bj + 1) * TILE).map(move |c| r * w + c))
                        .filter(|&k| edges[k])
                        .count();
                    assert_eq!(classes.edges_in_block((bi, bj)), want, "block {bi}, {bj}");
                    let decision = decide(&img, w, h, &bleed, (bi, bj), 9, &mut Scratch::default(), &mut Vec::new());
                    match decision {
                        Decision::Edge => assert!(want >= 9),
                        Decision::NotEdge(_) => assert!(want < 9),
                        Decision::Undecided(_) => {}
                    }
                }
            }
            for (k, &edge) in edges.iter().enumerate() {
                weak_linked += (edge && classes.visit.get(k) == Some(&LINKED)) as usize;
            }
            // The ramp has weak pixels linked and not linked to strong ones.
            if w == 256 {
                assert!(weak >= 20 && weak_linked >= 10 && weak_linked < weak, "{weak} weak, {weak_linked} linked");
            }
        }
    }
}
