//! The material keys of `.scn` `material` blocks and `mtl.NAME.` overrides:
//! shading, colours and the explicit render states (see `docs/scn.md`).

use super::scn_fields::{numbers, Fields};
use super::Diagnostic;
use crate::scene::{AlphaMode, BlendState, Compare, Cull, Material, Motion, RenderStates, ShadingModel, StencilOp};
use glam::{Vec3, Vec4};

const COMPARES: [&str; 8] = ["never", "less", "less_equal", "equal", "greater_equal", "greater", "not_equal", "always"];
const COMPARE_VALUES: [Compare; 8] = [
    Compare::Never,
    Compare::Less,
    Compare::LessEqual,
    Compare::Equal,
    Compare::GreaterEqual,
    Compare::Greater,
    Compare::NotEqual,
    Compare::Always,
];
const STENCIL_OPS: [&str; 6] = ["keep", "zero", "replace", "increment", "decrement", "invert"];
const STENCIL_OP_VALUES: [StencilOp; 6] = [
    StencilOp::Keep,
    StencilOp::Zero,
    StencilOp::Replace,
    StencilOp::IncrementClamp,
    StencilOp::DecrementClamp,
    StencilOp::Invert,
];

/// The material keys of a `material` block (or of `mtl.NAME.` overrides) applied
/// over `base`: keys that are absent keep `base`'s values. Texture keys are the
/// caller's.
pub(crate) fn material_fields(f: &mut Fields, base: Material) -> Result<Material, Diagnostic> {
    let base_color = match f.get("base_color") {
        None => base.base_color,
        Some(pair) => {
            let words = pair.value.split_whitespace().count();
            let c = if words == 3 {
                Vec3::from(numbers::<3>(f.path, pair, "3 or 4 numbers (r g b [a])")?).extend(1.0)
            } else {
                Vec4::from(numbers::<4>(f.path, pair, "3 or 4 numbers (r g b [a])")?)
            };
            if c.min_element() < 0.0 || c.w > 1.0 {
                return Err(Diagnostic::at(
                    f.path,
                    pair.line,
                    "\"base_color\" must be non-negative with alpha at most 1",
                ));
            }
            c
        }
    };
    let base_cutoff = match base.alpha_mode {
        AlphaMode::Mask { cutoff } => cutoff,
        _ => 0.5,
    };
    let cutoff = f.number("alpha_cutoff", 0.0..=1.0)?.unwrap_or(base_cutoff);
    let alpha_mode = match f.choice("alpha_mode", &["opaque", "mask", "blend"])? {
        None if matches!(base.alpha_mode, AlphaMode::Mask { .. }) => AlphaMode::Mask { cutoff },
        None => base.alpha_mode,
        Some((0, _)) => AlphaMode::Opaque,
        Some((1, _)) => AlphaMode::Mask { cutoff },
        Some(_) => AlphaMode::Blend,
    };
    let material = Material {
        base_color,
        ambient: f.number("ambient", 0.0..=100.0)?.unwrap_or(base.ambient),
        diffuse: f.number("diffuse", 0.0..=100.0)?.unwrap_or(base.diffuse),
        specular: f.number("specular", 0.0..=100.0)?.unwrap_or(base.specular),
        smoothness: f.number("smoothness", 0.0..=1.0)?.unwrap_or(base.smoothness),
        alpha_mode,
        double_sided: f.flag("double_sided")?.unwrap_or(base.double_sided),
        uv_scale: f.numbers::<2>("uv_scale", "2 numbers (u v)")?.map_or(base.uv_scale, glam::Vec2::from),
        uv_offset: f.numbers::<2>("uv_offset", "2 numbers (u v)")?.map_or(base.uv_offset, glam::Vec2::from),
        uv_rotation: f.number("uv_rotation", -360.0..=360.0)?.map_or(base.uv_rotation, f32::to_radians),
        shading: match f.choice("shading", &["blinn_phong", "unlit", "metallic_roughness"])? {
            None => base.shading,
            Some((0, _)) => ShadingModel::BlinnPhong,
            Some((1, _)) => ShadingModel::Unlit,
            Some(_) => ShadingModel::MetallicRoughness,
        },
        metallic: f.number("metallic", 0.0..=1.0)?.unwrap_or(base.metallic),
        roughness: f.number("roughness", 0.0..=1.0)?.unwrap_or(base.roughness),
        emissive: f.color("emissive")?.unwrap_or(base.emissive),
        fog: f.flag("fog")?.unwrap_or(base.fog),
        motion: motion_fields(f, base.motion)?,
        edge_fade: match f.get("edge_fade") {
            None => base.edge_fade,
            Some(pair) => match numbers::<2>(f.path, pair, "2 numbers (inner outer)")? {
                [inner, outer] if inner >= 0.0 && outer > inner && outer <= 1e6 => Some((inner, outer)),
                _ => {
                    let message = "\"edge_fade\" must be inner outer with 0 <= inner < outer <= 1000000";
                    return Err(Diagnostic::at(f.path, pair.line, message));
                }
            },
        },
        far_field: match f.get("far_field") {
            None => base.far_field,
            Some(pair) => {
                let [start, end] = numbers::<2>(f.path, pair, "2 numbers (start end)")?;
                match crate::scene::FarField::new(start, end).filter(|_| end <= 1e6) {
                    Some(field) => Some(field),
                    None => {
                        let message = "\"far_field\" must be start end with 0 < start < end <= 1000000";
                        return Err(Diagnostic::at(f.path, pair.line, message));
                    }
                }
            }
        },
        ..base.clone()
    };
    let states = render_states(f, material.render_states())?.or(base.states);
    Ok(Material { states, ..material })
}

