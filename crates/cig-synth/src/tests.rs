//! Tests of the whole generator: determinism, hydrology, roads, materials, scale.

use crate::flood::{Dims, NEIGHBOURS, NO_RECEIVER};
use crate::hydro::{DIRT, LAKE, PAVED, RIVER, RIVER_CENTRE, SEA, WATER};
use crate::{
    generate, synthesize, synthesize_with_report, Generated, SeaSide, SynthError, SynthOptions,
    SynthParams,
};
use cig_terrain::material::Material;
use std::collections::VecDeque;

fn params(size_km: f64, spacing_m: f64, seed: u64) -> SynthParams {
    SynthParams {
        size_km,
        spacing_m,
        seed,
        ..SynthParams::demo()
    }
}

fn run(p: &SynthParams) -> Generated {
    generate(p, &SynthOptions::default(), &mut |_, _| {}).expect("valid parameters")
}

fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01B3);
    }
    h
}

fn raster_hash(g: &Generated) -> u64 {
    let r = &g.raster;
    let mats = r.material.as_ref().expect("materials");
    fnv1a(
        r.elevation_m
            .iter()
            .flat_map(|v| v.to_bits().to_le_bytes())
            .chain(mats.iter().map(|m| m.to_byte())),
    )
}

/// Slope in degrees at every interior post.
fn slopes_deg(g: &Generated, spacing_m: f64) -> Vec<f64> {
    let r = &g.raster;
    let (rows, cols) = (r.grid.rows, r.grid.cols);
    let h = &r.elevation_m;
    let mut out = Vec::new();
    for y in 1..rows - 1 {
        for x in 1..cols - 1 {
            let gx = f64::from(h[y * cols + x + 1] - h[y * cols + x - 1]) / (2.0 * spacing_m);
            let gy = f64::from(h[(y + 1) * cols + x] - h[(y - 1) * cols + x]) / (2.0 * spacing_m);
            out.push((gx * gx + gy * gy).sqrt().atan().to_degrees());
        }
    }
    out
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

// ---------------------------------------------------------------- determinism

#[test]
fn same_parameters_give_identical_rasters() {
    let p = params(6.0, 30.0, 11);
    let a = run(&p);
    let b = run(&p);
    let bits =
        |g: &Generated| -> Vec<u32> { g.raster.elevation_m.iter().map(|v| v.to_bits()).collect() };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.raster.material, b.raster.material);
    assert_eq!(a.raster.grid, b.raster.grid);
    assert_eq!(a.report, b.report);
}

#[test]
fn thread_count_does_not_change_the_raster() {
    let p = params(6.0, 30.0, 5);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(|| run(&p));
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .expect("pool")
        .install(|| run(&p));
    assert_eq!(raster_hash(&one), raster_hash(&three));
}

#[test]
fn a_different_seed_gives_different_terrain() {
    let a = run(&params(6.0, 30.0, 1));
    let b = run(&params(6.0, 30.0, 2));
    let differing = a
        .raster
        .elevation_m
        .iter()
        .zip(&b.raster.elevation_m)
        .filter(|(x, y)| (**x - **y).abs() > 1.0)
        .count();
    assert!(
        differing > a.raster.elevation_m.len() * 3 / 4,
        "only {differing} posts differ"
    );
}

/// A pinned hash of a small case: any change of the output, on any machine, shows here.
/// If the generator is changed on purpose, update the value (and say so in the commit).
#[test]
fn golden_hash_of_a_small_case() {
    let g = run(&params(3.0, 60.0, 7));
    let hash = raster_hash(&g);
    assert_eq!(hash, GOLDEN_HASH, "golden hash changed: {hash:#018x}");
}

const GOLDEN_HASH: u64 = 0x1e69_371e_c96f_4e4e;

// ---------------------------------------------------------------- grid and parameters

#[test]
fn grid_follows_the_parameters() {
    let p = params(6.0, 30.0, 3);
    let g = run(&p);
    let grid = g.raster.grid;
    assert_eq!((grid.rows, grid.cols), (201, 201));
    assert_eq!(grid.south_lat_deg, p.origin_lat_deg);
    assert_eq!(grid.west_lon_deg, p.origin_lon_deg);
    let centre = grid.south_lat_deg + 100.0 * grid.dlat_deg;
    let (north, east) = cig_geo::metres_per_degree(centre);
    assert!((grid.dlat_deg * north - 30.0).abs() < 1e-3);
    assert!((grid.dlon_deg * east - 30.0).abs() < 1e-3);
    assert_eq!(g.raster.elevation_m.len(), grid.len());
    assert_eq!(g.raster.void_count(), 0);
    assert!(g.raster.elevation_m.iter().all(|v| v.is_finite()));
    assert_eq!(g.raster.material.as_ref().map(Vec::len), Some(grid.len()));
}

