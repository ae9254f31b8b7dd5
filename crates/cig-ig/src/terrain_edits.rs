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
//! edit; receivers ignore the ones they hold.
//!
//! Limits: height patches are not sent (the Gridded Data PDU is not implemented); healing is
//! not sent; other sequence numbers above 65535 are not sent (DIS object numbers are 16-bit),
//! and event numbers wrap at 65536 (a later crater with a reused event number is taken for
//! the earlier one).
//! The specific appearance fields for sizes are cig's use of bits the standard leaves to the
//! object type: another IG reads the object's type and place but not its size.

use cig_dis::dis_rs::detonation::model::{Detonation, DetonationDescriptor};
use cig_dis::object_state::{
    LinearObjectState, LinearSegment, ObjectId, ObjectType, PointObjectState, SimulationAddress,
};
use cig_dis::{DisMessage, EulerAngles};
use cig_dynterrain::soil::SoilMoisture;
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint, SpoilSide, TerrainEdit};
use cig_terrain::QuerySession;
use glam::{DMat3, DVec3};

/// A detonation more than this above the ground is an air burst: no crater.
pub const AIR_BURST_M: f64 = 3.0;
/// Every edit is announced again within this period, seconds.
pub const REANNOUNCE_S: f64 = 10.0;

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
        shape: EditShape::Crater {
            centre: GeoPoint {
                lat_deg: at.lat_deg,
                lon_deg: at.lon_deg,
            },
            radius_m: dims.radius_m,
            depth_m: dims.depth_m,
            lip_radius_m: dims.lip_radius_m,
            lip_height_m: dims.lip_height_m,
        },
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
    let from_detonation = matches!(edit.shape, EditShape::Crater { .. })
        && edit.sequence & !0xffff == DETONATION_SEQUENCES;
    let object = if from_detonation {
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
            modifications: if from_detonation {
                DETONATION_MODIFICATION
            } else {
                0
            },
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
                if p.modifications & DETONATION_MODIFICATION != 0 {
                    made.sequence |= DETONATION_SEQUENCES;
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
    last: std::collections::BTreeMap<u16, GeoPoint>,
    next_sequence: Option<u32>,
}

/// A vehicle the rut tracker follows: its id, where it is, the load it puts on the ground.
#[derive(Clone, Copy, Debug)]
pub struct RutVehicle {
    pub id: u16,
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
            let held = query
                .edits()
                .last_sequence(author)
                .map_or(1, |s| s.saturating_add(1));
            let sequence = self.next_sequence.get_or_insert(held);
            *sequence = (*sequence).max(held);
            for side in [-0.5, 0.5] {
                let shift = |p: GeoPoint| GeoPoint {
                    lat_deg: p.lat_deg + side * gauge_m * ry / mn,
                    lon_deg: p.lon_deg + side * gauge_m * rx / me,
                };
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
