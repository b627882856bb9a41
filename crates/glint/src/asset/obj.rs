//! Core layer: Wavefront OBJ + MTL through `tobj`. Polygons are triangulated; every
//! object/group × material run becomes its own part with its own MTL material;
//! missing normals are computed: faces are flat unless a smoothing group (`s 1`,
//! `s 2` ...) joins them, as in Blender's importer, and faces in one group share
//! angle-weighted normals at each position (see [`scan_obj`]); missing texture
//! coordinates are allowed. MTL texture statements are split into options (`-s`,
//! `-o`, `-bm` ...) and a file name that may hold spaces. A missing `.mtl` or
//! texture is a warning and a visible default, not a failure; a malformed one
//! (non-finite or negative numbers included) is an error at its line. Paths in the
//! files resolve inside the model's folder only (see [`LoadOptions`]).

use super::model::{Model, ModelPart};
use super::texture::read_texture;
use super::texture::TextureCache;
use super::{AssetFolder, Diagnostic, LoadOptions, MaterialDesc};
use crate::scene::{smooth_normals_in_groups, AlphaMode, Material, Mesh, MeshError};
use glam::{Mat4, Vec2, Vec3};
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};

/// Parse OBJ text read from `path` (which names it in messages and anchors the
/// MTL libraries and textures it names).
pub(crate) fn parse_obj(path: &Path, bytes: &[u8], options: LoadOptions) -> Result<Model, Diagnostic> {
    let folder = AssetFolder::of(path, &options);
    let texture_memory = options.texture_memory;
    let warnings = RefCell::new(Vec::new());
    let mtl_error = RefCell::new(None);
    let consumed = Cell::new(0);
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let mut reader = LineCounter { inner: bytes, consumed: &consumed };
    let loaded = tobj::load_obj_buf(&mut reader, &options, |mtl: &Path| match load_mtl(&folder, mtl, path) {
        Ok(library) => {
            if library.0.is_empty() {
                let message = format!("material library {}: defines no materials (no newmtl)", mtl.display());
                warnings.borrow_mut().push(Diagnostic::file(path, message));
            }
            Ok(library)
        }
        Err(MtlProblem::Unread(warning)) => {
            warnings.borrow_mut().push(warning);
            Err(tobj::LoadError::OpenFileFailed)
        }
        Err(MtlProblem::Invalid(error)) => {
            mtl_error.borrow_mut().get_or_insert(error);
            Err(tobj::LoadError::OpenFileFailed)
        }
    });
    let (models, materials) =
        loaded.map_err(|e| Diagnostic::at(path, line_at(bytes, consumed.get()), format!("{e}")))?;
    if let Some(error) = mtl_error.into_inner() {
        return Err(error);
    }
    let mut warnings = warnings.into_inner();
    let scan = scan_obj(path, bytes, &mut warnings)?;
    // A failed library is already a warning; the parts then use the default material.
    let materials = materials.unwrap_or_default();
    let mut textures = TextureCache::new(texture_memory);
    let materials: Vec<MaterialDesc> =
        materials.iter().map(|m| convert_material(m, &folder, path, &mut textures, &mut warnings)).collect();
    let triangles: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    // The scan counts faces as tobj does; should they ever disagree, every
    // triangle is flat and errors name the file only.
    let agrees = scan.groups.len() == triangles;
    if !agrees {
        let message = format!("{} triangles by smoothing group, {triangles} loaded; all flat", scan.groups.len());
        warnings.push(Diagnostic::file(path, message));
    }
    let mut parts = Vec::new();
    let mut first_triangle = 0;
    for model in models {
        let part_name = model.name.clone();
        let part_triangles = model.mesh.indices.len() / 3;
        let range = first_triangle..first_triangle + part_triangles;
        first_triangle += part_triangles;
        let mut groups: Vec<u64> = match agrees {
            true => scan.groups[range.clone()].to_vec(),
            false => range.clone().map(|t| FLAT + t as u64).collect(),
        };
        // The line of the part's first face: where a message about it points.
        let at = |message: String| match scan.line_of(range.start).filter(|_| agrees) {
            Some(line) => Diagnostic::at(path, line, message),
            None => Diagnostic::file(path, message),
        };
        match convert_mesh(&model.mesh, &mut groups) {
            Ok(Some(mesh)) => {
                let material = model.mesh.material_id.filter(|&i| i < materials.len());
                if model.mesh.material_id.is_some() && material.is_none() {
                    let message = format!(
                        "object {} uses a material no library defines; drawn with the default",
                        crate::text::quote(&part_name)
                    );
                    warnings.push(at(message));
                }
                parts.push(ModelPart::new(part_name, mesh, material, vec![Mat4::IDENTITY]));
            }
            Ok(None) => {}
            Err(MeshError::Empty) => {
                let message = format!(
                    "object {} has no triangles: its faces are points, lines or name one corner twice",
                    crate::text::quote(&part_name)
                );
                return Err(at(message));
            }
            Err(e) => return Err(at(format!("object {}: {e}", crate::text::quote(&part_name)))),
        }
    }
    if parts.is_empty() {
        return Err(Diagnostic::file(path, "no faces: expected at least one triangle or polygon"));
    }
    let textures = textures.into_textures();
    Ok(Model {
        path: path.to_path_buf(),
        parts,
        materials,
        textures,
        nodes: Vec::new(),
        animations: Vec::new(),
        skins: Vec::new(),
        cameras: Vec::new(),
        lights: Vec::new(),
        warnings,
    })
}

