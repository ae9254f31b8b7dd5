//! Surface material (soil) classification of every post.
//!
//! # Algorithm
//!
//! A rule cascade on the final heights, in priority order:
//!
//! 1. **Water**: lakes, rivers and sea from the hydrology; **paved / dirt road** from the roads.
//! 2. **Snow** above a snowline that falls with latitude (4800 m up to 20 deg, then 80 m per degree,
//!    at least 200 m; a 36 deg N site gets about 3500 m, so a coastal range gets none), jittered
//!    by +-150 m of noise, on slopes under 40 deg.
//! 3. **Rock** on slopes over about 35 deg (jittered 32-38 deg by noise) and on sharp crests
//!    (more than 25 m above the mean within 300 m, slope over 22 deg).
//! 4. **Sand** on gentle slopes (< 8.5 deg) within about 40 m of a lake, the sea or a river with a
//!    catchment over 30 km^2: beaches and bars.
//! 5. **Dry clay** in dry, flat, low basins: filled depressions that are not lakes, or slopes under
//!    3 deg at least 6 m below the mean within 300 m where a dryness noise is high (playas, dry
//!    valley floors).
//! 6. **Forest** where a patch noise (fBm, 1.2 km) plus a preference for north-facing slopes
//!    (poleward-facing in the southern hemisphere: the oak-woodland/grassland contrast of
//!    California's coast ranges) and for moderate slopes passes a threshold, below a tree line
//!    600 m under the snowline.
//! 7. **Grass** everywhere else.
//!
//! Slopes are central differences in metres; the 300 m mean uses a summed-area table, so its
//! footprint is the same in metres at every spacing.
//!
//! # Limits
//!
//! No climate, soil or land-use model: the classes are plausible, not mapped.

use crate::flood::Dims;
use crate::hydro::{DIRT, FLAT, LAKE, PAVED, RIVER, SEA, WATER};
use crate::noise::Layer;
use cig_terrain::material::Material;
use rand::RngCore;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Snowline in metres at a latitude.
pub(crate) fn snowline_m(lat_deg: f64) -> f64 {
    let a = lat_deg.abs();
    if a <= 20.0 {
        4_800.0
    } else {
        (4_800.0 - 80.0 * (a - 20.0)).max(200.0)
    }
}

/// Inputs of the classification.
pub(crate) struct Inputs<'a> {
    pub h: &'a [f32],
    pub flags: &'a [u16],
    pub acc: &'a [u32],
    pub dims: Dims,
    pub spacing_m: f64,
    pub centre_lat_deg: f64,
}

