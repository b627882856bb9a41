//! Core layer: WGSL sources. Every shader that reads scene data is the shared
//! `blocks.wgsl` (groups 0 and 1) followed by its own body.

const BLOCKS: &str = include_str!("blocks.wgsl");

/// Forward Blinn-Phong shader: `vs_main` / `fs_main`, groups 0–3.
pub(crate) fn forward() -> String {
    format!("{BLOCKS}\n{}", include_str!("forward.wgsl"))
}

/// Gradient sky shader: `vs_sky` / `fs_sky`, groups 0–1.
pub(crate) fn sky() -> String {
    format!("{BLOCKS}\n{}", include_str!("sky.wgsl"))
}

/// Mip blit shader: `vs_blit` / `fs_blit`, its own group 0.
pub(crate) const MIPMAP: &str = include_str!("mipmap.wgsl");
