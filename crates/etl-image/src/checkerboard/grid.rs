//! Growing a grid of corners from a seed by neighbour topology, then keeping it only if it
//! is a complete rectangle whose squares alternate in colour, including the outer ring of
//! squares beyond the outermost corners (a printed board always has it, the background
//! beyond a spurious extra row of corners does not).

use std::collections::HashMap;

use super::candidates::{line_diff, Corner};
use crate::grey::Plane;

/// A complete grid at the detection level: `pts[j * nc + i]` is grid corner (i, j), in an
/// arbitrary (but right-handed) orientation.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    pub nc: usize,
    pub nr: usize,
    pub pts: Vec<[f32; 2]>,
    /// Candidates used (indices into the corner list).
    pub members: Vec<usize>,
    /// True when cell (0, 0) (between corners (0,0), (1,0), (0,1), (1,1)) is dark.
    pub cell00_dark: bool,
}

/// Angle tolerance for "along this edge", rad.
const DIR_TOL: f32 = 0.3;
/// Tolerance between the edge directions of neighbouring corners, rad.
const LINE_TOL: f32 = 0.4;
/// A predicted corner is accepted within this fraction of the local spacing.
const PRED_TOL: f32 = 0.3;

type Pos = (i32, i32);

fn sub(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
fn norm(a: [f32; 2]) -> f32 {
    a[0].hypot(a[1])
}
fn dir(a: [f32; 2]) -> f32 {
    a[1].atan2(a[0])
}
fn lines_match(a: &Corner, b: &Corner) -> bool {
    (line_diff(a.line[0], b.line[0]) < LINE_TOL && line_diff(a.line[1], b.line[1]) < LINE_TOL)
        || (line_diff(a.line[0], b.line[1]) < LINE_TOL && line_diff(a.line[1], b.line[0]) < LINE_TOL)
}
fn along_a_line(c: &Corner, v: [f32; 2]) -> bool {
    let d = dir(v);
    line_diff(d, c.line[0]) < DIR_TOL || line_diff(d, c.line[1]) < DIR_TOL
}

struct Grower<'a> {
    c: &'a [Corner],
    map: HashMap<Pos, usize>,
    used: Vec<bool>,
}

impl Grower<'_> {
    fn p(&self, q: Pos) -> Option<[f32; 2]> {
        self.map.get(&q).map(|&k| self.c[k].p)
    }

    /// The nearest unused candidate within `tol` of `pred` compatible with `reference`.
    fn find(&self, pred: [f32; 2], tol: f32, reference: usize) -> Option<usize> {
        let r = &self.c[reference];
        let mut best: Option<(usize, f32)> = None;
        for (k, c) in self.c.iter().enumerate() {
            if self.used[k] {
                continue;
            }
            let d = norm(sub(c.p, pred));
            if d > tol || best.is_some_and(|(_, bd)| bd <= d) {
                continue;
            }
            if !lines_match(c, r) || !along_a_line(c, sub(c.p, r.p)) {
                continue;
            }
            best = Some((k, d));
        }
        best.map(|b| b.0)
    }

    /// Predicted position of an empty grid position from its filled neighbours, the local
    /// spacing and a filled 4-neighbour.
    fn predict(&self, q: Pos) -> Option<([f32; 2], f32, usize)> {
        let (i, j) = q;
        let mut acc = [0.0f32; 2];
        let mut spacing = 0.0f32;
        let mut n = 0.0f32;
        let mut reference = None;
        for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let a = (i - di, j - dj);
            if let Some(&k) = self.map.get(&a) {
                reference = Some(k);
                if let Some(pb) = self.p((i - 2 * di, j - 2 * dj)) {
                    let pa = self.c[k].p;
                    acc[0] += 2.0 * pa[0] - pb[0];
                    acc[1] += 2.0 * pa[1] - pb[1];
                    spacing += norm(sub(pa, pb));
                    n += 1.0;
                }
            }
        }
        for (di, dj) in [(1, 1), (1, -1), (-1, 1), (-1, -1)] {
            if let (Some(a), Some(b), Some(c)) = (self.p((i - di, j)), self.p((i, j - dj)), self.p((i - di, j - dj))) {
                acc[0] += a[0] + b[0] - c[0];
                acc[1] += a[1] + b[1] - c[1];
                spacing += 0.5 * (norm(sub(a, c)) + norm(sub(b, c)));
                n += 1.0;
            }
        }
        let reference = reference?;
        (n > 0.0).then(|| ([acc[0] / n, acc[1] / n], spacing / n, reference))
    }

    fn grow(&mut self, max_extent: i32) {
        loop {
            let mut frontier: Vec<Pos> = Vec::new();
            let (i0, i1, j0, j1) = bbox(&self.map);
            for &(i, j) in self.map.keys() {
                for q in [(i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)] {
                    if self.map.contains_key(&q) {
                        continue;
                    }
                    if q.0.max(i1) - q.0.min(i0) >= max_extent || q.1.max(j1) - q.1.min(j0) >= max_extent {
                        continue;
                    }
                    frontier.push(q);
                }
            }
            frontier.sort_unstable();
            frontier.dedup();
            let mut added = false;
            for q in frontier {
                if self.map.contains_key(&q) {
                    continue;
                }
                if let Some((pred, spacing, reference)) = self.predict(q) {
                    if let Some(k) = self.find(pred, (PRED_TOL * spacing).max(1.5), reference) {
                        self.map.insert(q, k);
                        self.used[k] = true;
                        added = true;
                    }
                }
            }
            if !added {
                break;
            }
        }
    }
}

