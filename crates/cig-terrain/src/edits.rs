//! Dynamic terrain: edits of the surface (craters, ruts, ditches with their spoil, berms,
//! fighting positions, height patches) as data, and the refined surface they make.
//!
//! Algorithm (source 002, the PC dynamic-terrain IG: deformation anywhere, local 1-to-4
//! tessellation, the T-junction map, de-tessellation; Outerra's overlay records replayed on
//! every tile): an edit is a record ([`TerrainEdit`]: shape, place, size, author, sequence
//! number, time). The database's surface is its tiles plus the edits on top: each edit's shape
//! is a continuous height change ([`EditShape::delta_m`]) that is zero on and outside its
//! footprint's edge, and edits add (a second crater in a first deepens it), so the surface
//! does not depend on the order edits arrive in and any tile loaded later sees the same change.
//! The change is carried on a finer lattice where the edit needs it: every finest cell the
//! edit's shape reaches (its footprint's part over the cell, conservatively) is split `f x f` (`f` a power of two from the edit's smallest feature, the
//! source's 1-to-4 tessellation applied `log2 f` times), over the window of the cell the
//! footprints cover ([`RefinedCell`]). The sub-cells are split along the same diagonal as their
//! cell, so each sub-triangle lies inside one of the cell's two triangles and the surface is
//! exactly the triangulation of (the cell's triangulated height + the change) at the fine posts:
//! the queries' surface and the renderer's patch are one. The changes are kept in 16-bit steps
//! of [`LATTICE_STEP_M`] (1/512 m) in overlapping blocks of one cache line ([`CellLattice`]),
//! so a height query reads one line of them. A refined window's border carries no
//! change (footprints end inside it), so its posts lie on the cell's own triangles: the
//! T-junctions there are coplanar and leave no crack. Each refined cell has the split its own
//! edits ask for; where it shares an edge with a cell split more coarsely, its posts on that
//! edge between the coarser cell's are set on the coarser cell's edge (the source's T-junction
//! map), so the two surfaces meet, to within half a step (a millimetre; the drawn patches'
//! skirts close it).
//! Removing an edit (healing) recomputes its cells from the edits left; a cell left with none
//! returns to its coarse form.
//!
//! An edit may add at most [`MAX_EDIT_POSTS`] fine posts (its split is lowered until it fits,
//! or it is refused), and a database holds at most [`MAX_EDITS`] edits, so no edit from outside
//! (a file, a DIS PDU) can take unbounded memory or time.
//!
//! Limits: shapes are laid out in the tangent metres of their reference point (east and north
//! scaled by the metres per degree there), exact to a few parts per million over the hundreds
//! of metres an edit spans. A split is at most [`MAX_SPLIT`] (a few decimetres at 30 m posts),
//! so a crater under a metre across is drawn with a few sub-cells. The coarser levels of the
//! pyramid do not carry the edits: edits are drawn and answered at the finest level.

use crate::raster::{triangulated_height, triangulated_slopes, Diagonal, GeoGrid};
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// Largest split of a finest cell (sub-cells per side).
pub const MAX_SPLIT: u32 = 128;
/// Largest height change one edit may make, metres.
pub const MAX_EDIT_HEIGHT_M: f64 = 50.0;
/// Largest horizontal extent of one edit, metres.
pub const MAX_EDIT_EXTENT_M: f64 = 2000.0;
/// Most posts a height patch may carry.
pub const MAX_PATCH_POSTS: u32 = 1 << 20;
/// Most fine posts one edit may add to the lattice: its split is lowered until it fits.
pub const MAX_EDIT_POSTS: u64 = 1 << 21;
/// Most edits a database holds.
pub const MAX_EDITS: usize = 200_000;

/// Who made an edit: the DIS simulation address of the node (site, application).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
pub struct EditAuthor {
    pub site: u16,
    pub application: u16,
}

/// An edit's identity: its author and the author's sequence number.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct EditId {
    pub author: EditAuthor,
    pub sequence: u32,
}

/// A geodetic point on the surface.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeoPoint {
    pub lat_deg: f64,
    pub lon_deg: f64,
}

/// Where a ditch's spoil goes, looking from its start to its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpoilSide {
    Left,
    Right,
    Both,
}

/// The shape of an edit, in geodetic places and metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum EditShape {
    /// A bowl of `radius_m` and `depth_m` (below the ground it was made in) with a raised lip
    /// of `lip_height_m` at the bowl's edge falling to nothing at `lip_radius_m`.
    Crater {
        centre: GeoPoint,
        radius_m: f64,
        depth_m: f64,
        lip_radius_m: f64,
        lip_height_m: f64,
    },
    /// One wheel's or track's rut from `from` to `to`: a rounded trough of `width_m` and
    /// `depth_m`. Consecutive segments sharing an end join without a step.
    Rut {
        from: GeoPoint,
        to: GeoPoint,
        width_m: f64,
        depth_m: f64,
    },
    /// A blade cut and fill: a ditch (or, shallow, a scraped strip) of top `width_m` and
    /// `depth_m` with a flat bottom half as wide, and its spoil as a berm beside it (the cut's
    /// volume, bulked by a quarter, on one side or split over both).
    Ditch {
        from: GeoPoint,
        to: GeoPoint,
        width_m: f64,
        depth_m: f64,
        spoil: SpoilSide,
    },
    /// A built-up berm of `width_m` at its foot and `height_m`.
    Berm {
        from: GeoPoint,
        to: GeoPoint,
        width_m: f64,
        height_m: f64,
    },
    /// A vehicle or infantry fighting position: a pit of `length_m` x `width_m` x `depth_m`
    /// facing `heading_deg` (clockwise from north), an entry ramp behind it and the spoil as
    /// a parapet in front.
    Position {
        centre: GeoPoint,
        heading_deg: f64,
        length_m: f64,
        width_m: f64,
        depth_m: f64,
    },
    /// A general change: `deltas_m` on a `cols` x `rows` grid of `spacing_m` (rows south to
    /// north, each west to east) from its south-west post, bilinear between the posts and
    /// falling linearly to nothing one spacing outside the grid.
    HeightPatch {
        south_west: GeoPoint,
        spacing_m: f64,
        cols: u32,
        rows: u32,
        deltas_m: Vec<f32>,
    },
}

/// An edit of the terrain: a shape made by an author at a time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TerrainEdit {
    pub author: EditAuthor,
    pub sequence: u32,
    /// When it was made, UTC seconds since 1970.
    pub time_utc_s: f64,
    pub shape: EditShape,
}

impl TerrainEdit {
    pub fn id(&self) -> EditId {
        EditId {
            author: self.author,
            sequence: self.sequence,
        }
    }
}

/// Why an edit was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EditError {
    #[error("terrain edit: {field} is {value}, not a finite number")]
    NotFinite { field: &'static str, value: f64 },
    #[error("terrain edit: {field} is {value}, outside {min}..={max}")]
    OutOfRange {
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("terrain edit: a height patch has {got} heights for {cols} x {rows} posts")]
    PatchSize { got: usize, cols: u32, rows: u32 },
    #[error("terrain edit: the edit reaches {lat_deg:.6}, {lon_deg:.6}, outside the database")]
    OutsideDatabase { lat_deg: f64, lon_deg: f64 },
    #[error("terrain edit: it would carry {posts} fine posts even at the coarsest split, more than {MAX_EDIT_POSTS}")]
    TooLarge { posts: u64 },
    #[error("terrain edit: the database already holds {MAX_EDITS} edits")]
    TooMany,
    #[error("terrain edit: {author_site}:{author_application} #{sequence} is not in the edits")]
    Unknown {
        author_site: u16,
        author_application: u16,
        sequence: u32,
    },
}

fn finite(field: &'static str, value: f64) -> Result<f64, EditError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(EditError::NotFinite { field, value })
    }
}

fn within(field: &'static str, value: f64, min: f64, max: f64) -> Result<f64, EditError> {
    let value = finite(field, value)?;
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(EditError::OutOfRange {
            field,
            value,
            min,
            max,
        })
    }
}

fn point(field: &'static str, p: GeoPoint) -> Result<GeoPoint, EditError> {
    within(field, p.lat_deg, -89.0, 89.0)?;
    within(field, p.lon_deg, -180.0, 360.0)?;
    Ok(p)
}

