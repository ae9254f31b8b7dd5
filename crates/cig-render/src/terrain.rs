//! GPU side of the terrain: a pool of fixed-size node meshes in one vertex buffer, their normal
//! and colour texels in two atlases, and the pipeline that morphs and shades them.
//!
//! Algorithm: every node mesh has the same vertex count and topology, so one shared index
//! buffer serves them all and a node is drawn with `base_vertex = slot * vertices_per_node`;
//! its per-node record (eye-relative centre, frame, morph distances, atlas rectangle) is read by
//! instance index from a storage buffer written once per view. Slots are recycled least
//! recently used. Meshes are rebuilt when finer data becomes resident.
//!
//! Limits: the pool holds `capacity` nodes (the database's node count, at most 16384 of 16 cells,
//! about 270 MB with the atlases); a view that needs more (full detail over a very large
//! database) draws the nearest ones and reports the rest as dropped in its statistics.

use crate::gpu::Gpu;
use cig_scene::lod::{NodeKey, SelectedNode, TerrainLod};
use cig_scene::terrain_mesh::{self, TerrainVertex};
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
}

struct Slot {
    key: NodeKey,
    data_level: u8,
    detail_level: u8,
    centre_ecef: glam::DVec3,
    axes: [glam::DVec3; 3],
    last_used_frame: u64,
}

/// The terrain's GPU resources.
pub struct TerrainGpu {
    pub node_cells: u32,
    pub vertices_per_node: u32,
    pub index_count: u32,
    pub grid_triangles: u32,
    pub capacity: usize,
    texels: u32,
    slots_per_row: u32,
    atlas_size: u32,
    pub vertex_pool: wgpu::Buffer,
    pub index_buffer: wgpu::Buffer,
    pub normal_atlas: wgpu::Texture,
    pub colour_atlas: wgpu::Texture,
    slots: Vec<Option<Slot>>,
    by_key: HashMap<NodeKey, usize>,
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

impl TerrainGpu {
    pub fn new(gpu: &Gpu, node_cells: u32, capacity: usize) -> TerrainGpu {
        let device = &gpu.device;
        let vertices_per_node = terrain_mesh::vertex_count(node_cells) as u32;
        let indices = terrain_mesh::indices(node_cells);
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
        let index_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("terrain indices"),
            size: (indices.len() * 4) as u64,
            usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue
            .write_buffer(&index_buffer, 0, bytemuck::cast_slice(&indices));
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
        TerrainGpu {
            node_cells,
            vertices_per_node,
            index_count: indices.len() as u32,
            grid_triangles: node_cells * node_cells * 2,
            capacity,
            texels,
            slots_per_row,
            atlas_size,
            vertex_pool,
            index_buffer,
            normal_atlas: atlas("terrain normals", wgpu::TextureFormat::Rgba8Unorm),
            colour_atlas: atlas("terrain colours", wgpu::TextureFormat::Rgba8UnormSrgb),
            slots: (0..capacity).map(|_| None).collect(),
            by_key: HashMap::new(),
            free: (0..capacity).rev().collect(),
        }
    }

    /// Triangles of one node (grid and skirts).
    pub fn triangles_per_node(&self) -> u32 {
        self.index_count / 3
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
        frame: u64,
        build_budget: usize,
    ) -> (Vec<NodeRecord>, MeshStats) {
        let mut stats = MeshStats::default();
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
                    s.data_level == node.data_level && s.detail_level == wanted_detail
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
                            let mesh = terrain_mesh::build_node_mesh(
                                &lod.layout,
                                lod.geoid(),
                                node.key,
                                (data_key, &data_tile),
                                detail_key.as_ref().map(|(k, t)| (*k, t.as_ref())),
                                node.error_m,
                            );
                            self.upload(gpu, index, &mesh);
                            self.slots[index] = Some(Slot {
                                key: node.key,
                                data_level: mesh.data_level,
                                detail_level: mesh.detail_level,
                                centre_ecef: mesh.centre_ecef,
                                axes: mesh.axes,
                                last_used_frame: frame,
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
        let mut records = Vec::with_capacity(nodes.len() + stand_ins.len());
        for (i, (node, slot)) in nodes.iter().zip(&slot_of).enumerate() {
            if let Some(index) = slot {
                if !covered(node.key) {
                    let least = min_morph.get(i).copied().unwrap_or(0.0);
                    records.extend(self.record(
                        *index,
                        node.morph_start_m,
                        node.morph_end_m,
                        least,
                        eye_ecef,
                    ));
                }
            }
        }
        for (_, index) in &stand_ins {
            if let Some(slot) = self.slots[*index].as_mut() {
                slot.last_used_frame = frame;
            }
            records.extend(self.record(*index, f32::INFINITY, f32::INFINITY, 0.0, eye_ecef));
        }
        stats.stand_ins = stand_ins.len();
        (records, stats)
    }

    /// The shader record of the mesh in slot `index`.
    fn record(
        &self,
        index: usize,
        morph_start_m: f32,
        morph_end_m: f32,
        least_morph: f32,
        eye_ecef: glam::DVec3,
    ) -> Option<NodeRecord> {
        let slot = self.slots.get(index)?.as_ref()?;
        let offset = (slot.centre_ecef - eye_ecef).as_vec3();
        let (sx, sy) = (
            index as u32 % self.slots_per_row,
            index as u32 / self.slots_per_row,
        );
        let texel = 1.0 / self.atlas_size as f32;
        let axis = |v: glam::DVec3| {
            let v = v.as_vec3();
            [v.x, v.y, v.z, 0.0]
        };
        Some(NodeRecord {
            offset: [
                offset.x,
                offset.y,
                offset.z,
                (index as u32 * self.vertices_per_node) as f32,
            ],
            axis_e: axis(slot.axes[0]),
            axis_n: axis(slot.axes[1]),
            axis_u: axis(slot.axes[2]),
            morph: [
                morph_start_m.min(1e30),
                morph_end_m.min(1.5e30),
                self.node_cells as f32,
                least_morph.clamp(0.0, 1.0),
            ],
            // Texel centres of the slot's first and last texel span the node.
            atlas: [
                (sx * self.texels) as f32 * texel + 0.5 * texel,
                (sy * self.texels) as f32 * texel + 0.5 * texel,
                (self.texels - 1) as f32 * texel,
                (self.texels - 1) as f32 * texel,
            ],
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
