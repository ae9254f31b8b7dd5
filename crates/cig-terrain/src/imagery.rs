//! Draped imagery: a pyramid of compressed colour tiles over the database, beside its
//! elevation tiles.
//!
//! Layout: level 0 is a regular geographic lattice of *texels* (areas, not points) whose
//! south-west corner is the database's south-west post and whose texel size is the finest post
//! spacing divided by a power of two (`2^fine_shift`, chosen at import so a texel is no larger
//! than the finest source pixel). Level `k` has texels `2^k` times larger; every level is cut
//! into square tiles of [`IMAGERY_TILE_TEXELS`] texels (south row first, as the post grid),
//! and level `levels - 1` is a single tile over the whole database. Tiles are sparse: a tile
//! with no imagery is not stored, and the renderer falls back to the next coarser level there
//! (where a coarser level has no tile either, the ground keeps its material colours).
//!
//! Tile format (little-endian): a 32-byte header (`CIGIMG` magic and format version, level,
//! the payload's length in 24 bits, row, column, texels per side, pixel format, CRC-32 of the payload), then the
//! payload: BC3 blocks (4x4 texels in 16 bytes: BC1 colour and an 8-bit interpolated alpha),
//! block rows from the south, deflated (a tile of a road over transparent ground, or of one
//! lake colour, shrinks tens of times; an aerial photograph a little). Colour is sRGB premultiplied by alpha (alpha 0 and black where
//! no image covers a texel), so a bilinear tap across a coverage edge blends without a dark
//! fringe. BC3 is what GPUs sample directly (4:1 against 8-bit RGBA, with smooth alpha for the
//! anti-aliased edges of painted roads and rivers); renderers without BC support decode it once
//! on upload.
//!
//! Sources: the clip-texture of SGI's IG work (Tanner, Migdal and Jones, "The Clipmap", 1998)
//! for the pyramid that the renderer windows around the eye; NPSNET's tile pyramid (source 003)
//! for the tiling. Limits: one sRGB colour layer; alpha is one bit per texel.

use crate::raster::GeoGrid;
use serde::{Deserialize, Serialize};

/// Texels along a side of every imagery tile.
pub const IMAGERY_TILE_TEXELS: u32 = 256;

/// Most levels an imagery pyramid may have.
pub const MAX_IMAGERY_LEVELS: u8 = 24;

/// Most times finer than the finest posts imagery texels may be (2^10: 3 cm under 30 m posts).
pub const MAX_FINE_SHIFT: u8 = 10;

const MAGIC: [u8; 8] = *b"CIGIMG\0\x01";
const HEADER_BYTES: usize = 32;
/// Pixel format code of deflated BC3 (sRGB premultiplied colour, 8-bit alpha) payloads.
const FORMAT_BC3_SRGB_DEFLATED: u32 = 3;

/// Identifies one imagery tile: its imagery level (0 = finest texels) and tile row (south
/// first) and column. Imagery levels are not terrain levels: see [`ImageryLayout`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ImageryKey {
    pub level: u8,
    pub row: u32,
    pub col: u32,
}

impl ImageryKey {
    /// The tile one level coarser that contains this one.
    pub fn parent(self) -> ImageryKey {
        ImageryKey {
            level: self.level + 1,
            row: self.row / 2,
            col: self.col / 2,
        }
    }
}

impl std::fmt::Display for ImageryKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "imagery L{}/{}_{}", self.level, self.row, self.col)
    }
}

/// The imagery pyramid's geometry.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageryLayout {
    /// South-west corner of the level-0 texel (0, 0): the database's south-west post, degrees.
    pub south_lat_deg: f64,
    pub west_lon_deg: f64,
    /// Level-0 texel size, degrees: the finest post spacing over `2^fine_shift`.
    pub texel_lat_deg: f64,
    pub texel_lon_deg: f64,
    /// How many times finer than the finest posts level-0 texels are, as a power of two.
    pub fine_shift: u8,
    /// Level-0 texels (rows, columns) over the database's extent.
    pub rows: u64,
    pub cols: u64,
    /// Texels along a tile's side.
    pub tile_texels: u32,
    /// Levels, finest (0) to a single tile (`levels - 1`).
    pub levels: u8,
}