fn bbox(map: &HashMap<Pos, usize>) -> (i32, i32, i32, i32) {
    let mut b = (i32::MAX, i32::MIN, i32::MAX, i32::MIN);
    for &(i, j) in map.keys() {
        b = (b.0.min(i), b.1.max(i), b.2.min(j), b.3.max(j));
    }
    b
}

/// The nearest candidate from `s` along direction `theta` (either sense given by `sign`).
fn neighbour(c: &[Corner], s: usize, theta: f32, sign: f32) -> Option<usize> {
    let u = [sign * theta.cos(), sign * theta.sin()];
    let mut best: Option<(usize, f32)> = None;
    for (k, q) in c.iter().enumerate() {
        if k == s {
            continue;
        }
        let v = sub(q.p, c[s].p);
        let d = norm(v);
        if d < 3.0 || best.is_some_and(|(_, bd)| bd <= d) {
            continue;
        }
        let cosang = (v[0] * u[0] + v[1] * u[1]) / d;
        if cosang < DIR_TOL.cos() || !lines_match(&c[s], q) {
            continue;
        }
        best = Some((k, d));
    }
    best.map(|b| b.0)
}

/// Grows the largest grid reachable from seed candidate `s` (at most `max_extent` corners
/// along either axis). Returns the grid positions filled (a map from (i, j) to candidate).
fn grow_from(c: &[Corner], s: usize, max_extent: i32) -> Option<HashMap<Pos, usize>> {
    let mut g = Grower { c, map: HashMap::new(), used: vec![false; c.len()] };
    g.map.insert((0, 0), s);
    g.used[s] = true;
    let mut axes = 0;
    for (e, (di, dj)) in [(0usize, (1, 0)), (1, (0, 1))] {
        let mut found = false;
        for sign in [1.0f32, -1.0] {
            if let Some(k) = neighbour(c, s, c[s].line[e], sign) {
                if g.used[k] {
                    continue;
                }
                let q = if sign > 0.0 { (di, dj) } else { (-di, -dj) };
                g.map.insert(q, k);
                g.used[k] = true;
                found = true;
            }
        }
        axes += usize::from(found);
    }
    if axes < 2 {
        return None;
    }
    g.grow(max_extent);
    Some(g.map)
}

/// Trims the filled set to a complete rectangle by dropping, one at a time, the border line
/// with the largest fraction missing.
fn complete_rectangle(map: &mut HashMap<Pos, usize>) {
    loop {
        if map.is_empty() {
            return;
        }
        let (i0, i1, j0, j1) = bbox(map);
        let (w, h) = (i1 - i0 + 1, j1 - j0 + 1);
        if map.len() as i32 == w * h {
            return;
        }
        let missing = |line: &dyn Fn(i32) -> Pos, n: i32| {
            (0..n).filter(|&t| !map.contains_key(&line(t))).count() as f32 / n as f32
        };
        let sides = [
            missing(&|t| (i0, j0 + t), h),
            missing(&|t| (i1, j0 + t), h),
            missing(&|t| (i0 + t, j0), w),
            missing(&|t| (i0 + t, j1), w),
        ];
        let worst = (0..4).max_by(|&a, &b| sides[a].total_cmp(&sides[b])).unwrap_or(0);
        remove_side(map, worst);
    }
}

