//! Culture to draw: the level-of-detail selection, culling and instancing of the trees,
//! bushes, buildings, walls, fences and poles that stand on the resident finest tiles.
//!
//! Algorithm: every culture object is an instance of one of a few unit meshes
//! ([`culture_model`]: a kind's levels in a unit box, x across, y along the heading, z up),
//! scaled by its width, length and height. Per view, the selection walks the resident finest
//! tiles within the farthest range any object can be drawn at, culls their 8 x 8-cell blocks
//! by the frustum (a bounding sphere per block) and by distance, and gives each object in a
//! block that survives its detail control parameter (source 004 Eq 16: `N_e = K_LOD r_c / R_s
//! f(v)`, `r_c` the object's bounding radius, `f(v)` removing it at 98 % fade in the fog, the
//! area-of-interest factor toward the periphery), which chooses its levels from the square-law
//! table with the dithered blend of [`crate::models::Model::lod_blend`]. As the study shows
//! nothing below the table's first step, an object dissolves away over the doubling of `N_e`
//! above it (from 3 to 1.5: a radius of 3 to 1.5 resolution elements), so no object pops in
//! or out at its farthest range. Blocks far from the eye against their size take the fog and
//! area-of-interest terms at their centre, so most objects cost one distance.
//! Instances come out grouped by kind and level, one instanced draw each.
//!
//! Positions: a tile's objects are turned once (when the tile becomes resident) into offsets
//! in metres from their block's anchor, an ECEF point at the block's centre, along the
//! anchor's east, north and up; within a 240 m block the earth's curvature is under 2 mm. The
//! eye-relative position of an object is then the anchor's (an f64 subtraction) plus its
//! offset, in f32, as the renderer wants it.
//!
//! Blocks hidden behind ridges are culled by an occlusion horizon built each frame from the
//! min/max quadtree leaves of the resident finest tiles in range ([`crate::horizon`]): only
//! where the terrain surely hides a whole block, with a margin for the drawn terrain's error.
//!
//! Limits: a partly hidden block is drawn whole (and depth tested); far culture is removed,
//! not replaced by an area texture; one unit mesh per kind (variants differ in size, heading
//! and tint only).

use crate::detail::{AoiByCosine, DetailSettings, LevelLookup, LodBlend};
use crate::horizon::{GeoRect, OccluderGrid, OcclusionHorizon};
use crate::models::{Model, ModelMesh};
use crate::view::Camera;
use cig_geo::Geodetic;
use cig_terrain::culture::{CultureKind, CultureTile, CULTURE_BLOCK_CELLS};
use cig_terrain::database::GeoidLookup;
use cig_terrain::pyramid::quadtree_index;
use cig_terrain::tile::Tile;
use cig_terrain::{PyramidLayout, TileCache, TileKey};
use glam::{DVec3, Vec3};
use std::collections::HashMap;
use std::sync::Arc;

/// Below the table's first step an object is gone; from there to twice it, it dissolves in
/// (as multiples of the first step's `N_e`).
const FADE_FROM: f64 = 1.0;
const FADE_TO: f64 = 2.0;

/// How many candidate blocks ahead of its turn a block's record, and its first objects, are
/// prefetched.
const PREFETCH_BLOCKS_AHEAD: usize = 8;
const PREFETCH_ITEMS_AHEAD: usize = 4;

/// Asks the CPU to bring the cache line holding the start of `value` in ahead of its use (a
/// hint only; nothing on targets without one).
#[inline(always)]
fn prefetch<T>(value: &T) {
    // SAFETY: a prefetch reads nothing into the program and never faults (on any address);
    // SSE, which it needs, is part of every x86-64 CPU.
    #[cfg(target_arch = "x86_64")]
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
            std::ptr::from_ref(value).cast::<i8>(),
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

/// Tiles nearer than this raise the occlusion horizon by their quadtree's leaves (240 m at
/// 30 m posts), farther ones by the nodes a level up.
const FINE_OCCLUDERS_M: f64 = 4000.0;

/// One instance for the GPU: the columns of its body-to-eye-relative-ECEF transform, scaled by
/// its size; `col0.w..col1.w` the share of its pixels this draw covers (dither thresholds, for
/// the level blend), `origin.w` a tint (-0.15..0.15, multiplies the colour by `1 + tint`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CultureInstance {
    pub col0: [f32; 4],
    pub col1: [f32; 4],
    pub col2: [f32; 4],
    pub origin: [f32; 4],
}

/// One instanced draw: a kind's level and where its instances lie among the frame's (the
/// draws' instances one after the other; [`CultureFrame::instances_of`] gives them).
#[derive(Clone, Debug, PartialEq)]
pub struct CultureDraw {
    pub kind: CultureKind,
    pub level: usize,
    pub instances: std::ops::Range<usize>,
    /// Index of its instances' bucket in the frame.
    bucket: usize,
}

/// What a view draws of the culture this frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CultureFrame {
    /// The instances by kind and level (the draws say which bucket is which), kept apart so
    /// they are written once, where they are drawn from.
    buckets: Vec<Vec<CultureInstance>>,
    pub draws: Vec<CultureDraw>,
    /// Objects drawn (an object blending two levels counts once).
    pub objects_drawn: usize,
    /// Objects in the blocks that survived culling (each given an `N_e`).
    pub objects_considered: usize,
    /// Blocks in range, those the frustum kept, and those (of the kept) hidden by terrain.
    pub blocks_in_range: usize,
    pub blocks_drawn: usize,
    pub blocks_occluded: usize,
}

impl CultureFrame {
    /// Instances of all the draws together.
    pub fn instance_count(&self) -> usize {
        self.draws.last().map_or(0, |d| d.instances.end)
    }

    /// The instances of `draw` (one of this frame's draws).
    pub fn instances_of(&self, draw: &CultureDraw) -> &[CultureInstance] {
        self.buckets.get(draw.bucket).map_or(&[], Vec::as_slice)
    }
}

/// How a view selects its culture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CultureSelect<'a> {
    pub detail: &'a DetailSettings,
    /// The `K_LOD` the objects are drawn at (the overload control's).
    pub klod: f64,
    /// The view's nominal `K_LOD`, which cue-important kinds keep under overload (§4.6).
    pub klod_nominal: f64,
    /// Kinds marked cue-important (indexed by the kind's byte), e.g. power poles for a
    /// helicopter trainer: they keep the nominal `K_LOD`.
    pub cue_important: [bool; 9],
    /// Where the trainee looks (a unit vector, ECEF: the selection takes it as one): the area
    /// of interest's centre.
    pub aim: DVec3,
    /// `false`: every object of the resident tiles in the frustum at its finest level, no
    /// removal (the unmanaged reference of `cig bench culture`).
    pub managed: bool,
    /// Make the culture of every tile in range before selecting (one-off frames); otherwise
    /// the tiles that became resident are made ready on a thread of the selector's own and
    /// their culture shows from the frame after.
    pub complete: bool,
    /// Cull blocks the terrain hides, with this margin in pixels for the drawn terrain's
    /// error (its level of detail's pixel error and one more); `None`: no occlusion culling.
    /// Managed selection only.
    pub occlusion_margin_px: Option<f64>,
}

/// An object ready for selection: its offset from its block's anchor and its look.
#[derive(Clone, Copy, Debug)]
struct RenderItem {
    /// East, north, up from the anchor, metres (up to the bottom of the drawn mesh).
    offset_m: [f32; 3],
    /// Unit heading along the length, in (east, north).
    heading: [f32; 2],
    /// Width, length and drawn height (buildings carried down to the footprint's lowest point).
    size_m: [f32; 3],
    critical_radius_m: f32,
    tint: f32,
    kind: CultureKind,
}

#[derive(Clone, Debug)]
struct RenderBlock {
    anchor_ecef: DVec3,
    east: Vec3,
    north: Vec3,
    up: Vec3,
    /// Radius of a sphere about the anchor holding every object of the block.
    radius_m: f64,
    /// Largest critical radius in the block.
    max_critical_m: f32,
    /// The ground the block's objects stand on and overhang, and the ellipsoidal height of
    /// its tallest top (for occlusion).
    rect: GeoRect,
    top_alt_m: f64,
    /// Mean height of the objects' middles above the anchor, metres.
    mean_up_m: f32,
    items: std::ops::Range<usize>,
}

