//! Dynamic terrain in an exercise: craters from DIS Detonations, and terrain edits carried
//! between nodes as DIS Point and Linear Object State PDUs.
//!
//! Algorithm (source 002, "terrain changes sent to other nodes"; IEEE 1278.1-2012 Synthetic
//! Environment family): a Detonation whose result is a ground impact (`cig_dis::detonation::
//! classify_result`) at or near the database's surface makes a crater whose size is cube-root
//! scaling of its charge (`cig_dynterrain::crater`) in the soil of the database's material under
//! it; the charge is the Explosion descriptor's explosive force, or the munition table's
//! effective charge for the Munition descriptor's entity type and warhead
//! (`cig_dynterrain::munitions`). Its identity is the detonation's event (site, application,
//! event number) and its time the event's, so every IG on the same database that hears the PDU
//! makes the same crater, and hearing it twice changes nothing (its sequence number is the
//! event number over [`DETONATION_SEQUENCES`], apart from the edits a simulation sends as
//! objects). An air burst (more than [`AIR_BURST_M`] above the database's own ground), a burst
//! on water, or an expendable makes none.
//!
//! Edits travel as Object State PDUs (`cig_dis::object_state`): a crater is a Point Object of
//! SISO-REF-010 type crater (1.1.3, subcategory by size) whose specific appearance carries its
//! radius and depth in centimetres (low and high 16 bits; the lip follows from them, 1.25 R
//! and D / 4); a fighting position is a vehicle defilade (1.2.1.4) or infantry fighting
//! position (1.2.2) with its length and width in decimetres and depth in centimetres packed
//! into the specific appearance (9, 9 and 10 bits) and its heading in the orientation; ruts,
//! ditches and berms are one-segment Linear Objects (rut 1.1.5; tank ditch 1.1.1, a berm being
//! a tank ditch of no depth) whose segment gives the centre, the heading (orientation), length,
//! width, height (the berm's; a ditch's spoil follows from its cut) and depth, the spoil's side
//! in the specific appearance's low two bits. An edit's identity is its object identifier (site, application,
//! object number = sequence). A node applies the edit as decoded from its own PDU, so sender
//! and receivers draw the same numbers. Every edit a node holds is announced again every
//! [`REANNOUNCE_S`] (spread over the period), so a node that joins late gets every earlier
//! edit; receivers ignore the ones they hold. A healed edit is sent with its general
//! appearance's state deactivated (SISO-REF-010 UID 229, bit 11, [`DEACTIVATED`]): receivers
//! remove it and remember it healed, ignoring its re-announcements from nodes that missed the
//! heal, and every node announces the heals it knows again with the edits (at most
//! [`MAX_HEALS_KEPT`], the newest), so the exercise settles on the healed ground.
//!
//! A CIGI host asks for craters with cig's user-defined Terrain Edit Request
//! ([`TerrainEditRequest`]; CIGI has no crater packet): a crater from a charge goes through
//! the same scaling as the operator's `cig db crater` ([`crater_at`]), and is this IG's edit
//! numbered [`HOST_REQUEST_SEQUENCES`] over the host's request id, sent like the others.
//!
//! Limits: height patches are not sent (the Gridded Data PDU is not implemented); other
//! sequence numbers above 65535 are not sent (DIS object numbers are 16-bit),
//! and event numbers wrap at 65536 (a later crater with a reused event number is taken for
//! the earlier one).
//! The specific appearance fields for sizes are cig's use of bits the standard leaves to the
//! object type: another IG reads the object's type and place but not its size.

use cig_cigi::{ByteOrder, UserDefined, Version};
use cig_dis::dis_rs::detonation::model::{Detonation, DetonationDescriptor};
use cig_dis::object_state::{
    LinearObjectState, LinearSegment, ObjectId, ObjectType, PointObjectState, SimulationAddress,
};
use cig_dis::{DisMessage, EulerAngles};
use cig_dynterrain::crater::CraterDimensions;
use cig_dynterrain::soil::SoilMoisture;
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint, SpoilSide, TerrainEdit};
use cig_terrain::{Material, QuerySession};
use glam::{DMat3, DVec3};

/// A detonation more than this above the ground is an air burst: no crater.
pub const AIR_BURST_M: f64 = 3.0;
/// Every edit is announced again within this period, seconds.
pub const REANNOUNCE_S: f64 = 10.0;
/// The general appearance's state bit (SISO-REF-010 UID 229, bit 11): the object is
/// deactivated, an edit healed.
pub const DEACTIVATED: u16 = 1 << 11;
/// Heals a node remembers and announces again (the newest).
pub const MAX_HEALS_KEPT: usize = 4096;

/// The crater a detonation makes, if any, at `time_utc_s` (the event's time).
pub fn crater_of_detonation(
    detonation: &Detonation,
    time_utc_s: f64,
    query: &mut QuerySession,
    moisture: SoilMoisture,
) -> Option<TerrainEdit> {
    let code = u8::from(detonation.detonation_result);
    let (surface, _) = cig_dis::detonation::classify_result(code)?;
    if surface != cig_dis::ImpactSurface::Ground {
        return None;
    }
    let l = &detonation.location_in_world_coordinates;
    let ecef = DVec3::new(l.x_coordinate, l.y_coordinate, l.z_coordinate);
    if !ecef.is_finite() || ecef.length() < 6.0e6 {
        return None;
    }
    let at = Geodetic::from_ecef(ecef);
    let ground = query.hot(at.lat_deg, at.lon_deg).ok()?;
    // Against the database's own ground, not the edited one: whether a crater is made does
    // not depend on the edits an IG already holds.
    let edited_m = query.edits().delta_m(at.lat_deg, at.lon_deg);
    let above_m = at.alt_m - (ground.height_ellipsoid_m() - edited_m);
    if !(-50.0..=AIR_BURST_M).contains(&above_m) {
        return None;
    }
    let charge_kg = match &detonation.descriptor {
        DetonationDescriptor::Munition(m) => {
            let t = &m.entity_type;
            cig_dynterrain::munitions::effective_charge_kg(
                cig_dynterrain::munitions::MunitionType::new(
                    u8::from(t.kind),
                    u8::from(t.domain),
                    u16::from(t.country),
                    t.category,
                    t.subcategory,
                    t.specific,
                    t.extra,
                ),
                u16::from(m.warhead),
                m.quantity,
            )
        }
        DetonationDescriptor::Explosion(e) => f64::from(e.explosive_force),
        DetonationDescriptor::Expendable(_) => return None,
    };
    let dims = cig_dynterrain::crater::dimensions(ground.material, moisture, charge_kg).ok()??;
    let event = &detonation.event_id;
    let edit = TerrainEdit {
        author: EditAuthor {
            site: event.simulation_address.site_id,
            application: event.simulation_address.application_id,
        },
        sequence: DETONATION_SEQUENCES | u32::from(event.event_id),
        time_utc_s,
        shape: crater_shape(
            GeoPoint {
                lat_deg: at.lat_deg,
                lon_deg: at.lon_deg,
            },
            &dims,
        ),
    };
    Some(as_sent(edit))
}

