//! The sea: on request ([`crate::SynthOptions::sea_side`]) the land falls into open sea on one
//! side of the area, a coast whose sea goes on beyond the database's edge.
//!
//! # Algorithm
//!
//! Let `d` be a point's distance inland from the sea-side edge, metres.
//!
//! 1. **Coastline.** The shore lies `c(x, y) = 0.32 L + 0.16 L tanh(1.6 n(x, y))` inland of
//!    the edge (`L` the area's side), `n` a fBm (Mandelbrot & Van Ness 1968; lacunarity 2, gain
//!    0.6, see [`SHORE_GAIN`]) of wavelength `L / 2` down to twice the post spacing: a fractal
//!    coast of bays, headlands, a few islets and lagoons, between 16 % and 48 % of the side from
//!    the edge and about 32 % on average. `s = c - d` is the distance seaward of the shore (positive at
//!    sea).
//! 2. **Drainage to the sea.** The coarse stream-power landform ([`crate::landform`]) has its
//!    base level lowered by up to 250 m toward the sea side (`250 (1 - smoothstep(0, 0.8 L,
//!    d))`), so its lowest boundary points, its outlets, lie on the sea side and the range's
//!    valleys run down to the coast; no lake basin is pressed in near the coast.
//! 3. **The descent.** Over a band `w = clamp(0.12 L, 400 m, 6 km)` wide landward of the
//!    shore, the carved ground `h` blends into a coastal plain rising inland at 1.5 %, and
//!    seaward into the sea floor `-D (s / 0.32 L)^(2/3)`, the power of the equilibrium beach
//!    profile (Dean 1991, "Equilibrium beach profiles", *J. Coastal Research* 7(1)), `D =
//!    clamp(0.1 (0.32 L)^(2/3), 40 m, 100 m)` (a wider sea is deeper): 25-130 m deep at the
//!    edge. With `f = smoothstep(-w, o, s)`, `h' = max(h, 0) (1 - f) + 0.015 (-s) f` where
//!    `s < 0` and `h' = h (1 - f) - D (s / 0.32 L)^(2/3) f` where `s >= 0`. A second fBm
//!    (wavelength `0.35 L`) marks stretches of the coast as cliffs, `k = smoothstep(0, 0.3,
//!    fBm)` (above 0 on about half the coast, 1 on a tenth): there the band narrows to
//!    `w (1 - 0.9 k)` and reaches `o = 0.5 k` of that out to sea, so the land's own relief runs
//!    steeply into the water (the materials make faces over 35 degrees rock); elsewhere
//!    (`o = 0`) the ground meets the sea on the plain: beaches (the materials' sand within 40 m
//!    of the water). The land side never lies below 0 m.
//! 4. The hydrology ([`crate::hydro`]) then finds the sea as every post below 0 m joined to the
//!    edge, sets it to the sea's surface, 0 m above mean sea level, as lakes hold their surface,
//!    and makes it the rivers' outlet.
//!
//! Everything is in metres from the south-west post, so the same seed gives the same coast at
//! every spacing (down to the finest octave the spacing carries). The coast's noise is seeded
//! from the request's seed without drawing from the shared generator, and each post is
//! computed on its own: deterministic on every machine and thread count.
//!
//! # Limits
//!
//! The sea floor is shaped only to place the shore: the database stores the sea's surface
//! (0 m), not its depth (no bathymetry for shallow-water waves). No waves or currents shape
//! the coast: no spits, bars, dunes, river deltas or estuaries; cliffs and beaches come from
//! noise, not from rock strength or exposure, and a small area (a few km) whose hills rise
//! steeply is mostly cliff. Lowering the base level changes the whole landform, so a coast's
//! hills are not the inland landscape of the same seed. Coastal lagoons can form behind the
//! shore (filled as lakes above 0 m). The coast belongs to the area (it scales with the side),
//! so two adjacent databases do not share a shore.

use crate::noise::{mix64, smoothstep, Layer};
use rayon::prelude::*;

/// The side of the database on which the land falls into the sea.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SeaSide {
    /// The sea lies north (the top rows).
    North,
    /// The sea lies east (the last columns).
    East,
    /// The sea lies south (the first rows).
    South,
    /// The sea lies west (the first columns).
    West,
}

