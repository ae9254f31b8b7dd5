//! The draped imagery on the GPU: a clipmap over the database's imagery pyramid
//! (`cig_terrain::imagery`).
//!
//! Algorithm (Tanner, Migdal and Jones, "The Clipmap: a virtual mipmap", SIGGRAPH 1998, the
//! clip-texture of SGI's image generators): every pyramid level keeps a window of
//! `WINDOW_TILES` x `WINDOW_TILES` tiles around the eye in one layer of a texture array,
//! addressed toroidally (a tile's slot is its row and column modulo the window, and the sampler
//! repeats), so when the eye moves only the tiles entering the window are loaded and written,
//! each into the slot of the one that left. A small page table (one texel per slot and level)
//! says which slots hold the tile the window expects; the terrain shader picks the level whose
//! texels match the pixel's footprint (from the screen derivatives of the imagery coordinate),
//! falls back to the next coarser level where a slot is empty (a tile not loaded yet, or no
//! imagery there), and blends two levels so no level border shows. Tiles are loaded by worker
//! threads and written at most `UPLOADS_PER_FRAME` a frame; one-off frames load every window
//! tile first. BC3 tiles go to the GPU as they are where the device samples BC formats;
//! elsewhere they are decoded to RGBA8 on the loading thread. The clipmap's texels (a byte
//! each in BC3, four in RGBA8) are held from the tile cache's paging budget
//! (`TileCache::reserve`), so one budget covers the terrain's tiles and its imagery.
//!
//! Limits: one clipmap centre per renderer (the first view's eye); another view far from it
//! samples coarser levels. Imagery coordinates are relative to an anchor texel at the eye, so
//! single precision holds texel accuracy over any database the layout allows.

use crate::gpu::Gpu;
use cig_terrain::cache::BudgetReservation;
use cig_terrain::imagery::{ImageryKey, ImageryLayout, ImageryTile, MAX_IMAGERY_LEVELS};
use cig_terrain::{TerrainDatabase, TileCache};
use std::sync::Arc;

/// Tiles along a side of each level's window.
pub const WINDOW_TILES: u32 = 8;
/// Tile uploads per interactive frame (a BC3 tile is 64 KiB).
const UPLOADS_PER_FRAME: usize = 24;
/// Tile loads in flight at most.
const LOADS_IN_FLIGHT: usize = 48;
/// Loading threads.
const LOADERS: usize = 2;
/// A page table entry where no level holds imagery.
const NO_LEVEL: u8 = 255;

/// One level's parameters in the shader (`ImageryLevel` in terrain.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct LevelParams {
    /// xy: the anchor's level texel coordinates modulo the clip size (the toroidal phase);
    /// zw: the window's south-west corner, level texels relative to the anchor.
    phase_lo: [f32; 4],
    /// xy: the window's north-east corner, level texels relative to the anchor; z: the
    /// level's texel size, metres; w: unused.
    hi: [f32; 4],
}

/// The shader's imagery uniform (`Imagery` in terrain.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    /// x: levels (0 without imagery), y: clip size in texels, z: tile texels, w: window tiles.
    info: [f32; 4],
    levels: [LevelParams; MAX_IMAGERY_LEVELS as usize],
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    /// Holds nothing the window wants.
    Empty,
    /// The tile is being loaded.
    Pending(ImageryKey),
    /// The tile is in the slot.
    Loaded(ImageryKey),
    /// The tile does not exist (no imagery there) or failed to load.
    Absent(ImageryKey),
}

struct Level {
    /// The window's south-west tile (row, column); `None` before the first update.
    origin: Option<(u32, u32)>,
    slots: Vec<Slot>,
    /// One byte per slot: the level the shader samples there (see `write_pages`).
    pages: Vec<u8>,
    /// Slots whose texels are all transparent (never written, or cleared).
    blank: Vec<bool>,
    pages_dirty: bool,
}

/// A loaded tile, as the GPU takes it.
struct Loaded {
    key: ImageryKey,
    /// BC3 blocks or RGBA8 texels; `None` where the tile is absent or failed.
    bytes: Option<Vec<u8>>,
}

