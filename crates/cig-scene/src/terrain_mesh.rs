//! Vertex data, triangles, skirts and per-pixel surface textures of one terrain node.
//!
//! Algorithm: a node of level `L` covers `n x n` cells of the level's posts, placed on the
//! WGS84 ellipsoid (heights above mean sea level plus the database's geoid), in ECEF relative
//! to the node's centre so that single precision holds centimetres. Its triangles are a cut of
//! the right-triangulated irregular network (RTIN) over those posts ([`rtin_triangles`];
//! Evans, Kirkpatrick and Townsend 2001): the node's square split by its diagonal, each right
//! triangle split at its hypotenuse's midpoint while that post is kept, down to the level's
//! cells, which are split as the database splits them (a checkerboard, see
//! `cig_terrain::raster::Diagonal`), so keeping every post gives the database's own surface.
//! A post is kept when its level error (`cig_terrain::rtin`, stored in the tile) exceeds the
//! node's tolerance ([`NodeCut`]: the least error along the node's ancestors, or a larger step
//! of it, see `cig_scene::lod`), so every triangle of the cut is within the tolerance of the
//! finest posts, and the cut conforms. The node's quadrants are always split (the cut holds at
//! least 8 triangles) so that a child's share of its parent's cut depends on the child's posts
//! alone; every post of a level drawn as a regular grid above (a node reaching past the
//! database's edge, or one whose tile lacks its posts' errors) is kept, and the kept posts are
//! closed under the hierarchy whatever a tile's bytes say ([`closed`]), so a cut always
//! conforms. Each vertex carries a morph target: its place on the cut it
//! morphs to (its parent's, whose posts are this node's even posts, or its own at a larger
//! tolerance), found by walking that cut's hierarchy ([`locate`]). A child keeps every post its
//! parent keeps (post errors never decrease towards finer levels, tolerances never increase),
//! so its triangles lie inside its parent's and at full morph the node's surface is exactly
//! the one it morphs to (CDLOD, Strugar 2010): nothing pops when the selection switches.
//! Where a node reaches past the database's last row or column its vertices are clamped onto
//! the edge, and so are the parent's; such a node keeps every post, and its targets are taken
//! on the parent's clamped cells with the parent level's heights, so the edge stays where it is
//! while the node morphs. Only the vertices the triangles use are stored, each with its place
//! on the node's grid (for its texels). Skirts (a strip hanging from each edge's kept posts,
//! lowered by the shader as far as neighbours can differ at that distance) hide the gaps where
//! neighbours are cut differently or differ in level. Normals and colours are sampled at twice
//! the post density, from the next finer level when it is resident, for per-pixel lighting.
//!
//! Limits: normals are expressed in the node centre's east-north-up frame, which differs from
//! the local vertical by up to half the node's angular size (under 0.3 degree for nodes below
//! 60 km). Colour texels carry their material's index (`material_texel`) so the shader can
//! draw borders between classes as curves; materials are sampled at the texels (twice the post
//! density), so features narrower than a post are not resolved. Nodes drawn from a
//! coarser level's data while their tile loads, and tiles without post errors (format 1),
//! are drawn as regular grids (their children keep all their posts); a parent drawn from
//! coarser data is not the cut its children morph to (a pop of up to its error when its own
//! tile arrives, which the renderer's fade-in covers). A mesh kept past the renderer's build
//! budget is drawn with its own cut's morph band until it is rebuilt.

use crate::node::{NodeKey, NodeLayout};
use cig_geo::{metres_per_degree, EnuFrame, Geodetic};
use cig_terrain::database::GeoidLookup;
use cig_terrain::raster::{triangulated_height, Diagonal};
use cig_terrain::tile::{even_posts_per_side, LodErrors, Tile};
use cig_terrain::{Material, TileKey};
use glam::DVec3;

/// One terrain vertex: position and morph target relative to the node centre (ECEF axes),
/// its place on the node's grid (east, north; 0 to 1), where its texels are, and whether it
/// is the foot of a skirt (1) rather than a post (0): a skirt's foot lies at its edge post and
/// the shader lowers it by the skirt's depth for the view.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TerrainVertex {
    pub position: [f32; 3],
    pub morph_target: [f32; 3],
    pub grid_uv: [f32; 2],
    pub skirt: f32,
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
    /// The vertices the mesh uses: its kept grid posts, then its skirts' (at most
    /// [`vertex_count`]).
    pub vertices: Vec<TerrainVertex>,
    /// How many of `vertices` are grid posts (the rest hang from the edges).
    pub grid_vertices: usize,
    /// The triangle list, grid then skirts (at most [`max_index_count`]).
    pub indices: Vec<u16>,
    /// `texels_per_side(n)^2` normals, RGBA8: xyz in the node's ENU frame mapped to 0..255.
    pub normals: Vec<[u8; 4]>,
    /// Same grid: sRGB colour of the surface material, alpha = specular (water, wet roads).
    pub colours: Vec<[u8; 4]>,
    /// Skirt depth for a node drawn while its data is still loading (from a coarser level, or
    /// in place of its descendants), metres: enough for neighbours drawn from other data.
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

