//! The bare-earth height field: a coarse fluvial landform from tectonic uplift and stream-power
//! erosion, resampled with domain warping, dressed with ridged-multifractal detail and cut by
//! smoothed valleys.
//!
//! # Algorithm
//!
//! 1. **Uplift map.** A ridged multifractal (Musgrave, in Ebert et al., *Texturing & Modeling*,
//!    3rd ed., 2003, ch. 16) at a 14 km wavelength, masked by a 45 km fBm and multiplied by a
//!    3 km "rock hardness" fBm, gives a relative uplift rate `U(x)`: linear ranges where it is
//!    high, lowlands where it is low.
//! 2. **Steady-state stream-power landform** on a coarse grid (200 m cells, coarser for areas
//!    over 70 km so the grid stays near 350 x 350). At steady state the detachment-limited
//!    stream-power law `dh/dt = U - K A^m S^n` (Howard 1994; Whipple & Tucker 1999) gives the
//!    channel slope `S = (U / K)^(1/n) A^(-m/n)`; with `n = 1`, `m = 0.45` a node's height is its
//!    receiver's plus `k U A^-0.45 d`. Receivers and drainage areas `A` come from the
//!    Priority-Flood and D8 routing of [`crate::flood`], randomised (random tie-breaks on flats,
//!    which makes invasion-percolation trees, and slopes jittered by +-30 %) so that networks are
//!    dendritic rather than parallel. Solving six times lets the network and the heights agree
//!    (the steady-state iteration of Cordonnier et al. 2016, "Large scale terrain generation from
//!    tectonic uplift and fluvial erosion", *Computer Graphics Forum* 35(2)). Outlets are the
//!    lowest points, within 10 km windows, of a base-level noise along the coarse grid's
//!    boundary, which lies outside the database, so rivers leave through a few gaps.
//! 3. **Resampling.** Each post samples the coarse heights by Catmull-Rom bicubic interpolation
//!    at a domain-warped position (Quilez 2002: fBm warps of 500 m at 9 km and 110 m at 2.5 km,
//!    small enough that the warp never folds), which bends the grid's 45-degree directions. The
//!    warp is smooth, so it is evaluated on a 125 m lattice and interpolated.
//! 4. **Detail.** A ridged multifractal (spectral exponent 1) from 1.6 km down to twice the post
//!    spacing adds spurs, gullies and rock faces. Its amplitude is at most 250 m times the
//!    landform's slope (and 70 m), so that its own slopes rarely exceed the landform's and it
//!    makes few closed pits, and it is cut to 20 % on valley floors.
//! 5. **Valleys.** Every coarse channel with a catchment over 0.12 km^2 is traced from its source
//!    to the next junction, smoothed by Chaikin corner cutting (1974), mapped back through the
//!    warp and cut into the posts: a floor `12 sqrt(A / km^2)` m wide on each side (at most
//!    400 m) at the channel's height, sides at 0.3 blending into the terrain over 160 m. This
//!    removes the saddles that interpolation leaves where a channel crosses a cell diagonally.
//! 6. **Lake basins.** A few bowls, deep enough to close on the local slope, are pressed into
//!    valley floors with catchments over 15 km^2, so that the hydrology finds lakes there
//!    (tectonic basins, landslide dams).
//!
//! With a sea side ([`crate::coast`]), the base level falls by up to 250 m toward the sea, so
//! the outlets and the valleys' mouths lie on the coast, and no basin is pressed in near it.
//!
//! All coordinates are metres from the database's south-west post. The coarse grid, warps,
//! channels and octaves depend on the area size and seed but never on the post spacing, so
//! databases of one area at different spacings show the same landscape.
//!
//! # Limits
//!
//! No hillslope diffusion, sediment transport or meandering is simulated; valley floors are flat
//! by construction, not by deposition. The landform depends on the area size (its boundary sets
//! the outlets), so two adjacent databases do not join seamlessly.

