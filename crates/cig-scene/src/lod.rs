//! Terrain level of detail: a quadtree of nodes over the database pyramid, selected each frame
//! by screen-space geometric error, with continuous vertex morphing between levels.
//!
//! Algorithm: Strugar's continuous distance-dependent level of detail (CDLOD, 2010) adapted to
//! error-driven ranges on a round earth. Every node covers `node_cells` cells of its pyramid
//! level; a node of level `L` has four children of level `L - 1`. A node whose geometric error
//! `e` (the exact vertical error of its level against the finest posts, stored in each tile's
//! min/max/error quadtree) would cover more than the allowed pixels anywhere in its bounding box
//! is refined; its error distance is `R = e * K / max_pixel_error` with `K` the view's pixels
//! per unit tangent, so a narrow (e.g. 6x periscope) view or a bigger frame refines further.
//! A node refines when its box comes nearer than `RANGE_MARGIN * R`; a drawn node's vertices
//! morph from its own grid at its own range to the parent's grid at the parent's range from the
//! eye, so the drawn surface changes continuously as the eye moves (the gradual transition of
//! the GE study, source 004 section 4.7). The band needs no room past the parent's range: a
//! vertex a fraction `t` of the way through it shows at most `(1 - t) e + t e_parent` of error,
//! which is the error `d / K` allowed at its distance `d = R + t (R_parent - R)`. The small
//! `RANGE_MARGIN` (1.05) covers the morph factor being taken per vertex rather than per point
//! (without it a point inside a triangle showed up to 1.3 % more). CDLOD's fixed morph regions
//! (refining at 1.3 R) drew 1.29 times the triangles on the demo pass. Nodes are culled against
//! the frustum with the per-node min/max heights (source 003: quadtree culling). Node boxes are
//! built from 9 sample points at the lowest and highest heights, in the node's local
//! east-north-up frame, so curvature is included.
//!
//! Round earth: triangles are straight chords through ECEF between posts on the curved
//! ellipsoid, so every error also counts the chord sag of the triangles it stands for
//! ([`NodeLayout::post_sag_m`]: a post's error at least its triangles' sag, a node's at least
//! its level's cells'). Without it a flat sea, whose posts carry no error, was drawn from a
//! few triangles tens of kilometres across whose middles lay tens of metres under the sea
//! (1165 px of error seen from a ship's bridge, now within the pixel).
//!
//! Cost per frame: the boxes persist across frames in a flat arena of slots linked as the
//! quadtree (a node's four children in consecutive slots), so a visit reaches its node without
//! hashing and reads one small record; a node is culled when all 18 sample points lie outside
//! one frustum plane, decided first by the oriented box that bounds them (wholly outside a
//! plane, or wholly inside all of them, by more than a millimetre) and only near a plane by the
//! points themselves, which gives the points' answer exactly. Each tile is asked of the cache
//! once per selection. The samples of every node lie on the rows and columns of a lattice half a
//! level-0 node apart, whose sines and cosines are tabulated once, so building a box takes no
//! trigonometry (and the arena is allocated once, so it is never copied while the view moves).
//!
//! Streaming: a node refines only when its children's tile is resident in the paging cache, so
//! the renderer always draws what is in memory; the renderer fades newly refined nodes in from
//! their parent's shape over half a second (a floor on the morph factor), so finer data morphs
//! in as it arrives. The selection lists the tiles it would have refined into.
//!
//! Meshes: each drawn node's triangles are a cut of the triangulated irregular network over
//! its level's posts at a tolerance (`terrain_mesh::NodeCut`): the least error along its
//! ancestors, so that children keep their parents' posts. Between its parent's tolerance and
//! its own error a drawn node takes tolerance steps by distance (quarter octaves below its
//! parent's; [`TOLERANCE_STEPS`]), each morphing into the next larger one over its band, which is
//! what lets the finest level, which has nothing finer to refine into, be drawn coarse where
//! the eye is far from it.
//!
//! Limits: morph ranges come from each node's own error, not one range per level, so
//! neighbours may differ by more than one level or meet while one is still partly morphed, and a
//! node may be drawn from coarser data than its level while its tile loads; neighbours' cuts
//! differ along shared edges. The resulting T-junction gaps are hidden by skirts (see
//! `terrain_mesh`). Pixels are measured as a length
//! seen across at the node's distance (`e K / d`): towards the frame's edges a perspective
//! projection spreads a length over up to `1 / cos^2` of the angle off the axis more pixels
//! (1.33 at the side of a 60 degree view), a deliberate choice: a measure by distance alone
//! gives every channel of a multi-channel display, and every heading, the same surface (no
//! swimming when the view turns, no seam between channels). Node boxes sample 9 points per
//! height, which is conservative for nodes up to about 1000 km across. The arena holds at most
//! about 50 000 nodes between frames (about 30 MB); past that it is emptied and rebuilt.

use crate::terrain_mesh::{adaptive_errors, NodeCut};
use crate::view::Camera;
use cig_geo::{EnuFrame, Geodetic, LatLonTrig};
use cig_terrain::database::GeoidLookup;
use cig_terrain::edits::EditLayer;
use cig_terrain::tile::{NodeBounds, Tile};
use cig_terrain::{TileCache, TileKey};
use glam::DVec3;
use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;

// The nodes live in `node` (shared with `terrain_mesh`); their old paths stay.
pub use crate::node::{NodeKey, NodeLayout, DEFAULT_NODE_CELLS};

/// Factor on every node's error distance `R`: the morph factor is taken per vertex and
/// interpolated across each triangle, which leaves a point inside a triangle up to about 2 %
/// past the error its own distance allows when the band starts exactly at `R`; 5 % more
/// distance covers it with room.
pub const RANGE_MARGIN: f64 = 1.05;

/// The distance within which a node of `error_m` refines (its `R`, margin included) for a
/// view of `pixels_per_tangent` at `max_pixel_error` pixels; infinite for any error at 0 px
/// (full detail), 0 for a node with no error.
pub fn error_range_m(error_m: f64, pixels_per_tangent: f64, max_pixel_error: f64) -> f64 {
    if error_m <= 0.0 {
        0.0
    } else if max_pixel_error > 0.0 {
        error_m * pixels_per_tangent / max_pixel_error * RANGE_MARGIN
    } else {
        f64::INFINITY
    }
}

/// How rough a database is for the level of detail: the geometric error of one level's nodes
/// (the exact vertical error of the level's grid against the finest posts, what the selection
/// refines by), as a distribution over the level's nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelErrors {
    pub level: u8,
    pub nodes: usize,
    pub median_m: f32,
    pub p90_m: f32,
    pub max_m: f32,
}

impl LevelErrors {
    /// The distribution of `errors_m` (one per node, any order); `None` when there are none.
    pub fn of(level: u8, mut errors_m: Vec<f32>) -> Option<LevelErrors> {
        if errors_m.is_empty() {
            return None;
        }
        errors_m.sort_by(f32::total_cmp);
        let at = |q: f64| errors_m[((errors_m.len() - 1) as f64 * q).round() as usize];
        Some(LevelErrors {
            level,
            nodes: errors_m.len(),
            median_m: at(0.5),
            p90_m: at(0.9),
            max_m: at(1.0),
        })
    }
}

/// Settings of the selection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodSettings {
    /// Largest geometric error allowed on screen, pixels; 0 forces full detail everywhere.
    pub max_pixel_error: f64,
}

impl Default for LodSettings {
    fn default() -> Self {
        LodSettings {
            max_pixel_error: 1.0,
        }
    }
}

/// A node chosen for drawing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelectedNode {
    pub key: NodeKey,
    /// Pyramid level of the data its mesh is built from (`>= key.level`; greater while the
    /// node's own tile is still loading).
    pub data_level: u8,
    /// Distance from the eye (metres) where vertices start morphing towards the parent grid,
    /// and where they have fully morphed; infinite for nodes that never morph.
    pub morph_start_m: f32,
    pub morph_end_m: f32,
    /// The node's geometric error against the finest posts, metres.
    pub error_m: f32,
    /// Distance from the eye to the node's box, metres.
    pub distance_m: f64,
    /// How its mesh is cut from its level's posts.
    pub cut: NodeCut,
}

/// Result of one selection.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    pub nodes: Vec<SelectedNode>,
    /// Tiles the selection would have refined into but are not resident (nearest first).
    pub wanted_tiles: Vec<TileKey>,
    /// Nodes visited (for statistics).
    pub visited: usize,
}

/// A node's box: everything the selection reads on every visit, kept small so that a visit
/// touches few cache lines (the 18 sample points live apart, read only when the box test cannot
/// decide).
#[derive(Clone, Copy, Debug)]
struct NodeBox {
    frame_origin: DVec3,
    /// Local ENU axes of the node centre.
    axes: [DVec3; 3],
    box_min: DVec3,
    box_max: DVec3,
    /// The node's geometric error (`NodeBounds::error_m` of its data).
    error_m: f32,
    /// What the terrain's edits add to the error of a node drawn without them (a coarser
    /// node: only the finest level draws the edits' patches), metres.
    edit_error_m: f32,
    /// The highest and lowest change the edits make under the node (in its box), and the
    /// cache's edits revision they were taken at.
    edit_range_m: (f32, f32),
    edit_stamp: u64,
    /// Slot of the first of the node's four children (in `children()` order), or
    /// [`NO_CHILDREN`] before the node was first refined.
    first_child: u32,
    /// Pyramid level of the data the box was built from, or [`UNBUILT`].
    data_level: u8,
    /// The node's mesh is a cut of its own level's posts (`terrain_mesh::adaptive_errors`);
    /// otherwise it is drawn as a regular grid, with no tolerance steps, and its descendants
    /// keep its posts.
    adaptive: bool,
}

/// `NodeBox::data_level` of a slot whose box is not built yet.
const UNBUILT: u8 = u8::MAX;

/// `NodeBox::first_child` of a slot whose children have no slots yet.
const NO_CHILDREN: u32 = u32::MAX;

/// Node slots kept across frames; past this the slots are dropped and rebuilt.
const MAX_CACHED_NODES: usize = 50_000;

/// Distance from a frustum plane within which the box test defers to the sample points,
/// metres: far above the rounding of the box's axes and the eye-relative differences.
const CULL_MARGIN_M: f64 = 1e-3;

const EMPTY_BOX: NodeBox = NodeBox {
    frame_origin: DVec3::ZERO,
    axes: [DVec3::ZERO; 3],
    box_min: DVec3::ZERO,
    box_max: DVec3::ZERO,
    error_m: 0.0,
    edit_error_m: 0.0,
    edit_range_m: (0.0, 0.0),
    edit_stamp: 0,
    first_child: NO_CHILDREN,
    data_level: UNBUILT,
    adaptive: false,
};

