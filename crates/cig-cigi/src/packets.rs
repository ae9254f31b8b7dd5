//! Typed CIGI packets, one struct per packet, shared by CIGI 3.3 and 4.0.
//!
//! Algorithm: each struct holds the union of the fields the packet has in
//! CIGI 3.3 (SISO-STD-013 ICD 3.3, section 4) and CIGI 4.0 (ICD 4.0), in
//! engineering units as the ICD defines them (degrees, metres, m/s, degC,
//! millibar, percent). Fields that exist in only one version say so; the
//! other version's encoder ignores them and its decoder leaves them at their
//! default. Enumerated fields are kept as the raw integer of their bit width
//! (the ICD value tables are cited in each doc comment) so that any value a
//! host sends survives a round trip; one-bit enumerations are `bool`s named
//! after their value 1.
//!
//! Limits: the CIGI 4.0 Entity Control was split into Entity Position, Entity
//! Control and Animation Control; those are separate structs here and are
//! only valid in a 4.0 message (the 3.3 [`EntityControl`] only in 3.x).

use crate::sample::{Sample, SampleField, SampleSource};

macro_rules! packet_struct {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty $(=> $bits:literal)? ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, PartialEq, Default)]
        pub struct $name {
            $( $(#[$fmeta])* pub $field: $ty, )*
        }

        impl Sample for $name {
            fn sample(source: &mut SampleSource) -> Self {
                Self {
                    $( $field: <$ty as SampleField>::sample_field(source, packet_struct!(@bits $($bits)?)), )*
                }
            }
        }
    };
    (@bits) => { 0 };
    (@bits $b:literal) => { $b };
}

packet_struct! {
    /// IG Control (host to IG, first packet of every host message).
    /// The major/minor version and the byte-swap magic number are written by
    /// the encoder from the message's version and byte order.
    pub struct IgControl {
        /// Database to load (0: none).
        pub database_number: i8,
        /// 0 reset/standby, 1 operate, 2 debug, 3 offline maintenance.
        pub ig_mode: u8 => 2,
        /// Timestamp field holds a valid value.
        pub timestamp_valid: bool,
        /// 3.3 "Extrapolation/Interpolation Enable", 4.0 "Smoothing Enable".
        pub smoothing_enable: bool,
        /// CIGI 4.0 only: entity type substitution enable.
        pub entity_substitution_enable: bool,
        /// Host frame number.
        pub host_frame_number: u32,
        /// Timestamp in 10 microsecond ticks.
        pub timestamp_10us: u32,
        /// IG frame number of the last Start of Frame received.
        pub last_ig_frame_number: u32,
    }
}

packet_struct! {
    /// Start of Frame (IG to host, first packet of every IG message).
    pub struct StartOfFrame {
        /// Loaded database (negative: loading; -128: not available).
        pub database_number: i8,
        /// CIGI 3.3 only: IG status code (0 normal).
        pub ig_status: u8,
        /// 0 reset/standby, 1 operate, 2 debug, 3 offline maintenance.
        pub ig_mode: u8 => 2,
        /// Timestamp field holds a valid value.
        pub timestamp_valid: bool,
        /// Earth reference model is host defined (false: WGS84).
        pub earth_reference_model_host_defined: bool,
        /// IG frame number.
        pub ig_frame_number: u32,
        /// Timestamp in 10 microsecond ticks.
        pub timestamp_10us: u32,
        /// Host frame number of the last IG Control received.
        pub last_host_frame_number: u32,
        /// CIGI 4.0 only: IG condition "overframing".
        pub overframing: bool,
        /// CIGI 4.0 only: IG condition "paging".
        pub paging: bool,
        /// CIGI 4.0 only: IG condition "excessive variable length data".
        pub excessive_variable_length_data: bool,
    }
}

packet_struct! {
    /// CIGI 3.3 Entity Control (packet 2). Not valid in a 4.0 message.
    pub struct EntityControl {
        /// Entity (0: ownship).
        pub entity_id: u16,
        /// 0 inactive/standby, 1 active, 2 destroyed.
        pub entity_state: u8 => 2,
        /// Attached to `parent_id` (position is then a body-axis offset).
        pub attach: bool,
        /// Collision detection enable.
        pub collision_detection_enable: bool,
        /// Inherit the parent's alpha.
        pub inherit_alpha: bool,
        /// 0 no clamp, 1 non-conformal, 2 conformal.
        pub ground_ocean_clamp: u8 => 2,
        /// Animation plays backward.
        pub animation_direction_backward: bool,
        /// Animation loops (false: one shot).
        pub animation_loop_continuous: bool,
        /// 0 stop, 1 pause, 2 play, 3 continue.
        pub animation_state: u8 => 2,
        /// Extrapolation/interpolation (smoothing) enable.
        pub smoothing_enable: bool,
        /// 0 transparent .. 255 opaque.
        pub alpha: u8,
        /// Entity type (model table key).
        pub entity_type: u16,
        /// Parent entity when attached.
        pub parent_id: u16,
        /// Roll, degrees.
        pub roll_deg: f32,
        /// Pitch, degrees.
        pub pitch_deg: f32,
        /// Yaw (heading), degrees.
        pub yaw_deg: f32,
        /// Latitude in degrees, or X offset in metres when attached.
        pub lat_deg_or_x_m: f64,
        /// Longitude in degrees, or Y offset in metres when attached.
        pub lon_deg_or_y_m: f64,
        /// Altitude in metres, or Z offset in metres when attached.
        pub alt_m_or_z_m: f64,
    }
}

