//! Tests of culture placement: determinism, where vegetation may stand, densities, stands,
//! settlement layout, poles, rules.

use super::*;
use crate::{generate, SynthParams};
use cig_terrain::pyramid::PyramidLayout;

const LAT_DEG: f64 = 36.0;
const LON_DEG: f64 = -121.0;

/// A square grid of `posts` a side, `spacing_m` apart, about 36 N.
fn grid(posts: usize, spacing_m: f64) -> GeoGrid {
    let (north, east) = metres_per_degree(LAT_DEG);
    GeoGrid {
        south_lat_deg: LAT_DEG,
        west_lon_deg: LON_DEG,
        dlat_deg: spacing_m / north,
        dlon_deg: spacing_m / east,
        rows: posts,
        cols: posts,
    }
}

/// A flat raster of one material at one height.
fn flat(posts: usize, spacing_m: f64, material: Material, height_m: f32) -> Raster {
    let g = grid(posts, spacing_m);
    Raster {
        grid: g,
        elevation_m: vec![height_m; g.len()],
        material: Some(vec![material; g.len()]),
    }
}

fn synthetic(size_km: f64, seed: u64) -> crate::Generated {
    let p = SynthParams {
        size_km,
        spacing_m: 30.0,
        seed,
        ..SynthParams::demo()
    };
    generate(&p, &crate::SynthOptions::default(), &mut |_, _| {}).expect("valid parameters")
}

fn is_vegetation(k: CultureKind) -> bool {
    k.is_tree() || k == CultureKind::Bush
}

/// Nearest post (row, col) of a placement.
fn nearest_post(g: &GeoGrid, p: &CulturePlacement) -> (usize, usize) {
    let (r, c) = g.fractional_index(p.lat_deg, p.lon_deg);
    (r.round() as usize, c.round() as usize)
}

// ---------------------------------------------------------------- determinism

#[test]
fn the_same_seed_gives_the_same_culture_on_any_thread_count_and_another_seed_other_culture() {
    let g = synthetic(8.0, 3);
    let rules = CultureRules::default();
    let run = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| place_culture(&g.raster, &g.report, &g.features, &rules, seed))
            .expect("valid rules")
    };
    let a = run(1, 7);
    let b = run(3, 7);
    assert!(a.len() > 1000, "{} placements", a.len());
    assert_eq!(a, b);
    let c = run(2, 8);
    assert_ne!(a, c);
    // Not merely shifted: most positions differ.
    let same = a.iter().zip(&c).filter(|(x, y)| x == y).count();
    assert!(same * 10 < a.len(), "{same} of {} identical", a.len());
}

// ---------------------------------------------------------------- vegetation

#[test]
fn no_vegetation_on_or_next_to_water_roads_rock_or_snow() {
    let g = synthetic(8.0, 3);
    let placed = place_culture(
        &g.raster,
        &g.report,
        &g.features,
        &CultureRules::default(),
        1,
    )
    .expect("valid rules");
    let grid = g.raster.grid;
    let mats = g.raster.material.as_ref().expect("materials");
    let mut checked = 0;
    for p in placed.iter().filter(|p| is_vegetation(p.kind)) {
        let (r, c) = nearest_post(&grid, p);
        let own = mats[r * grid.cols + c];
        assert!(
            !matches!(own, Material::Rock | Material::Snow),
            "{} on {own}",
            p.kind
        );
        for rr in r.saturating_sub(1)..=(r + 1).min(grid.rows - 1) {
            for cc in c.saturating_sub(1)..=(c + 1).min(grid.cols - 1) {
                let m = mats[rr * grid.cols + cc];
                assert!(
                    !matches!(
                        m,
                        Material::Water | Material::PavedRoad | Material::DirtRoad
                    ),
                    "{} at post ({r}, {c}) next to {m} at ({rr}, {cc})",
                    p.kind
                );
            }
        }
        checked += 1;
    }
    assert!(checked > 1000, "{checked} trees and bushes");
    let water_or_road = mats
        .iter()
        .filter(|m| {
            matches!(
                m,
                Material::Water | Material::PavedRoad | Material::DirtRoad
            )
        })
        .count();
    assert!(
        water_or_road > 100,
        "the test area has {water_or_road} water and road posts"
    );
}

