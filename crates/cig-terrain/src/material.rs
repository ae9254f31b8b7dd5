//! Material (soil) classes carried by every terrain post.
//!
//! The classes are those the dynamic-terrain IG of source 002 ("gridded posts carrying soil
//! data") needs for dust trails, trafficability and dynamic terrain: one byte per post.

use serde::{Deserialize, Serialize};

/// Surface material of a terrain post. The discriminant is the on-disk byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum Material {
    Water = 0,
    Sand = 1,
    DryClay = 2,
    Grass = 3,
    Forest = 4,
    Rock = 5,
    Snow = 6,
    PavedRoad = 7,
    DirtRoad = 8,
}

impl Material {
    /// Every material, in on-disk byte order.
    pub const ALL: [Material; 9] = [
        Material::Water,
        Material::Sand,
        Material::DryClay,
        Material::Grass,
        Material::Forest,
        Material::Rock,
        Material::Snow,
        Material::PavedRoad,
        Material::DirtRoad,
    ];

    /// The on-disk byte.
    pub fn to_byte(self) -> u8 {
        self as u8
    }

    /// Decodes an on-disk byte; `None` for bytes no material uses.
    pub fn from_byte(byte: u8) -> Option<Material> {
        Material::ALL.get(usize::from(byte)).copied()
    }

    /// The snake_case name used in JSON output and configuration.
    pub fn name(self) -> &'static str {
        match self {
            Material::Water => "water",
            Material::Sand => "sand",
            Material::DryClay => "dry_clay",
            Material::Grass => "grass",
            Material::Forest => "forest",
            Material::Rock => "rock",
            Material::Snow => "snow",
            Material::PavedRoad => "paved_road",
            Material::DirtRoad => "dirt_road",
        }
    }
}

impl std::fmt::Display for Material {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_round_trip_and_unknown_bytes_are_rejected() {
        for m in Material::ALL {
            assert_eq!(Material::from_byte(m.to_byte()), Some(m));
        }
        assert_eq!(Material::from_byte(9), None);
        assert_eq!(Material::from_byte(255), None);
    }
}
