//! Core layer: GPU twins of the shader data blocks (layouts match `shader/*.wgsl`)
//! and [`UniformBlock`], which writes a block only when its bytes change.

use crate::render::clusters::ClusterGrid;
use crate::scene::{AlphaMode, Background, Camera, Environment, Light, LightKind, Material, MaterialId, MAX_LIGHTS};
use glam::{Mat4, Vec4};

/// One light as the shader reads it (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LightGpu {
    /// xyz direction travelled (w = 0) or position (w = 1) (16 bytes).
    position: [f32; 4],
    /// rgb colour × intensity, w range (16 bytes).
    color: [f32; 4],
    /// xyz the spot's axis, w the cone's scale; the cone factor is
    /// `saturate(dot(axis, -l) · scale + offset)²` (1 for other lights) (16 bytes).
    spot: [f32; 4],
    /// x the cone's offset; y the first shadow view (−1: no shadows); z, w depth
    /// and normal bias in texels (16 bytes).
    params: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<LightGpu>() == 64);

impl Light {
    /// The shader's view of this light; `shadow` is its first shadow view (a 2D
    /// layer, or a cube for point lights) when its shadow maps were drawn.
    pub(crate) fn to_gpu(self, shadow: Option<u32>) -> LightGpu {
        // A light without a cone: scale 0, offset 1.
        let (mut spot, mut offset) = ([0.0; 4], 1.0);
        let (position, range) = match self.kind {
            LightKind::Directional { direction } => (direction.normalize_or(glam::Vec3::NEG_Y).extend(0.0), 0.0),
            LightKind::Point { position, range } => (position.extend(1.0), range.max(1e-3)),
            LightKind::Spot { position, direction, range, inner_angle, outer_angle } => {
                let outer = outer_angle.clamp(1e-3, std::f32::consts::FRAC_PI_2).cos();
                let inner = inner_angle.clamp(0.0, outer_angle).cos();
                let scale = 1.0 / (inner - outer).max(1e-3);
                spot = direction.normalize_or(glam::Vec3::NEG_Y).extend(scale).to_array();
                offset = -outer * scale;
                (position.extend(1.0), range.max(1e-3))
            }
        };
        LightGpu {
            position: position.to_array(),
            color: (self.color * self.intensity).extend(range).to_array(),
            spot,
            params: match (shadow, self.shadows) {
                (Some(first), Some(s)) => [offset, first as f32, s.depth_bias, s.normal_bias],
                _ => [offset, -1.0, 0.0, 0.0],
            },
        }
    }
}

/// The Scene block, `@group(0) @binding(0)` (4,224 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct SceneGpu {
    ambient: [f32; 4],              // 16: rgb, w glare
    sky_top: [f32; 4],              // 16
    sky_bottom: [f32; 4],           // 16
    fog: [f32; 4],                  // 16: rgb colour, w density
    counts: [u32; 4],               // 16: lights held (≤ 64), directional lights, a cluster tile's pixels, depth slices
    environment: [f32; 4],          // 16: intensity (0: none), cos and sin of its turn, last specular level
    environment_sky: [f32; 4], // 16: the specular level the sky is drawn from, 1 for the clusters' heat map, the soft-shadow filter's offset
    clusters: [f32; 4],        // 16: tiles across and down, slice = ⌊ln(depth)·z + w⌋
    lights: [LightGpu; MAX_LIGHTS], // 64 × 64
}
const _: () = assert!(std::mem::size_of::<SceneGpu>() == 128 + 64 * MAX_LIGHTS);