/// Trees per hectare over a flat forest, and per 150 m block (stands and clearings).
fn forest_counts(rules: &CultureRules, seed: u64) -> (f64, Vec<usize>) {
    let (posts, spacing) = (134, 30.0);
    let raster = flat(posts, spacing, Material::Forest, 300.0);
    let placed = scatter_by_material(&raster, rules, seed).expect("valid rules");
    let side_m = (posts - 1) as f64 * spacing;
    let trees = placed.iter().filter(|p| p.kind.is_tree()).count();
    let per_ha = trees as f64 / (side_m * side_m / HECTARE_M2);
    let blocks = (posts - 1) / 5;
    let mut counts = vec![0usize; blocks * blocks];
    for p in placed.iter().filter(|p| p.kind.is_tree()) {
        let (r, c) = raster.grid.fractional_index(p.lat_deg, p.lon_deg);
        let (br, bc) = ((r / 5.0) as usize, (c / 5.0) as usize);
        if br < blocks && bc < blocks {
            counts[br * blocks + bc] += 1;
        }
    }
    (per_ha, counts)
}

#[test]
fn forest_density_follows_the_rule_with_clearings_and_dense_stands() {
    let rules = CultureRules::default();
    let (per_ha, blocks) = forest_counts(&rules, 5);
    let want = rules.forest.trees_per_ha;
    assert!(
        (per_ha - want).abs() <= 0.25 * want,
        "{per_ha:.1} trees/ha, rule {want}"
    );
    // Stands: clearings and dense woods, not a uniform carpet.
    let mean = blocks.iter().sum::<usize>() as f64 / blocks.len() as f64;
    let sparse = blocks.iter().filter(|&&n| (n as f64) < 0.25 * mean).count();
    let dense = blocks.iter().filter(|&&n| (n as f64) > 1.5 * mean).count();
    let share = |n: usize| n as f64 / blocks.len() as f64;
    assert!(share(sparse) > 0.05, "clearings {:.3}", share(sparse));
    assert!(share(dense) > 0.05, "dense stands {:.3}", share(dense));

    // Without contrast the density is even.
    let uniform = CultureRules {
        stand_contrast: 0.0,
        ..CultureRules::default()
    };
    let (per_ha, blocks) = forest_counts(&uniform, 5);
    assert!((per_ha - want).abs() <= 0.05 * want, "{per_ha:.1} trees/ha");
    let mean = blocks.iter().sum::<usize>() as f64 / blocks.len() as f64;
    let sparse = blocks.iter().filter(|&&n| (n as f64) < 0.25 * mean).count();
    assert_eq!(sparse, 0);

    // Another density is followed too.
    let thick = CultureRules {
        forest: VegetationRule {
            trees_per_ha: 150.0,
            bushes_per_ha: 0.0,
        },
        ..CultureRules::default()
    };
    let (per_ha, _) = forest_counts(&thick, 6);
    assert!(
        (per_ha - 150.0).abs() <= 0.25 * 150.0,
        "{per_ha:.1} trees/ha"
    );
}

#[test]
fn trees_are_spread_not_clumped() {
    // The jittered grid keeps trees at least a fifth of a sub-cell apart.
    let rules = CultureRules {
        stand_contrast: 0.0,
        ..CultureRules::default()
    };
    let raster = flat(40, 30.0, Material::Forest, 300.0);
    let placed = scatter_by_material(&raster, &rules, 2).expect("valid rules");
    let frame = Frame::new(&raster.grid);
    let pts: Vec<Xy> = placed
        .iter()
        .filter(|p| p.kind.is_tree())
        .map(|p| frame.xy((p.lat_deg, p.lon_deg)))
        .collect();
    let pitch = (HECTARE_M2 / (2.0 * rules.forest.trees_per_ha)).sqrt();
    let mut closest = f64::INFINITY;
    for (i, &a) in pts.iter().enumerate() {
        for &b in &pts[i + 1..] {
            closest = closest.min(length(sub(a, b)));
        }
    }
    assert!(closest > 0.1 * pitch, "closest pair {closest:.2} m");
}

