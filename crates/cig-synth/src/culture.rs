//! Culture: where trees, bushes, buildings, garden walls, fences and power poles stand, as
//! [`CulturePlacement`]s for `cig_terrain::culture`.
//!
//! # Algorithm
//!
//! * **Vegetation by material** ([`scatter_by_material`]), on any raster with materials (a
//!   synthetic one, or an imported DEM after `cig_terrain::build::prepare_raster` derived them).
//!   [`CultureRules`] gives trees and bushes per hectare for forest, grass, sand and dry clay;
//!   water, rock, snow and roads get none, and neither does any post next to water or a road.
//!   Each post's cell (half a spacing about the post) is cut into sub-cells of side
//!   `sqrt(10000 / 2d)` metres for a density `d` per hectare, and each sub-cell holds at most
//!   one object, at a jittered position in its middle 80 % (a jittered grid: stratified, so
//!   objects never clump, a cheap stand-in for blue noise), kept with probability `d m A` (`A`
//!   the sub-cell's area in hectares, so the expected count is the rule's). The stand factor
//!   `m = clamp(1 + 4 c n, 0, 2)`, from a low-frequency fBm `n` (wavelength
//!   `stand_wavelength_m`, contrast `c`), gathers trees into stands with clearings and edges
//!   instead of a uniform carpet; it is symmetric about 1, so the mean density stays the rule's.
//!   A tree is a conifer with a probability that rises linearly with the post's altitude from
//!   `conifer_fraction` at `conifer_rise_from_m` to 1 at `conifer_only_above_m`. Sizes vary
//!   per object (triangular distributions): conifers 12-28 m tall with crowns 0.26-0.38 of their
//!   height, broadleaf trees 10-22 m with crowns 0.55-0.85 of it, bushes 0.8-3 m.
//! * **Settlements** ([`settlement_culture`]): every road centre line is walked in plots of
//!   `plot_frontage_m` (jittered 0.8-1.2); within `radius_m` of a settlement centre each side of
//!   each plot gets rows of buildings set back from the road, more rows and fuller plots near
//!   the centre (up to `max_rows` rows `row_depth_m` apart, filled with probability falling from
//!   0.92 at the centre to 0.37 at the edge), larger buildings in the front row near the centre,
//!   a shed behind some houses and a garden wall or fence along the front and one side of some
//!   front plots. Outside the settlements a farmstead (a house and one to three barns) stands
//!   beside a road every `farmstead_spacing_m` on average. Buildings are headed along the road
//!   at their plot (either way round). An object is placed only where its footprint (an
//!   oriented rectangle) keeps clear of every road and river ribbon (exact rectangle-segment
//!   distances), of water posts, of the database's edge and of every object placed before it
//!   (separating axes); buildings also need ground that is not rock or snow, a footprint that
//!   rises less than a quarter of its diagonal (bilinear heights at its corners), and their
//!   own road to be the nearest road (within 5 m), so that rows behind one road do not end up
//!   beside another.
//! * **Power poles**: every `pole_spacing_m` along each paved road, 2.5 m beyond its right
//!   edge, where the spot keeps clear of other roads, rivers and water (so lines break at
//!   junctions and bridges).
//! * [`place_culture`] (the synthetic database): settlements and poles first, then vegetation
//!   everywhere except on the posts under and next to their footprints.
//!
//! # Source
//!
//! The GE level-of-detail study (source 004 §1.2, §2.5): trees, houses and poles are the
//! culture a trainee reads for speed, height and distance over the ground, so they are placed
//! in their thousands and in believable patterns (woods with clearings and edges, houses lined
//! along roads, pole lines beside them). NPSNET (source 003) keeps such features with the
//! terrain tiles; `cig_terrain::culture::bin_placements` does that with these placements.
//!
//! # Determinism
//!
//! Every random choice is a SplitMix64 hash of the seed and of what is being decided (post row
//! and column and sub-cell; road index, plot and side), never a generator shared across rows:
//! rows of posts are scattered in parallel and joined in row order; settlements are built
//! serially in feature order; spatial indexes are `BTreeMap`s; arc tangents, powers and
//! hypotenuses come from `libm` (only IEEE-exact operations otherwise). The same raster, features, rules and seed give identical placements on every
//! machine and thread count.
//!
//! # Limits
//!
//! Settlements are frontages of the roads given (no street grid of their own); deeper rows
//! stand behind the front row without a lane to them. Plots are laid out in a flat metric
//! frame about the database's centre latitude, so headings of buildings far from it may differ
//! from their road's by up to the frame's distortion (under 0.1 degree 25 km from it at 36
//! degrees). Objects
//! are not checked against lakes given only as features (only as water posts). Vegetation
//! does not look at slope beyond the material (rock gets none), and trees are not thinned at
//! forest edges. Power lines between poles are not placed.

use crate::noise::{hash2, mix64, unit_from_hash, Layer};
use crate::{metres_per_degree, SynthReport};
use cig_terrain::culture::{CultureKind, CulturePlacement};
use cig_terrain::features::{Feature, LineKind};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use rayon::prelude::*;
use serde::Deserialize;
use std::collections::BTreeMap;

/// Square metres in a hectare.
const HECTARE_M2: f64 = 10_000.0;
/// Most trees per hectare a rule may ask for.
pub const MAX_TREES_PER_HA: f64 = 1_000.0;
/// Most bushes per hectare a rule may ask for.
pub const MAX_BUSHES_PER_HA: f64 = 2_000.0;

/// Trees and bushes on one material, per hectare.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VegetationRule {
    /// Trees per hectare (mean over the material, clearings included).
    pub trees_per_ha: f64,
    /// Bushes per hectare.
    pub bushes_per_ha: f64,
}

impl Default for VegetationRule {
    fn default() -> VegetationRule {
        VegetationRule {
            trees_per_ha: 0.0,
            bushes_per_ha: 0.0,
        }
    }
}

/// How buildings, garden walls, fences and power poles are laid out along roads.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SettlementRules {
    /// Radius of a settlement about its centre, metres (0: no settlements, farmsteads only).
    pub radius_m: f64,
    /// Road frontage of a plot, metres.
    pub plot_frontage_m: f64,
    /// Distance between rows of buildings behind the road, metres.
    pub row_depth_m: f64,
    /// Rows of buildings at a settlement's centre (one at its edge).
    pub max_rows: u32,
    /// Share of houses with a shed behind them.
    pub shed_fraction: f64,
    /// Share of front-row buildings at a settlement's centre that are larger buildings (falling
    /// to none at 0.4 of the radius).
    pub large_building_fraction: f64,
    /// Share of front-row houses whose plot has a garden wall or fence.
    pub enclosed_fraction: f64,
    /// Share of those enclosures that are walls (the others are fences).
    pub wall_fraction: f64,
    /// Mean distance between farmsteads along a road side outside the settlements, metres
    /// (0: none).
    pub farmstead_spacing_m: f64,
    /// Distance between power poles along paved roads, metres (0: none).
    pub pole_spacing_m: f64,
}

