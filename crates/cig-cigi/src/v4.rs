//! CIGI 4.0 packet layouts (SISO-STD-013 ICD 4.0).
//!
//! Algorithm: as for 3.3, one layout function per packet. Every 4.0 packet
//! starts with a 16-bit Packet Size and a 16-bit Packet ID, both in the
//! sender's byte order; fields were realigned so that every 16/32/64-bit
//! field sits on its natural boundary, and sizes are multiples of 8. Host to
//! IG packet IDs run from 0x00 (IG Control) upward; IG to host packets run
//! downward from 0x0FFF (HAT/HOT Response) to 0x0FF0 (Image Generator
//! Message), with Start of Frame at 0xFFFF; user-defined packets use
//! 0x1000..=0xFFFE.
//!
//! Source and limits: no independent 4.0 decoder was available, so offsets,
//! sizes and IDs were taken from the CIGI Class Library 4.0.2 pack/unpack
//! routines and its packet-ID definitions (facts only; the code here is our
//! own), and are checked by hand-built byte vectors in the tests. Six
//! IG-to-host IDs (0x0FFD..0x0FF1 other than the ones the CCL headers show)
//! follow the ICD's ordering of the 3.3 packets 104..116; see
//! `docs/cigi-conformance.md`. Byte order of a 4.0 message is detected from
//! the first packet's size field (IG Control and Start of Frame are 24 bytes,
//! so the high byte of the size is zero in the sender's order), as the CCL
//! does.

use crate::packets::*;
use crate::wire::{ByteOrder, FieldIo, Writer};

pub(crate) const IG_MESSAGE_ID: u16 = 0x0FF0;
pub(crate) const USER_DEFINED_FIRST: u16 = 0x1000;
pub(crate) const USER_DEFINED_LAST: u16 = 0xFFFE;

pub(crate) fn ig_control(io: &mut impl FieldIo, p: &mut IgControl) {
    io.i8(5, &mut p.database_number);
    io.flag(6, 0, &mut p.entity_substitution_enable);
    io.bits(7, 0, 2, &mut p.ig_mode);
    io.flag(7, 2, &mut p.timestamp_valid);
    io.flag(7, 3, &mut p.smoothing_enable);
    io.u32(8, &mut p.host_frame_number);
    io.u32(12, &mut p.last_ig_frame_number);
    io.u32(16, &mut p.timestamp_10us);
}

pub(crate) fn start_of_frame(io: &mut impl FieldIo, p: &mut StartOfFrame) {
    io.i8(5, &mut p.database_number);
    io.bits(7, 0, 2, &mut p.ig_mode);
    io.flag(7, 2, &mut p.timestamp_valid);
    io.flag(7, 3, &mut p.earth_reference_model_host_defined);
    io.u32(8, &mut p.ig_frame_number);
    io.u32(12, &mut p.timestamp_10us);
    io.u32(16, &mut p.last_host_frame_number);
    // The IG conditions are bits 8..10 of a 16-bit field: their byte depends
    // on the byte order, so they go through a 16-bit access.
    let mut conditions = (u16::from(p.overframing) << 8)
        | (u16::from(p.paging) << 9)
        | (u16::from(p.excessive_variable_length_data) << 10);
    io.u16(20, &mut conditions);
    p.overframing = conditions & 0x0100 != 0;
    p.paging = conditions & 0x0200 != 0;
    p.excessive_variable_length_data = conditions & 0x0400 != 0;
}

fn entity_position(io: &mut impl FieldIo, p: &mut EntityPosition) {
    io.flag(4, 0, &mut p.attach);
    io.bits(4, 1, 2, &mut p.ground_ocean_clamp);
    io.u16(6, &mut p.entity_id);
    io.u16(8, &mut p.parent_id);
    io.f32(12, &mut p.roll_deg);
    io.f32(16, &mut p.pitch_deg);
    io.f32(20, &mut p.yaw_deg);
    io.f64(24, &mut p.lat_deg_or_x_m);
    io.f64(32, &mut p.lon_deg_or_y_m);
    io.f64(40, &mut p.alt_m_or_z_m);
}