packet_struct! {
    /// CIGI 4.0 Entity Position (packet 0x01). Not valid in a 3.x message.
    pub struct EntityPosition {
        /// Entity (0: ownship).
        pub entity_id: u16,
        /// Parent entity when attached.
        pub parent_id: u16,
        /// Attached to `parent_id`.
        pub attach: bool,
        /// 0 no clamp, 1 non-conformal, 2 conformal.
        pub ground_ocean_clamp: u8 => 2,
        /// Roll, degrees.
        pub roll_deg: f32,
        /// Pitch, degrees.
        pub pitch_deg: f32,
        /// Yaw (heading), degrees.
        pub yaw_deg: f32,
        /// Latitude in degrees, or X offset in metres when attached.
        pub lat_deg_or_x_m: f64,
        /// Longitude in degrees, or Y offset in metres when attached.
        pub lon_deg_or_y_m: f64,
        /// Altitude in metres, or Z offset in metres when attached.
        pub alt_m_or_z_m: f64,
    }
}

packet_struct! {
    /// CIGI 4.0 Entity Control (packet 0x25): state and DIS-style entity type.
    /// Not valid in a 3.x message.
    pub struct EntityControl4 {
        /// Entity (0: ownship).
        pub entity_id: u16,
        /// 0 inactive/standby, 1 active, 2 destroyed.
        pub entity_state: u8 => 2,
        /// Collision detection enable.
        pub collision_detection_enable: bool,
        /// Inherit the parent's alpha.
        pub inherit_alpha: bool,
        /// Smoothing enable.
        pub smoothing_enable: bool,
        /// The entity type uses the extended (DIS) fields.
        pub extended_entity_type: bool,
        /// 0 transparent .. 255 opaque.
        pub alpha: u8,
        /// Entity kind (DIS).
        pub entity_kind: u8,
        /// Domain (DIS).
        pub entity_domain: u8,
        /// Short entity type, or country when `extended_entity_type`.
        pub entity_type_or_country: u16,
        /// Category (DIS).
        pub entity_category: u8,
        /// Subcategory (DIS).
        pub entity_subcategory: u8,
        /// Specific (DIS).
        pub entity_specific: u8,
        /// Extra (DIS).
        pub entity_extra: u8,
    }
}

packet_struct! {
    /// CIGI 4.0 Animation Control (packet 0x26). Not valid in a 3.x message.
    pub struct AnimationControl {
        /// Entity whose animation is controlled.
        pub entity_id: u16,
        /// Animation.
        pub animation_id: u16,
        /// Play (false: stop).
        pub play: bool,
        /// Reset to the first frame (false: continue from the current frame).
        pub frame_reset: bool,
        /// Loop (false: one shot).
        pub loop_continuous: bool,
        /// Inherit the parent's alpha.
        pub inherit_alpha: bool,
        /// 0 transparent .. 255 opaque.
        pub alpha: u8,
        /// Playback speed factor (1.0 normal).
        pub speed_factor: f32,
    }
}

packet_struct! {
    /// Conformal Clamped Entity Control.
    pub struct ConformalClampedEntity {
        /// Entity.
        pub entity_id: u16,
        /// Yaw (heading), degrees.
        pub yaw_deg: f32,
        /// Latitude, degrees.
        pub latitude_deg: f64,
        /// Longitude, degrees.
        pub longitude_deg: f64,
    }
}

packet_struct! {
    /// Component Control: six 32-bit words of component data, whose meaning
    /// (integer, float, packed bytes) the component defines. Words are byte
    /// swapped as whole 32-bit units.
    pub struct ComponentControl {
        /// Component.
        pub component_id: u16,
        /// Object the component belongs to (entity, view, ...).
        pub instance_id: u16,
        /// ICD table: 0 entity, 1 view, 2 view group, 3 sensor, 4 regional
        /// sea surface, 5 regional terrain surface, 6 regional layered
        /// weather, 7 global sea surface, 8 global terrain surface, 9 global
        /// layered weather, 10 atmosphere, 11 celestial sphere, 12 event,
        /// 13 system, 14 symbol surface, 15 symbol.
        pub component_class: u8 => 6,
        /// Discrete state.
        pub component_state: u8,
        /// Component data words.
        pub data: [u32; 6],
    }
}

packet_struct! {
    /// Short Component Control: as [`ComponentControl`] with two data words.
    pub struct ShortComponentControl {
        /// Component.
        pub component_id: u16,
        /// Object the component belongs to.
        pub instance_id: u16,
        /// See [`ComponentControl::component_class`].
        pub component_class: u8 => 6,
        /// Discrete state.
        pub component_state: u8,
        /// Component data words.
        pub data: [u32; 2],
    }
}

