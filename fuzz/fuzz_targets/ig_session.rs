//! The IG's world fed fuzzed host messages and DIS datagrams: whatever decodes is applied, the
//! world steps, and the frame's answers are computed and encoded, on a small analytic terrain.
//! Nothing may panic (non-finite numbers, huge offsets, attachment cycles, unknown ids).
//! The first byte picks CIGI (even) or DIS (odd); CIGI inputs are put behind a valid IG Control
//! of either version and byte order so the fuzzer reaches the packets at once.
#![no_main]

use cig_cigi::{encode_message, ByteOrder, IgControl, Message, Packet, Version};
use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use libfuzzer_sys::fuzz_target;
use std::sync::{Arc, OnceLock};

fn cache() -> Arc<TileCache> {
    static CACHE: OnceLock<Arc<TileCache>> = OnceLock::new();
    Arc::clone(CACHE.get_or_init(|| {
        let grid = GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 0.0003,
            dlon_deg: 0.0003,
            rows: 65,
            cols: 65,
        };
        let raster = Raster {
            grid,
            elevation_m: (0..grid.len()).map(|k| (k % 65) as f32 * 2.0).collect(),
            material: Some(vec![Material::Grass; grid.len()]),
        };
        let store = Arc::new(MemoryTileStore::new());
        let summary = build_pyramid::<cig_terrain::build::BuildError>(&raster, 32, &mut |t| {
            store.insert(t.key, t.encode());
            Ok(())
        })
        .expect("build");
        let manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec!["fuzz".into()]);
        let db = TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>)
            .expect("db");
        Arc::new(TileCache::new(Arc::new(db), PagingConfig::default()).expect("cache"))
    }))
}

const SCENARIO: &str = r#"
start_time = "2026-06-21T12:00:00Z"
[[entities]]
id = 1
model = "tank"
dis_id = "1:2:3"
dis_type = "1:1:225:1:1:0:0"
lat_deg = 36.01
lon_deg = -120.99
clamp = "height_and_attitude"
[dis]
exercise = 1
"#;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let mut q = QuerySession::new(cache());
    let Ok(scenario) = cig_ig::Scenario::from_toml(SCENARIO) else {
        return;
    };
    let Ok(start) = cig_environment::UtcTime::from_calendar(2026, 6, 21, 12, 0, 0.0) else {
        return;
    };
    let Ok(mut world) = cig_ig::IgWorld::new(
        scenario,
        cig_ig::WorldConfig {
            session: cig_ig::SessionConfig::default(),
            start,
            fog_mode: cig_scene::lighting::FogMode::Exponential,
            // Small pools: the fuzzer builds a world per input.
            effects: cig_effects::EffectsConfig {
                plume_slots: 4,
                puffs_per_column: 8,
                dust_slots: 4,
                puffs_per_dust_trail: 8,
                area: None,
            },
            join_exercise: true,
        },
    ) else {
        return;
    };
    if selector & 1 == 0 {
        let version = if selector & 2 == 0 { Version::V3_3 } else { Version::V4_0 };
        let order = if selector & 4 == 0 { ByteOrder::BigEndian } else { ByteOrder::LittleEndian };
        let mut input = Vec::new();
        let first = Message::new(version, order, vec![Packet::IgControl(IgControl { ig_mode: 1, ..IgControl::default() })]);
        if encode_message(&first, &mut input).is_err() {
            return;
        }
        input.extend_from_slice(rest);
        let _ = world.receive_cigi(&input);
    } else {
        world.receive_dis(rest, &mut q);
    }
    for frame in 0..3u32 {
        world.step(1.0 / 60.0, &mut q);
        let message = world.host_message(&mut q, frame);
        let mut bytes = Vec::new();
        let _ = encode_message(&message, &mut bytes);
        let fallback = cig_scene::View {
            eye: cig_geo::Geodetic::new(36.0, -121.0, 500.0),
            orientation: cig_scene::Hpr::default(),
            fov: cig_scene::FovDeg::symmetric(60.0, 45.0),
            width_px: 64,
            height_px: 48,
        };
        let _ = world.snapshot(64, 48, &fallback);
        let _ = world.take_dis_outgoing();
    }
});