/// `smoothstep`: 0 below 0, 1 above 1, C1 between.
#[inline]
fn smooth(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// A bump `(1 - u^2)^2` for `|u| < 1`, else 0: its area is 16/15.
#[inline]
fn bump(u: f64) -> f64 {
    let w = 1.0 - u * u;
    if w > 0.0 {
        w * w
    } else {
        0.0
    }
}

/// A shape laid out in the tangent metres of its reference point.
#[derive(Clone, Debug)]
struct Local {
    lat0_deg: f64,
    lon0_deg: f64,
    /// Metres per degree (north, east) at the reference point.
    m_per_deg: (f64, f64),
    form: Form,
    /// Footprint in local metres: (x_min, x_max, y_min, y_max).
    bounds_m: [f64; 4],
    /// The smallest feature the lattice must resolve, metres.
    feature_m: f64,
}

#[derive(Clone, Debug)]
enum Form {
    Crater {
        radius_m: f64,
        depth_m: f64,
        lip_radius_m: f64,
        lip_height_m: f64,
    },
    /// A straight run from the origin to `(ex, ey)` with a cross profile.
    Run {
        end: (f64, f64),
        length_m: f64,
        /// Half the run's width, over which its ends fade.
        taper_m: f64,
        profile: Profile,
    },
    Position {
        /// Unit vector of the heading (east, north).
        forward: (f64, f64),
        length_m: f64,
        width_m: f64,
        depth_m: f64,
    },
    Patch {
        spacing_m: f64,
        cols: u32,
        rows: u32,
        deltas_m: Arc<[f32]>,
    },
}

#[derive(Clone, Copy, Debug)]
enum Profile {
    /// A rounded trough of half-width `half_m`.
    Trough {
        half_m: f64,
        depth_m: f64,
    },
    /// A flat-bottomed cut of top half-width `half_m`, and spoil berms: `left_m`/`right_m`
    /// their heights (left of the run's direction is positive `q`), `berm_half_m` their
    /// half-width, centred `berm_offset_m` off the axis.
    Cut {
        half_m: f64,
        depth_m: f64,
        left_m: f64,
        right_m: f64,
        berm_half_m: f64,
        berm_offset_m: f64,
    },
    Berm {
        half_m: f64,
        height_m: f64,
    },
}

impl Profile {
    fn half_extent_m(&self) -> f64 {
        match *self {
            Profile::Trough { half_m, .. } | Profile::Berm { half_m, .. } => half_m,
            Profile::Cut {
                half_m,
                berm_half_m,
                berm_offset_m,
                left_m,
                right_m,
                ..
            } => {
                if left_m > 0.0 || right_m > 0.0 {
                    berm_offset_m + berm_half_m
                } else {
                    half_m
                }
            }
        }
    }

    fn at(&self, q: f64) -> f64 {
        match *self {
            Profile::Trough { half_m, depth_m } => -depth_m * bump(q / half_m),
            Profile::Berm { half_m, height_m } => height_m * bump(q / half_m),
            Profile::Cut {
                half_m,
                depth_m,
                left_m,
                right_m,
                berm_half_m,
                berm_offset_m,
            } => {
                let inner = 0.5 * half_m;
                let cut = -depth_m * (1.0 - smooth((q.abs() - inner) / (half_m - inner)));
                let berm = if q > 0.0 {
                    left_m * bump((q - berm_offset_m) / berm_half_m)
                } else {
                    right_m * bump((-q - berm_offset_m) / berm_half_m)
                };
                cut + berm
            }
        }
    }
}

impl EditShape {
    /// Checks every value, giving the first that is wrong.
    pub fn validate(&self) -> Result<(), EditError> {
        self.local().map(|_| ())
    }

    /// The shape's reference point: a crater's or position's centre, a run's start, a
    /// patch's south-west post.
    pub fn anchor(&self) -> GeoPoint {
        match self {
            EditShape::Crater { centre, .. } | EditShape::Position { centre, .. } => *centre,
            EditShape::Rut { from, .. }
            | EditShape::Ditch { from, .. }
            | EditShape::Berm { from, .. } => *from,
            EditShape::HeightPatch { south_west, .. } => *south_west,
        }
    }

    /// The height change the shape makes at a point, metres (the exact shape, before the
    /// lattice).
    pub fn delta_m(&self, lat_deg: f64, lon_deg: f64) -> f64 {
        self.local().map_or(0.0, |l| l.delta_m(lat_deg, lon_deg))
    }

    fn local(&self) -> Result<Local, EditError> {
        let run = |from: GeoPoint, to: GeoPoint, profile: Profile, feature_m: f64| {
            let from = point("from", from)?;
            let to = point("to", to)?;
            let m_per_deg = cig_geo::metres_per_degree(from.lat_deg);
            let end = (
                (to.lon_deg - from.lon_deg) * m_per_deg.1,
                (to.lat_deg - from.lat_deg) * m_per_deg.0,
            );
            let length_m = within("length", end.0.hypot(end.1), 0.0, MAX_EDIT_EXTENT_M)?;
            let reach = profile.half_extent_m();
            let taper_m = match profile {
                Profile::Trough { half_m, .. }
                | Profile::Berm { half_m, .. }
                | Profile::Cut { half_m, .. } => half_m,
            };
            let pad = reach.max(taper_m);
            Ok(Local {
                lat0_deg: from.lat_deg,
                lon0_deg: from.lon_deg,
                m_per_deg,
                form: Form::Run {
                    end,
                    length_m,
                    taper_m,
                    profile,
                },
                bounds_m: [
                    end.0.min(0.0) - pad,
                    end.0.max(0.0) + pad,
                    end.1.min(0.0) - pad,
                    end.1.max(0.0) + pad,
                ],
                feature_m,
            })
        };
        match self {
            EditShape::Crater {
                centre,
                radius_m,
                depth_m,
                lip_radius_m,
                lip_height_m,
            } => {
                let c = point("centre", *centre)?;
                let radius_m = within("radius_m", *radius_m, 0.05, 200.0)?;
                let depth_m = within("depth_m", *depth_m, 0.0, MAX_EDIT_HEIGHT_M)?;
                let lip_radius_m = within("lip_radius_m", *lip_radius_m, radius_m, 3.0 * radius_m)?;
                let lip_height_m = within("lip_height_m", *lip_height_m, 0.0, MAX_EDIT_HEIGHT_M)?;
                if lip_height_m > 0.0 {
                    // The lip must fall off outside the bowl's edge, not step down at it.
                    within(
                        "lip_radius_m",
                        lip_radius_m,
                        1.05 * radius_m,
                        3.0 * radius_m,
                    )?;
                }
                Ok(Local {
                    lat0_deg: c.lat_deg,
                    lon0_deg: c.lon_deg,
                    m_per_deg: cig_geo::metres_per_degree(c.lat_deg),
                    form: Form::Crater {
                        radius_m,
                        depth_m,
                        lip_radius_m,
                        lip_height_m,
                    },
                    bounds_m: [-lip_radius_m, lip_radius_m, -lip_radius_m, lip_radius_m],
                    feature_m: radius_m.min((lip_radius_m - radius_m).max(radius_m * 0.25)),
                })
            }
            EditShape::Rut {
                from,
                to,
                width_m,
                depth_m,
            } => {
                let width_m = within("width_m", *width_m, 0.05, 20.0)?;
                let depth_m = within("depth_m", *depth_m, 0.0, 5.0)?;
                run(
                    *from,
                    *to,
                    Profile::Trough {
                        half_m: 0.5 * width_m,
                        depth_m,
                    },
                    0.5 * width_m,
                )
            }
            EditShape::Ditch {
                from,
                to,
                width_m,
                depth_m,
                spoil,
            } => {
                let width_m = within("width_m", *width_m, 0.2, 100.0)?;
                let depth_m = within("depth_m", *depth_m, 0.0, 20.0)?;
                // The cut's cross-section: the flat bottom (half the width) and two smooth
                // sides, 3/4 of width x depth. Berms 1.5 x the width at the foot, profile area
                // 16/15 x half-width x height, hold it bulked by a quarter.
                let berm_half_m = 0.75 * width_m;
                let spoil_area = 1.25 * 0.75 * width_m * depth_m;
                let height_one = spoil_area / (16.0 / 15.0 * berm_half_m);
                let (left_m, right_m) = match spoil {
                    SpoilSide::Left => (height_one, 0.0),
                    SpoilSide::Right => (0.0, height_one),
                    SpoilSide::Both => (0.5 * height_one, 0.5 * height_one),
                };
                run(
                    *from,
                    *to,
                    Profile::Cut {
                        half_m: 0.5 * width_m,
                        depth_m,
                        left_m,
                        right_m,
                        berm_half_m,
                        berm_offset_m: 0.5 * width_m + berm_half_m,
                    },
                    0.25 * width_m,
                )
            }
            EditShape::Berm {
                from,
                to,
                width_m,
                height_m,
            } => {
                let width_m = within("width_m", *width_m, 0.2, 100.0)?;
                let height_m = within("height_m", *height_m, 0.0, 20.0)?;
                run(
                    *from,
                    *to,
                    Profile::Berm {
                        half_m: 0.5 * width_m,
                        height_m,
                    },
                    0.5 * width_m,
                )
            }
            EditShape::Position {
                centre,
                heading_deg,
                length_m,
                width_m,
                depth_m,
            } => {
                let c = point("centre", *centre)?;
                let heading = within("heading_deg", *heading_deg, -360.0, 720.0)?.to_radians();
                let length_m = within("length_m", *length_m, 0.5, 50.0)?;
                let width_m = within("width_m", *width_m, 0.5, 50.0)?;
                let depth_m = within("depth_m", *depth_m, 0.0, 10.0)?;
                let reach = position_reach_m(length_m, width_m, depth_m);
                Ok(Local {
                    lat0_deg: c.lat_deg,
                    lon0_deg: c.lon_deg,
                    m_per_deg: cig_geo::metres_per_degree(c.lat_deg),
                    form: Form::Position {
                        forward: (heading.sin(), heading.cos()),
                        length_m,
                        width_m,
                        depth_m,
                    },
                    bounds_m: [-reach, reach, -reach, reach],
                    feature_m: 0.25 * length_m.min(width_m),
                })
            }
            EditShape::HeightPatch {
                south_west,
                spacing_m,
                cols,
                rows,
                deltas_m,
            } => {
                let sw = point("south_west", *south_west)?;
                let spacing_m = within("spacing_m", *spacing_m, 0.05, 100.0)?;
                within("cols", f64::from(*cols), 2.0, 4096.0)?;
                within("rows", f64::from(*rows), 2.0, 4096.0)?;
                if u64::from(*cols) * u64::from(*rows) > u64::from(MAX_PATCH_POSTS)
                    || deltas_m.len() as u64 != u64::from(*cols) * u64::from(*rows)
                {
                    return Err(EditError::PatchSize {
                        got: deltas_m.len(),
                        cols: *cols,
                        rows: *rows,
                    });
                }
                for d in deltas_m.iter() {
                    within(
                        "deltas_m",
                        f64::from(*d),
                        -MAX_EDIT_HEIGHT_M,
                        MAX_EDIT_HEIGHT_M,
                    )?;
                }
                let w = spacing_m * f64::from(*cols);
                let h = spacing_m * f64::from(*rows);
                within("patch width", w, 0.0, MAX_EDIT_EXTENT_M)?;
                within("patch height", h, 0.0, MAX_EDIT_EXTENT_M)?;
                Ok(Local {
                    lat0_deg: sw.lat_deg,
                    lon0_deg: sw.lon_deg,
                    m_per_deg: cig_geo::metres_per_degree(sw.lat_deg),
                    form: Form::Patch {
                        spacing_m,
                        cols: *cols,
                        rows: *rows,
                        deltas_m: deltas_m.clone().into(),
                    },
                    bounds_m: [-spacing_m, w, -spacing_m, h],
                    feature_m: spacing_m,
                })
            }
        }
    }
}

/// How far a fighting position's pit, ramp and parapet reach from its centre, metres.
fn position_reach_m(length_m: f64, width_m: f64, depth_m: f64) -> f64 {
    let ramp = position_ramp_m(depth_m);
    let along = (0.5 * length_m + ramp).max(position_parapet_m(length_m, width_m).1);
    along.hypot(0.5 * width_m + position_slope_m(length_m, width_m))
}

/// The entry ramp's length: a 1 in 3 slope.
fn position_ramp_m(depth_m: f64) -> f64 {
    3.0 * depth_m
}

/// The pit walls' horizontal run.
fn position_slope_m(length_m: f64, width_m: f64) -> f64 {
    0.15 * length_m.min(width_m)
}

/// The parapet's centre and far reach ahead of the pit's centre: (centre, reach).
fn position_parapet_m(length_m: f64, width_m: f64) -> (f64, f64) {
    let slope = position_slope_m(length_m, width_m);
    let half = 0.25 * length_m.max(2.0);
    let centre = 0.5 * length_m + slope + half;
    (centre, centre + half)
}

impl Local {
    fn delta_m(&self, lat_deg: f64, lon_deg: f64) -> f64 {
        let x = (lon_deg - self.lon0_deg) * self.m_per_deg.1;
        let y = (lat_deg - self.lat0_deg) * self.m_per_deg.0;
        let [x0, x1, y0, y1] = self.bounds_m;
        if !(x > x0 && x < x1 && y > y0 && y < y1) {
            return 0.0;
        }
        match &self.form {
            Form::Crater {
                radius_m,
                depth_m,
                lip_radius_m,
                lip_height_m,
            } => {
                let r = x.hypot(y);
                if r >= *lip_radius_m {
                    return 0.0;
                }
                // The bowl (a paraboloid reaching the lip's height at the radius) and the lip
                // (level inside the radius, falling smoothly to nothing at the lip's radius),
                // joined by a smooth minimum: a rounded crest, not a knife edge.
                let s = r / radius_m;
                let bowl = -depth_m + (depth_m + lip_height_m) * s * s;
                let lip = if r <= *radius_m {
                    *lip_height_m
                } else {
                    lip_height_m * (1.0 - smooth((r - radius_m) / (lip_radius_m - radius_m)))
                };
                let k = 0.2 * (depth_m + lip_height_m);
                let h = (k - (bowl - lip).abs()).max(0.0) / k.max(1e-9);
                bowl.min(lip) - h * h * k * 0.25
            }
            Form::Run {
                end,
                length_m,
                taper_m,
                profile,
            } => {
                let (t, q) = if *length_m > 1e-9 {
                    let (ux, uy) = (end.0 / length_m, end.1 / length_m);
                    (x * ux + y * uy, -x * uy + y * ux)
                } else {
                    (x.hypot(y), 0.0)
                };
                // Ends fade over the taper, a partition of unity with the next segment's.
                let h = *taper_m;
                let along =
                    smooth((t + h) / (2.0 * h)) * (1.0 - smooth((t - length_m + h) / (2.0 * h)));
                along * profile.at(q)
            }
            Form::Position {
                forward,
                length_m,
                width_m,
                depth_m,
            } => {
                let a = x * forward.0 + y * forward.1;
                let b = x * forward.1 - y * forward.0;
                let slope = position_slope_m(*length_m, *width_m);
                let half_l = 0.5 * length_m;
                let ramp = position_ramp_m(*depth_m);
                let along = if a < -half_l {
                    ((a + half_l + ramp) / ramp).clamp(0.0, 1.0)
                } else if a <= half_l {
                    1.0
                } else {
                    1.0 - smooth((a - half_l) / slope)
                };
                let across = 1.0 - smooth((b.abs() - 0.5 * width_m) / slope);
                let pit = -depth_m * along * across;
                // The parapet holds half the pit's volume, bulked by a quarter, over the pit's
                // width plus its walls (the rest is spread thin).
                let (centre, reach) = position_parapet_m(*length_m, *width_m);
                let half = reach - centre;
                let span = 0.5 * width_m + slope;
                let volume = 0.5 * 1.25 * depth_m * length_m * width_m;
                let height = (volume / (16.0 / 15.0 * half * 2.0 * span)).min(*depth_m);
                let parapet =
                    height * bump((a - centre) / half) * (1.0 - smooth(b.abs() - span + 1.0));
                pit + parapet
            }
            Form::Patch {
                spacing_m,
                cols,
                rows,
                deltas_m,
            } => {
                let (fx, fy) = (x / spacing_m, y / spacing_m);
                let at = |i: i64, j: i64| -> f64 {
                    if i < 0 || j < 0 || i >= i64::from(*rows) || j >= i64::from(*cols) {
                        0.0
                    } else {
                        f64::from(deltas_m[(i as usize) * (*cols as usize) + j as usize])
                    }
                };
                let (j0, i0) = (fx.floor(), fy.floor());
                let (u, v) = (fx - j0, fy - i0);
                let (i0, j0) = (i0 as i64, j0 as i64);
                (1.0 - v) * ((1.0 - u) * at(i0, j0) + u * at(i0, j0 + 1))
                    + v * ((1.0 - u) * at(i0 + 1, j0) + u * at(i0 + 1, j0 + 1))
            }
        }
    }

    /// The part of the footprint over a rectangle (south, north, west, east, degrees), as a
    /// rectangle in degrees, or `None` when the shape changes nothing there. Conservative: a
    /// rectangle the shape changes anywhere, edges included, always has one.
    fn footprint_in(&self, [south, north, west, east]: [f64; 4]) -> Option<[f64; 4]> {
        const EPS_M: f64 = 1e-6;
        let (mn, me) = self.m_per_deg;
        let (x0, x1) = ((west - self.lon0_deg) * me, (east - self.lon0_deg) * me);
        let (y0, y1) = ((south - self.lat0_deg) * mn, (north - self.lat0_deg) * mn);
        let [bx0, bx1, by0, by1] = self.bounds_m;
        let (mut fx0, mut fx1, mut fy0, mut fy1) =
            (bx0.max(x0), bx1.min(x1), by0.max(y0), by1.min(y1));
        if fx0 > fx1 + EPS_M || fy0 > fy1 + EPS_M {
            return None;
        }
        match &self.form {
            Form::Crater { lip_radius_m, .. } => {
                let dx = (x0 - 0.0).max(0.0 - x1).max(0.0);
                let dy = (y0 - 0.0).max(0.0 - y1).max(0.0);
                if dx.hypot(dy) > lip_radius_m + EPS_M {
                    return None;
                }
            }
            Form::Run { end, .. } => {
                // Every changed point lies within the pad (the bounds' margin) of the run's
                // segment along both axes, so within sqrt(2) pad of it.
                let pad = (bx1 - end.0.max(0.0)).max(0.0) * std::f64::consts::SQRT_2 + EPS_M;
                let (dx, dy) = (end.0, end.1);
                let clipped = clip_segment(dx, x0 - pad, x1 + pad, 0.0, 1.0)
                    .and_then(|(a, b)| clip_segment(dy, y0 - pad, y1 + pad, a, b));
                let (t0, t1) = clipped?;
                fx0 = fx0.max((dx * t0).min(dx * t1) - pad);
                fx1 = fx1.min((dx * t0).max(dx * t1) + pad);
                fy0 = fy0.max((dy * t0).min(dy * t1) - pad);
                fy1 = fy1.min((dy * t0).max(dy * t1) + pad);
            }
            Form::Position { .. } | Form::Patch { .. } => {}
        }
        (fx0 <= fx1 + EPS_M && fy0 <= fy1 + EPS_M).then(|| {
            [
                self.lat0_deg + fy0 / mn,
                self.lat0_deg + fy1.max(fy0) / mn,
                self.lon0_deg + fx0 / me,
                self.lon0_deg + fx1.max(fx0) / me,
            ]
        })
    }

    /// The footprint in degrees: (south, north, west, east).
    fn bounds_deg(&self) -> [f64; 4] {
        let [x0, x1, y0, y1] = self.bounds_m;
        [
            self.lat0_deg + y0 / self.m_per_deg.0,
            self.lat0_deg + y1 / self.m_per_deg.0,
            self.lon0_deg + x0 / self.m_per_deg.1,
            self.lon0_deg + x1 / self.m_per_deg.1,
        ]
    }
}

/// Clips `t` in `[t0, t1]` to `lo <= d t <= hi` (a segment from the origin along one axis).
fn clip_segment(d: f64, lo: f64, hi: f64, t0: f64, t1: f64) -> Option<(f64, f64)> {
    if d.abs() < 1e-12 {
        return (lo <= 0.0 && 0.0 <= hi).then_some((t0, t1));
    }
    let (a, b) = (lo / d, hi / d);
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    let (t0, t1) = (t0.max(a), t1.min(b));
    (t0 <= t1).then_some((t0, t1))
}

/// An edit with its shape laid out.
#[derive(Debug)]
struct Entry {
    edit: TerrainEdit,
    local: Local,
    /// The cells' split it asks for.
    split: u32,
    /// Finest cells its footprint touches: rows then columns, inclusive.
    cells: [u32; 4],
}

/// The cells sharing an edge with a cell: west, east, south, north.
fn edge_neighbours((r, c): CellKey) -> [Option<CellKey>; 4] {
    [
        c.checked_sub(1).map(|c| (r, c)),
        Some((r, c + 1)),
        r.checked_sub(1).map(|r| (r, c)),
        Some((r + 1, c)),
    ]
}

/// Levels of [`EditLayer`]'s block pyramid: blocks of 2 to `2^BLOCK_LEVELS` finest cells
/// a side (a node of any level of a database up to 2^24 posts a side finds its range in
/// at most nine blocks).
const BLOCK_LEVELS: usize = 24;

/// Sub-cells along a side of a refined window's block (`RefinedCell::block_max_m`).
pub const BLOCK_SUB_CELLS: u32 = 8;

/// The changes of the refined cells are kept in steps of this many metres (a power of two,
/// so a step count times it is exact in single floats): 16-bit counts reach
/// [`MAX_EDIT_HEIGHT_M`] with room to spare.
pub const LATTICE_STEP_M: f32 = 1.0 / 512.0;

/// A change rounded to the lattice's steps ([`LATTICE_STEP_M`]).
#[inline]
pub fn lattice_rounded_m(change_m: f32) -> f32 {
    (change_m / LATTICE_STEP_M).round() * LATTICE_STEP_M
}

/// Fine posts along a [`PostBlock`] (east, north).
const BLOCK_POSTS: (usize, usize) = (8, 4);

/// 8 x 4 fine posts of a lattice (rows south to north) in one 64-byte cache line, as counts of
/// [`LATTICE_STEP_M`]. Neighbouring blocks share their edge posts, so every sub-cell's four
/// corners lie in one block: a height query reads one line of the lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct PostBlock([i16; BLOCK_POSTS.0 * BLOCK_POSTS.1]);

/// The fine lattice of a refined cell: the changes at the posts of its window. The layer
/// keeps it beside the cell's key (not behind the cell's record), so a height query reads it
/// in the same look-up that finds the cell, and the posts it needs in one cache line.
#[derive(Clone, Debug)]
pub struct CellLattice {
    /// Sub-cells per side of the whole cell (a power of two).
    pub split: u32,
    /// The window's south-west fine post (east, north), in sub-cells from the cell's corner.
    pub origin: (u32, u32),
    /// Fine posts along the window (east, north); at least 2 each.
    pub posts: (u32, u32),
    /// Blocks along the window's east.
    blocks_east: u32,
    /// The split, the window's origin and its last sub-cell as floats, for the queries.
    split_f: f64,
    origin_f: (f64, f64),
    last_f: (f64, f64),
    /// The window's posts in overlapping blocks (rows of blocks south to north).
    blocks: Arc<[PostBlock]>,
}

impl CellLattice {
    /// The lattice of a window's posts (`changes_m`, rows south to north, each a multiple of
    /// [`LATTICE_STEP_M`]: [`lattice_rounded_m`]).
    fn new(split: u32, origin: (u32, u32), posts: (u32, u32), changes_m: &[f32]) -> CellLattice {
        let (na, nb) = (posts.0 as usize, posts.1 as usize);
        debug_assert_eq!(changes_m.len(), na * nb);
        let (ea, eb) = (BLOCK_POSTS.0 - 1, BLOCK_POSTS.1 - 1);
        let (blocks_east, blocks_north) = ((na - 1).div_ceil(ea), (nb - 1).div_ceil(eb));
        let mut blocks = vec![PostBlock([0; 32]); blocks_east * blocks_north];
        for (k, block) in blocks.iter_mut().enumerate() {
            let (a0, b0) = ((k % blocks_east) * ea, (k / blocks_east) * eb);
            for y in 0..BLOCK_POSTS.1 {
                for x in 0..BLOCK_POSTS.0 {
                    let (a, b) = (a0 + x, b0 + y);
                    if a < na && b < nb {
                        let steps = (changes_m[b * na + a] / LATTICE_STEP_M).round();
                        block.0[y * BLOCK_POSTS.0 + x] =
                            steps.clamp(f32::from(i16::MIN), f32::from(i16::MAX)) as i16;
                    }
                }
            }
        }
        CellLattice {
            split,
            origin,
            posts,
            split_f: f64::from(split),
            origin_f: (f64::from(origin.0), f64::from(origin.1)),
            last_f: ((na - 1) as f64, (nb - 1) as f64),
            blocks_east: blocks_east as u32,
            blocks: blocks.into(),
        }
    }

    /// The window's sub-cell under `(u, v)` in the cell (0 to 1 east and north) and the
    /// fractions in it, or `None` outside the window.
    #[inline(always)]
    fn sub_cell(&self, u: f64, v: f64) -> Option<(usize, usize, f64, f64)> {
        let fu = u * self.split_f - self.origin_f.0;
        let fv = v * self.split_f - self.origin_f.1;
        if !(fu >= 0.0 && fv >= 0.0 && fu <= self.last_f.0 && fv <= self.last_f.1) {
            return None;
        }
        // The last sub-cell holds the window's far edges.
        let a = fu.min(self.last_f.0 - 1.0) as usize;
        let b = fv.min(self.last_f.1 - 1.0) as usize;
        Some((a, b, fu - a as f64, fv - b as f64))
    }

    /// The block holding sub-cell `(a, b)` of the window and the index of its south-west post
    /// in it.
    #[inline(always)]
    fn block_of(&self, a: usize, b: usize) -> (&PostBlock, usize) {
        let (ea, eb) = (BLOCK_POSTS.0 - 1, BLOCK_POSTS.1 - 1);
        let (p, q) = (a / ea, b / eb);
        let block = &self.blocks[q * self.blocks_east as usize + p];
        (block, (b - q * eb) * BLOCK_POSTS.0 + (a - p * ea))
    }

    /// The change at `(u, v)` in the cell (0 to 1 east and north), on the sub-cells split along
    /// `diagonal`.
    #[inline]
    pub fn delta_m(&self, u: f64, v: f64, diagonal: Diagonal) -> f64 {
        match self.sub_cell(u, v) {
            Some((a, b, x, y)) => triangulated_height(self.corners(a, b), x, y, diagonal),
            None => 0.0,
        }
    }

    /// The slopes of the change per sub-cell (east, north) at `(u, v)`.
    pub fn slopes(&self, u: f64, v: f64, diagonal: Diagonal) -> (f64, f64) {
        match self.sub_cell(u, v) {
            Some((a, b, x, y)) => triangulated_slopes(self.corners(a, b), x, y, diagonal),
            None => (0.0, 0.0),
        }
    }

    /// Asks the memory system for the posts [`CellLattice::delta_m`] reads at `(u, v)`
    /// without waiting for them.
    #[inline]
    pub fn prefetch_posts(&self, u: f64, v: f64) {
        if let Some((a, b, _, _)) = self.sub_cell(u, v) {
            crate::hint::prefetch(self.block_of(a, b).0);
        }
    }

    /// The changes at the corners of the window's sub-cell `(a, b)` (east, north), in
    /// [`triangulated_height`]'s order.
    #[inline]
    pub fn corners(&self, a: usize, b: usize) -> [f32; 4] {
        let (block, k) = self.block_of(a, b);
        let e = BLOCK_POSTS.0;
        [
            block.0[k],
            block.0[k + 1],
            block.0[k + e],
            block.0[k + e + 1],
        ]
        .map(|steps| f32::from(steps) * LATTICE_STEP_M)
    }

    /// The change at the window's post `(a, b)` (east, north).
    pub fn post_m(&self, a: usize, b: usize) -> f32 {
        let (na, nb) = (self.posts.0 as usize, self.posts.1 as usize);
        let (a, b) = (a.min(na - 1), b.min(nb - 1));
        // The sub-cell the post is a south-west corner of, or the last one.
        let (sa, sb) = (a.min(na - 2), b.min(nb - 2));
        let (block, k) = self.block_of(sa, sb);
        let steps = block.0[k + (b - sb) * BLOCK_POSTS.0 + (a - sa)];
        f32::from(steps) * LATTICE_STEP_M
    }

    /// Bytes the lattice's posts take.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&*self.blocks)
    }
}

