//! Core layer: [`Gpu`], the device, queue and what the adapter can do
//! (compute, vertex storage, MSAA, timestamps), headless or for a window; and
//! [`GpuError`].

use std::fmt;
use std::sync::Arc;

/// What a window must provide for [`Gpu::for_window`]: window and display
/// handles, shareable across threads (a `winit::window::Window` qualifies).
pub trait WindowHandles:
    wgpu::rwh::HasWindowHandle + wgpu::rwh::HasDisplayHandle + fmt::Debug + Send + Sync + 'static
{
}

impl<T: wgpu::rwh::HasWindowHandle + wgpu::rwh::HasDisplayHandle + fmt::Debug + Send + Sync + 'static> WindowHandles
    for T
{
}

/// Errors from creating the GPU context or a target.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter matched the requested backends (and name, if any).
    #[error("no GPU adapter found{0}; {fix}", fix = no_adapter_fix())]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("could not create a GPU device on '{adapter}': {source}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// What wgpu said.
        source: wgpu::RequestDeviceError,
    },
    /// A target size was zero or beyond the device limits.
    #[error("target size {width}x{height} is not supported (1..={max} per side)")]
    TargetSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Largest side the device allows.
        max: u32,
    },
    /// The sample count is not 1 or 4, or the adapter cannot do it.
    #[error("MSAA sample count {0} is not supported here (use 1 or 4)")]
    SampleCount(u32),
    /// The window's surface could not be created or has no format to show frames in.
    #[error("cannot show frames in the window: {0}")]
    Surface(String),
    /// The device failed: out of memory, or an error no scope caught.
    #[error("{0}")]
    Failed(String),
    /// Reading a frame back from the GPU failed.
    #[error("reading the frame back failed: {0}")]
    Readback(String),
    /// Writing a PNG failed.
    #[error("{path}: cannot write PNG: {source}")]
    Png {
        /// Output path.
        path: String,
        /// What the encoder said.
        source: image::ImageError,
    },
}

fn no_adapter_fix() -> &'static str {
    if cfg!(target_os = "linux") {
        "install a Vulkan driver (for a CPU rasterizer: apt-get install mesa-vulkan-drivers)"
    } else {
        "install or update the GPU driver"
    }
}

/// The GPU context: instance, adapter, device and queue, plus the capabilities
/// glint cares about. Create one per process and share it by reference.
pub struct Gpu {
    /// The adapter the device was created on.
    pub adapter: wgpu::Adapter,
    /// The logical device.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    anisotropy: u16,
    /// How the renderer may feed its shaders here.
    paths: DrawPaths,
    /// Errors no scope caught, kept instead of panicking.
    uncaptured: super::errors::UncapturedErrors,
}

/// Storage buffers the GPU culling pass binds in one compute stage.
const CULL_STORAGE_BUFFERS: u32 = 8;

/// What the renderer's draws may rely on, from the adapter's capabilities
/// ([`Gpu::with_webgl2_limits`] turns them all off but half-float blending,
/// which WebGL2 has with `EXT_float_blend`).
#[derive(Clone, Copy, Debug)]
struct DrawPaths {
    /// Vertex shaders read storage buffers (else data textures).
    vertex_storage: bool,
    /// Indexed draws take a base vertex (else vertex buffers are bound at each mesh).
    base_vertex: bool,
    /// Multi-draw-indirect with a first instance.
    indirect: bool,
    /// Compute passes that cull instances into the indirect commands.
    gpu_cull: bool,
    /// Those passes occlusion-cull too: a depth pyramid in a storage texture.
    occlusion: bool,
    /// Fragment shaders append to storage buffers, after the depth test
    /// (exact transparency's per-pixel lists).
    fragment_lists: bool,
    /// Half-float colour targets blend (weighted transparency's sums).
    blends_half_floats: bool,
}

impl fmt::Debug for Gpu {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Gpu({} on {:?})", self.info.name, self.info.backend)
    }
}