/// Tiles loading on worker threads.
struct Loader {
    requests: crossbeam_channel::Sender<ImageryKey>,
    results: crossbeam_channel::Receiver<Loaded>,
    in_flight: usize,
}

/// What the clipmap did this frame, for statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClipmapStats {
    pub tiles_uploaded: usize,
    pub tiles_pending: usize,
}

/// The clipmap's GPU resources and window state.
pub struct ImageryClipmap {
    /// The clipmap's share of the paging budget (given back when the clipmap is dropped).
    _reservation: BudgetReservation,
    layout: Option<ImageryLayout>,
    database: Arc<TerrainDatabase>,
    /// Whether the texture holds BC3 blocks (else RGBA8).
    compressed: bool,
    clip_texels: u32,
    texture: wgpu::Texture,
    pages: wgpu::Texture,
    params_buffer: wgpu::Buffer,
    levels: Vec<Level>,
    loader: Option<Loader>,
    /// Level-0 texel size, metres.
    fine_texel_m: f64,
    /// The anchor (level-0 texel row, column) of the view last prepared.
    anchor: (i64, i64),
}

fn decode_for_gpu(tile: ImageryTile, compressed: bool) -> Vec<u8> {
    if compressed {
        tile.blocks
    } else {
        tile.to_rgba()
    }
}