/// Indices of a node's mesh at most (every cell's two triangles and every skirt quad).
pub fn max_index_count(n: u32) -> usize {
    (n as usize * n as usize * 2 + 4 * n as usize * 2) * 3
}

/// How a node's mesh is cut from its level's posts (see [`build_node_mesh`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeCut {
    /// Posts whose level error ([`cig_terrain::tile::LodErrors`]) exceeds this are kept,
    /// metres: the least geometric error along the node and its ancestors, so that a child's
    /// kept posts include its parent's.
    pub tolerance_m: f32,
    /// The tolerance of the cut the mesh morphs to: the parent's (infinite for a root, which
    /// never morphs), or with `morphs_within_level` this node's own at a larger tolerance (the
    /// finest level's refinement steps, see `cig_scene::lod`).
    pub parent_tolerance_m: f32,
    pub morphs_within_level: bool,
    /// The level of the nearest ancestor drawn as a regular grid (one that reaches past the
    /// database's edge): every post of that level is kept, so that the node's mesh holds its
    /// ancestors' meshes.
    pub regular_ancestor_level: Option<u8>,
}

impl NodeCut {
    /// Every post kept (full detail, and the cut of nodes without level errors).
    pub const REGULAR: NodeCut = NodeCut {
        tolerance_m: -1.0,
        parent_tolerance_m: -1.0,
        morphs_within_level: false,
        regular_ancestor_level: None,
    };

    /// The cut of a node of geometric error `error_m` below a parent cut `parent` (`None` for
    /// a root), and whether the node itself is drawn as a regular grid.
    pub fn below(parent: Option<(NodeCut, u8, bool)>, error_m: f32) -> NodeCut {
        match parent {
            None => NodeCut {
                tolerance_m: error_m,
                parent_tolerance_m: f32::INFINITY,
                morphs_within_level: false,
                regular_ancestor_level: None,
            },
            Some((cut, parent_level, parent_regular)) => NodeCut {
                tolerance_m: error_m.min(cut.tolerance_m),
                parent_tolerance_m: cut.tolerance_m,
                morphs_within_level: false,
                regular_ancestor_level: if parent_regular {
                    Some(parent_level)
                } else {
                    cut.regular_ancestor_level
                },
            },
        }
    }
}

/// The posts of an `m`-cell square grid that `kept` keeps, and every post above a kept one in
/// the hierarchy (row-major, `(m + 1)^2`), so that the cut conforms whatever `kept` says.
fn closed(m: u32, kept: &dyn Fn(i32, i32) -> bool) -> Vec<bool> {
    let s = m as usize + 1;
    let mut out: Vec<bool> = (0..s * s)
        .map(|k| kept((k / s) as i32, (k % s) as i32))
        .collect();
    cig_terrain::rtin::fold_into_ancestors(s, s, &mut out, |a, b| a || b);
    out
}

/// A triangle of the hierarchy on a node's grid: its hypotenuse's ends and its right-angled
/// apex, as (row, column) grid indices.
type GridTriangle = [(i32, i32); 3];

/// The node square's two root triangles: its diagonal splits it as the database's checkerboard
/// of squares of its size splits it (`square_parity` = node row + column).
fn root_triangles(n: i32, square_parity: u32) -> [GridTriangle; 2] {
    let (sw, se, nw, ne) = ((0, 0), (0, n), (n, 0), (n, n));
    if square_parity.is_multiple_of(2) {
        [[sw, ne, se], [ne, sw, nw]]
    } else {
        [[se, nw, ne], [nw, se, sw]]
    }
}

fn midpoint([a, b, _]: &GridTriangle) -> Option<(i32, i32)> {
    let (r, c) = (a.0 + b.0, a.1 + b.1);
    (r % 2 == 0 && c % 2 == 0).then_some((r / 2, c / 2))
}

/// The two triangles a triangle splits into at its hypotenuse's midpoint `m`.
fn split([a, b, apex]: &GridTriangle, m: (i32, i32)) -> [GridTriangle; 2] {
    [[*apex, *a, m], [*b, *apex, m]]
}

fn cross(o: (i32, i32), p: (i32, i32), q: (i32, i32)) -> i64 {
    i64::from(p.0 - o.0) * i64::from(q.1 - o.1) - i64::from(p.1 - o.1) * i64::from(q.0 - o.0)
}