impl ImageryLayout {
    /// The layout over a database's finest post grid whose level-0 texels are the post spacing
    /// over `2^fine_shift` (clamped to [`MAX_FINE_SHIFT`]).
    pub fn new(grid: &GeoGrid, fine_shift: u8) -> ImageryLayout {
        let fine_shift = fine_shift.min(MAX_FINE_SHIFT);
        let scale = f64::from(1u32 << fine_shift);
        let cells = |posts: usize| (posts.max(2) - 1) as u64;
        let rows = cells(grid.rows) << fine_shift;
        let cols = cells(grid.cols) << fine_shift;
        let mut layout = ImageryLayout {
            south_lat_deg: grid.south_lat_deg,
            west_lon_deg: grid.west_lon_deg,
            texel_lat_deg: grid.dlat_deg / scale,
            texel_lon_deg: grid.dlon_deg / scale,
            fine_shift,
            rows,
            cols,
            tile_texels: IMAGERY_TILE_TEXELS,
            levels: 1,
        };
        while layout.tiles_at(layout.levels - 1) != (1, 1) && layout.levels < MAX_IMAGERY_LEVELS {
            layout.levels += 1;
        }
        layout
    }

    /// The smallest `fine_shift` whose level-0 texels are no larger than a source pixel of
    /// `pixel_m` metres over posts `post_m` metres apart (0 for pixels coarser than posts).
    pub fn fine_shift_for(post_m: f64, pixel_m: f64) -> u8 {
        if !(pixel_m > 0.0 && post_m > 0.0) {
            return 0;
        }
        let mut shift = 0u8;
        // A hundredth of slack, so a 1 m image over 32 m posts lands on 1 m texels.
        while post_m / f64::from(1u32 << shift) > pixel_m * 1.01 && shift < MAX_FINE_SHIFT {
            shift += 1;
        }
        shift
    }

    /// Texel size at `level`, degrees (latitude, longitude).
    pub fn texel_deg(&self, level: u8) -> (f64, f64) {
        let s = f64::from(1u32 << level.min(31));
        (self.texel_lat_deg * s, self.texel_lon_deg * s)
    }

    /// Texels (rows, columns) over the database at `level` (a partly covered texel counts).
    pub fn texels_at(&self, level: u8) -> (u64, u64) {
        let s = 1u64 << level.min(63);
        (self.rows.div_ceil(s), self.cols.div_ceil(s))
    }

    /// Tiles (rows, columns) at `level`.
    pub fn tiles_at(&self, level: u8) -> (u32, u32) {
        let (r, c) = self.texels_at(level);
        let t = u64::from(self.tile_texels);
        (r.div_ceil(t) as u32, c.div_ceil(t) as u32)
    }

    /// True when `key` names a tile of this pyramid.
    pub fn contains_key(&self, key: ImageryKey) -> bool {
        if key.level >= self.levels {
            return false;
        }
        let (rows, cols) = self.tiles_at(key.level);
        key.row < rows && key.col < cols
    }

    /// The tile's edges, degrees: (south, west, north, east). Tiles on the north and east
    /// edges reach past the database.
    pub fn tile_bounds_deg(&self, key: ImageryKey) -> (f64, f64, f64, f64) {
        let (tlat, tlon) = self.texel_deg(key.level);
        let t = f64::from(self.tile_texels);
        let south = self.south_lat_deg + f64::from(key.row) * t * tlat;
        let west = self.west_lon_deg + f64::from(key.col) * t * tlon;
        (south, west, south + t * tlat, west + t * tlon)
    }