impl SceneGpu {
    /// Pack the environment and up to [`MAX_LIGHTS`] lights, with each light's
    /// first shadow view where it has shadow maps. The directional lights come
    /// first, then the point and spot lights, each kind in the order given (the
    /// forward shader's light loops, `LightCounts`). A clustered frame may have
    /// more: its directional lights (at most [`MAX_LIGHTS`], checked by the
    /// caller) are all here, its point and spot lights in its light table.
    pub(crate) fn new(env: &Environment, lights: &[Light], shadows: &[Option<u32>]) -> Self {
        let (top, bottom) = match env.background {
            Background::Color(c) => (c, c),
            Background::Gradient { top, bottom } => (top, bottom),
        };
        let mut block = Self {
            ambient: env.ambient.extend(if env.glare.is_finite() { env.glare.max(0.0) } else { 0.0 }).to_array(),
            sky_top: top.extend(1.0).to_array(),
            sky_bottom: bottom.extend(1.0).to_array(),
            fog: env.fog.map_or([0.0; 4], |f| f.color.extend(f.density).to_array()),
            counts: [lights.len().min(MAX_LIGHTS) as u32, 0, 0, 0],
            environment: [0.0; 4],
            environment_sky: [0.0; 4],
            clusters: [0.0; 4],
            lights: [LightGpu::default(); MAX_LIGHTS],
        };
        if let Some(light) = env.light {
            let finite = |v: f32, fallback: f32| if v.is_finite() { v } else { fallback };
            let turn = finite(light.rotation, 0.0);
            block.environment = [finite(light.intensity, 1.0).max(0.0), turn.cos(), turn.sin(), 0.0];
            block.environment_sky = [finite(light.sky_blur, 0.0).clamp(0.0, 1.0), 0.0, 0.0, 0.0];
        }
        let directional = |l: &Light| matches!(l.kind, LightKind::Directional { .. });
        let ordered = (lights.iter().enumerate().filter(|(_, l)| directional(l)))
            .chain(lights.iter().enumerate().filter(|(_, l)| !directional(l)));
        for (slot, (k, light)) in block.lights.iter_mut().zip(ordered) {
            *slot = light.to_gpu(shadows.get(k).copied().flatten());
        }
        block.counts[1] = lights.iter().filter(|l| directional(l)).count() as u32;
        block
    }
}

impl SceneGpu {
    /// The block with the environment's specular map ending at level `last`
    /// (its roughness-1 level), the sky's blur scaled to it.
    pub(crate) fn with_specular_levels(mut self, last: f32) -> Self {
        self.environment[3] = last;
        self.environment_sky[0] *= last;
        self
    }

    /// The block for sub-frame `sample` of an accumulated still: its
    /// soft-shadow filter offset ([`SubFrame::shadow_offset`](crate::render::SubFrame::shadow_offset)).
    pub(crate) fn with_sub_frame(mut self, sample: crate::render::SubFrame) -> Self {
        [self.environment_sky[2], self.environment_sky[3]] = sample.shadow_offset().to_array();
        self
    }

    /// The block with the view's light cluster grid (`render/clusters.rs`),
    /// drawn as a heat map of lights per cluster when `heat_map`.
    pub(crate) fn with_clusters(mut self, grid: &ClusterGrid, heat_map: bool) -> Self {
        self.environment_sky[1] = f32::from(u8::from(heat_map));
        let (scale, bias) = grid.slice_rule();
        self.counts[2] = grid.tile_pixels;
        self.counts[3] = grid.slices;
        self.clusters = [grid.tiles[0] as f32, grid.tiles[1] as f32, scale, bias];
        self
    }
}

/// The Camera block, `@group(1) @binding(0)` (240 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct CameraGpu {
    view_proj: [f32; 16],     // 64
    view: [f32; 16],          // 64
    inv_view_proj: [f32; 16], // 64
    position: [f32; 4],       // 16
    motion: [f32; 4],         // 16: scene time (s), wind strength, wind direction x, z
    far_eye: [f32; 4],        // 16: the eye far fields are measured from; w: 1 when they are on
}
const _: () = assert!(std::mem::size_of::<CameraGpu>() == 240);

impl CameraGpu {
    /// The shader's view of `camera` through `projection` (its own at the
    /// target's aspect ratio, or that moved by a sub-frame's jitter).
    pub(crate) fn new(camera: Camera, projection: glam::Mat4) -> Self {
        let view = camera.view();
        let view_proj = projection * view;
        Self {
            view_proj: view_proj.to_cols_array(),
            view: view.to_cols_array(),
            inv_view_proj: view_proj.inverse().to_cols_array(),
            position: camera.eye.extend(1.0).to_array(),
            motion: [0.0; 4],
            far_eye: [0.0; 4],
        }
    }

    /// A shadow view's record: its matrices, the light's position, and in `w` the
    /// distance scale of cube faces (0 for depth views).
    pub(crate) fn for_shadow(view: &crate::render::passes::shadow_views::ShadowView) -> Self {
        let view_proj = view.view_proj();
        Self {
            view_proj: view_proj.to_cols_array(),
            view: view.view.to_cols_array(),
            inv_view_proj: view_proj.inverse().to_cols_array(),
            position: view.eye.extend(view.distance_scale).to_array(),
            motion: [0.0; 4],
            far_eye: [0.0; 4],
        }
    }