packet_struct! {
    /// Articulated Part Control.
    pub struct ArticulatedPart {
        /// Entity.
        pub entity_id: u16,
        /// Articulated part.
        pub part_id: u8,
        /// Part shown.
        pub part_enable: bool,
        /// `x_offset_m` is applied.
        pub x_offset_enable: bool,
        /// `y_offset_m` is applied.
        pub y_offset_enable: bool,
        /// `z_offset_m` is applied.
        pub z_offset_enable: bool,
        /// `roll_deg` is applied.
        pub roll_enable: bool,
        /// `pitch_deg` is applied.
        pub pitch_enable: bool,
        /// `yaw_deg` is applied.
        pub yaw_enable: bool,
        /// X offset, metres.
        pub x_offset_m: f32,
        /// Y offset, metres.
        pub y_offset_m: f32,
        /// Z offset, metres.
        pub z_offset_m: f32,
        /// Roll, degrees.
        pub roll_deg: f32,
        /// Pitch, degrees.
        pub pitch_deg: f32,
        /// Yaw, degrees.
        pub yaw_deg: f32,
    }
}

packet_struct! {
    /// Short Articulated Part Control: two single degrees of freedom.
    pub struct ShortArticulatedPart {
        /// Entity.
        pub entity_id: u16,
        /// First part.
        pub part_id_1: u8,
        /// Second part.
        pub part_id_2: u8,
        /// DOF of `dof_1`: 0 not used, 1 X, 2 Y, 3 Z offset (m), 4 yaw,
        /// 5 pitch, 6 roll (deg).
        pub dof_select_1: u8 => 3,
        /// DOF of `dof_2` (as `dof_select_1`).
        pub dof_select_2: u8 => 3,
        /// First part shown.
        pub part_enable_1: bool,
        /// Second part shown.
        pub part_enable_2: bool,
        /// Value for the first part (metres or degrees per `dof_select_1`).
        pub dof_1: f32,
        /// Value for the second part.
        pub dof_2: f32,
    }
}

packet_struct! {
    /// Rate Control (3.3) / Velocity Control (4.0).
    pub struct RateControl {
        /// Entity.
        pub entity_id: u16,
        /// Articulated part when `apply_to_part`.
        pub part_id: u8,
        /// Rates apply to the articulated part (false: the entity).
        pub apply_to_part: bool,
        /// Rates are in the local (entity) frame (false: world/parent).
        pub coordinate_system_local: bool,
        /// X linear rate, m/s.
        pub x_rate_mps: f32,
        /// Y linear rate, m/s.
        pub y_rate_mps: f32,
        /// Z linear rate, m/s.
        pub z_rate_mps: f32,
        /// Roll rate, deg/s.
        pub roll_rate_dps: f32,
        /// Pitch rate, deg/s.
        pub pitch_rate_dps: f32,
        /// Yaw rate, deg/s.
        pub yaw_rate_dps: f32,
    }
}

packet_struct! {
    /// Celestial Sphere Control: time of day and date (UTC).
    pub struct CelestialSphereControl {
        /// Hour 0..23.
        pub hour: u8,
        /// Minute 0..59.
        pub minute: u8,
        /// CIGI 4.0 only: seconds 0..<60.
        pub seconds: f32,
        /// Ephemeris model enable.
        pub ephemeris_enable: bool,
        /// Sun enable.
        pub sun_enable: bool,
        /// Moon enable.
        pub moon_enable: bool,
        /// Star field enable.
        pub star_field_enable: bool,
        /// `date_mmddyyyy`, `hour` and `minute` are valid.
        pub date_time_valid: bool,
        /// Date as the decimal number MMDDYYYY.
        pub date_mmddyyyy: u32,
        /// Star field intensity, percent.
        pub star_field_intensity_pct: f32,
    }
}

packet_struct! {
    /// Atmosphere Control (global atmosphere).
    pub struct AtmosphereControl {
        /// Atmospheric model enable.
        pub atmospheric_model_enable: bool,
        /// Relative humidity, percent (0..100; 7 bits in 4.0).
        pub humidity_pct: u8 => 7,
        /// Air temperature, degC.
        pub air_temperature_c: f32,
        /// Visibility range, metres.
        pub visibility_range_m: f32,
        /// Horizontal wind speed, m/s.
        pub horizontal_wind_speed_mps: f32,
        /// Vertical wind speed, m/s.
        pub vertical_wind_speed_mps: f32,
        /// Direction the wind blows from, degrees from true north.
        pub wind_direction_deg: f32,
        /// Barometric pressure, millibar.
        pub barometric_pressure_mbar: f32,
    }
}