/// Removes a border line: 0 = first column, 1 = last column, 2 = first row, 3 = last row.
fn remove_side(map: &mut HashMap<Pos, usize>, side: usize) {
    let (i0, i1, j0, j1) = bbox(map);
    map.retain(|&(i, j), _| match side {
        0 => i != i0,
        1 => i != i1,
        2 => j != j0,
        _ => j != j1,
    });
}

/// The mean grey level of the square with the four given corners (its central part).
/// `inner` marks the corners that are grid corners (all four for a square of the grid, one
/// or two for the outer ring); when the central part runs out of the image, an outer
/// square is sampled next to its inner edge only. `None`: not visible.
fn cell_value(s: &Plane, q: [[f32; 2]; 4], inner: [bool; 4]) -> Option<f32> {
    let c = [(q[0][0] + q[1][0] + q[2][0] + q[3][0]) * 0.25, (q[0][1] + q[1][1] + q[2][1] + q[3][1]) * 0.25];
    let mut pts = [c; 5];
    for (k, p) in q.iter().enumerate() {
        pts[k + 1] = [c[0] + 0.3 * (p[0] - c[0]), c[1] + 0.3 * (p[1] - c[1])];
    }
    if pts.iter().all(|&p| s.contains(p, 1.0)) {
        return Some(pts.iter().map(|p| s.bilinear(p[0], p[1])).sum::<f32>() / 5.0);
    }
    let n_inner = inner.iter().filter(|&&b| b).count();
    if n_inner == 0 || n_inner == 4 {
        return None;
    }
    let mut m = [0.0f32; 2];
    for (p, _) in q.iter().zip(inner).filter(|(_, b)| *b) {
        m[0] += p[0] / n_inner as f32;
        m[1] += p[1] / n_inner as f32;
    }
    // Three points a third of the way from the inner edge (or corner) towards the centre.
    let mid = [m[0] + 0.4 * (c[0] - m[0]), m[1] + 0.4 * (c[1] - m[1])];
    let side = [0.25 * (c[1] - m[1]), -0.25 * (c[0] - m[0])];
    let pts = [mid, [mid[0] + side[0], mid[1] + side[1]], [mid[0] - side[0], mid[1] - side[1]]];
    pts.iter().all(|&p| s.contains(p, 1.0)).then(|| pts.iter().map(|p| s.bilinear(p[0], p[1])).sum::<f32>() / 3.0)
}

/// Why a grid was rejected.
pub(crate) enum Reject {
    /// Squares do not alternate inside the grid: not a board.
    NotABoard,
    /// The outer ring of squares runs out of the image.
    AtBorder,
}

