//! CIGI 3.3 packet layouts (SISO-STD-013 ICD 3.3, section 4).
//!
//! Algorithm: one layout function per packet, visiting each field at the byte
//! offset and bit position of the ICD's packet diagrams (bit 0 is the least
//! significant bit). Every packet starts with an 8-bit Packet ID and an 8-bit
//! Packet Size in bytes (a multiple of 8). The offsets were checked against an
//! independent decoder, Wireshark's CIGI dissector (`tests/tshark.rs`).
//!
//! Limits: the IG Control / Start of Frame version fields and byte-swap magic
//! number are written by the message layer; Motion Tracker, Earth Reference
//! Model, Trajectory and the symbol packets are not decoded here (the message layer skips them with a
//! warning).

use crate::packets::*;
use crate::wire::{ByteOrder, FieldIo};

pub(crate) const IG_MESSAGE_ID: u16 = 117;
pub(crate) const USER_DEFINED_FIRST: u16 = 201;
pub(crate) const USER_DEFINED_LAST: u16 = 255;

pub(crate) fn ig_control(io: &mut impl FieldIo, p: &mut IgControl) {
    io.i8(3, &mut p.database_number);
    io.bits(4, 0, 2, &mut p.ig_mode);
    io.flag(4, 2, &mut p.timestamp_valid);
    io.flag(4, 3, &mut p.smoothing_enable);
    io.u32(8, &mut p.host_frame_number);
    io.u32(12, &mut p.timestamp_10us);
    io.u32(16, &mut p.last_ig_frame_number);
}

pub(crate) fn start_of_frame(io: &mut impl FieldIo, p: &mut StartOfFrame) {
    io.i8(3, &mut p.database_number);
    io.u8(4, &mut p.ig_status);
    io.bits(5, 0, 2, &mut p.ig_mode);
    io.flag(5, 2, &mut p.timestamp_valid);
    io.flag(5, 3, &mut p.earth_reference_model_host_defined);
    io.u32(8, &mut p.ig_frame_number);
    io.u32(12, &mut p.timestamp_10us);
    io.u32(16, &mut p.last_host_frame_number);
}

fn entity_control(io: &mut impl FieldIo, p: &mut EntityControl) {
    io.u16(2, &mut p.entity_id);
    io.bits(4, 0, 2, &mut p.entity_state);
    io.flag(4, 2, &mut p.attach);
    io.flag(4, 3, &mut p.collision_detection_enable);
    io.flag(4, 4, &mut p.inherit_alpha);
    io.bits(4, 5, 2, &mut p.ground_ocean_clamp);
    io.flag(5, 0, &mut p.animation_direction_backward);
    io.flag(5, 1, &mut p.animation_loop_continuous);
    io.bits(5, 2, 2, &mut p.animation_state);
    io.flag(5, 4, &mut p.smoothing_enable);
    io.u8(6, &mut p.alpha);
    io.u16(8, &mut p.entity_type);
    io.u16(10, &mut p.parent_id);
    io.f32(12, &mut p.roll_deg);
    io.f32(16, &mut p.pitch_deg);
    io.f32(20, &mut p.yaw_deg);
    io.f64(24, &mut p.lat_deg_or_x_m);
    io.f64(32, &mut p.lon_deg_or_y_m);
    io.f64(40, &mut p.alt_m_or_z_m);
}

fn conformal_clamped(io: &mut impl FieldIo, p: &mut ConformalClampedEntity) {
    io.u16(2, &mut p.entity_id);
    io.f32(4, &mut p.yaw_deg);
    io.f64(8, &mut p.latitude_deg);
    io.f64(16, &mut p.longitude_deg);
}

fn component_control(io: &mut impl FieldIo, p: &mut ComponentControl) {
    io.u16(2, &mut p.component_id);
    io.u16(4, &mut p.instance_id);
    io.bits(6, 0, 6, &mut p.component_class);
    io.u8(7, &mut p.component_state);
    for (i, word) in p.data.iter_mut().enumerate() {
        io.u32(8 + 4 * i, word);
    }
}