#[test]
fn conifers_take_over_with_altitude_and_sizes_vary_in_their_ranges() {
    let rules = CultureRules::default();
    let share = |height_m: f32| {
        let raster = flat(60, 30.0, Material::Forest, height_m);
        let placed = scatter_by_material(&raster, &rules, 9).expect("valid rules");
        let trees: Vec<_> = placed.iter().filter(|p| p.kind.is_tree()).collect();
        let conifers = trees
            .iter()
            .filter(|p| p.kind == CultureKind::ConiferTree)
            .count();
        (conifers as f64 / trees.len() as f64, placed)
    };
    let (low, placed) = share(200.0);
    assert!((low - rules.conifer_fraction).abs() < 0.05, "low {low:.3}");
    let (mid, _) = share(1_250.0);
    assert!((mid - 0.65).abs() < 0.06, "mid {mid:.3}");
    let (high, _) = share(2_000.0);
    assert_eq!(high, 1.0);

    let mut heights = Vec::new();
    let mut variants = std::collections::BTreeSet::new();
    for p in &placed {
        let (h, w) = (f64::from(p.height_m), f64::from(p.width_m));
        let ok = match p.kind {
            CultureKind::ConiferTree => {
                (12.0..=28.0).contains(&h) && (0.259..=0.381).contains(&(w / h))
            }
            CultureKind::BroadleafTree => {
                (10.0..=22.0).contains(&h) && (0.549..=0.851).contains(&(w / h))
            }
            CultureKind::Bush => (0.8..=3.0).contains(&h) && (0.89..=1.71).contains(&(w / h)),
            _ => false,
        };
        assert!(ok, "{} {h:.1} m tall, {w:.1} m wide", p.kind);
        assert_eq!(p.width_m, p.length_m);
        if p.kind == CultureKind::BroadleafTree {
            heights.push(h);
        }
        variants.insert(p.variant);
    }
    heights.sort_by(f64::total_cmp);
    let spread = heights[heights.len() * 9 / 10] - heights[heights.len() / 10];
    assert!(
        spread > 4.0,
        "broadleaf heights 10-90 % spread {spread:.1} m"
    );
    assert!(variants.len() > 200, "{} variants", variants.len());
}

#[test]
fn grass_sand_and_clay_get_their_sparse_vegetation_and_bare_materials_none() {
    let rules = CultureRules::default();
    let count = |m: Material| {
        let raster = flat(100, 30.0, m, 100.0);
        let placed = scatter_by_material(&raster, &rules, 4).expect("valid rules");
        let ha = (99.0 * 30.0f64).powi(2) / HECTARE_M2;
        let trees = placed.iter().filter(|p| p.kind.is_tree()).count() as f64 / ha;
        let bushes = placed
            .iter()
            .filter(|p| p.kind == CultureKind::Bush)
            .count() as f64
            / ha;
        (trees, bushes)
    };
    let (trees, bushes) = count(Material::Grass);
    assert!((trees - rules.grass.trees_per_ha).abs() < 0.4 * rules.grass.trees_per_ha);
    assert!((bushes - rules.grass.bushes_per_ha).abs() < 0.4 * rules.grass.bushes_per_ha);
    let (trees, bushes) = count(Material::Sand);
    assert_eq!(trees, 0.0);
    assert!(bushes > 0.0 && bushes < 2.0, "{bushes} bushes/ha on sand");
    for m in [
        Material::Water,
        Material::Rock,
        Material::Snow,
        Material::PavedRoad,
        Material::DirtRoad,
    ] {
        assert_eq!(count(m), (0.0, 0.0), "{m}");
    }
    // Without materials, nothing.
    let mut bare = flat(20, 30.0, Material::Forest, 100.0);
    bare.material = None;
    assert!(scatter_by_material(&bare, &rules, 1)
        .expect("valid rules")
        .is_empty());
}