    /// Latitude and longitude of the centre of texel (row, col) at `level`, degrees.
    pub fn texel_centre_deg(&self, level: u8, row: u64, col: u64) -> (f64, f64) {
        let (tlat, tlon) = self.texel_deg(level);
        (
            self.south_lat_deg + (row as f64 + 0.5) * tlat,
            self.west_lon_deg + (col as f64 + 0.5) * tlon,
        )
    }

    /// Fractional level-0 texel coordinates (row, col) of a point; texel `(i, j)` spans
    /// `[i, i + 1) x [j, j + 1)`, so its centre is at `(i + 0.5, j + 0.5)`.
    pub fn texel_coordinates(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        (
            (lat_deg - self.south_lat_deg) / self.texel_lat_deg,
            (lon_deg - self.west_lon_deg) / self.texel_lon_deg,
        )
    }

    /// Checks what readers rely on against the database's grid.
    pub fn validate(&self, grid: &GeoGrid) -> Result<(), String> {
        if self.fine_shift > MAX_FINE_SHIFT {
            return Err(format!(
                "imagery fine shift {} is over {MAX_FINE_SHIFT}",
                self.fine_shift
            ));
        }
        if ImageryLayout::new(grid, self.fine_shift) != *self {
            return Err("imagery layout does not match the database grid".to_string());
        }
        Ok(())
    }
}

/// The manifest's imagery section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageryManifest {
    pub layout: ImageryLayout,
    /// Tiles stored over all levels.
    pub tile_count: u64,
    /// Where the imagery came from (one line per image or feature file).
    pub sources: Vec<String>,
}

/// Why imagery tile bytes are not a usable tile.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ImageryDecodeError {
    #[error("imagery tile is truncated ({0} bytes)")]
    Truncated(usize),
    #[error("not an imagery tile (bad magic or version)")]
    Magic,
    #[error("imagery tile is {found}, expected {expected}")]
    Key {
        found: ImageryKey,
        expected: ImageryKey,
    },
    #[error("imagery tile header: {0}")]
    Header(String),
    #[error("imagery tile checksum mismatch")]
    Checksum,
}

/// One imagery tile: `texels` x `texels` texels of BC3 blocks, block rows from the south.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageryTile {
    pub key: ImageryKey,
    pub texels: u32,
    /// BC3 blocks, `(texels / 4)^2` of 16 bytes.
    pub blocks: Vec<u8>,
}

/// Block bytes of a square of `texels` texels.
pub fn block_bytes(texels: u32) -> usize {
    let blocks = (texels as usize).div_ceil(4);
    blocks * blocks * 16
}

impl ImageryTile {
    /// Compresses `texels` x `texels` sRGB RGBA texels (straight alpha, rows from the south);
    /// colour is stored premultiplied by alpha.
    pub fn from_rgba(key: ImageryKey, texels: u32, rgba: &[u8]) -> ImageryTile {
        let n = texels as usize;
        assert_eq!(rgba.len(), n * n * 4, "imagery tile texels");
        let premultiplied: Vec<u8> = rgba
            .chunks_exact(4)
            .flat_map(|px| {
                let a = u16::from(px[3]);
                let scale = |c: u8| ((u16::from(c) * a + 127) / 255) as u8;
                [scale(px[0]), scale(px[1]), scale(px[2]), px[3]]
            })
            .collect();
        let mut blocks = vec![0u8; block_bytes(texels)];
        let params = texpresso::Params {
            algorithm: texpresso::Algorithm::RangeFit,
            weights: texpresso::COLOUR_WEIGHTS_PERCEPTUAL,
            weigh_colour_by_alpha: false,
        };
        // Block by block; a block with no coverage stays zeros (alpha 0, black), which is
        // most of a tile of roads or rivers over bare ground.
        let per_row = n.div_ceil(4);
        for (b, block) in blocks.chunks_exact_mut(16).enumerate() {
            let (by, bx) = (b / per_row, b % per_row);
            let mut texels_rgba = [[0u8; 4]; 16];
            let mut mask = 0u32;
            let mut covered = false;
            for (i, px) in texels_rgba.iter_mut().enumerate() {
                let (x, y) = (4 * bx + i % 4, 4 * by + i / 4);
                if x < n && y < n {
                    let at = 4 * (y * n + x);
                    px.copy_from_slice(&premultiplied[at..at + 4]);
                    covered |= px[3] != 0;
                    mask |= 1 << i;
                }
            }
            if covered {
                texpresso::Format::Bc3.compress_block_masked(texels_rgba, mask, params, block);
            }
        }
        ImageryTile {
            key,
            texels,
            blocks,
        }
    }

