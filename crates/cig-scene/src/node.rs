//! The level-of-detail quadtree's nodes: [`NodeKey`] (one node of a pyramid level) and
//! [`NodeLayout`] (how the quadtree maps onto a database's pyramid: a node's tiles, bounds,
//! errors and the chord sag of its triangles), shared by the selection ([`crate::lod`]) and the
//! node meshes ([`crate::terrain_mesh`]).

use cig_terrain::pyramid::quadtree_index;
use cig_terrain::raster::GeoGrid;
use cig_terrain::tile::{NodeBounds, Tile};
use cig_terrain::{PyramidLayout, TileKey};

/// Default cells along a node's side.
pub const DEFAULT_NODE_CELLS: u32 = 16;

/// One node of the level-of-detail quadtree: `node_cells` cells of pyramid level `level`,
/// starting at node row `row` (south first) and column `col`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeKey {
    pub level: u8,
    pub row: u32,
    pub col: u32,
}

impl NodeKey {
    /// The node one level coarser that contains this one.
    pub fn parent(self) -> NodeKey {
        NodeKey {
            level: self.level + 1,
            row: self.row / 2,
            col: self.col / 2,
        }
    }

    pub fn children(self) -> [NodeKey; 4] {
        let level = self.level.saturating_sub(1);
        let (r, c) = (self.row * 2, self.col * 2);
        [
            NodeKey {
                level,
                row: r,
                col: c,
            },
            NodeKey {
                level,
                row: r,
                col: c + 1,
            },
            NodeKey {
                level,
                row: r + 1,
                col: c,
            },
            NodeKey {
                level,
                row: r + 1,
                col: c + 1,
            },
        ]
    }
}

/// How the quadtree maps onto a database's pyramid.
#[derive(Clone, Copy, Debug)]
pub struct NodeLayout {
    pub pyramid: PyramidLayout,
    pub node_cells: u32,
    /// The chord sag of a triangle whose hypotenuse is one finest cell's diagonal
    /// ([`finest_cell_sag_m`]); a triangle `n` finest cells across sags `n^2` times as much.
    finest_cell_sag_m: f64,
    /// Roads are drawn as shapes in the draped imagery, so the node colours give road posts
    /// the colour of the land beside them (a road one post wide would otherwise smear a band
    /// of asphalt several times the road's width around the painted ribbon).
    pub roads_as_shapes: bool,
}

impl NodeLayout {
    pub fn new(pyramid: PyramidLayout) -> NodeLayout {
        NodeLayout {
            pyramid,
            // A node's four children must lie in one tile of the finer level.
            node_cells: DEFAULT_NODE_CELLS.min(pyramid.tile_cells / 2).max(1),
            finest_cell_sag_m: finest_cell_sag_m(&pyramid.grid),
            roads_as_shapes: false,
        }
    }

    /// The layout with roads drawn as shapes (see [`NodeLayout::roads_as_shapes`]).
    pub fn with_roads_as_shapes(self, roads_as_shapes: bool) -> NodeLayout {
        NodeLayout {
            roads_as_shapes,
            ..self
        }
    }

    /// Finest cells along a node's side at `level`.
    pub fn finest_span(&self, level: u8) -> u64 {
        u64::from(self.node_cells) << level
    }

    /// Finest-grid (row, col) of the node's south-west post.
    pub fn finest_origin(&self, key: NodeKey) -> (u64, u64) {
        let span = self.finest_span(key.level);
        (u64::from(key.row) * span, u64::from(key.col) * span)
    }

    /// True when the node starts inside the database.
    pub fn exists(&self, key: NodeKey) -> bool {
        let (r0, c0) = self.finest_origin(key);
        key.level < self.pyramid.levels
            && r0 < (self.pyramid.grid.rows.max(2) - 1) as u64
            && c0 < (self.pyramid.grid.cols.max(2) - 1) as u64
    }

