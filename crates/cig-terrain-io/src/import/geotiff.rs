//! GeoTIFF elevation rasters (`.tif`, `.tiff`): TIFF 6.0 decoded by the `tiff` crate, with the
//! georeferencing of the OGC GeoTIFF 1.1 standard (OGC 19-008r4).
//!
//! Read: one-band images of 8/16/32/64-bit unsigned or signed integers or 32/64-bit floats,
//! strips or tiles, uncompressed, LZW, Deflate or PackBits, with or without a predictor;
//! classic TIFF and BigTIFF; the first image of the file only. Georeferencing comes from the
//! GeoKeyDirectoryTag (34735) and either ModelPixelScaleTag (33550) with ModelTiepointTag (33922)
//! or a ModelTransformationTag (34264) without rotation. GTRasterTypeGeoKey (1025) PixelIsArea
//! (the default) puts the posts at pixel centres, PixelIsPoint at the tie points. Voids are the
//! GDAL_NODATA tag's value (42113, ASCII) and any NaN.
//!
//! Coordinate systems: geographic WGS84 (GeographicTypeGeoKey 4326; 4269 NAD83 and 4258 ETRS89
//! are read as WGS84 with a warning, as is a user-defined geographic system on the WGS84 datum),
//! and UTM on WGS84 (ProjectedCSTypeGeoKey 326zz/327zz), which is resampled once onto a
//! geographic lattice (see [`super::utm`]). Any other system is an
//! [`ImportError::UnsupportedProjection`] naming its EPSG code. Vertical datum keys, scale and
//! offset metadata are ignored: heights are taken as metres above the EGM96 geoid.

use std::fs::File;
use std::io::{BufReader, Cursor, Read, Seek, SeekFrom};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use cig_geo::utm::UtmZone;
use cig_terrain::raster::{GeoGrid, Raster};
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::{ColorType, TiffError};

use super::utm::{resample_to_geographic, UtmGrid};
use super::{
    check_grid, check_post_count, finish, flip_rows, io_error, ImportError, SourceFormat,
    SourceInfo,
};

/// GeoKey ids this reader understands.
pub mod geokey {
    pub const GT_MODEL_TYPE: u16 = 1024;
    pub const GT_RASTER_TYPE: u16 = 1025;
    pub const GEOGRAPHIC_TYPE: u16 = 2048;
    pub const GEOG_GEODETIC_DATUM: u16 = 2050;
    pub const GEOG_ANGULAR_UNITS: u16 = 2054;
    pub const PROJECTED_CS_TYPE: u16 = 3072;
    pub const PROJ_LINEAR_UNITS: u16 = 3076;
    /// GTModelTypeGeoKey: projected.
    pub const MODEL_PROJECTED: u16 = 1;
    /// GTModelTypeGeoKey: geographic.
    pub const MODEL_GEOGRAPHIC: u16 = 2;
    /// GTRasterTypeGeoKey: PixelIsArea.
    pub const RASTER_PIXEL_IS_AREA: u16 = 1;
    /// GTRasterTypeGeoKey: PixelIsPoint.
    pub const RASTER_PIXEL_IS_POINT: u16 = 2;
    /// "User-defined" in every code key.
    pub const USER_DEFINED: u16 = 32767;
}

/// Compressed TIFF data never expands more than this (Deflate tops out near 1032:1, TIFF LZW
/// near 1400:1): a larger decoded image than `file length x ratio` is refused before allocating.
const MAX_EXPANSION: u64 = 4096;

/// True when the bytes start with a TIFF or BigTIFF byte-order mark.
pub fn has_tiff_magic(head: &[u8]) -> bool {
    matches!(
        head.get(..4),
        Some(b"II*\0") | Some(b"MM\0*") | Some(b"II+\0") | Some(b"MM\0+")
    )
}

/// Reads a GeoTIFF from its bytes; `name` names the file in errors and in the [`SourceInfo`].
pub fn read_geotiff_bytes(
    bytes: &[u8],
    name: impl AsRef<Path>,
) -> Result<(Raster, SourceInfo), ImportError> {
    read_geotiff(Cursor::new(bytes), bytes.len() as u64, name.as_ref())
}

