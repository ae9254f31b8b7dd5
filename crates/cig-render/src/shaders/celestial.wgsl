// The moon and the stars, in linear radiance (light units), for the sky pass: see celestial.rs.

struct Celestial {
    // xyz: unit direction from the eye to the moon's centre (ECEF); w: sin(angular radius), 0 hides it.
    moon_dir: vec4<f32>,
    // xyz: unit direction to the sun (ECEF); w: radiance of a moon element lit and seen head-on.
    moon_sun: vec4<f32>,
    // rgb: the moon's colour (unit luminance); w: earthshine radiance.
    moon_colour: vec4<f32>,
    // xyz: unit direction of the moon's rotation axis (north, ECEF); w: 1 to paint the maria.
    moon_north: vec4<f32>,
    // Rows of the matrix from ECEF to the J2000 frame of the star records.
    ecef_to_celestial0: vec4<f32>,
    ecef_to_celestial1: vec4<f32>,
    ecef_to_celestial2: vec4<f32>,
    // x: light units per lux times pi (radiance of 1 cd/m2); y: stars on (1) or off (0);
    // z: point-spread sigma in pixels; w: star field intensity (0..1).
    stars: vec4<f32>,
    // rgb: atmospheric extinction, magnitudes per air mass; w: 1 to apply it.
    extinction: vec4<f32>,
};

struct StarRecord {
    // xyz: unit direction (J2000 frame, proper motion to the date); w: illuminance, lux.
    dir_lux: vec4<f32>,
    // rgb: colour of unit luminance.
    colour: vec4<f32>,
};

@group(2) @binding(0) var<uniform> cel: Celestial;
@group(2) @binding(1) var<storage, read> star_records: array<StarRecord>;
// Per cube-map cell: first index into star_index, count.
@group(2) @binding(2) var<storage, read> star_cells: array<vec2<u32>>;
@group(2) @binding(3) var<storage, read> star_index: array<u32>;

const STAR_GRID: u32 = 32u;

// The large near-side maria: selenographic latitude, longitude (east toward Mare Crisium),
// angular radius (degrees); Procellarum and Frigoris as chains of discs.
const MARIA_COUNT: u32 = 17u;
const MARIA = array<vec3<f32>, 17>(
    vec3<f32>(32.8, -15.6, 18.9),  // Imbrium
    vec3<f32>(28.0, 17.5, 11.1),   // Serenitatis
    vec3<f32>(8.5, 31.4, 14.4),    // Tranquillitatis
    vec3<f32>(17.0, 59.1, 9.2),    // Crisium
    vec3<f32>(-7.8, 51.3, 12.0),   // Fecunditatis
    vec3<f32>(-15.2, 35.5, 5.5),   // Nectaris
    vec3<f32>(-21.3, -16.6, 11.8), // Nubium
    vec3<f32>(-24.4, -38.6, 6.4),  // Humorum
    vec3<f32>(13.3, 3.6, 4.0),     // Vaporum
    vec3<f32>(-3.0, -20.0, 8.0),   // Insularum / Cognitum
    vec3<f32>(5.0, -45.0, 15.0),   // Procellarum, south
    vec3<f32>(20.0, -55.0, 15.0),  // Procellarum, middle
    vec3<f32>(35.0, -50.0, 10.0),  // Procellarum, north
    vec3<f32>(56.0, -30.0, 6.0),   // Frigoris, west
    vec3<f32>(57.0, -5.0, 6.0),    // Frigoris, middle
    vec3<f32>(56.0, 20.0, 6.0),    // Frigoris, east
    vec3<f32>(-5.0, -2.0, 3.0),    // Sinus Medii
);

// Relative albedo of the moon at the unit normal `n`, for the moon seen along `m` (ECEF): the
// maria at 0.57 of the highlands, scaled so the near side's mean is about 1.
fn moon_albedo(n: vec3<f32>, m: vec3<f32>) -> f32 {
    if (cel.moon_north.w < 0.5) {
        return 1.0;
    }
    let z = -m;
    let north = normalize(cel.moon_north.xyz - z * dot(cel.moon_north.xyz, z));
    let x = cross(north, z);
    var mare = 0.0;
    for (var i = 0u; i < MARIA_COUNT; i = i + 1u) {
        let p = MARIA[i];
        let lat = radians(p.x);
        let lon = radians(p.y);
        let c = cos(lat) * (sin(lon) * x + cos(lon) * z) + sin(lat) * north;
        let angle = acos(clamp(dot(n, c), -1.0, 1.0));
        let r = radians(p.z);
        mare = max(mare, 1.0 - smoothstep(0.6 * r, 1.25 * r, angle));
    }
    return 1.15 - 0.5 * mare;
}
const PI_CEL: f32 = 3.14159265;
const luma_cel = vec3<f32>(0.2126, 0.7152, 0.0722);

