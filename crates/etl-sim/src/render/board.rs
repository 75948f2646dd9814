//! The printed board and its exact area coverage over a pixel's footprint.
//!
//! Board frames (formats::board): a checkerboard's inner corner (i, j) at (i s, j s), its
//! pattern covering [-s, cols s] x [-s, rows s], i.e. (cols + 1) x (rows + 1) squares; a
//! ChArUco board's pattern covering [0, cols s] x [0, rows s] (OpenCV's frame, origin at
//! the top-left outer corner). Either way the pattern's first square is black and the
//! colours alternate; a ChArUco board's white squares hold its markers, centred,
//! `marker_mm` wide: (n + 2) x (n + 2) cells, a black border one cell wide around the
//! n x n data cells of the dictionary's code (white for a 1 bit). Around the pattern lies
//! a white margin `margin_mm` wide, and beyond it the background, a flat surface in the
//! board's plane.
//!
//! Along each axis the board frame splits into slabs: background (below), margin, the
//! pattern's squares, margin, background (above); on a ChArUco board each square splits
//! further at the markers' cell boundaries (the white gap, the n + 2 cells, the white gap),
//! the same in every square. The reflectance is constant on every product of an X slab and
//! a Y slab, so the exact mean over a pixel's footprint (a quadrilateral on the board) is
//! the sum over the slab rectangles it touches of the area clipped by that rectangle times
//! its grey level, over the footprint's area.

use etl_core::board::CharucoBoard;
use etl_formats::board::Board;

/// Grey level of a region, before shading and noise (8-bit scale).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Levels {
    pub dark: f64,
    pub light: f64,
    pub background: f64,
}

/// Most slabs a square splits into: a marker of 7 x 7 data bits has 9 cells, plus the white
/// gap on either side.
const MAX_CUTS: usize = 11;

/// One axis of the board's slab grid.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Axis {
    /// Start of the pattern, mm (-square for a checkerboard, 0 for a ChArUco board).
    lo_mm: f64,
    square_mm: f64,
    /// Squares of the pattern along this axis.
    squares: i32,
    margin_mm: f64,
    /// Where each slab of a square starts, mm from the square's start: `cuts[0] = 0`,
    /// increasing, below `square_mm`.
    cuts: [f64; MAX_CUTS],
    /// Slabs per square (1 for a checkerboard).
    per_square: i32,
}

impl Axis {
    fn hi_mm(&self) -> f64 {
        self.lo_mm + self.squares as f64 * self.square_mm
    }

    /// Slabs of the pattern.
    fn slabs(&self) -> i32 {
        self.squares * self.per_square
    }

    /// Slab index of coordinate `x`: -2 background, -1 margin, 0..slabs() the pattern's
    /// slabs (square `s / per_square`, its slab `s % per_square`), `slabs()` margin,
    /// `slabs() + 1` background.
    #[inline]
    fn slab(&self, x: f64) -> i32 {
        let hi = self.hi_mm();
        if x < self.lo_mm {
            if x < self.lo_mm - self.margin_mm {
                -2
            } else {
                -1
            }
        } else if x < hi {
            let k = (((x - self.lo_mm) / self.square_mm) as i32).min(self.squares - 1);
            let off = x - (self.lo_mm + k as f64 * self.square_mm);
            let j = self.cuts[1..self.per_square as usize].iter().take_while(|&&c| c <= off).count() as i32;
            k * self.per_square + j
        } else if x < hi + self.margin_mm {
            self.slabs()
        } else {
            self.slabs() + 1
        }
    }

    /// The interval of slab `s`.
    fn bounds(&self, s: i32) -> (f64, f64) {
        let hi = self.hi_mm();
        let n = self.slabs();
        match s {
            i32::MIN..=-2 => (f64::NEG_INFINITY, self.lo_mm - self.margin_mm),
            -1 => (self.lo_mm - self.margin_mm, self.lo_mm),
            s if s < n => {
                // Consistent with `slab` at the boundaries: square k is [lo + k s, lo + (k+1) s),
                // its slab j [start + cuts[j], start + cuts[j + 1]).
                let (k, j) = (s / self.per_square, (s % self.per_square) as usize);
                let start = self.lo_mm + k as f64 * self.square_mm;
                let a = start + self.cuts[j];
                let b = if j + 1 < self.per_square as usize {
                    start + self.cuts[j + 1]
                } else if k + 1 == self.squares {
                    hi
                } else {
                    self.lo_mm + (k + 1) as f64 * self.square_mm
                };
                (a, b)
            }
            s if s == n => (hi, hi + self.margin_mm),
            _ => (hi + self.margin_mm, f64::INFINITY),
        }
    }
}

