//! Settlements and the road network: least-cost paths on a coarse grid, graded profiles and
//! rasterisation onto the posts.
//!
//! # Algorithm
//!
//! 1. **Road grid**: nodes every `max(60 m, size / 500, spacing)` with 16-connectivity (the
//!    eight neighbours and the eight knight moves, for 22.5-degree headings). Node heights are
//!    bilinear samples of the posts after hydrology; lakes and sea are impassable, rivers cost a
//!    bridge (paved) or ford (dirt) penalty, lake shores are expensive.
//! 2. **Edge cost** (metres-equivalent): `length * (1 + 3 (grade / max_grade)^4 + 4 max(0,
//!    side_slope - 0.1))`; edges steeper than twice the kind's maximum grade (10 % paved, 16 %
//!    dirt) are impassable. The quartic grade term makes roads contour around hills and take
//!    switchbacks instead of climbing straight.
//! 3. **Settlements** on flat, low ground away from water and the edge, chosen greedily by a
//!    score (slope, relative height, a hash of the seed) at a minimum separation.
//! 4. **Paved network**: Prim-like growth. A least-cost search (A*, Hart, Nilsson & Raphael
//!    1968, guided by the straight distance to the nearest unconnected settlement, which never
//!    overestimates since every edge costs at least its length) runs from every node already on
//!    the network (cost 0) until it settles an unconnected settlement; the path to it joins the
//!    network. Paths therefore start at a junction on the network and never run along it.
//! 5. **Dirt roads**: one Dijkstra (1959) search from the whole paved network gives a shortest-path tree;
//!    tracks run from random points back along that tree until they meet the network (paved or an
//!    earlier track), so tracks branch and merge like real ones.
//! 6. **Profiles**: node heights along each path are smoothed (5-node moving average), pinned at
//!    the junction to the road already there and clamped forward to the kind's maximum grade
//!    (cut and fill). Paths are smoothed by two rounds of Chaikin corner cutting (1974).
//! 7. **Rasterisation**: paved roads cover the posts within 0.75 spacing of the centre line (two
//!    posts wide at 30 m; one at coarser spacings), dirt roads the nearest post. Every road post
//!    takes the profile height of its nearest centre-line sample, so there is no cross slope;
//!    posts within 1.5 spacings beyond are blended into the terrain as embankments. Water and
//!    shore posts are never touched (a river crossing is a bridge, left to the feature database).
//!    A last grade envelope, `h(p) <= h(q) + 0.16 * distance(p, q)` over connected road posts
//!    (a Dijkstra distance transform, only lowering), bounds the grade where roads meet.
//!
//! # Limits
//!
//! The network is a tree (no loops); costs ignore curvature, so hairpins can be tight, and the
//! two legs of a hairpin less than two posts apart merge into one wide road with a step between
//! them (bounded by the grade envelope); bridges are gaps in the road raster; settlements are
//! points (no street grid).

use crate::flood::{Dims, NEIGHBOURS};
use crate::hydro::{DIRT, LAKE, PAVED, RIVER, SEA, SHORE, WATER};
use crate::noise::{mix64, unit_from_hash};
use rand::RngCore;
use rand_chacha::ChaCha8Rng;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Maximum grade of paved roads (rise over run).
pub(crate) const PAVED_MAX_GRADE: f64 = 0.10;
/// Maximum grade of dirt roads.
pub(crate) const DIRT_MAX_GRADE: f64 = 0.16;

const NONE: u32 = u32::MAX;

/// Road class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RoadKind {
    /// A dirt track.
    Dirt,
    /// A paved road.
    Paved,
}

impl RoadKind {
    fn max_grade(self) -> f64 {
        match self {
            RoadKind::Paved => PAVED_MAX_GRADE,
            RoadKind::Dirt => DIRT_MAX_GRADE,
        }
    }
}

/// A road centre line in local metres (x east, y north of the south-west post).
#[derive(Clone, Debug)]
pub(crate) struct LocalRoad {
    pub kind: RoadKind,
    pub points_m: Vec<(f64, f64)>,
    pub length_m: f64,
}

