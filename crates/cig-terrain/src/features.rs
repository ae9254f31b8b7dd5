//! Roads, rivers and lakes as shapes: the feature model, its validation, smoothed centre lines
//! with a spatial index, painting into the imagery pyramid's tiles, and levelling the terrain
//! under them.
//!
//! # Model
//!
//! A [`Feature`] is a line (paved road, dirt road, river: a centre line of WGS84 points and a
//! width) or a lake (an outer ring, holes, and an optional water level in metres MSL).
//! [`validate_features`] refuses what cannot be drawn, naming the feature's index.
//!
//! # Geometry
//!
//! Everything is worked in one local metric frame: an equirectangular projection about the
//! middle of the features' bounding box (metres per degree from `cig_geo` at that latitude; over
//! a 50 km database the scale error is under 1 %, a few centimetres across a road). Centre
//! lines are smoothed by centripetal Catmull-Rom splines (Barry and Goldman 1988; Yuksel,
//! Schaefer and Keyser 2011: no cusps or self-intersections within a segment), which pass
//! through the given points, sampled every quarter of the width. Segments (of centre lines and
//! lake rings) go into a grid of buckets, so painting a tile visits only nearby segments.
//!
//! # Painting
//!
//! [`FeatureLayer::paint`] colours a 256 x 256 imagery tile as a pure function of each texel's
//! centre and the level's texel size, so the same texel gets the same colour whichever tile
//! paints it (no seams) and nothing depends on the order tiles are painted in. Coverage is
//! analytic: the overlap of the texel's footprint across the line (its width projected on the
//! line's normal) with the ribbon, widened by the feature's soft edge; a ribbon narrower than a
//! texel gives partial coverage, so coarse levels blend. Lakes are an even-odd scanline fill
//! of their rings with the same anti-aliasing at the shore. Paved roads carry white edge lines
//! (0.15 m wide, 0.3 m in from the edge) and a dashed centre line (3 m dash, 9 m gap, along the
//! smoothed line's arc length) where texels are at most [`MARKING_MAX_TEXEL_M`]; coarser
//! texels get the asphalt mixed with the markings' share of white. Order: lakes, rivers, dirt
//! roads, paved roads (a road crossing a river is a bridge). A texel whose total coverage is
//! over one half becomes opaque (alpha 255); the others keep their alpha, and texels away from
//! every feature are untouched.
//!
//! # Levelling
//!
//! [`level_terrain`] changes the raster before the pyramid is built, so the one-surface
//! invariant holds: roads get the centre line's height (sampled along the smoothed line and
//! averaged over [`ROAD_PROFILE_WINDOW_M`]) at every post within half the width plus a post
//! spacing, blended back over one more spacing; lakes with a level are flat at it; materials
//! under roads, rivers and lakes are set to match.
//!
//! # Limits
//!
//! Junctions are drawn as overlapping ribbons (the later road's markings cross the earlier
//! road's asphalt); road ends are round; a spline through very sharp corners can still turn
//! tighter than the road's half width, leaving a pinched inner edge; the equirectangular frame
//! is meant for database-sized areas (not continents).

#![allow(
    clippy::needless_range_loop,
    reason = "texel and post loops index several arrays by row and column"
)]

use crate::imagery::{ImageryKey, ImageryLayout};
use crate::material::Material;
use crate::raster::Raster;

/// Widest line feature accepted, metres.
pub const MAX_WIDTH_M: f64 = 3000.0;

/// Coarsest texel, metres, on which road markings are drawn as shapes.
pub const MARKING_MAX_TEXEL_M: f64 = 1.0;

/// Length of the moving average along a road's centre line of the heights it is levelled to.
pub const ROAD_PROFILE_WINDOW_M: f64 = 60.0;

/// What a line feature is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LineKind {
    PavedRoad,
    DirtRoad,
    River,
}

/// What a feature is, as named in feature files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FeatureKind {
    Line(LineKind),
    Lake,
}

impl FeatureKind {
    /// Every name a feature file may use.
    pub const NAMES: [&'static str; 6] =
        ["paved_road", "road", "dirt_road", "track", "river", "lake"];

    /// The kind a feature file's `type` names; `None` for unknown names.
    pub fn from_name(name: &str) -> Option<FeatureKind> {
        match name.trim().to_ascii_lowercase().as_str() {
            "paved_road" | "road" => Some(FeatureKind::Line(LineKind::PavedRoad)),
            "dirt_road" | "track" => Some(FeatureKind::Line(LineKind::DirtRoad)),
            "river" => Some(FeatureKind::Line(LineKind::River)),
            "lake" => Some(FeatureKind::Lake),
            _ => None,
        }
    }

    /// The canonical name.
    pub fn name(self) -> &'static str {
        match self {
            FeatureKind::Line(LineKind::PavedRoad) => "paved_road",
            FeatureKind::Line(LineKind::DirtRoad) => "dirt_road",
            FeatureKind::Line(LineKind::River) => "river",
            FeatureKind::Lake => "lake",
        }
    }
}

/// A road, river or lake. Points are `(lat_deg, lon_deg)`, WGS84.
#[derive(Clone, Debug, PartialEq)]
pub enum Feature {
    /// A ribbon of `width_m` along a centre line.
    Line {
        kind: LineKind,
        width_m: f64,
        points_deg: Vec<(f64, f64)>,
    },
    /// Water inside `outer_deg` and outside every hole; the closing point may be repeated.
    Lake {
        outer_deg: Vec<(f64, f64)>,
        holes_deg: Vec<Vec<(f64, f64)>>,
        /// Water surface, metres MSL; `None` leaves the terrain as it is.
        level_m: Option<f64>,
    },
}

impl Feature {
    /// The feature's kind.
    pub fn kind(&self) -> FeatureKind {
        match self {
            Feature::Line { kind, .. } => FeatureKind::Line(*kind),
            Feature::Lake { .. } => FeatureKind::Lake,
        }
    }