fn entity_control(io: &mut impl FieldIo, p: &mut EntityControl4) {
    io.bits(4, 0, 2, &mut p.entity_state);
    io.flag(4, 2, &mut p.collision_detection_enable);
    io.flag(4, 3, &mut p.inherit_alpha);
    io.flag(4, 4, &mut p.smoothing_enable);
    io.flag(4, 5, &mut p.extended_entity_type);
    io.u8(5, &mut p.alpha);
    io.u16(6, &mut p.entity_id);
    io.u8(8, &mut p.entity_kind);
    io.u8(9, &mut p.entity_domain);
    io.u16(10, &mut p.entity_type_or_country);
    io.u8(12, &mut p.entity_category);
    io.u8(13, &mut p.entity_subcategory);
    io.u8(14, &mut p.entity_specific);
    io.u8(15, &mut p.entity_extra);
}

fn animation_control(io: &mut impl FieldIo, p: &mut AnimationControl) {
    io.flag(4, 0, &mut p.play);
    io.flag(4, 1, &mut p.frame_reset);
    io.flag(4, 2, &mut p.loop_continuous);
    io.flag(4, 3, &mut p.inherit_alpha);
    io.u8(5, &mut p.alpha);
    io.u16(6, &mut p.entity_id);
    io.u16(8, &mut p.animation_id);
    io.f32(12, &mut p.speed_factor);
}

fn conformal_clamped(io: &mut impl FieldIo, p: &mut ConformalClampedEntity) {
    io.u16(4, &mut p.entity_id);
    io.f32(8, &mut p.yaw_deg);
    io.f64(16, &mut p.latitude_deg);
    io.f64(24, &mut p.longitude_deg);
}

fn component_control(io: &mut impl FieldIo, p: &mut ComponentControl) {
    io.u16(4, &mut p.component_id);
    io.bits(6, 0, 6, &mut p.component_class);
    io.u8(7, &mut p.component_state);
    io.u16(8, &mut p.instance_id);
    for (i, word) in p.data.iter_mut().enumerate() {
        io.u32(16 + 4 * i, word);
    }
}

fn short_component_control(io: &mut impl FieldIo, p: &mut ShortComponentControl) {
    io.u16(4, &mut p.component_id);
    io.bits(6, 0, 6, &mut p.component_class);
    io.u8(7, &mut p.component_state);
    io.u16(8, &mut p.instance_id);
    for (i, word) in p.data.iter_mut().enumerate() {
        io.u32(16 + 4 * i, word);
    }
}

fn articulated_part(io: &mut impl FieldIo, p: &mut ArticulatedPart) {
    io.u16(4, &mut p.entity_id);
    io.u8(6, &mut p.part_id);
    io.flag(7, 0, &mut p.part_enable);
    io.flag(7, 1, &mut p.x_offset_enable);
    io.flag(7, 2, &mut p.y_offset_enable);
    io.flag(7, 3, &mut p.z_offset_enable);
    io.flag(7, 4, &mut p.roll_enable);
    io.flag(7, 5, &mut p.pitch_enable);
    io.flag(7, 6, &mut p.yaw_enable);
    io.f32(8, &mut p.x_offset_m);
    io.f32(12, &mut p.y_offset_m);
    io.f32(16, &mut p.z_offset_m);
    io.f32(20, &mut p.roll_deg);
    io.f32(24, &mut p.pitch_deg);
    io.f32(28, &mut p.yaw_deg);
}

fn short_articulated_part(io: &mut impl FieldIo, p: &mut ShortArticulatedPart) {
    io.u16(4, &mut p.entity_id);
    io.u8(6, &mut p.part_id_1);
    io.u8(7, &mut p.part_id_2);
    io.bits(8, 0, 3, &mut p.dof_select_1);
    io.bits(8, 3, 3, &mut p.dof_select_2);
    io.flag(8, 6, &mut p.part_enable_1);
    io.flag(8, 7, &mut p.part_enable_2);
    io.f32(12, &mut p.dof_1);
    io.f32(16, &mut p.dof_2);
}