impl Gpu {
    /// Create a headless context on the best adapter.
    ///
    /// Honours `WGPU_BACKEND` (e.g. `vulkan`, `gl`) to choose backends and
    /// `WGPU_ADAPTER_NAME` (a case-insensitive substring) to choose an adapter.
    /// Returns [`GpuError::NoAdapter`] with the fix when nothing matches.
    pub fn headless() -> Result<Self, GpuError> {
        Self::create(None, None).map(|(gpu, _)| gpu)
    }

    /// Create a headless context on the best adapter of `backends` only (for
    /// example `wgpu::Backends::GL`), whatever `WGPU_BACKEND` says.
    pub fn headless_on(backends: wgpu::Backends) -> Result<Self, GpuError> {
        Self::create(None, Some(backends)).map(|(gpu, _)| gpu)
    }

    /// Create a context whose adapter can present to `window`, and the window's
    /// surface (give it to [`WindowSurface::new`](super::WindowSurface::new)).
    /// Chooses backends and adapters as [`Gpu::headless`] does.
    pub fn for_window(window: Arc<dyn WindowHandles>) -> Result<(Self, wgpu::Surface<'static>), GpuError> {
        match Self::create(Some(window), None)? {
            (gpu, Some(surface)) => Ok((gpu, surface)),
            (_, None) => Err(GpuError::Surface("no surface was made for the window".into())),
        }
    }