/// An edit as every node that gets it over DIS has it (sizes through their PDU fields), or
/// itself when it is not sent: nodes apply the decoded form of their own edits, so sender and
/// receivers draw the same numbers.
pub fn as_sent(edit: TerrainEdit) -> TerrainEdit {
    pdu_of_edit(&edit, 0.0)
        .and_then(|m| edit_of_pdu(&m, edit.time_utc_s))
        .unwrap_or(edit)
}

/// Sequence numbers of craters made from Detonations: this bit over the event number, so they
/// never meet the object numbers of edits sent as Object State PDUs by the same simulation
/// (sent with [`DETONATION_MODIFICATION`] set in the Point Object's modifications).
pub const DETONATION_SEQUENCES: u32 = 0x1_0000;
/// cig's mark, in a Point Object State's modifications octet, of a crater named by its
/// Detonation's event.
pub const DETONATION_MODIFICATION: u8 = 0x80;
/// Sequence numbers of craters a CIGI host asked this IG for ([`TerrainEditRequest`]): this
/// bit over the host's request id, so they never meet the object numbers of the ruts and
/// other edits this IG numbers from its last one ([`RutTracker`], which skips this space) nor
/// the Detonations' craters (sent with [`HOST_REQUEST_MODIFICATION`] set).
pub const HOST_REQUEST_SEQUENCES: u32 = 0x8000_0000;
/// cig's mark, in a Point Object State's modifications octet, of a crater named by its host's
/// request id (bits 0 and 1 are the standard's location and orientation flags).
pub const HOST_REQUEST_MODIFICATION: u8 = 0x40;
/// Craters named apart from object numbers: (sequence space, mark in the modifications).
const NAMED_CRATER_SPACES: [(u32, u8); 2] = [
    (DETONATION_SEQUENCES, DETONATION_MODIFICATION),
    (HOST_REQUEST_SEQUENCES, HOST_REQUEST_MODIFICATION),
];
/// The author of the edits this IG makes when it has joined no exercise (in one, its DIS
/// simulation address).
pub const LOCAL_AUTHOR: EditAuthor = EditAuthor {
    site: 0,
    application: 1,
};

/// DIS Euler angles of a level heading at a place.
fn orientation_of_heading(at: Geodetic, heading_rad: f64) -> [f32; 3] {
    let frame = EnuFrame::new(at);
    let forward = frame.enu_vector_to_ecef(DVec3::new(heading_rad.sin(), heading_rad.cos(), 0.0));
    let right = frame.enu_vector_to_ecef(DVec3::new(heading_rad.cos(), -heading_rad.sin(), 0.0));
    let down = frame.enu_vector_to_ecef(DVec3::new(0.0, 0.0, -1.0));
    let e = EulerAngles::from_body_to_world(DMat3::from_cols(forward, right, down));
    [e.psi_rad as f32, e.theta_rad as f32, e.phi_rad as f32]
}

/// The level heading (radians clockwise from north) of DIS Euler angles at a place.
fn heading_of_orientation(at: Geodetic, orientation: [f32; 3]) -> f64 {
    let e = EulerAngles {
        psi_rad: f64::from(orientation[0]),
        theta_rad: f64::from(orientation[1]),
        phi_rad: f64::from(orientation[2]),
    };
    let forward = EnuFrame::new(at).ecef_vector_to_enu(e.body_to_world().col(0));
    forward.x.atan2(forward.y)
}

fn centimetres(m: f64) -> u32 {
    (m * 100.0).round().clamp(0.0, 65535.0) as u32
}

/// The Object State PDU that carries an edit (placed at `height_ellipsoid_m`), or `None` for
/// an edit that is not sent (see the module's limits).
pub fn pdu_of_edit(edit: &TerrainEdit, height_ellipsoid_m: f64) -> Option<DisMessage> {
    // A crater named apart from the object numbers: its number within its space, marked.
    let mark = match edit.shape {
        EditShape::Crater { .. } => NAMED_CRATER_SPACES
            .iter()
            .find(|(space, _)| edit.sequence & !0xffff == *space)
            .map(|(_, mark)| *mark),
        _ => None,
    };
    let object = if mark.is_some() {
        (edit.sequence & 0xffff) as u16
    } else {
        u16::try_from(edit.sequence).ok()?
    };
    let id = ObjectId {
        site: edit.author.site,
        application: edit.author.application,
        object,
    };
    let address = SimulationAddress {
        site: 0xffff,
        application: 0xffff,
    };
    let place = |p: GeoPoint| Geodetic::new(p.lat_deg, p.lon_deg, height_ellipsoid_m);
    let point = |object_type: ObjectType, at: Geodetic, orientation: [f32; 3], specific: u32| {
        DisMessage::PointObjectState(Box::new(PointObjectState {
            object_id: id,
            referenced_object_id: id,
            update_number: 1,
            force_id: 0,
            modifications: mark.unwrap_or(0),
            object_type,
            location_ecef_m: at.to_ecef().to_array(),
            orientation_rad: orientation,
            specific_appearance: specific,
            general_appearance: 0,
            requester: address,
            receiver: address,
        }))
    };
    let linear = |object_type: ObjectType,
                  from: GeoPoint,
                  to: GeoPoint,
                  width_m: f64,
                  height_m: f64,
                  depth_m: f64,
                  specific: u32| {
        let (mn, me) = cig_geo::metres_per_degree(from.lat_deg);
        let (dx, dy) = (
            (to.lon_deg - from.lon_deg) * me,
            (to.lat_deg - from.lat_deg) * mn,
        );
        let centre = Geodetic::new(
            from.lat_deg + 0.5 * dy / mn,
            from.lon_deg + 0.5 * dx / me,
            height_ellipsoid_m,
        );
        DisMessage::LinearObjectState(Box::new(LinearObjectState {
            object_id: id,
            referenced_object_id: id,
            update_number: 1,
            force_id: 0,
            requester: address,
            receiver: address,
            object_type,
            segments: vec![LinearSegment {
                segment_number: 1,
                modifications: 0,
                general_appearance: 0,
                specific_appearance: specific,
                location_ecef_m: centre.to_ecef().to_array(),
                orientation_rad: orientation_of_heading(centre, dx.atan2(dy)),
                length_m: dx.hypot(dy) as f32,
                width_m: width_m as f32,
                height_m: height_m as f32,
                depth_m: depth_m as f32,
            }],
        }))
    };
    Some(match &edit.shape {
        EditShape::Crater {
            centre,
            radius_m,
            depth_m,
            ..
        } => {
            let size = if *radius_m < 1.0 {
                ObjectType::POINT_CRATER_SMALL
            } else if *radius_m < 3.0 {
                ObjectType::POINT_CRATER_MEDIUM
            } else {
                ObjectType::POINT_CRATER_LARGE
            };
            point(
                size,
                place(*centre),
                [0.0; 3],
                centimetres(*radius_m) | (centimetres(*depth_m) << 16),
            )
        }
        EditShape::Position {
            centre,
            heading_deg,
            length_m,
            width_m,
            depth_m,
        } => {
            let at = place(*centre);
            let dm = |m: f64| ((m * 10.0).round() as u32).min(511);
            let kind = if *width_m < 2.0 {
                ObjectType::POINT_INFANTRY_FIGHTING_POSITION
            } else {
                ObjectType::POINT_VEHICLE_DEFILADE_TANK
            };
            point(
                kind,
                at,
                orientation_of_heading(at, heading_deg.to_radians()),
                dm(*length_m) | (dm(*width_m) << 9) | (centimetres(*depth_m).min(1023) << 18),
            )
        }
        EditShape::Rut {
            from,
            to,
            width_m,
            depth_m,
        } => linear(
            ObjectType::LINEAR_RUT,
            *from,
            *to,
            *width_m,
            0.0,
            *depth_m,
            0,
        ),
        EditShape::Ditch {
            from,
            to,
            width_m,
            depth_m,
            spoil,
        } => linear(
            ObjectType::LINEAR_TANK_DITCH,
            *from,
            *to,
            *width_m,
            0.0,
            *depth_m,
            match spoil {
                SpoilSide::Both => 0,
                SpoilSide::Left => 1,
                SpoilSide::Right => 2,
            },
        ),
        EditShape::Berm {
            from,
            to,
            width_m,
            height_m,
        } => linear(
            ObjectType::LINEAR_TANK_DITCH,
            *from,
            *to,
            *width_m,
            *height_m,
            0.0,
            0,
        ),
        EditShape::HeightPatch { .. } => return None,
    })
}