impl ImageryClipmap {
    /// The clipmap of the imagery of `cache`'s database (a 1-texel stand-in when it has none),
    /// its memory held from the cache's paging budget while it lives.
    pub fn new(gpu: &Gpu, cache: &TileCache) -> ImageryClipmap {
        let database = Arc::clone(cache.database());
        let layout = database.manifest().imagery.as_ref().map(|i| i.layout);
        // A CPU device (lavapipe) decodes BC blocks on every sample, at about twice the cost of
        // the whole terrain shading: there the tiles are decoded once on loading instead.
        let compressed = gpu
            .device
            .features()
            .contains(wgpu::Features::TEXTURE_COMPRESSION_BC)
            && gpu.info.device_type != wgpu::DeviceType::Cpu;
        let level_count = layout.map_or(1, |l| u32::from(l.levels));
        let clip_texels = layout.map_or(4, |l| l.tile_texels * WINDOW_TILES);
        let window = if layout.is_some() { WINDOW_TILES } else { 1 };
        let format = if compressed {
            wgpu::TextureFormat::Bc3RgbaUnormSrgb
        } else {
            wgpu::TextureFormat::Rgba8UnormSrgb
        };
        let device = &gpu.device;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("imagery clipmap"),
            size: wgpu::Extent3d {
                width: clip_texels,
                height: clip_texels,
                depth_or_array_layers: level_count,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let pages = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("imagery pages"),
            size: wgpu::Extent3d {
                width: window,
                height: window,
                depth_or_array_layers: level_count,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R8Uint,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let params_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("imagery"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let slots = (window * window) as usize;
        let levels = (0..level_count)
            .map(|_| Level {
                origin: None,
                slots: vec![Slot::Empty; slots],
                pages: vec![NO_LEVEL; slots],
                blank: vec![true; slots],
                pages_dirty: true,
            })
            .collect();
        let fine_texel_m = layout.map_or(1.0, |l| {
            let lat = l.south_lat_deg + 0.5 * l.rows as f64 * l.texel_lat_deg;
            let (north_m, east_m) = cig_geo::metres_per_degree(lat);
            (l.texel_lat_deg * north_m * l.texel_lon_deg * east_m).sqrt()
        });
        let loader = layout.map(|_| Self::start_loader(&database, compressed));
        let texel_bytes = if compressed { 1 } else { 4 };
        let wanted = u64::from(clip_texels).pow(2) * u64::from(level_count) * texel_bytes;
        let reservation = cache.reserve(if layout.is_some() { wanted } else { 0 });
        if reservation.bytes() < wanted && layout.is_some() {
            tracing::warn!(
                "the imagery clipmap takes {} MB, more than the paging budget leaves beside the tiles' minimum ({} MB of it held); raise paging.budget_bytes",
                wanted >> 20,
                reservation.bytes() >> 20
            );
        }
        let mut clipmap = ImageryClipmap {
            _reservation: reservation,
            layout,
            database,
            compressed,
            clip_texels,
            texture,
            pages,
            params_buffer,
            levels,
            loader,
            fine_texel_m,
            anchor: (0, 0),
        };
        clipmap.write_pages(gpu, true);
        clipmap
    }

    fn start_loader(database: &Arc<TerrainDatabase>, compressed: bool) -> Loader {
        let (requests, request_rx) = crossbeam_channel::unbounded::<ImageryKey>();
        let (result_tx, results) = crossbeam_channel::unbounded::<Loaded>();
        for i in 0..LOADERS {
            let request_rx = request_rx.clone();
            let result_tx = result_tx.clone();
            let database = Arc::clone(database);
            let spawned = std::thread::Builder::new()
                .name(format!("imagery loader {i}"))
                .spawn(move || {
                    for key in request_rx {
                        let bytes = load(&database, key).map(|t| decode_for_gpu(t, compressed));
                        if result_tx.send(Loaded { key, bytes }).is_err() {
                            break;
                        }
                    }
                });
            if let Err(e) = spawned {
                tracing::warn!("imagery loader thread not started: {e}");
            }
        }
        Loader {
            requests,
            results,
            in_flight: 0,
        }
    }

    pub fn texture_view(&self) -> wgpu::TextureView {
        self.texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        })
    }

    pub fn pages_view(&self) -> wgpu::TextureView {
        self.pages.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        })
    }

    pub fn params_buffer(&self) -> &wgpu::Buffer {
        &self.params_buffer
    }

    /// Moves the windows to `eye_lat_deg, eye_lon_deg`, takes in loaded tiles and asks for
    /// missing ones; with `complete`, loads every window tile in this thread first (one-off
    /// frames).
    pub fn update(
        &mut self,
        gpu: &Gpu,
        eye_lat_deg: f64,
        eye_lon_deg: f64,
        complete: bool,
    ) -> ClipmapStats {
        let Some(layout) = self.layout else {
            return ClipmapStats::default();
        };
        let (row0, col0) = layout.texel_coordinates(eye_lat_deg, eye_lon_deg);
        let t = f64::from(layout.tile_texels);
        let w = WINDOW_TILES;
        let mut clear_later = Vec::new();
        for k in 0..layout.levels {
            let (rows, cols) = layout.tiles_at(k);
            let scale = f64::from(1u32 << k);
            let origin_of = |pos: f64, count: u32| -> u32 {
                let start = (pos / scale / t - f64::from(w) * 0.5).round();
                start.clamp(0.0, f64::from(count.saturating_sub(w))) as u32
            };
            let origin = (origin_of(row0, rows), origin_of(col0, cols));
            let level = &mut self.levels[usize::from(k)];
            if level.origin == Some(origin) {
                continue;
            }
            level.origin = Some(origin);
            for dr in 0..w {
                for dc in 0..w {
                    let key = ImageryKey {
                        level: k,
                        row: origin.0 + dr,
                        col: origin.1 + dc,
                    };
                    let slot = slot_index(key);
                    let held = match level.slots[slot] {
                        Slot::Loaded(held) | Slot::Pending(held) | Slot::Absent(held) => Some(held),
                        Slot::Empty => None,
                    };
                    if held == Some(key) {
                        continue;
                    }
                    level.slots[slot] = if layout.contains_key(key) {
                        Slot::Empty
                    } else {
                        clear_later.push(key);
                        Slot::Absent(key)
                    };
                    level.pages_dirty = true;
                }
            }
        }
        for key in clear_later {
            self.clear_slot(gpu, key);
        }
        let mut stats = ClipmapStats::default();
        if complete {
            stats.tiles_uploaded += self.load_all_now(gpu);
        }
        stats.tiles_uploaded += self.take_loaded(
            gpu,
            if complete {
                usize::MAX
            } else {
                UPLOADS_PER_FRAME
            },
        );
        self.request_missing(row0, col0);
        stats.tiles_pending = self.loader.as_ref().map_or(0, |l| l.in_flight);
        self.write_pages(gpu, false);
        stats
    }

    /// Loads every empty slot's tile in this thread.
    fn load_all_now(&mut self, gpu: &Gpu) -> usize {
        let mut uploaded = 0;
        for k in 0..self.levels.len() {
            for slot in 0..self.levels[k].slots.len() {
                let want = match self.levels[k].slots[slot] {
                    Slot::Empty | Slot::Pending(_) => self.wanted_key(k, slot),
                    _ => None,
                };
                if let Some(key) = want {
                    let bytes =
                        load(&self.database, key).map(|t| decode_for_gpu(t, self.compressed));
                    uploaded += usize::from(self.place(gpu, Loaded { key, bytes }));
                }
            }
        }
        uploaded
    }

    /// The tile the window of level `k` expects in `slot`.
    fn wanted_key(&self, k: usize, slot: usize) -> Option<ImageryKey> {
        let origin = self.levels[k].origin?;
        let w = WINDOW_TILES;
        let (sr, sc) = ((slot as u32) / w, (slot as u32) % w);
        // The window row whose row modulo the window is the slot's.
        let row = origin.0 + (sr + w - origin.0 % w) % w;
        let col = origin.1 + (sc + w - origin.1 % w) % w;
        Some(ImageryKey {
            level: k as u8,
            row,
            col,
        })
    }

    /// Takes in finished loads (at most `budget`); returns how many were written.
    fn take_loaded(&mut self, gpu: &Gpu, budget: usize) -> usize {
        let mut written = 0;
        while written < budget {
            let Some(loader) = self.loader.as_mut() else {
                break;
            };
            let Ok(loaded) = loader.results.try_recv() else {
                break;
            };
            loader.in_flight = loader.in_flight.saturating_sub(1);
            written += usize::from(self.place(gpu, loaded));
        }
        written
    }

    /// Puts a loaded tile into its slot if the window still wants it; true when written.
    fn place(&mut self, gpu: &Gpu, loaded: Loaded) -> bool {
        let key = loaded.key;
        let slot = slot_index(key);
        let Some(level) = self.levels.get_mut(usize::from(key.level)) else {
            return false;
        };
        let wanted = matches!(level.slots[slot], Slot::Pending(k) if k == key)
            || (level.slots[slot] == Slot::Empty
                && self.wanted_key(usize::from(key.level), slot) == Some(key));
        if !wanted {
            return false;
        }
        let Some(bytes) = loaded.bytes else {
            self.levels[usize::from(key.level)].slots[slot] = Slot::Absent(key);
            self.clear_slot(gpu, key);
            return false;
        };
        self.write_slot(gpu, key, &bytes);
        let level = &mut self.levels[usize::from(key.level)];
        level.blank[slot] = false;
        level.slots[slot] = Slot::Loaded(key);
        level.pages_dirty = true;
        true
    }

    /// Makes the slot of `key` transparent (so the bilinear taps of a neighbouring tile find
    /// no stale imagery there).
    fn clear_slot(&mut self, gpu: &Gpu, key: ImageryKey) {
        let slot = slot_index(key);
        let Some(level) = self.levels.get_mut(usize::from(key.level)) else {
            return;
        };
        if std::mem::replace(&mut level.blank[slot], true) {
            return;
        }
        let t = self.layout.map_or(4, |l| l.tile_texels) as usize;
        let bytes = if self.compressed {
            // BC3 blocks of zeros: alpha 0, black.
            vec![0u8; t * t]
        } else {
            vec![0u8; t * t * 4]
        };
        self.write_slot(gpu, key, &bytes);
    }

    fn write_slot(&self, gpu: &Gpu, key: ImageryKey, bytes: &[u8]) {
        let t = self.layout.map_or(4, |l| l.tile_texels);
        let w = WINDOW_TILES;
        let (bytes_per_row, rows_per_image) = if self.compressed {
            (t / 4 * 16, t / 4)
        } else {
            (t * 4, t)
        };
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: (key.col % w) * t,
                    y: (key.row % w) * t,
                    z: u32::from(key.level),
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bytes_per_row),
                rows_per_image: Some(rows_per_image),
            },
            wgpu::Extent3d {
                width: t,
                height: t,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Asks the loaders for empty slots' tiles: coarse levels first (the fallback appears
    /// soonest), nearest the eye first within a level.
    fn request_missing(&mut self, row0: f64, col0: f64) {
        let Some(layout) = self.layout else {
            return;
        };
        let mut wanted: Vec<(u8, f64, usize)> = Vec::new();
        for k in (0..self.levels.len()).rev() {
            for slot in 0..self.levels[k].slots.len() {
                if self.levels[k].slots[slot] != Slot::Empty {
                    continue;
                }
                if let Some(key) = self.wanted_key(k, slot) {
                    let span = f64::from(layout.tile_texels) * f64::from(1u32 << k);
                    let dr = (f64::from(key.row) + 0.5) * span - row0;
                    let dc = (f64::from(key.col) + 0.5) * span - col0;
                    wanted.push((key.level, (dr * dr + dc * dc) / (span * span), slot));
                }
            }
        }
        wanted.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.total_cmp(&b.1)));
        for (k, _, slot) in wanted {
            let Some(key) = self.wanted_key(usize::from(k), slot) else {
                continue;
            };
            let Some(loader) = self.loader.as_mut() else {
                return;
            };
            if loader.in_flight >= LOADS_IN_FLIGHT {
                return;
            }
            if loader.requests.send(key).is_err() {
                return;
            }
            loader.in_flight += 1;
            self.levels[usize::from(k)].slots[slot] = Slot::Pending(key);
        }
    }

    /// Resolves and writes the page tables when a slot changed (or with `all`): each slot's
    /// byte is the finest level at or above its own whose tile there is loaded with every
    /// coarser tile above it (so the shader's blend with the next level up always finds it
    /// loaded), 255 where none is.
    fn write_pages(&mut self, gpu: &Gpu, all: bool) {
        if !(all || self.levels.iter().any(|l| l.pages_dirty)) {
            return;
        }
        let w = (self.levels[0].pages.len() as f64).sqrt() as u32;
        let count = self.levels.len();
        for k in (0..count).rev() {
            for slot in 0..self.levels[k].slots.len() {
                let key = self.wanted_key(k, slot);
                let loaded = key.is_some_and(|key| self.levels[k].slots[slot] == Slot::Loaded(key));
                let above = match key {
                    Some(key) if k + 1 < count => {
                        let parent = key.parent();
                        let parent_slot = slot_index(parent);
                        if self.wanted_key(k + 1, parent_slot) == Some(parent) {
                            self.levels[k + 1].pages[parent_slot]
                        } else {
                            NO_LEVEL
                        }
                    }
                    _ => NO_LEVEL,
                };
                // The next level up is loaded, or known to hold nothing there (the shader's
                // blend toward it then fades toward the material, as the imagery does).
                let parent_absent = key.is_some_and(|key| {
                    k + 1 < count
                        && self.levels[k + 1].slots[slot_index(key.parent())]
                            == Slot::Absent(key.parent())
                });
                let coarser_ready = k + 1 == count || usize::from(above) == k + 1 || parent_absent;
                self.levels[k].pages[slot] = if loaded && coarser_ready {
                    k as u8
                } else {
                    above
                };
            }
        }
        let texture = &self.pages;
        for (k, level) in self.levels.iter_mut().enumerate() {
            level.pages_dirty = false;
            gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: k as u32,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                &level.pages,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(w),
                    rows_per_image: Some(w),
                },
                wgpu::Extent3d {
                    width: w,
                    height: w,
                    depth_or_array_layers: 1,
                },
            );
        }
    }

    /// Writes the shader's parameters for a view whose eye is at `eye_lat_deg, eye_lon_deg`,
    /// and sets the anchor (level-0 texel row, column) node records are relative to.
    pub fn prepare_view(&mut self, gpu: &Gpu, eye_lat_deg: f64, eye_lon_deg: f64) {
        let mut params = Params {
            info: [0.0; 4],
            levels: [LevelParams::default(); MAX_IMAGERY_LEVELS as usize],
        };
        if let Some(layout) = self.layout {
            let (row0, col0) = layout.texel_coordinates(eye_lat_deg, eye_lon_deg);
            let anchor = (row0.floor() as i64, col0.floor() as i64);
            self.anchor = anchor;
            let n = f64::from(self.clip_texels);
            let t = f64::from(layout.tile_texels);
            params.info = [
                f32::from(layout.levels),
                self.clip_texels as f32,
                layout.tile_texels as f32,
                WINDOW_TILES as f32,
            ];
            for (k, level) in self.levels.iter().enumerate() {
                let scale = f64::from(1u32 << k);
                let (ar, ac) = (anchor.0 as f64 / scale, anchor.1 as f64 / scale);
                let (or, oc) = level.origin.unwrap_or((0, 0));
                let (rows, cols) = layout.texels_at(k as u8);
                let lo = (f64::from(or) * t - ar, f64::from(oc) * t - ac);
                let hi = (
                    (f64::from(or) * t + n).min(rows as f64) - ar,
                    (f64::from(oc) * t + n).min(cols as f64) - ac,
                );
                // x is the column (east), y the row (north), as the texture's axes.
                params.levels[k] = LevelParams {
                    phase_lo: [
                        ac.rem_euclid(n) as f32,
                        ar.rem_euclid(n) as f32,
                        lo.1 as f32,
                        lo.0 as f32,
                    ],
                    hi: [
                        hi.1 as f32,
                        hi.0 as f32,
                        (self.fine_texel_m * scale) as f32,
                        0.0,
                    ],
                };
            }
        }
        gpu.queue
            .write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&params));
    }

    /// What node records need to place a node in the imagery: the pyramid's fine shift and
    /// the view's anchor (level-0 texel row, column); `None` without imagery.
    pub fn frame(&self) -> Option<ImageryFrame> {
        self.layout.map(|l| ImageryFrame {
            fine_shift: l.fine_shift,
            anchor: self.anchor,
        })
    }
}

