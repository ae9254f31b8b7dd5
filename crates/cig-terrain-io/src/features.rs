//! Feature files: roads, rivers and lakes as GeoJSON (RFC 7946), for `--features FILE`, and
//! the culture of the same file ([`crate::culture`]).
//!
//! A FeatureCollection (or a single Feature) whose features carry
//!
//! * a geometry: LineString or MultiLineString for roads and rivers, Polygon or MultiPolygon
//!   for lakes (the first ring outer, the others holes); positions `[lon, lat]` in WGS84
//!   degrees (a third coordinate is ignored);
//! * properties: `type`, one of `paved_road` (or `road`), `dirt_road` (or `track`), `river`,
//!   `lake`; `width_m`, the width in metres, required for lines; `level_m`, the water level in
//!   metres MSL, optional for lakes.
//!
//! Each part of a Multi geometry becomes its own [`Feature`]. A feature whose `type` names a
//! culture kind (`conifer_tree`, `house`, `wall`, ...) is culture, read by [`crate::culture`]
//! into [`FeatureFile::culture`]; [`read_features`] checks it and leaves it out. Errors are one
//! line, the reason first (with the file's feature index, and its `id` for culture) and the
//! file last (broken JSON with its line and column); nothing in the file can panic.

use crate::culture::{culture_feature, CultureFeature, MAX_CULTURE_OBJECTS};
use cig_terrain::culture::CultureKind;
use cig_terrain::features::{Feature, FeatureError, FeatureKind};
use geojson::{GeoJson, JsonObject, JsonValue, Value};
use std::path::{Path, PathBuf};

/// Why a feature file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum FeatureFileError {
    #[error("cannot read the feature file: {source} ({})", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("not GeoJSON: {reason} ({})", path.display())]
    NotGeoJson { path: PathBuf, reason: String },
    #[error("{reason} ({})", path.display())]
    Invalid { path: PathBuf, reason: String },
}

/// What a feature file holds: roads, rivers and lakes, and culture.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FeatureFile {
    pub features: Vec<Feature>,
    pub culture: Vec<CultureFeature>,
}

/// Reads a GeoJSON feature file's roads, rivers and lakes (its culture is checked and left
/// out).
pub fn read_features(path: &Path) -> Result<Vec<Feature>, FeatureFileError> {
    read_feature_file(path).map(|f| f.features)
}

/// Reads a GeoJSON feature file: roads, rivers, lakes and culture.
pub fn read_feature_file(path: &Path) -> Result<FeatureFile, FeatureFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| FeatureFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_feature_file(&text).map_err(|e| match e {
        ParseError::NotGeoJson(reason) => FeatureFileError::NotGeoJson {
            path: path.to_path_buf(),
            reason,
        },
        ParseError::Invalid(reason) => FeatureFileError::Invalid {
            path: path.to_path_buf(),
            reason,
        },
    })
}

/// Why feature text is not usable (without the file name).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParseError {
    #[error("not GeoJSON: {0}")]
    NotGeoJson(String),
    #[error("{0}")]
    Invalid(String),
}

/// Parses GeoJSON text into roads, rivers and lakes (culture checked and left out).
pub fn parse_features(text: &str) -> Result<Vec<Feature>, ParseError> {
    parse_feature_file(text).map(|f| f.features)
}

/// Every `type` a feature may have, for messages.
fn known_types() -> String {
    let culture: Vec<&str> = CultureKind::ALL.iter().map(|k| k.name()).collect();
    format!(
        "paved_road, road, dirt_road, track, river, lake, {}",
        culture.join(", ")
    )
}

