//! Terrain occlusion horizon: which culture blocks are hidden behind ridges, cheaply and never
//! wrongly.
//!
//! Algorithm: an occlusion horizon (Downs, Möller and Séquin, "Occlusion horizons for driving
//! through urban scenery", I3D 2001), built from the terrain's own min/max quadtree instead of
//! building footprints. Around the eye, azimuth is cut into bins and distance into geometric
//! rings. Each occluder is a rectangle of ground (a quadtree node of a resident finest tile)
//! with the lowest point of the finest surface under it: every sight line whose azimuth lies in
//! the rectangle's angular span crosses the rectangle, where the surface stands at least that
//! high, so the terrain along that azimuth rises at least to the rectangle's lowest elevation
//! (taken at the worse of its nearest and farthest distance, the earth's curvature included).
//! A rectangle raises the horizon of the bins it wholly covers, in the ring of its farthest
//! distance; a running maximum over the rings gives, per ring and bin, the elevation the
//! terrain nearer than the ring is known to reach. A culture block (a rectangle with the top of
//! its tallest object) is hidden when, in every bin its span touches, that horizon stands above
//! the highest elevation any part of the block can have, by a margin (a pixel or two) for the
//! drawn surface's level-of-detail error. Building is linear in the occluders and the bins they
//! cover; a query reads one ring.
//!
//! Positions are east and north metres about the eye on the eye's meridian and parallel
//! (equirectangular), heights ellipsoidal with the earth's drop `d^2 / 2R`; elevations are kept
//! as tangents and azimuth as a pseudo-angle (both monotonic), so no trigonometry is done. The
//! projection's horizontal error (an east-west sight line of length `D` bends by about
//! `D tan(lat) / 2R` radians) is covered by widening each block's span by as many bins as that
//! and one more on either side.
//!
//! Limits: conservative by construction, so partly hidden blocks are drawn; a rectangle must
//! wholly cover a bin (0.35 degrees) to count, so far small ridges hide nothing; only terrain
//! occludes (not buildings, not woods).

/// Azimuth bins around the eye (each 0.35 degrees on average).
const BINS: usize = 1024;
/// The first ring's outer edge and the growth of each ring's edge over the one before.
const FIRST_RING_M: f64 = 25.0;
const RING_GROWTH: f64 = 1.15;
/// Rings out to about 65 km.
const RINGS: usize = 57;
/// Earth radii bounding the drop below the eye's tangent plane: the smaller for occluders (they
/// sink more), the larger for what they hide (it sinks less).
const OCCLUDER_RADIUS_M: f64 = 6.33e6;
const OCCLUDEE_RADIUS_M: f64 = 6.40e6;

/// A rectangle of ground between two parallels and two meridians, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeoRect {
    pub south_deg: f64,
    pub west_deg: f64,
    pub north_deg: f64,
    pub east_deg: f64,
}

/// A grid of ground cells between parallels and meridians with the lowest point of the surface
/// in each (ellipsoidal metres; NaN where unknown), row-major from the south-west cell.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccluderGrid {
    pub south_deg: f64,
    pub west_deg: f64,
    pub cell_dlat_deg: f64,
    pub cell_dlon_deg: f64,
    pub rows: usize,
    pub cols: usize,
    pub lowest_alt_m: Vec<f32>,
}

impl OccluderGrid {
    fn rect(&self, row: usize, col: usize, rows: usize, cols: usize) -> GeoRect {
        GeoRect {
            south_deg: self.south_deg + row as f64 * self.cell_dlat_deg,
            west_deg: self.west_deg + col as f64 * self.cell_dlon_deg,
            north_deg: self.south_deg + (row + rows) as f64 * self.cell_dlat_deg,
            east_deg: self.west_deg + (col + cols) as f64 * self.cell_dlon_deg,
        }
    }
}

/// Cells of an [`OccluderGrid`] taken together: each cell alone, and each 2 x 2 window, so
/// that the seam between two cells (which splits a bin that neither covers alone) lies inside
/// an occluder of its own.
const WINDOWS: [(usize, usize); 2] = [(1, 1), (2, 2)];
/// Cells per side of the chunks the view's azimuths are checked on first.
const CHUNK_CELLS: usize = 8;