// Display value (pre-tone-map, exposed) to which the disc's adaptation level is brought when it
// would be brighter: ACES gives 0.8 of its white there.
const MOON_ADAPTED_LEVEL: f32 = 1.0;
// Strongest compression of the disc's contrast (the exponent), reached when the adaptation
// level is 100 times the display's (two decades).
const MOON_MIN_GAMMA: f32 = 0.5;

// The moon's exposed luminance `v` seen by an eye locally adapted to the disc, whose adaptation
// level (the exposed luminance of an element lit and seen head-on at this phase) is `level`:
// unchanged while the level is under MOON_ADAPTED_LEVEL; above it the disc is scaled about its
// level (v / level brought to MOON_ADAPTED_LEVEL) with its contrast compressed by a power
// (v / level)^gamma, gamma going from 1 to MOON_MIN_GAMMA over two decades of excess.
fn moon_adapted(v: f32, level: f32) -> f32 {
    if (level <= MOON_ADAPTED_LEVEL || v <= 0.0) {
        return v;
    }
    let excess = level / MOON_ADAPTED_LEVEL;
    let gamma = mix(1.0, MOON_MIN_GAMMA, clamp(log2(excess) / log2(100.0), 0.0, 1.0));
    return MOON_ADAPTED_LEVEL * pow(v / level, gamma);
}

// The cube-map cell of a direction (same layout as celestial.rs's `cell_of`).
fn star_cell(d: vec3<f32>) -> u32 {
    let a = abs(d);
    var face: u32;
    var uv: vec2<f32>;
    if (a.x >= a.y && a.x >= a.z) {
        face = select(1u, 0u, d.x > 0.0);
        uv = d.yz / a.x;
    } else if (a.y >= a.z) {
        face = select(3u, 2u, d.y > 0.0);
        uv = d.xz / a.y;
    } else {
        face = select(5u, 4u, d.z > 0.0);
        uv = d.xy / a.z;
    }
    let cell = min(vec2<u32>(clamp(uv * 0.5 + 0.5, vec2<f32>(0.0), vec2<f32>(1.0)) * f32(STAR_GRID)),
                   vec2<u32>(STAR_GRID - 1u));
    return (face * STAR_GRID + cell.y) * STAR_GRID + cell.x;
}

// The faintest point-source illuminance (lux) the eye sees against a background of luminance
// `b_cd` (cd/m2): Schaefer (1990) after Hecht; see cig_environment::stars.
fn star_threshold_lux(b_cd: f32) -> f32 {
    let b_nl = max(b_cd, 0.0) / 3.18309886e-6;
    var c1 = 1.58489319e-10;
    var c2 = 1.25892541e-2;
    if (b_nl >= 1500.0) {
        c1 = 4.46683592e-9;
        c2 = 1.25892541e-6;
    }
    let s = 1.0 + sqrt(c2 * b_nl);
    return c1 * s * s * 10.7639104;
}

// Transmittance of the atmosphere toward `dir` (Kasten and Young's air mass; 0 below the
// apparent horizon).
fn celestial_transmittance(dir: vec3<f32>) -> vec3<f32> {
    let sin_h = dot(dir, g.eye_up.xyz);
    let elevation = asin(clamp(sin_h, -1.0, 1.0)) + g.eye_up.w;
    if (elevation <= 0.0) {
        return vec3<f32>(0.0);
    }
    if (cel.extinction.w < 0.5) {
        return vec3<f32>(1.0);
    }
    let h_deg = max(degrees(asin(clamp(sin_h, -1.0, 1.0))), 0.0);
    let air_mass = 1.0 / (sin(radians(h_deg)) + 0.50572 * pow(h_deg + 6.07995, -1.6364));
    return pow(vec3<f32>(10.0), -0.4 * cel.extinction.rgb * air_mass);
}

