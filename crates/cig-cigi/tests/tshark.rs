//! Comparison against an independent decoder: Wireshark's CIGI dissector
//! (`tshark`, Debian package `tshark`).
//!
//! Every CIGI 3.3 packet type this crate encodes is written, with
//! pseudo-random field values, into its own UDP datagram (after IG Control or
//! Start of Frame) in both byte orders; the datagrams go into a classic pcap
//! file that `tshark -T json` dissects; each field Wireshark reports must
//! equal what was encoded. Skips (with a message) when tshark is absent.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use cig_cigi::sample::{Sample, SampleSource};
use cig_cigi::*;

const PORT: u16 = 8004;

/// Classic pcap (libpcap 2.4, Ethernet link type) with one UDP/IPv4 frame per
/// payload.
fn write_pcap(path: &Path, payloads: &[Vec<u8>]) {
    let mut file = Vec::new();
    file.extend(0xa1b2_c3d4u32.to_le_bytes());
    file.extend(2u16.to_le_bytes());
    file.extend(4u16.to_le_bytes());
    file.extend(0i32.to_le_bytes());
    file.extend(0u32.to_le_bytes());
    file.extend(65_535u32.to_le_bytes());
    file.extend(1u32.to_le_bytes());
    for (i, payload) in payloads.iter().enumerate() {
        let udp_len = u16::try_from(8 + payload.len()).expect("datagram fits UDP");
        let ip_len = 20 + udp_len;
        let mut frame = vec![0u8; 12];
        frame.extend([0x08, 0x00]);
        frame.extend([0x45, 0]);
        frame.extend(ip_len.to_be_bytes());
        frame.extend([0, 0, 0, 0, 64, 17, 0, 0]);
        frame.extend([127, 0, 0, 1, 127, 0, 0, 1]);
        frame.extend(PORT.to_be_bytes());
        frame.extend(PORT.to_be_bytes());
        frame.extend(udp_len.to_be_bytes());
        frame.extend([0, 0]);
        frame.extend(payload);
        let len = u32::try_from(frame.len()).expect("frame length fits u32");
        file.extend(
            u32::try_from(i)
                .expect("frame index fits u32")
                .to_le_bytes(),
        );
        file.extend(0u32.to_le_bytes());
        file.extend(len.to_le_bytes());
        file.extend(len.to_le_bytes());
        file.extend(frame);
    }
    std::fs::write(path, file).expect("pcap written to the temp dir");
}

#[derive(Debug, Clone)]
enum Exp {
    U(u64),
    B(bool),
    F32(f32),
    F64(f64),
    Word(u32),
    Text(String),
}

use Exp::*;

fn matches(expected: &Exp, got: &str, order: ByteOrder) -> bool {
    let close = |want: f64, rel: f64| {
        got.parse::<f64>().is_ok_and(|g| {
            (g - want).abs() <= rel * want.abs().max(g.abs()) || (g == 0.0 && want.abs() < 1e-300)
        })
    };
    match expected {
        U(v) => got == v.to_string(),
        B(v) => got == if *v { "1" } else { "0" },
        // Wireshark prints floats with 6 and doubles with 15 significant digits.
        F32(v) => close(f64::from(*v), 1e-5),
        F64(v) => close(*v, 2e-14),
        Word(w) => {
            let bytes = match order {
                ByteOrder::BigEndian => w.to_be_bytes(),
                ByteOrder::LittleEndian => w.to_le_bytes(),
            };
            let mut hex = String::new();
            for (i, b) in bytes.iter().enumerate() {
                if i > 0 {
                    hex.push(':');
                }
                write!(hex, "{b:02x}").expect("writing to a String");
            }
            got == hex
        }
        Text(t) => got == t,
    }
}

macro_rules! fields {
    ($prefix:literal; $( $name:literal => $exp:expr ),* $(,)?) => {
        vec![ $( (format!("cigi.{}.{}", $prefix, $name), $exp) ),* ]
    };
}

fn u<T: Into<u64>>(v: T) -> Exp {
    U(v.into())
}