fn velocity_control(io: &mut impl FieldIo, p: &mut RateControl) {
    io.u16(4, &mut p.entity_id);
    io.u8(6, &mut p.part_id);
    io.flag(7, 0, &mut p.apply_to_part);
    io.flag(7, 1, &mut p.coordinate_system_local);
    io.f32(8, &mut p.x_rate_mps);
    io.f32(12, &mut p.y_rate_mps);
    io.f32(16, &mut p.z_rate_mps);
    io.f32(20, &mut p.roll_rate_dps);
    io.f32(24, &mut p.pitch_rate_dps);
    io.f32(28, &mut p.yaw_rate_dps);
}

fn celestial(io: &mut impl FieldIo, p: &mut CelestialSphereControl) {
    io.flag(4, 0, &mut p.ephemeris_enable);
    io.flag(4, 1, &mut p.sun_enable);
    io.flag(4, 2, &mut p.moon_enable);
    io.flag(4, 3, &mut p.star_field_enable);
    io.flag(4, 4, &mut p.date_time_valid);
    io.u8(6, &mut p.hour);
    io.u8(7, &mut p.minute);
    io.f32(8, &mut p.seconds);
    io.u32(12, &mut p.date_mmddyyyy);
    io.f32(16, &mut p.star_field_intensity_pct);
}

fn atmosphere(io: &mut impl FieldIo, p: &mut AtmosphereControl) {
    io.bits(4, 0, 7, &mut p.humidity_pct);
    io.flag(4, 7, &mut p.atmospheric_model_enable);
    io.f32(8, &mut p.air_temperature_c);
    io.f32(12, &mut p.visibility_range_m);
    io.f32(16, &mut p.horizontal_wind_speed_mps);
    io.f32(20, &mut p.vertical_wind_speed_mps);
    io.f32(24, &mut p.wind_direction_deg);
    io.f32(28, &mut p.barometric_pressure_mbar);
}

fn environmental_region(io: &mut impl FieldIo, p: &mut EnvironmentalRegionControl) {
    io.bits(4, 0, 2, &mut p.region_state);
    io.flag(4, 2, &mut p.merge_weather);
    io.flag(4, 3, &mut p.merge_aerosol);
    io.flag(4, 4, &mut p.merge_maritime);
    io.flag(4, 5, &mut p.merge_terrestrial);
    io.u16(6, &mut p.region_id);
    io.f64(8, &mut p.latitude_deg);
    io.f64(16, &mut p.longitude_deg);
    io.f32(24, &mut p.size_x_m);
    io.f32(28, &mut p.size_y_m);
    io.f32(32, &mut p.corner_radius_m);
    io.f32(36, &mut p.rotation_deg);
    io.f32(40, &mut p.transition_perimeter_m);
}

fn weather(io: &mut impl FieldIo, p: &mut WeatherControl) {
    io.u8(4, &mut p.layer_id);
    io.u8(5, &mut p.humidity_pct);
    io.flag(6, 0, &mut p.weather_enable);
    io.flag(6, 1, &mut p.scud_enable);
    io.flag(6, 2, &mut p.random_winds_enable);
    io.flag(6, 3, &mut p.random_lightning_enable);
    io.bits(6, 4, 4, &mut p.cloud_type);
    io.bits(7, 0, 2, &mut p.scope);
    io.bits(7, 2, 3, &mut p.severity);
    io.flag(7, 5, &mut p.top_scud_enable);
    io.u16(8, &mut p.entity_or_region_id);
    io.f32(12, &mut p.air_temperature_c);
    io.f32(16, &mut p.visibility_range_m);
    io.f32(20, &mut p.scud_frequency_pct);
    io.f32(24, &mut p.coverage_pct);
    io.f32(28, &mut p.base_elevation_m);
    io.f32(32, &mut p.thickness_m);
    io.f32(36, &mut p.transition_band_m);
    io.f32(40, &mut p.horizontal_wind_speed_mps);
    io.f32(44, &mut p.vertical_wind_speed_mps);
    io.f32(48, &mut p.wind_direction_deg);
    io.f32(52, &mut p.barometric_pressure_mbar);
    io.f32(56, &mut p.aerosol_concentration_gpm3);
    io.f32(60, &mut p.top_scud_frequency_pct);
    io.f32(64, &mut p.top_transition_band_m);
}