    /// The record with `environment`'s time and wind, which move the vertices
    /// of materials with a [`Motion`](crate::scene::Motion): in the Camera block
    /// because shadow passes, which bind no Scene block, move them too.
    pub(crate) fn with_motion(self, environment: &crate::scene::Environment) -> Self {
        let [strength, x, z] = environment.wind.to_gpu();
        let time = if environment.time.is_finite() { environment.time } else { 0.0 };
        Self { motion: [time, strength, x, z], ..self }
    }

    /// The record with far fields ([`FarField`](crate::scene::FarField))
    /// measured from `eye` (a camera view's own, or the camera view's a shadow
    /// view is drawn for), or off (`None`: every instance at its own width).
    pub(crate) fn with_far_eye(self, eye: Option<glam::Vec3>) -> Self {
        let far_eye = eye.map_or([0.0; 4], |e| e.extend(1.0).to_array());
        Self { far_eye, ..self }
    }
}

/// One material as the shader reads it: an element of the material table,
/// `@group(2) @binding(0)`, indexed by material id (96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct MaterialGpu {
    base_color: [f32; 4], // 16
    coeffs: [f32; 4],     // 16: ambient, diffuse, specular, Blinn-Phong exponent
    pbr: [f32; 4],        // 16: metallic, roughness, 2 reserved
    emissive: [f32; 4],   // 16: rgb, reserved
    uv_x: [f32; 3],       // 12: first row of the 2×3 uv transform
    alpha_cutoff: f32,    // 4
    uv_y: [f32; 3],       // 12: second row
    uv1_maps: u32,        // 4: MapSlots reading the second uv set
    motion: [f32; 4],     // 16: the Motion's parameters (scene/motion.rs), reserved
    fade: [f32; 4],       // 16: edge fade's inner and outer radius, far field's start and end
}
const _: () = assert!(std::mem::size_of::<MaterialGpu>() == 128);

impl Material {
    /// The shader's view of this material (what it does with them is the variant's
    /// business: see `ShaderFeatures`).
    pub(crate) fn to_gpu(&self) -> MaterialGpu {
        let cutoff = match self.alpha_mode {
            AlphaMode::Mask { cutoff } => cutoff,
            AlphaMode::Opaque | AlphaMode::Blend => 0.0,
        };
        let exponent = (1.0 + 11.0 * self.smoothness.clamp(0.0, 1.0)).exp2();
        let (s, c) = self.uv_rotation.sin_cos();
        let [m0, m1, m2] = self.motion.map_or([0.0; 3], crate::scene::Motion::params);
        let (inner, outer) = self.edge_fade.unwrap_or((0.0, 0.0));
        let far = self.far_field.map_or([0.0; 2], |f| [f.start, f.end]);
        MaterialGpu {
            base_color: self.base_color.to_array(),
            coeffs: Vec4::new(self.ambient, self.diffuse, self.specular, exponent).to_array(),
            pbr: [self.metallic.clamp(0.0, 1.0), self.roughness.clamp(0.0, 1.0), 0.0, 0.0],
            emissive: self.emissive.extend(0.0).to_array(),
            motion: [m0, m1, m2, 0.0],
            fade: [inner, outer, far[0], far[1]],
            uv_x: [c * self.uv_scale.x, -s * self.uv_scale.y, self.uv_offset.x],
            alpha_cutoff: cutoff,
            uv_y: [s * self.uv_scale.x, c * self.uv_scale.y, self.uv_offset.y],
            uv1_maps: self.uv1_maps.bits(),
        }
    }
}

/// One instance as the shader reads it, `@group(3) @binding(0)` (64 bytes): the
/// top three rows of its object-to-world matrix (the bottom row of an object
/// transform is 0 0 0 1, and is taken to be) and its material's index in the
/// material table, so draws of different materials can share one indirect call.
/// A skinned entity's joint matrices are stored as records of this same shape
/// right after its instances (rows only), so they live, move and upload with them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct InstanceGpu {
    rows: [[f32; 4]; 3], // 48
    material: u32,       // 4
    /// Records from this one to its entity's first joint matrix (0: not skinned).
    pub(crate) joints: u32, // 4
    /// How many joint matrices the entity has.
    pub(crate) joint_count: u32, // 4
    /// Bit 0: receives shadows; bits 16–31: the instance's motion phase in
    /// 1/65536 cycles ([`Entity::phases`](crate::Entity::phases)).
    flags: u32, // 4
}
const _: () = assert!(std::mem::size_of::<InstanceGpu>() == 64);

