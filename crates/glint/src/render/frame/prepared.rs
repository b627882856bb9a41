//! Core layer: what the prepare stage gives the stages after it: what each
//! submitted entity draws with ([`Prepared`]), what a table was made for
//! ([`PrepareKey`]), and which sky an environment draws ([`sky_pass`]).

use crate::gpu::TargetFormat;
use crate::render::frame_variant::FrameVariant;
use crate::render::gpu_driven::draw_list::BatchDraw;
use crate::render::resources::pipelines::{SkyPass, VertexLayout};
use crate::scene::{Background, Environment};

/// What a prepared table was made for: the frame's submissions, the
/// target, the view's variant and the environment's fog and sky.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PrepareKey {
    pub entities: usize,
    pub target: TargetFormat,
    pub variant: FrameVariant,
    pub fog: bool,
    pub sky: Option<SkyPass>,
    pub glare: bool,
}

/// What a submitted entity draws with, as stage 1 made it: its forward
/// pipeline, its mesh's vertex layout, and what its batches draw with.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prepared {
    pub pipeline: u16,
    pub layout: VertexLayout,
    pub draw: BatchDraw,
}

/// The sky a frame under `environment` draws: the environment's where it
/// lights the scene, else the gradient's, else none (a plain clear colour).
pub(crate) fn sky_pass(environment: &Environment) -> Option<SkyPass> {
    match (environment.light, environment.background) {
        (Some(_), _) => Some(SkyPass::Environment),
        (None, Background::Gradient { .. }) => Some(SkyPass::Gradient),
        (None, Background::Color(_)) => None,
    }
}
