//! [`View`], one camera's part of a frame: the camera, the rectangle of the
//! target it draws into ([`Viewport`]) and its options. Plain data: a frame
//! draws one or more views ([`Renderer::render_frame`](crate::Renderer::render_frame)),
//! each culled and drawn on its own.

use super::{Camera, PostEffect, RenderTargetId};

/// A rectangle of a target as fractions of its width and height, from its top
/// left corner: `x`, `y` at least 0, `x + width` and `y + height` at most 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left edge.
    pub x: f32,
    /// Top edge.
    pub y: f32,
    /// Width.
    pub width: f32,
    /// Height.
    pub height: f32,
}

impl Viewport {
    /// The whole target.
    pub const FULL: Self = Self { x: 0.0, y: 0.0, width: 1.0, height: 1.0 };

    /// Whether this is a non-empty rectangle inside the target (0..1 on both axes).
    pub fn is_valid(&self) -> bool {
        let inside = |start: f32, size: f32| start >= 0.0 && size > 0.0 && start + size <= 1.0 + 1e-6;
        inside(self.x, self.width) && inside(self.y, self.height)
    }

    /// The rectangle in pixels of a `width` × `height` target: (x, y, width,
    /// height), edges rounded to the nearest pixel, at least one pixel a side.
    /// Neighbouring viewports that share an edge share its pixel boundary.
    pub fn pixels(&self, width: u32, height: u32) -> [u32; 4] {
        let edge = |f: f32, size: u32| ((f.clamp(0.0, 1.0) * size as f32).round() as u32).min(size);
        let (x0, y0) = (edge(self.x, width), edge(self.y, height));
        let (x1, y1) = (edge(self.x + self.width, width), edge(self.y + self.height, height));
        let (x0, y0) = (x0.min(width.saturating_sub(1)), y0.min(height.saturating_sub(1)));
        [x0, y0, x1.max(x0 + 1) - x0, y1.max(y0 + 1) - y0]
    }
}

impl Default for Viewport {
    fn default() -> Self {
        Self::FULL
    }
}

/// How a view decides which instances to draw (`--cull` in the CLI, the
/// camera key `cull` in `.scn`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Culling {
    /// Draw every instance: to compare costs.
    Off,
    /// Frustum culling on the CPU: each entity's world box, then each
    /// 64-instance tile's, then each instance's where a tile crosses a plane.
    Cpu,
    /// Frustum culling on the GPU: a compute pass tests every instance and
    /// writes the instance counts of the view's indirect draws. Blended
    /// instances, which are sorted far to near on the CPU, are culled there.
    /// Where the adapter cannot (no compute or indirect drawing: GL, WebGL2),
    /// the view takes [`Culling::Cpu`]'s path and its statistics say so.
    #[default]
    Gpu,
}

impl Culling {
    /// Every way, in order.
    pub const ALL: [Self; 3] = [Self::Off, Self::Cpu, Self::Gpu];
    /// Their names in the CLI and `.scn` files, in the same order.
    pub const NAMES: [&'static str; 3] = ["off", "cpu", "gpu"];

    /// The way named `name` (one of [`Culling::NAMES`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::NAMES.iter().position(|n| *n == name).map(|k| Self::ALL[k])
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// What it did, for a status line: "culled on the GPU", "culled on the CPU" or "not culled".
    pub fn describe(self) -> &'static str {
        ["not culled", "culled on the CPU", "culled on the GPU"][self as usize]
    }
}

/// How a view blends its transparent surfaces: blended materials
/// ([`AlphaMode::Blend`](crate::scene::AlphaMode::Blend) with alpha blending)
/// and alpha-blended particle layers (the world key `transparency` in `.scn`,
/// `--transparency` in the CLI; `render/passes/transparency.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Transparency {
    /// Sorted far to near, per instance (particles per layer), and blended
    /// in that order: exact where surfaces do not cross, wrong where they do.
    /// The default: on every backend, and the cheapest where nothing crosses.
    /// The naive baseline ([`FrameMode::Naive`](crate::render::FrameMode::Naive))
    /// always draws so.
    #[default]
    Sorted,
    /// Weighted blended order-independent transparency (McGuire and Bavoil
    /// 2013): drawn in any order into sums of weighted colour and coverage,
    /// then composited; the same picture in any order, an approximation
    /// where layers differ much in colour. Needs blendable half-float
    /// targets; where the adapter has none the view stays sorted.
    Weighted,
    /// The reference: every transparent fragment kept in its pixel's list
    /// and blended in depth order (the nearest 32 of a pixel's fragments).
    /// Under MSAA the lists take one sample a pixel (sample 0's), so
    /// transparent silhouettes are not antialiased. Needs storage buffers in
    /// fragment shaders (Vulkan, GL): on the WebGL2 path and in browsers the
    /// frame is refused with an error.
    Exact,
}

impl Transparency {
    /// Every way, in order.
    pub const ALL: [Self; 3] = [Self::Sorted, Self::Weighted, Self::Exact];
    /// Their names in the CLI and `.scn` files, in the same order.
    pub const NAMES: [&'static str; 3] = ["sorted", "weighted", "exact"];

    /// The way named `name` (one of [`Transparency::NAMES`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::NAMES.iter().position(|n| *n == name).map(|k| Self::ALL[k])
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// Screen-space ambient occlusion of a view (camera key `ssao`): the contact
/// shadows an environment cannot give, darkening only ambient and environment
/// light (`render/passes/ambient_occlusion.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmbientOcclusion {
    /// How far around a point (world units) geometry occludes it.
    pub radius: f32,
    /// How strongly: the visibility found is raised to this power (0: none).
    pub intensity: f32,
}

impl AmbientOcclusion {
    /// The largest radius accepted (world units).
    pub const MAX_RADIUS: f32 = 1000.0;
    /// The largest intensity accepted.
    pub const MAX_INTENSITY: f32 = 16.0;

