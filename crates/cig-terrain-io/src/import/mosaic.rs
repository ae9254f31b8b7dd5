//! Mosaicking several geographic rasters into one lattice.
//!
//! Rules: the output spacing is the finest source's (smallest latitude spacing, then longitude
//! spacing); the output lattice is anchored on that source's posts, so they are kept unchanged;
//! the extent is the union of the sources (lattice posts inside it). Each output post takes its
//! value from the first source, finest first then in the given order, that covers it with a
//! value: the exact post value where the output post coincides with a source post (within 1e-6
//! of an index), otherwise [`triangulated_height`] on the source cell around it. A void in one
//! source is filled from the next source that has a value there (an SRTM void from the DTED
//! under it); posts no source has a value for are `NaN`. Limits: at most [`MAX_POSTS`] output posts; materials
//! are dropped (the mosaic's `material` is `None`) unless there is a single source, which is
//! returned unchanged.

use cig_terrain::raster::{triangulated_height, Diagonal, GeoGrid, Raster};
use rayon::prelude::*;

use super::{ImportError, MAX_POSTS};

/// Tolerance, in index units, for "on a post" and "inside a grid".
const INDEX_EPS: f64 = 1e-6;

/// A NaN payload no source value carries (sources' NaNs are made canonical): "not yet set".
const UNSET: u32 = 0x7fc0_dead;

/// Mosaics several rasters into one geographic grid (see the module documentation).
pub fn mosaic(sources: &[Raster]) -> Result<Raster, ImportError> {
    match sources {
        [] => return Err(ImportError::NoInput),
        [one] => return Ok(one.clone()),
        _ => {}
    }
    for (index, source) in sources.iter().enumerate() {
        check_source(index, source)?;
    }

    // Finest first, then the given order (a stable sort on a total order of quantised spacings).
    let quantise = |deg: f64| (deg * 1e12).round() as i64;
    let mut order: Vec<usize> = (0..sources.len()).collect();
    order.sort_by_key(|&i| {
        let g = &sources[i].grid;
        (quantise(g.dlat_deg), quantise(g.dlon_deg))
    });
    let prioritised: Vec<&Raster> = order.iter().map(|&i| &sources[i]).collect();
    let base = prioritised[0].grid;

    let south = fold(sources, |g| g.south_lat_deg, f64::min);
    let north = fold(sources, GeoGrid::north_lat_deg, f64::max);
    let west = fold(sources, |g| g.west_lon_deg, f64::min);
    let east = fold(sources, GeoGrid::east_lon_deg, f64::max);

    // Whole lattice steps from the base's first post to the union's edges (inwards).
    let steps = |distance: f64, spacing: f64| (distance / spacing + INDEX_EPS).floor().max(0.0);
    let rows_south = steps(base.south_lat_deg - south, base.dlat_deg);
    let rows_north = steps(north - base.south_lat_deg, base.dlat_deg);
    let cols_west = steps(base.west_lon_deg - west, base.dlon_deg);
    let cols_east = steps(east - base.west_lon_deg, base.dlon_deg);
    let rows = rows_south + rows_north + 1.0;
    let cols = cols_west + cols_east + 1.0;
    // `as` saturates; the product check refuses anything absurd.
    let (rows_u64, cols_u64) = (rows as u64, cols as u64);
    match rows_u64.checked_mul(cols_u64) {
        Some(posts) if posts <= MAX_POSTS => {}
        _ => {
            return Err(ImportError::MosaicTooLarge {
                rows: rows_u64,
                cols: cols_u64,
                limit: MAX_POSTS,
            })
        }
    }
    let grid = GeoGrid {
        south_lat_deg: base.south_lat_deg - rows_south * base.dlat_deg,
        west_lon_deg: base.west_lon_deg - cols_west * base.dlon_deg,
        dlat_deg: base.dlat_deg,
        dlon_deg: base.dlon_deg,
        rows: rows_u64 as usize,
        cols: cols_u64 as usize,
    };

    let mut elevation_m = vec![f32::from_bits(UNSET); grid.rows * grid.cols];
    elevation_m
        .par_chunks_mut(grid.cols)
        .enumerate()
        .for_each(|(row, line)| fill_row(&grid, row, line, &prioritised));
    for h in &mut elevation_m {
        if h.to_bits() == UNSET {
            *h = f32::NAN;
        }
    }
    tracing::info!(
        sources = sources.len(),
        rows = grid.rows,
        cols = grid.cols,
        "mosaicked DEM sources"
    );
    Ok(Raster {
        grid,
        elevation_m,
        material: None,
    })
}

fn fold(sources: &[Raster], key: impl Fn(&GeoGrid) -> f64, pick: fn(f64, f64) -> f64) -> f64 {
    sources
        .iter()
        .map(|s| key(&s.grid))
        .reduce(pick)
        .unwrap_or(f64::NAN)
}

