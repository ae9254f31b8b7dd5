//! The generated roads, rivers and lakes as shapes ([`cig_terrain::features::Feature`]), for
//! the imagery and the terrain levelling of `cig_terrain::features`.
//!
//! * **Roads**: the road builder's smoothed centre lines, [`PAVED_ROAD_WIDTH_M`] or
//!   [`DIRT_ROAD_WIDTH_M`] wide.
//! * **Rivers**: the D8 river centre posts joined into polylines along their receivers, one
//!   polyline from each source or confluence down to the next confluence (or the lake, sea or
//!   grid edge it ends in), smoothed by two rounds of Chaikin corner cutting (ends kept) and as
//!   wide as the hydrology's width for the catchment at the polyline's middle post.
//! * **Lakes**: each 8-connected region of lake posts traced by marching squares on
//!   `level - ground` (the bed before filling inside, the final surface outside), so the shore
//!   runs where the ground meets the water level, between the posts; diagonal lake posts stay
//!   joined, as the hydrology joined them; islands become holes.
//!
//! Everything is a function of the generated grids, in index order: deterministic.

use crate::flood::{Dims, NEIGHBOURS, NO_RECEIVER};
use crate::hydro::{river_width_m, LAKE, RIVER_CENTRE, SEA};
use crate::roads::RoadKind;
use crate::Road;
use cig_terrain::features::{Feature, LineKind};
use cig_terrain::raster::GeoGrid;
use std::collections::{BTreeMap, VecDeque};

/// A ring of (row, col) or (lat, lon) points.
type Ring = Vec<(f64, f64)>;

/// Width of the generated paved roads, metres (two lanes).
pub const PAVED_ROAD_WIDTH_M: f64 = 7.0;
/// Width of the generated dirt tracks, metres.
pub const DIRT_ROAD_WIDTH_M: f64 = 4.0;

/// What the generator leaves for the features.
pub(crate) struct Sources<'a> {
    pub grid: GeoGrid,
    pub dims: Dims,
    pub spacing_m: f64,
    /// Final heights.
    pub h: &'a [f32],
    /// Heights before depression filling.
    pub bed: &'a [f32],
    pub flags: &'a [u16],
    pub receiver: &'a [u32],
    pub acc: &'a [u32],
    pub roads: &'a [Road],
}

/// Lakes, then rivers, then roads.
pub(crate) fn build(src: &Sources) -> Vec<Feature> {
    let mut out = lakes(src);
    out.extend(rivers(src));
    out.extend(src.roads.iter().map(|r| Feature::Line {
        kind: match r.kind {
            RoadKind::Paved => LineKind::PavedRoad,
            RoadKind::Dirt => LineKind::DirtRoad,
        },
        width_m: match r.kind {
            RoadKind::Paved => PAVED_ROAD_WIDTH_M,
            RoadKind::Dirt => DIRT_ROAD_WIDTH_M,
        },
        points_deg: r.points_deg.clone(),
    }));
    out
}

/// Fractional (row, col) to (lat, lon).
fn to_deg(grid: &GeoGrid, (r, c): (f64, f64)) -> (f64, f64) {
    (
        grid.south_lat_deg + r * grid.dlat_deg,
        grid.west_lon_deg + c * grid.dlon_deg,
    )
}

/// Two rounds of Chaikin corner cutting, end points kept.
fn chaikin(pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut cur = pts.to_vec();
    for _ in 0..2 {
        if cur.len() < 3 {
            break;
        }
        let mut next = Vec::with_capacity(2 * cur.len());
        next.push(cur[0]);
        for w in cur.windows(2) {
            let (a, b) = (w[0], w[1]);
            next.push((0.75 * a.0 + 0.25 * b.0, 0.75 * a.1 + 0.25 * b.1));
            next.push((0.25 * a.0 + 0.75 * b.0, 0.25 * a.1 + 0.75 * b.1));
        }
        next.push(cur[cur.len() - 1]);
        cur = next;
    }
    cur
}

