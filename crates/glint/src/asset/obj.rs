//! Core layer: Wavefront OBJ + MTL through `tobj`. Polygons are triangulated; every
//! object/group × material run becomes its own part with its own MTL material;
//! missing normals are computed (angle-weighted, shared by vertices at one
//! position and in one smoothing group; see [`smoothing_groups`]); missing
//! texture coordinates are allowed. MTL texture statements are
//! split into options (`-s`, `-o`, `-bm` ...) and a file name that may hold spaces.
//! A missing `.mtl` or texture is a warning and a visible default, not a failure.
//! Paths in the files resolve inside the model's folder only (see [`LoadOptions`]).

use super::model::{Model, ModelPart};
use super::texture::TextureCache;
use super::{load_texture, read_capped, AssetFolder, Diagnostic, LoadOptions, MaterialDesc};
use crate::scene::{smooth_normals, smooth_normals_in_groups, AlphaMode, Material, Mesh};
use glam::{Mat4, Vec2, Vec3};
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};

/// Parse OBJ text read from `path` (which names it in messages and anchors the
/// MTL libraries and textures it names).
pub(crate) fn parse_obj(path: &Path, bytes: &[u8], options: LoadOptions) -> Result<Model, Diagnostic> {
    let folder = AssetFolder::of(path, options);
    let warnings = RefCell::new(Vec::new());
    let line = Cell::new(0);
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let mut reader = LineCounter { inner: bytes, line: &line };
    let loaded = tobj::load_obj_buf(&mut reader, &options, |mtl: &Path| {
        load_mtl(&folder, mtl, path).map_err(|warning| {
            warnings.borrow_mut().push(warning);
            tobj::LoadError::OpenFileFailed
        })
    });
    let (models, materials) = loaded.map_err(|e| Diagnostic::at(path, line.get().max(1), format!("{e}")))?;
    let mut warnings = warnings.into_inner();
    // A failed library is already a warning; the parts then use the default material.
    let materials = materials.unwrap_or_default();
    let mut textures = TextureCache::default();
    let materials: Vec<MaterialDesc> =
        materials.iter().map(|m| convert_material(m, &folder, path, &mut textures, &mut warnings)).collect();
    // tobj does not read `s` statements: find each triangle's group in the text,
    // only when some normals must be computed.
    let computes_normals = models.iter().any(|m| m.mesh.normals.len() != m.mesh.positions.len());
    let triangles: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    let groups = computes_normals.then(|| smoothing_groups(path, bytes, &mut warnings)).flatten().filter(|groups| {
        let agrees = groups.len() == triangles;
        if !agrees {
            let message = format!("{} faces by smoothing group, {triangles} loaded; groups ignored", groups.len());
            warnings.push(Diagnostic::file(path, message));
        }
        agrees
    });
    let mut parts = Vec::new();
    let mut first_triangle = 0;
    for model in models {
        let part_name = model.name.clone();
        let part_triangles = model.mesh.indices.len() / 3;
        let part_groups = groups.as_deref().map(|g| &g[first_triangle..first_triangle + part_triangles]);
        first_triangle += part_triangles;
        match convert_mesh(&model.mesh, part_groups) {
            Ok(Some(mesh)) => {
                let material = model.mesh.material_id.filter(|&i| i < materials.len());
                if model.mesh.material_id.is_some() && material.is_none() {
                    let message =
                        format!("object '{part_name}' uses a material no library defines; drawn with the default");
                    warnings.push(Diagnostic::file(path, message));
                }
                parts.push(ModelPart::new(part_name, mesh, material, vec![Mat4::IDENTITY]));
            }
            Ok(None) => {}
            Err(e) => return Err(Diagnostic::file(path, format!("object '{part_name}': {e}"))),
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

/// Counts the lines tobj has read, so a parse error can name its line.
struct LineCounter<'a, R> {
    inner: R,
    line: &'a Cell<usize>,
}

impl<R: std::io::Read> std::io::Read for LineCounter<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.inner.read(buf)
    }
}