/// What the road builder made.
pub(crate) struct RoadNetwork {
    pub settlements_m: Vec<(f64, f64)>,
    pub roads: Vec<LocalRoad>,
}

/// Node class on the road grid.
const LAND: u8 = 0;
const CROSSING: u8 = 1;
const NEAR_SHORE: u8 = 2;
const BLOCKED: u8 = 3;

struct RoadGrid {
    dims: Dims,
    cell_m: f64,
    z: Vec<f64>,
    side_slope: Vec<f64>,
    class: Vec<u8>,
}

/// Knight moves, which let least-cost paths take gentler headings than the eight neighbours.
const KNIGHT_MOVES: [(i64, i64); 8] = [
    (2, 1),
    (1, 2),
    (-1, 2),
    (-2, 1),
    (-2, -1),
    (-1, -2),
    (1, -2),
    (2, -1),
];

/// 16-connectivity: the eight neighbours (in [`NEIGHBOURS`] order), then the knight moves.
const MOVES: [(i64, i64); 16] = {
    let mut moves = [(0, 0); 16];
    let mut k = 0;
    while k < 8 {
        moves[k] = NEIGHBOURS[k];
        moves[k + 8] = KNIGHT_MOVES[k];
        k += 1;
    }
    moves
};

impl RoadGrid {
    fn new(h: &[f32], flags: &[u16], posts: Dims, spacing_m: f64, size_m: f64) -> RoadGrid {
        let cell_m = 60.0f64.max(size_m / 500.0).max(spacing_m);
        let extent_x = (posts.nx - 1) as f64 * spacing_m;
        let extent_y = (posts.ny - 1) as f64 * spacing_m;
        let nx = (extent_x / cell_m).floor() as usize + 1;
        let ny = (extent_y / cell_m).floor() as usize + 1;
        let dims = Dims { nx, ny };
        let n = dims.len();
        let mut z = vec![0.0; n];
        let mut class = vec![LAND; n];
        for j in 0..ny {
            for i in 0..nx {
                let x = i as f64 * cell_m;
                let y = j as f64 * cell_m;
                z[j * nx + i] = bilinear(h, posts, x / spacing_m, y / spacing_m);
                let p = nearest_post(posts, spacing_m, x, y);
                let mut cls = LAND;
                if flags[p] & (LAKE | SEA) != 0 {
                    cls = BLOCKED;
                } else {
                    for &(dx, dy) in NEIGHBOURS.iter().chain(std::iter::once(&(0, 0))) {
                        if let Some(q) = posts.offset(p, dx, dy) {
                            if flags[q] & (LAKE | SEA | SHORE) != 0 {
                                cls = cls.max(NEAR_SHORE);
                            } else if flags[q] & RIVER != 0 {
                                cls = cls.max(CROSSING);
                            }
                        }
                    }
                }
                class[j * nx + i] = cls;
            }
        }
        let mut side_slope = vec![0.0; n];
        for j in 0..ny {
            for i in 0..nx {
                let c = j * nx + i;
                let (il, ir) = (i.saturating_sub(1), (i + 1).min(nx - 1));
                let (jd, ju) = (j.saturating_sub(1), (j + 1).min(ny - 1));
                let gx = if ir > il {
                    (z[j * nx + ir] - z[j * nx + il]) / ((ir - il) as f64 * cell_m)
                } else {
                    0.0
                };
                let gy = if ju > jd {
                    (z[ju * nx + i] - z[jd * nx + i]) / ((ju - jd) as f64 * cell_m)
                } else {
                    0.0
                };
                side_slope[c] = (gx * gx + gy * gy).sqrt();
            }
        }
        RoadGrid {
            dims,
            cell_m,
            z,
            side_slope,
            class,
        }
    }

    fn position_m(&self, node: usize) -> (f64, f64) {
        (
            (node % self.dims.nx) as f64 * self.cell_m,
            (node / self.dims.nx) as f64 * self.cell_m,
        )
    }

