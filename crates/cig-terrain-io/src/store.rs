//! The terrain database on disk: a directory holding `manifest.json` and one memory-image file
//! per tile, `tiles/L<level>/<row>_<col>.tile` (format in `cig_terrain::tile`).
//!
//! Writing is all-or-nothing: a database is built in a hidden sibling directory and renamed
//! into place only when every tile and the manifest are written, so an interrupted or failed
//! build leaves what was on disk untouched. An existing database is replaced only when the
//! caller asks, and then by rename, never by writing over its files.

use cig_terrain::build::{build_pyramid, BuildError, BuildSummary};
use cig_terrain::database::{
    GeoidGrid, Manifest, ManifestError, StoreError, TerrainDatabase, TileStore, DB_FORMAT_NAME,
};
use cig_terrain::raster::Raster;
use cig_terrain::tile::Tile;
use cig_terrain::{ImageryKey, TileKey};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Name of the manifest file in a database directory.
pub const MANIFEST_FILE: &str = "manifest.json";

/// Why a database could not be written or opened.
#[derive(Debug, thiserror::Error)]
pub enum DbError {
    #[error("{reason}: {path}")]
    Io { reason: String, path: PathBuf },
    #[error("output already exists (pass --force to replace it): {0}")]
    Exists(PathBuf),
    #[error("not a cig terrain database (no {MANIFEST_FILE}): {0}")]
    NotADatabase(PathBuf),
    #[error("refusing to replace something that is not a cig terrain database: {0}")]
    NotReplaceable(PathBuf),
    #[error("bad manifest: {reason}: {path}")]
    Manifest { reason: String, path: PathBuf },
    #[error(transparent)]
    Build(#[from] BuildError),
    #[error("culture: {0}")]
    Culture(#[from] cig_terrain::culture::CultureError),
}

fn io_err(path: &Path, e: std::io::Error) -> DbError {
    DbError::Io {
        reason: e.to_string(),
        path: path.to_path_buf(),
    }
}

/// Tiles read from a database directory.
pub struct FsTileStore {
    root: PathBuf,
}

impl FsTileStore {
    pub fn new(root: impl Into<PathBuf>) -> FsTileStore {
        FsTileStore { root: root.into() }
    }

    /// Path of a tile's file.
    pub fn tile_path(&self, key: TileKey) -> PathBuf {
        tile_path(&self.root, key)
    }
}

/// Path of a tile's file under a database root.
pub fn tile_path(root: &Path, key: TileKey) -> PathBuf {
    root.join("tiles")
        .join(format!("L{}", key.level))
        .join(format!("{}_{}.tile", key.row, key.col))
}

impl TileStore for FsTileStore {
    fn read_tile(&self, key: TileKey) -> Result<Vec<u8>, StoreError> {
        read_store_file(&self.tile_path(key))
    }

    fn location(&self, key: TileKey) -> String {
        self.tile_path(key).display().to_string()
    }

    fn read_imagery_tile(&self, key: ImageryKey) -> Result<Vec<u8>, StoreError> {
        read_store_file(&imagery_tile_path(&self.root, key))
    }

    fn imagery_location(&self, key: ImageryKey) -> String {
        imagery_tile_path(&self.root, key).display().to_string()
    }

    fn read_culture_tile(&self, key: TileKey) -> Result<Vec<u8>, StoreError> {
        read_store_file(&culture_tile_path(&self.root, key))
    }

    fn culture_location(&self, key: TileKey) -> String {
        culture_tile_path(&self.root, key).display().to_string()
    }
}

/// Path of a finest tile's culture file under a database root (`culture/<row>_<col>.cul`).
pub fn culture_tile_path(root: &Path, key: TileKey) -> PathBuf {
    root.join("culture")
        .join(format!("{}_{}.cul", key.row, key.col))
}

/// Bins `placements` into the finest tiles of `layout` and writes their culture files under
/// `dir` (a database's staging directory), replacing any culture there. Returns the manifest's
/// culture section (`None` without placements). A bad placement is an error and nothing of
/// the culture is left in `dir`.
pub fn write_culture(
    dir: &Path,
    layout: &cig_terrain::PyramidLayout,
    placements: &[cig_terrain::CulturePlacement],
) -> Result<Option<cig_terrain::CultureManifest>, DbError> {
    let culture_dir = dir.join("culture");
    if culture_dir.exists() {
        std::fs::remove_dir_all(&culture_dir).map_err(|e| io_err(&culture_dir, e))?;
    }
    if placements.is_empty() {
        return Ok(None);
    }
    let (tiles, manifest) = cig_terrain::culture::bin_placements(layout, placements)?;
    std::fs::create_dir_all(&culture_dir).map_err(|e| io_err(&culture_dir, e))?;
    for tile in &tiles {
        let path = culture_tile_path(dir, tile.key);
        std::fs::write(&path, tile.encode()).map_err(|e| io_err(&path, e))?;
    }
    Ok(Some(manifest))
}

/// Replaces the culture of the database at `db` with `placements` (none removes it): the new
/// database is assembled in a staging sibling directory (every other file hard-linked, or
/// copied where links are refused), its culture and manifest written there, and renamed over
/// `db` only when complete. On any error (a placement outside the database among them) `db` is
/// unchanged. Returns the new manifest.
pub fn replace_culture(
    db: &Path,
    placements: &[cig_terrain::CulturePlacement],
) -> Result<Manifest, DbError> {
    change_in_staging::<DbError>(db, "culture", &mut |staging, manifest| {
        manifest.culture = write_culture(staging, &manifest.layout, placements)?;
        Ok(())
    })
}

/// Changes the database at `db` all-or-nothing: a staging sibling mirrors it (files
/// hard-linked, or copied where links are refused) but for its manifest and the top-level
/// entry `part`; `change(staging, manifest)` writes the new `part` there and updates the
/// manifest, which is then written, and the staging directory is renamed over `db`. On any
/// error the staging directory is removed and `db` is unchanged. Returns the new manifest.
pub(crate) fn change_in_staging<E: From<DbError>>(
    db: &Path,
    part: &str,
    change: &mut dyn FnMut(&Path, &mut Manifest) -> Result<(), E>,
) -> Result<Manifest, E> {
    let database = open_database(db)?;
    let mut manifest = database.manifest().clone();
    drop(database);
    let staging = staging_sibling(db, part)?;
    let result = (|| -> Result<(), E> {
        link_tree(db, &staging, &[part, MANIFEST_FILE])?;
        change(&staging, &mut manifest)?;
        write_manifest(&staging, &manifest)?;
        Ok(())
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(e);
    }
    swap_into_place(&staging, db)?;
    Ok(manifest)
}

/// A fresh hidden sibling directory's path for staging a change of `db`
/// (`.<name>.<what>-<pid>`), anything left there by an earlier process removed.
pub(crate) fn staging_sibling(db: &Path, what: &str) -> Result<PathBuf, DbError> {
    let parent = match db.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = db
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| DbError::Io {
            reason: "database path has no directory name".into(),
            path: db.to_path_buf(),
        })?;
    let staging = parent.join(format!(".{name}.{what}-{}", std::process::id()));
    if staging.exists() {
        std::fs::remove_dir_all(&staging).map_err(|e| io_err(&staging, e))?;
    }
    Ok(staging)
}

/// Mirrors `from` into a new directory `to`, files hard-linked (copied where linking fails);
/// the entries of `from` named in `skip` (at the top level only) are left out.
pub(crate) fn link_tree(from: &Path, to: &Path, skip: &[&str]) -> Result<(), DbError> {
    std::fs::create_dir(to).map_err(|e| io_err(to, e))?;
    for entry in std::fs::read_dir(from).map_err(|e| io_err(from, e))? {
        let entry = entry.map_err(|e| io_err(from, e))?;
        let name = entry.file_name();
        if skip.iter().any(|s| name == *s) {
            continue;
        }
        let (src, dst) = (entry.path(), to.join(&name));
        let kind = entry.file_type().map_err(|e| io_err(&src, e))?;
        if kind.is_dir() {
            link_tree(&src, &dst, &[])?;
        } else if std::fs::hard_link(&src, &dst).is_err() {
            std::fs::copy(&src, &dst).map_err(|e| io_err(&src, e))?;
        }
    }
    Ok(())
}

/// A tile file's bytes; `Missing` when there is no such file.
fn read_store_file(path: &Path) -> Result<Vec<u8>, StoreError> {
    std::fs::read(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            StoreError::Missing(path.display().to_string())
        } else {
            StoreError::Io {
                reason: e.to_string(),
                location: path.display().to_string(),
            }
        }
    })
}