fn rivers(src: &Sources) -> Vec<Feature> {
    let n = src.dims.len();
    let nx = src.dims.nx;
    let centre = |i: usize| src.flags[i] & RIVER_CENTRE != 0;
    let mut indeg = vec![0u8; n];
    for i in 0..n {
        if centre(i) {
            let r = src.receiver[i];
            if r != NO_RECEIVER && centre(r as usize) {
                indeg[r as usize] = indeg[r as usize].saturating_add(1);
            }
        }
    }
    let post_km2 = src.spacing_m * src.spacing_m * 1e-6;
    let mut out = Vec::new();
    for start in 0..n {
        if !centre(start) || indeg[start] == 1 {
            continue;
        }
        let mut chain = vec![start];
        let mut cur = start;
        loop {
            let r = src.receiver[cur];
            if r == NO_RECEIVER {
                break;
            }
            let r = r as usize;
            if !centre(r) {
                if src.flags[r] & (LAKE | SEA) != 0 {
                    chain.push(r);
                }
                break;
            }
            chain.push(r);
            if indeg[r] != 1 || chain.len() > n {
                break;
            }
            cur = r;
        }
        if chain.len() < 2 {
            continue;
        }
        let mid = chain[(chain.len() - 1) / 2];
        let width_m = river_width_m(f64::from(src.acc[mid]) * post_km2);
        let pts: Vec<(f64, f64)> = chain
            .iter()
            .map(|&i| ((i / nx) as f64, (i % nx) as f64))
            .collect();
        out.push(Feature::Line {
            kind: LineKind::River,
            width_m,
            points_deg: chaikin(&pts)
                .into_iter()
                .map(|p| to_deg(&src.grid, p))
                .collect(),
        });
    }
    out
}

fn lakes(src: &Sources) -> Vec<Feature> {
    let (nx, ny) = (src.dims.nx, src.dims.ny);
    let n = src.dims.len();
    let mut label = vec![u32::MAX; n];
    let mut out = Vec::new();
    let mut queue = VecDeque::new();
    let mut region = Vec::new();
    for start in 0..n {
        if src.flags[start] & LAKE == 0 || label[start] != u32::MAX {
            continue;
        }
        let id = start as u32;
        label[start] = id;
        queue.push_back(start);
        region.clear();
        while let Some(c) = queue.pop_front() {
            region.push(c);
            for &(dx, dy) in &NEIGHBOURS {
                if let Some(nb) = src.dims.offset(c, dx, dy) {
                    if src.flags[nb] & LAKE != 0 && label[nb] == u32::MAX {
                        label[nb] = id;
                        queue.push_back(nb);
                    }
                }
            }
        }
        let level = src.h[start];
        let (mut r0, mut c0, mut r1, mut c1) = (usize::MAX, usize::MAX, 0, 0);
        for &c in &region {
            let (r, cc) = (c / nx, c % nx);
            r0 = r0.min(r);
            r1 = r1.max(r);
            c0 = c0.min(cc);
            c1 = c1.max(cc);
        }
        let inside = |r: i64, c: i64| -> bool {
            r >= 0
                && c >= 0
                && (r as usize) < ny
                && (c as usize) < nx
                && label[r as usize * nx + c as usize] == id
        };
        let field = |r: i64, c: i64| -> f64 {
            if r < 0 || c < 0 || r as usize >= ny || c as usize >= nx {
                return -1.0;
            }
            let k = r as usize * nx + c as usize;
            if label[k] == id {
                f64::from(level - src.bed[k]).max(0.01)
            } else {
                f64::from(level - src.h[k]).min(-0.01)
            }
        };
        let rings = march(
            (r0 as i64 - 1, c0 as i64 - 1, r1 as i64 + 1, c1 as i64 + 1),
            &inside,
            &field,
        );
        out.extend(assemble(rings, f64::from(level), &src.grid));
    }
    out
}

