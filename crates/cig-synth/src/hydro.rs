//! Sea, lakes and rivers on the post grid.
//!
//! # Algorithm
//!
//! 1. **Sea**: posts below 0 m connected to the grid edge through posts below 0 m are sea (the
//!    coast of [`crate::coast`]); they are set to 0 m, the sea's surface at mean sea level (as
//!    lakes hold their surface), and become outlets.
//! 2. **Depressions**: Priority-Flood (Barnes et al. 2014, see [`crate::flood`]) from the grid
//!    edge and the sea fills every closed depression to its spill height. Each connected region of
//!    raised posts is exactly flat. A region of at least [`LAKE_MIN_AREA_M2`] (and four posts) that
//!    was at least [`LAKE_MIN_DEPTH_M`] deep becomes a lake: water at its spill height. Smaller or
//!    shallower pits are filled and stay land (flat alluvial floors), so there are no ponds of one
//!    or two posts.
//! 3. **Flow**: D8 receivers (O'Callaghan & Mark 1984) on the filled surface and flow
//!    accumulation in exact post counts; catchment area is posts times the post area.
//! 4. **Rivers**: posts whose catchment is at least [`RIVER_MIN_CATCHMENT_KM2`] (outside lakes and
//!    sea) are river centre posts. Each gets a water surface `depth` below the filled surface,
//!    `depth = 1.5 + 1.2 log10(A / km^2)` metres, never below the level of the lake or sea it
//!    drains into, made non-increasing downstream by a minimum sweep from the sources down. Posts
//!    within half the river width, `width = 4 sqrt(A / km^2)` metres (at most 150 m; hydraulic
//!    geometry, Leopold & Maddock 1953), become water at that surface; banks beyond are cut back
//!    at 1:2 so the channel is incised. A last sweep keeps the centre line non-increasing.
//!
//! # Limits
//!
//! Rivers follow D8 paths, so they are quantised to 45 degrees and do not meander; width is a
//! function of catchment only (no climate); lakes have no outflow channel below their spill.

use crate::flood::{accumulate, priority_flood, Dims, Flood, NEIGHBOURS, NO_RECEIVER};
use std::collections::VecDeque;

/// Smallest lake, square metres.
pub(crate) const LAKE_MIN_AREA_M2: f64 = 100_000.0;
/// Smallest lake depth (spill height minus deepest point), metres.
pub(crate) const LAKE_MIN_DEPTH_M: f32 = 2.0;
/// Smallest catchment of a river, km^2.
pub(crate) const RIVER_MIN_CATCHMENT_KM2: f64 = 3.0;

/// Post flags.
pub(crate) const SEA: u16 = 1;
pub(crate) const LAKE: u16 = 2;
pub(crate) const RIVER: u16 = 4;
pub(crate) const RIVER_CENTRE: u16 = 8;
/// A filled depression that is not a lake.
pub(crate) const FLAT: u16 = 16;
/// A land post next to a lake or the sea: nothing may lower it below the water.
pub(crate) const SHORE: u16 = 32;
pub(crate) const PAVED: u16 = 64;
pub(crate) const DIRT: u16 = 128;
/// Any water.
pub(crate) const WATER: u16 = SEA | LAKE | RIVER;

/// A lake found by the hydrology.
#[derive(Clone, Debug, PartialEq)]
pub struct Lake {
    /// Water surface (spill) height, metres.
    pub surface_m: f32,
    /// Number of posts.
    pub posts: usize,
    /// Area, km^2.
    pub area_km2: f64,
    /// Spill height minus the deepest point of the original pit, metres.
    pub max_depth_m: f32,
}

/// What the hydrology computed.
pub(crate) struct Hydrology {
    pub flood: Flood,
    pub acc: Vec<u32>,
    pub lakes: Vec<Lake>,
    /// Heights before depression filling (the lakes' beds), for tracing the shores.
    pub bed: Vec<f32>,
    pub river_centre_posts: usize,
    pub river_water_posts: usize,
}

/// Runs sea detection, depression filling, lakes, flow routing and river carving in place.
pub(crate) fn run(
    h: &mut [f32],
    flags: &mut [u16],
    dims: Dims,
    spacing_m: f64,
    progress: &mut dyn FnMut(&str, f32),
) -> Hydrology {
    let n = dims.len();
    progress("hydrology", 0.0);
    mark_sea(h, flags, dims);
    let outlets: Vec<u32> = (0..n)
        .filter(|&i| dims.is_edge(i) || flags[i] & SEA != 0)
        .map(|i| i as u32)
        .collect();
    let flood = priority_flood(h, dims, &outlets, spacing_m, spacing_m, None, 8);
    progress("hydrology", 0.5);
    let lakes = find_lakes(h, &flood.filled, flags, dims, spacing_m);
    let bed = h.to_vec();
    h.copy_from_slice(&flood.filled);
    mark_shores(flags, dims);
    let acc = accumulate(&flood, n);
    progress("hydrology", 0.8);
    let (river_centre_posts, river_water_posts) =
        carve_rivers(h, flags, dims, spacing_m, &flood, &acc);
    progress("hydrology", 1.0);
    Hydrology {
        flood,
        acc,
        lakes,
        bed,
        river_centre_posts,
        river_water_posts,
    }
}