/// The triangles of the hierarchy on an `n`-cell grid that a set of kept posts cuts, down to
/// the grid's cells: a triangle splits where the midpoint of its hypotenuse is kept.
pub fn rtin_triangles(
    n: u32,
    square_parity: u32,
    kept: &dyn Fn(i32, i32) -> bool,
) -> Vec<GridTriangle> {
    let mut out = Vec::new();
    let mut stack: Vec<GridTriangle> = root_triangles(n as i32, square_parity).to_vec();
    while let Some(t) = stack.pop() {
        match midpoint(&t) {
            Some(m) if kept(m.0, m.1) => stack.extend(split(&t, m)),
            _ => out.push(t),
        }
    }
    out
}

/// The triangle of the hierarchy cut by `kept` (on grid posts `2x`, i.e. a parent's posts on a
/// child's grid when `step` is 2) that holds grid point `p`, and `p`'s barycentric weights in it.
fn locate(
    n: u32,
    square_parity: u32,
    step: i32,
    kept: &dyn Fn(i32, i32) -> bool,
    p: (i32, i32),
) -> (GridTriangle, [f64; 3]) {
    let roots = root_triangles(n as i32, square_parity);
    let side = cross(roots[0][0], roots[0][1], p);
    let mut t = if side * cross(roots[0][0], roots[0][1], roots[0][2]) >= 0 {
        roots[0]
    } else {
        roots[1]
    };
    loop {
        let m = midpoint(&t).filter(|m| m.0 % step == 0 && m.1 % step == 0);
        match m {
            Some(m) if kept(m.0, m.1) => {
                let [first, second] = split(&t, m);
                // The children meet along apex-m; `first` lies on the side of the old `a`.
                let (apex, a) = (t[2], t[0]);
                t = if cross(apex, m, p) * cross(apex, m, a) >= 0 {
                    first
                } else {
                    second
                };
            }
            _ => break,
        }
    }
    let [a, b, c] = t;
    let area = cross(a, b, c) as f64;
    let weights = [
        cross(p, b, c) as f64 / area,
        cross(a, p, c) as f64 / area,
        cross(a, b, p) as f64 / area,
    ];
    (t, weights)
}

/// A node's triangle list (grid, then skirts), counter-clockwise seen from above, as indices
/// into its vertices (grid `i * (n + 1) + j`, then the four skirts).
pub fn mesh_indices(triangles: &[GridTriangle], n: u32) -> Vec<u16> {
    let s = n as i32 + 1;
    let index = |(r, c): (i32, i32)| (r * s + c) as u16;
    let mut out = Vec::with_capacity(triangles.len() * 3 + 8 * n as usize * 3);
    let mut used = vec![false; (s * s) as usize];
    for t in triangles {
        let [a, b, c] = *t;
        // (row, col) is (y, x): counter-clockwise in (x, y) is clockwise in (row, col).
        let (b, c) = if cross(a, b, c) < 0 { (b, c) } else { (c, b) };
        for v in [a, b, c] {
            used[index(v) as usize] = true;
            out.push(index(v));
        }
    }
    for (edge, grid_index) in edges(n).iter().enumerate() {
        let base = (s * s) as u32 + edge as u32 * s as u32;
        let kept: Vec<u32> = (0..=n).filter(|&t| used[grid_index(t) as usize]).collect();
        for pair in kept.windows(2) {
            let (ta, tb) = (pair[0], pair[1]);
            let (a, b) = (grid_index(ta) as u16, grid_index(tb) as u16);
            let (sa, sb) = ((base + ta) as u16, (base + tb) as u16);
            out.extend_from_slice(&[a, b, sb, a, sb, sa]);
        }
    }
    out
}

/// Renumbers a mesh's indices (on the full grid-and-skirts numbering) to the vertices they
/// use, in that numbering's order, and returns them with the old numbers of those vertices.
fn compact_indices(indices: &[u16], n: u32) -> (Vec<u16>, Vec<u16>) {
    let mut new_of = vec![u16::MAX; vertex_count(n)];
    for &i in indices {
        new_of[i as usize] = 0;
    }
    let mut used = Vec::new();
    for (old, new) in new_of.iter_mut().enumerate() {
        if *new == 0 {
            *new = used.len() as u16;
            used.push(old as u16);
        }
    }
    (indices.iter().map(|&i| new_of[i as usize]).collect(), used)
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

/// A point of a grid cell's surface, split as the database splits the cell (see
/// `cig_terrain::raster::triangulated_height`), from its corners and the fractions `east` and
/// `north` across it.
pub fn triangulated_point(
    [sw, se, nw, ne]: [DVec3; 4],
    east: f64,
    north: f64,
    diagonal: Diagonal,
) -> DVec3 {
    match diagonal {
        Diagonal::SouthWestNorthEast => {
            if east >= north {
                sw + (se - sw) * east + (ne - se) * north
            } else {
                sw + (nw - sw) * north + (ne - nw) * east
            }
        }
        Diagonal::NorthWestSouthEast => {
            if east + north <= 1.0 {
                sw + (se - sw) * east + (nw - sw) * north
            } else {
                ne + (nw - ne) * (1.0 - east) + (se - ne) * (1.0 - north)
            }
        }
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
        // Aged asphalt (broadband visible albedo about 0.15-0.2, lighter than green grass).
        Material::PavedRoad => [128, 128, 130, 60],
        Material::DirtRoad => [140, 116, 86, 0],
    }
}

/// A colour texel of a material: its sRGB colour, and in alpha its index (high nibble) and its
/// specular weight in sixteenths (low nibble), so the shader can draw sharp, smooth borders
/// between materials (it weighs the texels around a point by material) and still blend them.
pub fn material_texel(m: Material) -> [u8; 4] {
    const _: () = assert!(
        Material::ALL.len() <= 16,
        "a material index must fit a nibble"
    );
    let [r, g, b, specular] = material_colour(m);
    [r, g, b, ((m as u8) << 4) | (specular >> 4)]
}

/// Samples one resident tile on the finest grid's fractional indices.
struct Sampler<'a> {
    key: TileKey,
    tile: &'a Tile,
    /// Road posts take their neighbours' land colour ([`NodeLayout::roads_as_shapes`]).
    roads_as_shapes: bool,
    tile_span: f64,
    scale: f64,
    max_index: f64,
}

