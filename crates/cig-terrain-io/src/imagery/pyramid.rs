//! The imagery pyramid builder: bottom-up, one band of tile rows at a time (south to north),
//! each level's band built as soon as the two finer bands under it are done, so only two tile
//! rows of half-size texels per level stay in memory.
//!
//! A level-`k` tile is the alpha-weighted 2x2 box downsample of its level-`k-1` children where
//! they exist, over the images whose native level is at least `k`, sampled bilinearly at the
//! tile's texel centres (finer images over coarser ones), with the overlay layers whose native
//! level is at most `k` painted on top. A tile exists where a child exists, or an image or
//! overlay of native level `k` touches it, and is written only when some texel is not fully
//! transparent: the pyramid is sparse.

use std::collections::{BTreeSet, HashMap};

use cig_terrain::raster::GeoGrid;
use cig_terrain::{ImageryKey, ImageryLayout, ImageryTile};
use rayon::prelude::*;

use super::reader::{alpha_weighted_bilinear, ImageSource, Window};
use super::ImageryError;

/// A layer painted over the imagery of each tile at the levels at and above its native level
/// (roads, rivers and lake shores as shapes; another crate provides them).
pub trait OverlayLayer: Send + Sync {
    /// The finest imagery level the layer paints at, in `layout`.
    fn native_level(&self, layout: &ImageryLayout) -> u8;
    /// Whether the layer paints anything inside `bounds_deg` (south, west, north, east).
    fn touches(&self, bounds_deg: (f64, f64, f64, f64)) -> bool;
    /// Paints the tile `key`'s texels: `rgba` is `tile_texels^2` sRGB RGBA bytes, rows from
    /// the south, straight alpha (a feature's coverage of a texel is its alpha).
    fn paint(&self, layout: &ImageryLayout, key: ImageryKey, rgba: &mut [u8]);
    /// One line for the manifest's sources.
    fn describe(&self) -> String {
        "overlay".to_string()
    }
    /// The level-0 texel size the layer would like, metres, when it is to decide the
    /// pyramid's finest level (with or without images: the finer wins).
    fn finest_texel_m(&self) -> Option<f64> {
        None
    }
}

/// Roads, rivers and lake shores (`cig_terrain::features`) painted over the imagery.
impl OverlayLayer for cig_terrain::features::FeatureLayer {
    fn native_level(&self, layout: &ImageryLayout) -> u8 {
        cig_terrain::features::FeatureLayer::native_level(self, layout)
    }
    fn touches(&self, bounds_deg: (f64, f64, f64, f64)) -> bool {
        cig_terrain::features::FeatureLayer::touches(self, bounds_deg)
    }
    fn paint(&self, layout: &ImageryLayout, key: ImageryKey, rgba: &mut [u8]) {
        cig_terrain::features::FeatureLayer::paint(self, layout, key, rgba);
    }
    fn describe(&self) -> String {
        "features (roads, rivers, lake shores)".to_string()
    }
    fn finest_texel_m(&self) -> Option<f64> {
        (!self.is_empty()).then(|| cig_terrain::features::FeatureLayer::finest_texel_m(self))
    }
}

/// What a pyramid build made.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PyramidSummary {
    /// Tiles written, all levels.
    pub tiles: u64,
    /// Tiles written per level, finest first.
    pub tiles_per_level: Vec<u64>,
}

/// The pyramid over a database's grid (`spacing_m`: finest post spacing, north-south and
/// east-west) whose level-0 texels are no larger than the finest image's pixels (or an
/// overlay's wish, [`OverlayLayer::finest_texel_m`], when finer).
pub fn imagery_layout(
    grid: &GeoGrid,
    spacing_m: [f64; 2],
    images: &[ImageSource],
    overlays: &[&dyn OverlayLayer],
) -> ImageryLayout {
    let shift_for = |(north_m, east_m): (f64, f64)| {
        ImageryLayout::fine_shift_for(spacing_m[0], north_m)
            .max(ImageryLayout::fine_shift_for(spacing_m[1], east_m))
    };
    let shift = images
        .iter()
        .map(|image| shift_for(image.pixel_m()))
        .chain(
            overlays
                .iter()
                .filter_map(|o| o.finest_texel_m())
                .map(|m| shift_for((m, m))),
        )
        .max()
        .unwrap_or(0);
    ImageryLayout::new(grid, shift)
}

