//! The host's line-of-sight and collision answers see the database's culture: a house stops a
//! line of sight and is reported with its culture material code and its wall's normal, a fence
//! does not stop it but an entity's collision segment meets it (selected by the material mask).

use cig_cigi::{
    decode_message, encode_message, ByteOrder, CollisionSegmentDefinition, EntityControl,
    IgControl, LosSegmentRequest, Message, Packet, Version,
};
use cig_effects::EffectsConfig;
use cig_environment::UtcTime;
use cig_ig::session::CULTURE_MATERIAL_CODE_BASE;
use cig_ig::{IgWorld, Scenario, SessionConfig, WorldConfig};
use cig_scene::lighting::FogMode;
use cig_terrain::build::build_pyramid;
use cig_terrain::culture::bin_placements;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{CultureKind, CulturePlacement, PagingConfig, QuerySession, TileCache};
use std::sync::Arc;

const SOUTH: f64 = 36.0;
const WEST: f64 = -121.0;
const GROUND_M: f64 = 100.0;

fn lat_of_row(row: f64) -> f64 {
    SOUTH + row * 30.0 / cig_geo::metres_per_degree(SOUTH).0
}

fn lon_of_col(col: f64) -> f64 {
    WEST + col * 30.0 / cig_geo::metres_per_degree(SOUTH).1
}

/// The point `east_m`, `north_m` from post `(row, col)`.
fn at(row: f64, col: f64, east_m: f64, north_m: f64) -> (f64, f64) {
    (
        lat_of_row(row + north_m / 30.0),
        lon_of_col(col + east_m / 30.0),
    )
}

/// A plain at 100 m MSL (30 m posts, 64-cell tiles) with a fence 30 m long running north-south
/// at post (32, 32) and a house 20 m long east-west at post (32, 40); the geoid is zero.
fn query() -> QuerySession {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    let grid = GeoGrid {
        south_lat_deg: SOUTH,
        west_lon_deg: WEST,
        dlat_deg: 30.0 / n,
        dlon_deg: 30.0 / e,
        rows: 129,
        cols: 129,
    };
    let raster = Raster {
        grid,
        elevation_m: vec![GROUND_M as f32; grid.len()],
        material: Some(vec![Material::Grass; grid.len()]),
    };
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(&raster, 64, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec!["test".into()]);
    let object = |kind,
                  (lat_deg, lon_deg): (f64, f64),
                  [height_m, width_m, length_m]: [f32; 3],
                  heading_deg| {
        CulturePlacement {
            kind,
            lat_deg,
            lon_deg,
            height_m,
            width_m,
            length_m,
            heading_deg,
            variant: 0,
        }
    };
    let placements = [
        object(
            CultureKind::Fence,
            at(32.0, 32.0, 0.0, 0.0),
            [1.4, 0.1, 30.0],
            0.0,
        ),
        object(
            CultureKind::House,
            at(32.0, 40.0, 0.0, 0.0),
            [8.0, 10.0, 20.0],
            90.0,
        ),
    ];
    let (tiles, culture) = bin_placements(&manifest.layout, &placements).expect("placements");
    for tile in &tiles {
        store.insert_culture(tile.key, tile.encode());
    }
    manifest.culture = Some(culture);
    let db = TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db");
    let cache = TileCache::new(Arc::new(db), PagingConfig::default()).expect("cache");
    QuerySession::new(Arc::new(cache))
}

fn world() -> IgWorld {
    IgWorld::new(
        Scenario::from_toml("").expect("scenario"),
        WorldConfig {
            session: SessionConfig::default(),
            start: UtcTime::from_calendar(2026, 6, 21, 12, 0, 0.0).expect("time"),
            fog_mode: FogMode::Exponential,
            effects: EffectsConfig::default(),
            join_exercise: false,
        },
    )
    .expect("world")
}

fn send(world: &mut IgWorld, frame: u32, packets: Vec<Packet>) {
    let mut all = vec![Packet::IgControl(IgControl {
        ig_mode: 1,
        host_frame_number: frame,
        ..IgControl::default()
    })];
    all.extend(packets);
    let mut bytes = Vec::new();
    encode_message(
        &Message::new(Version::V3_3, ByteOrder::BigEndian, all),
        &mut bytes,
    )
    .expect("encode");
    world
        .receive_cigi(&bytes)
        .expect("the IG accepts the message");
}

fn frame(world: &mut IgWorld, q: &mut QuerySession) -> Vec<Packet> {
    world.step(1.0 / 60.0, q);
    let message = world.host_message(q, 1234);
    let mut bytes = Vec::new();
    encode_message(&message, &mut bytes).expect("encode");
    decode_message(&bytes).expect("decode").packets
}