/// Counts the bytes tobj has consumed, so a parse error can name its line
/// ([`line_at`]).
struct LineCounter<'a, R> {
    inner: R,
    consumed: &'a Cell<usize>,
}

impl<R: std::io::Read> std::io::Read for LineCounter<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let read = self.inner.read(buf)?;
        self.consumed.set(self.consumed.get() + read);
        Ok(read)
    }
}

impl<R: BufRead> BufRead for LineCounter<'_, R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }
    fn consume(&mut self, amount: usize) {
        self.consumed.set(self.consumed.get() + amount);
        self.inner.consume(amount);
    }
}

/// The 1-based line of the last line read when `consumed` bytes of `bytes` are:
/// tobj reads a line (newline included) and then parses it.
fn line_at(bytes: &[u8], consumed: usize) -> usize {
    let read = &bytes[..consumed.min(bytes.len())];
    let read = read.strip_suffix(b"\n").unwrap_or(read);
    read.iter().filter(|&&b| b == b'\n').count() + 1
}

/// Why an MTL library was not used: a file that cannot be read (a warning, the
/// parts draw with a default) or one that is malformed (an error).
enum MtlProblem {
    Unread(Diagnostic),
    Invalid(Diagnostic),
}

/// Load one MTL library named in the OBJ.
fn load_mtl(
    folder: &AssetFolder,
    mtl: &Path,
    obj: &Path,
) -> Result<(Vec<tobj::Material>, HashMap<String, usize>), MtlProblem> {
    let name = mtl.to_string_lossy();
    let path = folder.resolve(&name, obj).map_err(MtlProblem::Unread)?;
    let bytes = (folder.files.read(&path, super::MAX_MATERIAL_LIBRARY_BYTES))
        .map_err(|d| MtlProblem::Unread(Diagnostic::file(obj, format!("material library {d}"))))?;
    let text = checked_mtl(&path, &bytes).map_err(MtlProblem::Invalid)?;
    let consumed = Cell::new(0);
    let mut reader = LineCounter { inner: text.as_bytes(), consumed: &consumed };
    tobj::load_mtl_buf(&mut reader).map_err(|e| {
        MtlProblem::Invalid(Diagnostic::at(&path, line_at(text.as_bytes(), consumed.get()), format!("{e}")))
    })
}