packet_struct! {
    /// Environmental Region Control.
    pub struct EnvironmentalRegionControl {
        /// Region.
        pub region_id: u16,
        /// 0 inactive, 1 active, 2 destroyed.
        pub region_state: u8 => 2,
        /// Merge weather properties (false: use last).
        pub merge_weather: bool,
        /// Merge aerosol concentrations.
        pub merge_aerosol: bool,
        /// Merge maritime surface conditions.
        pub merge_maritime: bool,
        /// Merge terrestrial surface conditions.
        pub merge_terrestrial: bool,
        /// Centre latitude, degrees.
        pub latitude_deg: f64,
        /// Centre longitude, degrees.
        pub longitude_deg: f64,
        /// Size along X, metres.
        pub size_x_m: f32,
        /// Size along Y, metres.
        pub size_y_m: f32,
        /// Corner radius, metres.
        pub corner_radius_m: f32,
        /// Rotation from true north, degrees.
        pub rotation_deg: f32,
        /// Transition perimeter, metres.
        pub transition_perimeter_m: f32,
    }
}

packet_struct! {
    /// Weather Control (a global, regional or entity weather layer).
    pub struct WeatherControl {
        /// Entity ID (scope entity) or region ID (scope regional).
        pub entity_or_region_id: u16,
        /// Layer: 0 ground fog, 1-3 cloud layers, 4 rain, 5 snow, 6 sleet,
        /// 7 hail, 8 sand, 9 dust, 10+ IG defined.
        pub layer_id: u8,
        /// Relative humidity, percent.
        pub humidity_pct: u8,
        /// Layer enable.
        pub weather_enable: bool,
        /// Scud enable.
        pub scud_enable: bool,
        /// Random winds enable.
        pub random_winds_enable: bool,
        /// Random lightning enable.
        pub random_lightning_enable: bool,
        /// Cloud type (ICD table: 0 none, 1 altocumulus ... 10 stratus).
        pub cloud_type: u8 => 4,
        /// 0 global, 1 regional, 2 entity.
        pub scope: u8 => 2,
        /// Severity 0..5.
        pub severity: u8 => 3,
        /// Air temperature, degC.
        pub air_temperature_c: f32,
        /// Visibility range, metres.
        pub visibility_range_m: f32,
        /// Scud frequency, percent.
        pub scud_frequency_pct: f32,
        /// Coverage, percent.
        pub coverage_pct: f32,
        /// Base elevation, metres.
        pub base_elevation_m: f32,
        /// Thickness, metres.
        pub thickness_m: f32,
        /// Transition band, metres.
        pub transition_band_m: f32,
        /// Horizontal wind speed, m/s.
        pub horizontal_wind_speed_mps: f32,
        /// Vertical wind speed, m/s.
        pub vertical_wind_speed_mps: f32,
        /// Wind direction, degrees.
        pub wind_direction_deg: f32,
        /// Barometric pressure, millibar.
        pub barometric_pressure_mbar: f32,
        /// Aerosol concentration, g/m^3.
        pub aerosol_concentration_gpm3: f32,
        /// CIGI 4.0 only: top scud enable.
        pub top_scud_enable: bool,
        /// CIGI 4.0 only: top scud frequency, percent.
        pub top_scud_frequency_pct: f32,
        /// CIGI 4.0 only: top transition band, metres.
        pub top_transition_band_m: f32,
    }
}

packet_struct! {
    /// Maritime Surface Conditions Control.
    pub struct MaritimeSurfaceConditionsControl {
        /// Entity ID (scope entity) or region ID (scope regional).
        pub entity_or_region_id: u16,
        /// Surface conditions enable.
        pub surface_conditions_enable: bool,
        /// Whitecaps enable.
        pub whitecap_enable: bool,
        /// 0 global, 1 regional, 2 entity.
        pub scope: u8 => 2,
        /// Sea surface height, metres.
        pub sea_surface_height_m: f32,
        /// Surface water temperature, degC.
        pub surface_water_temperature_c: f32,
        /// Surface clarity, percent.
        pub surface_clarity_pct: f32,
    }
}

packet_struct! {
    /// Wave Control.
    pub struct WaveControl {
        /// Entity ID (scope entity) or region ID (scope regional).
        pub entity_or_region_id: u16,
        /// Wave.
        pub wave_id: u8,
        /// Wave enable.
        pub wave_enable: bool,
        /// 0 global, 1 regional, 2 entity.
        pub scope: u8 => 2,
        /// 0 plunging, 1 spilling, 2 surging.
        pub breaker_type: u8 => 2,
        /// Wave height, metres.
        pub height_m: f32,
        /// Wavelength, metres.
        pub wavelength_m: f32,
        /// Period, seconds.
        pub period_s: f32,
        /// Direction, degrees.
        pub direction_deg: f32,
        /// Phase offset, degrees.
        pub phase_offset_deg: f32,
        /// Leading (crest shape), degrees.
        pub leading_deg: f32,
    }
}

packet_struct! {
    /// Terrestrial Surface Conditions Control.
    pub struct TerrestrialSurfaceConditionsControl {
        /// Entity ID (scope entity) or region ID (scope regional).
        pub entity_or_region_id: u16,
        /// Surface condition (IG defined).
        pub surface_condition_id: u16,
        /// Condition enable.
        pub surface_condition_enable: bool,
        /// 0 global, 1 regional, 2 entity.
        pub scope: u8 => 2,
        /// Severity 0..31.
        pub severity: u8 => 5,
        /// Coverage, percent.
        pub coverage_pct: u8,
    }
}