/// Fast multiplicative hash for the small integer keys of nodes and tiles (the keys come from
/// the database's own layout, not from outside, so no flooding resistance is needed).
#[derive(Clone, Copy, Default)]
struct KeyHasher(u64);

impl KeyHasher {
    #[inline]
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.add(u64::from(b));
        }
    }
    fn write_u8(&mut self, n: u8) {
        self.add(u64::from(n));
    }
    fn write_u32(&mut self, n: u32) {
        self.add(u64::from(n));
    }
    fn write_u64(&mut self, n: u64) {
        self.add(n);
    }
    fn write_usize(&mut self, n: usize) {
        self.add(n as u64);
    }
}

type KeyHash = BuildHasherDefault<KeyHasher>;

/// A refined node's cut, level and whether it is drawn as a regular grid, handed to its
/// children.
type ParentCut = (NodeCut, u8, bool);

/// Memory of one selection: what it asked the tile cache, so each tile is looked up once
/// (the cache marks a tile used at the current paging step however often it is asked).
#[derive(Default)]
struct Scratch {
    stack: Vec<(u32, NodeKey, f64, Option<ParentCut>)>,
    wanted: Vec<(f64, TileKey)>,
    tiles: HashMap<TileKey, Option<Arc<Tile>>, KeyHash>,
    seen: HashSet<TileKey, KeyHash>,
    order: Vec<u128>,
}

impl Scratch {
    fn resident(&mut self, cache: &TileCache, key: TileKey) -> Option<&Arc<Tile>> {
        self.tiles
            .entry(key)
            .or_insert_with(|| cache.resident(key))
            .as_ref()
    }

    /// [`TerrainLod::resident_source`] through this selection's memory.
    fn source(
        &mut self,
        cache: &TileCache,
        layout: &NodeLayout,
        key: NodeKey,
    ) -> Option<(TileKey, Arc<Tile>)> {
        let mut level = key.level;
        while level < layout.pyramid.levels {
            let tk = layout.tile_of(key, level);
            if let Some(t) = self.resident(cache, tk) {
                return Some((tk, Arc::clone(t)));
            }
            level += 1;
        }
        None
    }

    /// The finest resident level holding `key` (without cloning the tile).
    fn source_level(&mut self, cache: &TileCache, layout: &NodeLayout, key: NodeKey) -> Option<u8> {
        let mut level = key.level;
        while level < layout.pyramid.levels {
            let tk = layout.tile_of(key, level);
            if self.resident(cache, tk).is_some() {
                return Some(level);
            }
            level += 1;
        }
        None
    }
}

/// Where a node's box lies against the frustum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum BoxSide {
    /// Wholly outside one plane: every sample point is culled.
    Outside,
    /// Wholly inside every plane: no sample point is culled.
    Inside,
    /// Near a plane: the sample points decide.
    Straddles,
}

/// Classifies an oriented box (centre and axes in the node's ENU frame, eye-relative origin)
/// against the camera's planes, deciding only where the box clears a plane by
/// [`CULL_MARGIN_M`].
fn box_side(camera: &Camera, b: &NodeBox) -> BoxSide {
    let origin_rel = b.frame_origin - camera.eye_ecef;
    let mid = (b.box_min + b.box_max) * 0.5;
    let half = (b.box_max - b.box_min) * 0.5;
    let mut inside = true;
    for plane in &camera.planes {
        let n_axes = DVec3::new(
            plane.normal.dot(b.axes[0]),
            plane.normal.dot(b.axes[1]),
            plane.normal.dot(b.axes[2]),
        );
        let centre = plane.normal.dot(origin_rel) + n_axes.dot(mid);
        let extent = n_axes.abs().dot(half);
        if centre + extent < plane.offset_m - CULL_MARGIN_M {
            return BoxSide::Outside;
        }
        if centre - extent < plane.offset_m + CULL_MARGIN_M {
            inside = false;
        }
    }
    if inside {
        BoxSide::Inside
    } else {
        BoxSide::Straddles
    }
}

/// The persistent part of the selection: node boxes cached across frames, in a flat arena of
/// slots linked as the quadtree (a node's four children sit in consecutive slots), so a visit
/// finds its node without hashing.
pub struct TerrainLod {
    pub layout: NodeLayout,
    geoid: GeoidLookup,
    roots: Vec<NodeKey>,
    /// Slot `i < roots.len()` is root `i`.
    boxes: Vec<NodeBox>,
    /// Sample points (ECEF) at the lowest and highest heights, per slot.
    points: Vec<[DVec3; 18]>,
    trig: TrigTable,
    scratch: Scratch,
}

/// Margin added to node boxes for the geoid's variation across a node and rounding, metres.
const BOX_MARGIN_M: f64 = 2.0;

impl TerrainLod {
    pub fn new(layout: NodeLayout, geoid: GeoidLookup) -> TerrainLod {
        let roots = layout.roots();
        // Room for every node up to the cap, taken once: growing the arena while the view moves
        // would copy it all in one frame (the memory is touched only as nodes are built).
        let capacity = (layout.node_count() as usize + 4).min(MAX_CACHED_NODES + 4);
        let mut lod = TerrainLod {
            layout,
            geoid,
            roots,
            boxes: Vec::with_capacity(capacity),
            points: Vec::with_capacity(capacity),
            trig: TrigTable::new(&layout),
            scratch: Scratch::default(),
        };
        lod.clear();
        lod
    }

    pub fn geoid(&self) -> &GeoidLookup {
        &self.geoid
    }

    /// The finest resident tile holding `key` (its level, the tile), walking up the pyramid.
    pub fn resident_source(&self, cache: &TileCache, key: NodeKey) -> Option<(TileKey, Arc<Tile>)> {
        let mut level = key.level;
        while level < self.layout.pyramid.levels {
            let tk = self.layout.tile_of(key, level);
            if let Some(t) = cache.resident(tk) {
                return Some((tk, t));
            }
            level += 1;
        }
        None
    }

    /// The highest and lowest change the terrain's edits make under `key`.
    fn edit_range_m(&self, edits: &EditLayer, key: NodeKey) -> (f32, f32) {
        let (r0, c0) = self.layout.finest_origin(key);
        let span = self.layout.finest_span(key.level);
        edits.range_over_m((r0, r0 + span), (c0, c0 + span))
    }

    /// Builds the box of `key` from the data of `data_level` into `slot`, with the terrain's
    /// edits under it (`edit_range_m`, taken at the cache's edits revision `edit_stamp`):
    /// the box holds the edited surface, and a node coarser than the finest level, which
    /// draws the ground without them, counts their largest change in its error, so the
    /// selection refines over an edit as far as it shows.
    fn build(
        &mut self,
        slot: usize,
        key: NodeKey,
        (tile_key, tile): (TileKey, &Tile),
        edit_range_m: (f32, f32),
        edit_stamp: u64,
    ) {
        let mut bounds = self.layout.node_bounds_in(key, tile_key, &tile.nodes);
        if bounds.min_m <= bounds.max_m {
            bounds.max_m += edit_range_m.0;
            bounds.min_m += edit_range_m.1;
        }
        let edit_error_m = if key.level > 0 {
            edit_range_m.0.max(-edit_range_m.1)
        } else {
            0.0
        };
        if let (Some(dst), Some(points)) = (self.boxes.get_mut(slot), self.points.get_mut(slot)) {
            *dst = NodeBox {
                first_child: dst.first_child,
                edit_error_m,
                edit_range_m,
                edit_stamp,
                adaptive: adaptive_errors(&self.layout, key, (tile_key, tile)).is_some(),
                ..node_box(
                    &self.layout,
                    &self.geoid,
                    &self.trig,
                    key,
                    tile_key.level,
                    bounds,
                    points,
                )
            };
        }
    }

    /// Slot of the first of `slot`'s children, making room for them on first use.
    fn children_of(&mut self, slot: usize) -> u32 {
        let first = self.boxes.get(slot).map_or(NO_CHILDREN, |b| b.first_child);
        if first != NO_CHILDREN {
            return first;
        }
        let first = self.boxes.len() as u32;
        self.boxes.extend([EMPTY_BOX; 4]);
        self.points.extend([[DVec3::ZERO; 18]; 4]);
        if let Some(b) = self.boxes.get_mut(slot) {
            b.first_child = first;
        }
        first
    }

