//! Composed shaders, assembled from the segments `build.rs` prepared when glint
//! was built: a variant's WGSL is the segments its defs select, joined. Nothing
//! is parsed or composed at run time, so the web page carries no shader
//! composer and spends no time composing. The shaders used as they are come
//! from there too, without their comments.

/// A piece of a composed shader and the `#ifdef` (`true`) / `#ifndef`
/// (`false`) tests it sits under.
pub(crate) struct Segment {
    pub(crate) when: &'static [(&'static str, bool)],
    pub(crate) piece: Piece,
}

/// Source text, or where a def's value (`#{DEF}`) goes.
pub(crate) enum Piece {
    Text(&'static str),
    Value(&'static str),
}

include!(concat!(env!("OUT_DIR"), "/shader_segments.rs"));

/// The defs a variant is assembled with: those set, and the values of those
/// that have one.
#[derive(Clone, Debug, Default)]
pub(crate) struct Defs {
    pub(crate) set: Vec<&'static str>,
    pub(crate) values: Vec<(&'static str, u32)>,
}

impl Defs {
    fn is_set(&self, name: &str) -> bool {
        self.set.contains(&name) || self.values.iter().any(|(n, _)| *n == name)
    }
}

/// The WGSL of `shader` with `defs`.
///
/// # Panics
/// When a `#{DEF}` the selected segments need has no value in `defs`: a bug in
/// glint, which names each valued def it uses.
pub(crate) fn assemble(shader: &[Segment], defs: &Defs) -> String {
    let mut wgsl = String::new();
    for segment in shader.iter().filter(|s| s.when.iter().all(|&(def, wanted)| defs.is_set(def) == wanted)) {
        match segment.piece {
            Piece::Text(text) => wgsl.push_str(text),
            Piece::Value(name) => {
                let value = defs.values.iter().find(|(n, _)| *n == name);
                let (_, value) = value.unwrap_or_else(|| panic!("shader def {name} has no value"));
                wgsl.push_str(&value.to_string());
            }
        }
    }
    wgsl
}
