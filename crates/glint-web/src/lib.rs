//! glint in the browser: the page `web/index.html` loads this wasm module,
//! which draws `.scn` scenes fetched over HTTP into its canvas, on WebGPU where
//! the browser has it and WebGL2 otherwise (the renderer's WebGL2 path, chosen
//! from the adapter's capabilities), with the viewer's fly camera. It is built
//! twice, with the feature `webgpu` or `webgl` (`web/build.sh`), and the page
//! loads the module its browser can use.
//!
//! The page's query string may name `scene=PATH` (a demo scene by default),
//! `backend=webgpu|webgl2` (default: WebGPU when there is an adapter), and
//! `size=WxH` (a fixed canvas size in pixels, for tests; default: the window
//! at its device pixel ratio). The page shows the backend, frame time and draw
//! counts, the scene's controls beside the canvas (`panel.rs`: the list the
//! viewer's overlay shows), and a broken scene's `file:line` message; the
//! canvas carries `data-frames` (frames drawn), `data-error`, and the last
//! frame's `data-shadow-views`, `data-instances` (drawn), `data-time`
//! (the scene clock) and `data-light-binning` (where its first view's light
//! clusters were binned, `cpu` or `gpu`, and the CPU's milliseconds) for
//! scripts, and `data-startup`, the first frame's startup stages (`startup.rs`).
#![cfg(target_arch = "wasm32")]

mod decode;
mod fetch;
mod input;
mod panel;
mod startup;

use glam::Vec2;
use glint::world::{Controls, Moves, Player};
use glint::{Gpu, OffscreenTarget, Renderer, View, WindowSurface, World};
use input::Input;
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

/// The demo scenes the picker offers, under the page.
const SCENES: [&str; 8] = [
    "scenes/showcase.scn",
    // 1,264 lights, 1,000 of them circling, shaded from light clusters.
    "scenes/lights.scn",
    "scenes/split.scn",
    "scenes/monitor.scn",
    "scenes/tablecloth.scn",
    "scenes/meadow.scn",
    "scenes/aquarium.scn",
    // 24,000 fish, drawn at the levels of detail their size needs.
    "scenes/underwater.scn",
];

thread_local! {
    /// The page's one viewer, for [`read_frame`].
    static VIEWER: RefCell<Option<Rc<RefCell<Viewer>>>> = const { RefCell::new(None) };
}

/// The last frame drawn, as `{ width, height, data }` with `data` its RGBA8
/// pixels, rows top to bottom (for the browser test: a WebGPU canvas cannot
/// always be read back by the page, the renderer's own target can).
#[wasm_bindgen]
pub async fn read_frame() -> Result<JsValue, JsValue> {
    let viewer = VIEWER.with(|v| v.borrow().clone()).ok_or("the viewer has not started")?;
    let readback = {
        let v = viewer.borrow();
        v.target.start_readback(&v.gpu)
    };
    // The browser answers between tasks: poll, and give it a turn, until it has.
    while !{
        let v = viewer.borrow();
        readback.poll(&v.gpu)
    } {
        let wait = js_sys::Promise::new(&mut |resolve, _| {
            if let Some(window) = web_sys::window() {
                let _ = window.set_timeout_with_callback_and_timeout_and_arguments_0(&resolve, 1);
            }
        });
        wasm_bindgen_futures::JsFuture::from(wait).await?;
    }
    let image = readback.finish().map_err(|e| e.to_string())?;
    let frame = js_sys::Object::new();
    js_sys::Reflect::set(&frame, &"width".into(), &image.width().into())?;
    js_sys::Reflect::set(&frame, &"height".into(), &image.height().into())?;
    js_sys::Reflect::set(&frame, &"data".into(), &js_sys::Uint8Array::from(image.as_raw().as_slice()))?;
    Ok(frame.into())
}

/// Start the viewer on the page's `#glint` canvas.
#[wasm_bindgen(start)]
pub fn start() {
    std::panic::set_hook(Box::new(|info| show_error(&format!("glint panicked: {info}"))));
    wasm_bindgen_futures::spawn_local(async {
        if let Err(e) = run().await {
            show_error(&e);
        }
    });
}