/// Checks the colours of the grid's squares and of the outer ring around it. `Ok(None)`:
/// all alternate; `Ok(Some(side))`: only the outer ring on `side` (0 = i low, 1 = i high,
/// 2 = j low, 3 = j high) fails, i.e. that border line of corners is not part of the board.
fn check_cells(s: &Plane, map: &HashMap<Pos, usize>, c: &[Corner]) -> Result<(Option<usize>, bool), Reject> {
    let (i0, i1, j0, j1) = bbox(map);
    let (nc, nr) = ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize);
    let e = extended_corners(map, c, [i0, j0], [nc, nr]);
    let v = cell_values(s, &e, [nc, nr])?;
    let (cc, cr) = (nc + 1, nr + 1);
    // Polarity and contrast from the inner cells.
    let (mut m0, mut n0, mut m1, mut n1) = (0.0f32, 0usize, 0.0f32, 0usize);
    for cj in 1..cr - 1 {
        for ci in 1..cc - 1 {
            if (ci + cj) % 2 == 0 {
                m0 += v[cj * cc + ci];
                n0 += 1;
            } else {
                m1 += v[cj * cc + ci];
                n1 += 1;
            }
        }
    }
    if n0 == 0 || n1 == 0 {
        return Err(Reject::NotABoard);
    }
    let (m0, m1) = (m0 / n0 as f32, m1 / n1 as f32);
    let contrast = (m1 - m0).abs();
    if contrast < 4.0 {
        return Err(Reject::NotABoard);
    }
    let sign = if m1 > m0 { 1.0 } else { -1.0 };
    let min_step = 0.25 * contrast;
    let mut side_fail = [0usize; 4];
    let side_of = |ci: usize, cj: usize| -> [bool; 4] { [ci == 0, ci == cc - 1, cj == 0, cj == cr - 1] };
    for cj in 0..cr {
        for ci in 0..cc {
            for (di, dj) in [(1usize, 0usize), (0, 1)] {
                let (bi, bj) = (ci + di, cj + dj);
                if bi >= cc || bj >= cr {
                    continue;
                }
                let (a, b) = (v[cj * cc + ci], v[bj * cc + bi]);
                if a.is_nan() || b.is_nan() {
                    continue;
                }
                // Parity of a: even -> "0" class; b has the other parity.
                let step = if (ci + cj) % 2 == 0 { sign * (b - a) } else { sign * (a - b) };
                if step >= min_step {
                    continue;
                }
                let (sa, sb) = (side_of(ci, cj), side_of(bi, bj));
                let mut any = false;
                for k in 0..4 {
                    if sa[k] || sb[k] {
                        side_fail[k] += 1;
                        any = true;
                    }
                }
                if !any {
                    return Err(Reject::NotABoard);
                }
            }
        }
    }
    let worst = (0..4).max_by_key(|&k| side_fail[k]).unwrap_or(0);
    // Cell (0,0) of the grid is cell (1,1) here; dark is the darker class.
    let cell00_dark = sign > 0.0;
    Ok(((side_fail[worst] > 0).then_some(worst), cell00_dark))
}

/// The `nc x nr` grid corners (grid position `[i0, j0]` first) extended by one on every
/// side by linear extrapolation, `2 a - b`: `(nc + 2) x (nr + 2)`, row-major.
fn extended_corners(
    map: &HashMap<Pos, usize>,
    c: &[Corner],
    [i0, j0]: [i32; 2],
    [nc, nr]: [usize; 2],
) -> Vec<[f32; 2]> {
    // Corners extended by one on every side (linear extrapolation).
    let (ec, er) = (nc + 2, nr + 2);
    let mut e = vec![[0.0f32; 2]; ec * er];
    for j in 0..nr {
        for i in 0..nc {
            e[(j + 1) * ec + i + 1] = c[map[&(i0 + i as i32, j0 + j as i32)]].p;
        }
    }
    let lerp2 = |a: [f32; 2], b: [f32; 2]| [2.0 * a[0] - b[0], 2.0 * a[1] - b[1]];
    for j in 1..=nr {
        e[j * ec] = lerp2(e[j * ec + 1], e[j * ec + 2]);
        e[j * ec + ec - 1] = lerp2(e[j * ec + ec - 2], e[j * ec + ec - 3]);
    }
    for i in 0..ec {
        e[i] = lerp2(e[ec + i], e[2 * ec + i]);
        e[(er - 1) * ec + i] = lerp2(e[(er - 2) * ec + i], e[(er - 3) * ec + i]);
    }
    e
}