/// Check the numbers of an MTL library line by line, before tobj reads it
/// (tobj takes `nan` and `inf`, and panics on a colour of fewer than three
/// numbers): colours (`Ka Kd Ks Ke`) are one grey value or three, finite and not
/// negative; `Ns` and `Ni` are finite and not negative; `d` (`-halo` is read as
/// plain `d`) and `Tr` lie in 0..=1; texture options take finite numbers. Returns
/// the text for tobj, line for line, with a grey `Kd g` written `Kd g g g`.
fn checked_mtl(path: &Path, bytes: &[u8]) -> Result<String, Diagnostic> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        Diagnostic::at(path, line, "not UTF-8 text: expected an MTL material library")
    })?;
    let mut out = String::with_capacity(text.len() + 16);
    for (number, line) in text.lines().enumerate() {
        let at = |message: String| Diagnostic::at(path, number + 1, message);
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        // What follows a `#` is a comment.
        let rest: Vec<&str> = words.take_while(|w| !w.starts_with('#')).collect();
        let numbers = |what: &str| -> Result<Vec<f32>, Diagnostic> {
            rest.iter().map(|w| w.parse::<f32>().map_err(|_| at(format!("{keyword}: expected {what}")))).collect()
        };
        match keyword {
            "Ka" | "Kd" | "Ks" | "Ke" => {
                let expected = "r g b (or one grey value), numbers ≥ 0";
                if matches!(rest.first(), Some(&("spectral" | "xyz"))) {
                    return Err(at(format!(
                        "{keyword}: spectral and xyz colours are not supported; expected {expected}"
                    )));
                }
                let values = numbers(expected)?;
                if !matches!(values.len(), 1 | 3) || values.iter().any(|v| !v.is_finite() || *v < 0.0) {
                    return Err(at(format!("{keyword}: expected {expected}, finite")));
                }
                if let [grey] = values[..] {
                    out += &format!("{keyword} {grey} {grey} {grey}\n");
                    continue;
                }
            }
            "Ns" | "Ni" | "d" | "Tr" => {
                let halo = keyword == "d" && rest.first() == Some(&"-halo");
                let (range, expected) = match keyword {
                    "Ns" | "Ni" => (0.0..=f32::MAX, "one finite number ≥ 0"),
                    _ => (0.0..=1.0, "one number from 0 to 1"),
                };
                let values: Vec<f32> = if halo {
                    rest[1..].iter().map(|w| w.parse::<f32>().unwrap_or(f32::NAN)).collect()
                } else {
                    numbers(expected)?
                };
                match values[..] {
                    [v] if range.contains(&v) => {
                        if halo {
                            out += &format!("d {v}\n");
                            continue;
                        }
                    }
                    _ => return Err(at(format!("{keyword}: expected {expected}"))),
                }
            }
            "map_Ka" | "map_Kd" | "map_Ks" | "map_Ke" | "map_Ns" | "map_ns" | "map_NS" | "map_d" | "map_Bump"
            | "map_bump" | "bump" | "disp" | "decal" | "refl" | "norm" => {
                let statement = line.trim_start()[keyword.len()..].trim();
                if let Err(TextureError::NonFinite(option)) = parse_texture_statement(statement) {
                    return Err(at(format!("{keyword}: texture option {option} takes finite numbers")));
                }
            }
            _ => {}
        }
        out += line;
        out.push('\n');
    }
    Ok(out)
}

/// An MTL texture statement: the file name and the options glint uses.
#[derive(Debug, PartialEq)]
struct TextureStatement {
    file: String,
    /// `-s u v w`: texture coordinate scale.
    scale: Option<Vec2>,
}

/// Why a texture statement was not understood.
#[derive(Debug, PartialEq)]
enum TextureError {
    /// An option's number is NaN or infinite: the library is malformed.
    NonFinite(String),
    /// Anything else (an unknown option, no file name): the map is ignored.
    Other(String),
}

impl std::fmt::Display for TextureError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NonFinite(option) => write!(f, "texture option {option} takes finite numbers"),
            Self::Other(message) => f.write_str(message),
        }
    }
}

/// Split `-opt args… file name` into options and the file name. Options take the
/// argument counts the MTL format gives them (`-o`, `-s`, `-t` take one to three
/// numbers); whatever follows the options is the file name, spaces included.
fn parse_texture_statement(text: &str) -> Result<TextureStatement, TextureError> {
    let tokens: Vec<&str> = text.split_whitespace().collect();
    let mut at = 0;
    let mut scale = None;
    while at < tokens.len() && tokens[at].starts_with('-') && tokens[at].len() > 1 {
        let option = tokens[at];
        at += 1;
        let numbers = |at: &mut usize, most: usize| {
            let mut values = Vec::new();
            while values.len() < most && *at < tokens.len() {
                match tokens[*at].parse::<f32>() {
                    Ok(v) if v.is_finite() => values.push(v),
                    Ok(_) => return Err(TextureError::NonFinite(option.to_string())),
                    Err(_) => break,
                }
                *at += 1;
            }
            Ok(values)
        };
        match option {
            "-o" | "-t" => drop(numbers(&mut at, 3)?),
            "-s" => {
                let v = numbers(&mut at, 3)?;
                if let [u, rest @ ..] = v.as_slice() {
                    scale = Some(Vec2::new(*u, rest.first().copied().unwrap_or(*u)));
                }
            }
            "-mm" => drop(numbers(&mut at, 2)?),
            "-bm" | "-boost" | "-texres" => drop(numbers(&mut at, 1)?),
            "-blendu" | "-blendv" | "-cc" | "-clamp" | "-imfchan" | "-type" => at += 1,
            other => return Err(TextureError::Other(format!("unknown texture option {}", crate::text::quote(other)))),
        }
    }
    let Some(first) = tokens.get(at) else {
        return Err(TextureError::Other("texture statement has options but no file name".into()));
    };
    // The file name runs from its first token to the end, so runs of spaces survive.
    let start = first.as_ptr() as usize - text.as_ptr() as usize;
    Ok(TextureStatement { file: text[start..].trim().to_string(), scale })
}