    /// The context, on an adapter of `only` (else of `WGPU_BACKEND`'s backends)
    /// that can present to `window` when there is one.
    fn create(
        window: Option<Arc<dyn WindowHandles>>,
        only: Option<wgpu::Backends>,
    ) -> Result<(Self, Option<wgpu::Surface<'static>>), GpuError> {
        let chosen = only.or_else(wgpu::Backends::from_env);
        // Without WGPU_BACKEND, try the native APIs first and reach for GL only
        // when they have no adapter: probing EGL logs errors on machines without it.
        let attempts = match chosen {
            Some(backends) => vec![backends],
            None => vec![wgpu::Backends::PRIMARY, wgpu::Backends::all()],
        };
        let mut last = None;
        for backends in attempts {
            let mut desc = match &window {
                Some(w) => wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(w.clone())),
                None => wgpu::InstanceDescriptor::new_without_display_handle_from_env(),
            };
            desc.backends = backends;
            // The renderer's indirect commands are made from its own validated data, so
            // wgpu's per-frame check of them is pure overhead (about 20 µs a frame on
            // lavapipe). Off the D3D12 backend only: there the check also supplies
            // `first_instance` to shaders. WGPU_VALIDATION_INDIRECT_CALL=1 turns it on.
            if !cfg!(windows) && std::env::var_os("WGPU_VALIDATION_INDIRECT_CALL").is_none() {
                desc.flags.remove(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL);
            }
            let instance = wgpu::Instance::new(desc);
            let surface = match &window {
                Some(w) => Some(instance.create_surface(w.clone()).map_err(|e| GpuError::Surface(e.to_string()))?),
                None => None,
            };
            match pollster::block_on(choose_adapter(&instance, backends, surface.as_ref())) {
                Ok(adapter) => return Ok((Self::from_adapter(adapter)?, surface)),
                Err(e) => last = Some(e),
            }
        }
        Err(last.unwrap_or_else(|| GpuError::NoAdapter(String::new())))
    }

    /// Create the device and queue on a chosen adapter.
    pub fn from_adapter(adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        pollster::block_on(Self::on_adapter(adapter, false))
    }

    /// [`Gpu::from_adapter`] without blocking, for the browser (where nothing
    /// may block the page's thread).
    pub async fn from_adapter_async(adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        Self::on_adapter(adapter, false).await
    }

    /// A new context on this one's adapter that draws as it must on WebGL2,
    /// whatever the adapter can do: a device with WebGL2's limits (no storage
    /// buffers at all), instance and material data in data textures, vertex
    /// buffers bound at each mesh, one draw call per batch. For testing that
    /// path natively.
    pub fn with_webgl2_limits(self) -> Result<Self, GpuError> {
        pollster::block_on(Self::on_adapter(self.adapter, true))
    }

    /// The device and queue on `adapter`, with WebGL2's limits and draw paths
    /// where the adapter needs them or `webgl2` asks for them.
    async fn on_adapter(adapter: wgpu::Adapter, webgl2: bool) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let features = adapter.features();
        // Vertex shaders read every instance's record from a storage buffer
        // where they can; WebGL2 and some GLES drivers have none there, and get
        // data textures and WebGL2's limits instead.
        let flags = adapter.get_downlevel_capabilities().flags;
        let vertex_storage = !webgl2
            && flags.contains(wgpu::DownlevelFlags::VERTEX_STORAGE)
            && adapter.limits().max_storage_buffers_per_shader_stage >= 3;
        // GPU culling: compute passes writing indirect commands, which GL's
        // backend runs without the checks glint relies on, and eight storage
        // buffers in a compute stage (WebGPU's default).
        let gpu_cull = vertex_storage
            && info.backend != wgpu::Backend::Gl
            && flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
            && adapter.limits().max_storage_buffers_per_shader_stage >= CULL_STORAGE_BUFFERS;
        let limits = match vertex_storage {
            true => wgpu::Limits {
                max_storage_buffers_per_shader_stage: match gpu_cull {
                    true => CULL_STORAGE_BUFFERS,
                    false => wgpu::Limits::downlevel_defaults().max_storage_buffers_per_shader_stage,
                },
                ..wgpu::Limits::downlevel_defaults()
            },
            false => wgpu::Limits::downlevel_webgl2_defaults(),
        };
        let desc = wgpu::DeviceDescriptor {
            label: Some("glint device"),
            // Timestamps let benchmarks report GPU time; a first instance in indirect
            // commands lets batches share one multi-draw-indirect call; a count
            // buffer lets GPU culling skip the commands it emptied.
            required_features: features
                & (wgpu::Features::TIMESTAMP_QUERY
                    | wgpu::Features::INDIRECT_FIRST_INSTANCE
                    | wgpu::Features::MULTI_DRAW_INDIRECT_COUNT
                    | wgpu::Features::SHADER_EARLY_DEPTH_TEST),
            required_limits: limits.using_resolution(adapter.limits()),
            ..Default::default()
        };
        let (device, queue) = (adapter.request_device(&desc).await)
            .map_err(|source| GpuError::Device { adapter: info.name.clone(), source })?;
        let uncaptured = super::errors::UncapturedErrors::install(&device);
        if info.device_type == wgpu::DeviceType::Cpu {
            super::keep_freed_heap_memory();
        }
        let anisotropy = if flags.contains(wgpu::DownlevelFlags::ANISOTROPIC_FILTERING) { 16 } else { 1 };
        log::info!(
            "glint: adapter '{}' ({:?}, {:?}); features {:?}",
            info.name,
            info.backend,
            info.device_type,
            features
        );
        let indirect = device.features().contains(wgpu::Features::INDIRECT_FIRST_INSTANCE)
            && flags.contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION);
        let base_vertex = !webgl2 && flags.contains(wgpu::DownlevelFlags::BASE_VERTEX);
        // Indirect commands carry base vertices.
        let indirect = indirect && base_vertex;
        let gpu_cull = gpu_cull && indirect;
        let r32_storage = adapter.get_texture_format_features(wgpu::TextureFormat::R32Float).allowed_usages;
        let occlusion = gpu_cull
            && device.limits().max_storage_textures_per_shader_stage >= 1
            && r32_storage.contains(wgpu::TextureUsages::STORAGE_BINDING);
        if gpu_cull && !occlusion {
            log::warn!(
                "glint: '{}' has no storage textures for a depth pyramid: GPU culling without occlusion",
                info.name
            );
        }
        // Exact transparency's fragments: the materials, light clusters,
        // list heads and nodes are four storage buffers in a fragment stage,
        // the colour packed into half floats.
        let fragment_lists = vertex_storage
            && flags
                .contains(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE | wgpu::DownlevelFlags::SHADER_F16_IN_F32)
            && device.features().contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST)
            && device.limits().max_storage_buffers_per_shader_stage >= 4;
        let blendable = |format| {
            let flags = adapter.get_texture_format_features(format).flags;
            flags.contains(wgpu::TextureFormatFeatureFlags::BLENDABLE)
        };
        let blends_half_floats =
            blendable(wgpu::TextureFormat::Rgba16Float) && blendable(wgpu::TextureFormat::R16Float);
        let paths = DrawPaths {
            vertex_storage,
            base_vertex,
            indirect,
            gpu_cull,
            occlusion,
            fragment_lists,
            blends_half_floats,
        };
        Ok(Self { adapter, device, queue, info, anisotropy, paths, uncaptured })
    }

    /// The first error the device reported outside glint's error scopes since
    /// the last call (out of memory, say), as [`GpuError::Failed`]; `Ok` when none.
    pub fn check(&self) -> Result<(), GpuError> {
        self.uncaptured.take().map_or(Ok(()), |m| Err(GpuError::Failed(m)))
    }

    /// Wait until the GPU has finished everything submitted so far.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device.poll(wgpu::PollType::wait_indefinitely()).map(drop).map_err(|e| GpuError::Readback(e.to_string()))
    }

    /// The bytes of `buffer` (which allows `COPY_SRC`), waiting for the GPU.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        read_buffer(&self.device, &self.queue, buffer)
    }

    /// The handle the renderer checks after each frame.
    pub(crate) fn uncaptured(&self) -> super::errors::UncapturedErrors {
        self.uncaptured.clone()
    }

    /// Whether command encoders take debug groups. Not lavapipe before Mesa 23
    /// on Vulkan: 22.3.6 crashes in `vkCmdBeginDebugUtilsLabelEXT` once a
    /// command buffer holds two groups (one alone is fine; GL's llvmpipe takes
    /// them all).
    pub fn debug_groups(&self) -> bool {
        let info = &self.info;
        let mesa = info.driver_info.strip_prefix("Mesa ").and_then(|v| v.split('.').next()?.parse::<u32>().ok());
        let old_lavapipe = info.backend == wgpu::Backend::Vulkan && info.driver == "llvmpipe";
        !(old_lavapipe && mesa.is_some_and(|major| major < 23))
    }

    /// Adapter name, backend and driver, for logs and benchmark reports.
    pub fn info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// Whether a colour target can be multisampled with `samples` samples.
    pub fn supports_msaa(&self, samples: u32) -> bool {
        samples == 1
            || self.adapter.get_texture_format_features(super::COLOR_FORMAT).flags.sample_count_supported(samples)
    }

    /// Whether the device draws from indirect commands with a first instance, so
    /// the renderer can merge batches into multi-draw-indirect calls.
    pub fn draws_indirect(&self) -> bool {
        self.paths.indirect
    }

    /// Whether views can cull on the GPU ([`Culling::Gpu`](crate::Culling::Gpu)):
    /// compute shaders, indirect drawing and storage buffers, and not GL's
    /// backend. Elsewhere such views cull on the CPU.
    pub fn culls_on_gpu(&self) -> bool {
        self.paths.gpu_cull
    }

    /// Whether views culled on the GPU are occlusion-culled too (two phases
    /// with a depth pyramid): where the device has storage textures.
    pub fn occlusion_culls(&self) -> bool {
        self.paths.occlusion
    }

    /// Whether vertex shaders read instances and materials from storage
    /// buffers; where not (WebGL2, some GLES drivers) they read data textures.
    pub fn vertex_storage(&self) -> bool {
        self.paths.vertex_storage
    }

    /// Whether indexed draws take a base vertex; where not (WebGL2), each
    /// draw binds its mesh's vertex buffers at the mesh.
    pub fn base_vertex(&self) -> bool {
        self.paths.base_vertex
    }

    /// Whether fragment shaders can append to per-pixel lists in storage
    /// buffers, after the depth test: exact transparency
    /// ([`Transparency::Exact`](crate::scene::Transparency::Exact)) needs it
    /// (Vulkan and GL; not the WebGL2 path).
    pub fn fragment_lists(&self) -> bool {
        self.paths.fragment_lists
    }

    /// Whether half-float colour targets can be blended: weighted
    /// transparency ([`Transparency::Weighted`](crate::scene::Transparency::Weighted))
    /// needs it (WebGL2 with `EXT_float_blend`); elsewhere views stay sorted.
    pub fn blends_half_floats(&self) -> bool {
        self.paths.blends_half_floats
    }

    /// Largest anisotropy the samplers use (1 when unsupported).
    pub fn max_anisotropy(&self) -> u16 {
        self.anisotropy
    }
}