fn maritime_control(io: &mut impl FieldIo, p: &mut MaritimeSurfaceConditionsControl) {
    io.flag(4, 0, &mut p.surface_conditions_enable);
    io.flag(4, 1, &mut p.whitecap_enable);
    io.bits(4, 2, 2, &mut p.scope);
    io.u16(6, &mut p.entity_or_region_id);
    io.f32(8, &mut p.sea_surface_height_m);
    io.f32(12, &mut p.surface_water_temperature_c);
    io.f32(16, &mut p.surface_clarity_pct);
}

fn wave_control(io: &mut impl FieldIo, p: &mut WaveControl) {
    io.u8(4, &mut p.wave_id);
    io.flag(5, 0, &mut p.wave_enable);
    io.bits(5, 1, 2, &mut p.scope);
    io.bits(5, 3, 2, &mut p.breaker_type);
    io.u16(6, &mut p.entity_or_region_id);
    io.f32(8, &mut p.height_m);
    io.f32(12, &mut p.wavelength_m);
    io.f32(16, &mut p.period_s);
    io.f32(20, &mut p.direction_deg);
    io.f32(24, &mut p.phase_offset_deg);
    io.f32(28, &mut p.leading_deg);
}

fn terrestrial_control(io: &mut impl FieldIo, p: &mut TerrestrialSurfaceConditionsControl) {
    io.u16(4, &mut p.entity_or_region_id);
    io.flag(6, 0, &mut p.surface_condition_enable);
    io.bits(6, 1, 2, &mut p.scope);
    io.bits(6, 3, 5, &mut p.severity);
    io.u8(7, &mut p.coverage_pct);
    io.u16(8, &mut p.surface_condition_id);
}

fn view_control(io: &mut impl FieldIo, p: &mut ViewControl) {
    io.u8(4, &mut p.group_id);
    io.flag(5, 0, &mut p.x_offset_enable);
    io.flag(5, 1, &mut p.y_offset_enable);
    io.flag(5, 2, &mut p.z_offset_enable);
    io.flag(5, 3, &mut p.roll_enable);
    io.flag(5, 4, &mut p.pitch_enable);
    io.flag(5, 5, &mut p.yaw_enable);
    io.u16(6, &mut p.view_id);
    io.u16(8, &mut p.entity_id);
    io.f32(12, &mut p.x_offset_m);
    io.f32(16, &mut p.y_offset_m);
    io.f32(20, &mut p.z_offset_m);
    io.f32(24, &mut p.roll_deg);
    io.f32(28, &mut p.pitch_deg);
    io.f32(32, &mut p.yaw_deg);
}

fn sensor_control(io: &mut impl FieldIo, p: &mut SensorControl) {
    io.u8(4, &mut p.sensor_id);
    io.flag(5, 0, &mut p.sensor_on);
    io.flag(5, 1, &mut p.polarity_black_hot);
    io.flag(5, 2, &mut p.line_dropout_enable);
    io.flag(5, 3, &mut p.automatic_gain);
    io.flag(5, 4, &mut p.track_black);
    io.bits(5, 5, 3, &mut p.track_mode);
    io.flag(6, 0, &mut p.response_type_extended);
    io.u16(8, &mut p.view_id);
    io.f32(12, &mut p.gain);
    io.f32(16, &mut p.level);
    io.f32(20, &mut p.ac_coupling_us);
    io.f32(24, &mut p.noise);
}