/// The board's layout in its own frame and the grey level of each region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BoardLayout {
    x: Axis,
    y: Axis,
    levels: Levels,
    /// The ChArUco board whose markers fill the white squares; `None` for a checkerboard.
    markers: Option<CharucoBoard>,
}

/// A polygon of at most `N` vertices on the stack (clipping a quadrilateral by a rectangle
/// gives at most 8).
const N: usize = 12;

#[derive(Clone, Copy)]
struct Poly {
    p: [[f64; 2]; N],
    n: usize,
}

impl Poly {
    fn signed_area(&self) -> f64 {
        let mut a = 0.0;
        for k in 0..self.n {
            let (p, q) = (self.p[k], self.p[(k + 1) % self.n]);
            a += p[0] * q[1] - p[1] * q[0];
        }
        0.5 * a
    }

    /// Keeps the part where `sign * (coord[axis] - bound) <= 0` (Sutherland-Hodgman).
    fn clip(&self, axis: usize, bound: f64, keep_below: bool) -> Poly {
        let mut out = Poly { p: [[0.0; 2]; N], n: 0 };
        if !bound.is_finite() {
            return *self;
        }
        let inside = |p: [f64; 2]| if keep_below { p[axis] <= bound } else { p[axis] >= bound };
        for k in 0..self.n {
            let (a, b) = (self.p[k], self.p[(k + 1) % self.n]);
            let (ia, ib) = (inside(a), inside(b));
            if ia && out.n < N {
                out.p[out.n] = a;
                out.n += 1;
            }
            if ia != ib && out.n < N {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                let mut q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                q[axis] = bound;
                out.p[out.n] = q;
                out.n += 1;
            }
        }
        out
    }
}

impl BoardLayout {
    /// The layout of a checkerboard with `inner_corners` [cols, rows] and `square_mm`
    /// squares, with a white margin of `margin_mm`.
    pub fn new(inner_corners: [usize; 2], square_mm: f64, margin_mm: f64, levels: Levels) -> Self {
        let axis = |n: usize| Axis {
            lo_mm: -square_mm,
            square_mm,
            squares: i32::try_from(n + 1).unwrap_or(i32::MAX / 4),
            margin_mm,
            cuts: [0.0; MAX_CUTS],
            per_square: 1,
        };
        BoardLayout { x: axis(inner_corners[0]), y: axis(inner_corners[1]), levels, markers: None }
    }

    /// The layout of `board` with a white margin of `margin_mm`.
    pub fn of(board: &Board, margin_mm: f64, levels: Levels) -> Self {
        let b = match board {
            Board::Checkerboard(c) => return BoardLayout::new(c.inner_corners, c.square_mm, margin_mm, levels),
            Board::Charuco(b) => *b,
        };
        let (s, m) = (b.square_mm(), b.marker_mm());
        let cells = b.dictionary().marker_bits() + 2;
        let (inset, cell) = (0.5 * (s - m), m / cells as f64);
        // The white gap, the marker's cells, the white gap: cells + 2 slabs per square.
        let mut cuts = [0.0; MAX_CUTS];
        for (k, c) in cuts.iter_mut().enumerate().take(cells + 2).skip(1) {
            *c = inset + (k - 1) as f64 * cell;
        }
        let axis = |n: u32| Axis {
            lo_mm: 0.0,
            square_mm: s,
            squares: n as i32,
            margin_mm,
            cuts,
            per_square: cells as i32 + 2,
        };
        BoardLayout { x: axis(b.squares()[0]), y: axis(b.squares()[1]), levels, markers: Some(b) }
    }

    /// The region (X slab, Y slab) of a board point.
    #[inline]
    pub fn region(&self, x_mm: f64, y_mm: f64) -> (i32, i32) {
        (self.x.slab(x_mm), self.y.slab(y_mm))
    }