/// A finest cell carrying changes on a finer lattice over a window of it.
#[derive(Clone, Debug)]
pub struct RefinedCell {
    pub lattice: CellLattice,
    /// Lowest and highest change in the window.
    pub min_m: f32,
    pub max_m: f32,
    /// The highest change in each block of [`BLOCK_SUB_CELLS`] x [`BLOCK_SUB_CELLS`]
    /// sub-cells of the window (rows south to north), for the sightlines' walk.
    pub block_max_m: Vec<f32>,
    /// Blocks along the window (east, north).
    pub blocks: (u32, u32),
    /// The edits touching the cell.
    edits: Vec<EditId>,
}

impl RefinedCell {
    /// The change at `(u, v)` in the cell ([`CellLattice::delta_m`]).
    #[inline]
    pub fn delta_m(&self, u: f64, v: f64, diagonal: Diagonal) -> f64 {
        self.lattice.delta_m(u, v, diagonal)
    }

    /// The slopes of the change per sub-cell ([`CellLattice::slopes`]).
    pub fn slopes(&self, u: f64, v: f64, diagonal: Diagonal) -> (f64, f64) {
        self.lattice.slopes(u, v, diagonal)
    }
}

/// A refined cell as the layer keeps it: its lattice inline, the whole record shared.
#[derive(Clone, Debug)]
struct CellSlot {
    lattice: CellLattice,
    cell: Arc<RefinedCell>,
}

