//! The shaders assembled from build.rs's segments against naga_oil's
//! composition of the same sources with the same defs.

use super::*;
use naga_oil::compose::{ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderDefValue};
use wgpu::naga;

/// naga_oil, with glint's shared modules added, validating as wgpu does
/// where exact transparency runs (half floats packed, the depth test
/// forced before its fragments append).
fn composer() -> Composer {
    use naga::valid::Capabilities;
    let capabilities =
        Capabilities::default() | Capabilities::SHADER_FLOAT16_IN_FLOAT32 | Capabilities::EARLY_DEPTH_TEST;
    let mut composer = Composer::default().with_capabilities(capabilities);
    let shared = [
        ("equirect.wgsl", include_str!("equirect.wgsl")),
        ("blocks.wgsl", include_str!("blocks.wgsl")),
        ("full_screen.wgsl", include_str!("full_screen.wgsl")),
        ("post_inputs.wgsl", include_str!("post_inputs.wgsl")),
        ("light_clusters.wgsl", include_str!("light_clusters.wgsl")),
        ("shadow_lookup.wgsl", include_str!("shadow_lookup.wgsl")),
        ("transparency_out.wgsl", include_str!("transparency_out.wgsl")),
    ];
    for (file_path, source) in shared {
        let module = ComposableModuleDescriptor { source, file_path, ..Default::default() };
        if let Err(e) = composer.add_composable_module(module) {
            panic!("{file_path}: {}", e.emit_to_string(&composer));
        }
    }
    composer
}

/// naga_oil's composition of `source` with `defs`.
fn composed(composer: &mut Composer, source: &str, defs: &Defs) -> naga::Module {
    let flags = defs.set.iter().map(|&d| (d.to_string(), ShaderDefValue::Bool(true)));
    let values = defs.values.iter().map(|&(d, v)| (d.to_string(), ShaderDefValue::UInt(v)));
    let desc = NagaModuleDescriptor { source, shader_defs: flags.chain(values).collect(), ..Default::default() };
    match composer.make_naga_module(desc) {
        Ok(module) => module,
        Err(e) => panic!("{defs:?}: {}", e.emit_to_string(composer)),
    }
}

/// A module's entry points and what they use, written out as WGSL: naga's
/// compaction drops what they do not use (but keeps named constants: those
/// unnamed elsewhere go here too), and naga_oil's decorations come off the
/// names of imported items.
fn written(mut module: naga::Module) -> String {
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    let module = &module;
    let info = naga::valid::Validator::new(Default::default(), naga::valid::Capabilities::all())
        .validate(module)
        .unwrap_or_else(|e| panic!("{e:?}"));
    let text = naga::back::wgsl::write_string(module, &info, naga::back::wgsl::WriterFlags::empty()).expect("writes");
    let mut out = String::new();
    let mut rest = text.as_str();
    while let Some(at) = rest.find("X_naga_oil_mod_X") {
        out.push_str(&rest[..at]);
        let tail = &rest[at + "X_naga_oil_mod_X".len()..];
        let end = tail.find(|c: char| !c.is_ascii_alphanumeric()).unwrap_or(tail.len());
        rest = &tail[end..];
    }
    out.push_str(rest);
    normalized(&out)
}

/// WGSL from naga's writer with its top-level items sorted, unused named
/// constants dropped, and each item's temporaries (`_eN`, numbered by
/// expression handles, which differ between equivalent modules) renumbered
/// in order of appearance.
fn normalized(wgsl: &str) -> String {
    let mut items: Vec<String> = Vec::new();
    let mut continues = false;
    for line in wgsl.lines().filter(|l| !l.trim().is_empty()) {
        let top = !line.starts_with([' ', '}']);
        if top && !continues {
            items.push(String::new());
        }
        continues = top && line.starts_with('@') && !line.trim_end().ends_with(['{', ';']);
        items.last_mut().expect("starts at the top").push_str(&format!("{line}\n"));
    }
    let mentions = |name: &str| items.iter().filter(|item| words(item).any(|w| w == name)).count();
    let unused =
        |item: &String| item.strip_prefix("const ").and_then(|l| l.split(':').next()).is_some_and(|n| mentions(n) < 2);
    // Numbered names' stems anywhere: the namer numbers clashing names module-wide.
    let stems: Vec<&str> = words(wgsl).filter_map(stem).collect();
    let mut kept: Vec<String> =
        items.iter().filter(|item| !unused(item)).map(|item| renumbered(item, &stems)).collect();
    kept.sort();
    kept.concat()
}