/// Reads a GeoTIFF file, streaming it from disk.
pub(crate) fn read_geotiff_file(path: &Path) -> Result<(Raster, SourceInfo), ImportError> {
    let file = File::open(path).map_err(|e| io_error(path, e))?;
    let len = file.metadata().map_err(|e| io_error(path, e))?.len();
    read_geotiff(BufReader::new(file), len, path)
}

fn read_geotiff<R: Read + Seek>(
    mut reader: R,
    file_len: u64,
    path: &Path,
) -> Result<(Raster, SourceInfo), ImportError> {
    let mut head = Vec::with_capacity(4);
    (&mut reader)
        .take(4)
        .read_to_end(&mut head)
        .map_err(|e| io_error(path, e))?;
    if !has_tiff_magic(&head) {
        return Err(ImportError::BadMagic {
            format: SourceFormat::GeoTiff,
            reason: "no TIFF byte-order mark \"II*\" or \"MM*\" at the start".to_string(),
            path: path.to_path_buf(),
        });
    }
    reader
        .seek(SeekFrom::Start(0))
        .map_err(|e| io_error(path, e))?;
    // The tiff crate is fuzzed upstream, but a decoder bug on hostile input must not bring the
    // importer down: a panic inside it becomes an error (our own code does not panic).
    catch_unwind(AssertUnwindSafe(|| decode(reader, file_len, path))).unwrap_or_else(|_| {
        Err(ImportError::Tiff {
            reason: "the TIFF decoder failed on malformed data".to_string(),
            path: path.to_path_buf(),
        })
    })
}

/// A `tiff` error as a one-line reason.
pub(crate) fn describe(error: TiffError) -> String {
    match error {
        TiffError::IoError(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the file ends inside the data it declares".to_string()
        }
        TiffError::LimitsExceeded => {
            "the image declares more data than the file can hold".to_string()
        }
        other => other.to_string(),
    }
}

/// Where the coordinate system puts the posts.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Crs {
    Geographic,
    Utm { zone: UtmZone, epsg: u32 },
}

#[derive(Default)]
struct GeoKeys {
    model_type: Option<u16>,
    raster_type: Option<u16>,
    geographic_type: Option<u16>,
    geodetic_datum: Option<u16>,
    angular_units: Option<u16>,
    projected_type: Option<u16>,
    linear_units: Option<u16>,
}

/// Model coordinates of post `(col, row)` (TIFF order, row 0 first in the file):
/// `x = x0 + col * dx`, `y = y0 + row * dy`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Affine {
    pub x0: f64,
    pub dx: f64,
    pub y0: f64,
    pub dy: f64,
}

/// A GeoTIFF's georeference: its coordinate system and where its pixels are in it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Georeference {
    pub crs: Crs,
    /// Model coordinates of the sample point of pixel `(col, row)`: the pixel's centre for
    /// PixelIsArea (the default), the tie point itself for PixelIsPoint.
    pub affine: Affine,
}

/// Reads the GeoKeys (coordinate system, raster type) and the pixel-to-model transformation of
/// the decoder's image; shared by the DEM and the imagery readers.
pub(crate) fn read_georeference<R: Read + Seek>(
    decoder: &mut Decoder<R>,
    path: &Path,
) -> Result<Georeference, ImportError> {
    let tiff_err = |e: TiffError| ImportError::Tiff {
        reason: describe(e),
        path: path.to_path_buf(),
    };
    let invalid = |reason: String| ImportError::InvalidHeader {
        format: SourceFormat::GeoTiff,
        reason,
        path: path.to_path_buf(),
    };
    let directory = decoder
        .find_tag(Tag::GeoKeyDirectoryTag)
        .map_err(tiff_err)?
        .map(|v| v.into_u16_vec())
        .transpose()
        .map_err(tiff_err)?
        .ok_or_else(|| invalid("no GeoKeyDirectoryTag (34735): not a GeoTIFF".to_string()))?;
    let keys = parse_geokeys(&directory).map_err(invalid)?;
    let crs = coordinate_system(&keys, path)?;
    let pixel_is_point = match keys.raster_type {
        None | Some(geokey::RASTER_PIXEL_IS_AREA) => false,
        Some(geokey::RASTER_PIXEL_IS_POINT) => true,
        Some(other) => return Err(invalid(format!("GTRasterTypeGeoKey {other} is unknown"))),
    };
    let affine = georeferencing(decoder, pixel_is_point, path)?;
    Ok(Georeference { crs, affine })
}

