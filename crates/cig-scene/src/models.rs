//! Entity models: a procedural library (tank, truck, three ships - destroyer (also named
//! `ship`), merchant and patrol_craft - building, tree), each with three levels of detail, and
//! the mesh form glTF models are converted to.
//!
//! Algorithm: models are assembled from boxes, prisms, cylinders and cones with flat-shaded
//! faces (one normal per face), in a body frame with +X right, +Y forward and +Z up and the
//! origin on the ground under the model's centre (a ship's on its waterline). Each level of
//! detail is selected by the detail control parameter `N_e` (GE study, source 004 section
//! 4.7: the resolution elements the model's critical radius subtends, see [`crate::detail`]),
//! and within a combination zone of the table the two levels blend: each covers a
//! complementary share of the model's pixels (a screen-door dissolve, the GE study's gradual
//! transition, section 2), so a level change never pops; below the table's first step the
//! coarsest level dissolves away.
//!
//! Ships: each is built to its [`ShipParticulars`] (length, beam, draft, masthead height) on a
//! hull of sections at stations along its length (sheer rising to a raked stem, flare forward,
//! a transom aft), with the features that tell one type from another at a periscope's 6x
//! (source 001: 8 degree field): masts with yards and radars, bridge window bands, funnels,
//! guns, containers. The finest level has about 1000-2000 triangles (source 001's ship models
//! had 500-4000 edges); the coarser levels follow source 001's three ways down: fewer, larger
//! patches, detail that does not make the broadside silhouette left out, small parts merged
//! into simple solids (a lattice mast becomes a tapered block). Every level keeps the length
//! and the masthead, and the funnel's exhaust (a hot part for the thermal view).
//!
//! Limits: the dissolve is an ordered 4x4 dither (16 steps), visible as a fine pattern while a
//! model sits in a combination zone. The procedural models are built of flat-shaded boxes,
//! prisms and polygons: recognisable types, not models of a particular vehicle or ship class.
//! A ship's finest-level masts, yards and rails are struts 0.06-0.3 m across, under a pixel
//! beyond a few kilometres at 6x, drawn only where the rasteriser's samples fall on them; the
//! containers are blocks of two rows, the hull has no bulb, propellers, rudders or anchors.

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

/// Painted steel hull (thermal material 9) in haze grey.
const HAZE_HULL: [u8; 4] = coded([126, 132, 138, 255], 9);
/// Below the waterline: red anti-fouling (thermal material 9).
const ANTIFOULING: [u8; 4] = coded(HULL_RED, 9);
/// A warship's or patrol craft's non-skid deck, darker than the sides.
const DECK_GREY: [u8; 4] = coded([88, 92, 96, 255], 9);
/// Deck markings (flight deck circle and centre line).
const MARKING: [u8; 4] = coded(WHITE, 9);
/// Masts, yards and lattice members (superstructure steel).
const MAST: [u8; 4] = coded([100, 104, 110, 255], 10);
/// Radar antennas, domes and array faces.
const ANTENNA: [u8; 4] = coded([62, 64, 68, 255], 10);
/// A close-in weapon's radome (white).
const RADOME: [u8; 4] = coded([205, 207, 204, 255], 10);
/// Hangar doors, a shade darker than the superstructure.
const DOOR: [u8; 4] = coded([98, 102, 108, 255], 10);
/// Boats and life rafts (orange).
const BOAT: [u8; 4] = coded([214, 104, 34, 255], 10);
/// A merchant ship's black topsides.
const MERCHANT_BLACK: [u8; 4] = coded([34, 36, 40, 255], 9);
/// A merchant ship's red-brown deck and hatch covers.
const MERCHANT_DECK: [u8; 4] = coded([104, 62, 50, 255], 9);
/// White superstructure (accommodation, wheelhouse, merchant masts).
const WHITE_SUPER: [u8; 4] = coded(WHITE, 10);
/// A merchant funnel's red casing: engine heat, as [`ENGINE_DECK_GREY`].
const FUNNEL_RED: [u8; 4] = coded([150, 46, 38, 255], 32);
/// Container colours (painted steel).
const CONTAINERS: [[u8; 4]; 6] = [
    coded([150, 48, 40, 255], 9),
    coded([40, 70, 130, 255], 9),
    coded([52, 110, 70, 255], 9),
    coded([186, 186, 180, 255], 9),
    coded([170, 110, 40, 255], 9),
    coded([108, 108, 112, 255], 9),
];

/// What a built-in ship is built to: the figures its finest mesh measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShipParticulars {
    /// Length overall, transom to stem head (m).
    pub length_m: f64,
    /// Greatest breadth of the hull (m).
    pub beam_m: f64,
    /// Depth of the keel below the waterline, the model's origin (m).
    pub draft_m: f64,
    /// Metacentric height (m): the righting arm per radian of heel.
    pub metacentric_height_m: f64,
    /// Height of the highest masthead above the waterline (m).
    pub masthead_height_m: f64,
}

const DESTROYER: ShipParticulars = ShipParticulars {
    length_m: 150.0,
    beam_m: 18.0,
    draft_m: 5.5,
    metacentric_height_m: 1.5,
    masthead_height_m: 40.0,
};
const MERCHANT: ShipParticulars = ShipParticulars {
    length_m: 180.0,
    beam_m: 28.0,
    draft_m: 9.0,
    metacentric_height_m: 1.0,
    masthead_height_m: 38.0,
};
const PATROL_CRAFT: ShipParticulars = ShipParticulars {
    length_m: 40.0,
    beam_m: 7.0,
    draft_m: 2.0,
    metacentric_height_m: 0.8,
    masthead_height_m: 14.0,
};

/// The particulars a built-in ship's meshes are built to: length, beam, draft (the keel
/// below the model's origin) and masthead height are what its finest level measures, and
/// every level keeps the length and the masthead. `ship` is the destroyer. `None` for a name
/// that is not a built-in ship.
pub fn ship_particulars(name: &str) -> Option<ShipParticulars> {
    match name {
        "ship" | "destroyer" => Some(DESTROYER),
        "merchant" => Some(MERCHANT),
        "patrol_craft" => Some(PATROL_CRAFT),
        _ => None,
    }
}

/// Appends a flat polygon (a fan from its first corner), leaving out degenerate triangles.
fn polygon(m: &mut ModelMesh, corners: &[Vec3], colour: [u8; 4]) {
    for k in 1..corners.len().saturating_sub(1) {
        let (a, b, c) = (corners[0], corners[k], corners[k + 1]);
        if (b - a).cross(c - a).length_squared() > 1e-10 {
            m.tri(a, b, c, colour);
        }
    }
}