fn view_definition(io: &mut impl FieldIo, p: &mut ViewDefinition) {
    io.u16(4, &mut p.view_id);
    io.u8(6, &mut p.group_id);
    io.flag(7, 0, &mut p.near_enable);
    io.flag(7, 1, &mut p.far_enable);
    io.flag(7, 2, &mut p.left_enable);
    io.flag(7, 3, &mut p.right_enable);
    io.flag(7, 4, &mut p.top_enable);
    io.flag(7, 5, &mut p.bottom_enable);
    io.bits(7, 6, 2, &mut p.mirror_mode);
    io.bits(8, 0, 3, &mut p.pixel_replication);
    io.flag(8, 3, &mut p.projection_orthographic);
    io.flag(8, 4, &mut p.reorder);
    io.bits(8, 5, 3, &mut p.view_type);
    io.f32(12, &mut p.near_m);
    io.f32(16, &mut p.far_m);
    io.f32(20, &mut p.left_deg);
    io.f32(24, &mut p.right_deg);
    io.f32(28, &mut p.top_deg);
    io.f32(32, &mut p.bottom_deg);
}

fn collision_segment(io: &mut impl FieldIo, p: &mut CollisionSegmentDefinition) {
    io.u8(4, &mut p.segment_id);
    io.flag(5, 0, &mut p.segment_enable);
    io.u16(6, &mut p.entity_id);
    io.f32(8, &mut p.x1_m);
    io.f32(12, &mut p.y1_m);
    io.f32(16, &mut p.z1_m);
    io.f32(20, &mut p.x2_m);
    io.f32(24, &mut p.y2_m);
    io.f32(28, &mut p.z2_m);
    io.u32(32, &mut p.material_mask);
}

fn collision_volume(io: &mut impl FieldIo, p: &mut CollisionVolumeDefinition) {
    io.u8(4, &mut p.volume_id);
    io.flag(5, 0, &mut p.volume_enable);
    io.flag(5, 1, &mut p.volume_type_cuboid);
    io.u16(6, &mut p.entity_id);
    io.f32(8, &mut p.x_m);
    io.f32(12, &mut p.y_m);
    io.f32(16, &mut p.z_m);
    io.f32(20, &mut p.height_or_radius_m);
    io.f32(24, &mut p.width_m);
    io.f32(28, &mut p.depth_m);
    io.f32(32, &mut p.roll_deg);
    io.f32(36, &mut p.pitch_deg);
    io.f32(40, &mut p.yaw_deg);
}

fn hat_hot_request(io: &mut impl FieldIo, p: &mut HatHotRequest) {
    io.u16(4, &mut p.hat_hot_id);
    io.u16(6, &mut p.entity_id);
    io.bits(8, 0, 2, &mut p.request_type);
    io.flag(8, 2, &mut p.coordinate_system_entity);
    io.u8(9, &mut p.update_period);
    io.f64(16, &mut p.lat_deg_or_x_m);
    io.f64(24, &mut p.lon_deg_or_y_m);
    io.f64(32, &mut p.alt_m_or_z_m);
}

fn los_segment(io: &mut impl FieldIo, p: &mut LosSegmentRequest) {
    io.u16(4, &mut p.los_id);
    io.u16(6, &mut p.entity_id);
    io.flag(8, 0, &mut p.request_type_extended);
    io.flag(8, 1, &mut p.source_coordinate_entity);
    io.flag(8, 2, &mut p.destination_coordinate_entity);
    io.flag(8, 3, &mut p.response_coordinate_entity);
    io.flag(8, 4, &mut p.destination_entity_id_valid);
    io.u8(9, &mut p.alpha_threshold);
    io.u16(10, &mut p.destination_entity_id);
    io.u8(12, &mut p.update_period);
    io.f64(16, &mut p.source_lat_deg_or_x_m);
    io.f64(24, &mut p.source_lon_deg_or_y_m);
    io.f64(32, &mut p.source_alt_m_or_z_m);
    io.f64(40, &mut p.destination_lat_deg_or_x_m);
    io.f64(48, &mut p.destination_lon_deg_or_y_m);
    io.f64(56, &mut p.destination_alt_m_or_z_m);
    io.u32(64, &mut p.material_mask);
}

