//! One terrain tile in memory and its memory-image file format.
//!
//! Source: NPSNET (source 003) stored each tile "in memory-image format, therefore no data
//! conversion has to be done during paging"; a 4-level quadtree per tile in heap order, lowest
//! resolution first. Here a tile holds `(tile_cells + 1)^2` posts (elevation `f32` metres above
//! mean sea level, material byte), and a min/max quadtree whose leaves are 8 x 8 cells, each node
//! carrying the minimum and maximum height of the *finest* surface below it (for culling and line
//! of sight) and the largest vertical error of this level's surface against the finest one (for
//! level-of-detail selection). Since format 2 a tile also holds, per post, the error of the
//! right-triangulated irregular network the renderer draws adaptively (see [`LodErrors`]).
//!
//! File layout (little-endian, 64-byte header, then the payload):
//!
//! | offset | field |
//! |---|---|
//! | 0 | magic `CIGTILE\0` |
//! | 8 | format version (u32) |
//! | 12 | level (u8), quadtree depth (u8), reserved (u16) |
//! | 16 | tile row, tile column (u32 each) |
//! | 24 | posts per side (u32) |
//! | 28 | quadtree node count (u32) |
//! | 32 | payload length in bytes (u64) |
//! | 40 | CRC-32 (IEEE) of every byte of the file but these four (u32) |
//! | 44 | reserved, zero (20 bytes) |
//! | 64 | elevations `f32[n*n]`, nodes `[min, max, error] f32[3*count]`, (format 2 only) [`LodErrors`]: `own f32[n*n]`, `coarser f32[m*m]` with `m = (n - 1) / 2 + 1`, then materials `u8[n*n]`, zero padding to 4 bytes |
//!
//! Format 1 (no level-of-detail errors) is still read; its tiles are drawn as regular grids.
//!
//! Limits: little-endian hosts read the arrays with one copy and no conversion; big-endian hosts
//! would convert each value (the code does, through `from_le_bytes`).

use crate::material::Material;
use crate::pyramid::{quadtree_node_count, TileKey};
use crate::raster::{triangulated_height, Diagonal};

/// Version of the tile file format written by this build (format 1 is read too).
pub const TILE_FORMAT_VERSION: u32 = 2;
/// The format without level-of-detail errors.
const TILE_FORMAT_WITHOUT_LOD_ERRORS: u32 = 1;
const MAGIC: &[u8; 8] = b"CIGTILE\0";
const HEADER_BYTES: usize = 64;
/// Cells along the side of a quadtree leaf.
pub const QUADTREE_LEAF_CELLS: usize = 8;

/// Bounds of one quadtree node, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct NodeBounds {
    /// Lowest point of the finest surface under the node.
    pub min_m: f32,
    /// Highest point of the finest surface under the node.
    pub max_m: f32,
    /// Largest vertical distance between this level's surface and the finest surface.
    pub error_m: f32,
}

impl NodeBounds {
    /// Bounds that any real value will replace.
    pub const EMPTY: NodeBounds = NodeBounds {
        min_m: f32::INFINITY,
        max_m: f32::NEG_INFINITY,
        error_m: 0.0,
    };

    /// The union of two bounds.
    pub fn union(self, other: NodeBounds) -> NodeBounds {
        NodeBounds {
            min_m: self.min_m.min(other.min_m),
            max_m: self.max_m.max(other.max_m),
            error_m: self.error_m.max(other.error_m),
        }
    }
}

/// Why tile bytes could not be decoded.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum TileDecodeError {
    #[error("tile is {len} bytes, shorter than its {HEADER_BYTES}-byte header")]
    TooShort { len: usize },
    #[error("not a cig tile (bad magic)")]
    BadMagic,
    #[error(
        "tile format version {found} is not supported (this build reads 1 to {TILE_FORMAT_VERSION})"
    )]
    Version { found: u32 },
    #[error("tile header is inconsistent: {0}")]
    Header(String),
    #[error("tile checksum mismatch (stored {stored:08x}, computed {computed:08x})")]
    Checksum { stored: u32, computed: u32 },
    #[error("tile holds {found} but {expected} was expected")]
    WrongTile { found: TileKey, expected: TileKey },
    #[error("tile holds invalid material byte {0}")]
    Material(u8),
}