/// Pick the adapter: the first whose name contains `WGPU_ADAPTER_NAME` when set,
/// else the high-performance default.
async fn choose_adapter(
    instance: &wgpu::Instance,
    backends: wgpu::Backends,
    surface: Option<&wgpu::Surface<'_>>,
) -> Result<wgpu::Adapter, GpuError> {
    if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
        let wanted = wanted.to_lowercase();
        let mut adapters = instance.enumerate_adapters(backends).await;
        adapters.retain(|a| surface.is_none_or(|s| a.is_surface_supported(s)));
        let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        return adapters
            .into_iter()
            .find(|a| a.get_info().name.to_lowercase().contains(&wanted))
            .ok_or_else(|| GpuError::NoAdapter(format!(" named like WGPU_ADAPTER_NAME='{wanted}' (have: {names:?})")));
    }
    let options = wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::from_env().unwrap_or(wgpu::PowerPreference::HighPerformance),
        compatible_surface: surface,
        ..Default::default()
    };
    instance
        .request_adapter(&options)
        .await
        .map_err(|e| GpuError::NoAdapter(format!(" for backends {backends:?} ({e})")))
}

/// The bytes of each of `buffers`, as the GPU holds them once its work so
/// far is done.
pub(crate) fn read_buffers(
    (device, queue): (&wgpu::Device, &wgpu::Queue),
    buffers: &[&wgpu::Buffer],
) -> Result<Vec<Vec<u8>>, GpuError> {
    buffers.iter().map(|b| read_buffer(device, queue, b)).collect()
}