fn decode<R: Read + Seek>(
    reader: R,
    file_len: u64,
    path: &Path,
) -> Result<(Raster, SourceInfo), ImportError> {
    let tiff_err = |e: TiffError| ImportError::Tiff {
        reason: describe(e),
        path: path.to_path_buf(),
    };
    let invalid = |reason: String| ImportError::InvalidHeader {
        format: SourceFormat::GeoTiff,
        reason,
        path: path.to_path_buf(),
    };
    let unsupported = |reason: String| ImportError::Unsupported {
        format: SourceFormat::GeoTiff,
        reason,
        path: path.to_path_buf(),
    };

    let mut limits = Limits::default();
    let budget = file_len
        .saturating_mul(MAX_EXPANSION)
        .clamp(16 << 20, super::MAX_POSTS.saturating_mul(8));
    limits.decoding_buffer_size = usize::try_from(budget).unwrap_or(usize::MAX);
    let mut decoder = Decoder::new(reader).map_err(tiff_err)?.with_limits(limits);

    let (width, height) = decoder.dimensions().map_err(tiff_err)?;
    check_post_count(u64::from(height), u64::from(width), path)?;
    if width == 0 || height == 0 {
        return Err(invalid(format!("empty image of {width} x {height} pixels")));
    }
    match decoder.colortype().map_err(tiff_err)? {
        ColorType::Gray(_) => {}
        other => {
            return Err(unsupported(format!(
                "colour type {other:?}: an elevation raster has one band"
            )))
        }
    }

    let Georeference { crs, affine } = read_georeference(&mut decoder, path)?;
    let nodata =
        match decoder.find_tag(Tag::GdalNodata).map_err(tiff_err)? {
            None => None,
            Some(value) => {
                let text = value.into_string().map_err(tiff_err)?;
                let text = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
                Some(text.parse::<f64>().map_err(|_| {
                    invalid(format!("GDAL_NODATA value \"{text}\" is not a number"))
                })?)
            }
        };

    // Both at most MAX_POSTS (checked above): no overflow.
    let (cols, rows) = (width as usize, height as usize);
    let data = decoder.read_image().map_err(tiff_err)?;
    let mut values = heights(data, nodata);
    if values.len() < rows * cols {
        return Err(ImportError::Corrupt {
            format: SourceFormat::GeoTiff,
            reason: format!(
                "decoded {} samples for {cols} x {rows} pixels",
                values.len()
            ),
            path: path.to_path_buf(),
        });
    }
    values.truncate(rows * cols);

    // Normalise to west-to-east columns and south-to-north rows.
    let Affine { x0, dx, y0, dy } = affine;
    let (west, step_x) = if dx > 0.0 {
        (x0, dx)
    } else {
        for row in values.chunks_exact_mut(cols) {
            row.reverse();
        }
        (x0 + (cols - 1) as f64 * dx, -dx)
    };
    let (south, step_y) = if dy > 0.0 {
        (y0, dy)
    } else {
        flip_rows(&mut values, cols);
        (y0 + (rows - 1) as f64 * dy, -dy)
    };

    match crs {
        Crs::Geographic => {
            let grid = GeoGrid {
                south_lat_deg: south,
                west_lon_deg: west,
                dlat_deg: step_y,
                dlon_deg: step_x,
                rows,
                cols,
            };
            check_grid(&grid, SourceFormat::GeoTiff, path)?;
            Ok(finish(grid, values, SourceFormat::GeoTiff, path, None))
        }
        Crs::Utm { zone, epsg } => {
            let source = UtmGrid {
                west_easting_m: west,
                south_northing_m: south,
                de_m: step_x,
                dn_m: step_y,
                rows,
                cols,
            };
            let (grid, values) = resample_to_geographic(&source, &values, zone, path)?;
            check_grid(&grid, SourceFormat::GeoTiff, path)?;
            Ok(finish(
                grid,
                values,
                SourceFormat::GeoTiff,
                path,
                Some(epsg),
            ))
        }
    }
}

