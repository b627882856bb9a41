//! `glint render`: one frame of a scene, a numbered sequence of them, part of a
//! sequence (`--frame-range`, so a render farm can split one), or an animated
//! GIF or PNG. Frame `k` of a sequence is always posed at `time + k / fps`, so
//! any range of it equals the same frames of the whole run: every simulation
//! steps to a frame's time from its start, whatever came before.

use crate::{check_camera, culled, load, output, CullArg};
use glint::asset::LoadOptions;
use glint::{Diagnostic, Error, Gpu, OffscreenTarget, Renderer, World};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

/// What `glint render` was asked for.
pub struct RenderArgs<'a> {
    pub scene: &'a Path,
    pub output: &'a Path,
    pub size: (u32, u32),
    pub msaa: u32,
    pub camera: Option<usize>,
    pub stats: bool,
    pub cull: Option<CullArg>,
    pub density: f32,
    /// Scene time of frame 0, seconds.
    pub time: f32,
    /// Frames in the whole sequence.
    pub frames: u32,
    /// The frames to render (all of them where not given).
    pub range: Option<crate::frames::FrameRange>,
    /// Leave the numbered frames already on disk alone.
    pub skip_existing: bool,
    /// Start the simulations from this cache's state at or before the first frame.
    pub sim_cache: Option<&'a Path>,
    pub fps: f32,
    /// Orbit the cameras once about their targets over the whole sequence.
    pub turntable: bool,
    /// Write one animated PNG rather than numbered PNGs.
    pub apng: bool,
    /// Sub-frames averaged into each frame ([`World::draw_still`]).
    pub spp: u32,
    /// Effects for every view into the picture, instead of its camera's chain (`--post`).
    pub post: Option<&'a str>,
    /// Levels of detail (`--lod`, `--lod-error`).
    pub lod: crate::lod::LodArgs,
    pub options: LoadOptions,
}

/// `views` with the effects `names` lists as the chain of each that draws
/// into the picture (not into a render target), each effect with the settings
/// its view's own chain had for it, else its defaults.
fn posted(views: Vec<glint::View>, names: &str) -> Result<Vec<glint::View>, String> {
    (views.into_iter())
        .map(|mut view| {
            if view.output.is_none() {
                let own = |default: glint::scene::PostEffect| {
                    view.post.iter().copied().find(|e| e.name() == default.name()).unwrap_or(default)
                };
                view.post = glint::scene::PostEffect::chain(names, &glint::scene::PostEffect::ALL.map(own))?;
            }
            Ok(view)
        })
        .collect()
}

/// Render the frames and write them as `args.output` says.
pub fn render(args: RenderArgs) -> Result<(), Error> {
    let RenderArgs { scene, output, size: (width, height), msaa, camera, stats, cull, density, time, fps, lod, .. } =
        args;
    let desc = load(scene, args.options)?;
    check_camera(&desc, scene, camera)?;
    let listed = match &args.range {
        Some(range) => range.frames(args.frames).map_err(|m| Diagnostic::file(scene, m))?,
        None => (0..args.frames).collect(),
    };
    let mut sink = Sink::new(output, args.apng, listed.len() as u32, fps)?;
    let frames = match args.skip_existing {
        true => sink.missing(&listed)?,
        false => listed,
    };
    let Some(&last) = frames.last() else {
        eprintln!("every frame asked for is on disk already (--skip-existing): nothing to render");
        return Ok(());
    };
    // Refuse simulation work over the limits before starting a GPU.
    check_sequence(&desc, (time, fps), last)?;
    let gpu = Gpu::headless()?;
    let msaa = if gpu.supports_msaa(msaa) {
        msaa
    } else {
        eprintln!("warning: {} cannot do {msaa}x MSAA; rendering without it", gpu.info().name);
        1
    };
    let mut target = OffscreenTarget::new(&gpu, width, height, msaa)?;
    let mut renderer = Renderer::new(&gpu);
    renderer.set_density(density);
    lod.apply(&mut renderer);
    let mut world = World::place(desc, &mut renderer)?;
    // The frame the simulations step on from.
    let mut next = 0;
    if let Some(cache) = args.sim_cache {
        match crate::sim_cache::resume(cache, (&mut world, &renderer, gpu.info()), (time, fps), frames[0])? {
            Some(k) => {
                eprintln!("simulations resumed from frame {k} of {}", cache.display());
                next = k + 1;
            }
            None => {
                eprintln!("{} holds no state before frame {}: simulations start at time 0", cache.display(), frames[0])
            }
        }
    }
    let views = lod.views(culled(world.views(camera), cull));
    let views = match args.post {
        Some(names) => posted(views, names).map_err(|m| Diagnostic::file(scene, format!("--post: {m}")))?,
        None => views,
    };
    let mut scratch = None;
    // A bar on a terminal; else (a farm's log) a line a frame.
    let lines = !std::io::stderr().is_terminal();
    let progress = progress_bar(frames.len(), "frames");
    for k in frames {
        let started = std::time::Instant::now();
        reach(&mut world, (&gpu, &mut renderer, &mut scratch), next..k, (time, fps))?;
        world.pose(frame_time(time, k, fps), &mut renderer)?;
        next = k + 1;
        let views = match args.turntable {
            true => views.iter().map(|v| turned(v, 360.0 * k as f32 / args.frames as f32)).collect(),
            false => views.clone(),
        };
        let mut frame = world.draw_still(&mut renderer, (&views, &mut target), args.spp)?;
        sink.write(k, target.read_rgba8(&gpu)?)?;
        gpu.check()?;
        if let Some(bar) = &progress {
            bar.inc(1);
        }
        if lines {
            let seconds = started.elapsed().as_secs_f64();
            eprintln!("frame {k}: time {:.4} s, drawn and written in {seconds:.3} s", frame_time(time, k, fps));
        }
        if stats {
            // The counts of views culled on the GPU, which a running frame loop reads a frame or two late.
            renderer.wait_for_counts(&mut frame);
            let info = gpu.info();
            // One view: its statistics; several: each view's, in order.
            let mut json = match frame.as_slice() {
                [one] => serde_json::to_value(one),
                all => serde_json::to_value(serde_json::json!({ "views": all })),
            }
            .expect("FrameStats serialises");
            json["adapter"] = format!("{} ({:?})", info.name, info.backend).into();
            json["size"] = format!("{width}x{height}").into();
            json["msaa"] = msaa.into();
            json["frame_number"] = k.into();
            output::print(&format!("{json}\n"))?;
        }
    }
    sink.finish()?;
    if let Some(bar) = progress {
        bar.finish();
    }
    Ok(())
}

