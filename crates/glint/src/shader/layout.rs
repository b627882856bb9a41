//! Core layer (tests only): the layout naga gives a WGSL struct, against which
//! every Rust struct that mirrors one is checked, member by member. The
//! checks sit beside each Rust struct ([`assert_mirrors!`]); adding, moving or
//! resizing a field on one side only fails them.

use wgpu::naga;

/// Assert that a Rust struct of `size` bytes mirrors struct `name` of the WGSL
/// `source`: the same size, and the same members (`fields`: each WGSL member's
/// name and the Rust offset that holds it), in order, at the same offsets.
#[track_caller]
pub(crate) fn assert_layout(source: &str, name: &str, size: usize, fields: &[(&str, usize)]) {
    let module =
        naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("naga lays the types out");
    let (_, ty) = (module.types.iter())
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in the WGSL"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else { panic!("{name} is not a struct") };
    let wgsl: Vec<(&str, usize)> =
        members.iter().map(|m| (m.name.as_deref().unwrap_or("?"), m.offset as usize)).collect();
    assert_eq!(fields, &wgsl[..], "{name}: the Rust struct's members (left) against the WGSL's (right)");
    assert_eq!(size, *span as usize, "{name}: the Rust struct's size against the WGSL's");
}

/// Assert that Rust struct `$ty` mirrors WGSL struct `$wgsl` of `$source`,
/// its fields named as the WGSL's members ([`assert_layout`]).
macro_rules! assert_mirrors {
    ($ty:ty, $source:expr, $wgsl:literal, [$($field:ident),* $(,)?]) => {
        $crate::shader::layout::assert_layout(
            $source,
            $wgsl,
            std::mem::size_of::<$ty>(),
            &[$((stringify!($field), std::mem::offset_of!($ty, $field))),*],
        )
    };
}
pub(crate) use assert_mirrors;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_on_one_side_only_fails_the_check() {
        let wgsl = "struct Pair { a: vec3<f32>, b: f32, c: vec4<u32> }";
        assert_layout(wgsl, "Pair", 32, &[("a", 0), ("b", 12), ("c", 16)]);
        let missing = std::panic::catch_unwind(|| assert_layout(wgsl, "Pair", 32, &[("a", 0), ("b", 12)]));
        assert!(missing.is_err(), "a member the Rust side lacks");
        let moved = std::panic::catch_unwind(|| assert_layout(wgsl, "Pair", 32, &[("a", 0), ("b", 16), ("c", 20)]));
        assert!(moved.is_err(), "a member at another offset");
        let longer = std::panic::catch_unwind(|| assert_layout(wgsl, "Pair", 48, &[("a", 0), ("b", 12), ("c", 16)]));
        assert!(longer.is_err(), "a Rust struct with more bytes");
    }
}