struct RenderTile {
    /// The tile this was made from (a reload makes it again).
    source: Arc<Tile>,
    blocks: Vec<RenderBlock>,
    items: Vec<RenderItem>,
}

/// Per-view culture selection over a [`TileCache`]'s resident finest tiles; keeps each
/// resident tile's objects in the form the selection walks.
pub struct CultureSelector {
    layout: PyramidLayout,
    geoid: GeoidLookup,
    tiles: HashMap<TileKey, RenderTile>,
    /// Levels of the kinds' models.
    levels: usize,
    /// The cache's eviction count when the tiles were last checked against it.
    eviction_epoch: u64,
    /// Instances per kind and level, kept from frame to frame for their room.
    buckets: Vec<Vec<CultureInstance>>,
    /// The terrain's occlusion horizon and the leaf grid it is built from, kept for their room.
    horizon: OcclusionHorizon,
    occluders: [OccluderGrid; 2],
    /// This frame's blocks that survived the frustum and range (tile, block), kept for room.
    candidates: Vec<(TileKey, usize)>,
    /// The candidates' hiding floors ([`OcclusionHorizon::hiding_floor`]) by distance, each
    /// lowered to the lowest at or beyond it (kept for their room).
    floors: Vec<(f64, f64)>,
    /// Makes newly resident tiles ready off the frame's thread (`None` where no thread could
    /// be started: they are then made in the frame).
    builder: Option<TileBuilder>,
    /// Each resident tile's street and settlement lights (the tile they were made from).
    lights: HashMap<TileKey, (Arc<Tile>, Arc<[crate::lights::LightPoint]>)>,
}

/// Turns resident tiles into their render form on a thread of its own, so a frame never waits
/// for a tile full of objects.
struct TileBuilder {
    requests: Option<std::sync::mpsc::Sender<(TileKey, Arc<Tile>)>>,
    done: std::sync::mpsc::Receiver<(TileKey, RenderTile)>,
    /// Tiles asked for and not yet back.
    pending: std::collections::HashSet<TileKey>,
    worker: Option<std::thread::JoinHandle<()>>,
}

impl TileBuilder {
    fn start(layout: PyramidLayout, geoid: GeoidLookup) -> Option<TileBuilder> {
        let (requests, inbox) = std::sync::mpsc::channel::<(TileKey, Arc<Tile>)>();
        let (outbox, done) = std::sync::mpsc::channel();
        let worker = std::thread::Builder::new()
            .name("culture blocks".into())
            .spawn(move || {
                while let Ok((key, tile)) = inbox.recv() {
                    if outbox
                        .send((key, make_render_tile(&layout, &geoid, tile)))
                        .is_err()
                    {
                        break;
                    }
                }
            })
            .ok()?;
        Some(TileBuilder {
            requests: Some(requests),
            done,
            pending: std::collections::HashSet::new(),
            worker: Some(worker),
        })
    }

    /// Asks for `tile` (once while it is pending); `false` when the worker is gone.
    fn request(&mut self, key: TileKey, tile: &Arc<Tile>) -> bool {
        if self.pending.contains(&key) {
            return true;
        }
        let sent = self
            .requests
            .as_ref()
            .is_some_and(|r| r.send((key, Arc::clone(tile))).is_ok());
        if sent {
            self.pending.insert(key);
        }
        sent
    }
}

impl TileBuilder {
    /// Moves the tiles made since the last call (those still resident) into `tiles`; `false`
    /// when the thread is gone.
    fn collect(&mut self, cache: &TileCache, tiles: &mut HashMap<TileKey, RenderTile>) -> bool {
        loop {
            match self.done.try_recv() {
                Ok((key, made)) => {
                    self.pending.remove(&key);
                    if cache
                        .resident(key)
                        .is_some_and(|r| Arc::ptr_eq(&r, &made.source))
                    {
                        tiles.insert(key, made);
                    }
                }
                Err(std::sync::mpsc::TryRecvError::Empty) => return true,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => return false,
            }
        }
    }
}

impl Drop for TileBuilder {
    fn drop(&mut self) {
        // Closing the requests ends the worker's loop.
        self.requests = None;
        if let Some(worker) = self.worker.take() {
            // A worker that panicked has nothing left to give back.
            let _ = worker.join();
        }
    }
}

impl CultureSelector {
    pub fn new(layout: PyramidLayout, geoid: GeoidLookup) -> CultureSelector {
        let builder_geoid = geoid.clone();
        let levels = CultureKind::ALL
            .into_iter()
            .map(|kind| culture_model(kind).lods.len())
            .max()
            .unwrap_or(1);
        CultureSelector {
            layout,
            geoid,
            tiles: HashMap::new(),
            lights: HashMap::new(),
            levels,
            eviction_epoch: u64::MAX,
            buckets: Vec::new(),
            horizon: OcclusionHorizon::default(),
            occluders: Default::default(),
            candidates: Vec::new(),
            floors: Vec::new(),
            builder: TileBuilder::start(layout, builder_geoid),
        }
    }

    /// Selects the culture `camera` draws this frame. `fade(distance_m, altitude_m)` is how far
    /// the fog has faded an object at that slant range and altitude (0 clear, 1 gone).
    pub fn select(
        &mut self,
        cache: &TileCache,
        camera: &Camera,
        select: &CultureSelect<'_>,
        fade: &dyn Fn(f64, f64) -> f64,
    ) -> CultureFrame {
        let mut frame = CultureFrame::default();
        let table = &select.detail.table;
        let first_step = table.value(1);
        let min_ne = first_step * FADE_FROM;
        // The farthest any object may be drawn: the largest radius at the lowest N_e.
        let max_radius_m = 40.0;
        let klod_most = select.klod.max(if select.cue_important.contains(&true) {
            select.klod_nominal
        } else {
            0.0
        });
        let range_m = if select.managed {
            klod_most * max_radius_m / min_ne
        } else {
            f64::INFINITY
        };
        let near = self.tiles_near(camera, range_m, cache);
        // Forget tiles that left the cache (only after it evicted something).
        let epoch = cache.eviction_epoch();
        if epoch != self.eviction_epoch {
            self.eviction_epoch = epoch;
            self.tiles.retain(|key, t| {
                cache
                    .resident(*key)
                    .is_some_and(|r| Arc::ptr_eq(&r, &t.source))
            });
        }
        let levels = self.levels.max(1);
        // Last frame's buckets, emptied: their room is kept.
        let mut buckets = std::mem::take(&mut self.buckets);
        buckets.resize_with(CultureKind::ALL.len() * levels, Vec::new);
        buckets.iter_mut().for_each(Vec::clear);
        let eye = camera.eye_ecef;
        // Tiles made ready since the last frame; without the thread, tiles are made in the
        // frame from now on.
        if let Some(builder) = &mut self.builder {
            if !builder.collect(cache, &mut self.tiles) {
                self.builder = None;
            }
        }
        // 1. The blocks in range, in the frustum and not too small to show anything.
        let mut candidates = std::mem::take(&mut self.candidates);
        candidates.clear();
        for (key, tile) in &near {
            if tile.culture.is_none() {
                continue;
            }
            let render = match self.tiles.get(key) {
                Some(r) if Arc::ptr_eq(&r.source, tile) => r,
                _ if !select.complete
                    && self.builder.as_mut().is_some_and(|b| b.request(*key, tile)) =>
                {
                    continue;
                }
                _ => {
                    let made = make_render_tile(&self.layout, &self.geoid, Arc::clone(tile));
                    self.tiles.insert(*key, made);
                    match self.tiles.get(key) {
                        Some(r) => r,
                        None => continue,
                    }
                }
            };
            for (index, block) in render.blocks.iter().enumerate() {
                let rel = block.anchor_ecef - eye;
                let distance = rel.length();
                if distance - block.radius_m > range_m {
                    continue;
                }
                frame.blocks_in_range += 1;
                if camera
                    .planes
                    .iter()
                    .any(|p| p.normal.dot(rel) < p.offset_m - block.radius_m)
                {
                    continue;
                }
                if select.managed {
                    let nearest = (distance - block.radius_m).max(1.0);
                    if klod_most * f64::from(block.max_critical_m) / nearest < min_ne {
                        continue;
                    }
                }
                candidates.push((*key, index));
            }
        }
        // 2. The terrain's horizon over them, when it can hide any.
        let occlusion = match select.occlusion_margin_px {
            Some(margin_px) if select.managed && !candidates.is_empty() => {
                self.build_horizon(&near, &candidates, camera, margin_px)
            }
            _ => false,
        };
        // 3. Their objects.
        let pass = ObjectPass {
            tiles: &self.tiles,
            horizon: occlusion.then_some(&self.horizon),
            camera,
            select,
            fade,
            lookup: LevelLookup::new(table, levels),
            aoi_by_cosine: select.detail.aoi.as_ref().map(AoiByCosine::new),
            klod_most,
            min_ne,
            range_m,
            levels,
        };
        let counts = pass.run(&candidates, &mut buckets);
        frame.objects_drawn = counts.objects_drawn;
        frame.objects_considered = counts.objects_considered;
        frame.blocks_drawn = counts.blocks_drawn;
        frame.blocks_occluded = counts.blocks_occluded;
        self.candidates = candidates;
        let mut start = 0;
        for (index, bucket) in buckets.iter().enumerate() {
            if bucket.is_empty() {
                continue;
            }
            frame.draws.push(CultureDraw {
                kind: CultureKind::ALL[index / levels],
                level: index % levels,
                instances: start..start + bucket.len(),
                bucket: index,
            });
            start += bucket.len();
        }
        frame.buckets = buckets;
        frame
    }

