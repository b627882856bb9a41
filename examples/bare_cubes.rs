//! The peers' many-cubes scene (../shared/peers/README.md) drawn with wgpu alone: one
//! pipeline, one instanced draw, no renderer. It is the floor under `glint bench
//! scenes/bench/peer_cubes_10k.scn`: what the driver costs for the same cubes, so
//! that what glint adds on top can be told from what any wgpu program pays.
//!
//! ```text
//! cargo run --release -p glint --example bare_cubes -- [--n N] [--frames F] [--warmup W]
//!     [--size WxH] [--instances vertex|storage] [--all] [--lambert] [--trim-heap]
//!     [--depth-layers L] [--sample-layers] [--sample-cube]
//! ```
//! - `--instances vertex` (default): each cube's matrix rows are per-instance vertex
//!   attributes, as three-d draws them; `storage`: instance records in a storage
//!   buffer reached through a buffer of draw indices, as glint draws them.
//! - `--all` draws every cube; by default only those in the frustum (as glint culls).
//! - `--lambert` shades with Lambert only, instead of glint's metallic-roughness BRDF.
//! - `--trim-heap` leaves glibc's heap settings alone on a CPU rasterizer, instead of
//!   keeping freed memory as glint does (`glint::gpu::keep_freed_heap_memory`).
//! - `--depth-layers L` first draws the cubes depth-only into each of L layers of a
//!   1024² depth array, one render pass a layer, as glint's shadow pass draws its
//!   cascades.
//! - `--sample-layers` and `--sample-cube` (either or both) shade the cubes with
//!   comparison lookups in layer 0 of that array and in a depth cube map, through one
//!   comparison sampler, as glint's forward pass samples its shadow maps and point
//!   lights' cubes. (On lavapipe glint's shadowed frames grow while its forward shader
//!   holds the cube lookup; these lookups alone do not make wgpu grow: compare
//!   `resident_mib_frame_100` and `resident_mib_end`.)
//!
//! Prints one JSON line: `{"program":"bare_cubes","n":..,"drawn":..,"frames":..,
//! "ms_median":..,"ms_p95":..,"cpu_encode_ms_median":..,"cpu_submit_ms_median":..,
//! "resident_mib_frame_100":..,"resident_mib_end":..}`; a frame runs from its first
//! call until the GPU is done; encode is the CPU time from creating the command
//! encoder until it is finished (what `glint bench` calls encode), submit the call
//! to `Queue::submit`. Resident memory is read after measured frame 100 (or the
//! last) and at the end (Linux; null elsewhere).

use glam::{Vec3, Vec3A};
use glint::render::cull::Frustum;
use std::time::Instant;
use wgpu::util::DeviceExt;

/// What both instance modes share: the camera, the vertex output and the shading.
const COMMON: &str = r#"
struct Camera { view_proj: mat4x4<f32>, eye: vec4<f32> }
@group(0) @binding(0) var<uniform> camera: Camera;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

fn place(rows: mat3x4<f32>, position: vec3<f32>, normal: vec3<f32>) -> Out {
    let p = vec4<f32>(position, 1.0);
    let world = vec3<f32>(dot(rows[0], p), dot(rows[1], p), dot(rows[2], p));
    let n = vec3<f32>(dot(rows[0].xyz, normal), dot(rows[1].xyz, normal), dot(rows[2].xyz, normal));
    return Out(camera.view_proj * vec4<f32>(world, 1.0), world, n);
}

const BASE: vec3<f32> = vec3<f32>(0.604, 0.445, 0.319);
const LIGHT: vec3<f32> = vec3<f32>(0.6667, 0.6667, 0.3333); // towards the light
const RADIANCE: f32 = 2.0;
const PI: f32 = 3.14159265;

@fragment
fn fs_lambert(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(BASE * RADIANCE * max(dot(normalize(in.normal), LIGHT), 0.0), 1.0);
}