// ---------------------------------------------------------------- settlements

struct Town {
    raster: Raster,
    features: Vec<Feature>,
    centre_deg: (f64, f64),
    frame: Frame,
}

/// A 6 km square of grass at 30 m with a settlement in the middle: a straight paved road
/// east-west through it, a gently curving paved road north from it, a dirt track to the
/// south-west, and a river (with its water posts) crossing the east.
fn town() -> Town {
    let posts = 201;
    let spacing = 30.0;
    let mut raster = flat(posts, spacing, Material::Grass, 100.0);
    let frame = Frame::new(&raster.grid);
    let deg = |p: Xy| frame.deg(p);
    let centre = (3_000.0, 3_000.0);
    let east_west: Vec<(f64, f64)> = (0..=60)
        .map(|k| deg((50.0 + k as f64 * 98.0, 3_000.0)))
        .collect();
    // An arc of radius 2 km bending east as it goes north.
    let north: Vec<(f64, f64)> = (0..=40)
        .map(|k| {
            let a = k as f64 / 40.0 * 0.8;
            deg((
                centre.0 + 2_000.0 * (1.0 - libm::cos(a)),
                centre.1 + 2_000.0 * libm::sin(a),
            ))
        })
        .collect();
    let south_west: Vec<(f64, f64)> = (0..=20)
        .map(|k| {
            let t = k as f64 * 120.0;
            deg((centre.0 - 0.6 * t, centre.1 - 0.8 * t))
        })
        .collect();
    let river_x = 4_500.0;
    let river: Vec<(f64, f64)> = (0..=30)
        .map(|k| deg((river_x, 10.0 + k as f64 * 198.0)))
        .collect();
    let features = vec![
        Feature::Line {
            kind: LineKind::River,
            width_m: 20.0,
            points_deg: river,
        },
        Feature::Line {
            kind: LineKind::PavedRoad,
            width_m: 7.0,
            points_deg: east_west,
        },
        Feature::Line {
            kind: LineKind::PavedRoad,
            width_m: 7.0,
            points_deg: north,
        },
        Feature::Line {
            kind: LineKind::DirtRoad,
            width_m: 4.0,
            points_deg: south_west,
        },
    ];
    // The river's posts are water.
    let g = raster.grid;
    if let Some(m) = raster.material.as_mut() {
        for r in 0..g.rows {
            for c in 0..g.cols {
                if (c as f64 * spacing - river_x).abs() <= 20.0 {
                    m[r * g.cols + c] = Material::Water;
                }
            }
        }
    }
    Town {
        raster,
        features,
        centre_deg: deg(centre),
        frame,
    }
}

/// Road centre lines of the town in its frame: (points, half width, paved).
fn roads_of(t: &Town) -> Vec<(Vec<Xy>, f64, bool)> {
    t.features
        .iter()
        .filter_map(|f| match f {
            Feature::Line {
                kind: kind @ (LineKind::PavedRoad | LineKind::DirtRoad),
                width_m,
                points_deg,
            } => Some((
                points_deg.iter().map(|&p| t.frame.xy(p)).collect(),
                0.5 * width_m,
                *kind == LineKind::PavedRoad,
            )),
            _ => None,
        })
        .collect()
}

/// Distance from `p` to a polyline and the polyline's direction there.
fn nearest_on(points: &[Xy], p: Xy) -> (f64, Xy) {
    let mut best = (f64::INFINITY, (1.0, 0.0));
    for w in points.windows(2) {
        let d = point_segment_distance(p, w[0], w[1]);
        if d < best.0 {
            let dir = sub(w[1], w[0]);
            best = (d, scale(dir, 1.0 / length(dir)));
        }
    }
    best
}

