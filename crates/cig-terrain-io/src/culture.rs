//! Culture in feature files: trees, bushes, buildings, walls, fences and power poles as GeoJSON,
//! read with the roads, rivers and lakes of the same file ([`crate::features`]) for
//! `cig db import --features FILE`.
//!
//! A feature is culture when its `type` property names a [`CultureKind`]: `conifer_tree`,
//! `broadleaf_tree`, `bush`, `house`, `shed`, `large_building`, `wall`, `fence` or
//! `power_pole` (the features of a road, river or lake `type` are read as before, so one file
//! may hold both). Positions are `[lon, lat]` in WGS84 degrees. Properties, sizes in metres:
//!
//! * `height_m`: required for buildings, walls and fences; optional for trees, bushes and
//!   poles (default [`CultureKind::typical_size_m`]);
//! * `width_m`, `length_m`: optional (default the kind's typical size; a tree's or bush's
//!   width is its crown's diameter, its length is its width);
//! * `heading_deg`: the length axis, degrees clockwise from north (default 0), for points;
//! * `density_per_ha`: objects per hectare of a tree or bush stand (required for polygons of
//!   trees and bushes);
//! * `spacing_m`: the most distance between objects along a line (default 50 m for power
//!   poles, the crown's width for trees and bushes).
//!
//! Geometry:
//!
//! * Point: one object where it stands (a building `width_m` x `length_m` at `heading_deg`);
//! * Polygon of a building kind: one building on the footprint's minimum-area bounding
//!   rectangle (its centre, length, width and heading, in a local metric frame); holes and
//!   `heading_deg`, `width_m` and `length_m` are not used;
//! * Polygon of trees or bushes: a stand filled at `density_per_ha` on a jittered grid (each
//!   object's offset, size within ±10 %, heading and variant a hash of the feature's index and
//!   its grid cell: the same file gives the same stand), holes left empty;
//! * Polygon of walls or fences: its rings as closed lines;
//! * LineString of walls or fences: each piece of the line cut into equal segments of at most
//!   [`MAX_SEGMENT_M`], each along the line; LineString of power poles, trees or bushes:
//!   objects evenly along the line, both ends included, at most `spacing_m` apart;
//! * MultiPoint, MultiLineString, MultiPolygon and GeometryCollection: the sum of their parts.
//!
//! Errors are one line naming the feature (its index in the file, and its `id` when it has
//! one); whether a position lies inside the database is checked once the DEMs are read
//! ([`check_culture_inside`]), before anything is written.
//!
//! Limits: a file yields at most [`MAX_CULTURE_OBJECTS`] objects; geometry across the
//! antimeridian is unwrapped into one local frame, across a pole it is refused by the database.

use crate::features::{FeatureFileError, ParseError};
use cig_terrain::culture::{CultureKind, CulturePlacement};
use cig_terrain::GeoGrid;
use geojson::{JsonObject, JsonValue, Value};
use std::path::Path;

/// Longest segment a wall or fence line is cut into, metres.
pub const MAX_SEGMENT_M: f64 = 20.0;
/// Default distance between power poles along a line, metres.
pub const DEFAULT_POLE_SPACING_M: f64 = 50.0;
/// Densest stand a file may ask for, objects per hectare (one a square metre).
pub const MAX_DENSITY_PER_HA: f64 = 10_000.0;
/// Most objects one feature file may yield (about 400 MB of placements).
pub const MAX_CULTURE_OBJECTS: usize = 10_000_000;
/// Most grid cells a stand's bounding box may take (a thin diagonal polygon's box may be far
/// larger than its area).
const MAX_STAND_CELLS: f64 = 1e8;
/// A stand's heights and crowns vary by up to this fraction about the feature's size.
const STAND_SIZE_JITTER: f64 = 0.1;
/// A stand's objects lie up to this fraction of the grid spacing off their cell's centre.
const STAND_POSITION_JITTER: f64 = 0.4;

/// The objects one feature of the file yields.
#[derive(Clone, Debug, PartialEq)]
pub struct CultureFeature {
    /// Index of the feature in the file's collection.
    pub index: usize,
    /// The feature's `id`, when it has one.
    pub id: Option<String>,
    pub kind: CultureKind,
    pub placements: Vec<CulturePlacement>,
}

impl CultureFeature {
    /// "feature 3" or "feature 3, id \"mill\"", for messages.
    pub fn label(&self) -> String {
        feature_label(self.index, self.id.as_deref())
    }
}

/// Every placement of the features, in file order.
pub fn placements(features: &[CultureFeature]) -> Vec<CulturePlacement> {
    features
        .iter()
        .flat_map(|f| f.placements.iter().copied())
        .collect()
}

/// "feature 3" or "feature 3, id \"mill\"".
pub(crate) fn feature_label(index: usize, id: Option<&str>) -> String {
    match id {
        Some(id) => format!("feature {index}, id {id:?}"),
        None => format!("feature {index}"),
    }
}

/// Checks that every object of `features` (read from `path`) stands inside the database's
/// `grid` (the same test as [`cig_terrain::culture::bin_placements`]); the first that does not
/// is the error, naming its feature and position.
pub fn check_culture_inside(
    path: &Path,
    features: &[CultureFeature],
    grid: &GeoGrid,
) -> Result<(), FeatureFileError> {
    let max_row = grid.rows.saturating_sub(1) as f64;
    let max_col = grid.cols.saturating_sub(1) as f64;
    for f in features {
        for p in &f.placements {
            let (row, col) = grid.fractional_index(p.lat_deg, p.lon_deg);
            let inside = row.is_finite()
                && col.is_finite()
                && (0.0..=max_row).contains(&row)
                && (0.0..=max_col).contains(&col);
            if !inside {
                return Err(FeatureFileError::Invalid {
                    path: path.to_path_buf(),
                    reason: format!(
                        "{} at {:.6}, {:.6} lies outside the database ({:.6} .. {:.6} N, \
                         {:.6} .. {:.6} E) ({})",
                        p.kind,
                        p.lat_deg,
                        p.lon_deg,
                        grid.south_lat_deg,
                        grid.north_lat_deg(),
                        grid.west_lon_deg,
                        grid.east_lon_deg(),
                        f.label()
                    ),
                });
            }
        }
    }
    Ok(())
}