impl Default for SettlementRules {
    fn default() -> SettlementRules {
        SettlementRules {
            radius_m: 1_600.0,
            plot_frontage_m: 24.0,
            row_depth_m: 30.0,
            max_rows: 5,
            shed_fraction: 0.5,
            large_building_fraction: 0.35,
            enclosed_fraction: 0.45,
            wall_fraction: 0.4,
            farmstead_spacing_m: 1_000.0,
            pole_spacing_m: 50.0,
        }
    }
}

/// What culture to place: densities per material, the conifer share and how stands gather,
/// and the settlement layout. Reads from TOML (unknown keys refused, missing keys default);
/// check with [`CultureRules::validate`].
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CultureRules {
    pub forest: VegetationRule,
    pub grass: VegetationRule,
    pub sand: VegetationRule,
    pub dry_clay: VegetationRule,
    /// Share of conifers among trees up to `conifer_rise_from_m`, in 0..1.
    pub conifer_fraction: f64,
    /// Altitude above which the conifer share rises, metres.
    pub conifer_rise_from_m: f64,
    /// Altitude from which every tree is a conifer, metres (not below `conifer_rise_from_m`).
    pub conifer_only_above_m: f64,
    /// Wavelength of the noise that gathers vegetation into stands, metres.
    pub stand_wavelength_m: f64,
    /// How strongly stands gather, in 0..1: 0 is a uniform density; 1 leaves about a tenth
    /// of the ground in clearings and a tenth at twice the mean density (0.8: about 6 %).
    pub stand_contrast: f64,
    pub settlements: SettlementRules,
}

impl Default for CultureRules {
    /// Open woodland and oak savanna, as around Fort Hunter Liggett: 35 trees per hectare of
    /// forest (the densest stands twice that), a tree and a few bushes per hectare of grass,
    /// rare bushes on sand and dry clay; a third of the trees conifers below 700 m, all of them
    /// above 1800 m.
    fn default() -> CultureRules {
        CultureRules {
            forest: VegetationRule {
                trees_per_ha: 35.0,
                bushes_per_ha: 6.0,
            },
            grass: VegetationRule {
                trees_per_ha: 1.0,
                bushes_per_ha: 2.5,
            },
            sand: VegetationRule {
                trees_per_ha: 0.0,
                bushes_per_ha: 0.8,
            },
            dry_clay: VegetationRule {
                trees_per_ha: 0.0,
                bushes_per_ha: 0.4,
            },
            conifer_fraction: 0.3,
            conifer_rise_from_m: 700.0,
            conifer_only_above_m: 1_800.0,
            stand_wavelength_m: 500.0,
            stand_contrast: 0.8,
            settlements: SettlementRules::default(),
        }
    }
}

/// A culture rule out of its range.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CultureRulesError {
    #[error("culture rules: {name} = {value}: {reason}")]
    Invalid {
        /// The rule, as named in a rules file (`forest.trees_per_ha`).
        name: String,
        value: f64,
        reason: &'static str,
    },
}

fn check(
    name: &str,
    value: f64,
    lo: f64,
    hi: f64,
    reason: &'static str,
) -> Result<(), CultureRulesError> {
    if value >= lo && value <= hi {
        Ok(())
    } else {
        Err(CultureRulesError::Invalid {
            name: name.to_string(),
            value,
            reason,
        })
    }
}

/// A spacing that is 0 (off) or within `lo..=hi`.
fn check_optional(
    name: &str,
    value: f64,
    lo: f64,
    hi: f64,
    reason: &'static str,
) -> Result<(), CultureRulesError> {
    if value == 0.0 {
        Ok(())
    } else {
        check(name, value, lo, hi, reason)
    }
}

const FRACTION: &str = "must be a fraction in 0..1";

impl SettlementRules {
    /// Checks every value; the error names the first bad one.
    ///
    /// # Errors
    /// When a value is out of its range (or not a number).
    pub fn validate(&self) -> Result<(), CultureRulesError> {
        check(
            "settlements.radius_m",
            self.radius_m,
            0.0,
            20_000.0,
            "must be within 0..20000 m",
        )?;
        check(
            "settlements.plot_frontage_m",
            self.plot_frontage_m,
            12.0,
            200.0,
            "must be within 12..200 m",
        )?;
        check(
            "settlements.row_depth_m",
            self.row_depth_m,
            15.0,
            200.0,
            "must be within 15..200 m",
        )?;
        check(
            "settlements.max_rows",
            f64::from(self.max_rows),
            1.0,
            8.0,
            "must be within 1..8",
        )?;
        for (name, value) in [
            ("settlements.shed_fraction", self.shed_fraction),
            (
                "settlements.large_building_fraction",
                self.large_building_fraction,
            ),
            ("settlements.enclosed_fraction", self.enclosed_fraction),
            ("settlements.wall_fraction", self.wall_fraction),
        ] {
            check(name, value, 0.0, 1.0, FRACTION)?;
        }
        check_optional(
            "settlements.farmstead_spacing_m",
            self.farmstead_spacing_m,
            100.0,
            1.0e6,
            "must be 0 (none) or within 100..1000000 m",
        )?;
        check_optional(
            "settlements.pole_spacing_m",
            self.pole_spacing_m,
            10.0,
            1_000.0,
            "must be 0 (none) or within 10..1000 m",
        )
    }
}

impl CultureRules {
    /// Checks every value; the error names the first bad one (negative densities, fractions
    /// outside 0..1, altitudes out of order …).
    ///
    /// # Errors
    /// When a value is out of its range (or not a number).
    pub fn validate(&self) -> Result<(), CultureRulesError> {
        for (material, rule) in [
            ("forest", &self.forest),
            ("grass", &self.grass),
            ("sand", &self.sand),
            ("dry_clay", &self.dry_clay),
        ] {
            check(
                &format!("{material}.trees_per_ha"),
                rule.trees_per_ha,
                0.0,
                MAX_TREES_PER_HA,
                "must be a density within 0..1000 per hectare",
            )?;
            check(
                &format!("{material}.bushes_per_ha"),
                rule.bushes_per_ha,
                0.0,
                MAX_BUSHES_PER_HA,
                "must be a density within 0..2000 per hectare",
            )?;
        }
        check(
            "conifer_fraction",
            self.conifer_fraction,
            0.0,
            1.0,
            FRACTION,
        )?;
        check("stand_contrast", self.stand_contrast, 0.0, 1.0, FRACTION)?;
        check(
            "conifer_rise_from_m",
            self.conifer_rise_from_m,
            -1.0e4,
            1.0e4,
            "must be an altitude within -10000..10000 m",
        )?;
        check(
            "conifer_only_above_m",
            self.conifer_only_above_m,
            self.conifer_rise_from_m,
            1.0e4,
            "must be an altitude from conifer_rise_from_m up to 10000 m",
        )?;
        check(
            "stand_wavelength_m",
            self.stand_wavelength_m,
            20.0,
            1.0e5,
            "must be within 20..100000 m",
        )?;
        self.settlements.validate()
    }

