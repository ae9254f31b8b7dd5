//! Digital Terrain Elevation Data levels 0, 1 and 2 (`.dt0`, `.dt1`, `.dt2`), as specified by
//! MIL-PRF-89020B ("Performance Specification, Digital Terrain Elevation Data").
//!
//! Layout: an 80-byte User Header Label (`UHL1`), a 648-byte Data Set Identification record
//! (`DSI`), a 2700-byte Accuracy Description record (`ACC`), then one data record per longitude
//! line, west to east: the `0xAA` sentinel, a 3-byte data block count, 2-byte longitude and
//! latitude counts, the line's elevations as big-endian *signed-magnitude* 16-bit metres, south
//! to north, and a 4-byte checksum, the unsigned sum of every byte of the record before it.
//! `-32767` (`0xFFFF`) is a void.
//!
//! The origin (south-west post, `DDDMMSSH`), the intervals (tenths of arc-seconds; longitude
//! intervals widen above 50 degrees of latitude) and the counts come from the UHL. Limits: every
//! checksum is verified and a mismatch is an error; the DSI and ACC records are checked for
//! their sentinels only; bytes after the last data record are ignored.

use std::path::Path;

use cig_terrain::raster::{GeoGrid, Raster};

use super::{check_grid, finish, ImportError, SourceFormat, SourceInfo};

/// Length of the User Header Label.
pub const UHL_LEN: usize = 80;
/// Length of the Data Set Identification record.
pub const DSI_LEN: usize = 648;
/// Length of the Accuracy Description record.
pub const ACC_LEN: usize = 2700;
/// Offset of the first data record.
pub const DATA_OFFSET: usize = UHL_LEN + DSI_LEN + ACC_LEN;
/// First byte of every data record.
pub const DATA_SENTINEL: u8 = 0xAA;
/// The void elevation (`0xFFFF` in signed magnitude).
pub const DTED_VOID: i16 = -32767;

/// Decodes a big-endian signed-magnitude 16-bit value (bit 15 is the sign).
pub fn signed_magnitude(hi: u8, lo: u8) -> i16 {
    let raw = u16::from_be_bytes([hi, lo]);
    // The magnitude is at most 0x7FFF, which fits an i16 whichever the sign.
    let magnitude = (raw & 0x7FFF) as i16;
    if raw & 0x8000 != 0 {
        -magnitude
    } else {
        magnitude
    }
}

/// Encodes a value as big-endian signed magnitude (`i16::MIN` saturates to `-32767`).
pub fn to_signed_magnitude(value: i16) -> [u8; 2] {
    let magnitude = value.unsigned_abs().min(0x7FFF);
    let raw = if value < 0 {
        magnitude | 0x8000
    } else {
        magnitude
    };
    raw.to_be_bytes()
}

/// The header fields [`read_dted_bytes`] uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DtedHeader {
    /// Longitude of the south-west post, degrees.
    pub origin_lon_deg: f64,
    /// Latitude of the south-west post, degrees.
    pub origin_lat_deg: f64,
    /// Longitude interval, tenths of arc-seconds.
    pub lon_interval_tenth_arcsec: u32,
    /// Latitude interval, tenths of arc-seconds.
    pub lat_interval_tenth_arcsec: u32,
    /// Number of longitude lines (data records, columns).
    pub lon_lines: usize,
    /// Number of latitude points per line (rows).
    pub lat_points: usize,
}

/// Parses a fixed-width decimal field (spaces around the digits are allowed).
fn field_uint(bytes: &[u8]) -> Option<u32> {
    let text = std::str::from_utf8(bytes).ok()?.trim();
    if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    text.parse().ok()
}

/// Parses an 8-character `DDDMMSSH` angle into degrees.
fn field_angle(bytes: &[u8], positive: u8, negative: u8) -> Option<f64> {
    let degrees = field_uint(bytes.get(0..3)?)?;
    let minutes = field_uint(bytes.get(3..5)?)?;
    let seconds = field_uint(bytes.get(5..7)?)?;
    if minutes >= 60 || seconds >= 60 {
        return None;
    }
    let value = f64::from(degrees) + f64::from(minutes) / 60.0 + f64::from(seconds) / 3600.0;
    match bytes.get(7)?.to_ascii_uppercase() {
        h if h == positive => Some(value),
        h if h == negative => Some(-value),
        _ => None,
    }
}