/// The horizon one view builds from its terrain, then asks of its culture blocks.
#[derive(Clone, Debug)]
pub struct OcclusionHorizon {
    eye_lat_deg: f64,
    eye_lon_deg: f64,
    eye_alt_m: f64,
    metres_per_deg: (f64, f64),
    /// `|tan(latitude)|` at the eye: how far the projection bends east-west sight lines.
    tan_lat: f64,
    /// Tangent of the vertical margin.
    margin_tan: f64,
    /// `[ring * BINS + bin]`: the elevation tangent the terrain nearer than the ring's outer
    /// edge reaches over the whole bin (after [`OcclusionHorizon::finish`]).
    table: Vec<f32>,
    occluders: usize,
    /// The view's span of pseudo-azimuth (`None`: all round); occluders outside it are skipped.
    view_span: Option<(f64, f64)>,
}

impl Default for OcclusionHorizon {
    fn default() -> Self {
        OcclusionHorizon {
            eye_lat_deg: 0.0,
            eye_lon_deg: 0.0,
            eye_alt_m: 0.0,
            metres_per_deg: (1.0, 1.0),
            tan_lat: 0.0,
            margin_tan: 0.0,
            table: vec![f32::NEG_INFINITY; RINGS * BINS],
            occluders: 0,
            view_span: None,
        }
    }
}

/// A rectangle as seen from the eye: its span of pseudo-azimuth (`hi` may pass 4 when it
/// straddles east) and its nearest and farthest horizontal distance.
struct Seen {
    lo: f64,
    hi: f64,
    near_m: f64,
    far_m: f64,
}

impl OcclusionHorizon {
    /// Starts a horizon for an eye at `eye_lat_deg`, `eye_lon_deg`, `eye_alt_m` (ellipsoidal);
    /// a block must sink `margin_tan` (a tangent of elevation: the drawn surface's error, a
    /// pixel or two) below the horizon to be hidden. Forgets the last horizon.
    pub fn begin(&mut self, eye_lat_deg: f64, eye_lon_deg: f64, eye_alt_m: f64, margin_tan: f64) {
        self.eye_lat_deg = eye_lat_deg;
        self.eye_lon_deg = eye_lon_deg;
        self.eye_alt_m = eye_alt_m;
        self.metres_per_deg = cig_geo::metres_per_degree(eye_lat_deg);
        self.tan_lat = eye_lat_deg.to_radians().tan().abs().min(1e3);
        self.margin_tan = margin_tan.max(0.0);
        self.table.fill(f32::NEG_INFINITY);
        self.occluders = 0;
        self.view_span = None;
    }