/// Path of an imagery tile's file under a database root (`imagery/L<level>/<row>_<col>.img`).
pub fn imagery_tile_path(root: &Path, key: ImageryKey) -> PathBuf {
    root.join("imagery")
        .join(format!("L{}", key.level))
        .join(format!("{}_{}.img", key.row, key.col))
}

/// Opens a database directory: reads and validates its manifest.
pub fn open_database(dir: &Path) -> Result<TerrainDatabase, DbError> {
    let manifest_path = dir.join(MANIFEST_FILE);
    let text = match std::fs::read_to_string(&manifest_path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(if dir.is_dir() {
                DbError::NotADatabase(dir.to_path_buf())
            } else {
                DbError::Io {
                    reason: "no such database directory".into(),
                    path: dir.to_path_buf(),
                }
            })
        }
        Err(e) => return Err(io_err(&manifest_path, e)),
    };
    let manifest: Manifest = serde_json::from_str(&text).map_err(|e| DbError::Manifest {
        reason: e.to_string(),
        path: manifest_path.clone(),
    })?;
    TerrainDatabase::new(manifest, Arc::new(FsTileStore::new(dir))).map_err(|e: ManifestError| {
        DbError::Manifest {
            reason: e.to_string(),
            path: manifest_path,
        }
    })
}

