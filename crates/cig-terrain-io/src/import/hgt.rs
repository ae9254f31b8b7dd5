//! SRTM height files (`.hgt`), as distributed by NASA/USGS for the Shuttle Radar Topography
//! Mission (SRTM "HGT" format, described in the SRTM Topography documentation of USGS EROS).
//!
//! A file is one 1 x 1 degree tile of big-endian signed 16-bit heights in metres (EGM96), north
//! row first, west column first, with `-32768` for voids. Its size gives the resolution:
//! 1201 x 1201 posts (3 arc-second) or 3601 x 3601 (1 arc-second); the tile's south-west corner
//! comes from the file name only (`N35W122.hgt`, case-insensitive, anything may follow the first
//! seven characters, e.g. `N35W122.SRTMGL1.hgt`). Limits: no other sizes (SRTM30 and the
//! compressed `.hgt.zip` distribution are not read: unzip first).

use std::path::Path;

use cig_terrain::raster::{GeoGrid, Raster};

use super::{check_grid, finish, ImportError, SourceFormat, SourceInfo};

/// The SRTM void marker.
pub const HGT_VOID: i16 = -32768;

/// Parses the south-west corner `(lat_deg, lon_deg)` from an SRTM file name such as
/// `N35W122.hgt` or `s09e033.SRTMGL1.hgt`.
pub fn corner_from_file_name(path: &Path) -> Option<(i32, i32)> {
    let name = path.file_name()?.to_str()?.as_bytes();
    let head = name.get(..7)?;
    let lat_sign = match head.first()?.to_ascii_uppercase() {
        b'N' => 1,
        b'S' => -1,
        _ => return None,
    };
    let lon_sign = match head.get(3)?.to_ascii_uppercase() {
        b'E' => 1,
        b'W' => -1,
        _ => return None,
    };
    let lat = digits(head.get(1..3)?)?;
    let lon = digits(head.get(4..7)?)?;
    let (lat, lon) = (lat_sign * lat, lon_sign * lon);
    ((-90..90).contains(&lat) && (-180..180).contains(&lon)).then_some((lat, lon))
}

fn digits(bytes: &[u8]) -> Option<i32> {
    bytes.iter().try_fold(0i32, |acc, &b| {
        b.is_ascii_digit().then(|| acc * 10 + i32::from(b - b'0'))
    })
}

/// Reads an SRTM tile from its bytes; `file_name` gives the tile's corner (and names the file in
/// errors).
pub fn read_hgt_bytes(
    bytes: &[u8],
    file_name: impl AsRef<Path>,
) -> Result<(Raster, SourceInfo), ImportError> {
    let path = file_name.as_ref();
    let posts_per_side: usize = match bytes.len() {
        2_884_802 => 1201,
        25_934_402 => 3601,
        size => {
            return Err(ImportError::HgtSize {
                size: size as u64,
                path: path.to_path_buf(),
            })
        }
    };
    let (lat, lon) = corner_from_file_name(path).ok_or_else(|| ImportError::HgtName {
        path: path.to_path_buf(),
    })?;
    let n = posts_per_side;
    let spacing_deg = 1.0 / (n - 1) as f64;
    let grid = GeoGrid {
        south_lat_deg: f64::from(lat),
        west_lon_deg: f64::from(lon),
        dlat_deg: spacing_deg,
        dlon_deg: spacing_deg,
        rows: n,
        cols: n,
    };
    check_grid(&grid, SourceFormat::SrtmHgt, path)?;
    let mut elevation_m = vec![f32::NAN; n * n];
    // File row r (north first) is raster row n - 1 - r.
    for (file_row, line) in bytes.chunks_exact(2 * n).enumerate() {
        let Some(out_row) = n.checked_sub(file_row + 1) else {
            break;
        };
        let Some(out) = elevation_m.get_mut(out_row * n..(out_row + 1) * n) else {
            break;
        };
        for (dst, pair) in out.iter_mut().zip(line.chunks_exact(2)) {
            if let &[hi, lo] = pair {
                let h = i16::from_be_bytes([hi, lo]);
                *dst = if h == HGT_VOID {
                    f32::NAN
                } else {
                    f32::from(h)
                };
            }
        }
    }
    Ok(finish(grid, elevation_m, SourceFormat::SrtmHgt, path, None))
}