fn short_component_control(io: &mut impl FieldIo, p: &mut ShortComponentControl) {
    io.u16(2, &mut p.component_id);
    io.u16(4, &mut p.instance_id);
    io.bits(6, 0, 6, &mut p.component_class);
    io.u8(7, &mut p.component_state);
    for (i, word) in p.data.iter_mut().enumerate() {
        io.u32(8 + 4 * i, word);
    }
}

fn articulated_part(io: &mut impl FieldIo, p: &mut ArticulatedPart) {
    io.u16(2, &mut p.entity_id);
    io.u8(4, &mut p.part_id);
    io.flag(5, 0, &mut p.part_enable);
    io.flag(5, 1, &mut p.x_offset_enable);
    io.flag(5, 2, &mut p.y_offset_enable);
    io.flag(5, 3, &mut p.z_offset_enable);
    io.flag(5, 4, &mut p.roll_enable);
    io.flag(5, 5, &mut p.pitch_enable);
    io.flag(5, 6, &mut p.yaw_enable);
    io.f32(8, &mut p.x_offset_m);
    io.f32(12, &mut p.y_offset_m);
    io.f32(16, &mut p.z_offset_m);
    io.f32(20, &mut p.roll_deg);
    io.f32(24, &mut p.pitch_deg);
    io.f32(28, &mut p.yaw_deg);
}

fn short_articulated_part(io: &mut impl FieldIo, p: &mut ShortArticulatedPart) {
    io.u16(2, &mut p.entity_id);
    io.u8(4, &mut p.part_id_1);
    io.u8(5, &mut p.part_id_2);
    io.bits(6, 0, 3, &mut p.dof_select_1);
    io.bits(6, 3, 3, &mut p.dof_select_2);
    io.flag(6, 6, &mut p.part_enable_1);
    io.flag(6, 7, &mut p.part_enable_2);
    io.f32(8, &mut p.dof_1);
    io.f32(12, &mut p.dof_2);
}

fn rate_control(io: &mut impl FieldIo, p: &mut RateControl) {
    io.u16(2, &mut p.entity_id);
    io.u8(4, &mut p.part_id);
    io.flag(5, 0, &mut p.apply_to_part);
    io.flag(5, 1, &mut p.coordinate_system_local);
    io.f32(8, &mut p.x_rate_mps);
    io.f32(12, &mut p.y_rate_mps);
    io.f32(16, &mut p.z_rate_mps);
    io.f32(20, &mut p.roll_rate_dps);
    io.f32(24, &mut p.pitch_rate_dps);
    io.f32(28, &mut p.yaw_rate_dps);
}

fn celestial(io: &mut impl FieldIo, p: &mut CelestialSphereControl) {
    io.u8(2, &mut p.hour);
    io.u8(3, &mut p.minute);
    io.flag(4, 0, &mut p.ephemeris_enable);
    io.flag(4, 1, &mut p.sun_enable);
    io.flag(4, 2, &mut p.moon_enable);
    io.flag(4, 3, &mut p.star_field_enable);
    io.flag(4, 4, &mut p.date_time_valid);
    io.u32(8, &mut p.date_mmddyyyy);
    io.f32(12, &mut p.star_field_intensity_pct);
}

fn atmosphere(io: &mut impl FieldIo, p: &mut AtmosphereControl) {
    io.flag(2, 0, &mut p.atmospheric_model_enable);
    io.u8(3, &mut p.humidity_pct);
    io.f32(4, &mut p.air_temperature_c);
    io.f32(8, &mut p.visibility_range_m);
    io.f32(12, &mut p.horizontal_wind_speed_mps);
    io.f32(16, &mut p.vertical_wind_speed_mps);
    io.f32(20, &mut p.wind_direction_deg);
    io.f32(24, &mut p.barometric_pressure_mbar);
}

fn environmental_region(io: &mut impl FieldIo, p: &mut EnvironmentalRegionControl) {
    io.u16(2, &mut p.region_id);
    io.bits(4, 0, 2, &mut p.region_state);
    io.flag(4, 2, &mut p.merge_weather);
    io.flag(4, 3, &mut p.merge_aerosol);
    io.flag(4, 4, &mut p.merge_maritime);
    io.flag(4, 5, &mut p.merge_terrestrial);
    io.f64(8, &mut p.latitude_deg);
    io.f64(16, &mut p.longitude_deg);
    io.f32(24, &mut p.size_x_m);
    io.f32(28, &mut p.size_y_m);
    io.f32(32, &mut p.corner_radius_m);
    io.f32(36, &mut p.rotation_deg);
    io.f32(40, &mut p.transition_perimeter_m);
}

