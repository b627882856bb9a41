//! Simulation caches: `glint bake` steps a scene's simulations once through a
//! sequence and stores their state every K frames; `glint render
//! --sim-cache` starts each simulation from the stored state at or before
//! its first frame, so a chunk far into a long sequence no longer steps its
//! cloth, schools and emitters from time 0. Frames drawn from a cache equal
//! the whole run's, byte for byte.
//!
//! A cache is a folder:
//! - `manifest.json`: the cache's format, the glint version that made it,
//!   the scene, its simulations (kind, line, path, time step and a hash of
//!   every setting that steers them), the adapter (for simulations stepped
//!   on the GPU, whose arithmetic differs from device to device), and each
//!   state file's frame, size and hash. The manifest carries a hash of its
//!   own values (`checksum`).
//! - `state_NNNNNN.bin`: the state at frame NNNNNN ([`SimState`]'s bytes).
//!
//! A cache made for another scene, another glint, other simulation settings
//! or another adapter is refused, saying which; a truncated or changed file
//! is an error, never a wrong picture. Hashes are xxh3-128 (corruption, not
//! tampering, is what they catch).

use crate::output;
use crate::render::frame_time;
use glint::asset::SceneDesc;
use glint::scene::SimPath;
use glint::world::{SimKind, SimState, SIM_STATE_FORMAT};
use glint::{Diagnostic, Error, Renderer, World};
use serde::{Deserialize, Serialize};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// The manifest's name in a cache's folder.
const MANIFEST: &str = "manifest.json";

/// The manifest's `kind`: what says a folder is a cache.
const KIND: &str = "glint simulation cache";

/// Largest manifest read (a 100,000-frame sequence's entries fit many times over).
const MAX_MANIFEST_BYTES: u64 = 64 << 20;

/// Largest state file read: more than the simulations' limits let a scene
/// hold (4,194,304 particle slots and as many fish, 32 bytes each, and 66,564
/// cloth nodes), well below this machine's memory.
const MAX_STATE_BYTES: u64 = 1 << 30;

/// What `glint bake` was asked for.
pub struct BakeArgs<'a> {
    pub scene: &'a Path,
    pub output: &'a Path,
    /// Frames in the sequence, from `time` on at `fps`.
    pub frames: u32,
    pub fps: f32,
    pub time: f32,
    /// Store the state every this many frames.
    pub every: u32,
    pub options: glint::asset::LoadOptions,
}

/// A cache's manifest.
#[derive(Serialize, Deserialize, PartialEq, Debug)]
struct Manifest {
    kind: String,
    format: u32,
    glint: String,
    scene: String,
    time: f32,
    fps: f32,
    frames: u32,
    every: u32,
    adapter: String,
    /// The CPU's vector instructions ([`cpu_level`]), for cloth solved on the CPU.
    cpu: String,
    simulations: Vec<Simulation>,
    states: Vec<StateFile>,
    /// xxh3-128 (hex) of the manifest's JSON with this field empty.
    checksum: String,
}

/// One simulation as the manifest lists it.
#[derive(Serialize, Deserialize, PartialEq, Debug, Clone)]
struct Simulation {
    kind: String,
    line: usize,
    path: String,
    dt: f64,
    /// xxh3-128 (hex) of every setting that steers it.
    settings: String,
}

/// One state file as the manifest lists it.
#[derive(Serialize, Deserialize, PartialEq, Debug)]
struct StateFile {
    frame: u32,
    file: String,
    bytes: u64,
    xxh3: String,
}