/// Wireshark field names and expected values of one packet.
fn expectations(packet: &Packet) -> Vec<(String, Exp)> {
    match packet {
        Packet::IgControl(p) => fields!("ig_control";
            "db_number" => Text(p.database_number.to_string()), "ig_mode" => u(p.ig_mode),
            "timestamp_valid" => B(p.timestamp_valid), "extrapolation_enable" => B(p.smoothing_enable),
            "minor_version" => U(3), "host_frame_number" => u(p.host_frame_number),
            "timestamp" => u(p.timestamp_10us), "last_ig_frame_number" => u(p.last_ig_frame_number)),
        Packet::StartOfFrame(p) => fields!("sof";
            "db_number" => Text(p.database_number.to_string()), "ig_status" => u(p.ig_status),
            "ig_mode" => u(p.ig_mode), "timestamp_valid" => B(p.timestamp_valid),
            "earth_reference_model" => B(p.earth_reference_model_host_defined), "minor_version" => U(3),
            "ig_frame_number" => u(p.ig_frame_number), "timestamp" => u(p.timestamp_10us),
            "last_host_frame_number" => u(p.last_host_frame_number)),
        Packet::EntityControl(p) => fields!("entity_control";
            "entity_id" => u(p.entity_id), "entity_state" => u(p.entity_state), "attach_state" => B(p.attach),
            "coll_det_request" => B(p.collision_detection_enable), "inherit_alpha" => B(p.inherit_alpha),
            "ground_ocean_clamp" => u(p.ground_ocean_clamp), "animation_dir" => B(p.animation_direction_backward),
            "animation_loop_mode" => B(p.animation_loop_continuous), "animation_state" => u(p.animation_state),
            "extrapolation_enable" => B(p.smoothing_enable), "alpha" => u(p.alpha), "entity_type" => u(p.entity_type),
            "parent_id" => u(p.parent_id), "roll" => F32(p.roll_deg), "pitch" => F32(p.pitch_deg), "yaw" => F32(p.yaw_deg),
            "lat_xoff" => F64(p.lat_deg_or_x_m), "lon_yoff" => F64(p.lon_deg_or_y_m), "alt_zoff" => F64(p.alt_m_or_z_m)),
        Packet::ConformalClampedEntity(p) => fields!("conformal_clamped_entity_control";
            "entity_id" => u(p.entity_id), "yaw" => F32(p.yaw_deg), "lat" => F64(p.latitude_deg), "lon" => F64(p.longitude_deg)),
        Packet::ComponentControl(p) => fields!("component_control";
            "component_id" => u(p.component_id), "instance_id" => u(p.instance_id),
            "component_class" => u(p.component_class), "component_state" => u(p.component_state),
            "data_1" => Word(p.data[0]), "data_2" => Word(p.data[1]), "data_3" => Word(p.data[2]),
            "data_4" => Word(p.data[3]), "data_5" => Word(p.data[4]), "data_6" => Word(p.data[5])),
        Packet::ShortComponentControl(p) => fields!("short_component_control";
            "component_id" => u(p.component_id), "instance_id" => u(p.instance_id),
            "component_class" => u(p.component_class), "component_state" => u(p.component_state),
            "data_1" => Word(p.data[0]), "data_2" => Word(p.data[1])),
        Packet::ArticulatedPart(p) => fields!("art_part_control";
            "entity_id" => u(p.entity_id), "part_id" => u(p.part_id), "part_enable" => B(p.part_enable),
            "xoff_enable" => B(p.x_offset_enable), "yoff_enable" => B(p.y_offset_enable), "zoff_enable" => B(p.z_offset_enable),
            "roll_enable" => B(p.roll_enable), "pitch_enable" => B(p.pitch_enable), "yaw_enable" => B(p.yaw_enable),
            "xoff" => F32(p.x_offset_m), "yoff" => F32(p.y_offset_m), "zoff" => F32(p.z_offset_m),
            "roll" => F32(p.roll_deg), "pitch" => F32(p.pitch_deg), "yaw" => F32(p.yaw_deg)),
        Packet::ShortArticulatedPart(p) => fields!("short_art_part_control";
            "entity_id" => u(p.entity_id), "part_id_1" => u(p.part_id_1), "part_id_2" => u(p.part_id_2),
            "dof_select_1" => u(p.dof_select_1), "dof_select_2" => u(p.dof_select_2),
            "part_enable_1" => B(p.part_enable_1), "part_enable_2" => B(p.part_enable_2),
            "dof_1" => F32(p.dof_1), "dof_2" => F32(p.dof_2)),
        Packet::RateControl(p) => fields!("rate_control";
            "entity_id" => u(p.entity_id), "part_id" => u(p.part_id), "apply_to_part" => B(p.apply_to_part),
            "coordinate_system" => B(p.coordinate_system_local), "x_rate" => F32(p.x_rate_mps), "y_rate" => F32(p.y_rate_mps),
            "z_rate" => F32(p.z_rate_mps), "roll_rate" => F32(p.roll_rate_dps), "pitch_rate" => F32(p.pitch_rate_dps),
            "yaw_rate" => F32(p.yaw_rate_dps)),
        Packet::CelestialSphereControl(p) => fields!("celestial_sphere_control";
            "hour" => u(p.hour), "minute" => u(p.minute), "ephemeris_enable" => B(p.ephemeris_enable),
            "sun_enable" => B(p.sun_enable), "moon_enable" => B(p.moon_enable), "star_enable" => B(p.star_field_enable),
            "date_time_valid" => B(p.date_time_valid), "date" => u(p.date_mmddyyyy),
            "star_intensity" => F32(p.star_field_intensity_pct)),
        Packet::AtmosphereControl(p) => fields!("atmosphere_control";
            "atmospheric_model_enable" => B(p.atmospheric_model_enable), "humidity" => u(p.humidity_pct),
            "air_temp" => F32(p.air_temperature_c), "visibility_range" => F32(p.visibility_range_m),
            "horiz_wind" => F32(p.horizontal_wind_speed_mps), "vert_wind" => F32(p.vertical_wind_speed_mps),
            "wind_direction" => F32(p.wind_direction_deg), "barometric_pressure" => F32(p.barometric_pressure_mbar)),
        Packet::EnvironmentalRegionControl(p) => fields!("env_region_control";
            "region_id" => u(p.region_id), "region_state" => u(p.region_state), "merge_weather" => B(p.merge_weather),
            "merge_aerosol" => B(p.merge_aerosol), "merge_maritime" => B(p.merge_maritime),
            "merge_terrestrial" => B(p.merge_terrestrial), "lat" => F64(p.latitude_deg), "lon" => F64(p.longitude_deg),
            "size_x" => F32(p.size_x_m), "size_y" => F32(p.size_y_m), "corner_radius" => F32(p.corner_radius_m),
            "rotation" => F32(p.rotation_deg), "transition_perimeter" => F32(p.transition_perimeter_m)),
        Packet::WeatherControl(p) => fields!("weather_control";
            "entity_region_id" => u(p.entity_or_region_id), "layer_id" => u(p.layer_id), "humidity" => u(p.humidity_pct),
            "weather_enable" => B(p.weather_enable), "scud_enable" => B(p.scud_enable),
            "random_winds_enable" => B(p.random_winds_enable), "random_lightning_enable" => B(p.random_lightning_enable),
            "cloud_type" => u(p.cloud_type), "scope" => u(p.scope), "severity" => u(p.severity),
            "air_temp" => F32(p.air_temperature_c), "visibility_range" => F32(p.visibility_range_m),
            "scud_frequency" => F32(p.scud_frequency_pct), "coverage" => F32(p.coverage_pct),
            "base_elevation" => F32(p.base_elevation_m), "thickness" => F32(p.thickness_m),
            "transition_band" => F32(p.transition_band_m), "horiz_wind" => F32(p.horizontal_wind_speed_mps),
            "vert_wind" => F32(p.vertical_wind_speed_mps), "wind_direction" => F32(p.wind_direction_deg),
            "barometric_pressure" => F32(p.barometric_pressure_mbar),
            "aerosol_concentration" => F32(p.aerosol_concentration_gpm3)),
        Packet::MaritimeSurfaceConditionsControl(p) => {
            fields!("maritime_surface_conditions_control";
            "entity_region_id" => u(p.entity_or_region_id),
            "surface_conditions_enable" => B(p.surface_conditions_enable),
            "whitecap_enable" => B(p.whitecap_enable), "scope" => u(p.scope),
            "sea_surface_height" => F32(p.sea_surface_height_m),
            "surface_water_temp" => F32(p.surface_water_temperature_c),
            "surface_clarity" => F32(p.surface_clarity_pct))
        }
        Packet::WaveControl(p) => fields!("wave_control";
            "entity_region_id" => u(p.entity_or_region_id), "wave_id" => u(p.wave_id),
            "wave_enable" => B(p.wave_enable), "scope" => u(p.scope), "breaker_type" => u(p.breaker_type),
            "height" => F32(p.height_m), "wavelength" => F32(p.wavelength_m), "period" => F32(p.period_s),
            "direction" => F32(p.direction_deg), "phase_offset" => F32(p.phase_offset_deg),
            "leading" => F32(p.leading_deg)),
        Packet::TerrestrialSurfaceConditionsControl(p) => {
            fields!("terrestrial_surface_conditions_control";
            "entity_region_id" => u(p.entity_or_region_id), "surface_condition_id" => u(p.surface_condition_id),
            "surface_condition_enable" => B(p.surface_condition_enable), "scope" => u(p.scope),
            "severity" => u(p.severity), "coverage" => u(p.coverage_pct))
        }
        Packet::ViewControl(p) => fields!("view_control";
            "view_id" => u(p.view_id), "group_id" => u(p.group_id), "xoff_enable" => B(p.x_offset_enable),
            "yoff_enable" => B(p.y_offset_enable), "zoff_enable" => B(p.z_offset_enable), "roll_enable" => B(p.roll_enable),
            "pitch_enable" => B(p.pitch_enable), "yaw_enable" => B(p.yaw_enable), "entity_id" => u(p.entity_id),
            "xoff" => F32(p.x_offset_m), "yoff" => F32(p.y_offset_m), "zoff" => F32(p.z_offset_m),
            "roll" => F32(p.roll_deg), "pitch" => F32(p.pitch_deg), "yaw" => F32(p.yaw_deg)),
        Packet::SensorControl(p) => fields!("sensor_control";
            "view_id" => u(p.view_id), "sensor_id" => u(p.sensor_id), "sensor_on_off" => B(p.sensor_on),
            "polarity" => B(p.polarity_black_hot), "line_dropout_enable" => B(p.line_dropout_enable),
            "auto_gain" => B(p.automatic_gain), "track_white_black" => B(p.track_black), "track_mode" => u(p.track_mode),
            "response_type" => B(p.response_type_extended), "gain" => F32(p.gain), "level" => F32(p.level),
            "ac_coupling" => F32(p.ac_coupling_us), "noise" => F32(p.noise)),
        Packet::ViewDefinition(p) => fields!("view_def";
            "view_id" => u(p.view_id), "group_id" => u(p.group_id), "near_enable" => B(p.near_enable),
            "far_enable" => B(p.far_enable), "left_enable" => B(p.left_enable), "right_enable" => B(p.right_enable),
            "top_enable" => B(p.top_enable), "bottom_enable" => B(p.bottom_enable), "mirror_mode" => u(p.mirror_mode),
            "pixel_replication" => u(p.pixel_replication), "projection_type" => B(p.projection_orthographic),
            "reorder" => B(p.reorder), "view_type" => u(p.view_type), "near" => F32(p.near_m), "far" => F32(p.far_m),
            "left" => F32(p.left_deg), "right" => F32(p.right_deg), "top" => F32(p.top_deg), "bottom" => F32(p.bottom_deg)),
        Packet::CollisionSegmentDefinition(p) => fields!("coll_det_seg_def";
            "entity_id" => u(p.entity_id), "segment_id" => u(p.segment_id), "segment_enable" => B(p.segment_enable),
            "x1" => F32(p.x1_m), "y1" => F32(p.y1_m), "z1" => F32(p.z1_m), "x2" => F32(p.x2_m), "y2" => F32(p.y2_m),
            "z2" => F32(p.z2_m), "material_mask" => u(p.material_mask)),
        Packet::CollisionVolumeDefinition(p) => fields!("coll_det_vol_def";
            "entity_id" => u(p.entity_id), "volume_id" => u(p.volume_id), "volume_enable" => B(p.volume_enable),
            "volume_type" => B(p.volume_type_cuboid), "x" => F32(p.x_m), "y" => F32(p.y_m), "z" => F32(p.z_m),
            "radius_height" => F32(p.height_or_radius_m), "width" => F32(p.width_m), "depth" => F32(p.depth_m),
            "roll" => F32(p.roll_deg), "pitch" => F32(p.pitch_deg), "yaw" => F32(p.yaw_deg)),
        Packet::HatHotRequest(p) => fields!("hat_hot_request";
            "hat_hot_id" => u(p.hat_hot_id), "type" => u(p.request_type),
            "coordinate_system" => B(p.coordinate_system_entity), "update_period" => u(p.update_period),
            "entity_id" => u(p.entity_id), "lat_xoff" => F64(p.lat_deg_or_x_m), "lon_yoff" => F64(p.lon_deg_or_y_m),
            "alt_zoff" => F64(p.alt_m_or_z_m)),
        Packet::LosSegmentRequest(p) => fields!("los_segment_request";
            "los_id" => u(p.los_id), "type" => B(p.request_type_extended),
            "source_coord" => B(p.source_coordinate_entity), "destination_coord" => B(p.destination_coordinate_entity),
            "response_coord" => B(p.response_coordinate_entity),
            "destination_entity_id_valid" => B(p.destination_entity_id_valid), "alpha_threshold" => u(p.alpha_threshold),
            "entity_id" => u(p.entity_id), "source_lat_xoff" => F64(p.source_lat_deg_or_x_m),
            "source_lon_yoff" => F64(p.source_lon_deg_or_y_m), "source_alt_zoff" => F64(p.source_alt_m_or_z_m),
            "destination_lat_xoff" => F64(p.destination_lat_deg_or_x_m),
            "destination_lon_yoff" => F64(p.destination_lon_deg_or_y_m),
            "destination_alt_zoff" => F64(p.destination_alt_m_or_z_m), "material_mask" => u(p.material_mask),
            "update_period" => u(p.update_period), "destination_entity_id" => u(p.destination_entity_id)),
        Packet::LosVectorRequest(p) => fields!("los_vector_request";
            "los_id" => u(p.los_id), "type" => B(p.request_type_extended), "source_coord" => B(p.source_coordinate_entity),
            "response_coord" => B(p.response_coordinate_entity), "alpha" => u(p.alpha_threshold),
            "entity_id" => u(p.entity_id), "azimuth" => F32(p.azimuth_deg), "elevation" => F32(p.elevation_deg),
            "min_range" => F32(p.min_range_m), "max_range" => F32(p.max_range_m),
            "source_lat_xoff" => F64(p.source_lat_deg_or_x_m), "source_lon_yoff" => F64(p.source_lon_deg_or_y_m),
            "source_alt_zoff" => F64(p.source_alt_m_or_z_m), "material_mask" => u(p.material_mask),
            "update_period" => u(p.update_period)),
        Packet::PositionRequest(p) => fields!("pos_request";
            "object_id" => u(p.object_id), "part_id" => u(p.part_id), "update_mode" => B(p.update_mode_continuous),
            "object_class" => u(p.object_class), "coord_system" => u(p.coordinate_system)),
        Packet::EnvironmentalConditionsRequest(p) => fields!("env_cond_request";
            "type" => u(p.request_type), "id" => u(p.request_id), "lat" => F64(p.latitude_deg),
            "lon" => F64(p.longitude_deg), "alt" => F64(p.altitude_m)),
        Packet::HatHotResponse(p) => fields!("hat_hot_response";
            "hat_hot_id" => u(p.hat_hot_id), "valid" => B(p.valid), "type" => B(p.response_type_hot),
            "host_frame_number_lsn" => u(p.host_frame_lsn), "height" => F64(p.height_m)),
        Packet::HatHotExtendedResponse(p) => fields!("hat_hot_ext_response";
            "hat_hot_id" => u(p.hat_hot_id), "valid" => B(p.valid), "host_frame_number_lsn" => u(p.host_frame_lsn),
            "hat" => F64(p.hat_m), "hot" => F64(p.hot_m), "material_code" => u(p.material_code),
            "normal_vector_azimuth" => F32(p.normal_azimuth_deg), "normal_vector_elevation" => F32(p.normal_elevation_deg)),
        Packet::LosResponse(p) => fields!("los_response";
            "los_id" => u(p.los_id), "valid" => B(p.valid), "entity_id_valid" => B(p.entity_id_valid),
            "visible" => B(p.visible), "host_frame_number_lsn" => u(p.host_frame_lsn), "count" => u(p.response_count),
            "entity_id" => u(p.entity_id), "range" => F64(p.range_m)),
        Packet::LosExtendedResponse(p) => fields!("3_2_los_ext_response";
            "los_id" => u(p.los_id), "valid" => B(p.valid), "entity_id_valid" => B(p.entity_id_valid),
            "range_valid" => B(p.range_valid), "visible" => B(p.visible), "host_frame_number_lsn" => u(p.host_frame_lsn),
            "response_count" => u(p.response_count), "entity_id" => u(p.entity_id), "range" => F64(p.range_m),
            "lat_xoff" => F64(p.lat_deg_or_x_m), "lon_yoff" => F64(p.lon_deg_or_y_m), "alt_zoff" => F64(p.alt_m_or_z_m),
            "red" => u(p.red), "green" => u(p.green), "blue" => u(p.blue), "alpha" => u(p.alpha),
            "material_code" => u(p.material_code), "normal_vector_azimuth" => F32(p.normal_azimuth_deg),
            "normal_vector_elevation" => F32(p.normal_elevation_deg)),
        Packet::SensorResponse(p) => fields!("sensor_response";
            "view_id" => u(p.view_id), "sensor_id" => u(p.sensor_id), "sensor_status" => u(p.sensor_status),
            "gate_x_size" => u(p.gate_x_size_px), "gate_y_size" => u(p.gate_y_size_px),
            "gate_x_pos" => F32(p.gate_x_position_deg), "gate_y_pos" => F32(p.gate_y_position_deg),
            "frame_ctr" => u(p.frame_counter)),
        Packet::SensorExtendedResponse(p) => fields!("sensor_ext_response";
            "view_id" => u(p.view_id), "sensor_id" => u(p.sensor_id), "sensor_status" => u(p.sensor_status),
            "entity_id_valid" => B(p.entity_id_valid), "entity_id" => u(p.entity_id),
            "gate_x_size" => u(p.gate_x_size_px), "gate_y_size" => u(p.gate_y_size_px),
            "gate_x_pos" => F32(p.gate_x_position_deg), "gate_y_pos" => F32(p.gate_y_position_deg),
            "frame_ctr" => u(p.frame_counter), "track_lat" => F64(p.track_latitude_deg),
            "track_lon" => F64(p.track_longitude_deg), "track_alt" => F64(p.track_altitude_m)),
        Packet::PositionResponse(p) => fields!("pos_response";
            "object_id" => u(p.object_id), "part_id" => u(p.part_id), "object_class" => u(p.object_class),
            "coord_system" => u(p.coordinate_system), "lat_xoff" => F64(p.lat_deg_or_x_m),
            "lon_yoff" => F64(p.lon_deg_or_y_m), "alt_zoff" => F64(p.alt_m_or_z_m), "roll" => F32(p.roll_deg),
            "pitch" => F32(p.pitch_deg), "yaw" => F32(p.yaw_deg)),
        Packet::WeatherConditionsResponse(p) => fields!("wea_cond_response";
            "request_id" => u(p.request_id), "humidity" => u(p.humidity_pct), "air_temp" => F32(p.air_temperature_c),
            "visibility_range" => F32(p.visibility_range_m), "horiz_speed" => F32(p.horizontal_wind_speed_mps),
            "vert_speed" => F32(p.vertical_wind_speed_mps), "wind_direction" => F32(p.wind_direction_deg),
            "barometric_pressure" => F32(p.barometric_pressure_mbar)),
        Packet::AerosolConcentrationResponse(p) => fields!("aerosol_concentration_response";
            "request_id" => u(p.request_id), "layer_id" => u(p.layer_id),
            "aerosol_concentration" => F32(p.aerosol_concentration_gpm3)),
        Packet::MaritimeSurfaceConditionsResponse(p) => {
            fields!("maritime_surface_conditions_response";
            "request_id" => u(p.request_id), "sea_surface_height" => F32(p.sea_surface_height_m),
            "surface_water_temp" => F32(p.surface_water_temperature_c), "surface_clarity" => F32(p.surface_clarity_pct))
        }
        Packet::TerrestrialSurfaceConditionsResponse(p) => fields!("terr_surface_cond_response";
            "request_id" => u(p.request_id), "surface_id" => u(p.surface_condition_id)),
        Packet::CollisionSegmentNotification(p) => fields!("coll_det_seg_notification";
            "entity_id" => u(p.entity_id), "segment_id" => u(p.segment_id), "type" => B(p.collision_with_entity),
            "contacted_entity_id" => u(p.contacted_entity_id), "material_code" => u(p.material_code),
            "intersection_distance" => F32(p.intersection_distance_m)),
        Packet::CollisionVolumeNotification(p) => fields!("coll_det_vol_notification";
            "entity_id" => u(p.entity_id), "volume_id" => u(p.volume_id), "type" => B(p.collision_with_entity),
            "contacted_entity_id" => u(p.contacted_entity_id), "contacted_volume_id" => u(p.contacted_volume_id)),
        Packet::AnimationStopNotification(p) => {
            fields!("animation_stop_notification"; "entity_id" => u(p.entity_id))
        }
        Packet::EventNotification(p) => fields!("event_notification";
            "event_id" => u(p.event_id), "data_1" => Word(p.data[0]), "data_2" => Word(p.data[1]),
            "data_3" => Word(p.data[2])),
        Packet::ImageGeneratorMessage(p) => fields!("image_generator_message";
            "message_id" => u(p.message_id), "message" => Text(p.text.clone())),
        other => panic!("no Wireshark expectation for {}", other.name()),
    }
}