/// What the page asked for in its query string.
struct Query {
    scene: String,
    backend: Option<String>,
    size: Option<(u32, u32)>,
    /// The share of every tile of tiled instances drawn (`Renderer::set_density`).
    density: f32,
}

impl Query {
    fn read() -> Self {
        let search = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
        let params = web_sys::UrlSearchParams::new_with_str(&search).ok();
        let get = |key: &str| params.as_ref().and_then(|p| p.get(key));
        let size = get("size").and_then(|s| {
            let (w, h) = s.split_once('x')?;
            Some((w.parse().ok()?, h.parse().ok()?))
                .filter(|&(w, h): &(u32, u32)| (1..=4096).contains(&w) && (1..=4096).contains(&h))
        });
        let density = get("density").and_then(|d| d.parse::<f32>().ok()).filter(|d| (0.0..=1.0).contains(d));
        Self {
            scene: get("scene").unwrap_or_else(|| SCENES[0].into()),
            backend: get("backend"),
            size,
            density: density.unwrap_or(1.0),
        }
    }
}

/// A loaded scene placed in its renderer.
struct Shown {
    world: World,
    renderer: Renderer,
    /// The views of the camera shown (all of the scene's for the free camera).
    views: Vec<View>,
    /// The scene clock and the fly camera.
    player: Player,
    /// What a touch drag orbits: the first view's target.
    centre: glam::Vec3,
    /// What the user chose in the panel.
    controls: Controls,
    /// The scene camera shown (`None`: the free camera).
    camera: Option<usize>,
}

/// Everything the frame loop needs.
struct Viewer {
    canvas: web_sys::HtmlCanvasElement,
    gpu: Gpu,
    surface: WindowSurface,
    target: OffscreenTarget,
    msaa: u32,
    backend: &'static str,
    fixed_size: Option<(u32, u32)>,
    density: f32,
    shown: Option<Shown>,
    input: Input,
    frames: u64,
    last: Option<f64>,
    frame_ms: f64,
    /// The startup's stages until the first frame is shown (then `None`).
    startup: Option<startup::Startup>,
}

async fn run() -> Result<(), String> {
    let mut startup = startup::Startup::begin();
    let query = Query::read();
    let document = web_sys::window().and_then(|w| w.document()).ok_or("no document")?;
    let canvas: web_sys::HtmlCanvasElement = (document.get_element_by_id("glint"))
        .ok_or("the page has no #glint canvas")?
        .dyn_into()
        .map_err(|_| "#glint is not a canvas")?;
    let (width, height) = query.size.unwrap_or_else(|| canvas_size(&canvas));
    canvas.set_width(width);
    canvas.set_height(height);
    let (gpu, surface, backend) = open_gpu(&canvas, query.backend.as_deref()).await?;
    startup.lap("gpu");
    // A lost device draws nothing more: say so instead of leaving the last frame up.
    gpu.device.set_device_lost_callback(move |reason, message| {
        show_error(&format!("the {backend} device was lost ({reason:?}): {message}; reload the page"))
    });
    let surface = WindowSurface::new(&gpu, surface, width, height).map_err(|e| e.to_string())?;
    let msaa = if gpu.supports_msaa(4) { 4 } else { 1 };
    let target = OffscreenTarget::new(&gpu, width, height, msaa).map_err(|e| e.to_string())?;
    let viewer = Rc::new(RefCell::new(Viewer {
        canvas: canvas.clone(),
        gpu,
        surface,
        target,
        msaa,
        backend,
        fixed_size: query.size,
        density: query.density,
        shown: None,
        input: Input::default(),
        frames: 0,
        last: None,
        frame_ms: 0.0,
        startup: Some(startup),
    }));
    VIEWER.with(|v| *v.borrow_mut() = Some(viewer.clone()));
    listen(&canvas, &viewer)?;
    picker(&document, &viewer, &query.scene)?;
    show(&viewer, &query.scene).await;
    animate(viewer);
    Ok(())
}