/// The keys of each motion (`motion` names one): the others are errors.
const MOTION_KEYS: [(&str, &[&str]); 4] = [
    ("wind", &["sway", "sway_base"]),
    ("flap", &["flap_amplitude", "flap_rate"]),
    ("circle", &["walk_radius", "walk_speed"]),
    ("swim", &["swim_amplitude", "swim_pivot"]),
];

/// A material's [`Motion`]: `motion` (`none`, `wind`, `flap`, `circle`, `swim`; else
/// `base`'s) and its keys, each over `base`'s value where `base` moves the
/// same way, else over its default.
fn motion_fields(f: &mut Fields, base: Option<Motion>) -> Result<Option<Motion>, Diagnostic> {
    let kind = match f.choice("motion", &["none", "wind", "flap", "circle", "swim"])? {
        Some((0, _)) => None,
        Some((k, _)) => Some(k - 1),
        None => base.map(|m| match m {
            Motion::Wind { .. } => 0,
            Motion::Flap { .. } => 1,
            Motion::Circle { .. } => 2,
            Motion::Swim { .. } => 3,
        }),
    };
    for (k, (name, keys)) in MOTION_KEYS.iter().enumerate() {
        if let Some(pair) = keys.iter().find_map(|key| f.get(key)).filter(|_| kind != Some(k)) {
            let message = format!("{} is a key of \"motion\" \"{name}\", which this material does not have", pair.key);
            return Err(Diagnostic::at(f.path, pair.line, message));
        }
    }
    Ok(match kind {
        None => None,
        Some(0) => {
            let (sway, base) = match base {
                Some(Motion::Wind { sway, base }) => (sway, base),
                _ => (0.3, 0.0),
            };
            let sway = f.number("sway", 0.0..=100.0)?.unwrap_or(sway);
            Some(Motion::Wind { sway, base: f.number("sway_base", -1e4..=1e4)?.unwrap_or(base) })
        }
        Some(1) => {
            let (amplitude, rate) = match base {
                Some(Motion::Flap { amplitude, rate }) => (amplitude, rate),
                _ => (0.8, 6.0),
            };
            let amplitude = f.number("flap_amplitude", 0.0..=10.0)?.unwrap_or(amplitude);
            Some(Motion::Flap { amplitude, rate: f.number("flap_rate", 0.0..=100.0)?.unwrap_or(rate) })
        }
        Some(3) => {
            let (amplitude, pivot) = match base {
                Some(Motion::Swim { amplitude, pivot }) => (amplitude, pivot),
                _ => (0.15, 0.0),
            };
            let amplitude = f.number("swim_amplitude", 0.0..=10.0)?.unwrap_or(amplitude);
            Some(Motion::Swim { amplitude, pivot: f.number("swim_pivot", -1e4..=1e4)?.unwrap_or(pivot) })
        }
        Some(_) => {
            let (radius, speed) = match base {
                Some(Motion::Circle { radius, speed }) => (radius, speed),
                _ => (glam::Vec2::new(1.0, 2.0), 0.5),
            };
            let radius = match f.get("walk_radius") {
                None => radius,
                Some(pair) => match numbers::<2>(f.path, pair, "2 numbers (min max)")? {
                    [lo, hi] if (0.0..=hi).contains(&lo) && hi <= 1e4 => glam::Vec2::new(lo, hi),
                    _ => {
                        let message = "\"walk_radius\" must be min max with 0 <= min <= max <= 10000";
                        return Err(Diagnostic::at(f.path, pair.line, message));
                    }
                },
            };
            Some(Motion::Circle { radius, speed: f.number("walk_speed", 0.0..=1000.0)?.unwrap_or(speed) })
        }
    })
}