/// Classifies every post.
pub(crate) fn classify(
    inp: &Inputs<'_>,
    rng: &mut ChaCha8Rng,
    progress: &mut dyn FnMut(&str, f32),
) -> Vec<Material> {
    progress("materials", 0.0);
    let dims = inp.dims;
    let nx = dims.nx;
    let ny = dims.ny;
    let s = inp.spacing_m;
    let patch = Layer::new(rng.next_u64(), 1_200.0);
    let jitter = Layer::new(rng.next_u64(), 700.0);
    let dryness = Layer::new(rng.next_u64(), 6_000.0);
    let snow_noise = Layer::new(rng.next_u64(), 2_500.0);

    // Summed-area table of heights (f64, serial: exact and order-fixed).
    let mut sat = vec![0.0f64; (nx + 1) * (ny + 1)];
    for r in 0..ny {
        let mut row_sum = 0.0;
        for c in 0..nx {
            row_sum += f64::from(inp.h[r * nx + c]);
            sat[(r + 1) * (nx + 1) + c + 1] = sat[r * (nx + 1) + c + 1] + row_sum;
        }
    }
    let mean_r = ((300.0 / s).round() as usize).max(1);

    // Posts near big water (lakes, sea, rivers over 30 km^2).
    let post_km2 = s * s * 1e-6;
    let big_river_posts = (30.0 / post_km2).ceil() as u32;
    let near_r = ((40.0 / s).round() as i64).max(1);
    let mut near_water = vec![false; dims.len()];
    for c in 0..dims.len() {
        let f = inp.flags[c];
        let big = f & (LAKE | SEA) != 0 || (f & RIVER != 0 && inp.acc[c] >= big_river_posts);
        if !big {
            continue;
        }
        let (cx, cy) = ((c % nx) as i64, (c / nx) as i64);
        for dy in -near_r..=near_r {
            for dx in -near_r..=near_r {
                let (x, y) = (cx + dx, cy + dy);
                if x >= 0 && y >= 0 && x < nx as i64 && y < ny as i64 {
                    near_water[y as usize * nx + x as usize] = true;
                }
            }
        }
    }
    progress("materials", 0.3);

    let snowline = snowline_m(inp.centre_lat_deg);
    let treeline = snowline - 600.0;
    let southern = inp.centre_lat_deg < 0.0;
    let tan = |deg: f64| libm::tan(deg.to_radians());
    let tan_snow_max = tan(40.0);
    let tan_rock = tan(35.0);
    let tan_rock_jitter = tan(38.0) - tan_rock;
    let tan_crest = tan(22.0);
    let tan_sand = tan(8.5);
    let tan_clay = tan(3.0);

    let mut out = vec![Material::Grass; dims.len()];
    out.par_chunks_mut(nx).enumerate().for_each(|(r, row)| {
        let y = r as f64 * s;
        let rd = r.saturating_sub(1);
        let ru = (r + 1).min(ny - 1);
        let r0 = r.saturating_sub(mean_r);
        let r1 = (r + mean_r).min(ny - 1);
        for (c, m) in row.iter_mut().enumerate() {
            let i = r * nx + c;
            let f = inp.flags[i];
            if f & WATER != 0 {
                *m = Material::Water;
                continue;
            }
            if f & PAVED != 0 {
                *m = Material::PavedRoad;
                continue;
            }
            if f & DIRT != 0 {
                *m = Material::DirtRoad;
                continue;
            }
            let x = c as f64 * s;
            let h = f64::from(inp.h[i]);
            let cl = c.saturating_sub(1);
            let cr = (c + 1).min(nx - 1);
            let gx = if cr > cl {
                (f64::from(inp.h[r * nx + cr]) - f64::from(inp.h[r * nx + cl]))
                    / ((cr - cl) as f64 * s)
            } else {
                0.0
            };
            let gy = if ru > rd {
                (f64::from(inp.h[ru * nx + c]) - f64::from(inp.h[rd * nx + c]))
                    / ((ru - rd) as f64 * s)
            } else {
                0.0
            };
            let slope = (gx * gx + gy * gy).sqrt();
            let c0 = c.saturating_sub(mean_r);
            let c1 = (c + mean_r).min(nx - 1);
            let sum = sat[(r1 + 1) * (nx + 1) + c1 + 1]
                - sat[r0 * (nx + 1) + c1 + 1]
                - sat[(r1 + 1) * (nx + 1) + c0]
                + sat[r0 * (nx + 1) + c0];
            let mean = sum / ((r1 - r0 + 1) * (c1 - c0 + 1)) as f64;
            let rel = h - mean;

            if h > snowline - 150.0
                && slope < tan_snow_max
                && h > snowline + 150.0 * snow_noise.fbm(x, y, 3, 2.0, 0.5, s)
            {
                *m = Material::Snow;
                continue;
            }
            let rocky = rel > 25.0 && slope > tan_crest
                || slope > tan_rock + tan_rock_jitter
                || (slope > tan_rock - tan_rock_jitter
                    && slope > tan_rock + tan_rock_jitter * jitter.fbm(x, y, 2, 2.0, 0.5, s));
            if rocky {
                *m = Material::Rock;
                continue;
            }
            if near_water[i] && slope < tan_sand {
                *m = Material::Sand;
                continue;
            }
            if slope < tan_clay {
                let dry = dryness.fbm(x, y, 2, 2.0, 0.5, s);
                if f & FLAT != 0 || (rel < -6.0 && dry > 0.1) {
                    *m = Material::DryClay;
                    continue;
                }
            }
            // Forest: patches, favouring poleward-facing moderate slopes, below the tree line.
            let poleward = if slope > 1e-6 {
                let facing_north = -gy / slope; // +1 where the ground falls to the north
                if southern {
                    -facing_north
                } else {
                    facing_north
                }
            } else {
                0.0
            };
            let steepness = (slope / 0.35).min(1.0);
            let mut score =
                patch.fbm(x, y, 3, 2.0, 0.5, s) + 0.45 * poleward * steepness + 0.25 * steepness
                    - 0.25;
            if slope < 0.05 {
                score -= 0.3;
            }
            if h > treeline {
                score -= (h - treeline) / 200.0;
            }
            *m = if score > 0.0 {
                Material::Forest
            } else {
                Material::Grass
            };
        }
    });
    progress("materials", 1.0);
    out
}