packet_struct! {
    /// View Control: places a view (eyepoint) relative to an entity.
    pub struct ViewControl {
        /// View.
        pub view_id: u16,
        /// View group (0: none).
        pub group_id: u8,
        /// `x_offset_m` is applied.
        pub x_offset_enable: bool,
        /// `y_offset_m` is applied.
        pub y_offset_enable: bool,
        /// `z_offset_m` is applied.
        pub z_offset_enable: bool,
        /// `roll_deg` is applied.
        pub roll_enable: bool,
        /// `pitch_deg` is applied.
        pub pitch_enable: bool,
        /// `yaw_deg` is applied.
        pub yaw_enable: bool,
        /// Entity the view is attached to.
        pub entity_id: u16,
        /// X offset, metres.
        pub x_offset_m: f32,
        /// Y offset, metres.
        pub y_offset_m: f32,
        /// Z offset, metres.
        pub z_offset_m: f32,
        /// Roll, degrees.
        pub roll_deg: f32,
        /// Pitch, degrees.
        pub pitch_deg: f32,
        /// Yaw, degrees.
        pub yaw_deg: f32,
    }
}

packet_struct! {
    /// Sensor Control.
    pub struct SensorControl {
        /// View the sensor is attached to.
        pub view_id: u16,
        /// Sensor.
        pub sensor_id: u8,
        /// Sensor on.
        pub sensor_on: bool,
        /// Black hot (false: white hot).
        pub polarity_black_hot: bool,
        /// Line-by-line dropout enable.
        pub line_dropout_enable: bool,
        /// Automatic gain enable.
        pub automatic_gain: bool,
        /// Track black (false: track white).
        pub track_black: bool,
        /// 0 off, 1 force correlate, 2 scene, 3 target, 4 ship, 5-7 IG defined.
        pub track_mode: u8 => 3,
        /// Respond with Sensor Extended Response (false: Sensor Response).
        pub response_type_extended: bool,
        /// Gain 0..1.
        pub gain: f32,
        /// Level 0..1.
        pub level: f32,
        /// AC coupling time constant, microseconds.
        pub ac_coupling_us: f32,
        /// Noise 0..1.
        pub noise: f32,
    }
}

packet_struct! {
    /// View Definition: frustum and display options of a view.
    pub struct ViewDefinition {
        /// View.
        pub view_id: u16,
        /// View group.
        pub group_id: u8,
        /// `near_m` is applied.
        pub near_enable: bool,
        /// `far_m` is applied.
        pub far_enable: bool,
        /// `left_deg` is applied.
        pub left_enable: bool,
        /// `right_deg` is applied.
        pub right_enable: bool,
        /// `top_deg` is applied.
        pub top_enable: bool,
        /// `bottom_deg` is applied.
        pub bottom_enable: bool,
        /// 0 none, 1 horizontal, 2 vertical, 3 both.
        pub mirror_mode: u8 => 2,
        /// 0 none, 1 1x2, 2 2x1, 3 2x2, 4-7 IG defined.
        pub pixel_replication: u8 => 3,
        /// Orthographic (false: perspective).
        pub projection_orthographic: bool,
        /// Bring this view to the top of the draw order.
        pub reorder: bool,
        /// IG-defined view type 0..7.
        pub view_type: u8 => 3,
        /// Near clipping plane, metres.
        pub near_m: f32,
        /// Far clipping plane, metres.
        pub far_m: f32,
        /// Left half angle, degrees (negative left of boresight).
        pub left_deg: f32,
        /// Right half angle, degrees.
        pub right_deg: f32,
        /// Top half angle, degrees.
        pub top_deg: f32,
        /// Bottom half angle, degrees.
        pub bottom_deg: f32,
    }
}

packet_struct! {
    /// Collision Detection Segment Definition.
    pub struct CollisionSegmentDefinition {
        /// Entity the segment belongs to.
        pub entity_id: u16,
        /// Segment.
        pub segment_id: u8,
        /// Segment enabled.
        pub segment_enable: bool,
        /// First end point X, metres (entity frame).
        pub x1_m: f32,
        /// First end point Y, metres.
        pub y1_m: f32,
        /// First end point Z, metres.
        pub z1_m: f32,
        /// Second end point X, metres.
        pub x2_m: f32,
        /// Second end point Y, metres.
        pub y2_m: f32,
        /// Second end point Z, metres.
        pub z2_m: f32,
        /// Material mask.
        pub material_mask: u32,
    }
}