    /// Limits the horizon to the azimuths of a view whose edge rays point along `directions`
    /// (east, north components, any length); `all_round` when the view holds the zenith or the
    /// nadir (its azimuths are then every azimuth).
    pub fn limit_to_view(&mut self, directions: &[(f64, f64)], all_round: bool) {
        self.view_span = if all_round || directions.is_empty() {
            None
        } else {
            let mut angles: Vec<f64> = directions
                .iter()
                .map(|&(e, n)| pseudo_angle(e, n))
                .collect();
            let span = |a: &[f64]| {
                a.iter()
                    .fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)))
            };
            let (mut lo, mut hi) = span(&angles);
            if hi - lo >= 2.0 {
                for a in &mut angles {
                    if *a < 2.0 {
                        *a += 4.0;
                    }
                }
                (lo, hi) = span(&angles);
            }
            // A view wider than half the circle, seen from above, is taken all round.
            (hi - lo < 2.0).then_some((lo, hi))
        };
    }

    /// Whether any of `rect` lies in the view's azimuths (always, when the eye is over it).
    pub fn in_view(&self, rect: &GeoRect) -> bool {
        match self.seen(rect) {
            Some(seen) => self.overlaps_view(&seen),
            None => true,
        }
    }

    fn overlaps_view(&self, seen: &Seen) -> bool {
        let Some((lo, hi)) = self.view_span else {
            return true;
        };
        // Compare on the circle: shift the rectangle's span by whole turns.
        [-4.0, 0.0, 4.0]
            .iter()
            .any(|shift| seen.lo + shift <= hi && seen.hi + shift >= lo)
    }

    /// What the horizon must rise above (an elevation tangent, margin aside) to hide what
    /// stands on `rect` up to `top_alt_m`, and the nearest distance of `rect`, metres; `None`
    /// when the eye stands over it (it cannot be hidden).
    pub fn hiding_floor(&self, rect: &GeoRect, top_alt_m: f64) -> Option<(f64, f64)> {
        let seen = self.seen(rect)?;
        let tan = self.top_tangent(&seen, top_alt_m) - seen.near_m / (2.0 * OCCLUDEE_RADIUS_M);
        Some((seen.near_m, tan))
    }

    /// The highest the ground of `rect`, nowhere above `highest_alt_m`, can raise the
    /// horizon (an elevation tangent), and its nearest distance, metres; `None` when the eye
    /// stands over it.
    pub fn raising_ceiling(&self, rect: &GeoRect, highest_alt_m: f64) -> Option<(f64, f64)> {
        let seen = self.seen(rect)?;
        Some((seen.near_m, self.top_tangent(&seen, highest_alt_m)))
    }

    fn top_tangent(&self, seen: &Seen, top_alt_m: f64) -> f64 {
        let rise = top_alt_m - self.eye_alt_m;
        if rise > 0.0 {
            rise / seen.near_m
        } else {
            rise / seen.far_m
        }
    }

    /// The nearest horizontal distance of `rect` from the eye, metres (0 over it).
    pub fn nearest_m(&self, rect: &GeoRect) -> f64 {
        self.seen(rect).map_or(0.0, |seen| seen.near_m)
    }

    /// Rectangles that raised the horizon since [`OcclusionHorizon::begin`].
    pub fn occluders(&self) -> usize {
        self.occluders
    }

    /// Adds ground `rect` whose surface nowhere lies below `lowest_alt_m` (ellipsoidal).
    pub fn add_occluder(&mut self, rect: &GeoRect, lowest_alt_m: f64) {
        if let Some(seen) = self.seen(rect) {
            self.add_seen(&seen, lowest_alt_m);
        }
    }

    fn add_seen(&mut self, seen: &Seen, lowest_alt_m: f64) {
        if !self.overlaps_view(seen) {
            return;
        }
        let Some(ring) = ring_at_or_beyond(seen.far_m) else {
            return;
        };
        let rise = lowest_alt_m - self.eye_alt_m;
        let tan = if rise > 0.0 {
            rise / seen.far_m
        } else {
            rise / seen.near_m.max(1.0)
        } - seen.far_m / (2.0 * OCCLUDER_RADIUS_M);
        let width = 4.0 / BINS as f64;
        let first = (seen.lo / width).ceil() as usize;
        let end = (seen.hi / width).floor() as usize;
        if first >= end {
            return;
        }
        self.occluders += 1;
        let row = &mut self.table[ring * BINS..(ring + 1) * BINS];
        let tan = tan as f32;
        for bin in first..end {
            let cell = &mut row[bin % BINS];
            *cell = cell.max(tan);
        }
    }

    /// Adds every cell of `grid`, and every 2 x 2 window of its cells. The
    /// cells' corners are seen once per chunk of cells, not once per window.
    pub fn add_grid(&mut self, grid: &OccluderGrid) {
        if grid.lowest_alt_m.len() != grid.rows * grid.cols {
            return;
        }
        let (m_lat, m_lon) = self.metres_per_deg;
        let (eye_lat, eye_lon) = (self.eye_lat_deg, self.eye_lon_deg);
        let east_m =
            |col: usize| (grid.west_deg + col as f64 * grid.cell_dlon_deg - eye_lon) * m_lon;
        let north_m =
            |row: usize| (grid.south_deg + row as f64 * grid.cell_dlat_deg - eye_lat) * m_lat;
        // Corners of a chunk and the cells past it its windows reach: (angle, distance).
        let side = CHUNK_CELLS + 2;
        let mut corners = [(0.0_f64, 0.0_f64); (CHUNK_CELLS + 2) * (CHUNK_CELLS + 2)];
        for chunk_row in (0..grid.rows).step_by(CHUNK_CELLS) {
            for chunk_col in (0..grid.cols).step_by(CHUNK_CELLS) {
                let rows = CHUNK_CELLS.min(grid.rows - chunk_row);
                let cols = CHUNK_CELLS.min(grid.cols - chunk_col);
                let known = (chunk_row..chunk_row + rows).any(|r| {
                    grid.lowest_alt_m[r * grid.cols + chunk_col..r * grid.cols + chunk_col + cols]
                        .iter()
                        .any(|v| !v.is_nan())
                });
                if !known {
                    continue;
                }
                // One cell more each way: the windows starting in the chunk reach into it.
                let reach = grid.rect(chunk_row, chunk_col, rows + 1, cols + 1);
                if !self.in_view(&reach) {
                    continue;
                }
                let corner_rows = (rows + 2).min(grid.rows + 1 - chunk_row);
                let corner_cols = (cols + 2).min(grid.cols + 1 - chunk_col);
                for r in 0..corner_rows {
                    let y = north_m(chunk_row + r);
                    for c in 0..corner_cols {
                        let x = east_m(chunk_col + c);
                        corners[r * side + c] = (pseudo_angle(x, y), (x * x + y * y).sqrt());
                    }
                }
                for row in chunk_row..chunk_row + rows {
                    for col in chunk_col..chunk_col + cols {
                        for (h, w) in WINDOWS {
                            if row + h > grid.rows || col + w > grid.cols {
                                continue;
                            }
                            let mut lowest = f32::INFINITY;
                            for r in row..row + h {
                                for c in col..col + w {
                                    // NaN (unknown) poisons the window.
                                    let v = grid.lowest_alt_m[r * grid.cols + c];
                                    lowest = if v.is_nan() || lowest.is_nan() {
                                        f32::NAN
                                    } else {
                                        lowest.min(v)
                                    };
                                }
                            }
                            if !lowest.is_finite() {
                                continue;
                            }
                            let (r0, c0) = (row - chunk_row, col - chunk_col);
                            let at = |r: usize, c: usize| corners[r * side + c];
                            let seen = Seen::of(
                                [east_m(col), east_m(col + w), north_m(row), north_m(row + h)],
                                [
                                    at(r0, c0),
                                    at(r0, c0 + w),
                                    at(r0 + h, c0 + w),
                                    at(r0 + h, c0),
                                ],
                            );
                            if let Some(seen) = seen {
                                self.add_seen(&seen, f64::from(lowest));
                            }
                        }
                    }
                }
            }
        }
    }

    /// Ends the building: each ring takes the horizon of the rings inside it.
    pub fn finish(&mut self) {
        for ring in 1..RINGS {
            let (inner, outer) = self.table.split_at_mut(ring * BINS);
            let inner = &inner[(ring - 1) * BINS..];
            for (o, i) in outer[..BINS].iter_mut().zip(inner) {
                *o = o.max(*i);
            }
        }
    }

    /// Whether everything standing on `rect` up to `top_alt_m` (ellipsoidal) is hidden behind
    /// the terrain added (after [`OcclusionHorizon::finish`]).
    pub fn hides(&self, rect: &GeoRect, top_alt_m: f64) -> bool {
        if self.occluders == 0 {
            return false;
        }
        let Some(seen) = self.seen(rect) else {
            return false;
        };
        let Some(ring) = ring_within(seen.near_m) else {
            return false;
        };
        let tan = self.top_tangent(&seen, top_alt_m) - seen.near_m / (2.0 * OCCLUDEE_RADIUS_M)
            + self.margin_tan;
        let width = 4.0 / BINS as f64;
        // Bins more on either side for the projection's horizontal error: on the eye's
        // meridian and parallel an east-west sight line of length D bends by about
        // D tan(lat) / 2R radians, and a bin is at least `width` radians wide (the pseudo-
        // angle grows at most one per radian).
        let bend_rad = seen.far_m * self.tan_lat / (2.0 * OCCLUDER_RADIUS_M);
        let extra = (bend_rad / width).ceil() as usize + 1;
        if 2 * extra + 2 >= BINS / 2 {
            return false;
        }
        let first = (seen.lo / width).floor() as usize + BINS - extra;
        let last = (seen.hi / width).floor() as usize + BINS + extra;
        let row = &self.table[ring * BINS..(ring + 1) * BINS];
        let tan = tan as f32;
        (first..=last).all(|bin| row[bin % BINS] > tan)
    }

    /// `rect` from the eye; `None` when the eye stands over it (or on its edge).
    fn seen(&self, rect: &GeoRect) -> Option<Seen> {
        let (m_lat, m_lon) = self.metres_per_deg;
        let w = (rect.west_deg - self.eye_lon_deg) * m_lon;
        let e = (rect.east_deg - self.eye_lon_deg) * m_lon;
        let s = (rect.south_deg - self.eye_lat_deg) * m_lat;
        let n = (rect.north_deg - self.eye_lat_deg) * m_lat;
        let corner = |x: f64, y: f64| (pseudo_angle(x, y), (x * x + y * y).sqrt());
        Seen::of(
            [w, e, s, n],
            [corner(w, s), corner(e, s), corner(e, n), corner(w, n)],
        )
    }
}