/// The coarsest level whose texels are no larger than `pixel_m` (north-south, east-west),
/// with a hundredth of slack; 0 when even level 0 is coarser.
pub fn native_level(layout: &ImageryLayout, spacing_m: [f64; 2], pixel_m: (f64, f64)) -> u8 {
    let scale = f64::from(1u32 << layout.fine_shift);
    let (texel_n, texel_e) = (spacing_m[0] / scale, spacing_m[1] / scale);
    let mut level = 0u8;
    while level + 1 < layout.levels {
        let s = f64::from(1u32 << (level + 1));
        if texel_n * s <= pixel_m.0 * 1.01 && texel_e * s <= pixel_m.1 * 1.01 {
            level += 1;
        } else {
            break;
        }
    }
    level
}

/// Builds the pyramid of `images` (and `overlays`) over `layout`, handing each finished tile
/// to `emit` (any level order; each key once). `progress(bands_done, bands_total)`.
pub fn build_pyramid(
    layout: &ImageryLayout,
    spacing_m: [f64; 2],
    images: &[ImageSource],
    overlays: &[&dyn OverlayLayer],
    emit: &mut dyn FnMut(ImageryTile) -> Result<(), ImageryError>,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<PyramidSummary, ImageryError> {
    let mut sources: Vec<(&ImageSource, u8)> = images
        .iter()
        .map(|image| (image, native_level(layout, spacing_m, image.pixel_m())))
        .collect();
    // Coarse first, so finer images are painted over them.
    sources.sort_by(|a, b| {
        let area = |s: &ImageSource| s.pixel_m().0 * s.pixel_m().1;
        area(b.0).total_cmp(&area(a.0))
    });
    let total = (0..layout.levels)
        .map(|k| u64::from(layout.tiles_at(k).0))
        .sum();
    let mut builder = Builder {
        layout: *layout,
        sources,
        overlays,
        pending: (0..layout.levels).map(|_| HashMap::new()).collect(),
        emit,
        progress,
        done: 0,
        total,
        summary: PyramidSummary {
            tiles: 0,
            tiles_per_level: vec![0; usize::from(layout.levels)],
        },
    };
    let (rows0, _) = layout.tiles_at(0);
    for r in 0..rows0 {
        builder.band(0, r)?;
    }
    for (image, _) in &builder.sources {
        image.release();
    }
    Ok(builder.summary)
}

/// Half-size texels of a finished tile, waiting for its parent.
type Half = Vec<u8>;

struct Builder<'a, 'e> {
    layout: ImageryLayout,
    sources: Vec<(&'a ImageSource, u8)>,
    overlays: &'a [&'a dyn OverlayLayer],
    /// Per level, the halves of its finished tiles by (row, col).
    pending: Vec<HashMap<(u32, u32), Half>>,
    emit: &'e mut dyn FnMut(ImageryTile) -> Result<(), ImageryError>,
    progress: &'e mut dyn FnMut(u64, u64),
    done: u64,
    total: u64,
    summary: PyramidSummary,
}

fn intersects(a: (f64, f64, f64, f64), b: (f64, f64, f64, f64)) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

impl Builder<'_, '_> {
    /// Builds band `r` of level `k`, then the coarser band above it when this was its last.
    fn band(&mut self, k: u8, r: u32) -> Result<(), ImageryError> {
        self.build_band(k, r)?;
        self.done += 1;
        (self.progress)(self.done, self.total);
        let (rows, _) = self.layout.tiles_at(k);
        if k + 1 < self.layout.levels && (r % 2 == 1 || r + 1 == rows) {
            self.band(k + 1, r / 2)?;
        }
        Ok(())
    }

    fn build_band(&mut self, k: u8, r: u32) -> Result<(), ImageryError> {
        let layout = self.layout;
        let (_, tile_cols) = layout.tiles_at(k);
        let t = f64::from(layout.tile_texels);
        let (tlat, tlon) = layout.texel_deg(k);
        let (tile_lat, tile_lon) = (t * tlat, t * tlon);
        let k_us = usize::from(k);

        let mut cols = BTreeSet::new();
        if k > 0 {
            for &(row, col) in self.pending[k_us - 1].keys() {
                if row / 2 == r {
                    cols.insert(col / 2);
                }
            }
        }
        let south = layout.south_lat_deg + f64::from(r) * tile_lat;
        let north = south + tile_lat;
        let col_range = |west: f64, east: f64| -> Option<(u32, u32)> {
            let lo = ((west - layout.west_lon_deg) / tile_lon).floor();
            let hi = ((east - layout.west_lon_deg) / tile_lon).ceil() - 1.0;
            let last = f64::from(tile_cols) - 1.0;
            if !(lo.is_finite() && hi.is_finite()) || hi < 0.0 || lo > last || hi < lo {
                return None;
            }
            Some((lo.max(0.0) as u32, hi.min(last) as u32))
        };
        for &(image, native) in &self.sources {
            let f = image.footprint_deg();
            if native == k && f.0 < north && south < f.2 {
                if let Some((lo, hi)) = col_range(f.1, f.3) {
                    cols.extend(lo..=hi);
                }
            }
        }
        for overlay in self.overlays {
            if overlay.native_level(&layout).min(layout.levels - 1) == k {
                for c in 0..tile_cols {
                    let key = ImageryKey {
                        level: k,
                        row: r,
                        col: c,
                    };
                    if overlay.touches(layout.tile_bounds_deg(key)) {
                        cols.insert(c);
                    }
                }
            }
        }
        if cols.is_empty() {
            return Ok(());
        }
        let (Some(&first), Some(&last)) = (cols.first(), cols.last()) else {
            return Ok(());
        };
        let band_bounds = (
            south,
            layout.west_lon_deg + f64::from(first) * tile_lon,
            north,
            layout.west_lon_deg + f64::from(last + 1) * tile_lon,
        );
        // Each contributing image's rows under the band.
        let mut windows: Vec<Option<Window>> = Vec::with_capacity(self.sources.len());
        for &(image, native) in &self.sources {
            let f = image.footprint_deg();
            if native < k || !intersects(f, band_bounds) {
                windows.push(None);
                continue;
            }
            let clip = (
                band_bounds.0.max(f.0),
                band_bounds.1.max(f.1),
                band_bounds.2.min(f.2),
                band_bounds.3.min(f.3),
            );
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            const STEPS: usize = 32;
            for s in 0..=STEPS {
                let u = s as f64 / STEPS as f64;
                let lat = clip.0 + u * (clip.2 - clip.0);
                let lon = clip.1 + u * (clip.3 - clip.1);
                for (la, lo_) in [(clip.0, lon), (clip.2, lon), (lat, clip.1), (lat, clip.3)] {
                    let (_, row) = image.pixel_of(la, lo_);
                    lo = lo.min(row);
                    hi = hi.max(row);
                }
            }
            let (_, height) = image.size();
            let max_row = f64::from(height - 1);
            let lo = (lo.floor() - 2.0).clamp(0.0, max_row) as u32;
            let hi = (hi.ceil() + 2.0).clamp(0.0, max_row) as u32;
            windows.push(Some(image.window(lo, hi)?));
        }

        let children = if k > 0 {
            Some(&self.pending[k_us - 1])
        } else {
            None
        };
        let keep_half = k + 1 < layout.levels;
        let sources = &self.sources;
        let overlays = self.overlays;
        let cols: Vec<u32> = cols.into_iter().collect();
        let made: Vec<(u32, ImageryTile, Option<Half>)> = cols
            .par_iter()
            .filter_map(|&c| {
                let key = ImageryKey {
                    level: k,
                    row: r,
                    col: c,
                };
                render_tile(&layout, key, sources, &windows, children, overlays).map(|rgba| {
                    let half = keep_half.then(|| downsample(&rgba, layout.tile_texels as usize));
                    (
                        c,
                        ImageryTile::from_rgba(key, layout.tile_texels, &rgba),
                        half,
                    )
                })
            })
            .collect();
        drop(windows);
        if k > 0 {
            self.pending[k_us - 1].retain(|&(row, _), _| row / 2 != r);
        }
        for (c, tile, half) in made {
            (self.emit)(tile)?;
            self.summary.tiles += 1;
            self.summary.tiles_per_level[k_us] += 1;
            if let Some(half) = half {
                self.pending[k_us].insert((r, c), half);
            }
        }
        Ok(())
    }
}

/// The texels of one tile, or `None` when every texel is transparent.
fn render_tile(
    layout: &ImageryLayout,
    key: ImageryKey,
    sources: &[(&ImageSource, u8)],
    windows: &[Option<Window>],
    children: Option<&HashMap<(u32, u32), Half>>,
    overlays: &[&dyn OverlayLayer],
) -> Option<Vec<u8>> {
    let n = layout.tile_texels as usize;
    let bounds = layout.tile_bounds_deg(key);
    let mut acc = vec![[0.0f32; 4]; n * n];
    let mut any = false;
    for ((image, _), window) in sources.iter().zip(windows) {
        let Some(window) = window else { continue };
        if !intersects(image.footprint_deg(), bounds) {
            continue;
        }
        any |= sample_image(layout, key, image, window, &mut acc);
    }
    if let Some(children) = children {
        let h = n / 2;
        for dr in 0..2u32 {
            for dc in 0..2u32 {
                let Some(half) = children.get(&(2 * key.row + dr, 2 * key.col + dc)) else {
                    continue;
                };
                any = true;
                for i in 0..h {
                    for j in 0..h {
                        let p = &half[(i * h + j) * 4..(i * h + j) * 4 + 4];
                        let src = [
                            f32::from(p[0]),
                            f32::from(p[1]),
                            f32::from(p[2]),
                            f32::from(p[3]) / 255.0,
                        ];
                        let at = (dr as usize * h + i) * n + dc as usize * h + j;
                        over(&mut acc[at], src);
                    }
                }
            }
        }
    }
    let mut rgba = vec![0u8; n * n * 4];
    for (px, a) in rgba.chunks_exact_mut(4).zip(&acc) {
        if a[3] > 0.0 {
            px[0] = a[0].round().clamp(0.0, 255.0) as u8;
            px[1] = a[1].round().clamp(0.0, 255.0) as u8;
            px[2] = a[2].round().clamp(0.0, 255.0) as u8;
            px[3] = (a[3] * 255.0).round().clamp(0.0, 255.0) as u8;
        }
    }
    for overlay in overlays {
        if overlay.native_level(layout) <= key.level && overlay.touches(bounds) {
            overlay.paint(layout, key, &mut rgba);
            any = true;
        }
    }
    if !any || rgba.chunks_exact(4).all(|p| p[3] == 0) {
        return None;
    }
    Some(rgba)
}

/// `src` (straight colour 0-255, alpha 0-1) over `dst`.
#[inline]
fn over(dst: &mut [f32; 4], src: [f32; 4]) {
    let (sa, da) = (src[3], dst[3]);
    if sa <= 0.0 {
        return;
    }
    if sa >= 1.0 || da <= 0.0 {
        *dst = src;
        return;
    }
    let oa = sa + da * (1.0 - sa);
    let wd = da * (1.0 - sa);
    for c in 0..3 {
        dst[c] = (src[c] * sa + dst[c] * wd) / oa;
    }
    dst[3] = oa;
}

/// Samples one image at the tile's texel centres into `acc`; true when any texel got colour.
fn sample_image(
    layout: &ImageryLayout,
    key: ImageryKey,
    image: &ImageSource,
    window: &Window,
    acc: &mut [[f32; 4]],
) -> bool {
    let n = layout.tile_texels as usize;
    let (tlat, tlon) = layout.texel_deg(key.level);
    let row0 = u64::from(key.row) * n as u64;
    let col0 = u64::from(key.col) * n as u64;
    let centre =
        |i: usize, j: usize| layout.texel_centre_deg(key.level, row0 + i as u64, col0 + j as u64);
    let mut any = false;
    if image.is_geographic() {
        // Pixel coordinates are linear in latitude and longitude: the columns' taps once per
        // tile, each row's two image rows once per texel row.
        let (lat0, lon0) = centre(0, 0);
        let (c00, r00) = image.pixel_of(lat0, lon0);
        let (c01, _) = image.pixel_of(lat0, lon0 + tlon);
        let (_, r10) = image.pixel_of(lat0 + tlat, lon0);
        let (dc, dr) = (c01 - c00, r10 - r00);
        let (w, h) = window.image_size();
        let taps = |f: f64, size: u32| -> Option<(usize, usize, f32)> {
            let last = f64::from(size) - 1.0;
            if !(f >= -0.5 && f <= last + 0.5) {
                return None;
            }
            let f = f.clamp(0.0, last);
            let i0 = (f.floor() as u32).min(size.saturating_sub(2));
            let i1 = (i0 + 1).min(size - 1);
            Some((
                i0 as usize,
                i1 as usize,
                (f - f64::from(i0)).clamp(0.0, 1.0) as f32,
            ))
        };
        let columns: Vec<Option<(usize, usize, f32)>> =
            (0..n).map(|j| taps(c00 + j as f64 * dc, w)).collect();
        for i in 0..n {
            let Some((r0, r1, fy)) = taps(r00 + i as f64 * dr, h) else {
                continue;
            };
            let (Some(row0), Some(row1)) = (window.row(r0 as u32), window.row(r1 as u32)) else {
                continue;
            };
            for (j, column) in columns.iter().enumerate() {
                let Some((c0, c1, fx)) = *column else {
                    continue;
                };
                let s = alpha_weighted_bilinear(
                    [
                        &row0[c0 * 4..c0 * 4 + 4],
                        &row0[c1 * 4..c1 * 4 + 4],
                        &row1[c0 * 4..c0 * 4 + 4],
                        &row1[c1 * 4..c1 * 4 + 4],
                    ],
                    fx,
                    fy,
                );
                if s[3] > 0.0 {
                    over(&mut acc[i * n + j], s);
                    any = true;
                }
            }
        }
    } else {
        // Projected exactly every STEP texels, interpolated between.
        const STEP: usize = 16;
        let nodes = n / STEP + 1;
        let mut grid = vec![(0.0f64, 0.0f64); nodes * nodes];
        for a in 0..nodes {
            for b in 0..nodes {
                let (lat, lon) = layout.texel_centre_deg(
                    key.level,
                    row0 + (a * STEP) as u64,
                    col0 + (b * STEP) as u64,
                );
                grid[a * nodes + b] = image.pixel_of(lat, lon);
            }
        }
        for i in 0..n {
            let (a, fi) = ((i / STEP).min(nodes - 2), (i % STEP) as f64 / STEP as f64);
            for j in 0..n {
                let (b, fj) = ((j / STEP).min(nodes - 2), (j % STEP) as f64 / STEP as f64);
                let p00 = grid[a * nodes + b];
                let p01 = grid[a * nodes + b + 1];
                let p10 = grid[(a + 1) * nodes + b];
                let p11 = grid[(a + 1) * nodes + b + 1];
                let lerp = |x: f64, y: f64, t: f64| x + (y - x) * t;
                let col = lerp(lerp(p00.0, p01.0, fj), lerp(p10.0, p11.0, fj), fi);
                let row = lerp(lerp(p00.1, p01.1, fj), lerp(p10.1, p11.1, fj), fi);
                let s = window.sample(col, row);
                if s[3] > 0.0 {
                    over(&mut acc[i * n + j], s);
                    any = true;
                }
            }
        }
    }
    any
}

/// Alpha-weighted 2x2 box downsample of `n` x `n` RGBA texels.
fn downsample(rgba: &[u8], n: usize) -> Half {
    let h = n / 2;
    let mut out = vec![0u8; h * h * 4];
    for i in 0..h {
        for j in 0..h {
            let mut acc = [0u32; 4];
            for (di, dj) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                let at = ((2 * i + di) * n + 2 * j + dj) * 4;
                let a = u32::from(rgba[at + 3]);
                for c in 0..3 {
                    acc[c] += u32::from(rgba[at + c]) * a;
                }
                acc[3] += a;
            }
            let o = (i * h + j) * 4;
            for c in 0..3 {
                if let Some(v) = (acc[c] + acc[3] / 2).checked_div(acc[3]) {
                    out[o + c] = v.min(255) as u8;
                }
            }
            out[o + 3] = ((acc[3] + 2) / 4).min(255) as u8;
        }
    }
    out
}