    /// Cost of the move from `a` by `(dx, dy)` to `b`, or `None` when impassable.
    #[inline]
    fn edge_cost(
        &self,
        kind: RoadKind,
        a: usize,
        b: usize,
        dx: i64,
        dy: i64,
        len: f64,
    ) -> Option<f64> {
        if self.class[b] == BLOCKED {
            return None;
        }
        if dx.abs() + dy.abs() == 3 {
            // A knight move passes between two nodes; both must be passable. They lie inside the
            // grid because both ends do.
            let nx = self.dims.nx as i64;
            let (sx, sy) = (dx.signum(), dy.signum());
            let mid1 = (a as i64 + sy * nx + sx) as usize;
            let mid2 = if dx.abs() == 2 {
                (a as i64 + sx) as usize
            } else {
                (a as i64 + sy * nx) as usize
            };
            if self.class[mid1] == BLOCKED || self.class[mid2] == BLOCKED {
                return None;
            }
        }
        let grade = (self.z[b] - self.z[a]).abs() / len;
        let g = grade / kind.max_grade();
        if g > 2.0 {
            return None;
        }
        let g2 = g * g;
        let side = (self.side_slope[b] - 0.1).max(0.0);
        let mut cost = len * (1.0 + 3.0 * g2 * g2 + 4.0 * side);
        match self.class[b] {
            CROSSING => {
                cost += match kind {
                    RoadKind::Paved => 400.0,
                    RoadKind::Dirt => 150.0,
                }
            }
            NEAR_SHORE => cost += 4.0 * len,
            _ => {}
        }
        Some(cost)
    }

    /// Dijkstra from `sources` (cost 0), or A* when `targets` is not empty: then it stops when
    /// the first of `targets` is settled and returns it, guided by the straight distance to the
    /// nearest target (admissible: every edge costs at least its length), so the target found is
    /// the cheapest to reach. `dist` and `prev` hold the search tree.
    fn dijkstra(
        &self,
        kind: RoadKind,
        sources: &[u32],
        targets: &[usize],
        dist: &mut Vec<f64>,
        prev: &mut Vec<u32>,
    ) -> Option<usize> {
        let n = self.dims.len();
        let nx = self.dims.nx as i64;
        let ny = self.dims.ny as i64;
        dist.clear();
        dist.resize(n, f64::INFINITY);
        prev.clear();
        prev.resize(n, NONE);
        let mut done = vec![false; n];
        let mut is_target = vec![false; n];
        let target_xy: Vec<(f64, f64)> = targets.iter().map(|&t| self.position_m(t)).collect();
        for &t in targets {
            is_target[t] = true;
        }
        let heuristic = |c: usize| -> f64 {
            let (x, y) = self.position_m(c);
            target_xy
                .iter()
                .map(|&(tx, ty)| ((tx - x) * (tx - x) + (ty - y) * (ty - y)).sqrt())
                .fold(f64::INFINITY, f64::min)
        };
        let h_of = |c: usize| {
            if targets.is_empty() {
                0.0
            } else {
                heuristic(c)
            }
        };
        let mut heap: BinaryHeap<Reverse<(u64, u32)>> = BinaryHeap::new();
        for &s in sources {
            dist[s as usize] = 0.0;
            heap.push(Reverse((h_of(s as usize).to_bits(), s)));
        }
        let lens: Vec<f64> = MOVES
            .iter()
            .map(|&(dx, dy)| self.cell_m * ((dx * dx + dy * dy) as f64).sqrt())
            .collect();
        while let Some(Reverse((_, a))) = heap.pop() {
            let a = a as usize;
            if done[a] {
                continue;
            }
            done[a] = true;
            if is_target[a] {
                return Some(a);
            }
            let da = dist[a];
            let (ax, ay) = ((a % self.dims.nx) as i64, (a / self.dims.nx) as i64);
            for (m, &(dx, dy)) in MOVES.iter().enumerate() {
                let (bx, by) = (ax + dx, ay + dy);
                if bx < 0 || by < 0 || bx >= nx || by >= ny {
                    continue;
                }
                let b = (by * nx + bx) as usize;
                if done[b] {
                    continue;
                }
                let Some(c) = self.edge_cost(kind, a, b, dx, dy, lens[m]) else {
                    continue;
                };
                let nd = da + c;
                if nd < dist[b] {
                    dist[b] = nd;
                    prev[b] = a as u32;
                    // Non-negative f64 order equals the order of their bit patterns.
                    heap.push(Reverse(((nd + h_of(b)).to_bits(), b as u32)));
                }
            }
        }
        None
    }
}

