//! A `camera` block's post-processing keys: `post` (the ordered effects) and
//! each effect's settings (`tonemap`, `exposure`, `bloom_threshold`,
//! `bloom_intensity`, `edge_color`, `edge_threshold`, `vignette`, `smaa`).

use super::scn_fields::Fields;
use super::Diagnostic;
use crate::scene::{PostEffect, SmaaPreset, Tonemap};

/// The camera's post chain (empty without a `post` key). An effect named twice,
/// an unknown name, more than [`MAX_POST_EFFECTS`](crate::scene::MAX_POST_EFFECTS) effects or a setting out of
/// range is an error at its line.
pub(crate) fn chain(f: &mut Fields) -> Result<Vec<PostEffect>, Diagnostic> {
    let mut defaults = PostEffect::ALL;
    if let PostEffect::Tonemap { operator, exposure } = &mut defaults[1] {
        if let Some((k, _)) = f.choice("tonemap", &["none", "reinhard", "aces", "agx"])? {
            *operator = [Tonemap::None, Tonemap::Reinhard, Tonemap::Aces, Tonemap::Agx][k];
        }
        *exposure = f.number("exposure", -20.0..=20.0)?.unwrap_or(0.0);
    }
    if let PostEffect::Bloom { threshold, intensity } = &mut defaults[0] {
        *threshold = f.number("bloom_threshold", 0.0..=1e4)?.unwrap_or(*threshold);
        *intensity = f.number("bloom_intensity", 0.0..=100.0)?.unwrap_or(*intensity);
    }
    if let PostEffect::Edges { color, threshold } = &mut defaults[3] {
        *color = f.color("edge_color")?.unwrap_or(*color);
        *threshold = f.number("edge_threshold", 0.0..=8.0)?.unwrap_or(*threshold);
    }
    if let PostEffect::Vignette { strength } = &mut defaults[4] {
        *strength = f.number("vignette", 0.0..=1.0)?.unwrap_or(*strength);
    }
    if let PostEffect::Smaa { preset } = &mut defaults[5] {
        if let Some((k, _)) = f.choice("smaa", &SmaaPreset::NAMES)? {
            *preset = SmaaPreset::ALL[k];
        }
    }
    let Some(pair) = f.get("post") else {
        return Ok(Vec::new());
    };
    PostEffect::chain(&pair.value, &defaults).map_err(|m| Diagnostic::at(f.path, pair.line, format!("\"post\": {m}")))
}
