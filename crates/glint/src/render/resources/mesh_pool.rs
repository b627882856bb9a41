//! Core layer: the mesh pool. Shapes' vertices and indices live in a few large
//! buffers ("pages") instead of a buffer pair each, so draws of different shapes
//! share their vertex and index bindings and can go in one multi-draw-indirect
//! call. A shape on the GPU is a [`MeshRange`]: page, base vertex, first index and
//! index count, and its levels of detail ([`Levels`]): more index ranges right
//! after its own, over the same vertices.
//!
//! A page holds meshes of one [`VertexLayout`], one buffer per vertex stream
//! (the interleaved [`Vertex`](crate::scene::Vertex) stream, plus those of the
//! optional colours, second uv set and skin weights the layout has). Pages grow by doubling, copying their contents on
//! the GPU, up to the device's largest buffer; then a new page starts.
//! Where the renderer computes, the vertex streams are storage buffers too, so
//! a GPU simulation can write a shape's vertices in place ([`VertexTarget`]).

use crate::gpu::VertexTarget;
use crate::render::error::MeshTooLarge;
use crate::render::resources::pipelines::{Stream, VertexLayout};
use crate::scene::levels::{DetailLevel, MAX_LEVELS};
use crate::scene::Mesh;

/// Where a shape's geometry lives in the pool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MeshRange {
    /// Page index: draws on the same page share their buffer bindings.
    pub page: u16,
    /// Added to every index (the mesh's first vertex in the page).
    pub base_vertex: i32,
    /// First index in the page's index buffer.
    pub first_index: u32,
    /// Indices drawn.
    pub index_count: u32,
    /// The shape's levels of detail, this range's among them.
    pub levels: Levels,
}

/// A shape's levels of detail in its page: level 0 is the whole mesh, each
/// further one fewer triangles over the same vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Levels {
    /// Levels, full detail included (1: the shape has no coarser ones).
    pub count: u8,
    /// Each level's first index in the page.
    pub first_index: [u32; MAX_LEVELS],
    /// Each level's index count.
    pub index_count: [u32; MAX_LEVELS],
    /// Each level's error in units of the shape's bounding radius (0 at full detail).
    pub error: [f32; MAX_LEVELS],
}

impl MeshRange {
    /// The range drawing level `level` (the coarsest where the shape has fewer).
    pub(crate) fn level(self, level: usize) -> MeshRange {
        let l = level.min(usize::from(self.levels.count.max(1)) - 1);
        MeshRange { first_index: self.levels.first_index[l], index_count: self.levels.index_count[l], ..self }
    }
}

struct Page {
    layout: VertexLayout,
    /// One buffer per vertex stream of the layout.
    streams: Vec<wgpu::Buffer>,
    indices: wgpu::Buffer,
    vertices_used: u64,
    indices_used: u64,
}

/// All pages.
pub(crate) struct MeshPool {
    pages: Vec<Page>,
    max_bytes: u64,
    /// Whether vertex streams are storage buffers too.
    storage: bool,
}

const FIRST_VERTEX_BYTES: u64 = 1 << 20;
const FIRST_INDEX_BYTES: u64 = 1 << 18;

impl MeshPool {
    /// No pages yet; with `storage`, vertex streams can be written by compute shaders.
    pub(crate) fn new(device: &wgpu::Device, storage: bool) -> Self {
        Self { pages: Vec::new(), max_bytes: device.limits().max_buffer_size.min(1 << 30), storage }
    }

    /// Copy `mesh` and its coarser `levels` into a page of its layout, growing
    /// or starting one as needed. Returns its range and the bytes written.
    pub(crate) fn add(
        &mut self,
        device: &wgpu::Device,
        queue: &crate::gpu::SubmitQueue,
        (mesh, levels): (&Mesh, &[DetailLevel]),
    ) -> Result<(MeshRange, u64), MeshTooLarge> {
        let layout = VertexLayout::of(mesh);
        let streams: Vec<&[u8]> = layout.streams().map(|s| s.bytes(mesh)).collect();
        let vertex_count = mesh.vertices().len() as u64;
        let levels = &levels[..levels.len().min(MAX_LEVELS - 1)];
        let all_indices: Vec<u32> =
            mesh.indices().iter().chain(levels.iter().flat_map(|l| &l.indices)).copied().collect();
        let index_bytes: u64 = (all_indices.len() * 4) as u64;
        let largest = streams.iter().map(|s| s.len() as u64).chain([index_bytes]).max().unwrap_or(0);
        if largest > self.max_bytes {
            return Err(MeshTooLarge { bytes: largest, max: self.max_bytes });
        }
        let fits = |p: &Page| {
            p.layout == layout
                && (p.vertices_used + vertex_count) * u64::from(Stream::Base.stride()) <= self.max_bytes
                && p.indices_used * 4 + index_bytes <= self.max_bytes
        };
        let index_count = all_indices.len() as u64;
        let index = match self.pages.iter().position(fits) {
            Some(i) => i,
            None => {
                let sizes = (vertex_count, index_count, self.max_bytes);
                let page = Page::new(device, (layout, self.storage), self.pages.len(), sizes);
                self.pages.push(page);
                self.pages.len() - 1
            }
        };
        let page = &mut self.pages[index];
        let (vertices, indices) = (page.vertices_used + vertex_count, page.indices_used + index_count);
        page.reserve((device, queue), self.storage, index, (vertices, indices, self.max_bytes));
        for ((buffer, bytes), stream) in page.streams.iter().zip(&streams).zip(layout.streams()) {
            queue.write_buffer(buffer, page.vertices_used * u64::from(stream.stride()), bytes);
        }
        queue.write_buffer(&page.indices, page.indices_used * 4, bytemuck::cast_slice(&all_indices));
        let first_index = page.indices_used as u32;
        let mut ranges = Levels { count: 1 + levels.len() as u8, ..Levels::default() };
        let (mut at, counts) =
            (first_index, std::iter::once(mesh.indices().len()).chain(levels.iter().map(|l| l.indices.len())));
        for (l, count) in counts.enumerate() {
            (ranges.first_index[l], ranges.index_count[l]) = (at, count as u32);
            at += count as u32;
        }
        for (l, level) in levels.iter().enumerate() {
            ranges.error[l + 1] = level.error;
        }
        let range = MeshRange {
            page: index as u16,
            base_vertex: page.vertices_used as i32,
            first_index,
            index_count: mesh.indices().len() as u32,
            levels: ranges,
        };
        page.vertices_used += vertex_count;
        page.indices_used += index_count;
        let written = streams.iter().map(|s| s.len() as u64).sum::<u64>() + index_bytes;
        Ok((range, written))
    }