fn weather(io: &mut impl FieldIo, p: &mut WeatherControl) {
    io.u16(2, &mut p.entity_or_region_id);
    io.u8(4, &mut p.layer_id);
    io.u8(5, &mut p.humidity_pct);
    io.flag(6, 0, &mut p.weather_enable);
    io.flag(6, 1, &mut p.scud_enable);
    io.flag(6, 2, &mut p.random_winds_enable);
    io.flag(6, 3, &mut p.random_lightning_enable);
    io.bits(6, 4, 4, &mut p.cloud_type);
    io.bits(7, 0, 2, &mut p.scope);
    io.bits(7, 2, 3, &mut p.severity);
    io.f32(8, &mut p.air_temperature_c);
    io.f32(12, &mut p.visibility_range_m);
    io.f32(16, &mut p.scud_frequency_pct);
    io.f32(20, &mut p.coverage_pct);
    io.f32(24, &mut p.base_elevation_m);
    io.f32(28, &mut p.thickness_m);
    io.f32(32, &mut p.transition_band_m);
    io.f32(36, &mut p.horizontal_wind_speed_mps);
    io.f32(40, &mut p.vertical_wind_speed_mps);
    io.f32(44, &mut p.wind_direction_deg);
    io.f32(48, &mut p.barometric_pressure_mbar);
    io.f32(52, &mut p.aerosol_concentration_gpm3);
}

fn maritime_control(io: &mut impl FieldIo, p: &mut MaritimeSurfaceConditionsControl) {
    io.u16(2, &mut p.entity_or_region_id);
    io.flag(4, 0, &mut p.surface_conditions_enable);
    io.flag(4, 1, &mut p.whitecap_enable);
    io.bits(4, 2, 2, &mut p.scope);
    io.f32(8, &mut p.sea_surface_height_m);
    io.f32(12, &mut p.surface_water_temperature_c);
    io.f32(16, &mut p.surface_clarity_pct);
}

fn wave_control(io: &mut impl FieldIo, p: &mut WaveControl) {
    io.u16(2, &mut p.entity_or_region_id);
    io.u8(4, &mut p.wave_id);
    io.flag(5, 0, &mut p.wave_enable);
    io.bits(5, 1, 2, &mut p.scope);
    io.bits(5, 3, 2, &mut p.breaker_type);
    io.f32(8, &mut p.height_m);
    io.f32(12, &mut p.wavelength_m);
    io.f32(16, &mut p.period_s);
    io.f32(20, &mut p.direction_deg);
    io.f32(24, &mut p.phase_offset_deg);
    io.f32(28, &mut p.leading_deg);
}

fn terrestrial_control(io: &mut impl FieldIo, p: &mut TerrestrialSurfaceConditionsControl) {
    io.u16(2, &mut p.entity_or_region_id);
    io.u16(4, &mut p.surface_condition_id);
    io.flag(6, 0, &mut p.surface_condition_enable);
    io.bits(6, 1, 2, &mut p.scope);
    io.bits(6, 3, 5, &mut p.severity);
    io.u8(7, &mut p.coverage_pct);
}

fn view_control(io: &mut impl FieldIo, p: &mut ViewControl) {
    io.u16(2, &mut p.view_id);
    io.u8(4, &mut p.group_id);
    io.flag(5, 0, &mut p.x_offset_enable);
    io.flag(5, 1, &mut p.y_offset_enable);
    io.flag(5, 2, &mut p.z_offset_enable);
    io.flag(5, 3, &mut p.roll_enable);
    io.flag(5, 4, &mut p.pitch_enable);
    io.flag(5, 5, &mut p.yaw_enable);
    io.u16(6, &mut p.entity_id);
    io.f32(8, &mut p.x_offset_m);
    io.f32(12, &mut p.y_offset_m);
    io.f32(16, &mut p.z_offset_m);
    io.f32(20, &mut p.roll_deg);
    io.f32(24, &mut p.pitch_deg);
    io.f32(28, &mut p.yaw_deg);
}

