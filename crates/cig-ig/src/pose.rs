//! Poses of entities and views: body-axis offsets, composed orientations, and the mean-sea-level
//! altitudes of the host interface.
//!
//! Algorithm (CIGI ICD 3.3 §3.2.3, "Entity Control" and "View Control"): an entity's body frame
//! has X forward, Y right and Z down; its yaw (heading), pitch and roll are relative to the local
//! north-east-down frame, or, for an attached entity or a view, relative to its parent's body
//! frame. A child's position is its parent's plus the offset turned into the parent's body axes;
//! its orientation is the parent's composed with its own. Offsets are applied in the parent's
//! local east-north-up tangent frame in double precision.
//!
//! CIGI altitudes are above mean sea level (the WGS84 earth reference model with the EGM96
//! geoid); the renderer and the terrain queries use heights above the ellipsoid. The conversion
//! uses the database's geoid grid (see `QuerySession::geoid_undulation_m`).
//!
//! Limits: offsets are applied in the parent's tangent plane, exact for the tens to thousands of
//! metres attachments span; the north-east-down frames of parent and child are taken as the
//! same (the error is the angle the offset subtends at the earth's centre, 0.009° per km).

use cig_geo::{EnuFrame, Geodetic};
use cig_scene::Hpr;
use glam::DVec3;

/// Where an entity or view is: position above the ellipsoid and orientation in the local
/// east-north-up frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub position: Geodetic,
    pub orientation: Hpr,
}

/// A body-axis offset (CIGI: x forward, y right, z down), metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyOffset {
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
}

/// The body axes' directions (forward, right, down) in east-north-up.
fn axes(orientation: Hpr) -> (DVec3, DVec3, DVec3) {
    let (forward, right, up) = orientation.axes_enu();
    (forward, right, -up)
}

/// The east-north-up displacement of a body-axis offset.
pub fn offset_enu(orientation: Hpr, offset: BodyOffset) -> DVec3 {
    let (forward, right, down) = axes(orientation);
    forward * offset.x_m + right * offset.y_m + down * offset.z_m
}

/// The orientation whose body axes are `forward` and `right` (east-north-up unit vectors).
pub fn hpr_from_axes(forward: DVec3, right: DVec3) -> Hpr {
    let forward = forward.normalize_or_zero();
    let heading = forward.x.atan2(forward.y);
    let pitch = forward.z.clamp(-1.0, 1.0).asin();
    let (sh, ch) = heading.sin_cos();
    let right0 = DVec3::new(ch, -sh, 0.0);
    let up0 = right0.cross(forward);
    let roll = (-right.dot(up0)).atan2(right.dot(right0));
    Hpr {
        heading_deg: wrap_deg(heading.to_degrees()),
        pitch_deg: pitch.to_degrees(),
        roll_deg: roll.to_degrees(),
    }
}

/// Degrees in [0, 360).
pub fn wrap_deg(deg: f64) -> f64 {
    let w = deg.rem_euclid(360.0);
    if w >= 360.0 {
        0.0
    } else {
        w
    }
}

/// Composes a parent's orientation with a child's relative one.
pub fn compose(parent: Hpr, relative: Hpr) -> Hpr {
    let (pf, pr, pu) = parent.axes_enu();
    let (rf, rr, _) = relative.axes_enu();
    // The relative axes are expressed as if the parent's right, forward, up were east, north, up.
    let to_world = |v: DVec3| pr * v.x + pf * v.y + pu * v.z;
    hpr_from_axes(to_world(rf), to_world(rr))
}

/// A child's pose from its parent's and its own offset and relative orientation.
pub fn child_pose(parent: Pose, offset: BodyOffset, relative: Hpr) -> Pose {
    let frame = EnuFrame::new(parent.position);
    Pose {
        position: frame.enu_to_geodetic(offset_enu(parent.orientation, offset)),
        orientation: compose(parent.orientation, relative),
    }
}

/// A point displaced by an east-north-up vector from `origin`.
pub fn displaced(origin: Geodetic, enu_m: DVec3) -> Geodetic {
    EnuFrame::new(origin).enu_to_geodetic(enu_m)
}

/// The position of a point `offset` from a pose, in the pose's body axes.
pub fn point_from(pose: Pose, offset: BodyOffset) -> Geodetic {
    displaced(pose.position, offset_enu(pose.orientation, offset))
}