use crate::coast::Coast;
use crate::flood::{accumulate, priority_flood, Dims, NO_RECEIVER};
use crate::noise::{fast_floor, smoothstep, unit_from_hash, Layer};
use rand::RngCore;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Concavity `m / n` of the stream-power law.
const CONCAVITY: f64 = 0.45;
/// Channel slope (m/m) at unit uplift on a 200 m x 200 m catchment.
const SLOPE_AT_REF_AREA: f64 = 0.5;
const REF_AREA_M2: f64 = 40_000.0;
/// Steady-state solves.
const ITERATIONS: usize = 6;
/// Warp amplitudes (metres) and wavelengths for 200 m coarse cells (scaled with the cell).
const WARP1_M: f64 = 500.0;
const WARP1_WAVELENGTH_M: f64 = 9_000.0;
const WARP2_M: f64 = 110.0;
const WARP2_WAVELENGTH_M: f64 = 2_500.0;
/// Smallest catchment of a carved channel, km^2.
const CHANNEL_MIN_AREA_KM2: f64 = 0.12;
/// Slope of the carved valley sides (rise over run).
const VALLEY_SIDE_SLOPE: f64 = 0.3;
/// Width beyond the valley floor over which the carving blends out, metres.
const VALLEY_BLEND_M: f64 = 160.0;
/// Largest amplitude of the ridged detail, metres.
const DETAIL_M: f64 = 70.0;
/// Detail amplitude per unit coarse slope, metres: keeps the detail's own slopes below the
/// landform's, so that it adds spurs and gullies rather than closed pits.
const DETAIL_PER_SLOPE_M: f64 = 250.0;

/// A lake basin: a bowl subtracted from the terrain.
#[derive(Clone, Copy, Debug)]
struct Bowl {
    x_m: f64,
    y_m: f64,
    radius_m: f64,
    depth_m: f64,
}

/// Two fields sampled on a regular lattice, bilinearly interpolated together.
struct Lattice {
    x0_m: f64,
    y0_m: f64,
    inv_cell: f64,
    dims: Dims,
    values: Vec<[f32; 2]>,
}

impl Lattice {
    fn new(x0_m: f64, y0_m: f64, cell_m: f64, dims: Dims, values: Vec<[f32; 2]>) -> Lattice {
        Lattice {
            x0_m,
            y0_m,
            inv_cell: 1.0 / cell_m,
            dims,
            values,
        }
    }

    #[inline]
    fn sample(&self, x_m: f64, y_m: f64) -> (f64, f64) {
        let fx = ((x_m - self.x0_m) * self.inv_cell).clamp(0.0, (self.dims.nx - 1) as f64);
        let fy = ((y_m - self.y0_m) * self.inv_cell).clamp(0.0, (self.dims.ny - 1) as f64);
        let ix = (fast_floor(fx) as usize).min(self.dims.nx - 2);
        let iy = (fast_floor(fy) as usize).min(self.dims.ny - 2);
        let tx = fx - ix as f64;
        let ty = fy - iy as f64;
        let nx = self.dims.nx;
        let i00 = iy * nx + ix;
        let (v00, v01, v10, v11) = (
            self.values[i00],
            self.values[i00 + 1],
            self.values[i00 + nx],
            self.values[i00 + nx + 1],
        );
        let lerp2 = |k: usize| {
            let a = f64::from(v00[k]) + (f64::from(v01[k]) - f64::from(v00[k])) * tx;
            let b = f64::from(v10[k]) + (f64::from(v11[k]) - f64::from(v10[k])) * tx;
            a + (b - a) * ty
        };
        (lerp2(0), lerp2(1))
    }
}

/// The coarse landform and the layers that turn it into post heights.
pub(crate) struct Landform {
    cell_m: f64,
    x0_m: f64,
    y0_m: f64,
    dims: Dims,
    height_m: Vec<f32>,
    /// ln(drainage area / km^2) and slope of the coarse grid.
    area_slope: Lattice,
    /// Warp displacement (x, y), metres.
    warp: Lattice,
    detail: Layer,
    bowls: Vec<Bowl>,
    channels: Vec<Segment>,
}

/// A straight piece of a smoothed channel centre line, in post-space metres.
#[derive(Clone, Copy, Debug)]
struct Segment {
    ax: f64,
    ay: f64,
    bx: f64,
    by: f64,
    /// Channel bed heights at the ends, metres.
    ha: f64,
    hb: f64,
    /// Half-widths of the flat valley floor at the ends, metres.
    floor_a: f64,
    floor_b: f64,
}