/// The error of each post as a vertex of the right-triangulated irregular network (RTIN) over
/// its level's posts, against the finest posts.
///
/// Every post but the corners of the network's root squares is the midpoint of the hypotenuse
/// of two of the network's triangles. `own_m[i * n + j]` is the largest vertical distance from
/// the finest posts of either triangle, or of any triangle below them down to this level's cells
/// (propagated upwards as in Martini, Agafonkin 2019, but exact: measured at the finest posts,
/// which bound two piecewise-linear surfaces whose vertices are finest posts). So a mesh of this
/// level's posts that keeps every post with `own_m > tol` is a conforming triangulation (every
/// kept post's ancestors are kept) within `tol` of the finest posts wherever its triangles are
/// larger than this level's cells. `coarser_m` holds the same for the next coarser level at this
/// tile's even posts, which is what the renderer needs to morph towards the parent's mesh. A
/// post's error never decreases towards finer levels (a finer level's network has more
/// triangles below each post), so meshes of nested nodes nest. Built by `build`; zero past the
/// database's edge.
#[derive(Clone, Debug, PartialEq)]
pub struct LodErrors {
    pub own_m: Vec<f32>,
    pub coarser_m: Vec<f32>,
}

/// Posts along the side of a tile's even-post grid.
pub fn even_posts_per_side(posts_per_side: usize) -> usize {
    (posts_per_side - 1) / 2 + 1
}

/// A decoded tile.
#[derive(Clone, Debug, PartialEq)]
pub struct Tile {
    pub key: TileKey,
    /// Posts along a side (`tile_cells + 1`).
    pub posts_per_side: usize,
    /// Elevation of each post in metres above mean sea level, row-major, south row first.
    pub elevation_m: Vec<f32>,
    /// Material byte of each post (see [`Material`]).
    pub material: Vec<u8>,
    /// Min/max/error quadtree, heap order, root first.
    pub nodes: Vec<NodeBounds>,
    /// Depth of the quadtree below the root.
    pub quadtree_depth: u32,
    /// Errors for adaptive meshes (`None` in format 1 tiles and rebuilt stand-ins).
    pub lod_errors: Option<LodErrors>,
    /// `Some(level)` when this tile was not read but rebuilt from a coarser level because the
    /// real one was unreadable (see `cache`).
    pub degraded_from_level: Option<u8>,
    /// The culture standing on a finest tile, clamped to its surface (loaded with the tile by
    /// `TerrainDatabase::load_tile`; `None` on coarser levels and where there is none).
    pub culture: Option<crate::culture::CultureTile>,
}

/// Depth of the min/max quadtree of a tile with `tile_cells` cells per side.
pub fn quadtree_depth_for(tile_cells: usize) -> u32 {
    let leaves_per_side = (tile_cells / QUADTREE_LEAF_CELLS).max(1);
    leaves_per_side.trailing_zeros()
}

impl Tile {
    /// Cells per side.
    pub fn cells(&self) -> usize {
        self.posts_per_side - 1
    }

    /// Elevation of post `(i, j)` (`i` northwards, `j` eastwards).
    #[inline]
    pub fn elevation(&self, i: usize, j: usize) -> f32 {
        self.elevation_m[i * self.posts_per_side + j]
    }

    /// Heights of cell `(i, j)`'s corners: south-west, south-east, north-west, north-east.
    #[inline]
    pub fn cell_corners(&self, i: usize, j: usize) -> [f32; 4] {
        let n = self.posts_per_side;
        let base = i * n + j;
        let e = &self.elevation_m[base..base + n + 2];
        [e[0], e[1], e[n], e[n + 1]]
    }

    /// How cell `(i, j)` is split (tiles start at a multiple of their even cell count, so the
    /// database-wide checkerboard of [`Diagonal::of_cell`] holds in tile indices).
    #[inline]
    pub fn cell_diagonal(i: usize, j: usize) -> Diagonal {
        Diagonal::of_cell(i, j)
    }