impl Seen {
    /// The rectangle between `[west, east, south, north]` (metres from the eye) whose corners
    /// (south-west, south-east, north-east, north-west) lie at `(pseudo-angle, distance)`;
    /// `None` when the eye stands over it (or on its edge).
    fn of(sides: [f64; 4], corners: [(f64, f64); 4]) -> Option<Seen> {
        let [w, e, s, n] = sides;
        if !(w < e && s < n) {
            return None;
        }
        if w <= 0.0 && e >= 0.0 && s <= 0.0 && n >= 0.0 {
            return None;
        }
        let mut angles = corners.map(|(a, _)| a);
        let (mut lo, mut hi) = min_max(&angles);
        if hi - lo >= 2.0 {
            // The span straddles east (pseudo-angle 0): count from the other side.
            for a in &mut angles {
                if *a < 2.0 {
                    *a += 4.0;
                }
            }
            (lo, hi) = min_max(&angles);
        }
        let dx = if w > 0.0 {
            w
        } else if e < 0.0 {
            -e
        } else {
            0.0
        };
        let dy = if s > 0.0 {
            s
        } else if n < 0.0 {
            -n
        } else {
            0.0
        };
        let far_m = corners.iter().map(|&(_, d)| d).fold(0.0_f64, f64::max);
        Some(Seen {
            lo,
            hi,
            near_m: (dx * dx + dy * dy).sqrt().max(1.0),
            far_m,
        })
    }
}