    /// Checks the feature, which is number `index` of its list.
    pub fn validate(&self, index: usize) -> Result<(), FeatureError> {
        let check_points = |pts: &[(f64, f64)]| -> Result<(), FeatureError> {
            for (point, &(lat, lon)) in pts.iter().enumerate() {
                if !(lat.is_finite() && lon.is_finite() && lat.abs() <= 90.0 && lon.abs() <= 180.0)
                {
                    return Err(FeatureError::BadCoordinate { index, point });
                }
            }
            Ok(())
        };
        match self {
            Feature::Line {
                width_m,
                points_deg,
                ..
            } => {
                check_points(points_deg)?;
                if !(width_m.is_finite() && *width_m > 0.0 && *width_m <= MAX_WIDTH_M) {
                    return Err(FeatureError::Width {
                        index,
                        width_m: *width_m,
                    });
                }
                let distinct = dedup(points_deg).len();
                if distinct < 2 {
                    return Err(FeatureError::TooFewPoints {
                        index,
                        points: distinct,
                        needed: 2,
                        what: "line",
                    });
                }
            }
            Feature::Lake {
                outer_deg,
                holes_deg,
                level_m,
            } => {
                for ring in std::iter::once(outer_deg).chain(holes_deg) {
                    check_points(ring)?;
                    let distinct = ring_points(ring).len();
                    if distinct < 3 {
                        return Err(FeatureError::TooFewPoints {
                            index,
                            points: distinct,
                            needed: 3,
                            what: "lake ring",
                        });
                    }
                }
                if let Some(level) = level_m {
                    if !level.is_finite() {
                        return Err(FeatureError::Level {
                            index,
                            level_m: *level,
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

/// Why features cannot be used.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum FeatureError {
    #[error("{points} distinct points, a {what} needs at least {needed} (feature {index})")]
    TooFewPoints {
        index: usize,
        points: usize,
        needed: usize,
        what: &'static str,
    },
    #[error("point {point} is not a finite latitude/longitude (feature {index})")]
    BadCoordinate { index: usize, point: usize },
    #[error(
        "width {width_m} m must be finite, above 0 and at most {MAX_WIDTH_M} m (feature {index})"
    )]
    Width { index: usize, width_m: f64 },
    #[error("width_m is missing (feature {index})")]
    MissingWidth { index: usize },
    #[error("unknown type {name:?}, expected one of paved_road, road, dirt_road, track, river, lake (feature {index})")]
    UnknownKind { index: usize, name: String },
    #[error("water level {level_m} m is not finite (feature {index})")]
    Level { index: usize, level_m: f64 },
}

/// Checks every feature; the first error names its index.
pub fn validate_features(features: &[Feature]) -> Result<(), FeatureError> {
    for (i, f) in features.iter().enumerate() {
        f.validate(i)?;
    }
    Ok(())
}

/// Consecutive duplicates removed.
fn dedup(pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
    for &p in pts {
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    out
}

/// A ring's distinct points without the repeated closing point.
fn ring_points(pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out = dedup(pts);
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    out
}

type P = (f64, f64);

/// The local metric frame: x east, y north, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Frame {
    lat0: f64,
    lon0: f64,
    /// Metres per degree north and east.
    my: f64,
    mx: f64,
}

impl Frame {
    fn for_features(features: &[Feature]) -> Frame {
        let (mut s, mut w, mut n, mut e) =
            (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
        let mut add = |pts: &[(f64, f64)]| {
            for &(lat, lon) in pts {
                s = s.min(lat);
                n = n.max(lat);
                w = w.min(lon);
                e = e.max(lon);
            }
        };
        for f in features {
            match f {
                Feature::Line { points_deg, .. } => add(points_deg),
                Feature::Lake {
                    outer_deg,
                    holes_deg,
                    ..
                } => {
                    add(outer_deg);
                    for h in holes_deg {
                        add(h);
                    }
                }
            }
        }
        let (lat0, lon0) = if s.is_finite() {
            (0.5 * (s + n), 0.5 * (w + e))
        } else {
            (0.0, 0.0)
        };
        let (my, mx) = cig_geo::metres_per_degree(lat0);
        Frame {
            lat0,
            lon0,
            my,
            mx: mx.max(1.0),
        }
    }

    fn x(&self, lon: f64) -> f64 {
        (lon - self.lon0) * self.mx
    }

    fn y(&self, lat: f64) -> f64 {
        (lat - self.lat0) * self.my
    }

    fn local(&self, (lat, lon): (f64, f64)) -> P {
        (self.x(lon), self.y(lat))
    }
}

fn sub(a: P, b: P) -> P {
    (a.0 - b.0, a.1 - b.1)
}

fn dot(a: P, b: P) -> f64 {
    a.0 * b.0 + a.1 * b.1
}

fn len(a: P) -> f64 {
    dot(a, a).sqrt()
}

/// A centripetal Catmull-Rom spline through `pts`, each span sampled at most `step` apart.
fn smooth_line(pts: &[P], step: f64) -> Vec<P> {
    let pts: Vec<P> = {
        let mut v: Vec<P> = Vec::with_capacity(pts.len());
        for &p in pts {
            if v.last().is_none_or(|&q| len(sub(p, q)) > 1e-6) {
                v.push(p);
            }
        }
        v
    };
    if pts.len() < 2 {
        return pts;
    }
    let n = pts.len();
    let get = |i: isize| -> P {
        if i < 0 {
            // Reflected end points keep the end tangents along the first and last spans.
            let (a, b) = (pts[0], pts[1]);
            (2.0 * a.0 - b.0, 2.0 * a.1 - b.1)
        } else if i as usize >= n {
            let (a, b) = (pts[n - 1], pts[n - 2]);
            (2.0 * a.0 - b.0, 2.0 * a.1 - b.1)
        } else {
            pts[i as usize]
        }
    };
    let mut out = vec![pts[0]];
    for i in 0..n - 1 {
        let (p0, p1, p2, p3) = (get(i as isize - 1), pts[i], pts[i + 1], get(i as isize + 2));
        let knot = |a: P, b: P| len(sub(b, a)).sqrt().max(1e-9);
        let t0 = 0.0;
        let t1 = t0 + knot(p0, p1);
        let t2 = t1 + knot(p1, p2);
        let t3 = t2 + knot(p2, p3);
        let chord = len(sub(p2, p1));
        let steps = ((chord / step).ceil() as usize).clamp(1, 4096);
        let lerp = |a: P, b: P, ta: f64, tb: f64, t: f64| -> P {
            let u = (t - ta) / (tb - ta);
            (a.0 + (b.0 - a.0) * u, a.1 + (b.1 - a.1) * u)
        };
        for k in 1..=steps {
            if k == steps {
                out.push(p2);
                break;
            }
            let t = t1 + (t2 - t1) * k as f64 / steps as f64;
            let a1 = lerp(p0, p1, t0, t1, t);
            let a2 = lerp(p1, p2, t1, t2, t);
            let a3 = lerp(p2, p3, t2, t3, t);
            let b1 = lerp(a1, a2, t0, t2, t);
            let b2 = lerp(a2, a3, t1, t3, t);
            out.push(lerp(b1, b2, t1, t2, t));
        }
    }
    out
}

/// Paint order and style of an item.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum ItemKind {
    Lake,
    River,
    Dirt,
    Paved,
}

/// One feature in the local frame.
#[derive(Clone, Debug)]
struct Item {
    kind: ItemKind,
    half_w: f64,
    /// Width of the soft edge, metres (0 for a hard edge).
    soft: f64,
    /// Lines: one smoothed centre line. Lakes: the rings, outer first, not closed.
    rings: Vec<Vec<P>>,
    level_m: Option<f64>,
    /// Lines: arc length of the smoothed centre line, metres.
    total_m: f64,
    /// (xmin, ymin, xmax, ymax), unexpanded.
    bbox: (f64, f64, f64, f64),
}

impl Item {
    /// How far from its segments the item can colour a texel whose footprint is `fp`.
    fn reach(&self, fp: f64) -> f64 {
        self.half_w + 0.5 * fp.max(self.soft)
    }
}

#[derive(Clone, Copy, Debug)]
struct Seg {
    item: u32,
    a: P,
    b: P,
    /// Arc length at `a` along the item's line.
    s0: f64,
}

impl Seg {
    /// Distance from `p`, arc length at the nearest point, and the unit direction.
    #[inline]
    fn nearest(&self, p: P) -> (f64, f64, P) {
        let ab = sub(self.b, self.a);
        let l2 = dot(ab, ab);
        let t = if l2 > 0.0 {
            (dot(sub(p, self.a), ab) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = (self.a.0 + ab.0 * t, self.a.1 + ab.1 * t);
        let l = l2.sqrt();
        let dir = if l > 0.0 {
            (ab.0 / l, ab.1 / l)
        } else {
            (1.0, 0.0)
        };
        (len(sub(p, q)), self.s0 + t * l, dir)
    }

    fn bbox(&self) -> (f64, f64, f64, f64) {
        (
            self.a.0.min(self.b.0),
            self.a.1.min(self.b.1),
            self.a.0.max(self.b.0),
            self.a.1.max(self.b.1),
        )
    }
}

/// Uniform grid of buckets of segment indices (compressed rows).
#[derive(Clone, Debug)]
struct Buckets {
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    starts: Vec<u32>,
    ids: Vec<u32>,
}

impl Buckets {
    fn new(segs: &[Seg]) -> Buckets {
        let (mut x0, mut y0, mut x1, mut y1) =
            (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
        for s in segs {
            let b = s.bbox();
            x0 = x0.min(b.0);
            y0 = y0.min(b.1);
            x1 = x1.max(b.2);
            y1 = y1.max(b.3);
        }
        if !x0.is_finite() {
            (x0, y0, x1, y1) = (0.0, 0.0, 1.0, 1.0);
        }
        let extent = (x1 - x0).max(y1 - y0).max(1.0);
        let cell = (extent / 512.0).max(32.0);
        let nx = ((x1 - x0) / cell).floor() as usize + 1;
        let ny = ((y1 - y0) / cell).floor() as usize + 1;
        let mut b = Buckets {
            x0,
            y0,
            cell,
            nx,
            ny,
            starts: vec![0; nx * ny + 1],
            ids: Vec::new(),
        };
        for pass in 0..2 {
            let mut fill = if pass == 1 {
                b.starts.clone()
            } else {
                Vec::new()
            };
            if pass == 1 {
                b.ids = vec![0; b.starts[nx * ny] as usize];
            }
            for (k, s) in segs.iter().enumerate() {
                let (c0, r0, c1, r1) = b.range(s.bbox());
                for r in r0..=r1 {
                    for c in c0..=c1 {
                        let cell = r * nx + c;
                        if pass == 0 {
                            b.starts[cell + 1] += 1;
                        } else {
                            b.ids[fill[cell] as usize] = k as u32;
                            fill[cell] += 1;
                        }
                    }
                }
            }
            if pass == 0 {
                for i in 0..nx * ny {
                    b.starts[i + 1] += b.starts[i];
                }
            }
        }
        b
    }

    /// Bucket columns and rows (c0, r0, c1, r1) overlapping a box, clamped.
    fn range(&self, (xa, ya, xb, yb): (f64, f64, f64, f64)) -> (usize, usize, usize, usize) {
        let idx = |v: f64, o: f64, n: usize| -> usize {
            let k = ((v - o) / self.cell).floor();
            if k.is_nan() || k < 0.0 {
                0
            } else {
                (k as usize).min(n - 1)
            }
        };
        (
            idx(xa, self.x0, self.nx),
            idx(ya, self.y0, self.ny),
            idx(xb, self.x0, self.nx),
            idx(yb, self.y0, self.ny),
        )
    }

    /// Sorted, distinct segment indices in buckets overlapping the box.
    fn query(&self, bx: (f64, f64, f64, f64)) -> Vec<u32> {
        if bx.2 < self.x0
            || bx.3 < self.y0
            || bx.0 > self.x0 + self.nx as f64 * self.cell
            || bx.1 > self.y0 + self.ny as f64 * self.cell
        {
            return Vec::new();
        }
        let (c0, r0, c1, r1) = self.range(bx);
        let mut out = Vec::new();
        for r in r0..=r1 {
            for c in c0..=c1 {
                let cell = r * self.nx + c;
                out.extend_from_slice(
                    &self.ids[self.starts[cell] as usize..self.starts[cell + 1] as usize],
                );
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

fn boxes_meet(a: (f64, f64, f64, f64), b: (f64, f64, f64, f64)) -> bool {
    a.0 <= b.2 && b.0 <= a.2 && a.1 <= b.3 && b.1 <= a.3
}

fn grow(b: (f64, f64, f64, f64), r: f64) -> (f64, f64, f64, f64) {
    (b.0 - r, b.1 - r, b.2 + r, b.3 + r)
}

/// Sorted x of the crossings of the horizontal line at `y` with the rings (half-open rule).
fn crossings(rings: &[Vec<P>], y: f64, out: &mut Vec<f64>) {
    out.clear();
    for ring in rings {
        let n = ring.len();
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            if (a.1 <= y) != (b.1 <= y) {
                out.push(a.0 + (y - a.1) * (b.0 - a.0) / (b.1 - a.1));
            }
        }
    }
    out.sort_unstable_by(f64::total_cmp);
}

/// Fraction of `[c - e/2, c + e/2]` inside `[lo, hi]`.
#[inline]
fn overlap(c: f64, e: f64, lo: f64, hi: f64) -> f64 {
    let e = e.max(1e-9);
    ((c + 0.5 * e).min(hi) - (c - 0.5 * e).max(lo)).max(0.0) / e
}

/// The prepared features: smoothed, indexed, ready to paint.
#[derive(Clone, Debug)]
pub struct FeatureLayer {
    frame: Frame,
    items: Vec<Item>,
    segs: Vec<Seg>,
    buckets: Buckets,
    max_reach_m: f64,
}

const ASPHALT: [f64; 3] = [78.0, 80.0, 83.0];
const MARKING: [f64; 3] = [228.0, 228.0, 222.0];
const DIRT: [f64; 3] = [146.0, 116.0, 76.0];
const WATER: [f64; 3] = [34.0, 66.0, 72.0];
const EDGE_LINE_W_M: f64 = 0.15;
const EDGE_LINE_INSET_M: f64 = 0.3;
const DASH_M: f64 = 3.0;
const DASH_PERIOD_M: f64 = 12.0;

/// Integer-lattice value noise in [-1, 1].
fn value_noise(x: f64, y: f64) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (u, v) = (x - fx, y - fy);
    let h = |i: i64, j: i64| -> f64 {
        let mut z = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let (i, j) = (fx as i64, fy as i64);
    let (u, v) = (u * u * (3.0 - 2.0 * u), v * v * (3.0 - 2.0 * v));
    let a = h(i, j) + (h(i + 1, j) - h(i, j)) * u;
    let b = h(i, j + 1) + (h(i + 1, j + 1) - h(i, j + 1)) * u;
    a + (b - a) * v
}

fn srgb_mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// Dashed length in `[0, s]` of the centre line's pattern.
fn dashed_length(s: f64) -> f64 {
    let k = (s / DASH_PERIOD_M).floor();
    k * DASH_M + (s - k * DASH_PERIOD_M).min(DASH_M)
}

/// Per-texel nearest-segment state of the item being painted.
struct Scratch {
    d: Vec<f64>,
    s: Vec<f64>,
    dir: Vec<P>,
    touched: Vec<u32>,
}

impl FeatureLayer {
    /// Validates, smooths and indexes the features.
    pub fn new(features: &[Feature]) -> Result<FeatureLayer, FeatureError> {
        validate_features(features)?;
        let frame = Frame::for_features(features);
        let mut items: Vec<(ItemKind, usize, Item)> = Vec::new();
        for (index, f) in features.iter().enumerate() {
            let item = match f {
                Feature::Line {
                    kind,
                    width_m,
                    points_deg,
                } => {
                    let local: Vec<P> = points_deg.iter().map(|&p| frame.local(p)).collect();
                    let line = smooth_line(&local, (0.25 * width_m).max(0.05));
                    let (ik, soft) = match kind {
                        LineKind::PavedRoad => (ItemKind::Paved, 0.0),
                        LineKind::DirtRoad => (ItemKind::Dirt, 0.3 * width_m),
                        LineKind::River => (ItemKind::River, (0.25 * width_m).clamp(1.0, 25.0)),
                    };
                    Item {
                        kind: ik,
                        half_w: 0.5 * width_m,
                        soft,
                        rings: vec![line],
                        level_m: None,
                        total_m: 0.0,
                        bbox: (0.0, 0.0, 0.0, 0.0),
                    }
                }
                Feature::Lake {
                    outer_deg,
                    holes_deg,
                    level_m,
                } => Item {
                    kind: ItemKind::Lake,
                    half_w: 0.0,
                    soft: 0.0,
                    rings: std::iter::once(outer_deg)
                        .chain(holes_deg)
                        .map(|r| ring_points(r).iter().map(|&p| frame.local(p)).collect())
                        .collect(),
                    level_m: *level_m,
                    total_m: 0.0,
                    bbox: (0.0, 0.0, 0.0, 0.0),
                },
            };
            items.push((item.kind, index, item));
        }
        items.sort_by_key(|(k, i, _)| (*k, *i));
        let mut items: Vec<Item> = items.into_iter().map(|(_, _, it)| it).collect();
        let mut segs = Vec::new();
        let mut max_reach_m: f64 = 0.0;
        for (k, item) in items.iter_mut().enumerate() {
            let mut bb = (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
            for ring in &item.rings {
                for &p in ring {
                    bb = (bb.0.min(p.0), bb.1.min(p.1), bb.2.max(p.0), bb.3.max(p.1));
                }
                let n = ring.len();
                let closed = item.kind == ItemKind::Lake;
                let count = if closed { n } else { n.saturating_sub(1) };
                let mut s0 = 0.0;
                for i in 0..count {
                    let (a, b) = (ring[i], ring[(i + 1) % n]);
                    segs.push(Seg {
                        item: k as u32,
                        a,
                        b,
                        s0,
                    });
                    s0 += len(sub(b, a));
                }
            }
            item.bbox = bb;
            if item.kind != ItemKind::Lake {
                item.total_m = item.rings[0].windows(2).map(|w| len(sub(w[1], w[0]))).sum();
            }
            max_reach_m = max_reach_m.max(item.half_w + 0.5 * item.soft);
        }
        let buckets = Buckets::new(&segs);
        Ok(FeatureLayer {
            frame,
            items,
            segs,
            buckets,
            max_reach_m,
        })
    }

    /// True when the layer has no feature.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The coarsest texel that shows the narrowest line well, metres: an eighth of its width
    /// (a 4 m track over eight texels, its edges anti-aliased), never finer than 0.4 m (the
    /// markings, 0.15 m wide, are drawn by their coverage), with a factor of the square root
    /// of two to spare (texel sizes come in powers of two); 4 m for lakes alone. The pyramid's
    /// finest level is chosen no coarser than this, so the layer paints at that level.
    pub fn finest_texel_m(&self) -> f64 {
        let narrowest = self
            .items
            .iter()
            .filter(|i| i.kind != ItemKind::Lake)
            .map(|i| 2.0 * i.half_w)
            .fold(f64::INFINITY, f64::min);
        let wanted = if narrowest.is_finite() {
            (narrowest / 8.0).max(0.4)
        } else {
            4.0
        };
        wanted * std::f64::consts::SQRT_2
    }

    /// The coarsest imagery level whose texels are no larger than
    /// [`FeatureLayer::finest_texel_m`] (level 0 when even its texels are larger), clamped to
    /// the layout's levels.
    pub fn native_level(&self, layout: &ImageryLayout) -> u8 {
        let target = self.finest_texel_m();
        let t0 = (layout.texel_lat_deg * self.frame.my).min(layout.texel_lon_deg * self.frame.mx);
        let mut level = 0u8;
        // A hundredth to spare, as `ImageryLayout::fine_shift_for` allows.
        while level + 1 < layout.levels
            && t0 * f64::from(1u32 << (level + 1).min(31)) <= target * 1.01
        {
            level += 1;
        }
        level
    }

    fn local_box(&self, (s, w, n, e): (f64, f64, f64, f64)) -> (f64, f64, f64, f64) {
        (
            self.frame.x(w),
            self.frame.y(s),
            self.frame.x(e),
            self.frame.y(n),
        )
    }

    /// True when painting a tile with these bounds, degrees (south, west, north, east), could
    /// change any texel.
    pub fn touches(&self, bounds_deg: (f64, f64, f64, f64)) -> bool {
        let bx = self.local_box(bounds_deg);
        let margin = 1.0;
        let near = self
            .buckets
            .query(grow(bx, self.max_reach_m + margin))
            .into_iter()
            .any(|k| {
                let s = &self.segs[k as usize];
                let it = &self.items[s.item as usize];
                boxes_meet(grow(s.bbox(), it.half_w + 0.5 * it.soft + margin), bx)
            });
        if near {
            return true;
        }
        // A tile wholly inside a lake meets none of its edges.
        let centre = (0.5 * (bx.0 + bx.2), 0.5 * (bx.1 + bx.3));
        let mut xs = Vec::new();
        self.items.iter().any(|it| {
            if it.kind != ItemKind::Lake || !boxes_meet(it.bbox, bx) {
                return false;
            }
            crossings(&it.rings, centre.1, &mut xs);
            xs.iter().filter(|&&x| x < centre.0).count() % 2 == 1
        })
    }

    /// Paints the features over a tile's sRGB RGBA texels (`tile_texels^2 * 4` bytes, rows from
    /// the south). A buffer of the wrong size is left as it is.
    pub fn paint(&self, layout: &ImageryLayout, key: ImageryKey, rgba: &mut [u8]) {
        let n = layout.tile_texels as usize;
        if rgba.len() != n * n * 4 || n == 0 {
            debug_assert!(false, "imagery tile buffer of {} bytes", rgba.len());
            return;
        }
        let (tlat, tlon) = layout.texel_deg(key.level);
        let (dyt, dxt) = (tlat * self.frame.my, tlon * self.frame.mx);
        let fp_max = dxt.max(dyt);
        let row0 = u64::from(key.row) * n as u64;
        let col0 = u64::from(key.col) * n as u64;
        let ys: Vec<f64> = (0..n)
            .map(|i| {
                self.frame
                    .y(layout.texel_centre_deg(key.level, row0 + i as u64, col0).0)
            })
            .collect();
        let xs: Vec<f64> = (0..n)
            .map(|j| {
                self.frame
                    .x(layout.texel_centre_deg(key.level, row0, col0 + j as u64).1)
            })
            .collect();
        let tile_box = (
            xs[0] - 0.5 * dxt,
            ys[0] - 0.5 * dyt,
            xs[n - 1] + 0.5 * dxt,
            ys[n - 1] + 0.5 * dyt,
        );
        let cands = self
            .buckets
            .query(grow(tile_box, self.max_reach_m + fp_max));
        let any_lake = self
            .items
            .iter()
            .any(|it| it.kind == ItemKind::Lake && boxes_meet(grow(it.bbox, fp_max), tile_box));
        if cands.is_empty() && !any_lake {
            return;
        }
        // Composite state: colour over the original, and the transmittance of the original.
        let mut rgb: Vec<[f64; 3]> = (0..n * n)
            .map(|k| {
                [
                    f64::from(rgba[4 * k]),
                    f64::from(rgba[4 * k + 1]),
                    f64::from(rgba[4 * k + 2]),
                ]
            })
            .collect();
        let mut trans = vec![1.0f64; n * n];
        let mut sc = Scratch {
            d: vec![f64::INFINITY; n * n],
            s: vec![0.0; n * n],
            dir: vec![(1.0, 0.0); n * n],
            touched: Vec::new(),
        };
        let mut xcross = Vec::new();
        let mut ci = 0usize;
        for (item_id, item) in self.items.iter().enumerate() {
            let start = ci;
            while ci < cands.len() && self.segs[cands[ci] as usize].item as usize == item_id {
                ci += 1;
            }
            let my_segs = &cands[start..ci];
            let reach = if item.kind == ItemKind::Lake {
                0.5 * fp_max
            } else {
                item.reach(fp_max)
            };
            // Nearest segment of this item for every texel within reach.
            for &k in my_segs {
                let seg = &self.segs[k as usize];
                let bb = grow(seg.bbox(), reach);
                if !boxes_meet(bb, tile_box) {
                    continue;
                }
                let (i0, i1) = index_range(bb.1, bb.3, ys[0], dyt, n);
                let (j0, j1) = index_range(bb.0, bb.2, xs[0], dxt, n);
                for i in i0..i1 {
                    for j in j0..j1 {
                        let (d, s, dir) = seg.nearest((xs[j], ys[i]));
                        if d >= reach {
                            continue;
                        }
                        let t = i * n + j;
                        if sc.d[t] == f64::INFINITY {
                            sc.touched.push(t as u32);
                        }
                        if d < sc.d[t] || (d == sc.d[t] && s < sc.s[t]) {
                            sc.d[t] = d;
                            sc.s[t] = s;
                            sc.dir[t] = dir;
                        }
                    }
                }
            }
            let mut put = |t: usize, cov: f64, col: [f64; 3]| {
                if cov <= 0.0 {
                    return;
                }
                let cov = cov.min(1.0);
                rgb[t] = srgb_mix(rgb[t], col, cov);
                trans[t] *= 1.0 - cov;
            };
            let footprint = |dir: P| dir.1.abs() * dxt + dir.0.abs() * dyt;
            if item.kind == ItemKind::Lake {
                if !boxes_meet(grow(item.bbox, fp_max), tile_box) {
                    continue;
                }
                let (i0, i1) = index_range(item.bbox.1, item.bbox.3, ys[0], dyt, n);
                for i in i0..i1 {
                    crossings(&item.rings, ys[i], &mut xcross);
                    if xcross.is_empty() {
                        continue;
                    }
                    let mut inside = false;
                    let mut c = 0usize;
                    let (j0, j1) = index_range(
                        xcross[0] - fp_max,
                        xcross[xcross.len() - 1] + fp_max,
                        xs[0],
                        dxt,
                        n,
                    );
                    for j in j0..j1 {
                        while c < xcross.len() && xcross[c] <= xs[j] {
                            inside = !inside;
                            c += 1;
                        }
                        let t = i * n + j;
                        let d = sc.d[t];
                        let cov = if d.is_finite() {
                            let fp = footprint(sc.dir[t]).max(1e-6);
                            let edge = (0.5 + d / fp).min(1.0);
                            if inside {
                                edge
                            } else {
                                1.0 - edge
                            }
                        } else if inside {
                            1.0
                        } else {
                            0.0
                        };
                        put(t, cov, WATER);
                    }
                }
            } else {
                for &t in &sc.touched {
                    let t = t as usize;
                    let (d, s, dir) = (sc.d[t], sc.s[t], sc.dir[t]);
                    let fp = footprint(dir).max(1e-6);
                    let e = fp.max(item.soft);
                    let cov = overlap(d, e, -item.half_w, item.half_w);
                    if cov <= 0.0 {
                        continue;
                    }
                    let col = match item.kind {
                        ItemKind::River => WATER,
                        ItemKind::Dirt => DIRT,
                        _ => {
                            let (x, y) = (xs[t % n], ys[t / n]);
                            self.asphalt(item, d, s, dir, fp, (x, y), (dxt, dyt))
                        }
                    };
                    put(t, cov, col);
                }
            }
            for &t in &sc.touched {
                sc.d[t as usize] = f64::INFINITY;
            }
            sc.touched.clear();
        }
        for k in 0..n * n {
            let cov = 1.0 - trans[k];
            if cov <= 0.0 {
                continue;
            }
            let px = &mut rgba[4 * k..4 * k + 4];
            // "Over" with straight alpha: the features' own colour (the blend un-done) covers
            // `cov` of the texel, what was there the rest; over a transparent texel the
            // coverage becomes the alpha, so a road narrower than a coarse texel fades rather
            // than vanishing or filling the texel.
            let base = [f64::from(px[0]), f64::from(px[1]), f64::from(px[2])];
            let below = f64::from(px[3]) / 255.0;
            let t = trans[k];
            let alpha = cov + below * t;
            for c in 0..3 {
                let own = (rgb[k][c] - base[c] * t) / cov;
                let colour = (own * cov + base[c] * below * t) / alpha;
                px[c] = colour.round().clamp(0.0, 255.0) as u8;
            }
            px[3] = (alpha * 255.0).round().clamp(0.0, 255.0) as u8;
        }
    }

    /// Asphalt with its markings at a texel `d` from the centre line, `s` along it.
    #[allow(clippy::too_many_arguments)]
    fn asphalt(
        &self,
        item: &Item,
        d: f64,
        s: f64,
        dir: P,
        fp: f64,
        (x, y): P,
        (dxt, dyt): P,
    ) -> [f64; 3] {
        let w = 2.0 * item.half_w;
        let amp = 6.0 / (1.0 + fp);
        let v = amp
            * (0.6 * value_noise(x / 1.7, y / 1.7) + 0.4 * value_noise(x / 6.1 + 17.0, y / 6.1));
        let base = [ASPHALT[0] + v, ASPHALT[1] + v, ASPHALT[2] + v];
        let edges = w >= 4.0;
        let centre = w >= 5.0;
        // No markings round the ends, which lie in junctions.
        let m = if s <= 0.0 || s >= item.total_m {
            0.0
        } else if fp <= MARKING_MAX_TEXEL_M {
            let mut m: f64 = 0.0;
            if edges {
                let off = item.half_w - EDGE_LINE_INSET_M - 0.5 * EDGE_LINE_W_M;
                m = m.max(overlap(
                    d,
                    fp,
                    off - 0.5 * EDGE_LINE_W_M,
                    off + 0.5 * EDGE_LINE_W_M,
                ));
            }
            if centre {
                let across = overlap(d, fp, -0.5 * EDGE_LINE_W_M, 0.5 * EDGE_LINE_W_M);
                if across > 0.0 {
                    let fa = (dir.0.abs() * dxt + dir.1.abs() * dyt).max(1e-6);
                    let along = (dashed_length(s + 0.5 * fa) - dashed_length(s - 0.5 * fa)) / fa;
                    m = m.max(across * along);
                }
            }
            m
        } else {
            let mut area = 0.0;
            if edges {
                area += 2.0 * EDGE_LINE_W_M;
            }
            if centre {
                area += EDGE_LINE_W_M * DASH_M / DASH_PERIOD_M;
            }
            area / w
        };
        srgb_mix(base, MARKING, m.clamp(0.0, 1.0))
    }
}

/// Indices `[lo, hi)` of the lattice `first + k * step` (k < n) within `[a, b]`, widened by
/// one each way (the caller tests each).
fn index_range(a: f64, b: f64, first: f64, step: f64, n: usize) -> (usize, usize) {
    let lo = ((a - first) / step).floor() - 1.0;
    let hi = ((b - first) / step).ceil() + 2.0;
    let clamp = |v: f64| -> usize {
        if v.is_nan() || v <= 0.0 {
            0
        } else {
            (v as usize).min(n)
        }
    };
    (clamp(lo), clamp(hi))
}

/// What [`level_terrain`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LevelReport {
    /// Posts given a road's height (shoulders included).
    pub road_posts: usize,
    /// Posts set to a lake's level.
    pub lake_posts: usize,
    /// Posts whose material was set (road or water).
    pub material_posts: usize,
}

/// Bilinear height at a fractional post index; `NaN` outside or over voids.
fn bilinear(r: &Raster, fr: f64, fc: f64) -> f64 {
    let g = r.grid;
    if !(fr >= 0.0 && fc >= 0.0) || g.rows < 2 || g.cols < 2 {
        return f64::NAN;
    }
    let r0 = (fr.floor() as usize).min(g.rows - 2);
    let c0 = (fc.floor() as usize).min(g.cols - 2);
    let (v, u) = (fr - r0 as f64, fc - c0 as f64);
    if v > 1.0 || u > 1.0 {
        return f64::NAN;
    }
    let h = |rr: usize, cc: usize| f64::from(r.elevation_at(rr, cc));
    let a = h(r0, c0) + (h(r0, c0 + 1) - h(r0, c0)) * u;
    let b = h(r0 + 1, c0) + (h(r0 + 1, c0 + 1) - h(r0 + 1, c0)) * u;
    a + (b - a) * v
}

/// Levels the terrain under the features and sets the materials under them (run after voids
/// are filled, before the pyramid is built, so HOT, HAT and LOS answer on the result).
///
/// Roads: every post within half the width plus one post spacing of the smoothed centre line
/// takes the line's height there (bilinear samples along the line, averaged over
/// [`ROAD_PROFILE_WINDOW_M`]), blended back to its own height over one more spacing; posts of
/// rivers and lakes are left alone (a crossing is a bridge). Lakes with a level: every post
/// inside is set to it. Rivers: heights unchanged. Materials (when the raster has none they are
/// classified first): paved or dirt road within `max(half width, half a spacing)` of a road,
/// water likewise under rivers and inside lakes.
pub fn level_terrain(
    raster: &mut Raster,
    features: &[Feature],
) -> Result<LevelReport, FeatureError> {
    let layer = FeatureLayer::new(features)?;
    let mut report = LevelReport::default();
    let g = raster.grid;
    if g.rows < 2 || g.cols < 2 || layer.is_empty() {
        return Ok(report);
    }
    if raster.material.is_none() && raster.void_count() == 0 {
        crate::classify::classify_materials(raster);
    }
    let fr = &layer.frame;
    let spacing = (g.dlat_deg * fr.my).max(g.dlon_deg * fr.mx);
    let post_y: Vec<f64> = (0..g.rows)
        .map(|r| fr.y(g.post_lat_lon_deg(r, 0).0))
        .collect();
    let post_x: Vec<f64> = (0..g.cols)
        .map(|c| fr.x(g.post_lat_lon_deg(0, c).1))
        .collect();
    let (dy, dx) = (post_y[1] - post_y[0], post_x[1] - post_x[0]);
    let original = raster.clone();
    let n = g.len();
    // Per post: the nearest distance of each item in turn (reset after each).
    let mut best_d = vec![f64::INFINITY; n];
    let mut best_s = vec![0.0f64; n];
    let mut touched: Vec<usize> = Vec::new();
    let mut protect = vec![false; n];
    // Road candidates: (weight, target height, distance).
    let mut road: Vec<(f64, f64, f64)> = vec![(0.0, 0.0, f64::INFINITY); n];
    let mut material: Vec<Option<(u8, f64, Material)>> = vec![None; n];
    let mut xcross = Vec::new();

    let rasterise = |segs: &[Seg],
                     reach: f64,
                     best_d: &mut [f64],
                     best_s: &mut [f64],
                     touched: &mut Vec<usize>| {
        for seg in segs {
            let bb = grow(seg.bbox(), reach);
            let (i0, i1) = index_range(bb.1, bb.3, post_y[0], dy, g.rows);
            let (j0, j1) = index_range(bb.0, bb.2, post_x[0], dx, g.cols);
            for i in i0..i1 {
                for j in j0..j1 {
                    let (d, s, _) = seg.nearest((post_x[j], post_y[i]));
                    if d > reach {
                        continue;
                    }
                    let t = i * g.cols + j;
                    if best_d[t] == f64::INFINITY {
                        touched.push(t);
                    }
                    if d < best_d[t] || (d == best_d[t] && s < best_s[t]) {
                        best_d[t] = d;
                        best_s[t] = s;
                    }
                }
            }
        }
    };
    let item_segs = |k: usize| -> &[Seg] {
        let a = layer.segs.partition_point(|s| (s.item as usize) < k);
        let b = layer.segs.partition_point(|s| (s.item as usize) <= k);
        &layer.segs[a..b]
    };
    let set_material = |t: usize,
                        prio: u8,
                        d: f64,
                        m: Material,
                        material: &mut Vec<Option<(u8, f64, Material)>>| {
        let better = match material[t] {
            None => true,
            Some((p, dd, _)) => prio > p || (prio == p && d < dd),
        };
        if better {
            material[t] = Some((prio, d, m));
        }
    };

    // Lakes and rivers first: they protect their posts from road levelling.
    let mut lake_inside: Vec<Option<f64>> = vec![None; n];
    for (k, item) in layer.items.iter().enumerate() {
        match item.kind {
            ItemKind::Lake => {
                let (i0, i1) = index_range(item.bbox.1, item.bbox.3, post_y[0], dy, g.rows);
                for i in i0..i1 {
                    crossings(&item.rings, post_y[i], &mut xcross);
                    for pair in xcross.chunks(2) {
                        if pair.len() < 2 {
                            break;
                        }
                        let (j0, j1) = index_range(pair[0], pair[1], post_x[0], dx, g.cols);
                        for j in j0..j1 {
                            if post_x[j] >= pair[0] && post_x[j] < pair[1] {
                                let t = i * g.cols + j;
                                protect[t] = true;
                                lake_inside[t] = Some(item.level_m.unwrap_or(f64::NAN));
                                set_material(t, 3, 0.0, Material::Water, &mut material);
                            }
                        }
                    }
                }
            }
            ItemKind::River => {
                let reach = item.half_w.max(0.5 * spacing);
                rasterise(item_segs(k), reach, &mut best_d, &mut best_s, &mut touched);
                for &t in &touched {
                    protect[t] = true;
                    set_material(t, 3, best_d[t], Material::Water, &mut material);
                    best_d[t] = f64::INFINITY;
                }
                touched.clear();
            }
            _ => {}
        }
    }
    // Roads.
    for (k, item) in layer.items.iter().enumerate() {
        if !matches!(item.kind, ItemKind::Paved | ItemKind::Dirt) {
            continue;
        }
        let line = &item.rings[0];
        let total: f64 = line.windows(2).map(|w| len(sub(w[1], w[0]))).sum();
        // Uniform samples of the terrain along the line, then a moving average.
        let ds = (0.5 * spacing).clamp(0.5, 5.0);
        let samples = ((total / ds).ceil() as usize).max(1) + 1;
        let mut heights = Vec::with_capacity(samples);
        let mut seg_i = 0usize;
        let mut seg_s0 = 0.0;
        for q in 0..samples {
            let s = (q as f64 * ds).min(total);
            while seg_i + 2 < line.len() && seg_s0 + len(sub(line[seg_i + 1], line[seg_i])) < s {
                seg_s0 += len(sub(line[seg_i + 1], line[seg_i]));
                seg_i += 1;
            }
            let (a, b) = (line[seg_i], line[(seg_i + 1).min(line.len() - 1)]);
            let l = len(sub(b, a));
            let u = if l > 0.0 {
                ((s - seg_s0) / l).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let p = (a.0 + (b.0 - a.0) * u, a.1 + (b.1 - a.1) * u);
            let h = bilinear(&original, (p.1 - post_y[0]) / dy, (p.0 - post_x[0]) / dx);
            heights.push(h);
        }
        let half = ((0.5 * ROAD_PROFILE_WINDOW_M / ds).round() as usize).max(1);
        let mut prefix = vec![(0.0f64, 0usize); samples + 1];
        for q in 0..samples {
            let (sum, cnt) = prefix[q];
            prefix[q + 1] = if heights[q].is_finite() {
                (sum + heights[q], cnt + 1)
            } else {
                (sum, cnt)
            };
        }
        let profile: Vec<f64> = (0..samples)
            .map(|q| {
                let (a, b) = (q.saturating_sub(half), (q + half + 1).min(samples));
                let cnt = prefix[b].1 - prefix[a].1;
                if cnt == 0 {
                    f64::NAN
                } else {
                    (prefix[b].0 - prefix[a].0) / cnt as f64
                }
            })
            .collect();
        let at = |s: f64| -> f64 {
            let f = (s / ds).clamp(0.0, (samples - 1) as f64);
            let q = (f.floor() as usize).min(samples - 1);
            let q1 = (q + 1).min(samples - 1);
            profile[q] + (profile[q1] - profile[q]) * (f - q as f64)
        };
        let core = item.half_w + spacing;
        let reach = core + spacing;
        rasterise(item_segs(k), reach, &mut best_d, &mut best_s, &mut touched);
        let (prio, m) = if item.kind == ItemKind::Paved {
            (2, Material::PavedRoad)
        } else {
            (1, Material::DirtRoad)
        };
        for &t in &touched {
            let (d, s) = (best_d[t], best_s[t]);
            best_d[t] = f64::INFINITY;
            if protect[t] {
                continue;
            }
            let target = at(s);
            if target.is_finite() {
                let w = if d <= core {
                    1.0
                } else {
                    1.0 - (d - core) / spacing
                };
                let w = w.clamp(0.0, 1.0);
                let c = road[t];
                if w > c.0 || (w == c.0 && d < c.2) {
                    road[t] = (w, target, d);
                }
            }
            if d <= item.half_w.max(0.5 * spacing) {
                set_material(t, prio, d, m, &mut material);
            }
        }
        touched.clear();
    }
    for t in 0..n {
        let (w, target, _) = road[t];
        if w > 0.0 {
            let h0 = f64::from(original.elevation_m[t]);
            let h = if h0.is_finite() {
                h0 + (target - h0) * w
            } else {
                target
            };
            raster.elevation_m[t] = h as f32;
            report.road_posts += 1;
        }
        if let Some(level) = lake_inside[t] {
            if level.is_finite() {
                raster.elevation_m[t] = level as f32;
                report.lake_posts += 1;
            }
        }
    }
    if let Some(mats) = raster.material.as_mut() {
        for (t, m) in material.iter().enumerate() {
            if let Some((_, _, m)) = m {
                mats[t] = *m;
                report.material_posts += 1;
            }
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{triangulated_height, Diagonal, GeoGrid};
    use proptest::prelude::*;

    const LAT: f64 = 36.0;
    const LON: f64 = -121.0;

    /// 30 m posts at 36 N; `posts` a side.
    fn grid(posts: usize) -> GeoGrid {
        let (my, mx) = cig_geo::metres_per_degree(LAT);
        GeoGrid {
            south_lat_deg: LAT,
            west_lon_deg: LON,
            dlat_deg: 30.0 / my,
            dlon_deg: 30.0 / mx,
            rows: posts,
            cols: posts,
        }
    }

    /// Level-0 texels of 30 m / 64 = 0.47 m.
    fn layout() -> ImageryLayout {
        ImageryLayout::new(&grid(65), 6)
    }

    /// Metres per level-0 texel.
    fn texel_m(l: &ImageryLayout) -> f64 {
        l.texel_lat_deg * cig_geo::metres_per_degree(LAT).0
    }

    /// A point at level-0 texel coordinates (row, col).
    fn at(l: &ImageryLayout, row: f64, col: f64) -> (f64, f64) {
        (
            l.south_lat_deg + row * l.texel_lat_deg,
            l.west_lon_deg + col * l.texel_lon_deg,
        )
    }

    fn road(kind: LineKind, width_m: f64, pts: Vec<(f64, f64)>) -> Feature {
        Feature::Line {
            kind,
            width_m,
            points_deg: pts,
        }
    }

    fn paint(
        layer: &FeatureLayer,
        l: &ImageryLayout,
        key: ImageryKey,
        fill: impl Fn(u64, u64) -> [u8; 4],
    ) -> Vec<u8> {
        let n = l.tile_texels as usize;
        let mut rgba = vec![0u8; n * n * 4];
        for i in 0..n {
            for j in 0..n {
                let px = fill(
                    u64::from(key.row) * n as u64 + i as u64,
                    u64::from(key.col) * n as u64 + j as u64,
                );
                rgba[4 * (i * n + j)..4 * (i * n + j) + 4].copy_from_slice(&px);
            }
        }
        layer.paint(l, key, &mut rgba);
        rgba
    }

    fn transparent(_: u64, _: u64) -> [u8; 4] {
        [0, 0, 0, 0]
    }

    fn key(level: u8, row: u32, col: u32) -> ImageryKey {
        ImageryKey { level, row, col }
    }

    #[test]
    fn validation_names_the_feature_and_the_reason() {
        let ok = road(
            LineKind::PavedRoad,
            7.0,
            vec![(36.0, -121.0), (36.001, -121.0)],
        );
        assert_eq!(validate_features(std::slice::from_ref(&ok)), Ok(()));
        let cases = [
            (
                road(LineKind::River, 7.0, vec![(36.0, -121.0), (36.0, -121.0)]),
                "needs at least 2",
            ),
            (
                road(LineKind::River, 0.0, vec![(36.0, -121.0), (36.1, -121.0)]),
                "width 0 m",
            ),
            (
                road(LineKind::River, 1e6, vec![(36.0, -121.0), (36.1, -121.0)]),
                "at most",
            ),
            (
                road(
                    LineKind::River,
                    f64::NAN,
                    vec![(36.0, -121.0), (36.1, -121.0)],
                ),
                "width NaN",
            ),
            (
                road(
                    LineKind::River,
                    5.0,
                    vec![(36.0, -121.0), (f64::NAN, -121.0)],
                ),
                "point 1",
            ),
            (
                road(LineKind::River, 5.0, vec![(36.0, -121.0), (95.0, -121.0)]),
                "point 1",
            ),
            (
                Feature::Lake {
                    outer_deg: vec![(36.0, -121.0), (36.1, -121.0), (36.0, -121.0)],
                    holes_deg: vec![],
                    level_m: None,
                },
                "lake ring",
            ),
            (
                Feature::Lake {
                    outer_deg: vec![(36.0, -121.0), (36.1, -121.0), (36.1, -121.1)],
                    holes_deg: vec![],
                    level_m: Some(f64::INFINITY),
                },
                "level",
            ),
        ];
        for (f, want) in cases {
            let err = validate_features(&[ok.clone(), f.clone()]).expect_err("refused");
            let msg = err.to_string();
            assert!(msg.contains(want) && msg.ends_with("(feature 1)"), "{msg}");
            assert!(FeatureLayer::new(&[f]).is_err());
        }
        assert_eq!(
            FeatureKind::from_name("track"),
            Some(FeatureKind::Line(LineKind::DirtRoad))
        );
        assert_eq!(
            FeatureKind::from_name("Road"),
            Some(FeatureKind::Line(LineKind::PavedRoad))
        );
        assert_eq!(FeatureKind::from_name("canal"), None);
        for name in FeatureKind::NAMES {
            let k = FeatureKind::from_name(name).expect("known");
            assert_eq!(FeatureKind::from_name(k.name()), Some(k));
        }
    }

    /// A straight road painted at level 0 and level 2 is as wide as it should be, within a
    /// texel, in every column.
    #[test]
    fn a_straight_road_is_painted_at_its_width() {
        let l = layout();
        let t = texel_m(&l);
        for (width, level) in [(7.0, 0u8), (7.0, 2), (3.0, 0), (12.0, 1)] {
            let layer = FeatureLayer::new(&[road(
                LineKind::PavedRoad,
                width,
                vec![at(&l, 100.3, -40.0), at(&l, 100.3, 2000.0)],
            )])
            .expect("valid");
            let rgba = paint(&layer, &l, key(level, 0, 0), transparent);
            let n = 256;
            let want = width / (t * f64::from(1u32 << level));
            for j in 5..n - 5 {
                // Texels more than half covered (the coverage is their alpha).
                let painted = (0..n).filter(|&i| rgba[4 * (i * n + j) + 3] > 127).count();
                assert!(
                    (painted as f64 - want).abs() <= 1.0,
                    "width {width} level {level} column {j}: {painted} texels, want {want:.2}"
                );
            }
        }
    }

    /// A zig-zag polyline becomes a smooth centre line (no corner above a few degrees) and the
    /// painted edges turn by at most a texel per column.
    #[test]
    fn a_zig_zag_becomes_a_smooth_ribbon() {
        let l = layout();
        let t = texel_m(&l);
        let pts: Vec<(f64, f64)> = (0..12)
            .map(|k| {
                at(
                    &l,
                    128.0 + if k % 2 == 0 { 6.0 } else { -6.0 } / t,
                    -20.0 + k as f64 * 30.0 / t,
                )
            })
            .collect();
        let layer = FeatureLayer::new(&[road(LineKind::DirtRoad, 4.0, pts)]).expect("valid");
        let line = &layer.items[0].rings[0];
        for w in line.windows(3) {
            let (a, b) = (sub(w[1], w[0]), sub(w[2], w[1]));
            let turn = (a.0 * b.1 - a.1 * b.0).atan2(dot(a, b)).abs().to_degrees();
            assert!(turn < 8.0, "corner of {turn} degrees");
        }
        let rgba = paint(&layer, &l, key(0, 0, 0), transparent);
        let n = 256;
        let top: Vec<i64> = (0..n)
            .map(|j| {
                (0..n)
                    .filter(|&i| rgba[4 * (i * n + j) + 3] == 255)
                    .max()
                    .expect("painted") as i64
            })
            .collect();
        let bottom: Vec<i64> = (0..n)
            .map(|j| {
                (0..n)
                    .filter(|&i| rgba[4 * (i * n + j) + 3] == 255)
                    .min()
                    .expect("painted") as i64
            })
            .collect();
        for edge in [&top, &bottom] {
            for j in 1..n - 1 {
                let second = edge[j + 1] - 2 * edge[j] + edge[j - 1];
                assert!(
                    second.abs() <= 1,
                    "edge turns by {second} texels at column {j}"
                );
            }
        }
    }

    fn mixed_layer(l: &ImageryLayout) -> FeatureLayer {
        let circle: Vec<(f64, f64)> = (0..40)
            .map(|k| {
                let a = k as f64 / 40.0 * std::f64::consts::TAU;
                at(l, 200.0 + 60.0 * a.sin(), 256.0 + 80.0 * a.cos())
            })
            .collect();
        FeatureLayer::new(&[
            Feature::Lake {
                outer_deg: circle,
                holes_deg: vec![],
                level_m: Some(100.0),
            },
            road(
                LineKind::River,
                20.0,
                vec![at(l, 0.0, 100.0), at(l, 150.0, 200.0), at(l, 200.0, 256.0)],
            ),
            road(
                LineKind::PavedRoad,
                7.0,
                vec![
                    at(l, 60.0, -10.0),
                    at(l, 90.0, 200.0),
                    at(l, 40.0, 330.0),
                    at(l, 130.0, 520.0),
                ],
            ),
            road(
                LineKind::DirtRoad,
                4.0,
                vec![at(l, 250.0, 20.0), at(l, 90.0, 255.5), at(l, 10.0, 500.0)],
            ),
        ])
        .expect("valid")
    }

    fn pattern(r: u64, c: u64) -> [u8; 4] {
        [
            (r * 7 % 256) as u8,
            (c * 3 % 256) as u8,
            ((r + c) % 256) as u8,
            if (r / 16 + c / 16).is_multiple_of(3) {
                0
            } else {
                255
            },
        ]
    }

    /// Two neighbouring 256-texel tiles give the same texels as one 512-texel tile over both,
    /// at a fine and a coarse level: no seam.
    #[test]
    fn neighbouring_tiles_have_no_seam() {
        let l = layout();
        let mut big = l;
        big.tile_texels = 512;
        let layer = mixed_layer(&l);
        for level in [0u8, 2] {
            let whole = paint(&layer, &big, key(level, 0, 0), pattern);
            assert!(whole
                .chunks(4)
                .zip(
                    paint(
                        &FeatureLayer::new(&[]).expect("empty"),
                        &big,
                        key(level, 0, 0),
                        pattern
                    )
                    .chunks(4)
                )
                .any(|(a, b)| a != b));
            for (row, col) in [(0u32, 0u32), (0, 1), (1, 0), (1, 1)] {
                let part = paint(&layer, &l, key(level, row, col), pattern);
                for i in 0..256usize {
                    for j in 0..256usize {
                        let (bi, bj) = (row as usize * 256 + i, col as usize * 256 + j);
                        assert_eq!(
                            &part[4 * (i * 256 + j)..4 * (i * 256 + j) + 4],
                            &whole[4 * (bi * 512 + bj)..4 * (bi * 512 + bj) + 4],
                            "level {level} tile {row}_{col} texel {i},{j}"
                        );
                    }
                }
            }
        }
    }

    /// The centre line's dashes run on across a tile border: every dash and gap along the
    /// line, the one cut by the border included, has its length.
    #[test]
    fn dashes_continue_across_a_tile_border() {
        let l = layout();
        let t = texel_m(&l);
        // The dash pattern starts at the line's start: a dash centred on the border.
        let start_col = 256.0 - (1.5 + 8.0 * DASH_PERIOD_M) / t;
        let row = 100.5;
        let layer = FeatureLayer::new(&[road(
            LineKind::PavedRoad,
            7.0,
            vec![at(&l, row, start_col), at(&l, row, 600.0)],
        )])
        .expect("valid");
        let mut line = Vec::new();
        for col in 0..2 {
            let rgba = paint(&layer, &l, key(0, 0, col), transparent);
            line.extend((0..256).map(|j| rgba[4 * (100 * 256 + j)] > 100));
        }
        assert!(line[255] && line[256], "a dash crosses the border");
        let mut runs = Vec::new();
        let mut k = line.iter().position(|&w| w).expect("a dash");
        assert!(
            (k as f64 - start_col).abs() <= 1.0,
            "the first dash starts with the line"
        );
        while k < 500 {
            let v = line[k];
            let len = line[k..].iter().take_while(|&&w| w == v).count();
            if k + len >= 500 {
                break;
            }
            runs.push((v, len));
            k += len;
        }
        assert!(runs.len() >= 8, "{runs:?}");
        for (dash, len) in runs {
            let want = if dash { DASH_M } else { DASH_PERIOD_M - DASH_M } / t;
            assert!(
                (len as f64 - want).abs() <= 1.5,
                "{} of {len} texels, want {want:.1}",
                if dash { "dash" } else { "gap" }
            );
        }
    }

    #[test]
    fn painting_keeps_texels_away_from_features_and_fills_lakes() {
        let l = layout();
        let layer = mixed_layer(&l);
        let before = paint(
            &FeatureLayer::new(&[]).expect("empty"),
            &l,
            key(0, 0, 1),
            pattern,
        );
        let after = paint(&layer, &l, key(0, 0, 1), pattern);
        // Lake centre (200, 256): tile (0, 1) row 200 column 0.
        let k = 4 * (200 * 256 + 10);
        assert_eq!(&after[k..k + 4], &[34, 66, 72, 255]);
        // Far from everything: the top-right corner.
        let k = 4 * (255 * 256 + 250);
        assert_eq!(&after[k..k + 4], &before[k..k + 4]);
        let untouched = after
            .chunks(4)
            .zip(before.chunks(4))
            .filter(|(a, b)| a == b)
            .count();
        assert!(untouched > 256 * 256 / 3, "{untouched}");
        assert!(layer.touches(l.tile_bounds_deg(key(0, 0, 1))));
        assert!(!layer.touches(l.tile_bounds_deg(key(0, 7, 7))));
        // A tile wholly inside a big lake is touched.
        let lake = FeatureLayer::new(&[Feature::Lake {
            outer_deg: vec![
                at(&l, -1000.0, -1000.0),
                at(&l, -1000.0, 3000.0),
                at(&l, 3000.0, 3000.0),
                at(&l, 3000.0, -1000.0),
            ],
            holes_deg: vec![],
            level_m: None,
        }])
        .expect("valid");
        assert!(lake.touches(l.tile_bounds_deg(key(0, 3, 3))));
        let water = paint(&lake, &l, key(0, 3, 3), transparent);
        assert!(water.chunks(4).all(|p| p == [34, 66, 72, 255]));
    }

    #[test]
    fn native_level_follows_the_narrowest_line() {
        let l = layout();
        let layer = FeatureLayer::new(&[road(
            LineKind::PavedRoad,
            8.0,
            vec![at(&l, 1.0, 1.0), at(&l, 9.0, 9.0)],
        )])
        .expect("valid");
        assert_eq!(
            layer.native_level(&l),
            1,
            "0.94 m texels for 1 m (an eighth of 8 m)"
        );
        let fine = ImageryLayout::new(&grid(65), 8);
        assert_eq!(
            layer.native_level(&fine),
            3,
            "0.12 m texels: three levels up"
        );
        let wide = FeatureLayer::new(&[road(
            LineKind::River,
            150.0,
            vec![at(&l, 1.0, 1.0), at(&l, 9.0, 9.0)],
        )])
        .expect("valid");
        assert_eq!(
            wide.native_level(&l),
            l.levels - 1,
            "18.8 m wanted: the coarsest level"
        );
        assert!(wide.native_level(&l) < l.levels);
    }

    /// A road across a slope: after levelling the posts across the road are equal, the road
    /// follows the slope along it, and posts beyond the shoulder (and the surface there) keep
    /// their heights.
    #[test]
    fn levelling_removes_the_cross_slope_and_leaves_far_posts() {
        let g = grid(41);
        let h0 =
            |r: usize, c: usize| (100.0 + 0.05 * 30.0 * c as f64 + 0.2 * 30.0 * r as f64) as f32;
        let mut raster = Raster::from_fn(g, h0);
        let before = raster.clone();
        let y = g.south_lat_deg + 20.0 * g.dlat_deg;
        let f = road(
            LineKind::PavedRoad,
            7.0,
            vec![(y, g.west_lon_deg - 0.001), (y, g.east_lon_deg() + 0.001)],
        );
        let report = level_terrain(&mut raster, &[f]).expect("valid");
        assert!(report.road_posts > 0 && report.material_posts > 0);
        let mats = raster.material.as_ref().expect("classified");
        for c in 4..37 {
            let row = |r: usize| raster.elevation_at(r, c);
            assert_eq!(row(19), row(20), "column {c}");
            assert_eq!(row(21), row(20), "column {c}");
            let along = 100.0 + 0.05 * 30.0 * c as f64 + 0.2 * 600.0;
            assert!(
                (f64::from(row(20)) - along).abs() < 0.05,
                "column {c}: {} vs {along}",
                row(20)
            );
            assert_eq!(mats[raster.index(20, c)], Material::PavedRoad);
            assert_ne!(mats[raster.index(19, c)], Material::PavedRoad);
            let shoulder = row(22);
            assert!(
                shoulder > row(20) && shoulder < h0(22, c),
                "shoulder blends"
            );
            for r in (0..=17).chain(23..41) {
                assert_eq!(
                    raster.elevation_at(r, c),
                    before.elevation_at(r, c),
                    "post {r},{c}"
                );
            }
        }
        // HOT on the surface far away is unchanged.
        for (r, c, u, v) in [(5usize, 7usize, 0.3, 0.6), (30, 12, 0.9, 0.1)] {
            let corners = |x: &Raster| {
                [
                    x.elevation_at(r, c),
                    x.elevation_at(r, c + 1),
                    x.elevation_at(r + 1, c),
                    x.elevation_at(r + 1, c + 1),
                ]
            };
            let d = Diagonal::of_cell(r, c);
            assert_eq!(
                triangulated_height(corners(&raster), u, v, d),
                triangulated_height(corners(&before), u, v, d)
            );
        }
    }

    /// A lake with a level makes a flat water surface at it, and only inside.
    #[test]
    fn a_lake_is_flat_at_its_level() {
        let g = grid(41);
        let bowl = |r: usize, c: usize| {
            let (x, y) = (30.0 * (c as f64 - 20.0), 30.0 * (r as f64 - 20.0));
            (90.0 + 1e-4 * (x * x + y * y)) as f32
        };
        let mut raster = Raster::from_fn(g, bowl);
        let centre = g.post_lat_lon_deg(20, 20);
        let (my, mx) = cig_geo::metres_per_degree(LAT);
        let ring: Vec<(f64, f64)> = (0..64)
            .map(|k| {
                let a = k as f64 / 64.0 * std::f64::consts::TAU;
                (
                    centre.0 + 300.0 * a.sin() / my,
                    centre.1 + 300.0 * a.cos() / mx,
                )
            })
            .collect();
        let lake = Feature::Lake {
            outer_deg: ring,
            holes_deg: vec![],
            level_m: Some(98.5),
        };
        let report = level_terrain(&mut raster, &[lake]).expect("valid");
        assert!(report.lake_posts > 250, "{report:?}");
        let mats = raster.material.as_ref().expect("classified");
        for r in 0..41 {
            for c in 0..41 {
                let d = 30.0 * (((r as f64 - 20.0).powi(2) + (c as f64 - 20.0).powi(2)).sqrt());
                let k = raster.index(r, c);
                if d < 295.0 {
                    assert_eq!(raster.elevation_m[k], 98.5);
                    assert_eq!(mats[k], Material::Water);
                } else if d > 305.0 {
                    assert_eq!(raster.elevation_m[k], bowl(r, c));
                }
            }
        }
        for (r, c) in [(18usize, 19usize), (22, 21), (20, 14)] {
            let h = [
                raster.elevation_at(r, c),
                raster.elevation_at(r, c + 1),
                raster.elevation_at(r + 1, c),
                raster.elevation_at(r + 1, c + 1),
            ];
            assert_eq!(
                triangulated_height(h, 0.37, 0.81, Diagonal::of_cell(r, c)),
                98.5
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

        /// Any road, at any level: tiles agree with the 512-texel tile over them.
        #[test]
        fn tiles_agree_for_any_road(
            a in (0.0f64..512.0, 0.0f64..512.0),
            b in (0.0f64..512.0, 0.0f64..512.0),
            width in 2.0f64..30.0,
            level in 0u8..3,
            kind in 0usize..3,
        ) {
            let l = layout();
            let mut big = l;
            big.tile_texels = 512;
            let kind = [LineKind::PavedRoad, LineKind::DirtRoad, LineKind::River][kind];
            let s = f64::from(1u32 << level);
            let Ok(layer) = FeatureLayer::new(&[road(kind, width, vec![at(&l, a.0 * s, a.1 * s), at(&l, 256.0 * s, 256.0 * s), at(&l, b.0 * s, b.1 * s)])]) else {
                return Ok(());
            };
            let whole = paint(&layer, &big, key(level, 0, 0), pattern);
            for (row, col) in [(0u32, 0u32), (0, 1), (1, 0), (1, 1)] {
                let part = paint(&layer, &l, key(level, row, col), pattern);
                for i in 0..256usize {
                    let bi = row as usize * 256 + i;
                    let bj = col as usize * 256;
                    prop_assert_eq!(&part[4 * i * 256..4 * (i + 1) * 256], &whole[4 * (bi * 512 + bj)..4 * (bi * 512 + bj + 256)]);
                }
            }
        }
    }
}