/// Parses GeoJSON text into roads, rivers, lakes and culture.
pub fn parse_feature_file(text: &str) -> Result<FeatureFile, ParseError> {
    // Parsed as JSON first: its errors name the line and column.
    let json: JsonValue =
        serde_json::from_str(text).map_err(|e| ParseError::NotGeoJson(one_line(&e.to_string())))?;
    let geojson = GeoJson::from_json_value(json)
        .map_err(|e: geojson::Error| ParseError::NotGeoJson(one_line(&e.to_string())))?;
    let features = match geojson {
        GeoJson::FeatureCollection(fc) => fc.features,
        GeoJson::Feature(f) => vec![f],
        GeoJson::Geometry(_) => {
            return Err(ParseError::Invalid(
                "a bare geometry has no type or width: expected a FeatureCollection".to_string(),
            ))
        }
    };
    let mut out = FeatureFile::default();
    let mut culture_budget = MAX_CULTURE_OBJECTS;
    for (index, f) in features.iter().enumerate() {
        let id = f.id.as_ref().map(|id| match id {
            geojson::feature::Id::String(s) => s.clone(),
            geojson::feature::Id::Number(n) => n.to_string(),
        });
        let label = crate::culture::feature_label(index, id.as_deref());
        let invalid = |reason: String| ParseError::Invalid(format!("{reason} (feature {index})"));
        let empty = JsonObject::new();
        let props = f.properties.as_ref().unwrap_or(&empty);
        let name = match props.get("type") {
            Some(JsonValue::String(s)) => s.clone(),
            Some(_) => {
                return Err(ParseError::Invalid(format!(
                    "property type is not a string ({label})"
                )))
            }
            None => {
                return Err(ParseError::Invalid(format!(
                    "property type is missing ({label})"
                )))
            }
        };
        let Some(kind) = FeatureKind::from_name(&name) else {
            let Some(culture) = CultureKind::from_name(&name.trim().to_ascii_lowercase()) else {
                return Err(ParseError::Invalid(format!(
                    "unknown type {name:?}, expected one of {} ({label})",
                    known_types()
                )));
            };
            let geometry = f.geometry.as_ref().ok_or_else(|| {
                ParseError::Invalid(format!("the feature has no geometry ({label})"))
            })?;
            out.culture.push(culture_feature(
                index,
                id,
                culture,
                props,
                &geometry.value,
                &mut culture_budget,
            )?);
            continue;
        };
        let number = |key: &str| -> Result<Option<f64>, ParseError> {
            match props.get(key) {
                None | Some(JsonValue::Null) => Ok(None),
                Some(JsonValue::Number(n)) => n
                    .as_f64()
                    .map(Some)
                    .ok_or_else(|| invalid(format!("property {key} is not a number"))),
                Some(_) => Err(invalid(format!("property {key} is not a number"))),
            }
        };
        let geometry = f
            .geometry
            .as_ref()
            .ok_or_else(|| invalid("the feature has no geometry".to_string()))?;
        let points = |pos: &[Vec<f64>]| -> Result<Vec<(f64, f64)>, ParseError> {
            pos.iter()
                .map(|p| match p.as_slice() {
                    [lon, lat, ..] => Ok((*lat, *lon)),
                    _ => Err(invalid(
                        "a position has fewer than two coordinates".to_string(),
                    )),
                })
                .collect()
        };
        let made: Vec<Feature> = match kind {
            FeatureKind::Line(line) => {
                let width_m = number("width_m")?.ok_or_else(|| {
                    ParseError::Invalid(FeatureError::MissingWidth { index }.to_string())
                })?;
                let parts: Vec<&Vec<Vec<f64>>> = match &geometry.value {
                    Value::LineString(l) => vec![l],
                    Value::MultiLineString(ls) => ls.iter().collect(),
                    other => {
                        return Err(invalid(format!(
                            "a {} needs a LineString or MultiLineString, not a {}",
                            kind.name(),
                            other.type_name()
                        )))
                    }
                };
                parts
                    .into_iter()
                    .map(|p| {
                        Ok(Feature::Line {
                            kind: line,
                            width_m,
                            points_deg: points(p)?,
                        })
                    })
                    .collect::<Result<_, ParseError>>()?
            }
            FeatureKind::Lake => {
                let level_m = number("level_m")?;
                let polys: Vec<&Vec<Vec<Vec<f64>>>> = match &geometry.value {
                    Value::Polygon(p) => vec![p],
                    Value::MultiPolygon(ps) => ps.iter().collect(),
                    other => {
                        return Err(invalid(format!(
                            "a lake needs a Polygon or MultiPolygon, not a {}",
                            other.type_name()
                        )))
                    }
                };
                polys
                    .into_iter()
                    .map(|rings| {
                        let Some((outer, holes)) = rings.split_first() else {
                            return Err(invalid("a polygon has no ring".to_string()));
                        };
                        Ok(Feature::Lake {
                            outer_deg: points(outer)?,
                            holes_deg: holes.iter().map(|h| points(h)).collect::<Result<_, _>>()?,
                            level_m,
                        })
                    })
                    .collect::<Result<_, ParseError>>()?
            }
        };
        if made.is_empty() {
            return Err(invalid("the geometry is empty".to_string()));
        }
        for m in &made {
            m.validate(index)
                .map_err(|e| ParseError::Invalid(e.to_string()))?;
        }
        out.features.extend(made);
    }
    Ok(out)
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The features as a GeoJSON FeatureCollection (what [`read_features`] reads back).
pub fn features_to_geojson(features: &[Feature]) -> String {
    let pos = |pts: &[(f64, f64)]| -> Vec<Vec<f64>> {
        pts.iter().map(|&(lat, lon)| vec![lon, lat]).collect()
    };
    let ring = |pts: &[(f64, f64)]| -> Vec<Vec<f64>> {
        let mut r = pos(pts);
        if let (Some(first), Some(last)) = (r.first().cloned(), r.last()) {
            if &first != last {
                r.push(first);
            }
        }
        r
    };
    let collection = geojson::FeatureCollection {
        bbox: None,
        foreign_members: None,
        features: features
            .iter()
            .map(|f| {
                let mut props = JsonObject::new();
                props.insert("type".into(), JsonValue::from(f.kind().name()));
                let value = match f {
                    Feature::Line {
                        width_m,
                        points_deg,
                        ..
                    } => {
                        props.insert("width_m".into(), JsonValue::from(*width_m));
                        Value::LineString(pos(points_deg))
                    }
                    Feature::Lake {
                        outer_deg,
                        holes_deg,
                        level_m,
                    } => {
                        if let Some(l) = level_m {
                            props.insert("level_m".into(), JsonValue::from(*l));
                        }
                        Value::Polygon(
                            std::iter::once(ring(outer_deg))
                                .chain(holes_deg.iter().map(|h| ring(h)))
                                .collect(),
                        )
                    }
                };
                geojson::Feature {
                    bbox: None,
                    geometry: Some(geojson::Geometry::new(value)),
                    id: None,
                    properties: Some(props),
                    foreign_members: None,
                }
            })
            .collect(),
    };
    GeoJson::FeatureCollection(collection).to_string()
}

/// Name of the feature file a database keeps beside its tiles: the roads, rivers and lakes
/// painted into its imagery, so new imagery (`cig db imagery`) is painted with them again.
pub const DATABASE_FEATURES_FILE: &str = "features.geojson";

/// Writes the features as a GeoJSON file.
pub fn write_features(path: &Path, features: &[Feature]) -> Result<(), FeatureFileError> {
    std::fs::write(path, features_to_geojson(features)).map_err(|source| FeatureFileError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_terrain::features::LineKind;

    fn sample() -> Vec<Feature> {
        vec![
            Feature::Line {
                kind: LineKind::PavedRoad,
                width_m: 7.5,
                points_deg: vec![(36.01, -121.2), (36.02, -121.19), (36.03, -121.195)],
            },
            Feature::Line {
                kind: LineKind::DirtRoad,
                width_m: 3.0,
                points_deg: vec![(36.0, -121.0), (36.001, -121.001)],
            },
            Feature::Line {
                kind: LineKind::River,
                width_m: 22.0,
                points_deg: vec![(36.1, -121.1), (36.2, -121.0)],
            },
            Feature::Lake {
                outer_deg: vec![
                    (36.0, -121.0),
                    (36.0, -120.9),
                    (36.1, -120.9),
                    (36.1, -121.0),
                ],
                holes_deg: vec![vec![(36.04, -120.96), (36.06, -120.96), (36.06, -120.94)]],
                level_m: Some(312.25),
            },
            Feature::Lake {
                outer_deg: vec![(36.3, -121.0), (36.3, -120.9), (36.4, -120.9)],
                holes_deg: vec![],
                level_m: None,
            },
        ]
    }

    /// Written features read back the same (lake rings come back closed, which the model
    /// accepts: compare after writing twice).
    #[test]
    fn round_trip() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("f.geojson");
        write_features(&path, &sample()).expect("written");
        let back = read_features(&path).expect("read back");
        assert_eq!(back.len(), 5);
        assert_eq!(back[..3], sample()[..3]);
        match (&back[3], &sample()[3]) {
            (
                Feature::Lake {
                    outer_deg,
                    holes_deg,
                    level_m,
                },
                Feature::Lake {
                    outer_deg: o,
                    level_m: l,
                    ..
                },
            ) => {
                assert_eq!(&outer_deg[..4], &o[..]);
                assert_eq!(outer_deg[4], o[0], "closed ring");
                assert_eq!(holes_deg.len(), 1);
                assert_eq!(level_m, l);
            }
            _ => panic!("a lake"),
        }
        write_features(&path, &back).expect("written again");
        assert_eq!(read_features(&path).expect("read"), back);
    }

    #[test]
    fn multi_geometries_and_aliases() {
        let text = r#"{"type":"FeatureCollection","features":[
            {"type":"Feature","properties":{"type":"road","width_m":6},
             "geometry":{"type":"MultiLineString","coordinates":[[[-121,36],[-121.01,36.01,5]],[[-121,36.1],[-121.01,36.11]]]}},
            {"type":"Feature","properties":{"type":"track","width_m":3.5},
             "geometry":{"type":"LineString","coordinates":[[-121,36],[-121.01,36.01]]}},
            {"type":"Feature","properties":{"type":"lake","level_m":null},
             "geometry":{"type":"MultiPolygon","coordinates":[[[[-121,36],[-121.01,36],[-121.01,36.01],[-121,36]]],[[[-122,36],[-122.01,36],[-122.01,36.01],[-122,36]]]]}}
        ]}"#;
        let f = parse_features(text).expect("valid");
        assert_eq!(f.len(), 5);
        assert_eq!(f[0].kind(), FeatureKind::Line(LineKind::PavedRoad));
        assert!(
            matches!(&f[0], Feature::Line { points_deg, .. } if points_deg[1] == (36.01, -121.01))
        );
        assert_eq!(f[2].kind(), FeatureKind::Line(LineKind::DirtRoad));
        assert!(matches!(&f[4], Feature::Lake { level_m: None, .. }));
    }

    #[test]
    fn bad_files_give_one_line_naming_the_file_and_the_reason() {
        let dir = tempfile::tempdir().expect("temp dir");
        let feature = |props: &str, geometry: &str| {
            format!(
                r#"{{"type":"FeatureCollection","features":[{{"type":"Feature","properties":{props},"geometry":{geometry}}}]}}"#
            )
        };
        let line = r#"{"type":"LineString","coordinates":[[-121,36],[-121.01,36.01]]}"#;
        let cases = [
            ("not json at all".to_string(), "not GeoJSON"),
            (r#"{"type":"Nonsense"}"#.to_string(), "not GeoJSON"),
            (
                feature(r#"{"type":"road"}"#, line),
                "width_m is missing (feature 0)",
            ),
            (
                feature(r#"{"type":"road","width_m":"wide"}"#, line),
                "width_m is not a number",
            ),
            (
                feature(r#"{"type":"road","width_m":-2}"#, line),
                "width -2 m",
            ),
            (
                feature(r#"{"type":"canal","width_m":5}"#, line),
                "unknown type \"canal\"",
            ),
            (feature(r#"{"width_m":5}"#, line), "type is missing"),
            (feature(r#"{"type":"lake"}"#, line), "needs a Polygon"),
            (
                feature(
                    r#"{"type":"river","width_m":5}"#,
                    r#"{"type":"Point","coordinates":[-121,36]}"#,
                ),
                "needs a LineString",
            ),
            (
                feature(
                    r#"{"type":"river","width_m":5}"#,
                    r#"{"type":"LineString","coordinates":[[-121,36]]}"#,
                ),
                "1 distinct points",
            ),
            (
                feature(
                    r#"{"type":"river","width_m":5}"#,
                    r#"{"type":"LineString","coordinates":[[-121,36],[-121]]}"#,
                ),
                "position",
            ),
            (
                feature(
                    r#"{"type":"river","width_m":5}"#,
                    r#"{"type":"LineString","coordinates":[[-121,36],[-121,99]]}"#,
                ),
                "not a finite latitude",
            ),
            (
                feature(r#"{"type":"river","width_m":5}"#, "null"),
                "no geometry",
            ),
            (
                feature(
                    r#"{"type":"lake"}"#,
                    r#"{"type":"Polygon","coordinates":[[[-121,36],[-121.1,36],[-121,36]]]}"#,
                ),
                "lake ring",
            ),
            (
                r#"{"type":"Point","coordinates":[1,2]}"#.to_string(),
                "bare geometry",
            ),
        ];
        for (k, (text, want)) in cases.iter().enumerate() {
            let path = dir.path().join(format!("bad{k}.geojson"));
            std::fs::write(&path, text).expect("written");
            let msg = read_features(&path).expect_err("refused").to_string();
            assert!(msg.contains(want), "{msg} (wanted {want})");
            assert!(msg.ends_with(&format!("({})", path.display())), "{msg}");
            assert!(!msg.contains('\n'), "{msg}");
        }
        let missing = dir.path().join("missing.geojson");
        let msg = read_features(&missing).expect_err("refused").to_string();
        assert!(
            msg.starts_with("cannot read") && msg.contains("missing.geojson"),
            "{msg}"
        );
    }
}