impl<R: BufRead> BufRead for LineCounter<'_, R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }
    fn consume(&mut self, amount: usize) {
        // tobj reads line by line: every consumed newline ends one.
        if let Ok(buf) = self.inner.fill_buf() {
            let newlines = buf[..amount.min(buf.len())].iter().filter(|&&b| b == b'\n').count();
            self.line.set(self.line.get() + newlines);
        }
        self.inner.consume(amount);
    }
}

/// Load one MTL library named in the OBJ; a problem comes back as a warning.
fn load_mtl(
    folder: &AssetFolder,
    mtl: &Path,
    obj: &Path,
) -> Result<(Vec<tobj::Material>, HashMap<String, usize>), Diagnostic> {
    let name = mtl.to_string_lossy();
    let path = folder.resolve(&name, obj)?;
    let bytes = read_capped(&path).map_err(|d| Diagnostic::file(obj, format!("material library {d}")))?;
    let line = Cell::new(0);
    let mut reader = LineCounter { inner: bytes.as_slice(), line: &line };
    tobj::load_mtl_buf(&mut reader).map_err(|e| Diagnostic::at(&path, line.get().max(1), format!("{e}")))
}

/// An MTL texture statement: the file name and the options glint uses.
#[derive(Debug, PartialEq)]
struct TextureStatement {
    file: String,
    /// `-s u v w`: texture coordinate scale.
    scale: Option<Vec2>,
}

/// Split `-opt args… file name` into options and the file name. Options take the
/// argument counts the MTL format gives them (`-o`, `-s`, `-t` take one to three
/// numbers); whatever follows the options is the file name, spaces included.
fn parse_texture_statement(text: &str) -> Result<TextureStatement, String> {
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
                    Ok(v) => values.push(v),
                    Err(_) => break,
                }
                *at += 1;
            }
            values
        };
        match option {
            "-o" | "-t" => drop(numbers(&mut at, 3)),
            "-s" => {
                let v = numbers(&mut at, 3);
                if let [u, rest @ ..] = v.as_slice() {
                    scale = Some(Vec2::new(*u, rest.first().copied().unwrap_or(*u)));
                }
            }
            "-mm" => drop(numbers(&mut at, 2)),
            "-bm" | "-boost" | "-texres" => drop(numbers(&mut at, 1)),
            "-blendu" | "-blendv" | "-cc" | "-clamp" | "-imfchan" | "-type" => at += 1,
            other => return Err(format!("unknown texture option '{other}'")),
        }
    }
    if at >= tokens.len() {
        return Err("texture statement has options but no file name".into());
    }
    // Rebuild the file name from the original text so runs of spaces survive.
    let start = text.find(tokens[at]).unwrap_or(0);
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
                warnings.push(Diagnostic::file(obj, format!("material '{}': {what}: {e}; ignored", m.name)));
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
        let decoded = cache.get_or_decode(path.clone(), srgb, || load_texture(&path, srgb));
        let drawn_without = |d| Diagnostic::file(obj, format!("material '{}': {what}: {d}; drawn without it", m.name));
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
        diffuse_map = cache.get_or_decode(key, true, || Ok::<_, Diagnostic>(masked)).ok();
        material.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    }
    MaterialDesc { material, diffuse_map, normal_map, specular_map, ..MaterialDesc::default() }
}

/// A triangle's smoothing group for [`smooth_normals_in_groups`]: `s 1`, `s 2` ...
/// are groups 1, 2 ...; `s off` / `s 0` is [`SMOOTHING_OFF`]; faces before any
/// `s` statement share [`BEFORE_ANY_S`], a group of their own.
const SMOOTHING_OFF: u64 = 0;
/// The group of faces before the file's first `s` statement.
const BEFORE_ANY_S: u64 = 1 << 32;
/// Flat face `f` (counted in file order) is put alone in group `FLAT + f`.
const FLAT: u64 = 1 << 33;

