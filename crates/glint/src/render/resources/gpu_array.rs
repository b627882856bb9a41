//! Core layer: [`GpuArray`], an array of records the shaders index by number
//! (instances, draw indices, the material table). Where vertex shaders can read
//! storage buffers it is one; where they cannot (WebGL2, some GLES drivers) it
//! is a data texture, as the vegetation demo stores its instances:
//! [`DATA_TEXTURE_WIDTH`] texels a row, a record taking `bytes / 16` RGBA32Uint
//! texels (or one R32Uint texel for a 4-byte record), record `i` starting at
//! texel `i * texels` in row-major order. `forward.wgsl` reads them back with
//! `textureLoad` (its `DATA_TEXTURES` variant).

use crate::gpu::DriverErrors;
use crate::render::error::RenderError;
use crate::shader::DATA_TEXTURE_WIDTH;

/// A buffer that grows by doubling (its contents are lost when it grows).
pub(crate) struct GrowBuffer {
    pub buffer: wgpu::Buffer,
    label: &'static str,
    usage: wgpu::BufferUsages,
}

impl GrowBuffer {
    pub(crate) fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages, bytes: u64) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(256).next_power_of_two(),
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self { buffer, label, usage }
    }

    /// Make room for `bytes`; returns whether the buffer was replaced.
    ///
    /// Fails, keeping the old buffer, when `bytes` is over the adapter's largest
    /// buffer (or, for a storage buffer, its largest binding), or when the device
    /// cannot allocate it. Growth doubles, but never past that limit.
    pub(crate) fn reserve(&mut self, device: &wgpu::Device, bytes: u64) -> Result<bool, RenderError> {
        if bytes <= self.buffer.size() {
            return Ok(false);
        }
        let limits = device.limits();
        let (limit, limit_name) = if self.usage.contains(wgpu::BufferUsages::STORAGE)
            && limits.max_storage_buffer_binding_size < limits.max_buffer_size
        {
            (limits.max_storage_buffer_binding_size, "the adapter's max_storage_buffer_binding_size")
        } else {
            (limits.max_buffer_size, "the adapter's max_buffer_size")
        };
        if bytes > limit {
            return Err(RenderError::TooLarge { what: self.label, bytes, limit, limit_name });
        }
        let size = bytes.max(256).next_power_of_two().min(limit & !255).max(bytes);
        let scope = DriverErrors::watch(device);
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(self.label),
            size,
            usage: self.usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        if let Some(error) = scope.finish() {
            return Err(RenderError::Device { what: self.label, message: error.to_string() });
        }
        self.buffer = buffer;
        Ok(true)
    }

    /// Write `data` at element `first` (elements of `T`); returns bytes written.
    pub(crate) fn write<T: bytemuck::Pod>(&self, queue: &wgpu::Queue, first: u64, data: &[T]) -> u64 {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if !bytes.is_empty() {
            queue.write_buffer(&self.buffer, first * std::mem::size_of::<T>() as u64, bytes);
        }
        bytes.len() as u64
    }
}

/// An array the shaders read: a storage buffer, or a data texture.
pub(crate) enum GpuArray {
    /// A storage buffer of the records.
    Buffer(GrowBuffer),
    /// A data texture of them.
    Texture(DataTexture),
}

/// The records of a [`GpuArray`] as texels of a 2D texture.
pub(crate) struct DataTexture {
    label: &'static str,
    format: wgpu::TextureFormat,
    /// Bytes of one texel (16 or 4).
    texel_bytes: u32,
    /// Texels of one record.
    texels: u32,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
}

impl GpuArray {
    /// An array of records of `bytes` each with room for `records`: a storage
    /// buffer when `storage`, else a data texture (`bytes` 4 or a multiple of 16).
    pub(crate) fn new(device: &wgpu::Device, label: &'static str, bytes: u32, records: u32, storage: bool) -> Self {
        if storage {
            let size = u64::from(bytes) * u64::from(records);
            // Copied from only to read it back for inspection.
            let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
            return Self::Buffer(GrowBuffer::new(device, label, usage, size));
        }
        debug_assert!(bytes == 4 || bytes % 16 == 0, "{label}: {bytes}-byte records do not fill texels");
        let (format, texel_bytes) =
            if bytes == 4 { (wgpu::TextureFormat::R32Uint, 4) } else { (wgpu::TextureFormat::Rgba32Uint, 16) };
        let texels = bytes / texel_bytes;
        let rows = rows_for(records, texels);
        let (texture, view) = data_texture(device, label, format, rows);
        Self::Texture(DataTexture { label, format, texel_bytes, texels, texture, view })
    }