    /// The tile of `level >= key.level` that contains the node.
    pub fn tile_of(&self, key: NodeKey, level: u8) -> TileKey {
        let (r0, c0) = self.finest_origin(key);
        let tile_span = self.pyramid.finest_cells_per_tile(level);
        TileKey {
            level,
            row: (r0 / tile_span) as u32,
            col: (c0 / tile_span) as u32,
        }
    }

    /// The tile of the next coarser level holding the node's parent (`None` for a root).
    pub fn parent_tile(&self, key: NodeKey) -> Option<TileKey> {
        (key.level + 1 < self.pyramid.levels).then(|| self.tile_of(key.parent(), key.level + 1))
    }

    /// True when the node reaches past the database's last row or column (its mesh's vertices
    /// are clamped onto the edge there).
    pub fn reaches_past_edge(&self, key: NodeKey) -> bool {
        let (r0, c0) = self.finest_origin(key);
        let span = self.finest_span(key.level);
        r0 + span > (self.pyramid.grid.rows.max(2) - 1) as u64
            || c0 + span > (self.pyramid.grid.cols.max(2) - 1) as u64
    }

    /// The chord sag of the two triangles that post `(i, j)` of `level`'s grid splits (the
    /// triangles of the RTIN whose hypotenuse midpoint it is; see `cig_terrain::rtin`).
    pub fn post_sag_m(&self, level: u8, i: u64, j: u64) -> f32 {
        let k = match cig_terrain::rtin::vertex_kind(i, j) {
            cig_terrain::rtin::Vertex::Diagonal { k }
            | cig_terrain::rtin::Vertex::Side { k, .. } => k,
            cig_terrain::rtin::Vertex::Origin => return 0.0,
        };
        self.sag_m(k as f64 * f64::from(1u32 << level.min(31)))
    }

    /// The chord sag of the cells of `level` (the triangles of a node drawn with every post of
    /// its level), a floor under a node's error: what refining to that level can reach.
    pub fn node_sag_m(&self, level: u8) -> f32 {
        self.sag_m(f64::from(1u32 << level.min(31)))
    }

    /// The chord sag of a triangle whose hypotenuse spans `cells` finest cells' diagonals.
    fn sag_m(&self, cells: f64) -> f32 {
        (self.finest_cell_sag_m * cells * cells) as f32
    }

    /// A node's error for the selection: its data's error, and at least its chord sag.
    pub fn node_error_m(&self, level: u8, data_error_m: f32) -> f32 {
        data_error_m.max(0.0).max(self.node_sag_m(level))
    }

    /// Nodes of the whole quadtree, every level.
    pub fn node_count(&self) -> u64 {
        (0..self.pyramid.levels)
            .map(|level| {
                let span = self.finest_span(level);
                let rows = ((self.pyramid.grid.rows.max(2) - 1) as u64).div_ceil(span);
                let cols = ((self.pyramid.grid.cols.max(2) - 1) as u64).div_ceil(span);
                rows * cols
            })
            .sum()
    }

    /// The coarsest level's nodes: the roots of the quadtree.
    pub fn roots(&self) -> Vec<NodeKey> {
        let level = self.pyramid.levels - 1;
        let span = self.finest_span(level);
        let rows = ((self.pyramid.grid.rows.max(2) - 1) as u64).div_ceil(span) as u32;
        let cols = ((self.pyramid.grid.cols.max(2) - 1) as u64).div_ceil(span) as u32;
        (0..rows)
            .flat_map(|row| (0..cols).map(move |col| NodeKey { level, row, col }))
            .collect()
    }

    /// Geodetic latitude and longitude of a finest-grid (row, col) index, clamped to the
    /// database.
    pub fn lat_lon_of_finest(&self, row: f64, col: f64) -> (f64, f64) {
        let g = &self.pyramid.grid;
        let row = row.clamp(0.0, (g.rows.max(1) - 1) as f64);
        let col = col.clamp(0.0, (g.cols.max(1) - 1) as f64);
        (
            g.south_lat_deg + row * g.dlat_deg,
            g.west_lon_deg + col * g.dlon_deg,
        )
    }