fn flatten(value: &serde_json::Value, out: &mut Vec<(String, String)>) {
    if let Some(map) = value.as_object() {
        for (key, v) in map {
            match v {
                serde_json::Value::String(s) => out.push((key.clone(), s.clone())),
                other => flatten(other, out),
            }
        }
    } else if let Some(items) = value.as_array() {
        for v in items {
            flatten(v, out);
        }
    }
}

fn sample_packets(src: &mut SampleSource) -> (Vec<Packet>, Vec<Packet>) {
    let mut celestial = CelestialSphereControl::sample(src);
    celestial.seconds = 0.0;
    let mut weather = WeatherControl::sample(src);
    weather.top_scud_enable = false;
    weather.top_scud_frequency_pct = 0.0;
    weather.top_transition_band_m = 0.0;
    let host = vec![
        Packet::EntityControl(Sample::sample(src)),
        Packet::ConformalClampedEntity(Sample::sample(src)),
        Packet::ComponentControl(Sample::sample(src)),
        Packet::ShortComponentControl(Sample::sample(src)),
        Packet::ArticulatedPart(Sample::sample(src)),
        Packet::ShortArticulatedPart(Sample::sample(src)),
        Packet::RateControl(Sample::sample(src)),
        Packet::CelestialSphereControl(celestial),
        Packet::AtmosphereControl(Sample::sample(src)),
        Packet::EnvironmentalRegionControl(Sample::sample(src)),
        Packet::WeatherControl(weather),
        Packet::MaritimeSurfaceConditionsControl(Sample::sample(src)),
        Packet::WaveControl(Sample::sample(src)),
        Packet::TerrestrialSurfaceConditionsControl(Sample::sample(src)),
        Packet::ViewControl(Sample::sample(src)),
        Packet::SensorControl(Sample::sample(src)),
        Packet::ViewDefinition(Sample::sample(src)),
        Packet::CollisionSegmentDefinition(Sample::sample(src)),
        Packet::CollisionVolumeDefinition(Sample::sample(src)),
        Packet::HatHotRequest(Sample::sample(src)),
        Packet::LosSegmentRequest(Sample::sample(src)),
        Packet::LosVectorRequest(Sample::sample(src)),
        Packet::PositionRequest(Sample::sample(src)),
        Packet::EnvironmentalConditionsRequest(Sample::sample(src)),
    ];
    let ig = vec![
        Packet::HatHotResponse(Sample::sample(src)),
        Packet::HatHotExtendedResponse(Sample::sample(src)),
        Packet::LosResponse(Sample::sample(src)),
        Packet::LosExtendedResponse(Sample::sample(src)),
        Packet::SensorResponse(Sample::sample(src)),
        Packet::SensorExtendedResponse(Sample::sample(src)),
        Packet::PositionResponse(Sample::sample(src)),
        Packet::WeatherConditionsResponse(Sample::sample(src)),
        Packet::AerosolConcentrationResponse(Sample::sample(src)),
        Packet::MaritimeSurfaceConditionsResponse(Sample::sample(src)),
        Packet::TerrestrialSurfaceConditionsResponse(Sample::sample(src)),
        Packet::CollisionSegmentNotification(Sample::sample(src)),
        Packet::CollisionVolumeNotification(Sample::sample(src)),
        Packet::AnimationStopNotification(Sample::sample(src)),
        Packet::EventNotification(Sample::sample(src)),
        Packet::ImageGeneratorMessage(Sample::sample(src)),
    ];
    (host, ig)
}

