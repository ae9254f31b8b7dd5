//! Renderer behaviour on lavapipe (or any GPU): golden images, cracks, popping, earth
//! curvature, precision far from the origin, and bad views.

mod common;

use cig_geo::{EnuFrame, Geodetic};
use cig_render::Image;
use cig_scene::lighting::{Fog, FogMode, SkyModel};
use cig_scene::models::{Model, ModelMesh};
use cig_scene::{EntityInstance, FrameSnapshot, Hpr};
use common::*;
use glam::{DVec3, Vec3};

#[test]
fn golden_images_match_in_daylight_and_at_dusk_with_fog_and_models() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = hills_point(-1500.0, -1500.0, 250.0);
    let mut snapshot = FrameSnapshot::new(
        MORNING_UNIX_S,
        vec![view(eye, (40.0, -10.0, 0.0), 60.0, (192, 128))],
    );
    let (day, stats) = render(&mut renderer, &cache, &snapshot, false);
    assert!(stats.terrain_nodes > 0 && stats.triangles > 0);
    check_golden("hills_day", &day);

    // Dusk, exponential-squared fog at 3 km, a tank and a building on the ground.
    snapshot.unix_time_s = MORNING_UNIX_S + 8.5 * 3600.0;
    snapshot.fog = Fog::from_visibility(FogMode::ExponentialSquared, 3000.0);
    snapshot.views[0] = view(
        hills_point(-1500.0, -1500.0, 25.0),
        (40.0, -4.0, 0.0),
        60.0,
        (192, 128),
    );
    let tank_at = hills_point(-1385.0, -1404.0, 0.0);
    let house_at = hills_point(-1330.0, -1450.0, 0.0);
    snapshot.entities = vec![
        EntityInstance {
            id: 1,
            cue_important: false,
            critical_radius_m: None,
            model: "tank".into(),
            position: tank_at,
            orientation: Hpr::default(),
        },
        EntityInstance {
            id: 2,
            cue_important: false,
            critical_radius_m: None,
            model: "building".into(),
            position: house_at,
            orientation: Hpr {
                heading_deg: 30.0,
                ..Default::default()
            },
        },
    ];
    let (dusk, stats) = render(&mut renderer, &cache, &snapshot, false);
    assert_eq!(stats.entities_drawn, 2);
    check_golden("hills_dusk_fog_models", &dusk);
    // At sunset the fog takes the horizon sky's colour: redder than the day's.
    let redness = |i: &Image| {
        i.rgba
            .chunks_exact(4)
            .map(|p| f64::from(p[0]) - f64::from(p[1]))
            .sum::<f64>()
            / (i.rgba.len() / 4) as f64
    };
    assert!(redness(&dusk) > redness(&day) + 10.0);
}

fn key_pixels(image: &Image) -> usize {
    image.rgba.chunks_exact(4).filter(|p| is_key(p)).count()
}

#[test]
fn no_background_shows_through_between_terrain_nodes() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let size = (256, 192);
    let mut checked = 0;
    for (k, (n, e, agl, heading, pitch)) in [
        (0.0, 0.0, 400.0, 0.0, -60.0),
        (500.0, -800.0, 250.0, 45.0, -40.0),
        (-900.0, 600.0, 600.0, 200.0, -55.0),
        (1200.0, 1200.0, 150.0, 300.0, -35.0),
        (-1500.0, -300.0, 900.0, 120.0, -75.0),
        (300.0, 1700.0, 350.0, 260.0, -45.0),
    ]
    .into_iter()
    .enumerate()
    {
        let snapshot_view = view(hills_point(n, e, agl), (heading, pitch, 0.0), 50.0, size);
        for max_pixel_error in [0.0, 1.0, 4.0] {
            let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![snapshot_view]);
            snapshot.max_pixel_error = max_pixel_error;
            let (image, _) = render(&mut renderer, &cache, &snapshot, true);
            let holes = key_pixels(&image);
            if holes > 0 {
                write_png(
                    &image,
                    &out_dir().join(format!("crack_{k}_{max_pixel_error}.png")),
                );
            }
            assert_eq!(
                holes, 0,
                "view {k} at {max_pixel_error} px: background shows through"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 18);
}

#[test]
fn no_cracks_while_finer_tiles_are_still_loading() {
    let db = hills();
    let layout = *db.layout();
    // Only the two coarsest levels and a scattering of finer tiles are resident.
    let cache = cache(&db);
    for level in 0..layout.levels {
        for key in layout.keys_at(level) {
            if level + 2 >= layout.levels || (key.row + key.col + u32::from(level)) % 3 == 0 {
                cache.load_now(key).expect("tile");
            }
        }
    }
    let mut renderer = renderer(&cache);
    for (n, e, agl, heading, pitch) in [
        (0.0, 0.0, 300.0, 30.0, -50.0),
        (800.0, -600.0, 500.0, 210.0, -60.0),
    ] {
        let snapshot = FrameSnapshot::new(
            MORNING_UNIX_S,
            vec![view(
                hills_point(n, e, agl),
                (heading, pitch, 0.0),
                50.0,
                (256, 192),
            )],
        );
        let (image, _) = cig_render::render_image_with(
            &mut renderer,
            &cache,
            &snapshot,
            0,
            cig_render::FrameOptions {
                mesh_budget: usize::MAX,
                key_background: true,
                fade_in_s: 0.0,
                adaptation: cig_render::Adaptation::Settled,
            },
        )
        .expect("render");
        assert_eq!(
            key_pixels(&image),
            0,
            "background shows through mixed-level terrain"
        );
    }
}

#[test]
fn level_of_detail_changes_frame_to_frame_no_more_than_full_detail_does() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let size = (200, 150);
    let frames = 10;
    let sequence = |renderer: &mut cig_render::Renderer, max_pixel_error: f64| -> Vec<Image> {
        (0..frames)
            .map(|i| {
                let eye = hills_point(-2000.0 + 40.0 * i as f64, -1800.0 + 30.0 * i as f64, 180.0);
                let mut snapshot = FrameSnapshot::new(
                    MORNING_UNIX_S,
                    vec![view(eye, (37.0, -6.0, 0.0), 60.0, size)],
                );
                snapshot.max_pixel_error = max_pixel_error;
                render(renderer, &cache, &snapshot, false).0
            })
            .collect()
    };
    let full = sequence(&mut renderer, 0.0);
    let lod = sequence(&mut renderer, 1.0);
    let change = |images: &[Image]| -> Vec<f64> {
        images
            .windows(2)
            .map(|w| mean_abs_diff(&w[0], &w[1]))
            .collect()
    };
    let (full_change, lod_change) = (change(&full), change(&lod));
    for (i, (f, l)) in full_change.iter().zip(&lod_change).enumerate() {
        assert!(
            *l <= f * 1.25 + 0.5,
            "step {i}: level-of-detail frames change by {l:.2} where full detail changes by {f:.2}"
        );
    }
    // And the level-of-detail frames stay close to the full-detail ones.
    for (i, (f, l)) in full.iter().zip(&lod).enumerate() {
        let flip = flip_mean(f, l);
        assert!(
            flip < 0.06,
            "frame {i}: FLIP {flip:.4} between full detail and 1 px"
        );
    }
}

