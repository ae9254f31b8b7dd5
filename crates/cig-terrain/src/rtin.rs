//! Exact per-post errors of the right-triangulated irregular network (RTIN) over each level's
//! posts, for adaptive meshes that nest across levels.
//!
//! Algorithm: every level's grid is split as a checkerboard ([`Diagonal::of_cell`]), which is
//! the finest cut of one RTIN hierarchy over the whole database: a square of `k` cells is split
//! by its diagonal (south-west to north-east where its square row plus column is even) into two
//! right triangles whose hypotenuse midpoint is the square's centre ("diagonal" vertices); each
//! of those splits at the midpoint of the square's side ("side" vertices) into two triangles
//! that are halves of `k / 2` squares, and so on down to a level's cells (Evans, Kirkpatrick and
//! Townsend 2001, "Right-triangulated irregular networks"). Each post is the hypotenuse midpoint
//! of exactly two triangles of one size. Its own error is the largest vertical distance between
//! those two triangles' planes and the finest posts inside them (exact for the piecewise-linear
//! surfaces, whose vertices are finest posts; Martini, Agafonkin 2019, uses the error at the
//! midpoint alone, which does not bound the mesh). A level's error of a post is the maximum of
//! its own error and its children's (the midpoints of the triangles it creates), down to the
//! level's cells, so the posts whose error exceeds a tolerance are closed under the hierarchy
//! (a conforming mesh), every triangle of that mesh larger than a cell is within the tolerance,
//! and a post's error at a finer level is never smaller (meshes of nested nodes nest).
//!
//! Cost: one pass over the finest posts per triangle size (twice the number of levels plus
//! twice the log of the tile size), in parallel over rows; memory: one `f32` per finest post
//! and 1.33 per level grid post.
//!
//! Limits: triangles reaching past the database's edge are measured over the posts inside it
//! with the edge posts repeated; posts past the edge get zero. Meshes that reach past the edge
//! are drawn as regular grids (their vertices are clamped onto it), so neither is drawn.

use crate::raster::{Diagonal, Raster};
use rayon::prelude::*;

/// One level's error of each post, on the level's post grid covering the database.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelErrorGrid {
    /// Posts of this level inside the database (its last row and column included).
    pub rows: usize,
    pub cols: usize,
    pub values: Vec<f32>,
}

impl LevelErrorGrid {
    /// The error of post `(i, j)` of this level; zero past the database's edge.
    pub fn at(&self, i: usize, j: usize) -> f32 {
        if i < self.rows && j < self.cols {
            self.values[i * self.cols + j]
        } else {
            0.0
        }
    }
}

/// The kind of vertex a post is in the hierarchy, on a grid of unit cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Vertex {
    /// Centre of a square of `k` cells (`k >= 2`), whose diagonal it splits.
    Diagonal { k: u64 },
    /// Midpoint of a side of squares of `k` cells (`k >= 2`), along a row (`horizontal`) or a
    /// column.
    Side { k: u64, horizontal: bool },
    /// The grid's origin, which no triangle splits.
    Origin,
}

/// What vertex post `(i, j)` is.
pub fn vertex_kind(i: u64, j: u64) -> Vertex {
    let (a, b) = (tz(i), tz(j));
    if a == b {
        if a == u32::MAX {
            Vertex::Origin
        } else {
            Vertex::Diagonal { k: 2u64 << a }
        }
    } else {
        Vertex::Side {
            k: 2u64 << a.min(b),
            horizontal: a > b,
        }
    }
}

fn tz(x: u64) -> u32 {
    if x == 0 {
        u32::MAX
    } else {
        x.trailing_zeros()
    }
}

/// The two triangles whose hypotenuse post `(i, j)` splits, each as its hypotenuse's ends and
/// its right-angled apex (`(row, col)`).
pub fn split_triangles(i: u64, j: u64) -> Option<[[(i64, i64); 3]; 2]> {
    let (i, j) = (i as i64, j as i64);
    match vertex_kind(i as u64, j as u64) {
        Vertex::Origin => None,
        Vertex::Diagonal { k } => {
            let h = k as i64 / 2;
            let (s, n, w, e) = (i - h, i + h, j - h, j + h);
            let (sw, se, nw, ne) = ((s, w), (s, e), (n, w), (n, e));
            let square = ((s / k as i64) + (w / k as i64)) as usize;
            Some(match Diagonal::of_cell(square, 0) {
                Diagonal::SouthWestNorthEast => [[sw, ne, se], [sw, ne, nw]],
                Diagonal::NorthWestSouthEast => [[nw, se, sw], [nw, se, ne]],
            })
        }
        Vertex::Side { k, horizontal } => {
            let h = k as i64 / 2;
            Some(if horizontal {
                let (a, b) = ((i, j - h), (i, j + h));
                [[a, b, (i - h, j)], [a, b, (i + h, j)]]
            } else {
                let (a, b) = ((i - h, j), (i + h, j));
                [[a, b, (i, j - h)], [a, b, (i, j + h)]]
            })
        }
    }
}