/// A GPU on the canvas: WebGPU unless `backend` says `webgl2` or the browser has
/// no WebGPU adapter, else WebGL2.
async fn open_gpu(
    canvas: &web_sys::HtmlCanvasElement,
    backend: Option<&str>,
) -> Result<(Gpu, wgpu::Surface<'static>, &'static str), String> {
    let tries: &[(wgpu::Backends, &'static str)] = match backend {
        Some("webgl2") => &[(wgpu::Backends::GL, "WebGL2")],
        Some("webgpu") => &[(wgpu::Backends::BROWSER_WEBGPU, "WebGPU")],
        _ => &[(wgpu::Backends::BROWSER_WEBGPU, "WebGPU"), (wgpu::Backends::GL, "WebGL2")],
    };
    let navigator = web_sys::window().ok_or("no window")?.navigator();
    let has_webgpu = js_sys::Reflect::has(&navigator, &"gpu".into()).unwrap_or(false);
    let mut why = Vec::new();
    for &(backends, name) in tries {
        if backends == wgpu::Backends::BROWSER_WEBGPU && !has_webgpu {
            why.push(format!("{name}: the browser has none"));
            continue;
        }
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let surface = match instance.create_surface(wgpu::SurfaceTarget::Canvas(canvas.clone())) {
            Ok(s) => s,
            Err(e) => {
                why.push(format!("{name}: {e}"));
                continue;
            }
        };
        let options = wgpu::RequestAdapterOptions { compatible_surface: Some(&surface), ..Default::default() };
        match instance.request_adapter(&options).await {
            Ok(adapter) => {
                let gpu = Gpu::from_adapter_async(adapter).await.map_err(|e| e.to_string())?;
                return Ok((gpu, surface, name));
            }
            Err(e) => why.push(format!("{name}: {e}")),
        }
    }
    Err(format!("no GPU for the canvas ({})", why.join("; ")))
}

/// Fetch and show `scene`, or put its error on the page (keeping the last scene).
async fn show(viewer: &Rc<RefCell<Viewer>>, scene: &str) {
    set_text("status", &format!("loading {scene} ..."));
    let mut waits = fetch::Waits::default();
    let desc = match fetch::load(scene, &mut waits).await {
        Ok(desc) => desc,
        Err(e) => return show_error(&e),
    };
    if let Some(startup) = &mut viewer.borrow_mut().startup {
        startup.split(&[("fetch", waits.fetch), ("decode", waits.decode)], "load");
    }
    for warning in &desc.warnings {
        web_sys::console::warn_1(&warning.to_string().into());
    }
    clear_error();
    let mut v = viewer.borrow_mut();
    let placed = Shown::place(desc, &v.gpu, v.density);
    if let Some(startup) = &mut v.startup {
        startup.lap("place");
    }
    match placed {
        Ok(mut shown) => {
            shown.controls.toggle_free_camera();
            v.shown = Some(shown);
        }
        Err(e) => return show_error(&format!("{scene}: {e}")),
    }
    drop(v);
    if let Err(e) = panel::build(viewer) {
        show_error(&e);
    }
    // Shown while the next animation frame, the scene's first, makes its pipelines.
    set_text("status", &format!("{scene}: preparing shaders and pipelines ..."));
}

/// The frame callback, which schedules itself again (so it holds a handle on itself).
type FrameCallback = Rc<RefCell<Option<Closure<dyn FnMut(f64)>>>>;

/// Draw a frame on every animation frame of the page.
fn animate(viewer: Rc<RefCell<Viewer>>) {
    let tick: FrameCallback = Rc::new(RefCell::new(None));
    let next = tick.clone();
    *tick.borrow_mut() = Some(Closure::new(move |now: f64| {
        if let Err(e) = viewer.borrow_mut().frame(now) {
            show_error(&e);
        }
        request_frame(next.borrow().as_ref().expect("set before the first frame"));
    }));
    request_frame(tick.borrow().as_ref().expect("just set"));
}

fn request_frame(callback: &Closure<dyn FnMut(f64)>) {
    if let Some(window) = web_sys::window() {
        let _ = window.request_animation_frame(callback.as_ref().unchecked_ref());
    }
}

impl Viewer {
    /// One frame at page time `now` (ms): follow the canvas's size, move the
    /// camera, pose and draw the scene, show it, and report on the page.
    fn frame(&mut self, now: f64) -> Result<(), String> {
        let dt = self.last.map_or(0.0, |last| (now - last) / 1e3);
        self.last = Some(now);
        self.follow_size()?;
        let (fly_input, wheel, orbit) = self.input.take();
        let pressed = self.input.take_pressed();
        let Some(shown) = &mut self.shown else { return Ok(()) };
        for key in pressed {
            match key.as_str() {
                "KeyH" => panel::toggle(),
                "Enter" => shown.controls.toggle_free_camera(),
                "Space" => shown.controls.toggle_pause(),
                _ => {}
            }
        }
        shown.show_cloth_debug_if_chosen(&self.gpu)?;
        shown.show_chosen_camera();
        let moves = Moves { fly: fly_input, wheel, orbit: Some((shown.centre, orbit)) };
        if let Some(startup) = &mut self.startup {
            // The controls panel, and the wait for the first animation frame.
            startup.lap("waiting");
        }
        // The blit onto the canvas goes in the frame's one submission.
        let mut canvas = self.surface.acquire(&self.gpu);
        let after: Vec<&mut dyn glint::AfterViews> =
            canvas.as_mut().map(|c| c as &mut dyn glint::AfterViews).into_iter().collect();
        let real = std::time::Duration::try_from_secs_f64(dt).unwrap_or_default();
        let world = (&mut shown.world, &mut shown.renderer);
        let drawn = (&shown.views[..], &mut self.target);
        let output = shown.player.frame(world, &mut shown.controls, drawn, (real, moves), after);
        let stats = output.map_err(|e| e.to_string())?.views;
        if let Some(canvas) = canvas {
            canvas.present(&self.gpu);
        }
        if let Some(mut startup) = self.startup.take() {
            // Each view's prepare stage (once per format and variant).
            let prepare: f64 = stats.iter().map(|s| s.cpu_ms.prepare).sum();
            startup.split(&[("prepare", prepare)], "first frame");
            startup.report(&self.canvas);
        }
        self.frames += 1;
        self.frame_ms = if self.frames == 1 { dt * 1e3 } else { 0.9 * self.frame_ms + 0.1 * dt * 1e3 };
        let draws: u32 = stats.iter().map(|s| s.draws).sum();
        let calls: u32 = stats.iter().map(|s| s.draw_calls).sum();
        let drawn: u64 = stats.iter().map(|s| s.instances_drawn).sum();
        let (w, h) = (self.target.width(), self.target.height());
        // How the views were culled: on the GPU with WebGPU, on the CPU with WebGL2.
        let culling = stats.first().map_or("none", |s| s.culling.name());
        set_text(
            "status",
            &format!(
                "{} | {} | {w}x{h} | {:.1} ms a frame | {draws} draws in {calls} calls | {drawn} instances | {} | {} views",
                self.backend,
                shown.world.desc().path.display(),
                self.frame_ms,
                stats.first().map_or("", |s| s.culled()),
                stats.len()
            ),
        );
        let _ = self.canvas.set_attribute("data-frames", &self.frames.to_string());
        let _ = self.canvas.set_attribute("data-backend", self.backend);
        let _ = self.canvas.set_attribute("data-culling", culling);
        // Where the simulations stepped: schools and emitters on the GPU with WebGPU, on the CPU with WebGL2.
        let simulations = stats.first().map(|s| s.simulations.to_string()).unwrap_or_default();
        let _ = self.canvas.set_attribute("data-simulations", &simulations);
        let shadow_views: u32 = stats.iter().map(|s| s.shadow_views).sum();
        let _ = self.canvas.set_attribute("data-shadow-views", &shadow_views.to_string());
        let _ = self.canvas.set_attribute("data-instances", &drawn.to_string());
        let _ = self.canvas.set_attribute("data-time", &shown.player.clock.time.to_string());
        let binning = stats.first().and_then(|s| s.light_clusters.map(|c| (c.on_gpu, s.cpu_ms.lights)));
        let binning = binning.map(|(gpu, ms)| format!("{} {ms:.3}", if gpu { "gpu" } else { "cpu" }));
        let _ = self.canvas.set_attribute("data-light-binning", binning.as_deref().unwrap_or(""));
        Ok(())
    }

    /// Resize the surface and target to the canvas's displayed size (unless fixed).
    fn follow_size(&mut self) -> Result<(), String> {
        let (width, height) = self.fixed_size.unwrap_or_else(|| canvas_size(&self.canvas));
        if (width, height) == (self.target.width(), self.target.height()) {
            return Ok(());
        }
        self.canvas.set_width(width);
        self.canvas.set_height(height);
        self.surface.resize(&self.gpu, width, height);
        self.target = OffscreenTarget::new(&self.gpu, width, height, self.msaa).map_err(|e| e.to_string())?;
        Ok(())
    }
}

impl Shown {
    /// `desc` placed in a new renderer on `gpu`, drawing `density` of every
    /// tile, its first camera chosen; an error when no camera draws into the page.
    fn place(desc: glint::asset::SceneDesc, gpu: &Gpu, density: f32) -> Result<Self, String> {
        let mut renderer = Renderer::new(gpu);
        renderer.set_density(density);
        let controls = Controls::new(&desc, density).for_adapter(gpu);
        let world = World::place(desc, &mut renderer).map_err(|e| e.to_string())?;
        let views = world.views(None);
        let camera = views.iter().find(|view| view.output.is_none()).ok_or("no camera draws into the page")?.camera;
        let player = Player::new(&camera);
        Ok(Self { world, renderer, views, player, centre: camera.target, controls, camera: None })
    }

    /// Place the scene again when the controls turned the cloths' debug
    /// view on or off (the cloths start again from rest), keeping the
    /// controls, the camera and the free camera's place.
    fn show_cloth_debug_if_chosen(&mut self, gpu: &Gpu) -> Result<(), String> {
        let Some(debug) = self.controls.cloth_debug_to_show(self.world.desc()) else { return Ok(()) };
        let mut desc = self.world.desc().clone();
        desc.set_cloth_debug(debug);
        let placed = Self::place(desc, gpu, self.controls.density())?;
        (self.world, self.renderer) = (placed.world, placed.renderer);
        self.player.clock.restart();
        self.views = self.world.views(self.camera);
        Ok(())
    }

    /// Show the scene camera the controls chose (its views alone), or the
    /// scene's views for the free camera, when the choice changed; the free
    /// camera starts again from the camera shown.
    fn show_chosen_camera(&mut self) {
        let chosen = self.controls.scene_camera();
        if chosen == self.camera {
            return;
        }
        self.camera = chosen;
        self.views = self.world.views(chosen);
        if let Some(view) = self.views.iter().find(|v| v.output.is_none()) {
            let camera = view.camera;
            self.player.fly_from(&camera);
        }
    }
}

/// The canvas's displayed size in device pixels (at least one a side).
fn canvas_size(canvas: &web_sys::HtmlCanvasElement) -> (u32, u32) {
    let ratio = web_sys::window().map_or(1.0, |w| w.device_pixel_ratio());
    let side = |css: i32| ((f64::from(css.max(1)) * ratio).round() as u32).clamp(1, 4096);
    (side(canvas.client_width()), side(canvas.client_height()))
}

/// The scene picker `#scene`: the demo scenes, `current` chosen; choosing one shows it.
fn picker(document: &web_sys::Document, viewer: &Rc<RefCell<Viewer>>, current: &str) -> Result<(), String> {
    let Some(select) = document.get_element_by_id("scene") else { return Ok(()) };
    let select: web_sys::HtmlSelectElement = select.dyn_into().map_err(|_| "#scene is not a select")?;
    let mut names: Vec<&str> = SCENES.to_vec();
    if !names.contains(&current) {
        names.push(current);
    }
    for name in names {
        let option = web_sys::HtmlOptionElement::new_with_text_and_value(name, name).map_err(|e| format!("{e:?}"))?;
        option.set_selected(name == current);
        select.add_with_html_option_element(&option).map_err(|e| format!("{e:?}"))?;
    }
    let viewer = viewer.clone();
    let chosen = select.clone();
    let on_change = Closure::<dyn FnMut(web_sys::Event)>::new(move |_| {
        let (viewer, scene) = (viewer.clone(), chosen.value());
        wasm_bindgen_futures::spawn_local(async move { show(&viewer, &scene).await });
    });
    select
        .add_event_listener_with_callback("change", on_change.as_ref().unchecked_ref())
        .map_err(|e| format!("{e:?}"))?;
    on_change.forget();
    Ok(())
}

/// Keyboard on the window; mouse, wheel and touch on the canvas.
fn listen(canvas: &web_sys::HtmlCanvasElement, viewer: &Rc<RefCell<Viewer>>) -> Result<(), String> {
    let window = web_sys::window().ok_or("no window")?;
    fn on<E: JsCast + 'static>(
        target: &web_sys::EventTarget,
        kind: &str,
        viewer: &Rc<RefCell<Viewer>>,
        mut handle: impl FnMut(&mut Input, &E) + 'static,
    ) -> Result<(), String> {
        let viewer = viewer.clone();
        let closure = Closure::<dyn FnMut(web_sys::Event)>::new(move |event: web_sys::Event| {
            if let Some(event) = event.dyn_ref::<E>() {
                handle(&mut viewer.borrow_mut().input, event);
            }
        });
        let added = target.add_event_listener_with_callback(kind, closure.as_ref().unchecked_ref());
        closure.forget();
        added.map_err(|e| format!("{e:?}"))
    }
    on(&window, "keydown", viewer, |input, e: &web_sys::KeyboardEvent| {
        // Keys typed into the panel's inputs (Space on a checkbox) are theirs.
        let tag = e.target().and_then(|t| js_sys::Reflect::get(&t, &"tagName".into()).ok()).and_then(|t| t.as_string());
        if !matches!(tag.as_deref(), Some("INPUT" | "SELECT" | "BUTTON")) {
            input.key_pressed(e.code(), e.repeat());
            input.key(e.code(), true);
        }
    })?;
    on(&window, "keyup", viewer, |input, e: &web_sys::KeyboardEvent| input.key(e.code(), false))?;
    on(canvas, "mousedown", viewer, |input, e: &web_sys::MouseEvent| input.button(e.button(), true))?;
    on(&window, "mouseup", viewer, |input, e: &web_sys::MouseEvent| input.button(e.button(), false))?;
    on(&window, "mousemove", viewer, |input, e: &web_sys::MouseEvent| {
        input.mouse_moved(Vec2::new(e.movement_x() as f32, e.movement_y() as f32))
    })?;
    on(canvas, "contextmenu", viewer, |_, e: &web_sys::MouseEvent| e.prevent_default())?;
    on(canvas, "wheel", viewer, |input, e: &web_sys::WheelEvent| {
        e.prevent_default();
        input.wheel(e.delta_y());
    })?;
    let first_touch = |e: &web_sys::TouchEvent| {
        e.prevent_default();
        e.touches().get(0).map(|t| Vec2::new(t.client_x() as f32, t.client_y() as f32))
    };
    on(canvas, "touchstart", viewer, move |input, e: &web_sys::TouchEvent| input.touch(first_touch(e)))?;
    on(canvas, "touchmove", viewer, move |input, e: &web_sys::TouchEvent| input.touch(first_touch(e)))?;
    on(canvas, "touchend", viewer, |input, _: &web_sys::TouchEvent| input.touch(None))?;
    Ok(())
}

fn set_text(id: &str, text: &str) {
    if let Some(element) = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id(id)) {
        element.set_text_content(Some(text));
    }
}

/// Put `message` on the page (`#error`, and the canvas's `data-error`) and in the console.
fn show_error(message: &str) {
    web_sys::console::error_1(&message.into());
    set_text("error", message);
    if let Some(canvas) = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id("glint")) {
        let _ = canvas.set_attribute("data-error", message);
    }
}

fn clear_error() {
    set_text("error", "");
    if let Some(canvas) = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id("glint")) {
        let _ = canvas.remove_attribute("data-error");
    }
}