/// A deckhouse, gun house or funnel casing: a box from `min` to `max` whose top is drawn in
/// by `inset` (metres: each side, the after end, the fore end), so its sides slope.
fn add_block(m: &mut ModelMesh, min: Vec3, max: Vec3, inset: [f32; 3], colour: [u8; 4]) {
    let [ix, ia, ifw] = inset;
    let (a, b) = (min, max);
    let b00 = v(a.x, a.y, a.z);
    let b10 = v(b.x, a.y, a.z);
    let b11 = v(b.x, b.y, a.z);
    let b01 = v(a.x, b.y, a.z);
    let t00 = v(a.x + ix, a.y + ia, b.z);
    let t10 = v(b.x - ix, a.y + ia, b.z);
    let t11 = v(b.x - ix, b.y - ifw, b.z);
    let t01 = v(a.x + ix, b.y - ifw, b.z);
    polygon(m, &[t00, t10, t11, t01], colour);
    polygon(m, &[b01, b11, b10, b00], colour);
    polygon(m, &[b00, b10, t10, t00], colour);
    polygon(m, &[b11, b01, t01, t11], colour);
    polygon(m, &[b01, b00, t00, t01], colour);
    polygon(m, &[b10, b11, t11, t10], colour);
}

/// A band of windows from `z0` to `z1` on the front and both sides of a block made by
/// [`add_block`] with the same corners and insets (centred on x 0), just proud of its faces.
fn add_window_band(m: &mut ModelMesh, min: Vec3, max: Vec3, inset: [f32; 3], z: [f32; 2]) {
    let at = |z: f32| {
        let f = (z - min.z) / (max.z - min.z);
        (
            max.x - inset[0] * f,
            min.y + inset[1] * f,
            max.y - inset[2] * f,
        )
    };
    let (proud, margin) = (0.04, 0.25);
    let [z0, z1] = z;
    let ((x0, a0, f0), (x1, a1, f1)) = (at(z0), at(z1));
    polygon(
        m,
        &[
            v(x0 - margin, f0 + proud, z0),
            v(-x0 + margin, f0 + proud, z0),
            v(-x1 + margin, f1 + proud, z1),
            v(x1 - margin, f1 + proud, z1),
        ],
        GLASS,
    );
    polygon(
        m,
        &[
            v(x0 + proud, a0 + margin, z0),
            v(x0 + proud, f0 - margin, z0),
            v(x1 + proud, f1 - margin, z1),
            v(x1 + proud, a1 + margin, z1),
        ],
        GLASS,
    );
    polygon(
        m,
        &[
            v(-x0 - proud, f0 - margin, z0),
            v(-x0 - proud, a0 + margin, z0),
            v(-x1 - proud, a1 + margin, z1),
            v(-x1 - proud, f1 - margin, z1),
        ],
        GLASS,
    );
}

/// A thin member from `a` to `b` (a mast leg, a brace, a yard, a rail): a three-sided prism.
fn add_strut(m: &mut ModelMesh, a: Vec3, b: Vec3, r: f32, colour: [u8; 4]) {
    m.add_cylinder(a, b - a, r, r, 3, colour);
}

/// A four-legged lattice mast standing on `foot` up to `top_z`: legs `half[0]` from its axis
/// (along x and y) at the foot and `half[1]` at the head, `bays` braced bays (a ring and a
/// diagonal on each face per bay).
fn add_lattice_mast(
    m: &mut ModelMesh,
    foot: Vec3,
    top_z: f32,
    half: [f32; 2],
    bays: u32,
    colour: [u8; 4],
) {
    let corner = |level: u32, k: usize| {
        let f = level as f32 / bays as f32;
        let h = half[0] + (half[1] - half[0]) * f;
        let (sx, sy) = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)][k % 4];
        v(
            foot.x + sx * h,
            foot.y + sy * h,
            foot.z + (top_z - foot.z) * f,
        )
    };
    for k in 0..4 {
        add_strut(m, corner(0, k), corner(bays, k), 0.15, colour);
        for level in 1..=bays {
            add_strut(m, corner(level, k), corner(level, k + 1), 0.08, colour);
            let (from, to) = if level % 2 == 0 {
                (k, k + 1)
            } else {
                (k + 1, k)
            };
            add_strut(m, corner(level - 1, from), corner(level, to), 0.07, colour);
        }
    }
}

/// A flat octagon facing +y (a phased-array face) centred on `centre`.
fn add_octagon(m: &mut ModelMesh, centre: Vec3, r: f32, colour: [u8; 4]) {
    let corners: Vec<Vec3> = (0..8)
        .map(|k| {
            let a = (k as f32 + 0.5) * std::f32::consts::TAU / 8.0;
            centre + v(-r * a.cos(), 0.0, r * a.sin())
        })
        .collect();
    polygon(m, &corners, colour);
}

/// A close-in weapon system on `at`: a pedestal, the white radome and the barrels pointing
/// along `facing` (+1 forward, -1 aft).
fn add_ciws(m: &mut ModelMesh, at: Vec3, facing: f32, fine: bool) {
    let seg = if fine { 8 } else { 6 };
    if fine {
        m.add_cylinder(at, v(0.0, 0.0, 0.9), 0.9, 0.9, seg, SUPERSTRUCTURE);
    }
    let dome = at + v(0.0, 0.0, 0.9);
    m.add_cylinder(dome, v(0.0, 0.0, 1.2), 0.7, 0.7, seg, RADOME);
    m.add_cylinder(
        dome + v(0.0, 0.0, 1.2),
        v(0.0, 0.0, 0.5),
        0.7,
        0.0,
        seg,
        RADOME,
    );
    if fine {
        m.add_cylinder(
            dome + v(0.0, 0.5 * facing, 0.3),
            v(0.0, 1.9 * facing, 0.0),
            0.12,
            0.12,
            6,
            ANTENNA,
        );
    }
}

/// A hull's lines, in the body frame: transom at `-length / 2`, stem head at `+length / 2`,
/// the waterline at z 0 and the keel at `-draft`. A station `t` is the fraction of the length
/// from the transom.
struct HullLines {
    length: f32,
    beam: f32,
    draft: f32,
    /// Deck height at the transom, amidships and at the stem head: the sheer line (it must
    /// not fall towards the bow: deckhouses stand on the deck height at their after end).
    sheer: [f32; 3],
    /// Keel height at the transom (the run rises to it over the after quarter).
    transom_keel: f32,
    /// Waterline and deck half-breadths at the transom, fractions of the half beam.
    transom: [f32; 2],
    /// Where the parallel middle body starts and ends.
    middle_body: [f32; 2],
    /// Exponents of the waterline's and the deck edge's entrance: the deck's is larger, so
    /// the deck stays wide further forward than the waterline (the bow's flare).
    entrance: [f32; 2],
    /// How far aft of the stem head the forefoot lies (the stem's rake).
    rake: f32,
    /// Below the waterline, the topsides and the deck.
    colours: [[u8; 4]; 3],
}