/// The posts that the two triangles split at `(i, j)` are split at next: none below squares of
/// two cells.
pub fn child_vertices(i: u64, j: u64) -> Option<[(i64, i64); 4]> {
    let (i, j) = (i as i64, j as i64);
    match vertex_kind(i as u64, j as u64) {
        Vertex::Origin => None,
        Vertex::Diagonal { k } => {
            let h = k as i64 / 2;
            Some([(i - h, j), (i + h, j), (i, j - h), (i, j + h)])
        }
        Vertex::Side { k, .. } if k >= 4 => {
            let q = k as i64 / 4;
            Some([
                (i - q, j - q),
                (i - q, j + q),
                (i + q, j - q),
                (i + q, j + q),
            ])
        }
        Vertex::Side { .. } => None,
    }
}

/// Folds each post's value into its ancestors' on a `rows x cols` grid of posts (row-major):
/// from the smallest squares up, every post's value becomes `combine` of its own and its
/// children's (those on the grid), so a post's value covers everything below it. Level errors
/// take the maximum; a mesh's kept posts take "any".
pub fn fold_into_ancestors<T: Copy>(
    rows: usize,
    cols: usize,
    values: &mut [T],
    combine: impl Fn(T, T) -> T,
) {
    let mut k = 2usize;
    while k / 2 < rows.max(cols) {
        let h = k / 2;
        // Side vertices of squares of k cells, then their centres (which split into them).
        for (first_i, first_j) in [(0, h), (h, 0), (h, h)] {
            for i in (first_i..rows).step_by(k) {
                for j in (first_j..cols).step_by(k) {
                    let Some(children) = child_vertices(i as u64, j as u64) else {
                        continue;
                    };
                    let mut value = values[i * cols + j];
                    for (ci, cj) in children {
                        if ci >= 0 && cj >= 0 && (ci as usize) < rows && (cj as usize) < cols {
                            value = combine(value, values[ci as usize * cols + cj as usize]);
                        }
                    }
                    values[i * cols + j] = value;
                }
            }
        }
        k *= 2;
    }
}

/// The own error of every finest post (row-major, as the raster).
pub fn own_errors(raster: &Raster) -> Vec<f32> {
    let (rows, cols) = (raster.grid.rows, raster.grid.cols);
    let height = |r: i64, c: i64| -> f64 {
        let r = r.clamp(0, rows as i64 - 1) as usize;
        let c = c.clamp(0, cols as i64 - 1) as usize;
        f64::from(raster.elevation_m[r * cols + c])
    };
    let mut out = vec![0.0f32; rows * cols];
    out.par_chunks_mut(cols).enumerate().for_each(|(r, row)| {
        for (c, value) in row.iter_mut().enumerate() {
            let (r, c) = (r as u64, c as u64);
            if let Some(triangles) = split_triangles(r, c) {
                let e = triangles
                    .iter()
                    .map(|t| triangle_error(t, rows, cols, &height))
                    .fold(0.0f64, f64::max);
                // Rounded up, so that the stored error still bounds the true one.
                *value = round_up(e);
            }
        }
    });
    out
}

fn round_up(e: f64) -> f32 {
    let f = e as f32;
    if f64::from(f) < e {
        f.next_up()
    } else {
        f
    }
}