    /// Takes back a frame's buckets: their room serves the next frame (instances are not
    /// written into newly mapped memory every frame).
    pub fn recycle(&mut self, frame: CultureFrame) {
        self.buckets = frame.buckets;
    }

    /// Builds this frame's occlusion horizon for the blocks `candidates` from the resident
    /// finest tiles `near` out to the farthest of them, limited to the view's azimuths: tiles within
    /// [`FINE_OCCLUDERS_M`] by their quadtree's leaves, farther ones by the nodes a level up
    /// (tiles rebuilt from coarser data are left out: their bounds are not the finest
    /// surface's). Ground that cannot rise above the hiding floor of any block beyond it
    /// (`self.floors`), judged by the quadtree's nodes of a quarter tile, is left out; returns
    /// `false`, building nothing, when that is all of it.
    fn build_horizon(
        &mut self,
        near: &[(TileKey, Arc<Tile>)],
        candidates: &[(TileKey, usize)],
        camera: &Camera,
        margin_px: f64,
    ) -> bool {
        let eye = camera.view.eye;
        self.horizon.begin(
            eye.lat_deg,
            eye.lon_deg,
            eye.alt_m,
            margin_px.max(0.0) / camera.pixels_per_tangent.max(1.0),
        );
        // The blocks' hiding floors by distance, each lowered to the lowest at or beyond it,
        // and the farthest block's reach.
        self.floors.clear();
        let mut reach_m = 0.0_f64;
        for (key, index) in candidates {
            if let Some(block) = self.tiles.get(key).and_then(|t| t.blocks.get(*index)) {
                reach_m =
                    reach_m.max((block.anchor_ecef - camera.eye_ecef).length() + block.radius_m);
                self.floors
                    .extend(self.horizon.hiding_floor(&block.rect, block.top_alt_m));
            }
        }
        self.floors.sort_by(|a, b| a.0.total_cmp(&b.0));
        for k in (0..self.floors.len().saturating_sub(1)).rev() {
            self.floors[k].1 = self.floors[k].1.min(self.floors[k + 1].1);
        }
        // The view's edge rays (where its side planes meet), on the ground's east and north.
        let enu = cig_geo::EnuFrame::new(eye);
        let east = enu.enu_vector_to_ecef(DVec3::X);
        let north = enu.enu_vector_to_ecef(DVec3::Y);
        let p = &camera.planes;
        let edges = [(0, 2), (0, 3), (1, 2), (1, 3)].map(|(a, b)| {
            let ray = p[a].normal.cross(p[b].normal);
            let ray = if ray.dot(camera.forward) < 0.0 {
                -ray
            } else {
                ray
            };
            (ray.dot(east), ray.dot(north))
        });
        let holds = |v: DVec3| p[..4].iter().all(|plane| plane.normal.dot(v) > 0.0);
        let all_round = holds(camera.local_up) || holds(-camera.local_up);
        self.horizon.limit_to_view(&edges, all_round);

        let g = self.layout.grid;
        let tile_cells = self.layout.tile_cells as usize;
        let depth = near
            .iter()
            .map(|(_, t)| t.quadtree_depth)
            .min()
            .unwrap_or(0);
        let (row_lo, row_hi, col_lo, col_hi) = near
            .iter()
            .fold((u32::MAX, 0, u32::MAX, 0), |(rl, rh, cl, ch), (k, _)| {
                (rl.min(k.row), rh.max(k.row), cl.min(k.col), ch.max(k.col))
            });
        let (tile_rows, tile_cols) = (
            (row_hi - row_lo + 1) as usize,
            (col_hi - col_lo + 1) as usize,
        );
        let levels = [depth, depth.saturating_sub(1)];
        for (grid, d) in self.occluders.iter_mut().zip(levels) {
            let per_tile = 1usize << d;
            let cell = (tile_cells >> d) as f64;
            grid.rows = tile_rows * per_tile;
            grid.cols = tile_cols * per_tile;
            grid.south_deg = g.south_lat_deg + (row_lo as usize * tile_cells) as f64 * g.dlat_deg;
            grid.west_deg = g.west_lon_deg + (col_lo as usize * tile_cells) as f64 * g.dlon_deg;
            grid.cell_dlat_deg = cell * g.dlat_deg;
            grid.cell_dlon_deg = cell * g.dlon_deg;
            grid.lowest_alt_m.clear();
            grid.lowest_alt_m.resize(grid.rows * grid.cols, f32::NAN);
        }
        let floors = &self.floors;
        // Whether ground nearest at `near_m` raising the horizon up to `tan` could hide a block.
        let may_hide = |reach: Option<(f64, f64)>| match reach {
            None => true,
            Some((near_m, tan)) => {
                let beyond = floors.partition_point(|f| f.0 <= near_m);
                floors.get(beyond).is_some_and(|f| f.1 < tan)
            }
        };
        let mut any = false;
        for (key, tile) in near {
            if tile.degraded_from_level.is_some() || tile.quadtree_depth != depth {
                continue;
            }
            let (row0, col0) = (key.row as usize * tile_cells, key.col as usize * tile_cells);
            let rect_of = |cells: usize, x: usize, y: usize, across: usize| GeoRect {
                south_deg: g.south_lat_deg + (row0 + y * cells) as f64 * g.dlat_deg,
                west_deg: g.west_lon_deg + (col0 + x * cells) as f64 * g.dlon_deg,
                north_deg: g.south_lat_deg + (row0 + (y + across) * cells) as f64 * g.dlat_deg,
                east_deg: g.west_lon_deg + (col0 + (x + across) * cells) as f64 * g.dlon_deg,
            };
            let rect = rect_of(tile_cells, 0, 0, 1);
            let nearest_m = self.horizon.nearest_m(&rect);
            if nearest_m > reach_m || !self.horizon.in_view(&rect) {
                continue;
            }
            // Heights are above the geoid: lift the lowest by its least undulation over the
            // tile and the highest by its greatest (at the corners and the centre, the geoid
            // grid being far coarser than a tile; a tenth of a metre for what lies between).
            let (undulation_low, undulation_high) = [
                (rect.south_deg, rect.west_deg),
                (rect.south_deg, rect.east_deg),
                (rect.north_deg, rect.west_deg),
                (rect.north_deg, rect.east_deg),
                (
                    0.5 * (rect.south_deg + rect.north_deg),
                    0.5 * (rect.west_deg + rect.east_deg),
                ),
            ]
            .iter()
            .map(|&(lat, lon)| self.geoid.undulation_m(lat, lon))
            .fold((f64::MAX, f64::MIN), |(lo, hi), u| (lo.min(u), hi.max(u)));
            let fine = nearest_m < FINE_OCCLUDERS_M;
            let (grid, d) = if fine {
                (&mut self.occluders[0], levels[0])
            } else {
                (&mut self.occluders[1], levels[1])
            };
            // Judged by the nodes of a quarter tile (or the tile's own, if coarser).
            let judge = d.min(2);
            let judged = 1usize << judge;
            let judge_cells = tile_cells >> judge;
            let per_judged = 1usize << (d - judge);
            let per_tile = 1usize << d;
            let node_cells = tile_cells >> d;
            for jy in 0..judged {
                for jx in 0..judged {
                    let top = f64::from(tile.nodes[quadtree_index(judge, jx, jy)].max_m)
                        + undulation_high
                        + 0.1;
                    let judged_rect = rect_of(judge_cells, jx, jy, 1);
                    if !may_hide(self.horizon.raising_ceiling(&judged_rect, top)) {
                        continue;
                    }
                    any = true;
                    for y in jy * per_judged..(jy + 1) * per_judged {
                        // Nodes reaching past the database's edge cover ground not drawn.
                        if row0 + (y + 1) * node_cells > g.rows.saturating_sub(1) {
                            break;
                        }
                        let grid_row = (key.row - row_lo) as usize * per_tile + y;
                        for x in jx * per_judged..(jx + 1) * per_judged {
                            if col0 + (x + 1) * node_cells > g.cols.saturating_sub(1) {
                                break;
                            }
                            let grid_col = (key.col - col_lo) as usize * per_tile + x;
                            let lowest = tile.nodes[quadtree_index(d, x, y)].min_m;
                            grid.lowest_alt_m[grid_row * grid.cols + grid_col] =
                                (f64::from(lowest) + undulation_low - 0.1) as f32;
                        }
                    }
                }
            }
        }
        if !any {
            return false;
        }
        for grid in &self.occluders {
            self.horizon.add_grid(grid);
        }
        self.horizon.finish();
        true
    }

