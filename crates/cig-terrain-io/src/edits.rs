//! Terrain edit files: an exercise's edits kept beside a database (`DB/edits.jsonl`, or any
//! file `cig db edits --export` writes and `cig serve --edits` appends to), never in its tiles.
//!
//! Format: JSON Lines. The first line names the format, its version and the database the
//! edits belong to (its finest lattice: south-west post, spacing, posts); each further line is
//! one [`TerrainEdit`] as `cig_terrain::edits` serialises it, in the order they were applied,
//! or the heal of an earlier one (`{"healed":{"author":{"site":..,"application":..},
//! "sequence":..}}`: the edit is removed, as `cig serve --edits` records a host's heal).
//! Every line ends with a newline, so a file cut short (a last line without one) is told
//! from a whole one. Reading is all-or-nothing: a file that is truncated, malformed, from
//! another database, or holds an edit the database refuses is an error naming the line, and
//! nothing of it is applied. Writing a whole file goes to a sibling temporary file renamed
//! over the old one; appending writes one whole line at a time and flushes it.
//!
//! Limits: two databases with the same lattice are taken as the same database (the header
//! does not fingerprint the posts).

use cig_terrain::edits::{EditError, EditId, EditLayer, TerrainEdit};
use cig_terrain::GeoGrid;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The edits file inside a database directory.
pub const EDITS_FILE: &str = "edits.jsonl";
const FORMAT: &str = "cig-terrain-edits";
const VERSION: u32 = 1;
/// Largest edit file read, bytes.
const MAX_FILE_BYTES: u64 = 1 << 30;

/// Why an edit file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum EditsFileError {
    #[error("{reason}: {path}")]
    Io { reason: String, path: PathBuf },
    #[error("line {line}: {reason}: {path}")]
    Line {
        line: usize,
        reason: String,
        path: PathBuf,
    },
    #[error("the edits are for another database ({reason}): {path}")]
    OtherDatabase { reason: String, path: PathBuf },
    #[error("truncated (the last line has no end): {path}")]
    Truncated { path: PathBuf },
}

#[derive(Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
    database: Lattice,
}

/// A database's finest lattice, as the header records it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Lattice {
    south_lat_deg: f64,
    west_lon_deg: f64,
    dlat_deg: f64,
    dlon_deg: f64,
    rows: usize,
    cols: usize,
}

impl Lattice {
    fn of(g: &GeoGrid) -> Lattice {
        Lattice {
            south_lat_deg: g.south_lat_deg,
            west_lon_deg: g.west_lon_deg,
            dlat_deg: g.dlat_deg,
            dlon_deg: g.dlon_deg,
            rows: g.rows,
            cols: g.cols,
        }
    }

    /// Why `self` is not `other`, if it is not.
    fn mismatch(&self, other: &Lattice) -> Option<String> {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-6);
        if self.rows != other.rows || self.cols != other.cols {
            Some(format!(
                "{} x {} posts, the database has {} x {}",
                self.rows, self.cols, other.rows, other.cols
            ))
        } else if !(close(self.south_lat_deg, other.south_lat_deg)
            && close(self.west_lon_deg, other.west_lon_deg))
        {
            Some(format!(
                "south-west post {:.6}, {:.6}, the database's {:.6}, {:.6}",
                self.south_lat_deg, self.west_lon_deg, other.south_lat_deg, other.west_lon_deg
            ))
        } else if !(close(self.dlat_deg, other.dlat_deg) && close(self.dlon_deg, other.dlon_deg)) {
            Some("another post spacing".into())
        } else {
            None
        }
    }
}

fn io_err(path: &Path, e: std::io::Error) -> EditsFileError {
    EditsFileError::Io {
        reason: e.to_string(),
        path: path.to_path_buf(),
    }
}

fn header_line(grid: &GeoGrid) -> String {
    let header = Header {
        format: FORMAT.into(),
        version: VERSION,
        database: Lattice::of(grid),
    };
    // A struct of numbers and strings always serialises.
    serde_json::to_string(&header).unwrap_or_default()
}

/// A line healing an earlier edit.
#[derive(Serialize, Deserialize)]
struct HealLine {
    healed: EditId,
}

fn edit_line(edit: &TerrainEdit) -> Result<String, EditsFileError> {
    serde_json::to_string(edit).map_err(|e| EditsFileError::Io {
        reason: format!("cannot write an edit: {e}"),
        path: PathBuf::new(),
    })
}