fn los_vector(io: &mut impl FieldIo, p: &mut LosVectorRequest) {
    io.u16(4, &mut p.los_id);
    io.u16(6, &mut p.entity_id);
    io.flag(8, 0, &mut p.request_type_extended);
    io.flag(8, 1, &mut p.source_coordinate_entity);
    io.flag(8, 2, &mut p.response_coordinate_entity);
    io.u8(9, &mut p.alpha_threshold);
    io.u8(10, &mut p.update_period);
    io.f32(16, &mut p.azimuth_deg);
    io.f32(20, &mut p.elevation_deg);
    io.f32(24, &mut p.min_range_m);
    io.f32(28, &mut p.max_range_m);
    io.f64(32, &mut p.source_lat_deg_or_x_m);
    io.f64(40, &mut p.source_lon_deg_or_y_m);
    io.f64(48, &mut p.source_alt_m_or_z_m);
    io.u32(56, &mut p.material_mask);
}

fn position_request(io: &mut impl FieldIo, p: &mut PositionRequest) {
    io.u8(4, &mut p.part_id);
    io.flag(5, 0, &mut p.update_mode_continuous);
    io.bits(5, 1, 3, &mut p.object_class);
    io.bits(5, 4, 2, &mut p.coordinate_system);
    io.u16(6, &mut p.object_id);
}

fn environmental_conditions_request(io: &mut impl FieldIo, p: &mut EnvironmentalConditionsRequest) {
    io.bits(4, 0, 4, &mut p.request_type);
    io.u8(5, &mut p.request_id);
    io.f64(8, &mut p.latitude_deg);
    io.f64(16, &mut p.longitude_deg);
    io.f64(24, &mut p.altitude_m);
}

fn hat_hot_response(io: &mut impl FieldIo, p: &mut HatHotResponse) {
    io.flag(4, 0, &mut p.valid);
    io.flag(4, 1, &mut p.response_type_hot);
    io.bits(4, 4, 4, &mut p.host_frame_lsn);
    io.u16(6, &mut p.hat_hot_id);
    io.f64(8, &mut p.height_m);
}

fn hat_hot_extended_response(io: &mut impl FieldIo, p: &mut HatHotExtendedResponse) {
    io.flag(4, 0, &mut p.valid);
    io.bits(4, 4, 4, &mut p.host_frame_lsn);
    io.u16(6, &mut p.hat_hot_id);
    io.f64(8, &mut p.hat_m);
    io.f64(16, &mut p.hot_m);
    io.u32(24, &mut p.material_code);
    io.f32(28, &mut p.normal_azimuth_deg);
    io.f32(32, &mut p.normal_elevation_deg);
}

fn los_response(io: &mut impl FieldIo, p: &mut LosResponse) {
    io.u16(4, &mut p.los_id);
    io.u16(6, &mut p.entity_id);
    io.flag(8, 0, &mut p.valid);
    io.flag(8, 1, &mut p.entity_id_valid);
    io.flag(8, 2, &mut p.visible);
    io.bits(8, 4, 4, &mut p.host_frame_lsn);
    io.u8(9, &mut p.response_count);
    io.f64(16, &mut p.range_m);
}

fn los_extended_response(io: &mut impl FieldIo, p: &mut LosExtendedResponse) {
    io.u16(4, &mut p.los_id);
    io.u16(6, &mut p.entity_id);
    io.flag(8, 0, &mut p.valid);
    io.flag(8, 1, &mut p.entity_id_valid);
    io.flag(8, 2, &mut p.range_valid);
    io.flag(8, 3, &mut p.visible);
    io.bits(8, 4, 4, &mut p.host_frame_lsn);
    io.u8(9, &mut p.response_count);
    io.f64(16, &mut p.range_m);
    io.f64(24, &mut p.lat_deg_or_x_m);
    io.f64(32, &mut p.lon_deg_or_y_m);
    io.f64(40, &mut p.alt_m_or_z_m);
    io.u8(48, &mut p.red);
    io.u8(49, &mut p.green);
    io.u8(50, &mut p.blue);
    io.u8(51, &mut p.alpha);
    io.u32(52, &mut p.material_code);
    io.f32(56, &mut p.normal_azimuth_deg);
    io.f32(60, &mut p.normal_elevation_deg);
}