impl CellSlot {
    fn new(cell: RefinedCell) -> CellSlot {
        CellSlot {
            lattice: cell.lattice.clone(),
            cell: Arc::new(cell),
        }
    }
}

/// What the edits over a point did to its ground, for the drawn surface's dynamic texture
/// (source 002's texture swaps and overlays): the freshest rut through it (tracks' marks
/// fade over hours while their shape stays), the freshest crater scorching it, and how far
/// the other edits (earthworks, craters' bowls and lips) moved it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroundMarks {
    /// 0 to 1: how much a rut marks the point (1 from 1 cm of sinkage), and when the
    /// freshest such rut was made (UTC seconds; meaningless while the weight is 0).
    pub track: f32,
    pub track_time_utc_s: f64,
    /// 0 to 1: a crater's scorch (1 inside 0.7 of its radius, none past its lip at 1.25),
    /// and when the freshest such crater was made.
    pub scorch: f32,
    pub scorch_time_utc_s: f64,
    /// The largest height change any edit but a rut makes here, metres.
    pub earth_moved_m: f64,
}

/// Adds a mark of weight `w` made at `time_s` to a (weight, time) pair: the heavier weight,
/// the freshest time of the marks that weigh anything.
fn take_mark((weight, time): (&mut f32, &mut f64), w: f32, time_s: f64) {
    if w > 0.0 {
        *time = if *weight > 0.0 {
            time.max(time_s)
        } else {
            time_s
        };
        *weight = weight.max(w);
    }
}

/// Where one finest cell is: (row, column) of its south-west post on the finest lattice.
pub type CellKey = (u32, u32);

/// The multiply-rotate hash of rustc's `FxHasher` for the cell maps the queries look up on
/// every answer (SipHash's resistance to chosen keys buys nothing here: keys are cells of
/// the database, and an edit's footprint is bounded).
#[derive(Clone, Copy, Default)]
pub struct CellHasher(u64);

