//! GPU side of the terrain: a pool of fixed-size node meshes in one vertex buffer, their normal
//! and colour texels in two atlases, and the pipeline that morphs and shades them.
//!
//! Algorithm: every node's vertices live in its slot of one vertex pool (`vertices_per_node`
//! each), and its triangles are the node's own cut of its level's posts
//! (`cig_scene::terrain_mesh`), kept on the CPU; each view concatenates the drawn nodes'
//! triangles, nearest first, into one index list of pool vertices and draws them all in one
//! call (a software rasterizer pays for every draw). The shader finds a vertex's slot from its
//! index, and the slot's record (eye-relative centre, frame, morph distances, skirt depth,
//! atlas rectangle, texels per data post and that post spacing, which the shader's material
//! borders and detail need) in a storage buffer written once per view. Slots are recycled least
//! recently used. Meshes are rebuilt when finer data becomes resident or a node's cut changes.
//!
//! Limits: the pool holds `capacity` nodes (the database's node count, at most 16384 of 16
//! cells, about 280 MB with the atlases and the meshes' indices); a view that needs more (full
//! detail over a very large database) draws the nearest ones and reports the rest as dropped in
//! its statistics.

use crate::gpu::Gpu;
use cig_scene::edit_patch::{CellPatches, NodePatches, PatchMarks, PatchedNode};
use cig_scene::lod::{NodeKey, SelectedNode, TerrainLod};
use cig_scene::terrain_mesh::{self, NodeCut, TerrainVertex};
use cig_terrain::TileCache;
use std::collections::HashMap;

/// Per-node record read by the shaders (must match `Node` in terrain.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct NodeRecord {
    pub offset: [f32; 4],
    pub axis_e: [f32; 4],
    pub axis_n: [f32; 4],
    pub axis_u: [f32; 4],
    pub morph: [f32; 4],
    pub atlas: [f32; 4],
    pub imagery: [f32; 4],
    /// The node's cells replaced by terrain-edit patches: bit `row * cells + col`.
    pub refined: [u32; 8],
    /// x: the node's cells a side when it has patches (0: none).
    pub edit: [f32; 4],
}

struct Slot {
    key: NodeKey,
    cut: NodeCut,
    /// The mesh's triangles, on the slot's vertices.
    indices: Vec<u16>,
    loading_skirt_m: f32,
    data_level: u8,
    detail_level: u8,
    centre_ecef: glam::DVec3,
    axes: [glam::DVec3; 3],
    last_used_frame: u64,
    /// The terrain edits' patches over the node (finest-level data only), as of the cache's
    /// edits revision `patch_revision`.
    patch: Option<std::sync::Arc<NodePatches>>,
    patch_revision: Option<u64>,
    /// The patch's cells, remade only where the edits changed them.
    cell_patches: CellPatches,
}

/// The terrain's GPU resources.
pub struct TerrainGpu {
    pub node_cells: u32,
    pub vertices_per_node: u32,
    pub capacity: usize,
    texels: u32,
    slots_per_row: u32,
    atlas_size: u32,
    /// Spacing of the database's finest posts, metres.
    finest_post_m: f32,
    pub vertex_pool: wgpu::Buffer,
    /// The drawn triangles of one view, on the vertex pool (grown as views need).
    pub index_buffer: wgpu::Buffer,
    index_capacity: u64,
    pub normal_atlas: wgpu::Texture,
    pub colour_atlas: wgpu::Texture,
    /// A view's terrain-edit patches (made when there are any).
    pub patch_vertices: Option<wgpu::Buffer>,
    pub patch_indices: Option<wgpu::Buffer>,
    /// The patches' marks (`TerrainFrame::patch_marks`), the terrain pipelines' group 2.
    patch_marks: wgpu::Buffer,
    pub marks_layout: wgpu::BindGroupLayout,
    pub marks_bind: wgpu::BindGroup,
    /// UTC time the patch marks' times count from (set by the first frame).
    marks_origin_utc_s: Option<f64>,
    slots: Vec<Option<Slot>>,
    by_key: HashMap<NodeKey, usize>,
    /// Where this view's records place nodes in the draped imagery (none without imagery).
    pub imagery_frame: Option<crate::imagery::ImageryFrame>,
    free: Vec<usize>,
}