/// Turn a tobj material into glint's, loading its textures (warnings for those
/// that fail: the material then draws without that map).
fn convert_material(
    m: &tobj::Material,
    folder: &AssetFolder,
    obj: &Path,
    cache: &mut TextureCache<PathBuf>,
    warnings: &mut Vec<Diagnostic>,
) -> MaterialDesc {
    let diffuse = m.diffuse.unwrap_or([0.8; 3]);
    let alpha = m.dissolve.unwrap_or(1.0).clamp(0.0, 1.0);
    let specular = m.specular.map_or(0.0, |s| (s[0] + s[1] + s[2]) / 3.0);
    // Blinn-Phong exponent 2^(1 + 11·smoothness): invert for Ns.
    let smoothness = m.shininess.map_or(0.3, |ns| ((ns.max(2.0).log2() - 1.0) / 11.0).clamp(0.0, 1.0));
    let mut material = Material {
        name: m.name.clone(),
        base_color: glam::Vec4::new(diffuse[0], diffuse[1], diffuse[2], alpha),
        specular: specular.clamp(0.0, 1.0),
        smoothness,
        alpha_mode: if alpha < 1.0 { AlphaMode::Blend } else { AlphaMode::Opaque },
        ..Material::default()
    };
    let mut texture = |statement: &Option<String>, srgb: bool, what: &str, material: &mut Material| {
        let text = statement.as_deref()?;
        let parsed = match parse_texture_statement(text) {
            Ok(p) => p,
            Err(e) => {
                warnings.push(Diagnostic::file(
                    obj,
                    format!("material {}: {what}: {e}; ignored", crate::text::quote(&m.name)),
                ));
                return None;
            }
        };
        if let Some(scale) = parsed.scale {
            material.uv_scale = scale;
        }
        let path = match folder.resolve(&parsed.file, obj) {
            Ok(p) => p,
            Err(d) => {
                warnings.push(d);
                return None;
            }
        };
        let decoded = cache.get_or_decode(path.clone(), srgb, |free| read_texture(&path, srgb, free, &folder.files));
        let drawn_without = |d| {
            Diagnostic::file(obj, format!("material {}: {what}: {d}; drawn without it", crate::text::quote(&m.name)))
        };
        decoded.map_err(|d| warnings.push(drawn_without(d))).ok()
    };
    let mut diffuse_map = texture(&m.diffuse_texture, true, "map_Kd", &mut material);
    let normal_map = texture(&m.normal_texture, false, "map_Bump", &mut material);
    let specular_map = texture(&m.specular_texture, false, "map_Ks", &mut material);
    // map_d becomes the diffuse map's alpha (a white map when there is none);
    // alpha-tested at 0.5, as cut-outs such as leaves expect.
    if let Some(dissolve) = texture(&m.dissolve_texture, false, "map_d", &mut material) {
        let key = PathBuf::from(format!("{:?} with map_d {dissolve}", diffuse_map));
        let color = diffuse_map.map(|d| cache.get(d).clone());
        let masked = super::texture::with_dissolve(color.as_ref(), cache.get(dissolve));
        diffuse_map = cache.get_or_decode(key, true, |_| Ok::<_, Diagnostic>(masked)).ok();
        material.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    }
    MaterialDesc { material, diffuse_map, normal_map, specular_map, ..MaterialDesc::default() }
}

/// Flat face `f` (counted in file order) has group `FLAT + f`, alone; smoothing
/// groups `s 1`, `s 2` ... are groups 1, 2 ... (below `FLAT`).
const FLAT: u64 = 1 << 32;

/// What one pass over the OBJ text finds that tobj does not report.
struct ObjScan {
    /// The smoothing group of every triangle tobj makes, in tobj's order: faces
    /// (`f` and `l` lines) in file order, an n-gon as n − 2 fan triangles, a point
    /// or a line as one (degenerate) triangle.
    groups: Vec<u64>,
    /// Each face's first triangle and line, in file order.
    faces: Vec<(usize, usize)>,
}

impl ObjScan {
    /// The line of the face that made `triangle`.
    fn line_of(&self, triangle: usize) -> Option<usize> {
        let face = self.faces.partition_point(|&(first, _)| first <= triangle).checked_sub(1)?;
        Some(self.faces[face].1)
    }
}