impl<'a> Sampler<'a> {
    fn new(layout: &NodeLayout, key: TileKey, tile: &'a Tile) -> Sampler<'a> {
        Sampler {
            key,
            tile,
            roads_as_shapes: layout.roads_as_shapes,
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
            [
                self.tile.elevation(i, j),
                self.tile.elevation(i, j + 2),
                self.tile.elevation(i + 2, j),
                self.tile.elevation(i + 2, j + 2),
            ],
            u,
            v,
            // The coarser level's cell (ci, cj) of this tile's even grid: the checkerboard of
            // that level (tiles start at even cells of it).
            Diagonal::of_cell(ci, cj),
        )
    }

    fn material(&self, row: f64, col: f64) -> Material {
        let (fi, fj) = self.local(row, col);
        self.tile
            .material_at(fi.round() as usize, fj.round() as usize)
    }

    /// The material that weighs most among the four posts around a point, each post weighing
    /// its bilinear weight there (ties to the nearest post's): between posts, borders follow
    /// the 0.5 level of the materials' bilinear fields (marching squares) rather than the
    /// nearest post's square, so a texel grid finer than the posts cuts the post grid's
    /// corners.
    fn majority_material(&self, row: f64, col: f64) -> Material {
        let (fi, fj) = self.local(row, col);
        let (i0, j0) = (fi.floor().max(0.0), fj.floor().max(0.0));
        let (i1, j1) = (
            (i0 + 1.0).min(self.max_index),
            (j0 + 1.0).min(self.max_index),
        );
        let (v, u) = (fi - i0, fj - j0);
        let corners = [
            (i0, j0, (1.0 - v) * (1.0 - u)),
            (i0, j1, (1.0 - v) * u),
            (i1, j0, v * (1.0 - u)),
            (i1, j1, v * u),
        ];
        let hidden = |m: Material| {
            self.roads_as_shapes && matches!(m, Material::PavedRoad | Material::DirtRoad)
        };
        let mut weight = [0.0f64; Material::ALL.len()];
        for (i, j, w) in corners {
            let m = self.tile.material_at(i as usize, j as usize);
            if !hidden(m) {
                weight[m as usize] += w;
            }
        }
        if weight.iter().all(|&w| w == 0.0) && self.roads_as_shapes {
            // Four road posts (a wide road, a junction, a settlement's streets): the land of
            // the posts around them within four posts, the nearest weighing most.
            let last = self.max_index as i64;
            for di in -4i64..=4 {
                for dj in -4i64..=4 {
                    let (i, j) = (
                        (fi.round() as i64 + di).clamp(0, last),
                        (fj.round() as i64 + dj).clamp(0, last),
                    );
                    let m = self.tile.material_at(i as usize, j as usize);
                    if !hidden(m) {
                        let (dr, dc) = (i as f64 - fi, j as f64 - fj);
                        weight[m as usize] += 1.0 / (1.0 + dr * dr + dc * dc);
                    }
                }
            }
        }
        let nearest = self.material(row, col);
        let lead = if hidden(nearest) {
            0.0
        } else {
            weight[nearest as usize]
        };
        Material::ALL
            .into_iter()
            .filter(|&m| weight[m as usize] > lead + 1e-9)
            .max_by(|a, b| weight[*a as usize].total_cmp(&weight[*b as usize]))
            .unwrap_or(nearest)
    }
}

/// The post errors a node's mesh is cut by: its own level's, from its own level's tile, for a
/// node inside the database; `None` for a node drawn as a regular grid (reaching past the
/// database's edge, drawn from a coarser level's data, or from a format 1 tile).
pub fn adaptive_errors<'a>(
    layout: &NodeLayout,
    key: NodeKey,
    (data_key, data): (TileKey, &'a Tile),
) -> Option<&'a LodErrors> {
    let errors = data.lod_errors.as_ref()?;
    (data_key.level == key.level
        && !layout.reaches_past_edge(key)
        && errors.own_m.len() == data.elevation_m.len()
        && errors.coarser_m.len() == even_posts_per_side(data.posts_per_side).pow(2))
    .then_some(errors)
}

