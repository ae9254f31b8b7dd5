//! Derives material classes for an imported elevation raster that carries none.
//!
//! Algorithm (rule-based, from elevation alone): slope from central differences in metres;
//! water where a connected region of at least [`MIN_LAKE_POSTS`] posts is exactly level (SRTM
//! and DTED flatten lakes and the sea to one height) or where the ground is at or below 0 m and
//! level; sand on gentle ground within two posts of water and less than 3 m above it; rock on
//! slopes steeper than 35 degrees; snow above a latitude-dependent snowline; forest on moderate
//! slopes below the tree line; dry clay on level lowland; grass elsewhere.
//!
//! Limits: this is a stand-in for land-cover data (there is no importer for land-cover rasters
//! or road vectors yet): imported databases get no roads, and forest and clay are guesses from
//! slope and height. Synthetic databases carry their own materials and do not use this.

use crate::material::Material;
use crate::raster::Raster;

/// Smallest level region taken for a lake.
pub const MIN_LAKE_POSTS: usize = 64;

/// Snowline in metres at a latitude: about 5000 m in the tropics, falling 100 m per degree
/// poleward of 25 degrees, never below 300 m.
pub fn snowline_m(lat_deg: f64) -> f64 {
    (5000.0 - 100.0 * (lat_deg.abs() - 25.0).max(0.0)).max(300.0)
}

/// Sets `raster.material` from elevation and slope. Voids must be filled first.
pub fn classify_materials(raster: &mut Raster) {
    let g = raster.grid;
    let (rows, cols) = (g.rows, g.cols);
    let h = &raster.elevation_m;
    let centre_lat = 0.5 * (g.south_lat_deg + g.north_lat_deg());
    let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(centre_lat);
    let dy_m = g.dlat_deg * north_m_per_deg;
    let dx_m = g.dlon_deg * east_m_per_deg;
    let at = |r: usize, c: usize| f64::from(h[r * cols + c]);
    let slope_deg = |r: usize, c: usize| -> f64 {
        let (r0, r1) = (r.saturating_sub(1), (r + 1).min(rows - 1));
        let (c0, c1) = (c.saturating_sub(1), (c + 1).min(cols - 1));
        let dzdy = if r1 > r0 {
            (at(r1, c) - at(r0, c)) / ((r1 - r0) as f64 * dy_m)
        } else {
            0.0
        };
        let dzdx = if c1 > c0 {
            (at(r, c1) - at(r, c0)) / ((c1 - c0) as f64 * dx_m)
        } else {
            0.0
        };
        (dzdx.hypot(dzdy)).atan().to_degrees()
    };

    // Level connected regions (4-neighbours with exactly equal height) become lakes.
    let mut water = vec![false; rows * cols];
    let mut seen = vec![false; rows * cols];
    let mut stack = Vec::new();
    let mut region = Vec::new();
    for start in 0..rows * cols {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        region.clear();
        stack.push(start);
        while let Some(k) = stack.pop() {
            region.push(k);
            let (r, c) = (k / cols, k % cols);
            let mut visit = |nk: usize| {
                if !seen[nk] && h[nk] == h[k] {
                    seen[nk] = true;
                    stack.push(nk);
                }
            };
            if r > 0 {
                visit(k - cols);
            }
            if r + 1 < rows {
                visit(k + cols);
            }
            if c > 0 {
                visit(k - 1);
            }
            if c + 1 < cols {
                visit(k + 1);
            }
        }
        let sea = h[start] <= 0.0 && region.len() >= 4;
        if region.len() >= MIN_LAKE_POSTS || sea {
            for &k in &region {
                water[k] = true;
            }
        }
    }

    let snowline = snowline_m(centre_lat);
    let treeline = snowline - 700.0;
    let near_water = |r: usize, c: usize| -> Option<f32> {
        let mut lowest: Option<f32> = None;
        for rr in r.saturating_sub(2)..=(r + 2).min(rows - 1) {
            for cc in c.saturating_sub(2)..=(c + 2).min(cols - 1) {
                let k = rr * cols + cc;
                if water[k] {
                    lowest = Some(lowest.map_or(h[k], |l: f32| l.min(h[k])));
                }
            }
        }
        lowest
    };
    let mut material = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        for c in 0..cols {
            let k = r * cols + c;
            let elev = at(r, c);
            let m = if water[k] {
                Material::Water
            } else {
                let slope = slope_deg(r, c);
                if slope > 35.0 {
                    Material::Rock
                } else if elev > snowline {
                    Material::Snow
                } else if slope < 5.0 && near_water(r, c).is_some_and(|w| elev < f64::from(w) + 3.0)
                {
                    Material::Sand
                } else if (10.0..=35.0).contains(&slope) && elev < treeline {
                    Material::Forest
                } else if slope < 2.0 && elev < 500.0 {
                    Material::DryClay
                } else {
                    Material::Grass
                }
            };
            material.push(m);
        }
    }
    raster.material = Some(material);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::GeoGrid;

    #[test]
    fn level_lake_steep_cliff_and_gentle_slope_get_their_classes() {
        let (rows, cols) = (60, 60);
        let grid = GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 30.0 / 110_950.0,
            dlon_deg: 30.0 / 90_000.0,
            rows,
            cols,
        };
        // West third: a level lake at 100 m; middle: a gentle rise; east: a 45-degree cliff.
        let elevation_m = (0..rows * cols)
            .map(|k| {
                let c = k % cols;
                if c < 20 {
                    100.0
                } else if c < 40 {
                    100.0 + (c - 19) as f32 * 2.0
                } else {
                    140.0 + (c - 39) as f32 * 30.0
                }
            })
            .collect();
        let mut raster = Raster {
            grid,
            elevation_m,
            material: None,
        };
        classify_materials(&mut raster);
        let m = raster.material.expect("classified");
        assert_eq!(m[30 * cols + 5], Material::Water);
        assert_eq!(m[30 * cols + 50], Material::Rock);
        assert_eq!(m[30 * cols + 20], Material::Sand);
        assert!(matches!(
            m[30 * cols + 30],
            Material::Grass | Material::DryClay | Material::Forest
        ));
    }

    #[test]
    fn snowline_falls_toward_the_poles() {
        assert_eq!(snowline_m(0.0), 5000.0);
        assert!(snowline_m(60.0) < snowline_m(36.0));
        assert_eq!(snowline_m(89.0), 300.0);
    }
}