fn min_max(values: &[f64; 4]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)))
}

/// A monotonic stand-in for the azimuth of `(east, north)` counter-clockwise from east, in
/// `[0, 4)` (the "diamond angle"): opposite directions differ by exactly 2.
fn pseudo_angle(east: f64, north: f64) -> f64 {
    let sum = east.abs() + north.abs();
    if sum == 0.0 {
        return 0.0;
    }
    let a = if north >= 0.0 {
        if east >= 0.0 {
            north / sum
        } else {
            1.0 - east / sum
        }
    } else if east < 0.0 {
        2.0 - north / sum
    } else {
        3.0 + east / sum
    };
    if a >= 4.0 {
        0.0
    } else {
        a
    }
}

/// Outer edge of ring `k`.
fn ring_edge_m(k: usize) -> f64 {
    FIRST_RING_M * RING_GROWTH.powi(k as i32)
}

/// The first ring whose outer edge is at or beyond `distance_m` (`None` past the last).
fn ring_at_or_beyond(distance_m: f64) -> Option<usize> {
    let k = ((distance_m / FIRST_RING_M).ln() / RING_GROWTH.ln()).ceil();
    let k = if k.is_finite() {
        k.max(0.0) as usize
    } else {
        0
    };
    // Guard the logarithm's rounding.
    let k = if k > 0 && ring_edge_m(k - 1) >= distance_m {
        k - 1
    } else {
        k
    };
    (k < RINGS).then_some(k)
}

