//! The world's lights for a frame: each drawn entity's lamps, switched by whoever owns it, the
//! fires of burning entities, and the scenario's standing lamps and flares.
//!
//! Algorithm. An entity's light set follows its model and, for DIS entities, its domain: the
//! built-in `tank` and `truck` (and any other ground model) are ground vehicles, `ship` a ship,
//! a model whose name holds "aircraft", "helicopter" or "plane" or any DIS air-domain platform
//! an aircraft; `building`, `tree` and non-platforms carry none. Its switches come from:
//! - a remote DIS entity's appearance, decoded by `cig_dis::LightsRequested` (the bit layout
//!   lives only there) and mapped here onto `cig_scene::lights::LightSwitches`: upper and lower
//!   anti-collision lights count as the anti-collision light, and an aircraft's strobes follow
//!   its anti-collision light (DIS has no strobe bit);
//! - a scenario entity's `lights` list ([`SWITCH_NAMES`]);
//! - a host entity's Component Control ([`LIGHTS_COMPONENT`], docs/cigi-conformance.md): a bit
//!   mask in [`SWITCH_NAMES`] order, bit 0 the least significant.
//!
//! Burning entities (the DIS appearance's flaming bit, or the scenario appearance's) carry a
//! fire's light (`cig_scene::lights::fire_light`, a burning car: 4 MW on 2 m).
//!
//! Sources: SISO-REF-010 (through `cig-dis`), CIGI 3.3 ICD §4.1.6 (Component Control: the
//! component identifiers of a class are IG-defined).
//!
//! Limits: the world does not know a model's bounding box, so each model's half extents are
//! fixed here ([`half_extent_m`]): the built-in models' sizes, and per-set defaults for other
//! models (glTF models' lamps may sit off their bodies).

use cig_scene::lights::{EntityLightSet, LightSwitches};

/// The names of the lamp switches, in [`LightSwitches`] order: the scenario's `lights` names
/// and the bits of the host's [`LIGHTS_COMPONENT`] mask (bit `i` is `SWITCH_NAMES[i]`).
pub const SWITCH_NAMES: [&str; 12] = [
    "head",
    "tail",
    "brake",
    "blackout",
    "blackout_brake",
    "spot",
    "landing",
    "navigation",
    "anti_collision",
    "strobe",
    "running",
    "interior",
];

/// The CIGI Component Control (class 0, entity; instance = the entity's identifier) that
/// switches an entity's lamps: component state 0 turns them all off; any other state sets them
/// from data word 0, a bit mask in [`SWITCH_NAMES`] order (bit 0 head … bit 11 interior).
pub const LIGHTS_COMPONENT: u16 = 100;

/// Component class of an entity in Component Control.
pub const COMPONENT_CLASS_ENTITY: u8 = 0;

/// A burning entity's fire: heat release, MW, and base diameter, m (a burning car).
pub const ENTITY_FIRE_MW: f32 = 4.0;
pub const ENTITY_FIRE_DIAMETER_M: f32 = 2.0;

/// The switch a name turns on, as its index in [`SWITCH_NAMES`].
pub fn switch_of_name(name: &str) -> Option<usize> {
    SWITCH_NAMES.iter().position(|n| *n == name)
}

fn switch_mut(s: &mut LightSwitches, index: usize) -> Option<&mut bool> {
    Some(match index {
        0 => &mut s.head,
        1 => &mut s.tail,
        2 => &mut s.brake,
        3 => &mut s.blackout,
        4 => &mut s.blackout_brake,
        5 => &mut s.spot,
        6 => &mut s.landing,
        7 => &mut s.navigation,
        8 => &mut s.anti_collision,
        9 => &mut s.strobe,
        10 => &mut s.running,
        11 => &mut s.interior,
        _ => return None,
    })
}

/// The switches a list of names turns on (unknown names are ignored: the scenario refuses them).
pub fn switches_of_names<S: AsRef<str>>(names: &[S]) -> LightSwitches {
    let mut s = LightSwitches::default();
    for i in names.iter().filter_map(|n| switch_of_name(n.as_ref())) {
        if let Some(b) = switch_mut(&mut s, i) {
            *b = true;
        }
    }
    s
}