#[test]
fn private_metres_per_degree_matches_cig_geo() {
    for lat in [-80.0, -45.0, 0.0, 12.5, 35.98, 60.0, 80.0] {
        let (n0, e0) = crate::metres_per_degree(lat);
        let (n1, e1) = cig_geo::metres_per_degree(lat);
        assert!((n0 - n1).abs() < 1e-6 && (e0 - e1).abs() < 1e-6, "{lat}");
    }
}

#[test]
fn invalid_parameters_are_refused_with_a_message_naming_them() {
    let ok = params(6.0, 30.0, 1);
    let cases: Vec<(SynthParams, &str)> = vec![
        (
            SynthParams {
                origin_lat_deg: 81.0,
                ..ok.clone()
            },
            "origin_lat_deg",
        ),
        (
            SynthParams {
                origin_lat_deg: f64::NAN,
                ..ok.clone()
            },
            "origin_lat_deg",
        ),
        (
            SynthParams {
                origin_lon_deg: 200.0,
                ..ok.clone()
            },
            "origin_lon_deg",
        ),
        (
            SynthParams {
                origin_lon_deg: 179.99,
                ..ok.clone()
            },
            "origin_lon_deg",
        ),
        (
            SynthParams {
                size_km: 0.0,
                ..ok.clone()
            },
            "size_km",
        ),
        (
            SynthParams {
                size_km: -3.0,
                ..ok.clone()
            },
            "size_km",
        ),
        (
            SynthParams {
                size_km: 1000.5,
                ..ok.clone()
            },
            "size_km",
        ),
        (
            SynthParams {
                size_km: f64::INFINITY,
                ..ok.clone()
            },
            "size_km",
        ),
        (
            SynthParams {
                spacing_m: 0.5,
                ..ok.clone()
            },
            "spacing_m",
        ),
        (
            SynthParams {
                spacing_m: 20_000.0,
                ..ok.clone()
            },
            "spacing_m",
        ),
        (
            SynthParams {
                spacing_m: f64::NAN,
                ..ok.clone()
            },
            "spacing_m",
        ),
        (
            SynthParams {
                size_km: 0.001,
                spacing_m: 10.0,
                ..ok.clone()
            },
            "size_km",
        ),
    ];
    for (p, name) in cases {
        match synthesize(&p, &mut |_, _| {}) {
            Err(e @ SynthError::InvalidParameter { .. }) => {
                let msg = e.to_string();
                assert!(msg.starts_with(name), "{msg}");
                assert!(!msg.contains('\n'), "{msg}");
            }
            other => panic!("{name}: expected InvalidParameter, got {other:?}"),
        }
    }
    let big = SynthParams {
        size_km: 1000.0,
        spacing_m: 50.0,
        ..ok
    };
    match synthesize(&big, &mut |_, _| {}) {
        Err(e @ SynthError::TooManyPosts { .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("size_km = 1000") && msg.contains("spacing_m = 50"),
                "{msg}"
            );
        }
        other => panic!("expected TooManyPosts, got {other:?}"),
    }
}

#[test]
fn progress_reports_every_stage_within_zero_to_one() {
    let mut seen: Vec<(String, f32)> = Vec::new();
    synthesize(&params(3.0, 60.0, 1), &mut |stage, f| {
        seen.push((stage.to_string(), f))
    })
    .expect("valid");
    for stage in ["landform", "elevation", "hydrology", "roads", "materials"] {
        let fr: Vec<f32> = seen.iter().filter(|s| s.0 == stage).map(|s| s.1).collect();
        assert!(!fr.is_empty(), "no progress for {stage}");
        assert!(fr.iter().all(|f| (0.0..=1.0).contains(f)));
        assert_eq!(fr.last().copied(), Some(1.0), "{stage} does not finish");
        assert!(
            fr.windows(2).all(|w| w[0] <= w[1]),
            "{stage} goes backwards"
        );
    }
}

// ---------------------------------------------------------------- hydrology

/// 30 km at 90 m: big enough to hold lake basins and long rivers.
fn hydro_case() -> Generated {
    run(&params(30.0, 90.0, 4))
}