/// Mean grey level of every cell of the extended corners `e` of an `nc x nr` grid: cells
/// `(ci, cj)`, `ci` in `0..=nc`, `cj` in `0..=nr`, row-major; NaN for an outer-ring cell out
/// of the image. Rejects a grid whose own squares leave the image, or whose outer ring is
/// more than half out on a side.
fn cell_values(s: &Plane, e: &[[f32; 2]], [nc, nr]: [usize; 2]) -> Result<Vec<f32>, Reject> {
    let ec = nc + 2;
    // Cells (ci, cj), ci in 0..=nc, cj in 0..=nr (cell 0 is the outer ring).
    let (cc, cr) = (nc + 1, nr + 1);
    let mut v = vec![0.0f32; cc * cr];
    for cj in 0..cr {
        for ci in 0..cc {
            let q = [e[cj * ec + ci], e[cj * ec + ci + 1], e[(cj + 1) * ec + ci], e[(cj + 1) * ec + ci + 1]];
            let real = |i: usize, j: usize| (1..=nc).contains(&i) && (1..=nr).contains(&j);
            let inner = [real(ci, cj), real(ci + 1, cj), real(ci, cj + 1), real(ci + 1, cj + 1)];
            v[cj * cc + ci] = match cell_value(s, q, inner) {
                Some(x) => x,
                // Squares of the grid must be visible; the outer ring may leave the image.
                None if inner.iter().all(|&b| b) => return Err(Reject::AtBorder),
                None => f32::NAN,
            };
        }
    }
    // At most half of each side of the outer ring out of the image.
    let unknown = |f: &dyn Fn(usize) -> usize, n: usize| (0..n).filter(|&t| v[f(t)].is_nan()).count() * 2 > n;
    if unknown(&|t| t * cc, cr)
        || unknown(&|t| t * cc + cc - 1, cr)
        || unknown(&|t| t, cc)
        || unknown(&|t| (cr - 1) * cc + t, cc)
    {
        return Err(Reject::AtBorder);
    }
    Ok(v)
}

/// The outcome of one seed.
pub(crate) enum Outcome {
    Grid(Grid),
    Rejected(Reject),
    TooSmall,
}

/// Grows, completes and checks a grid from seed `s`.
pub(crate) fn grid_from_seed(s: &Plane, c: &[Corner], seed: usize, max_extent: i32) -> (Outcome, Vec<usize>) {
    let Some(mut map) = grow_from(c, seed, max_extent) else {
        return (Outcome::TooSmall, vec![seed]);
    };
    let touched: Vec<usize> = map.values().copied().collect();
    complete_rectangle(&mut map);
    let mut cell00_dark = None;
    for _ in 0..8 {
        let (i0, i1, j0, j1) = bbox(&map);
        if map.len() < 4 || i1 - i0 < 1 || j1 - j0 < 1 {
            return (Outcome::TooSmall, touched);
        }
        match check_cells(s, &map, c) {
            Ok((None, dark)) => {
                cell00_dark = Some(dark);
                break;
            }
            Ok((Some(side), _)) => remove_side(&mut map, side),
            Err(r) => return (Outcome::Rejected(r), touched),
        }
    }
    let Some(cell00_dark) = cell00_dark else {
        return (Outcome::Rejected(Reject::NotABoard), touched);
    };
    let (i0, i1, j0, j1) = bbox(&map);
    let (nc, nr) = ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize);
    let mut pts = Vec::with_capacity(nc * nr);
    let mut members = Vec::with_capacity(nc * nr);
    for j in j0..=j1 {
        for i in i0..=i1 {
            let k = map[&(i, j)];
            pts.push(c[k].p);
            members.push(k);
        }
    }
    let mut g = Grid { nc, nr, pts, members, cell00_dark };
    make_right_handed(&mut g);
    (Outcome::Grid(g), touched)
}

/// Reverses the rows if needed so that `(p(1,0) - p(0,0)) x (p(0,1) - p(0,0)) > 0` in image
/// coordinates (u right, v down): the handedness of a board seen from its printed side.
fn make_right_handed(g: &mut Grid) {
    let a = sub(g.pts[1], g.pts[0]);
    let b = sub(g.pts[g.nc], g.pts[0]);
    if a[0] * b[1] - a[1] * b[0] >= 0.0 {
        return;
    }
    let (nc, nr) = (g.nc, g.nr);
    let mut pts = Vec::with_capacity(nc * nr);
    let mut members = Vec::with_capacity(nc * nr);
    for j in (0..nr).rev() {
        pts.extend_from_slice(&g.pts[j * nc..(j + 1) * nc]);
        members.extend_from_slice(&g.members[j * nc..(j + 1) * nc]);
    }
    g.pts = pts;
    g.members = members;
    // Cell (0,0) is now the old cell (0, nr-2): colour flips when nr - 2 is odd.
    if nr % 2 == 1 {
        g.cell00_dark = !g.cell00_dark;
    }
}