/// Draws a layer seed from the generator.
fn layer(rng: &mut ChaCha8Rng, wavelength_m: f64) -> Layer {
    Layer::new(rng.next_u64(), wavelength_m)
}

impl Landform {
    /// Builds the coarse landform for a square area `size_m` on a side, whose posts may reach
    /// `reach_m` (>= `size_m`) east and north of the origin; with a `coast`, its base level
    /// falls toward the sea and no lake basin lies near the shore.
    pub(crate) fn new(
        size_m: f64,
        reach_m: f64,
        rng: &mut ChaCha8Rng,
        coast: Option<&Coast>,
    ) -> Landform {
        let cell_m = (size_m / 350.0).max(200.0);
        let scale = cell_m / 200.0;
        let uplift_ridges = layer(rng, 14_000.0 * scale);
        let uplift_mask = layer(rng, 45_000.0 * scale);
        let base = layer(rng, 60_000.0 * scale);
        let initial = layer(rng, 5_000.0 * scale);
        let erodibility = layer(rng, 3_000.0 * scale);
        let jitter_seed = rng.next_u64();
        let warp_layers = [
            layer(rng, WARP1_WAVELENGTH_M * scale),
            layer(rng, WARP1_WAVELENGTH_M * scale),
            layer(rng, WARP2_WAVELENGTH_M * scale),
            layer(rng, WARP2_WAVELENGTH_M * scale),
        ];
        let detail = layer(rng, (8.0 * cell_m).max(1_600.0));

        let warp1_m = WARP1_M * scale;
        let warp2_m = WARP2_M * scale;
        let margin_m = warp1_m + warp2_m + 3.0 * cell_m;
        let x0_m = -margin_m;
        let y0_m = -margin_m;
        // The coarse grid depends on the area size only (never on the spacing), so that every spacing
        // sees the same landform; posts beyond it (at most half a spacing) clamp to its edge.
        let n_side = ((size_m + 2.0 * margin_m) / cell_m).ceil() as usize + 1;
        let dims = Dims {
            nx: n_side,
            ny: n_side,
        };
        let n = dims.len();
        let coarse_spacing = cell_m;

        let mut uplift = vec![0.0f64; n];
        let mut base_m = vec![0.0f64; n];
        let mut height = vec![0.0f32; n];
        for j in 0..dims.ny {
            for i in 0..dims.nx {
                let c = j * dims.nx + i;
                let x = x0_m + i as f64 * cell_m;
                let y = y0_m + j as f64 * cell_m;
                let r = uplift_ridges.ridged(x, y, 3, 2.0, 1.0, coarse_spacing);
                let mask = uplift_mask.fbm(x, y, 2, 2.0, 0.5, coarse_spacing);
                let ranges = smoothstep(0.15, 0.75, r);
                let m = smoothstep(-0.55, 0.45, mask);
                // Rock strength varies on a 3 km scale: a harder rock needs a steeper channel for
                // the same uplift, which deflects rivers and breaks up parallel drainage.
                let hardness = 1.0 + 0.5 * erodibility.fbm(x, y, 3, 2.0, 0.5, coarse_spacing);
                uplift[c] = (0.22 + 1.0 * ranges * (0.3 + 0.7 * m)) * hardness;
                base_m[c] = 200.0 + 120.0 * base.fbm(x, y, 2, 2.0, 0.5, coarse_spacing);
                if let Some(coast) = coast {
                    base_m[c] -= coast.base_drop_m(x, y);
                }
                // Initial surface: base level, uplift-shaped relief and multi-scale roughness, so
                // that the first routing already wanders.
                height[c] = (base_m[c]
                    + 150.0 * uplift[c]
                    + 60.0 * initial.fbm(x, y, 4, 2.0, 0.6, coarse_spacing))
                    as f32;
            }
        }

        let outlets = choose_outlets(dims, &base_m, (10_000.0 / cell_m).ceil() as usize);
        let mut is_outlet = vec![false; n];
        for &o in &outlets {
            is_outlet[o as usize] = true;
            height[o as usize] = base_m[o as usize] as f32;
        }

        let k = SLOPE_AT_REF_AREA * libm::pow(REF_AREA_M2, CONCAVITY);
        let cell_area = cell_m * cell_m;
        let diag = cell_m * std::f64::consts::SQRT_2;
        let mut acc = vec![1u32; n];
        let mut receiver = vec![NO_RECEIVER; n];
        for _ in 0..ITERATIONS {
            let flood = priority_flood(
                &height,
                dims,
                &outlets,
                cell_m,
                cell_m,
                Some(jitter_seed),
                8,
            );
            acc = accumulate(&flood, n);
            let mut next = height.clone();
            for &c in &flood.order {
                let c = c as usize;
                let r = flood.receiver[c];
                if is_outlet[c] || r == NO_RECEIVER {
                    next[c] = base_m[c] as f32;
                    continue;
                }
                let r = r as usize;
                let d = if r % dims.nx == c % dims.nx || r / dims.nx == c / dims.nx {
                    cell_m
                } else {
                    diag
                };
                let a = f64::from(acc[c]) * cell_area;
                let slope = k * uplift[c] * libm::pow(a, -CONCAVITY);
                next[c] = (f64::from(next[r]) + slope * d) as f32;
            }
            height = next;
            receiver = flood.receiver;
        }
        let mut slope = vec![0.0f32; n];
        for j in 0..dims.ny {
            for i in 0..dims.nx {
                let (il, ir) = (i.saturating_sub(1), (i + 1).min(dims.nx - 1));
                let (jd, ju) = (j.saturating_sub(1), (j + 1).min(dims.ny - 1));
                let hv = |ii: usize, jj: usize| f64::from(height[jj * dims.nx + ii]);
                let gx = (hv(ir, j) - hv(il, j)) / ((ir - il) as f64 * cell_m);
                let gy = (hv(i, ju) - hv(i, jd)) / ((ju - jd) as f64 * cell_m);
                slope[j * dims.nx + i] = (gx * gx + gy * gy).sqrt() as f32;
            }
        }
        let area_slope = Lattice::new(
            x0_m,
            y0_m,
            cell_m,
            dims,
            acc.iter()
                .zip(&slope)
                .map(|(&a, &s)| [libm::log(f64::from(a) * cell_area * 1e-6) as f32, s])
                .collect(),
        );

        // The warp is smooth at the 1 km scale: sample it on a lattice of 0.625 coarse cells
        // (125 m for 200 m cells) and interpolate, which is far cheaper than per post.
        let warp_cell_m = 0.625 * cell_m;
        let warp_x0 = -2.0 * warp_cell_m;
        let warp_side = ((reach_m + 4.0 * warp_cell_m) / warp_cell_m).ceil() as usize + 1;
        let warp_dims = Dims {
            nx: warp_side,
            ny: warp_side,
        };
        let mut warp = vec![[0.0f32; 2]; warp_dims.len()];
        warp.par_chunks_mut(warp_side)
            .enumerate()
            .for_each(|(j, row)| {
                let y = warp_x0 + j as f64 * warp_cell_m;
                for (i, v) in row.iter_mut().enumerate() {
                    let x = warp_x0 + i as f64 * warp_cell_m;
                    let [a, b, c, d] = &warp_layers;
                    *v = [
                        (warp1_m * a.fbm(x, y, 3, 2.0, 0.5, warp_cell_m)
                            + warp2_m * c.fbm(x, y, 2, 2.0, 0.5, warp_cell_m))
                            as f32,
                        (warp1_m * b.fbm(x, y, 3, 2.0, 0.5, warp_cell_m)
                            + warp2_m * d.fbm(x, y, 2, 2.0, 0.5, warp_cell_m))
                            as f32,
                    ];
                }
            });

        let mut landform = Landform {
            cell_m,
            x0_m,
            y0_m,
            dims,
            height_m: height,
            area_slope,
            warp: Lattice::new(warp_x0, warp_x0, warp_cell_m, warp_dims, warp),
            detail,
            bowls: Vec::new(),
            channels: Vec::new(),
        };
        landform.bowls = landform.choose_bowls(size_m, rng, coast);
        landform.channels = landform.trace_channels(&receiver, &acc);
        landform
    }