/// Bilinear sample of the posts at fractional (column, row).
fn bilinear(h: &[f32], dims: Dims, fc: f64, fr: f64) -> f64 {
    let fc = fc.clamp(0.0, (dims.nx - 1) as f64);
    let fr = fr.clamp(0.0, (dims.ny - 1) as f64);
    let c0 = (fc.floor() as usize).min(dims.nx.saturating_sub(2));
    let r0 = (fr.floor() as usize).min(dims.ny.saturating_sub(2));
    let c1 = (c0 + 1).min(dims.nx - 1);
    let r1 = (r0 + 1).min(dims.ny - 1);
    let tx = (fc - c0 as f64).clamp(0.0, 1.0);
    let ty = (fr - r0 as f64).clamp(0.0, 1.0);
    let at = |r: usize, c: usize| f64::from(h[r * dims.nx + c]);
    let a = at(r0, c0) + (at(r0, c1) - at(r0, c0)) * tx;
    let b = at(r1, c0) + (at(r1, c1) - at(r1, c0)) * tx;
    a + (b - a) * ty
}

fn nearest_post(dims: Dims, spacing_m: f64, x: f64, y: f64) -> usize {
    let c = ((x / spacing_m).round().max(0.0) as usize).min(dims.nx - 1);
    let r = ((y / spacing_m).round().max(0.0) as usize).min(dims.ny - 1);
    r * dims.nx + c
}