    /// Appends the street and settlement lights of the resident finest tiles within
    /// `range_m` of the camera's eye (`crate::lights::culture_lights`, made once per tile
    /// while it stays resident).
    pub fn culture_lights_near(
        &mut self,
        cache: &TileCache,
        camera: &Camera,
        range_m: f64,
        out: &mut Vec<crate::lights::LightPoint>,
    ) {
        let near = self.tiles_near(camera, range_m, cache);
        self.lights
            .retain(|key, (tile, _)| near.iter().any(|(k, t)| k == key && Arc::ptr_eq(t, tile)));
        let rules = crate::lights::CultureLightRules::default();
        for (key, tile) in near {
            let Some(culture) = &tile.culture else {
                continue;
            };
            let lights = self.lights.entry(key).or_insert_with(|| {
                let mut made = Vec::new();
                crate::lights::culture_lights(
                    &self.layout,
                    &self.geoid,
                    culture,
                    &rules,
                    &mut made,
                );
                (Arc::clone(&tile), made.into())
            });
            out.extend_from_slice(&lights.1);
        }
    }

    /// Resident finest tiles within `range_m` of the eye (every resident finest tile when the
    /// range is unbounded).
    fn tiles_near(
        &self,
        camera: &Camera,
        range_m: f64,
        cache: &TileCache,
    ) -> Vec<(TileKey, Arc<Tile>)> {
        let g = &self.layout.grid;
        let eye = camera.view.eye;
        let (m_lat, m_lon) = cig_geo::metres_per_degree(eye.lat_deg);
        let tile_cells = f64::from(self.layout.tile_cells);
        let (rows, cols) = self.layout.tiles_at(0);
        let span = |range: f64, m_per_deg: f64, d_deg: f64| {
            if range.is_finite() {
                (range / (m_per_deg * d_deg * tile_cells)).ceil() as i64 + 1
            } else {
                i64::from(rows.max(cols))
            }
        };
        let eye_row = ((eye.lat_deg - g.south_lat_deg) / g.dlat_deg / tile_cells).floor() as i64;
        let eye_col = ((eye.lon_deg - g.west_lon_deg) / g.dlon_deg / tile_cells).floor() as i64;
        let dr = span(range_m, m_lat, g.dlat_deg);
        let dc = span(range_m, m_lon.max(1.0), g.dlon_deg);
        let mut keys = Vec::new();
        for row in (eye_row - dr).max(0)..=(eye_row + dr).min(i64::from(rows) - 1) {
            for col in (eye_col - dc).max(0)..=(eye_col + dc).min(i64::from(cols) - 1) {
                let key = TileKey {
                    level: 0,
                    row: row as u32,
                    col: col as u32,
                };
                if let Some(tile) = cache.resident(key) {
                    keys.push((key, tile));
                }
            }
        }
        keys
    }
}

/// A vertical face seen by Eq 17: its centre (eye-relative), long axis and normal (unit
/// vectors), half length and half height.
#[derive(Clone, Copy, Debug)]
struct Face {
    centre: Vec3,
    along: Vec3,
    normal: Vec3,
    radii_m: [f32; 2],
}

/// `N_e` of a vertical face (a wall or a fence) centred `centre` (eye-relative), its long axis
/// `along` and its normal `normal` (unit vectors), of half length and half height `radii_m`:
/// source 004 Eq 17 with Eq 15's effective radius toward the eye's foot in the face's plane,
/// times the area-of-interest factor.
/// The tile `key`, kept in `last` for the blocks after it (a selection's blocks come tile by
/// tile).
fn tile_of<'t>(
    tiles: &'t HashMap<TileKey, RenderTile>,
    last: &mut Option<(TileKey, &'t RenderTile)>,
    key: TileKey,
) -> Option<&'t RenderTile> {
    match *last {
        Some((k, r)) if k == key => Some(r),
        _ => {
            let r = tiles.get(&key)?;
            *last = Some((key, r));
            Some(r)
        }
    }
}

/// What the objects' pass of a selection reads.
struct ObjectPass<'a> {
    tiles: &'a HashMap<TileKey, RenderTile>,
    /// The terrain's horizon, where it culls.
    horizon: Option<&'a OcclusionHorizon>,
    camera: &'a Camera,
    select: &'a CultureSelect<'a>,
    fade: &'a dyn Fn(f64, f64) -> f64,
    lookup: LevelLookup,
    aoi_by_cosine: Option<AoiByCosine>,
    klod_most: f64,
    min_ne: f64,
    range_m: f64,
    levels: usize,
}

/// What a pass over objects counted.
#[derive(Clone, Copy, Debug, Default)]
struct PassCounts {
    objects_drawn: usize,
    objects_considered: usize,
    blocks_drawn: usize,
    blocks_occluded: usize,
}