/// Step `args.scene`'s simulations through the sequence and write the cache.
pub fn bake(args: BakeArgs) -> Result<(), Error> {
    let desc = crate::load(args.scene, args.options)?;
    crate::render::check_sequence(&desc, (args.time, args.fps), args.frames - 1)?;
    let gpu = glint::Gpu::headless()?;
    let mut renderer = Renderer::new(&gpu);
    let mut world = World::place(desc, &mut renderer)?;
    let simulations = simulations(&world);
    std::fs::create_dir_all(args.output)
        .map_err(|e| Diagnostic::file(args.output, format!("cannot create the cache's folder: {e}")))?;
    let mut states = Vec::new();
    if !simulations.is_empty() {
        // GPU simulations step in a frame's simulate stage: a tiny one is drawn for them.
        let mut target = Some(glint::OffscreenTarget::new(&gpu, 16, 16, 1)?);
        let views = world.views(None);
        let lines = !std::io::stderr().is_terminal();
        let stored: Vec<u32> = (args.every..args.frames).step_by(args.every as usize).collect();
        let progress = crate::render::progress_bar(stored.len(), "states");
        let mut next = 0;
        for frame in stored {
            let started = std::time::Instant::now();
            let sequence = (args.time, args.fps);
            crate::render::reach(&mut world, (&gpu, &mut renderer, &mut target), next..frame, sequence)?;
            world.pose(frame_time(args.time, frame, args.fps), &mut renderer)?;
            next = frame + 1;
            world.draw(&mut renderer, &views, target.as_mut().expect("made above"))?;
            let bytes = world.sim_state(&renderer)?.to_bytes();
            gpu.check()?;
            let file = format!("state_{frame:06}.bin");
            output::write_file_whole(&args.output.join(&file), &bytes)?;
            if lines {
                eprintln!(
                    "frame {frame}: state stored in {:.3} s ({} bytes)",
                    started.elapsed().as_secs_f64(),
                    bytes.len()
                );
            }
            states.push(StateFile { frame, file, bytes: bytes.len() as u64, xxh3: hash(&bytes) });
            progress.iter().for_each(|bar| bar.inc(1));
        }
        progress.iter().for_each(|bar| bar.finish());
    }
    let mut manifest = Manifest {
        kind: KIND.into(),
        format: SIM_STATE_FORMAT,
        glint: env!("CARGO_PKG_VERSION").into(),
        scene: args.scene.display().to_string(),
        time: args.time,
        fps: args.fps,
        frames: args.frames,
        every: args.every,
        adapter: adapter_name(gpu.info()),
        cpu: cpu_level(),
        simulations,
        states,
        checksum: String::new(),
    };
    manifest.checksum = manifest_hash(&manifest);
    let json = serde_json::to_string_pretty(&manifest).expect("a manifest serialises");
    // Written last: a bake cut short leaves no manifest, so no cache to trust.
    output::write_file_whole(&args.output.join(MANIFEST), format!("{json}\n").as_bytes())?;
    Ok(())
}

/// Open the cache at `folder` for `world` (placed in `renderer` on the
/// adapter `adapter`, not yet posed), and resume its simulations from the state stored at or before `time` (the
/// first frame's); where none is stored that early they start from time 0.
/// Returns the frame resumed from.
pub fn resume(
    folder: &Path,
    (world, renderer, adapter): (&mut World, &Renderer, &wgpu::AdapterInfo),
    (time, fps): (f32, f32),
    first: u32,
) -> Result<Option<u32>, Error> {
    let manifest = open(folder)?;
    check(&manifest, folder, (world, adapter), (time, fps))?;
    let Some(entry) = manifest.states.iter().filter(|s| s.frame <= first).max_by_key(|s| s.frame) else {
        return Ok(None);
    };
    let path = state_path(folder, &entry.file)?;
    if entry.bytes > MAX_STATE_BYTES {
        let message =
            format!("the manifest says {} bytes, more than a state may hold ({MAX_STATE_BYTES})", entry.bytes);
        return Err(Diagnostic::file(&path, message).into());
    }
    let bytes = glint::asset::read_file(&path, entry.bytes)?;
    if bytes.len() as u64 != entry.bytes {
        let message = format!("truncated or changed: {} bytes, where the manifest says {}", bytes.len(), entry.bytes);
        return Err(Diagnostic::file(&path, message).into());
    }
    if hash(&bytes) != entry.xxh3 {
        return Err(Diagnostic::file(&path, "corrupt: its hash is not the manifest's (bake the cache again)").into());
    }
    let state = SimState::from_bytes(&bytes).map_err(|e| Diagnostic::file(&path, e))?;
    if state.time != frame_time(time, entry.frame, fps) {
        let message = format!(
            "saved at {} s, not at frame {}'s time ({} s)",
            state.time,
            entry.frame,
            frame_time(time, entry.frame, fps)
        );
        return Err(Diagnostic::file(&path, message).into());
    }
    world.resume(&state, renderer).map_err(|e| Diagnostic::file(&path, format!("cannot resume from it: {e}")))?;
    Ok(Some(entry.frame))
}

