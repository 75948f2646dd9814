//! Step 2: the outer contours of the dark regions.
//!
//! The dark pixels are grouped into 8-connected regions (runs of dark pixels along the rows,
//! joined by union-find where runs of consecutive rows touch); the outer boundary of each
//! region large enough to be a marker is then traced by Moore-neighbour tracing from its
//! first pixel in raster order, clockwise in the image (u right, v down), stopping by Jacob's
//! criterion (back at the start, about to repeat the first step). A marker's black border is
//! one region whose outer boundary is the marker's outline, whatever its data cells.

use super::threshold::Mask;

/// A region's outer boundary: its boundary pixels in order (detection-level pixel
/// indices), and whether the region touches the image border (a marker cut by the frame).
pub(crate) struct Contour {
    pub points: Vec<[i32; 2]>,
    pub touches_border: bool,
}

/// A run of dark pixels `[x0, x1)` in row `y`.
#[derive(Clone, Copy)]
struct Run {
    y: usize,
    x0: usize,
    x1: usize,
}

/// Per-region statistics gathered over its runs.
#[derive(Clone, Copy)]
struct Region {
    first: usize,
    pixels: usize,
    bbox: [usize; 4],
}

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

fn runs(mask: &Mask) -> (Vec<Run>, Vec<usize>) {
    let mut runs = Vec::new();
    let mut row_start = Vec::with_capacity(mask.height + 1);
    for y in 0..mask.height {
        row_start.push(runs.len());
        let row = &mask.data[y * mask.width..(y + 1) * mask.width];
        let mut x = 0;
        while x < row.len() {
            if row[x] {
                let x0 = x;
                while x < row.len() && row[x] {
                    x += 1;
                }
                runs.push(Run { y, x0, x1: x });
            } else {
                x += 1;
            }
        }
    }
    row_start.push(runs.len());
    (runs, row_start)
}

/// The outer contours of the dark regions whose bounding box is at least `min_side` px
/// one way and half that the other (a marker seen obliquely), at most `max_side` px either
/// way, with at least `min_pixels` pixels.
pub(crate) fn outer_contours(mask: &Mask, min_side: usize, max_side: usize, min_pixels: usize) -> Vec<Contour> {
    let (runs, row_start) = runs(mask);
    let mut parent: Vec<usize> = (0..runs.len()).collect();
    for y in 1..mask.height {
        let (mut a, a_end) = (row_start[y - 1], row_start[y]);
        let (mut b, b_end) = (row_start[y], row_start[y + 1]);
        // 8-connected: [a.x0, a.x1) and [b.x0, b.x1) touch when a.x0 <= b.x1 and b.x0 <= a.x1.
        while a < a_end && b < b_end {
            let (ra, rb) = (runs[a], runs[b]);
            if ra.x0 <= rb.x1 && rb.x0 <= ra.x1 {
                let (pa, pb) = (find(&mut parent, a), find(&mut parent, b));
                if pa != pb {
                    parent[pa.max(pb)] = pa.min(pb);
                }
            }
            if ra.x1 < rb.x1 {
                a += 1;
            } else {
                b += 1;
            }
        }
    }
    let mut regions: Vec<Option<Region>> = vec![None; runs.len()];
    for (k, r) in runs.iter().enumerate() {
        let root = find(&mut parent, k);
        let g = regions[root].get_or_insert(Region { first: k, pixels: 0, bbox: [r.x0, r.y, r.x1 - 1, r.y] });
        g.pixels += r.x1 - r.x0;
        g.bbox = [g.bbox[0].min(r.x0), g.bbox[1].min(r.y), g.bbox[2].max(r.x1 - 1), g.bbox[3].max(r.y)];
    }
    regions
        .iter()
        .flatten()
        .filter(|g| {
            let (bw, bh) = (g.bbox[2] - g.bbox[0] + 1, g.bbox[3] - g.bbox[1] + 1);
            bw.min(bh) >= min_side / 2 && bw.max(bh) >= min_side && bw.max(bh) <= max_side && g.pixels >= min_pixels
        })
        .map(|g| {
            let start = runs[g.first];
            let [x0, y0, x1, y1] = g.bbox;
            let touches_border = x0 == 0 || y0 == 0 || x1 + 1 == mask.width || y1 + 1 == mask.height;
            let limit = 4 * (x1 - x0 + y1 - y0 + 2) + 8;
            Contour { points: trace(mask, [start.x0 as i32, start.y as i32], limit), touches_border }
        })
        .collect()
}

