//! Display correction of a projected channel: a geometric warp and edge-blend ramps, the last
//! pass of its frame.
//!
//! # The algorithm
//!
//! **Warp.** A projector calibration gives, for a regular grid of points of the rendered view,
//! where each must appear on the projector's raster so that the picture lands undistorted on a
//! curved screen. The grid has `columns x rows` nodes; node `(i, j)` is the view's point
//! `(i / (columns - 1), j / (rows - 1))` (fractions of the width and height, from the top left)
//! and carries its display position, also in fractions of the display from the top left. The
//! renderer draws the grid's cells as two triangles each, placed at the display positions and
//! textured with the view's points: between nodes the mapping is bilinear in each triangle
//! (piecewise linear). Display areas no cell covers are black. The identity grid (every node on
//! its own view point) leaves the frame unchanged.
//!
//! **Blend.** Where two projectors overlap, each dims its share so that the light adds up to
//! one: a ramp of width `left`, `right`, `top`, `bottom` (fractions of the display) runs the
//! light's weight from 0 at the display's edge to 1 inside, as smoothstep `w = t^2 (3 - 2t)`
//! (two overlapping ramps of equal width add to 1 at every point, and their slope is 0 at both
//! ends, so no Mach band shows where a ramp starts). A projector's light goes as its input
//! value to the power `gamma`, so the input is multiplied by `w^(1/gamma)`; corners multiply the
//! two edges' weights.
//!
//! Limits: one warp grid per channel (no per-colour warps for lateral chromatic error); the
//! blend is the same in the three colours (no black-level uplift for the projectors' light in
//! the non-overlapping parts, which only matters in very dark scenes).

/// A display correction that cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DisplayError {
    #[error("the warp grid needs at least 2 x 2 nodes, not {columns} x {rows}")]
    GridTooSmall { columns: u32, rows: u32 },
    #[error("the warp grid of {columns} x {rows} nodes is larger than 1024 x 1024")]
    GridTooLarge { columns: u32, rows: u32 },
    #[error("the warp grid of {columns} x {rows} nodes needs {expected} display positions, it has {found}")]
    NodeCount {
        columns: u32,
        rows: u32,
        expected: usize,
        found: usize,
    },
    #[error("warp node {index} has a display position {position:?} that is not finite or lies more than one display away")]
    BadNode { index: usize, position: [f64; 2] },
    #[error("blend {edge} is {value}: a ramp is a fraction of the display between 0 and 0.5")]
    BadRamp { edge: &'static str, value: f64 },
    #[error("blend gamma is {0}: it lies between 1 and 4")]
    BadGamma(f64),
}

/// A channel's warp: display positions of a regular grid of the view's points.
#[derive(Clone, Debug, PartialEq)]
pub struct WarpMesh {
    columns: u32,
    rows: u32,
    /// Row by row from the top left: each node's display position, fractions of the display
    /// from its top left.
    display: Vec<[f32; 2]>,
}