fn sensor_response(io: &mut impl FieldIo, p: &mut SensorResponse) {
    io.u8(4, &mut p.sensor_id);
    io.bits(5, 0, 2, &mut p.sensor_status);
    io.u16(6, &mut p.view_id);
    io.u16(8, &mut p.gate_x_size_px);
    io.u16(10, &mut p.gate_y_size_px);
    io.f32(12, &mut p.gate_x_position_deg);
    io.f32(16, &mut p.gate_y_position_deg);
    io.u32(20, &mut p.frame_counter);
}

fn sensor_extended_response(io: &mut impl FieldIo, p: &mut SensorExtendedResponse) {
    io.u16(4, &mut p.view_id);
    io.u16(6, &mut p.entity_id);
    io.u8(8, &mut p.sensor_id);
    io.bits(9, 0, 2, &mut p.sensor_status);
    io.flag(9, 2, &mut p.entity_id_valid);
    io.u16(12, &mut p.gate_x_size_px);
    io.u16(14, &mut p.gate_y_size_px);
    io.f32(16, &mut p.gate_x_position_deg);
    io.f32(20, &mut p.gate_y_position_deg);
    io.u32(24, &mut p.frame_counter);
    io.f64(32, &mut p.track_latitude_deg);
    io.f64(40, &mut p.track_longitude_deg);
    io.f64(48, &mut p.track_altitude_m);
}

fn position_response(io: &mut impl FieldIo, p: &mut PositionResponse) {
    io.u8(4, &mut p.part_id);
    io.bits(5, 0, 3, &mut p.object_class);
    io.bits(5, 3, 2, &mut p.coordinate_system);
    io.u16(6, &mut p.object_id);
    io.f64(8, &mut p.lat_deg_or_x_m);
    io.f64(16, &mut p.lon_deg_or_y_m);
    io.f64(24, &mut p.alt_m_or_z_m);
    io.f32(32, &mut p.roll_deg);
    io.f32(36, &mut p.pitch_deg);
    io.f32(40, &mut p.yaw_deg);
}

fn weather_conditions_response(io: &mut impl FieldIo, p: &mut WeatherConditionsResponse) {
    io.u8(4, &mut p.request_id);
    io.u8(5, &mut p.humidity_pct);
    io.f32(8, &mut p.air_temperature_c);
    io.f32(12, &mut p.visibility_range_m);
    io.f32(16, &mut p.horizontal_wind_speed_mps);
    io.f32(20, &mut p.vertical_wind_speed_mps);
    io.f32(24, &mut p.wind_direction_deg);
    io.f32(28, &mut p.barometric_pressure_mbar);
}

fn aerosol_response(io: &mut impl FieldIo, p: &mut AerosolConcentrationResponse) {
    io.u8(4, &mut p.request_id);
    io.u8(5, &mut p.layer_id);
    io.f32(8, &mut p.aerosol_concentration_gpm3);
}

fn maritime_response(io: &mut impl FieldIo, p: &mut MaritimeSurfaceConditionsResponse) {
    io.u8(4, &mut p.request_id);
    io.f32(8, &mut p.sea_surface_height_m);
    io.f32(12, &mut p.surface_water_temperature_c);
    io.f32(16, &mut p.surface_clarity_pct);
}

fn terrestrial_response(io: &mut impl FieldIo, p: &mut TerrestrialSurfaceConditionsResponse) {
    io.u8(4, &mut p.request_id);
    io.u32(8, &mut p.surface_condition_id);
}

fn collision_segment_notification(io: &mut impl FieldIo, p: &mut CollisionSegmentNotification) {
    io.u16(4, &mut p.entity_id);
    io.u16(6, &mut p.contacted_entity_id);
    io.u8(8, &mut p.segment_id);
    io.flag(9, 0, &mut p.collision_with_entity);
    io.u32(12, &mut p.material_code);
    io.f32(16, &mut p.intersection_distance_m);
}

fn collision_volume_notification(io: &mut impl FieldIo, p: &mut CollisionVolumeNotification) {
    io.u16(4, &mut p.entity_id);
    io.u16(6, &mut p.contacted_entity_id);
    io.u8(8, &mut p.volume_id);
    io.flag(9, 0, &mut p.collision_with_entity);
    io.u8(10, &mut p.contacted_volume_id);
}