/// Local radius of curvature (Gaussian mean) of the WGS84 ellipsoid at `lat_deg`.
fn gaussian_radius_m(lat_deg: f64) -> f64 {
    let (a, e2) = (cig_geo::WGS84_A_M, cig_geo::WGS84_E2);
    let s2 = lat_deg.to_radians().sin().powi(2);
    let w = (1.0 - e2 * s2).sqrt();
    let m = a * (1.0 - e2) / (w * w * w);
    let n = a / w;
    (m * n).sqrt()
}

#[test]
fn a_ship_thirty_km_away_sinks_hull_first_below_the_horizon() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye_height_m = 10.0;
    let eye = Geodetic::new(36.0, -122.0, eye_height_m);
    let frame = EnuFrame::new(Geodetic::new(36.0, -122.0, 0.0));
    let distance_m = 30_000.0;
    let ship_ground = frame.enu_to_geodetic(DVec3::new(0.0, distance_m, 0.0));
    // Put it on the ellipsoid (the sea here is at 0 m with no geoid).
    let ship_at = Geodetic::new(ship_ground.lat_deg, ship_ground.lon_deg, 0.0);
    let ship_view = view(eye, (0.0, -0.1, 0.0), 0.6, (240, 240));
    let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![ship_view]);
    snapshot.fog = Fog::from_visibility(FogMode::Off, 1e6);
    snapshot.max_pixel_error = 0.5;
    // The geometric earth (the sea's refraction is `cig`'s hull-down test's).
    snapshot.refraction_k = 0.0;
    let (empty, _) = render(&mut renderer, &cache, &snapshot, true);
    snapshot.entities = vec![EntityInstance {
        id: 1,
        cue_important: false,
        critical_radius_m: None,
        model: "ship".into(),
        position: ship_at,
        orientation: Hpr::default(),
    }];
    let (with_ship, stats) = render(&mut renderer, &cache, &snapshot, true);
    assert_eq!(stats.entities_drawn, 1);
    let changed_rows: Vec<u32> = (0..with_ship.height)
        .filter(|&y| {
            (0..with_ship.width).any(|x| {
                let i = ((y * with_ship.width + x) * 4) as usize;
                (0..3).any(|c| empty.rgba[i + c].abs_diff(with_ship.rgba[i + c]) > 12)
            })
        })
        .collect();
    let (Some(&top), Some(&bottom)) = (changed_rows.first(), changed_rows.last()) else {
        panic!("the ship's mast should show above the horizon at 30 km");
    };
    // Geometry: the horizon is sqrt(2 R h) away; beyond it, (d - d_h)^2 / 2R is hidden.
    let r = gaussian_radius_m(36.0);
    let horizon_m = (2.0 * r * eye_height_m).sqrt();
    let hidden_m = (distance_m - horizon_m).powi(2) / (2.0 * r);
    assert!((26.0..29.0).contains(&hidden_m), "hidden height {hidden_m}");
    let camera = ship_view.camera();
    let up = frame.enu_vector_to_ecef(DVec3::Z);
    let row_of = |height_m: f64| {
        let p = ship_at.to_ecef() + up * height_m;
        camera.project_ecef(p).expect("in front").1
    };
    let masthead_m = cig_scene::models::ship_particulars("ship")
        .expect("the ship's particulars")
        .masthead_height_m;
    let mast_top_row = row_of(masthead_m);
    let hidden_row = row_of(hidden_m);
    write_png(&with_ship, &out_dir().join("ship_30km.png"));
    assert!(
        (f64::from(top) - mast_top_row).abs() < 2.5,
        "mast top at row {top}, geometry says {mast_top_row:.1}"
    );
    assert!(
        (f64::from(bottom) - hidden_row).abs() < 3.0,
        "the ship disappears below row {bottom}; the horizon should hide it below row {hidden_row:.1} ({hidden_m:.1} m)"
    );
    // The hull and the superstructure (to 19.8 m) are all hidden.
    assert!(f64::from(bottom) < row_of(19.8) - 5.0);
}

fn test_box() -> Model {
    let mut mesh = ModelMesh::default();
    mesh.add_box(
        Vec3::new(-6.0, -8.0, 0.0),
        Vec3::new(6.0, 8.0, 7.5),
        [200, 200, 200, 255],
    );
    Model::new("test_box", vec![mesh.clone(), mesh.clone(), mesh])
}

#[test]
fn geometry_lands_on_its_pixel_far_from_the_database_origin() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    renderer.set_models(vec![test_box()]);
    let size = (320, 240);
    // Far away (about 9000 km from the database) and near it: sub-pixel placement in both.
    for base in [
        Geodetic::new(61.2, 149.9, 35.0),
        Geodetic::new(36.01, -121.2, 1500.0),
    ] {
        let frame = EnuFrame::new(base);
        let box_at = frame.enu_to_geodetic(DVec3::new(0.0, 60.0, -3.75));
        let box_view = view(base, (0.0, 0.0, 0.0), 30.0, size);
        let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![box_view]);
        let (empty, _) = render(&mut renderer, &cache, &snapshot, true);
        snapshot.entities = vec![EntityInstance {
            id: 7,
            cue_important: false,
            critical_radius_m: None,
            model: "test_box".into(),
            position: box_at,
            orientation: Hpr::default(),
        }];
        let (image, _) = render(&mut renderer, &cache, &snapshot, true);
        let (mut sum_x, mut sum_y, mut count) = (0.0, 0.0, 0.0);
        let (mut min_x, mut max_x) = (u32::MAX, 0);
        for y in 0..size.1 {
            for x in 0..size.0 {
                let i = ((y * size.0 + x) * 4) as usize;
                let diff: u32 = (0..3)
                    .map(|c| u32::from(empty.rgba[i + c].abs_diff(image.rgba[i + c])))
                    .sum();
                if diff > 30 {
                    let w = 1.0;
                    sum_x += (f64::from(x) + 0.5) * w;
                    sum_y += (f64::from(y) + 0.5) * w;
                    count += w;
                    min_x = min_x.min(x);
                    max_x = max_x.max(x);
                }
            }
        }
        assert!(count > 100.0, "box not drawn at {base:?}");
        let (cx, cy) = (sum_x / count, sum_y / count);
        assert!((cx - 160.0).abs() < 0.35, "centroid x {cx} at {base:?}");
        assert!((cy - 120.0).abs() < 0.35, "centroid y {cy} at {base:?}");
        // The front face is 12 m wide at 52 m.
        let expected_px = 12.0 / 52.0 * box_view.camera().pixels_per_tangent;
        let width_px = f64::from(max_x - min_x + 1);
        assert!(
            (width_px - expected_px).abs() < 1.5,
            "width {width_px} px, expected {expected_px:.1}"
        );
    }
}

