//! Entity models: a procedural library (tank, truck, ship, building, tree), each with three
//! levels of detail, and the mesh form glTF models are converted to.
//!
//! Algorithm: models are assembled from boxes, prisms, cylinders and cones with flat-shaded
//! faces (one normal per face), in a body frame with +X right, +Y forward and +Z up and the
//! origin on the ground under the model's centre. Each level of detail is selected by the
//! detail control parameter `N_e` (GE study, source 004 section 4.7: the resolution elements
//! the model's critical radius subtends, see [`crate::detail`]), and within a combination zone
//! of the table the two levels blend: each covers a complementary share of the model's pixels
//! (a screen-door dissolve, the GE study's gradual transition, section 2), so a level change
//! never pops; below the table's first step the coarsest level dissolves away.
//!
//! Limits: the dissolve is an ordered 4x4 dither (16 steps), visible as a fine pattern while a
//! model sits in a combination zone; the procedural models are recognisable shapes, not training-grade
//! models.

use glam::Vec3;

/// One vertex of a model: body-frame position (metres), normal and sRGB colour.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ModelVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub colour: [u8; 4],
}

/// A triangle list.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelMesh {
    pub vertices: Vec<ModelVertex>,
    pub indices: Vec<u32>,
}

impl ModelMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends a flat-shaded triangle.
    pub fn tri(&mut self, a: Vec3, b: Vec3, c: Vec3, colour: [u8; 4]) {
        let n = (b - a).cross(c - a).normalize_or_zero();
        let base = self.vertices.len() as u32;
        for p in [a, b, c] {
            self.vertices.push(ModelVertex {
                position: p.to_array(),
                normal: n.to_array(),
                colour,
            });
        }
        self.indices.extend_from_slice(&[base, base + 1, base + 2]);
    }

    pub(crate) fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3, colour: [u8; 4]) {
        self.tri(a, b, c, colour);
        self.tri(a, c, d, colour);
    }

    /// An axis-aligned box from `min` to `max`.
    pub fn add_box(&mut self, min: Vec3, max: Vec3, colour: [u8; 4]) {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let (a, b) = (min, max);
        self.quad(
            p(a.x, a.y, b.z),
            p(b.x, a.y, b.z),
            p(b.x, b.y, b.z),
            p(a.x, b.y, b.z),
            colour,
        ); // top
        self.quad(
            p(a.x, b.y, a.z),
            p(b.x, b.y, a.z),
            p(b.x, a.y, a.z),
            p(a.x, a.y, a.z),
            colour,
        ); // bottom
        self.quad(
            p(a.x, a.y, a.z),
            p(b.x, a.y, a.z),
            p(b.x, a.y, b.z),
            p(a.x, a.y, b.z),
            colour,
        ); // back
        self.quad(
            p(b.x, b.y, a.z),
            p(a.x, b.y, a.z),
            p(a.x, b.y, b.z),
            p(b.x, b.y, b.z),
            colour,
        ); // front
        self.quad(
            p(a.x, b.y, a.z),
            p(a.x, a.y, a.z),
            p(a.x, a.y, b.z),
            p(a.x, b.y, b.z),
            colour,
        ); // left
        self.quad(
            p(b.x, a.y, a.z),
            p(b.x, b.y, a.z),
            p(b.x, b.y, b.z),
            p(b.x, a.y, b.z),
            colour,
        ); // right
    }

    /// A frustum of a cone (a cylinder when the radii are equal; a cone when `r1` is 0) along
    /// `axis` from `base`, with `segments` sides and caps.
    pub fn add_cylinder(
        &mut self,
        base: Vec3,
        axis: Vec3,
        r0: f32,
        r1: f32,
        segments: u32,
        colour: [u8; 4],
    ) {
        let dir = axis.normalize_or_zero();
        let helper = if dir.z.abs() < 0.9 { Vec3::Z } else { Vec3::X };
        let u = dir.cross(helper).normalize_or_zero();
        let v = dir.cross(u);
        let top = base + axis;
        let ring = |r: f32, c: Vec3, k: u32| {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            c + (u * a.cos() + v * a.sin()) * r
        };
        for k in 0..segments {
            let (b0, b1) = (ring(r0, base, k), ring(r0, base, k + 1));
            let (t0, t1) = (ring(r1, top, k), ring(r1, top, k + 1));
            if r1 > 0.0 {
                self.quad(b0, b1, t1, t0, colour);
                self.tri(top, t0, t1, colour);
            } else {
                self.tri(b0, b1, top, colour);
            }
            self.tri(base, b1, b0, colour);
        }
    }

    /// Appends another mesh.
    pub fn append(&mut self, other: &ModelMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Radius of the sphere around the body origin that holds every vertex.
    pub fn bounding_radius_m(&self) -> f32 {
        self.vertices
            .iter()
            .map(|v| Vec3::from(v.position).length())
            .fold(0.0, f32::max)
    }
}