fn parse_geokeys(directory: &[u16]) -> Result<GeoKeys, String> {
    let [version, _revision, _minor, count, entries @ ..] = directory else {
        return Err(format!(
            "GeoKeyDirectoryTag holds {} values, fewer than its 4-value header",
            directory.len()
        ));
    };
    if *version != 1 {
        return Err(format!("GeoKeyDirectoryTag version {version} is unknown"));
    }
    let mut keys = GeoKeys::default();
    for k in 0..usize::from(*count) {
        let Some(&[id, location, _count, value]) = entries.get(4 * k..4 * k + 4) else {
            return Err(format!(
                "GeoKeyDirectoryTag declares {count} keys but holds {}",
                entries.len() / 4
            ));
        };
        if location != 0 {
            // Stored in GeoDoubleParamsTag or GeoAsciiParamsTag: no key we use lives there.
            continue;
        }
        let slot = match id {
            geokey::GT_MODEL_TYPE => &mut keys.model_type,
            geokey::GT_RASTER_TYPE => &mut keys.raster_type,
            geokey::GEOGRAPHIC_TYPE => &mut keys.geographic_type,
            geokey::GEOG_GEODETIC_DATUM => &mut keys.geodetic_datum,
            geokey::GEOG_ANGULAR_UNITS => &mut keys.angular_units,
            geokey::PROJECTED_CS_TYPE => &mut keys.projected_type,
            geokey::PROJ_LINEAR_UNITS => &mut keys.linear_units,
            _ => continue,
        };
        *slot = Some(value);
    }
    Ok(keys)
}

fn coordinate_system(keys: &GeoKeys, path: &Path) -> Result<Crs, ImportError> {
    let unsupported_crs = |epsg: Option<u16>, crs: String| ImportError::UnsupportedProjection {
        epsg: epsg.map(u32::from),
        crs,
        path: path.to_path_buf(),
    };
    let unsupported = |reason: String| ImportError::Unsupported {
        format: SourceFormat::GeoTiff,
        reason,
        path: path.to_path_buf(),
    };
    let model = match keys.model_type {
        Some(model) => model,
        None if keys.projected_type.is_some() => geokey::MODEL_PROJECTED,
        None => geokey::MODEL_GEOGRAPHIC,
    };
    match model {
        geokey::MODEL_GEOGRAPHIC => {
            match keys.angular_units {
                None | Some(9102) => {}
                Some(unit) => {
                    return Err(unsupported(format!(
                        "angular unit EPSG:{unit} (only degrees, EPSG:9102)"
                    )))
                }
            }
            match keys.geographic_type {
                Some(4326) => {}
                Some(code @ (4269 | 4258)) => tracing::warn!(
                    path = %path.display(),
                    "geographic CRS EPSG:{code} is read as WGS84 (EPSG:4326); they differ by \
                     less than a metre"
                ),
                None | Some(geokey::USER_DEFINED) if keys.geodetic_datum == Some(6326) => {
                    tracing::warn!(
                        path = %path.display(),
                        "user-defined geographic CRS on the WGS84 datum is read as EPSG:4326"
                    )
                }
                None | Some(geokey::USER_DEFINED) => {
                    return Err(unsupported_crs(
                        None,
                        "a geographic CRS without an EPSG code or WGS84 datum".to_string(),
                    ))
                }
                Some(code) => return Err(unsupported_crs(Some(code), format!("EPSG:{code}"))),
            }
            Ok(Crs::Geographic)
        }
        geokey::MODEL_PROJECTED => {
            let code = match keys.projected_type {
                None | Some(geokey::USER_DEFINED) => {
                    return Err(unsupported_crs(
                        None,
                        "a user-defined projected CRS".to_string(),
                    ))
                }
                Some(code) => code,
            };
            let epsg = u32::from(code);
            let zone = UtmZone::from_epsg(epsg)
                .ok_or_else(|| unsupported_crs(Some(code), format!("EPSG:{code}")))?;
            match keys.linear_units {
                None | Some(9001) => {}
                Some(unit) => {
                    return Err(unsupported(format!(
                        "linear unit EPSG:{unit} (only metres, EPSG:9001)"
                    )))
                }
            }
            Ok(Crs::Utm { zone, epsg })
        }
        other => Err(unsupported_crs(
            None,
            format!("GTModelTypeGeoKey {other} (geocentric or unknown)"),
        )),
    }
}