/// The sizes and counts a culture feature's properties give, checked.
struct Props {
    height_m: Option<f64>,
    width_m: Option<f64>,
    length_m: Option<f64>,
    heading_deg: f64,
    density_per_ha: Option<f64>,
    spacing_m: Option<f64>,
}

/// Tallest an object of `kind` may be, metres (as `bin_placements` checks it).
fn max_height_m(kind: CultureKind) -> f64 {
    f64::from(kind.max_height_m())
}

fn max_extent_m(kind: CultureKind) -> f64 {
    f64::from(kind.max_extent_m())
}

impl Props {
    fn read(kind: CultureKind, props: &JsonObject, label: &str) -> Result<Props, String> {
        let number = |key: &str| -> Result<Option<f64>, String> {
            match props.get(key) {
                None | Some(JsonValue::Null) => Ok(None),
                Some(JsonValue::Number(n)) => match n.as_f64() {
                    Some(v) if v.is_finite() => Ok(Some(v)),
                    _ => Err(format!("property {key} is not a finite number ({label})")),
                },
                Some(_) => Err(format!("property {key} is not a number ({label})")),
            }
        };
        let size = |key: &str, max: f64| -> Result<Option<f64>, String> {
            let (what, unit) = if key.ends_with("_m") {
                ("size", "m")
            } else {
                ("density", "per hectare")
            };
            match number(key)? {
                Some(v) if v <= 0.0 => Err(format!("{key} {v} is not a positive {what} ({label})")),
                Some(v) if v > max => Err(format!(
                    "{key} {v} is more than the {max} {unit} a {kind} may have ({label})"
                )),
                other => Ok(other),
            }
        };
        let props = Props {
            height_m: size("height_m", max_height_m(kind))?,
            width_m: size("width_m", max_extent_m(kind))?,
            length_m: size("length_m", max_extent_m(kind))?,
            heading_deg: number("heading_deg")?.unwrap_or(0.0),
            density_per_ha: size("density_per_ha", MAX_DENSITY_PER_HA)?,
            spacing_m: size("spacing_m", 100_000.0)?,
        };
        if props.height_m.is_none() && (kind.is_building() || kind.is_linear()) {
            return Err(format!("a {kind} needs its height_m ({label})"));
        }
        Ok(props)
    }

    fn height(&self, kind: CultureKind) -> f64 {
        self.height_m.unwrap_or(f64::from(kind.typical_size_m()[0]))
    }

    fn width(&self, kind: CultureKind) -> f64 {
        self.width_m.unwrap_or(f64::from(kind.typical_size_m()[1]))
    }

    /// Along the heading: a building's or wall's length, a tree's or pole's width.
    fn length(&self, kind: CultureKind) -> f64 {
        if kind.is_building() || kind.is_linear() {
            self.length_m.unwrap_or(f64::from(kind.typical_size_m()[2]))
        } else {
            self.width(kind)
        }
    }
}