    /// The position `p` whose warped position `p + w(p)` is `(x_m, y_m)`: three fixed-point
    /// steps, which converge because the warp's gradient is well below 1.
    fn unwarp(&self, x_m: f64, y_m: f64) -> (f64, f64) {
        let (mut px, mut py) = (x_m, y_m);
        for _ in 0..3 {
            let (dx, dy) = self.warp.sample(px, py);
            px = x_m - dx;
            py = y_m - dy;
        }
        (px, py)
    }

    /// Centre lines of the coarse channels (catchment >= [`CHANNEL_MIN_AREA_KM2`]): chains from
    /// each source down to the first junction or outlet, smoothed by two rounds of Chaikin
    /// corner cutting and mapped back through the warp to post space.
    fn trace_channels(&self, receiver: &[u32], acc: &[u32]) -> Vec<Segment> {
        let n = self.dims.len();
        let cell_km2 = self.cell_m * self.cell_m * 1e-6;
        let min_cells = (CHANNEL_MIN_AREA_KM2 / cell_km2).ceil().max(2.0) as u32;
        let is_channel = |c: usize| acc[c] >= min_cells;
        let mut has_donor = vec![false; n];
        for c in 0..n {
            if is_channel(c) && receiver[c] != NO_RECEIVER {
                has_donor[receiver[c] as usize] = true;
            }
        }
        let mut visited = vec![false; n];
        let mut segments = Vec::new();
        let mut chain: Vec<(f64, f64, f64, f64)> = Vec::new();
        for (source, &donor) in has_donor.iter().enumerate() {
            if donor || !is_channel(source) {
                continue;
            }
            chain.clear();
            let mut c = source;
            visited[c] = true;
            loop {
                let x = self.x0_m + (c % self.dims.nx) as f64 * self.cell_m;
                let y = self.y0_m + (c / self.dims.nx) as f64 * self.cell_m;
                let area_km2 = f64::from(acc[c]) * cell_km2;
                chain.push((x, y, f64::from(self.height_m[c]), area_km2));
                let r = receiver[c];
                if r == NO_RECEIVER {
                    break;
                }
                let r = r as usize;
                if visited[r] {
                    let x = self.x0_m + (r % self.dims.nx) as f64 * self.cell_m;
                    let y = self.y0_m + (r / self.dims.nx) as f64 * self.cell_m;
                    let area_km2 = f64::from(acc[r]) * cell_km2;
                    chain.push((x, y, f64::from(self.height_m[r]), area_km2));
                    break;
                }
                visited[r] = true;
                c = r;
            }
            if chain.len() < 2 {
                continue;
            }
            let smooth = chaikin4(&chain);
            let mapped: Vec<(f64, f64, f64, f64)> = smooth
                .iter()
                .map(|&(x, y, h, a)| {
                    let (px, py) = self.unwarp(x, y);
                    (px, py, h, floor_half_width_m(a))
                })
                .collect();
            for w in mapped.windows(2) {
                segments.push(Segment {
                    ax: w[0].0,
                    ay: w[0].1,
                    bx: w[1].0,
                    by: w[1].1,
                    ha: w[0].2,
                    hb: w[1].2,
                    floor_a: w[0].3,
                    floor_b: w[1].3,
                });
            }
        }
        segments
    }

