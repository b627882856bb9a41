//! Core layer: the GPU passes a view's stages record, each with the pipelines
//! and images it owns: shadow maps (and the math of shadow views), ambient
//! occlusion, particle layers, the environment's prefiltered maps, and the
//! post chain, accumulated stills' running means, and order-independent
//! transparency's targets and composites.

pub(crate) mod accumulate;
pub(crate) mod ambient_occlusion;
pub(crate) mod environment;
pub(crate) mod particles;
pub(crate) mod post;
pub(crate) mod shadow_maps;
pub(crate) mod shadow_views;
pub(crate) mod smaa_area;
pub(crate) mod transparency;