/// The hull's stations (fractions of the length from the transom) and points per half
/// section at each level of detail. Coarser levels keep the transom and the stem head, so
/// the length does not change (source 001: fewer, larger planar patches at lower levels).
const HULL_STATIONS: [(&[f32], usize); 3] = [
    (
        &[
            0.0, 0.04, 0.1, 0.18, 0.26, 0.35, 0.45, 0.55, 0.63, 0.7, 0.77, 0.83, 0.88, 0.92, 0.955,
            0.98, 1.0,
        ],
        6,
    ),
    (&[0.0, 0.1, 0.25, 0.45, 0.65, 0.8, 0.9, 0.96, 1.0], 4),
    (&[0.0, 0.3, 0.7, 0.9, 1.0], 3),
];

impl HullLines {
    fn station(&self, y: f32) -> f32 {
        (y / self.length + 0.5).clamp(0.0, 1.0)
    }

    fn deck_at_station(&self, t: f32) -> f32 {
        let [aft, mid, bow] = self.sheer;
        if t < 0.45 {
            aft + (mid - aft) * t / 0.45
        } else {
            mid + (bow - mid) * ((t - 0.45) / 0.55).powi(2)
        }
    }

    /// Deck height at `y`.
    fn deck_z(&self, y: f32) -> f32 {
        self.deck_at_station(self.station(y))
    }

    fn keel_z(&self, t: f32) -> f32 {
        let run = (1.0 - t / 0.25).max(0.0);
        -self.draft + (self.transom_keel + self.draft) * run * run
    }

    /// Waterline and deck half-breadths at station `t`.
    fn half_breadths(&self, t: f32) -> (f32, f32) {
        let [m0, m1] = self.middle_body;
        let line = |transom: f32, entrance: f32| {
            if t < m0 {
                let u = 1.0 - t / m0;
                transom + (1.0 - transom) * (1.0 - u * u)
            } else if t <= m1 {
                1.0
            } else {
                1.0 - ((t - m1) / (1.0 - m1)).powf(entrance)
            }
        };
        let waterline = line(self.transom[0], self.entrance[0]).max(0.0);
        let deck = line(self.transom[1], self.entrance[1]).max(waterline);
        (self.beam / 2.0 * waterline, self.beam / 2.0 * deck)
    }

    /// The starboard half of the section at station `t`, keel (on the centreline) to deck
    /// edge, with `points` points (3, 4 or 6), and the index of its waterline point.
    fn section(&self, t: f32, points: usize) -> (Vec<Vec3>, usize) {
        let (hw, hd) = self.half_breadths(t);
        let (zk, zd) = (self.keel_z(t), self.deck_at_station(t));
        let (profile, waterline) = match points {
            3 => (vec![(0.0, zk), (hw, 0.0), (hd, zd)], 1),
            4 => (
                vec![(0.0, zk), (0.8 * hw, 0.55 * zk), (hw, 0.0), (hd, zd)],
                2,
            ),
            _ => (
                vec![
                    (0.0, zk),
                    (0.55 * hw, 0.92 * zk),
                    (0.9 * hw, 0.6 * zk),
                    (hw, 0.0),
                    (hw + 0.55 * (hd - hw), 0.45 * zd),
                    (hd, zd),
                ],
                3,
            ),
        };
        // The stem's rake: towards the bow each point lies aft of its station by a share of
        // the rake growing with its depth below the deck (never past the station aft of it).
        let start = 1.0 - 2.5 * self.rake / self.length;
        let rake = self.rake * ((t - start) / (1.0 - start)).clamp(0.0, 1.0).powi(2);
        let y = (t - 0.5) * self.length;
        let section = profile
            .into_iter()
            .map(|(x, z)| v(x, y - rake * (zd - z) / (zd - zk), z))
            .collect();
        (section, waterline)
    }

    /// The hull at a level of detail: both sides, the deck and the transom, closed.
    fn add_to(&self, m: &mut ModelMesh, level: usize) {
        let (stations, points) = HULL_STATIONS[level.min(2)];
        let [bottom, topsides, deck] = self.colours;
        let port = |p: Vec3| v(-p.x, p.y, p.z);
        let sections: Vec<(Vec<Vec3>, usize)> =
            stations.iter().map(|&t| self.section(t, points)).collect();
        // A side triangle lying on the centreline (between the keel and the stem) would be a
        // fin of no thickness, drawn twice facing both ways: left out, the hull stays closed.
        let side = |m: &mut ModelMesh, corners: [Vec3; 3], colour: [u8; 4]| {
            if corners.iter().any(|p| p.x.abs() > 1e-4) {
                polygon(m, &corners, colour);
            }
        };
        for pair in sections.windows(2) {
            let ((a, waterline), (b, _)) = (&pair[0], &pair[1]);
            for k in 0..a.len() - 1 {
                let colour = if k < *waterline { bottom } else { topsides };
                let (a0, a1, b0, b1) = (a[k], a[k + 1], b[k], b[k + 1]);
                side(m, [a0, b0, b1], colour);
                side(m, [a0, b1, a1], colour);
                side(m, [port(a0), port(a1), port(b1)], colour);
                side(m, [port(a0), port(b1), port(b0)], colour);
            }
            let (da, db) = (a[a.len() - 1], b[b.len() - 1]);
            polygon(m, &[port(da), da, db, port(db)], deck);
        }
        let aft = &sections[0].0;
        let mut transom = aft.clone();
        transom.extend(aft.iter().rev().take(aft.len() - 1).map(|&p| port(p)));
        polygon(m, &transom, topsides);
    }
}

fn destroyer_lines() -> HullLines {
    HullLines {
        length: DESTROYER.length_m as f32,
        beam: DESTROYER.beam_m as f32,
        draft: DESTROYER.draft_m as f32,
        sheer: [5.0, 6.5, 9.5],
        transom_keel: -1.5,
        transom: [0.55, 0.85],
        middle_body: [0.3, 0.55],
        entrance: [1.7, 2.6],
        rake: 10.0,
        colours: [ANTIFOULING, HAZE_HULL, DECK_GREY],
    }
}

