// Thermal sensor views' functions that need only the globals (sensor.rs): shared by the sky
// and by thermal.wgsl's users.

// The sky's band radiance along a direction (globals' sensor_sky0/1 at 0, 1, 3, 6, 10, 20, 40
// and 90 degrees of elevation).
fn th_sky(dir: vec3<f32>) -> f32 {
    let e = max(degrees(asin(clamp(dot(dir, g.eye_up.xyz), -1.0, 1.0))), 0.0);
    let at = array<f32, 8>(0.0, 1.0, 3.0, 6.0, 10.0, 20.0, 40.0, 90.0);
    let sky = array<f32, 8>(g.sensor_sky0.x, g.sensor_sky0.y, g.sensor_sky0.z, g.sensor_sky0.w,
        g.sensor_sky1.x, g.sensor_sky1.y, g.sensor_sky1.z, g.sensor_sky1.w);
    var value = sky[7];
    for (var k = 7u; k > 0u; k--) {
        if (e <= at[k]) {
            let f = (e - at[k - 1u]) / (at[k] - at[k - 1u]);
            value = mix(sky[k - 1u], sky[k], f);
        }
    }
    return value;
}

