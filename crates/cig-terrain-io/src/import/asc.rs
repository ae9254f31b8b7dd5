//! ESRI ASCII grids (`.asc`), the "ESRI ASCII raster format" of the ArcGIS documentation (also
//! GDAL's `AAIGrid` driver).
//!
//! A header of `keyword value` lines — `ncols`, `nrows`, `xllcorner` or `xllcenter`,
//! `yllcorner` or `yllcenter`, `cellsize` (or `dx` and `dy`), optionally `NODATA_value` — then
//! `nrows x ncols` numbers, north row first, separated by any white space. With `xllcorner` /
//! `yllcorner` the values are cell centres (posts at half a cell inside the corner); with
//! `xllcenter` / `yllcenter` the first post is at the given point. Limits: coordinates must be
//! geographic degrees (a `.prj` side file is not read; projected coordinates are refused as "not
//! on the globe"); a non-numeric value, a missing or extra value is an error naming its line.

use std::path::Path;

use cig_terrain::raster::{GeoGrid, Raster};

use super::{
    check_grid, check_post_count, finish, flip_rows, ImportError, SourceFormat, SourceInfo,
};

/// True when the bytes start (after white space) with an ESRI ASCII grid keyword.
pub fn looks_like_asc(head: &[u8]) -> bool {
    let start = head
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(head.len());
    let word: Vec<u8> = head
        .get(start..)
        .unwrap_or_default()
        .iter()
        .take(5)
        .map(u8::to_ascii_lowercase)
        .collect();
    word == b"ncols" || word == b"nrows"
}

#[derive(Default)]
struct Header {
    ncols: Option<u64>,
    nrows: Option<u64>,
    x_ll: Option<(f64, bool)>,
    y_ll: Option<(f64, bool)>,
    cellsize: Option<f64>,
    dx: Option<f64>,
    dy: Option<f64>,
    nodata: Option<f64>,
}

fn is_number_start(token: &str) -> bool {
    token
        .bytes()
        .next()
        .is_some_and(|b| b.is_ascii_digit() || b == b'-' || b == b'+' || b == b'.')
        || token.eq_ignore_ascii_case("nan")
}