/// A model with its levels of detail, finest first.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    pub name: String,
    pub lods: Vec<ModelMesh>,
    pub bounding_radius_m: f32,
    /// The critical radius `r_c` of the detail control parameter (source 004, Eq 16), when
    /// set apart from the bounding radius (see [`Model::critical_radius_m`]).
    pub critical_radius_m: Option<f32>,
}

pub use crate::detail::LodBlend;

impl Model {
    pub fn new(name: &str, lods: Vec<ModelMesh>) -> Model {
        let bounding_radius_m = lods
            .iter()
            .map(ModelMesh::bounding_radius_m)
            .fold(0.0, f32::max);
        Model {
            name: name.to_string(),
            lods,
            bounding_radius_m,
            critical_radius_m: None,
        }
    }

    /// The critical radius of the detail control parameter: the one set, else the bounding
    /// radius of the model's levels.
    pub fn critical_radius_m(&self) -> f32 {
        self.critical_radius_m
            .filter(|r| r.is_finite() && *r > 0.0)
            .unwrap_or(self.bounding_radius_m)
    }

    /// The levels to draw at a detail control parameter `ne` (see [`crate::detail`]), and how
    /// they share the model's pixels.
    ///
    /// In a pure zone of the table one level is drawn whole. In a combination zone the finer
    /// and the coarser level are both drawn, each on a complementary share of the pixels; the
    /// finer level's share falls linearly in `N_e` across the zone, so as a model recedes its
    /// detail dissolves into the coarser level and never pops; below the table's first step
    /// the coarsest level fades out. The choice depends on `N_e` alone (no memory of the last
    /// frame), so every frame and every IG agrees.
    pub fn lod_blend(&self, ne: f64, table: &crate::detail::DetailTable) -> LodBlend {
        table.levels_for(ne, self.lods.len())
    }
}

const OLIVE: [u8; 4] = [86, 92, 58, 255];
const DARK: [u8; 4] = [40, 40, 38, 255];
const GREY: [u8; 4] = [118, 122, 128, 255];

/// A colour with a thermal code in its alpha (crate::thermal).
const fn coded(colour: [u8; 4], code: u8) -> [u8; 4] {
    [colour[0], colour[1], colour[2], code]
}

/// Tracks and wheels: running gear that warms with motion.
const TRACKS: [u8; 4] = coded(DARK, 32 + 2);
/// Engine deck grilles (dark olive).
const ENGINE_DECK: [u8; 4] = coded([70, 76, 48, 255], 32);
/// Exhaust outlets (soot black).
const EXHAUST: [u8; 4] = coded([30, 28, 26, 255], 32 + 1);
/// A crew member's head and shoulders.
const CREW: [u8; 4] = coded([96, 84, 64, 255], 32 + 3);
/// A ship's funnel casing (engine heat, haze grey).
const ENGINE_DECK_GREY: [u8; 4] = coded([104, 108, 112, 255], 32);
/// Window glass (thermal material 12).
const GLASS: [u8; 4] = coded([52, 60, 70, 255], 12);
/// Ship superstructure grey (thermal material 10).
const SUPERSTRUCTURE: [u8; 4] = coded(GREY, 10);
const HULL_RED: [u8; 4] = [110, 40, 36, 255];
const WHITE: [u8; 4] = [220, 220, 215, 255];
const WALL: [u8; 4] = [196, 184, 160, 255];
const ROOF: [u8; 4] = [132, 60, 46, 255];
const BARK: [u8; 4] = [84, 62, 40, 255];
const LEAF: [u8; 4] = [46, 84, 40, 255];

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