/// Marching squares over the cells whose south-west corners lie in `(r0, c0)..(r1, c1)`
/// (inclusive lower, exclusive upper): closed rings of (row, col) with the inside on the left.
fn march(
    (r0, c0, r1, c1): (i64, i64, i64, i64),
    inside: &dyn Fn(i64, i64) -> bool,
    field: &dyn Fn(i64, i64) -> f64,
) -> Vec<Vec<(f64, f64)>> {
    // An edge is named by its first corner and direction: (row, col, 0 east / 1 north).
    type Edge = (i64, i64, u8);
    let crossing = |(r, c, d): Edge| -> (f64, f64) {
        let (r2, c2) = if d == 0 { (r, c + 1) } else { (r + 1, c) };
        let (ga, gb) = (field(r, c), field(r2, c2));
        let t = (ga / (ga - gb)).clamp(0.0, 1.0);
        (
            r as f64 + (r2 - r) as f64 * t,
            c as f64 + (c2 - c) as f64 * t,
        )
    };
    let mut next: BTreeMap<Edge, Edge> = BTreeMap::new();
    for r in r0..r1 {
        for c in c0..c1 {
            // Corners counter-clockwise: sw, se, ne, nw; edge k runs from corner k to k + 1.
            let corners = [(r, c), (r, c + 1), (r + 1, c + 1), (r + 1, c)];
            let edges: [Edge; 4] = [(r, c, 0), (r, c + 1, 1), (r + 1, c, 0), (r, c, 1)];
            let ins: Vec<bool> = corners.iter().map(|&(a, b)| inside(a, b)).collect();
            if ins.iter().all(|&v| v) || ins.iter().all(|&v| !v) {
                continue;
            }
            // Each run of outside corners, counter-clockwise, is cut off by one segment from
            // the edge entering the run to the edge leaving it (inside corners stay joined).
            for k in 0..4 {
                if ins[k] || !ins[(k + 3) % 4] {
                    continue;
                }
                let mut m = k;
                while !ins[(m + 1) % 4] {
                    m = (m + 1) % 4;
                }
                next.insert(edges[(k + 3) % 4], edges[m]);
            }
        }
    }
    let mut rings = Vec::new();
    while let Some((&first, _)) = next.iter().next() {
        let mut ring = Vec::new();
        let mut e = first;
        while let Some(f) = next.remove(&e) {
            ring.push(crossing(e));
            e = f;
        }
        if ring.len() >= 3 {
            rings.push(ring);
        }
    }
    rings
}

/// Signed area in (col, row) axes: positive counter-clockwise.
fn signed_area(ring: &[(f64, f64)]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            a.1 * b.0 - b.1 * a.0
        })
        .sum::<f64>()
        * 0.5
}

fn contains(ring: &[(f64, f64)], (r, c): (f64, f64)) -> bool {
    let n = ring.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a.0 <= r) != (b.0 <= r) && c < a.1 + (r - a.0) * (b.1 - a.1) / (b.0 - a.0) {
            inside = !inside;
        }
    }
    inside
}

/// Outer rings (counter-clockwise) become lakes; holes go to the outer ring around them.
fn assemble(rings: Vec<Vec<(f64, f64)>>, level: f64, grid: &GeoGrid) -> Vec<Feature> {
    let (outer, holes): (Vec<_>, Vec<_>) = rings.into_iter().partition(|r| signed_area(r) > 0.0);
    let mut lakes: Vec<(Ring, Vec<Ring>)> = outer.into_iter().map(|r| (r, Vec::new())).collect();
    for hole in holes {
        if let Some(l) = lakes.iter_mut().find(|(o, _)| contains(o, hole[0])) {
            l.1.push(hole);
        }
    }
    lakes
        .into_iter()
        .map(|(o, h)| Feature::Lake {
            outer_deg: o.into_iter().map(|p| to_deg(grid, p)).collect(),
            holes_deg: h
                .into_iter()
                .map(|r| r.into_iter().map(|p| to_deg(grid, p)).collect())
                .collect(),
            level_m: Some(level),
        })
        .collect()
}
