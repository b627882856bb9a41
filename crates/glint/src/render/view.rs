//! Core layer: [`ViewFrame`], what the frame's stages read of one
//! [`View`].

use crate::render::cull::Frustum;
use crate::render::frame::input::SubFrame;
use crate::render::frame_variant::FrameVariant;
use crate::render::lod::LodView;
use crate::scene::{AmbientOcclusion, Camera, Culling, TextureId, View};
use glam::Mat4;

/// A view's camera matrices for one frame at its aspect ratio: what culling,
/// queueing and the Camera block read.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ViewFrame {
    /// The camera.
    pub camera: Camera,
    /// That rectangle's size in pixels.
    pub size: [u32; 2],
    /// World to view.
    pub view: Mat4,
    /// View to clip: the camera's projection, moved by the sub-frame's jitter.
    pub projection: Mat4,
    /// Which sub-frame of an accumulated still it is drawn for.
    pub sample: SubFrame,
    /// Its frustum in world space.
    pub frustum: Frustum,
    /// How it culls: [`Culling::Gpu`] only where the device can.
    pub culling: Culling,
    /// Its screen-space ambient occlusion, its values clamped into range.
    pub ambient_occlusion: Option<AmbientOcclusion>,
    /// Its own render target's texture, which the entities it draws must not show.
    pub hides: Option<TextureId>,
    /// What it adds to its forward shader variants.
    pub variant: FrameVariant,
    /// How it picks levels of detail.
    pub lod: LodView,
    /// The pixels of error its levels of detail may make (0: full detail).
    pub lod_error: f32,
    /// How it asks to blend transparent surfaces (what it gets depends on
    /// the device: `passes/transparency.rs`).
    pub transparency: crate::scene::Transparency,
    /// Where far fields are measured from: its camera's eye, `None` with
    /// levels of detail off ([`FarField`](crate::scene::FarField)).
    pub far_eye: Option<glam::Vec3>,
}

impl ViewFrame {
    /// `view` drawn into a rectangle `width` × `height` pixels, by a renderer
    /// that can cull on the GPU when `gpu_cull` and draws levels of detail
    /// (and far fields, and their cross-fade) when `levels_of_detail`, leaving
    /// out the entities that show `hides`, with the forward variant `variant`,
    /// as sub-frame `sample` (its camera moved by [`SubFrame::jitter`]'s
    /// fraction of a pixel; culling and levels of detail see it moved too).
    pub fn new(
        view: &View,
        (width, height): (u32, u32),
        (gpu_cull, levels_of_detail, hides, variant): (bool, bool, Option<TextureId>, FrameVariant),
        sample: SubFrame,
    ) -> Self {
        let aspect = width as f32 / height.max(1) as f32;
        let camera = view.camera;
        let matrix = camera.view();
        // A pixel is 2 / width of clip space; clip y points up where pixels count down.
        let jitter = sample.jitter() * glam::Vec2::new(2.0 / width.max(1) as f32, -2.0 / height.max(1) as f32);
        let projection = Mat4::from_translation(jitter.extend(0.0)) * camera.projection(aspect);
        let view_proj = projection * matrix;
        let frustum = Frustum::from_view_proj(view_proj);
        let lod_error = if levels_of_detail { view.lod_error } else { 0.0 };
        let lod = LodView::new(view_proj, height, lod_error);
        let culling = match view.culling {
            Culling::Gpu if !gpu_cull => Culling::Cpu,
            culling => culling,
        };
        let ambient_occlusion = view.ambient_occlusion.map(AmbientOcclusion::clamped);
        Self {
            camera,
            size: [width, height],
            view: matrix,
            projection,
            sample,
            frustum,
            culling,
            ambient_occlusion,
            hides,
            variant: variant.with_lod_fade(lod_error > 0.0),
            lod,
            lod_error,
            far_eye: (lod_error > 0.0).then_some(camera.eye),
            transparency: view.transparency,
        }
    }
}
