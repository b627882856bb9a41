//! `glint view`: a window onto a scene with a free camera, hot reload of the
//! scene file and screenshots. Frames are drawn exactly as `glint render` draws
//! them (into an offscreen target) and then shown in the window.

mod events;
mod overlay;
mod script;
mod watch;

pub use script::{parse_at, Action, Scripted};

use glam::Vec2;
use glint::asset::{LoadOptions, SceneDesc};
use glint::scene::FlyInput;
use glint::world::{Controls, Moves, Player};
use glint::{Camera, Error, FrameStats, Gpu, GpuError, OffscreenTarget, Renderer, WindowSurface, World};
use overlay::Overlay;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use watch::SceneWatch;
use winit::dpi::PhysicalSize;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::KeyCode;
use winit::window::{CursorGrabMode, Window};

/// The keys, for `glint view --help`.
pub const KEYS: &str = "\
Keys:
  W A S D       move forward, left, back, right
  Q E           move down, up
  right mouse   hold and move the mouse to look around
  mouse wheel   faster or slower
  Shift         move 4x faster while held
  [ ]           draw less or more of every tile of tiled instances (density)
  , .           move the sun and sky half an hour back or on (time of day)
  Enter         switch between the free camera and the scene's camera
  Space         pause or play the scene
  H             hide or show the overlay: the scene's controls and the frame's
                statistics (and, opened, its draw calls)
  F12           save a screenshot (glint-NNNN.png in the current folder)
  Esc           quit

The scene file is loaded again when it changes on disk; a file with errors is
reported here and the last good scene stays on screen. The title bar shows the
frame time, how fast the scene plays (a frame advances it at most 1/30 s, so a
slow frame plays in slow motion) and the draw count; quitting prints the same.

Exit codes: 0 ok, 1 bad input (file:line: message on stderr), 2 no GPU adapter,
3 other failures (no display, GPU or render errors).";

/// How often the scene file is checked for changes.
const WATCH_INTERVAL: Duration = Duration::from_millis(300);
/// How often the title's frame time is refreshed (averaged over the interval).
const TITLE_INTERVAL: Duration = Duration::from_millis(500);

/// What `glint view` was asked for.
pub struct ViewArgs {
    /// The scene (or model) file.
    pub scene: PathBuf,
    /// Initial inner size of the window.
    pub size: (u32, u32),
    /// MSAA samples.
    pub msaa: u32,
    /// Which of the scene's cameras to show alone (`None`: every camera with a
    /// viewport, or the first).
    pub camera: Option<usize>,
    /// How every view culls, where given (else as its camera says).
    pub cull: Option<crate::CullArg>,
    /// Share of every tile drawn ([`Renderer::set_density`]).
    pub density: f32,
    /// Levels of detail (`--lod`, `--lod-error`).
    pub lod: crate::lod::LodArgs,
    /// Quit after this many frames.
    pub frames: Option<u32>,
    /// Write the last frame here on quitting.
    pub screenshot: Option<PathBuf>,
    /// Window actions at given frames.
    pub script: Vec<Scripted>,
    /// How model files may reach outside their folder.
    pub options: LoadOptions,
}

/// Open the window and run until it is closed (or `--frames` are drawn).
pub fn run(args: ViewArgs, desc: SceneDesc) -> Result<(), Error> {
    crate::check_camera(&desc, &args.scene, args.camera)?;
    let event_loop = EventLoop::new().map_err(|e| GpuError::Surface(format!("cannot open a window: {e}")))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App { args, desc: Some(desc), view: None, result: Ok(()) };
    event_loop.run_app(&mut app).map_err(|e| GpuError::Surface(format!("the window's event loop failed: {e}")))?;
    app.result
}

struct App {
    args: ViewArgs,
    /// The scene until the window exists.
    desc: Option<SceneDesc>,
    view: Option<View>,
    result: Result<(), Error>,
}

/// Everything that lives with the window.
struct View {
    window: Arc<Window>,
    gpu: Gpu,
    surface: WindowSurface,
    target: OffscreenTarget,
    msaa: u32,
    scene: Scene,
    watch: SceneWatch,
    last_watch: Instant,
    input: Input,
    /// The scene clock (animation and simulation time, and how fast it
    /// played) and the fly camera.
    player: Player,
    last_frame: Instant,
    /// Frames counted so far (drawn or skipped while the window has no area).
    frames: u32,
    last_title: Instant,
    /// What the user chose: camera, culling, shadows, post effects, density,
    /// time of day, pause and speed.
    controls: Controls,
    /// The scene camera shown when the free camera is not (`None`: free).
    shown_camera: Option<usize>,
    /// The camera the free camera's views start from (`--camera`).
    free_start: Option<usize>,
    /// How every view culls, where `--cull` says.
    cull: Option<crate::CullArg>,
    /// Levels of detail, as `--lod` and `--lod-error` say.
    lod: crate::lod::LodArgs,
    overlay: Overlay,
    /// CPU time of each frame's overlay, ms.
    overlay_ms: Vec<f64>,
    /// The last frame's statistics, per view.
    stats: Vec<FrameStats>,
    /// The last frame's command submissions (its overlay and the blit onto
    /// the window included): 1.
    submits: u32,
}