/// Which of a node's grid posts its cut keeps, and which of them the cut it morphs to keeps
/// (row-major on the `(n + 1)^2` grid), both closed under the hierarchy whatever a tile's
/// bytes say, so that every cut conforms.
struct CutPosts {
    s: usize,
    kept: Vec<bool>,
    morph_to: Vec<bool>,
    /// Grid steps between the posts of the cut morphed to: 2 for the parent's, 1 for the
    /// node's own at a larger tolerance.
    morph_to_step: i32,
}

impl CutPosts {
    fn of(
        layout: &NodeLayout,
        key: NodeKey,
        data: (TileKey, &Tile),
        parent: Option<(TileKey, &Tile)>,
        cut: NodeCut,
    ) -> CutPosts {
        let n = layout.node_cells;
        let (ni, s) = (n as i32, n as usize + 1);
        let half = ni / 2;
        let errors = adaptive_errors(layout, key, data);
        let forced_level = cut.regular_ancestor_level.filter(|&f| f > key.level);
        let (global_row, global_col) = (
            i64::from(key.row) * i64::from(ni),
            i64::from(key.col) * i64::from(ni),
        );
        // Posts of a level drawn as a regular grid above, which every cut below keeps.
        let on_forced_level = |i: i32, j: i32| {
            forced_level.is_some_and(|f| {
                let every = 1i64 << (f - key.level);
                (global_row + i64::from(i)) % every == 0 && (global_col + i64::from(j)) % every == 0
            })
        };
        // The node's own posts in its tile.
        let (data_key, data_tile) = data;
        let tile_span = i64::from(layout.pyramid.tile_cells);
        let (ti0, tj0) = (
            (global_row - i64::from(data_key.row) * tile_span) as i32,
            (global_col - i64::from(data_key.col) * tile_span) as i32,
        );
        let posts = data_tile.posts_per_side as i32;
        // A cut of the node's own posts at `tolerance_m`. The quadrants are always split, so
        // that a child's part of this mesh depends on the child's posts alone.
        let own_cut = |tolerance_m: f32| -> Vec<bool> {
            let Some(errors) = errors else {
                return vec![true; s * s];
            };
            // Each post's error counts its triangles' chord sag too (the curved surface they
            // span; `NodeLayout::post_sag_m`).
            let sag_m = |i: i32, j: i32| {
                layout.post_sag_m(
                    key.level,
                    (global_row + i64::from(i)) as u64,
                    (global_col + i64::from(j)) as u64,
                )
            };
            closed(n, &|i, j| {
                (i % half == 0 && j % half == 0)
                    || on_forced_level(i, j)
                    || errors
                        .own_m
                        .get(((ti0 + i) * posts + tj0 + j) as usize)
                        .is_none_or(|&e| e.max(sag_m(i, j)) > tolerance_m)
            })
        };
        let kept = own_cut(cut.tolerance_m);
        if cut.morphs_within_level {
            return CutPosts {
                s,
                kept,
                morph_to: own_cut(cut.parent_tolerance_m),
                morph_to_step: 1,
            };
        }
        // The parent's posts are this node's even ones: its errors from this tile's coarser
        // errors, or, when this tile has none (format 1, or data still coarser), from the
        // parent's tile; none when the parent is a regular grid.
        let parent_regular = cut.regular_ancestor_level == Some(key.level + 1);
        let parent_errors: Option<(&[f32], i32, i32, i32)> = match errors {
            _ if parent_regular => None,
            Some(e) => Some((
                e.coarser_m.as_slice(),
                even_posts_per_side(data_tile.posts_per_side) as i32,
                ti0 / 2,
                tj0 / 2,
            )),
            None => parent.and_then(|(k, t)| {
                let e = t.lod_errors.as_ref()?;
                (k.level == key.level + 1 && e.own_m.len() == t.elevation_m.len()).then(|| {
                    let origin = |node: i64, tile: u32| node / 2 - i64::from(tile) * tile_span;
                    (
                        e.own_m.as_slice(),
                        t.posts_per_side as i32,
                        origin(global_row, k.row) as i32,
                        origin(global_col, k.col) as i32,
                    )
                })
            }),
        };
        let on_parent_grid = closed(n / 2, &|a, b| {
            let Some((values, stride, pi0, pj0)) = parent_errors else {
                return true;
            };
            let (pa, pb) = (pi0 + a, pj0 + b);
            let sag_m = layout.post_sag_m(
                key.level + 1,
                (global_row / 2 + i64::from(a)) as u64,
                (global_col / 2 + i64::from(b)) as u64,
            );
            on_forced_level(2 * a, 2 * b)
                || pa < 0
                || pb < 0
                || values
                    .get((pa * stride + pb) as usize)
                    .is_none_or(|&e| e.max(sag_m) > cut.parent_tolerance_m)
        });
        let h = half as usize + 1;
        let morph_to = (0..s * s)
            .map(|k| {
                let (i, j) = (k / s, k % s);
                i % 2 == 0 && j % 2 == 0 && on_parent_grid[(i / 2) * h + j / 2]
            })
            .collect();
        CutPosts {
            s,
            kept,
            morph_to,
            morph_to_step: 2,
        }
    }