/// Reads an ESRI ASCII grid from its text; `name` names the file in errors and in the
/// [`SourceInfo`].
pub fn read_asc_str(
    text: &str,
    name: impl AsRef<Path>,
) -> Result<(Raster, SourceInfo), ImportError> {
    let path = name.as_ref();
    let parse_error = |line: usize, reason: String| ImportError::Parse {
        line,
        reason,
        path: path.to_path_buf(),
    };

    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l)).peekable();
    let mut header = Header::default();
    // Header: keyword lines until the first line that starts with a number.
    while let Some(&(line_no, line)) = lines.peek() {
        let mut tokens = line.split_whitespace();
        let Some(key) = tokens.next() else {
            lines.next();
            continue;
        };
        if is_number_start(key) {
            break;
        }
        lines.next();
        let value_text = tokens.next().ok_or_else(|| {
            parse_error(line_no, format!("header keyword \"{key}\" has no value"))
        })?;
        if let Some(extra) = tokens.next() {
            return Err(parse_error(
                line_no,
                format!("unexpected \"{extra}\" after the header value"),
            ));
        }
        let number = || -> Result<f64, ImportError> {
            value_text
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    parse_error(
                        line_no,
                        format!("value \"{value_text}\" of \"{key}\" is not a finite number"),
                    )
                })
        };
        let count = || -> Result<u64, ImportError> {
            value_text
                .parse::<u64>()
                .ok()
                .filter(|&v| v > 0)
                .ok_or_else(|| {
                    parse_error(
                        line_no,
                        format!("value \"{value_text}\" of \"{key}\" is not a positive integer"),
                    )
                })
        };
        match key.to_ascii_lowercase().as_str() {
            "ncols" => header.ncols = Some(count()?),
            "nrows" => header.nrows = Some(count()?),
            "xllcorner" => header.x_ll = Some((number()?, true)),
            "xllcenter" | "xllcentre" => header.x_ll = Some((number()?, false)),
            "yllcorner" => header.y_ll = Some((number()?, true)),
            "yllcenter" | "yllcentre" => header.y_ll = Some((number()?, false)),
            "cellsize" => header.cellsize = Some(number()?),
            "dx" => header.dx = Some(number()?),
            "dy" => header.dy = Some(number()?),
            "nodata_value" => {
                // Allow "nan" as a no-data value; it matches nothing, NaN values are voids anyway.
                header.nodata = Some(value_text.parse::<f64>().map_err(|_| {
                    parse_error(
                        line_no,
                        format!("value \"{value_text}\" of \"{key}\" is not a number"),
                    )
                })?)
            }
            _ => {
                return Err(parse_error(
                    line_no,
                    format!("unknown header keyword \"{key}\""),
                ))
            }
        }
    }

    let header_line = lines.peek().map_or(text.lines().count(), |&(n, _)| n);
    let missing = |what: &str| parse_error(header_line, format!("the header has no {what}"));
    let ncols = header.ncols.ok_or_else(|| missing("ncols"))?;
    let nrows = header.nrows.ok_or_else(|| missing("nrows"))?;
    let (x_ll, x_corner) = header
        .x_ll
        .ok_or_else(|| missing("xllcorner or xllcenter"))?;
    let (y_ll, y_corner) = header
        .y_ll
        .ok_or_else(|| missing("yllcorner or yllcenter"))?;
    let (dx, dy) = match (header.cellsize, header.dx, header.dy) {
        (Some(c), _, _) => (c, c),
        (None, Some(dx), Some(dy)) => (dx, dy),
        _ => return Err(missing("cellsize (nor dx and dy)")),
    };
    if !(dx > 0.0 && dy > 0.0) {
        return Err(ImportError::InvalidHeader {
            format: SourceFormat::EsriAscii,
            reason: format!("cell size {dx} x {dy} is not positive"),
            path: path.to_path_buf(),
        });
    }
    check_post_count(nrows, ncols, path)?;
    // Both are at most MAX_POSTS: they fit usize.
    let (rows, cols) = (nrows as usize, ncols as usize);
    let grid = GeoGrid {
        south_lat_deg: if y_corner { y_ll + 0.5 * dy } else { y_ll },
        west_lon_deg: if x_corner { x_ll + 0.5 * dx } else { x_ll },
        dlat_deg: dy,
        dlon_deg: dx,
        rows,
        cols,
    };
    check_grid(&grid, SourceFormat::EsriAscii, path)?;

    let expected = rows * cols;
    // Each value takes at least two bytes of text: never reserve more than the text can hold.
    let mut elevation_m = Vec::with_capacity(expected.min(text.len() / 2 + 1));
    let mut last_line = header_line;
    for (line_no, line) in lines {
        last_line = line_no;
        for token in line.split_whitespace() {
            if elevation_m.len() == expected {
                return Err(parse_error(
                    line_no,
                    format!("more than nrows x ncols = {expected} values (\"{token}\")"),
                ));
            }
            let value: f64 = token
                .parse()
                .map_err(|_| parse_error(line_no, format!("non-numeric value \"{token}\"")))?;
            let height_m = value as f32;
            let void = !height_m.is_finite() || header.nodata == Some(value);
            elevation_m.push(if void { f32::NAN } else { height_m });
        }
    }
    if elevation_m.len() < expected {
        return Err(parse_error(
            last_line,
            format!(
                "the data end after {} of nrows x ncols = {expected} values",
                elevation_m.len()
            ),
        ));
    }
    flip_rows(&mut elevation_m, cols);
    Ok(finish(
        grid,
        elevation_m,
        SourceFormat::EsriAscii,
        path,
        None,
    ))
}