impl std::hash::Hasher for CellHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(u64::from(*b));
        }
    }

    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

type CellMap<V> = HashMap<CellKey, V, std::hash::BuildHasherDefault<CellHasher>>;

/// The edits of a database and the refined surface they make: an immutable snapshot,
/// cheap to clone (shared parts), changed by [`EditLayer::apply`] and [`EditLayer::remove`].
#[derive(Clone, Debug)]
pub struct EditLayer {
    grid: GeoGrid,
    tile_cells: u32,
    /// The finest posts' spacing (the smaller of east and north) at the database's centre.
    post_spacing_m: f64,
    order: Vec<EditId>,
    entries: HashMap<EditId, Arc<Entry>>,
    cells: CellMap<CellSlot>,
    /// Per finest tile (row, column): the highest change in it (0 or more) and the lowest
    /// (0 or less).
    tiles: CellMap<(f32, f32)>,
    /// The refined cells of each finest tile, and the revision that last changed them.
    tile_members: CellMap<Arc<HashSet<CellKey>>>,
    tile_revisions: CellMap<u64>,
    /// The highest change (0 or more) and the lowest (0 or less) in aligned blocks of
    /// `2^(k + 1)` finest cells a side, keyed by the block's (row, column) at `k`: a pyramid
    /// over the refined cells, for a node of any level to find its edits' range in a few
    /// look-ups ([`EditLayer::range_over_m`]).
    blocks: Vec<CellMap<(f32, f32)>>,
    /// Each author's highest sequence number.
    last_sequences: HashMap<EditAuthor, u32>,
    max_raise_m: f32,
    revision: u64,
}

/// What [`EditLayer::apply`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Applied {
    /// The edit is new and now part of the surface.
    Added,
    /// An edit with that author and sequence number is already there (a re-announcement).
    Known,
}

impl EditLayer {
    /// No edits, over the finest lattice `grid` cut into tiles of `tile_cells`.
    pub fn new(grid: GeoGrid, tile_cells: u32) -> EditLayer {
        let centre = grid.south_lat_deg + 0.5 * grid.dlat_deg * (grid.rows.max(1) - 1) as f64;
        let (mn, me) = cig_geo::metres_per_degree(centre.clamp(-89.0, 89.0));
        EditLayer {
            grid,
            tile_cells: tile_cells.max(1),
            post_spacing_m: (grid.dlat_deg * mn).min(grid.dlon_deg * me).max(1e-3),
            order: Vec::new(),
            entries: HashMap::new(),
            cells: CellMap::default(),
            tiles: CellMap::default(),
            tile_members: CellMap::default(),
            tile_revisions: CellMap::default(),
            blocks: vec![CellMap::default(); BLOCK_LEVELS],
            last_sequences: HashMap::new(),
            max_raise_m: 0.0,
            revision: 0,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Grows by one with every change.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// The edits in the order they were applied.
    pub fn edits(&self) -> impl Iterator<Item = &TerrainEdit> + '_ {
        self.order
            .iter()
            .filter_map(|id| self.entries.get(id).map(|e| &e.edit))
    }

    /// The edits from the `start`-th applied on, in the order they were applied (the ones
    /// added since a reader last saw `start` edits, when none was removed since).
    pub fn edits_from(&self, start: usize) -> impl Iterator<Item = &TerrainEdit> + '_ {
        self.order
            .get(start..)
            .unwrap_or_default()
            .iter()
            .filter_map(|id| self.entries.get(id).map(|e| &e.edit))
    }

    /// The edit `id`, if held.
    pub fn get(&self, id: EditId) -> Option<&TerrainEdit> {
        self.entries.get(&id).map(|e| &e.edit)
    }

    pub fn contains(&self, id: EditId) -> bool {
        self.entries.contains_key(&id)
    }

    /// The highest sequence number an author has used, if any.
    pub fn last_sequence(&self, author: EditAuthor) -> Option<u32> {
        self.last_sequences.get(&author).copied()
    }

    /// The revision that last changed a finest tile's refined cells (0: never).
    pub fn tile_revision(&self, row: u32, col: u32) -> u64 {
        self.tile_revisions.get(&(row, col)).copied().unwrap_or(0)
    }

    /// The refined cell at a finest cell, if any.
    #[inline]
    pub fn cell(&self, key: CellKey) -> Option<&RefinedCell> {
        if self.cells.is_empty() {
            return None;
        }
        self.cells.get(&key).map(|c| &*c.cell)
    }

    /// The lattice of the refined cell at a finest cell, if any: [`EditLayer::cell`]'s
    /// changes, read without reaching the cell's record.
    #[inline]
    pub fn lattice(&self, key: CellKey) -> Option<&CellLattice> {
        if self.cells.is_empty() {
            return None;
        }
        self.cells.get(&key).map(|c| &c.lattice)
    }

    /// The refined cell at a finest cell as the layer shares it: the same `Arc` until the
    /// cell changes (an edit through it applied or healed), so a reader can keep what it
    /// made of the cell and remake it only when this changes.
    pub fn shared_cell(&self, key: CellKey) -> Option<&Arc<RefinedCell>> {
        self.cells.get(&key).map(|c| &c.cell)
    }