fn sensor_control(io: &mut impl FieldIo, p: &mut SensorControl) {
    io.u16(2, &mut p.view_id);
    io.u8(4, &mut p.sensor_id);
    io.flag(5, 0, &mut p.sensor_on);
    io.flag(5, 1, &mut p.polarity_black_hot);
    io.flag(5, 2, &mut p.line_dropout_enable);
    io.flag(5, 3, &mut p.automatic_gain);
    io.flag(5, 4, &mut p.track_black);
    io.bits(5, 5, 3, &mut p.track_mode);
    io.flag(6, 0, &mut p.response_type_extended);
    io.f32(8, &mut p.gain);
    io.f32(12, &mut p.level);
    io.f32(16, &mut p.ac_coupling_us);
    io.f32(20, &mut p.noise);
}

fn view_definition(io: &mut impl FieldIo, p: &mut ViewDefinition) {
    io.u16(2, &mut p.view_id);
    io.u8(4, &mut p.group_id);
    io.flag(5, 0, &mut p.near_enable);
    io.flag(5, 1, &mut p.far_enable);
    io.flag(5, 2, &mut p.left_enable);
    io.flag(5, 3, &mut p.right_enable);
    io.flag(5, 4, &mut p.top_enable);
    io.flag(5, 5, &mut p.bottom_enable);
    io.bits(5, 6, 2, &mut p.mirror_mode);
    io.bits(6, 0, 3, &mut p.pixel_replication);
    io.flag(6, 3, &mut p.projection_orthographic);
    io.flag(6, 4, &mut p.reorder);
    io.bits(6, 5, 3, &mut p.view_type);
    io.f32(8, &mut p.near_m);
    io.f32(12, &mut p.far_m);
    io.f32(16, &mut p.left_deg);
    io.f32(20, &mut p.right_deg);
    io.f32(24, &mut p.top_deg);
    io.f32(28, &mut p.bottom_deg);
}

fn collision_segment(io: &mut impl FieldIo, p: &mut CollisionSegmentDefinition) {
    io.u16(2, &mut p.entity_id);
    io.u8(4, &mut p.segment_id);
    io.flag(5, 0, &mut p.segment_enable);
    io.f32(8, &mut p.x1_m);
    io.f32(12, &mut p.y1_m);
    io.f32(16, &mut p.z1_m);
    io.f32(20, &mut p.x2_m);
    io.f32(24, &mut p.y2_m);
    io.f32(28, &mut p.z2_m);
    io.u32(32, &mut p.material_mask);
}

fn collision_volume(io: &mut impl FieldIo, p: &mut CollisionVolumeDefinition) {
    io.u16(2, &mut p.entity_id);
    io.u8(4, &mut p.volume_id);
    io.flag(5, 0, &mut p.volume_enable);
    io.flag(5, 1, &mut p.volume_type_cuboid);
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
    io.u16(2, &mut p.hat_hot_id);
    io.bits(4, 0, 2, &mut p.request_type);
    io.flag(4, 2, &mut p.coordinate_system_entity);
    io.u8(5, &mut p.update_period);
    io.u16(6, &mut p.entity_id);
    io.f64(8, &mut p.lat_deg_or_x_m);
    io.f64(16, &mut p.lon_deg_or_y_m);
    io.f64(24, &mut p.alt_m_or_z_m);
}

fn los_segment(io: &mut impl FieldIo, p: &mut LosSegmentRequest) {
    io.u16(2, &mut p.los_id);
    io.flag(4, 0, &mut p.request_type_extended);
    io.flag(4, 1, &mut p.source_coordinate_entity);
    io.flag(4, 2, &mut p.destination_coordinate_entity);
    io.flag(4, 3, &mut p.response_coordinate_entity);
    io.flag(4, 4, &mut p.destination_entity_id_valid);
    io.u8(5, &mut p.alpha_threshold);
    io.u16(6, &mut p.entity_id);
    io.f64(8, &mut p.source_lat_deg_or_x_m);
    io.f64(16, &mut p.source_lon_deg_or_y_m);
    io.f64(24, &mut p.source_alt_m_or_z_m);
    io.f64(32, &mut p.destination_lat_deg_or_x_m);
    io.f64(40, &mut p.destination_lon_deg_or_y_m);
    io.f64(48, &mut p.destination_alt_m_or_z_m);
    io.u32(56, &mut p.material_mask);
    io.u8(60, &mut p.update_period);
    io.u16(62, &mut p.destination_entity_id);
}