#[test]
fn level_of_detail_draws_far_fewer_triangles_than_full_detail() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = hills_point(-3800.0, -3800.0, 1500.0);
    let mut snapshot = FrameSnapshot::new(
        MORNING_UNIX_S,
        vec![view(eye, (45.0, -12.0, 0.0), 60.0, (160, 120))],
    );
    snapshot.max_pixel_error = 0.0;
    let (_, full) = render(&mut renderer, &cache, &snapshot, false);
    snapshot.max_pixel_error = 1.0;
    let (_, lod) = render(&mut renderer, &cache, &snapshot, false);
    snapshot.max_pixel_error = 4.0;
    let (_, coarse) = render(&mut renderer, &cache, &snapshot, false);
    // This 8 km database is steep (24 m of error at level 1), so 1 px keeps much of it fine;
    // the 50 km benchmark measures the real ratio.
    assert!(
        lod.terrain_triangles * 14 < full.terrain_triangles * 10
            && coarse.terrain_triangles * 3 < full.terrain_triangles,
        "1 px: {}, 4 px: {}, full: {}",
        lod.terrain_triangles,
        coarse.terrain_triangles,
        full.terrain_triangles
    );
    // A narrow (6x) view of the same frame size refines further than a wide one.
    let narrow = view(eye, (45.0, -5.0, 0.0), 10.0, (160, 120));
    let wide = view(eye, (45.0, -5.0, 0.0), 60.0, (160, 120));
    let level = |sel: &cig_scene::Selection| {
        sel.nodes
            .iter()
            .map(|n| f64::from(n.key.level))
            .sum::<f64>()
            / sel.nodes.len().max(1) as f64
    };
    let narrow_sel = renderer.select(&cache, &narrow, 1.0);
    let wide_sel = renderer.select(&cache, &wide, 1.0);
    assert!(
        level(&narrow_sel) < level(&wide_sel),
        "{} vs {}",
        level(&narrow_sel),
        level(&wide_sel)
    );
}

#[test]
fn bad_views_are_errors_not_panics() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let mut bad = view(
        hills_point(0.0, 0.0, 100.0),
        (0.0, 0.0, 0.0),
        60.0,
        (64, 48),
    );
    bad.width_px = 0;
    let snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![bad]);
    let err = cig_render::render_image(&mut renderer, &cache, &snapshot, 0).expect_err("zero size");
    assert!(err.to_string().contains("frame size"), "{err}");
    let mut bad = view(
        hills_point(0.0, 0.0, 100.0),
        (0.0, 0.0, 0.0),
        60.0,
        (64, 48),
    );
    bad.eye.alt_m = -5000.0;
    let snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![bad]);
    let err = cig_render::render_image(&mut renderer, &cache, &snapshot, 0).expect_err("below");
    assert!(err.to_string().contains("below the ellipsoid"), "{err}");
}

/// Writes a glTF 2.0 file (JSON with an embedded base64 buffer) of a red square pyramid, 4 m
/// wide and 6 m tall, apex up (+Y in glTF).
fn write_pyramid_gltf(path: &std::path::Path) {
    let p: [[f32; 3]; 5] = [
        [-2.0, 0.0, -2.0],
        [2.0, 0.0, -2.0],
        [2.0, 0.0, 2.0],
        [-2.0, 0.0, 2.0],
        [0.0, 6.0, 0.0],
    ];
    let idx: [u16; 18] = [0, 1, 2, 0, 2, 3, 0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0];
    let mut bytes: Vec<u8> = p.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
    const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut b64 = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk
            .iter()
            .enumerate()
            .fold(0u32, |acc, (i, &b)| acc | (u32::from(b) << (16 - 8 * i)));
        for k in 0..4 {
            if k <= chunk.len() {
                b64.push(B64[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                b64.push('=');
            }
        }
    }
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.02, 0.02, 1.0]}}],
        "buffers": [{"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{b64}")}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 60},
            {"buffer": 0, "byteOffset": 60, "byteLength": 36}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3",
             "min": [-2.0, 0.0, -2.0], "max": [2.0, 6.0, 2.0]},
            {"bufferView": 1, "componentType": 5123, "count": 18, "type": "SCALAR"}
        ]
    });
    std::fs::write(path, serde_json::to_vec_pretty(&json).expect("json")).expect("write gltf");
}

#[test]
fn a_gltf_file_loads_with_three_levels_and_draws_where_placed() {
    let dir = out_dir().join("gltf");
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("pyramid.gltf");
    write_pyramid_gltf(&path);
    let model = cig_render::load_gltf_model(&path, "pyramid").expect("load");
    assert_eq!(model.lods.len(), 3);
    assert_eq!(model.lods[0].triangle_count(), 6);
    // glTF +Y (up) became body +Z: the apex is 6 m up.
    let top = model.lods[0]
        .vertices
        .iter()
        .map(|v| v.position[2])
        .fold(f32::MIN, f32::max);
    assert!((top - 6.0).abs() < 1e-5);

    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    renderer.set_models(vec![model]);
    let base = Geodetic::new(50.0, 10.0, 500.0);
    let frame = EnuFrame::new(base);
    let at = frame.enu_to_geodetic(DVec3::new(0.0, 30.0, -3.0));
    let mut snapshot = FrameSnapshot::new(
        MORNING_UNIX_S,
        vec![view(base, (0.0, 0.0, 0.0), 40.0, (160, 120))],
    );
    snapshot.entities = vec![EntityInstance {
        id: 1,
        cue_important: false,
        critical_radius_m: None,
        model: "pyramid".into(),
        position: at,
        orientation: Hpr::default(),
    }];
    let (image, stats) = render(&mut renderer, &cache, &snapshot, true);
    write_png(&image, &dir.join("pyramid.png"));
    assert_eq!(stats.entities_drawn, 1);
    let red = image
        .rgba
        .chunks_exact(4)
        .filter(|p| {
            let [r, g, b] = [p[0], p[1], p[2]].map(i32::from);
            !is_key(p) && r > g + 30 && r > b + 30
        })
        .count();
    assert!(red > 200, "{red} red pixels");

    // Broken files are errors naming the file.
    let broken = dir.join("broken.gltf");
    std::fs::write(&broken, b"{ \"asset\": ").expect("write");
    let err = cig_render::load_gltf_model(&broken, "x").expect_err("broken");
    assert!(err.to_string().contains("broken.gltf"), "{err}");
}