/// Where one view's node records place nodes in the imagery (see [`ImageryClipmap::frame`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageryFrame {
    pub fine_shift: u8,
    /// Level-0 imagery texel (row, column) the view's coordinates are relative to.
    pub anchor: (i64, i64),
}

impl ImageryFrame {
    /// A node's imagery rectangle for its shader record: the level-0 texel coordinates
    /// (column, row) of its south-west post relative to the anchor, and its extent in level-0
    /// texels (east, north).
    pub fn node_rect(&self, finest_origin: (u64, u64), finest_span: u64) -> [f32; 4] {
        let s = 1u64 << self.fine_shift;
        let extent = (finest_span * s) as f32;
        [
            ((finest_origin.1 * s) as i64 - self.anchor.1) as f32,
            ((finest_origin.0 * s) as i64 - self.anchor.0) as f32,
            extent,
            extent,
        ]
    }
}

/// The slot of a tile in its level's window.
fn slot_index(key: ImageryKey) -> usize {
    let w = WINDOW_TILES;
    ((key.row % w) * w + key.col % w) as usize
}

/// Loads a tile; `None` where there is none or it cannot be read (logged once per tile).
fn load(database: &TerrainDatabase, key: ImageryKey) -> Option<ImageryTile> {
    match database.load_imagery_tile(key) {
        Ok(tile) => tile,
        Err(e) => {
            tracing::warn!("imagery tile not drawn: {e}");
            None
        }
    }
}
