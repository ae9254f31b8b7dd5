//! Terrain paging: keeps the tiles around every eyepoint resident, loads on worker threads,
//! never blocks its caller on the store, and stays under a memory budget.
//!
//! Source: NPSNET (source 003, "Terrain paging"): a 16 x 16 km active area around the viewer
//! is kept in memory and paged on other processors while the simulation goes on; the area moves
//! only when the viewer leaves a 1200 m box around its centre, so a viewer going back and forth
//! across a 1000 m data boundary must travel 200 m back before anything is paged out again.
//! Here the same rule holds for any number of eyepoints, with every size configurable: the
//! active area of level `k` is `active_area_m * ring_growth^k` wide (concentric resolution
//! rings, as NPSNET drew coarser terrain farther out), the top tile is wanted first and then every
//! level's tiles by their distance from the eye in units of that level's ring, so a tight budget
//! trims the outer parts of every ring; whatever does not fit the budget is not requested.
//! Tiles no eyepoint wants are evicted least-recently-used first. The wanted list is worked out
//! again only when an active area moves, so a frame's update is a walk over it.
//!
//! Memory accounting: resident tiles plus tiles being loaded never exceed `budget_bytes`
//! less what other terrain data paged around the same eyes holds ([`TileCache::reserve`]: the
//! renderer's imagery clipmap), so one budget covers both (a load reserves its bytes before
//! it is issued). A tile that fails to load (missing,
//! unreadable, checksum mismatch) is logged once and never retried; lookups fall back to its
//! parent level.
//!
//! Limits: the active areas are squares in a local metric frame at the database centre, which is
//! accurate for databases up to a few hundred km; query sessions may keep a tile they are using
//! alive for a moment after it is evicted.

use crate::database::{LoadError, TerrainDatabase};
use crate::edits::EditLayer;
use crate::pyramid::TileKey;
use crate::tile::{quadtree_depth_for, tile_memory_bytes, Tile};
use cig_geo::Geodetic;
use crossbeam_channel::{Receiver, Sender};
use parking_lot::Mutex;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Paging configuration (the `[paging]` table of the configuration file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PagingConfig {
    /// Side of the finest level's square active area around each eyepoint, metres.
    pub active_area_m: f64,
    /// Side of the hysteresis box around the active area's centre, metres.
    pub hysteresis_box_m: f64,
    /// The active area's centre moves in steps of this size, metres.
    pub recenter_step_m: f64,
    /// Growth of the active area from one level to the next coarser one.
    pub ring_growth: f64,
    /// Most bytes of resident (and loading) tiles.
    pub budget_bytes: u64,
    /// Threads that read tiles.
    pub worker_threads: usize,
}

impl Default for PagingConfig {
    fn default() -> Self {
        PagingConfig {
            active_area_m: 16_000.0,
            hysteresis_box_m: 1_200.0,
            recenter_step_m: 1_000.0,
            ring_growth: 2.0,
            budget_bytes: 512 * 1024 * 1024,
            worker_threads: 2,
        }
    }
}

/// Fewest tiles a paging budget must hold.
pub const MIN_BUDGET_TILES: u64 = 16;

/// A paging configuration that cannot work.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PagingConfigError {
    #[error("paging.{name} = {value} must be {rule}")]
    Invalid {
        name: &'static str,
        value: String,
        rule: &'static str,
    },
    #[error("paging.budget_bytes = {budget_bytes} must hold at least {MIN_BUDGET_TILES} tiles of this database ({min_bytes} bytes)")]
    BudgetTooSmall { budget_bytes: u64, min_bytes: u64 },
}

