//! Geographic post grids and whole-area rasters: the exchange form between importers, the
//! synthetic generator and the pyramid builder.
//!
//! A [`GeoGrid`] is a regular WGS84 latitude/longitude lattice of *posts* (point samples, as in
//! DTED and SRTM), row 0 at the south edge, column 0 at the west edge. A post is a point, not a
//! cell: a grid of `rows x cols` posts spans `(rows - 1) x (cols - 1)` cells.

use crate::material::Material;

/// A regular geographic lattice of posts. Post `(row, col)` lies at
/// `lat = south_lat_deg + row * dlat_deg`, `lon = west_lon_deg + col * dlon_deg`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GeoGrid {
    /// Latitude of row 0 (the southernmost posts), degrees.
    pub south_lat_deg: f64,
    /// Longitude of column 0 (the westernmost posts), degrees.
    pub west_lon_deg: f64,
    /// Post spacing in latitude, degrees (> 0).
    pub dlat_deg: f64,
    /// Post spacing in longitude, degrees (> 0).
    pub dlon_deg: f64,
    /// Number of post rows (south to north).
    pub rows: usize,
    /// Number of post columns (west to east).
    pub cols: usize,
}

impl GeoGrid {
    /// A grid of `rows x cols` posts `spacing_deg` apart both ways, its south-west post at
    /// 0 N 0 E (for tests and examples).
    pub fn at_origin(rows: usize, cols: usize, spacing_deg: f64) -> GeoGrid {
        GeoGrid {
            south_lat_deg: 0.0,
            west_lon_deg: 0.0,
            dlat_deg: spacing_deg,
            dlon_deg: spacing_deg,
            rows,
            cols,
        }
    }

    /// The grid's centre (latitude, longitude), degrees.
    pub fn centre_deg(&self) -> (f64, f64) {
        (
            0.5 * (self.south_lat_deg + self.north_lat_deg()),
            0.5 * (self.west_lon_deg + self.east_lon_deg()),
        )
    }

    /// Latitude of the northernmost row, degrees.
    pub fn north_lat_deg(&self) -> f64 {
        self.south_lat_deg + (self.rows.saturating_sub(1)) as f64 * self.dlat_deg
    }

    /// Longitude of the easternmost column, degrees.
    pub fn east_lon_deg(&self) -> f64 {
        self.west_lon_deg + (self.cols.saturating_sub(1)) as f64 * self.dlon_deg
    }

    /// Number of posts.
    pub fn len(&self) -> usize {
        self.rows * self.cols
    }

    /// True when the grid holds no post.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Latitude and longitude of post `(row, col)`, degrees.
    pub fn post_lat_lon_deg(&self, row: usize, col: usize) -> (f64, f64) {
        (
            self.south_lat_deg + row as f64 * self.dlat_deg,
            self.west_lon_deg + col as f64 * self.dlon_deg,
        )
    }

    /// Fractional (row, col) of a point; integral values are posts.
    pub fn fractional_index(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        (
            (lat_deg - self.south_lat_deg) / self.dlat_deg,
            (lon_deg - self.west_lon_deg) / self.dlon_deg,
        )
    }

    /// True when the point lies inside the grid's rectangle (edges included).
    pub fn contains(&self, lat_deg: f64, lon_deg: f64) -> bool {
        let (r, c) = self.fractional_index(lat_deg, lon_deg);
        let eps = 1e-9;
        r >= -eps
            && c >= -eps
            && r <= (self.rows.saturating_sub(1)) as f64 + eps
            && c <= (self.cols.saturating_sub(1)) as f64 + eps
    }
}

/// A whole-area elevation raster on a [`GeoGrid`], row-major, south row first.
///
/// `elevation_m` holds heights above mean sea level (EGM96), `NaN` where the source had a void
/// (nodata). `material` is `None` until classified or set by the source.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    pub grid: GeoGrid,
    pub elevation_m: Vec<f32>,
    pub material: Option<Vec<Material>>,
}

impl Raster {
    /// A raster of the heights `height_m(row, col)` on `grid`, without materials.
    pub fn from_fn(grid: GeoGrid, height_m: impl Fn(usize, usize) -> f32) -> Raster {
        Raster {
            grid,
            elevation_m: (0..grid.len())
                .map(|k| height_m(k / grid.cols, k % grid.cols))
                .collect(),
            material: None,
        }
    }