#[test]
fn a_gltf_node_graph_with_a_cycle_is_refused() {
    let dir = out_dir().join("gltf-cycle");
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("cycle.gltf");
    write_pyramid_gltf(&path);
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).expect("read")).expect("json");
    json["nodes"] = serde_json::json!([{"mesh": 0, "children": [0]}]);
    std::fs::write(&path, serde_json::to_vec(&json).expect("json")).expect("write");
    let err = cig_render::load_gltf_model(&path, "cycle").expect_err("cycle");
    assert!(err.to_string().contains("not a tree"), "{err}");
}

#[test]
fn ancestors_stand_in_while_finer_meshes_are_still_being_built() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let v = view(
        hills_point(-1500.0, -1500.0, 1500.0),
        (45.0, -40.0, 0.0),
        50.0,
        (256, 192),
    );
    let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    // A coarse frame first: the coarse nodes get meshes.
    snapshot.max_pixel_error = 16.0;
    render(&mut renderer, &cache, &snapshot, true);
    // Then full detail with only 4 new meshes allowed: the rest is drawn by their ancestors.
    snapshot.max_pixel_error = 0.0;
    cig_render::load_for_view(&mut renderer, &cache, &snapshot, 0, 64).expect("load");
    let (image, stats) = cig_render::render_image_with(
        &mut renderer,
        &cache,
        &snapshot,
        0,
        cig_render::FrameOptions {
            mesh_budget: 4,
            key_background: true,
            fade_in_s: 0.5,
            adaptation: cig_render::Adaptation::Settled,
        },
    )
    .expect("render");
    assert!(
        stats.meshes_deferred > 0 && stats.node_stand_ins > 0,
        "{stats:?}"
    );
    assert_eq!(key_pixels(&image), 0, "holes while meshes build");
}

#[test]
fn a_ground_fog_layer_fills_the_valleys_and_leaves_the_hills_clear() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = hills_point(-1500.0, -1500.0, 1200.0);
    let v = view(eye, (45.0, -35.0, 0.0), 60.0, (160, 120));
    let camera = v.camera();
    let mut q = cig_terrain::QuerySession::new(cache.clone());
    let frame = EnuFrame::new(eye);
    // Ground points in view that the eye sees, with their heights and pixels.
    let mut seen: Vec<(f64, (f64, f64))> = Vec::new();
    for i in 0..30 {
        for j in 0..30 {
            let g = frame.enu_to_geodetic(DVec3::new(
                -200.0 + 80.0 * f64::from(i),
                -200.0 + 80.0 * f64::from(j),
                0.0,
            ));
            let Ok(s) = q.hot(g.lat_deg, g.lon_deg) else {
                continue;
            };
            let ground = Geodetic::new(g.lat_deg, g.lon_deg, s.height_ellipsoid_m());
            let Some((x, y)) = camera.project_ecef(ground.to_ecef()) else {
                continue;
            };
            if !(6.0..154.0).contains(&x) || !(6.0..114.0).contains(&y) {
                continue;
            }
            let above = Geodetic::new(ground.lat_deg, ground.lon_deg, ground.alt_m + 2.0);
            if q.los(eye, above).is_ok_and(|r| r.visible) {
                seen.push((ground.alt_m, (x, y)));
            }
        }
    }
    seen.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (low, high) = (seen[0], seen[seen.len() - 1]);
    assert!(
        high.0 - low.0 > 40.0,
        "the view spans valleys and hills: {low:?} {high:?}"
    );
    let mut clear = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    clear.fog = Fog::from_visibility(FogMode::Off, 40_000.0);
    let mut fogged = clear.clone();
    fogged.ground_fog = Some(cig_scene::FogLayer {
        top_m: 0.5 * (low.0 + high.0),
        visibility_m: 60.0,
    });
    let (a, _) = render(&mut renderer, &cache, &clear, false);
    let (b, _) = render(&mut renderer, &cache, &fogged, false);
    let change_at = |(x, y): (f64, f64)| {
        let mut sum = 0.0;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let i =
                    ((y as i64 + dy) as usize * a.width as usize + (x as i64 + dx) as usize) * 4;
                for c in 0..3 {
                    sum += (f64::from(a.rgba[i + c]) - f64::from(b.rgba[i + c])).abs();
                }
            }
        }
        sum / 27.0
    };
    let valley = change_at(low.1);
    let hill = change_at(high.1);
    assert!(valley > 25.0, "the valley floor is fogged: {valley}");
    assert!(hill < 6.0, "the hilltop above the layer is clear: {hill}");
}

#[test]
fn pipelines_built_for_the_frames_switches_draw_what_the_unspecialised_ones_do() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = hills_point(-1500.0, -1500.0, 400.0);
    let base = FrameSnapshot::new(
        MORNING_UNIX_S,
        vec![view(eye, (45.0, -12.0, 0.0), 60.0, (96, 72))],
    );
    let mut frames: Vec<(&str, FrameSnapshot)> = Vec::new();
    for (name, mode) in [
        ("no fog", FogMode::Off),
        ("linear fog", FogMode::Linear),
        ("exponential fog", FogMode::Exponential),
        ("exponential-squared fog", FogMode::ExponentialSquared),
    ] {
        let mut s = base.clone();
        s.fog = Fog::from_visibility(mode, 2500.0);
        frames.push((name, s));
    }
    let mut layer = frames[0].1.clone();
    layer.ground_fog = Some(cig_scene::FogLayer {
        top_m: eye.alt_m - 250.0,
        visibility_m: 100.0,
    });
    frames.push(("ground fog", layer));
    let mut flat = frames[1].1.clone();
    flat.sky.model = SkyModel::Flat;
    frames.push(("flat sky, linear fog", flat));
    // Near the ground, with the ground's detail and plain (the GROUND_DETAIL switch).
    let mut near = frames[2].1.clone();
    near.views[0] = view(
        hills_point(-1500.0, -1500.0, 25.0),
        (45.0, -35.0, 0.0),
        60.0,
        (96, 72),
    );
    let mut plain = near.clone();
    plain.ground_detail = false;
    frames.push(("near ground", near));
    frames.push(("near plain ground", plain));
    // Ten hours on the moon is 33 degrees up and the sun 16 degrees down; six more, the moon
    // is 35 degrees down: the sky-view table with and without the moon's light.
    for (name, later_s) in [("moonlit night", 36_000.0), ("moonless night", 57_600.0)] {
        let mut night = base.clone();
        night.unix_time_s += later_s;
        frames.push((name, night));
    }
    // Mean difference (0..255 per channel) under which two images count as the same.
    const SAME_MEAN: f64 = 0.05;
    let mut images = Vec::new();
    for (name, frame) in &frames {
        renderer.set_shader_specialisation(true);
        let (specialised, _) = render(&mut renderer, &cache, frame, false);
        renderer.set_shader_specialisation(false);
        let (unspecialised, _) = render(&mut renderer, &cache, frame, false);
        let largest = specialised
            .rgba
            .iter()
            .zip(&unspecialised.rgba)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap_or(0);
        let mean = mean_abs_diff(&specialised, &unspecialised);
        assert!(
            largest <= 2 && mean < SAME_MEAN,
            "{name}: the specialised pipeline differs (largest {largest}, mean {mean})"
        );
        images.push((name, specialised));
    }
    // Each switch changes the picture far beyond that, so a pipeline built for the wrong one
    // would show.
    for (i, (a_name, a)) in images.iter().enumerate() {
        for (b_name, b) in &images[i + 1..] {
            let d = mean_abs_diff(a, b);
            assert!(
                d > 10.0 * SAME_MEAN,
                "{a_name} and {b_name} look alike: {d}"
            );
        }
    }
}