    /// Grey level of region (sx, sy).
    #[inline]
    pub fn level(&self, (sx, sy): (i32, i32)) -> f64 {
        let bg = |s: i32, a: &Axis| s <= -2 || s > a.slabs();
        let margin = |s: i32, a: &Axis| s == -1 || s == a.slabs();
        if bg(sx, &self.x) || bg(sy, &self.y) {
            return self.levels.background;
        }
        if margin(sx, &self.x) || margin(sy, &self.y) {
            return self.levels.light;
        }
        let (kx, jx) = (sx / self.x.per_square, sx % self.x.per_square);
        let (ky, jy) = (sy / self.y.per_square, sy % self.y.per_square);
        if (kx + ky) % 2 == 0 {
            return self.levels.dark;
        }
        match &self.markers {
            Some(b) if self.marker_is_dark(b, [kx, ky], [jx, jy]) => self.levels.dark,
            _ => self.levels.light,
        }
    }

    /// Whether slab [jx, jy] of the white square [kx, ky] of `b` is a dark cell of its
    /// marker: the border ring of cells, or a 0 bit of the code.
    fn marker_is_dark(&self, b: &CharucoBoard, [kx, ky]: [i32; 2], [jx, jy]: [i32; 2]) -> bool {
        let cells = self.x.per_square - 2;
        // Slab 0 and slab cells + 1 are the white gaps; slabs 1..=cells the marker's cells.
        let (cx, cy) = (jx - 1, jy - 1);
        if !(0..cells).contains(&cx) || !(0..cells).contains(&cy) {
            return false;
        }
        if cx == 0 || cy == 0 || cx == cells - 1 || cy == cells - 1 {
            return true;
        }
        let Some(id) = b.marker_at(kx as u32, ky as u32) else { return false };
        let (row, col) = ((cy - 1) as usize, (cx - 1) as usize);
        b.dictionary().is_white(id, row, col) == Some(false)
    }

    /// Grey level of a board point.
    #[inline]
    pub fn level_at(&self, x_mm: f64, y_mm: f64) -> f64 {
        self.level(self.region(x_mm, y_mm))
    }

    /// The grey level over the rectangle [lo[0], hi[0]] x [lo[1], hi[1]] (mm) when it is
    /// the same all over it: the rectangle lies in one slab rectangle (a checkerboard's
    /// square, a marker's cell), or in the background, or in the white margin's frame, or
    /// across at most 16 slab rectangles of one grey level; `None` otherwise (it may still
    /// be uniform, e.g. when the background is as light as the margin over many slabs).
    pub fn level_over(&self, lo: [f64; 2], hi: [f64; 2]) -> Option<f64> {
        let (sx0, sy0) = self.region(lo[0], lo[1]);
        let (sx1, sy1) = self.region(hi[0], hi[1]);
        if sx0 == sx1 && sy0 == sy1 {
            return Some(self.level((sx0, sy0)));
        }
        // Slabs are monotone in the coordinate: [s0, s1] are all the slabs met.
        let beyond = |a: &Axis, s0: i32, s1: i32| s1 <= -2 || s0 > a.slabs();
        if beyond(&self.x, sx0, sx1) || beyond(&self.y, sy0, sy1) {
            return Some(self.levels.background);
        }
        let margin_strip = |a: &Axis, s0: i32, s1: i32| s0 == s1 && (s0 == -1 || s0 == a.slabs());
        let inside = |a: &Axis, s0: i32, s1: i32| s0 >= -1 && s1 <= a.slabs();
        if (margin_strip(&self.x, sx0, sx1) && inside(&self.y, sy0, sy1))
            || (margin_strip(&self.y, sy0, sy1) && inside(&self.x, sx0, sx1))
        {
            return Some(self.levels.light);
        }
        // A few slab rectangles of one colour (a tile across a marker's border cells, or
        // across equal cells and the white gap): uniform too. Every slab rectangle the
        // rectangle meets lies in the ranges, so this is exact.
        let (nx, ny) = (i64::from(sx1) - i64::from(sx0) + 1, i64::from(sy1) - i64::from(sy0) + 1);
        if nx * ny <= 16 {
            let first = self.level((sx0, sy0));
            let same = (sx0..=sx1).all(|sx| (sy0..=sy1).all(|sy| self.level((sx, sy)) == first));
            return same.then_some(first);
        }
        None
    }