fn tank() -> Model {
    // Every level keeps the engine deck at the rear of the hull top (a FLIR sees it far away).
    let mut l2 = ModelMesh::default();
    l2.add_box(v(-1.8, -3.5, 0.0), v(1.8, 3.5, 2.3), OLIVE);
    l2.add_box(v(-1.1, -3.4, 2.3), v(1.1, -1.8, 2.35), ENGINE_DECK);
    let mut l1 = ModelMesh::default();
    l1.add_box(v(-1.8, -3.5, 0.4), v(1.8, 3.5, 1.6), OLIVE);
    l1.add_box(v(-1.2, -1.5, 1.6), v(1.2, 1.2, 2.4), OLIVE);
    l1.add_box(v(-0.1, 1.2, 1.9), v(0.1, 5.8, 2.1), DARK);
    l1.add_box(v(-1.1, -3.4, 1.6), v(1.1, -1.8, 1.65), ENGINE_DECK);
    let mut l0 = ModelMesh::default();
    l0.add_box(v(-1.3, -3.5, 0.5), v(1.3, 3.3, 1.6), OLIVE);
    l0.add_box(v(-1.9, -3.6, 0.0), v(-1.3, 3.6, 1.0), TRACKS);
    l0.add_box(v(1.3, -3.6, 0.0), v(1.9, 3.6, 1.0), TRACKS);
    l0.add_box(v(-1.9, -3.6, 1.0), v(1.9, 3.6, 1.15), OLIVE);
    l0.add_box(v(-1.2, -1.6, 1.6), v(1.2, 1.3, 2.35), OLIVE);
    l0.add_cylinder(v(0.0, 1.3, 2.0), v(0.0, 4.6, 0.0), 0.09, 0.08, 10, DARK);
    l0.add_cylinder(v(0.5, -0.6, 2.35), v(0.0, 0.0, 0.3), 0.3, 0.3, 10, OLIVE);
    // The commander's head out of the hatch, the engine deck grilles and two exhausts.
    l0.add_cylinder(v(0.5, -0.6, 2.65), v(0.0, 0.0, 0.3), 0.14, 0.12, 8, CREW);
    l0.add_box(v(-1.1, -3.4, 1.6), v(1.1, -1.8, 1.65), ENGINE_DECK);
    for x in [-0.8_f32, 0.8] {
        l0.add_box(v(x - 0.25, -3.62, 0.9), v(x + 0.25, -3.5, 1.3), EXHAUST);
    }
    Model::new("tank", vec![l0, l1, l2])
}