    /// A test raster of `rows x cols` posts 0.001 degrees apart at the origin.
    #[cfg(test)]
    pub(crate) fn for_test(
        rows: usize,
        cols: usize,
        height_m: impl Fn(usize, usize) -> f32,
    ) -> Raster {
        Raster::from_fn(GeoGrid::at_origin(rows, cols, 0.001), height_m)
    }

    /// Index of post `(row, col)` in the row-major arrays.
    pub fn index(&self, row: usize, col: usize) -> usize {
        row * self.grid.cols + col
    }

    /// Elevation of post `(row, col)`; `NaN` for a void.
    pub fn elevation_at(&self, row: usize, col: usize) -> f32 {
        self.elevation_m[self.index(row, col)]
    }

    /// Number of void (`NaN`) posts.
    pub fn void_count(&self) -> usize {
        self.elevation_m.iter().filter(|h| h.is_nan()).count()
    }
}

/// How a grid cell is split into its two triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Diagonal {
    /// Along the south-west to north-east diagonal: triangles `(sw, se, ne)` and `(sw, nw, ne)`.
    SouthWestNorthEast,
    /// Along the north-west to south-east diagonal: triangles `(sw, se, nw)` and `(se, ne, nw)`.
    NorthWestSouthEast,
}

impl Diagonal {
    /// The split of cell `(row, col)` of any level's grid (indices counted on that level from
    /// the database's south-west post): a checkerboard, south-west to north-east where
    /// `row + col` is even. This is the finest cut of a right-triangulated irregular network
    /// (each square split by a diagonal, each right triangle at its hypotenuse's midpoint), so
    /// the grid of every level and every adaptive mesh the renderer draws
    /// (`cig_scene::terrain_mesh`) are cuts of one hierarchy: a level's cells are unions of the
    /// finer level's triangles (see [`crate::rtin`]).
    #[inline]
    pub fn of_cell(row: usize, col: usize) -> Diagonal {
        if (row + col).is_multiple_of(2) {
            Diagonal::SouthWestNorthEast
        } else {
            Diagonal::NorthWestSouthEast
        }
    }
}

/// Height on the triangulated surface of one grid cell.
///
/// This is *the* surface of the database: every query and the renderer at full detail use it.
/// The cell's corners are `h00` (south-west), `h01` (south-east), `h10` (north-west) and `h11`
/// (north-east); `u` is the fraction eastwards and `v` northwards, both in `[0, 1]`. The cell is
/// split along `diagonal` ([`Diagonal::of_cell`] for a database's cells): along the south-west
/// to north-east diagonal the south-east triangle (`u >= v`) is `(h00, h01, h11)` and the
/// north-west one `(h00, h10, h11)`; along the other diagonal the south-west triangle
/// (`u + v <= 1`) is `(h00, h01, h10)` and the north-east one `(h01, h11, h10)`. At a corner the
/// result is that corner's height exactly.
#[inline]
pub fn triangulated_height(
    [h00, h01, h10, h11]: [f32; 4],
    u: f64,
    v: f64,
    diagonal: Diagonal,
) -> f64 {
    let (h00, h01, h10, h11) = (h00 as f64, h01 as f64, h10 as f64, h11 as f64);
    match diagonal {
        Diagonal::SouthWestNorthEast => {
            if u >= v {
                h00 + u * (h01 - h00) + v * (h11 - h01)
            } else {
                h00 + v * (h10 - h00) + u * (h11 - h10)
            }
        }
        Diagonal::NorthWestSouthEast => {
            if u + v <= 1.0 {
                h00 + u * (h01 - h00) + v * (h10 - h00)
            } else {
                h11 + (1.0 - u) * (h10 - h11) + (1.0 - v) * (h01 - h11)
            }
        }
    }
}

/// The slopes `(dh/du, dh/dv)` per cell of the triangle of a cell holding `(u, v)`, split as in
/// [`triangulated_height`].
#[inline]
pub fn triangulated_slopes(
    [h00, h01, h10, h11]: [f32; 4],
    u: f64,
    v: f64,
    diagonal: Diagonal,
) -> (f64, f64) {
    let (h00, h01, h10, h11) = (h00 as f64, h01 as f64, h10 as f64, h11 as f64);
    match diagonal {
        Diagonal::SouthWestNorthEast => {
            if u >= v {
                (h01 - h00, h11 - h01)
            } else {
                (h11 - h10, h10 - h00)
            }
        }
        Diagonal::NorthWestSouthEast => {
            if u + v <= 1.0 {
                (h01 - h00, h10 - h00)
            } else {
                (h11 - h10, h11 - h01)
            }
        }
    }
}