/// The smoothing group of every triangle tobj makes from the OBJ text, in tobj's
/// order: faces (`f` and `l` lines) in file order, an n-gon as n − 2 fan
/// triangles, a point or a line as one (degenerate) triangle. `None` when
/// the file has no `s` statement (then every face smooths
/// with its neighbours). An `s` value that is neither a number nor `off` is a
/// warning and means off.
fn smoothing_groups(path: &Path, bytes: &[u8], warnings: &mut Vec<Diagnostic>) -> Option<Vec<u64>> {
    // tobj has read the file line by line as UTF-8 already.
    let text = std::str::from_utf8(bytes).ok()?;
    let mut groups = Vec::new();
    let mut current = BEFORE_ANY_S;
    let (mut any, mut faces) = (false, 0);
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("s") => {
                any = true;
                current = match words.next().map(|w| (w, w.parse::<u32>())) {
                    Some((_, Ok(group))) => u64::from(group),
                    Some(("off", _)) => SMOOTHING_OFF,
                    other => {
                        let found = other.map_or("nothing", |(w, _)| w);
                        let message = format!("expected a smoothing group number or 'off', found '{found}'; off");
                        warnings.push(Diagnostic::at(path, number + 1, message));
                        SMOOTHING_OFF
                    }
                };
            }
            Some("f" | "l") => {
                let triangles = words.count().saturating_sub(2).max(1);
                let group = if current == SMOOTHING_OFF { FLAT + faces } else { current };
                groups.extend(std::iter::repeat_n(group, triangles));
                faces += 1;
            }
            _ => {}
        }
    }
    any.then_some(groups)
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

/// Build a glint mesh from a tobj mesh, with each triangle's smoothing group when
/// the file has them: `Ok(None)` for a mesh without faces.
fn convert_mesh(mesh: &tobj::Mesh, groups: Option<&[u64]>) -> Result<Option<Mesh>, crate::scene::MeshError> {
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
    let Some(groups) = groups else {
        let normals = smooth_normals(&positions, &mesh.indices);
        return Mesh::from_attributes(&positions, &normals, &uvs, mesh.indices.clone()).map(Some);
    };
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
    }

    #[test]
    fn paths_stay_inside_the_model_folder() {
        let obj = Path::new("m/model.obj");
        let inside = AssetFolder::of(obj, LoadOptions::default());
        assert_eq!(inside.resolve("tex/a.png", obj).expect("inside"), Path::new("m/tex/a.png"));
        assert!(inside.resolve("tex/../a.png", obj).is_ok());
        for outside in ["../secret.png", "tex/../../secret.png", "/etc/passwd", "file:///etc/passwd", "http://x/y.png"]
        {
            assert!(inside.resolve(outside, obj).is_err(), "{outside}");
        }
        let anywhere = AssetFolder::of(obj, LoadOptions { allow_outside_assets: true });
        assert_eq!(anywhere.resolve("../shared/a.png", obj).expect("allowed"), Path::new("m/../shared/a.png"));
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

    #[test]
    fn without_smoothing_groups_every_corner_is_smooth() {
        let (meshes, _) = parts(&cube(|_| ""));
        let corner = normals_at(&meshes[0], Vec3::ONE);
        assert!(
            !corner.is_empty() && corner.iter().all(|n| (*n - Vec3::ONE.normalize()).length() < 1e-5),
            "{corner:?}"
        );
    }

    #[test]
    fn smoothing_off_gives_flat_faces() {
        for off in ["s off", "s 0"] {
            let (meshes, warnings) = parts(&cube(|_| off));
            assert!(warnings.is_empty(), "{warnings:?}");
            let mesh = &meshes[0];
            assert_eq!(mesh.vertices().len(), 24, "{off}: each face has its own four corners");
            for triangle in mesh.indices().chunks_exact(3) {
                let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(mesh.vertices()[triangle[k] as usize].position));
                let face = (b - a).cross(c - a).normalize();
                for &i in triangle {
                    assert!((Vec3::from(mesh.vertices()[i as usize].normal) - face).length() < 1e-5, "{off}");
                }
            }
        }
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
}
