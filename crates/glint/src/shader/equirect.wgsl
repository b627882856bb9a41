// Environment maps: the equirectangular mapping (asset/environment.rs has the
// convention and its Rust twin) and the nine-coefficient spherical-harmonic
// basis the diffuse light is stored in (render/passes/environment.rs).
#define_import_path glint::equirect

const EQUIRECT_PI: f32 = 3.14159265;

// The texel coordinates of unit direction `d`: u = atan2(x, -z) / 2π + ½, v = acos(y) / π.
fn equirect_uv(d: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(atan2(d.x, -d.z) / (2.0 * EQUIRECT_PI) + 0.5, acos(clamp(d.y, -1.0, 1.0)) / EQUIRECT_PI);
}

// The unit direction at texel coordinates `uv`.
fn equirect_direction(uv: vec2<f32>) -> vec3<f32> {
    let phi = 2.0 * EQUIRECT_PI * (uv.x - 0.5);
    let theta = EQUIRECT_PI * uv.y;
    return vec3<f32>(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

// The real spherical harmonics of bands 0–2 at unit direction `d`, in the
// order the irradiance texture stores their coefficients.
fn sh_basis(d: vec3<f32>) -> array<f32, 9> {
    return array<f32, 9>(
        0.282095,
        0.488603 * d.y,
        0.488603 * d.z,
        0.488603 * d.x,
        1.092548 * d.x * d.y,
        1.092548 * d.y * d.z,
        0.315392 * (3.0 * d.z * d.z - 1.0),
        1.092548 * d.x * d.z,
        0.546274 * (d.x * d.x - d.y * d.y),
    );
}