    /// Exact mean grey level over the quadrilateral `quad` (board frame, mm; vertices in
    /// order around it).
    pub fn mean_over(&self, quad: &[[f64; 2]; 4]) -> f64 {
        let mut poly = Poly { p: [[0.0; 2]; N], n: 4 };
        poly.p[..4].copy_from_slice(quad);
        let total = poly.signed_area();
        if !(total.abs() > 0.0) || !total.is_finite() {
            return self.level_at(quad[0][0], quad[0][1]);
        }
        let (mut sx0, mut sx1, mut sy0, mut sy1) = (i32::MAX, i32::MIN, i32::MAX, i32::MIN);
        for q in quad {
            let (sx, sy) = self.region(q[0], q[1]);
            sx0 = sx0.min(sx);
            sx1 = sx1.max(sx);
            sy0 = sy0.min(sy);
            sy1 = sy1.max(sy);
        }
        let mut sum = 0.0;
        for sx in sx0..=sx1 {
            let (xa, xb) = self.x.bounds(sx);
            let px = poly.clip(0, xa, false).clip(0, xb, true);
            if px.n < 3 {
                continue;
            }
            for sy in sy0..=sy1 {
                let (ya, yb) = self.y.bounds(sy);
                let c = px.clip(1, ya, false).clip(1, yb, true);
                if c.n >= 3 {
                    sum += c.signed_area() * self.level((sx, sy));
                }
            }
        }
        sum / total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const L: Levels = Levels { dark: 40.0, light: 210.0, background: 100.0 };

    #[test]
    fn colours_of_the_pattern_margin_and_background() {
        let b = BoardLayout::new([14, 12], 1.5, 1.0, L);
        assert_eq!(b.level_at(-0.75, -0.75), 40.0); // square (-1, -1): black
        assert_eq!(b.level_at(0.75, -0.75), 210.0);
        assert_eq!(b.level_at(0.75, 0.75), 40.0);
        assert_eq!(b.level_at(20.0, 17.0), 40.0); // square (13, 11): 24 even
        assert_eq!(b.level_at(-1.6, 3.0), 210.0); // margin
        assert_eq!(b.level_at(21.5, 3.0), 210.0);
        assert_eq!(b.level_at(-2.6, 3.0), 100.0); // background
        assert_eq!(b.level_at(3.0, 19.6), 100.0);
    }

    #[test]
    fn uniform_rectangles() {
        // Pattern [-1.5, 7.5] x [-1.5, 6], margin 0.5 wide.
        let b = BoardLayout::new([5, 4], 1.5, 0.5, L);
        assert_eq!(b.level_over([1.6, 0.1], [2.9, 1.4]), Some(210.0)); // square (1, 0)
        assert_eq!(b.level_over([-1.4, -1.4], [-0.1, -0.1]), Some(40.0)); // square (-1, -1)
        assert_eq!(b.level_over([0.1, 0.1], [1.6, 1.4]), None); // two squares
        assert_eq!(b.level_over([-9.0, -9.0], [-2.1, 20.0]), Some(100.0)); // left of the board
        assert_eq!(b.level_over([-9.0, 6.6], [20.0, 9.0]), Some(100.0)); // above it
        assert_eq!(b.level_over([-9.0, -9.0], [-1.9, 20.0]), None); // reaches the margin
        assert_eq!(b.level_over([-1.9, -1.9], [-1.6, 6.4]), Some(210.0)); // left margin strip
        assert_eq!(b.level_over([-1.9, 6.1], [7.9, 6.4]), Some(210.0)); // top margin strip
        assert_eq!(b.level_over([-1.9, 6.1], [7.9, 6.6]), None); // into the background
        assert_eq!(b.level_over([-1.9, 5.9], [-1.6, 6.4]), Some(210.0)); // a margin corner
                                                                         // The margin and the white square (-1, 0): light; with the black (-1, -1): mixed.
        assert_eq!(b.level_over([-1.9, 0.0], [-1.4, 0.2]), Some(210.0));
        assert_eq!(b.level_over([-1.9, -0.2], [-1.4, 0.2]), None);
    }

    #[test]
    fn coverage_of_squares_is_exact() {
        let b = BoardLayout::new([5, 4], 1.0, 0.5, L);
        // A unit square centred on inner corner (1, 1): half black, half white.
        let q = [[0.5, 0.5], [1.5, 0.5], [1.5, 1.5], [0.5, 1.5]];
        assert!((b.mean_over(&q) - 125.0).abs() < 1e-12);
        // Reverse orientation gives the same mean.
        let r = [q[3], q[2], q[1], q[0]];
        assert!((b.mean_over(&r) - 125.0).abs() < 1e-12);
        // A diamond inside square (0, 0) (black) touching its edges.
        let d = [[0.5, 0.0], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5]];
        assert!((b.mean_over(&d) - 40.0).abs() < 1e-12);
        // A strip 0.25 into the black square (0, 0) and 0.75 into white (1, 0).
        let s = [[0.75, 0.2], [1.75, 0.2], [1.75, 0.4], [0.75, 0.4]];
        assert!((b.mean_over(&s) - (0.25 * 40.0 + 0.75 * 210.0)).abs() < 1e-12);
        // Straddling the margin and background: the margin is [-1.5, -1), background below.
        let m = [[-1.75, 0.2], [-1.25, 0.2], [-1.25, 0.3], [-1.75, 0.3]];
        assert!((b.mean_over(&m) - 155.0).abs() < 1e-12);
    }