/// Scan the OBJ text once, after tobj has read it: every `v`, `vt` and `vn`
/// number must be finite (tobj takes `nan` and `inf`; a position is divided by
/// its `w` as tobj does), and each face gets its smoothing group. Faces are flat
/// until an `s N` statement (N > 0) puts them in group N; `s off` and `s 0` make
/// them flat again. An `s` value that is neither a number nor `off` is a warning
/// and means off.
fn scan_obj(path: &Path, bytes: &[u8], warnings: &mut Vec<Diagnostic>) -> Result<ObjScan, Diagnostic> {
    // tobj has read the file line by line as UTF-8 already.
    let text = std::str::from_utf8(bytes).map_err(|_| Diagnostic::file(path, "not UTF-8 text"))?;
    let mut scan = ObjScan { groups: Vec::new(), faces: Vec::new() };
    let mut current = None;
    for (number, line) in text.lines().enumerate() {
        let at = |message: &str| Diagnostic::at(path, number + 1, message);
        let mut words = line.split_whitespace();
        let finite = |words: std::str::SplitWhitespace, count: usize| {
            let values: Vec<f32> = words.take(count).filter_map(|w| w.parse::<f32>().ok()).collect();
            values.iter().all(|v| v.is_finite())
        };
        match words.next() {
            Some("v") => {
                let values: Vec<f32> = words.filter_map(|w| w.parse::<f32>().ok()).collect();
                // x y z, x y z w (divided by w) or x y z r g b.
                let w = if values.len() == 4 { values[3] } else { 1.0 };
                if !values.iter().take(3).map(|v| v / w).chain(values.iter().copied()).all(f32::is_finite) {
                    return Err(at("vertex position is not finite (NaN or infinite)"));
                }
            }
            Some("vt") if !finite(words.clone(), 2) => {
                return Err(at("texture coordinate is not finite (NaN or infinite)"));
            }
            Some("vn") if !finite(words.clone(), 3) => return Err(at("normal is not finite (NaN or infinite)")),
            Some("s") => {
                current = match words.next().map(|w| (w, w.parse::<u32>())) {
                    Some((_, Ok(0))) | Some(("off", _)) => None,
                    Some((_, Ok(group))) => Some(u64::from(group)),
                    _ => {
                        let message = "expected a smoothing group number or 'off'; read as off";
                        warnings.push(Diagnostic::at(path, number + 1, message));
                        None
                    }
                };
            }
            Some("f" | "l") => {
                let triangles = words.count().saturating_sub(2).max(1);
                let group = current.unwrap_or(FLAT + scan.faces.len() as u64);
                scan.faces.push((scan.groups.len(), number + 1));
                scan.groups.extend(std::iter::repeat_n(group, triangles));
            }
            _ => {}
        }
    }
    Ok(scan)
}

/// Give faces that name the same corners in the same order one flat group, so
/// they share vertices (a file repeating a face a million times then has three,
/// not three million). A flat face is a run of triangles with one group ≥ `FLAT`.
fn merge_repeated_flat_faces(indices: &[u32], groups: &mut [u64]) {
    let mut first: HashMap<&[u32], u64> = HashMap::new();
    let mut start = 0;
    while start < groups.len() {
        let group = groups[start];
        let end = start + groups[start..].iter().take_while(|&&g| g == group).count();
        if group >= FLAT {
            let canonical = *first.entry(&indices[start * 3..end * 3]).or_insert(group);
            groups[start..end].fill(canonical);
        }
        start = end;
    }
}

/// Split the vertices that triangles of different smoothing groups share: for
/// each new vertex its old one and its group, and the new indices.
fn split_by_group(indices: &[u32], groups: &[u64]) -> (Vec<u32>, Vec<u64>, Vec<u32>) {
    let mut new_vertex: HashMap<(u32, u64), u32> = HashMap::new();
    let (mut source, mut vertex_groups, mut new_indices) = (Vec::new(), Vec::new(), Vec::with_capacity(indices.len()));
    for (triangle, &group) in indices.chunks_exact(3).zip(groups) {
        for &v in triangle {
            let next = source.len() as u32;
            let at = *new_vertex.entry((v, group)).or_insert_with(|| {
                source.push(v);
                vertex_groups.push(group);
                next
            });
            new_indices.push(at);
        }
    }
    (source, vertex_groups, new_indices)
}