#[test]
fn lakes_are_flat_and_never_above_their_shores() {
    let g = hydro_case();
    assert!(!g.report.lakes.is_empty(), "the case should hold lakes");
    let grid = g.raster.grid;
    let dims = Dims {
        nx: grid.cols,
        ny: grid.rows,
    };
    let h = &g.raster.elevation_m;
    let mut seen = vec![false; dims.len()];
    let mut regions = 0;
    for start in 0..dims.len() {
        if seen[start] || g.flags[start] & LAKE == 0 {
            continue;
        }
        regions += 1;
        seen[start] = true;
        let level = h[start];
        let mut queue = VecDeque::from([start]);
        let mut posts = 0usize;
        while let Some(c) = queue.pop_front() {
            posts += 1;
            assert_eq!(h[c], level, "lake post {c} is not at its lake's level");
            for &(dx, dy) in &NEIGHBOURS {
                let Some(nb) = dims.offset(c, dx, dy) else {
                    continue;
                };
                if g.flags[nb] & LAKE != 0 {
                    if !seen[nb] {
                        seen[nb] = true;
                        queue.push_back(nb);
                    }
                } else if g.flags[nb] & WATER == 0 {
                    assert!(
                        h[nb] >= level - 1e-3,
                        "land post {nb} at {} below lake level {level}",
                        h[nb]
                    );
                }
            }
        }
        // No ponds of a few posts.
        let area_m2 = posts as f64 * 90.0 * 90.0;
        assert!(
            area_m2 >= crate::hydro::LAKE_MIN_AREA_M2 && posts >= 4,
            "{posts} posts"
        );
    }
    assert_eq!(regions, g.report.lakes.len());
    let material = g.raster.material.as_ref().expect("materials");
    for (i, f) in g.flags.iter().enumerate() {
        if f & WATER != 0 {
            assert_eq!(material[i], Material::Water);
        }
    }
}

#[test]
fn rivers_run_downhill_and_end_in_a_lake_the_sea_or_the_edge() {
    let g = hydro_case();
    let grid = g.raster.grid;
    let dims = Dims {
        nx: grid.cols,
        ny: grid.rows,
    };
    let h = &g.raster.elevation_m;
    let centres: Vec<usize> = (0..dims.len())
        .filter(|&i| g.flags[i] & RIVER_CENTRE != 0)
        .collect();
    assert!(centres.len() > 200, "only {} river posts", centres.len());
    let mut ends_at_edge = 0;
    for &c in &centres {
        assert!(g.flags[c] & RIVER != 0, "centre {c} is not water");
        let r = g.receiver[c];
        if r == NO_RECEIVER {
            assert!(dims.is_edge(c), "river post {c} has no outlet");
            ends_at_edge += 1;
            continue;
        }
        let r = r as usize;
        let f = g.flags[r];
        if f & RIVER_CENTRE != 0 {
            assert!(
                h[r] <= h[c],
                "river climbs from {c} ({}) to {r} ({})",
                h[c],
                h[r]
            );
        } else {
            assert!(
                f & (LAKE | SEA) != 0,
                "river post {c} drains to {r}, which is neither river, lake nor sea"
            );
        }
    }
    assert!(ends_at_edge > 0, "no river leaves the area");
}

#[test]
fn river_width_grows_with_catchment() {
    let mut last = 0.0;
    for a in [3.0, 10.0, 50.0, 200.0, 1000.0] {
        let w = crate::hydro::river_width_m(a);
        assert!(w > last, "{a} km^2: {w} m");
        last = w;
    }
}

// ---------------------------------------------------------------- roads

/// The demo's area and size at a coarse spacing, so that it runs in the dev profile.
fn demo_area(spacing_m: f64) -> Generated {
    run(&params(50.0, spacing_m, 1))
}