/// A 150 m destroyer at a level of detail (0 finest): flush deck with sheer and flare, a gun
/// forward, vertical launchers fore and aft, a stepped forward superstructure with the bridge
/// and its window band, array faces, a lattice foremast with yards, radar and a topmast, two
/// funnels, a pole mainmast, a hangar and a flight deck.
fn destroyer_level(level: usize) -> ModelMesh {
    let lines = destroyer_lines();
    let d = |y: f32| lines.deck_z(y);
    let top = DESTROYER.masthead_height_m as f32;
    let fine = level == 0;
    let mut m = ModelMesh::default();
    lines.add_to(&mut m, level);
    // Superstructure: the 01 level forward, the midships deckhouse running aft into the
    // hangar, the 02 level and the bridge with its window band and wings.
    let bridge = (v(-5.5, 20.0, 15.4), v(5.5, 30.0, 18.5), [0.2, 0.0, 0.6]);
    if level == 2 {
        add_block(
            &mut m,
            v(-6.5, -46.0, d(-46.0) - 0.1),
            v(6.5, 34.0, 12.0),
            [0.3, 0.2, 1.0],
            SUPERSTRUCTURE,
        );
        add_block(
            &mut m,
            v(-6.0, 16.0, 11.9),
            v(6.0, 31.0, 18.5),
            [0.3, 0.0, 0.8],
            SUPERSTRUCTURE,
        );
    } else {
        add_block(
            &mut m,
            v(-7.0, 8.0, d(8.0) - 0.1),
            v(7.0, 34.0, 12.0),
            [0.4, 0.0, 1.0],
            SUPERSTRUCTURE,
        );
        add_block(
            &mut m,
            v(-6.0, -46.0, d(-46.0) - 0.1),
            v(6.0, 8.5, 12.0),
            [0.3, 0.2, 0.0],
            SUPERSTRUCTURE,
        );
        add_block(
            &mut m,
            v(-6.0, 16.0, 11.9),
            v(6.0, 31.0, 15.5),
            [0.3, 0.0, 0.0],
            SUPERSTRUCTURE,
        );
        add_block(&mut m, bridge.0, bridge.1, bridge.2, SUPERSTRUCTURE);
        add_window_band(&mut m, bridge.0, bridge.1, bridge.2, [16.9, 17.9]);
        m.add_box(v(-8.0, 25.0, 15.3), v(8.0, 29.0, 15.6), SUPERSTRUCTURE);
        // The hangar doors.
        for (x0, x1) in [(0.6_f32, 5.2_f32), (-5.2, -0.6)] {
            polygon(
                &mut m,
                &[
                    v(x0, -46.05, 6.2),
                    v(x1, -46.05, 6.2),
                    v(x1, -46.05, 11.0),
                    v(x0, -46.05, 11.0),
                ],
                DOOR,
            );
        }
    }
    if fine {
        // Wing bulwarks and the array faces either side of the 02 level's front.
        for s in [-1.0_f32, 1.0] {
            let (x0, x1) = (s * 5.5, s * 7.9);
            m.add_box(
                v(x0.min(x1), 25.0, 15.6),
                v(x0.max(x1), 29.0, 16.6),
                SUPERSTRUCTURE,
            );
            add_octagon(&mut m, v(s * 3.0, 31.05, 13.75), 1.5, ANTENNA);
        }
    }
    // The gun: a gun house with a sloped face on its ring, the barrel run out forward.
    let gz = d(45.5) - 0.05;
    if level == 2 {
        m.add_box(v(-1.7, 45.5, gz), v(1.7, 50.5, gz + 2.6), SUPERSTRUCTURE);
    } else {
        if fine {
            m.add_cylinder(
                v(0.0, 48.0, gz),
                v(0.0, 0.0, 0.5),
                1.9,
                1.9,
                8,
                SUPERSTRUCTURE,
            );
        }
        add_block(
            &mut m,
            v(-1.7, 45.5, gz + 0.4),
            v(1.7, 50.5, gz + 2.8),
            [0.5, 0.3, 1.8],
            SUPERSTRUCTURE,
        );
        m.add_cylinder(
            v(0.0, 49.2, gz + 1.5),
            v(0.0, 7.3, 0.7),
            0.16,
            0.12,
            if fine { 8 } else { 4 },
            SUPERSTRUCTURE,
        );
    }
    // Vertical launchers fore and aft, their cell hatches at the finest level.
    if level < 2 {
        for (y0, y1, rows) in [(36.0_f32, 44.0_f32, 4), (-54.0, -47.0, 3)] {
            let z1 = d(y1) + 0.6;
            m.add_box(v(-3.2, y0, d(y0) - 0.05), v(3.2, y1, z1), SUPERSTRUCTURE);
            if fine {
                let pitch = (y1 - y0 - 0.8) / rows as f32;
                for i in 0..rows {
                    let ya = y0 + 0.4 + i as f32 * pitch;
                    for (x0, x1) in [(0.3_f32, 2.9_f32), (-2.9, -0.3)] {
                        m.add_box(
                            v(x0, ya + 0.15, z1),
                            v(x1, ya + pitch - 0.15, z1 + 0.08),
                            DECK_GREY,
                        );
                    }
                }
            }
        }
        // Close-in weapons on the 01 level forward and the hangar roof aft.
        add_ciws(&mut m, v(0.0, 32.0, 12.0), 1.0, fine);
        add_ciws(&mut m, v(0.0, -42.0, 12.0), -1.0, fine);
        // Boats either side amidships.
        for s in [-1.0_f32, 1.0] {
            let (x0, x1) = (s * 6.4, s * 8.3);
            let z0 = d(-8.0) + 1.2;
            add_block(
                &mut m,
                v(x0.min(x1), -8.0, z0),
                v(x0.max(x1), -1.0, z0 + 1.0),
                [0.2, 0.3, 1.0],
                BOAT,
            );
            if fine {
                for y in [-7.0_f32, -2.0] {
                    add_strut(
                        &mut m,
                        v(s * 5.6, y, 11.5),
                        v(s * 7.35, y, 11.5),
                        0.08,
                        MAST,
                    );
                    add_strut(
                        &mut m,
                        v(s * 7.35, y, 11.5),
                        v(s * 7.35, y, z0 + 1.0),
                        0.06,
                        MAST,
                    );
                }
            }
        }
    }
    // The foremast on the bridge roof: a lattice with yards, a platform, the surface search
    // radar and a topmast with its dome up to the masthead.
    let (mast_y, roof) = (24.0, 18.5);
    if level == 2 {
        add_block(
            &mut m,
            v(-1.5, mast_y - 1.5, roof - 0.1),
            v(1.5, mast_y + 1.5, top),
            [1.15, 1.15, 1.15],
            MAST,
        );
        m.add_box(
            v(-5.0, mast_y - 0.2, 29.8),
            v(5.0, mast_y + 0.2, 30.2),
            MAST,
        );
    } else {
        if fine {
            add_lattice_mast(&mut m, v(0.0, mast_y, roof), 33.0, [1.5, 0.5], 4, MAST);
            add_strut(
                &mut m,
                v(-5.0, mast_y, 30.0),
                v(5.0, mast_y, 30.0),
                0.12,
                MAST,
            );
            add_strut(
                &mut m,
                v(-2.0, mast_y, 36.0),
                v(2.0, mast_y, 36.0),
                0.08,
                MAST,
            );
            for x in [-4.8_f32, 4.8] {
                add_strut(
                    &mut m,
                    v(x, mast_y, 30.0),
                    v(x, mast_y, 28.5),
                    0.04,
                    ANTENNA,
                );
            }
            m.add_cylinder(
                v(0.0, mast_y + 0.9, 33.25),
                v(0.0, 0.0, 0.5),
                0.25,
                0.25,
                6,
                MAST,
            );
        } else {
            add_block(
                &mut m,
                v(-1.5, mast_y - 1.5, roof - 0.1),
                v(1.5, mast_y + 1.5, 33.0),
                [1.0, 1.0, 1.0],
                MAST,
            );
            m.add_box(
                v(-5.0, mast_y - 0.12, 29.9),
                v(5.0, mast_y + 0.12, 30.1),
                MAST,
            );
        }
        m.add_box(
            v(-1.3, mast_y - 1.3, 33.0),
            v(1.3, mast_y + 1.3, 33.25),
            MAST,
        );
        m.add_box(
            v(-1.8, mast_y + 0.75, 33.75),
            v(1.8, mast_y + 1.05, 34.5),
            ANTENNA,
        );
        m.add_cylinder(
            v(0.0, mast_y, 33.25),
            v(0.0, 0.0, top - 33.25),
            0.18,
            0.1,
            if fine { 6 } else { 4 },
            MAST,
        );
        m.add_cylinder(
            v(0.0, mast_y, 37.0),
            v(0.0, 0.0, 1.2),
            0.55,
            0.55,
            if fine { 8 } else { 6 },
            ANTENNA,
        );
    }
    // Two funnels: casings warm with the engines, the uptakes' outlets are the exhaust.
    for (y0, y1) in [(0.0_f32, 8.0_f32), (-20.0, -12.0)] {
        let inset = [0.5, 0.6, 1.2];
        add_block(
            &mut m,
            v(-2.2, y0, 11.9),
            v(2.2, y1, 19.5),
            inset,
            ENGINE_DECK_GREY,
        );
        let (x, ya, yf) = (
            2.2 - inset[0] - 0.2,
            y0 + inset[1] + 0.2,
            y1 - inset[2] - 0.2,
        );
        if level == 2 {
            polygon(
                &mut m,
                &[
                    v(-x, ya, 19.55),
                    v(x, ya, 19.55),
                    v(x, yf, 19.55),
                    v(-x, yf, 19.55),
                ],
                EXHAUST,
            );
        } else {
            m.add_box(v(-x, ya, 19.5), v(x, yf, 19.8), EXHAUST);
        }
        if fine {
            for px in [-0.7_f32, 0.7] {
                for py in [ya + 1.3, yf - 1.3] {
                    m.add_cylinder(v(px, py, 19.8), v(0.0, 0.0, 0.7), 0.45, 0.45, 6, EXHAUST);
                }
            }
        }
    }
    // The pole mainmast aft of the second funnel.
    let aft_y = -24.0;
    if level == 2 {
        m.add_box(v(-0.4, aft_y - 0.4, 11.9), v(0.4, aft_y + 0.4, 30.0), MAST);
    } else {
        m.add_cylinder(
            v(0.0, aft_y, 11.9),
            v(0.0, 0.0, 18.1),
            0.3,
            0.12,
            if fine { 6 } else { 4 },
            MAST,
        );
        if fine {
            add_strut(
                &mut m,
                v(-3.0, aft_y, 26.0),
                v(3.0, aft_y, 26.0),
                0.08,
                MAST,
            );
            m.add_box(
                v(-0.8, aft_y + 0.2, 27.6),
                v(0.8, aft_y + 0.4, 28.2),
                ANTENNA,
            );
            for x in [-1.5_f32, 1.5] {
                add_strut(
                    &mut m,
                    v(x, aft_y - 2.0, 12.0),
                    v(0.0, aft_y, 20.0),
                    0.1,
                    MAST,
                );
            }
        } else {
            m.add_box(v(-3.0, aft_y - 0.1, 25.9), v(3.0, aft_y + 0.1, 26.1), MAST);
        }
    }
    if fine {
        // The flight deck's landing circle and centre line.
        let (cy, r, w) = (-64.0_f32, 4.5_f32, 0.3_f32);
        let on_deck = |x: f32, y: f32| v(x, y, d(y) + 0.03);
        for k in 0..16 {
            let a0 = k as f32 * std::f32::consts::TAU / 16.0;
            let a1 = (k + 1) as f32 * std::f32::consts::TAU / 16.0;
            let ring = |a: f32, r: f32| on_deck(r * a.cos(), cy + r * a.sin());
            polygon(
                &mut m,
                &[ring(a0, r), ring(a1, r), ring(a1, r - w), ring(a0, r - w)],
                MARKING,
            );
        }
        polygon(
            &mut m,
            &[
                on_deck(-0.15, -74.0),
                on_deck(0.15, -74.0),
                on_deck(0.15, -54.5),
                on_deck(-0.15, -54.5),
            ],
            MARKING,
        );
        // Jackstaff and ensign staff.
        for y in [73.5_f32, -74.5] {
            add_strut(
                &mut m,
                v(0.0, y, d(y) - 0.1),
                v(0.0, y, d(y) + 3.0),
                0.05,
                MAST,
            );
        }
    }
    m
}