fn truck() -> Model {
    let mut l2 = ModelMesh::default();
    l2.add_box(v(-1.2, -3.5, 0.0), v(1.2, 3.5, 3.0), OLIVE);
    let mut l1 = ModelMesh::default();
    l1.add_box(v(-1.2, 1.5, 0.5), v(1.2, 3.5, 2.6), OLIVE);
    l1.add_box(v(-1.2, -3.5, 0.5), v(1.2, 1.4, 3.0), OLIVE);
    l1.add_box(v(-1.2, -3.5, 0.0), v(1.2, 3.5, 0.5), DARK);
    l1.add_box(v(-0.9, 3.5, 0.9), v(0.9, 3.56, 1.6), ENGINE_DECK);
    let mut l0 = ModelMesh::default();
    l0.add_box(v(-1.2, 1.5, 0.9), v(1.2, 3.5, 2.6), OLIVE);
    l0.add_box(v(-1.15, 2.6, 1.9), v(1.15, 3.52, 2.4), GLASS);
    l0.add_box(v(-1.25, -3.5, 1.0), v(1.25, 1.4, 3.0), OLIVE);
    l0.add_box(v(-1.0, -3.5, 0.6), v(1.0, 3.4, 0.9), DARK);
    for y in [2.5_f32, -0.8, -2.4] {
        for x in [-1.05_f32, 1.05] {
            l0.add_cylinder(v(x - 0.15, y, 0.5), v(0.3, 0.0, 0.0), 0.5, 0.5, 12, TRACKS);
        }
    }
    // The radiator grille at the front and the exhaust stack behind the cab.
    l0.add_box(v(-0.9, 3.5, 0.95), v(0.9, 3.56, 1.6), ENGINE_DECK);
    l0.add_cylinder(v(1.1, 1.45, 1.0), v(0.0, 0.0, 2.2), 0.07, 0.07, 8, EXHAUST);
    Model::new("truck", vec![l0, l1, l2])
}

fn ship() -> Model {
    // A 90 m frigate-like hull: tall mast so curvature hides the hull first.
    let hull = |m: &mut ModelMesh, detailed: bool| {
        let (bow, stern, beam, deck, keel) = (45.0, -45.0, 6.0, 6.0, -3.0);
        let p = [
            v(-beam, stern, keel),
            v(beam, stern, keel),
            v(beam * 0.9, 30.0, keel),
            v(0.0, bow, keel + 2.0),
            v(-beam * 0.9, 30.0, keel),
        ];
        let q = p.map(|x| v(x.x * 1.05, x.y, deck));
        for k in 0..5 {
            let k1 = (k + 1) % 5;
            m.quad(
                p[k],
                p[k1],
                q[k1],
                q[k],
                HULL_RED.map(|c| if detailed { c } else { c / 2 + 60 }),
            );
        }
        m.tri(q[0], q[1], q[2], GREY);
        m.tri(q[0], q[2], q[3], GREY);
        m.tri(q[0], q[3], q[4], GREY);
    };
    // The funnel: its casing warms with the engines, its top is the exhaust.
    let funnel = |m: &mut ModelMesh| {
        m.add_box(v(-1.6, -18.0, 13.0), v(1.6, -14.0, 18.5), ENGINE_DECK_GREY);
        m.add_box(v(-1.3, -17.7, 18.5), v(1.3, -14.3, 18.8), EXHAUST);
    };
    let mut l0 = ModelMesh::default();
    hull(&mut l0, true);
    l0.add_box(v(-4.5, -20.0, 6.0), v(4.5, 8.0, 13.0), SUPERSTRUCTURE);
    l0.add_box(v(-3.0, -12.0, 13.0), v(3.0, 2.0, 17.0), SUPERSTRUCTURE);
    l0.add_cylinder(
        v(0.0, -4.0, 17.0),
        v(0.0, 0.0, 20.0),
        0.6,
        0.25,
        8,
        SUPERSTRUCTURE,
    );
    l0.add_box(v(-4.0, -4.2, 29.0), v(4.0, -3.8, 29.4), SUPERSTRUCTURE);
    l0.add_cylinder(
        v(0.0, 20.0, 6.0),
        v(0.0, 0.0, 2.5),
        2.0,
        1.6,
        12,
        SUPERSTRUCTURE,
    );
    l0.add_cylinder(v(0.0, 20.0, 7.5), v(0.0, 8.0, 0.0), 0.15, 0.12, 8, DARK);
    l0.add_box(v(-2.0, -30.0, 13.0), v(2.0, -25.0, 15.0), WHITE);
    funnel(&mut l0);
    let mut l1 = ModelMesh::default();
    hull(&mut l1, true);
    l1.add_box(v(-4.5, -20.0, 6.0), v(4.5, 8.0, 13.0), SUPERSTRUCTURE);
    l1.add_box(v(-3.0, -12.0, 13.0), v(3.0, 2.0, 17.0), SUPERSTRUCTURE);
    l1.add_cylinder(
        v(0.0, -4.0, 17.0),
        v(0.0, 0.0, 20.0),
        0.6,
        0.25,
        4,
        SUPERSTRUCTURE,
    );
    funnel(&mut l1);
    let mut l2 = ModelMesh::default();
    hull(&mut l2, false);
    l2.add_box(v(-4.5, -20.0, 6.0), v(4.5, 8.0, 17.0), SUPERSTRUCTURE);
    l2.add_box(v(-0.5, -4.5, 17.0), v(0.5, -3.5, 37.0), SUPERSTRUCTURE);
    l2.add_box(v(-1.6, -18.0, 17.0), v(1.6, -14.0, 18.8), ENGINE_DECK_GREY);
    Model::new("ship", vec![l0, l1, l2])
}