#[test]
fn roads_connect_the_settlements_with_bounded_grade_and_cross_slope() {
    let spacing = 30.0;
    let g = run(&params(20.0, spacing, 2));
    let rep = &g.report;
    assert!(
        rep.settlements_deg.len() >= 2,
        "{} settlements",
        rep.settlements_deg.len()
    );
    assert!(rep.paved_road_km > 1.0, "paved {} km", rep.paved_road_km);
    assert!(rep.dirt_road_km > 1.0, "dirt {} km", rep.dirt_road_km);
    let grid = g.raster.grid;
    let to_xy = |(lat, lon): (f64, f64)| {
        let (r, c) = grid.fractional_index(lat, lon);
        (c * spacing, r * spacing)
    };
    let dist = |a: (f64, f64), b: (f64, f64)| ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt();

    // Connectivity: every paved road starts on a settlement or an earlier paved road and ends at
    // a settlement; union-find over settlements.
    let towns: Vec<(f64, f64)> = rep.settlements_deg.iter().map(|&p| to_xy(p)).collect();
    let mut parent: Vec<usize> = (0..towns.len()).collect();
    fn find(p: &mut [usize], i: usize) -> usize {
        let mut i = i;
        while p[i] != i {
            i = p[i];
        }
        i
    }
    let mut road_town: Vec<usize> = Vec::new();
    let paved: Vec<Vec<(f64, f64)>> = rep
        .roads
        .iter()
        .filter(|r| r.kind == crate::RoadKind::Paved)
        .map(|r| r.points_deg.iter().map(|&p| to_xy(p)).collect())
        .collect();
    let tol = 150.0;
    for (k, road) in paved.iter().enumerate() {
        let (start, end) = (road[0], road[road.len() - 1]);
        let end_town = (0..towns.len())
            .find(|&t| dist(towns[t], end) < 1.0)
            .expect("a paved road ends at a settlement");
        let start_town = (0..towns.len())
            .find(|&t| dist(towns[t], start) < tol)
            .or_else(|| {
                (0..k).find_map(|j| {
                    paved[j]
                        .iter()
                        .any(|&p| dist(p, start) < tol)
                        .then_some(road_town[j])
                })
            })
            .expect("a paved road starts on the network");
        road_town.push(end_town);
        let (a, b) = (find(&mut parent, start_town), find(&mut parent, end_town));
        parent[a] = b;
    }
    let root = find(&mut parent, 0);
    for t in 0..towns.len() {
        assert_eq!(
            find(&mut parent, t),
            root,
            "settlement {t} is not connected"
        );
    }

    // Grade between adjacent road posts.
    let dims = Dims {
        nx: grid.cols,
        ny: grid.rows,
    };
    let h = &g.raster.elevation_m;
    let is_road = |i: usize| g.flags[i] & (PAVED | DIRT) != 0;
    let mut road_posts = 0;
    for c in 0..dims.len() {
        if !is_road(c) {
            continue;
        }
        road_posts += 1;
        for (k, &(dx, dy)) in NEIGHBOURS.iter().enumerate() {
            if let Some(nb) = dims.offset(c, dx, dy) {
                if is_road(nb) {
                    let d = if k < 4 {
                        spacing
                    } else {
                        spacing * 2f64.sqrt()
                    };
                    let grade = f64::from((h[nb] - h[c]).abs()) / d;
                    assert!(
                        grade <= crate::roads::DIRT_MAX_GRADE + 1e-3,
                        "grade {grade}"
                    );
                }
            }
        }
    }
    assert!(road_posts > 100);

    // Cross slope of paved roads: pairs of paved posts across the road (within about 17 degrees
    // of the normal) whose nearest centre-line point, over all paved roads, is on the same road
    // within a spacing of the section's centre (so the two legs of a hairpin do not count).
    let nearest = |x: f64, y: f64| -> (usize, f64, f64) {
        let mut best = (usize::MAX, 0.0, f64::INFINITY);
        for (ri, road) in paved.iter().enumerate() {
            let mut s0 = 0.0;
            for w in road.windows(2) {
                let (a, b) = (w[0], w[1]);
                let len = dist(a, b);
                let t = if len > 0.0 {
                    (((x - a.0) * (b.0 - a.0) + (y - a.1) * (b.1 - a.1)) / (len * len))
                        .clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d = dist((x, y), (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t));
                if d < best.2 {
                    best = (ri, s0 + t * len, d);
                }
                s0 += len;
            }
        }
        best
    };
    let mut cross = Vec::new();
    for (ri, road) in paved.iter().enumerate() {
        let mut s0 = 0.0;
        for w in road.windows(2) {
            let (a, b) = (w[0], w[1]);
            let len = dist(a, b);
            s0 += len;
            if len < 1.0 {
                continue;
            }
            let s_mid = s0 - 0.5 * len;
            let (tx, ty) = ((b.0 - a.0) / len, (b.1 - a.1) / len);
            let mid = (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1));
            let (mc, mr) = (
                (mid.0 / spacing).round() as i64,
                (mid.1 / spacing).round() as i64,
            );
            let mut near: Vec<(usize, f64, f64)> = Vec::new();
            for r in mr - 2..=mr + 2 {
                for c in mc - 2..=mc + 2 {
                    if r < 0 || c < 0 || r >= dims.ny as i64 || c >= dims.nx as i64 {
                        continue;
                    }
                    let (x, y) = (c as f64 * spacing, r as f64 * spacing);
                    let i = r as usize * dims.nx + c as usize;
                    if g.flags[i] & PAVED == 0 || dist((x, y), mid) > 1.2 * spacing {
                        continue;
                    }
                    let (nr, ns, _) = nearest(x, y);
                    if nr == ri && (ns - s_mid).abs() <= spacing {
                        near.push((i, x, y));
                    }
                }
            }
            for (k, &(p, px, py)) in near.iter().enumerate() {
                for &(q, qx, qy) in &near[k + 1..] {
                    let d = dist((px, py), (qx, qy));
                    let along = ((qx - px) * tx + (qy - py) * ty).abs();
                    if along <= 0.3 * d {
                        cross.push(f64::from((h[p] - h[q]).abs()) / d);
                    }
                }
            }
        }
    }
    assert!(cross.len() > 50, "only {} cross sections", cross.len());
    let p95 = percentile(&mut cross, 0.95);
    assert!(p95 <= 0.06, "95th percentile cross slope {p95}");
    let max = cross.iter().fold(0.0f64, |a, &b| a.max(b));
    assert!(
        max <= crate::roads::DIRT_MAX_GRADE + 1e-3,
        "cross slope {max}"
    );
}