/// What happened to the meshes in one frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeshStats {
    pub built: usize,
    pub deferred: usize,
    pub dropped: usize,
    /// Ancestors drawn in place of nodes whose meshes are not built yet.
    pub stand_ins: usize,
}

/// What one view draws of the terrain.
#[derive(Clone, Debug, Default)]
pub struct TerrainFrame {
    /// Shader records by slot (zero for slots not drawn).
    pub records: Vec<NodeRecord>,
    /// The drawn nodes' triangles, nearest node first, as vertex pool indices.
    pub indices: Vec<u32>,
    /// Nodes drawn (stand-ins included).
    pub nodes: usize,
    /// The drawn nodes' terrain-edit patches: vertices whose skirt field names their slot
    /// (`-(slot + 1)`, less a half at a skirt's foot), and their triangles.
    pub patch_vertices: Vec<TerrainVertex>,
    pub patch_indices: Vec<u32>,
    /// The patches' marks: first the frame's time from the marks' origin (x), then one per
    /// patch vertex (the shader reads vertex `i`'s at `i + 1`).
    pub patch_marks: Vec<PatchMarks>,
}

/// How far the frame's time may be from the patch marks' time origin before the origin moves
/// (and every patch is rebuilt): 10 days, where single floats still hold a second.
const MARKS_ORIGIN_SPAN_S: f64 = 864_000.0;

/// Skirt depth of a node drawn from its own level's data, metres: the floor under the depth
/// that grows with distance (see [`TerrainGpu::prepare`]).
const SKIRT_FLOOR_M: f32 = 0.5;

/// Skirt depth per metre of distance over the error the view allows per metre: neighbours each
/// lie within the allowed error of the finest surface, so at most twice it apart; 10 % more.
const SKIRT_OVER_ALLOWED_ERROR: f64 = 2.2;