/// One part of a geometry.
enum Part<'a> {
    Point(&'a [f64]),
    Line(&'a [Vec<f64>]),
    Polygon(&'a [Vec<Vec<f64>>]),
}

fn collect_parts<'a>(value: &'a Value, out: &mut Vec<Part<'a>>) {
    match value {
        Value::Point(p) => out.push(Part::Point(p)),
        Value::MultiPoint(ps) => out.extend(ps.iter().map(|p| Part::Point(p))),
        Value::LineString(l) => out.push(Part::Line(l)),
        Value::MultiLineString(ls) => out.extend(ls.iter().map(|l| Part::Line(l))),
        Value::Polygon(p) => out.push(Part::Polygon(p)),
        Value::MultiPolygon(ps) => out.extend(ps.iter().map(|p| Part::Polygon(p))),
        Value::GeometryCollection(gs) => {
            for g in gs {
                collect_parts(&g.value, out);
            }
        }
    }
}

/// A local east-north frame in metres about a point (tangent-plane approximation, good to a
/// part in 10^4 over a few kilometres).
#[derive(Clone, Copy, Debug)]
struct Frame {
    lat0_deg: f64,
    lon0_deg: f64,
    m_per_deg_north: f64,
    m_per_deg_east: f64,
}

impl Frame {
    fn at(lat0_deg: f64, lon0_deg: f64) -> Frame {
        let (north, east) = cig_geo::metres_per_degree(lat0_deg);
        Frame {
            lat0_deg,
            lon0_deg,
            m_per_deg_north: north,
            m_per_deg_east: east.max(1e-6),
        }
    }

    /// East and north metres of a (lat, lon).
    fn local(&self, (lat, lon): (f64, f64)) -> [f64; 2] {
        let dlon = (lon - self.lon0_deg + 180.0).rem_euclid(360.0) - 180.0;
        [
            dlon * self.m_per_deg_east,
            (lat - self.lat0_deg) * self.m_per_deg_north,
        ]
    }

    /// (lat, lon) of east and north metres.
    fn geo(&self, [x, y]: [f64; 2]) -> (f64, f64) {
        let lon = self.lon0_deg + x / self.m_per_deg_east;
        (
            self.lat0_deg + y / self.m_per_deg_north,
            (lon + 180.0).rem_euclid(360.0) - 180.0,
        )
    }
}

/// Compass bearing of an east-north direction, degrees in 0..360.
fn bearing_deg([x, y]: [f64; 2]) -> f64 {
    x.atan2(y).to_degrees().rem_euclid(360.0)
}

/// splitmix64's finaliser.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A hash of a feature's index and a position's integer coordinates.
fn hash(index: usize, part: usize, a: i64, b: i64) -> u64 {
    // Bit reinterpretation of the signed coordinates is intended: only mixing matters.
    mix(mix(mix(mix(index as u64) ^ part as u64) ^ a as u64) ^ b as u64)
}

/// The `lane`-th of four 16-bit fractions of a hash, in 0..=1.
fn unit(h: u64, lane: u32) -> f64 {
    ((h >> (16 * lane)) & 0xFFFF) as f64 / 65535.0
}

/// The hash of a geodetic position, to about a centimetre.
fn position_hash(index: usize, part: usize, (lat, lon): (f64, f64)) -> u64 {
    hash(
        index,
        part,
        (lat * 1e7).round() as i64,
        (lon * 1e7).round() as i64,
    )
}

/// The smallest-area rectangle around a set of points (local metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Rectangle {
    pub centre: [f64; 2],
    /// The longer side, metres.
    pub length_m: f64,
    /// The shorter side, metres.
    pub width_m: f64,
    /// Bearing of the length axis, degrees clockwise from north in 0..180.
    pub heading_deg: f64,
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without repeated points.
fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut pts: Vec<[f64; 2]> = points.to_vec();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The minimum-area bounding rectangle (rotating calipers over the hull's edges); `None` when
/// the points span no area.
pub(crate) fn min_area_rectangle(points: &[[f64; 2]]) -> Option<Rectangle> {
    let hull = convex_hull(points);
    if hull.len() < 3 {
        return None;
    }
    let mut best: Option<(f64, Rectangle)> = None;
    for k in 0..hull.len() {
        let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy);
        if len <= 0.0 {
            continue;
        }
        let u = [dx / len, dy / len];
        let v = [-u[1], u[0]];
        let (mut umin, mut umax, mut vmin, mut vmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in &hull {
            let pu = p[0] * u[0] + p[1] * u[1];
            let pv = p[0] * v[0] + p[1] * v[1];
            umin = umin.min(pu);
            umax = umax.max(pu);
            vmin = vmin.min(pv);
            vmax = vmax.max(pv);
        }
        let (eu, ev) = (umax - umin, vmax - vmin);
        let area = eu * ev;
        if best.as_ref().is_some_and(|(a, _)| *a <= area) {
            continue;
        }
        let (cu, cv) = (0.5 * (umin + umax), 0.5 * (vmin + vmax));
        let centre = [cu * u[0] + cv * v[0], cu * u[1] + cv * v[1]];
        let (length_m, width_m, axis) = if eu >= ev { (eu, ev, u) } else { (ev, eu, v) };
        let rect = Rectangle {
            centre,
            length_m,
            width_m,
            heading_deg: bearing_deg(axis).rem_euclid(180.0),
        };
        best = Some((area, rect));
    }
    best.map(|(_, r)| r).filter(|r| r.width_m > 0.0)
}

/// Whether `p` lies inside `ring` (even-odd rule; the ring closed or not).
fn in_ring(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = ring.len();
    if n < 3 {
        return false;
    }
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (ring[i], ring[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Area of a ring by the shoelace formula, square metres (unsigned).
fn ring_area_m2(ring: &[[f64; 2]]) -> f64 {
    let n = ring.len();
    let mut twice = 0.0;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        twice += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * twice.abs()
}

/// Reads one culture feature of `kind`. `label` names it; `budget` is how many more objects
/// the file may yield (reduced by this feature's).
pub(crate) fn culture_feature(
    index: usize,
    id: Option<String>,
    kind: CultureKind,
    props: &JsonObject,
    geometry: &Value,
    budget: &mut usize,
) -> Result<CultureFeature, ParseError> {
    let label = feature_label(index, id.as_deref());
    let invalid = |reason: String| ParseError::Invalid(format!("{reason} ({label})"));
    let props = Props::read(kind, props, &label).map_err(ParseError::Invalid)?;
    let mut parts = Vec::new();
    collect_parts(geometry, &mut parts);
    if parts.is_empty() {
        return Err(invalid("the geometry is empty".to_string()));
    }
    let mut maker = Maker {
        kind,
        index,
        props: &props,
        out: Vec::new(),
        limit: *budget,
    };
    for (part_index, part) in parts.iter().enumerate() {
        match *part {
            Part::Point(p) => position(p).and_then(|at| maker.point(part_index, at)),
            Part::Line(line) => positions(line).and_then(|pts| maker.line(part_index, &pts)),
            Part::Polygon(rings) => rings
                .iter()
                .map(|r| positions(r))
                .collect::<Result<Vec<_>, _>>()
                .and_then(|rings| maker.polygon(part_index, &rings)),
        }
        .map_err(invalid)?;
    }
    for p in &maker.out {
        check_size(p).map_err(invalid)?;
    }
    *budget -= maker.out.len();
    Ok(CultureFeature {
        index,
        id,
        kind,
        placements: maker.out,
    })
}

/// (lat, lon) of a GeoJSON position, checked.
fn position(p: &[f64]) -> Result<(f64, f64), String> {
    match p {
        [lon, lat, ..] => {
            if !(lat.is_finite() && (-90.0..=90.0).contains(lat)) {
                Err(format!("{lat} is not a finite latitude in -90..90"))
            } else if !(lon.is_finite() && (-180.0..=180.0).contains(lon)) {
                Err(format!("{lon} is not a finite longitude in -180..180"))
            } else {
                Ok((*lat, *lon))
            }
        }
        _ => Err("a position has fewer than two coordinates".to_string()),
    }
}

fn positions(ps: &[Vec<f64>]) -> Result<Vec<(f64, f64)>, String> {
    ps.iter().map(|p| position(p)).collect()
}

/// The bounds `bin_placements` checks ([`CulturePlacement::check`]), named by the placement's
/// values.
fn check_size(p: &CulturePlacement) -> Result<(), String> {
    p.check().map_err(|e| e.to_string())
}

/// A straight piece of a line: its start's frame, its east-north vector and its length.
#[derive(Clone, Copy)]
struct Piece {
    frame: Frame,
    d: [f64; 2],
    len_m: f64,
}

/// Builds a feature's placements.
struct Maker<'a> {
    kind: CultureKind,
    index: usize,
    props: &'a Props,
    out: Vec<CulturePlacement>,
    /// Objects the file may still yield, this feature's included.
    limit: usize,
}

impl Maker<'_> {
    /// Reserves room for about `estimate` more objects.
    fn reserve(&mut self, estimate: f64, what: &str) -> Result<(), String> {
        if !(estimate.is_finite() && self.out.len() as f64 + estimate <= self.limit as f64) {
            return Err(format!(
                "the {what} would hold about {estimate:.0} objects, more than the \
                 {MAX_CULTURE_OBJECTS} a feature file may yield"
            ));
        }
        Ok(())
    }

    fn push(
        &mut self,
        (lat_deg, lon_deg): (f64, f64),
        [height_m, width_m, length_m]: [f64; 3],
        heading_deg: f64,
        h: u64,
    ) {
        self.out.push(CulturePlacement {
            kind: self.kind,
            lat_deg,
            lon_deg,
            height_m: height_m as f32,
            width_m: width_m as f32,
            length_m: length_m as f32,
            heading_deg: heading_deg.rem_euclid(360.0) as f32,
            variant: (h >> 56) as u8,
        });
    }

    /// The sizes of a single object.
    fn sizes(&self) -> [f64; 3] {
        [
            self.props.height(self.kind),
            self.props.width(self.kind),
            self.props.length(self.kind),
        ]
    }

    fn point(&mut self, part: usize, at: (f64, f64)) -> Result<(), String> {
        self.reserve(1.0, "point")?;
        let h = position_hash(self.index, part, at);
        let heading = if self.kind.is_building() || self.kind.is_linear() {
            self.props.heading_deg
        } else {
            360.0 * unit(h, 0)
        };
        self.push(at, self.sizes(), heading, h);
        Ok(())
    }

    fn line(&mut self, part: usize, pts: &[(f64, f64)]) -> Result<(), String> {
        let kind = self.kind;
        if kind.is_building() {
            return Err(format!(
                "a {kind} needs a Point or a Polygon (its footprint), not a LineString"
            ));
        }
        // Each piece in a frame at its start: lengths and headings stay exact along long lines.
        let pieces: Vec<Piece> = pts
            .windows(2)
            .filter_map(|w| {
                let frame = Frame::at(w[0].0, w[0].1);
                let d = frame.local(w[1]);
                let len_m = d[0].hypot(d[1]);
                (len_m > 1e-3).then_some(Piece { frame, d, len_m })
            })
            .collect();
        let total_m: f64 = pieces.iter().map(|p| p.len_m).sum();
        if pieces.is_empty() {
            return Err(format!("a {kind} line needs at least two distinct points"));
        }
        if kind.is_linear() {
            let estimate: f64 = pieces
                .iter()
                .map(|p| (p.len_m / MAX_SEGMENT_M).ceil())
                .sum();
            self.reserve(estimate, "line")?;
            let [height, width, _] = self.sizes();
            for (
                k,
                &Piece {
                    frame,
                    d,
                    len_m: len,
                },
            ) in pieces.iter().enumerate()
            {
                let n = (len / MAX_SEGMENT_M).ceil().max(1.0);
                let heading = bearing_deg(d);
                for s in 0..n as usize {
                    let t = (s as f64 + 0.5) / n;
                    let at = frame.geo([d[0] * t, d[1] * t]);
                    let h = hash(self.index, part, k as i64, s as i64);
                    self.push(at, [height, width, len / n], heading, h);
                }
            }
            return Ok(());
        }
        let spacing_m = self
            .props
            .spacing_m
            .unwrap_or(if kind == CultureKind::PowerPole {
                DEFAULT_POLE_SPACING_M
            } else {
                self.props.width(kind)
            });
        let intervals = (total_m / spacing_m).ceil().max(1.0);
        self.reserve(intervals + 1.0, "line")?;
        let step_m = total_m / intervals;
        let mut piece = 0;
        let mut start_m = 0.0;
        for k in 0..=intervals as usize {
            let s = (k as f64 * step_m).min(total_m);
            while piece + 1 < pieces.len() && s > start_m + pieces[piece].len_m {
                start_m += pieces[piece].len_m;
                piece += 1;
            }
            let Piece {
                frame,
                d,
                len_m: len,
            } = pieces[piece];
            let t = ((s - start_m) / len).clamp(0.0, 1.0);
            let at = frame.geo([d[0] * t, d[1] * t]);
            let h = hash(self.index, part, k as i64, -1);
            let heading = if kind == CultureKind::PowerPole {
                bearing_deg(d)
            } else {
                360.0 * unit(h, 0)
            };
            let sizes = self.varied(h);
            self.push(at, sizes, heading, h);
        }
        Ok(())
    }

    /// A stand object's sizes: the feature's, varied by the hash (trees and bushes only).
    fn varied(&self, h: u64) -> [f64; 3] {
        let [height, width, length] = self.sizes();
        if !(self.kind.is_tree() || self.kind == CultureKind::Bush) {
            return [height, width, length];
        }
        let f = |lane: u32| 1.0 + STAND_SIZE_JITTER * (2.0 * unit(h, lane) - 1.0);
        let max = max_extent_m(self.kind);
        let width = (width * f(2)).min(max);
        [(height * f(1)).min(max_height_m(self.kind)), width, width]
    }

    fn polygon(&mut self, part: usize, rings: &[Vec<(f64, f64)>]) -> Result<(), String> {
        let kind = self.kind;
        let Some(outer) = rings.first() else {
            return Err("a polygon has no ring".to_string());
        };
        if kind.is_linear() {
            for ring in rings {
                let mut closed = ring.clone();
                if let (Some(&first), Some(&last)) = (ring.first(), ring.last()) {
                    if first != last {
                        closed.push(first);
                    }
                }
                self.line(part, &closed)?;
            }
            return Ok(());
        }
        if kind == CultureKind::PowerPole {
            return Err(format!(
                "a {kind} needs a Point or a LineString, not a Polygon"
            ));
        }
        // A frame at the middle of the outer ring's box.
        let (mut s, mut n, mut w, mut e) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        let frame0 = Frame::at(outer[0].0, outer[0].1);
        for &p in outer {
            let q = frame0.local(p);
            s = s.min(q[1]);
            n = n.max(q[1]);
            w = w.min(q[0]);
            e = e.max(q[0]);
        }
        let mid = frame0.geo([0.5 * (w + e), 0.5 * (s + n)]);
        let frame = Frame::at(mid.0, mid.1);
        let local: Vec<Vec<[f64; 2]>> = rings
            .iter()
            .map(|r| r.iter().map(|&p| frame.local(p)).collect())
            .collect();
        if kind.is_building() {
            let rect = min_area_rectangle(&local[0])
                .ok_or_else(|| format!("the {kind}'s footprint has no area"))?;
            let max = max_extent_m(kind);
            if rect.length_m > max {
                return Err(format!(
                    "the {kind}'s footprint is {:.1} m long, more than the {max} m a {kind} \
                     may have",
                    rect.length_m
                ));
            }
            self.reserve(1.0, "footprint")?;
            let at = frame.geo(rect.centre);
            let h = position_hash(self.index, part, at);
            let height = self.props.height(kind);
            self.push(
                at,
                [height, rect.width_m, rect.length_m],
                rect.heading_deg,
                h,
            );
            return Ok(());
        }
        let Some(density) = self.props.density_per_ha else {
            return Err(format!(
                "a stand of {kind} (a Polygon) needs its density_per_ha"
            ));
        };
        let holes = &local[1..];
        let area_m2 =
            (ring_area_m2(&local[0]) - holes.iter().map(|h| ring_area_m2(h)).sum::<f64>()).max(0.0);
        self.reserve(area_m2 / 10_000.0 * density * 1.2 + 1.0, "stand")?;
        let spacing_m = 100.0 / density.sqrt();
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in &local[0] {
            x0 = x0.min(p[0]);
            x1 = x1.max(p[0]);
            y0 = y0.min(p[1]);
            y1 = y1.max(p[1]);
        }
        let (i0, i1) = (
            (x0 / spacing_m).floor() as i64,
            (x1 / spacing_m).ceil() as i64,
        );
        let (j0, j1) = (
            (y0 / spacing_m).floor() as i64,
            (y1 / spacing_m).ceil() as i64,
        );
        let cells = (i1 - i0) as f64 * (j1 - j0) as f64;
        if cells > MAX_STAND_CELLS {
            return Err(format!(
                "the stand's bounding box would take {cells:.0} grid cells of {spacing_m:.1} m, \
                 more than {MAX_STAND_CELLS:.0}: split the polygon or lower its density"
            ));
        }
        for j in j0..j1 {
            for i in i0..i1 {
                let h = hash(self.index, part, i, j);
                let jitter = |lane: u32| STAND_POSITION_JITTER * (2.0 * unit(h, lane) - 1.0);
                let p = [
                    (i as f64 + 0.5 + jitter(0)) * spacing_m,
                    (j as f64 + 0.5 + jitter(3)) * spacing_m,
                ];
                if !in_ring(p, &local[0]) || holes.iter().any(|r| in_ring(p, r)) {
                    continue;
                }
                let heading = 360.0 * unit(h.rotate_left(17), 0);
                let sizes = self.varied(h);
                self.push(frame.geo(p), sizes, heading, h);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{parse_feature_file, read_feature_file};

    const LAT0: f64 = 45.0;
    const LON0: f64 = 7.0;

    /// A GeoJSON position `[lon, lat]` `east_m`, `north_m` from the test's origin.
    fn at(east_m: f64, north_m: f64) -> String {
        let (lat, lon) = Frame::at(LAT0, LON0).geo([east_m, north_m]);
        format!("[{lon:.10}, {lat:.10}]")
    }

    fn ring(points_m: &[(f64, f64)]) -> String {
        let mut pts: Vec<String> = points_m.iter().map(|&(e, n)| at(e, n)).collect();
        pts.push(pts[0].clone());
        format!("[{}]", pts.join(", "))
    }

    fn collection(features: &[String]) -> String {
        format!(
            r#"{{"type": "FeatureCollection", "features": [{}]}}"#,
            features.join(",\n")
        )
    }

    fn feature(props: &str, geometry_type: &str, coordinates: &str) -> String {
        format!(
            r#"{{"type": "Feature", "properties": {props}, "geometry": {{"type": "{geometry_type}", "coordinates": {coordinates}}}}}"#
        )
    }

    fn culture_of(text: &str) -> Vec<CultureFeature> {
        parse_feature_file(text).expect("valid").culture
    }

    /// East and north metres of a placement from the test's origin.
    fn local(p: &CulturePlacement) -> [f64; 2] {
        Frame::at(LAT0, LON0).local((p.lat_deg, p.lon_deg))
    }

    fn heading_diff_deg(a: f64, b: f64, period: f64) -> f64 {
        let d = (a - b).rem_euclid(period);
        d.min(period - d)
    }

    #[test]
    fn points_give_one_object_with_the_given_or_typical_sizes() {
        let text = collection(&[
            feature(r#"{"type": "conifer_tree"}"#, "Point", &at(10.0, 20.0)),
            feature(
                r#"{"type": "house", "height_m": 7.5, "width_m": 9, "length_m": 14, "heading_deg": 30}"#,
                "Point",
                &at(50.0, 60.0),
            ),
            feature(
                r#"{"type": "shed", "height_m": 4}"#,
                "Point",
                &at(80.0, 60.0),
            ),
            feature(
                r#"{"type": "bush", "height_m": 1.5, "width_m": 2}"#,
                "Point",
                &at(0.0, 0.0),
            ),
        ]);
        let culture = culture_of(&text);
        assert_eq!(culture.len(), 4);
        let tree = culture[0].placements[0];
        assert_eq!(tree.kind, CultureKind::ConiferTree);
        let [h, w, _] = CultureKind::ConiferTree.typical_size_m();
        assert_eq!((tree.height_m, tree.width_m, tree.length_m), (h, w, w));
        let [e, n] = local(&tree);
        assert!(
            (e - 10.0).abs() < 0.01 && (n - 20.0).abs() < 0.01,
            "{e} {n}"
        );
        let house = culture[1].placements[0];
        assert_eq!(
            (
                house.height_m,
                house.width_m,
                house.length_m,
                house.heading_deg
            ),
            (7.5, 9.0, 14.0, 30.0)
        );
        let shed = culture[2].placements[0];
        let [_, w, l] = CultureKind::Shed.typical_size_m();
        assert_eq!((shed.height_m, shed.width_m, shed.length_m), (4.0, w, l));
        let bush = culture[3].placements[0];
        assert_eq!(
            (bush.height_m, bush.width_m, bush.length_m),
            (1.5, 2.0, 2.0)
        );
    }

    #[test]
    fn a_rotated_footprint_gives_its_rectangle() {
        for (heading_deg, length_m, width_m) in [
            (35.0, 30.0, 12.0),
            (121.0, 48.0, 20.0),
            (0.0, 25.0, 10.0),
            (10.0, 40.0, 8.0),
            (90.0, 14.0, 9.0),
            (170.0, 22.0, 21.0),
        ] {
            let (s, c) = (
                f64::to_radians(heading_deg).sin(),
                f64::to_radians(heading_deg).cos(),
            );
            // The length axis along the bearing (east = sin, north = cos), the width across.
            let corner = |a: f64, b: f64| {
                let (u, v) = (a * length_m / 2.0, b * width_m / 2.0);
                (300.0 + u * s - v * c, 200.0 + u * c + v * s)
            };
            let footprint = ring(&[
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            ]);
            let text = collection(&[feature(
                r#"{"type": "large_building", "height_m": 12}"#,
                "Polygon",
                &format!("[{footprint}]"),
            )]);
            let culture = culture_of(&text);
            let b = culture[0].placements[0];
            assert!(
                (f64::from(b.length_m) / length_m - 1.0).abs() < 0.01,
                "length {} for {length_m}",
                b.length_m
            );
            assert!(
                (f64::from(b.width_m) / width_m - 1.0).abs() < 0.01,
                "width {} for {width_m}",
                b.width_m
            );
            let d = heading_diff_deg(f64::from(b.heading_deg), heading_deg, 180.0);
            assert!(d < 1.0, "heading {} for {heading_deg}", b.heading_deg);
            let [e, n] = local(&b);
            assert!(
                (e - 300.0).abs() < 0.1 && (n - 200.0).abs() < 0.1,
                "{e} {n}"
            );
            assert_eq!(b.height_m, 12.0);
        }
    }

    #[test]
    fn the_smallest_rectangle_of_an_l_shape_is_its_box() {
        let l_shape = [
            [0.0, 0.0],
            [20.0, 0.0],
            [20.0, 5.0],
            [5.0, 5.0],
            [5.0, 12.0],
            [0.0, 12.0],
        ];
        let r = min_area_rectangle(&l_shape).expect("an area");
        assert!((r.length_m - 20.0).abs() < 1e-9 && (r.width_m - 12.0).abs() < 1e-9);
        assert!(heading_diff_deg(r.heading_deg, 90.0, 180.0) < 1e-6, "{r:?}");
        assert!(min_area_rectangle(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_none());
    }

    #[test]
    fn a_stand_fills_its_polygon_at_its_density_outside_its_holes() {
        // 400 m x 250 m (10 ha) less a 100 m x 100 m hole (1 ha): 9 ha at 300 a hectare.
        let outer = ring(&[(0.0, 0.0), (400.0, 0.0), (400.0, 250.0), (0.0, 250.0)]);
        let hole = ring(&[
            (100.0, 100.0),
            (200.0, 100.0),
            (200.0, 200.0),
            (100.0, 200.0),
        ]);
        let text = collection(&[feature(
            r#"{"type": "broadleaf_tree", "density_per_ha": 300, "height_m": 20}"#,
            "Polygon",
            &format!("[{outer}, {hole}]"),
        )]);
        let stand = &culture_of(&text)[0].placements;
        let expected = 9.0 * 300.0;
        let n = stand.len() as f64;
        assert!(
            (n / expected - 1.0).abs() < 0.2,
            "{n} trees for {expected} expected"
        );
        for t in stand {
            let [e, n] = local(t);
            assert!(
                (-0.5..=400.5).contains(&e) && (-0.5..=250.5).contains(&n),
                "{e} {n}"
            );
            assert!(
                !((100.0..200.0).contains(&e) && (100.0..200.0).contains(&n)),
                "a tree in the hole at {e} {n}"
            );
            assert!((18.0..=22.0).contains(&t.height_m), "{}", t.height_m);
        }
        // Sizes vary, and the same file gives the same stand.
        assert!(stand.iter().any(|t| t.height_m != stand[0].height_m));
        assert_eq!(&culture_of(&text)[0].placements, stand);
    }

    #[test]
    fn wall_lines_are_cut_into_segments_along_the_line() {
        let text = collection(&[feature(
            r#"{"type": "wall", "height_m": 1.8}"#,
            "LineString",
            &format!(
                "[{}, {}, {}]",
                at(0.0, 0.0),
                at(100.0, 0.0),
                at(100.0, 45.0)
            ),
        )]);
        let wall = &culture_of(&text)[0].placements;
        // 100 m east in five segments of 20 m, then 45 m north in three of 15 m.
        assert_eq!(wall.len(), 8, "{wall:?}");
        for (k, seg) in wall.iter().enumerate() {
            let [e, n] = local(seg);
            if k < 5 {
                assert!((seg.length_m - 20.0).abs() < 0.01, "{}", seg.length_m);
                assert!(heading_diff_deg(f64::from(seg.heading_deg), 90.0, 360.0) < 0.1);
                assert!((e - (10.0 + 20.0 * k as f64)).abs() < 0.05 && n.abs() < 0.05);
            } else {
                assert!((seg.length_m - 15.0).abs() < 0.01, "{}", seg.length_m);
                assert!(heading_diff_deg(f64::from(seg.heading_deg), 0.0, 360.0) < 0.1);
                assert!((e - 100.0).abs() < 0.05);
            }
            assert_eq!(seg.height_m, 1.8);
            assert_eq!(seg.width_m, CultureKind::Wall.typical_size_m()[1]);
        }
        let total: f32 = wall.iter().map(|s| s.length_m).sum();
        assert!((total - 145.0).abs() < 0.05, "{total}");
    }

    #[test]
    fn poles_stand_evenly_along_their_line() {
        let line = format!(
            "[{}, {}, {}]",
            at(0.0, 0.0),
            at(0.0, 130.0),
            at(100.0, 130.0)
        );
        let poles = |props: &str| {
            culture_of(&collection(&[feature(props, "LineString", &line)]))[0]
                .placements
                .clone()
        };
        // 230 m at most 50 m apart: 5 spans of 46 m, 6 poles, both ends.
        let default = poles(r#"{"type": "power_pole"}"#);
        assert_eq!(default.len(), 6);
        let ends = (local(&default[0]), local(&default[5]));
        assert!(ends.0[0].abs() < 0.05 && ends.0[1].abs() < 0.05, "{ends:?}");
        assert!((ends.1[0] - 100.0).abs() < 0.05 && (ends.1[1] - 130.0).abs() < 0.05);
        let second = local(&default[1]);
        assert!((second[1] - 46.0).abs() < 0.05, "{second:?}");
        let past_corner = local(&default[3]);
        assert!(
            (past_corner[0] - 8.0).abs() < 0.05 && (past_corner[1] - 130.0).abs() < 0.05,
            "{past_corner:?}"
        );
        assert_eq!(
            default[0].height_m,
            CultureKind::PowerPole.typical_size_m()[0]
        );
        // At most 100 m: 3 spans, 4 poles.
        assert_eq!(
            poles(r#"{"type": "power_pole", "spacing_m": 100, "height_m": 12}"#).len(),
            4
        );
    }

    #[test]
    fn multi_geometries_are_the_sum_of_their_parts_and_roads_stay_features() {
        let house = |e: f64| ring(&[(e, 0.0), (e + 10.0, 0.0), (e + 10.0, 8.0), (e, 8.0)]);
        let text = collection(&[
            feature(
                r#"{"type": "paved_road", "width_m": 7}"#,
                "LineString",
                &format!("[{}, {}]", at(0.0, -50.0), at(300.0, -50.0)),
            ),
            feature(
                r#"{"type": "bush"}"#,
                "MultiPoint",
                &format!("[{}, {}, {}]", at(1.0, 1.0), at(2.0, 2.0), at(3.0, 3.0)),
            ),
            feature(
                r#"{"type": "house", "height_m": 8}"#,
                "MultiPolygon",
                &format!("[[{}], [{}]]", house(0.0), house(40.0)),
            ),
            feature(
                r#"{"type": "fence", "height_m": 1.2}"#,
                "MultiLineString",
                &format!(
                    "[[{}, {}], [{}, {}]]",
                    at(0.0, 20.0),
                    at(30.0, 20.0),
                    at(0.0, 30.0),
                    at(10.0, 30.0)
                ),
            ),
            r#"{"type": "Feature", "properties": {"type": "shed", "height_m": 4}, "geometry": {"type": "GeometryCollection", "geometries": [{"type": "Point", "coordinates": [7.001, 45.001]}, {"type": "Point", "coordinates": [7.002, 45.001]}]}}"#.to_string(),
        ]);
        let file = parse_feature_file(&text).expect("valid");
        assert_eq!(file.features.len(), 1, "the road");
        let counts: Vec<(CultureKind, usize)> = file
            .culture
            .iter()
            .map(|f| (f.kind, f.placements.len()))
            .collect();
        assert_eq!(
            counts,
            [
                (CultureKind::Bush, 3),
                (CultureKind::House, 2),
                (CultureKind::Fence, 3),
                (CultureKind::Shed, 2)
            ]
        );
        assert_eq!(file.culture[0].index, 1);
        assert_eq!(placements(&file.culture).len(), 10);
        // A walled polygon is its ring: 2 x (30 + 20) m in 20 m pieces.
        let yard = collection(&[feature(
            r#"{"type": "wall", "height_m": 2}"#,
            "Polygon",
            &format!(
                "[{}]",
                ring(&[(0.0, 0.0), (30.0, 0.0), (30.0, 20.0), (0.0, 20.0)])
            ),
        )]);
        let wall = &culture_of(&yard)[0].placements;
        assert_eq!(wall.len(), 2 + 1 + 2 + 1);
        let total: f32 = wall.iter().map(|s| s.length_m).sum();
        assert!((total - 100.0).abs() < 0.05, "{total}");
    }

    /// The message `text` is refused with, read from a file (so it ends with the path).
    fn refusal(text: &str) -> String {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("culture.geojson");
        std::fs::write(&path, text).expect("written");
        let msg = read_feature_file(&path).expect_err("refused").to_string();
        assert!(!msg.contains('\n'), "{msg}");
        assert!(msg.ends_with(&format!("({})", path.display())), "{msg}");
        msg
    }

    #[test]
    fn bad_culture_is_refused_naming_the_feature() {
        let point = at(0.0, 0.0);
        let tree = feature(r#"{"type": "conifer_tree"}"#, "Point", &point);
        let one = |f: String| collection(&[tree.clone(), f]);
        let cases = [
            (
                one(r#"{"type": "Feature", "id": "mill-3", "properties": {"type": "windmill"}, "geometry": {"type": "Point", "coordinates": [7, 45]}}"#.to_string()),
                vec!["unknown type \"windmill\"", "feature 1, id \"mill-3\"", "conifer_tree", "paved_road"],
            ),
            (
                one(feature(r#"{"type": "house"}"#, "Point", &point)),
                vec!["house needs its height_m", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "wall", "width_m": 0.5}"#, "LineString", &format!("[{point}, {}]", at(5.0, 0.0)))),
                vec!["wall needs its height_m", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "house", "height_m": -3}"#, "Point", &point)),
                vec!["height_m -3 is not a positive size", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "bush", "width_m": 0}"#, "Point", &point)),
                vec!["width_m 0 is not a positive size", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "conifer_tree", "height_m": 250}"#, "Point", &point)),
                vec!["height_m 250 is more than the 60 m a conifer_tree may have", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "shed", "height_m": "tall"}"#, "Point", &point)),
                vec!["height_m is not a number", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "conifer_tree", "density_per_ha": -5}"#, "Polygon", &format!("[{}]", ring(&[(0.0, 0.0), (50.0, 0.0), (0.0, 50.0)])))),
                vec!["density_per_ha -5 is not a positive density", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "conifer_tree"}"#, "Polygon", &format!("[{}]", ring(&[(0.0, 0.0), (50.0, 0.0), (0.0, 50.0)])))),
                vec!["needs its density_per_ha", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "house", "height_m": 8}"#, "LineString", &format!("[{point}, {}]", at(5.0, 0.0)))),
                vec!["house needs a Point or a Polygon", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "power_pole"}"#, "Polygon", &format!("[{}]", ring(&[(0.0, 0.0), (50.0, 0.0), (0.0, 50.0)])))),
                vec!["power_pole needs a Point or a LineString", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "house", "height_m": 8}"#, "Polygon", &format!("[{}]", ring(&[(0.0, 0.0), (90.0, 0.0), (90.0, 10.0), (0.0, 10.0)])))),
                vec!["footprint is 90.0 m long, more than the 60 m", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "house", "height_m": 8}"#, "Polygon", &format!("[{}]", ring(&[(0.0, 0.0), (10.0, 0.0), (20.0, 0.0)])))),
                vec!["footprint has no area", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "fence", "height_m": 1}"#, "LineString", &format!("[{point}, {point}]"))),
                vec!["at least two distinct points", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "bush"}"#, "Point", "[7, 95]")),
                vec!["95 is not a finite latitude", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "bush", "density_per_ha": 9000}"#, "Polygon", "[[[0, 0], [10, 0], [10, 10], [0, 0]]]")),
                vec!["more than the 10000000 a feature file may yield", "(feature 1)"],
            ),
            (
                one(feature(r#"{"type": "bush", "density_per_ha": 10000}"#, "Polygon", "[[[7, 45], [7.2, 45.2], [7.2, 45.20001], [7, 45]]]")),
                vec!["grid cells", "(feature 1)"],
            ),
            (
                one(r#"{"type": "Feature", "properties": {"type": "bush"}, "geometry": null}"#.to_string()),
                vec!["no geometry", "(feature 1)"],
            ),
            (
                "{\"type\": \"FeatureCollection\",\n \"features\": [\n  {\"type\": \"Feature\" \"properties\": {}}]}".to_string(),
                vec!["not GeoJSON", "line 3 column"],
            ),
        ];
        for (text, wanted) in cases {
            let msg = refusal(&text);
            for want in wanted {
                assert!(msg.contains(want), "{msg} (wanted {want})");
            }
        }
    }

    #[test]
    fn objects_outside_the_database_are_named_with_their_position() {
        let text = collection(&[
            feature(r#"{"type": "bush"}"#, "Point", &at(10.0, 10.0)),
            r#"{"type": "Feature", "id": 17, "properties": {"type": "house", "height_m": 6}, "geometry": {"type": "MultiPoint", "coordinates": [[7.001, 45.001], [7.5, 45.001]]}}"#.to_string(),
        ]);
        let culture = culture_of(&text);
        let grid = GeoGrid {
            south_lat_deg: 44.99,
            west_lon_deg: 6.99,
            dlat_deg: 1.0 / 1200.0,
            dlon_deg: 1.0 / 1200.0,
            rows: 100,
            cols: 100,
        };
        let path = Path::new("/data/culture.geojson");
        let msg = check_culture_inside(path, &culture, &grid)
            .expect_err("refused")
            .to_string();
        for want in [
            "house at 45.001000, 7.500000 lies outside the database",
            "(feature 1, id \"17\")",
        ] {
            assert!(msg.contains(want), "{msg} (wanted {want})");
        }
        assert!(msg.ends_with("(/data/culture.geojson)"), "{msg}");
        let inside = GeoGrid { cols: 700, ..grid };
        check_culture_inside(path, &culture, &inside).expect("all inside");
    }
}