/// Marks posts below 0 m connected to the edge as sea and sets them to 0 m.
fn mark_sea(h: &mut [f32], flags: &mut [u16], dims: Dims) {
    let mut queue = VecDeque::new();
    for i in 0..dims.len() {
        if dims.is_edge(i) && h[i] < 0.0 {
            flags[i] |= SEA;
            queue.push_back(i);
        }
    }
    while let Some(c) = queue.pop_front() {
        for &(dx, dy) in &NEIGHBOURS {
            if let Some(nb) = dims.offset(c, dx, dy) {
                if flags[nb] & SEA == 0 && h[nb] < 0.0 {
                    flags[nb] |= SEA;
                    queue.push_back(nb);
                }
            }
        }
    }
    for (hh, f) in h.iter_mut().zip(flags.iter()) {
        if f & SEA != 0 {
            *hh = 0.0;
        }
    }
}

/// Labels the connected raised regions of the flood; big, deep ones become lakes, the rest flats.
fn find_lakes(
    h: &[f32],
    filled: &[f32],
    flags: &mut [u16],
    dims: Dims,
    spacing_m: f64,
) -> Vec<Lake> {
    let n = dims.len();
    let post_area_m2 = spacing_m * spacing_m;
    let mut seen = vec![false; n];
    let mut lakes = Vec::new();
    let mut region = Vec::new();
    let mut queue = VecDeque::new();
    for start in 0..n {
        if seen[start] || filled[start] <= h[start] {
            continue;
        }
        seen[start] = true;
        region.clear();
        queue.push_back(start);
        let level = filled[start];
        let mut max_depth = 0.0f32;
        while let Some(c) = queue.pop_front() {
            region.push(c);
            max_depth = max_depth.max(level - h[c]);
            for &(dx, dy) in &NEIGHBOURS {
                if let Some(nb) = dims.offset(c, dx, dy) {
                    if !seen[nb] && filled[nb] > h[nb] && filled[nb] == level {
                        seen[nb] = true;
                        queue.push_back(nb);
                    }
                }
            }
        }
        let area_m2 = region.len() as f64 * post_area_m2;
        let is_lake =
            area_m2 >= LAKE_MIN_AREA_M2 && region.len() >= 4 && max_depth >= LAKE_MIN_DEPTH_M;
        let flag = if is_lake { LAKE } else { FLAT };
        for &c in &region {
            flags[c] |= flag;
        }
        if is_lake {
            lakes.push(Lake {
                surface_m: level,
                posts: region.len(),
                area_km2: area_m2 * 1e-6,
                max_depth_m: max_depth,
            });
        }
    }
    lakes
}

/// Flags land posts next to a lake or the sea.
pub(crate) fn mark_shores(flags: &mut [u16], dims: Dims) {
    for c in 0..dims.len() {
        if flags[c] & (LAKE | SEA) == 0 {
            continue;
        }
        for &(dx, dy) in &NEIGHBOURS {
            if let Some(nb) = dims.offset(c, dx, dy) {
                if flags[nb] & (LAKE | SEA) == 0 {
                    flags[nb] |= SHORE;
                }
            }
        }
    }
}

/// River width in metres for a catchment in km^2.
pub(crate) fn river_width_m(catchment_km2: f64) -> f64 {
    (4.0 * catchment_km2.sqrt()).min(150.0)
}

/// River incision in metres for a catchment in km^2.
fn river_depth_m(catchment_km2: f64) -> f64 {
    1.5 + 1.2 * libm::log10(catchment_km2.max(1.0))
}

/// Lowers each river centre post's value to its upstream neighbour's where that is lower, from
/// the sources down (the priority flood's order reversed), so values never rise downstream.
fn never_rise_downstream(values: &mut [f32], flood: &Flood, flags: &[u16]) {
    for &c in flood.order.iter().rev() {
        let c = c as usize;
        if flags[c] & RIVER_CENTRE == 0 {
            continue;
        }
        let r = flood.receiver[c];
        if r != NO_RECEIVER && flags[r as usize] & RIVER_CENTRE != 0 {
            let r = r as usize;
            values[r] = values[r].min(values[c]);
        }
    }
}

