//! Vertex data, skirts and per-pixel surface textures of one terrain node.
//!
//! Algorithm: a node of level `L` is a regular `(n + 1) x (n + 1)` grid of the level's posts
//! placed on the WGS84 ellipsoid (heights above mean sea level plus the database's geoid), in
//! ECEF relative to the node's centre so that single precision holds centimetres. Each vertex
//! carries a morph target: its place on the parent's mesh, i.e. the midpoint of its even
//! neighbours (along the south-west to north-east diagonal for cell centres, which is the
//! diagonal every triangle of the database uses). At full morph the node's surface is exactly
//! its parent's, so a node morphs continuously into its parent (CDLOD, Strugar 2010) and a fully
//! morphed node meets its coarser neighbour exactly. Where a node reaches past the database's
//! last row or column its vertices are clamped onto the edge, and so are the parent's; the
//! target is then taken on the parent's clamped cells with the parent level's heights, so the
//! edge stays where it is while the node morphs (the midpoint rule moved it inwards by up to a
//! cell and, with the finer level's heights, left a step of up to the parent's error there).
//! Skirts (a strip hanging down from each edge) hide the gaps left where neighbours differ by
//! more than one level or are drawn from different data while tiles load. Normals and colours are sampled at twice the vertex density, from the
//! next finer level when it is resident, for per-pixel lighting.
//!
//! Limits: normals are expressed in the node centre's east-north-up frame, which differs from
//! the local vertical by up to half the node's angular size (under 0.3 degree for nodes below
//! 60 km); materials are blended bilinearly in colour, not per class.

use crate::lod::{NodeKey, NodeLayout};
use cig_geo::{metres_per_degree, EnuFrame, Geodetic};
use cig_terrain::database::GeoidLookup;
use cig_terrain::raster::triangulated_height;
use cig_terrain::tile::Tile;
use cig_terrain::{Material, TileKey};
use glam::DVec3;

/// One terrain vertex: position and morph target relative to the node centre (ECEF axes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TerrainVertex {
    pub position: [f32; 3],
    pub morph_target: [f32; 3],
}

/// The CPU-side mesh and textures of one node.
#[derive(Clone, Debug)]
pub struct NodeMesh {
    pub key: NodeKey,
    /// Level of the posts the vertices come from.
    pub data_level: u8,
    /// Level of the posts the normals and colours come from.
    pub detail_level: u8,
    pub centre_ecef: DVec3,
    /// East, north and up at the centre (ECEF unit vectors): the frame of the normals.
    pub axes: [DVec3; 3],
    pub vertices: Vec<TerrainVertex>,
    /// `texels_per_side(n)^2` normals, RGBA8: xyz in the node's ENU frame mapped to 0..255.
    pub normals: Vec<[u8; 4]>,
    /// Same grid: sRGB colour of the surface material, alpha = specular (water, wet roads).
    pub colours: Vec<[u8; 4]>,
    /// Skirt depth, metres.
    pub skirt_depth_m: f32,
}

/// Vertices of a node of `n` cells a side: the grid and four skirts.
pub fn vertex_count(n: u32) -> usize {
    let s = n as usize + 1;
    s * s + 4 * s
}

/// Texels of a node's normal and colour textures along a side.
pub fn texels_per_side(n: u32) -> usize {
    2 * n as usize + 1
}

/// The triangle list shared by every node of `n` cells a side (grid, then skirts).
pub fn indices(n: u32) -> Vec<u32> {
    let s = n + 1;
    let mut out = Vec::with_capacity((n * n * 6 + 4 * n * 6) as usize);
    for i in 0..n {
        for j in 0..n {
            let sw = i * s + j;
            let (se, nw) = (sw + 1, sw + s);
            let ne = nw + 1;
            out.extend_from_slice(&[sw, se, ne, sw, ne, nw]);
        }
    }
    for (edge, grid_index) in edges(n).iter().enumerate() {
        let base = s * s + edge as u32 * s;
        for t in 0..n {
            let (a, b) = (grid_index(t), grid_index(t + 1));
            let (sa, sb) = (base + t, base + t + 1);
            out.extend_from_slice(&[a, b, sb, a, sb, sa]);
        }
    }
    out
}