    /// Material of post `(i, j)`.
    #[inline]
    pub fn material_at(&self, i: usize, j: usize) -> Material {
        Material::from_byte(self.material[i * self.posts_per_side + j]).unwrap_or(Material::Grass)
    }

    /// Root bounds of the tile.
    pub fn bounds(&self) -> NodeBounds {
        self.nodes.first().copied().unwrap_or(NodeBounds::EMPTY)
    }

    /// Height of this tile's triangulated surface at fractional post index `(fi, fj)`, clamped to
    /// the tile.
    #[inline]
    pub fn surface_height(&self, fi: f64, fj: f64) -> f64 {
        let (i, j, u, v) = self.cell_of(fi, fj);
        triangulated_height(self.cell_corners(i, j), u, v, Self::cell_diagonal(i, j))
    }

    /// Cell `(i, j)` holding fractional index `(fi, fj)` and the fractions `(u, v)` within it.
    #[inline]
    pub fn cell_of(&self, fi: f64, fj: f64) -> (usize, usize, f64, f64) {
        let max_cell = (self.cells() - 1) as f64;
        let ci = fi.floor().clamp(0.0, max_cell);
        let cj = fj.floor().clamp(0.0, max_cell);
        let v = (fi - ci).clamp(0.0, 1.0);
        let u = (fj - cj).clamp(0.0, 1.0);
        (ci as usize, cj as usize, u, v)
    }