// glTF metallic-roughness, metallic 0, roughness 0.5 (the peers' material).
@fragment
fn fs_pbr(in: Out) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let v = normalize(camera.eye.xyz - in.world);
    let a2 = 0.0625;
    let n_l = max(dot(n, LIGHT), 0.0);
    let n_v = max(dot(n, v), 1e-4);
    let h = normalize(LIGHT + v);
    let n_h = max(dot(n, h), 0.0);
    let f = 0.04 + 0.96 * pow(1.0 - max(dot(v, h), 0.0), 5.0);
    let k = n_h * n_h * (a2 - 1.0) + 1.0;
    let d = a2 / (PI * k * k);
    let vis = 0.5 / max(n_l * sqrt(n_v * n_v * (1.0 - a2) + a2) + n_v * sqrt(n_l * n_l * (1.0 - a2) + a2), 1e-6);
    let brdf = (1.0 - f) * BASE / PI + f * d * vis;
    return vec4<f32>(PI * RADIANCE * brdf * n_l, 1.0);
}
"#;

/// Instances as per-instance vertex attributes (three-d's way).
const VERTEX_INSTANCES: &str = r#"
@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>,
             @location(4) r0: vec4<f32>, @location(5) r1: vec4<f32>, @location(6) r2: vec4<f32>) -> Out {
    return place(mat3x4<f32>(r0, r1, r2), position, normal);
}

"#;

/// Instances in a storage buffer, reached through the draw's indices (glint's way).
const STORAGE_INSTANCES: &str = r#"
@group(0) @binding(1) var<storage, read> instances: array<mat3x4<f32>>;
@group(0) @binding(2) var<storage, read> draw_indices: array<u32>;

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>,
              @builtin(instance_index) i: u32) -> Out {
    return place(instances[draw_indices[i]], position, normal);
}

"#;

/// The depth textures the shadowed shading reads (`--sample-layers`, `--sample-cube`).
const SAMPLER: &str = "@group(0) @binding(4) var compare: sampler_comparison;\n";
const LAYERS: &str = "@group(0) @binding(3) var layers: texture_depth_2d_array;\n";
const CUBE: &str = "@group(0) @binding(5) var cube: texture_depth_cube;\n";

/// Lambert shading darkened by comparison lookups in layer 0 of the depth layers
/// and in the depth cube (as glint's forward pass samples its shadow maps); `LIT`
/// is replaced by the lookups asked for.
const SAMPLED: &str = r#"
@fragment
fn fs_sampled(in: Out) -> @location(0) vec4<f32> {
    let lit = LIT;
    return vec4<f32>(BASE * RADIANCE * lit * max(dot(normalize(in.normal), LIGHT), 0.0), 1.0);
}
"#;

struct Args {
    n: usize,
    frames: usize,
    warmup: usize,
    size: (u32, u32),
    storage: bool,
    all: bool,
    lambert: bool,
    trim_heap: bool,
    depth_layers: u32,
    sample_layers: bool,
    sample_cube: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        n: 10_000,
        frames: 30,
        warmup: 5,
        size: (640, 360),
        storage: false,
        all: false,
        lambert: false,
        trim_heap: false,
        depth_layers: 0,
        sample_layers: false,
        sample_cube: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = || it.next().ok_or(format!("{arg} needs a value"));
        let number = |s: String| s.parse::<usize>().map_err(|_| format!("{arg}: '{s}' is not a count"));
        match arg.as_str() {
            "--n" => a.n = number(value()?)?.clamp(1, 2_000_000),
            "--frames" => a.frames = number(value()?)?.clamp(1, 100_000),
            "--warmup" => a.warmup = number(value()?)?.min(100_000),
            "--size" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or(format!("--size: '{v}' is not WxH"))?;
                let side = |s: &str| s.parse::<u32>().ok().filter(|&x| (1..=8192).contains(&x));
                a.size = side(w).zip(side(h)).ok_or(format!("--size: '{v}' is not WxH within 1..8192"))?;
            }
            "--instances" => match value()?.as_str() {
                "vertex" => a.storage = false,
                "storage" => a.storage = true,
                v => return Err(format!("--instances: '{v}' is not vertex or storage")),
            },
            "--all" => a.all = true,
            "--lambert" => a.lambert = true,
            "--trim-heap" => a.trim_heap = true,
            "--depth-layers" => a.depth_layers = number(value()?)?.min(16) as u32,
            "--sample-layers" => a.sample_layers = true,
            "--sample-cube" => a.sample_cube = true,
            other => return Err(format!("unknown argument {other}")),
        }
    }
    Ok(a)
}