/// Settlement sites: flat, low, dry ground away from the edge, at least `sep_m` apart.
fn choose_settlements(grid: &RoadGrid, wanted: usize, seed: u64) -> Vec<usize> {
    let nx = grid.dims.nx;
    let ny = grid.dims.ny;
    let extent = (nx.min(ny) - 1) as f64 * grid.cell_m;
    let inset = (0.06 * extent).max(1_000.0f64.min(0.2 * extent));
    let sep_m = (0.2 * extent).max(2_000.0f64.min(0.4 * extent));
    let (mut zmin, mut zmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for &z in &grid.z {
        zmin = zmin.min(z);
        zmax = zmax.max(z);
    }
    let mut cands: Vec<(f64, usize)> = Vec::new();
    for c in 0..grid.dims.len() {
        let (x, y) = grid.position_m(c);
        let xmax = (nx - 1) as f64 * grid.cell_m;
        let ymax = (ny - 1) as f64 * grid.cell_m;
        if x < inset || y < inset || x > xmax - inset || y > ymax - inset {
            continue;
        }
        if grid.class[c] != LAND || grid.side_slope[c] > 0.06 {
            continue;
        }
        let rel = (grid.z[c] - zmin) / (zmax - zmin + 1.0);
        let jitter = unit_from_hash(mix64(seed ^ c as u64));
        let score = grid.side_slope[c] / 0.06 + 1.2 * rel + 0.8 * jitter;
        cands.push((score, c));
    }
    cands.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut chosen: Vec<usize> = Vec::new();
    for &(_, c) in &cands {
        if chosen.len() >= wanted {
            break;
        }
        let (x, y) = grid.position_m(c);
        let far = chosen.iter().all(|&o| {
            let (ox, oy) = grid.position_m(o);
            (ox - x) * (ox - x) + (oy - y) * (oy - y) >= sep_m * sep_m
        });
        if far {
            chosen.push(c);
        }
    }
    chosen
}

/// Nodes from the network junction to `end`, following `prev`.
fn trace(prev: &[u32], end: usize, on_network: &[bool]) -> Vec<usize> {
    let mut path = vec![end];
    let mut c = end;
    while !on_network[c] {
        let p = prev[c];
        if p == NONE {
            break;
        }
        c = p as usize;
        path.push(c);
    }
    path.reverse();
    path
}

/// Graded profile along a node path, pinned at the start to `start_z`.
fn profile(grid: &RoadGrid, path: &[usize], start_z: f64, max_grade: f64) -> Vec<f64> {
    let raw: Vec<f64> = path.iter().map(|&c| grid.z[c]).collect();
    let n = raw.len();
    let mut z: Vec<f64> = (0..n)
        .map(|i| {
            let lo = i.saturating_sub(2);
            let hi = (i + 2).min(n - 1);
            raw[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64
        })
        .collect();
    z[0] = start_z;
    for i in 1..n {
        let (x0, y0) = grid.position_m(path[i - 1]);
        let (x1, y1) = grid.position_m(path[i]);
        let d = ((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0)).sqrt();
        let lim = max_grade * d;
        z[i] = z[i].clamp(z[i - 1] - lim, z[i - 1] + lim);
    }
    z
}

/// Two rounds of Chaikin corner cutting on (x, y, z), keeping the end points.
fn chaikin(points: &[(f64, f64, f64)]) -> Vec<(f64, f64, f64)> {
    let mut pts = points.to_vec();
    for _ in 0..2 {
        if pts.len() < 3 {
            return pts;
        }
        let mut out = Vec::with_capacity(2 * pts.len());
        out.push(pts[0]);
        for w in pts.windows(2) {
            let (a, b) = (w[0], w[1]);
            let q = (
                0.75 * a.0 + 0.25 * b.0,
                0.75 * a.1 + 0.25 * b.1,
                0.75 * a.2 + 0.25 * b.2,
            );
            let r = (
                0.25 * a.0 + 0.75 * b.0,
                0.25 * a.1 + 0.75 * b.1,
                0.25 * a.2 + 0.75 * b.2,
            );
            out.push(q);
            out.push(r);
        }
        // Replace the first and last cut points by the true ends.
        out.remove(1);
        out.pop();
        if let Some(&last) = pts.last() {
            out.push(last);
        }
        pts = out;
    }
    pts
}

/// Per-post road rasterisation state.
struct Paint {
    kind: Vec<u8>,
    dist: Vec<f32>,
    z: Vec<f32>,
    shoulder_t: Vec<f32>,
    shoulder_z: Vec<f32>,
}

/// Builds settlements and roads and writes them into `h` and `flags`.
pub(crate) fn build(
    h: &mut [f32],
    flags: &mut [u16],
    posts: Dims,
    spacing_m: f64,
    size_m: f64,
    rng: &mut ChaCha8Rng,
    progress: &mut dyn FnMut(&str, f32),
) -> RoadNetwork {
    progress("roads", 0.0);
    let grid = RoadGrid::new(h, flags, posts, spacing_m, size_m);
    let n = grid.dims.len();
    let area_km2 = size_m * size_m * 1e-6;
    let wanted_towns = ((area_km2 / 350.0).round() as usize).clamp(2, 12);
    let wanted_tracks = ((area_km2 / 60.0).round() as usize).clamp(2, 60);
    let town_seed = rng.next_u64();
    let towns = choose_settlements(&grid, wanted_towns, town_seed);
    let mut network = RoadNetwork {
        settlements_m: towns.iter().map(|&c| grid.position_m(c)).collect(),
        roads: Vec::new(),
    };
    if towns.is_empty() {
        progress("roads", 1.0);
        return network;
    }
    let mut on_network = vec![false; n];
    let mut road_z = vec![f64::NAN; n];
    let mut paths: Vec<(RoadKind, Vec<usize>, Vec<f64>)> = Vec::new();
    on_network[towns[0]] = true;
    road_z[towns[0]] = grid.z[towns[0]];
    let mut dist = Vec::new();
    let mut prev = Vec::new();
    let mut sources: Vec<u32> = vec![towns[0] as u32];
    let mut unconnected: Vec<usize> = towns[1..].to_vec();
    for k in 1..towns.len() {
        let Some(end) = grid.dijkstra(
            RoadKind::Paved,
            &sources,
            &unconnected,
            &mut dist,
            &mut prev,
        ) else {
            break;
        };
        unconnected.retain(|&t| t != end);
        let path = trace(&prev, end, &on_network);
        if path.len() >= 2 && on_network[path[0]] {
            let start_z = road_z[path[0]];
            let z = profile(&grid, &path, start_z, PAVED_MAX_GRADE);
            for (&c, &zz) in path.iter().zip(&z) {
                if !on_network[c] {
                    on_network[c] = true;
                    road_z[c] = zz;
                    sources.push(c as u32);
                }
            }
            paths.push((RoadKind::Paved, path, z));
        } else {
            on_network[end] = true;
            road_z[end] = grid.z[end];
            sources.push(end as u32);
        }
        progress("roads", 0.6 * k as f32 / towns.len() as f32);
    }

    // Dirt tracks: random end points, traced back along one shortest-path tree.
    grid.dijkstra(RoadKind::Dirt, &sources, &[], &mut dist, &mut prev);
    let extent = (grid.dims.nx.min(grid.dims.ny) - 1) as f64 * grid.cell_m;
    let min_track_m = 1_500.0f64.min(0.25 * extent);
    let track_sep_m = 2_000.0f64.min(0.2 * extent);
    let mut ends: Vec<usize> = Vec::new();
    let mut tries = 0;
    while ends.len() < wanted_tracks && tries < 40 * wanted_tracks {
        tries += 1;
        let c = (rng.next_u64() % n as u64) as usize;
        if grid.class[c] != LAND || on_network[c] || !dist[c].is_finite() {
            continue;
        }
        // Long enough, and not absurdly expensive (3x the straight distance of the area).
        if dist[c] < min_track_m || dist[c] > 3.0 * extent {
            continue;
        }
        let (x, y) = grid.position_m(c);
        let far = ends.iter().all(|&o| {
            let (ox, oy) = grid.position_m(o);
            (ox - x) * (ox - x) + (oy - y) * (oy - y) >= track_sep_m * track_sep_m
        });
        if far {
            ends.push(c);
        }
    }
    for &end in &ends {
        let path = trace(&prev, end, &on_network);
        if path.len() < 2 || !on_network[path[0]] {
            continue;
        }
        let z = profile(&grid, &path, road_z[path[0]], DIRT_MAX_GRADE);
        for (&c, &zz) in path.iter().zip(&z) {
            if !on_network[c] {
                on_network[c] = true;
                road_z[c] = zz;
            }
        }
        paths.push((RoadKind::Dirt, path, z));
    }
    progress("roads", 0.8);

    // Rasterise: dirt first, then paved (paved wins where they overlap).
    let np = posts.len();
    let mut paint = Paint {
        kind: vec![0; np],
        dist: vec![f32::INFINITY; np],
        z: vec![0.0; np],
        shoulder_t: vec![f32::INFINITY; np],
        shoulder_z: vec![0.0; np],
    };
    paths.sort_by_key(|p| p.0);
    for (kind, path, z) in &paths {
        let pts: Vec<(f64, f64, f64)> = path
            .iter()
            .zip(z)
            .map(|(&c, &zz)| {
                let (x, y) = grid.position_m(c);
                (x, y, zz)
            })
            .collect();
        let smooth = chaikin(&pts);
        let length_m = rasterise(&smooth, *kind, flags, posts, spacing_m, &mut paint);
        network.roads.push(LocalRoad {
            kind: *kind,
            points_m: smooth.iter().map(|p| (p.0, p.1)).collect(),
            length_m,
        });
    }
    for p in 0..np {
        if paint.kind[p] != 0 {
            h[p] = paint.z[p];
            flags[p] |= if paint.kind[p] == 2 { PAVED } else { DIRT };
        } else if paint.shoulder_t[p] < 1.0 {
            let t = paint.shoulder_t[p].max(0.0);
            let zr = paint.shoulder_z[p];
            h[p] = zr + (h[p] - zr) * t;
        }
    }
    grade_envelope(h, flags, posts, spacing_m, DIRT_MAX_GRADE);
    progress("roads", 1.0);
    network
}

/// Paints one smoothed centre line; returns its length in metres.
fn rasterise(
    pts: &[(f64, f64, f64)],
    kind: RoadKind,
    flags: &[u16],
    posts: Dims,
    spacing_m: f64,
    paint: &mut Paint,
) -> f64 {
    let kind_code: u8 = match kind {
        RoadKind::Dirt => 1,
        RoadKind::Paved => 2,
    };
    let road_r = if kind == RoadKind::Paved && spacing_m <= 40.0 {
        0.75 * spacing_m
    } else {
        0.0
    };
    let edge_r = road_r.max(0.5 * spacing_m);
    let shoulder_w = 1.5 * spacing_m;
    let reach = ((edge_r + shoulder_w) / spacing_m).ceil() as i64;
    let step = spacing_m / 3.0;
    let mut length = 0.0;
    let nx = posts.nx as i64;
    let ny = posts.ny as i64;
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let seg = ((b.0 - a.0) * (b.0 - a.0) + (b.1 - a.1) * (b.1 - a.1)).sqrt();
        length += seg;
        let steps = ((seg / step).ceil() as usize).max(1);
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            let x = a.0 + (b.0 - a.0) * t;
            let y = a.1 + (b.1 - a.1) * t;
            let z = (a.2 + (b.2 - a.2) * t) as f32;
            let near = nearest_post(posts, spacing_m, x, y);
            let cx = (x / spacing_m).round() as i64;
            let cy = (y / spacing_m).round() as i64;
            for dy in -reach..=reach {
                let r = cy + dy;
                if r < 0 || r >= ny {
                    continue;
                }
                for dx in -reach..=reach {
                    let c = cx + dx;
                    if c < 0 || c >= nx {
                        continue;
                    }
                    let p = (r * nx + c) as usize;
                    if flags[p] & (WATER | SHORE) != 0 {
                        continue;
                    }
                    let px = c as f64 * spacing_m;
                    let py = r as f64 * spacing_m;
                    let d = ((px - x) * (px - x) + (py - y) * (py - y)).sqrt();
                    if p == near || d <= road_r {
                        let df = d as f32;
                        if kind_code > paint.kind[p]
                            || (kind_code == paint.kind[p] && df < paint.dist[p])
                        {
                            paint.kind[p] = kind_code;
                            paint.dist[p] = df;
                            paint.z[p] = z;
                        }
                    }
                    let t = ((d - edge_r) / shoulder_w) as f32;
                    if t < paint.shoulder_t[p] {
                        paint.shoulder_t[p] = t;
                        paint.shoulder_z[p] = z;
                    }
                }
            }
        }
    }
    length
}