// ---------------------------------------------------------------- materials and relief

#[test]
fn demo_area_has_plausible_materials_relief_and_slopes() {
    let spacing = 150.0;
    let g = demo_area(spacing);
    let rep = &g.report;
    for (m, f) in &rep.material_fractions {
        assert!(*f <= 0.8, "{m} covers {f}");
    }
    let frac = |m| rep.material_fraction(m);
    assert!(
        frac(Material::Water) > 0.001,
        "water {}",
        frac(Material::Water)
    );
    assert!(frac(Material::PavedRoad) + frac(Material::DirtRoad) > 0.001);
    assert!(frac(Material::Grass) > 0.15);
    assert!(frac(Material::Forest) > 0.05);
    assert!(frac(Material::Rock) > 0.001 && frac(Material::Rock) < 0.3);
    assert!(frac(Material::Snow) < 0.01, "snow {}", frac(Material::Snow));
    let total: f64 = rep.material_fractions.iter().map(|(_, f)| f).sum();
    assert!((total - 1.0).abs() < 1e-9);

    // Coast-range relief: roughly 100-1500 m.
    assert!(rep.elevation_min_m >= -50.0, "min {}", rep.elevation_min_m);
    assert!(rep.elevation_max_m <= 3000.0, "max {}", rep.elevation_max_m);
    assert!(
        rep.elevation_max_m - rep.elevation_min_m > 400.0,
        "relief {} .. {}",
        rep.elevation_min_m,
        rep.elevation_max_m
    );

    let mut slopes = slopes_deg(&g, spacing);
    let n = slopes.len() as f64;
    let steep = slopes.iter().filter(|&&s| s > 35.0).count() as f64 / n;
    let flat = slopes.iter().filter(|&&s| s < 2.0).count() as f64 / n;
    let median = percentile(&mut slopes, 0.5);
    assert!((3.0..=25.0).contains(&median), "median slope {median}");
    assert!(steep < 0.1, "{steep} steeper than 35 deg");
    assert!(flat < 0.4, "{flat} flatter than 2 deg");
}

#[test]
fn slopes_at_thirty_metres_are_mostly_below_35_degrees_with_some_faces() {
    let g = run(&params(12.0, 30.0, 9));
    let mut slopes = slopes_deg(&g, 30.0);
    let n = slopes.len() as f64;
    let steep = slopes.iter().filter(|&&s| s > 35.0).count() as f64 / n;
    let p99 = percentile(&mut slopes, 0.99);
    assert!(steep < 0.1, "{steep} steeper than 35 deg");
    assert!(p99 > 20.0, "99th percentile slope only {p99} deg");
}

// ---------------------------------------------------------------- scale

#[test]
fn the_landscape_does_not_depend_on_the_spacing() {
    let fine = run(&params(12.0, 30.0, 6));
    let coarse = run(&params(12.0, 60.0, 6));
    let other = run(&params(12.0, 60.0, 7));
    let cols_f = fine.raster.grid.cols;
    let cols_c = coarse.raster.grid.cols;
    assert_eq!(cols_f, 2 * cols_c - 1);
    let median_diff = |a: &Generated| {
        let mut d: Vec<f64> = Vec::new();
        for r in 0..cols_c {
            for c in 0..cols_c {
                let hf = fine.raster.elevation_m[2 * r * cols_f + 2 * c];
                let hc = a.raster.elevation_m[r * cols_c + c];
                d.push(f64::from((hf - hc).abs()));
            }
        }
        percentile(&mut d, 0.5)
    };
    let same = median_diff(&coarse);
    let different = median_diff(&other);
    assert!(same < 15.0, "median |30 m - 60 m| = {same} m");
    // The comparison can tell landscapes apart.
    assert!(
        different > 30.0,
        "different seeds differ by only {different} m"
    );
}