/// Reads an edit file for the database whose finest lattice is `grid`, and checks each edit
/// against a layer of that database: the edits in order, or the first thing wrong.
pub fn read_edits(path: &Path, grid: &GeoGrid) -> Result<Vec<TerrainEdit>, EditsFileError> {
    let meta = std::fs::metadata(path).map_err(|e| io_err(path, e))?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(EditsFileError::Io {
            reason: format!("{} bytes, more than an edit file may hold", meta.len()),
            path: path.to_path_buf(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| io_err(path, e))?;
    let text = std::str::from_utf8(&bytes).map_err(|e| EditsFileError::Line {
        line: 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|b| **b == b'\n')
            .count(),
        reason: "not UTF-8 text".into(),
        path: path.to_path_buf(),
    })?;
    if !text.is_empty() && !text.ends_with('\n') {
        return Err(EditsFileError::Truncated {
            path: path.to_path_buf(),
        });
    }
    let line_err = |line: usize, reason: String| EditsFileError::Line {
        line,
        reason,
        path: path.to_path_buf(),
    };
    let mut lines = text.lines().enumerate();
    let Some((_, first)) = lines.next() else {
        return Err(line_err(1, "empty: no header".into()));
    };
    let header: Header = serde_json::from_str(first)
        .map_err(|e| line_err(1, format!("not an edit file header ({e})")))?;
    if header.format != FORMAT || header.version != VERSION {
        return Err(line_err(
            1,
            format!(
                "format {} version {}, not {FORMAT} version {VERSION}",
                header.format, header.version
            ),
        ));
    }
    if let Some(reason) = header.database.mismatch(&Lattice::of(grid)) {
        return Err(EditsFileError::OtherDatabase {
            reason,
            path: path.to_path_buf(),
        });
    }
    let mut layer = EditLayer::new(*grid, 1 << 12);
    let mut edits = Vec::new();
    for (k, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let value: serde_json::Value =
            serde_json::from_str(line).map_err(|e| line_err(k + 1, e.to_string()))?;
        if value.get("healed").is_some() {
            let heal: HealLine =
                serde_json::from_value(value).map_err(|e| line_err(k + 1, e.to_string()))?;
            layer
                .remove(heal.healed)
                .map_err(|e| line_err(k + 1, e.to_string()))?;
            edits.retain(|e: &TerrainEdit| e.id() != heal.healed);
            continue;
        }
        let edit: TerrainEdit =
            serde_json::from_value(value).map_err(|e| line_err(k + 1, e.to_string()))?;
        check(&mut layer, &edit).map_err(|e| line_err(k + 1, e.to_string()))?;
        edits.push(edit);
    }
    Ok(edits)
}

/// Checks an edit by applying it to a layer that collects them.
fn check(layer: &mut EditLayer, edit: &TerrainEdit) -> Result<(), EditError> {
    layer.apply(edit.clone()).map(|_| ())
}

/// Writes a whole edit file (to a sibling temporary file, renamed over `path`).
pub fn write_edits<'a>(
    path: &Path,
    grid: &GeoGrid,
    edits: impl IntoIterator<Item = &'a TerrainEdit>,
) -> Result<(), EditsFileError> {
    let mut text = header_line(grid);
    text.push('\n');
    for edit in edits {
        text.push_str(&edit_line(edit).map_err(|e| with_path(e, path))?);
        text.push('\n');
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "edits".into());
    let temp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&temp).map_err(|e| io_err(&temp, e))?;
        file.write_all(text.as_bytes())
            .and_then(|()| file.sync_all())
            .map_err(|e| io_err(&temp, e))?;
        std::fs::rename(&temp, path).map_err(|e| io_err(path, e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    result
}

fn with_path(e: EditsFileError, path: &Path) -> EditsFileError {
    match e {
        EditsFileError::Io { reason, .. } => EditsFileError::Io {
            reason,
            path: path.to_path_buf(),
        },
        other => other,
    }
}

/// An edit file open for appending (`cig serve --edits`): created with its header when it
/// does not exist, checked against the database when it does.
pub struct EditAppender {
    path: PathBuf,
    file: std::fs::File,
}

impl EditAppender {
    /// Opens `path` for the database of `grid`, returning the edits it already holds.
    pub fn open(
        path: &Path,
        grid: &GeoGrid,
    ) -> Result<(EditAppender, Vec<TerrainEdit>), EditsFileError> {
        let existing = if path.exists() {
            read_edits(path, grid)?
        } else {
            write_edits(path, grid, std::iter::empty())?;
            Vec::new()
        };
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| io_err(path, e))?;
        Ok((
            EditAppender {
                path: path.to_path_buf(),
                file,
            },
            existing,
        ))
    }

    /// Appends one edit as one whole line, flushed.
    pub fn append(&mut self, edit: &TerrainEdit) -> Result<(), EditsFileError> {
        let mut line = edit_line(edit).map_err(|e| with_path(e, &self.path))?;
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| io_err(&self.path, e))
    }

    /// Appends the heal of an earlier edit as one whole line, flushed.
    pub fn append_heal(&mut self, id: EditId) -> Result<(), EditsFileError> {
        let mut line =
            serde_json::to_string(&HealLine { healed: id }).map_err(|e| EditsFileError::Io {
                reason: format!("cannot write a heal: {e}"),
                path: self.path.clone(),
            })?;
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| io_err(&self.path, e))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The edits of a database directory (`DB/edits.jsonl`), none when it has no such file.
pub fn read_database_edits(db: &Path, grid: &GeoGrid) -> Result<Vec<TerrainEdit>, EditsFileError> {
    let path = db.join(EDITS_FILE);
    if !path.exists() {
        return Ok(Vec::new());
    }
    read_edits(&path, grid)
}