fn words(text: &str) -> impl Iterator<Item = &str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).filter(|w| !w.is_empty())
}

/// `item` with its numbered names (`_eN` temporaries, numbered by expression
/// handles, and the namer's `name_N`, numbered by what it met first, with the
/// bare `name` of each of `stems`: which of two clashing names keeps the bare
/// one depends on the order the module's functions came in) renamed
/// `stem#0`, `stem#1`, ... in order of appearance.
fn renumbered(item: &str, stems: &[&str]) -> String {
    fn family<'a>(stems: &[&str], w: &'a str) -> Option<&'a str> {
        stem(w).or_else(|| stems.contains(&w).then_some(w))
    }
    let mut names: Vec<&str> = Vec::new();
    for word in words(item).filter(|w| family(stems, w).is_some()) {
        if !names.contains(&word) {
            names.push(word);
        }
    }
    let mut out = String::new();
    let mut word = String::new();
    for c in item.chars().chain(std::iter::once(' ')) {
        if c.is_ascii_alphanumeric() || c == '_' {
            word.push(c);
            continue;
        }
        match family(stems, &word) {
            Some(s) => {
                let k = names.iter().filter(|n| family(stems, n) == Some(s)).position(|n| *n == word).expect("listed");
                out.push_str(&format!("{s}#{k}"));
            }
            None => out.push_str(&word),
        }
        word.clear();
        out.push(c);
    }
    out.pop();
    out
}

/// The stem of a numbered name: `_e` of `_e12`, `d` of `d_2`.
fn stem(word: &str) -> Option<&str> {
    let digits = |n: &str| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit());
    if word.strip_prefix("_e").is_some_and(digits) {
        return Some("_e");
    }
    let (stem, number) = word.rsplit_once('_')?;
    (!stem.is_empty() && digits(number)).then_some(stem)
}

fn parsed(wgsl: &str) -> naga::Module {
    naga::front::wgsl::parse_str(wgsl).unwrap_or_else(|e| panic!("{}\n{wgsl}", e.emit_to_string(wgsl)))
}

/// Whether `wgsl` (assembled) is what naga_oil composes from `source` with
/// `defs`, and valid: panics where not.
fn check(composer: &mut Composer, wgsl: &str, source: &str, defs: &Defs) -> naga::Module {
    let module = parsed(wgsl);
    let expected = written(composed(composer, source, defs));
    assert!(written(module.clone()) == expected, "{defs:?}: the assembled shader differs from naga_oil's");
    module
}

/// Every feature set of up to three bits, and all of them at once: each line
/// of `forward.wgsl` sits under at most three tests (the nesting is at most
/// three deep), so this meets every line's condition both ways and every
/// interaction between conditions; exhaustive would be 2^24 sets.
fn covering_sets() -> Vec<ShaderFeatures> {
    let bits: Vec<u32> = ShaderFeatures::all().iter().map(|f| f.bits()).collect();
    let mut sets = vec![0, ShaderFeatures::all().bits()];
    for (i, a) in bits.iter().enumerate() {
        for (j, b) in bits.iter().enumerate().skip(i) {
            sets.extend(bits.iter().skip(j).map(|c| a | b | c));
        }
    }
    sets.sort();
    sets.dedup();
    sets.into_iter().map(ShaderFeatures::from_bits_truncate).collect()
}