fn footprint_of(frame: &Frame, p: &CulturePlacement) -> Footprint {
    let h = f64::from(p.heading_deg).to_radians();
    Footprint {
        centre: frame.xy((p.lat_deg, p.lon_deg)),
        axis: (libm::sin(h), libm::cos(h)),
        half_length_m: 0.5 * f64::from(p.length_m),
        half_width_m: 0.5 * f64::from(p.width_m),
    }
}

/// Points covering a footprint, 0.5 m apart (edges included).
fn samples(f: &Footprint) -> Vec<Xy> {
    let nl = (2.0 * f.half_length_m / 0.5).ceil() as usize;
    let nw = (2.0 * f.half_width_m / 0.5).ceil() as usize;
    let mut out = Vec::new();
    for i in 0..=nl {
        for j in 0..=nw {
            let a = -f.half_length_m + 2.0 * f.half_length_m * i as f64 / nl as f64;
            let b = -f.half_width_m + 2.0 * f.half_width_m * j as f64 / nw as f64;
            out.push(add(f.centre, add(scale(f.axis, a), scale(f.across(), b))));
        }
    }
    out
}

/// Angle between two directions as lines (0..90 degrees).
fn line_angle_deg(a: Xy, b: Xy) -> f64 {
    let cos = (dot(a, b) / (length(a) * length(b))).abs().min(1.0);
    libm::acos(cos).to_degrees()
}

#[test]
fn buildings_line_the_roads_without_overlapping_them_each_other_or_the_river() {
    let t = town();
    let rules = SettlementRules::default();
    let placed = settlement_culture(&t.raster, &[t.centre_deg], &t.features, &rules, 11)
        .expect("valid rules");
    let roads = roads_of(&t);
    let count = |k: CultureKind| placed.iter().filter(|p| p.kind == k).count();
    let buildings: Vec<&CulturePlacement> =
        placed.iter().filter(|p| p.kind.is_building()).collect();
    assert!(buildings.len() > 400, "{} buildings", buildings.len());
    assert!(count(CultureKind::House) > 200);
    assert!(count(CultureKind::Shed) > 50);
    assert!(count(CultureKind::LargeBuilding) > 5);
    assert!(count(CultureKind::Wall) > 10 && count(CultureKind::Fence) > 10);
    assert!(placed.iter().all(|p| !is_vegetation(p.kind)));

    let footprints: Vec<(CultureKind, Footprint)> = placed
        .iter()
        .filter(|p| p.kind != CultureKind::PowerPole)
        .map(|p| (p.kind, footprint_of(&t.frame, p)))
        .collect();
    // Nothing overlaps anything else.
    for (i, (ka, a)) in footprints.iter().enumerate() {
        for (kb, b) in &footprints[i + 1..] {
            if length(sub(a.centre, b.centre)) < a.radius_m() + b.radius_m() {
                assert!(!a.overlaps(b, 0.0), "{ka} overlaps {kb} at {:?}", a.centre);
            }
        }
    }
    // No footprint on a road or in the river.
    let river_x = 4_500.0;
    let mut aligned = 0;
    for (kind, f) in &footprints {
        let near_roads: Vec<_> = roads
            .iter()
            .filter(|(points, half, _)| nearest_on(points, f.centre).0 < f.radius_m() + half + 1.0)
            .collect();
        for p in samples(f) {
            for (points, half, _) in &near_roads {
                let (d, _) = nearest_on(points, p);
                assert!(d > *half, "{kind} on a road at {p:?}");
            }
            assert!((p.0 - river_x).abs() > 10.0, "{kind} in the river at {p:?}");
        }
        if !kind.is_building() {
            continue;
        }
        // Headed along its road, the nearest (or one about as near, at a junction).
        let mut near: Vec<(f64, Xy)> = roads
            .iter()
            .map(|(pts, _, _)| nearest_on(pts, f.centre))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let along = |k: usize| line_angle_deg(f.axis, near[k].1) <= 15.0;
        if along(0) {
            aligned += 1;
        } else {
            assert!(
                near[1].0 < near[0].0 + 6.0 && along(1),
                "{kind} at {:?} headed {:.1} degrees off its road",
                f.centre,
                line_angle_deg(f.axis, near[0].1)
            );
        }
        // Set back: no building further than the rows reach.
        let reach = 3.5 + 10.0 + f64::from(rules.max_rows) * rules.row_depth_m + 60.0;
        assert!(near[0].0 < reach, "{kind} {:.0} m from a road", near[0].0);
    }
    assert!(
        aligned * 10 >= buildings.len() * 9,
        "{aligned} of {} aligned",
        buildings.len()
    );

    // Denser at the centre than at the edge.
    let centre = t.frame.xy(t.centre_deg);
    let within = |lo: f64, hi: f64| {
        buildings
            .iter()
            .filter(|p| {
                let d = length(sub(t.frame.xy((p.lat_deg, p.lon_deg)), centre));
                d >= lo && d < hi
            })
            .count()
    };
    assert!(
        within(0.0, 400.0) > within(1_200.0, 1_600.0),
        "{} vs {}",
        within(0.0, 400.0),
        within(1_200.0, 1_600.0)
    );
}