fn check_source(index: usize, source: &Raster) -> Result<(), ImportError> {
    let g = &source.grid;
    let reason = if g.rows == 0 || g.cols == 0 {
        Some(format!("empty grid of {} x {} posts", g.rows, g.cols))
    } else if g.rows.checked_mul(g.cols) != Some(source.elevation_m.len()) {
        Some(format!(
            "{} heights for {} x {} posts",
            source.elevation_m.len(),
            g.rows,
            g.cols
        ))
    } else if !(g.dlat_deg.is_finite()
        && g.dlat_deg > 0.0
        && g.dlon_deg.is_finite()
        && g.dlon_deg > 0.0)
    {
        Some(format!(
            "spacing {} x {} degrees is not positive",
            g.dlat_deg, g.dlon_deg
        ))
    } else if !(g.south_lat_deg.is_finite()
        && g.west_lon_deg.is_finite()
        && g.north_lat_deg().is_finite()
        && g.east_lon_deg().is_finite())
    {
        Some("origin is not finite".to_string())
    } else {
        None
    };
    match reason {
        Some(reason) => Err(ImportError::InvalidSource { index, reason }),
        None => Ok(()),
    }
}

/// Fills the unset and void posts of output row `row` from the sources, in priority order.
fn fill_row(grid: &GeoGrid, row: usize, line: &mut [f32], sources: &[&Raster]) {
    let lat = grid.south_lat_deg + row as f64 * grid.dlat_deg;
    for source in sources {
        let g = &source.grid;
        let fr = (lat - g.south_lat_deg) / g.dlat_deg;
        if !(fr >= -INDEX_EPS && fr <= (g.rows - 1) as f64 + INDEX_EPS) {
            continue;
        }
        // Output columns inside this source's longitude range.
        let first = ((g.west_lon_deg - grid.west_lon_deg) / grid.dlon_deg - INDEX_EPS).ceil();
        let last = ((g.east_lon_deg() - grid.west_lon_deg) / grid.dlon_deg + INDEX_EPS).floor();
        let first = first.max(0.0) as usize;
        let last = last.min((grid.cols - 1) as f64);
        if last < 0.0 {
            continue;
        }
        let last = last as usize;
        if first > last {
            continue;
        }
        let Some(span) = line.get_mut(first..=last) else {
            continue;
        };
        for (offset, dst) in span.iter_mut().enumerate() {
            // Unset, or void in a source tried before: this source may have a value.
            if !dst.is_nan() {
                continue;
            }
            let lon = grid.west_lon_deg + (first + offset) as f64 * grid.dlon_deg;
            let fc = (lon - g.west_lon_deg) / g.dlon_deg;
            if !(fc >= -INDEX_EPS && fc <= (g.cols - 1) as f64 + INDEX_EPS) {
                continue;
            }
            *dst = sample(source, fr, fc);
        }
    }
}

/// The source's height at fractional `(row, col)` (inside its grid): the post's value on a
/// post, the triangulated surface elsewhere; canonical `NaN` for voids.
///
/// Indices within [`INDEX_EPS`] of an integer are snapped to it. On a triangle edge (a cell side
/// or the south-west to north-east diagonal) the surface is the straight line between the edge's
/// two posts (both triangles agree there), so a void post off the edge cannot spoil it.
fn sample(source: &Raster, fr: f64, fc: f64) -> f32 {
    let g = &source.grid;
    let (last_row, last_col) = (g.rows - 1, g.cols - 1);
    let at = |r: usize, c: usize| {
        source
            .elevation_m
            .get(r * g.cols + c)
            .copied()
            .unwrap_or(f32::NAN)
    };
    let snap = |f: f64, last: usize| {
        let f = f.clamp(0.0, last as f64);
        let rounded = f.round();
        if (f - rounded).abs() <= INDEX_EPS {
            (rounded, true)
        } else {
            (f, false)
        }
    };
    let (fr, row_exact) = snap(fr, last_row);
    let (fc, col_exact) = snap(fc, last_col);
    // Non-negative and at most `last`: the casts are exact floors.
    let r0 = (fr.floor() as usize).min(last_row.saturating_sub(1));
    let c0 = (fc.floor() as usize).min(last_col.saturating_sub(1));
    let (r1, c1) = ((r0 + 1).min(last_row), (c0 + 1).min(last_col));
    let v = (fr - r0 as f64).clamp(0.0, 1.0);
    let u = (fc - c0 as f64).clamp(0.0, 1.0);
    let lerp = |a: f32, b: f32, t: f64| f64::from(a) + t * (f64::from(b) - f64::from(a));
    let h = match (row_exact, col_exact) {
        (true, true) => f64::from(at(fr as usize, fc as usize)),
        (true, false) => lerp(at(fr as usize, c0), at(fr as usize, c1), u),
        (false, true) => lerp(at(r0, fc as usize), at(r1, fc as usize), v),
        // On the cell's diagonal, between the south-west and north-east posts.
        (false, false) if (u - v).abs() <= INDEX_EPS => lerp(at(r0, c0), at(r1, c1), u),
        // A source cell is read as split south-west to north-east (the source has no
        // triangulation of its own; this one is exact on the diagonal branch above).
        (false, false) => triangulated_height(
            [at(r0, c0), at(r0, c1), at(r1, c0), at(r1, c1)],
            u,
            v,
            Diagonal::SouthWestNorthEast,
        ),
    } as f32;
    if h.is_nan() {
        f32::NAN
    } else {
        h
    }
}