/// The Object State PDU that heals an edit: [`pdu_of_edit`]'s with its general appearance
/// (the point's or every segment's) deactivated.
pub fn heal_pdu_of_edit(edit: &TerrainEdit, height_ellipsoid_m: f64) -> Option<DisMessage> {
    let mut message = pdu_of_edit(edit, height_ellipsoid_m)?;
    match &mut message {
        DisMessage::PointObjectState(p) => p.general_appearance |= DEACTIVATED,
        DisMessage::LinearObjectState(l) => {
            for segment in &mut l.segments {
                segment.general_appearance |= DEACTIVATED;
            }
        }
        _ => {}
    }
    Some(message)
}

/// Whether an Object State PDU deactivates its object (a point's general appearance, or a
/// linear object's first segment's).
pub fn is_deactivated(message: &DisMessage) -> bool {
    match message {
        DisMessage::PointObjectState(p) => p.general_appearance & DEACTIVATED != 0,
        DisMessage::LinearObjectState(l) => l
            .segments
            .first()
            .is_some_and(|s| s.general_appearance & DEACTIVATED != 0),
        _ => false,
    }
}

/// The edit an Object State PDU carries, if it is one cig reads, made at `time_utc_s`.
pub fn edit_of_pdu(message: &DisMessage, time_utc_s: f64) -> Option<TerrainEdit> {
    let edit = |id: ObjectId, shape: EditShape| TerrainEdit {
        author: EditAuthor {
            site: id.site,
            application: id.application,
        },
        sequence: u32::from(id.object),
        time_utc_s,
        shape,
    };
    let geodetic = |ecef: [f64; 3]| {
        let v = DVec3::from_array(ecef);
        (v.is_finite() && v.length() > 6.0e6).then(|| Geodetic::from_ecef(v))
    };
    match message {
        DisMessage::PointObjectState(p) => {
            let at = geodetic(p.location_ecef_m)?;
            let centre = GeoPoint {
                lat_deg: at.lat_deg,
                lon_deg: at.lon_deg,
            };
            let t = p.object_type;
            let s = p.specific_appearance;
            let crater = ObjectType::POINT_CRATER;
            if (t.domain, t.kind, t.category) == (crater.domain, crater.kind, crater.category) {
                let radius_m = f64::from(s & 0xffff) / 100.0;
                let depth_m = f64::from(s >> 16) / 100.0;
                let mut made = edit(
                    p.object_id,
                    EditShape::Crater {
                        centre,
                        radius_m,
                        depth_m,
                        lip_radius_m: 1.25 * radius_m,
                        lip_height_m: 0.25 * depth_m,
                    },
                );
                if let Some((space, _)) = NAMED_CRATER_SPACES
                    .iter()
                    .find(|(_, mark)| p.modifications & mark != 0)
                {
                    made.sequence |= space;
                }
                return Some(made);
            }
            let tank = ObjectType::POINT_VEHICLE_DEFILADE_TANK;
            let infantry = ObjectType::POINT_INFANTRY_FIGHTING_POSITION;
            let is =
                |o: ObjectType| (t.domain, t.kind, t.category) == (o.domain, o.kind, o.category);
            if is(tank) || is(infantry) {
                return Some(edit(
                    p.object_id,
                    EditShape::Position {
                        centre,
                        heading_deg: heading_of_orientation(at, p.orientation_rad).to_degrees(),
                        length_m: f64::from(s & 511) / 10.0,
                        width_m: f64::from((s >> 9) & 511) / 10.0,
                        depth_m: f64::from((s >> 18) & 1023) / 100.0,
                    },
                ));
            }
            None
        }
        DisMessage::LinearObjectState(l) => {
            let [segment] = l.segments.as_slice() else {
                return None;
            };
            let centre = geodetic(segment.location_ecef_m)?;
            let heading = heading_of_orientation(centre, segment.orientation_rad);
            let half = 0.5 * f64::from(segment.length_m);
            let (mn, me) = cig_geo::metres_per_degree(centre.lat_deg);
            let end = |sign: f64| GeoPoint {
                lat_deg: centre.lat_deg + sign * half * heading.cos() / mn,
                lon_deg: centre.lon_deg + sign * half * heading.sin() / me,
            };
            let (from, to) = (end(-1.0), end(1.0));
            let width_m = f64::from(segment.width_m);
            let t = l.object_type;
            let is = |o: ObjectType| {
                (t.domain, t.kind, t.category, t.subcategory)
                    == (o.domain, o.kind, o.category, o.subcategory)
            };
            let shape = if is(ObjectType::LINEAR_RUT) {
                EditShape::Rut {
                    from,
                    to,
                    width_m,
                    depth_m: f64::from(segment.depth_m),
                }
            } else if is(ObjectType::LINEAR_TANK_DITCH) {
                if segment.depth_m > 0.0 {
                    EditShape::Ditch {
                        from,
                        to,
                        width_m,
                        depth_m: f64::from(segment.depth_m),
                        spoil: match segment.specific_appearance & 3 {
                            1 => SpoilSide::Left,
                            2 => SpoilSide::Right,
                            _ => SpoilSide::Both,
                        },
                    }
                } else {
                    EditShape::Berm {
                        from,
                        to,
                        width_m,
                        height_m: f64::from(segment.height_m),
                    }
                }
            } else {
                return None;
            };
            Some(edit(l.object_id, shape))
        }
        _ => None,
    }
}

/// A remote DIS entity's id among the rut tracker's vehicles (apart from the session's 16-bit
/// entity ids).
pub fn remote_rut_id(site: u16, application: u16, entity: u16) -> u64 {
    (1 << 48) | (u64::from(site) << 32) | (u64::from(application) << 16) | u64::from(entity)
}

/// Ruts are laid in straight pieces of this much travel, metres.
pub const RUT_SEGMENT_M: f64 = 8.0;
/// Ruts shallower than this are not made, metres.
pub const MIN_RUT_DEPTH_M: f64 = 0.01;
/// A vehicle that moved more than this between two frames jumped: no rut across the gap.
const RUT_JUMP_M: f64 = 60.0;