impl ObjectPass<'_> {
    /// Levels and instances of the objects of `candidates` into `buckets` (by kind and level).
    fn run(
        &self,
        candidates: &[(TileKey, usize)],
        buckets: &mut [Vec<CultureInstance>],
    ) -> PassCounts {
        let ObjectPass {
            tiles,
            horizon,
            camera,
            select,
            fade,
            ref lookup,
            ref aoi_by_cosine,
            klod_most,
            min_ne,
            range_m,
            levels,
        } = *self;
        let mut counts = PassCounts::default();
        let eye = camera.eye_ecef;
        let local_up = camera.local_up.as_vec3();
        let aim32 = select.aim.as_vec3();
        let mut current: Option<(TileKey, &RenderTile)> = None;
        let mut ahead: Option<(TileKey, &RenderTile)> = None;
        for (position, &(key, index)) in candidates.iter().enumerate() {
            // The blocks come from all over the tiles' memory: each block's record is asked
            // for eight blocks ahead of its turn and its first objects four ahead, so their
            // cache misses overlap the work on the blocks before them.
            for (lead, objects) in [(PREFETCH_BLOCKS_AHEAD, false), (PREFETCH_ITEMS_AHEAD, true)] {
                let Some(&(ahead_key, ahead_index)) = candidates.get(position + lead) else {
                    continue;
                };
                let Some(render) = tile_of(tiles, &mut ahead, ahead_key) else {
                    continue;
                };
                let Some(block) = render.blocks.get(ahead_index) else {
                    continue;
                };
                if objects {
                    for item in render.items[block.items.clone()].iter().take(2) {
                        prefetch(item);
                    }
                } else {
                    prefetch(block);
                }
            }
            let Some(render) = tile_of(tiles, &mut current, key) else {
                continue;
            };
            let Some(block) = render.blocks.get(index) else {
                continue;
            };
            let rel = block.anchor_ecef - eye;
            let distance = rel.length();
            if horizon.is_some_and(|h| h.hides(&block.rect, block.top_alt_m)) {
                counts.blocks_occluded += 1;
                continue;
            }
            counts.blocks_drawn += 1;
            let rel32 = rel.as_vec3();
            // A block far from the eye against its size takes its fog and area-of-interest
            // terms at its centre (within 1/4 of a radian of every object's), so each
            // object costs a distance; near blocks are exact object by object.
            let block_scale = (select.managed && distance > 4.0 * block.radius_m).then(|| {
                let centre = rel32 + block.up * block.mean_up_m;
                let altitude = camera.view.eye.alt_m + f64::from(local_up.dot(centre));
                let fog = crate::detail::visibility_factor(fade(distance, altitude));
                let aoi = select.detail.aoi.as_ref().map_or(1.0, |aoi| {
                    let angle_deg = select.aim.angle_between(centre.as_dvec3()).to_degrees();
                    crate::detail::aoi_factor(angle_deg, aoi)
                });
                fog * aoi
            });
            // A near block wholly short of the fog's removal fade (which grows with distance
            // and with depth in a ground fog layer) needs no fog object by object.
            let fog_free = select.managed && block_scale.is_none() && {
                let far = distance + block.radius_m;
                let anchor_alt = camera.view.eye.alt_m + f64::from(local_up.dot(rel32));
                fade(far, anchor_alt - block.radius_m) < crate::detail::REMOVAL_FADE
                    && fade(far, anchor_alt + block.radius_m) < crate::detail::REMOVAL_FADE
            };
            // Beyond this distance (metres times N_e) no far object of the block can show.
            let gone_beyond = (distance - block.radius_m).max(1.0) * min_ne;
            for item in &render.items[block.items.clone()] {
                if let Some(scale) = block_scale {
                    // The block's objects come largest first, walls and fences before all:
                    // once one is too small to show from the block's nearest point, so is
                    // every one after it.
                    if !item.kind.is_linear()
                        && klod_most * scale * f64::from(item.critical_radius_m) < gone_beyond
                    {
                        break;
                    }
                }
                counts.objects_considered += 1;
                let o = item.offset_m;
                let pos = rel32 + block.east * o[0] + block.north * o[1] + block.up * o[2];
                let klod = if select.cue_important[item.kind as usize] {
                    select.klod_nominal
                } else {
                    select.klod
                };
                let blend = match block_scale {
                    Some(scale) if !item.kind.is_linear() => {
                        // N_e = K r_c / R f(v) a: gone beyond K r_c f(v) a / N_e,min.
                        let reach = klod * scale * f64::from(item.critical_radius_m);
                        let d2 = f64::from(pos.length_squared());
                        if d2 * min_ne * min_ne > reach * reach {
                            continue;
                        }
                        culture_blend(reach / d2.sqrt().max(1.0), lookup)
                    }
                    _ if select.managed => {
                        let d = f64::from(pos.length()).max(1.0);
                        if d > range_m {
                            continue;
                        }
                        let centre = pos + block.up * (0.5 * item.size_m[2]);
                        let fog = if fog_free {
                            0.0
                        } else {
                            let altitude = camera.view.eye.alt_m + f64::from(local_up.dot(centre));
                            fade(d, altitude)
                        };
                        let aoi = aoi_by_cosine.as_ref().map_or(1.0, |table| {
                            table.factor(f64::from(aim32.dot(centre) / centre.length().max(1e-6)))
                        });
                        let ne = if item.kind.is_linear() {
                            // A wall or fence is a face: Eq 17 with the ellipse of its half
                            // length and half height, seen from the eye's distance off its
                            // plane (edge on, it dissolves).
                            let [he, hn] = item.heading;
                            let face = Face {
                                centre,
                                along: block.east * he + block.north * hn,
                                normal: block.east * hn - block.north * he,
                                radii_m: [0.5 * item.size_m[1], 0.5 * item.size_m[2]],
                            };
                            ne_of_face(klod, &face, fog, aoi)
                        } else {
                            crate::detail::ne_3d(
                                klod,
                                f64::from(item.critical_radius_m),
                                d,
                                crate::detail::visibility_factor(fog),
                            ) * aoi
                        };
                        culture_blend(ne, lookup)
                    }
                    _ => LodBlend::single(0),
                };
                if blend.coverage <= 0.0 {
                    continue;
                }
                counts.objects_drawn += 1;
                let [he, hn] = item.heading;
                let forward = block.east * he + block.north * hn;
                let right = block.east * hn - block.north * he;
                let [w, l, h] = item.size_m;
                let split = blend.finer_share * blend.coverage;
                let whole = |share: f32| if share >= 1.0 { 2.0 } else { share };
                let mut push = |level: usize, from: f32, to: f32| {
                    let r = right * w;
                    let f = forward * l;
                    let u = block.up * h;
                    let index = item.kind as usize * levels + level.min(levels - 1);
                    buckets[index].push(CultureInstance {
                        col0: [r.x, r.y, r.z, from],
                        col1: [f.x, f.y, f.z, to],
                        col2: [u.x, u.y, u.z, culture_thermal_default(item.kind)],
                        origin: [pos.x, pos.y, pos.z, item.tint],
                    });
                };
                push(blend.finer, 0.0, whole(split));
                if let Some(coarser) = blend.coarser {
                    push(coarser, split, whole(blend.coverage));
                }
            }
        }
        counts
    }
}

fn ne_of_face(klod: f64, face: &Face, fade: f64, aoi_factor: f64) -> f64 {
    let Face {
        centre,
        along,
        normal,
        radii_m,
    } = *face;
    let rel = centre.as_dvec3();
    let n = normal.as_dvec3();
    let off_plane_m = rel.dot(n).abs();
    let in_plane = rel - n * rel.dot(n);
    let ground_range_m = in_plane.length();
    let theta_deg = if ground_range_m > 1e-6 {
        (in_plane.dot(along.as_dvec3()).abs() / ground_range_m)
            .clamp(0.0, 1.0)
            .acos()
            .to_degrees()
    } else {
        90.0
    };
    let effective =
        crate::detail::effective_radius_m(f64::from(radii_m[0]), f64::from(radii_m[1]), theta_deg);
    crate::detail::ne_2d(
        klod,
        effective,
        off_plane_m,
        rel.length().max(1.0),
        ground_range_m,
        crate::detail::visibility_factor(fade),
    ) * aoi_factor
}

/// The levels of a culture object at `ne`: the models' blend, except that an object is gone
/// below the table's first step (source 004 Table 3: nothing is shown below step 1) and
/// dissolves in over one doubling of `N_e` above it, so it never pops at its farthest range.
pub fn culture_blend(ne: f64, levels: &LevelLookup) -> LodBlend {
    let first = levels.table().value(1);
    if ne.is_nan() || ne < first * FADE_FROM {
        return LodBlend {
            coverage: 0.0,
            ..LodBlend::single(levels.coarsest())
        };
    }
    let mut blend = levels.levels_for(ne);
    if ne < first * FADE_TO {
        blend.coverage =
            (((ne - first * FADE_FROM) / (first * (FADE_TO - FADE_FROM))) as f32).clamp(0.0, 1.0);
    }
    blend
}