#[test]
fn every_cigi_3_3_packet_matches_wireshark_in_both_byte_orders() {
    if Command::new("tshark").arg("--version").output().is_err() {
        eprintln!("SKIPPED: tshark not found (Debian package `tshark`); the Wireshark comparison did not run");
        return;
    }
    let mut src = SampleSource::new(0x00C1_6133);
    // (order, the two packets of the frame) per datagram.
    let mut frames: Vec<(ByteOrder, Vec<Packet>)> = Vec::new();
    for order in [ByteOrder::BigEndian, ByteOrder::LittleEndian] {
        for round in 0..3 {
            let (host, ig) = sample_packets(&mut src);
            for packet in host {
                let mut first = IgControl::sample(&mut src);
                first.entity_substitution_enable = false;
                first.database_number = i8::try_from(round).unwrap();
                // Wireshark only accepts IG Control as CIGI when the IG mode
                // is one the ICD defines for the host (0-2).
                first.ig_mode %= 3;
                frames.push((order, vec![Packet::IgControl(first), packet]));
            }
            for packet in ig {
                let mut first = StartOfFrame::sample(&mut src);
                first.overframing = false;
                first.paging = false;
                first.excessive_variable_length_data = false;
                frames.push((order, vec![Packet::StartOfFrame(first), packet]));
            }
        }
    }
    let payloads: Vec<Vec<u8>> = frames
        .iter()
        .map(|(order, packets)| {
            let mut out = Vec::new();
            encode_message(
                &Message::new(Version::V3_3, *order, packets.clone()),
                &mut out,
            )
            .unwrap();
            out
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let pcap = dir.path().join("cigi33.pcap");
    write_pcap(&pcap, &payloads);
    if let Some(keep) = std::env::var_os("CIGI_KEEP_PCAP") {
        std::fs::copy(&pcap, keep).unwrap();
    }
    let output = Command::new("tshark")
        .arg("-r")
        .arg(&pcap)
        .args(["-d", &format!("udp.port=={PORT},cigi"), "-T", "json"])
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "tshark failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let dissected = json.as_array().unwrap();
    assert_eq!(dissected.len(), frames.len());
    let mut checked = 0;
    for (i, ((order, packets), frame)) in frames.iter().zip(dissected).enumerate() {
        let mut fields = Vec::new();
        flatten(&frame["_source"]["layers"]["cigi"], &mut fields);
        let expected_magic = match order {
            ByteOrder::BigEndian => "0x8000",
            ByteOrder::LittleEndian => "0x0080",
        };
        let magic = fields
            .iter()
            .find(|(k, _)| k == "cigi.byte_swap")
            .map(|(_, v)| v.as_str());
        assert_eq!(
            magic,
            Some(expected_magic),
            "frame {i}: Wireshark reads the magic number as written"
        );
        for packet in packets {
            for (name, expected) in expectations(packet) {
                let got = fields
                    .iter()
                    .find(|(k, _)| *k == name)
                    .map(|(_, v)| v.as_str());
                let Some(got) = got else {
                    panic!(
                        "frame {i} ({order:?}): Wireshark shows no field {name} for {}",
                        packet.name()
                    );
                };
                assert!(
                    matches(&expected, got, *order),
                    "frame {i} ({order:?}) {}: {name} is {got} in Wireshark, {expected:?} encoded",
                    packet.name()
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 1000, "only {checked} fields compared");
}