/// A loaded scene placed in its own renderer, and the views it shows (the fly
/// camera moves the first one into the window).
struct Scene {
    world: World,
    renderer: Renderer,
    views: Vec<glint::View>,
}

impl Scene {
    /// `desc` placed in a new renderer, showing camera `camera` (see
    /// [`World::views`]), culled as `cull` says where given.
    fn new(
        gpu: &Gpu,
        desc: SceneDesc,
        camera: Option<usize>,
        (cull, density, lod): (Option<crate::CullArg>, f32, crate::lod::LodArgs),
    ) -> Result<Self, Error> {
        let mut renderer = Renderer::new(gpu);
        renderer.set_density(density);
        lod.apply(&mut renderer);
        // The overlay shows each pass's GPU time, where the device can tell.
        renderer.enable_gpu_timing();
        let world = World::place(desc, &mut renderer)?;
        let views = lod.views(crate::culled(world.views(camera), cull));
        Ok(Self { world, renderer, views })
    }

    /// The view the fly camera moves: the first into the window.
    fn flown(&self) -> usize {
        self.views.iter().position(|v| v.output.is_none()).unwrap_or(0)
    }

    /// Its camera, where the fly camera starts.
    fn camera(&self) -> Camera {
        self.views[self.flown()].camera
    }
}

/// Keys and mouse state between frames.
#[derive(Default)]
struct Input {
    held: HashSet<KeyCode>,
    looking: bool,
    look: Vec2,
    wheel: f32,
}

impl Input {
    fn axis(&self, plus: KeyCode, minus: KeyCode) -> f32 {
        f32::from(u8::from(self.held.contains(&plus))) - f32::from(u8::from(self.held.contains(&minus)))
    }

    /// This frame's camera input; the mouse movement is used up.
    fn take(&mut self) -> FlyInput {
        FlyInput {
            forward: self.axis(KeyCode::KeyW, KeyCode::KeyS),
            right: self.axis(KeyCode::KeyD, KeyCode::KeyA),
            up: self.axis(KeyCode::KeyE, KeyCode::KeyQ),
            fast: self.held.contains(&KeyCode::ShiftLeft) || self.held.contains(&KeyCode::ShiftRight),
            look: std::mem::take(&mut self.look),
        }
    }
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: Error) {
        if self.result.is_ok() {
            self.result = Err(error);
        }
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop, desc: SceneDesc) -> Result<View, Error> {
        let (width, height) = self.args.size;
        let title = format!("glint: {}", self.args.scene.display());
        let attributes =
            Window::default_attributes().with_title(title).with_inner_size(PhysicalSize::new(width, height));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| GpuError::Surface(format!("cannot open a window: {e}")))?,
        );
        let (gpu, surface) = Gpu::for_window(window.clone())?;
        let size = window.inner_size();
        let surface = WindowSurface::new(&gpu, surface, size.width, size.height)?;
        let msaa = if gpu.supports_msaa(self.args.msaa) { self.args.msaa } else { 1 };
        let target = OffscreenTarget::new(&gpu, size.width.max(1), size.height.max(1), msaa)?;
        let mut controls = free_controls(&desc, &gpu, self.args.density);
        // `--lod`, `--lod-error` and `--cluster-heat` as the controls' first choices.
        let lod = self.args.lod;
        let off = (lod.lod == crate::lod::LodSwitch::Off).then_some(("levels", 0.0));
        // (A scene without point or spot lights has no clusters, nor the control.)
        let heat_control = controls.list().iter().any(|c| c.id == "cluster_heat");
        let heat = (lod.cluster_heat && heat_control).then_some(("cluster_heat", 1.0));
        for (id, value) in off.into_iter().chain(lod.lod_error.map(|px| ("lod_error", px))).chain(heat) {
            controls.set(id, value).map_err(|e| glint::Diagnostic::file(&self.args.scene, e))?;
        }
        let scene = Scene::new(&gpu, desc, self.args.camera, (self.args.cull, self.args.density, self.args.lod))?;
        let camera = scene.camera();
        let overlay = Overlay::new(&window, &gpu, target.format().color);
        eprintln!("glint view: {} on {} ({:?})", self.args.scene.display(), gpu.info().name, gpu.info().backend);
        let now = Instant::now();
        Ok(View {
            player: Player::new(&camera),
            window,
            surface,
            target,
            msaa,
            scene,
            watch: SceneWatch::new(&self.args.scene, self.args.options.clone()),
            last_watch: now,
            input: Input::default(),
            last_frame: now,
            frames: 0,
            last_title: now,
            controls,
            shown_camera: None,
            free_start: self.args.camera,
            cull: self.args.cull,
            lod: self.args.lod,
            overlay,
            overlay_ms: Vec::new(),
            stats: Vec::new(),
            submits: 0,
            gpu,
        })
    }
}

