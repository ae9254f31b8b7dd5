//! Resampling of UTM rasters onto a geographic lattice, done once at import.
//!
//! The geographic lattice has the source's spacing converted to degrees at the centre latitude
//! of the footprint (`spacing_m / metres per degree`) and covers the whole footprint (its
//! bounding box in latitude and longitude). Each geographic post is projected into the source's
//! UTM zone with [`cig_geo::utm::geodetic_to_utm`] and interpolated bilinearly between the four
//! source posts around it; posts outside the source footprint, and posts whose interpolation
//! touches a void, are `NaN`. Limits: WGS84 UTM zones only (EPSG 326zz/327zz); the output is
//! refused above [`super::MAX_POSTS`] posts.

use std::path::Path;

use cig_geo::utm::{geodetic_to_utm, utm_to_geodetic, UtmZone};
use cig_terrain::raster::GeoGrid;
use rayon::prelude::*;

use super::{check_post_count, ImportError, SourceFormat};

/// A regular UTM lattice of posts: post `(row, col)` lies at
/// `easting = west_easting_m + col * de_m`, `northing = south_northing_m + row * dn_m`, row 0 at
/// the south.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UtmGrid {
    pub west_easting_m: f64,
    pub south_northing_m: f64,
    /// Post spacing eastwards, metres (> 0).
    pub de_m: f64,
    /// Post spacing northwards, metres (> 0).
    pub dn_m: f64,
    pub rows: usize,
    pub cols: usize,
}

/// Bilinear interpolation in a south-first row-major lattice at fractional `(row, col)`;
/// `NaN` outside the lattice (beyond a 1e-9 tolerance) or when a corner with weight is void.
pub fn bilinear(values: &[f32], rows: usize, cols: usize, row: f64, col: f64) -> f32 {
    let eps = 1e-9;
    let (last_row, last_col) = (rows.saturating_sub(1) as f64, cols.saturating_sub(1) as f64);
    if rows == 0
        || cols == 0
        || !(row >= -eps && col >= -eps && row <= last_row + eps && col <= last_col + eps)
    {
        return f32::NAN;
    }
    // Snap to posts so that a post's neighbours with zero weight cannot spoil it.
    let snap = |f: f64, last: f64| {
        let f = f.clamp(0.0, last);
        if (f - f.round()).abs() <= eps {
            f.round()
        } else {
            f
        }
    };
    let (row, col) = (snap(row, last_row), snap(col, last_col));
    // In range and non-negative: the casts are exact floors.
    let r0 = (row.floor() as usize).min(rows.saturating_sub(2));
    let c0 = (col.floor() as usize).min(cols.saturating_sub(2));
    let (r1, c1) = ((r0 + 1).min(rows - 1), (c0 + 1).min(cols - 1));
    let (v, u) = (
        (row - r0 as f64).clamp(0.0, 1.0),
        (col - c0 as f64).clamp(0.0, 1.0),
    );
    let corners = [
        (r0, c0, (1.0 - u) * (1.0 - v)),
        (r0, c1, u * (1.0 - v)),
        (r1, c0, (1.0 - u) * v),
        (r1, c1, u * v),
    ];
    let mut sum = 0.0f64;
    for (r, c, weight) in corners {
        if weight <= 0.0 {
            continue;
        }
        match values.get(r * cols + c) {
            Some(h) if !h.is_nan() => sum += weight * f64::from(*h),
            _ => return f32::NAN,
        }
    }
    sum as f32
}