/// Turns a resident tile's culture into blocks of anchor-relative offsets.
fn make_render_tile(layout: &PyramidLayout, geoid: &GeoidLookup, tile: Arc<Tile>) -> RenderTile {
    let mut blocks = Vec::new();
    let mut items = Vec::new();
    if let Some(culture) = &tile.culture {
        let (dlat, dlon) = layout.spacing_deg(0);
        let (row0, col0) = layout.finest_index_of_post(tile.key, 0, 0);
        let south = layout.grid.south_lat_deg + row0 as f64 * dlat;
        let west = layout.grid.west_lon_deg + col0 as f64 * dlon;
        for b in CultureTile::blocks(culture) {
            let half = CULTURE_BLOCK_CELLS as f64 * 0.5;
            let fi0 = f64::from(b.block_row) * CULTURE_BLOCK_CELLS as f64 + half;
            let fj0 = f64::from(b.block_col) * CULTURE_BLOCK_CELLS as f64 + half;
            let lat = south + fi0 * dlat;
            let lon = west + fj0 * dlon;
            let undulation = geoid.undulation_m(lat, lon);
            let anchor = Geodetic::new(lat, lon, undulation);
            let enu = cig_geo::EnuFrame::new(anchor);
            let east = enu.enu_vector_to_ecef(DVec3::X).as_vec3();
            let north = enu.enu_vector_to_ecef(DVec3::Y).as_vec3();
            let up = enu.enu_vector_to_ecef(DVec3::Z).as_vec3();
            let (m_lat, m_lon) = cig_geo::metres_per_degree(lat);
            let start = items.len();
            let mut radius_m: f64 = 0.0;
            let mut max_critical_m: f32 = 0.0;
            // East and north extent of the objects about the anchor, metres.
            let mut reach = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
            for item in &culture.items[b.start..b.end] {
                let e = (f64::from(item.fj) - fj0) * dlon * m_lon;
                let n = (f64::from(item.fi) - fi0) * dlat * m_lat;
                let building_like = item.kind.is_building() || item.kind.is_linear();
                let sink = if building_like { item.sink_m } else { 0.0 };
                let up_m = f64::from(item.base_m - sink);
                let heading = item.heading_deg().to_radians();
                let critical = item.bounding_radius_m();
                let footprint = f64::from(item.footprint_radius_m());
                radius_m = radius_m.max((e * e + n * n).sqrt() + footprint);
                reach = [
                    reach[0].min(e - footprint),
                    reach[1].max(e + footprint),
                    reach[2].min(n - footprint),
                    reach[3].max(n + footprint),
                ];
                max_critical_m = max_critical_m.max(critical);
                items.push(RenderItem {
                    offset_m: [e as f32, n as f32, up_m as f32],
                    heading: [heading.sin() as f32, heading.cos() as f32],
                    size_m: [item.width_m, item.length_m, item.height_m + sink],
                    critical_radius_m: critical,
                    tint: (f32::from(item.variant) / 255.0 - 0.5) * 0.3,
                    kind: item.kind,
                });
            }
            // Walls and fences first (their N_e depends on the view), then largest first: the
            // selection stops at the first far object too small to show.
            items[start..].sort_by(|a, b| {
                b.kind
                    .is_linear()
                    .cmp(&a.kind.is_linear())
                    .then(b.critical_radius_m.total_cmp(&a.critical_radius_m))
            });
            // The vertical extent: the anchor sits at sea level, objects from their base up.
            let (low, high) = items[start..]
                .iter()
                .fold((f64::MAX, f64::MIN), |(lo, hi), it| {
                    (
                        lo.min(f64::from(it.offset_m[2])),
                        hi.max(f64::from(it.offset_m[2] + it.size_m[2])),
                    )
                });
            let vertical = low.abs().max(high.abs());
            let count = (items.len() - start).max(1) as f32;
            let mean_up_m = items[start..]
                .iter()
                .map(|it| it.offset_m[2] + 0.5 * it.size_m[2])
                .sum::<f32>()
                / count;
            blocks.push(RenderBlock {
                anchor_ecef: anchor.to_ecef(),
                east,
                north,
                up,
                radius_m: radius_m.hypot(vertical),
                max_critical_m,
                rect: GeoRect {
                    south_deg: lat + reach[2] / m_lat,
                    west_deg: lon + reach[0] / m_lon,
                    north_deg: lat + reach[3] / m_lat,
                    east_deg: lon + reach[1] / m_lon,
                },
                top_alt_m: undulation + high,
                mean_up_m,
                items: start..items.len(),
            });
        }
    }
    RenderTile {
        source: tile,
        blocks,
        items,
    }
}

/// The name a culture kind's model is registered under in a renderer.
pub fn culture_model_name(kind: CultureKind) -> String {
    format!("culture/{}", kind.name())
}

fn rgb(r: u8, g: u8, b: u8) -> [u8; 4] {
    [r, g, b, 255]
}

/// Each culture kind's thermal material for surfaces without their own code, as the
/// instance's `col2.w` (crate::thermal: the default code, no entity heat).
fn culture_thermal_default(kind: CultureKind) -> f32 {
    use cig_thermal::ThermalMaterial as M;
    let m = match kind {
        CultureKind::ConiferTree | CultureKind::BroadleafTree | CultureKind::Bush => {
            M::CanopyFoliage
        }
        CultureKind::House | CultureKind::Shed | CultureKind::LargeBuilding => M::BuildingWall,
        CultureKind::Wall => M::Rock,
        CultureKind::Fence | CultureKind::PowerPole => M::Forest,
    };
    f32::from(crate::thermal::material_code(m))
}

/// A colour whose alpha is a thermal material's code (crate::thermal): glass, bark, stone.
fn rgb_of(r: u8, g: u8, b: u8, material: cig_thermal::ThermalMaterial) -> [u8; 4] {
    [r, g, b, crate::thermal::material_code(material)]
}

/// An ellipsoid about `centre` with semi-axes `radii`, `segments` around and `rings` from pole
/// to pole (flat-shaded).
fn add_ellipsoid(
    m: &mut ModelMesh,
    centre: Vec3,
    radii: Vec3,
    segments: u32,
    rings: u32,
    colour: [u8; 4],
) {
    let point = |ring: u32, seg: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * seg as f32 / segments as f32;
        centre
            + Vec3::new(
                radii.x * theta.sin() * phi.cos(),
                radii.y * theta.sin() * phi.sin(),
                radii.z * theta.cos(),
            )
    };
    for ring in 0..rings {
        for seg in 0..segments {
            let (a, b) = (point(ring, seg), point(ring, seg + 1));
            let (c, d) = (point(ring + 1, seg + 1), point(ring + 1, seg));
            if ring == 0 {
                m.tri(a, d, c, colour);
            } else if ring + 1 == rings {
                m.tri(a, c, b, colour);
            } else {
                m.quad(a, d, c, b, colour);
            }
        }
    }
}

/// A two-sided vertical panel along y in the plane x = 0, from `z0` to `z1` (a wall's or a
/// fence's coarsest level).
fn panel(m: &mut ModelMesh, z0: f32, z1: f32, colour: [u8; 4]) {
    let v = Vec3::new;
    m.quad(
        v(0.0, -0.5, z0),
        v(0.0, 0.5, z0),
        v(0.0, 0.5, z1),
        v(0.0, -0.5, z1),
        colour,
    );
    m.quad(
        v(0.0, 0.5, z0),
        v(0.0, -0.5, z0),
        v(0.0, -0.5, z1),
        v(0.0, 0.5, z1),
        colour,
    );
}

/// A gable-roofed building in the unit box: walls to `eave` of the height, the ridge along y.
fn gabled(m: &mut ModelMesh, eave: f32, wall: [u8; 4], roof: [u8; 4]) {
    let v = Vec3::new;
    m.add_box(v(-0.5, -0.5, 0.0), v(0.5, 0.5, eave), wall);
    let (w, d, h, r) = (0.52, 0.53, eave, 1.0);
    // Counter-clockwise seen from outside: the slopes face up and out.
    m.quad(v(-w, d, h), v(-w, -d, h), v(0.0, -d, r), v(0.0, d, r), roof);
    m.quad(v(w, -d, h), v(w, d, h), v(0.0, d, r), v(0.0, -d, r), roof);
    m.tri(v(-0.5, -0.5, h), v(0.5, -0.5, h), v(0.0, -0.5, r), wall);
    m.tri(v(0.5, 0.5, h), v(-0.5, 0.5, h), v(0.0, 0.5, r), wall);
}