/// The manifest of the cache at `folder`, its own hash checked.
fn open(folder: &Path) -> Result<Manifest, Error> {
    let path = folder.join(MANIFEST);
    if !path.is_file() {
        let message = format!("no {MANIFEST}: not a glint simulation cache (glint bake makes one)");
        return Err(Diagnostic::file(folder, message).into());
    }
    let bytes = glint::asset::read_file(&path, MAX_MANIFEST_BYTES)?;
    let manifest: Manifest = serde_json::from_slice(&bytes)
        .map_err(|e| Diagnostic::at(&path, e.line(), format!("not a glint simulation cache's manifest: {e}")))?;
    if manifest.kind != KIND {
        return Err(Diagnostic::file(&path, format!("its kind is {:?}, not {KIND:?}", manifest.kind)).into());
    }
    if manifest.format != SIM_STATE_FORMAT || manifest.glint != env!("CARGO_PKG_VERSION") {
        let message = format!(
            "made by glint {} (cache format {}), but this is glint {} (format {SIM_STATE_FORMAT}): bake it again",
            manifest.glint,
            manifest.format,
            env!("CARGO_PKG_VERSION")
        );
        return Err(Diagnostic::file(&path, message).into());
    }
    if manifest_hash(&manifest) != manifest.checksum {
        let message = "corrupt: its values do not match its checksum (bake the cache again)";
        return Err(Diagnostic::file(&path, message).into());
    }
    Ok(manifest)
}

/// Refuse a cache made for another scene, other settings, another sequence
/// or another machine.
fn check(
    manifest: &Manifest,
    folder: &Path,
    (world, info): (&World, &wgpu::AdapterInfo),
    (time, fps): (f32, f32),
) -> Result<(), Error> {
    let path = folder.join(MANIFEST);
    let refuse = |message: String| -> Error { Diagnostic::file(&path, message).into() };
    if (manifest.time, manifest.fps) != (time, fps) {
        return Err(refuse(format!(
            "baked for a sequence at {} fps from {} s, but this one is at {fps} fps from {time} s: \
             render at the cache's --fps and --time, or bake it again",
            manifest.fps, manifest.time
        )));
    }
    let ours = simulations(world);
    let theirs = &manifest.simulations;
    let kinds = |list: &[Simulation]| list.iter().map(|s| s.kind.clone()).collect::<Vec<_>>();
    if kinds(theirs) != kinds(&ours) {
        return Err(refuse(format!(
            "made for another scene ({}, with {}), where this one has {}",
            manifest.scene,
            listed(theirs),
            listed(&ours)
        )));
    }
    for (cached, here) in theirs.iter().zip(&ours) {
        let which = format!("the {} at line {}", here.kind, here.line);
        if cached.dt != here.dt {
            return Err(refuse(format!(
                "made for other simulation settings: {which} steps by {} s here, by {} s in the cache",
                here.dt, cached.dt
            )));
        }
        if cached.settings != here.settings {
            return Err(refuse(format!(
                "made for other simulation settings: {which} is set up otherwise than when the cache was baked \
                 (line {} of {})",
                cached.line, manifest.scene
            )));
        }
        if cached.path != here.path {
            return Err(refuse(format!(
                "{which} stepped on the {} when the cache was baked, but steps on the {} here",
                cached.path, here.path
            )));
        }
    }
    let adapter = adapter_name(info);
    if ours.iter().any(|s| s.path == "GPU") && manifest.adapter != adapter {
        return Err(refuse(format!(
            "baked on {}, but this is {adapter}: simulations stepped on the GPU step alike only on the same adapter",
            manifest.adapter
        )));
    }
    let cpu = cpu_level();
    if ours.iter().any(|s| s.kind == "cloth" && s.path == "CPU") && manifest.cpu != cpu {
        return Err(refuse(format!(
            "baked on a {} CPU, but this is a {cpu} one: the cloth's solver takes other vector instructions there, \
             and its steps differ in their last bits",
            manifest.cpu
        )));
    }
    Ok(())
}

/// The vector instructions this CPU gives the cloth's solver (faer picks
/// them as it runs): "x86_64 with AVX-512", "x86_64 with AVX2 and FMA",
/// "x86_64", or the architecture alone.
fn cpu_level() -> String {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return "x86_64 with AVX-512".into();
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            return "x86_64 with AVX2 and FMA".into();
        }
    }
    std::env::consts::ARCH.into()
}