/// Resamples a UTM raster (south-first heights on `source`) onto a geographic lattice.
pub fn resample_to_geographic(
    source: &UtmGrid,
    values: &[f32],
    zone: UtmZone,
    path: &Path,
) -> Result<(GeoGrid, Vec<f32>), ImportError> {
    let invalid = |reason: String| ImportError::InvalidHeader {
        format: SourceFormat::GeoTiff,
        reason,
        path: path.to_path_buf(),
    };
    let UtmGrid {
        west_easting_m: e0,
        south_northing_m: n0,
        de_m,
        dn_m,
        rows,
        cols,
    } = *source;
    if rows == 0 || cols == 0 || values.len() < rows.saturating_mul(cols) {
        return Err(invalid(format!(
            "empty UTM raster of {rows} x {cols} posts"
        )));
    }
    let e1 = e0 + (cols - 1) as f64 * de_m;
    let n1 = n0 + (rows - 1) as f64 * dn_m;
    // Beyond these the transverse Mercator series are meaningless.
    if !(e0.is_finite() && e1.is_finite() && n0.is_finite() && n1.is_finite())
        || e0 < -2.0e6
        || e1 > 3.0e6
        || n0 < -1.0e7
        || n1 > 2.0e7
        || !(de_m > 0.0 && dn_m > 0.0)
    {
        return Err(invalid(format!(
            "UTM footprint eastings {e0} to {e1} m, northings {n0} to {n1} m is not in a zone"
        )));
    }

    // Bounding box of the footprint: sample its boundary densely (edges are curves in lat/lon).
    const STEPS: usize = 64;
    let (mut lat_min, mut lat_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut lon_min, mut lon_max) = (f64::INFINITY, f64::NEG_INFINITY);
    for step in 0..=STEPS {
        let t = step as f64 / STEPS as f64;
        let (e, n) = (e0 + t * (e1 - e0), n0 + t * (n1 - n0));
        for (easting, northing) in [(e, n0), (e, n1), (e0, n), (e1, n)] {
            let (lat, lon) = utm_to_geodetic(zone, easting, northing);
            lat_min = lat_min.min(lat);
            lat_max = lat_max.max(lat);
            lon_min = lon_min.min(lon);
            lon_max = lon_max.max(lon);
        }
    }
    let on_globe = lat_min.is_finite()
        && lat_max.is_finite()
        && lon_min.is_finite()
        && lon_max.is_finite()
        && (-90.0..=90.0).contains(&lat_min)
        && (-90.0..=90.0).contains(&lat_max);
    if !on_globe {
        return Err(invalid(format!(
            "UTM footprint eastings {e0} to {e1} m, northings {n0} to {n1} m is not on the globe"
        )));
    }

    let centre_lat = 0.5 * (lat_min + lat_max);
    let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(centre_lat);
    let dlat_deg = dn_m / north_m_per_deg;
    let dlon_deg = de_m / east_m_per_deg;
    let out_rows = ((lat_max - lat_min) / dlat_deg - 1e-9).ceil() + 1.0;
    let out_cols = ((lon_max - lon_min) / dlon_deg - 1e-9).ceil() + 1.0;
    if !(dlat_deg > 0.0 && dlon_deg > 0.0 && out_rows.is_finite() && out_cols.is_finite()) {
        return Err(invalid(format!(
            "UTM spacing {de_m} x {dn_m} m gives no geographic spacing"
        )));
    }
    // `as` saturates: the post-count check catches absurd sizes.
    let (out_rows, out_cols) = (out_rows.max(1.0) as u64, out_cols.max(1.0) as u64);
    check_post_count(out_rows, out_cols, path)?;
    let grid = GeoGrid {
        south_lat_deg: lat_min,
        west_lon_deg: lon_min,
        dlat_deg,
        dlon_deg,
        rows: out_rows as usize,
        cols: out_cols as usize,
    };

    let mut out = vec![f32::NAN; grid.rows * grid.cols];
    out.par_chunks_mut(grid.cols)
        .enumerate()
        .for_each(|(row, line)| {
            for (col, dst) in line.iter_mut().enumerate() {
                let (lat, lon) = grid.post_lat_lon_deg(row, col);
                let (e, n) = geodetic_to_utm(zone, lat, lon);
                *dst = bilinear(values, rows, cols, (n - n0) / dn_m, (e - e0) / de_m);
            }
        });
    tracing::info!(
        path = %path.display(),
        zone = ?zone,
        rows = grid.rows,
        cols = grid.cols,
        "resampled UTM raster onto a geographic lattice"
    );
    Ok((grid, out))
}