impl PagingConfig {
    /// Checks the configuration.
    pub fn validate(&self) -> Result<(), PagingConfigError> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(PagingConfigError::Invalid {
                    name,
                    value: v.to_string(),
                    rule: "a positive number",
                })
            }
        };
        positive("active_area_m", self.active_area_m)?;
        positive("hysteresis_box_m", self.hysteresis_box_m)?;
        positive("recenter_step_m", self.recenter_step_m)?;
        if !(self.ring_growth.is_finite() && self.ring_growth >= 1.0) {
            return Err(PagingConfigError::Invalid {
                name: "ring_growth",
                value: self.ring_growth.to_string(),
                rule: "at least 1",
            });
        }
        if self.hysteresis_box_m <= self.recenter_step_m {
            return Err(PagingConfigError::Invalid {
                name: "hysteresis_box_m",
                value: self.hysteresis_box_m.to_string(),
                rule: "larger than recenter_step_m (a box no larger thrashes)",
            });
        }

        if !(1..=64).contains(&self.worker_threads) {
            return Err(PagingConfigError::Invalid {
                name: "worker_threads",
                value: self.worker_threads.to_string(),
                rule: "from 1 to 64",
            });
        }
        Ok(())
    }
}

/// Counters of the cache's work so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct CacheStats {
    pub resident_tiles: usize,
    pub resident_bytes: u64,
    pub in_flight: usize,
    pub loads_completed: u64,
    pub loads_failed: u64,
    pub evictions: u64,
    pub active_area_moves: u64,
}

struct Resident {
    tile: Arc<Tile>,
    last_used: u64,
}

#[derive(Default)]
struct State {
    resident: HashMap<TileKey, Resident>,
    in_flight: HashSet<TileKey>,
    failed: HashMap<TileKey, String>,
    wanted: HashSet<TileKey>,
    /// The wanted tiles in priority order (recomputed when an active area moves).
    wanted_order: Vec<TileKey>,
    resident_bytes: u64,
    clock: u64,
    areas: Vec<Option<(f64, f64)>>,
    stats: CacheStats,
}

/// (north, east) metres in the paging frame.
type LocalM = (f64, f64);

impl State {
    fn snapshot(&self) -> CacheStats {
        CacheStats {
            resident_tiles: self.resident.len(),
            resident_bytes: self.resident_bytes,
            in_flight: self.in_flight.len(),
            ..self.stats
        }
    }
}

/// Part of a cache's paging budget held for other data ([`TileCache::reserve`]); given back
/// when dropped.
#[derive(Debug)]
pub struct BudgetReservation {
    counter: Arc<AtomicU64>,
    bytes: u64,
}

impl BudgetReservation {
    /// The bytes granted.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

impl Drop for BudgetReservation {
    fn drop(&mut self) {
        self.counter.fetch_sub(self.bytes, Ordering::AcqRel);
    }
}

/// The paging tile cache over one database.
pub struct TileCache {
    db: Arc<TerrainDatabase>,
    config: PagingConfig,
    state: Mutex<State>,
    requests: Option<Sender<TileKey>>,
    completions: Receiver<(TileKey, Result<Tile, LoadError>)>,
    workers: Vec<std::thread::JoinHandle<()>>,
    tile_bytes: u64,
    /// Bytes a finest tile's culture may take at most (counted with every finest tile).
    culture_tile_bytes: u64,
    /// Bytes of the budget held by [`BudgetReservation`]s.
    reserved: Arc<AtomicU64>,
    eviction_epoch: AtomicU64,
    /// Metres per degree (north, east) at the database centre: the paging frame.
    metres_per_deg: (f64, f64),
    /// The terrain edits on top of the tiles (`crate::edits`), swapped whole.
    edits: parking_lot::RwLock<Arc<EditLayer>>,
    /// Grows by one each time the edits are swapped.
    edits_revision: AtomicU64,
}

impl TileCache {
    /// Starts the cache and its worker threads.
    pub fn new(
        db: Arc<TerrainDatabase>,
        config: PagingConfig,
    ) -> Result<TileCache, PagingConfigError> {
        config.validate()?;
        let layout = *db.layout();
        let tile_bytes = tile_memory_bytes(
            layout.posts_per_side(),
            quadtree_depth_for(layout.tile_cells as usize),
        ) as u64;
        let culture_tile_bytes = db
            .manifest()
            .culture
            .as_ref()
            .map_or(0, |c| c.max_tile_bytes());
        let tile_bytes_with_culture = tile_bytes + culture_tile_bytes;
        if config.budget_bytes < MIN_BUDGET_TILES * tile_bytes_with_culture {
            return Err(PagingConfigError::BudgetTooSmall {
                budget_bytes: config.budget_bytes,
                min_bytes: MIN_BUDGET_TILES * tile_bytes_with_culture,
            });
        }
        let (req_tx, req_rx) = crossbeam_channel::unbounded::<TileKey>();
        let (done_tx, done_rx) = crossbeam_channel::unbounded();
        let workers = (0..config.worker_threads)
            .map(|n| {
                let rx = req_rx.clone();
                let tx = done_tx.clone();
                let db = Arc::clone(&db);
                std::thread::Builder::new()
                    .name(format!("cig-pager-{n}"))
                    .spawn(move || {
                        while let Ok(key) = rx.recv() {
                            if tx.send((key, db.load_tile(key))).is_err() {
                                break;
                            }
                        }
                    })
            })
            .filter_map(Result::ok)
            .collect();
        let centre_lat = 0.5 * (layout.grid.south_lat_deg + layout.grid.north_lat_deg());
        Ok(TileCache {
            db,
            config,
            state: Mutex::new(State::default()),
            requests: Some(req_tx),
            completions: done_rx,
            workers,
            tile_bytes,
            culture_tile_bytes,
            reserved: Arc::new(AtomicU64::new(0)),
            eviction_epoch: AtomicU64::new(0),
            metres_per_deg: cig_geo::metres_per_degree(centre_lat),
            edits: parking_lot::RwLock::new(Arc::new(EditLayer::new(
                layout.grid,
                layout.tile_cells,
            ))),
            edits_revision: AtomicU64::new(0),
        })
    }