#[test]
fn every_forward_variant_is_what_naga_oil_composes_and_validates() {
    use p3_maybe_rayon::prelude::*;
    // Each set with one of these light mixes in turn: no lights, each kind
    // alone, both; and both ways of reading the arrays.
    let mixes =
        [(0, 0), (1, 0), (0, 1), (2, 3)].map(|(directional, positional)| LightCounts { directional, positional });
    let sets = covering_sets();
    let cases: Vec<(usize, bool)> = (0..sets.len()).flat_map(|k| [(k, true), (k, false)]).collect();
    cases.par_chunks(cases.len().div_ceil(current_num_threads())).for_each(|chunk| {
        let mut composer = composer();
        for &(k, storage) in chunk {
            let (features, lights) = (sets[k], mixes[k % mixes.len()]);
            let defs = forward_defs(features, lights, storage);
            let module = check(&mut composer, &forward(features, lights, storage), include_str!("forward.wgsl"), &defs);
            let stored = (module.global_variables.iter())
                .filter(|(_, v)| matches!(v.space, naga::AddressSpace::Storage { .. }))
                .count();
            // Exact transparency's lists are storage buffers (a path that has them).
            let lists = features.contains(ShaderFeatures::TRANSPARENCY_LISTS);
            assert_eq!(stored == 0, !storage && !lists, "{features:?}: {stored} storage buffers");
        }
    });
}

#[test]
fn the_other_composed_shaders_are_what_naga_oil_composes() {
    let mut composer = composer();
    check(&mut composer, &sky(), include_str!("sky.wgsl"), &Defs::default());
    check(&mut composer, &prefilter(), include_str!("prefilter.wgsl"), &Defs::default());
    for soft in [None, Some(false), Some(true)] {
        for lit in [None, Some(false), Some(true)] {
            for (data_textures, lists) in [(false, false), (true, false), (false, true)] {
                let variant = ParticleShading { soft, lit, data_textures, lists };
                check(&mut composer, &particles(variant), include_str!("particles.wgsl"), &particle_defs(variant));
            }
        }
    }
    let (ssao_source, compute) = (include_str!("ssao.wgsl"), include_str!("ssao_compute.wgsl"));
    for multisampled in [false, true] {
        let defs = ssao_defs(multisampled);
        check(&mut composer, &ssao(multisampled), ssao_source, &defs);
        let both = format!("{}{SSAO_COMPUTE}", ssao(multisampled));
        check(&mut composer, &both, &format!("{ssao_source}{compute}"), &defs);
    }
}

#[test]
fn the_shaders_without_defs_are_what_naga_oil_composes() {
    // Their imports ahead of their own text, comments dropped.
    let sources = [
        (BLIT, include_str!("blit.wgsl")),
        (POST, include_str!("post.wgsl")),
        (SMAA, include_str!("smaa.wgsl")),
        (ACCUMULATE, include_str!("accumulate.wgsl")),
        (CULL, include_str!("cull.wgsl")),
        (PYRAMID, include_str!("pyramid.wgsl")),
        (PARTICLES_STEP, include_str!("particles_step.wgsl")),
        (SCHOOL, include_str!("school.wgsl")),
        (SCHOOL_PLACE, include_str!("school_place.wgsl")),
        (SCAN, include_str!("scan.wgsl")),
        (RADIX, include_str!("radix.wgsl")),
        (CLOTH, include_str!("cloth.wgsl")),
        (CLOTH_PLACE, include_str!("cloth_place.wgsl")),
        (BIN_LIGHTS, include_str!("bin_lights.wgsl")),
        (TRANSPARENCY, include_str!("transparency.wgsl")),
        (TRANSPARENCY_LISTS, include_str!("transparency_lists.wgsl")),
    ];
    let mut composer = composer();
    for (plain, source) in sources {
        assert!(!plain.contains("//") && !plain.contains('#'));
        check(&mut composer, plain, source, &Defs::default());
    }
}

#[test]
fn the_shaders_need_no_cube_map_capability() {
    // Point lights' cubes are sampled as 2D layers, so adapters without cube-map
    // arrays (NVIDIA's GL driver, WebGL2) take the same shader.
    let without = naga::valid::Capabilities::all() - naga::valid::Capabilities::CUBE_ARRAY_TEXTURES;
    let lights = LightCounts { directional: 1, positional: 1 };
    let module = parsed(&forward(ShaderFeatures::all(), lights, true));
    naga::valid::Validator::new(Default::default(), without).validate(&module).expect("valid");
    let cubes = module.global_variables.iter().filter(|(_, v)| {
        matches!(module.types[v.ty].inner, naga::TypeInner::Image { dim: naga::ImageDimension::Cube, .. })
    });
    assert_eq!(cubes.count(), 0, "no cube-map bindings");
}