    /// The texels as sRGB RGBA bytes, colour premultiplied by alpha (rows from the south).
    pub fn to_rgba(&self) -> Vec<u8> {
        let n = self.texels as usize;
        let mut rgba = vec![0u8; n * n * 4];
        texpresso::Format::Bc3.decompress(&self.blocks, n, n, &mut rgba);
        rgba
    }

    /// The tile's file bytes.
    pub fn encode(&self) -> Vec<u8> {
        let payload = miniz_oxide::deflate::compress_to_vec(&self.blocks, 3);
        let mut out = Vec::with_capacity(HEADER_BYTES + payload.len());
        out.extend_from_slice(&MAGIC);
        out.push(self.key.level);
        // The deflated payload's length, 24 bits (a tile's blocks are 64 KiB at most).
        out.extend_from_slice(&(payload.len() as u32).to_le_bytes()[..3]);
        out.extend_from_slice(&self.key.row.to_le_bytes());
        out.extend_from_slice(&self.key.col.to_le_bytes());
        out.extend_from_slice(&self.texels.to_le_bytes());
        out.extend_from_slice(&FORMAT_BC3_SRGB_DEFLATED.to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        debug_assert_eq!(out.len(), HEADER_BYTES);
        out.extend_from_slice(&payload);
        out
    }

    /// Reads a tile's bytes, checking magic, key (when given), size and checksum.
    pub fn decode(
        bytes: &[u8],
        expected: Option<ImageryKey>,
    ) -> Result<ImageryTile, ImageryDecodeError> {
        if bytes.len() < HEADER_BYTES {
            return Err(ImageryDecodeError::Truncated(bytes.len()));
        }
        if bytes[..8] != MAGIC {
            return Err(ImageryDecodeError::Magic);
        }
        let word = |at: usize| {
            u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
        };
        let key = ImageryKey {
            level: bytes[8],
            row: word(12),
            col: word(16),
        };
        if let Some(expected) = expected {
            if key != expected {
                return Err(ImageryDecodeError::Key {
                    found: key,
                    expected,
                });
            }
        }
        let texels = word(20);
        if texels != IMAGERY_TILE_TEXELS {
            return Err(ImageryDecodeError::Header(format!(
                "{texels} texels per side (this build reads {IMAGERY_TILE_TEXELS})"
            )));
        }
        if word(24) != FORMAT_BC3_SRGB_DEFLATED {
            return Err(ImageryDecodeError::Header(format!(
                "pixel format {}",
                word(24)
            )));
        }
        let payload = &bytes[HEADER_BYTES..];
        let stored = u32::from_le_bytes([bytes[9], bytes[10], bytes[11], 0]) as usize;
        if payload.len() != stored {
            return Err(ImageryDecodeError::Truncated(bytes.len()));
        }
        if crc32fast::hash(payload) != word(28) {
            return Err(ImageryDecodeError::Checksum);
        }
        let expected = block_bytes(texels);
        let blocks = miniz_oxide::inflate::decompress_to_vec_with_limit(payload, expected)
            .map_err(|_| ImageryDecodeError::Truncated(bytes.len()))?;
        if blocks.len() != expected {
            return Err(ImageryDecodeError::Truncated(bytes.len()));
        }
        Ok(ImageryTile {
            key,
            texels,
            blocks,
        })
    }
}
