//! Core layer: image-based lighting on the GPU. An environment image
//! ([`EnvironmentImage`], equirectangular) is uploaded once as a *source* with a
//! box-filtered mip chain ([`Registry::add_environment`](crate::render::Registry::add_environment)); when a frame's
//! environment differs from the one prefiltered last (another image, or the sky
//! baked for another time of day), full-screen passes (`shader/prefilter.wgsl`;
//! render passes, so WebGL2 runs them too) make:
//! - the *specular map*: equirectangular, the source's size at level 0, level k
//!   prefiltered for roughness k / (levels − 1) (at most [`SPECULAR_LEVELS`]);
//! - the *irradiance*: nine spherical-harmonic coefficients (a 9 × 1 texture);
//! - the *BRDF table* (once per renderer): the split-sum scale and bias,
//!   [`BRDF_SIZE`]² over (n·v, roughness).
//!
//! The Scene bind group (`@group(0)` bindings 5–8) shows them; 1 × 1 stand-ins
//! until an environment is used. The environment's turn and intensity are
//! applied where it is looked up, so changing them prefilters nothing.

use crate::gpu::{full_screen_pipeline, sampler_entry, texture_entry, HDR_FORMAT};
use crate::render::error::RenderError;
use crate::scene::EnvironmentImage;
use crate::scene::{Background, Environment, EnvironmentId, EnvironmentSource, Light, LightKind};

/// The widest environment source uploaded, and so the widest specular map:
/// a larger image is halved on the CPU first (about a 512² cube face's
/// detail). Prefiltering costs [`SPECULAR_SAMPLES`] GGX samples a texel, so
/// an 8192-texel-wide map took 37–76 s and 3 GB on lavapipe (`docs/limits.md`).
pub(crate) const MAX_SOURCE_SIDE: u32 = 2048;
/// The most levels of the specular map: roughness steps of 0.2.
pub(crate) const SPECULAR_LEVELS: u32 = 6;
/// GGX samples per specular texel (filtered importance sampling keeps this low).
const SPECULAR_SAMPLES: u32 = 128;
/// The BRDF table's side, and its samples per texel.
pub(crate) const BRDF_SIZE: u32 = 64;
const BRDF_SAMPLES: u32 = 512;
/// The irradiance sums the first source level at most this wide.
const IRRADIANCE_WIDTH: u32 = 64;
/// One parameter record per pass, at the uniform offset alignment.
const PARAMS_STRIDE: u64 = 256;

/// An environment source uploaded with its mip chain.
pub(crate) struct SourceImage {
    texture: wgpu::Texture,
}

/// What the maps were last prefiltered from.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Prefiltered {
    Image(EnvironmentId),
    /// The baked sky's top and bottom colours and its sun (direction, colour).
    Sky([f32; 12]),
}

/// The prefiltering pipelines (made on first use).
struct PrefilterPipelines {
    layout: wgpu::BindGroupLayout,
    specular: wgpu::RenderPipeline,
    irradiance: wgpu::RenderPipeline,
    brdf: wgpu::RenderPipeline,
    params: wgpu::Buffer,
}

/// The maps the forward and sky shaders read, and what made them.
pub(crate) struct EnvironmentMaps {
    specular: wgpu::TextureView,
    irradiance: wgpu::TextureView,
    /// The textures behind the two views (None for the stand-ins).
    textures: Option<(wgpu::Texture, wgpu::Texture)>,
    brdf: Option<wgpu::TextureView>,
    placeholder: wgpu::TextureView,
    sampler: wgpu::Sampler,
    /// The specular map's levels (1 for the stand-in).
    levels: u32,
    prefiltered: Option<Prefiltered>,
    pipelines: Option<PrefilterPipelines>,
    /// Bumped whenever a view must be bound anew (the Scene bind group points at one generation).
    generation: u64,
}