fn animation_stop(io: &mut impl FieldIo, p: &mut AnimationStopNotification) {
    io.u16(4, &mut p.entity_id);
}

fn event_notification(io: &mut impl FieldIo, p: &mut EventNotification) {
    io.u16(4, &mut p.event_id);
    for (i, word) in p.data.iter_mut().enumerate() {
        io.u32(8 + 4 * i, word);
    }
}

/// Writes the 4.0 packet header: 16-bit Packet Size, 16-bit Packet ID.
pub(crate) fn write_header(bytes: &mut [u8], id: u16, size: usize, order: ByteOrder) {
    let mut w = Writer::new(bytes, order);
    let mut size16 = u16::try_from(size).unwrap_or(0);
    let mut id16 = id;
    w.u16(0, &mut size16);
    w.u16(2, &mut id16);
}

codec_table! {
    header = write_header;
    IgControl => 0x00, 24, ig_control;
    EntityPosition => 0x01, 48, entity_position;
    ConformalClampedEntity => 0x02, 32, conformal_clamped;
    ComponentControl => 0x03, 40, component_control;
    ShortComponentControl => 0x04, 24, short_component_control;
    ArticulatedPart => 0x05, 32, articulated_part;
    ShortArticulatedPart => 0x06, 24, short_articulated_part;
    RateControl => 0x07, 32, velocity_control;
    CelestialSphereControl => 0x08, 24, celestial;
    AtmosphereControl => 0x09, 32, atmosphere;
    EnvironmentalRegionControl => 0x0A, 48, environmental_region;
    WeatherControl => 0x0B, 72, weather;
    MaritimeSurfaceConditionsControl => 0x0C, 24, maritime_control;
    WaveControl => 0x0D, 32, wave_control;
    TerrestrialSurfaceConditionsControl => 0x0E, 16, terrestrial_control;
    ViewControl => 0x0F, 40, view_control;
    SensorControl => 0x10, 32, sensor_control;
    ViewDefinition => 0x14, 40, view_definition;
    CollisionSegmentDefinition => 0x15, 40, collision_segment;
    CollisionVolumeDefinition => 0x16, 48, collision_volume;
    HatHotRequest => 0x17, 40, hat_hot_request;
    LosSegmentRequest => 0x18, 72, los_segment;
    LosVectorRequest => 0x19, 64, los_vector;
    PositionRequest => 0x1A, 8, position_request;
    EnvironmentalConditionsRequest => 0x1B, 32, environmental_conditions_request;
    EntityControl4 => 0x25, 16, entity_control;
    AnimationControl => 0x26, 16, animation_control;
    StartOfFrame => 0xFFFF, 24, start_of_frame;
    HatHotResponse => 0x0FFF, 16, hat_hot_response;
    HatHotExtendedResponse => 0x0FFE, 40, hat_hot_extended_response;
    LosResponse => 0x0FFD, 24, los_response;
    LosExtendedResponse => 0x0FFC, 64, los_extended_response;
    SensorResponse => 0x0FFB, 24, sensor_response;
    SensorExtendedResponse => 0x0FFA, 56, sensor_extended_response;
    PositionResponse => 0x0FF9, 48, position_response;
    WeatherConditionsResponse => 0x0FF8, 32, weather_conditions_response;
    AerosolConcentrationResponse => 0x0FF7, 16, aerosol_response;
    MaritimeSurfaceConditionsResponse => 0x0FF6, 24, maritime_response;
    TerrestrialSurfaceConditionsResponse => 0x0FF5, 16, terrestrial_response;
    CollisionSegmentNotification => 0x0FF4, 24, collision_segment_notification;
    CollisionVolumeNotification => 0x0FF3, 16, collision_volume_notification;
    AnimationStopNotification => 0x0FF2, 8, animation_stop;
    EventNotification => 0x0FF1, 24, event_notification;
}

/// Header length of a 4.0 packet (size and ID).
pub(crate) const HEADER_BYTES: usize = 4;
/// Header length of the 4.0 Image Generator Message (size, ID, message ID,
/// reserved).
pub(crate) const IG_MESSAGE_HEADER_BYTES: usize = 8;