/// The switches of a [`LIGHTS_COMPONENT`] mask (bits above 11 are ignored).
pub fn switches_of_mask(mask: u32) -> LightSwitches {
    let mut s = LightSwitches::default();
    for i in 0..SWITCH_NAMES.len() {
        if mask & (1 << i) != 0 {
            if let Some(b) = switch_mut(&mut s, i) {
                *b = true;
            }
        }
    }
    s
}

/// The mask of switches, the inverse of [`switches_of_mask`].
pub fn mask_of_switches(s: &LightSwitches) -> u32 {
    let mut copy = *s;
    (0..SWITCH_NAMES.len())
        .filter(|i| switch_mut(&mut copy, *i).is_some_and(|b| *b))
        .fold(0, |m, i| m | (1 << i))
}

/// The switches a DIS appearance's lights ask for (module documentation).
pub fn switches_of_dis(l: cig_dis::LightsRequested) -> LightSwitches {
    let anti_collision = l.anti_collision || l.upper_anti_collision || l.lower_anti_collision;
    LightSwitches {
        head: l.head,
        tail: l.tail,
        brake: l.brake,
        blackout: l.blackout,
        blackout_brake: l.blackout_brake,
        spot: l.spot,
        landing: l.landing,
        navigation: l.navigation,
        anti_collision,
        strobe: anti_collision,
        running: l.running,
        interior: l.interior,
    }
}

/// DIS platform kind and domains.
const DIS_KIND_PLATFORM: u8 = 1;
const DIS_DOMAIN_LAND: u8 = 1;
const DIS_DOMAIN_AIR: u8 = 2;
const DIS_DOMAIN_SURFACE: u8 = 3;

/// The light set of an entity drawn with `model`, and for a DIS entity its kind and domain.
pub fn light_set(model: &str, dis_kind_domain: Option<(u8, u8)>) -> EntityLightSet {
    let name = model.to_ascii_lowercase();
    if let Some((kind, domain)) = dis_kind_domain {
        if kind != DIS_KIND_PLATFORM {
            return EntityLightSet::None;
        }
        match domain {
            DIS_DOMAIN_AIR => return EntityLightSet::Aircraft,
            DIS_DOMAIN_SURFACE => return EntityLightSet::Ship,
            DIS_DOMAIN_LAND if !(name == "building" || name == "tree") => {
                return EntityLightSet::GroundVehicle
            }
            _ => {}
        }
    }
    if ["aircraft", "helicopter", "plane"]
        .iter()
        .any(|k| name.contains(k))
    {
        EntityLightSet::Aircraft
    } else if name.contains("ship")
        || name.contains("boat")
        || cig_scene::models::ship_particulars(&name).is_some()
    {
        EntityLightSet::Ship
    } else if name == "building" || name == "tree" || name.is_empty() {
        EntityLightSet::None
    } else {
        EntityLightSet::GroundVehicle
    }
}

/// An entity's half length, half width (an aircraft's half span) and half height, metres: the
/// built-in models' sizes, else the set's default.
pub fn half_extent_m(model: &str, set: EntityLightSet) -> [f32; 3] {
    match model {
        "tank" => [3.5, 1.8, 1.2],
        "truck" => [3.5, 1.25, 1.5],
        "ship" | "destroyer" => [75.0, 9.0, 20.0],
        "merchant" => [90.0, 14.0, 19.0],
        "patrol_craft" => [20.0, 3.5, 7.0],
        _ => match set {
            EntityLightSet::GroundVehicle => [2.5, 1.0, 0.8],
            EntityLightSet::Aircraft => [8.0, 8.0, 2.0],
            EntityLightSet::Ship => [20.0, 4.0, 5.0],
            EntityLightSet::None => [0.0; 3],
        },
    }
}

/// One drawn entity as the lights see it.
#[derive(Clone, Debug, PartialEq)]
pub struct LitEntity<'a> {
    pub id: u32,
    pub model: &'a str,
    pub dis_kind_domain: Option<(u8, u8)>,
    pub switches: LightSwitches,
    pub burning: bool,
    pub position: cig_geo::Geodetic,
    pub orientation: cig_scene::view::Hpr,
}