impl TerrainGpu {
    /// `finest_post_m`: the spacing of the database's finest posts, metres (the shader sizes
    /// its material borders by it).
    pub fn new(gpu: &Gpu, node_cells: u32, capacity: usize, finest_post_m: f32) -> TerrainGpu {
        let device = &gpu.device;
        let vertices_per_node = terrain_mesh::vertex_count(node_cells) as u32;
        let index_capacity =
            (capacity as u64 * terrain_mesh::max_index_count(node_cells) as u64).min(1 << 20);
        let texels = terrain_mesh::texels_per_side(node_cells) as u32;
        let max_dim = device.limits().max_texture_dimension_2d;
        let slots_per_row = ((capacity as f64).sqrt().ceil() as u32)
            .min(max_dim / texels)
            .max(1);
        let capacity = capacity.min((slots_per_row * slots_per_row) as usize);
        let atlas_size = slots_per_row * texels;
        let vertex_pool = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("terrain vertex pool"),
            size: (capacity as u64)
                * u64::from(vertices_per_node)
                * std::mem::size_of::<TerrainVertex>() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let index_buffer = index_buffer(device, index_capacity);
        let atlas = |label, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: atlas_size,
                    height: atlas_size,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        };
        let marks_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("terrain edit marks"),
            entries: &[crate::pass::storage_entry(0)],
        });
        let patch_marks = marks_buffer(device, 1024);
        let marks_bind = marks_bind_group(device, &marks_layout, &patch_marks);
        TerrainGpu {
            node_cells,
            vertices_per_node,
            capacity,
            texels,
            slots_per_row,
            atlas_size,
            finest_post_m,
            vertex_pool,
            index_buffer,
            index_capacity,
            normal_atlas: atlas("terrain normals", wgpu::TextureFormat::Rgba8Unorm),
            colour_atlas: atlas("terrain colours", wgpu::TextureFormat::Rgba8UnormSrgb),
            patch_vertices: None,
            patch_indices: None,
            patch_marks,
            marks_layout,
            marks_bind,
            marks_origin_utc_s: None,
            slots: (0..capacity).map(|_| None).collect(),
            by_key: HashMap::new(),
            imagery_frame: None,
            free: (0..capacity).rev().collect(),
        }
    }

    fn allocate(&mut self, frame: u64) -> Option<usize> {
        if let Some(slot) = self.free.pop() {
            return Some(slot);
        }
        // Recycle the least recently used slot not used this frame.
        let (index, _) = self
            .slots
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.as_ref().map(|s| (i, s.last_used_frame)))
            .filter(|&(_, used)| used < frame)
            .min_by_key(|&(_, used)| used)?;
        if let Some(old) = self.slots[index].take() {
            self.by_key.remove(&old.key);
        }
        Some(index)
    }

    /// Makes sure each selected node has a mesh built from the best data resident, building at
    /// most `build_budget` meshes, and returns the records to draw. A node beyond the budget
    /// keeps an older mesh; one with none is replaced by its nearest ancestor that has a mesh,
    /// which then stands in for every selected node below it (no holes while meshes build).
    /// `min_morph[i]` is the least morph of `nodes[i]` (fading finer data in).
    #[allow(clippy::too_many_arguments, reason = "one frame's inputs, all needed")]
    pub fn prepare(
        &mut self,
        gpu: &Gpu,
        lod: &TerrainLod,
        cache: &TileCache,
        nodes: &[SelectedNode],
        min_morph: &[f32],
        eye_ecef: glam::DVec3,
        allowed_error_per_m: f64,
        (frame, now_utc_s): (u64, f64),
        build_budget: usize,
        out: &mut TerrainFrame,
    ) -> MeshStats {
        let skirt_per_m = (SKIRT_OVER_ALLOWED_ERROR * allowed_error_per_m) as f32;
        let mut stats = MeshStats::default();
        let edits = cache.edits();
        // The marks' times are kept near the frame's (single floats): a new origin, hour
        // aligned, remakes every patch.
        let origin_utc_s = match self.marks_origin_utc_s {
            Some(o) if (now_utc_s - o).abs() <= MARKS_ORIGIN_SPAN_S => o,
            _ => {
                let o = if now_utc_s.is_finite() {
                    (now_utc_s / 3600.0).floor() * 3600.0
                } else {
                    0.0
                };
                self.marks_origin_utc_s = Some(o);
                for slot in self.slots.iter_mut().flatten() {
                    slot.patch_revision = None;
                    slot.cell_patches = CellPatches::default();
                }
                o
            }
        };
        // Pass 1: a slot for every node that can have one this frame.
        let mut slot_of: Vec<Option<usize>> = Vec::with_capacity(nodes.len());
        for node in nodes {
            let existing = self.by_key.get(&node.key).copied();
            let detail_key = (node.key.level > 0)
                .then(|| lod.layout.tile_of(node.key, node.key.level - 1))
                .and_then(|k| cache.resident(k).map(|t| (k, t)));
            let wanted_detail = detail_key
                .as_ref()
                .map_or(node.data_level, |(k, _)| k.level);
            let up_to_date = existing
                .and_then(|i| self.slots[i].as_ref())
                .is_some_and(|s| {
                    s.data_level == node.data_level
                        && s.detail_level == wanted_detail
                        && s.cut == node.cut
                });
            let slot_index = if up_to_date {
                existing
            } else if stats.built < build_budget {
                match lod.resident_source(cache, node.key) {
                    Some((data_key, data_tile)) => {
                        let index = match existing {
                            Some(i) => Some(i),
                            None => self.allocate(frame),
                        };
                        if let Some(index) = index {
                            let parent = lod
                                .layout
                                .parent_tile(node.key)
                                .and_then(|k| cache.resident(k).map(|t| (k, t)));
                            let mut mesh = terrain_mesh::build_node_mesh(
                                &lod.layout,
                                lod.geoid(),
                                node.key,
                                terrain_mesh::NodeTiles {
                                    data: (data_key, &data_tile),
                                    detail: detail_key.as_ref().map(|(k, t)| (*k, t.as_ref())),
                                    parent: parent.as_ref().map(|(k, t)| (*k, t.as_ref())),
                                },
                                node.error_m,
                                node.cut,
                            );
                            self.upload(gpu, index, &mesh);
                            self.slots[index] = Some(Slot {
                                key: node.key,
                                cut: node.cut,
                                indices: std::mem::take(&mut mesh.indices),
                                loading_skirt_m: mesh.skirt_depth_m,
                                data_level: mesh.data_level,
                                detail_level: mesh.detail_level,
                                centre_ecef: mesh.centre_ecef,
                                axes: mesh.axes,
                                last_used_frame: frame,
                                patch: None,
                                patch_revision: None,
                                cell_patches: CellPatches::default(),
                            });
                            self.by_key.insert(node.key, index);
                            stats.built += 1;
                        } else {
                            stats.dropped += 1;
                        }
                        index
                    }
                    None => existing,
                }
            } else {
                stats.deferred += 1;
                existing
            };
            if let Some(slot) = slot_index.and_then(|i| self.slots[i].as_mut()) {
                slot.last_used_frame = frame;
                // The edits' patches, remade when the edits in the node's tile change.
                if slot.data_level == 0 {
                    let tile = lod.layout.tile_of(slot.key, 0);
                    let revision = edits.tile_revision(tile.row, tile.col);
                    if slot.patch_revision != Some(revision) {
                        if let Some((k, data)) = lod
                            .resident_source(cache, slot.key)
                            .filter(|(k, _)| k.level == 0)
                        {
                            slot.patch_revision = Some(revision);
                            slot.patch = PatchedNode {
                                layout: &lod.layout,
                                geoid: lod.geoid(),
                                key: slot.key,
                                tile: (k, &data),
                                centre_ecef: slot.centre_ecef,
                                edits: &edits,
                                time_origin_utc_s: origin_utc_s,
                            }
                            .build(&mut slot.cell_patches)
                            .map(std::sync::Arc::new);
                        }
                    }
                }
            }
            slot_of.push(slot_index);
        }
        // Pass 2: ancestors stand in for nodes that have no mesh yet.
        let mut stand_ins: Vec<(NodeKey, usize)> = Vec::new();
        for (node, slot) in nodes.iter().zip(&slot_of) {
            if slot.is_some() {
                continue;
            }
            let mut key = node.key;
            while key.level + 1 < lod.layout.pyramid.levels {
                key = key.parent();
                if let Some(&index) = self.by_key.get(&key) {
                    if !stand_ins.iter().any(|(k, _)| *k == key) {
                        stand_ins.push((key, index));
                    }
                    break;
                }
            }
        }
        let covered = |key: NodeKey| {
            stand_ins.iter().any(|(a, _)| {
                a.level > key.level
                    && key.row >> (a.level - key.level) == a.row
                    && key.col >> (a.level - key.level) == a.col
            })
        };
        // Where a node shows more error than its distance allows (its finer tiles or its mesh
        // are not there yet), its neighbours may be that far from it: every skirt of the view
        // reaches that deep while it lasts.
        let mut floor_m = SKIRT_FLOOR_M;
        for (node, slot) in nodes.iter().zip(&slot_of) {
            let Some(index) = slot else { continue };
            let shown_m = if self.settled(*index, node) {
                f64::from(node.cut.tolerance_m.max(node.error_m))
            } else {
                f64::from(self.loading_skirt_m(*index))
            };
            let excess_m = shown_m - allowed_error_per_m * node.distance_m;
            if excess_m > 0.0 {
                floor_m = floor_m.max((SKIRT_OVER_ALLOWED_ERROR * excess_m) as f32);
            }
        }
        for (_, index) in &stand_ins {
            floor_m = floor_m.max(self.loading_skirt_m(*index));
        }
        // The caller's buffers, kept from frame to frame.
        out.records.clear();
        out.indices.clear();
        out.patch_vertices.clear();
        out.patch_indices.clear();
        out.patch_marks.clear();
        out.patch_marks
            .push([(now_utc_s - origin_utc_s) as f32, 0.0, 0.0, 0.0]);
        out.nodes = 0;
        for (i, (node, slot)) in nodes.iter().zip(&slot_of).enumerate() {
            if let Some(index) = slot {
                if !covered(node.key) {
                    let least = min_morph.get(i).copied().unwrap_or(0.0);
                    let loading_m = self.loading_skirt_m(*index).max(floor_m);
                    let skirt = if self.settled(*index, node) {
                        (floor_m, skirt_per_m, loading_m)
                    } else {
                        (loading_m, 0.0, loading_m)
                    };
                    // A mesh kept past the build budget morphs as its own cut does.
                    let (start_m, end_m) = match self.slots[*index].as_ref() {
                        Some(s) if s.cut != node.cut => {
                            band_of(s.cut, node.morph_end_m, allowed_error_per_m)
                        }
                        _ => (node.morph_start_m, node.morph_end_m),
                    };
                    if let Some(record) =
                        self.record(*index, start_m, end_m, least, skirt, eye_ecef)
                    {
                        self.add_to_frame(out, *index, record);
                    }
                }
            }
        }
        for (_, index) in &stand_ins {
            if let Some(slot) = self.slots[*index].as_mut() {
                slot.last_used_frame = frame;
            }
            let loading_m = self.loading_skirt_m(*index).max(floor_m);
            let skirt = (loading_m, 0.0, loading_m);
            if let Some(record) =
                self.record(*index, f32::INFINITY, f32::INFINITY, 0.0, skirt, eye_ecef)
            {
                self.add_to_frame(out, *index, record);
            }
        }
        stats.stand_ins = stand_ins.len();
        stats
    }

    /// True when slot `index` holds `node`'s mesh from its own level's data and its cut.
    fn settled(&self, index: usize, node: &SelectedNode) -> bool {
        self.slots
            .get(index)
            .and_then(|s| s.as_ref())
            .is_some_and(|s| s.data_level == node.key.level && s.cut == node.cut)
    }

    /// The skirt depth of slot `index`'s mesh drawn while data loads.
    fn loading_skirt_m(&self, index: usize) -> f32 {
        self.slots
            .get(index)
            .and_then(|s| s.as_ref())
            .map_or(SKIRT_FLOOR_M, |s| s.loading_skirt_m)
    }

    /// Adds slot `index`'s triangles and record to a view's frame.
    fn add_to_frame(&self, out: &mut TerrainFrame, index: usize, mut record: NodeRecord) {
        let Some(slot) = self.slots.get(index).and_then(|s| s.as_ref()) else {
            return;
        };
        if out.records.len() <= index {
            out.records.resize(index + 1, NodeRecord::default());
        }
        if let Some(patch) = slot.patch.as_ref().filter(|_| slot.data_level == 0) {
            record.refined = patch.refined_mask;
            record.edit[0] = self.node_cells as f32;
            let tag = -(index as f32 + 1.0);
            patch.append_to(
                (
                    &mut out.patch_vertices,
                    &mut out.patch_indices,
                    &mut out.patch_marks,
                ),
                |v| TerrainVertex {
                    skirt: tag - 0.5 * v.skirt,
                    ..*v
                },
            );
        }
        out.records[index] = record;
        let base = index as u32 * self.vertices_per_node;
        out.indices
            .extend(slot.indices.iter().map(|&i| base + u32::from(i)));
        out.nodes += 1;
    }

    /// Writes a view's terrain-edit patches to their buffers, growing them when they do not
    /// fit.
    pub fn write_patches(
        &mut self,
        gpu: &Gpu,
        vertices: &[TerrainVertex],
        indices: &[u32],
        marks: &[PatchMarks],
    ) {
        if indices.is_empty() {
            return;
        }
        let marks_bytes = std::mem::size_of_val(marks) as u64;
        if self.patch_marks.size() < marks_bytes {
            self.patch_marks = marks_buffer(&gpu.device, marks_bytes);
            self.marks_bind = marks_bind_group(&gpu.device, &self.marks_layout, &self.patch_marks);
        }
        gpu.queue
            .write_buffer(&self.patch_marks, 0, bytemuck::cast_slice(marks));
        let vertex_bytes = std::mem::size_of_val(vertices) as u64;
        let index_bytes = std::mem::size_of_val(indices) as u64;
        let grow = |buffer: &mut Option<wgpu::Buffer>, bytes: u64, usage, label| {
            if buffer.as_ref().is_none_or(|b| b.size() < bytes) {
                *buffer = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: bytes.next_power_of_two().max(1024),
                    usage: usage | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }));
            }
        };
        grow(
            &mut self.patch_vertices,
            vertex_bytes,
            wgpu::BufferUsages::VERTEX,
            "terrain edit patch vertices",
        );
        grow(
            &mut self.patch_indices,
            index_bytes,
            wgpu::BufferUsages::INDEX,
            "terrain edit patch indices",
        );
        if let (Some(v), Some(i)) = (&self.patch_vertices, &self.patch_indices) {
            gpu.queue.write_buffer(v, 0, bytemuck::cast_slice(vertices));
            gpu.queue.write_buffer(i, 0, bytemuck::cast_slice(indices));
        }
    }

    /// Writes a view's triangles to the index buffer, growing it when they do not fit.
    pub fn write_indices(&mut self, gpu: &Gpu, indices: &[u32]) {
        let needed = indices.len() as u64;
        if needed > self.index_capacity {
            self.index_capacity = needed.next_power_of_two();
            self.index_buffer = index_buffer(&gpu.device, self.index_capacity);
        }
        if !indices.is_empty() {
            gpu.queue
                .write_buffer(&self.index_buffer, 0, bytemuck::cast_slice(indices));
        }
    }

    /// The shader record of the mesh in slot `index`; its skirts hang `floor_m + per_m * d`
    /// at distance `d`, at most `most_m`.
    fn record(
        &self,
        index: usize,
        morph_start_m: f32,
        morph_end_m: f32,
        least_morph: f32,
        (skirt_floor_m, skirt_per_m, skirt_most_m): (f32, f32, f32),
        eye_ecef: glam::DVec3,
    ) -> Option<NodeRecord> {
        let slot = self.slots.get(index)?.as_ref()?;
        let offset = (slot.centre_ecef - eye_ecef).as_vec3();
        let (sx, sy) = (
            index as u32 % self.slots_per_row,
            index as u32 / self.slots_per_row,
        );
        let texel = 1.0 / self.atlas_size as f32;
        let axis = |v: glam::DVec3, w: f32| {
            let v = v.as_vec3();
            [v.x, v.y, v.z, w]
        };
        Some(NodeRecord {
            offset: [offset.x, offset.y, offset.z, skirt_per_m],
            // w: texels per post of the data the colours were sampled from (texels are at
            // half the node's post spacing; the detail level's posts may be finer or coarser).
            axis_e: axis(
                slot.axes[0],
                texels_per_post(slot.detail_level, slot.key.level, self.texels),
            ),
            // w: the post spacing of that data, metres.
            axis_n: axis(
                slot.axes[1],
                self.finest_post_m * 2f32.powi(i32::from(slot.detail_level)),
            ),
            axis_u: axis(slot.axes[2], skirt_most_m),
            morph: [
                morph_start_m.min(1e30),
                morph_end_m.min(1.5e30),
                skirt_floor_m,
                least_morph.clamp(0.0, 1.0),
            ],
            // Texel centres of the slot's first and last texel span the node.
            atlas: [
                (sx * self.texels) as f32 * texel + 0.5 * texel,
                (sy * self.texels) as f32 * texel + 0.5 * texel,
                (self.texels - 1) as f32 * texel,
                (self.texels - 1) as f32 * texel,
            ],
            imagery: self.imagery_frame.map_or([0.0; 4], |frame| {
                let span = u64::from(self.node_cells) << slot.key.level;
                frame.node_rect(
                    (
                        u64::from(slot.key.row) * span,
                        u64::from(slot.key.col) * span,
                    ),
                    span,
                )
            }),
            refined: [0; 8],
            edit: [0.0; 4],
        })
    }

    fn upload(&self, gpu: &Gpu, index: usize, mesh: &terrain_mesh::NodeMesh) {
        let stride = std::mem::size_of::<TerrainVertex>() as u64;
        gpu.queue.write_buffer(
            &self.vertex_pool,
            index as u64 * u64::from(self.vertices_per_node) * stride,
            bytemuck::cast_slice(&mesh.vertices),
        );

        let (sx, sy) = (
            index as u32 % self.slots_per_row,
            index as u32 / self.slots_per_row,
        );
        for (texture, texels) in [
            (&self.normal_atlas, &mesh.normals),
            (&self.colour_atlas, &mesh.colours),
        ] {
            gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: sx * self.texels,
                        y: sy * self.texels,
                        z: 0,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(texels),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.texels * 4),
                    rows_per_image: Some(self.texels),
                },
                wgpu::Extent3d {
                    width: self.texels,
                    height: self.texels,
                    depth_or_array_layers: 1,
                },
            );
        }
    }

    /// Nodes with a mesh on the GPU.
    pub fn resident_nodes(&self) -> usize {
        self.by_key.len()
    }
}