/// `world`'s simulations as a manifest lists them.
fn simulations(world: &World) -> Vec<Simulation> {
    let desc: &SceneDesc = world.desc();
    let settings = (desc.cloths.iter().map(|c| (c.line, c.dt, format!("{:?}|{:?}", c.setup, c.integrator))))
        .chain(desc.schools.iter().map(|s| (s.line, f64::from(s.dt), format!("{:?}", s.params))))
        .chain(desc.emitters.iter().map(|e| (e.line, f64::from(e.dt), format!("{:?}", e.params))));
    (world.simulations().into_iter().zip(settings))
        .map(|((kind, path), (line, dt, settings))| Simulation {
            kind: kind.name().into(),
            line,
            path: match path {
                Some(SimPath::Gpu) => "GPU",
                Some(SimPath::Cpu) => "CPU",
                None => "none",
            }
            .into(),
            dt,
            settings: hash(settings.as_bytes()),
        })
        .collect()
}

/// "1 cloth, 1 school, 2 emitters": how many of each kind `list` has.
fn listed(list: &[Simulation]) -> String {
    SimKind::listed(&list.iter().filter_map(|s| SimKind::named(&s.kind)).collect::<Vec<_>>())
}

/// "lavapipe (Vulkan, Mesa 22.3.6)": the adapter as a manifest names it.
fn adapter_name(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {})", info.name, info.backend, info.driver_info)
}

/// xxh3-128 of `bytes`, in hex.
fn hash(bytes: &[u8]) -> String {
    format!("{:032x}", xxhash_rust::xxh3::xxh3_128(bytes))
}

/// The hash of `manifest`'s values, its checksum left out.
fn manifest_hash(manifest: &Manifest) -> String {
    let mut value = serde_json::to_value(manifest).expect("a manifest serialises");
    value["checksum"] = "".into();
    hash(value.to_string().as_bytes())
}

/// `file` in `folder`, where it is a plain name (a manifest names no other folder).
fn state_path(folder: &Path, file: &str) -> Result<PathBuf, Error> {
    let plain = Path::new(file).file_name().is_some_and(|name| name == file) && !file.starts_with('.');
    if !plain {
        let message = format!("names the state file {file:?}: expected a file name in the cache's folder");
        return Err(Diagnostic::file(&folder.join(MANIFEST), message).into());
    }
    Ok(folder.join(file))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest() -> Manifest {
        let cloth = Simulation { kind: "cloth".into(), line: 3, path: "CPU".into(), dt: 0.01, settings: "ab".into() };
        Manifest {
            kind: KIND.into(),
            format: SIM_STATE_FORMAT,
            glint: "0.1.0".into(),
            scene: "a.scn".into(),
            time: 0.0,
            fps: 30.0,
            frames: 600,
            every: 10,
            adapter: "lavapipe".into(),
            cpu: "x86_64".into(),
            simulations: vec![cloth.clone(), Simulation { kind: "emitter".into(), ..cloth.clone() }, cloth],
            states: vec![StateFile { frame: 10, file: "state_000010.bin".into(), bytes: 8, xxh3: "cd".into() }],
            checksum: String::new(),
        }
    }

    #[test]
    fn the_checksum_covers_every_value_but_itself() {
        let mut m = manifest();
        let before = manifest_hash(&m);
        m.checksum = "anything".into();
        assert_eq!(manifest_hash(&m), before);
        m.states[0].frame = 11;
        assert_ne!(manifest_hash(&m), before);
        let mut m = manifest();
        m.simulations[0].dt = 0.02;
        assert_ne!(manifest_hash(&m), before);
    }

    #[test]
    fn state_files_lie_in_the_cache_folder() {
        let folder = Path::new("cache");
        assert_eq!(state_path(folder, "state_000010.bin").ok(), Some(folder.join("state_000010.bin")));
        for outside in ["../x.bin", "/etc/passwd", "a/b.bin", "..", ".hidden", ""] {
            assert!(state_path(folder, outside).is_err(), "{outside:?}");
        }
    }

    #[test]
    fn simulations_are_listed_by_kind() {
        assert_eq!(listed(&manifest().simulations), "2 cloths, 1 emitter");
        assert_eq!(listed(&[]), "no simulations");
    }
}