    /// Share of conifers among trees at an altitude.
    pub fn conifer_share(&self, altitude_m: f64) -> f64 {
        let (lo, hi) = (self.conifer_rise_from_m, self.conifer_only_above_m);
        let t = if altitude_m <= lo {
            0.0
        } else if altitude_m >= hi {
            1.0
        } else {
            (altitude_m - lo) / (hi - lo)
        };
        self.conifer_fraction + (1.0 - self.conifer_fraction) * t
    }

    fn vegetation(&self, material: Material) -> Option<&VegetationRule> {
        match material {
            Material::Forest => Some(&self.forest),
            Material::Grass => Some(&self.grass),
            Material::Sand => Some(&self.sand),
            Material::DryClay => Some(&self.dry_clay),
            Material::Water
            | Material::Rock
            | Material::Snow
            | Material::PavedRoad
            | Material::DirtRoad => None,
        }
    }
}

// ---------------------------------------------------------------- random streams

/// Salts that keep the hashes of different decisions apart.
const SALT_SCATTER: u64 = 0x6375_6c74_7572_6531;
const SALT_SETTLE: u64 = 0x7365_7474_6c65_6d31;
const SALT_POLES: u64 = 0x706f_6c65_7331_0001;
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// A SplitMix64 stream from a hash: the decisions about one object, in a fixed order.
struct Stream(u64);

impl Stream {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix64(self.0)
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        unit_from_hash(self.next_u64())
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Triangular in `[lo, hi)`, peaked in the middle.
    fn triangular(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * 0.5 * (self.unit() + self.unit())
    }

    fn variant(&mut self) -> u8 {
        (self.next_u64() >> 56) as u8
    }
}

// ---------------------------------------------------------------- vegetation

/// Trees or bushes of one material.
struct VegetationLayer {
    trees: bool,
    density_per_ha: f64,
    /// Side of a sub-cell that holds at most one object at twice the density, metres.
    pitch_m: f64,
    seed: u64,
    stands: Layer,
}

/// The layers of every material, by its byte.
fn vegetation_layers(rules: &CultureRules, seed: u64) -> Vec<Vec<VegetationLayer>> {
    Material::ALL
        .iter()
        .map(|&m| {
            let Some(rule) = rules.vegetation(m) else {
                return Vec::new();
            };
            [(true, rule.trees_per_ha), (false, rule.bushes_per_ha)]
                .into_iter()
                .filter(|&(_, d)| d > 0.0)
                .map(|(trees, d)| {
                    let layer_seed = mix64(seed ^ (u64::from(m.to_byte()) << 8 | u64::from(trees)));
                    VegetationLayer {
                        trees,
                        density_per_ha: d,
                        pitch_m: (HECTARE_M2 / (2.0 * d)).sqrt(),
                        seed: layer_seed,
                        stands: Layer::new(layer_seed, rules.stand_wavelength_m),
                    }
                })
                .collect()
        })
        .collect()
}

/// Posts where no vegetation goes: water and roads, every post next to them, and `keep_out`.
fn blocked_posts(grid: &GeoGrid, material: &[Material], keep_out: Option<&[bool]>) -> Vec<bool> {
    let (rows, cols) = (grid.rows, grid.cols);
    let mut out = match keep_out {
        Some(k) if k.len() == material.len() => k.to_vec(),
        _ => vec![false; material.len()],
    };
    for r in 0..rows {
        for c in 0..cols {
            let m = material[r * cols + c];
            if !matches!(
                m,
                Material::Water | Material::PavedRoad | Material::DirtRoad
            ) {
                continue;
            }
            for rr in r.saturating_sub(1)..=(r + 1).min(rows - 1) {
                for cc in c.saturating_sub(1)..=(c + 1).min(cols - 1) {
                    out[rr * cols + cc] = true;
                }
            }
        }
    }
    out
}

/// Height and crown diameter of a tree, metres.
fn tree_size(conifer: bool, s: &mut Stream) -> (f64, f64) {
    if conifer {
        let h = s.triangular(12.0, 28.0);
        (h, h * s.range(0.26, 0.38))
    } else {
        let h = s.triangular(10.0, 22.0);
        (h, h * s.range(0.55, 0.85))
    }
}

/// Trees and bushes on the materials of `raster` by `rules` (see the module docs): for any
/// raster with materials, synthetic or imported; none without materials.
///
/// # Errors
/// When the rules are out of range ([`CultureRules::validate`]).
pub fn scatter_by_material(
    raster: &Raster,
    rules: &CultureRules,
    seed: u64,
) -> Result<Vec<CulturePlacement>, CultureRulesError> {
    rules.validate()?;
    Ok(scatter(raster, rules, seed, None))
}