/// The eight neighbours, clockwise in the image (v down) from east.
const DIRS: [[i32; 2]; 8] = [[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1]];

/// Moore-neighbour tracing of the outer boundary from `start`, the region's first pixel in
/// raster order (so its west neighbour is background). At most `limit` points.
fn trace(mask: &Mask, start: [i32; 2], limit: usize) -> Vec<[i32; 2]> {
    let dark = |p: [i32; 2]| mask.dark(p[0] as isize, p[1] as isize);
    let mut out = vec![start];
    // `back`: direction from the current pixel to the background pixel the search starts
    // after (west, for the first pixel).
    let (mut p, mut back) = (start, 4usize);
    let mut first_step: Option<usize> = None;
    while out.len() < limit {
        let mut next = None;
        for k in 1..=8 {
            let d = (back + k) % 8;
            let q = [p[0] + DIRS[d][0], p[1] + DIRS[d][1]];
            if dark(q) {
                next = Some((d, q));
                break;
            }
        }
        let Some((d, q)) = next else {
            break; // an isolated pixel
        };
        if p == start {
            match first_step {
                None => first_step = Some(d),
                Some(f) if f == d => break,
                Some(_) => {}
            }
        }
        // The background pixel scanned just before q, seen from q: the previous direction
        // from p, (d + 7) % 8, is p + DIRS[d - 1]; from q it is DIRS[d - 1] - DIRS[d].
        let prev = DIRS[(d + 7) % 8];
        let rel = [p[0] + prev[0] - q[0], p[1] + prev[1] - q[1]];
        back = DIRS.iter().position(|&v| v == rel).unwrap_or((d + 4) % 8);
        if q != start {
            out.push(q);
        }
        p = q;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask_of(rows: &[&str]) -> Mask {
        let width = rows[0].len();
        let data = rows.iter().flat_map(|r| r.bytes().map(|b| b == b'#')).collect();
        Mask { width, height: rows.len(), data }
    }

    /// A ring with a hole and a separate blob: the ring's outer boundary is traced once,
    /// clockwise, without the hole; the blob too small is dropped.
    #[test]
    fn outer_boundary_of_a_ring_clockwise() {
        let m = mask_of(&[
            "..........", //
            ".#####....", //
            ".#...#..#.", //
            ".#...#....", //
            ".#####....", //
            "..........", //
        ]);
        let c = outer_contours(&m, 3, 100, 4);
        assert_eq!(c.len(), 1);
        let p = &c[0].points;
        assert_eq!(p.len(), 14, "{p:?}");
        assert_eq!(p[0], [1, 1]);
        assert_eq!(p[1], [2, 1], "clockwise in the image: east first along the top");
        assert!(!c[0].touches_border);
        // Every boundary pixel once.
        assert_eq!(distinct(p), p.len());
    }

    fn distinct(p: &[[i32; 2]]) -> usize {
        let mut sorted = p.to_vec();
        sorted.sort();
        sorted.dedup();
        sorted.len()
    }

    /// Regions touching by a corner only are one (8-connectivity); a region on the image
    /// border is flagged.
    #[test]
    fn diagonal_contact_joins_and_border_is_flagged() {
        let m = mask_of(&[
            "###...", //
            "###...", //
            "###...", //
            "...###", //
            "...###", //
            "...###", //
        ]);
        let c = outer_contours(&m, 3, 100, 4);
        assert_eq!(c.len(), 1);
        assert!(c[0].touches_border);
        // The two contact pixels are passed twice (out along one square, back along the other).
        let p = &c[0].points;
        assert_eq!(p.len(), 18, "{p:?}");
        assert_eq!(distinct(p), 16);
    }
}