// Linear radiance (light units, before exposure) of the moon and stars toward `dir` (ECEF), in
// front of a sky of radiance `sky_behind` (π L, light units, un-exposed): the background the
// eye's threshold for the stars is set by.
fn celestial_radiance(dir: vec3<f32>, sky_behind: vec3<f32>) -> vec3<f32> {
    let transmittance = celestial_transmittance(dir);
    if (max(transmittance.r, max(transmittance.g, transmittance.b)) <= 0.0) {
        return vec3<f32>(0.0);
    }
    let pixel_rad = 1.0 / max(g.flags.w, 1.0);
    var out = vec3<f32>(0.0);

    // The moon: a sphere lit by the sun (Lommel-Seeliger), with earthshine on the dark side;
    // the disc's edge is antialiased by its coverage of the pixel.
    var moon_cover = 0.0;
    let m = cel.moon_dir.xyz;
    let sin_r = cel.moon_dir.w;
    let cos_m = dot(dir, m);
    if (sin_r > 0.0 && cos_m > 0.0) {
        let s = dir - m * cos_m;
        let dist = length(s);
        moon_cover = clamp((sin_r - dist) / pixel_rad + 0.5, 0.0, 1.0);
        if (moon_cover > 0.0) {
            let s_in = s * min(1.0, 0.999 * sin_r / max(dist, 1e-12));
            let h = sqrt(max(sin_r * sin_r - dot(s_in, s_in), 0.0));
            let n = (s_in - m * h) / sin_r;
            let cos_i = dot(n, cel.moon_sun.xyz);
            let cos_e = h / sin_r;
            var lit = cel.moon_colour.w;
            if (cos_i > 0.0) {
                lit += cel.moon_sun.w * 2.0 * cos_i / (cos_i + cos_e);
            }
            lit *= moon_albedo(n, m);
            // The eye's local adaptation to the disc (see celestial.rs): compressed about the
            // disc's own level when it would pass the display's range, before the coverage so the
            // antialiased edge stays a linear blend. Only the moon: the stars are left physical.
            let seen = max(dot(cel.moon_colour.rgb * transmittance, luma_cel), 1e-30);
            let adapted = moon_adapted(lit * seen * g.flags.y, cel.moon_sun.w * seen * g.flags.y);
            out += cel.moon_colour.rgb * (adapted / (seen * max(g.flags.y, 1e-30))) * moon_cover;
        }
    }

    // The stars of this direction's cell, each a small gaussian of unit integral times its
    // illuminance, faded by the eye's threshold against the sky behind it: a star whose
    // illuminance at the eye (after extinction) is under the threshold is not drawn, one a
    // magnitude over it is drawn whole.
    let luma = vec3<f32>(0.2126, 0.7152, 0.0722);
    let sky_cd = dot(sky_behind, luma) / max(cel.stars.x, 1e-30);
    let threshold = star_threshold_lux(sky_cd);
    let star_t = dot(transmittance, luma);
    // Sirius, the brightest, gives 9.8e-6 lux above the atmosphere: over that threshold, no
    // star is seen.
    if (cel.stars.y > 0.5 && threshold < 9.8e-6 * star_t) {
        let c = vec3<f32>(dot(cel.ecef_to_celestial0.xyz, dir),
                          dot(cel.ecef_to_celestial1.xyz, dir),
                          dot(cel.ecef_to_celestial2.xyz, dir));
        let cell = star_cells[star_cell(c)];
        let sigma = cel.stars.z * pixel_rad;
        let inv_two_sigma2 = 1.0 / (2.0 * sigma * sigma);
        let norm = inv_two_sigma2 / PI_CEL;
        var stars = vec3<f32>(0.0);
        for (var i = 0u; i < cell.y; i = i + 1u) {
            let star = star_records[star_index[cell.x + i]];
            let sd = star.dir_lux.xyz;
            let cos_s = dot(c, sd);
            let off = c - sd * cos_s;
            let d2 = dot(off, off);
            if (cos_s > 0.0 && d2 < 16.0 * sigma * sigma) {
                let lux = star.dir_lux.w * cel.stars.w;
                // 0 at the threshold, 1 one magnitude (a factor 2.512) over it.
                let seen = clamp(log2(lux * star_t / threshold) * 0.75257, 0.0, 1.0);
                stars += star.colour.rgb * (lux * seen * norm * exp(-d2 * inv_two_sigma2));
            }
        }
        out += stars * cel.stars.x * (1.0 - moon_cover);
    }
    return out * transmittance;
}