/// [`scatter_by_material`] with valid rules, leaving out the posts of `keep_out`.
fn scatter(
    raster: &Raster,
    rules: &CultureRules,
    seed: u64,
    keep_out: Option<&[bool]>,
) -> Vec<CulturePlacement> {
    let g = raster.grid;
    let Some(material) = raster.material.as_deref() else {
        return Vec::new();
    };
    if g.rows < 2 || g.cols < 2 || material.len() != g.len() || raster.elevation_m.len() != g.len()
    {
        return Vec::new();
    }
    let seed = mix64(seed ^ SALT_SCATTER);
    let layers = vegetation_layers(rules, seed);
    let blocked = blocked_posts(&g, material, keep_out);
    let centre_lat = 0.5 * (g.south_lat_deg + g.north_lat_deg());
    let (north_m, east_centre_m) = metres_per_degree(centre_lat);
    let sy = g.dlat_deg * north_m;
    let sx_centre = g.dlon_deg * east_centre_m;
    let noise_spacing_m = sy.min(sx_centre);
    let contrast = 4.0 * rules.stand_contrast;
    let (max_r, max_c) = ((g.rows - 1) as f64, (g.cols - 1) as f64);
    let rows: Vec<Vec<CulturePlacement>> = (0..g.rows)
        .into_par_iter()
        .map(|r| {
            let mut out = Vec::new();
            let lat = g.south_lat_deg + r as f64 * g.dlat_deg;
            let sx = g.dlon_deg * metres_per_degree(lat).1;
            let r_lo = (r as f64 - 0.5).max(0.0);
            let r_hi = (r as f64 + 0.5).min(max_r);
            let cell_h_m = (r_hi - r_lo) * sy;
            for c in 0..g.cols {
                let i = r * g.cols + c;
                if blocked[i] {
                    continue;
                }
                let post_layers = &layers[usize::from(material[i].to_byte())];
                if post_layers.is_empty() {
                    continue;
                }
                let c_lo = (c as f64 - 0.5).max(0.0);
                let c_hi = (c as f64 + 0.5).min(max_c);
                let cell_w_m = (c_hi - c_lo) * sx;
                let (x_m, y_m) = (c as f64 * sx_centre, r as f64 * sy);
                let altitude_m = f64::from(raster.elevation_m[i]);
                let conifer_share = if altitude_m.is_finite() {
                    rules.conifer_share(altitude_m)
                } else {
                    rules.conifer_fraction
                };
                for layer in post_layers {
                    let n = layer.stands.fbm(x_m, y_m, 3, 2.0, 0.5, noise_spacing_m);
                    let stand = (1.0 + contrast * n).clamp(0.0, 2.0);
                    let density = layer.density_per_ha * stand;
                    if density <= 0.0 {
                        continue;
                    }
                    let nr = ((cell_h_m / layer.pitch_m).ceil() as usize).max(1);
                    let nc = ((cell_w_m / layer.pitch_m).ceil() as usize).max(1);
                    let keep =
                        density * (cell_h_m / nr as f64) * (cell_w_m / nc as f64) / HECTARE_M2;
                    let base = hash2(layer.seed, r as i64, c as i64);
                    for k in 0..nr * nc {
                        let h = mix64(base ^ (k as u64).wrapping_mul(GOLDEN));
                        if unit_from_hash(h) >= keep {
                            continue;
                        }
                        let mut s = Stream(h);
                        let (a, b) = ((k / nc) as f64, (k % nc) as f64);
                        let fi = r_lo + (a + s.range(0.1, 0.9)) / nr as f64 * (r_hi - r_lo);
                        let fj = c_lo + (b + s.range(0.1, 0.9)) / nc as f64 * (c_hi - c_lo);
                        let (kind, height_m, width_m) = if layer.trees {
                            let conifer = s.unit() < conifer_share;
                            let (h, w) = tree_size(conifer, &mut s);
                            let kind = if conifer {
                                CultureKind::ConiferTree
                            } else {
                                CultureKind::BroadleafTree
                            };
                            (kind, h, w)
                        } else {
                            let h = s.triangular(0.8, 3.0);
                            (CultureKind::Bush, h, h * s.range(0.9, 1.7))
                        };
                        out.push(CulturePlacement {
                            kind,
                            lat_deg: g.south_lat_deg + fi * g.dlat_deg,
                            lon_deg: g.west_lon_deg + fj * g.dlon_deg,
                            height_m: height_m as f32,
                            width_m: width_m as f32,
                            length_m: width_m as f32,
                            heading_deg: s.range(0.0, 360.0) as f32,
                            variant: s.variant(),
                        });
                    }
                }
            }
            out
        })
        .collect();
    let total = rows.iter().map(Vec::len).sum();
    let mut out = Vec::with_capacity(total);
    for row in rows {
        out.extend(row);
    }
    out
}

// ---------------------------------------------------------------- geometry

type Xy = (f64, f64);

fn sub(a: Xy, b: Xy) -> Xy {
    (a.0 - b.0, a.1 - b.1)
}

fn add(a: Xy, b: Xy) -> Xy {
    (a.0 + b.0, a.1 + b.1)
}

fn scale(a: Xy, k: f64) -> Xy {
    (a.0 * k, a.1 * k)
}

fn dot(a: Xy, b: Xy) -> f64 {
    a.0 * b.0 + a.1 * b.1
}

fn length(a: Xy) -> f64 {
    dot(a, a).sqrt()
}