    /// Selects the nodes to draw for one camera.
    pub fn select(
        &mut self,
        cache: &TileCache,
        camera: &Camera,
        settings: &LodSettings,
    ) -> Selection {
        let mut selection = Selection::default();
        if self.boxes.len() > MAX_CACHED_NODES {
            self.clear();
        }
        let mut scratch = std::mem::take(&mut self.scratch);
        // The revision first: a change between the two reads is seen again next frame.
        let edits_revision = cache.edits_revision();
        let edits = cache.edits();
        scratch.stack.clear();
        scratch.wanted.clear();
        scratch.tiles.clear();
        scratch.seen.clear();
        scratch.stack.extend(
            self.roots
                .iter()
                .enumerate()
                .map(|(slot, &key)| (slot as u32, key, f64::INFINITY, None)),
        );
        while let Some((slot, key, parent_range_m, parent_cut)) = scratch.stack.pop() {
            let slot = slot as usize;
            selection.visited += 1;
            // The next node's box and sample points, fetched while this one is decided: after a
            // frame they are cold (measured on lavapipe: a third off the selection's time).
            if let Some(&(next, ..)) = scratch.stack.last() {
                if let Some(b) = self.boxes.get(next as usize) {
                    cig_terrain::hint::prefetch(b);
                }
                if let Some(p) = self.points.get(next as usize) {
                    cig_terrain::hint::prefetch(p);
                }
            }
            let Some(data_level) = scratch.source_level(cache, &self.layout, key) else {
                scratch
                    .wanted
                    .push((f64::INFINITY, self.layout.tile_of(key, key.level)));
                continue;
            };
            let (built_level, edit_stamp, edit_range_m) =
                self.boxes.get(slot).map_or((UNBUILT, 0, (0.0, 0.0)), |b| {
                    (b.data_level, b.edit_stamp, b.edit_range_m)
                });
            let mut rebuild = built_level != data_level;
            let mut edits_now = edit_range_m;
            if edit_stamp != edits_revision {
                edits_now = self.edit_range_m(&edits, key);
                if edits_now != edit_range_m {
                    rebuild = true;
                } else if let Some(b) = self.boxes.get_mut(slot) {
                    b.edit_stamp = edits_revision;
                }
            }
            if rebuild {
                if let Some((tile_key, tile)) = scratch.source(cache, &self.layout, key) {
                    self.build(slot, key, (tile_key, &tile), edits_now, edits_revision);
                }
            }
            let Some(g) = self.boxes.get(slot).copied() else {
                continue;
            };
            let culled = match box_side(camera, &g) {
                BoxSide::Outside => true,
                BoxSide::Inside => false,
                BoxSide::Straddles => self
                    .points
                    .get(slot)
                    .is_some_and(|points| camera.culls(&points.map(|p| p - camera.eye_ecef))),
            };
            if culled {
                continue;
            }
            let d = camera.eye_ecef - g.frame_origin;
            let local = DVec3::new(d.dot(g.axes[0]), d.dot(g.axes[1]), d.dot(g.axes[2]));
            let distance_m = (local.clamp(g.box_min, g.box_max) - local).length();
            let error_m = f64::from(g.error_m.max(0.0));
            let range_m = error_range_m(
                error_m + f64::from(g.edit_error_m),
                camera.pixels_per_tangent,
                settings.max_pixel_error,
            );
            let cut = own_cut(parent_cut, error_m, settings);
            let wants_refine = key.level > 0 && distance_m < range_m;
            if wants_refine {
                let child_tile = self.layout.tile_of(key, key.level - 1);
                if scratch.resident(cache, child_tile).is_some() {
                    let first = self.children_of(slot);
                    let handed = Some((cut, key.level, !g.adaptive));
                    for (i, child) in key.children().into_iter().enumerate() {
                        if self.layout.exists(child) {
                            scratch
                                .stack
                                .push((first + i as u32, child, range_m, handed));
                        }
                    }
                    continue;
                }
                scratch.wanted.push((distance_m, child_tile));
            }
            let (cut, morph_start_m, morph_end_m) = drawn_cut(
                g.adaptive,
                cut,
                (distance_m, range_m, parent_range_m),
                camera,
                settings,
            );
            selection.nodes.push(SelectedNode {
                key,
                data_level: g.data_level,
                morph_start_m: morph_start_m as f32,
                morph_end_m: morph_end_m as f32,
                error_m: error_m as f32,
                distance_m,
                cut,
            });
        }
        let wanted = &mut scratch.wanted;
        wanted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        wanted.dedup_by(|a, b| a.1 == b.1);
        let seen = &mut scratch.seen;
        selection.wanted_tiles = wanted
            .iter()
            .filter(|(_, k)| seen.insert(*k))
            .map(|(_, k)| *k)
            .collect();
        sort_by_distance(&mut selection.nodes, &mut scratch.order);
        // Tiles are not kept alive past the selection.
        scratch.tiles.clear();
        self.scratch = scratch;
        selection
    }

    /// Forgets cached node boxes (e.g. after tiles were evicted and reloaded at another level).
    pub fn clear(&mut self) {
        self.boxes.clear();
        self.points.clear();
        self.boxes.resize(self.roots.len(), EMPTY_BOX);
        self.points.resize(self.roots.len(), [DVec3::ZERO; 18]);
    }

    /// Node slots held (for statistics and tests).
    pub fn cached_nodes(&self) -> usize {
        self.boxes.len()
    }
}

/// A node's cut at its own error, below its parent's (full detail keeps every post).
fn own_cut(parent: Option<ParentCut>, error_m: f64, settings: &LodSettings) -> NodeCut {
    if settings.max_pixel_error > 0.0 {
        NodeCut::below(parent, error_m as f32)
    } else {
        NodeCut::REGULAR
    }
}

/// A drawn node's cut and morph band (start, end), from its cut at its own error and its box
/// distance, own range and parent's range: a tolerance step for an adaptive mesh (regular
/// grids take none; see `terrain_mesh::adaptive_errors`), CDLOD's band between the node's and
/// its parent's range otherwise, none for a root.
fn drawn_cut(
    adaptive: bool,
    cut: NodeCut,
    (distance_m, range_m, parent_range_m): (f64, f64, f64),
    camera: &Camera,
    settings: &LodSettings,
) -> (NodeCut, f64, f64) {
    if !parent_range_m.is_finite() {
        return (cut, f64::INFINITY, f64::INFINITY);
    }
    if settings.max_pixel_error > 0.0 && adaptive {
        return tolerance_step(
            cut,
            distance_m,
            camera.pixels_per_tangent,
            settings.max_pixel_error,
            range_m,
            parent_range_m,
        );
    }
    (cut, morph_start(range_m, parent_range_m), parent_range_m)
}

/// Tolerance steps of a drawn node: between its parent's tolerance and its own error a node is
/// cut at `2^(-1/4)` of its parent's tolerance, `2^(-1/2)` of it nearer still, and so on for
/// at most this many steps (a factor of 256); the finest level (whose own error is zero) then
/// at zero (every post that is not on a plane with its neighbours). A node is drawn at most one
/// step finer than its distance needs: on the demo pass steps of 2 drew 144 600 triangles,
/// steps of `sqrt 2` 122 800 and quarter octaves 113 500, for about 3 mesh rebuilds a frame.
pub const TOLERANCE_STEPS: i32 = 32;

/// The tolerance of step `j` over the parent's: `2^(-j/4)`, exactly the same on every machine
/// (powers of two and rounded constants).
fn step_factor(j: i32) -> f32 {
    /// `2^(-k/4)` for `k` = 0 to 3.
    const QUARTERS: [f32; 4] = [
        1.0,
        0.840_896_4,
        std::f32::consts::FRAC_1_SQRT_2,
        0.594_603_56,
    ];
    0.5f32.powi(j / 4) * QUARTERS[(j % 4) as usize]
}

/// The cut and morph band of a drawn node at box distance `distance_m`, from `cut` (its cut
/// at its own error, `min(e, t_parent)`): the largest step tolerance `t_j = t_parent 2^(-j/4)`
/// above its own whose error distance `R(t_j)` the node's box is beyond (its own error when
/// none is), morphing to the next larger step's cut (to the parent's at the first step), from
/// `R(t_j)` to `R(t_(j-1))` (see [`TOLERANCE_STEPS`]). A vertex a fraction `m` through the
/// band shows at most `(1 - m) t_j + m t_(j-1)`, the error its distance allows, as across
/// levels; when the box comes nearer than `R(t_j)` the node takes the next step, whose
/// vertices beyond `R(t_j)` are fully morphed onto this cut, so nothing pops. These are
/// CDLOD's morph bands in tolerance instead of post spacing (the cuts of one node nest: the
/// same post errors, smaller tolerances). The finest level, which has nothing finer to refine
/// into, gains the most: its nodes are drawn from their parent's range inwards.
fn tolerance_step(
    cut: NodeCut,
    distance_m: f64,
    pixels_per_tangent: f64,
    max_pixel_error: f64,
    range_m: f64,
    parent_range_m: f64,
) -> (NodeCut, f64, f64) {
    let parent_tolerance_m = cut.parent_tolerance_m;
    let own_m = cut.tolerance_m;
    let range_of = |t: f32| error_range_m(f64::from(t), pixels_per_tangent, max_pixel_error);
    if !(parent_tolerance_m > 0.0 && parent_tolerance_m.is_finite()) {
        return (cut, morph_start(range_m, parent_range_m), parent_range_m);
    }
    // Step `j`'s tolerance, or `None` past the last step above the node's own.
    let step_tolerance = |j: i32| {
        let t = parent_tolerance_m * step_factor(j);
        (j <= TOLERANCE_STEPS && t > own_m).then_some(t)
    };
    let mut j = 1;
    let tolerance_m = loop {
        match step_tolerance(j) {
            Some(t) if range_of(t) > distance_m => j += 1,
            Some(t) => break t,
            None => break own_m,
        }
    };
    // The first step morphs to the parent's cut over CDLOD's band, later ones to the previous
    // step's cut of this node.
    let (morph_to_m, morph_end_m, within) = if j == 1 {
        (parent_tolerance_m, parent_range_m, false)
    } else {
        let t = parent_tolerance_m * step_factor(j - 1);
        (t, range_of(t), true)
    };
    let start_m = if tolerance_m == own_m {
        range_m
    } else {
        range_of(tolerance_m)
    };
    (
        NodeCut {
            tolerance_m,
            parent_tolerance_m: morph_to_m,
            morphs_within_level: within,
            ..cut
        },
        morph_start(start_m, morph_end_m),
        morph_end_m,
    )
}

/// Where a drawn node's vertices start morphing towards the parent's grid: at its own error
/// distance, where it would refine, so that the morph band `[range, parent_range]` shows at
/// most the error its distance allows. A node whose error is no smaller than its parent's is
/// drawn only beyond `parent_range` (it refines nearer), fully morphed.
fn morph_start(range_m: f64, parent_range_m: f64) -> f64 {
    range_m.min(parent_range_m)
}

/// Sorts `nodes` nearest first, keeping the traversal order between equal distances (a stable
/// sort by [`f64::total_cmp`], done as an unstable sort of packed (distance, index) keys).
fn sort_by_distance(nodes: &mut Vec<SelectedNode>, order: &mut Vec<u128>) {
    // The bits of an f64 made unsigned-comparable in the order of `total_cmp`.
    let key = |d: f64| {
        let bits = d.to_bits();
        if bits >> 63 == 1 {
            !bits
        } else {
            bits | (1 << 63)
        }
    };
    order.clear();
    order.extend(
        nodes
            .iter()
            .enumerate()
            .map(|(i, n)| (u128::from(key(n.distance_m)) << 64) | i as u128),
    );
    order.sort_unstable();
    let sorted: Vec<SelectedNode> = order
        .iter()
        .filter_map(|k| nodes.get((k & u128::from(u64::MAX)) as usize).copied())
        .collect();
    *nodes = sorted;
}

/// Sines and cosines of the latitudes of the finest rows, and of the longitudes of the finest
/// columns, where node samples fall (multiples of half a node of level 0), worked out once:
/// neighbouring nodes and a node's children share most of their samples' rows and columns.
struct TrigTable {
    /// Finest rows (and columns) between table entries.
    step: f64,
    /// Entry `k`: the latitude of finest row `k * step` (its longitude fields unused).
    lat: Vec<LatLonTrig>,
    /// Entry `k`: the longitude of finest column `k * step` (its latitude fields unused).
    lon: Vec<LatLonTrig>,
}