impl View {
    fn resize(&mut self, size: PhysicalSize<u32>) -> Result<(), GpuError> {
        if self.surface.resize(&self.gpu, size.width, size.height)
            && (self.target.width(), self.target.height()) != (size.width, size.height)
        {
            self.target = OffscreenTarget::new(&self.gpu, size.width, size.height, self.msaa)?;
        }
        Ok(())
    }

    /// Load the scene again if its file changed; a bad file is reported and the
    /// current scene stays.
    fn reload_if_changed(
        &mut self,
        path: &Path,
        camera_index: Option<usize>,
        cull: (Option<crate::CullArg>, f32, crate::lod::LodArgs),
    ) {
        if self.last_watch.elapsed() < WATCH_INTERVAL {
            return;
        }
        self.last_watch = Instant::now();
        match self.watch.poll() {
            None => {}
            Some(Err(e)) => eprintln!("error: {e}\n  (keeping the last good scene)"),
            Some(Ok(desc)) => {
                for warning in &desc.warnings {
                    eprintln!("warning: {warning}");
                }
                // The views come from the new file (the chosen camera, or all
                // views when it has no longer one); the fly camera's place
                // stays, and so do the density and the free camera.
                let controls = free_controls(&desc, &self.gpu, self.controls.density());
                match Scene::new(&self.gpu, desc, camera_index, cull) {
                    Ok(scene) => (self.scene, self.controls, self.shown_camera) = (scene, controls, None),
                    Err(e) => {
                        eprintln!("error: {e}\n  (keeping the last good scene)");
                        return;
                    }
                }
                // Animations and cloths start again from the beginning, rather
                // than a new cloth stepping all the way to the old time at once.
                self.player.clock.restart();
                eprintln!("reloaded {}", path.display());
            }
        }
    }

    /// Place the scene again when the controls turned the cloths' debug view
    /// on or off; the cloths start again from rest.
    fn show_cloth_debug_if_chosen(
        &mut self,
        camera: Option<usize>,
        cull: (Option<crate::CullArg>, f32, crate::lod::LodArgs),
    ) -> Result<(), Error> {
        let Some(debug) = self.controls.cloth_debug_to_show(self.scene.world.desc()) else { return Ok(()) };
        let mut desc = self.scene.world.desc().clone();
        desc.set_cloth_debug(debug);
        self.scene = Scene::new(&self.gpu, desc, camera, cull)?;
        self.shown_camera = None;
        self.player.clock.restart();
        Ok(())
    }

    /// Move the camera, draw the scene and show it.
    fn draw(&mut self) -> Result<(), Error> {
        let now = Instant::now();
        let dt = now - self.last_frame;
        self.last_frame = now;
        let moves = Moves { fly: self.input.take(), wheel: std::mem::take(&mut self.input.wheel), orbit: None };
        self.show_chosen_camera();
        // The overlay shows the last frame's statistics and calls, and is drawn
        // into this frame, before the blit onto the window: one submission.
        self.overlay.record(dt.as_secs_f32() * 1e3);
        let scene = &mut self.scene;
        let size = (self.target.width(), self.target.height());
        let last = (&self.stats[..], scene.renderer.explained());
        let overlay_ms = self.overlay.prepare((&self.window, &self.gpu), size, &mut self.controls, last);
        scene.renderer.set_explaining(self.overlay.visible && self.overlay.calls_open);
        let mut window = self.surface.acquire(&self.gpu);
        let mut after: Vec<&mut dyn glint::AfterViews> = vec![&mut self.overlay];
        after.extend(window.as_mut().map(|w| w as &mut dyn glint::AfterViews));
        let world = (&mut scene.world, &mut scene.renderer);
        let drawn = (&scene.views[..], &mut self.target);
        let output = self.player.frame(world, &mut self.controls, drawn, (dt, moves), after)?;
        if let Some(window) = window {
            window.present(&self.gpu);
        }
        self.overlay_ms.extend(overlay_ms.map(|ms| ms + self.overlay.take_record_ms()));
        self.submits = output.submits;
        let stats = output.views;
        if self.last_title.elapsed() >= TITLE_INTERVAL {
            let recent = self.player.clock.take_recent();
            self.window.set_title(&format!(
                "glint: {} | {:.1} ms | plays at {:.2}x | {}",
                self.scene.world.desc().path.display(),
                recent.frame_ms(),
                recent.speed(),
                view_counts(&stats)
            ));
            self.last_title = Instant::now();
        }
        self.stats = stats;
        Ok(())
    }