    /// Cuts the smoothed channels into the posts (row-major, `cols` wide, `spacing_m` apart):
    /// a flat floor, then sides at [`VALLEY_SIDE_SLOPE`] blending back into the terrain, so that
    /// every valley drains even where the interpolated surface has a saddle. Then presses in the
    /// lake basins.
    pub(crate) fn carve(&self, h: &mut [f32], cols: usize, spacing_m: f64) {
        let rows = h.len() / cols.max(1);
        if rows == 0 {
            return;
        }
        // Row bands are carved in parallel; each applies its segments in the global order, so
        // the result does not depend on the thread count.
        const BAND_ROWS: usize = 32;
        let bands = rows.div_ceil(BAND_ROWS);
        let mut per_band: Vec<Vec<u32>> = vec![Vec::new(); bands];
        let row_range = |lo: f64, hi: f64| -> Option<(usize, usize)> {
            let r1 = (hi / spacing_m).ceil();
            if r1 < 0.0 {
                return None;
            }
            let r0 = (lo / spacing_m).floor().max(0.0) as usize;
            let r1 = (r1 as usize).min(rows - 1);
            (r0 <= r1).then_some((r0, r1))
        };
        for (i, seg) in self.channels.iter().enumerate() {
            let reach = seg.floor_a.max(seg.floor_b) + VALLEY_BLEND_M;
            if let Some((r0, r1)) =
                row_range(seg.ay.min(seg.by) - reach, seg.ay.max(seg.by) + reach)
            {
                for band in per_band
                    .iter_mut()
                    .take(r1 / BAND_ROWS + 1)
                    .skip(r0 / BAND_ROWS)
                {
                    band.push(i as u32);
                }
            }
        }
        h.par_chunks_mut(BAND_ROWS * cols)
            .enumerate()
            .for_each(|(band, chunk)| {
                let first_row = band * BAND_ROWS;
                for &i in &per_band[band] {
                    self.carve_segment(
                        &self.channels[i as usize],
                        chunk,
                        first_row,
                        cols,
                        spacing_m,
                    );
                }
                for b in &self.bowls {
                    press_bowl(b, chunk, first_row, cols, spacing_m);
                }
            });
    }