impl InstanceGpu {
    /// An instance drawn with `transform` and material `material`, darkened by
    /// shadows when `receive_shadows`.
    pub(crate) fn new(transform: &Mat4, material: MaterialId, receive_shadows: bool) -> Self {
        let t = transform.transpose();
        Self {
            rows: [t.x_axis.to_array(), t.y_axis.to_array(), t.z_axis.to_array()],
            material: material.0,
            flags: u32::from(receive_shadows),
            ..Self::default()
        }
    }

    /// This instance at motion phase `phase` (a fraction of a cycle).
    pub(crate) fn with_phase(mut self, phase: f32) -> Self {
        let steps = (phase.rem_euclid(1.0) * 65536.0) as u32 & 0xffff;
        self.flags = (self.flags & 0xffff) | steps << 16;
        self
    }

    /// This instance skinned by `count` joint matrices stored `offset` records after it.
    pub(crate) fn with_joints(self, offset: u32, count: u32) -> Self {
        Self { joints: offset, joint_count: count, ..self }
    }

    /// The instance's transform, bottom row 0 0 0 1.
    #[cfg(test)]
    pub(crate) fn transform(&self) -> Mat4 {
        Mat4::from_cols_array_2d(&[self.rows[0], self.rows[1], self.rows[2], [0.0, 0.0, 0.0, 1.0]]).transpose()
    }
}

/// A compact instance (16 bytes), four to a 64-byte record of the instance
/// buffer: `x` and `z` of its position (f32), its `y` and scale (two half
/// floats), then its turn about +Y (the low 16 bits, 1/65536 of a turn), its
/// material (15 bits) and whether it receives shadows (the top bit).
/// `forward.wgsl`'s `compact_instance` reads it back.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct CompactGpu(pub(crate) [u32; 4]);

/// Materials a compact instance can name (15 bits).
pub(crate) const COMPACT_MATERIALS: u32 = 1 << 15;

impl CompactGpu {
    /// `transform`'s position, scale (its Y axis's length) and turn about +Y
    /// (of its Z axis), with `material` (below [`COMPACT_MATERIALS`]); a
    /// transform that is not finite draws nothing (scale 0).
    pub(crate) fn new(transform: &Mat4, material: MaterialId, receive_shadows: bool) -> Self {
        if !transform.is_finite() {
            return Self::default();
        }
        let p = transform.w_axis;
        let scale = transform.y_axis.truncate().length();
        let z = transform.z_axis;
        let turn = z.x.atan2(z.z).rem_euclid(std::f32::consts::TAU) / std::f32::consts::TAU;
        let turn = ((turn * 65536.0).round() as u32) & 0xffff;
        let half = |v: f32| u32::from(half::f16::from_f32(v).to_bits());
        let ids = turn | (material.0 & (COMPACT_MATERIALS - 1)) << 16 | u32::from(receive_shadows) << 31;
        Self([p.x.to_bits(), p.z.to_bits(), half(p.y) | half(scale) << 16, ids])
    }

    /// Four of them as one record of the instance buffer.
    pub(crate) fn record(four: [Self; 4]) -> InstanceGpu {
        bytemuck::cast(four)
    }
}

/// A uniform buffer holding one block, rewritten only when its bytes change.
pub(crate) struct UniformBlock<T: bytemuck::Pod + PartialEq> {
    pub(crate) buffer: wgpu::Buffer,
    last: Option<T>,
}

impl<T: bytemuck::Pod + PartialEq> UniformBlock<T> {
    pub(crate) fn new(device: &wgpu::Device, label: &str) -> Self {
        Self {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<T>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            last: None,
        }
    }