/// A box whose finest level is red and coarser levels blue, to see which level covers a pixel.
fn two_tone_box() -> Model {
    let level = |colour: [u8; 4]| {
        let mut mesh = ModelMesh::default();
        mesh.add_box(Vec3::new(-6.0, -8.0, 0.0), Vec3::new(6.0, 8.0, 7.5), colour);
        mesh
    };
    let blue = level([30, 40, 220, 255]);
    Model::new(
        "two_tone",
        vec![level([220, 30, 30, 255]), blue.clone(), blue],
    )
}

#[test]
fn model_levels_dissolve_into_each_other_across_the_switching_size() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let model = two_tone_box();
    let radius_m = f64::from(model.critical_radius_m());
    renderer.set_models(vec![model]);
    let size = (320, 240);
    let base = Geodetic::new(36.01, -121.2, 1500.0);
    let frame = EnuFrame::new(base);
    let box_view = view(base, (0.0, 0.0, 0.0), 30.0, size);
    let klod = renderer.detail.klod_for(&box_view);
    let table = renderer.detail.table;
    // (share of red among the box's pixels) at a detail control parameter N_e (Eq 16: the box
    // at the view's centre, clear air).
    let mut red_share = |ne: f64| {
        let distance_m = klod * radius_m / ne;
        let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![box_view]);
        snapshot.entities = vec![EntityInstance {
            id: 1,
            cue_important: false,
            critical_radius_m: None,
            model: "two_tone".into(),
            position: frame.enu_to_geodetic(DVec3::new(0.0, distance_m, -3.75)),
            orientation: Hpr::default(),
        }];
        let (image, _) = render(&mut renderer, &cache, &snapshot, true);
        let (mut red, mut blue) = (0u32, 0u32);
        for px in image.rgba.chunks_exact(4) {
            if is_key(px) {
                continue;
            }
            let (r, b) = (i32::from(px[0]), i32::from(px[2]));
            if r > b + 20 {
                red += 1;
            } else if b > r + 20 {
                blue += 1;
            }
        }
        assert!(red + blue > 30, "box not drawn at N_e {ne}");
        f64::from(red) / f64::from(red + blue)
    };
    // The combination zone below the finest level's first step (Table 3: step 6, N_e 54).
    let finest_step = (1..=table.steps())
        .find(|&s| table.level_of_step(s, 3) == 0)
        .expect("a step draws the finest level");
    let (start, end) = table.blend_zone(finest_step);
    assert!(
        red_share(end * 1.2) > 0.97,
        "finest level whole above the zone"
    );
    assert!(
        red_share(start * 0.9) < 0.03,
        "coarser level whole below the zone"
    );
    let half = red_share((start + end) / 2.0);
    assert!((0.35..0.65).contains(&half), "half way: red share {half}");
    let inner = red_share(start + 0.8 * (end - start));
    assert!(
        inner > half + 0.1,
        "nearer the finer end: {inner} vs {half}"
    );
}

/// A box that fades out below the table's first step instead of popping, and is gone where
/// the fog has faded it by 98 %.
#[test]
fn a_model_fades_out_at_its_farthest_range_and_goes_in_thick_fog() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let model = two_tone_box();
    let radius_m = f64::from(model.critical_radius_m());
    renderer.set_models(vec![model]);
    let base = Geodetic::new(36.01, -121.2, 1500.0);
    let frame = EnuFrame::new(base);
    let box_view = view(base, (0.0, 0.0, 0.0), 30.0, (320, 240));
    // A fixed K_LOD that puts step 1 near: the box is large on screen while it fades.
    renderer.detail.klod = Some(15.0);
    let one = renderer.detail.table.value(1);
    let mut image_at = |ne: f64, visibility_m: f64, with_box: bool| {
        let distance_m = 15.0 * radius_m / ne;
        let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![box_view]);
        snapshot.fog = Fog::from_visibility(FogMode::Exponential, visibility_m);
        if with_box {
            snapshot.entities = vec![EntityInstance {
                id: 1,
                cue_important: false,
                critical_radius_m: None,
                model: "two_tone".into(),
                position: frame.enu_to_geodetic(DVec3::new(0.0, distance_m, -3.75)),
                orientation: Hpr::default(),
            }];
        }
        render(&mut renderer, &cache, &snapshot, true).0.rgba
    };
    let mut drawn = |ne: f64| {
        image_at(ne, 40_000.0, true)
            .chunks_exact(4)
            .filter(|px| !is_key(px) && i32::from(px[2]) > i32::from(px[0]) + 20)
            .count() as f64
    };
    let whole = drawn(one);
    assert!(whole > 30.0, "box not drawn: {whole}");
    // At half the first step's N_e the box is twice as far (a quarter of the pixels) and
    // covers half of them.
    let half = drawn(one / 2.0) / whole;
    assert!(
        (0.06..0.2).contains(&half),
        "half faded: {half} of the whole"
    );
    // Just past the visibility (fade over 98 %) the box is gone although its N_e would put it
    // at step 1: the frame is the frame without it.
    let distance_m = 15.0 * radius_m / one;
    let visibility_m = distance_m / 1.02;
    assert!(
        image_at(one, visibility_m, true) == image_at(one, visibility_m, false),
        "removed in the fog"
    );
}

/// The share of the finest level (red) among the two-tone box pixels (red or blue, not the
/// terrain's green-blue) in the left and right halves of a frame.
fn shares(image: &Image) -> [f64; 2] {
    let mut counts = [[0u32; 2]; 2];
    for (i, px) in image.rgba.chunks_exact(4).enumerate() {
        if is_key(px) {
            continue;
        }
        let half = usize::from(i as u32 % image.width >= image.width / 2);
        let (r, g, b) = (i32::from(px[0]), i32::from(px[1]), i32::from(px[2]));
        if r > b + 20 && r > g + 40 {
            counts[half][0] += 1;
        } else if b > r + 20 && b > g + 60 {
            counts[half][1] += 1;
        }
    }
    counts.map(|[red, blue]| {
        assert!(red + blue > 10, "a box is not drawn");
        f64::from(red) / f64::from(red + blue)
    })
}