impl SeaSide {
    /// Every side, in the order the error message names them.
    pub const ALL: [SeaSide; 4] = [SeaSide::West, SeaSide::East, SeaSide::North, SeaSide::South];

    /// The side's name on the command line: "west", "east", "north" or "south".
    pub fn name(self) -> &'static str {
        match self {
            SeaSide::North => "north",
            SeaSide::East => "east",
            SeaSide::South => "south",
            SeaSide::West => "west",
        }
    }
}

impl std::fmt::Display for SeaSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is not a [`SeaSide`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0:?} is not a side: west, east, north or south")]
pub struct UnknownSeaSide(pub String);

impl std::str::FromStr for SeaSide {
    type Err = UnknownSeaSide;

    /// "west", "east", "north" or "south", in any case.
    fn from_str(text: &str) -> Result<SeaSide, UnknownSeaSide> {
        SeaSide::ALL
            .into_iter()
            .find(|side| text.eq_ignore_ascii_case(side.name()))
            .ok_or_else(|| UnknownSeaSide(text.to_string()))
    }
}

/// Mean distance of the shore from the sea-side edge, as a fraction of the side.
const SHORE_FRACTION: f64 = 0.32;
/// Half the shore's swing about it, as a fraction of the side (reached through `tanh`).
const SHORE_SWING_FRACTION: f64 = 0.16;
/// Steepness of the `tanh` that bounds the swing.
const SHORE_SWING_GAIN: f64 = 1.6;
/// Octaves of the shore's fBm (the finest fade out at twice the post spacing).
const SHORE_OCTAVES: usize = 12;
/// Amplitude ratio of successive octaves of the shore's fBm: 0.6 (`2^-0.74`) makes a shore
/// of fractal dimension about 1.26, as measured on rugged coasts (Mandelbrot 1967, "How long
/// is the coast of Britain?", *Science* 156).
const SHORE_GAIN: f64 = 0.6;
/// Rise of the coastal plain inland, metres per metre.
const PLAIN_SLOPE: f64 = 0.015;
/// Most the coarse landform's base level is lowered on the sea side, metres.
const BASE_DROP_M: f64 = 250.0;

/// The coast of one request.
pub(crate) struct Coast {
    side: SeaSide,
    size_m: f64,
    /// Mean distance of the shore from the edge, metres.
    shore_m: f64,
    /// Half the swing of the shore, metres.
    swing_m: f64,
    /// Width of the landward descent, metres.
    descent_m: f64,
    /// Sea-floor depth `shore_m` out from the shore, metres.
    depth_m: f64,
    shape: Layer,
    cliffs: Layer,
}

impl Coast {
    /// The coast on `side` of a square area `size_m` on a side; its noise is seeded from
    /// `seed` alone (the shared generator is not drawn from).
    pub(crate) fn new(side: SeaSide, size_m: f64, seed: u64) -> Coast {
        let shore_m = SHORE_FRACTION * size_m;
        let shape_seed = mix64(seed ^ 0xC0A5_7C0A_57C0_A57C);
        Coast {
            side,
            size_m,
            shore_m,
            swing_m: SHORE_SWING_FRACTION * size_m,
            descent_m: (0.12 * size_m).clamp(400.0, 6_000.0),
            depth_m: (0.1 * libm::cbrt(shore_m * shore_m)).clamp(40.0, 100.0),
            shape: Layer::new(shape_seed, 0.5 * size_m),
            cliffs: Layer::new(mix64(shape_seed), 0.35 * size_m),
        }
    }

    /// Distance inland from the sea-side edge, metres (negative beyond it).
    #[inline]
    fn inland_m(&self, x_m: f64, y_m: f64) -> f64 {
        match self.side {
            SeaSide::West => x_m,
            SeaSide::East => self.size_m - x_m,
            SeaSide::South => y_m,
            SeaSide::North => self.size_m - y_m,
        }
    }