type EdgeIndex = Box<dyn Fn(u32) -> u32>;

/// The four edges (south, north, west, east) as maps from position along the edge to the
/// grid vertex index.
fn edges(n: u32) -> [EdgeIndex; 4] {
    let s = n + 1;
    [
        Box::new(move |t| t),
        Box::new(move |t| n * s + t),
        Box::new(move |t| t * s),
        Box::new(move |t| t * s + n),
    ]
}

/// A point of a grid cell's surface, split as the database splits every cell (south-west to
/// north-east; see `cig_terrain::raster::triangulated_height`), from its corners and the
/// fractions `east` and `north` across it.
pub fn triangulated_point([sw, se, nw, ne]: [DVec3; 4], east: f64, north: f64) -> DVec3 {
    if east >= north {
        sw + (se - sw) * east + (ne - se) * north
    } else {
        sw + (nw - sw) * north + (ne - nw) * east
    }
}

/// Base colour (sRGB) and specular weight of a material.
pub fn material_colour(m: Material) -> [u8; 4] {
    match m {
        Material::Water => [38, 66, 92, 255],
        Material::Sand => [194, 178, 128, 0],
        Material::DryClay => [158, 120, 86, 0],
        Material::Grass => [96, 122, 62, 0],
        Material::Forest => [52, 76, 42, 0],
        Material::Rock => [122, 116, 108, 0],
        Material::Snow => [236, 239, 243, 40],
        Material::PavedRoad => [72, 72, 74, 60],
        Material::DirtRoad => [140, 116, 86, 0],
    }
}

/// Samples one resident tile on the finest grid's fractional indices.
struct Sampler<'a> {
    key: TileKey,
    tile: &'a Tile,
    tile_span: f64,
    scale: f64,
    max_index: f64,
}

