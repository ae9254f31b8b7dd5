// A thermal sensor's AC coupling (ac_coupling.rs): each line of the scene's band radiance
// through a first-order high-pass, as an AC-coupled detector's signal along its scan line;
// a level added back so the gain window stays where it was.

struct AcParams {
    // x: the filter's step per pixel, 1 - exp(-pixel time / time constant); y: the level
    // added back (radiance); z, w: unused.
    p: vec4<f32>,
};

@group(0) @binding(0) var scene: texture_2d<f32>;
@group(0) @binding(1) var coupled: texture_storage_2d<rgba16float, write>;
@group(0) @binding(2) var<uniform> params: AcParams;

@compute @workgroup_size(64)
fn couple(@builtin(global_invocation_id) gid: vec3<u32>) {
    let dims = textureDimensions(scene);
    let y = gid.x;
    if (y >= dims.y) {
        return;
    }
    let k = params.p.x;
    // The baseline starts at the line's first pixel (the line's DC restore).
    var baseline = textureLoad(scene, vec2<i32>(0, i32(y)), 0).r;
    for (var x = 0u; x < dims.x; x++) {
        let s = textureLoad(scene, vec2<i32>(i32(x), i32(y)), 0).r;
        baseline += (s - baseline) * k;
        let v = s - baseline + params.p.y;
        textureStore(coupled, vec2<i32>(i32(x), i32(y)), vec4<f32>(v, v, v, 1.0));
    }
}