fn texture(device: &wgpu::Device, label: &str, (width, height): (u32, u32), levels: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: HDR_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// Levels of a full mip chain for a `width` × `height` image.
fn full_chain(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

impl SourceImage {
    /// Upload `image` (halved on the CPU until it fits `max_side`) as
    /// half floats with a box-filtered mip chain made on the CPU.
    pub(crate) fn upload(device: &wgpu::Device, queue: &wgpu::Queue, image: &EnvironmentImage, max_side: u32) -> Self {
        let mut level = image.pixels().clone();
        while level.width().max(level.height()) > max_side {
            level = halve(&level);
        }
        let levels = full_chain(level.width(), level.height());
        let texture = texture(device, &format!("environment: {}", image.name), level.dimensions(), levels);
        for k in 0..levels {
            let halves: Vec<u16> = (level.pixels())
                .flat_map(|p| [p[0], p[1], p[2], 1.0])
                .map(|v| half::f16::from_f32(v).to_bits())
                .collect();
            queue.write_texture(
                wgpu::TexelCopyTextureInfo { mip_level: k, ..texture.as_image_copy() },
                bytemuck::cast_slice(&halves),
                wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(8 * level.width()), rows_per_image: None },
                wgpu::Extent3d { width: level.width(), height: level.height(), depth_or_array_layers: 1 },
            );
            if k + 1 < levels {
                level = halve(&level);
            }
        }
        Self { texture }
    }
}

/// `image` at half its size (at least 1 × 1), each texel the mean of the ones it covers.
fn halve(image: &image::Rgb32FImage) -> image::Rgb32FImage {
    let (w, h) = image.dimensions();
    let (hw, hh) = ((w / 2).max(1), (h / 2).max(1));
    image::Rgb32FImage::from_fn(hw, hh, |x, y| {
        let mut sum = [0.0f32; 3];
        let xs = [(2 * x).min(w - 1), (2 * x + 1).min(w - 1)];
        let ys = [(2 * y).min(h - 1), (2 * y + 1).min(h - 1)];
        for (sx, sy) in ys.iter().flat_map(|&sy| xs.iter().map(move |&sx| (sx, sy))) {
            for (s, v) in sum.iter_mut().zip(image.get_pixel(sx, sy).0) {
                *s += v / 4.0;
            }
        }
        image::Rgb(sum)
    })
}

impl EnvironmentMaps {
    /// Stand-ins (black, 1 × 1) until an environment is used.
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let view = |label| texture(device, label, (9, 1), 1).create_view(&Default::default());
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("environment: sampler (u repeats, v clamped, trilinear)"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        Self {
            specular: view("environment: no specular map"),
            irradiance: view("environment: no irradiance"),
            textures: None,
            brdf: None,
            placeholder: view("environment: stand-in"),
            sampler,
            levels: 1,
            prefiltered: None,
            pipelines: None,
            generation: 0,
        }
    }

    /// The Scene bind group's entries 5–8.
    pub(crate) fn entries(&self) -> [wgpu::BindGroupEntry<'_>; 4] {
        let view = |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
        [
            view(5, &self.specular),
            view(6, &self.irradiance),
            view(7, self.brdf.as_ref().unwrap_or(&self.placeholder)),
            wgpu::BindGroupEntry { binding: 8, resource: wgpu::BindingResource::Sampler(&self.sampler) },
        ]
    }

    /// How many times the maps were replaced.
    pub(crate) fn generation(&self) -> u64 {
        self.generation
    }

    /// The specular map's last level (the one for roughness 1).
    pub(crate) fn last_level(&self) -> f32 {
        (self.levels - 1) as f32
    }

    /// Prefilter `environment`'s light (under `lights`, whose first directional
    /// light is a baked sky's sun) unless the maps already hold it: the passes
    /// are recorded into a command buffer, returned to run before the frame.
    /// None when nothing had to be done.
    pub(crate) fn update<'s>(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        sources: impl Fn(EnvironmentId) -> Option<&'s SourceImage>,
        environment: &Environment,
        lights: &[Light],
    ) -> Result<Option<wgpu::CommandBuffer>, RenderError> {
        let Some(light) = environment.light else { return Ok(None) };
        let wanted = match light.source {
            EnvironmentSource::Image(id) => Prefiltered::Image(id),
            EnvironmentSource::Sky => Prefiltered::Sky(sky_inputs(environment, lights)),
        };
        if self.prefiltered == Some(wanted) && self.brdf.is_some() {
            return Ok(None);
        }
        let scope = crate::gpu::DriverErrors::watch(device);
        if self.pipelines.is_none() {
            let wgsl = crate::shader::prefilter();
            let module =
                crate::render::resources::pipelines::shader_module(device, "environment: prefilter shader", wgsl);
            self.pipelines = Some(PrefilterPipelines::new(device, &module));
        }
        let baked;
        let source = match wanted {
            Prefiltered::Image(id) => sources(id).ok_or(RenderError::UnknownEnvironment(id))?,
            Prefiltered::Sky(inputs) => {
                let [tx, ty, tz, bx, by, bz, dx, dy, dz, cx, cy, cz] = inputs;
                let sun = (inputs[9..] != [0.0; 3]).then(|| (glam::vec3(dx, dy, dz), glam::vec3(cx, cy, cz)));
                let sky = EnvironmentImage::sky(glam::vec3(tx, ty, tz), glam::vec3(bx, by, bz), sun);
                baked = SourceImage::upload(device, queue, &sky, device.limits().max_texture_dimension_2d);
                &baked
            }
        };
        let commands = self.prefilter(device, queue, source);
        if let Some(error) = scope.finish() {
            return Err(RenderError::Device { what: "the environment's prefiltering", message: error.to_string() });
        }
        self.prefiltered = Some(wanted);
        Ok(Some(commands))
    }

    /// Record every prefiltering pass for `source` (and the BRDF table once).
    fn prefilter(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, source: &SourceImage) -> wgpu::CommandBuffer {
        let pipelines = self.pipelines.as_ref().expect("made by update");
        let size = source.texture.size();
        let source_levels = source.texture.mip_level_count();
        let levels = SPECULAR_LEVELS.min(source_levels);
        let specular = texture(device, "environment: specular map", (size.width, size.height), levels);
        let irradiance = texture(device, "environment: irradiance (spherical harmonics)", (9, 1), 1);
        let irradiance_level = (0..source_levels).find(|&k| (size.width >> k) <= IRRADIANCE_WIDTH).unwrap_or(0);
        // Records: the specular levels, then the irradiance, then the BRDF table.
        let source_info = [size.width as f32, size.height as f32, source_levels as f32, SPECULAR_SAMPLES as f32];
        let mut records: Vec<[f32; 12]> = (0..levels)
            .map(|k| {
                let roughness = if levels > 1 { k as f32 / (levels - 1) as f32 } else { 0.0 };
                let (w, h) = ((size.width >> k).max(1) as f32, (size.height >> k).max(1) as f32);
                let [a, b, c, d] = source_info;
                [roughness, k as f32, w, h, a, b, c, d, 0.0, 0.0, 0.0, 0.0]
            })
            .collect();
        records.push([0.0, 0.0, 9.0, 1.0, 0.0, 0.0, 0.0, 0.0, irradiance_level as f32, 0.0, 0.0, 0.0]);
        let brdf_size = BRDF_SIZE as f32;
        records.push([0.0, 0.0, brdf_size, brdf_size, 0.0, 0.0, 0.0, BRDF_SAMPLES as f32, 0.0, 0.0, 0.0, 0.0]);
        let mut bytes = vec![0u8; PARAMS_STRIDE as usize * records.len()];
        for (k, record) in records.iter().enumerate() {
            let at = k * PARAMS_STRIDE as usize;
            bytes[at..at + 48].copy_from_slice(bytemuck::cast_slice(record));
        }
        queue.write_buffer(&pipelines.params, 0, &bytes);
        let source_view = source.texture.create_view(&Default::default());
        let group = pipelines.group(device, &source_view, &self.sampler);
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("environment: prefilter") });
        let mut pass = |target: &wgpu::TextureView, pipeline: &wgpu::RenderPipeline, record: usize| {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("environment: prefilter"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[(PARAMS_STRIDE * record as u64) as u32]);
            pass.draw(0..3, 0..1);
        };
        for k in 0..levels {
            let level = specular.create_view(&wgpu::TextureViewDescriptor {
                base_mip_level: k,
                mip_level_count: Some(1),
                ..Default::default()
            });
            pass(&level, &pipelines.specular, k as usize);
        }
        let irradiance_view = irradiance.create_view(&Default::default());
        pass(&irradiance_view, &pipelines.irradiance, levels as usize);
        if self.brdf.is_none() {
            let brdf = texture(device, "environment: BRDF table", (BRDF_SIZE, BRDF_SIZE), 1);
            let view = brdf.create_view(&Default::default());
            pass(&view, &pipelines.brdf, levels as usize + 1);
            self.brdf = Some(view);
        }
        self.specular = specular.create_view(&Default::default());
        self.irradiance = irradiance_view;
        self.textures = Some((specular, irradiance));
        self.levels = levels;
        self.generation += 1;
        encoder.finish()
    }
}