/// The last ring whose outer edge is within `distance_m` (`None` inside the first).
fn ring_within(distance_m: f64) -> Option<usize> {
    if distance_m < FIRST_RING_M {
        return None;
    }
    let k = ((distance_m / FIRST_RING_M).ln() / RING_GROWTH.ln()).floor() as usize;
    let k = if ring_edge_m(k) > distance_m {
        k.saturating_sub(1)
    } else {
        k
    };
    Some(k.min(RINGS - 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_geo::Geodetic;
    use proptest::prelude::*;

    #[test]
    fn the_pseudo_angle_grows_counter_clockwise_and_opposites_differ_by_two() {
        let mut last = -1.0;
        for k in 0..3600 {
            let a = f64::from(k) * 0.1_f64.to_radians();
            let p = pseudo_angle(a.cos(), a.sin());
            assert!(p > last, "{k}: {p} after {last}");
            last = p;
            let q = pseudo_angle(-a.cos(), -a.sin());
            assert!(((q - p).rem_euclid(4.0) - 2.0).abs() < 1e-9, "{k}");
        }
    }

    #[test]
    fn rings_bracket_their_distances() {
        for d in [1.0, 24.9, 25.0, 25.1, 100.0, 999.0, 5000.0, 64_000.0] {
            if let Some(k) = ring_at_or_beyond(d) {
                assert!(ring_edge_m(k) >= d * (1.0 - 1e-12), "{d}: {k}");
                assert!(k == 0 || ring_edge_m(k - 1) < d, "{d}: {k}");
            }
            if let Some(k) = ring_within(d) {
                assert!(ring_edge_m(k) <= d * (1.0 + 1e-12), "{d}: {k}");
            }
        }
        assert_eq!(ring_within(10.0), None);
        assert_eq!(ring_at_or_beyond(1e9), None);
    }

    /// A ridge of `height_m` running east-west `ridge_north_m` north of the eye, on flat
    /// ground at 0 m, as 30 m cells.
    fn ridge_horizon(height_m: f64, ridge_north_m: f64, eye_alt_m: f64) -> OcclusionHorizon {
        let (lat0, lon0) = (36.0, -121.0);
        let (m_lat, m_lon) = cig_geo::metres_per_degree(lat0);
        let mut h = OcclusionHorizon::default();
        h.begin(lat0, lon0, eye_alt_m, 0.002);
        let n = 400;
        let mut grid = OccluderGrid {
            south_deg: lat0 - 6000.0 / m_lat,
            west_deg: lon0 - 6000.0 / m_lon,
            cell_dlat_deg: 30.0 / m_lat,
            cell_dlon_deg: 30.0 / m_lon,
            rows: n,
            cols: n,
            lowest_alt_m: Vec::new(),
        };
        for i in 0..n {
            for _ in 0..n {
                let s = i as f64 * 30.0 - 6000.0;
                let on_ridge = (s - ridge_north_m).abs() < 45.0;
                grid.lowest_alt_m
                    .push(if on_ridge { height_m as f32 } else { 0.0 });
            }
        }
        h.add_grid(&grid);
        h.finish();
        h
    }

    fn block_at(north_m: f64, east_m: f64) -> GeoRect {
        let (lat0, lon0) = (36.0, -121.0);
        let (m_lat, m_lon) = cig_geo::metres_per_degree(lat0);
        GeoRect {
            south_deg: lat0 + (north_m - 120.0) / m_lat,
            west_deg: lon0 + (east_m - 120.0) / m_lon,
            north_deg: lat0 + (north_m + 120.0) / m_lat,
            east_deg: lon0 + (east_m + 120.0) / m_lon,
        }
    }

    #[test]
    fn a_wood_behind_a_ridge_is_hidden_and_one_in_front_or_above_it_is_not() {
        // A 100 m ridge 1 km north of an eye 2 m above the plain.
        let h = ridge_horizon(100.0, 1000.0, 2.0);
        assert!(h.occluders() > 1000);
        // 25 m trees 3 km north: hidden (they would need to stand ~290 m high to show).
        assert!(h.hides(&block_at(3000.0, 0.0), 25.0));
        assert!(h.hides(&block_at(3000.0, 400.0), 25.0));
        // Tall enough to rise over the ridge: seen.
        assert!(!h.hides(&block_at(3000.0, 0.0), 400.0));
        // In front of the ridge, beside it, behind the eye: seen.
        assert!(!h.hides(&block_at(600.0, 0.0), 25.0));
        assert!(!h.hides(&block_at(0.0, 3000.0), 25.0));
        assert!(!h.hides(&block_at(-3000.0, 0.0), 25.0));
        // From 600 m up the ridge hides nothing 3 km away.
        let high = ridge_horizon(100.0, 1000.0, 600.0);
        assert!(!high.hides(&block_at(3000.0, 0.0), 25.0));
        // Limited to a view looking north, it still hides what lies north, and it skips the
        // ground behind the eye.
        let mut north = OcclusionHorizon::default();
        north.begin(36.0, -121.0, 2.0, 0.002);
        north.limit_to_view(&[(-1.0, 1.0), (1.0, 1.0)], false);
        let (m_lat, m_lon) = cig_geo::metres_per_degree(36.0);
        let behind = GeoRect {
            south_deg: 36.0 - 1100.0 / m_lat,
            west_deg: -121.0 - 100.0 / m_lon,
            north_deg: 36.0 - 1000.0 / m_lat,
            east_deg: -121.0 + 100.0 / m_lon,
        };
        assert!(!north.in_view(&behind));
        north.add_occluder(&behind, 500.0);
        assert_eq!(north.occluders(), 0);
        let ahead = GeoRect {
            south_deg: 36.0 + 1000.0 / m_lat,
            west_deg: -121.0 - 1000.0 / m_lon,
            north_deg: 36.0 + 1100.0 / m_lat,
            east_deg: -121.0 + 1000.0 / m_lon,
        };
        north.add_occluder(&ahead, 500.0);
        north.finish();
        assert_eq!(north.occluders(), 1);
        assert!(north.hides(&block_at(3000.0, 0.0), 25.0));
        // An empty horizon hides nothing.
        let mut empty = OcclusionHorizon::default();
        empty.begin(36.0, -121.0, 2.0, 0.002);
        empty.finish();
        assert!(!empty.hides(&block_at(3000.0, 0.0), 0.0));
    }

    /// Height of a smooth random landscape at `(north, east)` metres.
    fn landscape_m(waves: &[(f64, f64, f64, f64)], north: f64, east: f64) -> f64 {
        waves
            .iter()
            .map(|&(amp, kn, ke, phase)| amp * (kn * north + ke * east + phase).sin())
            .sum::<f64>()
            + 200.0
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Whatever the horizon hides is hidden: every sight line from the eye to points of a
        /// hidden block (marched in true ECEF geometry over the posts' triangulated surface)
        /// passes under the ground.
        #[test]
        fn a_hidden_block_is_hidden_along_every_sight_line(
            waves in proptest::collection::vec(
                (10.0..120.0_f64, -0.004..0.004_f64, -0.004..0.004_f64, 0.0..6.3_f64), 2..5),
            eye_up in 1.5..60.0_f64,
            lat0 in -75.0..75.0_f64,
            blocks in proptest::collection::vec((-5000.0..5000.0_f64, -5000.0..5000.0_f64,
                0.0..40.0_f64), 40),
        ) {
            let lon0 = 10.0;
            let (m_lat, m_lon) = cig_geo::metres_per_degree(lat0);
            let cell = 30.0;
            let ground = |n: f64, e: f64| landscape_m(&waves, n, e);
            let eye_alt = ground(0.0, 0.0) + eye_up;
            let mut h = OcclusionHorizon::default();
            h.begin(lat0, lon0, eye_alt, 1.0 / 300.0);
            // Cells of 4 x 4 posts, each bounded by its posts' lowest (the triangulated
            // surface's lowest point is a post).
            let span = 4.0 * cell;
            let mut grid = OccluderGrid {
                south_deg: lat0 - 50.0 * span / m_lat,
                west_deg: lon0 - 50.0 * span / m_lon,
                cell_dlat_deg: span / m_lat,
                cell_dlon_deg: span / m_lon,
                rows: 100,
                cols: 100,
                lowest_alt_m: Vec::new(),
            };
            for i in -50..50 {
                for j in -50..50 {
                    let (s, w) = (f64::from(i) * span, f64::from(j) * span);
                    let mut lowest = f64::MAX;
                    for a in 0..=4 {
                        for b in 0..=4 {
                            lowest = lowest.min(ground(s + f64::from(a) * cell, w + f64::from(b) * cell));
                        }
                    }
                    grid.lowest_alt_m.push(lowest as f32);
                }
            }
            h.add_grid(&grid);
            h.finish();
            // The surface between posts: bilinear within a cell bounds the triangulated one
            // from neither side, so take the lower of the two triangulations.
            let surface = |n: f64, e: f64| {
                let (fi, fj) = (n / cell, e / cell);
                let (i0, j0) = (fi.floor(), fj.floor());
                let (u, v) = (fi - i0, fj - j0);
                let p = |a: f64, b: f64| ground((i0 + a) * cell, (j0 + b) * cell);
                let (h00, h01, h10, h11) = (p(0.0, 0.0), p(0.0, 1.0), p(1.0, 0.0), p(1.0, 1.0));
                let diag_a = if u > v { h00 + (h10 - h00) * u + (h11 - h10) * v }
                    else { h00 + (h01 - h00) * v + (h11 - h01) * u };
                let diag_b = if u + v < 1.0 { h00 + (h10 - h00) * u + (h01 - h00) * v }
                    else { h11 + (h01 - h11) * (1.0 - u) + (h10 - h11) * (1.0 - v) };
                diag_a.min(diag_b)
            };
            let eye = Geodetic::new(lat0, lon0, eye_alt).to_ecef();
            for (bn, be, top_above) in blocks {
                let rect = GeoRect {
                    south_deg: lat0 + (bn - 120.0) / m_lat,
                    west_deg: lon0 + (be - 120.0) / m_lon,
                    north_deg: lat0 + (bn + 120.0) / m_lat,
                    east_deg: lon0 + (be + 120.0) / m_lon,
                };
                let mut top = f64::MIN;
                for a in 0..=8 {
                    for b in 0..=8 {
                        top = top.max(ground(bn - 120.0 + f64::from(a) * 30.0, be - 120.0 + f64::from(b) * 30.0));
                    }
                }
                let top = top + top_above;
                if !h.hides(&rect, top) {
                    continue;
                }
                for a in 0..=4 {
                    for b in 0..=4 {
                        let (n, e) = (bn - 120.0 + f64::from(a) * 60.0, be - 120.0 + f64::from(b) * 60.0);
                        let target = Geodetic::new(lat0 + n / m_lat, lon0 + e / m_lon, top).to_ecef();
                        let mut blocked = false;
                        for k in 1..400 {
                            let p = Geodetic::from_ecef(eye + (target - eye) * (f64::from(k) / 400.0));
                            let (pn, pe) = ((p.lat_deg - lat0) * m_lat, (p.lon_deg - lon0) * m_lon);
                            if p.alt_m < surface(pn, pe) {
                                blocked = true;
                                break;
                            }
                        }
                        prop_assert!(blocked, "block at ({bn:.0}, {be:.0}) up to {top:.1} m: the sight line to ({n:.0}, {e:.0}) is clear");
                    }
                }
            }
        }
    }
}