/// Largest vertical distance between the plane of `t` and the finest posts inside it (and
/// inside the database).
fn triangle_error(
    t: &[(i64, i64); 3],
    rows: usize,
    cols: usize,
    height: &dyn Fn(i64, i64) -> f64,
) -> f64 {
    let [(r0, c0), (r1, c1), (r2, c2)] = *t;
    let (h0, h1, h2) = (height(r0, c0), height(r1, c1), height(r2, c2));
    let det = ((r1 - r0) * (c2 - c0) - (r2 - r0) * (c1 - c0)) as f64;
    let r_lo = r0.min(r1).min(r2).max(0);
    let r_hi = r0.max(r1).max(r2).min(rows as i64 - 1);
    let c_lo = c0.min(c1).min(c2).max(0);
    let c_hi = c0.max(c1).max(c2).min(cols as i64 - 1);
    let edge = |(ar, ac): (i64, i64), (br, bc): (i64, i64), (pr, pc): (i64, i64)| {
        (br - ar) * (pc - ac) - (pr - ar) * (bc - ac)
    };
    let sign = if det > 0.0 { 1 } else { -1 };
    let mut worst = 0.0f64;
    for r in r_lo..=r_hi {
        for c in c_lo..=c_hi {
            let p = (r, c);
            let w0 = edge((r1, c1), (r2, c2), p) * sign;
            let w1 = edge((r2, c2), (r0, c0), p) * sign;
            let w2 = edge((r0, c0), (r1, c1), p) * sign;
            if w0 < 0 || w1 < 0 || w2 < 0 {
                continue;
            }
            let plane = (w0 as f64 * h0 + w1 as f64 * h1 + w2 as f64 * h2) / det.abs();
            worst = worst.max((plane - height(r, c)).abs());
        }
    }
    worst
}

/// Level `level`'s error of each of its posts, from the finest posts' own errors.
pub fn level_errors(raster: &Raster, own: &[f32], level: u8) -> LevelErrorGrid {
    let step = 1usize << level;
    let (fine_rows, fine_cols) = (raster.grid.rows, raster.grid.cols);
    let rows = (fine_rows - 1) / step + 1;
    let cols = (fine_cols - 1) / step + 1;
    let mut values: Vec<f32> = (0..rows * cols)
        .map(|k| own[(k / cols) * step * fine_cols + (k % cols) * step])
        .collect();
    fold_into_ancestors(rows, cols, &mut values, f32::max);
    LevelErrorGrid { rows, cols, values }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_post_but_the_origin_splits_two_triangles_with_it_as_hypotenuse_midpoint() {
        for i in 0..40u64 {
            for j in 0..40u64 {
                let Some(triangles) = split_triangles(i, j) else {
                    assert_eq!((i, j), (0, 0));
                    continue;
                };
                for [a, b, apex] in triangles {
                    assert_eq!((a.0 + b.0, a.1 + b.1), (2 * i as i64, 2 * j as i64));
                    // Right angle at the apex.
                    let (u, v) = ((a.0 - apex.0, a.1 - apex.1), (b.0 - apex.0, b.1 - apex.1));
                    assert_eq!(u.0 * v.0 + u.1 * v.1, 0, "{i},{j}");
                    assert_eq!(u.0 * u.0 + u.1 * u.1, v.0 * v.0 + v.1 * v.1);
                }
            }
        }
    }

    #[test]
    fn a_plane_has_no_error_and_a_spike_reaches_its_ancestors() {
        let plane = Raster::for_test(33, 33, |r, c| 3.0 * r as f32 - 2.0 * c as f32 + 7.0);
        let own = own_errors(&plane);
        let inside = |(r, c): (i64, i64)| (0..33).contains(&r) && (0..33).contains(&c);
        for (k, &e) in own.iter().enumerate() {
            let (r, c) = ((k / 33) as u64, (k % 33) as u64);
            if split_triangles(r, c).is_some_and(|t| t.iter().flatten().all(|&p| inside(p))) {
                assert!(e < 1e-3, "({r}, {c}): {e}");
            }
        }
        let spiky = Raster::for_test(33, 33, |r, c| if (r, c) == (5, 9) { 10.0 } else { 0.0 });
        let own = own_errors(&spiky);
        for level in 0..3u8 {
            let grid = level_errors(&spiky, &own, level);
            // Every post whose triangles hold the spike strictly inside has at least its error;
            // the post itself (level 0) has its own.
            let step = 1usize << level;
            let centre = grid.at(16 / step, 16 / step);
            assert!(centre >= 10.0 - 1e-4, "level {level}: centre {centre}");
        }
        // Finer levels never have smaller errors at the same post.
        let coarse = level_errors(&spiky, &own, 1);
        let fine = level_errors(&spiky, &own, 0);
        for i in 0..coarse.rows {
            for j in 0..coarse.cols {
                assert!(fine.at(2 * i, 2 * j) >= coarse.at(i, j));
            }
        }
    }
}