/// Under the overload control (source 004 Table 4, §4.6) a cue-important model keeps its level
/// while another of the same size at the same range and angle drops to a coarser one.
#[test]
fn cue_important_models_keep_their_step_under_overload() {
    use cig_scene::overload::{CounterLimits, OverloadSettings};
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let model = two_tone_box();
    let radius_m = f64::from(model.critical_radius_m());
    renderer.set_models(vec![model]);
    // A triangle budget the terrain alone exceeds: K_LOD falls every frame to the floor.
    renderer
        .set_overload(Some(OverloadSettings {
            triangles: Some(CounterLimits {
                capacity: 2.0,
                begin_decrement: 1.0,
                begin_increment: 0.5,
            }),
            models: None,
            gpu_ms: None,
            ..OverloadSettings::default()
        }))
        .expect("valid settings");
    let size = (320, 240);
    let base = Geodetic::new(36.01, -121.2, 1500.0);
    let frame = EnuFrame::new(base);
    let box_view = view(base, (0.0, 0.0, 0.0), 30.0, size);
    let nominal = renderer.detail.klod_for(&box_view);
    // Both boxes well inside the finest level's pure zone at the nominal K_LOD, 9 degrees
    // either side of the view's centre (the same area-of-interest factor).
    let finest = renderer.detail.table.value(6) * 1.2;
    let distance_m = nominal * radius_m / finest;
    let east_m = distance_m * 9f64.to_radians().tan();
    let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![box_view]);
    snapshot.entities = [(-east_m, true), (east_m, false)]
        .iter()
        .enumerate()
        .map(|(i, &(east, cue))| EntityInstance {
            id: i as u32 + 1,
            cue_important: cue,
            critical_radius_m: None,
            model: "two_tone".into(),
            position: frame.enu_to_geodetic(DVec3::new(east, distance_m, -3.75)),
            orientation: Hpr::default(),
        })
        .collect();
    // Red share of the box pixels in the left (cue) and right halves.
    let (first, stats) = render(&mut renderer, &cache, &snapshot, true);
    assert_eq!(stats.klod, stats.klod_nominal);
    assert_eq!(stats.overload, "decrement");
    let [cue, other] = shares(&first);
    assert!(
        cue > 0.97 && other > 0.97,
        "both finest unloaded: {cue} {other}"
    );
    let mut last = None;
    for _ in 0..11 {
        last = Some(render(&mut renderer, &cache, &snapshot, true));
    }
    let (image, stats) = last.expect("frames drawn");
    assert!(
        (stats.klod - 0.1 * stats.klod_nominal).abs() < 1e-6 * stats.klod_nominal,
        "K_LOD at the floor: {} of {}",
        stats.klod,
        stats.klod_nominal
    );
    let [cue, other] = shares(&image);
    assert!(cue > 0.97, "the cue keeps the finest level: {cue}");
    assert!(other < 0.03, "the other drops to a coarser level: {other}");
}

/// The scene of the two-tone box tests: the hills, a renderer that draws the box, and a
/// level view 320 x 240 px across `fov_deg` from 1500 m, with the box's radius and the view's
/// nominal K_LOD.
struct BoxScene {
    cache: std::sync::Arc<cig_terrain::TileCache>,
    renderer: cig_render::Renderer,
    radius_m: f64,
    frame: EnuFrame,
    view: cig_scene::View,
    nominal: f64,
}

fn box_scene(fov_deg: f64) -> BoxScene {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let model = two_tone_box();
    let radius_m = f64::from(model.critical_radius_m());
    renderer.set_models(vec![model]);
    let size = (320, 240);
    let base = Geodetic::new(36.01, -121.2, 1500.0);
    let frame = EnuFrame::new(base);
    let box_view = view(base, (0.0, 0.0, 0.0), fov_deg, size);
    let nominal = renderer.detail.klod_for(&box_view);
    BoxScene {
        cache,
        renderer,
        radius_m,
        frame,
        view: box_view,
        nominal,
    }
}

/// Two two-tone boxes `distance_m` from the origin of `frame` (slant range), `angle_deg`
/// left and right of north, with the model table's critical radii given (left first).
fn box_pair(
    frame: &EnuFrame,
    distance_m: f64,
    angle_deg: f64,
    critical_radius_m: [Option<f32>; 2],
) -> Vec<EntityInstance> {
    let (sin, cos) = angle_deg.to_radians().sin_cos();
    [-1.0, 1.0]
        .iter()
        .zip(critical_radius_m)
        .enumerate()
        .map(|(i, (&side, critical_radius_m))| EntityInstance {
            id: i as u32 + 1,
            cue_important: false,
            critical_radius_m,
            model: "two_tone".into(),
            position: frame.enu_to_geodetic(DVec3::new(
                side * distance_m * sin,
                distance_m * cos,
                -3.75,
            )),
            orientation: Hpr::default(),
        })
        .collect()
}

/// The area of interest follows the host's point of interest (source 004 §3.4): two boxes 20
/// degrees either side of the view's centre draw at their finest level, and when the point of
/// interest moves onto the left one the right one, 40 degrees from it, drops to a coarser level.
#[test]
fn the_point_of_interest_moves_where_models_keep_their_detail() {
    let BoxScene {
        cache,
        mut renderer,
        radius_m,
        frame,
        view: box_view,
        nominal,
    } = box_scene(60.0);
    // N_e 70 at the point of interest: 63 at 20 degrees from it (the finest level, from 54),
    // 37 at 40 degrees (the middle level: the area of interest falls to half by 45 degrees).
    let distance_m = nominal * radius_m / 70.0;
    let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![box_view]);
    snapshot.entities = box_pair(&frame, distance_m, 20.0, [None, None]);
    let centred = render(&mut renderer, &cache, &snapshot, true).0;
    write_png(&centred, &out_dir().join("point_of_interest_centre.png"));
    let [left, right] = shares(&centred);
    assert!(
        left > 0.97 && right > 0.97,
        "both finest at the centre's point: {left} {right}"
    );
    snapshot.points_of_interest_deg = vec![Some([-20.0, 0.0])];
    let [left, right] = shares(&render(&mut renderer, &cache, &snapshot, true).0);
    assert!(left > 0.97, "the box looked at keeps its detail: {left}");
    assert!(
        right < 0.03,
        "the box 40 degrees away drops a level: {right}"
    );
}

/// A critical radius the model table sets (source 004 Eq 16: `r_c`) replaces the model's own
/// in the detail control parameter: of two identical boxes side by side at a range where the
/// box's own radius gives the middle level, the one given twice the radius draws its finest.
#[test]
fn a_critical_radius_from_the_model_table_sets_the_level() {
    let BoxScene {
        cache,
        mut renderer,
        radius_m,
        frame,
        view: box_view,
        nominal,
    } = box_scene(30.0);
    // N_e 35 with the box's own radius (the middle level), 70 with twice it (the finest),
    // both 8 degrees from the centre (inside the area of interest).
    let distance_m = nominal * radius_m / 35.0;
    let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![box_view]);
    snapshot.entities = box_pair(&frame, distance_m, 8.0, [Some(2.0 * radius_m as f32), None]);
    let image = render(&mut renderer, &cache, &snapshot, true).0;
    let [left, right] = shares(&image);
    assert!(
        left > 0.97,
        "twice the critical radius: the finest level ({left})"
    );
    assert!(right < 0.03, "its own radius: a coarser level ({right})");
}