#[test]
fn public_api_returns_the_report() {
    let (raster, report) =
        synthesize_with_report(&params(3.0, 60.0, 1), &mut |_, _| {}).expect("valid");
    assert_eq!(report.rows, raster.grid.rows);
    assert!(report.to_string().contains("materials:"));
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

        /// Any valid small request gives a complete raster of the promised shape.
        #[test]
        fn any_valid_small_request_gives_a_complete_raster(
            lat in -80.0f64..80.0,
            lon in -180.0f64..170.0,
            size_km in 0.2f64..4.0,
            spacing_m in 20.0f64..250.0,
            seed in any::<u64>(),
        ) {
            let p = SynthParams { origin_lat_deg: lat, origin_lon_deg: lon, size_km, spacing_m, seed };
            let side = (size_km * 1000.0 / spacing_m).round() as usize + 1;
            let r = synthesize(&p, &mut |_, _| {}).expect("valid parameters");
            prop_assert_eq!((r.grid.rows, r.grid.cols), (side, side));
            prop_assert!(r.elevation_m.iter().all(|v| v.is_finite() && *v > -500.0 && *v < 9000.0));
            prop_assert_eq!(r.material.as_ref().map(Vec::len), Some(side * side));
        }
    }
}

// ---------------------------------------------------------------- features

fn inside_ring(ring: &[(f64, f64)], (lat, lon): (f64, f64)) -> bool {
    let n = ring.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a.0 <= lat) != (b.0 <= lat) && lon < a.1 + (lat - a.0) * (b.1 - a.1) / (b.0 - a.0) {
            inside = !inside;
        }
    }
    inside
}

#[test]
fn features_are_deterministic_and_valid() {
    let p = params(6.0, 30.0, 11);
    let a = run(&p);
    let b = run(&p);
    assert_eq!(a.features, b.features);
    assert!(!a.features.is_empty());
    cig_terrain::features::validate_features(&a.features).expect("valid features");
    let roads = a
        .features
        .iter()
        .filter(|f| {
            matches!(
                f,
                crate::Feature::Line {
                    kind: cig_terrain::features::LineKind::PavedRoad
                        | cig_terrain::features::LineKind::DirtRoad,
                    ..
                }
            )
        })
        .count();
    assert_eq!(roads, a.report.roads.len());
    let (_, _, public) = crate::synthesize_with_features(&p, &mut |_, _| {}).expect("valid");
    assert_eq!(public, a.features);
}

/// Every lake post lies inside its traced shore and every other post outside it; the lakes
/// carry the hydrology's level; rivers are there, as wide as their catchments make them.
#[test]
fn lake_shores_enclose_exactly_the_lake_posts_and_rivers_are_lines() {
    use cig_terrain::features::{Feature, LineKind};
    let g = hydro_case();
    let grid = g.raster.grid;
    type LakeRef<'a> = (&'a Vec<(f64, f64)>, &'a Vec<Vec<(f64, f64)>>, f64);
    let lakes: Vec<LakeRef> = g
        .features
        .iter()
        .filter_map(|f| match f {
            Feature::Lake {
                outer_deg,
                holes_deg,
                level_m,
            } => Some((outer_deg, holes_deg, level_m.expect("level"))),
            _ => None,
        })
        .collect();
    assert!(lakes.len() >= g.report.lakes.len() && !lakes.is_empty());
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let k = r * grid.cols + c;
            let p = grid.post_lat_lon_deg(r, c);
            let holder = lakes
                .iter()
                .find(|(o, h, _)| inside_ring(o, p) && !h.iter().any(|hole| inside_ring(hole, p)));
            if g.flags[k] & LAKE != 0 {
                let (_, _, level) = holder.unwrap_or_else(|| panic!("lake post {r},{c} outside"));
                assert_eq!(*level, f64::from(g.raster.elevation_m[k]));
            } else {
                assert!(holder.is_none(), "land post {r},{c} inside a lake");
            }
        }
    }
    let rivers: Vec<f64> = g
        .features
        .iter()
        .filter_map(|f| match f {
            Feature::Line {
                kind: LineKind::River,
                width_m,
                ..
            } => Some(*width_m),
            _ => None,
        })
        .collect();
    assert!(rivers.len() >= 3, "{} rivers", rivers.len());
    assert!(
        rivers.iter().all(|&w| (6.0..=150.0).contains(&w)),
        "{rivers:?}"
    );
    let layer = cig_terrain::features::FeatureLayer::new(&g.features).expect("valid features");
    assert!(!layer.is_empty());
}

// ---------------------------------------------------------------- the sea

fn coast_run(size_km: f64, spacing_m: f64, seed: u64, side: SeaSide) -> Generated {
    let options = SynthOptions::default().with_sea_side(Some(side));
    generate(&params(size_km, spacing_m, seed), &options, &mut |_, _| {}).expect("valid")
}

/// 3 km at 30 m with the sea to the west: the test case of the coast.
fn west_coast() -> Generated {
    coast_run(3.0, 30.0, 1, SeaSide::West)
}