/// Most entries of each table, 2.6 MB (half a million posts a side with 16-cell nodes; beyond,
/// the trigonometry is done per node).
const MAX_TRIG_ENTRIES: usize = 1 << 16;

impl TrigTable {
    fn new(layout: &NodeLayout) -> TrigTable {
        let step = f64::from(layout.node_cells) / 2.0;
        let grid = &layout.pyramid.grid;
        let entries = |posts: usize| {
            let n = ((posts.max(2) - 1) as f64 / step).floor() as usize + 1;
            if n <= MAX_TRIG_ENTRIES {
                n
            } else {
                0
            }
        };
        TrigTable {
            step,
            lat: (0..entries(grid.rows))
                .map(|k| LatLonTrig::new(layout.lat_lon_of_finest(k as f64 * step, 0.0).0, 0.0))
                .collect(),
            lon: (0..entries(grid.cols))
                .map(|k| LatLonTrig::new(0.0, layout.lat_lon_of_finest(0.0, k as f64 * step).1))
                .collect(),
        }
    }

    /// The entry of finest row or column `index` when the table holds it (`index` a multiple
    /// of the step inside the database, where `lat_lon_of_finest` does not clamp).
    fn entry(&self, table: &[LatLonTrig], index: f64) -> Option<LatLonTrig> {
        let k = index / self.step;
        if k.fract() == 0.0 && k >= 0.0 {
            table.get(k as usize).copied()
        } else {
            None
        }
    }

    /// `LatLonTrig::new(lat_deg, lon_deg)` for the position of finest `(row, col)`, which is
    /// `(lat_deg, lon_deg)`.
    fn at(&self, row: f64, col: f64, lat_deg: f64, lon_deg: f64) -> LatLonTrig {
        match (self.entry(&self.lat, row), self.entry(&self.lon, col)) {
            (Some(lat), Some(lon)) => lat.with_lon_of(lon),
            _ => LatLonTrig::new(lat_deg, lon_deg),
        }
    }
}