fn los_vector(io: &mut impl FieldIo, p: &mut LosVectorRequest) {
    io.u16(2, &mut p.los_id);
    io.flag(4, 0, &mut p.request_type_extended);
    io.flag(4, 1, &mut p.source_coordinate_entity);
    io.flag(4, 2, &mut p.response_coordinate_entity);
    io.u8(5, &mut p.alpha_threshold);
    io.u16(6, &mut p.entity_id);
    io.f32(8, &mut p.azimuth_deg);
    io.f32(12, &mut p.elevation_deg);
    io.f32(16, &mut p.min_range_m);
    io.f32(20, &mut p.max_range_m);
    io.f64(24, &mut p.source_lat_deg_or_x_m);
    io.f64(32, &mut p.source_lon_deg_or_y_m);
    io.f64(40, &mut p.source_alt_m_or_z_m);
    io.u32(48, &mut p.material_mask);
    io.u8(52, &mut p.update_period);
}

fn position_request(io: &mut impl FieldIo, p: &mut PositionRequest) {
    io.u16(2, &mut p.object_id);
    io.u8(4, &mut p.part_id);
    io.flag(5, 0, &mut p.update_mode_continuous);
    io.bits(5, 1, 3, &mut p.object_class);
    io.bits(5, 4, 2, &mut p.coordinate_system);
}

fn environmental_conditions_request(io: &mut impl FieldIo, p: &mut EnvironmentalConditionsRequest) {
    io.bits(2, 0, 4, &mut p.request_type);
    io.u8(3, &mut p.request_id);
    io.f64(8, &mut p.latitude_deg);
    io.f64(16, &mut p.longitude_deg);
    io.f64(24, &mut p.altitude_m);
}

fn hat_hot_response(io: &mut impl FieldIo, p: &mut HatHotResponse) {
    io.u16(2, &mut p.hat_hot_id);
    io.flag(4, 0, &mut p.valid);
    io.flag(4, 1, &mut p.response_type_hot);
    io.bits(4, 4, 4, &mut p.host_frame_lsn);
    io.f64(8, &mut p.height_m);
}

fn hat_hot_extended_response(io: &mut impl FieldIo, p: &mut HatHotExtendedResponse) {
    io.u16(2, &mut p.hat_hot_id);
    io.flag(4, 0, &mut p.valid);
    io.bits(4, 4, 4, &mut p.host_frame_lsn);
    io.f64(8, &mut p.hat_m);
    io.f64(16, &mut p.hot_m);
    io.u32(24, &mut p.material_code);
    io.f32(28, &mut p.normal_azimuth_deg);
    io.f32(32, &mut p.normal_elevation_deg);
}

fn los_response(io: &mut impl FieldIo, p: &mut LosResponse) {
    io.u16(2, &mut p.los_id);
    io.flag(4, 0, &mut p.valid);
    io.flag(4, 1, &mut p.entity_id_valid);
    io.flag(4, 2, &mut p.visible);
    io.bits(4, 4, 4, &mut p.host_frame_lsn);
    io.u8(5, &mut p.response_count);
    io.u16(6, &mut p.entity_id);
    io.f64(8, &mut p.range_m);
}

fn los_extended_response(io: &mut impl FieldIo, p: &mut LosExtendedResponse) {
    io.u16(2, &mut p.los_id);
    io.flag(4, 0, &mut p.valid);
    io.flag(4, 1, &mut p.entity_id_valid);
    io.flag(4, 2, &mut p.range_valid);
    io.flag(4, 3, &mut p.visible);
    io.bits(4, 4, 4, &mut p.host_frame_lsn);
    io.u8(5, &mut p.response_count);
    io.u16(6, &mut p.entity_id);
    io.f64(8, &mut p.range_m);
    io.f64(16, &mut p.lat_deg_or_x_m);
    io.f64(24, &mut p.lon_deg_or_y_m);
    io.f64(32, &mut p.alt_m_or_z_m);
    io.u8(40, &mut p.red);
    io.u8(41, &mut p.green);
    io.u8(42, &mut p.blue);
    io.u8(43, &mut p.alpha);
    io.u32(44, &mut p.material_code);
    io.f32(48, &mut p.normal_azimuth_deg);
    io.f32(52, &mut p.normal_elevation_deg);
}