    /// Make room for `records` records of `bytes` each; returns whether the
    /// array was replaced (its contents are lost: write them all again, and
    /// rebuild the bind groups that hold it). Fails, keeping the old one, past
    /// the adapter's limits or when the device cannot allocate it.
    pub(crate) fn reserve(&mut self, device: &wgpu::Device, bytes: u32, records: usize) -> Result<bool, RenderError> {
        match self {
            Self::Buffer(buffer) => buffer.reserve(device, u64::from(bytes) * records as u64),
            Self::Texture(t) => {
                let records = u32::try_from(records).unwrap_or(u32::MAX);
                let rows = rows_for(records, t.texels);
                if rows <= t.texture.height() {
                    return Ok(false);
                }
                let side = device.limits().max_texture_dimension_2d;
                let grown = rows.next_power_of_two().min(side);
                if rows > side {
                    let bytes = u64::from(rows) * u64::from(DATA_TEXTURE_WIDTH * t.texel_bytes);
                    let limit = u64::from(side) * u64::from(DATA_TEXTURE_WIDTH * t.texel_bytes);
                    let limit_name = "a data texture of the adapter's max_texture_dimension_2d rows";
                    return Err(RenderError::TooLarge { what: t.label, bytes, limit, limit_name });
                }
                let scope = DriverErrors::watch(device);
                let (texture, view) = data_texture(device, t.label, t.format, grown);
                if let Some(error) = scope.finish() {
                    return Err(RenderError::Device { what: t.label, message: error.to_string() });
                }
                (t.texture, t.view) = (texture, view);
                Ok(true)
            }
        }
    }

    /// Write `data` at record `first`; returns bytes written. A data texture
    /// takes at most three writes: the rest of a row, whole rows, and the start of one.
    pub(crate) fn write<T: bytemuck::Pod>(&self, queue: &wgpu::Queue, first: u64, data: &[T]) -> u64 {
        let t = match self {
            Self::Buffer(buffer) => return buffer.write(queue, first, data),
            Self::Texture(t) => t,
        };
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let texel_bytes = t.texel_bytes as usize;
        let mut at = first * u64::from(t.texels);
        let end = at + (bytes.len() / texel_bytes) as u64;
        let width = u64::from(DATA_TEXTURE_WIDTH);
        let mut written = 0;
        while at < end {
            let (row, column) = ((at / width) as u32, (at % width) as u32);
            let left = end - at;
            // Whole rows when at a row's start, else what remains of this row.
            let (w, h) = match column == 0 && left >= width {
                true => (DATA_TEXTURE_WIDTH, (left / width) as u32),
                false => ((left.min(width - u64::from(column))) as u32, 1),
            };
            let count = w as usize * h as usize * texel_bytes;
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &t.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: column, y: row, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                &bytes[written..written + count],
                wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(w * t.texel_bytes), rows_per_image: None },
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            );
            written += count;
            at += u64::from(w) * u64::from(h);
        }
        bytes.len() as u64
    }

    /// The storage buffer, where the array is one.
    pub(crate) fn buffer(&self) -> Option<&wgpu::Buffer> {
        match self {
            Self::Buffer(b) => Some(&b.buffer),
            Self::Texture(_) => None,
        }
    }

    /// The array for a bind group entry.
    pub(crate) fn binding(&self) -> wgpu::BindingResource<'_> {
        match self {
            Self::Buffer(buffer) => buffer.buffer.as_entire_binding(),
            Self::Texture(t) => wgpu::BindingResource::TextureView(&t.view),
        }
    }
}

/// Rows of [`DATA_TEXTURE_WIDTH`] texels that `records` records of `texels` texels fill (at least one).
fn rows_for(records: u32, texels: u32) -> u32 {
    (u64::from(records.max(1)) * u64::from(texels)).div_ceil(u64::from(DATA_TEXTURE_WIDTH)).min(u64::from(u32::MAX))
        as u32
}

fn data_texture(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
    rows: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: DATA_TEXTURE_WIDTH, height: rows, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    (texture, view)
}

/// A bind-group layout entry for a [`GpuArray`] at `binding`, seen by `visibility`.
pub(crate) fn layout_entry(binding: u32, visibility: wgpu::ShaderStages, storage: bool) -> wgpu::BindGroupLayoutEntry {
    let ty = match storage {
        true => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        false => wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
    };
    wgpu::BindGroupLayoutEntry { binding, visibility, ty, count: None }
}