/// Appends an entity's lamps and, when it burns, its fire at `unix_time_s` to `out`.
pub fn add_entity_lights(
    e: &LitEntity<'_>,
    unix_time_s: f64,
    out: &mut Vec<cig_scene::lights::LightPoint>,
) {
    let set = light_set(e.model, e.dis_kind_domain);
    cig_scene::lights::entity_lights(
        set,
        &e.switches,
        e.id,
        e.position,
        e.orientation,
        half_extent_m(e.model, set),
        out,
    );
    if e.burning && e.position.to_ecef().is_finite() {
        out.push(cig_scene::lights::fire_light(
            e.position,
            ENTITY_FIRE_MW,
            ENTITY_FIRE_DIAMETER_M,
            u64::from(e.id),
            unix_time_s,
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_geo::Geodetic;

    #[test]
    fn names_and_masks_agree_with_the_switches_order() {
        let s = switches_of_names(&["head", "strobe", "interior"]);
        assert!(s.head && s.strobe && s.interior && !s.tail);
        assert_eq!(mask_of_switches(&s), 1 | (1 << 9) | (1 << 11));
        assert_eq!(switches_of_mask(mask_of_switches(&s)), s);
        assert_eq!(switches_of_mask(0xFFFF_F000), LightSwitches::default());
        assert_eq!(switch_of_name("headlights"), None);
        for (i, name) in SWITCH_NAMES.iter().enumerate() {
            assert_eq!(mask_of_switches(&switches_of_names(&[name])), 1 << i);
        }
    }

    #[test]
    fn dis_bits_switch_lamps_through_cig_dis() {
        let land = |bits| {
            switches_of_dis(cig_dis::LightsRequested::from_appearance(
                bits,
                DIS_KIND_PLATFORM,
                DIS_DOMAIN_LAND,
            ))
        };
        let s = land((1 << 12) | (1 << 14));
        assert!(s.head && s.brake && !s.tail && !s.landing);
        let s = switches_of_dis(cig_dis::LightsRequested::from_appearance(
            (1 << 12) | (1 << 18),
            DIS_KIND_PLATFORM,
            DIS_DOMAIN_AIR,
        ));
        assert!(s.landing && s.anti_collision && s.strobe && !s.head && !s.navigation);
    }

    #[test]
    fn light_sets_follow_model_and_domain() {
        assert_eq!(light_set("tank", None), EntityLightSet::GroundVehicle);
        assert_eq!(
            light_set("truck", Some((1, 1))),
            EntityLightSet::GroundVehicle
        );
        assert_eq!(light_set("ship", None), EntityLightSet::Ship);
        assert_eq!(light_set("Cargo_Plane", None), EntityLightSet::Aircraft);
        assert_eq!(light_set("truck", Some((1, 2))), EntityLightSet::Aircraft);
        assert_eq!(light_set("building", None), EntityLightSet::None);
        assert_eq!(light_set("tree", Some((1, 1))), EntityLightSet::None);
        assert_eq!(light_set("truck", Some((2, 1))), EntityLightSet::None);
    }

    #[test]
    fn headlamps_and_fires_add_lights() {
        let mut e = LitEntity {
            id: 7,
            model: "truck",
            dis_kind_domain: None,
            switches: LightSwitches::default(),
            burning: false,
            position: Geodetic::new(51.0, -1.5, 100.0),
            orientation: cig_scene::view::Hpr::default(),
        };
        let count = |e: &LitEntity<'_>| {
            let mut out = Vec::new();
            add_entity_lights(e, 1.7e9, &mut out);
            out
        };
        assert!(count(&e).is_empty());
        e.switches.head = true;
        assert_eq!(count(&e).len(), 2);
        e.burning = true;
        let lit = count(&e);
        assert_eq!(lit.len(), 3);
        assert_eq!(lit[2].spectrum, cig_environment::nvg::LightSpectrum::Flame);
        e.model = "building";
        assert_eq!(count(&e).len(), 1, "a burning building: its fire only");
    }
}