/// Carves rivers; returns (centre posts, water posts).
fn carve_rivers(
    h: &mut [f32],
    flags: &mut [u16],
    dims: Dims,
    spacing_m: f64,
    flood: &Flood,
    acc: &[u32],
) -> (usize, usize) {
    let n = dims.len();
    let post_km2 = spacing_m * spacing_m * 1e-6;
    let threshold_posts = (RIVER_MIN_CATCHMENT_KM2 / post_km2).ceil().max(2.0) as u32;
    let mut centres = 0usize;
    for c in 0..n {
        if acc[c] >= threshold_posts && flags[c] & (LAKE | SEA) == 0 {
            flags[c] |= RIVER_CENTRE;
            centres += 1;
        }
    }
    // Base level: the lake or sea each river ultimately drains into first.
    let mut base = vec![f32::NEG_INFINITY; n];
    for &c in &flood.order {
        let c = c as usize;
        let r = flood.receiver[c];
        if r == NO_RECEIVER {
            continue;
        }
        let r = r as usize;
        base[c] = if flags[r] & (LAKE | SEA) != 0 {
            h[r]
        } else {
            base[r]
        };
    }
    // Water surface of every centre post, then a minimum sweep from the sources downstream.
    let mut surface = vec![f32::NAN; n];
    for c in 0..n {
        if flags[c] & RIVER_CENTRE != 0 {
            let a = f64::from(acc[c]) * post_km2;
            let s = (f64::from(h[c]) - river_depth_m(a)) as f32;
            surface[c] = s.max(base[c]);
        }
    }
    never_rise_downstream(&mut surface, flood, flags);
    // Paint the channels: water within half the width, banks cut back beyond.
    let nx = dims.nx as i64;
    let ny = dims.ny as i64;
    for c in 0..n {
        if flags[c] & RIVER_CENTRE == 0 {
            continue;
        }
        let a = f64::from(acc[c]) * post_km2;
        let half_m = 0.5 * river_width_m(a);
        let bank_m = spacing_m.max(25.0);
        let reach = ((half_m + bank_m) / spacing_m).floor() as i64;
        let s = surface[c];
        let cx = (c % dims.nx) as i64;
        let cy = (c / dims.nx) as i64;
        for dy in -reach..=reach {
            let y = cy + dy;
            if y < 0 || y >= ny {
                continue;
            }
            for dx in -reach..=reach {
                let x = cx + dx;
                if x < 0 || x >= nx {
                    continue;
                }
                let p = (y * nx + x) as usize;
                if flags[p] & (LAKE | SEA) != 0 {
                    continue;
                }
                let d = spacing_m * ((dx * dx + dy * dy) as f64).sqrt();
                if p == c || d <= half_m {
                    h[p] = h[p].min(s);
                    flags[p] |= RIVER;
                } else if d <= half_m + bank_m && flags[p] & (RIVER | SHORE) == 0 {
                    let bank = (f64::from(s) + 0.5 * (d - half_m)) as f32;
                    h[p] = h[p].min(bank);
                }
            }
        }
    }
    // Keep the centre line non-increasing after the painting.
    never_rise_downstream(h, flood, flags);
    let water = flags.iter().filter(|&&f| f & RIVER != 0).count();
    (centres, water)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight valley along the middle row of a 10 m grid whose catchment grows from the
    /// threshold at the head to 3000 km^2 at the outlet: the painted river widens downstream and
    /// its centre line never climbs.
    #[test]
    fn painted_river_widens_with_catchment_and_descends() {
        let (nx, ny) = (200usize, 41usize);
        let dims = Dims { nx, ny };
        let spacing = 10.0;
        let mid = ny / 2;
        let mut h = vec![0.0f32; nx * ny];
        for y in 0..ny {
            for x in 0..nx {
                h[y * nx + x] =
                    (100.0 + 0.05 * x as f64 + 2.0 * (y as f64 - mid as f64).abs()) as f32;
            }
        }
        let outlets: Vec<u32> = (0..dims.len())
            .filter(|&i| dims.is_edge(i))
            .map(|i| i as u32)
            .collect();
        let flood = priority_flood(&h, dims, &outlets, spacing, spacing, None, 8);
        let post_km2 = spacing * spacing * 1e-6;
        let mut acc = vec![1u32; nx * ny];
        for x in 1..nx - 1 {
            let f = (nx - 1 - x) as f64 / (nx - 2) as f64;
            let km2 = 3.0 + 3000.0 * f * f;
            acc[mid * nx + x] = (km2 / post_km2).ceil() as u32;
        }
        let mut flags = vec![0u16; nx * ny];
        let mut carved = flood.filled.clone();
        carve_rivers(&mut carved, &mut flags, dims, spacing, &flood, &acc);
        let water_in_column =
            |x: usize| (0..ny).filter(|&y| flags[y * nx + x] & RIVER != 0).count();
        let head = water_in_column(nx - 10);
        let foot = water_in_column(10);
        assert_eq!(head, 1, "a small river is one post wide");
        assert!(foot >= 9, "a 3000 km^2 river is only {foot} posts wide");
        for x in 2..nx - 1 {
            let c = mid * nx + x;
            assert!(flags[c] & RIVER_CENTRE != 0);
            assert!(carved[c] < flood.filled[c], "not incised at {x}");
            assert!(carved[c - 1] <= carved[c], "climbs at {x}");
        }
    }
}