packet_struct! {
    /// Collision Detection Volume Definition.
    pub struct CollisionVolumeDefinition {
        /// Entity the volume belongs to.
        pub entity_id: u16,
        /// Volume.
        pub volume_id: u8,
        /// Volume enabled.
        pub volume_enable: bool,
        /// Cuboid (false: sphere).
        pub volume_type_cuboid: bool,
        /// Centre X, metres.
        pub x_m: f32,
        /// Centre Y, metres.
        pub y_m: f32,
        /// Centre Z, metres.
        pub z_m: f32,
        /// Sphere radius or cuboid height, metres.
        pub height_or_radius_m: f32,
        /// Cuboid width, metres.
        pub width_m: f32,
        /// Cuboid depth, metres.
        pub depth_m: f32,
        /// Roll, degrees.
        pub roll_deg: f32,
        /// Pitch, degrees.
        pub pitch_deg: f32,
        /// Yaw, degrees.
        pub yaw_deg: f32,
    }
}

packet_struct! {
    /// HAT/HOT Request.
    pub struct HatHotRequest {
        /// Request (echoed in the response).
        pub hat_hot_id: u16,
        /// 0 HAT, 1 HOT, 2 extended (both).
        pub request_type: u8 => 2,
        /// Point given as an entity-relative offset (false: geodetic).
        pub coordinate_system_entity: bool,
        /// 0: one answer; n: answer every n frames.
        pub update_period: u8,
        /// Entity for entity-relative requests.
        pub entity_id: u16,
        /// Latitude in degrees, or X offset in metres.
        pub lat_deg_or_x_m: f64,
        /// Longitude in degrees, or Y offset in metres.
        pub lon_deg_or_y_m: f64,
        /// Altitude in metres, or Z offset in metres.
        pub alt_m_or_z_m: f64,
    }
}

packet_struct! {
    /// Line of Sight Segment Request.
    pub struct LosSegmentRequest {
        /// Request (echoed in the response).
        pub los_id: u16,
        /// Extended response requested (false: basic).
        pub request_type_extended: bool,
        /// Source point is entity relative.
        pub source_coordinate_entity: bool,
        /// Destination point is entity relative.
        pub destination_coordinate_entity: bool,
        /// Response position wanted entity relative.
        pub response_coordinate_entity: bool,
        /// `destination_entity_id` is valid.
        pub destination_entity_id_valid: bool,
        /// Minimum alpha of a surface that stops the ray.
        pub alpha_threshold: u8,
        /// Source entity for entity-relative points.
        pub entity_id: u16,
        /// Source latitude (deg) or X offset (m).
        pub source_lat_deg_or_x_m: f64,
        /// Source longitude (deg) or Y offset (m).
        pub source_lon_deg_or_y_m: f64,
        /// Source altitude or Z offset, metres.
        pub source_alt_m_or_z_m: f64,
        /// Destination latitude (deg) or X offset (m).
        pub destination_lat_deg_or_x_m: f64,
        /// Destination longitude (deg) or Y offset (m).
        pub destination_lon_deg_or_y_m: f64,
        /// Destination altitude or Z offset, metres.
        pub destination_alt_m_or_z_m: f64,
        /// Material mask.
        pub material_mask: u32,
        /// 0: one answer; n: answer every n frames.
        pub update_period: u8,
        /// Destination entity for entity-relative destinations.
        pub destination_entity_id: u16,
    }
}

packet_struct! {
    /// Line of Sight Vector Request.
    pub struct LosVectorRequest {
        /// Request (echoed in the response).
        pub los_id: u16,
        /// Extended response requested (false: basic).
        pub request_type_extended: bool,
        /// Source point is entity relative.
        pub source_coordinate_entity: bool,
        /// Response position wanted entity relative.
        pub response_coordinate_entity: bool,
        /// Minimum alpha of a surface that stops the ray.
        pub alpha_threshold: u8,
        /// Source entity.
        pub entity_id: u16,
        /// Vector azimuth, degrees.
        pub azimuth_deg: f32,
        /// Vector elevation, degrees.
        pub elevation_deg: f32,
        /// Minimum range, metres.
        pub min_range_m: f32,
        /// Maximum range, metres.
        pub max_range_m: f32,
        /// Source latitude (deg) or X offset (m).
        pub source_lat_deg_or_x_m: f64,
        /// Source longitude (deg) or Y offset (m).
        pub source_lon_deg_or_y_m: f64,
        /// Source altitude or Z offset, metres.
        pub source_alt_m_or_z_m: f64,
        /// Material mask.
        pub material_mask: u32,
        /// 0: one answer; n: answer every n frames.
        pub update_period: u8,
    }
}

packet_struct! {
    /// Position Request.
    pub struct PositionRequest {
        /// Object (entity, view, ...).
        pub object_id: u16,
        /// Articulated part for class "articulated part".
        pub part_id: u8,
        /// Continuous updates (false: one shot).
        pub update_mode_continuous: bool,
        /// 0 entity, 1 articulated part, 2 view, 3 view group, 4 motion tracker.
        pub object_class: u8 => 3,
        /// 0 geodetic, 1 parent entity, 2 submodel.
        pub coordinate_system: u8 => 2,
    }
}