fn sensor_response(io: &mut impl FieldIo, p: &mut SensorResponse) {
    io.u16(2, &mut p.view_id);
    io.u8(4, &mut p.sensor_id);
    io.bits(5, 0, 2, &mut p.sensor_status);
    io.u16(8, &mut p.gate_x_size_px);
    io.u16(10, &mut p.gate_y_size_px);
    io.f32(12, &mut p.gate_x_position_deg);
    io.f32(16, &mut p.gate_y_position_deg);
    io.u32(20, &mut p.frame_counter);
}

fn sensor_extended_response(io: &mut impl FieldIo, p: &mut SensorExtendedResponse) {
    io.u16(2, &mut p.view_id);
    io.u8(4, &mut p.sensor_id);
    io.bits(5, 0, 2, &mut p.sensor_status);
    io.flag(5, 2, &mut p.entity_id_valid);
    io.u16(6, &mut p.entity_id);
    io.u16(8, &mut p.gate_x_size_px);
    io.u16(10, &mut p.gate_y_size_px);
    io.f32(12, &mut p.gate_x_position_deg);
    io.f32(16, &mut p.gate_y_position_deg);
    io.u32(20, &mut p.frame_counter);
    io.f64(24, &mut p.track_latitude_deg);
    io.f64(32, &mut p.track_longitude_deg);
    io.f64(40, &mut p.track_altitude_m);
}

fn position_response(io: &mut impl FieldIo, p: &mut PositionResponse) {
    io.u16(2, &mut p.object_id);
    io.u8(4, &mut p.part_id);
    io.bits(5, 0, 3, &mut p.object_class);
    io.bits(5, 3, 2, &mut p.coordinate_system);
    io.f64(8, &mut p.lat_deg_or_x_m);
    io.f64(16, &mut p.lon_deg_or_y_m);
    io.f64(24, &mut p.alt_m_or_z_m);
    io.f32(32, &mut p.roll_deg);
    io.f32(36, &mut p.pitch_deg);
    io.f32(40, &mut p.yaw_deg);
}

fn weather_conditions_response(io: &mut impl FieldIo, p: &mut WeatherConditionsResponse) {
    io.u8(2, &mut p.request_id);
    io.u8(3, &mut p.humidity_pct);
    io.f32(4, &mut p.air_temperature_c);
    io.f32(8, &mut p.visibility_range_m);
    io.f32(12, &mut p.horizontal_wind_speed_mps);
    io.f32(16, &mut p.vertical_wind_speed_mps);
    io.f32(20, &mut p.wind_direction_deg);
    io.f32(24, &mut p.barometric_pressure_mbar);
}

fn aerosol_response(io: &mut impl FieldIo, p: &mut AerosolConcentrationResponse) {
    io.u8(2, &mut p.request_id);
    io.u8(3, &mut p.layer_id);
    io.f32(4, &mut p.aerosol_concentration_gpm3);
}

fn maritime_response(io: &mut impl FieldIo, p: &mut MaritimeSurfaceConditionsResponse) {
    io.u8(2, &mut p.request_id);
    io.f32(4, &mut p.sea_surface_height_m);
    io.f32(8, &mut p.surface_water_temperature_c);
    io.f32(12, &mut p.surface_clarity_pct);
}

fn terrestrial_response(io: &mut impl FieldIo, p: &mut TerrestrialSurfaceConditionsResponse) {
    io.u8(2, &mut p.request_id);
    io.u32(4, &mut p.surface_condition_id);
}

fn collision_segment_notification(io: &mut impl FieldIo, p: &mut CollisionSegmentNotification) {
    io.u16(2, &mut p.entity_id);
    io.u8(4, &mut p.segment_id);
    io.flag(5, 0, &mut p.collision_with_entity);
    io.u16(6, &mut p.contacted_entity_id);
    io.u32(8, &mut p.material_code);
    io.f32(12, &mut p.intersection_distance_m);
}

