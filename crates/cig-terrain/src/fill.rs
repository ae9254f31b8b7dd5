//! Fills voids (nodata posts) in a raster.
//!
//! Algorithm: pull-push (Gortler et al. 1996, "The Lumigraph", the hole-filling pass): build a
//! pyramid of NaN-aware 2 x 2 means until a level has no void, then fill each finer level's voids
//! by bilinear interpolation from the level above, finishing with Laplace relaxation sweeps over
//! the filled posts only so that the patch meets its rim smoothly. Known posts are never changed.
//!
//! Limits: large voids come out smooth (no invented relief); a raster with no valid post at all
//! cannot be filled.

use crate::raster::Raster;

/// Why voids could not be filled.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FillError {
    #[error("every one of the {0} posts is void; nothing to fill from")]
    AllVoid(usize),
}

/// Fills every `NaN` post of `raster.elevation_m`; returns how many were filled.
pub fn fill_voids(raster: &mut Raster) -> Result<usize, FillError> {
    let rows = raster.grid.rows;
    let cols = raster.grid.cols;
    let voids = raster.void_count();
    if voids == 0 {
        return Ok(0);
    }
    if voids == raster.elevation_m.len() {
        return Err(FillError::AllVoid(voids));
    }
    let filled = pull_push(&raster.elevation_m, rows, cols);
    let void_mask: Vec<bool> = raster.elevation_m.iter().map(|h| h.is_nan()).collect();
    let mut heights = filled;
    // Laplace relaxation on the filled posts only.
    for _ in 0..32 {
        for r in 0..rows {
            for c in 0..cols {
                let k = r * cols + c;
                if !void_mask[k] {
                    continue;
                }
                let mut sum = 0.0f32;
                let mut n = 0.0f32;
                if r > 0 {
                    sum += heights[k - cols];
                    n += 1.0;
                }
                if r + 1 < rows {
                    sum += heights[k + cols];
                    n += 1.0;
                }
                if c > 0 {
                    sum += heights[k - 1];
                    n += 1.0;
                }
                if c + 1 < cols {
                    sum += heights[k + 1];
                    n += 1.0;
                }
                heights[k] = sum / n;
            }
        }
    }
    raster.elevation_m = heights;
    Ok(voids)
}

fn pull_push(values: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    if values.iter().all(|v| !v.is_nan()) || (rows <= 1 && cols <= 1) {
        return values.to_vec();
    }
    let crow = rows.div_ceil(2);
    let ccol = cols.div_ceil(2);
    let mut coarse = vec![f32::NAN; crow * ccol];
    for r in 0..crow {
        for c in 0..ccol {
            let mut sum = 0.0f64;
            let mut n = 0u32;
            for (dr, dc) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                let (rr, cc) = (2 * r + dr, 2 * c + dc);
                if rr < rows && cc < cols {
                    let v = values[rr * cols + cc];
                    if !v.is_nan() {
                        sum += f64::from(v);
                        n += 1;
                    }
                }
            }
            if n > 0 {
                coarse[r * ccol + c] = (sum / f64::from(n)) as f32;
            }
        }
    }
    let coarse = pull_push(&coarse, crow, ccol);
    let mut out = values.to_vec();
    for r in 0..rows {
        for c in 0..cols {
            let k = r * cols + c;
            if !out[k].is_nan() {
                continue;
            }
            // Fine post (r, c) sits at coarse coordinate ((r - 0.5) / 2, (c - 0.5) / 2).
            let fr = ((r as f64 - 0.5) / 2.0).clamp(0.0, (crow - 1) as f64);
            let fc = ((c as f64 - 0.5) / 2.0).clamp(0.0, (ccol - 1) as f64);
            let r0 = fr.floor() as usize;
            let c0 = fc.floor() as usize;
            let r1 = (r0 + 1).min(crow - 1);
            let c1 = (c0 + 1).min(ccol - 1);
            let (tr, tc) = (fr - r0 as f64, fc - c0 as f64);
            let at = |rr: usize, cc: usize| f64::from(coarse[rr * ccol + cc]);
            let v = (1.0 - tr) * ((1.0 - tc) * at(r0, c0) + tc * at(r0, c1))
                + tr * ((1.0 - tc) * at(r1, c0) + tc * at(r1, c1));
            out[k] = v as f32;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fills_a_hole_in_a_plane_close_to_the_plane_and_keeps_known_posts() {
        let plane = |r: usize, c: usize| 100.0 + r as f32 * 2.0 + c as f32;
        let mut r = Raster::for_test(40, 50, |row, col| {
            if (10..20).contains(&row) && (15..30).contains(&col) {
                f32::NAN
            } else {
                plane(row, col)
            }
        });
        let filled = fill_voids(&mut r).expect("fill");
        assert_eq!(filled, 150);
        assert_eq!(r.void_count(), 0);
        for row in 0..40 {
            for col in 0..50 {
                let h = r.elevation_at(row, col);
                let inside = (10..20).contains(&row) && (15..30).contains(&col);
                if inside {
                    assert!((h - plane(row, col)).abs() < 3.0, "{row},{col}: {h}");
                } else {
                    assert_eq!(h, plane(row, col));
                }
            }
        }
    }

    #[test]
    fn all_void_is_an_error() {
        let mut r = Raster::for_test(4, 4, |_, _| f32::NAN);
        assert_eq!(fill_voids(&mut r), Err(FillError::AllVoid(16)));
    }
}