packet_struct! {
    /// Environmental Conditions Request.
    pub struct EnvironmentalConditionsRequest {
        /// Bit mask: 1 maritime, 2 terrestrial, 4 weather, 8 aerosol.
        pub request_type: u8 => 4,
        /// Request (echoed in the responses).
        pub request_id: u8,
        /// Latitude, degrees.
        pub latitude_deg: f64,
        /// Longitude, degrees.
        pub longitude_deg: f64,
        /// Altitude, metres.
        pub altitude_m: f64,
    }
}

packet_struct! {
    /// HAT/HOT Response.
    pub struct HatHotResponse {
        /// Request answered.
        pub hat_hot_id: u16,
        /// The answer is valid.
        pub valid: bool,
        /// `height_m` is a HOT (false: a HAT).
        pub response_type_hot: bool,
        /// Least significant 4 bits of the host frame the answer is for.
        pub host_frame_lsn: u8 => 4,
        /// Height above / of terrain, metres.
        pub height_m: f64,
    }
}

packet_struct! {
    /// HAT/HOT Extended Response.
    pub struct HatHotExtendedResponse {
        /// Request answered.
        pub hat_hot_id: u16,
        /// The answer is valid.
        pub valid: bool,
        /// Least significant 4 bits of the host frame the answer is for.
        pub host_frame_lsn: u8 => 4,
        /// Height above terrain, metres.
        pub hat_m: f64,
        /// Height of terrain, metres.
        pub hot_m: f64,
        /// Material code of the surface.
        pub material_code: u32,
        /// Surface normal azimuth, degrees.
        pub normal_azimuth_deg: f32,
        /// Surface normal elevation, degrees.
        pub normal_elevation_deg: f32,
    }
}

packet_struct! {
    /// Line of Sight Response.
    pub struct LosResponse {
        /// Request answered.
        pub los_id: u16,
        /// The answer is valid.
        pub valid: bool,
        /// `entity_id` is valid (an entity was hit).
        pub entity_id_valid: bool,
        /// The destination is visible (segment requests).
        pub visible: bool,
        /// Least significant 4 bits of the host frame the answer is for.
        pub host_frame_lsn: u8 => 4,
        /// Number of responses for this request.
        pub response_count: u8,
        /// Entity hit.
        pub entity_id: u16,
        /// Range to the intersection, metres.
        pub range_m: f64,
    }
}

packet_struct! {
    /// Line of Sight Extended Response.
    pub struct LosExtendedResponse {
        /// Request answered.
        pub los_id: u16,
        /// The answer is valid.
        pub valid: bool,
        /// `entity_id` is valid.
        pub entity_id_valid: bool,
        /// `range_m` is valid.
        pub range_valid: bool,
        /// The destination is visible.
        pub visible: bool,
        /// Least significant 4 bits of the host frame the answer is for.
        pub host_frame_lsn: u8 => 4,
        /// Number of responses for this request.
        pub response_count: u8,
        /// Entity hit.
        pub entity_id: u16,
        /// Range, metres.
        pub range_m: f64,
        /// Intersection latitude (deg) or X offset (m).
        pub lat_deg_or_x_m: f64,
        /// Intersection longitude (deg) or Y offset (m).
        pub lon_deg_or_y_m: f64,
        /// Intersection altitude or Z offset, metres.
        pub alt_m_or_z_m: f64,
        /// Surface colour red.
        pub red: u8,
        /// Surface colour green.
        pub green: u8,
        /// Surface colour blue.
        pub blue: u8,
        /// Surface alpha.
        pub alpha: u8,
        /// Material code.
        pub material_code: u32,
        /// Surface normal azimuth, degrees.
        pub normal_azimuth_deg: f32,
        /// Surface normal elevation, degrees.
        pub normal_elevation_deg: f32,
    }
}

packet_struct! {
    /// Sensor Response.
    pub struct SensorResponse {
        /// View.
        pub view_id: u16,
        /// Sensor.
        pub sensor_id: u8,
        /// 0 searching, 1 tracking, 2 impending breaklock, 3 breaklock.
        pub sensor_status: u8 => 2,
        /// Gate width, pixels.
        pub gate_x_size_px: u16,
        /// Gate height, pixels.
        pub gate_y_size_px: u16,
        /// Gate horizontal position, degrees.
        pub gate_x_position_deg: f32,
        /// Gate vertical position, degrees.
        pub gate_y_position_deg: f32,
        /// IG frame of the data.
        pub frame_counter: u32,
    }
}

packet_struct! {
    /// Sensor Extended Response.
    pub struct SensorExtendedResponse {
        /// View.
        pub view_id: u16,
        /// Sensor.
        pub sensor_id: u8,
        /// 0 searching, 1 tracking, 2 impending breaklock, 3 breaklock.
        pub sensor_status: u8 => 2,
        /// `entity_id` is valid.
        pub entity_id_valid: bool,
        /// Tracked entity.
        pub entity_id: u16,
        /// Gate width, pixels.
        pub gate_x_size_px: u16,
        /// Gate height, pixels.
        pub gate_y_size_px: u16,
        /// Gate horizontal position, degrees.
        pub gate_x_position_deg: f32,
        /// Gate vertical position, degrees.
        pub gate_y_position_deg: f32,
        /// IG frame of the data.
        pub frame_counter: u32,
        /// Track point latitude, degrees.
        pub track_latitude_deg: f64,
        /// Track point longitude, degrees.
        pub track_longitude_deg: f64,
        /// Track point altitude, metres.
        pub track_altitude_m: f64,
    }
}