/// Ruts behind the ground vehicles this IG moves: every [`RUT_SEGMENT_M`] of travel on the
/// ground, one rut under each track or wheel line, as deep as the Bekker sinkage of the
/// vehicle's ground pressure in the soil there (`cig_dynterrain::soil::rut_depth_m`: none on
/// rock or paved road), as wide as its contact, the lines apart by its gauge (tracked: 0.6 of
/// a track's length, 1 to 3.5 m; wheeled: 2 m).
#[derive(Debug, Default)]
pub struct RutTracker {
    last: std::collections::BTreeMap<u64, GeoPoint>,
    next_sequence: Option<u32>,
    /// Ruts laid in the current second: (the second, how many).
    second: (f64, u32),
    /// Pieces of travel left without ruts, the second's budget spent.
    pub dropped: u64,
}

/// Ruts laid at most each second (the vehicles listed first get theirs first: the IG's own
/// before the exercise's): every rut is an edit every node carries, refines cells and is
/// announced again, so an exercise of hundreds of vehicles cannot lay one every 8 m each.
pub const MAX_RUTS_PER_S: u32 = 20;

/// A vehicle the rut tracker follows: its id (a session entity's id, or a remote entity's
/// [`remote_rut_id`]), where it is, the load it puts on the ground.
#[derive(Clone, Copy, Debug)]
pub struct RutVehicle {
    pub id: u64,
    pub position: Geodetic,
    pub load: cig_dynterrain::soil::VehicleLoad,
}

impl RutTracker {
    /// Follows the vehicles one frame on: the ruts they made since the last piece, authored
    /// by `author` at `time_utc_s`. Vehicles not listed are forgotten.
    pub fn advance(
        &mut self,
        vehicles: &[RutVehicle],
        author: EditAuthor,
        time_utc_s: f64,
        moisture: SoilMoisture,
        query: &mut QuerySession,
    ) -> Vec<TerrainEdit> {
        self.last
            .retain(|id, _| vehicles.iter().any(|v| v.id == *id));
        let mut ruts = Vec::new();
        for v in vehicles {
            let here = GeoPoint {
                lat_deg: v.position.lat_deg,
                lon_deg: v.position.lon_deg,
            };
            let Some(last) = self.last.get(&v.id).copied() else {
                self.last.insert(v.id, here);
                continue;
            };
            let (mn, me) = cig_geo::metres_per_degree(last.lat_deg);
            let (dx, dy) = (
                (here.lon_deg - last.lon_deg) * me,
                (here.lat_deg - last.lat_deg) * mn,
            );
            let moved_m = dx.hypot(dy);
            if moved_m > RUT_JUMP_M || !moved_m.is_finite() {
                self.last.insert(v.id, here);
                continue;
            }
            if moved_m < RUT_SEGMENT_M {
                continue;
            }
            self.last.insert(v.id, here);
            let second = time_utc_s.floor();
            if self.second.0 != second {
                self.second = (second, 0);
            }
            if self.second.1 + 2 > MAX_RUTS_PER_S {
                self.dropped += 1;
                continue;
            }
            let mid = (
                0.5 * (last.lat_deg + here.lat_deg),
                0.5 * (last.lon_deg + here.lon_deg),
            );
            let Ok(ground) = query.hot(mid.0, mid.1) else {
                continue;
            };
            let depth_m = cig_dynterrain::soil::rut_depth_m(ground.material, moisture, &v.load);
            if depth_m < MIN_RUT_DEPTH_M {
                continue;
            }
            let gauge_m = match v.load.running_gear {
                cig_dynterrain::soil::RunningGear::Tracked => {
                    (0.6 * v.load.contact_length_m()).clamp(1.0, 3.5)
                }
                _ => 2.0,
            };
            // Across the travel, to the right.
            let (rx, ry) = (dy / moved_m, -dx / moved_m);
            let held =
                last_object_sequence(query.edits(), author).map_or(1, |s| s.saturating_add(1));
            let sequence = self.next_sequence.get_or_insert(held);
            *sequence = (*sequence).max(held);
            for side in [-0.5, 0.5] {
                let shift = |p: GeoPoint| GeoPoint {
                    lat_deg: p.lat_deg + side * gauge_m * ry / mn,
                    lon_deg: p.lon_deg + side * gauge_m * rx / me,
                };
                self.second.1 += 1;
                ruts.push(as_sent(TerrainEdit {
                    author,
                    sequence: *sequence,
                    time_utc_s,
                    shape: EditShape::Rut {
                        from: shift(last),
                        to: shift(here),
                        width_m: v.load.contact_width_m().clamp(0.1, 1.5),
                        depth_m,
                    },
                }));
                *sequence = sequence.wrapping_add(1);
            }
        }
        ruts
    }
}

/// The last sequence number an author used outside [`HOST_REQUEST_SEQUENCES`]: where this
/// IG's ruts (and any other edit it numbers in turn) go on from.
fn last_object_sequence(edits: &cig_terrain::EditLayer, author: EditAuthor) -> Option<u32> {
    match edits.last_sequence(author) {
        // Only an author holding a host's crater needs the look through its edits.
        Some(last) if last >= HOST_REQUEST_SEQUENCES => edits
            .edits()
            .filter(|e| e.author == author && e.sequence < HOST_REQUEST_SEQUENCES)
            .map(|e| e.sequence)
            .max(),
        last => last,
    }
}

/// A crater edit's shape of these dimensions at a point.
fn crater_shape(centre: GeoPoint, dims: &CraterDimensions) -> EditShape {
    EditShape::Crater {
        centre,
        radius_m: dims.radius_m,
        depth_m: dims.depth_m,
        lip_radius_m: dims.lip_radius_m,
        lip_height_m: dims.lip_height_m,
    }
}

/// How big a crater asked for at a point is (the operator's `cig db crater`, a host's
/// [`TerrainEditRequest`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CraterSize {
    /// A surface burst of this TNT-equivalent charge: cube-root scaling in the soil of the
    /// database's material there (`cig_dynterrain::crater::dimensions`).
    Charge { charge_kg: f64 },
    /// This radius and depth, the lip as a scaled crater's (1.25 R wide, D / 4 high).
    Explicit { radius_m: f64, depth_m: f64 },
}

/// A crater placed on the database: where, in what ground, how big.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedCrater {
    pub centre: GeoPoint,
    /// The database's material at the centre.
    pub material: Material,
    pub dimensions: CraterDimensions,
}

impl PlacedCrater {
    /// The crater as an edit's shape.
    pub fn shape(&self) -> EditShape {
        crater_shape(self.centre, &self.dimensions)
    }
}

/// Why no crater was placed.
#[derive(Debug, thiserror::Error)]
pub enum CraterAtError {
    #[error("no terrain at {lat_deg:.6}, {lon_deg:.6}: {source}")]
    NoTerrain {
        lat_deg: f64,
        lon_deg: f64,
        source: cig_terrain::QueryError,
    },
    #[error("crater charge: {0}")]
    Charge(#[from] cig_dynterrain::crater::CraterError),
    #[error("a {charge_kg} kg charge on {material} at {lat_deg:.6}, {lon_deg:.6} makes no crater")]
    NoCrater {
        charge_kg: f64,
        material: Material,
        lat_deg: f64,
        lon_deg: f64,
    },
    #[error(
        "a crater's radius and depth must be finite and above 0, not {radius_m} m and {depth_m} m"
    )]
    Size { radius_m: f64, depth_m: f64 },
}