/// Check, before any work, that each pose of the sequence `(time, fps)` up
/// to frame `last` stays within the posing budget: its first from the
/// simulations' start, then each one frame on from the last
/// ([`SceneDesc::check_pose_from`](glint::asset::SceneDesc::check_pose_from)).
pub(crate) fn check_sequence(
    desc: &glint::asset::SceneDesc,
    (time, fps): (f32, f32),
    last: u32,
) -> Result<(), Diagnostic> {
    desc.check_pose(frame_time(time, 0, fps))?;
    if desc.cloths.is_empty() && desc.schools.is_empty() && desc.emitters.is_empty() {
        return Ok(());
    }
    let at = |k| frame_time(time, k, fps);
    (0..last).try_for_each(|j| desc.check_pose_work(Some(at(j)), at(j + 1)))
}

/// Before posing frame `frames.end`, step `world`'s simulations through the
/// earlier `frames` one at a time where going there at once would pass the
/// posing budget (a chunk far into a long sequence, with no cache to start
/// from), as the whole run does; a simulation stepped on the GPU steps in
/// a frame drawn into a tiny `scratch` target (made on first use). Elsewhere
/// it does nothing: the pose steps there itself.
pub(crate) fn reach(
    world: &mut World,
    (gpu, renderer, scratch): (&Gpu, &mut Renderer, &mut Option<OffscreenTarget>),
    frames: std::ops::Range<u32>,
    (time, fps): (f32, f32),
) -> Result<(), Error> {
    let at = |k: u32| frame_time(time, k, fps);
    if frames.is_empty() || world.desc().check_pose_from(world.simulated_to(), at(frames.end)).is_ok() {
        return Ok(());
    }
    let on_gpu = world.simulations().iter().any(|(_, path)| *path == Some(glint::scene::SimPath::Gpu));
    let views = world.views(None);
    for k in frames {
        world.pose(at(k), renderer)?;
        if on_gpu {
            let target = match scratch {
                Some(target) => target,
                None => scratch.insert(OffscreenTarget::new(gpu, 16, 16, 1)?),
            };
            world.draw(renderer, &views, target)?;
        }
    }
    Ok(())
}

/// A progress bar of `count` steps counting `what`, where there is more than
/// one and standard error is a terminal (a farm's log gets a line a step).
pub(crate) fn progress_bar(count: usize, what: &str) -> Option<indicatif::ProgressBar> {
    (count > 1 && std::io::stderr().is_terminal()).then(|| {
        let bar = indicatif::ProgressBar::new(count as u64);
        let template = format!("{{bar:40}} {{pos}}/{{len}} {what}, {{elapsed}} ({{eta}} left)");
        bar.set_style(indicatif::ProgressStyle::with_template(&template).expect("valid template"));
        bar
    })
}

/// Scene time of frame `k` of a sequence starting at `time`.
pub(crate) fn frame_time(time: f32, k: u32, fps: f32) -> f32 {
    time + k as f32 / fps
}