#[test]
fn power_poles_stand_beside_the_paved_roads_every_fifty_metres() {
    let t = town();
    let rules = SettlementRules::default();
    let placed = settlement_culture(&t.raster, &[t.centre_deg], &t.features, &rules, 3)
        .expect("valid rules");
    let roads = roads_of(&t);
    let poles: Vec<&CulturePlacement> = placed
        .iter()
        .filter(|p| p.kind == CultureKind::PowerPole)
        .collect();
    let paved_m: f64 = roads
        .iter()
        .filter(|r| r.2)
        .map(|(pts, _, _)| pts.windows(2).map(|w| length(sub(w[1], w[0]))).sum::<f64>())
        .sum();
    let expected = paved_m / rules.pole_spacing_m;
    assert!(
        poles.len() as f64 > 0.85 * expected && poles.len() as f64 <= expected + 2.0,
        "{} poles along {paved_m:.0} m of paved road",
        poles.len()
    );
    for p in poles {
        let xy = t.frame.xy((p.lat_deg, p.lon_deg));
        let (d, dir) = roads
            .iter()
            .filter(|r| r.2)
            .map(|(pts, _, _)| nearest_on(pts, xy))
            .fold(
                (f64::INFINITY, (0.0, 0.0)),
                |a, b| if b.0 < a.0 { b } else { a },
            );
        assert!(
            d > 3.5 + 1.0 && d < 3.5 + 4.0,
            "pole {d:.2} m from the paved road"
        );
        // Not beside a dirt road instead.
        for (pts, half, paved) in &roads {
            if !paved {
                assert!(nearest_on(pts, xy).0 > half + 1.0);
            }
        }
        assert!((9.0..=11.0).contains(&f64::from(p.height_m)));
        let heading = f64::from(p.heading_deg).to_radians();
        assert!(line_angle_deg((libm::sin(heading), libm::cos(heading)), dir) < 15.0);
    }
    // No poles without the rule.
    let none = SettlementRules {
        pole_spacing_m: 0.0,
        ..rules
    };
    let placed =
        settlement_culture(&t.raster, &[t.centre_deg], &t.features, &none, 3).expect("valid rules");
    assert!(placed.iter().all(|p| p.kind != CultureKind::PowerPole));
}

#[test]
fn farmsteads_stand_along_roads_outside_settlements() {
    let t = town();
    let rules = SettlementRules::default();
    // No settlement: only farmsteads (and poles).
    let placed = settlement_culture(&t.raster, &[], &t.features, &rules, 5).expect("valid rules");
    let houses = placed
        .iter()
        .filter(|p| p.kind == CultureKind::House)
        .count();
    let sheds = placed
        .iter()
        .filter(|p| p.kind == CultureKind::Shed)
        .count();
    let road_m = 5_880.0 + 1_600.0 + 2_400.0;
    let expected = 2.0 * road_m / rules.farmstead_spacing_m;
    assert!(
        houses as f64 > 0.4 * expected && (houses as f64) < 2.0 * expected,
        "{houses} farmhouses, about {expected:.0} expected"
    );
    assert!(sheds >= houses, "{sheds} barns for {houses} farmhouses");
    assert!(placed.iter().all(|p| p.kind != CultureKind::LargeBuilding));
}