/// The destroyer under `name` (`destroyer`, or `ship`, its older name).
fn destroyer(name: &str) -> Model {
    Model::new(name, (0..3).map(destroyer_level).collect())
}

fn merchant_lines() -> HullLines {
    HullLines {
        length: MERCHANT.length_m as f32,
        beam: MERCHANT.beam_m as f32,
        draft: MERCHANT.draft_m as f32,
        sheer: [7.0, 7.0, 10.0],
        transom_keel: -3.5,
        transom: [0.35, 0.85],
        middle_body: [0.22, 0.68],
        entrance: [2.0, 3.2],
        rake: 7.0,
        colours: [ANTIFOULING, MERCHANT_BLACK, MERCHANT_DECK],
    }
}

/// A 180 m container ship at a level of detail: long low hull, the accommodation aft with
/// the wheelhouse, its window band and bridge wings out to the ship's side, a radar mast, the
/// funnel aft of it, ten bays of containers forward, a breakwater and a foremast at the bow.
fn merchant_level(level: usize) -> ModelMesh {
    let lines = merchant_lines();
    let d = |y: f32| lines.deck_z(y);
    let top = MERCHANT.masthead_height_m as f32;
    let fine = level == 0;
    let mut m = ModelMesh::default();
    lines.add_to(&mut m, level);
    // The accommodation block and the wheelhouse, the wings out to the ship's side.
    let wheelhouse = (v(-9.0, -63.0, 24.9), v(9.0, -55.5, 28.5), [0.0, 0.0, 0.3]);
    if level == 2 {
        m.add_box(v(-11.5, -68.0, 6.9), v(11.5, -54.0, 25.0), WHITE_SUPER);
    } else {
        add_block(
            &mut m,
            v(-11.0, -88.5, 6.95),
            v(11.0, -66.0, 10.0),
            [0.1, 0.3, 0.0],
            WHITE_SUPER,
        );
        let lower = (v(-11.5, -68.0, 9.9), v(11.5, -54.0, 16.0), [0.0; 3]);
        let upper = (v(-10.0, -66.0, 15.9), v(10.0, -55.0, 25.0), [0.0; 3]);
        add_block(&mut m, lower.0, lower.1, lower.2, WHITE_SUPER);
        add_block(&mut m, upper.0, upper.1, upper.2, WHITE_SUPER);
        for z in [17.0_f32, 20.0, 23.0] {
            add_window_band(&mut m, upper.0, upper.1, upper.2, [z, z + 1.0]);
        }
        if fine {
            for z in [11.5_f32, 14.2] {
                add_window_band(&mut m, lower.0, lower.1, lower.2, [z, z + 0.9]);
            }
        }
        // Lifeboats either side of the accommodation.
        for s in [-1.0_f32, 1.0] {
            let (x0, x1) = (s * 10.2, s * 12.4);
            add_block(
                &mut m,
                v(x0.min(x1), -65.0, 16.5),
                v(x0.max(x1), -58.0, 19.0),
                [0.3, 0.8, 0.8],
                BOAT,
            );
        }
    }
    add_block(
        &mut m,
        wheelhouse.0,
        wheelhouse.1,
        wheelhouse.2,
        WHITE_SUPER,
    );
    add_window_band(
        &mut m,
        wheelhouse.0,
        wheelhouse.1,
        wheelhouse.2,
        [26.4, 27.8],
    );
    m.add_box(v(-13.8, -59.0, 24.9), v(13.8, -55.5, 25.3), WHITE_SUPER);
    if level < 2 {
        for s in [-1.0_f32, 1.0] {
            let (x0, x1) = (s * 9.0, s * 13.8);
            m.add_box(
                v(x0.min(x1), -59.0, 25.3),
                v(x0.max(x1), -55.5, 26.4),
                WHITE_SUPER,
            );
        }
    }
    // The radar mast on the wheelhouse roof, up to the masthead.
    let mast_y = -60.5;
    if level == 2 {
        m.add_box(
            v(-0.4, mast_y - 0.4, 28.4),
            v(0.4, mast_y + 0.4, top),
            WHITE_SUPER,
        );
    } else {
        m.add_cylinder(
            v(0.0, mast_y, 28.4),
            v(0.0, 0.0, top - 28.4),
            0.35,
            0.2,
            if fine { 8 } else { 4 },
            WHITE_SUPER,
        );
        if fine {
            add_strut(
                &mut m,
                v(-3.5, mast_y, 34.0),
                v(3.5, mast_y, 34.0),
                0.1,
                WHITE_SUPER,
            );
            m.add_box(v(-1.2, -62.5, 35.0), v(1.2, -59.0, 35.2), WHITE_SUPER);
            m.add_cylinder(v(0.0, -61.8, 35.2), v(0.0, 0.0, 0.4), 0.2, 0.2, 6, ANTENNA);
            // The X-band radar on its pedestal at the front of the wheelhouse roof.
            m.add_cylinder(
                v(0.0, -57.0, 28.4),
                v(0.0, 0.0, 1.2),
                0.25,
                0.25,
                6,
                WHITE_SUPER,
            );
            m.add_box(v(-1.8, -57.15, 29.6), v(1.8, -56.85, 30.0), ANTENNA);
        } else {
            m.add_box(
                v(-3.5, mast_y - 0.1, 33.9),
                v(3.5, mast_y + 0.1, 34.1),
                WHITE_SUPER,
            );
        }
        m.add_box(v(-2.6, -61.95, 35.6), v(2.6, -61.65, 36.0), ANTENNA);
    }
    // The funnel aft of the accommodation: a red casing with a black (exhaust) top.
    // (At the coarsest level there is no poop deck: the casing stands on the main deck.)
    let base = if level == 2 { 6.9 } else { 9.9 };
    let casing = (v(-3.5, -80.0, base), v(3.5, -70.0, 30.5), [0.6, 0.4, 1.5]);
    add_block(&mut m, casing.0, casing.1, casing.2, FUNNEL_RED);
    let (tx, ta, tf) = (3.5 - 0.6, -80.0 + 0.4, -70.0 - 1.5);
    if level == 2 {
        polygon(
            &mut m,
            &[
                v(-tx + 0.2, ta + 0.2, 30.55),
                v(tx - 0.2, ta + 0.2, 30.55),
                v(tx - 0.2, tf - 0.2, 30.55),
                v(-tx + 0.2, tf - 0.2, 30.55),
            ],
            EXHAUST,
        );
    } else {
        let per_m = 1.5 / (30.5 - base);
        add_block(
            &mut m,
            v(-tx, ta, 30.5),
            v(tx, tf, 32.0),
            [0.6 * per_m, 0.4 * per_m, 1.5 * per_m],
            EXHAUST,
        );
        if fine {
            for x in [-0.9_f32, 0.9] {
                m.add_cylinder(v(x, -75.5, 32.0), v(0.0, 0.0, 1.2), 0.5, 0.5, 8, EXHAUST);
            }
        }
    }
    // Containers: ten 40 ft bays on their hatch covers, narrowing into the bow.
    if level == 2 {
        m.add_box(v(-12.2, -51.0, 6.9), v(12.2, 52.2, 18.8), CONTAINERS[5]);
        m.add_box(
            v(-7.0, 53.0, d(53.0) - 0.1),
            v(7.0, 78.2, d(78.2) + 9.2),
            CONTAINERS[1],
        );
    } else {
        for bay in 0..10_usize {
            let y0 = -51.0 + 13.0 * bay as f32;
            let y1 = y0 + 12.2;
            let (_, half) = lines.half_breadths(lines.station(y1));
            let rows = (((2.0 * (half - 0.9)) / 2.44).floor() as usize).min(10) & !1;
            let x0 = -(rows as f32) * 1.22;
            let hatch = d(y1) + 1.4;
            // Stack heights and colours vary from stack to stack (a fixed scramble).
            let tiers = |group: usize| 3 + scramble(bay * 8 + group) % 3;
            let colour =
                |group: usize, k: usize| CONTAINERS[scramble(bay * 8 + group + 100 * k) % 6];
            if fine {
                m.add_box(
                    v(x0 - 0.3, y0 - 0.2, d(y0) - 0.05),
                    v(-x0 + 0.3, y1 + 0.2, hatch),
                    MERCHANT_DECK,
                );
                // Each stack of two rows: its lower tiers of one colour, its upper of another.
                for group in 0..rows / 2 {
                    let gx = x0 + group as f32 * 4.88;
                    let lower = 1 + scramble(bay * 8 + group + 50) % (tiers(group) - 1);
                    let z_split = hatch + 2.6 * lower as f32;
                    m.add_box(
                        v(gx + 0.02, y0, hatch),
                        v(gx + 4.86, y1, z_split),
                        colour(group, 1),
                    );
                    m.add_box(
                        v(gx + 0.02, y0, z_split),
                        v(gx + 4.86, y1, hatch + 2.6 * tiers(group) as f32),
                        colour(group, 2),
                    );
                }
            } else {
                let high = (0..rows / 2).map(tiers).max().unwrap_or(2);
                m.add_box(
                    v(x0, y0, d(y0) - 0.05),
                    v(-x0, y1, hatch + 2.6 * high as f32),
                    colour(0, 1),
                );
            }
        }
        // The breakwater across the forecastle.
        m.add_box(
            v(-6.0, 79.0, d(79.0) - 0.05),
            v(6.0, 79.6, d(79.6) + 1.8),
            WHITE_SUPER,
        );
    }
    // The foremast at the bow.
    let fore_y = 84.0;
    if level == 2 {
        m.add_box(
            v(-0.3, fore_y - 0.3, d(fore_y) - 0.1),
            v(0.3, fore_y + 0.3, 22.0),
            WHITE_SUPER,
        );
    } else {
        m.add_cylinder(
            v(0.0, fore_y, d(fore_y) - 0.1),
            v(0.0, 0.0, 22.0 - d(fore_y) + 0.1),
            0.3,
            0.18,
            if fine { 8 } else { 4 },
            WHITE_SUPER,
        );
        if fine {
            add_strut(
                &mut m,
                v(-1.8, fore_y, 19.5),
                v(1.8, fore_y, 19.5),
                0.07,
                WHITE_SUPER,
            );
            m.add_box(
                v(-0.6, fore_y - 0.6, 17.5),
                v(0.6, fore_y + 0.6, 17.7),
                WHITE_SUPER,
            );
            for x in [-2.2_f32, 2.2] {
                m.add_box(
                    v(x - 0.6, 80.5, d(80.5) - 0.05),
                    v(x + 0.6, 82.0, d(82.0) + 1.0),
                    ANTENNA,
                );
            }
        } else {
            m.add_box(
                v(-1.8, fore_y - 0.1, 19.4),
                v(1.8, fore_y + 0.1, 19.6),
                WHITE_SUPER,
            );
        }
    }
    m
}

