//! The imagery pyramid's public maths and tile format: layout, fine shift, tile bytes round
//! trip, damaged tiles refused.

use cig_terrain::imagery::*;
use cig_terrain::raster::GeoGrid;

fn grid(rows: usize, cols: usize) -> GeoGrid {
    GeoGrid {
        south_lat_deg: 35.0,
        west_lon_deg: -120.5,
        dlat_deg: 1.0 / 3600.0,
        dlon_deg: 1.0 / 3600.0,
        rows,
        cols,
    }
}

fn pattern(texels: u32) -> Vec<u8> {
    let n = texels as usize;
    let mut rgba = vec![0u8; n * n * 4];
    for i in 0..n {
        for j in 0..n {
            let at = (i * n + j) * 4;
            // Flat 4x4 blocks of one colour each; the left quarter transparent.
            let (bi, bj) = (i / 4, j / 4);
            rgba[at] = (bi * 4) as u8;
            rgba[at + 1] = (bj * 4) as u8;
            rgba[at + 2] = 128;
            rgba[at + 3] = if j < n / 4 { 0 } else { 255 };
        }
    }
    rgba
}

#[test]
fn tiles_round_trip_through_their_bytes() {
    let key = ImageryKey {
        level: 2,
        row: 3,
        col: 5,
    };
    let rgba = pattern(IMAGERY_TILE_TEXELS);
    let tile = ImageryTile::from_rgba(key, IMAGERY_TILE_TEXELS, &rgba);
    let bytes = tile.encode();
    let back = ImageryTile::decode(&bytes, Some(key)).expect("decode");
    assert_eq!(back, tile);
    let decoded = back.to_rgba();
    for (a, b) in decoded.chunks_exact(4).zip(rgba.chunks_exact(4)) {
        assert_eq!(a[3] >= 128, b[3] >= 128, "alpha {a:?} for {b:?}");
        if b[3] >= 128 {
            // One colour per block: only RGB565 rounding remains.
            for c in 0..3 {
                assert!(a[c].abs_diff(b[c]) <= 8, "{a:?} for {b:?}");
            }
        }
    }
}

#[test]
fn damaged_tiles_are_refused() {
    let key = ImageryKey {
        level: 0,
        row: 1,
        col: 1,
    };
    let tile = ImageryTile::from_rgba(key, IMAGERY_TILE_TEXELS, &pattern(IMAGERY_TILE_TEXELS));
    let bytes = tile.encode();
    assert_eq!(
        ImageryTile::decode(&bytes[..20], Some(key)),
        Err(ImageryDecodeError::Truncated(20))
    );
    let short = bytes.len() - 1;
    assert_eq!(
        ImageryTile::decode(&bytes[..short], Some(key)),
        Err(ImageryDecodeError::Truncated(short))
    );
    let mut flipped = bytes.clone();
    let last = flipped.len() - 1;
    flipped[last] ^= 1;
    assert_eq!(
        ImageryTile::decode(&flipped, Some(key)),
        Err(ImageryDecodeError::Checksum)
    );
    let mut magic = bytes.clone();
    magic[0] = b'X';
    assert_eq!(
        ImageryTile::decode(&magic, None),
        Err(ImageryDecodeError::Magic)
    );
    let other = ImageryKey { col: 2, ..key };
    assert!(matches!(
        ImageryTile::decode(&bytes, Some(other)),
        Err(ImageryDecodeError::Key { .. })
    ));
    let mut texels = bytes.clone();
    texels[20] = 128;
    assert!(matches!(
        ImageryTile::decode(&texels, None),
        Err(ImageryDecodeError::Header(_))
    ));
}

#[test]
fn layout_maths() {
    // 64 cells at 1" posts, texels 8 times finer: 512 texels, 2 x 2 tiles, then 1.
    let g = grid(65, 65);
    let layout = ImageryLayout::new(&g, 3);
    assert_eq!((layout.rows, layout.cols), (512, 512));
    assert_eq!(layout.levels, 2);
    assert_eq!(layout.tiles_at(0), (2, 2));
    assert_eq!(layout.tiles_at(1), (1, 1));
    assert!(layout.contains_key(ImageryKey {
        level: 0,
        row: 1,
        col: 1
    }));
    assert!(!layout.contains_key(ImageryKey {
        level: 0,
        row: 2,
        col: 0
    }));
    assert!(!layout.contains_key(ImageryKey {
        level: 2,
        row: 0,
        col: 0
    }));
    let t = 1.0 / 3600.0 / 8.0;
    assert!((layout.texel_lat_deg - t).abs() < 1e-15);
    // A texel's centre maps back to the middle of the texel.
    let (lat, lon) = layout.texel_centre_deg(0, 300, 41);
    let (r, c) = layout.texel_coordinates(lat, lon);
    assert!(
        (r - 300.5).abs() < 1e-6 && (c - 41.5).abs() < 1e-6,
        "{r} {c}"
    );
    // Level 1 texels are twice as large; bounds of tile (0, 1) at level 0.
    assert_eq!(layout.texel_deg(1).0, 2.0 * layout.texel_deg(0).0);
    let (s, w, n, e) = layout.tile_bounds_deg(ImageryKey {
        level: 0,
        row: 0,
        col: 1,
    });
    assert!((s - 35.0).abs() < 1e-12 && (n - s - 256.0 * t).abs() < 1e-12);
    assert!((w - (-120.5 + 256.0 * t)).abs() < 1e-12 && (e - w - 256.0 * t).abs() < 1e-12);
    // Parents, partial tiles, a 3 x 5 pyramid.
    let key = ImageryKey {
        level: 0,
        row: 5,
        col: 3,
    };
    assert_eq!(
        key.parent(),
        ImageryKey {
            level: 1,
            row: 2,
            col: 1
        }
    );
    let odd = ImageryLayout::new(&grid(100, 160), 4);
    assert_eq!((odd.rows, odd.cols), (99 * 16, 159 * 16));
    assert_eq!(odd.tiles_at(0), (7, 10));
    assert_eq!(odd.tiles_at(odd.levels - 1), (1, 1));
    assert_eq!(odd.tiles_at(odd.levels - 2), (1, 2));
    assert!(odd.validate(&grid(100, 160)).is_ok());
    assert!(odd.validate(&grid(100, 161)).is_err());
}

#[test]
fn fine_shift_matches_the_finest_pixel() {
    assert_eq!(ImageryLayout::fine_shift_for(32.0, 1.0), 5);
    assert_eq!(ImageryLayout::fine_shift_for(30.0, 1.0), 5);
    assert_eq!(ImageryLayout::fine_shift_for(30.0, 30.0), 0);
    assert_eq!(ImageryLayout::fine_shift_for(30.0, 100.0), 0);
    assert_eq!(ImageryLayout::fine_shift_for(30.0, 0.001), MAX_FINE_SHIFT);
    assert_eq!(ImageryLayout::fine_shift_for(30.0, 0.0), 0);
    assert_eq!(ImageryLayout::fine_shift_for(f64::NAN, 1.0), 0);
    let layout = ImageryLayout::new(&grid(65, 65), 40);
    assert_eq!(layout.fine_shift, MAX_FINE_SHIFT);
}