/// Distance from `p` to the segment `a`-`b`.
fn point_segment_distance(p: Xy, a: Xy, b: Xy) -> f64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    let t = if len2 > 0.0 {
        (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    length(sub(p, add(a, scale(ab, t))))
}

/// Whether the segment `a`-`b` meets the box `[-hx, hx] x [-hy, hy]` (Liang-Barsky clipping).
fn segment_meets_box(a: Xy, b: Xy, hx: f64, hy: f64) -> bool {
    let d = sub(b, a);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.0, a.0 + hx),
        (d.0, hx - a.0),
        (-d.1, a.1 + hy),
        (d.1, hy - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// An oriented rectangle: centre, unit length axis, half length and half width (metres, x
/// east and y north in the local frame).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Footprint {
    centre: Xy,
    axis: Xy,
    half_length_m: f64,
    half_width_m: f64,
}

impl Footprint {
    /// The width axis (to the left of the length axis).
    fn across(&self) -> Xy {
        (-self.axis.1, self.axis.0)
    }

    fn corners(&self) -> [Xy; 4] {
        let u = scale(self.axis, self.half_length_m);
        let v = scale(self.across(), self.half_width_m);
        [
            add(self.centre, add(u, v)),
            add(self.centre, sub(u, v)),
            sub(self.centre, add(u, v)),
            sub(self.centre, sub(u, v)),
        ]
    }

    fn radius_m(&self) -> f64 {
        libm::hypot(self.half_length_m, self.half_width_m)
    }

    /// Into the rectangle's own frame.
    fn local(&self, p: Xy) -> Xy {
        let d = sub(p, self.centre);
        (dot(d, self.axis), dot(d, self.across()))
    }

    /// Distance from the rectangle to the segment `a`-`b` (0 when they meet).
    fn segment_distance_m(&self, a: Xy, b: Xy) -> f64 {
        let (hx, hy) = (self.half_length_m, self.half_width_m);
        let (la, lb) = (self.local(a), self.local(b));
        if segment_meets_box(la, lb, hx, hy) {
            return 0.0;
        }
        let to_box = |p: Xy| libm::hypot((p.0.abs() - hx).max(0.0), (p.1.abs() - hy).max(0.0));
        let mut d = to_box(la).min(to_box(lb));
        for corner in [(hx, hy), (hx, -hy), (-hx, hy), (-hx, -hy)] {
            d = d.min(point_segment_distance(corner, la, lb));
        }
        d
    }

    /// Whether the two rectangles, each grown by `gap_m / 2`, overlap (separating axes).
    fn overlaps(&self, other: &Footprint, gap_m: f64) -> bool {
        let d = sub(other.centre, self.centre);
        let g = 0.5 * gap_m;
        for axis in [self.axis, self.across(), other.axis, other.across()] {
            let extent = |f: &Footprint| {
                (f.half_length_m + g) * dot(f.axis, axis).abs()
                    + (f.half_width_m + g) * dot(f.across(), axis).abs()
            };
            if dot(d, axis).abs() > extent(self) + extent(other) {
                return false;
            }
        }
        true
    }
}

/// A flat metric frame: x east and y north of the south-west post, scaled at the centre
/// latitude.
#[derive(Clone, Copy, Debug)]
struct Frame {
    south_lat_deg: f64,
    west_lon_deg: f64,
    north_m_per_deg: f64,
    east_m_per_deg: f64,
}

impl Frame {
    fn new(g: &GeoGrid) -> Frame {
        let (north, east) = metres_per_degree(0.5 * (g.south_lat_deg + g.north_lat_deg()));
        Frame {
            south_lat_deg: g.south_lat_deg,
            west_lon_deg: g.west_lon_deg,
            north_m_per_deg: north,
            east_m_per_deg: east,
        }
    }

    fn xy(&self, (lat, lon): (f64, f64)) -> Xy {
        (
            (lon - self.west_lon_deg) * self.east_m_per_deg,
            (lat - self.south_lat_deg) * self.north_m_per_deg,
        )
    }

    fn deg(&self, (x, y): Xy) -> (f64, f64) {
        (
            self.south_lat_deg + y / self.north_m_per_deg,
            self.west_lon_deg + x / self.east_m_per_deg,
        )
    }
}

/// A road or river centre line in the local frame.
struct Line {
    kind: LineKind,
    half_width_m: f64,
    points: Vec<Xy>,
    /// Arc length at each point.
    along_m: Vec<f64>,
}

impl Line {
    fn new(kind: LineKind, width_m: f64, points: Vec<Xy>) -> Line {
        let mut along_m = Vec::with_capacity(points.len());
        let mut s = 0.0;
        for (k, &p) in points.iter().enumerate() {
            if k > 0 {
                s += length(sub(p, points[k - 1]));
            }
            along_m.push(s);
        }
        Line {
            kind,
            half_width_m: 0.5 * width_m,
            points,
            along_m,
        }
    }

    fn length_m(&self) -> f64 {
        self.along_m.last().copied().unwrap_or(0.0)
    }

    /// Point and unit tangent at arc length `s`; `segment` is where the last call ended (calls
    /// must come in increasing `s`). `None` on a line of no length.
    fn at(&self, s: f64, segment: &mut usize) -> Option<(Xy, Xy)> {
        let last = self.points.len().checked_sub(2)?;
        while *segment < last && self.along_m[*segment + 1] < s {
            *segment += 1;
        }
        // Skip segments of no length forwards, then backwards.
        let mut k = *segment;
        while k < last && self.along_m[k + 1] - self.along_m[k] <= 1e-9 {
            k += 1;
        }
        while k > 0 && self.along_m[k + 1] - self.along_m[k] <= 1e-9 {
            k -= 1;
        }
        let (a, b) = (self.points[k], self.points[k + 1]);
        let len = self.along_m[k + 1] - self.along_m[k];
        if len <= 1e-9 {
            return None;
        }
        let t = ((s - self.along_m[k]) / len).clamp(0.0, 1.0);
        let dir = scale(sub(b, a), 1.0 / len);
        Some((add(a, scale(sub(b, a), t)), dir))
    }
}

/// A segment of a road or river, for the clearance tests.
struct Segment {
    a: Xy,
    b: Xy,
    half_width_m: f64,
    road: bool,
    /// Index of its line.
    line: u32,
}

/// Cell of the segment index, metres.
const SEGMENT_CELL_M: f64 = 64.0;
/// Cell of the footprint index, metres.
const FOOTPRINT_CELL_M: f64 = 32.0;
/// Largest clearance asked beyond a ribbon's half width, metres (the segment index's reach).
const MAX_CLEARANCE_M: f64 = 8.0;
/// Clearance of buildings beyond a road's edge, metres.
const BUILDING_ROAD_GAP_M: f64 = 2.0;
/// Clearance of walls, fences and poles beyond a road's edge, metres.
const LINEAR_ROAD_GAP_M: f64 = 1.0;
/// Clearance of everything beyond a river's edge, metres.
const RIVER_GAP_M: f64 = 4.0;
/// Gap between a building and anything placed, metres.
const BUILDING_GAP_M: f64 = 2.0;
/// Gap between a wall, fence or pole and anything placed, metres.
const LINEAR_GAP_M: f64 = 0.5;
/// Poles stand this far beyond a paved road's right edge, metres.
const POLE_OFFSET_M: f64 = 2.5;

fn cells_of(min: Xy, max: Xy, cell_m: f64) -> impl Iterator<Item = (i64, i64)> {
    let (i0, i1) = (
        (min.0 / cell_m).floor() as i64,
        (max.0 / cell_m).floor() as i64,
    );
    let (j0, j1) = (
        (min.1 / cell_m).floor() as i64,
        (max.1 / cell_m).floor() as i64,
    );
    (j0..=j1).flat_map(move |j| (i0..=i1).map(move |i| (i, j)))
}

/// The state of a settlement layout: the ground, the ribbons to keep clear of and what is
/// placed so far.
struct Site<'a> {
    raster: &'a Raster,
    frame: Frame,
    /// Post spacing east and north, metres.
    spacing_m: Xy,
    /// Far corner of the grid, metres.
    extent_m: Xy,
    segments: Vec<Segment>,
    segment_index: BTreeMap<(i64, i64), Vec<u32>>,
    placed: Vec<Footprint>,
    placed_index: BTreeMap<(i64, i64), Vec<u32>>,
    out: Vec<CulturePlacement>,
}

