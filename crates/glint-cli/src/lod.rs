//! `--lod on|off` and `--lod-error PX`: levels of detail on `render`, `view`,
//! `explain` and `bench` (whose `--lod` also takes `both`: the frame with
//! levels beside the frame at full detail); and `--clusters auto|on|off` and
//! `--cluster-heat`, the renderer's other switches those commands share
//! (light clusters).

use glint::{Renderer, View};

/// Whether views draw levels of detail.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LodSwitch {
    /// Each instance at the coarsest level its view's error allows (the default).
    #[default]
    On,
    /// Every mesh at full detail.
    Off,
}

/// `glint bench --lod`: as [`LodSwitch`], or both frames side by side.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchLod {
    /// With levels of detail (the default).
    #[default]
    On,
    /// At full detail.
    Off,
    /// Both, side by side, with their ratios.
    Both,
}

impl BenchLod {
    /// The sides measured: with levels (true), at full detail (false).
    pub fn sides(self) -> &'static [bool] {
        match self {
            Self::On => &[true],
            Self::Off => &[false],
            Self::Both => &[true, false],
        }
    }
}

/// Whether views shade point and spot lights from light clusters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ClustersArg {
    /// When a frame has more than 8 point and spot lights (the default).
    #[default]
    Auto,
    /// Whenever a frame has one.
    On,
    /// Never: every fragment loops over every light (at most 64).
    Off,
}

/// `--lod`, `--lod-error`, `--clusters` and `--cluster-heat`.
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub struct LodArgs {
    /// Levels of detail: on (each instance at the coarsest level whose error
    /// its view allows) or off (every mesh at full detail).
    #[arg(long, value_enum, default_value_t = LodSwitch::On)]
    pub lod: LodSwitch,
    /// The error, in pixels (0..=1000), a level of detail may make in every
    /// view, whatever its camera's "lod_error" says (default 1).
    #[arg(long, value_name = "PX", value_parser = parse_lod_error)]
    pub lod_error: Option<f32>,
    /// Light clusters: auto (when a frame has more than 8 point and spot
    /// lights), on, or off (every fragment loops over every light, at most
    /// 64; for comparison and teaching).
    #[arg(long, value_enum, default_value_t = ClustersArg::Auto)]
    pub clusters: ClustersArg,
    /// Draw clustered views as a heat map of the lights in each fragment's
    /// cluster on the jet scale (dark blue: none; a step for each doubling,
    /// through blue, cyan, green, yellow and red; dark red: 255 or more),
    /// each tile's edge darkened.
    #[arg(long)]
    pub cluster_heat: bool,
}

/// `--lod-error`: pixels, 0..=1000.
pub fn parse_lod_error(s: &str) -> Result<f32, String> {
    crate::number_in(s, 0.0..=1000.0, "pixels of error")
}

impl LodArgs {
    /// These settings with levels `on` or not (for one side of `--lod both`).
    pub fn with(self, on: bool) -> Self {
        Self { lod: if on { LodSwitch::On } else { LodSwitch::Off }, ..self }
    }

    /// Tell `renderer` whether to draw levels, cluster lights and show their heat map, and to keep large meshes' levels
    /// in the user's cache folder between runs (`levels/` under
    /// `$GLINT_CACHE_DIR`, else `$XDG_CACHE_HOME/glint`, else `~/.cache/glint`;
    /// `GLINT_CACHE_DIR=` empty keeps none).
    pub fn apply(self, renderer: &mut Renderer) {
        renderer.set_levels_of_detail(self.lod == LodSwitch::On);
        renderer.set_clusters(match self.clusters {
            ClustersArg::Auto => glint::render::Clusters::Auto,
            ClustersArg::On => glint::render::Clusters::On,
            ClustersArg::Off => glint::render::Clusters::Off,
        });
        renderer.set_cluster_heat_map(self.cluster_heat);
        renderer.set_level_cache(glint::scene::level_cache::LevelCache::user());
    }

    /// `views` with `--lod-error`'s error where given.
    pub fn views(self, views: Vec<View>) -> Vec<View> {
        match self.lod_error {
            Some(pixels) => views.into_iter().map(|v| v.with_lod_error(pixels)).collect(),
            None => views,
        }
    }
}