/// The crater asked for at a point: its size from the charge in the soil of the database's
/// material there (in `moisture`), or as given. One function for every asker, so the
/// operator's and a host's craters of one charge are the same crater. Whether the edit fits
/// the database (its extent, its height) is the edit layer's to say when it is applied.
pub fn crater_at(
    query: &mut QuerySession,
    lat_deg: f64,
    lon_deg: f64,
    size: CraterSize,
    moisture: SoilMoisture,
) -> Result<PlacedCrater, CraterAtError> {
    let ground = query
        .hot(lat_deg, lon_deg)
        .map_err(|source| CraterAtError::NoTerrain {
            lat_deg,
            lon_deg,
            source,
        })?;
    let dimensions = match size {
        CraterSize::Charge { charge_kg } => {
            cig_dynterrain::crater::dimensions(ground.material, moisture, charge_kg)?.ok_or(
                CraterAtError::NoCrater {
                    charge_kg,
                    material: ground.material,
                    lat_deg,
                    lon_deg,
                },
            )?
        }
        CraterSize::Explicit { radius_m, depth_m } => {
            if !(radius_m.is_finite() && depth_m.is_finite() && radius_m > 0.0 && depth_m > 0.0) {
                return Err(CraterAtError::Size { radius_m, depth_m });
            }
            CraterDimensions {
                radius_m,
                depth_m,
                lip_radius_m: cig_dynterrain::crater::LIP_RADIUS_RATIO * radius_m,
                lip_height_m: cig_dynterrain::crater::LIP_HEIGHT_RATIO * depth_m,
            }
        }
    };
    Ok(PlacedCrater {
        centre: GeoPoint { lat_deg, lon_deg },
        material: ground.material,
        dimensions,
    })
}

/// CIGI 3.x packet ID of cig's user-defined Terrain Edit Request (3.x user IDs are 201-255).
pub const TERRAIN_EDIT_REQUEST_ID_V3: u16 = 220;
/// CIGI 4.0 packet ID of the Terrain Edit Request (4.0 user IDs are 0x1000-0xFFFE).
pub const TERRAIN_EDIT_REQUEST_ID_V4: u16 = 0x10DC;

/// Where a Terrain Edit Request's fields lie, octets from the packet's start (header
/// included; the codec hands over the bytes after the header).
struct RequestLayout {
    header_bytes: usize,
    size_bytes: usize,
    kind: usize,
    request_id: usize,
    lat: usize,
    lon: usize,
    /// Charge (kind 0) or radius (kind 1), f32.
    first: usize,
    /// Depth (kind 1), f32.
    second: usize,
}

/// 3.x: ID u8, size u8, kind u8, reserved u8, request id u32, lat f64, lon f64, f32, f32.
const LAYOUT_V3: RequestLayout = RequestLayout {
    header_bytes: 2,
    size_bytes: 32,
    kind: 2,
    request_id: 4,
    lat: 8,
    lon: 16,
    first: 24,
    second: 28,
};
/// 4.0: size u16, ID u16, kind u8, 3 reserved, lat f64, lon f64, f32, f32, request id u32,
/// 4 reserved.
const LAYOUT_V4: RequestLayout = RequestLayout {
    header_bytes: 4,
    size_bytes: 40,
    kind: 4,
    request_id: 32,
    lat: 8,
    lon: 16,
    first: 24,
    second: 28,
};

fn request_layout(packet_id: u16, version: Version) -> Option<&'static RequestLayout> {
    match (version.major, packet_id) {
        (3, TERRAIN_EDIT_REQUEST_ID_V3) => Some(&LAYOUT_V3),
        (4, TERRAIN_EDIT_REQUEST_ID_V4) => Some(&LAYOUT_V4),
        _ => None,
    }
}

/// What a host asks for in a Terrain Edit Request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EditRequestAction {
    /// Kind 0 (a charge) or 1 (a radius and depth): a crater at a point.
    Crater {
        lat_deg: f64,
        lon_deg: f64,
        size: CraterSize,
    },
    /// Kind 2: remove the crater this IG made for this host's request of the same id.
    Heal,
}

/// cig's user-defined CIGI packet "Terrain Edit Request": a host asks the IG for a crater (from
/// a charge in the soil there, or of a given size) or to heal one it asked for earlier
/// (`docs/cigi-conformance.md` gives the layout byte by byte: 3.x ID 220, 32 octets; 4.0 ID
/// 0x10DC, 40 octets; fields in the byte order of the message).
///
/// The crater is this IG's edit (its DIS address, else [`LOCAL_AUTHOR`]) numbered
/// [`HOST_REQUEST_SEQUENCES`] over the request id, so a request sent twice makes one crater,
/// and it travels to the exercise and into `cig serve --edits` like the IG's other edits.
///
/// A heal removes the crater here, goes to the exercise as the crater's Object State
/// deactivated (the other nodes remove it and remember it healed) and into the journal as a
/// heal line.
///
/// Limits: request ids are 0-65535 (a DIS object number carries the crater); an id healed is
/// not to be asked for again in the same exercise: the other nodes remember it healed and
/// ignore the new crater.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainEditRequest {
    pub request_id: u16,
    pub action: EditRequestAction,
}

/// Why a Terrain Edit Request was refused as malformed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EditRequestError {
    #[error("Terrain Edit Request: {got} octets, CIGI {version} wants {expected}")]
    Length {
        got: usize,
        expected: usize,
        version: Version,
    },
    #[error("Terrain Edit Request {request_id}: unknown kind {kind} (0 crater from a charge, 1 crater of a radius and depth, 2 heal)")]
    UnknownKind { request_id: u32, kind: u8 },
    #[error("Terrain Edit Request {request_id}: the request id is above 65535 (a DIS object number carries it)")]
    RequestId { request_id: u32 },
    #[error("Terrain Edit Request {request_id}: {field} is {value}, {expected}")]
    BadValue {
        request_id: u32,
        field: &'static str,
        value: f64,
        expected: &'static str,
    },
}

/// The fields of a packet, read in its message's byte order.
struct FieldReader<'a> {
    data: &'a [u8],
    header_bytes: usize,
    order: ByteOrder,
}

impl FieldReader<'_> {
    fn bytes<const N: usize>(&self, offset: usize) -> [u8; N] {
        // The length is checked before any field is read: a short packet never gets here.
        offset
            .checked_sub(self.header_bytes)
            .and_then(|at| self.data.get(at..at + N))
            .and_then(|b| b.try_into().ok())
            .unwrap_or([0; N])
    }
    fn u32(&self, offset: usize) -> u32 {
        let b = self.bytes(offset);
        match self.order {
            ByteOrder::BigEndian => u32::from_be_bytes(b),
            ByteOrder::LittleEndian => u32::from_le_bytes(b),
        }
    }
    fn f32(&self, offset: usize) -> f64 {
        f64::from(f32::from_bits(self.u32(offset)))
    }
    fn f64(&self, offset: usize) -> f64 {
        let b = self.bytes(offset);
        match self.order {
            ByteOrder::BigEndian => f64::from_be_bytes(b),
            ByteOrder::LittleEndian => f64::from_le_bytes(b),
        }
    }
}

impl TerrainEditRequest {
    /// Kind codes on the wire.
    const CHARGE: u8 = 0;
    const EXPLICIT: u8 = 1;
    const HEAL: u8 = 2;