/// Write each `(buffer, bytes, what)`'s bytes over the whole of its buffer,
/// when every one is its buffer's size (else none is written, and the error
/// names `what`).
pub(crate) fn refill(queue: &wgpu::Queue, writes: &[(&wgpu::Buffer, &[u8], &str)]) -> Result<(), String> {
    for (buffer, bytes, what) in writes {
        if bytes.len() as u64 != buffer.size() {
            return Err(format!("{} bytes of {what}, where the simulation holds {}", bytes.len(), buffer.size()));
        }
    }
    writes.iter().for_each(|(buffer, bytes, _)| queue.write_buffer(buffer, 0, bytes));
    Ok(())
}

/// The bytes of `buffer` (which allows `COPY_SRC`), copied to a mapped buffer
/// and read once the GPU is done.
pub(crate) fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u8>, GpuError> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    queue.submit([encoder.finish()]);
    let (sender, receiver) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| drop(sender.send(r)));
    let failed = |e: &dyn std::fmt::Display| GpuError::Readback(e.to_string());
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| failed(&e))?;
    receiver.recv().map_err(|e| failed(&e))?.map_err(|e| failed(&e))?;
    let bytes = staging.get_mapped_range(..).map_err(|e| failed(&e))?.to_vec();
    Ok(bytes)
}
