//! Render targets in a scene: the `render_target` block, the camera key
//! `output` naming one, the material map value `target:NAME` showing one, and
//! the check that cameras drawing targets do not need each other's in a circle.
//! Names are found through a hash map and the order through one sort over the
//! cameras ([`draw_order`]), so a scene's targets and cameras load in linear time.

use super::scn_fields::Fields;
use super::Diagnostic;
use crate::asset::{CameraView, MaterialDesc, TextureRef};
use crate::scene::draw_order;
use crate::text::{list, quote};
use std::collections::HashMap;
use std::path::Path;

/// Largest side of a render target: what every adapter can draw, WebGL2's included.
pub const MAX_RENDER_TARGET_SIDE: u32 = 2048;
/// Most render targets one scene may define.
pub const MAX_RENDER_TARGETS: usize = 1024;
/// Most GPU memory a scene's render targets may take together, counted as
/// colour (4 bytes a pixel, 8 for `hdr`) plus depth (4 bytes): twenty-one
/// 2048² HDR targets, or 64 LDR ones. 120 such HDR targets ran a lavapipe
/// device out of memory.
pub const MAX_RENDER_TARGET_BYTES: u64 = 1 << 30;

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

impl RenderTargetDesc {
    /// Bytes of GPU memory it takes, as [`MAX_RENDER_TARGET_BYTES`] counts them.
    pub fn bytes(&self) -> u64 {
        let per_pixel = if self.hdr { 8 + 4 } else { 4 + 4 };
        u64::from(self.size.0) * u64::from(self.size.1) * per_pixel
    }
}

/// The render targets a scene has defined so far, by name.
#[derive(Default)]
pub(crate) struct Targets {
    pub(crate) list: Vec<RenderTargetDesc>,
    names: HashMap<String, usize>,
    bytes: u64,
}

impl Targets {
    /// Read a `render_target` block and add it, refusing a second block of the
    /// same name and targets past [`MAX_RENDER_TARGETS`] or [`MAX_RENDER_TARGET_BYTES`].
    pub(crate) fn parse(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        if self.list.len() == MAX_RENDER_TARGETS {
            let message =
                format!("more than {MAX_RENDER_TARGETS} render targets: a scene may define at most that many");
            return Err(Diagnostic::at(f.path, f.block.line, message));
        }
        let name_pair = f.require("name")?;
        let name = name_pair.value.trim().to_string();
        if self.names.contains_key(&name) {
            let message = format!("render target {} is defined twice", quote(&name));
            return Err(Diagnostic::at(f.path, name_pair.line, message));
        }
        let size_pair = f.require("size")?;
        let side = |v: &str| v.parse::<u32>().ok().filter(|s| (1..=MAX_RENDER_TARGET_SIDE).contains(s));
        let size = match size_pair.value.split_whitespace().collect::<Vec<_>>()[..] {
            [w, h] if side(w).is_some() && side(h).is_some() => (side(w).unwrap_or(1), side(h).unwrap_or(1)),
            _ => {
                let message = format!(
                    "\"size\" is {}, expected two whole numbers (width height) in 1..={MAX_RENDER_TARGET_SIDE}",
                    quote(&size_pair.value)
                );
                return Err(Diagnostic::at(f.path, size_pair.line, message));
            }
        };
        let hdr = matches!(f.choice("format", &["ldr", "hdr"])?, Some((1, _)));
        let target = RenderTargetDesc { name, size, hdr };
        self.bytes += target.bytes();
        if self.bytes > MAX_RENDER_TARGET_BYTES {
            let message = format!(
                "with this render target the scene's targets need {} MiB, more than the {} MiB limit",
                self.bytes >> 20,
                MAX_RENDER_TARGET_BYTES >> 20
            );
            return Err(Diagnostic::at(f.path, f.block.line, message));
        }
        self.names.insert(target.name.clone(), self.list.len());
        self.list.push(target);
        Ok(())
    }

    /// The render target `key` names (a camera's `output`), by index.
    pub(crate) fn named(&self, f: &mut Fields, key: &str) -> Result<Option<usize>, Diagnostic> {
        let Some(pair) = f.get(key) else { return Ok(None) };
        self.find(f.path, pair.line, pair.value.trim()).map(Some)
    }

    /// The index of the target called `name`, or an error at `line` naming a few known ones.
    fn find(&self, path: &Path, line: usize, name: &str) -> Result<usize, Diagnostic> {
        self.names.get(name).copied().ok_or_else(|| {
            let known: Vec<&str> = self.list.iter().map(|t| t.name.as_str()).collect();
            let message = format!("unknown render target {} (defined: {})", quote(name), list(&known));
            Diagnostic::at(path, line, message)
        })
    }

    /// A map value `target:NAME`: the target's pending texture reference; `None`
    /// when `value` names a file instead.
    pub(crate) fn map(&self, path: &Path, line: usize, value: &str) -> Option<Result<TextureRef, Diagnostic>> {
        let name = value.trim().strip_prefix("target:")?;
        Some(self.find(path, line, name.trim()).map(|k| PENDING + k))
    }
}

/// Where a map value `target:NAME` puts its texture until the scene's file
/// textures are all known: [`finish_maps`] moves it after them.
const PENDING: usize = usize::MAX / 2;

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
/// [`finish_maps`]), `targets` the number of render targets; `lines` is each
/// camera's block line.
pub(crate) fn check_order(
    path: &Path,
    cameras: &[CameraView],
    lines: &[usize],
    materials: &[MaterialDesc],
    textures: usize,
    targets: usize,
) -> Result<(), Diagnostic> {
    // The targets each material shows, each once.
    let shows: Vec<Vec<usize>> = (materials.iter())
        .map(|m| {
            let mut t: Vec<usize> = m.maps().iter().flatten().filter_map(|r| r.checked_sub(textures)).collect();
            t.sort_unstable();
            t.dedup();
            t
        })
        .collect();
    // A camera drawing target o shows target t when some material shows t but
    // not o: fewer materials show both than show t.
    let mut showing = vec![0usize; targets];
    let mut both: HashMap<(usize, usize), usize> = HashMap::new();
    for s in &shows {
        for &t in s {
            showing[t] += 1;
            for &o in s {
                *both.entry((o, t)).or_default() += 1;
            }
        }
    }
    let shown_by_all: Vec<usize> = (0..targets).filter(|&t| showing[t] > 0).collect();
    let mut shown_from: HashMap<Option<usize>, Vec<usize>> = HashMap::new();
    let shown: Vec<Vec<usize>> = (cameras.iter())
        .map(|c| {
            (shown_from.entry(c.output))
                .or_insert_with(|| match c.output {
                    None => shown_by_all.clone(),
                    Some(o) => (shown_by_all.iter().copied())
                        .filter(|&t| t != o && showing[t] > both.get(&(o, t)).copied().unwrap_or(0))
                        .collect(),
                })
                .clone()
        })
        .collect();
    let outputs: Vec<Option<usize>> = cameras.iter().map(|c| c.output).collect();
    draw_order(&outputs, &shown, targets).map(|_| ()).map_err(|stuck| {
        let message = "camera: its render target and another camera's each show the other's picture, \
                       so neither can be drawn first (a cycle of render targets)";
        Diagnostic::at(path, lines.get(stuck).copied().unwrap_or(0), message)
    })
}