/// An index buffer of `entries` 32-bit indices.
fn index_buffer(device: &wgpu::Device, entries: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("terrain indices"),
        size: entries.max(1) * 4,
        usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The morph band (start, end) of a mesh cut at `cut` for a view that allows
/// `allowed_error_per_m` per metre of distance (the selection's, for a mesh built for an
/// earlier cut of its node): from its tolerance's error distance to the one it morphs to, or
/// to the parent's range `parent_range_m`.
fn band_of(cut: NodeCut, parent_range_m: f32, allowed_error_per_m: f64) -> (f32, f32) {
    if allowed_error_per_m.is_nan()
        || allowed_error_per_m <= 0.0
        || !cut.parent_tolerance_m.is_finite()
    {
        return (f32::INFINITY, f32::INFINITY);
    }
    // The selection's range function, with pixels per unit of error for pixels per tangent.
    let range_m =
        |t: f32| cig_scene::lod::error_range_m(f64::from(t), 1.0 / allowed_error_per_m, 1.0) as f32;
    let end_m = if cut.morphs_within_level {
        range_m(cut.parent_tolerance_m)
    } else {
        parent_range_m
    };
    (range_m(cut.tolerance_m).min(end_m), end_m)
}

/// Texels of a node's colour atlas per post of the data its colours were sampled from: texels
/// lie at half the node's post spacing (`texels_per_side = 2n + 1`), so a post of level
/// `detail_level` spans `2^(detail_level + 1 - node_level)` texels; a node drawn from data so
/// much coarser that a post would span the whole node counts its whole side as one post, so
/// the shader never reads outside the node's texels.
pub(crate) fn texels_per_post(detail_level: u8, node_level: u8, texels_per_side: u32) -> f32 {
    let exponent = (i32::from(detail_level) + 1 - i32::from(node_level)).clamp(0, 30);
    let side = texels_per_side.saturating_sub(1).max(1);
    (1u32 << exponent).min(side) as f32
}

/// A storage buffer for patch marks of at least `bytes` (a power of two).
fn marks_buffer(device: &wgpu::Device, bytes: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("terrain edit marks"),
        size: bytes.next_power_of_two().max(1024),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn marks_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffer: &wgpu::Buffer,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("terrain edit marks"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    })
}

#[cfg(test)]
mod texel_tests {
    use super::texels_per_post;

    #[test]
    fn texels_per_post_follow_the_data_level_and_stay_inside_the_node() {
        // 16-cell nodes: 33 texels a side.
        assert_eq!(texels_per_post(0, 1, 33), 1.0, "finer data: a texel a post");
        assert_eq!(
            texels_per_post(3, 3, 33),
            2.0,
            "the node's own data: two texels a post"
        );
        assert_eq!(texels_per_post(5, 3, 33), 8.0, "coarser data");
        assert_eq!(
            texels_per_post(9, 3, 33),
            32.0,
            "far coarser: the whole side"
        );
        assert_eq!(texels_per_post(20, 0, 33), 32.0);
        assert_eq!(texels_per_post(0, 3, 33), 1.0, "never under a texel");
    }
}