/// A model deep in a ground fog layer is removed like one in the global fog (f(v) counts the
/// layer along the ray), while the same model above the layer's top is drawn.
#[test]
fn a_model_in_a_thick_ground_fog_layer_is_removed() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let model = two_tone_box();
    renderer.set_models(vec![model]);
    let base = Geodetic::new(36.01, -121.2, 1500.0);
    let frame = EnuFrame::new(base);
    let box_view = view(base, (0.0, 0.0, 0.0), 30.0, (320, 240));
    // The box 150 m ahead, the layer's transmittance to it `t`: its visibility from
    // Koschmieder's 3.912 over the optical depth.
    let mut image_at = |top_m: f64, t: f64, with_box: bool| {
        let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![box_view]);
        snapshot.ground_fog = Some(cig_scene::FogLayer {
            top_m,
            visibility_m: 3.912 * 150.0 / -t.ln(),
        });
        if with_box {
            snapshot.entities = vec![EntityInstance {
                id: 1,
                cue_important: false,
                critical_radius_m: None,
                model: "two_tone".into(),
                position: frame.enu_to_geodetic(DVec3::new(0.0, 150.0, -3.75)),
                orientation: Hpr::default(),
            }];
        }
        render(&mut renderer, &cache, &snapshot, true).0.rgba
    };
    let top = base.alt_m + 100.0;
    // Faded by just over 98 % (1.9 % left, the global fog's 1.5 % on top): removed, the frame
    // is the frame without it, though its faint trace would show in the pixels.
    assert!(
        image_at(top, 0.019, true) == image_at(top, 0.019, false),
        "removed in the layer"
    );
    // Faded by 96 %: still drawn.
    assert!(
        image_at(top, 0.04, true) != image_at(top, 0.04, false),
        "drawn when a trace is left"
    );
    // The same layer with its top far below the eye and the box: drawn.
    assert!(
        image_at(base.alt_m - 500.0, 0.019, true) != image_at(base.alt_m - 500.0, 0.019, false),
        "drawn above the layer"
    );
}

/// No pop on a slow approach (issue 18, source 004 §2.5): a tank approached from where it
/// first appears (N_e well below the first step) to where it draws its finest level, 4 % of
/// the range a frame, changes its pixel coverage between two frames only as the approach
/// does (8 % a frame, within 12 % and 3 px of the pixel grid): it fades in, and its levels
/// dissolve into each other, rather than appearing or switching at once.
#[test]
fn a_slowly_approached_model_never_pops() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let size = (200, 150);
    let base = Geodetic::new(36.01, -121.2, 1500.0);
    let frame = EnuFrame::new(base);
    // Looking 10 degrees up, so the tank stands against the keyed sky.
    let tank_view = view(base, (0.0, 10.0, 0.0), 30.0, size);
    let klod = renderer.detail.klod_for(&tank_view);
    let radius_m = f64::from(
        cig_scene::models::builtin("tank")
            .expect("tank")
            .critical_radius_m(),
    );
    let (sin10, cos10) = 10f64.to_radians().sin_cos();
    let coverage = |renderer: &mut cig_render::Renderer, ne: f64| {
        let distance_m = klod * radius_m / ne;
        let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![tank_view]);
        snapshot.entities = vec![EntityInstance {
            id: 1,
            cue_important: false,
            critical_radius_m: None,
            model: "tank".into(),
            position: frame.enu_to_geodetic(DVec3::new(
                0.0,
                distance_m * cos10,
                distance_m * sin10,
            )),
            orientation: Hpr::default(),
        }];
        let image = render(renderer, &cache, &snapshot, true).0;
        // The upper four fifths (the horizon's strip of terrain is below them).
        let rows = image.height as usize * 4 / 5;
        image.rgba[..rows * image.width as usize * 4]
            .chunks_exact(4)
            .filter(|px| !is_key(px))
            .count() as f64
    };
    let mut ne = 0.3;
    let mut previous = coverage(&mut renderer, ne);
    let mut frames = 0;
    let mut largest_step: f64 = 0.0;
    while ne < 120.0 {
        ne *= 1.04;
        let now = coverage(&mut renderer, ne);
        // The projected area grows as N_e squared (1.0816 a frame); 12 % either side of that
        // and 3 px for the pixel grid.
        let expected = previous * 1.0816;
        assert!(
            now <= expected * 1.12 + 3.0 && now >= expected / 1.12 - 3.0,
            "at N_e {ne:.2} the coverage went from {previous} to {now} px in one frame"
        );
        if previous > 20.0 {
            largest_step = largest_step.max(now / previous);
        }
        previous = now;
        frames += 1;
    }
    eprintln!("{frames} frames; largest growth between frames {largest_step:.3}");
    assert!(previous > 200.0, "the tank ends large: {previous} px");
}

/// Terrain edits around a point of the hills: three craters (6, 3.7 and 1.5 m across), a
/// 40 m tank ditch with its spoil, a berm, a tank's fighting position and a tank's two ruts
/// (20 m at 14 and 17.4 m north), all made at `MORNING_UNIX_S`.
fn dig_in(cache: &cig_terrain::TileCache, centre: Geodetic) {
    use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint, SpoilSide, TerrainEdit};
    let frame = EnuFrame::new(centre);
    let at = |east_m: f64, north_m: f64| {
        let g = frame.enu_to_geodetic(DVec3::new(east_m, north_m, 0.0));
        GeoPoint {
            lat_deg: g.lat_deg,
            lon_deg: g.lon_deg,
        }
    };
    let crater = |east_m, north_m, radius_m: f64, depth_m: f64| EditShape::Crater {
        centre: at(east_m, north_m),
        radius_m,
        depth_m,
        lip_radius_m: 1.25 * radius_m,
        lip_height_m: 0.25 * depth_m,
    };
    let shapes = [
        crater(0.0, 0.0, 3.07, 1.53),
        crater(9.0, 4.0, 1.85, 0.93),
        crater(-6.0, 7.0, 0.77, 0.38),
        EditShape::Ditch {
            from: at(-20.0, -15.0),
            to: at(20.0, -18.0),
            width_m: 4.0,
            depth_m: 2.5,
            spoil: SpoilSide::Left,
        },
        EditShape::Berm {
            from: at(25.0, -5.0),
            to: at(30.0, 25.0),
            width_m: 3.0,
            height_m: 1.5,
        },
        EditShape::Position {
            centre: at(-25.0, 12.0),
            heading_deg: 30.0,
            length_m: 9.0,
            width_m: 4.5,
            depth_m: 2.0,
        },
        EditShape::Rut {
            from: at(-5.0, 14.0),
            to: at(15.0, 14.0),
            width_m: 0.6,
            depth_m: 0.08,
        },
        EditShape::Rut {
            from: at(-5.0, 17.4),
            to: at(15.0, 17.4),
            width_m: 0.6,
            depth_m: 0.08,
        },
    ];
    for (sequence, shape) in shapes.into_iter().enumerate() {
        cache
            .update_edits(|layer| {
                layer.apply(TerrainEdit {
                    author: EditAuthor::default(),
                    sequence: sequence as u32,
                    time_utc_s: MORNING_UNIX_S,
                    shape,
                })
            })
            .expect("an edit");
    }
}