/// A material's explicit render states: `None` when no state key is given, else
/// `derived` (what its alpha mode and sidedness imply) with the given keys applied.
fn render_states(f: &mut Fields, derived: RenderStates) -> Result<Option<RenderStates>, Diagnostic> {
    let mut s = derived;
    let mut any = false;
    let mut pick = |v: Option<(usize, &_)>| {
        v.map(|(i, _)| {
            any = true;
            i
        })
    };
    if let Some(i) = pick(f.choice("blend", &["replace", "alpha", "additive", "multiply"])?) {
        s.blend = [BlendState::Replace, BlendState::Alpha, BlendState::Additive, BlendState::Multiply][i];
    }
    if let Some(i) = pick(f.choice("depth_compare", &COMPARES)?) {
        s.depth.compare = COMPARE_VALUES[i];
    }
    if let Some(i) = pick(f.choice("cull", &["back", "front", "none"])?) {
        s.raster.cull = [Cull::Back, Cull::Front, Cull::None][i];
    }
    if let Some(i) = pick(f.choice("stencil_compare", &COMPARES)?) {
        s.stencil.compare = COMPARE_VALUES[i];
    }
    for (key, op) in [
        ("stencil_pass", &mut s.stencil.pass),
        ("stencil_fail", &mut s.stencil.fail),
        ("stencil_depth_fail", &mut s.stencil.depth_fail),
    ] {
        if let Some(i) = pick(f.choice(key, &STENCIL_OPS)?) {
            *op = STENCIL_OP_VALUES[i];
        }
    }
    if let Some(write) = f.flag("depth_write")? {
        s.depth.write = write;
        any = true;
    }
    for (key, field) in [
        ("stencil_ref", &mut s.stencil.reference),
        ("stencil_read_mask", &mut s.stencil.read_mask),
        ("stencil_write_mask", &mut s.stencil.write_mask),
    ] {
        if let Some(v) = f.integer(key, 0..=255)? {
            *field = v as u8;
            any = true;
        }
    }
    if let Some(bias) = f.integer("depth_bias", -65536..=65536)? {
        s.raster.depth_bias = bias as i32;
        any = true;
    }
    if let Some(slope) = f.number("slope_bias", -100.0..=100.0)? {
        s.raster.slope_bias_bits = slope.to_bits();
        any = true;
    }
    Ok(any.then_some(s))
}