/// The peers' grid: rows, columns, and each cube's centre (2 units apart, centred).
fn grid(n: usize) -> (usize, usize, Vec<Vec3>) {
    let rows = ((n as f64 * 9.0 / 32.0).sqrt().ceil() as usize).max(1);
    let cols = n.div_ceil(rows);
    let at = |i: usize| {
        let (r, c) = ((i / cols) as f32, (i % cols) as f32);
        Vec3::new((c - (cols as f32 - 1.0) / 2.0) * 2.0, 0.0, (r - (rows as f32 - 1.0) / 2.0) * 2.0)
    };
    (rows, cols, (0..n).map(at).collect())
}

/// This process's resident memory, MiB (Linux's `/proc/self/statm`, 4 KiB pages).
fn resident_mib() -> Option<f64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    Some(statm.split_whitespace().nth(1)?.parse::<f64>().ok()? * 4096.0 / (1024.0 * 1024.0))
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((p * (sorted.len() - 1) as f64).round() as usize).min(sorted.len() - 1)]
}

fn main() {
    let args = parse_args().unwrap_or_else(|e| {
        eprintln!("bare_cubes: {e}");
        std::process::exit(2);
    });
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default())).unwrap_or_else(|e| {
            eprintln!("bare_cubes: no adapter: {e}");
            std::process::exit(1);
        });
    let info = adapter.get_info();
    eprintln!("bare_cubes: {} ({:?}, {:?})", info.name, info.backend, info.device_type);
    if info.device_type == wgpu::DeviceType::Cpu && !args.trim_heap {
        glint::gpu::keep_freed_heap_memory();
    }
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
        ..Default::default()
    }))
    .expect("device");

    let (width, height) = args.size;
    let (rows, cols, centres) = grid(args.n);
    let eye_height = rows as f32 / (22.5f32).to_radians().tan();
    let x = -(cols as f32 * 2.0) / 4.0;
    let eye = Vec3::new(x, eye_height, 0.0);
    let view = glam::camera::rh::view::look_at_mat4(eye, Vec3::new(x, 0.0, 0.0), Vec3::NEG_Z);
    let proj = glam::camera::rh::proj::directx::perspective(
        45f32.to_radians(),
        width as f32 / height as f32,
        0.1,
        eye_height * 2.0,
    );
    let view_proj = proj * view;
    let frustum = Frustum::from_view_proj(view_proj);
    let drawn: Vec<u32> = (0..args.n as u32)
        .filter(|&i| args.all || frustum.intersects(Vec3A::from(centres[i as usize]), Vec3A::splat(0.5)))
        .collect();
    // Rows of each cube's object-to-world matrix, in draw order for vertex instances.
    let rows_of = |c: Vec3| [[1.0, 0.0, 0.0, c.x], [0.0, 1.0, 0.0, c.y], [0.0, 0.0, 1.0, c.z]];
    let records: Vec<[[f32; 4]; 3]> = if args.storage {
        centres.iter().map(|&c| rows_of(c)).collect()
    } else {
        drawn.iter().map(|&i| rows_of(centres[i as usize])).collect()
    };

    let cube = glint::asset::procedural::cube();
    let buffer = |label, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
    };
    let vertices = buffer("vertices", bytemuck::cast_slice(cube.vertices()), wgpu::BufferUsages::VERTEX);
    let indices = buffer("indices", bytemuck::cast_slice(cube.indices()), wgpu::BufferUsages::INDEX);
    let usage = if args.storage { wgpu::BufferUsages::STORAGE } else { wgpu::BufferUsages::VERTEX };
    let instances = buffer("instances", bytemuck::cast_slice(&records), usage);
    let draw_indices = buffer("draw indices", bytemuck::cast_slice(&drawn), wgpu::BufferUsages::STORAGE);
    let mut camera = view_proj.to_cols_array().to_vec();
    camera.extend([eye.x, eye.y, eye.z, 1.0]);
    let camera = buffer("camera", bytemuck::cast_slice(&camera), wgpu::BufferUsages::UNIFORM);

    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty,
        count: None,
    };
    let storage_entry = |binding| {
        entry(
            binding,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        )
    };
    let uniform = wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let color_format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let layers_descriptor = |format| wgpu::TextureDescriptor {
        label: Some("depth layers"),
        size: wgpu::Extent3d { width: 1024, height: 1024, depth_or_array_layers: args.depth_layers.max(1) },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    };
    let layers = device.create_texture(&layers_descriptor(depth_format));
    let layers_sampled = layers.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    // What the depth passes bind instead: a texture may not be drawn into and sampled in one pass.
    let stand_in = device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("stand-in depth layer"),
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            ..layers_descriptor(depth_format)
        })
        .create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
    let compare = device.create_sampler(&wgpu::SamplerDescriptor {
        compare: Some(wgpu::CompareFunction::LessEqual),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let cube_view = device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("depth cube"),
            size: wgpu::Extent3d { width: 64, height: 64, depth_or_array_layers: 6 },
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            ..layers_descriptor(depth_format)
        })
        .create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::Cube),
            ..Default::default()
        });
    let mut layout_entries = vec![entry(0, uniform)];
    let mut group_entries = vec![wgpu::BindGroupEntry { binding: 0, resource: camera.as_entire_binding() }];
    if args.storage {
        layout_entries.extend([storage_entry(1), storage_entry(2)]);
        group_entries.extend([
            wgpu::BindGroupEntry { binding: 1, resource: instances.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: draw_indices.as_entire_binding() },
        ]);
    }
    if args.sample_layers || args.sample_cube {
        layout_entries.push(entry(4, wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison)));
        group_entries.push(wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::Sampler(&compare) });
    }
    let depth_entry = |binding, view_dimension| {
        entry(
            binding,
            wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Depth,
                view_dimension,
                multisampled: false,
            },
        )
    };
    if args.sample_layers {
        layout_entries.push(depth_entry(3, wgpu::TextureViewDimension::D2Array));
        group_entries
            .push(wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&layers_sampled) });
    }
    if args.sample_cube {
        layout_entries.push(depth_entry(5, wgpu::TextureViewDimension::Cube));
        group_entries
            .push(wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&cube_view) });
    }
    let group_layout =
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &layout_entries });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &group_layout,
        entries: &group_entries,
    });
    for e in group_entries.iter_mut().filter(|e| e.binding == 3) {
        e.resource = wgpu::BindingResource::TextureView(&stand_in);
    }
    let depth_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &group_layout,
        entries: &group_entries,
    });
    let instancing = if args.storage { STORAGE_INSTANCES } else { VERTEX_INSTANCES };
    let mut lookups = vec!["1.0"];
    let mut declarations = String::new();
    if args.sample_layers || args.sample_cube {
        declarations.push_str(SAMPLER);
    }
    if args.sample_layers {
        declarations.push_str(LAYERS);
        lookups.push("textureSampleCompareLevel(layers, compare, fract(in.world.xz * 0.01), 0, 0.5)");
    }
    if args.sample_cube {
        declarations.push_str(CUBE);
        lookups.push("textureSampleCompareLevel(cube, compare, normalize(in.normal), 0.5)");
    }
    let sampled = if declarations.is_empty() {
        String::new()
    } else {
        declarations + &SAMPLED.replace("LIT", &lookups.join(" * "))
    };
    let source = [COMMON, instancing, &sampled].concat();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("bare_cubes"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&group_layout)],
        immediate_size: 0,
    });
    let vertex_layouts = [
        Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<glint::scene::Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
        }),
        Some(wgpu::VertexBufferLayout {
            array_stride: 48,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &wgpu::vertex_attr_array![4 => Float32x4, 5 => Float32x4, 6 => Float32x4],
        }),
    ];
    let color_targets = [Some(color_format.into())];
    // The colour pipeline, or (for the depth layers) the same vertices depth-only.
    let make_pipeline = |shaded: bool| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("bare_cubes"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: if args.storage { &vertex_layouts[..1] } else { &vertex_layouts },
            },
            primitive: wgpu::PrimitiveState { cull_mode: Some(wgpu::Face::Back), ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: depth_format,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: shaded.then(|| wgpu::FragmentState {
                module: &module,
                entry_point: Some(match (args.sample_layers || args.sample_cube, args.lambert) {
                    (true, _) => "fs_sampled",
                    (false, true) => "fs_lambert",
                    (false, false) => "fs_pbr",
                }),
                compilation_options: Default::default(),
                targets: &color_targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    let pipeline = make_pipeline(true);
    let depth_only = make_pipeline(false);
    let texture = |format, label| {
        device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&Default::default())
    };
    let color = texture(color_format, "color");
    let depth = texture(depth_format, "depth");
    let layer_views: Vec<_> = (0..args.depth_layers)
        .map(|layer| {
            layers.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            })
        })
        .collect();
    let draw_cubes = |pass: &mut wgpu::RenderPass<'_>, pipeline: &wgpu::RenderPipeline, group: &wgpu::BindGroup| {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        if !args.storage {
            pass.set_vertex_buffer(1, instances.slice(..));
        }
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..cube.indices().len() as u32, 0, 0..drawn.len() as u32);
    };

    let mut times = Vec::with_capacity(args.frames);
    let (mut encode_ms, mut submit_ms) = (Vec::with_capacity(args.frames), Vec::with_capacity(args.frames));
    let mut resident_frame_100 = None;
    for frame in 0..args.warmup + args.frames {
        let start = Instant::now();
        let mut encoder = device.create_command_encoder(&Default::default());
        for view in &layer_views {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            draw_cubes(&mut pass, &depth_only, &depth_group);
        }
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.1, g: 0.1, b: 0.12, a: 1.0 }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            draw_cubes(&mut pass, &pipeline, &group);
        }
        let commands = encoder.finish();
        let encoded = start.elapsed();
        queue.submit([commands]);
        let submitted = start.elapsed();
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
        if frame >= args.warmup {
            times.push(start.elapsed().as_secs_f64() * 1e3);
            encode_ms.push(encoded.as_secs_f64() * 1e3);
            submit_ms.push((submitted - encoded).as_secs_f64() * 1e3);
            if times.len() == args.frames.min(100) {
                resident_frame_100 = resident_mib();
            }
        }
    }
    let mib = |m: Option<f64>| m.map_or("null".to_string(), |m| format!("{m:.1}"));
    for v in [&mut times, &mut encode_ms, &mut submit_ms] {
        v.sort_by(f64::total_cmp);
    }
    println!(
        "{{\"program\":\"bare_cubes\",\"instances\":\"{}\",\"n\":{},\"drawn\":{},\"frames\":{},\"ms_median\":{:.3},\"ms_p95\":{:.3},\"cpu_encode_ms_median\":{:.4},\"cpu_submit_ms_median\":{:.4},\"resident_mib_frame_100\":{},\"resident_mib_end\":{}}}",
        if args.storage { "storage" } else { "vertex" },
        args.n,
        drawn.len(),
        args.frames,
        percentile(&times, 0.5),
        percentile(&times, 0.95),
        percentile(&encode_ms, 0.5),
        percentile(&submit_ms, 0.5),
        mib(resident_frame_100),
        mib(resident_mib())
    );
}