/// A fixed scramble of a number (a 32-bit integer hash), for the containers' variety.
fn scramble(k: usize) -> usize {
    let mut x = (k as u32).wrapping_mul(0x9E37_79B9);
    x ^= x >> 15;
    x = x.wrapping_mul(0x85EB_CA6B);
    x ^= x >> 13;
    x as usize
}

fn merchant() -> Model {
    Model::new("merchant", (0..3).map(merchant_level).collect())
}

fn patrol_craft_lines() -> HullLines {
    HullLines {
        length: PATROL_CRAFT.length_m as f32,
        beam: PATROL_CRAFT.beam_m as f32,
        draft: PATROL_CRAFT.draft_m as f32,
        sheer: [2.6, 2.9, 4.2],
        transom_keel: -1.0,
        transom: [0.85, 0.95],
        middle_body: [0.25, 0.5],
        entrance: [1.5, 2.6],
        rake: 5.0,
        colours: [ANTIFOULING, HAZE_HULL, DECK_GREY],
    }
}

/// A 40 m patrol craft at a level of detail: a fast hull with a raked bow and a wide
/// transom, the deckhouse with the bridge's sloped windows, a tripod mast with the radar, a
/// small gun forward, a boat aft, an exhaust stack and exhausts in the transom.
fn patrol_craft_level(level: usize) -> ModelMesh {
    let lines = patrol_craft_lines();
    let d = |y: f32| lines.deck_z(y);
    let top = PATROL_CRAFT.masthead_height_m as f32;
    let fine = level == 0;
    let mut m = ModelMesh::default();
    lines.add_to(&mut m, level);
    add_block(
        &mut m,
        v(-2.6, -8.0, d(-8.0) - 0.05),
        v(2.6, 5.0, 5.6),
        [0.2, 0.2, 0.5],
        SUPERSTRUCTURE,
    );
    let bridge = (v(-2.3, -1.0, 5.55), v(2.3, 4.3, 7.8), [0.25, 0.0, 0.9]);
    add_block(&mut m, bridge.0, bridge.1, bridge.2, SUPERSTRUCTURE);
    if level < 2 {
        add_window_band(&mut m, bridge.0, bridge.1, bridge.2, [6.3, 7.3]);
    }
    // The mast on the bridge roof, the radar on a platform forward of it.
    let mast_y = 0.5;
    if level == 2 {
        m.add_box(v(-0.2, mast_y - 0.2, 7.75), v(0.2, mast_y + 0.2, top), MAST);
    } else {
        m.add_cylinder(
            v(0.0, mast_y, 7.75),
            v(0.0, 0.0, top - 7.75),
            0.1,
            0.06,
            if fine { 6 } else { 4 },
            MAST,
        );
        m.add_box(v(-1.0, 1.1, 12.55), v(1.0, 1.3, 12.8), ANTENNA);
        if fine {
            for x in [-1.2_f32, 1.2] {
                add_strut(&mut m, v(x, -0.6, 7.75), v(0.0, mast_y, 11.0), 0.05, MAST);
            }
            add_strut(
                &mut m,
                v(-1.5, mast_y, 12.0),
                v(1.5, mast_y, 12.0),
                0.05,
                MAST,
            );
            m.add_box(v(-0.5, 0.4, 12.2), v(0.5, 1.6, 12.3), MAST);
            m.add_cylinder(v(0.0, 1.2, 12.3), v(0.0, 0.0, 0.25), 0.12, 0.12, 8, MAST);
        } else {
            m.add_box(
                v(-1.5, mast_y - 0.05, 11.95),
                v(1.5, mast_y + 0.05, 12.05),
                MAST,
            );
        }
    }
    // The gun forward: a ring, a shielded mount and the barrel.
    let gz = d(10.0) - 0.05;
    if level < 2 {
        if fine {
            m.add_cylinder(
                v(0.0, 10.6, gz),
                v(0.0, 0.0, 0.45),
                0.55,
                0.55,
                8,
                SUPERSTRUCTURE,
            );
        }
        add_block(
            &mut m,
            v(-0.6, 10.0, gz + 0.45),
            v(0.6, 11.2, gz + 1.25),
            [0.1, 0.1, 0.3],
            SUPERSTRUCTURE,
        );
        m.add_cylinder(
            v(0.0, 10.9, gz + 0.85),
            v(0.0, 2.4, 0.12),
            0.05,
            0.05,
            if fine { 6 } else { 4 },
            SUPERSTRUCTURE,
        );
    }
    // The exhaust stack at the after end of the deckhouse, and the exhausts in the transom.
    add_block(
        &mut m,
        v(-0.7, -7.4, 5.55),
        v(0.7, -5.6, 6.9),
        [0.15, 0.0, 0.4],
        ENGINE_DECK_GREY,
    );
    if level == 2 {
        polygon(
            &mut m,
            &[
                v(-0.45, -7.3, 6.95),
                v(0.45, -7.3, 6.95),
                v(0.45, -6.2, 6.95),
                v(-0.45, -6.2, 6.95),
            ],
            EXHAUST,
        );
    } else {
        m.add_box(v(-0.45, -7.3, 6.9), v(0.45, -6.2, 7.05), EXHAUST);
        for x in [-1.6_f32, 1.6] {
            m.add_box(
                v(x - 0.25, -20.08, 0.35),
                v(x + 0.25, -19.95, 0.85),
                EXHAUST,
            );
        }
        // The boat on the after deck.
        add_block(
            &mut m,
            v(-1.1, -16.5, d(-16.5) + 0.25),
            v(1.1, -11.5, d(-16.5) + 0.95),
            [0.2, 0.3, 0.9],
            BOAT,
        );
    }
    if fine {
        // Life rafts on the deckhouse roof and guard rails along the deck edge.
        for x in [0.6_f32, -1.7] {
            m.add_cylinder(
                v(x, -3.5, 5.95),
                v(1.1, 0.0, 0.0),
                0.35,
                0.35,
                8,
                WHITE_SUPER,
            );
        }
        let (stations, _) = HULL_STATIONS[0];
        let rail: Vec<Vec3> = stations[1..stations.len() - 1]
            .iter()
            .map(|&t| {
                let (section, _) = lines.section(t, 3);
                section[2] + v(-0.1, 0.0, 1.0)
            })
            .collect();
        for pair in rail.windows(2) {
            for s in [-1.0_f32, 1.0] {
                let side = |p: Vec3| v(s * p.x, p.y, p.z);
                add_strut(&mut m, side(pair[0]), side(pair[1]), 0.03, MAST);
            }
        }
    }
    m
}