    /// Encodes the tile in its memory-image file format.
    pub fn encode(&self) -> Vec<u8> {
        let n2 = self.posts_per_side * self.posts_per_side;
        let lod_len = self
            .lod_errors
            .as_ref()
            .map_or(0, |e| (e.own_m.len() + e.coarser_m.len()) * 4);
        let version = if self.lod_errors.is_some() {
            TILE_FORMAT_VERSION
        } else {
            TILE_FORMAT_WITHOUT_LOD_ERRORS
        };
        let payload_len = n2 * 4 + self.nodes.len() * 12 + lod_len + n2;
        let padded = payload_len.next_multiple_of(4);
        let mut out = Vec::with_capacity(HEADER_BYTES + padded);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&version.to_le_bytes());
        out.push(self.key.level);
        out.push(self.quadtree_depth as u8);
        out.extend_from_slice(&[0, 0]);
        out.extend_from_slice(&self.key.row.to_le_bytes());
        out.extend_from_slice(&self.key.col.to_le_bytes());
        out.extend_from_slice(&(self.posts_per_side as u32).to_le_bytes());
        out.extend_from_slice(&(self.nodes.len() as u32).to_le_bytes());
        out.extend_from_slice(&(padded as u64).to_le_bytes());
        out.extend_from_slice(&[0u8; 24]); // CRC and reserved, CRC patched below
        for h in &self.elevation_m {
            out.extend_from_slice(&h.to_le_bytes());
        }
        for node in &self.nodes {
            for v in [node.min_m, node.max_m, node.error_m] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        if let Some(errors) = &self.lod_errors {
            for v in errors.own_m.iter().chain(&errors.coarser_m) {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out.extend_from_slice(&self.material);
        out.resize(HEADER_BYTES + padded, 0);
        let crc = tile_crc(&out);
        out[40..44].copy_from_slice(&crc.to_le_bytes());
        out
    }

    /// Decodes a tile, checking magic, version, sizes, checksum and (when given) its key.
    pub fn decode(bytes: &[u8], expected: Option<TileKey>) -> Result<Tile, TileDecodeError> {
        if bytes.len() < HEADER_BYTES {
            return Err(TileDecodeError::TooShort { len: bytes.len() });
        }
        if &bytes[0..8] != MAGIC {
            return Err(TileDecodeError::BadMagic);
        }
        let u32_at =
            |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let version = u32_at(8);
        if version != TILE_FORMAT_VERSION && version != TILE_FORMAT_WITHOUT_LOD_ERRORS {
            return Err(TileDecodeError::Version { found: version });
        }
        let key = TileKey {
            level: bytes[12],
            row: u32_at(16),
            col: u32_at(20),
        };
        let depth = u32::from(bytes[13]);
        let n = u32_at(24) as usize;
        let node_count = u32_at(28) as usize;
        let mut len8 = [0u8; 8];
        len8.copy_from_slice(&bytes[32..40]);
        let payload_len = u64::from_le_bytes(len8);
        let stored_crc = u32_at(40);
        if !(2..=8193).contains(&n) || depth > 12 {
            return Err(TileDecodeError::Header(format!(
                "{n} posts per side, quadtree depth {depth}"
            )));
        }
        if node_count != quadtree_node_count(depth) {
            return Err(TileDecodeError::Header(format!(
                "{node_count} quadtree nodes for depth {depth}"
            )));
        }
        let n2 = n * n;
        let m = even_posts_per_side(n);
        let lod_len = if version == TILE_FORMAT_VERSION {
            (n2 + m * m) * 4
        } else {
            0
        };
        let needed = n2 * 5 + node_count * 12 + lod_len;
        if payload_len != needed.next_multiple_of(4) as u64
            || bytes.len() as u64 != HEADER_BYTES as u64 + payload_len
        {
            return Err(TileDecodeError::Header(format!(
                "payload of {payload_len} bytes in a file of {} bytes, {needed} needed",
                bytes.len()
            )));
        }
        if bytes[14..16]
            .iter()
            .chain(&bytes[44..HEADER_BYTES])
            .any(|&b| b != 0)
        {
            return Err(TileDecodeError::Header(
                "reserved header bytes are not zero".into(),
            ));
        }
        let computed = tile_crc(bytes);
        if computed != stored_crc {
            return Err(TileDecodeError::Checksum {
                stored: stored_crc,
                computed,
            });
        }
        if let Some(expected) = expected {
            if expected != key {
                return Err(TileDecodeError::WrongTile {
                    found: key,
                    expected,
                });
            }
        }
        let p = &bytes[HEADER_BYTES..];
        let elevation_m = f32_vec(&p[..n2 * 4]);
        let node_values = f32_vec(&p[n2 * 4..n2 * 4 + node_count * 12]);
        let nodes = node_values
            .chunks_exact(3)
            .map(|c| NodeBounds {
                min_m: c[0],
                max_m: c[1],
                error_m: c[2],
            })
            .collect();
        let lod_start = n2 * 4 + node_count * 12;
        let lod_errors = (lod_len > 0).then(|| LodErrors {
            own_m: f32_vec(&p[lod_start..lod_start + n2 * 4]),
            coarser_m: f32_vec(&p[lod_start + n2 * 4..lod_start + lod_len]),
        });
        if let Some(errors) = &lod_errors {
            if errors
                .own_m
                .iter()
                .chain(&errors.coarser_m)
                .any(|e| !(e.is_finite() && *e >= 0.0))
            {
                return Err(TileDecodeError::Header(
                    "level-of-detail errors must be finite and not negative".into(),
                ));
            }
        }
        let material = p[lod_start + lod_len..lod_start + lod_len + n2].to_vec();
        if let Some(&bad) = material.iter().find(|&&m| Material::from_byte(m).is_none()) {
            return Err(TileDecodeError::Material(bad));
        }
        if p[needed..].iter().any(|&b| b != 0) {
            return Err(TileDecodeError::Header("padding bytes are not zero".into()));
        }
        Ok(Tile {
            key,
            posts_per_side: n,
            elevation_m,
            material,
            nodes,
            quadtree_depth: depth,
            lod_errors,
            degraded_from_level: None,
            culture: None,
        })
    }
}

/// Resident bytes of a tile with `posts_per_side` posts and a quadtree of `depth`.
pub fn tile_memory_bytes(posts_per_side: usize, depth: u32) -> usize {
    let even = even_posts_per_side(posts_per_side);
    std::mem::size_of::<Tile>()
        + posts_per_side * posts_per_side * 9
        + even * even * 4
        + quadtree_node_count(depth) * std::mem::size_of::<NodeBounds>()
}

fn tile_crc(bytes: &[u8]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&bytes[..40]);
    hasher.update(&bytes[44..]);
    hasher.finalize()
}

/// Reads little-endian `f32`s: a plain copy on little-endian hosts.
fn f32_vec(bytes: &[u8]) -> Vec<f32> {
    #[cfg(target_endian = "little")]
    {
        bytemuck::pod_collect_to_vec(bytes)
    }
    #[cfg(not(target_endian = "little"))]
    {
        bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample_tile(n: usize, seed: u32) -> Tile {
        let depth = quadtree_depth_for(n - 1);
        Tile {
            key: TileKey {
                level: 2,
                row: 7,
                col: seed,
            },
            posts_per_side: n,
            elevation_m: (0..n * n)
                .map(|k| (k as f32 * 0.37 + seed as f32).sin() * 100.0)
                .collect(),
            material: (0..n * n).map(|k| (k % 9) as u8).collect(),
            nodes: (0..quadtree_node_count(depth))
                .map(|k| NodeBounds {
                    min_m: -(k as f32),
                    max_m: k as f32,
                    error_m: 0.5,
                })
                .collect(),
            quadtree_depth: depth,
            lod_errors: Some(LodErrors {
                own_m: (0..n * n).map(|k| (k % 7) as f32 * 1.5).collect(),
                coarser_m: (0..even_posts_per_side(n).pow(2))
                    .map(|k| (k % 5) as f32 * 2.5)
                    .collect(),
            }),
            degraded_from_level: None,
            culture: None,
        }
    }

    #[test]
    fn encode_decode_round_trip() {
        let tile = sample_tile(33, 3);
        let bytes = tile.encode();
        assert_eq!(
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]),
            2
        );
        assert_eq!(Tile::decode(&bytes, Some(tile.key)), Ok(tile));
    }