    /// Carves one channel segment into the rows of `chunk` (whose first row is `first_row`).
    fn carve_segment(
        &self,
        seg: &Segment,
        chunk: &mut [f32],
        first_row: usize,
        cols: usize,
        spacing_m: f64,
    ) {
        let band_rows = chunk.len() / cols;
        let reach = seg.floor_a.max(seg.floor_b) + VALLEY_BLEND_M;
        let c1 = ((seg.ax.max(seg.bx) + reach) / spacing_m).ceil();
        let r1 = ((seg.ay.max(seg.by) + reach) / spacing_m).ceil();
        if c1 < 0.0 || r1 < 0.0 {
            return;
        }
        let c0 = ((seg.ax.min(seg.bx) - reach) / spacing_m).floor().max(0.0) as usize;
        let r0 = ((seg.ay.min(seg.by) - reach) / spacing_m).floor().max(0.0) as usize;
        let c1 = (c1 as usize).min(cols - 1);
        let r0 = r0.max(first_row);
        let r1 = (r1 as usize).min(first_row + band_rows - 1);
        let (ex, ey) = (seg.bx - seg.ax, seg.by - seg.ay);
        let len2 = ex * ex + ey * ey;
        for r in r0..=r1 {
            let y = r as f64 * spacing_m;
            let row = &mut chunk[(r - first_row) * cols..(r - first_row + 1) * cols];
            for (c, v) in row.iter_mut().enumerate().take(c1 + 1).skip(c0) {
                let x = c as f64 * spacing_m;
                let t = if len2 > 0.0 {
                    (((x - seg.ax) * ex + (y - seg.ay) * ey) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let dx = x - (seg.ax + ex * t);
                let dy = y - (seg.ay + ey * t);
                let d = (dx * dx + dy * dy).sqrt();
                let floor = seg.floor_a + (seg.floor_b - seg.floor_a) * t;
                let outer = floor + VALLEY_BLEND_M;
                if d >= outer {
                    continue;
                }
                // A floor sloping gently (2 %) to the centre line keeps the river in the middle.
                let bed = seg.ha + (seg.hb - seg.ha) * t;
                let target = bed + 0.02 * d.min(floor) + (d - floor).max(0.0) * VALLEY_SIDE_SLOPE;
                let old = f64::from(*v);
                if old > target {
                    let w = 1.0 - smoothstep(floor + 0.4 * VALLEY_BLEND_M, outer, d);
                    *v = (old - w * (old - target)) as f32;
                }
            }
        }
    }

    /// Lake basins on wide, gently sloping valley floors inside the area (and away from the
    /// coast).
    fn choose_bowls(&self, size_m: f64, rng: &mut ChaCha8Rng, coast: Option<&Coast>) -> Vec<Bowl> {
        let area_km2 = size_m * size_m * 1e-6;
        let wanted = ((area_km2 / 600.0).ceil() as usize).min(30);
        let min_ln_area = libm::log(15.0) as f32;
        let mut candidates = Vec::new();
        let nx = self.dims.nx;
        let inset = 0.08 * size_m;
        for j in 0..self.dims.ny {
            for i in 0..nx {
                let c = j * nx + i;
                let x = self.x0_m + i as f64 * self.cell_m;
                let y = self.y0_m + j as f64 * self.cell_m;
                if x < inset || y < inset || x > size_m - inset || y > size_m - inset {
                    continue;
                }
                if coast.is_some_and(|k| !k.allows_lake_basin(x, y)) {
                    continue;
                }
                let [ln_area, slope] = self.area_slope.values[c];
                let slope = f64::from(slope);
                if ln_area >= min_ln_area && slope < 0.08 {
                    candidates.push((x, y, slope));
                }
            }
        }
        let mut bowls: Vec<Bowl> = Vec::new();
        let min_sep_m = 5_000.0f64.min(size_m * 0.3);
        let mut tries = 0;
        while bowls.len() < wanted && !candidates.is_empty() && tries < 200 {
            tries += 1;
            let pick = (rng.next_u64() % candidates.len() as u64) as usize;
            let (x, y, slope) = candidates[pick];
            let u1 = unit_from_hash(rng.next_u64());
            let u2 = unit_from_hash(rng.next_u64());
            if bowls.iter().any(|b| {
                let dx = b.x_m - x;
                let dy = b.y_m - y;
                dx * dx + dy * dy < min_sep_m * min_sep_m
            }) {
                continue;
            }
            // Deep enough that the downstream rim closes the basin on this slope.
            let radius_m = 500.0 + 900.0 * u1;
            let (px, py) = self.unwarp(x, y);
            bowls.push(Bowl {
                x_m: px,
                y_m: py,
                radius_m,
                depth_m: 1.2 * slope * radius_m + 8.0 + 17.0 * u2,
            });
        }
        bowls
    }

    /// Catmull-Rom weights for fraction `t`.
    #[inline]
    fn cubic_weights(t: f64) -> [f64; 4] {
        let t2 = t * t;
        let t3 = t2 * t;
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ]
    }

    /// Bicubic coarse height at a point in metres.
    #[inline]
    fn coarse_height(&self, x_m: f64, y_m: f64) -> f64 {
        let fx = ((x_m - self.x0_m) / self.cell_m).clamp(0.0, (self.dims.nx - 1) as f64);
        let fy = ((y_m - self.y0_m) / self.cell_m).clamp(0.0, (self.dims.ny - 1) as f64);
        let ix = (fast_floor(fx) as usize).min(self.dims.nx - 2);
        let iy = (fast_floor(fy) as usize).min(self.dims.ny - 2);
        let wx = Self::cubic_weights(fx - ix as f64);
        let wy = Self::cubic_weights(fy - iy as f64);
        let nx = self.dims.nx;
        let clamp_x = |i: i64| i.clamp(0, nx as i64 - 1) as usize;
        let clamp_y = |j: i64| j.clamp(0, self.dims.ny as i64 - 1) as usize;
        let mut h = 0.0;
        for (b, wyb) in wy.iter().enumerate() {
            let row = clamp_y(iy as i64 + b as i64 - 1) * nx;
            let mut s = 0.0;
            for (a, wxa) in wx.iter().enumerate() {
                s += wxa * f64::from(self.height_m[row + clamp_x(ix as i64 + a as i64 - 1)]);
            }
            h += wyb * s;
        }
        h
    }

    /// Bare-earth height (metres) of the point `(x_m, y_m)` for posts `spacing_m` apart.
    pub(crate) fn height(&self, x_m: f64, y_m: f64, spacing_m: f64) -> f64 {
        let (dx, dy) = self.warp.sample(x_m, y_m);
        let (wx, wy) = (x_m + dx, y_m + dy);
        let coarse = self.coarse_height(wx, wy);
        let (ln_area, slope) = self.area_slope.sample(wx, wy);
        // Detail: ridged multifractal, scaled with the landform's slope and smoothed on valley
        // floors (large catchments).
        let valley = smoothstep(libm::log(0.2), libm::log(6.0), ln_area);
        let amp = (DETAIL_PER_SLOPE_M * slope).min(DETAIL_M) * (1.0 - 0.8 * valley);
        let mut h = coarse;
        if amp > 0.01 {
            let r = self.detail.ridged(x_m, y_m, 10, 2.0, 1.0, spacing_m);
            h += amp * (r - 0.3);
        }
        h
    }
}

/// Lowers the rows of `chunk` (first row `first_row`) by a lake basin.
fn press_bowl(b: &Bowl, chunk: &mut [f32], first_row: usize, cols: usize, spacing_m: f64) {
    let band_rows = chunk.len() / cols;
    let c1 = ((b.x_m + b.radius_m) / spacing_m).ceil();
    let r1 = ((b.y_m + b.radius_m) / spacing_m).ceil();
    if c1 < 0.0 || r1 < 0.0 {
        return;
    }
    let c0 = ((b.x_m - b.radius_m) / spacing_m).floor().max(0.0) as usize;
    let r0 = (((b.y_m - b.radius_m) / spacing_m).floor().max(0.0) as usize).max(first_row);
    let c1 = (c1 as usize).min(cols - 1);
    let r1 = (r1 as usize).min(first_row + band_rows - 1);
    for r in r0..=r1 {
        let dy = r as f64 * spacing_m - b.y_m;
        for c in c0..=c1 {
            let dx = c as f64 * spacing_m - b.x_m;
            let d2 = (dx * dx + dy * dy) / (b.radius_m * b.radius_m);
            if d2 < 1.0 {
                let t = 1.0 - d2;
                let i = (r - first_row) * cols + c;
                chunk[i] = (f64::from(chunk[i]) - b.depth_m * t * t) as f32;
            }
        }
    }
}

/// Half-width of a valley's flat floor for a catchment in km^2, metres.
fn floor_half_width_m(area_km2: f64) -> f64 {
    (12.0 * area_km2.sqrt()).min(400.0)
}

/// Two rounds of Chaikin corner cutting on (x, y, height, area), keeping the end points.
fn chaikin4(points: &[(f64, f64, f64, f64)]) -> Vec<(f64, f64, f64, f64)> {
    let mix = |a: (f64, f64, f64, f64), b: (f64, f64, f64, f64), t: f64| {
        (
            a.0 + (b.0 - a.0) * t,
            a.1 + (b.1 - a.1) * t,
            a.2 + (b.2 - a.2) * t,
            a.3 + (b.3 - a.3) * t,
        )
    };
    let mut pts = points.to_vec();
    for _ in 0..2 {
        if pts.len() < 3 {
            break;
        }
        let last = pts[pts.len() - 1];
        let mut out = Vec::with_capacity(2 * pts.len());
        out.push(pts[0]);
        for (i, w) in pts.windows(2).enumerate() {
            if i > 0 {
                out.push(mix(w[0], w[1], 0.25));
            }
            if i + 2 < pts.len() {
                out.push(mix(w[0], w[1], 0.75));
            }
        }
        out.push(last);
        pts = out;
    }
    pts
}

/// Boundary nodes whose base level is the lowest within `window` nodes either way along the
/// boundary ring (ties to the lower index); at least one.
fn choose_outlets(dims: Dims, base_m: &[f64], window: usize) -> Vec<u32> {
    let nx = dims.nx;
    let ny = dims.ny;
    // The boundary ring, counter-clockwise from the south-west corner.
    let mut ring: Vec<usize> = Vec::with_capacity(2 * (nx + ny));
    for i in 0..nx {
        ring.push(i);
    }
    for j in 1..ny {
        ring.push(j * nx + nx - 1);
    }
    for i in (0..nx - 1).rev() {
        ring.push((ny - 1) * nx + i);
    }
    for j in (1..ny - 1).rev() {
        ring.push(j * nx);
    }
    let len = ring.len();
    let w = window.min(len / 2);
    let mut outlets = Vec::new();
    for (k, &c) in ring.iter().enumerate() {
        let mut lowest = true;
        for d in 1..=w {
            for o in [ring[(k + d) % len], ring[(k + len - d) % len]] {
                if base_m[o] < base_m[c] || (base_m[o] == base_m[c] && o < c) {
                    lowest = false;
                }
            }
            if !lowest {
                break;
            }
        }
        if lowest {
            outlets.push(c as u32);
        }
    }
    if outlets.is_empty() {
        outlets.push(ring[0] as u32);
    }
    outlets
}