    /// Show the scene camera the controls chose, or go back to the free
    /// camera's views, when the choice changed.
    fn show_chosen_camera(&mut self) {
        let chosen = self.controls.scene_camera();
        if chosen == self.shown_camera {
            return;
        }
        self.shown_camera = chosen;
        let scene = &mut self.scene;
        scene.views = self.lod.views(crate::culled(scene.world.views(chosen.or(self.free_start)), self.cull));
        // The free camera starts again from the scene camera shown.
        let camera = scene.camera();
        self.player.fly_from(&camera);
    }

    fn do_action(&mut self, action: &Action) -> Result<(), Error> {
        match action {
            Action::Resize(w, h) => {
                // Where the window system answers at once (X11 without a window
                // manager), follow it now rather than at the Resized event.
                if let Some(size) = self.window.request_inner_size(PhysicalSize::new(*w, *h)) {
                    self.resize(size)?;
                }
            }
            Action::Minimize => self.window.set_minimized(true),
            Action::Restore => self.window.set_minimized(false),
            Action::Screenshot(path) => self.screenshot(path)?,
            Action::Density(d) => self.set_density(*d),
            Action::TimeOfDay(h) => self.set_time_of_day(*h),
            Action::Overlay(on) => self.overlay.visible = *on,
            Action::Set(id, value) => {
                let scene = &self.scene.world.desc().path;
                self.controls.set(id, *value).map_err(|e| glint::Diagnostic::file(scene, e))?;
                eprintln!("{id} set to {value}");
            }
            Action::Stats(path) => {
                let json = serde_json::json!({
                    "time": self.player.clock.time,
                    "overlay": self.overlay.visible,
                    "submits": self.submits,
                    "views": self.stats
                });
                crate::output::write_file(path, format!("{json}\n").as_bytes())?;
            }
        }
        Ok(())
    }

    /// Draw `density` (clamped to 0..=1) of every tile from the next frame on.
    fn set_density(&mut self, density: f32) {
        let density = density.clamp(0.0, 1.0);
        self.controls.set_density(density);
        eprintln!("density {density:.1}");
    }

    /// Move the sun and sky to `hours` (wrapped to 0..24) from the next frame on.
    fn set_time_of_day(&mut self, hours: f32) {
        let hours = hours.rem_euclid(24.0);
        self.controls.set_time_of_day(hours);
        eprintln!("time of day {:02}:{:02}", hours as u32, (hours.fract() * 60.0).round() as u32);
    }

    /// The hour the scene's sun was last set to (noon where it never was).
    fn time_of_day(&self) -> f32 {
        self.controls.time_of_day().unwrap_or(12.0)
    }

    /// Start or stop looking around: the cursor hides and stays put while the right
    /// button is held (where the window system allows; looking works either way).
    fn set_looking(&mut self, looking: bool) {
        self.input.looking = looking;
        self.window.set_cursor_visible(!looking);
        let grab = if looking {
            self.window
                .set_cursor_grab(CursorGrabMode::Locked)
                .or_else(|_| self.window.set_cursor_grab(CursorGrabMode::Confined))
        } else {
            self.window.set_cursor_grab(CursorGrabMode::None)
        };
        if let Err(e) = grab {
            log::debug!("cursor grab: {e}");
        }
    }

    fn screenshot(&self, path: &Path) -> Result<(), Error> {
        crate::output::save_png(&self.gpu, &self.target, path)?;
        eprintln!("wrote {} ({}x{})", path.display(), self.target.width(), self.target.height());
        Ok(())
    }
}

/// Each view's draw counts for the title: "N draws, M shadow draws", named
/// "view K: …" when there are several.
fn view_counts(stats: &[glint::FrameStats]) -> String {
    let counts =
        |s: &glint::FrameStats| format!("{} draws, {} shadow draws, {}", s.draws, s.passes.shadow.draws, s.culled());
    match stats {
        [one] => counts(one),
        all => all.iter().enumerate().map(|(k, s)| format!("view {k}: {}", counts(s))).collect::<Vec<_>>().join(" | "),
    }
}

/// The controls of `desc` on `gpu` with the free camera chosen, as the viewer starts.
fn free_controls(desc: &SceneDesc, gpu: &Gpu, density: f32) -> Controls {
    let mut controls = Controls::new(desc, density).for_adapter(gpu);
    controls.toggle_free_camera();
    controls
}