    fn kept(&self, i: i32, j: i32) -> bool {
        self.kept[i as usize * self.s + j as usize]
    }

    fn morph_to(&self, i: i32, j: i32) -> bool {
        self.morph_to[i as usize * self.s + j as usize]
    }
}

/// The resident tiles a node's mesh is built from.
#[derive(Clone, Copy)]
pub struct NodeTiles<'a> {
    /// The node's level or coarser: the vertices.
    pub data: (TileKey, &'a Tile),
    /// The next finer level, when resident: normals and colours.
    pub detail: Option<(TileKey, &'a Tile)>,
    /// The parent's level, when resident: the parent's cut when `data` has no post errors.
    pub parent: Option<(TileKey, &'a Tile)>,
}

/// Builds the mesh of `key` from the tile `data` (the node's level or coarser) and, when
/// resident, the finer tile `detail` for normals and colours and the parent level's tile
/// `parent` (whose post errors give the parent's cut when `data` has none).
pub fn build_node_mesh(
    layout: &NodeLayout,
    geoid: &GeoidLookup,
    key: NodeKey,
    tiles: NodeTiles<'_>,
    error_m: f32,
    cut: NodeCut,
) -> NodeMesh {
    let NodeTiles {
        data,
        detail,
        parent,
    } = tiles;
    let n = layout.node_cells;
    // 16-bit indices and the quadrant split: `NodeLayout::new` keeps nodes at 8 or 16 cells.
    debug_assert!(
        n.is_power_of_two() && (2..=128).contains(&n),
        "{n} cells a node"
    );
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
    let clamped = layout.reaches_past_edge(key);
    let cut_posts = CutPosts::of(layout, key, data, parent, cut);
    let kept = |i: i32, j: i32| cut_posts.kept(i, j);
    let square_parity = key.row + key.col;
    let triangles = rtin_triangles(n, square_parity, &kept);
    let indices = mesh_indices(&triangles, n);

    // Morph targets: each vertex's place on the parent's mesh. Inside the database that is the
    // triangle of the parent's cut holding the vertex (the parent's posts are this node's even
    // posts, at the same heights), interpolated linearly as the GPU draws it. Where the node
    // reaches past the database's last row or column, the parent's grid of vertices (every
    // other one of this node's, clamped onto the edge the same way) with the parent level's
    // heights, interpolated across the parent cell's triangles, keeps the vertex where it is
    // horizontally, so the edge does not recede while a node morphs.
    let half_cells = n as usize / 2;
    let parent_row = |a: usize| (r0 + (2 * a) as f64 * step).min(max_row);
    let parent_col = |b: usize| (c0 + (2 * b) as f64 * step).min(max_col);
    let parent_height = |row: f64, col: f64| {
        if data.0.level > key.level {
            data_sampler.height_msl_m(row, col)
        } else {
            data_sampler.coarser_height_msl_m(row, col)
        }
    };
    let ps = half_cells + 1;
    let mut parent_rel = vec![DVec3::ZERO; if clamped { ps * ps } else { 0 }];
    if clamped {
        for a in 0..ps {
            for b in 0..ps {
                let (row, col) = (parent_row(a), parent_col(b));
                let (lat, lon) = layout.lat_lon_of_finest(row, col);
                let h = parent_height(row, col) + geoid.undulation_m(lat, lon);
                parent_rel[a * ps + b] = Geodetic::new(lat, lon, h).to_ecef() - centre_ecef;
            }
        }
    }
    // The parent cell holding grid line `k` (of `n + 1`) and the fraction across it.
    let parent_cell = |k: usize, own: f64, parent: &dyn Fn(usize) -> f64| -> (usize, f64) {
        let a = (k / 2).min(half_cells - 1);
        let (start, end) = (parent(a), parent(a + 1));
        let fraction = if end > start {
            ((own - start) / (end - start)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a, fraction)
    };
    let morph_target = |i: usize, j: usize| -> DVec3 {
        if clamped {
            let (a, north) = parent_cell(i, rel_row(i), &parent_row);
            let (b, east) = parent_cell(j, rel_col(j), &parent_col);
            let corner = |da: usize, db: usize| parent_rel[(a + da) * ps + b + db];
            triangulated_point(
                [corner(0, 0), corner(0, 1), corner(1, 0), corner(1, 1)],
                east,
                north,
                Diagonal::of_cell(a, b),
            )
        } else {
            let (t, w) = locate(
                n,
                square_parity,
                cut_posts.morph_to_step,
                &|i, j| cut_posts.morph_to(i, j),
                (i as i32, j as i32),
            );
            t.iter()
                .zip(w)
                .map(|(&(r, c), w)| rel[r as usize * s + c as usize] * w)
                .sum()
        }
    };
    let span_m = span * grid.dlat_deg * metres_per_degree(lat_c).0;
    let skirt_depth_m =
        (5.0 + 0.02 * span_m + 3.0 * f64::from(error_m) + (h_max - h_min) * 0.1) as f32;
    // The vertices the triangles use, grid first (row-major), then the skirts'.
    let grid_uv = |g: usize| [(g % s) as f32 / n as f32, (g / s) as f32 / n as f32];
    let (indices, used) = compact_indices(&indices, n);
    let mut vertices = Vec::with_capacity(used.len());
    let mut grid_vertices = 0;
    for &old in &used {
        let old = old as usize;
        let (g, skirt) = if old < s * s {
            grid_vertices += 1;
            (old, 0.0)
        } else {
            let k = old - s * s;
            (edges(n)[k / s]((k % s) as u32) as usize, 1.0)
        };
        vertices.push(TerrainVertex {
            position: rel[g].as_vec3().to_array(),
            morph_target: morph_target(g / s, g % s).as_vec3().to_array(),
            grid_uv: grid_uv(g),
            skirt,
        });
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
            colours.push(material_texel(
                detail_sampler.majority_material(row.min(max_row), col.min(max_col)),
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
        grid_vertices,
        indices,
        normals,
        colours,
        skirt_depth_m,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_terrain::raster::{GeoGrid, Raster};
    use cig_terrain::rtin::{level_errors, own_errors};
    use proptest::prelude::*;

    fn twice_area(t: &GridTriangle) -> i64 {
        cross(t[0], t[1], t[2]).abs()
    }

    /// The triangles of a cut, checked to tile the node's square with no vertex inside
    /// another triangle's edge (no T-junction).
    fn assert_conforming(triangles: &[GridTriangle], n: i32) {
        let area: i64 = triangles.iter().map(twice_area).sum();
        assert_eq!(
            area,
            2 * i64::from(n) * i64::from(n),
            "the triangles tile the square"
        );
        let vertices: std::collections::HashSet<(i32, i32)> =
            triangles.iter().flatten().copied().collect();
        for t in triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                for &v in &vertices {
                    if v == a || v == b || cross(a, b, v) != 0 {
                        continue;
                    }
                    let inside = (v.0 - a.0) * (v.0 - b.0) <= 0 && (v.1 - a.1) * (v.1 - b.1) <= 0;
                    assert!(!inside, "{v:?} lies inside edge {a:?}-{b:?}");
                }
            }
        }
    }

    #[test]
    fn keeping_every_post_cuts_the_checkerboard_of_cells() {
        for n in [8u32, 16] {
            for parity in [0u32, 1] {
                let triangles = rtin_triangles(n, parity, &|_, _| true);
                assert_eq!(triangles.len(), (2 * n * n) as usize);
                assert_conforming(&triangles, n as i32);
                for t in &triangles {
                    // Each is half of one cell, split along that cell's diagonal.
                    let (r, c) = (
                        t.iter().map(|v| v.0).min().unwrap(),
                        t.iter().map(|v| v.1).min().unwrap(),
                    );
                    let [a, b, _] = *t;
                    let along_sw_ne = (b.0 - a.0) * (b.1 - a.1) > 0;
                    let expected = Diagonal::of_cell(r as usize, c as usize);
                    assert_eq!(
                        along_sw_ne,
                        expected == Diagonal::SouthWestNorthEast,
                        "cell ({r}, {c}) of a square of parity {parity}"
                    );
                }
            }
        }
    }

    proptest! {
        /// Whatever a tile's bytes say, the kept set is closed before cutting: the cut
        /// conforms, and every post the bytes keep is a vertex of it.
        #[test]
        fn any_kept_set_once_closed_cuts_a_conforming_mesh(
            bits in proptest::collection::vec(any::<bool>(), 17 * 17), parity in 0u32..2,
        ) {
            let raw = |i: i32, j: i32| bits[(i * 17 + j) as usize];
            let kept = closed(16, &raw);
            let triangles = rtin_triangles(16, parity, &|i, j| kept[(i * 17 + j) as usize]);
            assert_conforming(&triangles, 16);
            let vertices: std::collections::HashSet<(i32, i32)> =
                triangles.iter().flatten().copied().collect();
            for i in 0..17 {
                for j in 0..17 {
                    if raw(i, j) {
                        prop_assert!(vertices.contains(&(i, j)), "({i}, {j}) kept but not cut");
                    }
                }
            }
        }
    }

    fn random_raster(n: usize, seed: u64, roughness_m: f32) -> Raster {
        Raster::from_fn(GeoGrid::at_origin(n, n, 0.001), |r, c| {
            // A hash of the post (xorshift of its index and the seed) for the noise.
            let mut state = (seed | 1) ^ ((r * n + c) as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let noise = (state % 10_000) as f32 / 10_000.0 - 0.5;
            30.0 * (r as f32 / 5.0).sin() + 0.7 * c as f32 + roughness_m * noise
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// A cut by the stored post errors conforms, and every post of the level lies within
        /// the tolerance of the cut's surface (the exact bound the level of detail relies on),
        /// and so does every finest post below a coarser level's cut.
        #[test]
        fn cuts_conform_and_stay_within_their_tolerance(
            seed in 1u64..1_000_000, tolerance_m in 0.0f32..40.0, roughness_m in 0.0f32..20.0,
            level in 0u8..2,
        ) {
            let n = 16usize;
            let step = 1usize << level;
            let raster = random_raster(n * step + 1, seed, roughness_m);
            let own = own_errors(&raster);
            let errors = level_errors(&raster, &own, level);
            let half = (n / 2) as i32;
            let kept = |i: i32, j: i32| {
                (i % half == 0 && j % half == 0) || errors.at(i as usize, j as usize) > tolerance_m
            };
            let triangles = rtin_triangles(n as u32, 0, &kept);
            assert_conforming(&triangles, n as i32);
            let fine = raster.grid.cols;
            let height = |r: usize, c: usize| f64::from(raster.elevation_m[r * fine + c]);
            let mut worst = 0.0f64;
            let cells = 2 * n * n;
            for r in 0..=n * step {
                for c in 0..=n * step {
                    let p = ((r / step) as i32, (c / step) as i32);
                    // The finest post in level coordinates (exact fractions of a cell).
                    let (fr, fc) = (r as f64 / step as f64, c as f64 / step as f64);
                    let (t, w) = locate(n as u32, 0, 1, &kept, p);
                    let mut value = 0.0;
                    let mut inside = true;
                    // Weights at the fractional point, from the triangle `locate` gave for
                    // its cell's corner, refound among all triangles when it does not hold it.
                    let weights = |t: &GridTriangle| {
                        let [a, b, cc] = t.map(|v| (f64::from(v.0), f64::from(v.1)));
                        let x = |o: (f64, f64), p: (f64, f64), q: (f64, f64)| {
                            (p.0 - o.0) * (q.1 - o.1) - (p.1 - o.1) * (q.0 - o.0)
                        };
                        let area = x(a, b, cc);
                        let q = (fr, fc);
                        [x(q, b, cc) / area, x(a, q, cc) / area, x(a, b, q) / area]
                    };
                    let holder = if step == 1 {
                        prop_assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-9);
                        prop_assert!(w.iter().all(|&w| w >= -1e-12));
                        t
                    } else {
                        *triangles
                            .iter()
                            .find(|t| weights(t).iter().all(|&w| w >= -1e-12))
                            .expect("a triangle holds every point")
                    };
                    for (v, w) in holder.iter().zip(weights(&holder)) {
                        inside &= w >= -1e-12;
                        value += w * height(v.0 as usize * step, v.1 as usize * step);
                    }
                    prop_assert!(inside);
                    let big = twice_area(&holder) > 1;
                    if big || level == 0 {
                        worst = worst.max((value - height(r, c)).abs());
                    }
                }
            }
            prop_assert!(worst <= f64::from(tolerance_m) + 1e-3, "{worst} m against {tolerance_m} m");
            prop_assert!(triangles.len() <= cells);
        }
    }
}

#[cfg(test)]
mod texel_tests {
    use super::*;

    #[test]
    fn a_material_texel_carries_its_colour_index_and_specular_weight() {
        for m in Material::ALL {
            let [r, g, b, spec] = material_colour(m);
            let [tr, tg, tb, tag] = material_texel(m);
            assert_eq!([tr, tg, tb], [r, g, b]);
            assert_eq!(tag >> 4, m as u8, "{m:?}");
            assert_eq!(tag & 15, spec >> 4, "{m:?}");
        }
        // Distinct materials give distinct tags.
        let tags: std::collections::BTreeSet<u8> = Material::ALL
            .iter()
            .map(|&m| material_texel(m)[3] >> 4)
            .collect();
        assert_eq!(tags.len(), Material::ALL.len());
    }
}