    /// The terrain edits every query and mesh of this database sees.
    pub fn edits(&self) -> Arc<EditLayer> {
        Arc::clone(&self.edits.read())
    }

    /// Replaces the terrain edits: queries see them from their next call.
    pub fn set_edits(&self, edits: Arc<EditLayer>) {
        *self.edits.write() = edits;
        self.edits_revision.fetch_add(1, Ordering::Release);
    }

    /// Changes the edits in place (applies or heals under the lock, so concurrent changes are
    /// not lost) and returns what `change` returned.
    pub fn update_edits<T>(&self, change: impl FnOnce(&mut EditLayer) -> T) -> T {
        let mut guard = self.edits.write();
        let before = guard.revision();
        let result = change(Arc::make_mut(&mut guard));
        // Queries and meshes move on only when the surface changed (a re-announced edit does
        // not change it).
        if guard.revision() != before {
            self.edits_revision.fetch_add(1, Ordering::Release);
        }
        result
    }

    /// Grows by one each time the edits change.
    pub fn edits_revision(&self) -> u64 {
        self.edits_revision.load(Ordering::Acquire)
    }

    pub fn database(&self) -> &Arc<TerrainDatabase> {
        &self.db
    }

    /// Holds up to `bytes` of the paging budget for other data paged around the same eyes
    /// (the renderer's imagery clipmap), for as long as the returned reservation lives; the
    /// tiles get the rest. At most what leaves room for the minimum of tiles is granted
    /// ([`BudgetReservation::bytes`] says how much).
    pub fn reserve(&self, bytes: u64) -> BudgetReservation {
        let floor = MIN_BUDGET_TILES * self.tile_bytes;
        let mut granted = 0;
        let _ = self
            .reserved
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |held| {
                let room = self.config.budget_bytes.saturating_sub(floor + held);
                granted = bytes.min(room);
                Some(held + granted)
            });
        BudgetReservation {
            counter: Arc::clone(&self.reserved),
            bytes: granted,
        }
    }

    /// The part of the budget the tiles may use: the budget less the reservations.
    pub fn tile_budget_bytes(&self) -> u64 {
        self.config
            .budget_bytes
            .saturating_sub(self.reserved.load(Ordering::Acquire))
    }

    pub fn config(&self) -> &PagingConfig {
        &self.config
    }

    /// Bytes one resident tile counts against the budget (a finest tile also counts its
    /// culture: [`TileCache::bytes_of`]).
    pub fn tile_bytes(&self) -> u64 {
        self.tile_bytes
    }