/// Where the posts of a database came from, and how much was filled.
#[derive(Clone, Debug, Default)]
pub struct BuildInputs {
    pub sources: Vec<String>,
    pub void_posts_filled: u64,
    pub tile_cells: u32,
}

/// Builds `raster` (voids filled, materials set) into a database at `out`. Replaces an
/// existing `out` only when `replace` is set. `progress(tiles_written, tiles_total)`.
pub fn write_database(
    out: &Path,
    raster: &Raster,
    inputs: &BuildInputs,
    replace: bool,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Manifest, DbError> {
    write_database_with::<DbError>(out, raster, inputs, replace, progress, &mut |_, _| Ok(()))
}

/// [`write_database`], with `finish(staging, manifest)` called once the tiles are written and
/// before the database is moved into place: it may add files to the staging directory and
/// change the manifest (written again after it). An error from it leaves `out` untouched.
pub fn write_database_with<E: From<DbError>>(
    out: &Path,
    raster: &Raster,
    inputs: &BuildInputs,
    replace: bool,
    progress: &mut dyn FnMut(u64, u64),
    finish: &mut dyn FnMut(&Path, &mut Manifest) -> Result<(), E>,
) -> Result<Manifest, E> {
    check_output(out, replace)?;
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| DbError::Io {
            reason: "output path has no directory name".into(),
            path: out.to_path_buf(),
        })?;
    std::fs::create_dir_all(&parent).map_err(|e| io_err(&parent, e))?;
    let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
    if staging.exists() {
        std::fs::remove_dir_all(&staging).map_err(|e| io_err(&staging, e))?;
    }
    let result = write_into(&staging, raster, inputs, progress)
        .map_err(E::from)
        .and_then(|mut manifest| {
            finish(&staging, &mut manifest)?;
            write_manifest(&staging, &manifest)?;
            Ok(manifest)
        });
    let manifest = match result {
        Ok(m) => m,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&staging);
            return Err(e);
        }
    };
    swap_into_place(&staging, out)?;
    Ok(manifest)
}