#[test]
fn terrain_edits_are_drawn_without_holes_at_every_level_of_detail() {
    let db = hills();
    let plain_cache = cache(&db);
    let edited_cache = cache(&db);
    let centre = hills_point(0.0, 0.0, 0.0);
    dig_in(&edited_cache, centre);
    let mut plain_renderer = renderer(&plain_cache);
    let mut edited_renderer = renderer(&edited_cache);
    let size = (256, 192);
    // Close and grazing, looking down, and far enough for coarser nodes around the edits.
    for (k, (n, e, agl, heading, pitch)) in [
        (-25.0, -10.0, 12.0, 20.0, -25.0),
        (-8.0, 0.0, 30.0, 0.0, -70.0),
        (30.0, 40.0, 4.0, 220.0, -30.0),
        (-300.0, -200.0, 120.0, 35.0, -35.0),
    ]
    .into_iter()
    .enumerate()
    {
        let snapshot_view = view(hills_point(n, e, agl), (heading, pitch, 0.0), 60.0, size);
        for max_pixel_error in [0.0, 1.0, 4.0] {
            let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![snapshot_view]);
            snapshot.max_pixel_error = max_pixel_error;
            let (edited, stats) = render(&mut edited_renderer, &edited_cache, &snapshot, true);
            let holes = key_pixels(&edited);
            if holes > 0 {
                write_png(
                    &edited,
                    &out_dir().join(format!("edit_hole_{k}_{max_pixel_error}.png")),
                );
            }
            assert_eq!(
                holes, 0,
                "view {k} at {max_pixel_error} px: background shows through"
            );
            if k < 3 && max_pixel_error <= 1.0 {
                // Up close the edits change the picture: their patches are drawn.
                let (plain, plain_stats) =
                    render(&mut plain_renderer, &plain_cache, &snapshot, true);
                assert!(
                    stats.terrain_triangles > plain_stats.terrain_triangles + 500,
                    "view {k}: {} vs {} triangles",
                    stats.terrain_triangles,
                    plain_stats.terrain_triangles
                );
                let changed = mean_abs_diff(&edited, &plain);
                assert!(
                    changed > 0.3,
                    "view {k}: the edits change {changed} per channel"
                );
                if max_pixel_error == 1.0 {
                    write_png(&edited, &out_dir().join(format!("edits_{k}.png")));
                }
            }
        }
    }
}

/// The edits' dynamic texture: a fresh crater is scorched and a tank's fresh tracks are dark
/// on the grass; two days later the scorch has weathered and the tracks' marks are gone
/// (their ruts' shape stays).
#[test]
fn fresh_craters_are_scorched_and_track_marks_fade() {
    let db = hills();
    let cache = cache(&db);
    dig_in(&cache, hills_point(0.0, 0.0, 0.0));
    let mut renderer = renderer(&cache);
    let size = (256, 192);
    let luma = |image: &cig_render::Image, x: u32, y: u32| {
        let k = ((y * image.width + x) * 4) as usize;
        let px = &image.rgba[k..k + 3];
        0.2126 * f64::from(px[0]) + 0.7152 * f64::from(px[1]) + 0.0722 * f64::from(px[2])
    };
    let shot = |renderer: &mut cig_render::Renderer, north_m: f64, east_m: f64, unix_s: f64| {
        let v = view(
            hills_point(north_m, east_m, 20.0),
            (0.0, -89.0, 0.0),
            60.0,
            size,
        );
        render(
            renderer,
            &cache,
            &FrameSnapshot::new(unix_s, vec![v]),
            false,
        )
        .0
    };
    let later = MORNING_UNIX_S + 2.0 * 86_400.0;
    // The crater's middle, looking down on it.
    let (fresh, weathered) = (
        shot(&mut renderer, 0.0, 0.0, MORNING_UNIX_S),
        shot(&mut renderer, 0.0, 0.0, later),
    );
    write_png(&fresh, &out_dir().join("crater_fresh.png"));
    write_png(&weathered, &out_dir().join("crater_weathered.png"));
    let middle = |image: &cig_render::Image| {
        let (cx, cy) = (size.0 / 2, size.1 / 2);
        let mut sum = 0.0;
        for y in cy - 12..cy + 12 {
            for x in cx - 12..cx + 12 {
                sum += luma(image, x, y);
            }
        }
        sum / 576.0
    };
    let (scorched, bare) = (middle(&fresh), middle(&weathered));
    assert!(
        scorched < 0.6 * bare,
        "the fresh crater's middle is {scorched:.1}, two days later {bare:.1}"
    );
    // The tracks, looking down between them.
    let (fresh, faded) = (
        shot(&mut renderer, 15.7, 5.0, MORNING_UNIX_S),
        shot(&mut renderer, 15.7, 5.0, later),
    );
    write_png(&fresh, &out_dir().join("tracks_fresh.png"));
    write_png(&faded, &out_dir().join("tracks_faded.png"));
    let marked = (0..size.1)
        .flat_map(|y| (0..size.0).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let k = ((y * size.0 + x) * 4) as usize;
            let change: u32 = (0..3)
                .map(|c| u32::from(fresh.rgba[k + c].abs_diff(faded.rgba[k + c])))
                .sum();
            change > 24
        })
        .count();
    // Two strips 0.6 m wide and 20 m long at 11 px a metre: at most 2 x 7 x 220 px.
    assert!(
        (600..6000).contains(&marked),
        "{marked} px changed where the fresh tracks are"
    );
}

#[test]
fn a_gpu_error_is_kept_until_taken() {
    // A device of its own: the shared one's errors belong to the other tests.
    let gpu = cig_render::Gpu::headless().expect("a GPU adapter (install mesa-vulkan-drivers)");
    assert_eq!(gpu.take_errors(), None);
    // A buffer mapped both for reading and for writing: refused without a feature the IG never
    // asks for.
    let _refused = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("refused"),
        size: 16,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::MAP_WRITE,
        mapped_at_creation: false,
    });
    let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
    let (count, first) = gpu.take_errors().expect("the error is kept");
    assert!(count >= 1 && !first.is_empty(), "{count}: {first}");
    assert_eq!(gpu.take_errors(), None, "taken once");
}