    /// The request a user-defined packet carries (`data`: the octets after its header, in
    /// `byte_order`, of a message of `version`); `None` for another user-defined packet.
    /// Refused: a wrong length, an unknown kind, a request id above 65535, a position or size
    /// that is not finite, a latitude beyond the poles or a longitude beyond -180..180, a
    /// charge, radius or depth not above 0. A heal's position and sizes are not read.
    pub fn decode(
        packet_id: u16,
        data: &[u8],
        byte_order: ByteOrder,
        version: Version,
    ) -> Result<Option<TerrainEditRequest>, EditRequestError> {
        let Some(layout) = request_layout(packet_id, version) else {
            return Ok(None);
        };
        let expected = layout.size_bytes - layout.header_bytes;
        if data.len() != expected {
            return Err(EditRequestError::Length {
                got: data.len() + layout.header_bytes,
                expected: layout.size_bytes,
                version,
            });
        }
        let r = FieldReader {
            data,
            header_bytes: layout.header_bytes,
            order: byte_order,
        };
        let request_id = r.u32(layout.request_id);
        let kind = r.bytes::<1>(layout.kind)[0];
        let Ok(id) = u16::try_from(request_id) else {
            return Err(EditRequestError::RequestId { request_id });
        };
        let check = |field: &'static str, value: f64, ok: bool, expected: &'static str| {
            if value.is_finite() && ok {
                Ok(value)
            } else {
                Err(EditRequestError::BadValue {
                    request_id,
                    field,
                    value,
                    expected,
                })
            }
        };
        let positive = |field: &'static str, value: f64| {
            check(field, value, value > 0.0, "not a finite number above 0")
        };
        let place = || -> Result<(f64, f64), EditRequestError> {
            let lat = r.f64(layout.lat);
            let lon = r.f64(layout.lon);
            Ok((
                check(
                    "latitude_deg",
                    lat,
                    lat.abs() <= 90.0,
                    "not a finite latitude in -90..90",
                )?,
                check(
                    "longitude_deg",
                    lon,
                    lon.abs() <= 180.0,
                    "not a finite longitude in -180..180",
                )?,
            ))
        };
        let size = match kind {
            Self::CHARGE => Some(CraterSize::Charge {
                charge_kg: positive("charge_kg", r.f32(layout.first))?,
            }),
            Self::EXPLICIT => Some(CraterSize::Explicit {
                radius_m: positive("radius_m", r.f32(layout.first))?,
                depth_m: positive("depth_m", r.f32(layout.second))?,
            }),
            Self::HEAL => None,
            kind => return Err(EditRequestError::UnknownKind { request_id, kind }),
        };
        let action = match size {
            Some(size) => {
                let (lat_deg, lon_deg) = place()?;
                EditRequestAction::Crater {
                    lat_deg,
                    lon_deg,
                    size,
                }
            }
            None => EditRequestAction::Heal,
        };
        Ok(Some(TerrainEditRequest {
            request_id: id,
            action,
        }))
    }

    /// The packet a host sends for this request in a message of `version` and `byte_order`
    /// (`None` for a version other than 3.x or 4.0). Unused fields are zero.
    pub fn to_packet(&self, version: Version, byte_order: ByteOrder) -> Option<UserDefined> {
        let (packet_id, layout) = match version.major {
            3 => (TERRAIN_EDIT_REQUEST_ID_V3, &LAYOUT_V3),
            4 => (TERRAIN_EDIT_REQUEST_ID_V4, &LAYOUT_V4),
            _ => return None,
        };
        let mut data = vec![0u8; layout.size_bytes - layout.header_bytes];
        let mut put = |offset: usize, be: &[u8], le: &[u8]| {
            let bytes = match byte_order {
                ByteOrder::BigEndian => be,
                ByteOrder::LittleEndian => le,
            };
            let at = offset - layout.header_bytes;
            if let Some(slot) = data.get_mut(at..at + bytes.len()) {
                slot.copy_from_slice(bytes);
            }
        };
        let id = u32::from(self.request_id);
        put(layout.request_id, &id.to_be_bytes(), &id.to_le_bytes());
        let (kind, lat_deg, lon_deg, first, second) = match self.action {
            EditRequestAction::Crater {
                lat_deg,
                lon_deg,
                size: CraterSize::Charge { charge_kg },
            } => (Self::CHARGE, lat_deg, lon_deg, charge_kg, 0.0),
            EditRequestAction::Crater {
                lat_deg,
                lon_deg,
                size: CraterSize::Explicit { radius_m, depth_m },
            } => (Self::EXPLICIT, lat_deg, lon_deg, radius_m, depth_m),
            EditRequestAction::Heal => (Self::HEAL, 0.0, 0.0, 0.0, 0.0),
        };
        put(layout.kind, &[kind], &[kind]);
        put(layout.lat, &lat_deg.to_be_bytes(), &lat_deg.to_le_bytes());
        put(layout.lon, &lon_deg.to_be_bytes(), &lon_deg.to_le_bytes());
        for (offset, value) in [(layout.first, first), (layout.second, second)] {
            let v = value as f32;
            put(offset, &v.to_be_bytes(), &v.to_le_bytes());
        }
        Some(UserDefined { packet_id, data })
    }
}

/// Counters of a host's Terrain Edit Requests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EditRequestCounters {
    /// Packets with the request's ID, malformed ones included.
    pub received: u64,
    pub craters_made: u64,
    pub healed: u64,
    /// Well-formed requests not carried out: outside the database, too large for an edit, no
    /// crater (water), a request id already holding a crater, a heal of an id holding none,
    /// the database's edits full.
    pub refused: u64,
    /// Malformed: see [`TerrainEditRequest::decode`].
    pub malformed: u64,
}

/// A host's Terrain Edit Requests carried out: the counters, and whether a problem has been
/// logged (the first malformed and the first refused request are warned of; the others are
/// counted, logged at debug level and told to the host).
#[derive(Debug, Default)]
pub struct HostEditRequests {
    counters: EditRequestCounters,
    malformed_logged: bool,
    refused_logged: bool,
}

/// What a frame's Terrain Edit Requests did.
#[derive(Debug, Default)]
pub struct EditRequestsDone {
    /// The craters added, to announce to the exercise.
    pub added: Vec<TerrainEdit>,
    /// The craters healed, to announce to the exercise.
    pub healed: Vec<TerrainEdit>,
    /// One line per request malformed or refused, for the host.
    pub problems: Vec<String>,
}

/// A well-formed request, ready to go into the edits.
enum Planned {
    Add(u16, TerrainEdit),
    Heal(u16, cig_terrain::EditId),
}

impl HostEditRequests {
    pub fn counters(&self) -> EditRequestCounters {
        self.counters
    }

    fn note(&mut self, problem: String, malformed: bool, done: &mut EditRequestsDone) {
        let logged = if malformed {
            self.counters.malformed += 1;
            &mut self.malformed_logged
        } else {
            self.counters.refused += 1;
            &mut self.refused_logged
        };
        if *logged {
            tracing::debug!("{problem}");
        } else {
            *logged = true;
            tracing::warn!("{problem} (later ones are counted in the report and told to the host)");
        }
        done.problems.push(problem);
    }