/// Moves a finished `staging` directory to `out`, replacing an existing `out` by rename (the
/// old one is put back if the second rename fails).
pub(crate) fn swap_into_place(staging: &Path, out: &Path) -> Result<(), DbError> {
    if out.exists() {
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = out
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let old = parent.join(format!(".{name}.old-{}", std::process::id()));
        std::fs::rename(out, &old).map_err(|e| io_err(out, e))?;
        if let Err(e) = std::fs::rename(staging, out) {
            // Put the old database back; the new one stays in the staging directory.
            let _ = std::fs::rename(&old, out);
            return Err(io_err(out, e));
        }
        std::fs::remove_dir_all(&old).map_err(|e| io_err(&old, e))?;
    } else {
        std::fs::rename(staging, out).map_err(|e| io_err(out, e))?;
    }
    Ok(())
}

/// Writes `manifest.json` into a database directory.
pub(crate) fn write_manifest(dir: &Path, manifest: &Manifest) -> Result<(), DbError> {
    let manifest_path = dir.join(MANIFEST_FILE);
    let text = serde_json::to_string_pretty(manifest).map_err(|e| DbError::Manifest {
        reason: e.to_string(),
        path: manifest_path.clone(),
    })?;
    std::fs::write(&manifest_path, text).map_err(|e| io_err(&manifest_path, e))
}

/// Whether a database may be written at `out`: it does not exist, or it is a database (even a
/// damaged one) and `replace` is set. Never anything else is replaced. Callers may ask before
/// spending time on a build; [`write_database`] asks again.
pub fn check_output(out: &Path, replace: bool) -> Result<(), DbError> {
    if !out.exists() {
        Ok(())
    } else if !replace {
        Err(DbError::Exists(out.to_path_buf()))
    } else if looks_like_database(out) {
        Ok(())
    } else {
        Err(DbError::NotReplaceable(out.to_path_buf()))
    }
}

/// True when `dir` holds a manifest that says it is a cig terrain database.
fn looks_like_database(dir: &Path) -> bool {
    std::fs::read(dir.join(MANIFEST_FILE))
        .ok()
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .is_some_and(|v| v.get("format").and_then(|f| f.as_str()) == Some(DB_FORMAT_NAME))
}

fn write_into(
    staging: &Path,
    raster: &Raster,
    inputs: &BuildInputs,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Manifest, DbError> {
    let layout = cig_terrain::PyramidLayout::new(raster.grid, inputs.tile_cells);
    let total = layout.tile_count();
    let mut made_dirs = vec![false; usize::from(layout.levels)];
    let mut written = 0u64;
    let summary: BuildSummary =
        build_pyramid::<DbError>(raster, inputs.tile_cells, &mut |tile: &Tile| {
            let path = tile_path(staging, tile.key);
            let level = usize::from(tile.key.level);
            if !made_dirs.get(level).copied().unwrap_or(true) {
                if let Some(dir) = path.parent() {
                    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
                }
                made_dirs[level] = true;
            }
            std::fs::write(&path, tile.encode()).map_err(|e| io_err(&path, e))?;
            written += 1;
            progress(written, total);
            Ok(())
        })?;
    let geoid = GeoidGrid::egm96_over(&raster.grid, 0.25);
    let manifest = Manifest::from_build(
        &summary,
        geoid,
        inputs.void_posts_filled,
        inputs.sources.clone(),
    );
    write_manifest(staging, &manifest)?;
    Ok(manifest)
}