    /// Bytes the layer holds: its edits (records, laid-out shapes, a height patch's posts),
    /// its refined cells (records, lattices, blocks' highest changes) and its indices; the
    /// hash tables counted at their entries' size, not their spare capacity.
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        let edits: usize = self
            .entries
            .values()
            .map(|e| {
                let posts = match &e.edit.shape {
                    EditShape::HeightPatch { deltas_m, .. } => 2 * deltas_m.len() * 4,
                    _ => 0,
                };
                size_of::<EditId>() + 2 * size_of::<usize>() + size_of::<Entry>() + posts
            })
            .sum::<usize>()
            + self.order.len() * size_of::<EditId>();
        let cells: usize = self
            .cells
            .values()
            .map(|slot| {
                size_of::<CellKey>()
                    + size_of::<CellSlot>()
                    + 2 * size_of::<usize>()
                    + size_of::<RefinedCell>()
                    + slot.lattice.bytes()
                    + slot.cell.block_max_m.len() * 4
                    + slot.cell.edits.len() * size_of::<EditId>()
            })
            .sum();
        let indices = self.blocks.iter().map(|b| b.len()).sum::<usize>()
            * (size_of::<CellKey>() + 8)
            + self.tile_members.values().map(|m| m.len()).sum::<usize>() * size_of::<CellKey>()
            + self.tiles.len() * 3 * (size_of::<CellKey>() + 8);
        edits + cells + indices
    }

    /// Every refined cell.
    pub fn cells(&self) -> impl Iterator<Item = (CellKey, &RefinedCell)> + '_ {
        self.cells.iter().map(|(k, c)| (*k, &*c.cell))
    }

    /// What the edits through the finest cell `key` did to the ground at a point (exact
    /// shapes, before the lattice); nothing outside the refined cells.
    pub fn ground_marks(&self, key: CellKey, lat_deg: f64, lon_deg: f64) -> GroundMarks {
        let mut marks = GroundMarks::default();
        let Some(CellSlot { cell, .. }) = self.cells.get(&key) else {
            return marks;
        };
        for entry in cell.edits.iter().filter_map(|id| self.entries.get(id)) {
            let time_s = entry.edit.time_utc_s;
            match (&entry.edit.shape, &entry.local.form) {
                (EditShape::Rut { .. }, _) => {
                    let w = (entry.local.delta_m(lat_deg, lon_deg).abs() / 0.01).min(1.0) as f32;
                    take_mark((&mut marks.track, &mut marks.track_time_utc_s), w, time_s);
                }
                (EditShape::Crater { .. }, Form::Crater { radius_m, .. }) => {
                    let l = &entry.local;
                    let x = (lon_deg - l.lon0_deg) * l.m_per_deg.1;
                    let y = (lat_deg - l.lat0_deg) * l.m_per_deg.0;
                    let t = ((1.25 - x.hypot(y) / radius_m) / 0.55).clamp(0.0, 1.0);
                    let w = (t * t * (3.0 - 2.0 * t)) as f32;
                    take_mark((&mut marks.scorch, &mut marks.scorch_time_utc_s), w, time_s);
                    marks.earth_moved_m =
                        marks.earth_moved_m.max(l.delta_m(lat_deg, lon_deg).abs());
                }
                _ => {
                    marks.earth_moved_m = marks
                        .earth_moved_m
                        .max(entry.local.delta_m(lat_deg, lon_deg).abs());
                }
            }
        }
        marks
    }

    /// The highest change anywhere (0 or more), metres.
    pub fn max_raise_m(&self) -> f32 {
        self.max_raise_m
    }

    /// The highest and lowest change in a finest tile (row, column): (0, 0) where nothing
    /// changed.
    #[inline]
    pub fn tile_range_m(&self, row: u32, col: u32) -> (f32, f32) {
        if self.tiles.is_empty() {
            return (0.0, 0.0);
        }
        self.tiles.get(&(row, col)).copied().unwrap_or((0.0, 0.0))
    }

    /// The change the edits make at a point on the lattice's surface, metres.
    pub fn delta_m(&self, lat_deg: f64, lon_deg: f64) -> f64 {
        let g = &self.grid;
        let row_f = (lat_deg - g.south_lat_deg) / g.dlat_deg;
        let col_f = (lon_deg - g.west_lon_deg) / g.dlon_deg;
        if !(row_f >= 0.0 && col_f >= 0.0) {
            return 0.0;
        }
        let (r, c) = (
            (row_f as usize).min(g.rows.saturating_sub(2)),
            (col_f as usize).min(g.cols.saturating_sub(2)),
        );
        self.cell((r as u32, c as u32)).map_or(0.0, |cell| {
            cell.delta_m(col_f - c as f64, row_f - r as f64, Diagonal::of_cell(r, c))
        })
    }

    /// The exact shapes' change at a point (without the lattice), metres.
    pub fn shape_delta_m(&self, lat_deg: f64, lon_deg: f64) -> f64 {
        self.order
            .iter()
            .filter_map(|id| self.entries.get(id))
            .map(|e| e.local.delta_m(lat_deg, lon_deg))
            .sum()
    }

    /// Adds an edit: checked whole first, so a refused edit changes nothing.
    pub fn apply(&mut self, edit: TerrainEdit) -> Result<Applied, EditError> {
        let id = edit.id();
        if self.entries.contains_key(&id) {
            return Ok(Applied::Known);
        }
        finite("time_utc_s", edit.time_utc_s)?;
        let local = edit.shape.local()?;
        let [south, north, west, east] = local.bounds_deg();
        let g = &self.grid;
        let to_row = |lat: f64| (lat - g.south_lat_deg) / g.dlat_deg;
        let to_col = |lon: f64| (lon - g.west_lon_deg) / g.dlon_deg;
        let (r0, r1, c0, c1) = (to_row(south), to_row(north), to_col(west), to_col(east));
        let max_r = (g.rows - 1) as f64;
        let max_c = (g.cols - 1) as f64;
        if !(r0 >= 0.0 && c0 >= 0.0 && r1 <= max_r && c1 <= max_c) {
            let (lat_deg, lon_deg) = if r0 < 0.0 || c0 < 0.0 {
                (south, west)
            } else {
                (north, east)
            };
            return Err(EditError::OutsideDatabase { lat_deg, lon_deg });
        }
        // Cells the closed footprint touches (a footprint ending on a cell edge touches both).
        const EPS: f64 = 1e-9;
        let cell_range = |lo: f64, hi: f64, max: f64| {
            let last = (max as u32).saturating_sub(1);
            (
                ((lo - EPS).floor().max(0.0) as u32).min(last),
                ((hi + EPS).floor().max(0.0) as u32).min(last),
            )
        };
        if self.entries.len() >= MAX_EDITS {
            return Err(EditError::TooMany);
        }
        let (row_lo, row_hi) = cell_range(r0, r1, max_r);
        let (col_lo, col_hi) = cell_range(c0, c1, max_c);
        // The cells the shape itself reaches, with the share of each its footprint covers.
        let mut reached = Vec::new();
        for r in row_lo..=row_hi {
            for c in col_lo..=col_hi {
                let rect = self.cell_rect((r, c));
                if let Some([s0, s1, w0, w1]) = local.footprint_in(rect) {
                    let share = ((s1 - s0) / g.dlat_deg).clamp(0.0, 1.0)
                        * ((w1 - w0) / g.dlon_deg).clamp(0.0, 1.0);
                    reached.push(((r, c), share));
                }
                if reached.len() > (MAX_EDIT_POSTS / 4) as usize {
                    return Err(EditError::TooLarge {
                        posts: 4 * reached.len() as u64,
                    });
                }
            }
        }
        let wanted = (self.post_spacing_m / (local.feature_m / 4.0).max(0.02)).max(1.0);
        let mut split = wanted.log2().ceil().exp2().clamp(1.0, f64::from(MAX_SPLIT)) as u32;
        let posts = |split: u32| -> u64 {
            let f = f64::from(split);
            reached
                .iter()
                .map(|(_, share)| ((share.sqrt() * f + 2.0) * (share.sqrt() * f + 2.0)) as u64)
                .sum()
        };
        while split > 1 && posts(split) > MAX_EDIT_POSTS {
            split /= 2;
        }
        if posts(split) > MAX_EDIT_POSTS {
            return Err(EditError::TooLarge {
                posts: posts(split),
            });
        }
        let entry = Arc::new(Entry {
            edit,
            local,
            split,
            cells: [row_lo, row_hi, col_lo, col_hi],
        });
        self.entries.insert(id, Arc::clone(&entry));
        self.order.push(id);
        let last = self.last_sequences.entry(id.author).or_insert(id.sequence);
        *last = (*last).max(id.sequence);
        let mut touched = Vec::new();
        for ((r, c), _) in reached {
            {
                let slot = self.cells.entry((r, c)).or_insert_with(|| {
                    CellSlot::new(RefinedCell {
                        lattice: CellLattice::new(1, (0, 0), (2, 2), &[0.0; 4]),
                        min_m: 0.0,
                        max_m: 0.0,
                        block_max_m: vec![0.0],
                        blocks: (1, 1),
                        edits: Vec::new(),
                    })
                });
                Arc::make_mut(&mut slot.cell).edits.push(id);
                touched.push((r, c));
            }
        }
        self.rebuild(touched);
        Ok(Applied::Added)
    }

    /// Removes (heals) an edit: its cells return to what the other edits make of them. The
    /// edit removed.
    pub fn remove(&mut self, id: EditId) -> Result<TerrainEdit, EditError> {
        let Some(entry) = self.entries.remove(&id) else {
            return Err(EditError::Unknown {
                author_site: id.author.site,
                author_application: id.author.application,
                sequence: id.sequence,
            });
        };
        self.order.retain(|k| *k != id);
        if self.last_sequences.get(&id.author) == Some(&id.sequence) {
            match self
                .entries
                .keys()
                .filter(|k| k.author == id.author)
                .map(|k| k.sequence)
                .max()
            {
                Some(s) => self.last_sequences.insert(id.author, s),
                None => self.last_sequences.remove(&id.author),
            };
        }
        let [r0, r1, c0, c1] = entry.cells;
        let mut touched = Vec::new();
        for r in r0..=r1 {
            for c in c0..=c1 {
                if let Some(slot) = self.cells.get_mut(&(r, c)) {
                    Arc::make_mut(&mut slot.cell).edits.retain(|k| *k != id);
                    touched.push((r, c));
                }
            }
        }
        self.rebuild(touched);
        Ok(entry.edit.clone())
    }

    /// Recomputes the touched cells and their refined edge neighbours (whose T-junction maps
    /// depend on the touched cells' splits), each at its own edits' split.
    fn rebuild(&mut self, touched: Vec<CellKey>) {
        self.revision += 1;
        let mut tiles_changed: HashSet<(u32, u32)> = HashSet::new();
        let mut todo: HashSet<CellKey> = HashSet::new();
        let mut changed_blocks: HashSet<CellKey> =
            touched.iter().map(|&(r, c)| (r / 2, c / 2)).collect();
        for key in touched {
            if self
                .cells
                .get(&key)
                .is_some_and(|c| c.cell.edits.is_empty())
            {
                self.cells.remove(&key);
                let tile = self.tile_of(key);
                if let Some(members) = self.tile_members.get_mut(&tile) {
                    Arc::make_mut(members).remove(&key);
                }
                tiles_changed.insert(tile);
            }
            // The cell and its edge neighbours, whose edges meet its fine posts.
            for n in edge_neighbours(key).into_iter().flatten().chain([key]) {
                if self.cells.contains_key(&n) {
                    todo.insert(n);
                }
            }
        }
        for key in todo {
            if let Some(old) = self.cells.get(&key) {
                let edits = old.cell.edits.clone();
                let split = self.own_split(&edits);
                let coarser = edge_neighbours(key).map(|n| {
                    n.and_then(|n| self.cells.get(&n))
                        .map(|c| self.own_split(&c.cell.edits))
                        .filter(|s| *s < split)
                });
                let cell = self.compute_cell(key, split, coarser, edits);
                self.cells.insert(key, CellSlot::new(cell));
                changed_blocks.insert((key.0 / 2, key.1 / 2));
                let tile = self.tile_of(key);
                let members = self.tile_members.entry(tile).or_default();
                if !members.contains(&key) {
                    Arc::make_mut(members).insert(key);
                }
                tiles_changed.insert(tile);
            }
        }
        for tile in tiles_changed {
            self.tile_revisions.insert(tile, self.revision);
            let mut range = (0.0f32, 0.0f32);
            if let Some(members) = self.tile_members.get(&tile) {
                for key in members.iter() {
                    if let Some(slot) = self.cells.get(key) {
                        range.0 = range.0.max(slot.cell.max_m);
                        range.1 = range.1.min(slot.cell.min_m);
                    }
                }
            }
            if self.tile_members.get(&tile).is_some_and(|m| m.is_empty()) {
                self.tile_members.remove(&tile);
            }
            if range == (0.0, 0.0) {
                self.tiles.remove(&tile);
            } else {
                self.tiles.insert(tile, range);
            }
        }
        self.max_raise_m = self.tiles.values().fold(0.0, |m, r| m.max(r.0));
        self.update_blocks(changed_blocks);
    }

    /// Recomputes the block pyramid's blocks over changed cells, level by level from their
    /// four children.
    fn update_blocks(&mut self, mut changed: HashSet<CellKey>) {
        for k in 0..BLOCK_LEVELS {
            let mut parents = HashSet::with_capacity(changed.len());
            for &(br, bc) in &changed {
                let mut range = None::<(f32, f32)>;
                for (dr, dc) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    let child = (2 * br + dr, 2 * bc + dc);
                    let r = if k == 0 {
                        self.cells
                            .get(&child)
                            .map(|c| (c.cell.max_m.max(0.0), c.cell.min_m.min(0.0)))
                    } else {
                        self.blocks[k - 1].get(&child).copied()
                    };
                    if let Some((hi, lo)) = r {
                        range = Some(range.map_or((hi, lo), |(h, l)| (h.max(hi), l.min(lo))));
                    }
                }
                match range {
                    Some(r) => self.blocks[k].insert((br, bc), r),
                    None => self.blocks[k].remove(&(br, bc)),
                };
                parents.insert((br / 2, bc / 2));
            }
            changed = parents;
        }
    }

    /// The highest change (0 or more) and the lowest (0 or less) over finest cells `rows`
    /// and `cols` (half-open), or a range that holds it (whole aligned blocks): (0, 0) where
    /// nothing changed. At most nine look-ups.
    pub fn range_over_m(&self, rows: (u64, u64), cols: (u64, u64)) -> (f32, f32) {
        if self.cells.is_empty() || rows.1 <= rows.0 || cols.1 <= cols.0 {
            return (0.0, 0.0);
        }
        let span = (rows.1 - rows.0).max(cols.1 - cols.0);
        // Blocks at least half the span: at most three a side.
        let k = (63 - span.leading_zeros() as usize).clamp(1, BLOCK_LEVELS) - 1;
        let shift = k + 1;
        let mut range = (0.0f32, 0.0f32);
        for br in (rows.0 >> shift)..=((rows.1 - 1) >> shift) {
            for bc in (cols.0 >> shift)..=((cols.1 - 1) >> shift) {
                let (Ok(br), Ok(bc)) = (u32::try_from(br), u32::try_from(bc)) else {
                    continue;
                };
                if let Some(&(hi, lo)) = self.blocks[k].get(&(br, bc)) {
                    range = (range.0.max(hi), range.1.min(lo));
                }
            }
        }
        range
    }

    /// The split a cell's edits ask for: the finest of theirs.
    fn own_split(&self, edits: &[EditId]) -> u32 {
        edits
            .iter()
            .filter_map(|id| self.entries.get(id))
            .map(|e| e.split)
            .max()
            .unwrap_or(1)
    }

    /// A finest cell as (south, north, west, east), degrees.
    fn cell_rect(&self, (r, c): CellKey) -> [f64; 4] {
        let g = &self.grid;
        [
            g.south_lat_deg + f64::from(r) * g.dlat_deg,
            g.south_lat_deg + f64::from(r + 1) * g.dlat_deg,
            g.west_lon_deg + f64::from(c) * g.dlon_deg,
            g.west_lon_deg + f64::from(c + 1) * g.dlon_deg,
        ]
    }

    fn tile_of(&self, (r, c): CellKey) -> (u32, u32) {
        (r / self.tile_cells, c / self.tile_cells)
    }

    /// The window, fine posts and changes of one cell from its edits, its edges' posts set
    /// on the edges of the neighbours split more coarsely (`coarser`: west, east, south,
    /// north), so that their surfaces meet without a crack.
    fn compute_cell(
        &self,
        (r, c): CellKey,
        split: u32,
        coarser: [Option<u32>; 4],
        edits: Vec<EditId>,
    ) -> RefinedCell {
        let g = &self.grid;
        let f = f64::from(split);
        // In the edits' identity order, so every IG sums a cell's changes the same way.
        let mut entries: Vec<&Entry> = edits
            .iter()
            .filter_map(|id| self.entries.get(id).map(|e| &**e))
            .collect();
        entries.sort_by_key(|e| e.edit.id());
        let rect = self.cell_rect((r, c));
        // The window: the footprints' union clipped to the cell, in sub-cells.
        let (mut a0, mut a1, mut b0, mut b1) = (split, 0u32, split, 0u32);
        for e in &entries {
            let Some([south, north, west, east]) = e.local.footprint_in(rect) else {
                continue;
            };
            let to_fine_col = |lon: f64| ((lon - g.west_lon_deg) / g.dlon_deg - f64::from(c)) * f;
            let to_fine_row = |lat: f64| ((lat - g.south_lat_deg) / g.dlat_deg - f64::from(r)) * f;
            let clamp = |x: f64| x.clamp(0.0, f) as u32;
            a0 = a0.min(clamp(to_fine_col(west).floor()));
            a1 = a1.max(clamp(to_fine_col(east).ceil()));
            b0 = b0.min(clamp(to_fine_row(south).floor()));
            b1 = b1.max(clamp(to_fine_row(north).ceil()));
        }
        let widen = |lo: u32, hi: u32| {
            if hi > lo {
                (lo, hi)
            } else if lo < split {
                (lo, lo + 1)
            } else {
                (split - 1, split)
            }
        };
        let (a0, a1) = widen(a0.min(a1), a1);
        let (b0, b1) = widen(b0.min(b1), b1);
        let (na, nb) = (a1 - a0 + 1, b1 - b0 + 1);
        let mut deltas_m = Vec::with_capacity((na * nb) as usize);
        for b in 0..nb {
            let lat = g.south_lat_deg + (f64::from(r) + f64::from(b0 + b) / f) * g.dlat_deg;
            for a in 0..na {
                let lon = g.west_lon_deg + (f64::from(c) + f64::from(a0 + a) / f) * g.dlon_deg;
                let d = entries
                    .iter()
                    .map(|e| e.local.delta_m(lat, lon))
                    .sum::<f64>();
                // Kept in the lattice's steps.
                deltas_m.push(lattice_rounded_m(
                    d.clamp(-MAX_EDIT_HEIGHT_M, MAX_EDIT_HEIGHT_M) as f32,
                ));
            }
        }
        // The T-junction map: along an edge shared with a coarser cell, the posts between
        // the coarser cell's take the line between those (outside the window the change is
        // nothing, on both sides), to within half the lattice's step.
        let (na_u, nb_u) = (na as usize, nb as usize);
        for (side, coarse) in coarser.iter().enumerate() {
            let Some(coarse) = *coarse else { continue };
            let k = split / coarse.max(1);
            // The edge's posts: (index in the window, fine index along the edge), if the
            // window reaches the edge.
            let (reaches, along0, count, stride, first) = match side {
                0 => (a0 == 0, b0, nb, na_u, 0),
                1 => (a1 == split, b0, nb, na_u, na_u - 1),
                2 => (b0 == 0, a0, na, 1, 0),
                _ => (b1 == split, a0, na, 1, (nb_u - 1) * na_u),
            };
            if !reaches || k <= 1 {
                continue;
            }
            let value = |t: u32| -> f32 {
                if t < along0 || t >= along0 + count {
                    0.0
                } else {
                    deltas_m[first + (t - along0) as usize * stride]
                }
            };
            let fixed: Vec<(usize, f32)> = (0..count)
                .filter_map(|i| {
                    let t = along0 + i;
                    let off = t % k;
                    (off != 0).then(|| {
                        let (lo, hi) = (t - off, t - off + k);
                        let w = off as f32 / k as f32;
                        (
                            first + i as usize * stride,
                            lattice_rounded_m(value(lo) * (1.0 - w) + value(hi) * w),
                        )
                    })
                })
                .collect();
            for (index, v) in fixed {
                deltas_m[index] = v;
            }
        }
        let (min_m, max_m) = deltas_m
            .iter()
            .fold((0.0f32, 0.0f32), |(lo, hi), &d| (lo.min(d), hi.max(d)));
        let blocks = (
            (na - 1).div_ceil(BLOCK_SUB_CELLS),
            (nb - 1).div_ceil(BLOCK_SUB_CELLS),
        );
        let mut block_max_m = vec![f32::NEG_INFINITY; (blocks.0 * blocks.1) as usize];
        for b in 0..nb {
            // A post on a block's edge belongs to both blocks.
            let rows = [b / BLOCK_SUB_CELLS, b.saturating_sub(1) / BLOCK_SUB_CELLS];
            for a in 0..na {
                let d = deltas_m[(b * na + a) as usize];
                let cols = [a / BLOCK_SUB_CELLS, a.saturating_sub(1) / BLOCK_SUB_CELLS];
                for r in rows {
                    for c in cols {
                        if r < blocks.1 && c < blocks.0 {
                            let m = &mut block_max_m[(r * blocks.0 + c) as usize];
                            *m = m.max(d);
                        }
                    }
                }
            }
        }
        RefinedCell {
            lattice: CellLattice::new(split, (a0, b0), (na, nb), &deltas_m),
            min_m,
            max_m,
            block_max_m,
            blocks,
            edits,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> GeoGrid {
        GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 1.0 / 3600.0,
            dlon_deg: 1.0 / 3600.0,
            rows: 257,
            cols: 257,
        }
    }

    fn crater(seq: u32, lat: f64, lon: f64, radius_m: f64, depth_m: f64) -> TerrainEdit {
        TerrainEdit {
            author: EditAuthor {
                site: 1,
                application: 2,
            },
            sequence: seq,
            time_utc_s: 1.8e9,
            shape: EditShape::Crater {
                centre: GeoPoint {
                    lat_deg: lat,
                    lon_deg: lon,
                },
                radius_m,
                depth_m,
                lip_radius_m: 1.25 * radius_m,
                lip_height_m: 0.25 * depth_m,
            },
        }
    }

    #[test]
    fn the_block_pyramid_bounds_every_range_of_cells_and_follows_healing() {
        let mut layer = EditLayer::new(grid(), 64);
        let places = [
            (36.01, -120.99),
            (36.0105, -120.9895),
            (36.05, -120.95),
            (36.06, -120.93),
        ];
        for (i, &(lat, lon)) in places.iter().enumerate() {
            layer
                .apply(crater(
                    i as u32 + 1,
                    lat,
                    lon,
                    3.0 + i as f64,
                    1.0 + 0.5 * i as f64,
                ))
                .expect("crater");
        }
        let brute = |layer: &EditLayer, rows: (u64, u64), cols: (u64, u64)| {
            layer
                .cells()
                .filter(|((r, c), _)| {
                    (rows.0..rows.1).contains(&u64::from(*r))
                        && (cols.0..cols.1).contains(&u64::from(*c))
                })
                .fold((0.0f32, 0.0f32), |(h, l), (_, cell)| {
                    (h.max(cell.max_m), l.min(cell.min_m))
                })
        };
        let mut state = 7u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % n
        };
        let mut nonzero = 0;
        for _ in 0..2000 {
            let (r0, c0) = (next(256), next(256));
            let span = 1 + next(64);
            let rows = (r0, (r0 + span).min(256));
            let cols = (c0, (c0 + span).min(256));
            let exact = brute(&layer, rows, cols);
            let got = layer.range_over_m(rows, cols);
            assert!(
                got.0 >= exact.0 && got.1 <= exact.1,
                "{rows:?} {cols:?}: {got:?} < {exact:?}"
            );
            nonzero += usize::from(exact != (0.0, 0.0));
        }
        assert!(nonzero > 20, "{nonzero}");
        // The whole database; and an aligned node away from every edit sees none.
        let all = brute(&layer, (0, 256), (0, 256));
        assert_eq!(layer.range_over_m((0, 256), (0, 256)), all);
        assert!(all.0 > 0.3 && all.1 < -2.0, "{all:?}");
        assert_eq!(layer.range_over_m((128, 144), (0, 16)), (0.0, 0.0));
        // Healed: nothing left anywhere.
        for i in 0..places.len() {
            let id = EditId {
                author: EditAuthor {
                    site: 1,
                    application: 2,
                },
                sequence: i as u32 + 1,
            };
            layer.remove(id).expect("heal");
        }
        assert_eq!(layer.range_over_m((0, 256), (0, 256)), (0.0, 0.0));
        assert!(layer.blocks.iter().all(|b| b.is_empty()));
    }

    #[test]
    fn a_crater_is_carried_finer_than_the_posts_and_follows_its_shape() {
        let mut layer = EditLayer::new(grid(), 64);
        let (lat, lon) = (36.03, -120.97);
        assert_eq!(
            layer.apply(crater(1, lat, lon, 1.5, 0.6)),
            Ok(Applied::Added)
        );
        // The centre and half the radius: the lattice within 5 cm of the shape.
        let (mn, me) = cig_geo::metres_per_degree(lat);
        for (dx, dy) in [(0.0, 0.0), (0.75, 0.0), (0.0, -0.75), (0.53, 0.53)] {
            let (la, lo) = (lat + dy / mn, lon + dx / me);
            let shape = layer.shape_delta_m(la, lo);
            let lattice = layer.delta_m(la, lo);
            assert!((shape - lattice).abs() < 0.05, "{shape} vs {lattice}");
        }
        assert!((layer.shape_delta_m(lat, lon) + 0.6).abs() < 1e-9);
        // Beyond the lip nothing changed.
        assert_eq!(layer.delta_m(lat + 3.0 / mn, lon), 0.0);
        assert!(layer.cells().all(|(_, c)| c.lattice.split > 1));
    }

    #[test]
    fn edits_add_and_a_second_crater_deepens_the_first() {
        let mut layer = EditLayer::new(grid(), 64);
        let (lat, lon) = (36.03, -120.97);
        layer.apply(crater(1, lat, lon, 2.0, 0.5)).expect("first");
        let one = layer.delta_m(lat, lon);
        layer.apply(crater(2, lat, lon, 2.0, 0.5)).expect("second");
        let two = layer.delta_m(lat, lon);
        assert!(two < one - 0.4, "{one} then {two}");
        // A re-announced edit changes nothing.
        let revision = layer.revision();
        assert_eq!(
            layer.apply(crater(2, lat, lon, 2.0, 0.5)),
            Ok(Applied::Known)
        );
        assert_eq!(layer.revision(), revision);
        // Order does not matter.
        let mut other = EditLayer::new(grid(), 64);
        other.apply(crater(2, lat, lon, 2.0, 0.5)).expect("b");
        other.apply(crater(1, lat, lon, 2.0, 0.5)).expect("a");
        assert_eq!(other.delta_m(lat, lon), two);
    }

    #[test]
    fn healing_returns_cells_to_their_coarse_form() {
        let mut layer = EditLayer::new(grid(), 64);
        let (lat, lon) = (36.03, -120.97);
        layer.apply(crater(1, lat, lon, 2.0, 0.5)).expect("first");
        let id = EditId {
            author: EditAuthor {
                site: 1,
                application: 2,
            },
            sequence: 1,
        };
        layer.remove(id).expect("remove");
        assert_eq!(layer.cells().count(), 0);
        assert_eq!(layer.delta_m(lat, lon), 0.0);
        assert_eq!(layer.tile_range_m(0, 0), (0.0, 0.0));
        assert!(layer.remove(id).is_err());
    }

    #[test]
    fn neighbouring_cells_split_differently_meet_without_a_step() {
        let mut layer = EditLayer::new(grid(), 64);
        // A post at row 100, col 100: a small crater right on it touches four cells, a big
        // one north of it asks for a coarser split in the cells it alone touches.
        let g = grid();
        let lat = g.south_lat_deg + 100.0 * g.dlat_deg;
        let lon = g.west_lon_deg + 100.0 * g.dlon_deg;
        layer.apply(crater(1, lat, lon, 0.6, 0.3)).expect("small");
        layer
            .apply(crater(2, lat + 40.0 * g.dlat_deg / 30.0, lon, 25.0, 2.0))
            .expect("big");
        let splits: HashSet<u32> = layer.cells().map(|(_, c)| c.lattice.split).collect();
        assert!(splits.len() >= 2, "{splits:?}");
        // Along every shared edge the two cells give the same change.
        let mut edges = 0;
        for ((r, c), cell) in layer.cells() {
            let here_diag = Diagonal::of_cell(r as usize, c as usize);
            for (other, on_edge) in [((r, c + 1), true), ((r + 1, c), false)] {
                let Some(next) = layer.cell(other) else {
                    continue;
                };
                edges += 1;
                let next_diag = Diagonal::of_cell(other.0 as usize, other.1 as usize);
                for k in 0..=256 {
                    let t = f64::from(k) / 256.0;
                    let (here, there) = if on_edge {
                        (
                            cell.delta_m(1.0, t, here_diag),
                            next.delta_m(0.0, t, next_diag),
                        )
                    } else {
                        (
                            cell.delta_m(t, 1.0, here_diag),
                            next.delta_m(t, 0.0, next_diag),
                        )
                    };
                    // Within half the lattice's step: the T-junction map's posts lie on the
                    // coarser edge to the step they are kept in.
                    assert!(
                        (here - there).abs() <= 0.5 * f64::from(LATTICE_STEP_M) + 1e-6,
                        "{:?} ({}) / {:?} ({}) at {t}: {here} vs {there}",
                        (r, c),
                        cell.lattice.split,
                        other,
                        next.lattice.split
                    );
                }
            }
            // The window's border carries no change unless it is the cell's edge.
            let nb = cell.lattice.posts.1 as usize;
            if cell.lattice.origin.0 > 0 {
                for b in 0..nb {
                    assert_eq!(cell.lattice.post_m(0, b), 0.0);
                }
            }
        }
        assert!(edges >= 4, "{edges} shared edges");
    }

    #[test]
    fn bad_edits_are_refused_whole() {
        let mut layer = EditLayer::new(grid(), 64);
        for e in [
            crater(1, 36.03, -120.97, -1.0, 0.5),
            crater(1, 36.03, -120.97, f64::NAN, 0.5),
            crater(1, 36.03, -120.97, 2.0, f64::INFINITY),
            crater(1, 35.0, -120.97, 2.0, 0.5),
            crater(1, 36.0, -121.0, 2.0, 0.5),
        ] {
            let err = layer.apply(e).expect_err("refused");
            assert!(!err.to_string().contains('\n'));
        }
        assert!(layer.is_empty());
        assert_eq!(layer.cells().count(), 0);
        let patch = TerrainEdit {
            shape: EditShape::HeightPatch {
                south_west: GeoPoint {
                    lat_deg: 36.02,
                    lon_deg: -120.98,
                },
                spacing_m: 1.0,
                cols: 4,
                rows: 4,
                deltas_m: vec![1.0; 15],
            },
            ..crater(2, 0.0, 0.0, 1.0, 1.0)
        };
        assert!(matches!(
            layer.apply(patch),
            Err(EditError::PatchSize { .. })
        ));
    }

    #[test]
    fn a_long_thin_diagonal_rut_refines_only_the_cells_it_crosses_within_the_post_budget() {
        let mut layer = EditLayer::new(grid(), 64);
        let from = GeoPoint {
            lat_deg: 36.005,
            lon_deg: -120.995,
        };
        let (mn, me) = cig_geo::metres_per_degree(from.lat_deg);
        let to = GeoPoint {
            lat_deg: from.lat_deg + 1400.0 / mn,
            lon_deg: from.lon_deg + 1400.0 / me,
        };
        let rut = TerrainEdit {
            shape: EditShape::Rut {
                from,
                to,
                width_m: 0.05,
                depth_m: 0.02,
            },
            ..crater(1, 0.0, 0.0, 1.0, 1.0)
        };
        layer.apply(rut).expect("the split is lowered to fit");
        let cells = layer.cells().count();
        // A diagonal 2 km long crosses about 2 x 66 cells of 30 m (and their corners'
        // neighbours), not the 66 x 66 of its bounding box.
        assert!(cells < 400, "{cells} cells refined");
        let posts: usize = layer
            .cells()
            .map(|(_, c)| (c.lattice.posts.0 * c.lattice.posts.1) as usize)
            .sum();
        assert!(
            posts as u64 <= MAX_EDIT_POSTS + MAX_EDIT_POSTS / 4,
            "{posts} posts"
        );
        // Still there on the lattice.
        let mid = (
            0.5 * (from.lat_deg + to.lat_deg),
            0.5 * (from.lon_deg + to.lon_deg),
        );
        assert!(layer.shape_delta_m(mid.0, mid.1) < -0.019);
    }

    #[test]
    fn a_ditch_cuts_and_piles_its_spoil_on_the_chosen_side() {
        let mut layer = EditLayer::new(grid(), 64);
        let from = GeoPoint {
            lat_deg: 36.03,
            lon_deg: -120.97,
        };
        let (mn, me) = cig_geo::metres_per_degree(from.lat_deg);
        let to = GeoPoint {
            lat_deg: from.lat_deg,
            lon_deg: from.lon_deg + 40.0 / me,
        };
        let ditch = TerrainEdit {
            shape: EditShape::Ditch {
                from,
                to,
                width_m: 4.0,
                depth_m: 2.0,
                spoil: SpoilSide::Left,
            },
            ..crater(1, 0.0, 0.0, 1.0, 1.0)
        };
        layer.apply(ditch).expect("ditch");
        let mid = from.lon_deg + 20.0 / me;
        assert!((layer.delta_m(from.lat_deg, mid) + 2.0).abs() < 0.05);
        // Left of an eastward run is north.
        let berm = layer.delta_m(from.lat_deg + 5.0 / mn, mid);
        assert!(berm > 1.0, "{berm}");
        assert!(layer.delta_m(from.lat_deg - 5.0 / mn, mid).abs() < 1e-6);
        // Spoil volume about the cut's, bulked.
        let step = 0.1;
        let (mut cut, mut fill) = (0.0, 0.0);
        for k in -150..150 {
            let d = layer.shape_delta_m(from.lat_deg + f64::from(k) * step / mn, mid);
            if d < 0.0 {
                cut -= d * step;
            } else {
                fill += d * step;
            }
        }
        assert!((fill / cut - 1.25).abs() < 0.05, "{cut} {fill}");
    }
}