fn building() -> Model {
    let roof = |m: &mut ModelMesh| {
        let (w, d, h, r) = (6.0, 8.0, 6.0, 9.0);
        m.quad(v(-w, -d, h), v(w, -d, h), v(w, 0.0, r), v(-w, 0.0, r), ROOF);
        m.quad(v(w, d, h), v(-w, d, h), v(-w, 0.0, r), v(w, 0.0, r), ROOF);
        m.tri(v(-w, d, h), v(-w, -d, h), v(-w, 0.0, r), WALL);
        m.tri(v(w, -d, h), v(w, d, h), v(w, 0.0, r), WALL);
    };
    let mut l0 = ModelMesh::default();
    l0.add_box(v(-6.0, -8.0, 0.0), v(6.0, 8.0, 6.0), WALL);
    roof(&mut l0);
    for y in [-5.0_f32, 0.0, 5.0] {
        for z in [1.2_f32, 4.0] {
            l0.add_box(v(-6.05, y - 0.7, z), v(6.05, y + 0.7, z + 1.2), DARK);
        }
    }
    l0.add_box(v(2.5, -8.6, 6.0), v(3.5, -7.6, 9.5), WALL);
    let mut l1 = ModelMesh::default();
    l1.add_box(v(-6.0, -8.0, 0.0), v(6.0, 8.0, 6.0), WALL);
    roof(&mut l1);
    let mut l2 = ModelMesh::default();
    l2.add_box(v(-6.0, -8.0, 0.0), v(6.0, 8.0, 7.5), WALL);
    Model::new("building", vec![l0, l1, l2])
}

fn tree() -> Model {
    let mut l0 = ModelMesh::default();
    l0.add_cylinder(v(0.0, 0.0, 0.0), v(0.0, 0.0, 3.0), 0.3, 0.22, 8, BARK);
    l0.add_cylinder(v(0.0, 0.0, 2.0), v(0.0, 0.0, 5.0), 2.6, 0.0, 12, LEAF);
    l0.add_cylinder(v(0.0, 0.0, 4.5), v(0.0, 0.0, 4.5), 2.0, 0.0, 12, LEAF);
    let mut l1 = ModelMesh::default();
    l1.add_cylinder(v(0.0, 0.0, 0.0), v(0.0, 0.0, 2.0), 0.3, 0.3, 4, BARK);
    l1.add_cylinder(v(0.0, 0.0, 2.0), v(0.0, 0.0, 7.0), 2.6, 0.0, 6, LEAF);
    let mut l2 = ModelMesh::default();
    l2.add_cylinder(v(0.0, 0.0, 0.0), v(0.0, 0.0, 9.0), 2.4, 0.0, 3, LEAF);
    Model::new("tree", vec![l0, l1, l2])
}

/// The names of the built-in models.
pub const BUILTIN_MODELS: [&str; 5] = ["tank", "truck", "ship", "building", "tree"];