impl WarpMesh {
    /// A grid of `columns x rows` nodes and their display positions, row by row from the top
    /// left. Positions may lie off the display (by at most one display), as a calibration's
    /// outer nodes do.
    pub fn new(columns: u32, rows: u32, display: Vec<[f64; 2]>) -> Result<WarpMesh, DisplayError> {
        if columns < 2 || rows < 2 {
            return Err(DisplayError::GridTooSmall { columns, rows });
        }
        if columns > 1024 || rows > 1024 {
            return Err(DisplayError::GridTooLarge { columns, rows });
        }
        let expected = columns as usize * rows as usize;
        if display.len() != expected {
            return Err(DisplayError::NodeCount {
                columns,
                rows,
                expected,
                found: display.len(),
            });
        }
        if let Some((index, position)) = display
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|v| v.is_finite() && (-1.0..=2.0).contains(v)))
        {
            return Err(DisplayError::BadNode {
                index,
                position: *position,
            });
        }
        Ok(WarpMesh {
            columns,
            rows,
            display: display.iter().map(|p| [p[0] as f32, p[1] as f32]).collect(),
        })
    }

    /// The grid that leaves the view where it is.
    pub fn identity(columns: u32, rows: u32) -> Result<WarpMesh, DisplayError> {
        let display = (0..rows)
            .flat_map(|j| {
                (0..columns).map(move |i| {
                    [
                        f64::from(i) / f64::from(columns.max(2) - 1),
                        f64::from(j) / f64::from(rows.max(2) - 1),
                    ]
                })
            })
            .collect();
        WarpMesh::new(columns, rows, display)
    }

    pub fn columns(&self) -> u32 {
        self.columns
    }
    pub fn rows(&self) -> u32 {
        self.rows
    }

    /// The view's point of node `index` (fractions from the top left).
    pub fn view_point(&self, index: usize) -> [f32; 2] {
        let i = index as u32 % self.columns;
        let j = index as u32 / self.columns;
        [
            i as f32 / (self.columns - 1) as f32,
            j as f32 / (self.rows - 1) as f32,
        ]
    }

    /// Each node's display position, row by row from the top left.
    pub fn display_positions(&self) -> &[[f32; 2]] {
        &self.display
    }

    /// The triangles' node indices: two per cell, split along the same diagonal as drawn.
    pub fn triangle_indices(&self) -> Vec<u32> {
        let mut out = Vec::with_capacity(((self.columns - 1) * (self.rows - 1) * 6) as usize);
        for j in 0..self.rows - 1 {
            for i in 0..self.columns - 1 {
                let a = j * self.columns + i;
                let b = a + 1;
                let c = a + self.columns;
                let d = c + 1;
                out.extend_from_slice(&[a, c, b, b, c, d]);
            }
        }
        out
    }

    /// Where the view's point `(u, v)` appears on the display, as the drawn triangles place it
    /// (`None` off the grid).
    pub fn display_of(&self, u: f64, v: f64) -> Option<[f64; 2]> {
        if !((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)) {
            return None;
        }
        let x = u * f64::from(self.columns - 1);
        let y = v * f64::from(self.rows - 1);
        let i = (x.floor() as u32).min(self.columns - 2);
        let j = (y.floor() as u32).min(self.rows - 2);
        let (fx, fy) = (x - f64::from(i), y - f64::from(j));
        let node = |di: u32, dj: u32| {
            let p = self.display[((j + dj) * self.columns + i + di) as usize];
            [f64::from(p[0]), f64::from(p[1])]
        };
        // The cell's triangles (a, c, b) and (b, c, d): the first holds fx + fy <= 1.
        let (a, b, c, d) = (node(0, 0), node(1, 0), node(0, 1), node(1, 1));
        Some(if fx + fy <= 1.0 {
            [0, 1].map(|k| a[k] + (b[k] - a[k]) * fx + (c[k] - a[k]) * fy)
        } else {
            [0, 1].map(|k| d[k] + (c[k] - d[k]) * (1.0 - fx) + (b[k] - d[k]) * (1.0 - fy))
        })
    }
}

/// Edge-blend ramps: widths as fractions of the display, and the projector's gamma.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeBlend {
    pub left: f64,
    pub right: f64,
    pub top: f64,
    pub bottom: f64,
    pub gamma: f64,
}

impl EdgeBlend {
    pub fn validate(&self) -> Result<(), DisplayError> {
        for (edge, value) in [
            ("left", self.left),
            ("right", self.right),
            ("top", self.top),
            ("bottom", self.bottom),
        ] {
            if !(value.is_finite() && (0.0..=0.5).contains(&value)) {
                return Err(DisplayError::BadRamp { edge, value });
            }
        }
        if !(self.gamma.is_finite() && (1.0..=4.0).contains(&self.gamma)) {
            return Err(DisplayError::BadGamma(self.gamma));
        }
        Ok(())
    }

    /// The light's weight at display point `(x, y)` (fractions from the top left).
    pub fn light_weight(&self, x: f64, y: f64) -> f64 {
        ramp(x, self.left)
            * ramp(1.0 - x, self.right)
            * ramp(y, self.top)
            * ramp(1.0 - y, self.bottom)
    }

    /// What the frame's (gamma-encoded) value is multiplied by at `(x, y)`.
    pub fn value_factor(&self, x: f64, y: f64) -> f64 {
        self.light_weight(x, y).powf(1.0 / self.gamma)
    }
}