fn collision_volume_notification(io: &mut impl FieldIo, p: &mut CollisionVolumeNotification) {
    io.u16(2, &mut p.entity_id);
    io.u8(4, &mut p.volume_id);
    io.flag(5, 0, &mut p.collision_with_entity);
    io.u16(6, &mut p.contacted_entity_id);
    io.u8(8, &mut p.contacted_volume_id);
}

fn animation_stop(io: &mut impl FieldIo, p: &mut AnimationStopNotification) {
    io.u16(2, &mut p.entity_id);
}

fn event_notification(io: &mut impl FieldIo, p: &mut EventNotification) {
    io.u16(2, &mut p.event_id);
    for (i, word) in p.data.iter_mut().enumerate() {
        io.u32(4 + 4 * i, word);
    }
}

/// Writes the 3.x packet header: 8-bit Packet ID, 8-bit Packet Size.
pub(crate) fn write_header(bytes: &mut [u8], id: u16, size: usize, _order: ByteOrder) {
    if let Some(b) = bytes.get_mut(0) {
        *b = u8::try_from(id).unwrap_or(0);
    }
    if let Some(b) = bytes.get_mut(1) {
        *b = u8::try_from(size).unwrap_or(0);
    }
}

codec_table! {
    header = write_header;
    IgControl => 1, 24, ig_control;
    EntityControl => 2, 48, entity_control;
    ConformalClampedEntity => 3, 24, conformal_clamped;
    ComponentControl => 4, 32, component_control;
    ShortComponentControl => 5, 16, short_component_control;
    ArticulatedPart => 6, 32, articulated_part;
    ShortArticulatedPart => 7, 16, short_articulated_part;
    RateControl => 8, 32, rate_control;
    CelestialSphereControl => 9, 16, celestial;
    AtmosphereControl => 10, 32, atmosphere;
    EnvironmentalRegionControl => 11, 48, environmental_region;
    WeatherControl => 12, 56, weather;
    MaritimeSurfaceConditionsControl => 13, 24, maritime_control;
    WaveControl => 14, 32, wave_control;
    TerrestrialSurfaceConditionsControl => 15, 8, terrestrial_control;
    ViewControl => 16, 32, view_control;
    SensorControl => 17, 24, sensor_control;
    ViewDefinition => 21, 32, view_definition;
    CollisionSegmentDefinition => 22, 40, collision_segment;
    CollisionVolumeDefinition => 23, 48, collision_volume;
    HatHotRequest => 24, 32, hat_hot_request;
    LosSegmentRequest => 25, 64, los_segment;
    LosVectorRequest => 26, 56, los_vector;
    PositionRequest => 27, 8, position_request;
    EnvironmentalConditionsRequest => 28, 32, environmental_conditions_request;
    StartOfFrame => 101, 24, start_of_frame;
    HatHotResponse => 102, 16, hat_hot_response;
    HatHotExtendedResponse => 103, 40, hat_hot_extended_response;
    LosResponse => 104, 16, los_response;
    LosExtendedResponse => 105, 56, los_extended_response;
    SensorResponse => 106, 24, sensor_response;
    SensorExtendedResponse => 107, 48, sensor_extended_response;
    PositionResponse => 108, 48, position_response;
    WeatherConditionsResponse => 109, 32, weather_conditions_response;
    AerosolConcentrationResponse => 110, 8, aerosol_response;
    MaritimeSurfaceConditionsResponse => 111, 16, maritime_response;
    TerrestrialSurfaceConditionsResponse => 112, 8, terrestrial_response;
    CollisionSegmentNotification => 113, 16, collision_segment_notification;
    CollisionVolumeNotification => 114, 16, collision_volume_notification;
    AnimationStopNotification => 115, 8, animation_stop;
    EventNotification => 116, 16, event_notification;
}

/// Header length of a 3.x packet (ID and size bytes).
pub(crate) const HEADER_BYTES: usize = 2;
/// Header length of the 3.x Image Generator Message (ID, size, message ID).
pub(crate) const IG_MESSAGE_HEADER_BYTES: usize = 4;
