//! `cig query hat|los`.

use crate::cli::{HatArgs, LosArgs};
use crate::config::Config;
use anyhow::Context;
use cig_geo::Geodetic;
use cig_terrain::QuerySession;
use std::path::Path;

/// Opens a database with a paging cache and a query session.
pub fn session(db: &Path, config: &Config) -> anyhow::Result<QuerySession> {
    Ok(QuerySession::new(crate::dynterrain::open_cache(
        db,
        &config.paging,
    )?))
}

pub fn surface_json(s: &cig_terrain::SurfacePoint) -> serde_json::Value {
    serde_json::json!({
        "lat": s.lat_deg,
        "lon": s.lon_deg,
        "height_m": s.height_msl_m,
        "height_ellipsoid_m": s.height_ellipsoid_m(),
        "geoid_undulation_m": s.geoid_undulation_m,
        "normal": s.normal_enu,
        "material": s.material.name(),
        "level": s.level,
    })
}

/// A line of sight's answer; a hit on a culture object carries it as `culture` (its kind, its
/// tile and index there, its sizes, heading and base, the normal where it was met), and
/// `material` is then the terrain's under the object.
pub fn los_json(r: &cig_terrain::LosResult) -> serde_json::Value {
    serde_json::json!({
        "visible": r.visible,
        "hit": r.hit.map(|h| {
            let mut hit = serde_json::json!({
                "lat": h.point.lat_deg,
                "lon": h.point.lon_deg,
                "alt_m": h.point.alt_m,
                "range_m": h.range_m,
                "material": h.material.name(),
                "level": h.level,
            });
            if let Some(c) = &h.culture {
                hit["culture"] = culture_hit_json(c);
            }
            hit
        }),
    })
}

/// A culture object met by a query.
pub fn culture_hit_json(c: &cig_terrain::CultureHit) -> serde_json::Value {
    serde_json::json!({
        "kind": c.kind.name(),
        "tile": {"row": c.tile.row, "col": c.tile.col},
        "index": c.index,
        "height_m": c.item.height_m,
        "width_m": c.item.width_m,
        "length_m": c.item.length_m,
        "heading_deg": c.item.heading_deg(),
        "base_m": c.item.base_m,
        "normal": c.normal_enu,
    })
}

pub fn hat(args: &HatArgs, config: &Config) -> anyhow::Result<()> {
    let mut q = session(&args.db, config)?;
    let s = q
        .hot(args.lat, args.lon)
        .with_context(|| format!("no terrain answer from {}", args.db.display()))?;
    let mut json = surface_json(&s);
    if let Some(alt) = args.alt {
        anyhow::ensure!(alt.is_finite(), "--alt {alt} is not a number");
        json["alt_m"] = alt.into();
        json["hat_m"] = (alt - s.height_ellipsoid_m()).into();
    }
    if args.json {
        println!("{json}");
    } else {
        println!(
            "terrain at {:.7}, {:.7}: {:.2} m above sea level ({:.2} m above the ellipsoid), {}, normal [{:.4}, {:.4}, {:.4}]",
            s.lat_deg, s.lon_deg, s.height_msl_m, s.height_ellipsoid_m(), s.material,
            s.normal_enu[0], s.normal_enu[1], s.normal_enu[2]
        );
        if let Some(alt) = args.alt {
            println!(
                "height above terrain: {:.2} m",
                alt - s.height_ellipsoid_m()
            );
        }
        if s.level > 0 {
            println!(
                "(answered from level {}: the finest tile is unreadable)",
                s.level
            );
        }
    }
    Ok(())
}

pub fn los(args: &LosArgs, config: &Config) -> anyhow::Result<()> {
    let mut q = session(&args.db, config)?;
    let from = Geodetic::new(args.lat1, args.lon1, args.alt1);
    let to = Geodetic::new(args.lat2, args.lon2, args.alt2);
    let k = crate::sea::parse_refraction(&args.refraction)?;
    let refraction = cig_ig::sea::sightline_refraction_with_k(from, to, k);
    let r = q
        .los_refracted(from, to, cig_terrain::CultureTest::LineOfSight, refraction)
        .with_context(|| format!("no line-of-sight answer from {}", args.db.display()))?;
    if args.json {
        println!("{}", los_json(&r));
    } else {
        match r.hit {
            None => println!("visible"),
            Some(h) => {
                let by = h
                    .culture
                    .map_or(String::new(), |c| format!(" by a {}", c.kind));
                println!(
                    "blocked{by} at {:.7}, {:.7}, {:.2} m, {:.1} m from the start ({})",
                    h.point.lat_deg, h.point.lon_deg, h.point.alt_m, h.range_m, h.material
                )
            }
        }
    }
    Ok(())
}