/// The smoothstep ramp's weight at `distance` from the edge for a ramp `width` wide.
fn ramp(distance: f64, width: f64) -> f64 {
    if width <= 0.0 {
        return 1.0;
    }
    let t = (distance / width).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A channel's display correction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DisplayCorrection {
    pub warp: Option<WarpMesh>,
    pub blend: Option<EdgeBlend>,
}

impl DisplayCorrection {
    pub fn is_none(&self) -> bool {
        self.warp.is_none() && self.blend.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn bad_grids_and_blends_are_refused() {
        assert!(matches!(
            WarpMesh::new(1, 3, vec![[0.0, 0.0]; 3]),
            Err(DisplayError::GridTooSmall { .. })
        ));
        assert!(matches!(
            WarpMesh::new(2, 2, vec![[0.0, 0.0]; 3]),
            Err(DisplayError::NodeCount { found: 3, .. })
        ));
        assert!(matches!(
            WarpMesh::new(
                2,
                2,
                vec![[0.0, 0.0], [f64::NAN, 0.0], [0.0, 1.0], [1.0, 1.0]]
            ),
            Err(DisplayError::BadNode { index: 1, .. })
        ));
        let blend = EdgeBlend {
            left: 0.6,
            right: 0.0,
            top: 0.0,
            bottom: 0.0,
            gamma: 2.2,
        };
        assert!(matches!(
            blend.validate(),
            Err(DisplayError::BadRamp { edge: "left", .. })
        ));
        let blend = EdgeBlend {
            left: 0.1,
            gamma: 0.0,
            ..blend
        };
        assert_eq!(blend.validate(), Err(DisplayError::BadGamma(0.0)));
    }

    proptest! {
        #[test]
        fn the_identity_grid_keeps_every_point(columns in 2u32..20, rows in 2u32..20, u in 0.0f64..=1.0, v in 0.0f64..=1.0) {
            let mesh = WarpMesh::identity(columns, rows).expect("a grid");
            let p = mesh.display_of(u, v).expect("on the grid");
            prop_assert!((p[0] - u).abs() < 1e-6 && (p[1] - v).abs() < 1e-6, "{p:?}");
        }

        #[test]
        fn two_overlapping_ramps_add_to_one_light(width in 0.01f64..0.5, t in 0.0f64..=1.0) {
            // The left projector's right ramp and the right one's left ramp over one overlap.
            let left = EdgeBlend { left: 0.0, right: width, top: 0.0, bottom: 0.0, gamma: 2.2 };
            let right = EdgeBlend { left: width, right: 0.0, ..left };
            let x_left = 1.0 - width + t * width;
            let x_right = t * width;
            let sum = left.light_weight(x_left, 0.5) + right.light_weight(x_right, 0.5);
            prop_assert!((sum - 1.0).abs() < 1e-9, "{sum}");
            // What reaches the screen from each is its value factor to the gamma.
            let light = left.value_factor(x_left, 0.5).powf(2.2) + right.value_factor(x_right, 0.5).powf(2.2);
            prop_assert!((light - 1.0).abs() < 1e-9, "{light}");
        }
    }

    #[test]
    fn a_keystone_grid_moves_points_as_its_triangles_do() {
        // The top edge drawn narrower: a keystone.
        let mesh = WarpMesh::new(2, 2, vec![[0.1, 0.0], [0.9, 0.0], [0.0, 1.0], [1.0, 1.0]])
            .expect("a grid");
        let corner = mesh.display_of(0.0, 0.0).expect("on the grid");
        assert!(
            (corner[0] - 0.1).abs() < 1e-6 && corner[1] == 0.0,
            "{corner:?}"
        );
        let top_middle = mesh.display_of(0.5, 0.0).expect("on the grid");
        assert!((top_middle[0] - 0.5).abs() < 1e-6);
        let p = mesh.display_of(0.25, 0.25).expect("on the grid");
        // In the first triangle: a + (b - a) 0.25 + (c - a) 0.25.
        assert!(
            (p[0] - (0.1 + 0.8 * 0.25 - 0.1 * 0.25)).abs() < 1e-6,
            "{p:?}"
        );
        assert_eq!(mesh.display_of(1.5, 0.0), None);
        assert_eq!(mesh.triangle_indices(), vec![0, 2, 1, 1, 2, 3]);
    }
}