#[test]
fn a_house_stops_a_line_of_sight_and_a_fence_does_not() {
    let mut q = query();
    let mut w = world();
    let los = |id, (lat_a, lon_a): (f64, f64), (lat_b, lon_b): (f64, f64), alt| {
        Packet::LosSegmentRequest(LosSegmentRequest {
            los_id: id,
            request_type_extended: true,
            source_lat_deg_or_x_m: lat_a,
            source_lon_deg_or_y_m: lon_a,
            source_alt_m_or_z_m: alt,
            destination_lat_deg_or_x_m: lat_b,
            destination_lon_deg_or_y_m: lon_b,
            destination_alt_m_or_z_m: alt,
            ..LosSegmentRequest::default()
        })
    };
    send(
        &mut w,
        1,
        vec![
            // Across the fence, 1 m up.
            los(
                1,
                at(32.0, 32.0, -40.0, 2.0),
                at(32.0, 32.0, 40.0, 2.0),
                GROUND_M + 1.0,
            ),
            // South to north through the house (10 m wide), 2 m up.
            los(
                2,
                at(32.0, 40.0, 3.0, -50.0),
                at(32.0, 40.0, 3.0, 50.0),
                GROUND_M + 2.0,
            ),
        ],
    );
    let mut by_id = std::collections::BTreeMap::new();
    for p in frame(&mut w, &mut q) {
        if let Packet::LosExtendedResponse(r) = p {
            by_id.insert(r.los_id, r);
        }
    }
    let fence = &by_id[&1];
    assert!(
        fence.valid && fence.visible && !fence.range_valid,
        "{fence:?}"
    );
    let house = &by_id[&2];
    assert!(
        house.valid && !house.visible && house.range_valid,
        "{house:?}"
    );
    assert!((house.range_m - 45.0).abs() < 0.05, "{house:?}");
    assert_eq!(
        house.material_code,
        CULTURE_MATERIAL_CODE_BASE + CultureKind::House as u32
    );
    // The house's south wall faces south: azimuth 180, elevation 0.
    assert!(
        (house.normal_azimuth_deg.rem_euclid(360.0) - 180.0).abs() < 0.1
            && house.normal_elevation_deg.abs() < 0.1,
        "{house:?}"
    );
    assert!(
        (house.alt_m_or_z_m - (GROUND_M + 2.0)).abs() < 0.01,
        "{house:?}"
    );
}

#[test]
fn a_collision_segment_meets_a_fence_when_its_mask_selects_culture() {
    let mut q = query();
    let mut w = world();
    // An entity 20 m west of the fence, 1 m up, heading east; its segment reaches 40 m ahead.
    let (lat, lon) = at(32.0, 32.0, -20.0, 2.0);
    let entity = Packet::EntityControl(EntityControl {
        entity_id: 7,
        entity_state: 1,
        entity_type: 1,
        collision_detection_enable: true,
        yaw_deg: 90.0,
        lat_deg_or_x_m: lat,
        lon_deg_or_y_m: lon,
        alt_m_or_z_m: GROUND_M + 1.0,
        ..EntityControl::default()
    });
    let segment = |id, mask| {
        Packet::CollisionSegmentDefinition(CollisionSegmentDefinition {
            entity_id: 7,
            segment_id: id,
            segment_enable: true,
            x1_m: 0.0,
            y1_m: 0.0,
            z1_m: 0.0,
            x2_m: 40.0,
            y2_m: 0.0,
            z2_m: 0.0,
            material_mask: mask,
        })
    };
    let fence_code = CULTURE_MATERIAL_CODE_BASE + CultureKind::Fence as u32;
    send(
        &mut w,
        1,
        vec![
            entity,
            segment(1, 1 << fence_code),
            // Terrain materials only: the fence is not reported.
            segment(2, 0x1ff),
        ],
    );
    let mut notes = Vec::new();
    for n in 0..2 {
        for p in frame(&mut w, &mut q) {
            if let Packet::CollisionSegmentNotification(c) = p {
                notes.push((n, c));
            }
        }
    }
    assert!(!notes.is_empty(), "the segment must meet the fence");
    for (_, c) in &notes {
        assert_eq!(c.segment_id, 1, "{c:?}");
        assert_eq!(c.material_code, fence_code);
        assert!(!c.collision_with_entity);
        assert!((c.intersection_distance_m - 19.95).abs() < 0.05, "{c:?}");
    }
}