/// Build a glint mesh from a tobj mesh and each of its triangles' smoothing
/// group (see [`scan_obj`]; used only when the file gives no normals):
/// `Ok(None)` for a mesh without faces.
fn convert_mesh(mesh: &tobj::Mesh, groups: &mut [u64]) -> Result<Option<Mesh>, MeshError> {
    if mesh.indices.is_empty() {
        return Ok(None);
    }
    let positions: Vec<Vec3> = mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let count = positions.len();
    // OBJ's v runs up the image; glint's (like glTF's) runs down.
    let uvs: Vec<Vec2> = if mesh.texcoords.len() == count * 2 {
        mesh.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])).collect()
    } else {
        vec![Vec2::ZERO; count]
    };
    if mesh.normals.len() == count * 3 {
        let normals: Vec<Vec3> = mesh.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])).collect();
        return Mesh::from_attributes(&positions, &normals, &uvs, mesh.indices.clone()).map(Some);
    }
    merge_repeated_flat_faces(&mesh.indices, groups);
    // tobj's indices are within its vertex arrays.
    let (source, vertex_groups, indices) = split_by_group(&mesh.indices, groups);
    let positions: Vec<Vec3> = source.iter().map(|&v| positions[v as usize]).collect();
    let uvs: Vec<Vec2> = source.iter().map(|&v| uvs[v as usize]).collect();
    let normals = smooth_normals_in_groups(&positions, &indices, &vertex_groups);
    Mesh::from_attributes(&positions, &normals, &uvs, indices).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_options_are_options_and_the_rest_is_the_file_name() {
        let s = parse_texture_statement("-s 2 3 1 -o 0.5 0.5 0 -bm 0.2 my wood.png").expect("valid");
        assert_eq!(s, TextureStatement { file: "my wood.png".into(), scale: Some(Vec2::new(2.0, 3.0)) });
        let s = parse_texture_statement("-clamp on -s 4 tiles.png").expect("valid");
        assert_eq!(s, TextureStatement { file: "tiles.png".into(), scale: Some(Vec2::splat(4.0)) });
        assert_eq!(parse_texture_statement("plain.png").expect("valid").file, "plain.png");
        assert!(parse_texture_statement("-bm 0.5").is_err(), "options without a file");
        assert!(parse_texture_statement("-zap 1 x.png").is_err());
        for bad in ["-s nan 1 1 x.png", "-o 0 inf x.png", "-bm -inf x.png", "-s 1e39 x.png"] {
            let option = bad.split(' ').next().unwrap_or_default().to_string();
            assert_eq!(parse_texture_statement(bad), Err(TextureError::NonFinite(option)), "{bad}");
        }
    }

    /// A unit cube's eight corners, then its six quads (counter-clockwise from
    /// outside), each quad preceded by the line `before(face)`.
    fn cube(before: impl Fn(usize) -> &'static str) -> String {
        let mut text = String::new();
        for z in [-1, 1] {
            for y in [-1, 1] {
                for x in [-1, 1] {
                    text += &format!("v {x} {y} {z}\n");
                }
            }
        }
        // Corner i is at (x, y, z) = bits (0, 1, 2) of i - 1.
        let quads = ["1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6"];
        for (face, quad) in quads.iter().enumerate() {
            text += &format!("{}\nf {quad}\n", before(face));
        }
        text
    }

    fn parts(text: &str) -> (Vec<Mesh>, Vec<Diagnostic>) {
        let model = parse_obj(Path::new("cube.obj"), text.as_bytes(), LoadOptions::default()).expect("loads");
        (model.parts.into_iter().map(|p| p.mesh).collect(), model.warnings)
    }

    /// Every vertex normal, keyed by its position.
    fn normals_at(mesh: &Mesh, position: Vec3) -> Vec<Vec3> {
        let at = mesh.vertices().iter().filter(|v| Vec3::from(v.position) == position);
        at.map(|v| Vec3::from(v.normal)).collect()
    }

    /// Every corner of every triangle has its face's normal.
    fn assert_flat(mesh: &Mesh, what: &str) {
        for triangle in mesh.indices().chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(mesh.vertices()[triangle[k] as usize].position));
            let face = (b - a).cross(c - a).normalize();
            for &i in triangle {
                assert!((Vec3::from(mesh.vertices()[i as usize].normal) - face).length() < 1e-5, "{what}");
            }
        }
    }

    #[test]
    fn faces_are_flat_without_a_smoothing_group() {
        // No `s` at all (as in the classic Cornell box), `s off`, `s 0`, and faces
        // before the first `s 1`: flat, as Blender's importer draws them.
        let before_s1 = |face| if face < 5 { "" } else { "s 1" };
        let cases: [(&str, &dyn Fn(usize) -> &'static str); 4] =
            [("no s", &|_| ""), ("s off", &|_| "s off"), ("s 0", &|_| "s 0"), ("before s 1", &before_s1)];
        for (what, before) in cases {
            let (meshes, warnings) = parts(&cube(before));
            assert!(warnings.is_empty(), "{warnings:?}");
            assert_eq!(meshes[0].vertices().len(), 24, "{what}: each face has its own four corners");
            assert_flat(&meshes[0], what);
        }
    }

    #[test]
    fn one_smoothing_group_smooths_every_corner() {
        let (meshes, _) = parts(&cube(|face| if face == 0 { "s 1" } else { "" }));
        assert_eq!(meshes[0].vertices().len(), 8);
        let corner = normals_at(&meshes[0], Vec3::ONE);
        assert!(corner.len() == 1 && (corner[0] - Vec3::ONE.normalize()).length() < 1e-5, "{corner:?}");
    }

    #[test]
    fn repeated_flat_faces_share_their_vertices() {
        let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n{}f 2 4 3\n", "f 1 2 3\n".repeat(5));
        let (meshes, _) = parts(&text);
        assert_eq!(meshes[0].indices().len(), 6 * 3, "every face is drawn");
        assert_eq!(meshes[0].vertices().len(), 3 + 3, "the repeats share three vertices");
        assert_flat(&meshes[0], "repeats");
    }

    #[test]
    fn smoothing_groups_smooth_only_within_a_group() {
        // The two z faces in group 2, the four x and y faces in group 1.
        let (meshes, _) = parts(&cube(|face| if face < 2 { "s 2" } else { "s 1" }));
        let mut corner = normals_at(&meshes[0], Vec3::ONE);
        corner.sort_by(|a, b| a.z.total_cmp(&b.z));
        assert_eq!(corner.len(), 2, "one corner vertex per group: {corner:?}");
        assert!((corner[0] - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-5, "x and y faces: {corner:?}");
        assert!((corner[1] - Vec3::Z).length() < 1e-5, "the z faces do not smooth with each other: {corner:?}");
    }

    #[test]
    fn smoothing_groups_follow_faces_across_objects_and_polygon_sizes() {
        // Two objects: the first all smooth, the second flat; triangle counts per
        // face differ (a quad, then a pentagon fan) to check the face order.
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0.5\nv 0 0 1\n\
                    o smooth\ns 1\nf 1 2 3 4\nf 1 6 2\n\
                    o flat\ns off\nf 1 2 3 5 4\nf 1 6 2\ns bogus\nf 2 6 3\n";
        let (meshes, warnings) = parts(text);
        assert_eq!(meshes.len(), 2);
        assert_eq!(meshes[0].vertices().len(), 5, "smooth: corners shared");
        assert_eq!(meshes[1].vertices().len(), 5 + 3 + 3, "flat: the pentagon's corners, then two triangles");
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert_eq!(warnings[0].line, Some(15), "{}", warnings[0]);
    }

    #[test]
    fn non_finite_positions_normals_and_uvs_are_errors_at_their_line() {
        let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let cases = [
            ("v nan 0 0\n", "position"),
            ("v 1e39 0 0\n", "position"),
            // Finite as written, infinite once divided by w.
            ("v 1 1 1 1e-39\n", "position"),
            ("v 1 1 1 inf\n", "position"),
            ("vt nan 0\n", "texture coordinate"),
            ("vt 0 -inf\n", "texture coordinate"),
            ("vn nan nan nan\n", "normal"),
            ("vn 0 0 inf\n", "normal"),
        ];
        for (bad, what) in cases {
            let text = format!("{triangle}# the bad line:\n{bad}f 1 2 3\n");
            let e = parse_obj(Path::new("bad.obj"), text.as_bytes(), LoadOptions::default()).expect_err(bad);
            assert_eq!(e.line, Some(5), "{bad}: {e}");
            assert!(e.message.contains(what) && e.message.contains("not finite"), "{bad}: {e}");
        }
    }

    #[test]
    fn per_object_errors_name_the_line_of_the_objects_first_face() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\no good\nf 1 2 3\no lines\nl 1 2\nf 1 1 2\n";
        let e = parse_obj(Path::new("lines.obj"), text.as_bytes(), LoadOptions::default()).expect_err("no triangles");
        assert_eq!(e.line, Some(7), "{e}");
        assert!(e.message.contains("'lines'") && e.message.contains("no triangles"), "{e}");
    }

    /// Load `obj` with `mtl` beside it as `lib.mtl`, in a fresh folder.
    fn load_with_mtl(name: &str, obj: &str, mtl: &str) -> Result<Model, Diagnostic> {
        let dir = std::env::temp_dir().join(format!("glint-obj-mtl-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(dir.join("lib.mtl"), mtl).expect("write mtl");
        let path = dir.join("model.obj");
        let result = parse_obj(&path, obj.as_bytes(), LoadOptions::default());
        let _ = std::fs::remove_dir_all(&dir);
        result
    }

    const USES_LIB: &str = "mtllib lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";

    #[test]
    fn mtl_numbers_must_be_finite_and_in_range_with_the_mtl_line() {
        let cases = [
            "Kd nan 0 0",
            "Kd 1 0 inf",
            "Ka -0.5 0 0",
            "Ks 1 1 1e39",
            "Ke nan",
            // tobj panics on a colour of two numbers.
            "Kd 1 0",
            "Kd spectral sun.rfl",
            "Ns nan",
            "Ns -1",
            "Ni inf",
            "Ni -1.5",
            "d nan",
            "d 1.5",
            "d -halo -1",
            "Tr nan",
            "Tr -0.5",
            "map_Kd -s nan 1 1 tiles.png",
            "map_Bump -bm inf normal.png",
            "bump -o 0 1e39 0 normal.png",
        ];
        for (k, bad) in cases.iter().enumerate() {
            let mtl = format!("# made by a test\nnewmtl m\n{bad}\nillum 2\n");
            let e = load_with_mtl(&format!("bad{k}"), USES_LIB, &mtl).expect_err(bad);
            assert!(e.path.ends_with("lib.mtl"), "{bad}: the MTL is named: {e}");
            assert_eq!(e.line, Some(3), "{bad}: {e}");
            let keyword = bad.split_whitespace().next().unwrap_or_default();
            assert!(e.message.starts_with(keyword), "{bad}: {e}");
        }
    }

    #[test]
    fn mtl_grey_colours_halo_dissolve_and_comments_are_read() {
        let mtl = "newmtl m\nKd 0.25 # grey\nd -halo 0.5\nNs 10 # shiny\nTr 0.5\n";
        let model = load_with_mtl("grey", USES_LIB, mtl).expect("valid");
        assert!(model.warnings.is_empty(), "{:?}", model.warnings);
        let color = model.materials[0].material.base_color;
        assert_eq!(color, glam::Vec4::new(0.25, 0.25, 0.25, 0.5), "Kd 0.25 is grey; d -halo 0.5 is d 0.5");
        // A malformed statement tobj finds is an error at its MTL line too.
        let e = load_with_mtl("illum", USES_LIB, "newmtl m\n\nillum bright\n").expect_err("bad illum");
        assert!(e.path.ends_with("lib.mtl") && e.line == Some(3), "{e}");
        // A library without materials loads, with a warning.
        let model = load_with_mtl("empty", USES_LIB, "root:x:0:0\n").expect("loads");
        assert!(model.warnings.iter().any(|w| w.message.contains("defines no materials")), "{:?}", model.warnings);
    }

    /// Hostile repetition loads in linear time. A benchmark, not a timed test:
    /// `cargo test --release -p glint --lib repeated_faces -- --ignored --nocapture`
    /// prints each case's time; `GLINT_OBJ_BENCH_FACES` sets N (default 10⁶).
    #[test]
    #[ignore = "a benchmark: prints load times, asserts none"]
    fn repeated_faces_load_in_linear_time() {
        let n: usize = std::env::var("GLINT_OBJ_BENCH_FACES").ok().and_then(|s| s.parse().ok()).unwrap_or(1_000_000);
        let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let circle: String = (0..n)
            .map(|i| {
                let a = i as f32 / n as f32 * std::f32::consts::TAU;
                format!("v {} {} 0\n", a.cos(), a.sin())
            })
            .collect();
        let fan: String = (1..=n).map(|i| format!(" {i}")).collect();
        let cases = [
            ("N faces 'f 1 2 3'", format!("{triangle}{}", "f 1 2 3\n".repeat(n))),
            ("N faces 'f 1 2 3' in 's 1'", format!("{triangle}s 1\n{}", "f 1 2 3\n".repeat(n))),
            ("one face of N corners over 3 vertices", format!("{triangle}f{}\n", " 1 2 3".repeat(n / 3))),
            ("one convex face of N distinct corners", format!("{circle}f{fan}\n")),
        ];
        for (name, text) in cases {
            let start = web_time::Instant::now();
            let loaded = parse_obj(Path::new("bench.obj"), text.as_bytes(), LoadOptions::default());
            let seconds = start.elapsed().as_secs_f64();
            let outcome = match loaded {
                Ok(model) => {
                    format!("{} triangles", model.parts.iter().map(|p| p.mesh.indices().len() / 3).sum::<usize>())
                }
                Err(e) => format!("error: {e}"),
            };
            println!("{name}, N = {n}: {seconds:.3} s ({outcome})");
        }
    }
}