/// Parses the User Header Label (the first 80 bytes).
pub fn parse_uhl(uhl: &[u8], path: &Path) -> Result<DtedHeader, ImportError> {
    let invalid = |reason: &str| ImportError::InvalidHeader {
        format: SourceFormat::Dted,
        reason: reason.to_string(),
        path: path.to_path_buf(),
    };
    let head = uhl.get(..uhl.len().min(4)).unwrap_or_default();
    if !b"UHL1".starts_with(head) {
        return Err(ImportError::BadMagic {
            format: SourceFormat::Dted,
            reason: "the file does not start with \"UHL1\"".to_string(),
            path: path.to_path_buf(),
        });
    }
    if uhl.len() < UHL_LEN {
        return Err(ImportError::Truncated {
            what: "DTED user header label".to_string(),
            expected: UHL_LEN as u64,
            found: uhl.len() as u64,
            path: path.to_path_buf(),
        });
    }
    let origin_lon_deg = uhl
        .get(4..12)
        .and_then(|f| field_angle(f, b'E', b'W'))
        .ok_or_else(|| invalid("longitude of origin is not DDDMMSSH"))?;
    let origin_lat_deg = uhl
        .get(12..20)
        .and_then(|f| field_angle(f, b'N', b'S'))
        .ok_or_else(|| invalid("latitude of origin is not DDDMMSSH"))?;
    let lon_interval = uhl
        .get(20..24)
        .and_then(field_uint)
        .filter(|&v| v > 0)
        .ok_or_else(|| invalid("longitude interval is not a positive number"))?;
    let lat_interval = uhl
        .get(24..28)
        .and_then(field_uint)
        .filter(|&v| v > 0)
        .ok_or_else(|| invalid("latitude interval is not a positive number"))?;
    let lon_lines = uhl
        .get(47..51)
        .and_then(field_uint)
        .filter(|&v| v > 0)
        .ok_or_else(|| invalid("number of longitude lines is not a positive number"))?;
    let lat_points = uhl
        .get(51..55)
        .and_then(field_uint)
        .filter(|&v| v > 0)
        .ok_or_else(|| invalid("number of latitude points is not a positive number"))?;
    Ok(DtedHeader {
        origin_lon_deg,
        origin_lat_deg,
        lon_interval_tenth_arcsec: lon_interval,
        lat_interval_tenth_arcsec: lat_interval,
        // Four decimal digits at most: these fit any usize.
        lon_lines: lon_lines as usize,
        lat_points: lat_points as usize,
    })
}

/// Reads a DTED file from its bytes; `name` names the file in errors and in the [`SourceInfo`].
pub fn read_dted_bytes(
    bytes: &[u8],
    name: impl AsRef<Path>,
) -> Result<(Raster, SourceInfo), ImportError> {
    let path = name.as_ref();
    let header = parse_uhl(bytes, path)?;
    if bytes.len() < DATA_OFFSET {
        return Err(ImportError::Truncated {
            what: "DTED header records (UHL, DSI, ACC)".to_string(),
            expected: DATA_OFFSET as u64,
            found: bytes.len() as u64,
            path: path.to_path_buf(),
        });
    }
    for (offset, magic, what) in [(UHL_LEN, b"DSI", "DSI"), (UHL_LEN + DSI_LEN, b"ACC", "ACC")] {
        if bytes.get(offset..offset + 3) != Some(magic.as_slice()) {
            return Err(ImportError::BadMagic {
                format: SourceFormat::Dted,
                reason: format!("no \"{what}\" record at byte {offset}"),
                path: path.to_path_buf(),
            });
        }
    }

    let rows = header.lat_points;
    let cols = header.lon_lines;
    let grid = GeoGrid {
        south_lat_deg: header.origin_lat_deg,
        west_lon_deg: header.origin_lon_deg,
        dlat_deg: f64::from(header.lat_interval_tenth_arcsec) / 36_000.0,
        dlon_deg: f64::from(header.lon_interval_tenth_arcsec) / 36_000.0,
        rows,
        cols,
    };
    check_grid(&grid, SourceFormat::Dted, path)?;

    // rows and cols have at most four digits: none of this can overflow.
    let record_len = 12 + 2 * rows;
    let data_len = bytes.len() - DATA_OFFSET;
    let complete_records = data_len / record_len;
    if complete_records < cols {
        return Err(ImportError::Truncated {
            what: format!("DTED data record {complete_records}"),
            expected: record_len as u64,
            found: (data_len % record_len) as u64,
            path: path.to_path_buf(),
        });
    }

    let mut elevation_m = vec![f32::NAN; rows * cols];
    let records = bytes
        .get(DATA_OFFSET..)
        .unwrap_or_default()
        .chunks_exact(record_len)
        .take(cols);
    for (col, record) in records.enumerate() {
        let (body, checksum) = record.split_at(record_len - 4);
        if body.first() != Some(&DATA_SENTINEL) {
            return Err(ImportError::Corrupt {
                format: SourceFormat::Dted,
                reason: format!(
                    "data record {col} starts with {:#04x}, not the 0xaa sentinel",
                    body.first().copied().unwrap_or_default()
                ),
                path: path.to_path_buf(),
            });
        }
        let computed = body
            .iter()
            .fold(0u32, |sum, &b| sum.wrapping_add(u32::from(b)));
        let stored = checksum
            .try_into()
            .map(u32::from_be_bytes)
            .unwrap_or_default();
        if computed != stored {
            return Err(ImportError::Checksum {
                record: col,
                stored,
                computed,
                path: path.to_path_buf(),
            });
        }
        let heights = body.get(8..).unwrap_or_default().chunks_exact(2);
        for (row, pair) in heights.enumerate() {
            let (Some(&hi), Some(&lo)) = (pair.first(), pair.get(1)) else {
                continue;
            };
            let h = signed_magnitude(hi, lo);
            if let Some(dst) = elevation_m.get_mut(row * cols + col) {
                *dst = if h == DTED_VOID {
                    f32::NAN
                } else {
                    f32::from(h)
                };
            }
        }
    }
    Ok(finish(grid, elevation_m, SourceFormat::Dted, path, None))
}
