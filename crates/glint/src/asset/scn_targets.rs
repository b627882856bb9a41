//! Render targets in a scene: the `render_target` block, the camera key
//! `output` naming one, the material map value `target:NAME` showing one, and
//! the check that cameras drawing targets do not need each other's in a circle.

use super::scn_fields::Fields;
use super::Diagnostic;
use crate::asset::{CameraView, MaterialDesc, TextureRef};
use std::path::Path;

/// Largest side of a render target: what every adapter can draw, WebGL2's included.
pub const MAX_RENDER_TARGET_SIDE: u32 = 2048;

/// A `render_target` block.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderTargetDesc {
    /// `name`: how cameras' `output` and materials' `target:NAME` maps call it.
    pub name: String,
    /// `size`: width and height in pixels.
    pub size: (u32, u32),
    /// `format` `hdr` (half floats) rather than `ldr` (8-bit sRGB).
    pub hdr: bool,
}

/// Read a `render_target` block; `existing` are the scene's earlier ones.
pub(crate) fn parse(f: &mut Fields, existing: &[RenderTargetDesc]) -> Result<RenderTargetDesc, Diagnostic> {
    let name_pair = f.require("name")?;
    let name = name_pair.value.trim().to_string();
    if existing.iter().any(|t| t.name == name) {
        return Err(Diagnostic::at(f.path, name_pair.line, format!("render target '{name}' is defined twice")));
    }
    let size_pair = f.require("size")?;
    let size = match size_pair.value.split_whitespace().map(str::parse::<u32>).collect::<Vec<_>>()[..] {
        [Ok(w), Ok(h)] if (1..=MAX_RENDER_TARGET_SIDE).contains(&w) && (1..=MAX_RENDER_TARGET_SIDE).contains(&h) => {
            (w, h)
        }
        _ => {
            let message = format!(
                "\"size\" is '{}', expected two whole numbers (width height) in 1..={MAX_RENDER_TARGET_SIDE}",
                size_pair.value
            );
            return Err(Diagnostic::at(f.path, size_pair.line, message));
        }
    };
    let hdr = matches!(f.choice("format", &["ldr", "hdr"])?, Some((1, _)));
    Ok(RenderTargetDesc { name, size, hdr })
}

/// The render target `key` names (a camera's `output`), by index.
pub(crate) fn named(f: &mut Fields, key: &str, targets: &[RenderTargetDesc]) -> Result<Option<usize>, Diagnostic> {
    let Some(pair) = f.get(key) else { return Ok(None) };
    find(f.path, pair.line, pair.value.trim(), targets).map(Some)
}

/// The index of the target called `name`, or an error at `line` naming the known ones.
fn find(path: &Path, line: usize, name: &str, targets: &[RenderTargetDesc]) -> Result<usize, Diagnostic> {
    targets.iter().position(|t| t.name == name).ok_or_else(|| {
        let known: Vec<&str> = targets.iter().map(|t| t.name.as_str()).collect();
        let message = format!(
            "unknown render target '{name}' (render_target blocks come before the cameras and materials that name them; defined: {})",
            if known.is_empty() { "none".to_string() } else { known.join(", ") }
        );
        Diagnostic::at(path, line, message)
    })
}

/// Where a map value `target:NAME` puts its texture until the scene's file
/// textures are all known: [`finish_maps`] moves it after them.
const PENDING: usize = usize::MAX / 2;

/// A map value `target:NAME`: the target's pending texture reference; `None`
/// when `value` names a file instead.
pub(crate) fn map(
    path: &Path,
    line: usize,
    value: &str,
    targets: &[RenderTargetDesc],
) -> Option<Result<TextureRef, Diagnostic>> {
    let name = value.trim().strip_prefix("target:")?;
    Some(find(path, line, name.trim(), targets).map(|k| PENDING + k))
}

/// Give `target:NAME` maps their final references: the scene's `files` file
/// textures come first, then one per render target in file order.
pub(crate) fn finish_maps(materials: &mut [MaterialDesc], files: usize) {
    for map in materials.iter_mut().flat_map(MaterialDesc::maps_mut) {
        if let Some(r) = map.as_mut().filter(|r| **r >= PENDING) {
            *r = files + (*r - PENDING);
        }
    }
}

/// Check that cameras drawing render targets can be drawn in some order, each
/// before the cameras that show its target (a camera does not show its own:
/// materials showing it are left out of its view); else an error at the line of
/// a camera in the cycle. `textures` is the number of file textures (after
/// [`finish_maps`]); `lines` is each camera's block line.
pub(crate) fn check_order(
    path: &Path,
    cameras: &[CameraView],
    lines: &[usize],
    materials: &[MaterialDesc],
    textures: usize,
) -> Result<(), Diagnostic> {
    let shows = |m: &MaterialDesc, target: usize| m.maps().contains(&Some(textures + target));
    // Camera b needs camera a first when a draws target T and b draws a material
    // showing T (one that does not also show b's own target).
    let needs = |b: usize, a: usize| {
        let (Some(t), own) = (cameras[a].output, cameras[b].output) else { return false };
        a != b && materials.iter().any(|m| shows(m, t) && own.is_none_or(|o| !shows(m, o)))
    };
    let drawing: Vec<usize> = (0..cameras.len()).filter(|&k| cameras[k].output.is_some()).collect();
    let mut done: Vec<usize> = Vec::new();
    let ready = |done: &[usize]| {
        let waits = |b: usize| drawing.iter().any(|&a| needs(b, a) && !done.contains(&a));
        drawing.iter().copied().find(|&b| !done.contains(&b) && !waits(b))
    };
    while let Some(b) = ready(&done) {
        done.push(b);
    }
    match drawing.iter().find(|b| !done.contains(b)) {
        Some(&stuck) => {
            let message = "camera: its render target and another camera's each show the other's picture, \
                           so neither can be drawn first (a cycle of render targets)";
            Err(Diagnostic::at(path, lines.get(stuck).copied().unwrap_or(0), message))
        }
        None => Ok(()),
    }
}