packet_struct! {
    /// Position Response.
    pub struct PositionResponse {
        /// Object.
        pub object_id: u16,
        /// Articulated part.
        pub part_id: u8,
        /// 0 entity, 1 articulated part, 2 view, 3 view group, 4 motion tracker.
        pub object_class: u8 => 3,
        /// 0 geodetic, 1 parent entity, 2 submodel.
        pub coordinate_system: u8 => 2,
        /// Latitude (deg) or X offset (m).
        pub lat_deg_or_x_m: f64,
        /// Longitude (deg) or Y offset (m).
        pub lon_deg_or_y_m: f64,
        /// Altitude or Z offset, metres.
        pub alt_m_or_z_m: f64,
        /// Roll, degrees.
        pub roll_deg: f32,
        /// Pitch, degrees.
        pub pitch_deg: f32,
        /// Yaw, degrees.
        pub yaw_deg: f32,
    }
}

packet_struct! {
    /// Weather Conditions Response.
    pub struct WeatherConditionsResponse {
        /// Request answered.
        pub request_id: u8,
        /// Relative humidity, percent.
        pub humidity_pct: u8,
        /// Air temperature, degC.
        pub air_temperature_c: f32,
        /// Visibility range, metres.
        pub visibility_range_m: f32,
        /// Horizontal wind speed, m/s.
        pub horizontal_wind_speed_mps: f32,
        /// Vertical wind speed, m/s.
        pub vertical_wind_speed_mps: f32,
        /// Wind direction, degrees.
        pub wind_direction_deg: f32,
        /// Barometric pressure, millibar.
        pub barometric_pressure_mbar: f32,
    }
}

packet_struct! {
    /// Aerosol Concentration Response.
    pub struct AerosolConcentrationResponse {
        /// Request answered.
        pub request_id: u8,
        /// Weather layer.
        pub layer_id: u8,
        /// Aerosol concentration, g/m^3.
        pub aerosol_concentration_gpm3: f32,
    }
}

packet_struct! {
    /// Maritime Surface Conditions Response.
    pub struct MaritimeSurfaceConditionsResponse {
        /// Request answered.
        pub request_id: u8,
        /// Sea surface height, metres.
        pub sea_surface_height_m: f32,
        /// Surface water temperature, degC.
        pub surface_water_temperature_c: f32,
        /// Surface clarity, percent.
        pub surface_clarity_pct: f32,
    }
}

packet_struct! {
    /// Terrestrial Surface Conditions Response.
    pub struct TerrestrialSurfaceConditionsResponse {
        /// Request answered.
        pub request_id: u8,
        /// Dominant surface condition.
        pub surface_condition_id: u32,
    }
}

packet_struct! {
    /// Collision Detection Segment Notification.
    pub struct CollisionSegmentNotification {
        /// Entity whose segment collided.
        pub entity_id: u16,
        /// Segment.
        pub segment_id: u8,
        /// Collided with an entity (false: with the terrain/non-entity).
        pub collision_with_entity: bool,
        /// Entity collided with.
        pub contacted_entity_id: u16,
        /// Material code.
        pub material_code: u32,
        /// Distance from the segment start, metres.
        pub intersection_distance_m: f32,
    }
}

packet_struct! {
    /// Collision Detection Volume Notification.
    pub struct CollisionVolumeNotification {
        /// Entity whose volume collided.
        pub entity_id: u16,
        /// Volume.
        pub volume_id: u8,
        /// Collided with an entity.
        pub collision_with_entity: bool,
        /// Entity collided with.
        pub contacted_entity_id: u16,
        /// Volume of the contacted entity.
        pub contacted_volume_id: u8,
    }
}

packet_struct! {
    /// Animation Stop Notification.
    pub struct AnimationStopNotification {
        /// Entity whose animation stopped.
        pub entity_id: u16,
    }
}

packet_struct! {
    /// Event Notification.
    pub struct EventNotification {
        /// Event.
        pub event_id: u16,
        /// Event data words.
        pub data: [u32; 3],
    }
}

packet_struct! {
    /// Image Generator Message (text from the IG).
    pub struct ImageGeneratorMessage {
        /// Message.
        pub message_id: u16,
        /// Text, at most [`crate::MAX_IG_MESSAGE_TEXT_BYTES`] bytes of ASCII.
        pub text: String,
    }
}

packet_struct! {
    /// A user-defined packet, passed through as raw bytes.
    pub struct UserDefined {
        /// Packet ID (3.x: 201..=255; 4.0: 0x1000..=0xFFFE).
        pub packet_id: u16,
        /// The bytes after the packet header (3.x: 2 bytes, 4.0: 4 bytes),
        /// in the sender's byte order (the codec cannot know their layout).
        pub data: Vec<u8>,
    }
}