/// Per row, the first column (from the west) that is not sea.
fn shore_columns(g: &Generated) -> Vec<usize> {
    let cols = g.raster.grid.cols;
    (0..g.raster.grid.rows)
        .map(|r| {
            (0..cols)
                .find(|&c| g.flags[r * cols + c] & SEA == 0)
                .unwrap_or(cols)
        })
        .collect()
}

#[test]
fn the_western_edge_is_sea_at_mean_sea_level_over_a_floor_deepening_outward() {
    let g = west_coast();
    let (rows, cols) = (g.raster.grid.rows, g.raster.grid.cols);
    let material = g.raster.material.as_ref().expect("materials");
    for r in 0..rows {
        let k = r * cols;
        assert!(g.flags[k] & SEA != 0, "edge post of row {r} is not sea");
        assert_eq!(material[k], Material::Water);
        // Stored as the water's surface, as lakes are: 0 m above mean sea level.
        assert_eq!(g.raster.elevation_m[k], 0.0);
        let depth = -g.ground[k];
        assert!((20.0..150.0).contains(&depth), "floor {depth} m deep");
    }
    // Every sea post is water at 0 m over ground below it; every other post is at or above 0 m.
    for (k, f) in g.flags.iter().enumerate() {
        if f & SEA != 0 {
            assert_eq!(material[k], Material::Water);
            assert_eq!(g.raster.elevation_m[k], 0.0);
            assert!(g.ground[k] < 0.0);
        } else {
            assert!(
                g.raster.elevation_m[k] >= 0.0,
                "land post {k} below the sea"
            );
        }
    }
    // The columns that are sea in every row: the floor's mean depth grows toward the edge.
    let open_sea = shore_columns(&g).into_iter().min().expect("rows");
    assert!(
        open_sea >= 10,
        "sea in every row only out to column {open_sea}"
    );
    let mean_depth = |c: usize| -> f64 {
        (0..rows)
            .map(|r| -f64::from(g.ground[r * cols + c]))
            .sum::<f64>()
            / rows as f64
    };
    let depths: Vec<f64> = (0..open_sea).map(mean_depth).collect();
    for c in 1..open_sea {
        assert!(
            depths[c - 1] > depths[c],
            "the floor does not deepen outward: {depths:?}"
        );
    }
}

#[test]
fn a_west_coast_leaves_the_east_land_and_a_third_of_the_area_sea() {
    let g = west_coast();
    let (rows, cols) = (g.raster.grid.rows, g.raster.grid.cols);
    let h = &g.raster.elevation_m;
    let mut east = 0usize;
    let mut east_land = 0usize;
    for r in 0..rows {
        for c in cols / 2..cols {
            let k = r * cols + c;
            east += 1;
            east_land += usize::from(g.flags[k] & SEA == 0 && h[k] > 0.0);
        }
    }
    assert!(
        east_land as f64 >= 0.97 * east as f64,
        "{east_land} of {east} eastern posts are land"
    );
    let sea = g.flags.iter().filter(|&&f| f & SEA != 0).count() as f64 / h.len() as f64;
    assert!((0.2..=0.45).contains(&sea), "sea covers {sea}");
    assert!((g.report.material_fraction(Material::Water) - sea).abs() < 0.05);
}

#[test]
fn the_coastline_is_not_a_straight_line() {
    let shore = shore_columns(&west_coast());
    let (lo, hi) = (
        shore.iter().min().copied().unwrap_or(0),
        shore.iter().max().copied().unwrap_or(0),
    );
    assert!(hi - lo > 5, "the shore spans columns {lo}..{hi} only");
    // Not a slanted line either: the shore turns back and forth along the coast.
    let turns = shore
        .windows(3)
        .filter(|w| (w[1] > w[0] && w[2] < w[1]) || (w[1] < w[0] && w[2] > w[1]))
        .count();
    assert!(turns >= 3, "{turns} turns: {shore:?}");
}