/// What a baked sky depends on: the gradient (a plain background colour is
/// both ends) and the first directional light's direction and colour × intensity.
fn sky_inputs(environment: &Environment, lights: &[Light]) -> [f32; 12] {
    let (top, bottom) = match environment.background {
        Background::Color(c) => (c, c),
        Background::Gradient { top, bottom } => (top, bottom),
    };
    let sun = lights.iter().find_map(|l| match l.kind {
        LightKind::Directional { direction } => Some((direction, l.color * l.intensity)),
        _ => None,
    });
    let (direction, color) = sun.unwrap_or_default();
    let mut inputs = [0.0; 12];
    for (k, v) in [top, bottom, direction, color].iter().enumerate() {
        inputs[3 * k..3 * k + 3].copy_from_slice(&v.to_array());
    }
    inputs
}

impl PrefilterPipelines {
    fn new(device: &wgpu::Device, module: &wgpu::ShaderModule) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("environment: prefilter layout"),
            entries: &[
                texture_entry(0),
                sampler_entry(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(48),
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("environment: prefilter"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            full_screen_pipeline(device, entry, (&pipeline_layout, module), ("vs_full", entry), HDR_FORMAT)
        };
        Self {
            specular: pipeline("fs_specular"),
            irradiance: pipeline("fs_irradiance"),
            brdf: pipeline("fs_brdf"),
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("environment: prefilter parameters"),
                size: PARAMS_STRIDE * u64::from(SPECULAR_LEVELS + 2),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            layout,
        }
    }

    fn group(&self, device: &wgpu::Device, source: &wgpu::TextureView, sampler: &wgpu::Sampler) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("environment: prefilter source"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(source) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(sampler) },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.params,
                        offset: 0,
                        size: wgpu::BufferSize::new(48),
                    }),
                },
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    //! The prefiltered maps against a brute-force CPU integration of the
    //! same environment (every texel of it, weighted by its solid angle).
    use super::*;
    use crate::gpu::Gpu;
    use crate::scene::{EnvironmentLight, Lighting};
    use glam::Vec3;

    /// A smooth environment with a broad bright region, so the prefilter's
    /// sampling error stays small against the difference between levels.
    fn environment() -> EnvironmentImage {
        EnvironmentImage::from_fn("test", 128, 64, |d| {
            let warm = d.dot(Vec3::new(0.6, 0.5, -0.62).normalize()).max(0.0).powi(4);
            Vec3::new(0.2 + 3.0 * warm, 0.3 + 1.5 * warm, 0.6 + 0.4 * d.y)
        })
    }

    /// Each texel's direction, radiance and solid angle.
    fn texels(env: &EnvironmentImage) -> Vec<(Vec3, Vec3, f32)> {
        let (w, h) = env.pixels().dimensions();
        let texel = 2.0 * std::f32::consts::PI * std::f32::consts::PI / (w * h) as f32;
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let d = crate::scene::equirect_direction([(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32]);
                let radiance = Vec3::from_array(env.pixels().get_pixel(x, y).0);
                (d, radiance, texel * (1.0 - d.y * d.y).max(0.0).sqrt())
            })
            .collect()
    }

    /// The GGX-weighted mean radiance around `n` (n = v = r): each texel
    /// weighted by D(h) (n·l), what the prefilter's estimator converges to.
    fn prefiltered(texels: &[(Vec3, Vec3, f32)], n: Vec3, roughness: f32) -> Vec3 {
        let a2 = (roughness * roughness).max(1e-3).powi(2);
        let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
        for &(l, radiance, solid_angle) in texels {
            let n_l = n.dot(l);
            if n_l <= 0.0 {
                continue;
            }
            let n_h = n.dot((n + l).normalize());
            let k = n_h * n_h * (a2 - 1.0) + 1.0;
            // With v = n, sampling h by D(h)(n·h) gives l a density D(h) / 4.
            let w = a2 / (k * k) * n_l * solid_angle;
            sum += radiance * w;
            weight += w;
        }
        sum / weight
    }

    /// What a white Lambert surface facing `n` returns: E(n) / π.
    fn irradiance(texels: &[(Vec3, Vec3, f32)], n: Vec3) -> Vec3 {
        let e: Vec3 = texels.iter().map(|&(l, radiance, solid_angle)| radiance * n.dot(l).max(0.0) * solid_angle).sum();
        e / std::f32::consts::PI
    }

    /// Mip `level` of `texture` (half floats, RGBA) as f32 texels.
    fn read_level(gpu: &Gpu, texture: &wgpu::Texture, level: u32) -> (u32, u32, Vec<[f32; 4]>) {
        let (w, h) = ((texture.width() >> level).max(1), (texture.height() >> level).max(1));
        let row = (8 * w).div_ceil(256) * 256;
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: u64::from(row * h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { mip_level: level, ..texture.as_image_copy() },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: None },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        gpu.queue.submit([encoder.finish()]);
        buffer.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("mapped"));
        gpu.device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
        let bytes = buffer.slice(..).get_mapped_range().expect("mapped").to_vec();
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let at = (y * row + 8 * x) as usize;
                let halves: &[u16] = bytemuck::cast_slice(&bytes[at..at + 8]);
                std::array::from_fn(|c| half::f16::from_bits(halves[c]).to_f32())
            })
            .collect();
        (w, h, texels)
    }

    #[test]
    fn a_prefilter_record_mirrors_its_wgsl_struct() {
        // Each pass's record is twelve floats, the WGSL's three vec4s.
        let fields = [("level", 0), ("source", 16), ("irradiance", 32)];
        crate::shader::layout::assert_layout(&crate::shader::prefilter(), "Params", size_of::<[f32; 12]>(), &fields);
    }

    #[test]
    fn a_wide_environment_is_prefiltered_from_a_reduced_copy() {
        // An 8192-texel-wide specular map took 37–76 s and 3 GB to prefilter
        // on lavapipe: the source is halved to 2048 wide first.
        let gpu = match Gpu::headless() {
            Ok(gpu) => gpu,
            Err(e) if std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() == Ok("1") => panic!("{e}"),
            Err(e) => return eprintln!("skipping GPU test: {e}"),
        };
        let wide = EnvironmentImage::from_fn("wide", 4 * MAX_SOURCE_SIDE, 8, |d| Vec3::splat(0.5 + 0.5 * d.y));
        let mut renderer = crate::render::Renderer::new(&gpu);
        let id = renderer.add_environment(&wide);
        let source = renderer.res.registry.environment(id).expect("uploaded");
        assert_eq!((source.texture.width(), source.texture.height()), (MAX_SOURCE_SIDE, 2));
        let light = Some(EnvironmentLight::new(EnvironmentSource::Image(id)));
        let environment = Environment { light, ..Environment::default() };
        assert!(renderer.prefilter_environment(&Lighting::new(&[], environment)).expect("prefiltered"));
        let (specular, _) = renderer.res.environment.textures.clone().expect("made");
        assert_eq!(specular.width(), MAX_SOURCE_SIDE);
    }

    #[test]
    fn the_prefiltered_maps_match_a_brute_force_integration() {
        let gpu = match Gpu::headless() {
            Ok(gpu) => gpu,
            Err(e) if std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() == Ok("1") => panic!("{e}"),
            Err(e) => return eprintln!("skipping GPU test: {e}"),
        };
        let env = environment();
        let mut renderer = crate::render::Renderer::new(&gpu);
        let id = renderer.add_environment(&env);
        let light = Some(EnvironmentLight::new(EnvironmentSource::Image(id)));
        let environment = Environment { light, ..Environment::default() };
        assert!(renderer.prefilter_environment(&Lighting::new(&[], environment)).expect("prefiltered"));
        assert!(!renderer.prefilter_environment(&Lighting::new(&[], environment)).expect("kept"), "done once");
        let (specular, irradiance_map) = renderer.res.environment.textures.clone().expect("made");
        assert_eq!(specular.mip_level_count(), SPECULAR_LEVELS);
        let texels = texels(&env);
        // Roughness 0.2, 0.6 and 1 (levels 1, 3 and 5), at directions toward,
        // beside and away from the bright region; within 3 % of the largest
        // channel (the importance sampling's error: at most 2.4 % when written).
        let mut worst = 0.0f32;
        for level in [1, 3, 5] {
            let roughness = level as f32 / (SPECULAR_LEVELS - 1) as f32;
            let (w, h, map) = read_level(&gpu, &specular, level);
            for uv in [[0.63, 0.3], [0.4, 0.5], [0.1, 0.7], [0.85, 0.45]] {
                let (x, y) = ((uv[0] * w as f32) as u32, (uv[1] * h as f32) as u32);
                let center = [(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32];
                let want = prefiltered(&texels, crate::scene::equirect_direction(center), roughness);
                let got = Vec3::from_slice(&map[(y * w + x) as usize][..3]);
                let error = (got - want).abs().max_element() / want.max_element();
                eprintln!("roughness {roughness} at {uv:?}: {got} vs {want} ({:.1} %)", error * 100.0);
                worst = worst.max(error);
            }
        }
        assert!(worst < 0.03, "worst {:.1} %", worst * 100.0);
        // The harmonics' diffuse light: within 3 % of the largest channel.
        let (_, _, coefficients) = read_level(&gpu, &irradiance_map, 0);
        for n in [Vec3::Y, Vec3::NEG_Y, Vec3::new(0.6, 0.5, -0.62).normalize(), Vec3::X, Vec3::NEG_Z] {
            let basis = sh_basis(n);
            let got: Vec3 = coefficients.iter().zip(basis).map(|(c, y)| Vec3::from_slice(&c[..3]) * y).sum();
            let want = irradiance(&texels, n);
            let error = (got - want).abs().max_element() / want.max_element();
            assert!(error < 0.03, "irradiance toward {n}: {got} vs {want} ({:.1} %)", error * 100.0);
        }
    }

    /// `equirect.wgsl`'s sh_basis.
    fn sh_basis(d: Vec3) -> [f32; 9] {
        [
            0.282095,
            0.488603 * d.y,
            0.488603 * d.z,
            0.488603 * d.x,
            1.092548 * d.x * d.y,
            1.092548 * d.y * d.z,
            0.315392 * (3.0 * d.z * d.z - 1.0),
            1.092548 * d.x * d.z,
            0.546274 * (d.x * d.x - d.y * d.y),
        ]
    }
}