/// A built-in model by name.
pub fn builtin(name: &str) -> Option<Model> {
    match name {
        "tank" => Some(tank()),
        "truck" => Some(truck()),
        "ship" => Some(ship()),
        "building" => Some(building()),
        "tree" => Some(tree()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_model_has_three_levels_getting_coarser() {
        for name in BUILTIN_MODELS {
            let m = builtin(name).expect("builtin");
            assert_eq!(m.lods.len(), 3, "{name}");
            let tris: Vec<usize> = m.lods.iter().map(ModelMesh::triangle_count).collect();
            assert!(tris[0] > tris[1] && tris[1] > tris[2], "{name}: {tris:?}");
            assert!(m.bounding_radius_m > 1.0);
            for lod in &m.lods {
                assert!(lod
                    .indices
                    .iter()
                    .all(|&i| (i as usize) < lod.vertices.len()));
                assert!(
                    lod.vertices.iter().all(|v| v.position[2] >= -3.01),
                    "{name} below keel"
                );
            }
        }
        assert!(builtin("zeppelin").is_none());
    }

    #[test]
    fn lod_blend_follows_ne_and_dissolves_across_each_switch() {
        use crate::detail::DetailTable;
        let m = builtin("tank").expect("tank");
        let table = DetailTable::default();
        let single = |ne: f64, level: usize| {
            assert_eq!(m.lod_blend(ne, &table), LodBlend::single(level), "N_e {ne}");
        };
        single(500.0, 0);
        single(f64::INFINITY, 0);
        single(30.0, 1);
        single(4.0, 2);
        // Gone where N_e is 0 or not a number (removed by the fog), fading below step 1.
        assert_eq!(m.lod_blend(f64::NAN, &table).coverage, 0.0);
        assert_eq!(m.lod_blend(-3.0, &table).coverage, 0.0);
        assert!((m.lod_blend(0.75, &table).coverage - 0.5).abs() < 1e-6);
        // Across the switch to the finest level (step 6, N_e 54) the finer share falls from 1
        // to 0 as N_e falls.
        let mut last_share = 1.0;
        for step in 0..=40 {
            let ne = 60.0 - f64::from(step) * 0.5;
            let blend = m.lod_blend(ne, &table);
            let share = if blend.coarser.is_some() {
                assert_eq!((blend.finer, blend.coarser), (0, Some(1)), "N_e {ne}");
                blend.finer_share
            } else if blend.finer == 0 {
                1.0
            } else {
                0.0
            };
            assert!(
                share <= last_share + 1e-6,
                "N_e {ne}: {share} after {last_share}"
            );
            assert!(
                last_share - share < 0.1,
                "N_e {ne}: jumps from {last_share} to {share}"
            );
            last_share = share;
        }
        assert_eq!(last_share, 0.0);
        // Half way through the combination zone the two levels share the pixels equally.
        let (start, end) = table.blend_zone(6);
        let mid = m.lod_blend((start + end) / 2.0, &table);
        assert!((mid.finer_share - 0.5).abs() < 1e-6, "{mid:?}");
        let (start, end) = table.blend_zone(3);
        let second = m.lod_blend((start + end) / 2.0, &table);
        assert_eq!((second.finer, second.coarser), (1, Some(2)));
        // A set critical radius replaces the bounding radius.
        let mut set = m.clone();
        set.critical_radius_m = Some(2.0);
        assert_eq!(set.critical_radius_m(), 2.0);
        assert_eq!(m.critical_radius_m(), m.bounding_radius_m);
    }
}

/// A cell of the clustering grid.
type Cell = (i32, i32, i32);
/// Sum of positions, count and sum of colours of the vertices of one cell.
type ClusterSum = (Vec3, u32, [u32; 4]);

/// A coarser version of `mesh` by vertex clustering (Rossignac and Borrel, 1993): vertices are
/// snapped to a grid of `cells` cells along the mesh's largest extent, vertices of one cell
/// merge at their mean, and triangles that collapse are dropped. Flat normals are recomputed.
/// Limits: topology is not preserved (thin parts may vanish), which is what a distant level
/// wants.
pub fn simplify_by_clustering(mesh: &ModelMesh, cells: u32) -> ModelMesh {
    let cells = cells.max(1);
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for v in &mesh.vertices {
        lo = lo.min(Vec3::from(v.position));
        hi = hi.max(Vec3::from(v.position));
    }
    let extent = (hi - lo).max_element().max(1e-6);
    let cell = extent / cells as f32;
    let key = |p: Vec3| {
        let q = ((p - lo) / cell).floor();
        (q.x as i32, q.y as i32, q.z as i32)
    };
    let mut clusters: std::collections::BTreeMap<Cell, ClusterSum> =
        std::collections::BTreeMap::new();
    for v in &mesh.vertices {
        let e = clusters
            .entry(key(Vec3::from(v.position)))
            .or_insert((Vec3::ZERO, 0, [0; 4]));
        e.0 += Vec3::from(v.position);
        e.1 += 1;
        for (acc, c) in e.2[..3].iter_mut().zip(v.colour) {
            *acc += u32::from(c);
        }
        // The alpha is a thermal code (crate::thermal), not a colour: the cluster keeps its
        // first vertex's.
        if e.1 == 1 {
            e.2[3] = u32::from(v.colour[3]);
        }
    }
    let index_of: std::collections::BTreeMap<Cell, usize> =
        clusters.keys().enumerate().map(|(i, k)| (*k, i)).collect();
    let centres: Vec<(Vec3, [u8; 4])> = clusters
        .values()
        .map(|(sum, n, c)| {
            let rgb = |i: usize| (c[i] / n) as u8;
            (*sum / *n as f32, [rgb(0), rgb(1), rgb(2), c[3] as u8])
        })
        .collect();
    let mut out = ModelMesh::default();
    let mut seen = std::collections::BTreeSet::new();
    for t in mesh.indices.chunks_exact(3) {
        let Some(ids) = t
            .iter()
            .map(|&i| {
                mesh.vertices
                    .get(i as usize)
                    .and_then(|v| index_of.get(&key(Vec3::from(v.position))).copied())
            })
            .collect::<Option<Vec<usize>>>()
        else {
            continue;
        };
        let (a, b, c) = (ids[0], ids[1], ids[2]);
        if a == b || b == c || a == c {
            continue;
        }
        // One triangle per cluster triple and winding.
        let rot = if a <= b && a <= c {
            (a, b, c)
        } else if b <= a && b <= c {
            (b, c, a)
        } else {
            (c, a, b)
        };
        if !seen.insert(rot) {
            continue;
        }
        out.tri(centres[a].0, centres[b].0, centres[c].0, centres[a].1);
    }
    out
}

/// A model from one finest mesh, with two coarser levels made by vertex clustering.
pub fn model_with_generated_lods(name: &str, mesh: ModelMesh) -> Model {
    let lod1 = simplify_by_clustering(&mesh, 24);
    let lod2 = simplify_by_clustering(&mesh, 6);
    Model::new(name, vec![mesh, lod1, lod2])
}

#[cfg(test)]
mod simplify_tests {
    use super::*;

    #[test]
    fn clustering_reduces_triangles_and_keeps_the_extent() {
        let mut mesh = ModelMesh::default();
        mesh.add_cylinder(
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 10.0),
            3.0,
            1.0,
            48,
            [200, 100, 50, 255],
        );
        let model = model_with_generated_lods("cyl", mesh.clone());
        let tris: Vec<usize> = model.lods.iter().map(ModelMesh::triangle_count).collect();
        assert!(
            tris[0] > tris[1] && tris[1] > tris[2] && tris[2] > 0,
            "{tris:?}"
        );
        let r0 = mesh.bounding_radius_m();
        let r2 = model.lods[2].bounding_radius_m();
        assert!((r0 - r2).abs() < r0 * 0.3, "{r0} vs {r2}");
    }
}
