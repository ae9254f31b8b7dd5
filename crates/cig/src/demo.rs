//! `cig demo`: builds the demo database when missing, then shows the terrain answers and paging
//! a trainer relies on. (The renderer will extend it to draw the database.)

use crate::cli::DemoArgs;
use crate::config::Config;
use cig_geo::Geodetic;
use cig_terrain::{QuerySession, TileCache};
use cig_terrain_io::store::open_database;
use std::sync::Arc;
use std::time::Instant;

/// The demo database: 50 km x 50 km at 30 m posts from near Fort Hunter Liggett, California.
pub fn demo_params() -> cig_synth::SynthParams {
    cig_synth::SynthParams {
        origin_lat_deg: 35.98,
        origin_lon_deg: -121.23,
        size_km: 50.0,
        spacing_m: 30.0,
        seed: 1,
    }
}

pub fn run(args: &DemoArgs, config: &Config) -> anyhow::Result<()> {
    if !args.db.exists() {
        println!(
            "building the demo database (50 km x 50 km, 30 m posts): {}",
            args.db.display()
        );
        let started = Instant::now();
        crate::db::synthesize_database(&demo_params(), &args.db, false, config)?;
        println!("built in {:.1} s", started.elapsed().as_secs_f64());
    }
    crate::db::info(&crate::cli::InfoArgs {
        db: args.db.clone(),
        json: false,
    })?;
    let db = Arc::new(open_database(&args.db)?);
    let g = db.layout().grid;
    let cache = Arc::new(TileCache::new(Arc::clone(&db), config.paging.clone())?);
    let mut q = QuerySession::new(Arc::clone(&cache));
    let (clat, clon) = (
        0.5 * (g.south_lat_deg + g.north_lat_deg()),
        0.5 * (g.west_lon_deg + g.east_lon_deg()),
    );
    println!();
    println!("height above terrain of a helicopter at 1500 m over five points:");
    for k in 0..5 {
        let f = 0.1 + 0.2 * k as f64;
        let lat = g.south_lat_deg + f * (g.north_lat_deg() - g.south_lat_deg);
        let lon = g.west_lon_deg + (1.0 - f) * (g.east_lon_deg() - g.west_lon_deg);
        let (hat, s) = q.hat(Geodetic::new(lat, lon, 1500.0))?;
        println!(
            "  {lat:.5}, {lon:.5}: ground {:7.1} m MSL, {:<10} HAT {:7.1} m",
            s.height_msl_m,
            s.material.name(),
            hat
        );
    }
    println!();
    // The tank sits on the highest point within 4 km of the centre: an overwatch position.
    let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(clat);
    let (mut olat, mut olon, mut best) = (clat, clon, f64::NEG_INFINITY);
    for i in -40..=40 {
        for j in -40..=40 {
            let lat = clat + f64::from(i) * 100.0 / north_m_per_deg;
            let lon = clon + f64::from(j) * 100.0 / east_m_per_deg;
            let h = q.height_msl_m(lat, lon)?;
            if h > best {
                (olat, olon, best) = (lat, lon, h);
            }
        }
    }
    // Climb post by post to the summit itself.
    loop {
        let mut next = (olat, olon, best);
        for (di, dj) in [
            (-1, -1),
            (-1, 0),
            (-1, 1),
            (0, -1),
            (0, 1),
            (1, -1),
            (1, 0),
            (1, 1),
        ] {
            let lat = olat + f64::from(di) * g.dlat_deg;
            let lon = olon + f64::from(dj) * g.dlon_deg;
            if let Ok(h) = q.height_msl_m(lat, lon) {
                if h > next.2 {
                    next = (lat, lon, h);
                }
            }
        }
        if next.2 <= best {
            break;
        }
        (olat, olon, best) = next;
    }
    println!("line of sight from a tank 2 m above a hilltop ({olat:.5}, {olon:.5}), 8 km in 8 directions:");
    let (clat, clon) = (olat, olon);
    let eye_ground = q.hot(clat, clon)?.height_ellipsoid_m();
    for k in 0..8 {
        let az = f64::from(k) * 45.0;
        let lat2 = clat + 8000.0 * az.to_radians().cos() / north_m_per_deg;
        let lon2 = clon + 8000.0 * az.to_radians().sin() / east_m_per_deg;
        let target_ground = q.hot(lat2, lon2)?.height_ellipsoid_m();
        let r = q.los(
            Geodetic::new(clat, clon, eye_ground + 2.0),
            Geodetic::new(lat2, lon2, target_ground + 2.0),
        )?;
        match r.hit {
            None => println!("  azimuth {az:5.1}: target visible"),
            Some(h) => println!(
                "  azimuth {az:5.1}: blocked {:6.0} m out, by {}",
                h.range_m, h.material
            ),
        }
    }
    println!();
    println!("paging while flying west to east at 300 m/s for 150 s (60 Hz updates):");
    let started = Instant::now();
    let mut max_bytes = 0;
    for frame in 0..9000u32 {
        let t_s = f64::from(frame) / 60.0;
        let lon = g.west_lon_deg
            + 0.05 * (g.east_lon_deg() - g.west_lon_deg)
            + 300.0 * t_s / east_m_per_deg;
        let stats = cache.update(&[Geodetic::new(clat, lon.min(g.east_lon_deg()), 1500.0)]);
        max_bytes = max_bytes.max(stats.resident_bytes);
    }
    cache.wait_idle();
    let s = cache.stats();
    println!(
        "  {} tiles loaded, {} evicted, {} area moves; at most {:.1} MiB resident (budget {:.0} MiB); {:.2} s for 9000 updates",
        s.loads_completed,
        s.evictions,
        s.active_area_moves,
        max_bytes as f64 / 1048576.0,
        config.paging.budget_bytes as f64 / 1048576.0,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