/// `view` with its camera turned `degrees` about its target, around its up axis.
pub fn turned(view: &glint::View, degrees: f32) -> glint::View {
    let camera = view.camera;
    let turn = glam::Quat::from_axis_angle(camera.up.normalize_or(glam::Vec3::Y), degrees.to_radians());
    let eye = camera.target + turn * (camera.eye - camera.target);
    glint::View { camera: camera.looking_at(eye, camera.target), ..view.clone() }
}

/// Where rendered frames go.
enum Sink {
    /// One PNG a frame, named by the pattern's `%0Nd` (or the name itself for
    /// one frame); a sequence's folder is made where missing.
    Pngs { pattern: PathBuf, sequence: bool },
    /// An animated GIF, begun at the first frame.
    Gif { path: PathBuf, fps: f32, encoder: Option<gif::Encoder<std::io::BufWriter<std::fs::File>>> },
    /// An animated PNG, begun at the first frame.
    Apng { path: PathBuf, frames: u32, fps: f32, writer: Option<png::Writer<std::io::BufWriter<std::fs::File>>> },
}

impl Sink {
    /// The sink `output` names (`.gif`: a GIF; `apng`: an animated PNG; else
    /// numbered PNGs), checked before any frame is drawn.
    fn new(output: &Path, apng: bool, frames: u32, fps: f32) -> Result<Self, Diagnostic> {
        let path = output.to_path_buf();
        let gif = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("gif"));
        if gif && apng {
            return Err(Diagnostic::file(output, "--apng writes a PNG: name the output .png, not .gif"));
        }
        if gif {
            return Ok(Self::Gif { path, fps, encoder: None });
        }
        if apng {
            return Ok(Self::Apng { path, frames, fps, writer: None });
        }
        if frames > 1 && !output.to_string_lossy().contains('%') {
            let message = "several frames need a numbered output such as -o frames/%04d.png, or an animation \
                           (-o clip.gif, or -o clip.png --apng)";
            return Err(Diagnostic::file(output, message));
        }
        numbered(output, 0).map_err(|m| Diagnostic::file(output, m))?;
        Ok(Self::Pngs { sequence: output.to_string_lossy().contains('%'), pattern: path })
    }

    /// Of `frames`, those whose numbered file is not on disk yet
    /// (`--skip-existing`, for numbered PNGs only).
    fn missing(&self, frames: &[u32]) -> Result<Vec<u32>, Diagnostic> {
        let Self::Pngs { pattern, .. } = self else {
            let message = "--skip-existing leaves numbered frames alone: an animation is written whole";
            return Err(Diagnostic::file(self.path(), message));
        };
        let mut missing = Vec::new();
        for &k in frames {
            let path = numbered(pattern, k).map_err(|m| Diagnostic::file(pattern, m))?;
            if !path.is_file() {
                missing.push(k);
            }
        }
        Ok(missing)
    }

    /// The file or pattern it writes.
    fn path(&self) -> &Path {
        match self {
            Self::Pngs { pattern, .. } => pattern,
            Self::Gif { path, .. } | Self::Apng { path, .. } => path,
        }
    }

    /// Add frame `k` of the sequence.
    fn write(&mut self, k: u32, image: image::RgbaImage) -> Result<(), Error> {
        match self {
            Self::Pngs { pattern, sequence } => {
                let path = numbered(pattern, k).map_err(|m| Diagnostic::file(pattern, m))?;
                if let Some(dir) = path.parent().filter(|d| *sequence && !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir)
                        .map_err(|e| Diagnostic::file(dir, format!("cannot create the frames folder: {e}")))?;
                }
                let bytes = output::png_bytes(&image)
                    .map_err(|e| Diagnostic::file(&path, format!("cannot encode the PNG: {e}")))?;
                match sequence {
                    true => output::write_file_whole(&path, &bytes)?,
                    false => output::write_file(&path, &bytes)?,
                }
            }
            Self::Gif { path, fps, encoder } => {
                let (width, height) = (image.width() as u16, image.height() as u16);
                if encoder.is_none() {
                    let file = std::io::BufWriter::new(create(path)?);
                    let mut gif = gif::Encoder::new(file, width, height, &[]).map_err(|e| cannot_write(path, e))?;
                    gif.set_repeat(gif::Repeat::Infinite).map_err(|e| cannot_write(path, e))?;
                    *encoder = Some(gif);
                }
                // A GIF pixel is opaque or wholly transparent: frames are opaque.
                let mut pixels = image.into_raw();
                pixels.chunks_exact_mut(4).for_each(|p| p[3] = 255);
                let mut frame = gif::Frame::from_rgba_speed(width, height, &mut pixels, GIF_SPEED);
                frame.delay = (100.0 / *fps).round().clamp(1.0, f32::from(u16::MAX)) as u16;
                encoder.as_mut().expect("begun above").write_frame(&frame).map_err(|e| cannot_write(path, e))?;
            }
            Self::Apng { path, frames, fps, writer } => {
                if writer.is_none() {
                    *writer = Some(apng_writer(path, image.dimensions(), *frames, *fps)?);
                }
                writer.as_mut().expect("begun above").write_image_data(&image).map_err(|e| cannot_write(path, e))?;
            }
        }
        Ok(())
    }

    /// Finish an animation's file (numbered PNGs are already whole).
    fn finish(self) -> Result<(), Diagnostic> {
        match self {
            Self::Pngs { .. } => Ok(()),
            Self::Gif { path, encoder, .. } => match encoder {
                Some(gif) => {
                    gif.into_inner().map_err(|e| cannot_write(&path, e))?.flush().map_err(|e| cannot_write(&path, e))
                }
                None => Ok(()),
            },
            Self::Apng { path, writer, .. } => match writer {
                Some(w) => w.finish().map_err(|e| cannot_write(&path, e)),
                None => Ok(()),
            },
        }
    }
}