fn patrol_craft() -> Model {
    Model::new("patrol_craft", (0..3).map(patrol_craft_level).collect())
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

/// The names of the built-in models (`ship` is the destroyer under its older name).
pub const BUILTIN_MODELS: [&str; 8] = [
    "tank",
    "truck",
    "ship",
    "destroyer",
    "merchant",
    "patrol_craft",
    "building",
    "tree",
];

/// A built-in model by name.
pub fn builtin(name: &str) -> Option<Model> {
    match name {
        "tank" => Some(tank()),
        "truck" => Some(truck()),
        "ship" | "destroyer" => Some(destroyer(name)),
        "merchant" => Some(merchant()),
        "patrol_craft" => Some(patrol_craft()),
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
                // Nothing below the ground, or below a ship's keel.
                let floor = ship_particulars(name).map_or(0.0, |p| -p.draft_m as f32);
                assert!(
                    lod.vertices.iter().all(|v| v.position[2] >= floor - 0.01),
                    "{name} below keel"
                );
            }
        }
        assert!(builtin("zeppelin").is_none());
    }

    const SHIPS: [&str; 4] = ["ship", "destroyer", "merchant", "patrol_craft"];

    /// The corners of the box holding every vertex.
    fn extent(mesh: &ModelMesh) -> (Vec3, Vec3) {
        mesh.vertices.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(v.position.into()), hi.max(v.position.into())),
        )
    }

    fn within(got: f32, want: f64, tolerance: f64) -> bool {
        (f64::from(got) - want).abs() <= want * tolerance
    }

    #[test]
    fn each_ship_measures_its_particulars() {
        for name in SHIPS {
            let p = ship_particulars(name).expect("a ship");
            let m = builtin(name).expect("built in");
            assert_eq!(m.name, name);
            assert!(BUILTIN_MODELS.contains(&name), "{name}");
            let (lo, hi) = extent(&m.lods[0]);
            assert!(
                within(hi.y - lo.y, p.length_m, 0.03),
                "{name}: length {lo} {hi}"
            );
            assert!(
                within(hi.x - lo.x, p.beam_m, 0.05),
                "{name}: beam {lo} {hi}"
            );
            assert!(
                within(hi.z, p.masthead_height_m, 0.02),
                "{name}: masthead {hi}"
            );
            assert!(within(-lo.z, p.draft_m, 0.05), "{name}: draft {lo}");
            // Centred on the origin, fore and aft.
            assert!((hi.y + lo.y).abs() < 0.03 * hi.y, "{name}: {lo} {hi}");
            assert!(p.metacentric_height_m > 0.0 && p.metacentric_height_m < p.beam_m / 4.0);
        }
        assert_eq!(
            builtin("ship").map(|m| m.lods),
            builtin("destroyer").map(|m| m.lods)
        );
        assert!(ship_particulars("tank").is_none());
        assert!(ship_particulars("building").is_none());
    }

    #[test]
    fn ship_levels_get_coarser_but_keep_length_and_masthead() {
        for name in SHIPS {
            let p = ship_particulars(name).expect("a ship");
            let m = builtin(name).expect("built in");
            let tris: Vec<usize> = m.lods.iter().map(ModelMesh::triangle_count).collect();
            assert!(tris[0] > tris[1] && tris[1] > tris[2], "{name}: {tris:?}");
            assert!((500..=5000).contains(&tris[0]), "{name}: {tris:?}");
            assert!(tris[2] <= 200, "{name}: {tris:?}");
            for (level, lod) in m.lods.iter().enumerate() {
                let (lo, hi) = extent(lod);
                assert!(
                    within(hi.y - lo.y, p.length_m, 0.05),
                    "{name} level {level}: length {lo} {hi}"
                );
                assert!(
                    within(hi.z, p.masthead_height_m, 0.05),
                    "{name} level {level}: masthead {hi}"
                );
            }
        }
    }

    #[test]
    fn every_ship_level_has_a_hot_exhaust_and_unit_normals_facing_out() {
        use crate::thermal::{decode, ThermalCode};
        use cig_thermal::HotPart;
        for name in SHIPS {
            let p = ship_particulars(name).expect("a ship");
            let m = builtin(name).expect("built in");
            for (level, lod) in m.lods.iter().enumerate() {
                assert!(
                    lod.vertices
                        .iter()
                        .any(|v| decode(v.colour[3]) == ThermalCode::Hot(HotPart::Exhaust)),
                    "{name} level {level} has no exhaust"
                );
                // Every surface says its material: none falls back on the instance default
                // (which `crate::thermal` chooses by model name).
                assert!(
                    lod.vertices
                        .iter()
                        .all(|v| v.colour[3] != crate::thermal::DEFAULT_CODE),
                    "{name} level {level} has an uncoded surface"
                );
                for v in &lod.vertices {
                    let n = Vec3::from(v.normal);
                    assert!(
                        n.is_finite() && (n.length() - 1.0).abs() < 1e-3,
                        "{name} level {level}: normal {n}"
                    );
                }
                // Faces wound outwards: the closed parts enclose a positive volume, the hull's
                // below the waterline alone more than a third of its block.
                let volume: f32 = lod
                    .indices
                    .chunks_exact(3)
                    .map(|t| {
                        let p = |i: u32| Vec3::from(lod.vertices[i as usize].position);
                        p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0
                    })
                    .sum();
                let block = p.length_m * p.beam_m * p.draft_m;
                assert!(
                    f64::from(volume) > block / 3.0,
                    "{name} level {level}: volume {volume} against {block}"
                );
            }
        }
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