    /// A ChArUco board of 5 x 4 squares of 10 mm, markers 7 mm of DICT_4X4_50 (cells of
    /// 7/6 mm, inset 1.5 mm): squares, gaps, marker borders and data cells as etl-core's
    /// codes say, the margin and background around.
    #[test]
    fn charuco_cells_are_the_codes() {
        let board = Board::charuco([5, 4], 10.0, 7.0, "DICT_4X4_50").unwrap();
        let b = *board.as_charuco().unwrap();
        let layout = BoardLayout::of(&board, 2.0, L);
        let cell = 7.0 / 6.0;
        for id in 0..b.markers() as u32 {
            let [tl, ..] = b.marker_corners_mm(id).unwrap();
            for row in 0..6 {
                for col in 0..6 {
                    let (x, y) = (tl[0] + (col as f64 + 0.5) * cell, tl[1] + (row as f64 + 0.5) * cell);
                    let border = row == 0 || col == 0 || row == 5 || col == 5;
                    let white = !border && b.dictionary().is_white(id, row - 1, col - 1).unwrap();
                    assert_eq!(layout.level_at(x, y), if white { 210.0 } else { 40.0 }, "{id} ({row}, {col})");
                }
            }
            // The white gap around the marker.
            assert_eq!(layout.level_at(tl[0] - 0.75, tl[1] + 3.0), 210.0);
            assert_eq!(layout.level_at(tl[0] + 7.75, tl[1] + 3.0), 210.0);
        }
        assert_eq!(layout.level_at(5.0, 5.0), 40.0); // square (0, 0): black
        assert_eq!(layout.level_at(45.0, 35.0), 40.0); // square (4, 3): black
        assert_eq!(layout.level_at(-1.0, 5.0), 210.0); // margin
        assert_eq!(layout.level_at(51.0, 39.0), 210.0);
        assert_eq!(layout.level_at(-2.5, 5.0), 100.0); // background
                                                       // Marker 0, DICT_4X4_50, as OpenCV draws it: first data row 1011.
        let row0: Vec<f64> =
            (0..4).map(|c| layout.level_at(11.5 + (c as f64 + 1.5) * cell, 1.5 + 1.5 * cell)).collect();
        assert_eq!(row0, [210.0, 40.0, 210.0, 210.0]);
    }

    #[test]
    fn charuco_coverage_is_exact_across_cells() {
        let board = Board::charuco([5, 4], 10.0, 7.0, "DICT_4X4_50").unwrap();
        let layout = BoardLayout::of(&board, 2.0, L);
        // Marker 0 spans x in [11.5, 18.5]: half in the white gap, half in its black border.
        let q = [[11.0, 1.6], [12.0, 1.6], [12.0, 2.0], [11.0, 2.0]];
        assert!((layout.mean_over(&q) - 125.0).abs() < 1e-12);
        // A square over the corner (10, 10) of four squares: two black, two white with
        // the gaps (1.5 mm) and marker borders of markers 0 (square (1, 0)) and 2 (square
        // (0, 1)) inside: [9, 11] x [9, 11] is half black squares, the white quarters
        // [10, 11] x [9, 10] and [9, 10] x [10, 11] all gap (the markers start 1.5 mm in).
        let c = [[9.0, 9.0], [11.0, 9.0], [11.0, 11.0], [9.0, 11.0]];
        assert!((layout.mean_over(&c) - 125.0).abs() < 1e-12);
        // A tilted square over marker 0's corner cell edge: exact by the slab split.
        let cell = 7.0 / 6.0;
        let (x0, y0) = (11.5 + cell, 1.5 + cell); // corner between border cells and data cell (0, 0)
        let d = [[x0 - 0.2, y0], [x0, y0 - 0.2], [x0 + 0.2, y0], [x0, y0 + 0.2]];
        // Three quarters in the border (black), one in data cell (0, 0): white (row 1011).
        let m = layout.mean_over(&d);
        assert!((m - (0.75 * 40.0 + 0.25 * 210.0)).abs() < 1e-9, "{m}");
    }
}