/// NeuQuant's sampling factor for GIF palettes: 1 is best and slowest, 30
/// fastest; 10 is the gif crate's own default.
const GIF_SPEED: i32 = 10;

fn create(path: &Path) -> Result<std::fs::File, Diagnostic> {
    std::fs::File::create(path).map_err(|e| Diagnostic::file(path, format!("cannot create: {e}")))
}

fn cannot_write(path: &Path, e: impl std::fmt::Display) -> Diagnostic {
    Diagnostic::file(path, format!("cannot write: {e}"))
}

/// An animated PNG of `frames` frames of `size`, shown `1 / fps` s each, looping.
fn apng_writer(
    path: &Path,
    (width, height): (u32, u32),
    frames: u32,
    fps: f32,
) -> Result<png::Writer<std::io::BufWriter<std::fs::File>>, Diagnostic> {
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(create(path)?), width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let (numerator, denominator) = frame_delay(fps);
    encoder
        .set_animated(frames, 0)
        .and_then(|()| encoder.set_frame_delay(numerator, denominator))
        .map_err(|e| cannot_write(path, e))?;
    encoder.write_header().map_err(|e| cannot_write(path, e))
}

/// `1 / fps` seconds as an APNG delay fraction: milliseconds where they fit
/// in 16 bits, else whole seconds (at most 65,535).
fn frame_delay(fps: f32) -> (u16, u16) {
    let ms = (1000.0 / fps).round();
    if ms <= f32::from(u16::MAX) {
        (ms.max(1.0) as u16, 1000)
    } else {
        ((1.0 / fps).round().min(f32::from(u16::MAX)) as u16, 1)
    }
}

/// Widest frame number `%0Nd` may ask for: more digits than any frame count
/// needs, and far below what a file name can hold.
const MAX_FRAME_DIGITS: usize = 32;

/// `pattern` with its `%d` or `%0Nd` replaced by `k` (the pattern itself when it has none).
fn numbered(pattern: &Path, k: u32) -> Result<PathBuf, String> {
    let text = pattern.to_string_lossy();
    let Some(at) = text.find('%') else { return Ok(pattern.to_path_buf()) };
    let rest = &text[at + 1..];
    let Some(end) = rest.find('d') else { return Err("expected %d or %0Nd in the output name".into()) };
    let expected = format!("expected %d or %0Nd with N at most {MAX_FRAME_DIGITS}");
    let width = match &rest[..end] {
        "" => 0,
        w if w.starts_with('0') => match w[1..].parse::<usize>() {
            Ok(n) if n <= MAX_FRAME_DIGITS => n,
            _ => return Err(format!("bad frame-number format: {expected}")),
        },
        _ => return Err(format!("bad frame-number format: {expected}")),
    };
    Ok(PathBuf::from(format!("{}{k:0width$}{}", &text[..at], &rest[end + 1..])))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_delays_fit_sixteen_bits() {
        assert_eq!(frame_delay(30.0), (33, 1000));
        assert_eq!(frame_delay(1000.0), (1, 1000));
        assert_eq!(frame_delay(0.1), (10_000, 1000));
        assert_eq!(frame_delay(0.001), (1000, 1));
    }

    #[test]
    fn numbered_names_fill_the_frame_number() {
        assert_eq!(numbered(Path::new("f/%04d.png"), 12), Ok(PathBuf::from("f/0012.png")));
        assert_eq!(numbered(Path::new("a%db.png"), 7), Ok(PathBuf::from("a7b.png")));
        assert!(numbered(Path::new("%x.png"), 1).is_err());
        assert!(numbered(Path::new("%099d.png"), 1).is_err());
    }
}