    /// Bytes tile `key` counts against the budget: a finest tile counts the most its culture
    /// may take besides its posts.
    pub fn bytes_of(&self, key: TileKey) -> u64 {
        if key.level == 0 {
            self.tile_bytes + self.culture_tile_bytes
        } else {
            self.tile_bytes
        }
    }

    pub fn stats(&self) -> CacheStats {
        self.state.lock().snapshot()
    }

    /// Number of evictions so far; query sessions drop their tile references when it changes.
    pub fn eviction_epoch(&self) -> u64 {
        self.eviction_epoch.load(Ordering::Relaxed)
    }

    /// One paging step for this frame: takes in finished loads, moves active areas, requests
    /// what the eyepoints need and evicts what none needs. Never waits for a load.
    pub fn update(&self, eyepoints: &[Geodetic]) -> CacheStats {
        let mut s = self.state.lock();
        s.clock += 1;
        while let Ok((key, result)) = self.completions.try_recv() {
            self.finish_load(&mut s, key, result);
        }
        // The wanted list changes only when an active area moves or eyepoints come and go.
        let mut moved = s.areas.len() != eyepoints.len();
        s.areas.resize(eyepoints.len(), None);
        let mut eyes_m = Vec::with_capacity(eyepoints.len());
        for (n, eye) in eyepoints.iter().enumerate() {
            let (north_m, east_m) = self.to_local_m(eye.lat_deg, eye.lon_deg);
            let centre = match s.areas[n] {
                Some((cn, ce))
                    if (north_m - cn).abs() <= 0.5 * self.config.hysteresis_box_m
                        && (east_m - ce).abs() <= 0.5 * self.config.hysteresis_box_m =>
                {
                    (cn, ce)
                }
                previous => {
                    let step = self.config.recenter_step_m;
                    let c = (
                        (north_m / step).round() * step,
                        (east_m / step).round() * step,
                    );
                    if previous.is_some() {
                        s.stats.active_area_moves += 1;
                    }
                    s.areas[n] = Some(c);
                    moved = true;
                    c
                }
            };
            eyes_m.push((centre, (north_m, east_m)));
        }
        if moved {
            self.plan_wanted(&mut s, &eyes_m);
        }
        let clock = s.clock;
        let State {
            resident,
            in_flight,
            failed,
            wanted_order,
            ..
        } = &mut *s;
        let mut to_request = Vec::new();
        for key in wanted_order.iter() {
            if let Some(r) = resident.get_mut(key) {
                r.last_used = clock;
            } else if !in_flight.contains(key) && !failed.contains_key(key) {
                to_request.push(*key);
            }
        }
        for key in to_request {
            if !self.make_room(&mut s, self.bytes_of(key)) {
                break;
            }
            if let Some(tx) = &self.requests {
                if tx.send(key).is_ok() {
                    s.in_flight.insert(key);
                }
            }
        }
        // Tiles nobody wants stay as a least-recently-used cache until room is needed.
        s.snapshot()
    }