/// Windows and a door on a building's walls (slightly proud of them).
fn windows(m: &mut ModelMesh, eave: f32, floors: u32, per_side: u32, colour: [u8; 4]) {
    let v = Vec3::new;
    for floor in 0..floors {
        let z0 = eave * (0.18 + floor as f32 / floors as f32 * 0.9);
        let z1 = z0 + eave * 0.45 / floors as f32;
        for k in 0..per_side {
            let y = -0.5 + (k as f32 + 0.5) / per_side as f32;
            let half = 0.22 / per_side as f32;
            m.add_box(v(-0.505, y - half, z0), v(0.505, y + half, z1), colour);
        }
        m.add_box(v(-0.2, -0.505, z0), v(0.2, 0.505, z1), colour);
    }
}

/// The unit model of a culture kind, finest level first (three levels, as the built-in models).
pub fn culture_model(kind: CultureKind) -> Model {
    let v = Vec3::new;
    let bark = rgb_of(78, 60, 42, cig_thermal::ThermalMaterial::Forest);
    let lods: Vec<ModelMesh> = match kind {
        CultureKind::ConiferTree => {
            let needles = rgb(34, 66, 38);
            let dark = rgb(28, 54, 32);
            let mut l0 = ModelMesh::default();
            l0.add_cylinder(v(0.0, 0.0, -0.02), v(0.0, 0.0, 0.3), 0.06, 0.04, 6, bark);
            for (k, (z, r, h)) in [(0.16, 0.5, 0.42), (0.38, 0.4, 0.38), (0.58, 0.28, 0.42)]
                .into_iter()
                .enumerate()
            {
                let colour = if k % 2 == 0 { needles } else { dark };
                l0.add_cylinder(v(0.0, 0.0, z), v(0.0, 0.0, h), r, 0.0, 10, colour);
            }
            // Coarser levels keep the finest one's silhouette and its mean shade (a polygon
            // inscribed in a circle covers less: its radius grows to the circle's area).
            let mean = rgb(31, 60, 35);
            let mut l1 = ModelMesh::default();
            l1.add_cylinder(v(0.0, 0.0, -0.02), v(0.0, 0.0, 0.22), 0.06, 0.06, 3, bark);
            l1.add_cylinder(v(0.0, 0.0, 0.14), v(0.0, 0.0, 0.86), 0.55, 0.0, 6, mean);
            let mut l2 = ModelMesh::default();
            l2.add_cylinder(v(0.0, 0.0, 0.05), v(0.0, 0.0, 0.95), 0.6, 0.0, 4, mean);
            vec![l0, l1, l2]
        }
        CultureKind::BroadleafTree => {
            let leaves = rgb(58, 92, 42);
            let mut l0 = ModelMesh::default();
            l0.add_cylinder(v(0.0, 0.0, -0.02), v(0.0, 0.0, 0.5), 0.05, 0.035, 6, bark);
            add_ellipsoid(&mut l0, v(0.0, 0.0, 0.66), v(0.5, 0.5, 0.34), 10, 6, leaves);
            add_ellipsoid(
                &mut l0,
                v(0.18, 0.1, 0.8),
                v(0.26, 0.26, 0.2),
                6,
                4,
                rgb(66, 102, 46),
            );
            let mut l1 = ModelMesh::default();
            l1.add_cylinder(v(0.0, 0.0, -0.02), v(0.0, 0.0, 0.4), 0.05, 0.05, 3, bark);
            add_ellipsoid(&mut l1, v(0.0, 0.0, 0.66), v(0.5, 0.5, 0.34), 6, 4, leaves);
            let mut l2 = ModelMesh::default();
            add_ellipsoid(&mut l2, v(0.0, 0.0, 0.6), v(0.6, 0.6, 0.4), 4, 2, leaves);
            vec![l0, l1, l2]
        }
        CultureKind::Bush => {
            let leaves = rgb(70, 96, 48);
            let mut l0 = ModelMesh::default();
            add_ellipsoid(&mut l0, v(0.0, 0.0, 0.5), v(0.5, 0.5, 0.5), 8, 5, leaves);
            let mut l1 = ModelMesh::default();
            add_ellipsoid(&mut l1, v(0.0, 0.0, 0.5), v(0.5, 0.5, 0.5), 5, 3, leaves);
            let mut l2 = ModelMesh::default();
            add_ellipsoid(&mut l2, v(0.0, 0.0, 0.45), v(0.5, 0.5, 0.45), 3, 2, leaves);
            vec![l0, l1, l2]
        }
        CultureKind::House | CultureKind::Shed => {
            let (wall, roof, eave) = if kind == CultureKind::House {
                (rgb(206, 196, 176), rgb(140, 62, 48), 0.62)
            } else {
                (rgb(150, 124, 96), rgb(92, 92, 96), 0.7)
            };
            let mut l0 = ModelMesh::default();
            gabled(&mut l0, eave, wall, roof);
            let floors = if kind == CultureKind::House { 2 } else { 1 };
            windows(
                &mut l0,
                eave,
                floors,
                3,
                rgb_of(52, 58, 66, cig_thermal::ThermalMaterial::Glass),
            );
            if kind == CultureKind::House {
                l0.add_box(v(0.2, 0.15, 0.7), v(0.3, 0.25, 1.02), rgb(120, 70, 60));
            }
            let mut l1 = ModelMesh::default();
            gabled(&mut l1, eave, wall, roof);
            // The coarsest: four walls and the roof, no floor or ceiling.
            let mut l2 = ModelMesh::default();
            let p = |x: f32, y: f32, z: f32| v(x * 0.5, y * 0.5, z);
            for (a, b) in [
                ((-1.0, -1.0), (1.0, -1.0)),
                ((1.0, -1.0), (1.0, 1.0)),
                ((1.0, 1.0), (-1.0, 1.0)),
                ((-1.0, 1.0), (-1.0, -1.0)),
            ] {
                l2.quad(
                    p(a.0, a.1, 0.0),
                    p(b.0, b.1, 0.0),
                    p(b.0, b.1, eave),
                    p(a.0, a.1, eave),
                    wall,
                );
            }
            l2.quad(
                v(-0.5, 0.5, eave),
                v(-0.5, -0.5, eave),
                v(0.0, -0.5, 1.0),
                v(0.0, 0.5, 1.0),
                roof,
            );
            l2.quad(
                v(0.5, -0.5, eave),
                v(0.5, 0.5, eave),
                v(0.0, 0.5, 1.0),
                v(0.0, -0.5, 1.0),
                roof,
            );
            vec![l0, l1, l2]
        }
        CultureKind::LargeBuilding => {
            let wall = rgb(176, 172, 164);
            let roof = rgb(96, 96, 100);
            let mut l0 = ModelMesh::default();
            l0.add_box(v(-0.5, -0.5, 0.0), v(0.5, 0.5, 0.96), wall);
            l0.add_box(v(-0.48, -0.48, 0.96), v(0.48, 0.48, 1.0), roof);
            windows(
                &mut l0,
                0.96,
                4,
                6,
                rgb_of(60, 70, 84, cig_thermal::ThermalMaterial::Glass),
            );
            let mut l1 = ModelMesh::default();
            l1.add_box(v(-0.5, -0.5, 0.0), v(0.5, 0.5, 0.96), wall);
            l1.add_box(v(-0.48, -0.48, 0.96), v(0.48, 0.48, 1.0), roof);
            let mut l2 = ModelMesh::default();
            l2.add_box(v(-0.5, -0.5, 0.0), v(0.5, 0.5, 1.0), wall);
            vec![l0, l1, l2]
        }
        CultureKind::Wall => {
            let stone = rgb(150, 140, 124);
            let mut l0 = ModelMesh::default();
            l0.add_box(v(-0.5, -0.5, 0.0), v(0.5, 0.5, 0.92), stone);
            l0.add_box(v(-0.6, -0.5, 0.92), v(0.6, 0.5, 1.0), rgb(128, 120, 108));
            let mut l1 = ModelMesh::default();
            l1.add_box(v(-0.5, -0.5, 0.0), v(0.5, 0.5, 1.0), stone);
            let mut l2 = ModelMesh::default();
            panel(&mut l2, 0.0, 1.0, stone);
            vec![l0, l1, l2]
        }
        CultureKind::Fence => {
            let wood = rgb(112, 92, 70);
            let mut l0 = ModelMesh::default();
            for k in 0..5 {
                let y = -0.5 + k as f32 * 0.25;
                l0.add_box(v(-0.5, y - 0.008, 0.0), v(0.5, y + 0.008, 1.0), wood);
            }
            for z in [0.45, 0.85] {
                l0.add_box(v(-0.2, -0.5, z), v(0.2, 0.5, z + 0.05), wood);
            }
            let mut l1 = ModelMesh::default();
            for y in [-0.5, 0.0, 0.5] {
                l1.add_box(v(-0.5, y - 0.01, 0.0), v(0.5, y + 0.01, 1.0), wood);
            }
            l1.add_box(v(-0.2, -0.5, 0.8), v(0.2, 0.5, 0.86), wood);
            let mut l2 = ModelMesh::default();
            panel(&mut l2, 0.8, 0.86, wood);
            vec![l0, l1, l2]
        }
        CultureKind::PowerPole => {
            let wood = rgb(96, 76, 56);
            let mut l0 = ModelMesh::default();
            l0.add_cylinder(v(0.0, 0.0, -0.02), v(0.0, 0.0, 1.02), 0.5, 0.4, 8, wood);
            l0.add_box(v(-3.5, -0.3, 0.88), v(3.5, 0.3, 0.91), wood);
            for x in [-3.0, 0.0, 3.0] {
                l0.add_box(
                    v(x - 0.2, -0.2, 0.91),
                    v(x + 0.2, 0.2, 0.94),
                    rgb(200, 200, 190),
                );
            }
            let mut l1 = ModelMesh::default();
            l1.add_cylinder(v(0.0, 0.0, -0.02), v(0.0, 0.0, 1.02), 0.5, 0.4, 4, wood);
            l1.add_box(v(-3.5, -0.3, 0.88), v(3.5, 0.3, 0.91), wood);
            let mut l2 = ModelMesh::default();
            l2.add_cylinder(v(0.0, 0.0, 0.0), v(0.0, 0.0, 1.0), 0.5, 0.5, 3, wood);
            vec![l0, l1, l2]
        }
    };
    Model::new(&culture_model_name(kind), lods)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_culture_model_has_three_levels_getting_coarser_in_the_unit_box() {
        for kind in CultureKind::ALL {
            let m = culture_model(kind);
            assert_eq!(m.lods.len(), 3, "{kind}");
            let tris: Vec<usize> = m.lods.iter().map(ModelMesh::triangle_count).collect();
            assert!(tris[0] > tris[1] && tris[1] > tris[2], "{kind}: {tris:?}");
            for lod in &m.lods {
                assert!(lod
                    .indices
                    .iter()
                    .all(|&i| (i as usize) < lod.vertices.len()));
                for vtx in &lod.vertices {
                    let [x, y, z] = vtx.position;
                    // The pole's cross-arm reaches out 3.5 pole widths.
                    let reach = if kind == CultureKind::PowerPole {
                        3.6
                    } else {
                        0.61
                    };
                    assert!(x.abs() <= reach && y.abs() <= 0.61, "{kind}: {x} {y}");
                    assert!((-0.03..=1.03).contains(&z), "{kind}: z {z}");
                }
            }
        }
    }

    #[test]
    fn a_wall_is_a_face_of_eq_17_seen_face_on_and_dissolving_edge_on() {
        // A 20 m x 2 m wall along x, 100 m ahead (y), seen face on.
        let (along, normal) = (Vec3::X, Vec3::Y);
        let face_on = ne_of_face(
            1467.0,
            &Face {
                centre: Vec3::new(0.0, 100.0, 0.0),
                along,
                normal,
                radii_m: [10.0, 1.0],
            },
            0.0,
            1.0,
        );
        // Eq 17 with R_g = 0: K r_e H / R_s^2 = K r_e / R_s, r_e the short radius.
        assert!((face_on - 1467.0 * 1.0 / 100.0).abs() < 1e-6, "{face_on}");
        // Edge on (the eye in its plane) it has no size; obliquely, between.
        let edge_on = ne_of_face(
            1467.0,
            &Face {
                centre: Vec3::new(100.0, 0.0, 0.0),
                along,
                normal,
                radii_m: [10.0, 1.0],
            },
            0.0,
            1.0,
        );
        assert_eq!(edge_on, 0.0);
        let oblique = ne_of_face(
            1467.0,
            &Face {
                centre: Vec3::new(70.7, 70.7, 0.0),
                along,
                normal,
                radii_m: [10.0, 1.0],
            },
            0.0,
            1.0,
        );
        // Obliquely its long radius faces the eye's foot (Eq 15): more than face on, at most
        // the long radius's N_e of a 3-D model.
        assert!(
            oblique > face_on && oblique < 1467.0 * 10.0 / 100.0 * 1.2,
            "{oblique}"
        );
        // Removed in the fog at 98 % fade.
        let fogged = ne_of_face(
            1467.0,
            &Face {
                centre: Vec3::new(0.0, 100.0, 0.0),
                along,
                normal,
                radii_m: [10.0, 1.0],
            },
            0.985,
            1.0,
        );
        assert_eq!(fogged, 0.0);
    }

    #[test]
    fn every_roof_slope_faces_up_and_out() {
        // A roof wound the wrong way is lit from inside: black in the picture.
        for kind in [CultureKind::House, CultureKind::Shed] {
            for (level, lod) in culture_model(kind).lods.iter().enumerate() {
                let mut slopes = 0;
                for tri in lod.indices.chunks_exact(3) {
                    let p: Vec<Vec3> = tri
                        .iter()
                        .map(|&i| Vec3::from(lod.vertices[i as usize].position))
                        .collect();
                    let centroid = (p[0] + p[1] + p[2]) / 3.0;
                    let normal = Vec3::from(lod.vertices[tri[0] as usize].normal);
                    let sloped = normal.x.abs() > 0.1 && normal.z.abs() > 0.1;
                    if centroid.z > 0.72 && sloped {
                        slopes += 1;
                        assert!(
                            normal.z > 0.0 && normal.x * centroid.x > 0.0,
                            "{kind} level {level}: roof at {centroid} has normal {normal}"
                        );
                    }
                }
                assert!(slopes >= 4, "{kind} level {level}: {slopes} roof triangles");
            }
        }
    }

    #[test]
    fn culture_dissolves_over_one_doubling_above_the_first_step() {
        let table = crate::detail::DetailTable::default();
        let lookup = LevelLookup::new(&table, 3);
        let first = table.value(1);
        assert_eq!(culture_blend(first * 0.99, &lookup).coverage, 0.0);
        assert_eq!(culture_blend(f64::NAN, &lookup).coverage, 0.0);
        let mid = culture_blend(first * 1.5, &lookup);
        assert!((mid.coverage - 0.5).abs() < 1e-5, "{mid:?}");
        assert_eq!(mid.finer, 2, "the coarsest level dissolves");
        assert_eq!(culture_blend(first * 2.01, &lookup).coverage, 1.0);
        // Coverage never jumps as N_e falls slowly.
        let mut last = 1.0_f32;
        for k in 0..600 {
            let ne = first * 2.4 - f64::from(k) * first * 0.003;
            let c = culture_blend(ne, &lookup).coverage;
            assert!(
                last - c <= 0.01 && c <= last + 1e-6,
                "N_e {ne}: {last} -> {c}"
            );
            last = c;
        }
        assert_eq!(last, 0.0);
    }
}
