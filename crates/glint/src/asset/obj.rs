//! Core layer: Wavefront OBJ + MTL through `tobj`. Polygons are triangulated; every
//! object/group × material run becomes its own part with its own MTL material;
//! missing normals are computed (angle-weighted, shared by vertices at one
//! position); missing texture coordinates are allowed. MTL texture statements are
//! split into options (`-s`, `-o`, `-bm` ...) and a file name that may hold spaces.
//! A missing `.mtl` or texture is a warning and a visible default, not a failure.
//! Paths in the files resolve inside the model's folder only (see [`LoadOptions`]).

use super::model::{Model, ModelPart};
use super::texture::TextureCache;
use super::{load_texture, read_capped, AssetFolder, Diagnostic, LoadOptions, MaterialDesc};
use crate::scene::{AlphaMode, Material, Mesh};
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
    let mut parts = Vec::new();
    for model in models {
        let part_name = model.name.clone();
        match convert_mesh(&model.mesh) {
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

/// Build a glint mesh from a tobj mesh: `Ok(None)` for a mesh without faces.
fn convert_mesh(mesh: &tobj::Mesh) -> Result<Option<Mesh>, crate::scene::MeshError> {
    if mesh.indices.is_empty() {
        return Ok(None);
    }
    let positions: Vec<Vec3> = mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let count = positions.len();
    let normals: Vec<Vec3> = if mesh.normals.len() == count * 3 {
        mesh.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])).collect()
    } else {
        crate::scene::smooth_normals(&positions, &mesh.indices)
    };
    // OBJ's v runs up the image; glint's (like glTF's) runs down.
    let uvs: Vec<Vec2> = if mesh.texcoords.len() == count * 2 {
        mesh.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])).collect()
    } else {
        vec![Vec2::ZERO; count]
    };
    Mesh::from_attributes(&positions, &normals, &uvs, mesh.indices.clone()).map(Some)
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
}