    /// These settings with non-finite or out-of-range values clamped into range.
    pub fn clamped(self) -> Self {
        let clamp = |v: f32, max: f32, default: f32| if v.is_finite() { v.clamp(0.0, max) } else { default };
        let defaults = Self::default();
        Self {
            radius: clamp(self.radius, Self::MAX_RADIUS, defaults.radius),
            intensity: clamp(self.intensity, Self::MAX_INTENSITY, defaults.intensity),
        }
    }
}

impl Default for AmbientOcclusion {
    fn default() -> Self {
        Self { radius: 0.5, intensity: 1.0 }
    }
}

/// One camera's part of a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// What it sees from where.
    pub camera: Camera,
    /// Where in the target it draws (the whole target by default).
    pub viewport: Viewport,
    /// How it culls ([`Culling::Gpu`] by default, which takes the CPU's path where
    /// the adapter cannot cull on the GPU; [`Culling::Off`] draws everything, to compare costs).
    pub culling: Culling,
    /// Post-processing passes, in order (none by default: the view is drawn
    /// straight into the target, and the chain costs nothing).
    pub post: Vec<PostEffect>,
    /// The render target it draws into instead of the frame's target (`None`,
    /// the default: the frame's). Its viewport is then a rectangle of that target.
    pub output: Option<RenderTargetId>,
    /// Its screen-space ambient occlusion (`None`, the default: none, and no
    /// depth pre-pass).
    pub ambient_occlusion: Option<AmbientOcclusion>,
    /// The error a level of detail may make, in pixels of this view
    /// ([`DEFAULT_LOD_ERROR`] by default; 0 draws every mesh at full detail):
    /// each instance draws the coarsest level of its shape whose error
    /// projects to at most this ([`crate::scene::levels`]).
    pub lod_error: f32,
    /// How it blends transparent surfaces ([`Transparency::Sorted`] by default).
    pub transparency: Transparency,
}

/// A view's default [`View::lod_error`]: half a pixel. At one pixel a scene
/// of many small shapes changes visibly at their edges (the 700 spheres of
/// `tests/scenes/instancing.scn` put 0.9% of their pixels off by more than
/// 40/255, past the reference tolerance; at half a pixel 0.4%).
pub const DEFAULT_LOD_ERROR: f32 = 0.5;

impl View {
    /// The whole target seen by `camera`, culled.
    pub fn new(camera: Camera) -> Self {
        Self {
            camera,
            viewport: Viewport::FULL,
            culling: Culling::Gpu,
            post: Vec::new(),
            output: None,
            ambient_occlusion: None,
            lod_error: DEFAULT_LOD_ERROR,
            transparency: Transparency::Sorted,
        }
    }

    /// This view allowing `pixels` of error from levels of detail (0: full detail).
    pub fn with_lod_error(self, pixels: f32) -> Self {
        Self { lod_error: pixels, ..self }
    }

    /// This view blending transparent surfaces as `transparency` says.
    pub fn with_transparency(self, transparency: Transparency) -> Self {
        Self { transparency, ..self }
    }

    /// This view drawing into `viewport`.
    pub fn with_viewport(self, viewport: Viewport) -> Self {
        Self { viewport, ..self }
    }

    /// This view with `post` as its post-processing chain.
    pub fn with_post(self, post: Vec<PostEffect>) -> Self {
        Self { post, ..self }
    }

    /// This view drawing into render target `output`.
    pub fn with_output(self, output: RenderTargetId) -> Self {
        Self { output: Some(output), ..self }
    }

    /// This view culled as `culling` says.
    pub fn with_culling(self, culling: Culling) -> Self {
        Self { culling, ..self }
    }

    /// This view with screen-space ambient occlusion (`None`: without).
    pub fn with_ambient_occlusion(self, ambient_occlusion: Option<AmbientOcclusion>) -> Self {
        Self { ambient_occlusion, ..self }
    }
}

impl From<Camera> for View {
    fn from(camera: Camera) -> Self {
        Self::new(camera)
    }
}

impl From<&Camera> for View {
    fn from(camera: &Camera) -> Self {
        Self::new(*camera)
    }
}

impl From<&View> for View {
    fn from(view: &View) -> Self {
        view.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viewports_are_checked_and_split_a_target_into_whole_pixels() {
        assert!(Viewport::FULL.is_valid());
        let left = Viewport { x: 0.0, y: 0.0, width: 0.5, height: 1.0 };
        let right = Viewport { x: 0.5, ..left };
        assert!(left.is_valid() && right.is_valid());
        for bad in [
            Viewport { x: -0.1, ..left },
            Viewport { x: 0.6, ..left },
            Viewport { width: 0.0, ..left },
            Viewport { height: 1.5, ..left },
            Viewport { y: f32::NAN, ..left },
        ] {
            assert!(!bad.is_valid(), "{bad:?}");
        }
        // An odd width: the halves meet at one pixel boundary and cover the target.
        let (l, r) = (left.pixels(101, 40), right.pixels(101, 40));
        assert_eq!(l, [0, 0, 51, 40]);
        assert_eq!(r, [51, 0, 50, 40]);
        assert_eq!(Viewport { x: 0.999, y: 0.999, width: 0.001, height: 0.001 }.pixels(10, 10), [9, 9, 1, 1]);
    }
}