impl<'a> Site<'a> {
    fn new(raster: &'a Raster, lines: &[Line]) -> Site<'a> {
        let g = raster.grid;
        let frame = Frame::new(&g);
        let spacing_m = (
            g.dlon_deg * frame.east_m_per_deg,
            g.dlat_deg * frame.north_m_per_deg,
        );
        let mut site = Site {
            raster,
            frame,
            spacing_m,
            extent_m: (
                (g.cols.saturating_sub(1)) as f64 * spacing_m.0,
                (g.rows.saturating_sub(1)) as f64 * spacing_m.1,
            ),
            segments: Vec::new(),
            segment_index: BTreeMap::new(),
            placed: Vec::new(),
            placed_index: BTreeMap::new(),
            out: Vec::new(),
        };
        for (line_index, line) in lines.iter().enumerate() {
            for w in line.points.windows(2) {
                let id = site.segments.len() as u32;
                let reach = line.half_width_m + MAX_CLEARANCE_M;
                let min = (w[0].0.min(w[1].0) - reach, w[0].1.min(w[1].1) - reach);
                let max = (w[0].0.max(w[1].0) + reach, w[0].1.max(w[1].1) + reach);
                for cell in cells_of(min, max, SEGMENT_CELL_M) {
                    site.segment_index.entry(cell).or_default().push(id);
                }
                site.segments.push(Segment {
                    a: w[0],
                    b: w[1],
                    half_width_m: line.half_width_m,
                    road: matches!(line.kind, LineKind::PavedRoad | LineKind::DirtRoad),
                    line: line_index as u32,
                });
            }
        }
        site
    }

    /// The material of the post nearest to `p` (`None` without materials) and the ground's
    /// height at `p` (bilinear between the posts), if `p` is inside the grid.
    fn ground(&self, p: Xy) -> Option<(Option<Material>, f64)> {
        let g = &self.raster.grid;
        let fc = p.0 / self.spacing_m.0;
        let fr = p.1 / self.spacing_m.1;
        let (max_c, max_r) = ((g.cols - 1) as f64, (g.rows - 1) as f64);
        if !(fc >= 0.0 && fr >= 0.0 && fc <= max_c && fr <= max_r) {
            return None;
        }
        let i = fr.round() as usize * g.cols + fc.round() as usize;
        let material = self
            .raster
            .material
            .as_ref()
            .and_then(|m| m.get(i).copied());
        let (c0, r0) = ((fc as usize).min(g.cols - 2), (fr as usize).min(g.rows - 2));
        let (tx, ty) = (fc - c0 as f64, fr - r0 as f64);
        let h = |r: usize, c: usize| f64::from(self.raster.elevation_m[r * g.cols + c]);
        let south = h(r0, c0) + (h(r0, c0 + 1) - h(r0, c0)) * tx;
        let north = h(r0 + 1, c0) + (h(r0 + 1, c0 + 1) - h(r0 + 1, c0)) * tx;
        Some((material, south + (north - south) * ty))
    }

    /// Whether `f` may stand here: inside the grid, clear of water (and for buildings of rock,
    /// snow and steep ground), of roads and rivers, and of everything placed.
    fn fits(&self, f: &Footprint, building: bool) -> bool {
        let corners = f.corners();
        let margin = 0.5;
        for p in corners {
            if !(p.0 >= margin
                && p.1 >= margin
                && p.0 <= self.extent_m.0 - margin
                && p.1 <= self.extent_m.1 - margin)
            {
                return false;
            }
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in corners.into_iter().chain(std::iter::once(f.centre)) {
            let Some((material, h)) = self.ground(p) else {
                return false;
            };
            match material {
                Some(Material::Water) => return false,
                Some(Material::Rock | Material::Snow) if building => return false,
                _ => {}
            }
            lo = lo.min(h);
            hi = hi.max(h);
        }
        let rise_m = hi - lo;
        if building && (rise_m.is_nan() || rise_m > 0.25 * 2.0 * f.radius_m()) {
            return false;
        }
        let road_gap = if building {
            BUILDING_ROAD_GAP_M
        } else {
            LINEAR_ROAD_GAP_M
        };
        let r = f.radius_m();
        let min = (f.centre.0 - r, f.centre.1 - r);
        let max = (f.centre.0 + r, f.centre.1 + r);
        for cell in cells_of(min, max, SEGMENT_CELL_M) {
            for &id in self.segment_index.get(&cell).into_iter().flatten() {
                let s = &self.segments[id as usize];
                let gap = if s.road { road_gap } else { RIVER_GAP_M };
                if f.segment_distance_m(s.a, s.b) < s.half_width_m + gap {
                    return false;
                }
            }
        }
        let gap = if building {
            BUILDING_GAP_M
        } else {
            LINEAR_GAP_M
        };
        let reach = r + gap;
        let min = (f.centre.0 - reach, f.centre.1 - reach);
        let max = (f.centre.0 + reach, f.centre.1 + reach);
        for cell in cells_of(min, max, FOOTPRINT_CELL_M) {
            for &id in self.placed_index.get(&cell).into_iter().flatten() {
                if f.overlaps(&self.placed[id as usize], gap) {
                    return false;
                }
            }
        }
        true
    }

    /// Whether no road but `own` (a line index) comes nearer to `p` than `own` does, less a
    /// tolerance: a building belongs to the road nearest to it.
    fn nearest_road_is(&self, p: Xy, own: u32) -> bool {
        const TOLERANCE_M: f64 = 5.0;
        let mut reach = SEGMENT_CELL_M;
        loop {
            let (mut own_m, mut other_m) = (f64::INFINITY, f64::INFINITY);
            let min = (p.0 - reach, p.1 - reach);
            let max = (p.0 + reach, p.1 + reach);
            for cell in cells_of(min, max, SEGMENT_CELL_M) {
                for &id in self.segment_index.get(&cell).into_iter().flatten() {
                    let s = &self.segments[id as usize];
                    if !s.road {
                        continue;
                    }
                    let d = point_segment_distance(p, s.a, s.b);
                    if s.line == own {
                        own_m = own_m.min(d);
                    } else {
                        other_m = other_m.min(d);
                    }
                }
            }
            // Every segment nearer than `reach` has been seen.
            if own_m <= reach || reach > 1_000.0 {
                return other_m >= own_m - TOLERANCE_M;
            }
            reach *= 2.0;
        }
    }

    /// Places an object of `kind` with footprint `f` and `height_m` if it fits; a building
    /// of road `own_road` only where that road is the nearest.
    fn place(
        &mut self,
        kind: CultureKind,
        f: Footprint,
        height_m: f64,
        variant: u8,
        own_road: Option<u32>,
    ) -> bool {
        if !self.fits(&f, kind.is_building()) {
            return false;
        }
        if let Some(own) = own_road {
            if !self.nearest_road_is(f.centre, own) {
                return false;
            }
        }
        let id = self.placed.len() as u32;
        let r = f.radius_m();
        let min = (f.centre.0 - r, f.centre.1 - r);
        let max = (f.centre.0 + r, f.centre.1 + r);
        for cell in cells_of(min, max, FOOTPRINT_CELL_M) {
            self.placed_index.entry(cell).or_default().push(id);
        }
        self.placed.push(f);
        let (lat_deg, lon_deg) = self.frame.deg(f.centre);
        let heading_deg = libm::atan2(f.axis.0, f.axis.1)
            .to_degrees()
            .rem_euclid(360.0);
        self.out.push(CulturePlacement {
            kind,
            lat_deg,
            lon_deg,
            height_m: height_m as f32,
            width_m: (2.0 * f.half_width_m) as f32,
            length_m: (2.0 * f.half_length_m) as f32,
            heading_deg: heading_deg as f32,
            variant,
        });
        true
    }
}

/// Length, width and height of a building, metres.
fn building_size(kind: CultureKind, farm: bool, s: &mut Stream) -> (f64, f64, f64) {
    match kind {
        CultureKind::LargeBuilding => {
            (s.range(18.0, 40.0), s.range(12.0, 20.0), s.range(8.0, 16.0))
        }
        CultureKind::Shed if farm => (s.range(10.0, 24.0), s.range(7.0, 12.0), s.range(5.0, 8.0)),
        CultureKind::Shed => (s.range(5.0, 9.0), s.range(4.0, 6.0), s.range(3.5, 5.0)),
        _ => (s.range(9.0, 14.0), s.range(7.0, 10.0), s.range(6.0, 9.0)),
    }
}

/// Where a plot meets its road: the road (a line index) and its half width, the point on its
/// centre line, the road's direction there and the unit normal towards the plot.
#[derive(Clone, Copy, Debug)]
struct Plot {
    road: u32,
    road_half_m: f64,
    point: Xy,
    tangent: Xy,
    normal: Xy,
}

impl Plot {
    /// A footprint `offset_m` from the centre line towards the plot and `along_m` along the
    /// road, its length along the road (either way round).
    fn footprint(&self, offset_m: f64, along_m: f64, size: (f64, f64), flip: bool) -> Footprint {
        Footprint {
            centre: add(
                self.point,
                add(scale(self.normal, offset_m), scale(self.tangent, along_m)),
            ),
            axis: if flip {
                scale(self.tangent, -1.0)
            } else {
                self.tangent
            },
            half_length_m: 0.5 * size.0,
            half_width_m: 0.5 * size.1,
        }
    }
}

/// One road plot's side in a settlement: rows of buildings, a shed behind some houses, a
/// garden wall or fence along some front plots. `t` is the distance to the settlement centre
/// over its radius.
fn town_plot(site: &mut Site, rules: &SettlementRules, plot: &Plot, t: f64, s: &mut Stream) {
    let frontage = rules.plot_frontage_m;
    let rows_f = 1.0 + f64::from(rules.max_rows - 1) * libm::pow(1.0 - t, 1.5);
    let rows = ((rows_f + s.unit()).floor() as u32).clamp(1, rules.max_rows);
    let filled = 0.92 * (1.0 - 0.6 * t * t);
    let front_gap = s.range(5.0, 10.0);
    let road = Some(plot.road);
    for row in 0..rows {
        if s.unit() >= filled {
            continue;
        }
        let large =
            row == 0 && t < 0.4 && s.unit() < rules.large_building_fraction * (1.0 - t / 0.4);
        let kind = if large {
            CultureKind::LargeBuilding
        } else {
            CultureKind::House
        };
        let (l, w, h) = building_size(kind, false, s);
        let along = if large {
            0.0
        } else {
            s.range(-0.15, 0.15) * frontage
        };
        let offset = plot.road_half_m + front_gap + f64::from(row) * rules.row_depth_m + 0.5 * w;
        let flip = s.unit() < 0.5;
        let f = plot.footprint(offset, along, (l, w), flip);
        let variant = s.variant();
        if !site.place(kind, f, h, variant, road) {
            continue;
        }
        if row == 0 && kind == CultureKind::House && s.unit() < rules.enclosed_fraction {
            let (wall_kind, thickness, height) = if s.unit() < rules.wall_fraction {
                (CultureKind::Wall, s.range(0.3, 0.5), s.range(1.2, 2.0))
            } else {
                (CultureKind::Fence, 0.1, s.range(1.1, 1.5))
            };
            let front_offset = plot.road_half_m + front_gap - 1.5;
            let front_len = frontage * s.range(0.7, 0.9);
            let front = plot.footprint(front_offset, along, (front_len, thickness), false);
            let variant = s.variant();
            site.place(wall_kind, front, height, variant, None);
            // One side of the plot, from the front boundary to behind the house.
            let side_len = offset + 0.5 * w + 3.0 - front_offset;
            let side_sign = if s.unit() < 0.5 { -1.0 } else { 1.0 };
            let side = Footprint {
                centre: add(
                    plot.point,
                    add(
                        scale(plot.normal, front_offset + 0.5 * side_len),
                        scale(plot.tangent, along + side_sign * 0.5 * front_len),
                    ),
                ),
                axis: plot.normal,
                half_length_m: 0.5 * side_len,
                half_width_m: 0.5 * thickness,
            };
            let variant = s.variant();
            site.place(wall_kind, side, height, variant, None);
        }
        if kind == CultureKind::House && s.unit() < rules.shed_fraction {
            let (sl, sw, sh) = building_size(CultureKind::Shed, false, s);
            let shed_offset = offset + 0.5 * w + s.range(3.0, 6.0) + 0.5 * sw;
            let shed_along = along + s.range(-0.5, 0.5) * (frontage - sl).max(0.0);
            let flip = s.unit() < 0.5;
            let f = plot.footprint(shed_offset, shed_along, (sl, sw), flip);
            let variant = s.variant();
            site.place(CultureKind::Shed, f, sh, variant, road);
        }
    }
}

/// A farmstead beside a road: a house and one to three barns behind it.
fn farmstead(site: &mut Site, plot: &Plot, s: &mut Stream) {
    let road = Some(plot.road);
    let (l, w, h) = building_size(CultureKind::House, true, s);
    let offset = plot.road_half_m + s.range(12.0, 35.0) + 0.5 * w;
    let flip = s.unit() < 0.5;
    let house = plot.footprint(offset, 0.0, (l, w), flip);
    let variant = s.variant();
    if !site.place(CultureKind::House, house, h, variant, road) {
        return;
    }
    let barns = 1 + (s.unit() * 2.99) as u32;
    for _ in 0..barns {
        let (bl, bw, bh) = building_size(CultureKind::Shed, true, s);
        let barn_offset = offset + 0.5 * w + s.range(6.0, 16.0) + 0.5 * bw;
        let along = s.range(-18.0, 18.0);
        let flip = s.unit() < 0.5;
        let f = plot.footprint(barn_offset, along, (bl, bw), flip);
        let variant = s.variant();
        site.place(CultureKind::Shed, f, bh, variant, road);
    }
}

/// Roads and rivers of `features` in the local frame, in feature order.
fn lines_of(features: &[Feature], frame: &Frame) -> Vec<Line> {
    features
        .iter()
        .filter_map(|f| match f {
            Feature::Line {
                kind,
                width_m,
                points_deg,
            } if width_m.is_finite() && *width_m > 0.0 => {
                let points: Vec<Xy> = points_deg
                    .iter()
                    .map(|&p| frame.xy(p))
                    .filter(|p| p.0.is_finite() && p.1.is_finite())
                    .collect();
                (points.len() >= 2).then(|| Line::new(*kind, *width_m, points))
            }
            _ => None,
        })
        .collect()
}

/// Buildings, garden walls, fences and power poles along the roads of `features` (see the
/// module docs): settlements about `settlements_deg` (`(lat_deg, lon_deg)`, e.g.
/// [`SynthReport::settlements_deg`]), farmsteads between them, poles along the paved roads.
/// Rivers among the features are kept clear of; so are the raster's water posts.
///
/// # Errors
/// When the rules are out of range ([`SettlementRules::validate`]).
pub fn settlement_culture(
    raster: &Raster,
    settlements_deg: &[(f64, f64)],
    features: &[Feature],
    rules: &SettlementRules,
    seed: u64,
) -> Result<Vec<CulturePlacement>, CultureRulesError> {
    rules.validate()?;
    let g = raster.grid;
    if g.rows < 2 || g.cols < 2 || raster.elevation_m.len() != g.len() {
        return Ok(Vec::new());
    }
    let frame = Frame::new(&g);
    let lines = lines_of(features, &frame);
    let mut site = Site::new(raster, &lines);
    let centres: Vec<Xy> = settlements_deg
        .iter()
        .map(|&p| frame.xy(p))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();

    // Power poles first, so that buildings keep clear of the pole lines.
    if rules.pole_spacing_m > 0.0 {
        let pole_seed = mix64(seed ^ SALT_POLES);
        for (li, line) in lines.iter().enumerate() {
            if line.kind != LineKind::PavedRoad {
                continue;
            }
            let mut segment = 0;
            let mut s_m = 0.5 * rules.pole_spacing_m;
            let mut k = 0i64;
            while s_m < line.length_m() {
                if let Some((p, tangent)) = line.at(s_m, &mut segment) {
                    let right = (tangent.1, -tangent.0);
                    let mut s = Stream(hash2(pole_seed, li as i64, k));
                    let f = Footprint {
                        centre: add(p, scale(right, line.half_width_m + POLE_OFFSET_M)),
                        axis: tangent,
                        half_length_m: 0.15,
                        half_width_m: 0.15,
                    };
                    let height = s.range(9.0, 11.0);
                    let variant = s.variant();
                    site.place(CultureKind::PowerPole, f, height, variant, None);
                }
                s_m += rules.pole_spacing_m;
                k += 1;
            }
        }
    }

    // Plots along every road, settlement or farmland.
    let plot_seed = mix64(seed ^ SALT_SETTLE);
    let radius = rules.radius_m;
    for (li, line) in lines.iter().enumerate() {
        if !matches!(line.kind, LineKind::PavedRoad | LineKind::DirtRoad) {
            continue;
        }
        let mut segment = 0;
        let mut station = Stream(hash2(plot_seed, li as i64, -1));
        let mut s_m = station.range(0.0, 0.5) * rules.plot_frontage_m;
        let mut k = 0i64;
        while s_m < line.length_m() {
            let step = rules.plot_frontage_m * station.range(0.8, 1.2);
            if let Some((p, tangent)) = line.at(s_m, &mut segment) {
                let d = centres
                    .iter()
                    .map(|&c| length(sub(p, c)))
                    .fold(f64::INFINITY, f64::min);
                for (side_index, side) in [1.0, -1.0].into_iter().enumerate() {
                    let plot = Plot {
                        road: li as u32,
                        road_half_m: line.half_width_m,
                        point: p,
                        tangent,
                        normal: scale((-tangent.1, tangent.0), side),
                    };
                    let mut s = Stream(hash2(plot_seed, li as i64, 2 * k + side_index as i64));
                    if d < radius {
                        town_plot(&mut site, rules, &plot, d / radius, &mut s);
                    } else if rules.farmstead_spacing_m > 0.0
                        && s.unit() < step / rules.farmstead_spacing_m
                    {
                        farmstead(&mut site, &plot, &mut s);
                    }
                }
            }
            s_m += step;
            k += 1;
        }
    }
    Ok(site.out)
}

/// Widest crown radius of a tree (a 22 m broadleaf tree with a crown 0.85 of its height) and
/// a little more: vegetation keeps this far from settlement objects.
const KEEP_OUT_MARGIN_M: f64 = 10.0;

/// Posts under and next to the footprints of `placements` (buildings, walls, fences, poles),
/// where no vegetation goes.
fn footprint_posts(raster: &Raster, placements: &[CulturePlacement]) -> Vec<bool> {
    let g = raster.grid;
    let frame = Frame::new(&g);
    let (sx, sy) = (
        g.dlon_deg * frame.east_m_per_deg,
        g.dlat_deg * frame.north_m_per_deg,
    );
    let mut out = vec![false; g.len()];
    for p in placements {
        let (x, y) = frame.xy((p.lat_deg, p.lon_deg));
        let r = 0.5 * libm::hypot(f64::from(p.width_m), f64::from(p.length_m)) + KEEP_OUT_MARGIN_M;
        let (rx, ry) = (r + 0.5 * sx, r + 0.5 * sy);
        let c0 = ((x - rx) / sx).ceil().max(0.0) as usize;
        let c1 = (((x + rx) / sx).floor().max(-1.0) as i64).min(g.cols as i64 - 1);
        let r0 = ((y - ry) / sy).ceil().max(0.0) as usize;
        let r1 = (((y + ry) / sy).floor().max(-1.0) as i64).min(g.rows as i64 - 1);
        for row in r0 as i64..=r1 {
            for col in c0 as i64..=c1 {
                out[row as usize * g.cols + col as usize] = true;
            }
        }
    }
    out
}

/// The culture of a synthetic database: [`settlement_culture`] about the report's settlements
/// along the roads of `features`, then [`scatter_by_material`] everywhere but under and next
/// to what that placed. Settlement objects come first, then vegetation in row order.
///
/// # Errors
/// When the rules are out of range ([`CultureRules::validate`]).
pub fn place_culture(
    raster: &Raster,
    report: &SynthReport,
    features: &[Feature],
    rules: &CultureRules,
    seed: u64,
) -> Result<Vec<CulturePlacement>, CultureRulesError> {
    rules.validate()?;
    let mut out = settlement_culture(
        raster,
        &report.settlements_deg,
        features,
        &rules.settlements,
        seed,
    )?;
    let keep_out = footprint_posts(raster, &out);
    out.extend(scatter(raster, rules, seed, Some(&keep_out)));
    Ok(out)
}

#[cfg(test)]
mod tests;