    /// Write `mesh`'s base vertex stream over the shape at `range`, which holds a
    /// mesh of the same layout and vertex count (positions and normals changed,
    /// e.g. by morph targets). Returns the bytes written.
    pub(crate) fn rewrite_vertices(&self, queue: &wgpu::Queue, range: MeshRange, mesh: &Mesh) -> u64 {
        let page = &self.pages[range.page as usize];
        let bytes = Stream::Base.bytes(mesh);
        queue.write_buffer(&page.streams[0], range.base_vertex as u64 * u64::from(Stream::Base.stride()), bytes);
        bytes.len() as u64
    }

    /// Where the shape at `range` (of `vertices` vertices) has its base vertex
    /// stream; `None` where vertex streams are not storage buffers.
    pub(crate) fn vertex_target(&self, range: MeshRange, vertices: u32) -> Option<VertexTarget<'_>> {
        let page = self.pages.get(range.page as usize).filter(|_| self.storage)?;
        Some(VertexTarget { buffer: &page.streams[0], first: range.base_vertex as u32, count: vertices })
    }

    /// Bind page `page`'s vertex streams and index buffer.
    pub(crate) fn bind(&self, pass: &mut wgpu::RenderPass<'_>, page: u16) {
        self.bind_from(pass, page, 0);
    }

    /// Bind page `page`'s buffers with the vertex streams starting at vertex
    /// `first`, for devices whose indexed draws take no base vertex (WebGL2):
    /// a mesh's draw then gives base vertex 0.
    pub(crate) fn bind_from(&self, pass: &mut wgpu::RenderPass<'_>, page: u16, first: u64) {
        let page = &self.pages[page as usize];
        // Only the filled part: the rest was never written.
        for ((slot, buffer), stream) in page.streams.iter().enumerate().zip(page.layout.streams()) {
            let stride = u64::from(stream.stride());
            pass.set_vertex_buffer(slot as u32, buffer.slice(first * stride..page.vertices_used * stride));
        }
        pass.set_index_buffer(page.indices.slice(..page.indices_used * 4), wgpu::IndexFormat::Uint32);
    }
}

impl Page {
    /// A page with room for at least `vertices` and `indices` (at most `max`
    /// bytes a buffer), its vertex streams storage buffers too with `storage`.
    fn new(
        device: &wgpu::Device,
        (layout, storage): (VertexLayout, bool),
        index: usize,
        (vertices, indices, max): (u64, u64, u64),
    ) -> Self {
        let buffer = |label: String, bytes: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&label),
                size: bytes,
                usage: usage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let streams = layout
            .streams()
            .enumerate()
            .map(|(s, stream)| {
                let bytes =
                    (vertices * u64::from(stream.stride())).max(FIRST_VERTEX_BYTES).next_power_of_two().min(max);
                let usage = match storage {
                    true => wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
                    false => wgpu::BufferUsages::VERTEX,
                };
                buffer(format!("mesh pool: page {index} ({layout:?}) stream {s}"), bytes, usage)
            })
            .collect();
        let indices = buffer(
            format!("mesh pool: page {index} indices"),
            (indices * 4).max(FIRST_INDEX_BYTES).next_power_of_two().min(max),
            wgpu::BufferUsages::INDEX,
        );
        Self { layout, streams, indices, vertices_used: 0, indices_used: 0 }
    }

    /// Grow the buffers (doubling, at most `max` bytes each) to hold `vertices` and
    /// `indices` in all, copying what they hold on the GPU.
    fn reserve(
        &mut self,
        (device, queue): (&wgpu::Device, &crate::gpu::SubmitQueue),
        storage: bool,
        index: usize,
        (vertices, indices, max): (u64, u64, u64),
    ) {
        let stride = u64::from(Stream::Base.stride());
        if vertices * stride <= self.streams[0].size() && indices * 4 <= self.indices.size() {
            return;
        }
        let mut grown = Page::new(device, (self.layout, storage), index, (vertices, indices, max));
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("mesh pool: grow page") });
        for ((old, new), stream) in self.streams.iter().zip(&grown.streams).zip(self.layout.streams()) {
            encoder.copy_buffer_to_buffer(old, 0, new, 0, Some(self.vertices_used * u64::from(stream.stride())));
        }
        encoder.copy_buffer_to_buffer(&self.indices, 0, &grown.indices, 0, Some(self.indices_used * 4));
        queue.submit([encoder.finish()]);
        grown.vertices_used = self.vertices_used;
        grown.indices_used = self.indices_used;
        *self = grown;
    }
}