#[test]
fn each_side_puts_the_sea_on_that_side() {
    for side in SeaSide::ALL {
        let g = coast_run(3.0, 30.0, 4, side);
        let (rows, cols) = (g.raster.grid.rows, g.raster.grid.cols);
        let sea = |r: usize, c: usize| g.flags[r * cols + c] & SEA != 0;
        // (the side's edge, the opposite edge) as post lists.
        let edge = |west: bool, east: bool, south: bool| -> Vec<(usize, usize)> {
            if west || east {
                let c = if west { 0 } else { cols - 1 };
                (0..rows).map(|r| (r, c)).collect()
            } else {
                let r = if south { 0 } else { rows - 1 };
                (0..cols).map(|c| (r, c)).collect()
            }
        };
        let (near, far) = match side {
            SeaSide::West => (edge(true, false, false), edge(false, true, false)),
            SeaSide::East => (edge(false, true, false), edge(true, false, false)),
            SeaSide::South => (edge(false, false, true), edge(false, false, false)),
            SeaSide::North => (edge(false, false, false), edge(false, false, true)),
        };
        assert!(near.iter().all(|&(r, c)| sea(r, c)), "{side}: edge not sea");
        assert!(!far.iter().any(|&(r, c)| sea(r, c)), "{side}: sea opposite");
        // The sea's centroid lies toward the side.
        let (mut n, mut sr, mut sc) = (0.0, 0.0, 0.0);
        for r in 0..rows {
            for c in 0..cols {
                if sea(r, c) {
                    n += 1.0;
                    sr += r as f64;
                    sc += c as f64;
                }
            }
        }
        let (fr, fc) = (sr / n / (rows - 1) as f64, sc / n / (cols - 1) as f64);
        let toward = match side {
            SeaSide::West => 1.0 - fc,
            SeaSide::East => fc,
            SeaSide::South => 1.0 - fr,
            SeaSide::North => fr,
        };
        assert!(
            toward > 0.8,
            "{side}: the sea's centroid at {fr:.2}, {fc:.2}"
        );
    }
}

#[test]
fn the_coast_is_deterministic_and_follows_the_seed() {
    let a = west_coast();
    let b = west_coast();
    assert_eq!(raster_hash(&a), raster_hash(&b));
    assert_eq!(a.report, b.report);
    assert_eq!(a.features, b.features);
    let other = coast_run(3.0, 30.0, 2, SeaSide::West);
    assert_ne!(shore_columns(&a), shore_columns(&other));
    let inland = run(&params(3.0, 30.0, 1));
    assert_ne!(raster_hash(&a), raster_hash(&inland));
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(west_coast);
    assert_eq!(raster_hash(&one), raster_hash(&a));
}

#[test]
fn the_default_options_change_no_byte() {
    let p = params(3.0, 60.0, 7);
    let (raster, report, features) =
        crate::synthesize_with_options(&p, &SynthOptions::default(), &mut |_, _| {})
            .expect("valid");
    let g = run(&p);
    assert_eq!(raster_hash(&g), GOLDEN_HASH);
    assert_eq!(raster.elevation_m, g.raster.elevation_m);
    assert_eq!(raster.material, g.raster.material);
    assert_eq!((report, features), (g.report, g.features));
}

#[test]
fn no_culture_road_or_lake_lies_in_the_sea_and_rivers_reach_it() {
    let g = coast_run(6.0, 30.0, 2, SeaSide::South);
    let grid = g.raster.grid;
    let dims = Dims {
        nx: grid.cols,
        ny: grid.rows,
    };
    let sea = |k: usize| g.flags[k] & SEA != 0;
    let near_sea = |k: usize| {
        sea(k)
            || NEIGHBOURS
                .iter()
                .any(|&(dx, dy)| dims.offset(k, dx, dy).is_some_and(sea))
    };
    let post = |lat: f64, lon: f64| {
        let (r, c) = grid.fractional_index(lat, lon);
        let r = (r.round().max(0.0) as usize).min(grid.rows - 1);
        let c = (c.round().max(0.0) as usize).min(grid.cols - 1);
        r * grid.cols + c
    };
    for (k, f) in g.flags.iter().enumerate() {
        assert!(
            f & (LAKE | RIVER) == 0 || !sea(k),
            "lake or river post {k} in the sea"
        );
        if f & LAKE != 0 {
            assert!(!near_sea(k), "lake post {k} touches the sea");
        }
        if f & (PAVED | DIRT) != 0 {
            assert!(!near_sea(k), "road post {k} on the shore");
        }
    }
    assert!(!g.report.roads.is_empty(), "the case should hold roads");
    for road in &g.report.roads {
        for &(lat, lon) in &road.points_deg {
            assert!(!sea(post(lat, lon)), "road point {lat}, {lon} at sea");
        }
    }
    let culture = crate::culture::place_culture(
        &g.raster,
        &g.report,
        &g.features,
        &crate::culture::CultureRules::default(),
        2,
    )
    .expect("default rules");
    assert!(culture.len() > 1_000, "{} objects", culture.len());
    for p in &culture {
        let k = post(p.lat_deg, p.lon_deg);
        assert!(
            !near_sea(k),
            "{:?} at {}, {} by the sea",
            p.kind,
            p.lat_deg,
            p.lon_deg
        );
    }
    // Rivers end in the sea.
    let mouths = (0..dims.len())
        .filter(|&k| g.flags[k] & RIVER_CENTRE != 0)
        .filter(|&k| g.receiver[k] != NO_RECEIVER && sea(g.receiver[k] as usize))
        .count();
    assert!(mouths >= 1, "no river reaches the sea");
}