fn georeferencing<R: Read + Seek>(
    decoder: &mut Decoder<R>,
    pixel_is_point: bool,
    path: &Path,
) -> Result<Affine, ImportError> {
    let invalid = |reason: String| ImportError::InvalidHeader {
        format: SourceFormat::GeoTiff,
        reason,
        path: path.to_path_buf(),
    };
    let mut f64_tag = |tag: Tag| -> Result<Option<Vec<f64>>, ImportError> {
        decoder
            .find_tag(tag)
            .and_then(|v| v.map(|v| v.into_f64_vec()).transpose())
            .map_err(|e| ImportError::Tiff {
                reason: describe(e),
                path: path.to_path_buf(),
            })
    };
    let scale = f64_tag(Tag::ModelPixelScaleTag)?;
    let tiepoints = f64_tag(Tag::ModelTiepointTag)?;
    let transformation = f64_tag(Tag::ModelTransformationTag)?;
    // Raster-space coordinate of post (0, 0): the centre of the first pixel for PixelIsArea.
    let offset = if pixel_is_point { 0.0 } else { 0.5 };
    let affine = match (
        scale.as_deref(),
        tiepoints.as_deref(),
        transformation.as_deref(),
    ) {
        (Some(&[sx, sy, ..]), Some(&[i, j, _k, x, y, ..]), _) => Affine {
            x0: x + (offset - i) * sx,
            dx: sx,
            y0: y - (offset - j) * sy,
            dy: -sy,
        },
        (_, _, Some(&[a, b, _, d, e, f, _, h, ..])) => {
            if b != 0.0 || e != 0.0 {
                return Err(ImportError::Unsupported {
                    format: SourceFormat::GeoTiff,
                    reason: "rotated or sheared ModelTransformationTag".to_string(),
                    path: path.to_path_buf(),
                });
            }
            Affine {
                x0: a * offset + d,
                dx: a,
                y0: f * offset + h,
                dy: f,
            }
        }
        _ => {
            return Err(invalid(
                "no georeferencing: needs ModelPixelScaleTag (33550) and ModelTiepointTag \
                 (33922), or ModelTransformationTag (34264)"
                    .to_string(),
            ))
        }
    };
    let Affine { x0, dx, y0, dy } = affine;
    if !(x0.is_finite() && y0.is_finite() && dx.is_finite() && dy.is_finite())
        || dx == 0.0
        || dy == 0.0
    {
        return Err(invalid(format!(
            "degenerate georeferencing: origin ({x0}, {y0}), pixel size {dx} x {dy}"
        )));
    }
    Ok(affine)
}

/// Converts decoded samples to metres, `NaN` for the no-data value, NaN and infinite samples.
fn heights(data: DecodingResult, nodata: Option<f64>) -> Vec<f32> {
    fn convert<T: Copy>(samples: Vec<T>, nodata: Option<f64>, to_f64: fn(T) -> f64) -> Vec<f32> {
        samples
            .into_iter()
            .map(|sample| {
                let value = to_f64(sample);
                let height_m = value as f32;
                if nodata == Some(value) || !height_m.is_finite() {
                    f32::NAN
                } else {
                    height_m
                }
            })
            .collect()
    }
    match data {
        DecodingResult::U8(v) => convert(v, nodata, f64::from),
        DecodingResult::U16(v) => convert(v, nodata, f64::from),
        DecodingResult::U32(v) => convert(v, nodata, f64::from),
        DecodingResult::U64(v) => convert(v, nodata, |x| x as f64),
        DecodingResult::I8(v) => convert(v, nodata, f64::from),
        DecodingResult::I16(v) => convert(v, nodata, f64::from),
        DecodingResult::I32(v) => convert(v, nodata, f64::from),
        DecodingResult::I64(v) => convert(v, nodata, |x| x as f64),
        DecodingResult::F64(v) => convert(v, nodata, |x| x),
        DecodingResult::F32(v) => {
            // GDAL writes a float32 no-data value with more or fewer digits than the sample:
            // compare in single precision.
            let nodata_f32 = nodata.map(|n| n as f32);
            v.into_iter()
                .map(|h| {
                    if h.is_finite() && Some(h) != nodata_f32 {
                        h
                    } else {
                        f32::NAN
                    }
                })
                .collect()
        }
    }
}