    /// Carries out the Terrain Edit Requests among a frame's user-defined packets (others are
    /// passed over): craters made by `author` at `time_utc_s` in dry soil (a host's crater,
    /// like a Detonation's, does not depend on the IG's weather; a host wanting a wet-soil
    /// crater gives its size), each as the exercise will have it ([`as_sent`]), and heals,
    /// all in one change of the terrain's edits, in the packets' order.
    pub fn apply(
        &mut self,
        packets: &[crate::session::UserPacket],
        author: EditAuthor,
        time_utc_s: f64,
        query: &mut QuerySession,
    ) -> EditRequestsDone {
        let mut done = EditRequestsDone::default();
        let mut planned = Vec::new();
        for p in packets {
            let request = match TerrainEditRequest::decode(
                p.packet.packet_id,
                &p.packet.data,
                p.byte_order,
                p.version,
            ) {
                Ok(Some(request)) => request,
                Ok(None) => continue,
                Err(e) => {
                    self.counters.received += 1;
                    self.note(e.to_string(), true, &mut done);
                    continue;
                }
            };
            self.counters.received += 1;
            let id = cig_terrain::EditId {
                author,
                sequence: HOST_REQUEST_SEQUENCES | u32::from(request.request_id),
            };
            match request.action {
                EditRequestAction::Heal => planned.push(Planned::Heal(request.request_id, id)),
                EditRequestAction::Crater {
                    lat_deg,
                    lon_deg,
                    size,
                } => match crater_at(query, lat_deg, lon_deg, size, SoilMoisture::Dry) {
                    Ok(crater) => planned.push(Planned::Add(
                        request.request_id,
                        as_sent(TerrainEdit {
                            author,
                            sequence: id.sequence,
                            time_utc_s,
                            shape: crater.shape(),
                        }),
                    )),
                    Err(e) => self.note(
                        format!("Terrain Edit Request {} refused: {e}", request.request_id),
                        false,
                        &mut done,
                    ),
                },
            }
        }
        if planned.is_empty() {
            return done;
        }
        // One change of the edits for the frame's requests.
        let outcomes: Vec<Result<Option<TerrainEdit>, String>> =
            query.cache().update_edits(|layer| {
                planned
                    .iter()
                    .map(|p| match p {
                        Planned::Add(_, edit) => match layer.apply(edit.clone()) {
                            Ok(cig_terrain::edits::Applied::Added) => Ok(None),
                            Ok(cig_terrain::edits::Applied::Known) => {
                                Err("its request id already holds a crater (heal it first)".into())
                            }
                            Err(e) => Err(e.to_string()),
                        },
                        Planned::Heal(_, id) => layer
                            .remove(*id)
                            .map(Some)
                            .map_err(|_| "no crater holds its request id".to_string()),
                    })
                    .collect()
            });
        for (p, outcome) in planned.into_iter().zip(outcomes) {
            match (p, outcome) {
                (Planned::Add(request_id, edit), Ok(_)) => {
                    self.counters.craters_made += 1;
                    tracing::debug!("crater made for the host's Terrain Edit Request {request_id}");
                    done.added.push(edit);
                }
                (Planned::Heal(request_id, _), Ok(healed)) => {
                    self.counters.healed += 1;
                    done.healed.extend(healed);
                    tracing::debug!(
                        "crater of the host's Terrain Edit Request {request_id} healed"
                    );
                }
                (Planned::Add(request_id, _) | Planned::Heal(request_id, _), Err(why)) => self
                    .note(
                        format!("Terrain Edit Request {request_id} refused: {why}"),
                        false,
                        &mut done,
                    ),
            }
        }
        done
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Terrain Edit Request's octets after its header, built from the layout table of
    /// `docs/cigi-conformance.md` (offsets from the packet's start), not from the decoder's.
    #[allow(
        clippy::too_many_arguments,
        reason = "one argument per field of the packet"
    )]
    fn packet(
        version: Version,
        order: ByteOrder,
        kind: u8,
        request_id: u32,
        lat: f64,
        lon: f64,
        first: f32,
        second: f32,
    ) -> Vec<u8> {
        let big = order == ByteOrder::BigEndian;
        let (size, header, kind_at, id_at) = if version.major == 3 {
            (32, 2, 2, 4)
        } else {
            (40, 4, 4, 32)
        };
        let mut p = vec![0u8; size];
        p[kind_at] = kind;
        let mut put = |at: usize, be: &[u8], le: &[u8]| {
            p[at..at + be.len()].copy_from_slice(if big { be } else { le });
        };
        put(id_at, &request_id.to_be_bytes(), &request_id.to_le_bytes());
        put(8, &lat.to_be_bytes(), &lat.to_le_bytes());
        put(16, &lon.to_be_bytes(), &lon.to_le_bytes());
        put(24, &first.to_be_bytes(), &first.to_le_bytes());
        put(28, &second.to_be_bytes(), &second.to_le_bytes());
        p.split_off(header)
    }

    const ORDERS: [ByteOrder; 2] = [ByteOrder::BigEndian, ByteOrder::LittleEndian];
    const VERSIONS: [(Version, u16); 2] = [
        (Version::V3_3, TERRAIN_EDIT_REQUEST_ID_V3),
        (Version::V4_0, TERRAIN_EDIT_REQUEST_ID_V4),
    ];

    #[test]
    fn requests_decode_in_both_versions_and_byte_orders() {
        for (version, id) in VERSIONS {
            for order in ORDERS {
                let charge = packet(version, order, 0, 4660, 35.995, -121.215, 100.0, 0.0);
                assert_eq!(
                    TerrainEditRequest::decode(id, &charge, order, version),
                    Ok(Some(TerrainEditRequest {
                        request_id: 4660,
                        action: EditRequestAction::Crater {
                            lat_deg: 35.995,
                            lon_deg: -121.215,
                            size: CraterSize::Charge { charge_kg: 100.0 },
                        },
                    })),
                    "{version} {order:?}"
                );
                let sized = packet(version, order, 1, 65535, -12.5, 179.75, 2.5, 0.75);
                assert_eq!(
                    TerrainEditRequest::decode(id, &sized, order, version),
                    Ok(Some(TerrainEditRequest {
                        request_id: 65535,
                        action: EditRequestAction::Crater {
                            lat_deg: -12.5,
                            lon_deg: 179.75,
                            size: CraterSize::Explicit {
                                radius_m: 2.5,
                                depth_m: 0.75,
                            },
                        },
                    }))
                );
                // A heal's place and sizes are not read.
                let heal = packet(version, order, 2, 7, f64::NAN, 0.0, -1.0, f32::NAN);
                let request = TerrainEditRequest {
                    request_id: 7,
                    action: EditRequestAction::Heal,
                };
                assert_eq!(
                    TerrainEditRequest::decode(id, &heal, order, version),
                    Ok(Some(request))
                );
                // The encoder writes the same octets as the layout table.
                for (bytes, request) in [
                    (
                        &charge,
                        TerrainEditRequest::decode(id, &charge, order, version),
                    ),
                    (
                        &sized,
                        TerrainEditRequest::decode(id, &sized, order, version),
                    ),
                ] {
                    let request = request.ok().flatten().expect("decoded");
                    let encoded = request.to_packet(version, order).expect("encoded");
                    assert_eq!((encoded.packet_id, &encoded.data), (id, bytes));
                }
                // The other byte order reads other numbers (or refuses them).
                let other = ORDERS
                    .into_iter()
                    .find(|o| *o != order)
                    .expect("two orders");
                assert_ne!(
                    TerrainEditRequest::decode(id, &charge, other, version),
                    TerrainEditRequest::decode(id, &charge, order, version)
                );
            }
        }
    }

    #[test]
    fn other_user_packets_are_not_requests() {
        let data = packet(
            Version::V3_3,
            ByteOrder::BigEndian,
            0,
            1,
            36.0,
            -121.0,
            5.0,
            0.0,
        );
        for (id, version) in [
            (221, Version::V3_3),
            (201, Version::V3_3),
            (0x10DD, Version::V4_0),
            // Each version's ID means nothing in the other.
            (TERRAIN_EDIT_REQUEST_ID_V4, Version::V3_3),
            (TERRAIN_EDIT_REQUEST_ID_V3, Version::V4_0),
        ] {
            assert_eq!(
                TerrainEditRequest::decode(id, &data, ByteOrder::BigEndian, version),
                Ok(None)
            );
            assert_eq!(
                TerrainEditRequest::decode(id, &[], ByteOrder::BigEndian, version),
                Ok(None)
            );
        }
    }

    #[test]
    fn malformed_requests_are_refused_with_their_reason() {
        for (version, id) in VERSIONS {
            for order in ORDERS {
                let good = packet(version, order, 1, 9, 36.0, -121.0, 2.0, 1.0);
                let decode = |data: &[u8]| TerrainEditRequest::decode(id, data, order, version);
                // Lengths: short, long by one, long by a whole 8 octets, empty.
                let mut long = good.clone();
                long.push(0);
                let mut longer = good.clone();
                longer.extend([0; 8]);
                for bad in [&good[..good.len() - 1], &long, &longer, &[]] {
                    let e = decode(bad).expect_err("wrong length");
                    assert!(
                        matches!(e, EditRequestError::Length { expected, .. }
                            if expected == if version.major == 3 { 32 } else { 40 }),
                        "{e}"
                    );
                }
                let bad_value = |kind: u8, lat: f64, lon: f64, first: f32, second: f32| {
                    decode(&packet(version, order, kind, 9, lat, lon, first, second))
                };
                for (kind, lat, lon, first, second, field) in [
                    (0, f64::NAN, -121.0, 5.0, 0.0, "latitude_deg"),
                    (0, 36.0, f64::INFINITY, 5.0, 0.0, "longitude_deg"),
                    (0, 90.5, -121.0, 5.0, 0.0, "latitude_deg"),
                    (1, 36.0, -181.0, 5.0, 1.0, "longitude_deg"),
                    (0, 36.0, -121.0, f32::NAN, 0.0, "charge_kg"),
                    (0, 36.0, -121.0, -5.0, 0.0, "charge_kg"),
                    (0, 36.0, -121.0, 0.0, 0.0, "charge_kg"),
                    (0, 36.0, -121.0, f32::INFINITY, 0.0, "charge_kg"),
                    (1, 36.0, -121.0, -2.0, 1.0, "radius_m"),
                    (1, 36.0, -121.0, 2.0, f32::NAN, "depth_m"),
                    (1, 36.0, -121.0, 2.0, -0.5, "depth_m"),
                ] {
                    let e = bad_value(kind, lat, lon, first, second).expect_err("bad value");
                    assert!(
                        matches!(e, EditRequestError::BadValue { field: f, request_id: 9, .. } if f == field),
                        "{field}: {e}"
                    );
                    assert!(e.to_string().contains(field), "{e}");
                }
                for kind in [3, 255] {
                    assert_eq!(
                        decode(&packet(version, order, kind, 9, 36.0, -121.0, 2.0, 1.0)),
                        Err(EditRequestError::UnknownKind {
                            request_id: 9,
                            kind
                        })
                    );
                }
                assert_eq!(
                    decode(&packet(version, order, 0, 65536, 36.0, -121.0, 2.0, 0.0)),
                    Err(EditRequestError::RequestId { request_id: 65536 })
                );
            }
        }
    }

    #[test]
    fn ruts_are_numbered_on_past_a_hosts_craters_not_after_them() {
        let (n, e) = cig_geo::metres_per_degree(36.0);
        let grid = cig_terrain::GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 30.0 / n,
            dlon_deg: 30.0 / e,
            rows: 65,
            cols: 65,
        };
        let mut layer = cig_terrain::EditLayer::new(grid, 64);
        let author = EditAuthor {
            site: 1,
            application: 7,
        };
        let crater = |sequence: u32, lat_deg: f64| TerrainEdit {
            author,
            sequence,
            time_utc_s: 1.0e9,
            shape: EditShape::Crater {
                centre: GeoPoint {
                    lat_deg,
                    lon_deg: -120.99,
                },
                radius_m: 2.0,
                depth_m: 1.0,
                lip_radius_m: 2.5,
                lip_height_m: 0.25,
            },
        };
        assert_eq!(last_object_sequence(&layer, author), None);
        layer
            .apply(crater(HOST_REQUEST_SEQUENCES | 9, 36.01))
            .expect("applied");
        assert_eq!(last_object_sequence(&layer, author), None);
        for (sequence, lat) in [(5, 36.003), (DETONATION_SEQUENCES | 2, 36.006)] {
            layer.apply(crater(sequence, lat)).expect("applied");
        }
        // Detonations' numbers count as before; the host's space is passed over.
        assert_eq!(
            last_object_sequence(&layer, author),
            Some(DETONATION_SEQUENCES | 2)
        );
        assert_eq!(
            layer.last_sequence(author),
            Some(HOST_REQUEST_SEQUENCES | 9)
        );
    }

    #[test]
    fn a_host_crater_travels_in_its_own_numbers() {
        let edit = TerrainEdit {
            author: EditAuthor {
                site: 1,
                application: 7,
            },
            sequence: HOST_REQUEST_SEQUENCES | 4660,
            time_utc_s: 1.0e9,
            shape: EditShape::Crater {
                centre: GeoPoint {
                    lat_deg: 36.0,
                    lon_deg: -121.0,
                },
                radius_m: 2.0,
                depth_m: 1.0,
                lip_radius_m: 2.5,
                lip_height_m: 0.25,
            },
        };
        let pdu = pdu_of_edit(&edit, 100.0).expect("sent");
        let DisMessage::PointObjectState(p) = &pdu else {
            panic!("a point object: {pdu:?}");
        };
        assert_eq!(
            (p.object_id.object, p.modifications),
            (4660, HOST_REQUEST_MODIFICATION)
        );
        let back = edit_of_pdu(&pdu, 1.0e9).expect("read");
        assert_eq!(back.id(), edit.id());
        // The same object number from a Detonation or as a plain object is another edit.
        let mut detonation = edit.clone();
        detonation.sequence = DETONATION_SEQUENCES | 4660;
        let d = edit_of_pdu(&pdu_of_edit(&detonation, 100.0).expect("sent"), 1.0e9);
        assert_eq!(d.map(|e| e.sequence), Some(detonation.sequence));
        let mut plain = edit.clone();
        plain.sequence = 4660;
        let d = edit_of_pdu(&pdu_of_edit(&plain, 100.0).expect("sent"), 1.0e9);
        assert_eq!(d.map(|e| e.sequence), Some(4660));
    }
}