    /// Recomputes the wanted tiles, in priority order, from the active areas.
    fn plan_wanted(&self, s: &mut State, eyes_m: &[(LocalM, LocalM)]) {
        let mut wanted = Vec::new();
        for &(centre, eye) in eyes_m {
            self.wanted_for(centre, eye, &mut wanted);
        }
        // The single top tile first (the fallback everywhere), then by distance from the eye in
        // units of each level's ring size, so that every ring keeps its nearest tiles and a
        // tight budget trims the rings' outer parts; cut at the budget.
        wanted.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.2.cmp(&b.2)));
        let capacity = (self.tile_budget_bytes() / self.tile_bytes.max(1)) as usize;
        s.wanted.clear();
        s.wanted_order.clear();
        for (_, _, key) in wanted {
            if s.wanted.len() >= capacity {
                break;
            }
            if s.wanted.insert(key) {
                s.wanted_order.push(key);
            }
        }
    }

    /// Requests tiles a renderer wants beyond the active areas (e.g. finer levels of distant
    /// terrain a narrow view resolves), nearest first as given, at most `max` new loads. It
    /// evicts only tiles no eyepoint wants and nobody used in the current paging step, and never
    /// waits. Returns the number of loads requested.
    pub fn prefetch(&self, keys: &[TileKey], max: usize) -> usize {
        let mut s = self.state.lock();
        let clock = s.clock;
        let mut sent = 0;
        for &key in keys {
            if sent >= max {
                break;
            }
            if !self.db.layout().contains_key(key)
                || s.resident.contains_key(&key)
                || s.in_flight.contains(&key)
                || s.failed.contains_key(&key)
            {
                continue;
            }
            if !self.make_room_sparing(&mut s, self.bytes_of(key), clock) {
                break;
            }
            if let Some(tx) = &self.requests {
                if tx.send(key).is_ok() {
                    s.in_flight.insert(key);
                    sent += 1;
                }
            }
        }
        sent
    }

    /// Waits until no load is in flight (for tests, benchmarks and start-up), then takes them in.
    pub fn wait_idle(&self) {
        loop {
            {
                let mut s = self.state.lock();
                while let Ok((key, result)) = self.completions.try_recv() {
                    self.finish_load(&mut s, key, result);
                }
                if s.in_flight.is_empty() {
                    return;
                }
            }
            if let Ok((key, result)) = self
                .completions
                .recv_timeout(std::time::Duration::from_millis(50))
            {
                let mut s = self.state.lock();
                self.finish_load(&mut s, key, result);
            }
        }
    }

    /// The resident tile for `key`, if any (marks it used).
    pub fn resident(&self, key: TileKey) -> Option<Arc<Tile>> {
        let mut s = self.state.lock();
        let clock = s.clock;
        s.resident.get_mut(&key).map(|r| {
            r.last_used = clock;
            Arc::clone(&r.tile)
        })
    }

    /// The finest resident tile covering a level-0 tile's area, walking up the levels: what a
    /// renderer draws while finer tiles are still loading.
    pub fn best_resident(&self, level0: TileKey) -> Option<Arc<Tile>> {
        let mut key = level0;
        loop {
            if let Some(t) = self.resident(key) {
                return Some(t);
            }
            if key.level + 1 >= self.db.layout().levels {
                return None;
            }
            key = key.parent();
        }
    }

    /// The tile for `key`, loading it in the calling thread if it is not resident (queries may
    /// wait for the finest tile). A tile that fails is logged once and remembered as failed.
    pub fn load_now(&self, key: TileKey) -> Result<Arc<Tile>, LoadError> {
        self.load_now_reporting(key).map(|(tile, _)| tile)
    }

    /// [`TileCache::load_now`], also saying whether the tile is held by the cache (`false`: it
    /// did not fit the budget and lives only as long as the caller keeps it).
    pub fn load_now_reporting(&self, key: TileKey) -> Result<(Arc<Tile>, bool), LoadError> {
        if let Some(t) = self.resident(key) {
            return Ok((t, true));
        }
        if let Some(reason) = self.state.lock().failed.get(&key) {
            return Err(LoadError::Store(crate::database::StoreError::Io {
                reason: format!("failed earlier ({reason})"),
                location: self.db.tile_location(key),
            }));
        }
        let result = self.db.load_tile(key);
        let mut s = self.state.lock();
        match result {
            Ok(tile) => {
                let tile = Arc::new(tile);
                if let Some(r) = s.resident.get(&key) {
                    return Ok((Arc::clone(&r.tile), true));
                }
                // Room is made from tiles no eyepoint wants; a query never evicts what the
                // eyepoints need. Without room the tile serves this query uncached.
                let cached = self.make_room(&mut s, self.bytes_of(key));
                if cached {
                    self.insert_resident(&mut s, key, Arc::clone(&tile));
                    s.stats.loads_completed += 1;
                }
                Ok((tile, cached))
            }
            Err(e) => {
                self.record_failure(&mut s, key, &e);
                Err(e)
            }
        }
    }

    fn finish_load(&self, s: &mut State, key: TileKey, result: Result<Tile, LoadError>) {
        if !s.in_flight.remove(&key) {
            return;
        }
        match result {
            Ok(tile) => {
                s.stats.loads_completed += 1;
                if s.resident.contains_key(&key) {
                    return;
                }
                // The bytes were reserved when the load was issued.
                self.insert_resident(s, key, Arc::new(tile));
            }
            Err(e) => self.record_failure(s, key, &e),
        }
    }

    /// Makes `tile` resident; the caller has made room for it.
    fn insert_resident(&self, s: &mut State, key: TileKey, tile: Arc<Tile>) {
        let last_used = s.clock;
        s.resident_bytes += self.bytes_of(key);
        s.resident.insert(key, Resident { tile, last_used });
    }

    fn record_failure(&self, s: &mut State, key: TileKey, e: &LoadError) {
        if s.failed.insert(key, e.to_string()).is_none() {
            s.stats.loads_failed += 1;
            tracing::warn!(tile = %key, "terrain tile skipped, served from a coarser level: {e}");
        }
    }

    /// Evicts least-recently-used tiles until `bytes` more fit under the budget (counting loads
    /// in flight). Only tiles no eyepoint wants are evicted.
    fn make_room(&self, s: &mut State, bytes: u64) -> bool {
        self.make_room_sparing(s, bytes, u64::MAX)
    }

    /// [`TileCache::make_room`], also sparing tiles used at or after paging step `used_since`.
    fn make_room_sparing(&self, s: &mut State, bytes: u64, used_since: u64) -> bool {
        let budget = self.tile_budget_bytes();
        let in_flight: u64 = s.in_flight.iter().map(|&k| self.bytes_of(k)).sum();
        while s.resident_bytes + in_flight + bytes > budget {
            let victim = s
                .resident
                .iter()
                .filter(|(k, r)| !s.wanted.contains(k) && r.last_used < used_since)
                .min_by_key(|(k, r)| (r.last_used, **k))
                .map(|(k, _)| *k);
            let Some(victim) = victim else {
                return false;
            };
            if s.resident.remove(&victim).is_some() {
                s.resident_bytes -= self.bytes_of(victim);
                s.stats.evictions += 1;
                self.eviction_epoch.fetch_add(1, Ordering::Relaxed);
            }
        }
        true
    }

    fn to_local_m(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        let g = &self.db.layout().grid;
        (
            (lat_deg - g.south_lat_deg) * self.metres_per_deg.0,
            (lon_deg - g.west_lon_deg) * self.metres_per_deg.1,
        )
    }

    /// Adds (level, distance from eye, key) for every tile of every level's ring.
    fn wanted_for(&self, centre: LocalM, eye: LocalM, out: &mut Vec<(u8, f64, TileKey)>) {
        let layout = self.db.layout();
        for level in 0..layout.levels {
            let half =
                0.5 * self.config.active_area_m * self.config.ring_growth.powi(i32::from(level));
            let (dlat, dlon) = layout.spacing_deg(level);
            let tile_n_m = dlat * f64::from(layout.tile_cells) * self.metres_per_deg.0;
            let tile_e_m = dlon * f64::from(layout.tile_cells) * self.metres_per_deg.1;
            let (rows, cols) = layout.tiles_at(level);
            let range = |lo: f64, hi: f64, size: f64, count: u32| -> Option<(u32, u32)> {
                let first = (lo / size).floor().max(0.0);
                let last = ((hi / size).ceil() - 1.0).min(f64::from(count) - 1.0);
                (first <= last).then_some((first as u32, last as u32))
            };
            let Some((r0, r1)) = range(centre.0 - half, centre.0 + half, tile_n_m, rows) else {
                continue;
            };
            let Some((c0, c1)) = range(centre.1 - half, centre.1 + half, tile_e_m, cols) else {
                continue;
            };
            for row in r0..=r1 {
                for col in c0..=c1 {
                    let cn = (f64::from(row) + 0.5) * tile_n_m;
                    let ce = (f64::from(col) + 0.5) * tile_e_m;
                    let d = (cn - eye.0).abs().max((ce - eye.1).abs()) / half;
                    let priority = if level + 1 == layout.levels { -1.0 } else { d };
                    out.push((level, priority, TileKey { level, row, col }));
                }
            }
        }
    }
}

impl Drop for TileCache {
    fn drop(&mut self) {
        self.requests = None;
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}