    /// Write `value` if it differs from what the buffer holds; returns bytes written.
    pub(crate) fn update(&mut self, queue: &wgpu::Queue, value: T) -> u64 {
        if self.last.as_ref() == Some(&value) {
            return 0;
        }
        queue.write_buffer(&self.buffer, 0, bytemuck::bytes_of(&value));
        self.last = Some(value);
        std::mem::size_of::<T>() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_scene_block_holds_directional_lights_first_with_their_own_shadow_views() {
        let lamp = Light::point(Vec3::Y, Vec3::ONE, 1.0, 5.0);
        let sun = Light::directional(Vec3::NEG_Y, Vec3::ONE, 2.0);
        let shadowed = |l: Light| Light { shadows: Some(crate::scene::ShadowSettings::default()), ..l };
        let lights = [shadowed(lamp), sun, shadowed(Light { intensity: 3.0, ..sun })];
        let block = SceneGpu::new(&Environment::default(), &lights, &[Some(7), None, Some(2)]);
        assert_eq!(block.counts[..2], [3, 2], "three lights, two directional");
        // Directional ones in the order given (intensity 2, then 3), then the lamp.
        assert_eq!([block.lights[0].color[0], block.lights[1].color[0]], [2.0, 3.0]);
        assert_eq!(
            [block.lights[0].position[3], block.lights[1].position[3], block.lights[2].position[3]],
            [0.0, 0.0, 1.0]
        );
        // Each keeps the shadow view of its place in the caller's list.
        assert_eq!([block.lights[0].params[1], block.lights[1].params[1], block.lights[2].params[1]], [-1.0, 2.0, 7.0]);
    }

    #[test]
    fn the_blocks_mirror_their_wgsl_structs() {
        use crate::shader::layout::{assert_layout, assert_mirrors};
        let wgsl = crate::shader::forward_for_layouts();
        assert_mirrors!(LightGpu, &wgsl, "Light", [position, color, spot, params]);
        assert_mirrors!(
            SceneGpu,
            &wgsl,
            "SceneBlock",
            [ambient, sky_top, sky_bottom, fog, counts, environment, environment_sky, clusters, lights]
        );
        assert_mirrors!(CameraGpu, &wgsl, "CameraBlock", [view_proj, view, inv_view_proj, position, motion, far_eye]);
        assert_mirrors!(
            MaterialGpu,
            &wgsl,
            "MaterialBlock",
            [base_color, coeffs, pbr, emissive, uv_x, alpha_cutoff, uv_y, uv1_maps, motion, fade]
        );
        let at = |field: usize, row: usize| field + 16 * row;
        let rows = std::mem::offset_of!(InstanceGpu, rows);
        let fields = [
            ("row_x", at(rows, 0)),
            ("row_y", at(rows, 1)),
            ("row_z", at(rows, 2)),
            ("material", std::mem::offset_of!(InstanceGpu, material)),
            ("joints", std::mem::offset_of!(InstanceGpu, joints)),
            ("joint_count", std::mem::offset_of!(InstanceGpu, joint_count)),
            ("flags", std::mem::offset_of!(InstanceGpu, flags)),
        ];
        assert_layout(&wgsl, "Instance", std::mem::size_of::<InstanceGpu>(), &fields);
    }

    #[test]
    fn a_compact_instance_keeps_position_scale_turn_material_and_shadow_flag() {
        let turn = 2.5_f32;
        let (scale, rotation) = (Vec3::splat(0.7), glam::Quat::from_rotation_y(turn));
        let m = Mat4::from_scale_rotation_translation(scale, rotation, Vec3::new(12.5, 0.3, -7.25));
        let CompactGpu([x, z, ys, ids]) = CompactGpu::new(&m, MaterialId(300), true);
        assert_eq!((f32::from_bits(x), f32::from_bits(z)), (12.5, -7.25), "x and z exact");
        let (y, scale) = (half::f16::from_bits(ys as u16).to_f32(), half::f16::from_bits((ys >> 16) as u16).to_f32());
        assert!((y - 0.3).abs() < 3e-4 && (scale - 0.7).abs() < 5e-4, "y {y}, scale {scale}");
        let back = (ids & 0xffff) as f32 / 65536.0 * std::f32::consts::TAU;
        assert!((back - turn).abs() < 1e-4, "turn {back}");
        assert_eq!(((ids >> 16) & 0x7fff, ids >> 31), (300, 1));
        assert_eq!(CompactGpu::new(&Mat4::from_translation(Vec3::NAN), MaterialId(1), true), CompactGpu::default());
    }
}