    /// Distance seaward of the shore, metres: positive at sea.
    #[inline]
    pub(crate) fn seaward_m(&self, x_m: f64, y_m: f64, spacing_m: f64) -> f64 {
        let n = self
            .shape
            .fbm(x_m, y_m, SHORE_OCTAVES, 2.0, SHORE_GAIN, spacing_m);
        let shore = self.shore_m + self.swing_m * libm::tanh(SHORE_SWING_GAIN * n);
        shore - self.inland_m(x_m, y_m)
    }

    /// Depth of the sea floor `seaward_m` (> 0) out from the shore, metres.
    #[inline]
    fn depth_at_m(&self, seaward_m: f64) -> f64 {
        let t = seaward_m / self.shore_m;
        self.depth_m * libm::cbrt(t * t)
    }

    /// How far the coarse landform's base level is lowered at a point, metres.
    pub(crate) fn base_drop_m(&self, x_m: f64, y_m: f64) -> f64 {
        BASE_DROP_M * (1.0 - smoothstep(0.0, 0.8 * self.size_m, self.inland_m(x_m, y_m)))
    }

    /// Whether a lake basin may be pressed in at a point: inland of the farthest the coast
    /// and its descent reach.
    pub(crate) fn allows_lake_basin(&self, x_m: f64, y_m: f64) -> bool {
        self.inland_m(x_m, y_m) > self.shore_m + self.swing_m + self.descent_m
    }

    /// The ground at a point whose carved height is `h_m`, for posts `spacing_m` apart.
    pub(crate) fn ground_m(&self, h_m: f64, x_m: f64, y_m: f64, spacing_m: f64) -> f64 {
        let s = self.seaward_m(x_m, y_m, spacing_m);
        let cliff = smoothstep(0.0, 0.3, self.cliffs.fbm(x_m, y_m, 3, 2.0, 0.5, spacing_m));
        let w = self.descent_m * (1.0 - 0.9 * cliff);
        if s <= -w {
            return h_m.max(0.0);
        }
        let reach = 0.5 * w * cliff;
        let f = smoothstep(-w, reach, s);
        if s < 0.0 {
            h_m.max(0.0) * (1.0 - f) + PLAIN_SLOPE * -s * f
        } else {
            h_m * (1.0 - f) - self.depth_at_m(s) * f
        }
    }

    /// Lays the coast over the carved posts (row-major, `cols` wide, `spacing_m` apart, the
    /// first row south); every post independently, so the thread count does not matter.
    pub(crate) fn apply(&self, h: &mut [f32], cols: usize, spacing_m: f64) {
        h.par_chunks_mut(cols.max(1))
            .enumerate()
            .for_each(|(r, row)| {
                let y = r as f64 * spacing_m;
                for (c, v) in row.iter_mut().enumerate() {
                    let x = c as f64 * spacing_m;
                    *v = self.ground_m(f64::from(*v), x, y, spacing_m) as f32;
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_parse_in_any_case_and_a_bad_one_names_the_accepted_values() {
        for side in SeaSide::ALL {
            assert_eq!(side.name().parse::<SeaSide>(), Ok(side));
            assert_eq!(side.to_string().to_uppercase().parse::<SeaSide>(), Ok(side));
        }
        let e = "up".parse::<SeaSide>().expect_err("not a side");
        assert_eq!(
            e.to_string(),
            "\"up\" is not a side: west, east, north or south"
        );
    }

    /// Along a line from the sea-side edge inland: the floor deepens out to sea, the land rises
    /// from the shore, and nothing landward is below 0 m.
    #[test]
    fn the_profile_falls_from_the_land_to_the_sea_floor() {
        let size_m = 20_000.0;
        let coast = Coast::new(SeaSide::West, size_m, 3);
        for y in [1_000.0, 7_000.0, 13_000.0, 19_000.0] {
            let h: Vec<f64> = (0..=200)
                .map(|i| coast.ground_m(300.0, f64::from(i) * 100.0, y, 30.0))
                .collect();
            assert!(h[0] < -20.0 && h[0] > -140.0, "edge at {}", h[0]);
            assert!(h[200] == 300.0, "inland at {}", h[200]);
            let shore = h.iter().position(|&v| v >= 0.0).expect("a shore");
            assert!((30..=160).contains(&shore), "shore at {shore}");
        }
        assert_eq!(coast.ground_m(-10.0, 19_000.0, 100.0, 30.0), 0.0);
    }
}