// ---------------------------------------------------------------- the synthetic database

#[test]
fn a_synthetic_area_gets_culture_that_bins_into_its_tiles() {
    let g = synthetic(10.0, 2);
    let rules = CultureRules::default();
    let placed = place_culture(&g.raster, &g.report, &g.features, &rules, 1).expect("valid rules");
    let (tiles, manifest) =
        cig_terrain::culture::bin_placements(&PyramidLayout::new(g.raster.grid, 64), &placed)
            .expect("placements inside the database with sane sizes");
    assert!(!tiles.is_empty());
    assert!(manifest.trees() > 10_000, "{} trees", manifest.trees());
    assert!(
        manifest.buildings() > 100,
        "{} buildings",
        manifest.buildings()
    );
    assert!(manifest.counts.get("power_pole").copied().unwrap_or(0) > 20);

    // No tree or bush inside a building.
    let frame = Frame::new(&g.raster.grid);
    let mut index: BTreeMap<(i64, i64), Vec<Footprint>> = BTreeMap::new();
    for p in placed.iter().filter(|p| p.kind.is_building()) {
        let f = footprint_of(&frame, p);
        let cell = (
            (f.centre.0 / 100.0).floor() as i64,
            (f.centre.1 / 100.0).floor() as i64,
        );
        index.entry(cell).or_default().push(f);
    }
    for p in placed.iter().filter(|p| is_vegetation(p.kind)) {
        let xy = frame.xy((p.lat_deg, p.lon_deg));
        let (ci, cj) = ((xy.0 / 100.0).floor() as i64, (xy.1 / 100.0).floor() as i64);
        for di in -1..=1 {
            for dj in -1..=1 {
                for f in index.get(&(ci + di, cj + dj)).into_iter().flatten() {
                    let (a, b) = f.local(xy);
                    let r = 0.5 * f64::from(p.width_m);
                    assert!(
                        a.abs() > f.half_length_m + r || b.abs() > f.half_width_m + r,
                        "{} in a building at {xy:?}",
                        p.kind
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------- geometry

#[test]
fn rectangles_measure_their_distance_to_segments_and_their_overlaps() {
    let f = Footprint {
        centre: (10.0, 10.0),
        axis: (1.0, 0.0),
        half_length_m: 4.0,
        half_width_m: 2.0,
    };
    // Parallel above, crossing, beyond a corner, ending inside.
    assert!((f.segment_distance_m((0.0, 15.0), (20.0, 15.0)) - 3.0).abs() < 1e-12);
    assert_eq!(f.segment_distance_m((10.0, 0.0), (10.0, 20.0)), 0.0);
    assert!((f.segment_distance_m((17.0, 16.0), (30.0, 16.0)) - 5.0).abs() < 1e-12);
    assert_eq!(f.segment_distance_m((10.0, 10.5), (30.0, 30.0)), 0.0);
    let turned = Footprint {
        axis: (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        ..f
    };
    // A corner of the turned rectangle reaches (10 + 3 sqrt(2) / ... ): check against sampling.
    let seg = ((0.0, 16.0), (20.0, 16.0));
    let sampled = samples(&turned)
        .into_iter()
        .map(|p| point_segment_distance(p, seg.0, seg.1))
        .fold(f64::INFINITY, f64::min);
    assert!((turned.segment_distance_m(seg.0, seg.1) - sampled).abs() < 0.3);

    let near = Footprint {
        centre: (10.0, 13.5),
        ..f
    };
    assert!(f.overlaps(&near, 0.0));
    let apart = Footprint {
        centre: (10.0, 14.5),
        half_width_m: 0.4,
        ..f
    };
    assert!(!f.overlaps(&apart, 0.0));
    assert!(f.overlaps(&apart, 3.0));
    let diagonal = Footprint {
        centre: (16.5, 14.5),
        axis: turned.axis,
        ..f
    };
    assert_eq!(
        f.overlaps(&diagonal, 0.0),
        samples(&diagonal).iter().any(|&p| {
            let (a, b) = f.local(p);
            a.abs() <= 4.0 && b.abs() <= 2.0
        })
    );
}

// ---------------------------------------------------------------- rules

#[test]
fn bad_rules_are_refused_with_their_names() {
    let err = |rules: CultureRules| rules.validate().expect_err("refused").to_string();
    let msg = err(CultureRules {
        forest: VegetationRule {
            trees_per_ha: -1.0,
            bushes_per_ha: 0.0,
        },
        ..CultureRules::default()
    });
    assert!(msg.contains("forest.trees_per_ha = -1"), "{msg}");
    let msg = err(CultureRules {
        dry_clay: VegetationRule {
            trees_per_ha: 0.0,
            bushes_per_ha: f64::NAN,
        },
        ..CultureRules::default()
    });
    assert!(msg.contains("dry_clay.bushes_per_ha = NaN"), "{msg}");
    let msg = err(CultureRules {
        conifer_fraction: 1.5,
        ..CultureRules::default()
    });
    assert!(
        msg.contains("conifer_fraction = 1.5") && msg.contains("0..1"),
        "{msg}"
    );
    let msg = err(CultureRules {
        stand_contrast: -0.1,
        ..CultureRules::default()
    });
    assert!(msg.contains("stand_contrast"), "{msg}");
    let msg = err(CultureRules {
        conifer_rise_from_m: 1_000.0,
        conifer_only_above_m: 500.0,
        ..CultureRules::default()
    });
    assert!(msg.contains("conifer_only_above_m = 500"), "{msg}");
    let msg = err(CultureRules {
        settlements: SettlementRules {
            shed_fraction: 2.0,
            ..SettlementRules::default()
        },
        ..CultureRules::default()
    });
    assert!(msg.contains("settlements.shed_fraction = 2"), "{msg}");
    let msg = err(CultureRules {
        settlements: SettlementRules {
            pole_spacing_m: 5.0,
            ..SettlementRules::default()
        },
        ..CultureRules::default()
    });
    assert!(msg.contains("settlements.pole_spacing_m = 5"), "{msg}");
    assert!(CultureRules::default().validate().is_ok());

    // Every entry point checks.
    let bad = CultureRules {
        grass: VegetationRule {
            trees_per_ha: f64::INFINITY,
            bushes_per_ha: 0.0,
        },
        ..CultureRules::default()
    };
    let raster = flat(10, 30.0, Material::Grass, 0.0);
    assert!(scatter_by_material(&raster, &bad, 1).is_err());
    let bad_settlements = SettlementRules {
        max_rows: 0,
        ..SettlementRules::default()
    };
    assert!(settlement_culture(&raster, &[], &[], &bad_settlements, 1).is_err());
}

#[test]
fn rules_read_from_toml_with_defaults_and_refuse_unknown_keys() {
    let rules: CultureRules = toml::from_str(
        "conifer_fraction = 0.6\n[forest]\ntrees_per_ha = 80\n[settlements]\npole_spacing_m = 60\n",
    )
    .expect("valid rules file");
    assert_eq!(rules.conifer_fraction, 0.6);
    assert_eq!(rules.forest.trees_per_ha, 80.0);
    assert_eq!(rules.forest.bushes_per_ha, 0.0);
    assert_eq!(rules.grass, CultureRules::default().grass);
    assert_eq!(rules.settlements.pole_spacing_m, 60.0);
    assert_eq!(
        rules.settlements.radius_m,
        SettlementRules::default().radius_m
    );
    assert!(rules.validate().is_ok());
    for bad in [
        "conifer_share = 0.5\n",
        "[forest]\ntrees_per_hectare = 3\n",
        "[settlements]\nradius = 3\n",
    ] {
        let err = toml::from_str::<CultureRules>(bad).expect_err("unknown key");
        assert!(err.to_string().contains("unknown field"), "{err}");
    }
}