/// Lowers road posts so that `h(p) <= h(q) + grade * distance(p, q)` for 8-connected road posts.
fn grade_envelope(h: &mut [f32], flags: &[u16], posts: Dims, spacing_m: f64, grade: f64) {
    let is_road = |p: usize| flags[p] & (PAVED | DIRT) != 0;
    let mut heap: BinaryHeap<Reverse<(u64, u32)>> = BinaryHeap::new();
    let key = |v: f32| -> u64 {
        let b = v.to_bits();
        u64::from(if b >> 31 == 1 { !b } else { b | 0x8000_0000 })
    };
    for (p, &v) in h.iter().enumerate().take(posts.len()) {
        if is_road(p) {
            heap.push(Reverse((key(v), p as u32)));
        }
    }
    let straight = (grade * spacing_m) as f32;
    let diagonal = (grade * spacing_m * std::f64::consts::SQRT_2) as f32;
    while let Some(Reverse((k, p))) = heap.pop() {
        let p = p as usize;
        if k != key(h[p]) {
            continue;
        }
        for (i, &(dx, dy)) in NEIGHBOURS.iter().enumerate() {
            let Some(q) = posts.offset(p, dx, dy) else {
                continue;
            };
            if !is_road(q) {
                continue;
            }
            let lim = h[p] + if i < 4 { straight } else { diagonal };
            if h[q] > lim {
                h[q] = lim;
                heap.push(Reverse((key(lim), q as u32)));
            }
        }
    }
}
