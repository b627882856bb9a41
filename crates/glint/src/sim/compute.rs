//! Bind groups of the simulations' compute shaders: each binds whole buffers
//! in binding order, the first few uniform blocks and the rest read-write
//! storage (the layout every `sim/*.wgsl` declares).

/// A compute layout of `count` buffers: bindings below `uniforms` are uniform
/// blocks (binding `dynamic` with a dynamic offset), the rest storage.
pub(crate) fn layout(
    device: &wgpu::Device,
    label: &str,
    count: u32,
    uniforms: u32,
    dynamic: Option<u32>,
) -> wgpu::BindGroupLayout {
    let entry = |binding: u32| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: match binding < uniforms {
                true => wgpu::BufferBindingType::Uniform,
                false => wgpu::BufferBindingType::Storage { read_only: false },
            },
            has_dynamic_offset: dynamic == Some(binding),
            min_binding_size: None,
        },
        count: None,
    };
    let entries: Vec<_> = (0..count).map(entry).collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

/// A bind group of `resources` in binding order.
pub(crate) fn bind<'a>(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: impl IntoIterator<Item = wgpu::BindingResource<'a>>,
) -> wgpu::BindGroup {
    let entries: Vec<_> = resources
        .into_iter()
        .enumerate()
        .map(|(k, resource)| wgpu::BindGroupEntry { binding: k as u32, resource })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}