    #[test]
    fn level_of_detail_errors_that_are_not_finite_or_are_negative_are_refused() {
        for bad in [f32::NAN, f32::INFINITY, -1.0] {
            let mut tile = sample_tile(17, 5);
            if let Some(errors) = tile.lod_errors.as_mut() {
                errors.own_m[40] = bad;
            }
            assert!(
                matches!(
                    Tile::decode(&tile.encode(), None),
                    Err(TileDecodeError::Header(_))
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn format_1_tiles_without_lod_errors_still_round_trip() {
        let tile = Tile {
            lod_errors: None,
            ..sample_tile(17, 4)
        };
        let bytes = tile.encode();
        assert_eq!(
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]),
            1
        );
        assert_eq!(
            bytes.len(),
            64 + (17 * 17 * 5 + tile.nodes.len() * 12).next_multiple_of(4)
        );
        assert_eq!(Tile::decode(&bytes, Some(tile.key)), Ok(tile));
    }

    #[test]
    fn flipped_byte_fails_the_checksum() {
        let tile = sample_tile(17, 1);
        let mut bytes = tile.encode();
        let k = bytes.len() / 2;
        bytes[k] ^= 0x40;
        assert!(matches!(
            Tile::decode(&bytes, None),
            Err(TileDecodeError::Checksum { .. })
        ));
    }

    #[test]
    fn wrong_key_is_reported() {
        let tile = sample_tile(17, 1);
        let other = TileKey {
            level: 0,
            row: 0,
            col: 0,
        };
        assert!(matches!(
            Tile::decode(&tile.encode(), Some(other)),
            Err(TileDecodeError::WrongTile { .. })
        ));
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let _ = Tile::decode(&bytes, None);
        }

        #[test]
        fn mutated_tiles_never_panic_and_are_rejected(pos in 0usize..10_000, val in any::<u8>(), cut in 0usize..10_000) {
            let tile = sample_tile(9, 2);
            let mut bytes = tile.encode();
            let pos = pos % bytes.len();
            let changed = bytes[pos] != val;
            bytes[pos] = val;
            let result = Tile::decode(&bytes, None);
            if changed {
                prop_assert!(result.is_err());
            }
            let cut = cut % bytes.len();
            prop_assert!(Tile::decode(&bytes[..cut], None).is_err());
        }
    }
}