/// A layer of the database's lattice holding `edits` (already checked by [`read_edits`]).
pub fn layer_of(
    grid: &GeoGrid,
    tile_cells: u32,
    edits: Vec<TerrainEdit>,
) -> Result<EditLayer, EditError> {
    let mut layer = EditLayer::new(*grid, tile_cells);
    for edit in edits {
        layer.apply(edit)?;
    }
    Ok(layer)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint};

    fn grid() -> GeoGrid {
        GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 1.0 / 3600.0,
            dlon_deg: 1.0 / 3600.0,
            rows: 301,
            cols: 301,
        }
    }

    fn crater(sequence: u32, radius_m: f64) -> TerrainEdit {
        TerrainEdit {
            author: EditAuthor {
                site: 1,
                application: 1,
            },
            sequence,
            time_utc_s: 1.9e9 + f64::from(sequence),
            shape: EditShape::Crater {
                centre: GeoPoint {
                    lat_deg: 36.04,
                    lon_deg: -120.96,
                },
                radius_m,
                depth_m: 0.5 * radius_m,
                lip_radius_m: 1.25 * radius_m,
                lip_height_m: 0.125 * radius_m,
            },
        }
    }

    #[test]
    fn a_file_round_trips_and_refuses_truncation_other_databases_and_bad_edits() {
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("e.jsonl");
        let edits = vec![crater(1, 1.5), crater(2, 3.0)];
        write_edits(&path, &grid(), &edits).expect("write");
        assert_eq!(read_edits(&path, &grid()).expect("read"), edits);
        // Appending keeps what was there.
        let (mut appender, existing) = EditAppender::open(&path, &grid()).expect("open");
        assert_eq!(existing, edits);
        appender.append(&crater(3, 2.0)).expect("append");
        assert_eq!(read_edits(&path, &grid()).expect("read").len(), 3);
        // A heal removes its edit; a heal of an edit not held names its line.
        appender.append_heal(crater(2, 3.0).id()).expect("heal");
        let healed = read_edits(&path, &grid()).expect("read");
        assert_eq!(healed, vec![crater(1, 1.5), crater(3, 2.0)]);
        let healed_text = std::fs::read_to_string(&path).expect("text");
        appender.append_heal(crater(9, 3.0).id()).expect("heal");
        let err = read_edits(&path, &grid()).expect_err("unknown heal");
        assert!(err.to_string().starts_with("line 6:"), "{err}");
        std::fs::write(
            &path,
            healed_text.replace("\"sequence\":2}}", "\"sequence\":\"x\"}}"),
        )
        .expect("bad heal");
        assert!(read_edits(&path, &grid()).is_err());
        std::fs::write(
            &path,
            healed_text.lines().take(4).collect::<Vec<_>>().join("\n") + "\n",
        )
        .expect("restore");
        // Cut anywhere inside the last line: truncated.
        let text = std::fs::read_to_string(&path).expect("text");
        for cut in [text.len() - 1, text.len() - 20] {
            std::fs::write(&path, &text[..cut]).expect("cut");
            let err = read_edits(&path, &grid()).expect_err("truncated");
            assert!(!err.to_string().contains('\n'), "{err}");
        }
        // Another database.
        std::fs::write(&path, &text).expect("restore");
        let mut other = grid();
        other.rows = 302;
        assert!(matches!(
            read_edits(&path, &other),
            Err(EditsFileError::OtherDatabase { .. })
        ));
        // An edit the database refuses, or garbage, names its line.
        let bad = text.replace("\"radius_m\":3.0", "\"radius_m\":-3.0");
        std::fs::write(&path, bad).expect("bad");
        let err = read_edits(&path, &grid()).expect_err("refused");
        assert!(err.to_string().starts_with("line 3:"), "{err}");
        std::fs::write(&path, "{\"format\":\"x\"}\n").expect("garbage");
        assert!(read_edits(&path, &grid()).is_err());
        std::fs::write(&path, [0xff, 0xfe, b'\n']).expect("binary");
        assert!(read_edits(&path, &grid()).is_err());
    }
}