impl<'a> Sampler<'a> {
    fn new(layout: &NodeLayout, key: TileKey, tile: &'a Tile) -> Sampler<'a> {
        Sampler {
            key,
            tile,
            tile_span: layout.pyramid.finest_cells_per_tile(key.level) as f64,
            scale: (1u64 << key.level) as f64,
            max_index: tile.cells() as f64,
        }
    }

    fn local(&self, row: f64, col: f64) -> (f64, f64) {
        (
            ((row - f64::from(self.key.row) * self.tile_span) / self.scale)
                .clamp(0.0, self.max_index),
            ((col - f64::from(self.key.col) * self.tile_span) / self.scale)
                .clamp(0.0, self.max_index),
        )
    }

    /// Clamps a finest-grid row and column to this tile's extent.
    fn clamp_to_tile(&self, row: f64, col: f64) -> (f64, f64) {
        let r0 = f64::from(self.key.row) * self.tile_span;
        let c0 = f64::from(self.key.col) * self.tile_span;
        (
            row.clamp(r0, r0 + self.max_index * self.scale),
            col.clamp(c0, c0 + self.max_index * self.scale),
        )
    }

    fn height_msl_m(&self, row: f64, col: f64) -> f64 {
        let (fi, fj) = self.local(row, col);
        self.tile.surface_height(fi, fj)
    }

    /// The surface of the next coarser level as this tile's even posts define it (level
    /// `L + 1` keeps every other post of level `L`), on finest-grid indices.
    fn coarser_height_msl_m(&self, row: f64, col: f64) -> f64 {
        let (fi, fj) = self.local(row, col);
        let max_cell = (self.tile.cells() / 2).max(1) - 1;
        let (ci, cj) = (
            ((fi / 2.0).floor().max(0.0) as usize).min(max_cell),
            ((fj / 2.0).floor().max(0.0) as usize).min(max_cell),
        );
        let v = (fi / 2.0 - ci as f64).clamp(0.0, 1.0);
        let u = (fj / 2.0 - cj as f64).clamp(0.0, 1.0);
        let (i, j) = (2 * ci, 2 * cj);
        triangulated_height(
            self.tile.elevation(i, j),
            self.tile.elevation(i, j + 2),
            self.tile.elevation(i + 2, j),
            self.tile.elevation(i + 2, j + 2),
            u,
            v,
        )
    }

    fn material(&self, row: f64, col: f64) -> Material {
        let (fi, fj) = self.local(row, col);
        self.tile
            .material_at(fi.round() as usize, fj.round() as usize)
    }
}

/// Builds the mesh of `key` from the tile `data` (the node's level or coarser) and, when
/// resident, the finer tile `detail` for normals and colours.
pub fn build_node_mesh(
    layout: &NodeLayout,
    geoid: &GeoidLookup,
    key: NodeKey,
    data: (TileKey, &Tile),
    detail: Option<(TileKey, &Tile)>,
    error_m: f32,
) -> NodeMesh {
    let n = layout.node_cells;
    let s = n as usize + 1;
    let grid = &layout.pyramid.grid;
    let max_row = (grid.rows.max(1) - 1) as f64;
    let max_col = (grid.cols.max(1) - 1) as f64;
    let (r0, c0) = layout.finest_origin(key);
    let (r0, c0) = (r0 as f64, c0 as f64);
    let span = layout.finest_span(key.level) as f64;
    let step = span / f64::from(n);
    let data_sampler = Sampler::new(layout, data.0, data.1);
    let detail_sampler = detail.map(|(k, t)| Sampler::new(layout, k, t));
    let detail_sampler = detail_sampler.as_ref().unwrap_or(&data_sampler);

    let (lat_c, lon_c) = layout.lat_lon_of_finest(r0 + span / 2.0, c0 + span / 2.0);
    let centre_height = data_sampler.height_msl_m(
        (r0 + span / 2.0).min(max_row),
        (c0 + span / 2.0).min(max_col),
    ) + geoid.undulation_m(lat_c, lon_c);
    let frame = EnuFrame::new(Geodetic::new(lat_c, lon_c, centre_height));
    let centre_ecef = frame.origin_ecef();
    let axes = [
        frame.enu_vector_to_ecef(DVec3::X),
        frame.enu_vector_to_ecef(DVec3::Y),
        frame.enu_vector_to_ecef(DVec3::Z),
    ];

    // Grid positions (ECEF relative to the centre, double precision until the end).
    let mut rel = vec![DVec3::ZERO; s * s];
    let (mut h_min, mut h_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let rel_row = |i: usize| (r0 + i as f64 * step).min(max_row);
    let rel_col = |j: usize| (c0 + j as f64 * step).min(max_col);
    for i in 0..s {
        let row = rel_row(i);
        for j in 0..s {
            let col = rel_col(j);
            let (lat, lon) = layout.lat_lon_of_finest(row, col);
            let h = data_sampler.height_msl_m(row, col);
            h_min = h_min.min(h);
            h_max = h_max.max(h);
            let ecef = Geodetic::new(lat, lon, h + geoid.undulation_m(lat, lon)).to_ecef();
            rel[i * s + j] = ecef - centre_ecef;
        }
    }
    // Morph targets: each vertex's place on the parent's mesh, i.e. on the parent's grid of
    // vertices (every other one of this node's, clamped onto the database's edge the same way)
    // with the parent level's heights, interpolated across the parent cell's triangles. Away
    // from the edge this is the midpoint of the vertex's even neighbours (along the south-west
    // to north-east diagonal for cell centres); at the edge it keeps the vertex where it is
    // horizontally, so the edge does not recede while a node morphs.
    let half = n as usize / 2;
    let parent_row = |a: usize| (r0 + (2 * a) as f64 * step).min(max_row);
    let parent_col = |b: usize| (c0 + (2 * b) as f64 * step).min(max_col);
    let parent_height = |row: f64, col: f64| {
        if data.0.level > key.level {
            data_sampler.height_msl_m(row, col)
        } else {
            data_sampler.coarser_height_msl_m(row, col)
        }
    };
    let ps = half + 1;
    let mut parent_rel = vec![DVec3::ZERO; ps * ps];
    for a in 0..ps {
        for b in 0..ps {
            let (row, col) = (parent_row(a), parent_col(b));
            let (lat, lon) = layout.lat_lon_of_finest(row, col);
            let h = parent_height(row, col) + geoid.undulation_m(lat, lon);
            parent_rel[a * ps + b] = Geodetic::new(lat, lon, h).to_ecef() - centre_ecef;
        }
    }
    // The parent cell holding grid line `k` (of `n + 1`) and the fraction across it.
    let parent_cell = |k: usize, own: f64, parent: &dyn Fn(usize) -> f64| -> (usize, f64) {
        let a = (k / 2).min(half - 1);
        let (start, end) = (parent(a), parent(a + 1));
        let fraction = if end > start {
            ((own - start) / (end - start)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a, fraction)
    };
    let morph_target = |i: usize, j: usize| -> DVec3 {
        let (a, north) = parent_cell(i, rel_row(i), &parent_row);
        let (b, east) = parent_cell(j, rel_col(j), &parent_col);
        let corner = |da: usize, db: usize| parent_rel[(a + da) * ps + b + db];
        triangulated_point(
            [corner(0, 0), corner(0, 1), corner(1, 0), corner(1, 1)],
            east,
            north,
        )
    };
    let span_m = span * grid.dlat_deg * metres_per_degree(lat_c).0;
    let skirt_depth_m =
        (5.0 + 0.02 * span_m + 3.0 * f64::from(error_m) + (h_max - h_min) * 0.1) as f32;
    let down = -axes[2] * f64::from(skirt_depth_m);
    let mut vertices = Vec::with_capacity(vertex_count(n));
    for i in 0..s {
        for j in 0..s {
            vertices.push(TerrainVertex {
                position: rel[i * s + j].as_vec3().to_array(),
                morph_target: morph_target(i, j).as_vec3().to_array(),
            });
        }
    }
    for grid_index in edges(n).iter() {
        for t in 0..=n {
            let g = grid_index(t) as usize;
            let (i, j) = (g / s, g % s);
            vertices.push(TerrainVertex {
                position: (rel[g] + down).as_vec3().to_array(),
                morph_target: (morph_target(i, j) + down).as_vec3().to_array(),
            });
        }
    }

    // Normals and colours at twice the vertex density.
    let t = texels_per_side(n);
    let texel_step = span / (t - 1) as f64;
    let (m_north, m_east) = metres_per_degree(lat_c);
    let dy_m = texel_step * grid.dlat_deg * m_north;
    let dx_m = texel_step * grid.dlon_deg * m_east;
    let mut normals = Vec::with_capacity(t * t);
    let mut colours = Vec::with_capacity(t * t);
    for a in 0..t {
        let row = r0 + a as f64 * texel_step;
        for b in 0..t {
            let col = c0 + b as f64 * texel_step;
            // Central differences, one-sided where the tile or the database ends (divided by
            // the distance actually sampled).
            let at = |dr: f64, dc: f64| {
                let (r, c) = detail_sampler.clamp_to_tile(
                    (row + dr).clamp(0.0, max_row),
                    (col + dc).clamp(0.0, max_col),
                );
                (r, c, detail_sampler.height_msl_m(r, c))
            };
            let (_, ce, he) = at(0.0, texel_step);
            let (_, cw, hw) = at(0.0, -texel_step);
            let (rn, _, hn) = at(texel_step, 0.0);
            let (rs, _, hs) = at(-texel_step, 0.0);
            let dzdx = if ce > cw {
                (he - hw) / ((ce - cw) / texel_step * dx_m)
            } else {
                0.0
            };
            let dzdy = if rn > rs {
                (hn - hs) / ((rn - rs) / texel_step * dy_m)
            } else {
                0.0
            };
            let normal = DVec3::new(-dzdx, -dzdy, 1.0).normalize();
            let enc = |v: f64| ((v * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8;
            normals.push([enc(normal.x), enc(normal.y), enc(normal.z), 255]);
            colours.push(material_colour(
                detail_sampler.material(row.min(max_row), col.min(max_col)),
            ));
        }
    }
    NodeMesh {
        key,
        data_level: data.0.level,
        detail_level: detail_sampler.key.level,
        centre_ecef,
        axes,
        vertices,
        normals,
        colours,
        skirt_depth_m,
    }
}