    /// Min/max/error bounds of a node read from a resident tile of level `tile.level >=
    /// key.level` (the deepest quadtree node of that tile that covers the whole node).
    pub fn node_bounds_in(&self, key: NodeKey, tile: TileKey, nodes: &[NodeBounds]) -> NodeBounds {
        let depth_max = cig_terrain::tile::quadtree_depth_for(self.pyramid.tile_cells as usize);
        let tile_span = self.pyramid.finest_cells_per_tile(tile.level);
        let span = self.finest_span(key.level).min(tile_span);
        let mut depth = 0u32;
        while depth < depth_max && (tile_span >> (depth + 1)) >= span {
            depth += 1;
        }
        let q_span = tile_span >> depth;
        let (r0, c0) = self.finest_origin(key);
        let y = ((r0 - u64::from(tile.row) * tile_span) / q_span) as usize;
        let x = ((c0 - u64::from(tile.col) * tile_span) / q_span) as usize;
        nodes
            .get(quadtree_index(depth, x, y))
            .copied()
            .unwrap_or(NodeBounds::EMPTY)
    }

    /// Appends to `out` the error of every node of the tile's level that lies in `tile`.
    pub fn node_errors_in(&self, tile_key: TileKey, tile: &Tile, out: &mut Vec<f32>) {
        let per_tile = (self.pyramid.tile_cells / self.node_cells).max(1);
        for r in 0..per_tile {
            for c in 0..per_tile {
                let key = NodeKey {
                    level: tile_key.level,
                    row: tile_key.row * per_tile + r,
                    col: tile_key.col * per_tile + c,
                };
                if self.exists(key) {
                    let data_error_m = self.node_bounds_in(key, tile_key, &tile.nodes).error_m;
                    out.push(self.node_error_m(key.level, data_error_m));
                }
            }
        }
    }
}

/// How far a triangle's interpolated points may lie from the surface's own points, for a
/// triangle whose hypotenuse is the diagonal of one cell of `grid`: the drawn mesh's triangles
/// are straight in ECEF while the posts lie on the curved ellipsoid on a latitude-longitude
/// grid, so a triangle's plane dips under the surface by the sagitta of its circumcircle
/// (radius half the hypotenuse `h`, on the smallest radius of curvature `R`: `h^2 / 8R`; a flat
/// sea's 10 km triangle by 2 m), and the grid's parallels, which curve by `1 / (R cos lat)` and
/// converge by `tan lat / R`, move its points up to `(1 + sin lat) / cos lat` times that (at the
/// database's latitude farthest from the equator; 1.96 at 36 degrees). The cell's diagonal is
/// measured where a degree of longitude is longest (the latitude nearest the equator). The
/// level of detail counts the sag as error like any other.
fn finest_cell_sag_m(grid: &GeoGrid) -> f64 {
    let (south, north) = (grid.south_lat_deg, grid.north_lat_deg());
    let nearest_equator_deg = if south <= 0.0 && north >= 0.0 {
        0.0
    } else {
        south.abs().min(north.abs())
    };
    let (m_per_deg_lat, m_per_deg_lon) = cig_geo::metres_per_degree(nearest_equator_deg);
    let diagonal_m = (grid.dlat_deg * m_per_deg_lat).hypot(grid.dlon_deg * m_per_deg_lon);
    let farthest = south.abs().max(north.abs()).min(89.0).to_radians();
    let grid_factor = (1.0 + farthest.sin()) / farthest.cos();
    diagonal_m * diagonal_m * grid_factor / (8.0 * SMALLEST_RADIUS_OF_CURVATURE_M)
}

/// The WGS84 ellipsoid's smallest radius of curvature, `a (1 - e^2)` (the meridian's at the
/// equator), metres.
const SMALLEST_RADIUS_OF_CURVATURE_M: f64 = 6_335_439.3;