/// The body-axis offset of `point` from a pose (inverse of [`point_from`]).
pub fn offset_of(pose: Pose, point: Geodetic) -> BodyOffset {
    let enu = EnuFrame::new(pose.position).geodetic_to_enu(point);
    let (forward, right, down) = axes(pose.orientation);
    BodyOffset {
        x_m: enu.dot(forward),
        y_m: enu.dot(right),
        z_m: enu.dot(down),
    }
}

/// The relative orientation `child` has in `parent`'s body frame (inverse of [`compose`]).
pub fn relative(parent: Hpr, child: Hpr) -> Hpr {
    let (pf, pr, pu) = parent.axes_enu();
    let (cf, cr, _) = child.axes_enu();
    let to_parent = |v: DVec3| DVec3::new(v.dot(pr), v.dot(pf), v.dot(pu));
    hpr_from_axes(to_parent(cf), to_parent(cr))
}

/// Azimuth (clockwise from north) and elevation of a unit east-north-up vector, degrees.
pub fn azimuth_elevation_deg(v: DVec3) -> (f64, f64) {
    let v = v.normalize_or_zero();
    (
        wrap_deg(v.x.atan2(v.y).to_degrees()),
        v.z.clamp(-1.0, 1.0).asin().to_degrees(),
    )
}

/// The east-north-up unit vector of an azimuth and elevation, degrees.
pub fn direction_enu(azimuth_deg: f64, elevation_deg: f64) -> DVec3 {
    let (sa, ca) = azimuth_deg.to_radians().sin_cos();
    let (se, ce) = elevation_deg.to_radians().sin_cos();
    DVec3::new(sa * ce, ca * ce, se)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn close(a: Hpr, b: Hpr) -> bool {
        let (af, ar, _) = a.axes_enu();
        let (bf, br, _) = b.axes_enu();
        (af - bf).length() < 1e-9 && (ar - br).length() < 1e-9
    }

    #[test]
    fn a_forward_offset_of_a_north_facing_parent_goes_north() {
        let parent = Pose {
            position: Geodetic::new(0.0, 0.0, 0.0),
            orientation: Hpr::default(),
        };
        let p = point_from(
            parent,
            BodyOffset {
                x_m: 1000.0,
                y_m: 0.0,
                z_m: -10.0,
            },
        );
        assert!((p.lat_deg - 1000.0 / 110_574.0).abs() < 1e-5, "{p:?}");
        assert!(p.lon_deg.abs() < 1e-12);
        assert!((p.alt_m - 10.0).abs() < 0.2);
    }

    #[test]
    fn yaw_then_yaw_adds() {
        let a = Hpr {
            heading_deg: 30.0,
            ..Hpr::default()
        };
        let b = Hpr {
            heading_deg: 45.0,
            ..Hpr::default()
        };
        let c = compose(a, b);
        assert!((c.heading_deg - 75.0).abs() < 1e-9, "{c:?}");
    }

    proptest! {
        #[test]
        fn compose_and_relative_are_inverse(
            h1 in 0.0..360.0f64, p1 in -80.0..80.0f64, r1 in -170.0..170.0f64,
            h2 in 0.0..360.0f64, p2 in -80.0..80.0f64, r2 in -170.0..170.0f64,
        ) {
            let parent = Hpr { heading_deg: h1, pitch_deg: p1, roll_deg: r1 };
            let child = Hpr { heading_deg: h2, pitch_deg: p2, roll_deg: r2 };
            let world = compose(parent, child);
            prop_assert!(close(relative(parent, world), child));
            prop_assert!(close(hpr_from_axes(child.axes_enu().0, child.axes_enu().1), child));
        }

        #[test]
        fn offsets_round_trip(
            h in 0.0..360.0f64, p in -80.0..80.0f64, r in -170.0..170.0f64,
            x in -500.0..500.0f64, y in -500.0..500.0f64, z in -500.0..500.0f64,
            lat in -80.0..80.0f64, lon in -180.0..180.0f64,
        ) {
            let pose = Pose { position: Geodetic::new(lat, lon, 100.0), orientation: Hpr { heading_deg: h, pitch_deg: p, roll_deg: r } };
            let offset = BodyOffset { x_m: x, y_m: y, z_m: z };
            let back = offset_of(pose, point_from(pose, offset));
            prop_assert!((back.x_m - x).abs() < 1e-6 && (back.y_m - y).abs() < 1e-6 && (back.z_m - z).abs() < 1e-6);
        }
    }
}