/// The box of node `key` built from `bounds` read from data of `data_level`, and its 18
/// sample points (written to `points`): the 9 points of a 3 x 3 grid over the node at its
/// lowest and highest heights (with margins), and the box bounding them in the ENU frame of the
/// node's centre.
fn node_box(
    layout: &NodeLayout,
    geoid: &GeoidLookup,
    trig_table: &TrigTable,
    key: NodeKey,
    data_level: u8,
    bounds: NodeBounds,
    points: &mut [DVec3; 18],
) -> NodeBox {
    let (r0, c0) = layout.finest_origin(key);
    let span = layout.finest_span(key.level) as f64;
    let (lo, hi) = if bounds.min_m <= bounds.max_m {
        (f64::from(bounds.min_m), f64::from(bounds.max_m))
    } else {
        (0.0, 0.0)
    };
    // The surface bulges above the chords between the 9 sample points by up to
    // D^2 / (32 R) for a node D across.
    let span_m = span * layout.pyramid.grid.dlat_deg * 111_000.0;
    let bulge_m = span_m * span_m / (32.0 * 6_356_000.0);
    // The 3 x 3 samples share three latitudes and three longitudes (a latitude depends on the
    // row only): the trigonometry is done once for each, on the diagonal (or read from the
    // table).
    const FRACTIONS: [f64; 3] = [0.0, 0.5, 1.0];
    let diagonal = FRACTIONS.map(|f| {
        let (row, col) = (r0 as f64 + f * span, c0 as f64 + f * span);
        let (lat, lon) = layout.lat_lon_of_finest(row, col);
        (lat, lon, trig_table.at(row, col, lat, lon))
    });
    let mut centre = None;
    let mut k = 0;
    for (i, &(lat, _, lat_trig)) in diagonal.iter().enumerate() {
        for (j, &(_, lon, lon_trig)) in diagonal.iter().enumerate() {
            let trig = lat_trig.with_lon_of(lon_trig);
            let n = geoid.undulation_m(lat, lon);
            if (i, j) == (1, 1) {
                centre = Some((lat, lon, n, trig));
            }
            for h in [lo - BOX_MARGIN_M, hi + BOX_MARGIN_M + bulge_m] {
                if let Some(p) = points.get_mut(k) {
                    *p = trig.to_ecef(h + n);
                }
                k += 1;
            }
        }
    }
    // The centre is the middle sample (`span / 2` and `0.5 * span` are the same number).
    let (lat_c, lon_c, n_c, trig_c) = centre.unwrap_or_else(|| {
        let (lat, lon) = layout.lat_lon_of_finest(r0 as f64 + span / 2.0, c0 as f64 + span / 2.0);
        (
            lat,
            lon,
            geoid.undulation_m(lat, lon),
            LatLonTrig::new(lat, lon),
        )
    });
    let frame = EnuFrame::with_trig(Geodetic::new(lat_c, lon_c, n_c + (lo + hi) / 2.0), trig_c);
    let axes = [
        frame.enu_vector_to_ecef(DVec3::X),
        frame.enu_vector_to_ecef(DVec3::Y),
        frame.enu_vector_to_ecef(DVec3::Z),
    ];
    let mut box_min = DVec3::splat(f64::INFINITY);
    let mut box_max = DVec3::splat(f64::NEG_INFINITY);
    for p in points.iter() {
        let d = *p - frame.origin_ecef();
        let local = DVec3::new(d.dot(axes[0]), d.dot(axes[1]), d.dot(axes[2]));
        box_min = box_min.min(local);
        box_max = box_max.max(local);
    }
    NodeBox {
        frame_origin: frame.origin_ecef(),
        axes,
        box_min,
        box_max,
        error_m: layout.node_error_m(key.level, bounds.error_m),
        edit_error_m: 0.0,
        edit_range_m: (0.0, 0.0),
        edit_stamp: 0,
        first_child: NO_CHILDREN,
        data_level,
        adaptive: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::{FovDeg, Hpr, View};
    use cig_terrain::build::{build_pyramid, BuildError};
    use cig_terrain::database::{GeoidGrid, MemoryTileStore};
    use cig_terrain::{GeoGrid, Manifest, Material, PagingConfig, Raster, TerrainDatabase};
    use proptest::prelude::*;
    use std::sync::OnceLock;

    /// The selection as it was before the node arena (commit c2719fb): every visited node's box
    /// rebuilt from scratch with one geodetic conversion per sample point, every point tested
    /// against every plane, every tile asked of the cache. The new selection must give exactly
    /// its answer.
    fn reference_select(
        layout: &NodeLayout,
        geoid: &GeoidLookup,
        cache: &TileCache,
        camera: &Camera,
        settings: &LodSettings,
    ) -> Selection {
        struct Geometry {
            data_level: u8,
            adaptive: bool,
            bounds: NodeBounds,
            points: [DVec3; 18],
            frame_origin: DVec3,
            axes: [DVec3; 3],
            box_min: DVec3,
            box_max: DVec3,
        }
        let geometry = |key: NodeKey| -> Option<Geometry> {
            let mut level = key.level;
            let (tile_key, tile) = loop {
                if level >= layout.pyramid.levels {
                    return None;
                }
                let tk = layout.tile_of(key, level);
                if let Some(t) = cache.resident(tk) {
                    break (tk, t);
                }
                level += 1;
            };
            let bounds = layout.node_bounds_in(key, tile_key, &tile.nodes);
            let (r0, c0) = layout.finest_origin(key);
            let span = layout.finest_span(key.level) as f64;
            let (lat_c, lon_c) =
                layout.lat_lon_of_finest(r0 as f64 + span / 2.0, c0 as f64 + span / 2.0);
            let n_c = geoid.undulation_m(lat_c, lon_c);
            let (lo, hi) = if bounds.min_m <= bounds.max_m {
                (f64::from(bounds.min_m), f64::from(bounds.max_m))
            } else {
                (0.0, 0.0)
            };
            let span_m = span * layout.pyramid.grid.dlat_deg * 111_000.0;
            let bulge_m = span_m * span_m / (32.0 * 6_356_000.0);
            let mut points = [DVec3::ZERO; 18];
            let mut k = 0;
            for (fr, fc) in [
                (0.0, 0.0),
                (0.0, 0.5),
                (0.0, 1.0),
                (0.5, 0.0),
                (0.5, 0.5),
                (0.5, 1.0),
                (1.0, 0.0),
                (1.0, 0.5),
                (1.0, 1.0),
            ] {
                let (lat, lon) =
                    layout.lat_lon_of_finest(r0 as f64 + fr * span, c0 as f64 + fc * span);
                let n = geoid.undulation_m(lat, lon);
                for h in [lo - BOX_MARGIN_M, hi + BOX_MARGIN_M + bulge_m] {
                    points[k] = Geodetic::new(lat, lon, h + n).to_ecef();
                    k += 1;
                }
            }
            let frame = EnuFrame::new(Geodetic::new(lat_c, lon_c, n_c + (lo + hi) / 2.0));
            let axes = [
                frame.enu_vector_to_ecef(DVec3::X),
                frame.enu_vector_to_ecef(DVec3::Y),
                frame.enu_vector_to_ecef(DVec3::Z),
            ];
            let mut box_min = DVec3::splat(f64::INFINITY);
            let mut box_max = DVec3::splat(f64::NEG_INFINITY);
            for p in &points {
                let d = *p - frame.origin_ecef();
                let local = DVec3::new(d.dot(axes[0]), d.dot(axes[1]), d.dot(axes[2]));
                box_min = box_min.min(local);
                box_max = box_max.max(local);
            }
            Some(Geometry {
                data_level: tile_key.level,
                adaptive: adaptive_errors(layout, key, (tile_key, &tile)).is_some(),
                bounds,
                points,
                frame_origin: frame.origin_ecef(),
                axes,
                box_min,
                box_max,
            })
        };
        let mut selection = Selection::default();
        let mut stack: Vec<(NodeKey, f64, Option<ParentCut>)> = layout
            .roots()
            .into_iter()
            .map(|k| (k, f64::INFINITY, None))
            .collect();
        let mut wanted: Vec<(f64, TileKey)> = Vec::new();
        while let Some((key, parent_range_m, parent_cut)) = stack.pop() {
            selection.visited += 1;
            let Some(g) = geometry(key) else {
                wanted.push((f64::INFINITY, layout.tile_of(key, key.level)));
                continue;
            };
            let rel: [DVec3; 18] = g.points.map(|p| p - camera.eye_ecef);
            if camera.culls(&rel) {
                continue;
            }
            let d = camera.eye_ecef - g.frame_origin;
            let local = DVec3::new(d.dot(g.axes[0]), d.dot(g.axes[1]), d.dot(g.axes[2]));
            let distance_m = (local.clamp(g.box_min, g.box_max) - local).length();
            let error_m = f64::from(layout.node_error_m(key.level, g.bounds.error_m));
            let range_m =
                error_range_m(error_m, camera.pixels_per_tangent, settings.max_pixel_error);
            let cut = own_cut(parent_cut, error_m, settings);
            let wants_refine = key.level > 0 && distance_m < range_m;
            if wants_refine {
                let child_tile = layout.tile_of(key, key.level - 1);
                if cache.resident(child_tile).is_some() {
                    for child in key.children() {
                        if layout.exists(child) {
                            stack.push((child, range_m, Some((cut, key.level, !g.adaptive))));
                        }
                    }
                    continue;
                }
                wanted.push((distance_m, child_tile));
            }
            let (cut, morph_start_m, morph_end_m) = drawn_cut(
                g.adaptive,
                cut,
                (distance_m, range_m, parent_range_m),
                camera,
                settings,
            );
            selection.nodes.push(SelectedNode {
                key,
                data_level: g.data_level,
                morph_start_m: morph_start_m as f32,
                morph_end_m: morph_end_m as f32,
                error_m: error_m as f32,
                distance_m,
                cut,
            });
        }
        wanted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        wanted.dedup_by(|a, b| a.1 == b.1);
        let mut seen = std::collections::HashSet::new();
        selection.wanted_tiles = wanted
            .into_iter()
            .filter(|(_, k)| seen.insert(*k))
            .map(|(_, k)| k)
            .collect();
        selection
            .nodes
            .sort_by(|a, b| a.distance_m.total_cmp(&b.distance_m));
        selection
    }

    const SOUTH_LAT_DEG: f64 = 36.0;
    const WEST_LON_DEG: f64 = -121.0;
    const POSTS: usize = 301;
    const DLAT_DEG: f64 = 0.00027;
    const DLON_DEG: f64 = 0.00033;

    /// A 9 km database rough at the post scale (hills plus hashed noise), with a geoid that
    /// varies across it, in 16-cell tiles so that its pyramid has five levels.
    fn rough_database() -> Arc<TerrainDatabase> {
        static DB: OnceLock<Arc<TerrainDatabase>> = OnceLock::new();
        Arc::clone(DB.get_or_init(|| rough_database_with(None)))
    }

    /// The rough database with the tiles of one level written in format 1 (no post errors), as
    /// a database partly rewritten by an older build would be.
    fn rough_database_mixing_formats() -> Arc<TerrainDatabase> {
        static DB: OnceLock<Arc<TerrainDatabase>> = OnceLock::new();
        Arc::clone(DB.get_or_init(|| rough_database_with(Some(2))))
    }

    fn rough_database_with(format_1_level: Option<u8>) -> Arc<TerrainDatabase> {
        {
            let grid = GeoGrid {
                south_lat_deg: SOUTH_LAT_DEG,
                west_lon_deg: WEST_LON_DEG,
                dlat_deg: DLAT_DEG,
                dlon_deg: DLON_DEG,
                rows: POSTS,
                cols: POSTS,
            };
            let mut elevation_m = Vec::with_capacity(POSTS * POSTS);
            for row in 0..POSTS {
                for col in 0..POSTS {
                    let (y, x) = (row as f64 / 40.0, col as f64 / 55.0);
                    let hills = 400.0 * (y.sin() * x.cos()).abs() + 150.0 * (0.3 * x + y).sin();
                    let mut h = (row as u64 * 0x9E37_79B9 + col as u64 * 0x85EB_CA6B) ^ 0x5bd1e995;
                    h = (h ^ (h >> 15)).wrapping_mul(0x2C1B_3C6D);
                    let noise = (h % 1000) as f64 / 1000.0 * 30.0;
                    elevation_m.push((hills + noise) as f32);
                }
            }
            let raster = Raster {
                grid,
                elevation_m,
                material: Some(vec![Material::Grass; POSTS * POSTS]),
            };
            let store = Arc::new(MemoryTileStore::new());
            let summary = build_pyramid::<BuildError>(&raster, 16, &mut |t| {
                if Some(t.key.level) == format_1_level {
                    let older = Tile {
                        lod_errors: None,
                        ..t.clone()
                    };
                    store.insert(t.key, older.encode());
                } else {
                    store.insert(t.key, t.encode());
                }
                Ok(())
            })
            .expect("the test pyramid builds");
            let geoid = GeoidGrid::sample(
                SOUTH_LAT_DEG,
                WEST_LON_DEG,
                SOUTH_LAT_DEG + 0.1,
                WEST_LON_DEG + 0.12,
                0.02,
                |lat, lon| -30.0 + 40.0 * (lat - SOUTH_LAT_DEG) - 25.0 * (lon - WEST_LON_DEG),
            );
            Arc::new(
                TerrainDatabase::new(Manifest::from_build(&summary, geoid, 0, vec![]), store)
                    .expect("the test database opens"),
            )
        }
    }

    fn lod_for(db: &TerrainDatabase) -> TerrainLod {
        let manifest = db.manifest();
        TerrainLod::new(
            NodeLayout::new(manifest.layout),
            GeoidLookup::new(&manifest.geoid),
        )
    }

    /// A cache holding the tiles of the levels `levels` and, of level 0 and 1, those whose
    /// (row + col) is even when `checkerboard` (so nodes are drawn from coarser data and ask
    /// for the missing tiles).
    fn cache_with(
        db: &Arc<TerrainDatabase>,
        levels: std::ops::Range<u8>,
        checkerboard: bool,
    ) -> TileCache {
        let cache = TileCache::new(Arc::clone(db), PagingConfig::default()).expect("cache");
        let layout = *db.layout();
        for level in levels {
            let (rows, cols) = layout.tiles_at(level);
            for row in 0..rows {
                for col in 0..cols {
                    if checkerboard && level < 2 && (row + col) % 2 == 1 {
                        continue;
                    }
                    cache
                        .load_now(TileKey { level, row, col })
                        .expect("the test tile loads");
                }
            }
        }
        cache
    }

    fn view_at(
        north: f64,
        east: f64,
        alt_m: f64,
        hpr: (f64, f64, f64),
        fov_deg: f64,
        size: (u32, u32),
    ) -> View {
        View {
            eye: Geodetic::new(
                SOUTH_LAT_DEG + north * DLAT_DEG * (POSTS - 1) as f64,
                WEST_LON_DEG + east * DLON_DEG * (POSTS - 1) as f64,
                alt_m,
            ),
            orientation: Hpr {
                heading_deg: hpr.0,
                pitch_deg: hpr.1,
                roll_deg: hpr.2,
            },
            fov: FovDeg::from_horizontal(fov_deg, size.0, size.1),
            width_px: size.0,
            height_px: size.1,
        }
    }

    fn assert_same(new: &Selection, reference: &Selection, what: &str) {
        assert_eq!(new.visited, reference.visited, "{what}: nodes visited");
        assert_eq!(
            new.wanted_tiles, reference.wanted_tiles,
            "{what}: wanted tiles"
        );
        assert_eq!(
            new.nodes.len(),
            reference.nodes.len(),
            "{what}: nodes selected"
        );
        for (a, b) in new.nodes.iter().zip(&reference.nodes) {
            // Bit for bit: the same node, data, morph range, error and distance.
            assert_eq!(a.key, b.key, "{what}");
            assert_eq!(a.data_level, b.data_level, "{what}: {:?}", a.key);
            assert_eq!(
                a.morph_start_m.to_bits(),
                b.morph_start_m.to_bits(),
                "{what}"
            );
            assert_eq!(a.morph_end_m.to_bits(), b.morph_end_m.to_bits(), "{what}");
            assert_eq!(a.error_m.to_bits(), b.error_m.to_bits(), "{what}");
            assert_eq!(a.cut, b.cut, "{what}: {:?}", a.key);
            assert_eq!(
                a.distance_m.to_bits(),
                b.distance_m.to_bits(),
                "{what}: {:?}",
                a.key
            );
        }
    }

    /// Views of every kind over the test database: low passes, high views, looking down,
    /// looking up, rolled, narrow and wide, eyes outside the database.
    fn views() -> Vec<(View, f64)> {
        vec![
            (
                view_at(0.1, 0.1, 600.0, (45.0, -3.0, 0.0), 60.0, (640, 480)),
                1.0,
            ),
            (
                view_at(0.5, 0.5, 700.0, (200.0, -10.0, 15.0), 60.0, (320, 240)),
                1.0,
            ),
            (
                view_at(0.3, 0.8, 3000.0, (10.0, -60.0, 0.0), 90.0, (800, 600)),
                1.0,
            ),
            (
                view_at(0.5, 0.5, 9000.0, (0.0, -90.0, 0.0), 40.0, (256, 256)),
                0.5,
            ),
            (
                view_at(0.9, 0.2, 650.0, (120.0, -4.0, -20.0), 10.0, (640, 480)),
                1.0,
            ),
            (
                view_at(0.5, 0.5, 400.0, (0.0, 15.0, 0.0), 60.0, (320, 240)),
                1.0,
            ),
            (
                view_at(-0.3, -0.2, 900.0, (40.0, -5.0, 0.0), 60.0, (1920, 1080)),
                1.0,
            ),
            (
                view_at(0.6, 0.4, 800.0, (300.0, -8.0, 5.0), 70.0, (640, 480)),
                4.0,
            ),
            (
                view_at(0.2, 0.7, 620.0, (90.0, -2.0, 0.0), 60.0, (160, 120)),
                0.0,
            ),
        ]
    }

    #[test]
    fn the_node_arena_selects_exactly_what_the_reference_selection_selects() {
        let db = rough_database();
        let cache = cache_with(&db, 0..db.layout().levels, false);
        let mut lod = lod_for(&db);
        assert!(lod.layout.pyramid.levels >= 4, "a deep enough quadtree");
        // Twice over: the first pass builds the boxes, the second reuses them.
        for pass in 0..2 {
            for (n, (view, px)) in views().into_iter().enumerate() {
                let camera = view.camera();
                let settings = LodSettings {
                    max_pixel_error: px,
                };
                let new = lod.select(&cache, &camera, &settings);
                let reference =
                    reference_select(&lod.layout, lod.geoid(), &cache, &camera, &settings);
                assert!(!reference.nodes.is_empty(), "view {n} sees terrain");
                assert_same(&new, &reference, &format!("pass {pass}, view {n}"));
            }
        }
    }

    #[test]
    fn boxes_follow_the_data_as_finer_tiles_arrive_and_are_evicted() {
        let db = rough_database();
        let mut lod = lod_for(&db);
        let levels = db.layout().levels;
        // Coarse data only, then a checkerboard of the finer levels, then everything, then
        // coarse again (a fresh cache: the finer tiles gone): boxes rebuilt each time.
        let caches = [
            cache_with(&db, 2..levels, false),
            cache_with(&db, 0..levels, true),
            cache_with(&db, 0..levels, false),
            cache_with(&db, 3..levels, false),
            cache_with(&db, 0..0, false),
        ];
        for (c, cache) in caches.iter().enumerate() {
            for (n, (view, px)) in views().into_iter().enumerate() {
                let camera = view.camera();
                let settings = LodSettings {
                    max_pixel_error: px,
                };
                let new = lod.select(cache, &camera, &settings);
                let reference =
                    reference_select(&lod.layout, lod.geoid(), cache, &camera, &settings);
                assert_same(&new, &reference, &format!("cache {c}, view {n}"));
                if c == 1 && n == 0 {
                    // Nodes refine only into resident tiles: where a finer tile is missing
                    // its parent is drawn and the tile is asked for.
                    assert!(
                        !new.wanted_tiles.is_empty()
                            && new.nodes.iter().any(|s| s.key.level == 0)
                            && new.nodes.iter().any(|s| s.key.level == 1),
                        "the checkerboard mixes levels"
                    );
                }
            }
        }
        lod.clear();
        assert_eq!(lod.cached_nodes(), lod.layout.roots().len());
    }

    /// A node mesh's grid triangles, found by cell: the surface a mesh draws at any point of
    /// its grid, read from its index list (an independent reading of what the GPU draws).
    struct MeshSurface {
        n: usize,
        /// Grid (row, column) of each grid vertex.
        at: Vec<(usize, usize)>,
        triangles: Vec<[usize; 3]>,
        by_cell: Vec<Vec<usize>>,
    }

    impl MeshSurface {
        fn new(mesh: &crate::terrain_mesh::NodeMesh, n: u32) -> MeshSurface {
            let n = n as usize;
            let at: Vec<(usize, usize)> = mesh.vertices[..mesh.grid_vertices]
                .iter()
                .map(|v| {
                    let k = |f: f32| (f64::from(f) * n as f64).round() as usize;
                    (k(v.grid_uv[1]), k(v.grid_uv[0]))
                })
                .collect();
            let triangles: Vec<[usize; 3]> = mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
                .filter(|t| t.iter().all(|&v| v < mesh.grid_vertices))
                .collect();
            let mut by_cell = vec![Vec::new(); n * n];
            for (k, t) in triangles.iter().enumerate() {
                let rows = t.map(|v| at[v].0);
                let cols = t.map(|v| at[v].1);
                let (r_lo, r_hi) = (*rows.iter().min().unwrap(), *rows.iter().max().unwrap());
                let (c_lo, c_hi) = (*cols.iter().min().unwrap(), *cols.iter().max().unwrap());
                for r in r_lo..r_hi.max(r_lo + 1).min(n) {
                    for c in c_lo..c_hi.max(c_lo + 1).min(n) {
                        by_cell[r * n + c].push(k);
                    }
                }
            }
            MeshSurface {
                n,
                at,
                triangles,
                by_cell,
            }
        }

        /// The point of the mesh (vertex positions `at`) over grid point `(row, col)`.
        fn point(&self, at: &[DVec3], row: f64, col: f64) -> DVec3 {
            let cell = (row.floor() as usize).min(self.n - 1) * self.n
                + (col.floor() as usize).min(self.n - 1);
            let rc = |v: usize| (self.at[v].0 as f64, self.at[v].1 as f64);
            for &k in &self.by_cell[cell] {
                let [a, b, c] = self.triangles[k].map(rc);
                let cross = |o: (f64, f64), p: (f64, f64), q: (f64, f64)| {
                    (p.0 - o.0) * (q.1 - o.1) - (p.1 - o.1) * (q.0 - o.0)
                };
                let p = (row, col);
                let area = cross(a, b, c);
                let w = [
                    cross(p, b, c) / area,
                    cross(a, p, c) / area,
                    cross(a, b, p) / area,
                ];
                if w.iter().all(|&w| w >= -1e-9) {
                    let [va, vb, vc] = self.triangles[k];
                    return at[va] * w[0] + at[vb] * w[1] + at[vc] * w[2];
                }
            }
            panic!("no triangle of the mesh holds grid point ({row}, {col})");
        }
    }

    /// The largest error, in pixels as the selection measures them (`pixels_per_tangent` over
    /// the distance), between the surface a selection draws (its nodes' meshes morphed as the
    /// terrain shader morphs them) and the finest posts, over every finest post of every drawn
    /// node, and the number of posts measured.
    fn drawn_error_px(
        lod: &TerrainLod,
        cache: &TileCache,
        camera: &Camera,
        selection: &Selection,
    ) -> (f64, usize) {
        let layout = &lod.layout;
        let grid = layout.pyramid.grid;
        let tile_cells = layout.pyramid.finest_cells_per_tile(0);
        let n = layout.node_cells as usize;
        let (mut worst_px, mut posts) = (0.0f64, 0usize);
        let edits = cache.edits();
        for node in &selection.nodes {
            let data_key = layout.tile_of(node.key, node.data_level);
            let data = cache.resident(data_key).expect("every tile is resident");
            let parent_key = layout.parent_tile(node.key);
            let parent = parent_key.and_then(|k| cache.resident(k).map(|t| (k, t)));
            let mesh = crate::terrain_mesh::build_node_mesh(
                layout,
                lod.geoid(),
                node.key,
                crate::terrain_mesh::NodeTiles {
                    data: (data_key, &data),
                    detail: None,
                    parent: parent.as_ref().map(|(k, t)| (*k, t.as_ref())),
                },
                node.error_m,
                node.cut,
            );
            // The terrain shader's morph: by the distance of each vertex's morph target.
            let (start, end) = (
                f64::from(node.morph_start_m.min(1e30)),
                f64::from(node.morph_end_m.min(1.5e30)),
            );
            let drawn: Vec<DVec3> = mesh.vertices[..mesh.grid_vertices]
                .iter()
                .map(|v| {
                    let position = DVec3::from(v.position.map(f64::from));
                    let target = DVec3::from(v.morph_target.map(f64::from));
                    let d = (mesh.centre_ecef + target - camera.eye_ecef).length();
                    let m = ((d - start) / (end - start).max(1e-3)).clamp(0.0, 1.0);
                    mesh.centre_ecef + position.lerp(target, m)
                })
                .collect();
            let surface = MeshSurface::new(&mesh, layout.node_cells);
            let (r0, c0) = layout.finest_origin(node.key);
            let step = 1u64 << node.key.level;
            let span = layout.finest_span(node.key.level);
            for r in r0..=(r0 + span).min(grid.rows as u64 - 1) {
                for c in c0..=(c0 + span).min(grid.cols as u64 - 1) {
                    // The mesh's rows and columns stop at the database's last post (its
                    // vertices past the edge are clamped there): a post in the last cell lies
                    // a fraction of that shorter cell along it.
                    let along = |p: u64, p0: u64, last: u64| {
                        let k = (((p - p0) / step) as usize).min(n - 1);
                        let start = (p0 + k as u64 * step).min(last);
                        let end = (p0 + (k as u64 + 1) * step).min(last);
                        let fraction = if end > start {
                            (p - start) as f64 / (end - start) as f64
                        } else {
                            0.0
                        };
                        (k, fraction)
                    };
                    // A finest node's cells next to an edit are drawn by its patches (checked
                    // by `edit_patch`'s tests), not by its mesh.
                    if node.key.level == 0
                        && [(0, 0), (0, 1), (1, 0), (1, 1)].iter().any(|&(dr, dc)| {
                            let cell = (r.wrapping_sub(dr), c.wrapping_sub(dc));
                            u32::try_from(cell.0).is_ok_and(|row| {
                                u32::try_from(cell.1)
                                    .is_ok_and(|col| edits.cell((row, col)).is_some())
                            })
                        })
                    {
                        continue;
                    }
                    let (i, u) = along(r, r0, grid.rows as u64 - 1);
                    let (j, v) = along(c, c0, grid.cols as u64 - 1);
                    let shown = surface.point(&drawn, i as f64 + u, j as f64 + v);
                    let tile_key = TileKey {
                        level: 0,
                        row: (r / tile_cells) as u32,
                        col: (c / tile_cells) as u32,
                    };
                    let tile = cache.resident(tile_key).expect("level 0 is resident");
                    let h = f64::from(tile.elevation(
                        (r - u64::from(tile_key.row) * tile_cells) as usize,
                        (c - u64::from(tile_key.col) * tile_cells) as usize,
                    ));
                    let (lat, lon) = layout.lat_lon_of_finest(r as f64, c as f64);
                    let h = h + edits.delta_m(lat, lon);
                    let truth =
                        Geodetic::new(lat, lon, h + lod.geoid().undulation_m(lat, lon)).to_ecef();
                    let px = (shown - truth).length() * camera.pixels_per_tangent
                        / (truth - camera.eye_ecef).length();
                    worst_px = worst_px.max(px);
                    posts += 1;
                }
            }
        }
        (worst_px, posts)
    }

    /// The rough test terrain: nothing at the finest level, more at every coarser one, and
    /// the distribution ordered.
    #[test]
    fn level_errors_grow_with_the_level() {
        let db = rough_database();
        let cache = cache_with(&db, 0..db.layout().levels, false);
        let layout = NodeLayout::new(*db.layout());
        let mut previous_median = -1.0f32;
        for level in 0..layout.pyramid.levels {
            let mut node_errors = Vec::new();
            for key in layout.pyramid.keys_at(level) {
                let tile = cache.resident(key).expect("every tile is resident");
                layout.node_errors_in(key, &tile, &mut node_errors);
            }
            let errors = LevelErrors::of(level, node_errors).expect("every level has nodes");
            assert!(errors.nodes > 0);
            assert!(errors.median_m <= errors.p90_m && errors.p90_m <= errors.max_m);
            if level == 0 {
                // Its data is exact; what is left is the chord sag of its nodes' triangles.
                assert_eq!(
                    errors.max_m,
                    layout.node_sag_m(0),
                    "the finest level is exact"
                );
                assert!(errors.max_m < 0.001);
            } else {
                assert!(
                    errors.median_m > previous_median,
                    "level {level}: {errors:?}"
                );
            }
            previous_median = errors.median_m;
        }
        // 10 m at 1 px across 1920 px and 60 degrees: 16.6 km, and the 5 % margin.
        let fov = crate::view::FovDeg::from_horizontal(60.0, 1920, 1080);
        let r = error_range_m(10.0, fov.pixels_per_tangent(1920, 1080), 1.0);
        assert!((r - 16_628.0 * RANGE_MARGIN).abs() < 1.0, "{r}");
        assert_eq!(error_range_m(0.0, 1000.0, 1.0), 0.0);
        assert_eq!(error_range_m(1.0, 1000.0, 0.0), f64::INFINITY);
    }

    /// The mesh of `key` cut at `cut`, from its own level's tile.
    fn own_mesh(
        lod: &TerrainLod,
        cache: &TileCache,
        key: NodeKey,
        cut: NodeCut,
    ) -> crate::terrain_mesh::NodeMesh {
        let tile_key = lod.layout.tile_of(key, key.level);
        let tile = cache.resident(tile_key).expect("every tile is resident");
        let parent_key = lod.layout.parent_tile(key);
        let parent = parent_key.and_then(|k| cache.resident(k).map(|t| (k, t)));
        crate::terrain_mesh::build_node_mesh(
            &lod.layout,
            lod.geoid(),
            key,
            crate::terrain_mesh::NodeTiles {
                data: (tile_key, &tile),
                detail: None,
                parent: parent.as_ref().map(|(k, t)| (*k, t.as_ref())),
            },
            0.0,
            cut,
        )
    }

    /// The cut a selection gives `key` when every tile is resident: the least error along the
    /// path from its root, and the level of its nearest ancestor that reaches past the edge.
    fn cut_of(layout: &NodeLayout, cache: &TileCache, key: NodeKey) -> NodeCut {
        let error_and_regular = |k: NodeKey| {
            let tile_key = layout.tile_of(k, k.level);
            let tile = cache.resident(tile_key).expect("every tile is resident");
            let error_m = layout
                .node_bounds_in(k, tile_key, &tile.nodes)
                .error_m
                .max(0.0);
            let regular = adaptive_errors(layout, k, (tile_key, &tile)).is_none();
            (error_m, regular)
        };
        let mut chain = vec![key];
        while chain
            .last()
            .is_some_and(|k| k.level + 1 < layout.pyramid.levels)
        {
            let parent = chain.last().map(|k| k.parent()).expect("not empty");
            chain.push(parent);
        }
        let mut parent = None;
        let mut cut = NodeCut::REGULAR;
        for k in chain.into_iter().rev() {
            let (error_m, regular) = error_and_regular(k);
            cut = NodeCut::below(parent, error_m);
            parent = Some((cut, k.level, regular));
        }
        cut
    }

    /// No pop when a parent takes over from its children: a child's fully morphed vertices lie
    /// on the parent's own mesh (built from the parent's tile with the parent's cut, and read
    /// back from its triangle list), everywhere, the nodes that reach past the database's last
    /// row and column included (their vertices are clamped onto the edge, and stay on it).
    #[test]
    fn fully_morphed_children_lie_on_their_parents_mesh() {
        children_lie_on_their_parents_mesh(&rough_database());
    }

    /// The same where one level's tiles are format 1: they are regular grids, and the cuts
    /// below them keep all their posts.
    #[test]
    fn fully_morphed_children_lie_on_a_format_1_parents_grid() {
        children_lie_on_their_parents_mesh(&rough_database_mixing_formats());
    }

    fn children_lie_on_their_parents_mesh(db: &Arc<TerrainDatabase>) {
        let cache = cache_with(db, 0..db.layout().levels, false);
        let lod = lod_for(db);
        let layout = &lod.layout;
        let n = layout.node_cells as usize;
        let build = |key: NodeKey| own_mesh(&lod, &cache, key, cut_of(layout, &cache, key));
        let grid = layout.pyramid.grid;
        let (last_row, last_col) = ((grid.rows - 1) as f64, (grid.cols - 1) as f64);
        let (mut checked, mut at_edge, mut worst_m) = (0usize, 0usize, 0.0f64);
        let (mut child_triangles, mut grid_triangles) = (0usize, 0usize);
        for level in 0..layout.pyramid.levels - 1 {
            let (tiles_rows, tiles_cols) = layout.pyramid.tiles_at(level);
            let nodes_per_tile = layout.pyramid.tile_cells / layout.node_cells;
            for row in 0..tiles_rows * nodes_per_tile {
                for col in 0..tiles_cols * nodes_per_tile {
                    let key = NodeKey { level, row, col };
                    if !layout.exists(key) {
                        continue;
                    }
                    let (child, parent) = (build(key), build(key.parent()));
                    if !layout.reaches_past_edge(key) {
                        child_triangles += child.indices.len() / 3;
                        grid_triangles += 2 * n * n + 8 * n;
                    }
                    let parent_positions: Vec<DVec3> = parent
                        .vertices
                        .iter()
                        .map(|v| parent.centre_ecef + DVec3::from(v.position.map(f64::from)))
                        .collect();
                    let parent_surface = MeshSurface::new(&parent, layout.node_cells);
                    let (r0, c0) = layout.finest_origin(key);
                    let (pr0, pc0) = layout.finest_origin(key.parent());
                    let step = (1u64 << level) as f64;
                    // The parent cell (and fraction) holding a finest-grid row or column.
                    let cell = |own: f64, p0: f64, last: f64| {
                        let k = (((own - p0) / (2.0 * step)) as usize).min(n - 1);
                        let start = (p0 + k as f64 * 2.0 * step).min(last);
                        let end = (p0 + (k + 1) as f64 * 2.0 * step).min(last);
                        let f = if end > start {
                            (own - start) / (end - start)
                        } else {
                            0.0
                        };
                        (k, f)
                    };
                    let child_surface = MeshSurface::new(&child, layout.node_cells);
                    for (k, &(i, j)) in child_surface.at.iter().enumerate() {
                        {
                            let own_row = (r0 as f64 + i as f64 * step).min(last_row);
                            let own_col = (c0 as f64 + j as f64 * step).min(last_col);
                            let (a, v) = cell(own_row, pr0 as f64, last_row);
                            let (b, u) = cell(own_col, pc0 as f64, last_col);
                            let on_parent =
                                parent_surface.point(&parent_positions, a as f64 + v, b as f64 + u);
                            let target = child.vertices[k].morph_target.map(f64::from);
                            let target = child.centre_ecef + DVec3::from(target);
                            worst_m = worst_m.max((target - on_parent).length());
                            checked += 1;
                            if own_row == last_row || own_col == last_col {
                                at_edge += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(
            checked > 10_000 && at_edge > 500,
            "{checked} vertices, {at_edge} on the edge"
        );
        assert!(
            worst_m < 0.02,
            "a fully morphed vertex is {worst_m} m off its parent's mesh"
        );
        // The cuts are adaptive: inside the database, fewer triangles than the regular grids.
        assert!(
            child_triangles * 10 < grid_triangles * 9,
            "{child_triangles} triangles where the grids have {grid_triangles}"
        );
    }

    /// No pop between a node's tolerance steps: a node cut at a step's tolerance, fully
    /// morphed, lies on its own cut at the next larger step (read back from that mesh's
    /// triangles), and the smaller step keeps more of the posts.
    #[test]
    fn fully_morphed_tolerance_steps_lie_on_the_larger_step() {
        let db = rough_database();
        let cache = cache_with(&db, 0..db.layout().levels, false);
        let lod = lod_for(&db);
        let layout = &lod.layout;
        let (mut checked, mut worst_m) = (0usize, 0.0f64);
        let (mut fine_triangles, mut coarse_triangles) = (0usize, 0usize);
        for level in 0..2u8 {
            for key in (0..8)
                .flat_map(|row| (0..8).map(move |col| NodeKey { level, row, col }))
                .filter(|&k| layout.exists(k) && !layout.reaches_past_edge(k))
            {
                let base = cut_of(layout, &cache, key);
                let larger = (base.parent_tolerance_m * 0.5).max(base.tolerance_m);
                let build = |cut: NodeCut| own_mesh(&lod, &cache, key, cut);
                let coarse = build(NodeCut {
                    tolerance_m: larger,
                    ..base
                });
                let fine = build(NodeCut {
                    tolerance_m: (larger * 0.5).max(base.tolerance_m),
                    parent_tolerance_m: larger,
                    morphs_within_level: true,
                    ..base
                });
                fine_triangles += fine.indices.len() / 3;
                coarse_triangles += coarse.indices.len() / 3;
                let positions: Vec<DVec3> = coarse
                    .vertices
                    .iter()
                    .map(|v| coarse.centre_ecef + DVec3::from(v.position.map(f64::from)))
                    .collect();
                let coarse_surface = MeshSurface::new(&coarse, layout.node_cells);
                let fine_surface = MeshSurface::new(&fine, layout.node_cells);
                for (k, &(i, j)) in fine_surface.at.iter().enumerate() {
                    let on_coarse = coarse_surface.point(&positions, i as f64, j as f64);
                    let target = fine.vertices[k].morph_target.map(f64::from);
                    let target = fine.centre_ecef + DVec3::from(target);
                    worst_m = worst_m.max((target - on_coarse).length());
                    checked += 1;
                }
            }
        }
        assert!(checked > 2000, "{checked} vertices");
        assert!(
            worst_m < 0.02,
            "a fully morphed vertex is {worst_m} m off the larger step"
        );
        assert!(
            fine_triangles > coarse_triangles,
            "{fine_triangles} triangles at the smaller step, {coarse_triangles} at the larger"
        );
    }

    /// The level-of-detail guarantee, checked on the drawn surface itself: everywhere, morph
    /// bands included, the terrain is within the allowed pixels of the finest posts, and
    /// within a centimetre of them at full detail; and the bound is nearly reached (the
    /// selection does not refine more than it needs to).
    #[test]
    fn the_drawn_surface_is_within_the_allowed_pixels_of_the_finest_posts() {
        let db = rough_database();
        let cache = cache_with(&db, 0..db.layout().levels, false);
        let mut lod = lod_for(&db);
        for (k, (view, px)) in views().into_iter().enumerate() {
            let camera = view.camera();
            let settings = LodSettings {
                max_pixel_error: px,
            };
            let selection = lod.select(&cache, &camera, &settings);
            let (worst_px, posts) = drawn_error_px(&lod, &cache, &camera, &selection);
            assert!(posts > 1000, "view {k}: {posts} posts measured");
            if px == 0.0 {
                let worst_m = worst_px * 1e4 / camera.pixels_per_tangent;
                assert!(worst_m < 0.01, "view {k}: {worst_m} m at full detail");
            } else {
                assert!(
                    worst_px <= px,
                    "view {k}: {worst_px:.3} px drawn, {px} allowed"
                );
                if selection.nodes.iter().any(|n| n.key.level > 0) {
                    assert!(
                        worst_px > px * 0.9,
                        "view {k}: {worst_px:.3} px drawn, {px} allowed: refined too far"
                    );
                }
            }
        }
    }

    /// A flat sea at 0 m, 301 x 301 posts 300 m apart (90 km), geoid 0, in 16-cell tiles: its
    /// posts carry no error at all, so only the earth's curvature says how coarse it may be
    /// drawn.
    fn flat_sea_database() -> Arc<TerrainDatabase> {
        static DB: OnceLock<Arc<TerrainDatabase>> = OnceLock::new();
        Arc::clone(DB.get_or_init(|| {
            let grid = GeoGrid {
                south_lat_deg: SOUTH_LAT_DEG,
                west_lon_deg: WEST_LON_DEG,
                dlat_deg: DLAT_DEG * 10.0,
                dlon_deg: DLON_DEG * 10.0,
                rows: POSTS,
                cols: POSTS,
            };
            let mut raster = Raster::from_fn(grid, |_, _| 0.0);
            raster.material = Some(vec![Material::Water; grid.len()]);
            let store = Arc::new(MemoryTileStore::new());
            let summary = build_pyramid::<BuildError>(&raster, 16, &mut |t| {
                store.insert(t.key, t.encode());
                Ok(())
            })
            .expect("the sea pyramid builds");
            let manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec![]);
            Arc::new(TerrainDatabase::new(manifest, store).expect("the sea database opens"))
        }))
    }

    /// The level-of-detail guarantee over a flat sea seen from a ship's bridge and from the
    /// air: the chords of coarse triangles cut below the curved surface (a 10 km triangle's
    /// middle lies 2 m under the sea), so the sea, too, is drawn within the allowed pixels.
    #[test]
    fn a_flat_sea_is_drawn_within_the_allowed_pixels_of_the_curved_surface() {
        let db = flat_sea_database();
        let cache = cache_with(&db, 0..db.layout().levels, false);
        let mut lod = lod_for(&db);
        let at = |north: f64, east: f64, alt_m: f64, hpr: (f64, f64, f64), size: (u32, u32)| {
            let mut view = view_at(north * 10.0, east * 10.0, alt_m, hpr, 60.0, size);
            view.fov = FovDeg::from_horizontal(60.0, size.0, size.1);
            view
        };
        for (k, view) in [
            at(0.5, 0.5, 20.0, (0.0, -3.0, 0.0), (640, 480)),
            at(0.3, 0.6, 15.0, (130.0, -8.0, 0.0), (1920, 1080)),
            at(0.5, 0.5, 3000.0, (45.0, -30.0, 0.0), (640, 480)),
        ]
        .into_iter()
        .enumerate()
        {
            let camera = view.camera();
            let selection = lod.select(
                &cache,
                &camera,
                &LodSettings {
                    max_pixel_error: 1.0,
                },
            );
            let (worst_px, posts) = drawn_error_px(&lod, &cache, &camera, &selection);
            assert!(posts > 1000, "view {k}: {posts} posts measured");
            assert!(
                worst_px <= 1.0,
                "view {k}: {worst_px:.3} px drawn, 1 allowed"
            );
            // The bound is conservative (the grid factor, side posts sized as diagonals) and the
            // finest cells cannot refine: well short of the pixel, but not far short.
            assert!(
                worst_px > 0.1,
                "view {k}: {worst_px:.3} px drawn: refined too far"
            );
        }
    }

    /// Edits are drawn by the finest level only, so a coarser node over one counts the
    /// edit's change in its error: over a 3 m deep ditch dug 3 km from a ship's bridge on the
    /// flat sea (whose coarse nodes carry no error of their own), the selection refines to
    /// the finest level over the ditch and the drawn surface stays within the pixel of the
    /// edited one; healed, the coarse nodes come back.
    #[test]
    fn edits_count_in_coarser_nodes_errors_so_the_bound_holds_over_them() {
        use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint, SpoilSide, TerrainEdit};
        let db = flat_sea_database();
        let cache = cache_with(&db, 0..db.layout().levels, false);
        let mut lod = lod_for(&db);
        let (lat, lon) = (SOUTH_LAT_DEG + 0.5 * 10.0 * DLAT_DEG * 300.0, WEST_LON_DEG);
        let eye_lon = lon + 0.5 * 10.0 * DLON_DEG * 300.0;
        let (_, east_m) = cig_geo::metres_per_degree(lat);
        let ditch_lon = eye_lon + 3000.0 / east_m;
        let ditch = TerrainEdit {
            author: EditAuthor {
                site: 1,
                application: 1,
            },
            sequence: 1,
            time_utc_s: 1.8e9,
            shape: EditShape::Ditch {
                from: GeoPoint {
                    lat_deg: lat - 0.006,
                    lon_deg: ditch_lon,
                },
                to: GeoPoint {
                    lat_deg: lat + 0.006,
                    lon_deg: ditch_lon,
                },
                width_m: 24.0,
                depth_m: 3.0,
                spoil: SpoilSide::Both,
            },
        };
        let mut view = view_at(
            0.5 * 10.0,
            0.5 * 10.0,
            20.0,
            (90.0, -1.0, 0.0),
            60.0,
            (1920, 1080),
        );
        view.eye.lon_deg = eye_lon;
        view.eye.lat_deg = lat;
        let camera = view.camera();
        let settings = LodSettings {
            max_pixel_error: 1.0,
        };
        let over_ditch = |selection: &Selection, lod: &TerrainLod| {
            selection
                .nodes
                .iter()
                .filter(|n| {
                    let (r0, c0) = lod.layout.finest_origin(n.key);
                    let span = lod.layout.finest_span(n.key.level);
                    let (lat0, lon0) = lod.layout.lat_lon_of_finest(r0 as f64, c0 as f64);
                    let (lat1, lon1) = lod
                        .layout
                        .lat_lon_of_finest((r0 + span) as f64, (c0 + span) as f64);
                    (lon0..=lon1).contains(&ditch_lon) && lat0 < lat + 0.006 && lat1 > lat - 0.006
                })
                .map(|n| n.key.level)
                .collect::<Vec<u8>>()
        };
        let plain = lod.select(&cache, &camera, &settings);
        let plain_levels = over_ditch(&plain, &lod);
        assert!(
            plain_levels.iter().all(|&l| l > 0),
            "unedited, the sea is drawn coarse there: {plain_levels:?}"
        );
        cache
            .update_edits(|layer| layer.apply(ditch))
            .expect("the ditch is dug");
        let edited = lod.select(&cache, &camera, &settings);
        let edited_levels = over_ditch(&edited, &lod);
        assert!(
            edited_levels.contains(&0),
            "the finest level draws the ditch: {edited_levels:?}"
        );
        let (worst_px, posts) = drawn_error_px(&lod, &cache, &camera, &edited);
        assert!(posts > 1000, "{posts} posts measured");
        assert!(
            worst_px <= 1.0,
            "{worst_px:.3} px drawn over the ditch, 1 allowed"
        );
        cache
            .update_edits(|layer| {
                let id = layer.edits().next().map(|e| e.id()).expect("one edit");
                layer.remove(id)
            })
            .expect("healed");
        let healed = lod.select(&cache, &camera, &settings);
        assert_eq!(over_ditch(&healed, &lod), plain_levels);
        assert_eq!(healed.nodes.len(), plain.nodes.len());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Any view over or beside the database (mostly looking at it): the same selection as
        /// the reference, on a cache where finer tiles are missing here and there.
        #[test]
        fn any_view_selects_as_the_reference_does(
            north in -0.3f64..1.3, east in -0.3f64..1.3, alt_m in 0.0f64..6000.0,
            heading_off in -80.0f64..80.0, pitch in -90.0f64..20.0, roll in -45.0f64..45.0,
            fov in 2.0f64..150.0, width in 16u32..2000, height in 16u32..1200,
            px in prop::sample::select(vec![0.0, 0.3, 1.0, 2.5, 8.0]),
        ) {
            let db = rough_database();
            static CACHE: OnceLock<TileCache> = OnceLock::new();
            let cache = CACHE.get_or_init(|| cache_with(&db, 0..db.layout().levels, true));
            let mut lod = lod_for(&db);
            // Mostly towards the database's centre (its posts are about as far apart north
            // as east), so that most views see some of it.
            let heading = (0.5 - east).atan2(0.5 - north).to_degrees() + heading_off;
            let view = view_at(north, east, alt_m, (heading, pitch, roll), fov, (width, height));
            prop_assume!(view.validate().is_ok());
            let camera = view.camera();
            let settings = LodSettings { max_pixel_error: px };
            for _ in 0..2 {
                let new = lod.select(cache, &camera, &settings);
                let reference = reference_select(&lod.layout, lod.geoid(), cache, &camera, &settings);
                assert_same(&new, &reference, "random view");
            }
        }

        /// The packed-key sort orders as a stable sort by `f64::total_cmp` does.
        #[test]
        fn the_distance_sort_is_the_stable_total_order(
            distances in prop::collection::vec(prop::sample::select(vec![0.0, -0.0, 1.5, 1.5, 2.0, 1e9, f64::INFINITY, 3.25]), 0..60),
        ) {
            let node = |i: usize, d: f64| SelectedNode {
                key: NodeKey { level: 0, row: i as u32, col: 0 },
                data_level: 0,
                morph_start_m: 0.0,
                morph_end_m: 0.0,
                error_m: 0.0,
                distance_m: d,
                cut: NodeCut::REGULAR,
            };
            let mut nodes: Vec<SelectedNode> = distances.iter().enumerate().map(|(i, &d)| node(i, d)).collect();
            let mut expected = nodes.clone();
            expected.sort_by(|a, b| a.distance_m.total_cmp(&b.distance_m));
            sort_by_distance(&mut nodes, &mut Vec::new());
            prop_assert_eq!(
                nodes.iter().map(|n| (n.key, n.distance_m.to_bits())).collect::<Vec<_>>(),
                expected.iter().map(|n| (n.key, n.distance_m.to_bits())).collect::<Vec<_>>()
            );
        }
    }
}
