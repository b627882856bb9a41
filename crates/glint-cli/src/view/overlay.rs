//! The viewer's overlay, drawn with egui over the frame (into the offscreen
//! target, so screenshots hold it): a controls panel showing the scene's
//! [`Controls`] list, and a stats panel with the frame time and its history,
//! each view's counts, stage CPU times and pass GPU times, and, when opened,
//! the frame's draw calls as `glint explain` lists them. `H` hides it.
//!
//! egui lays the panels out again when the user touches them, when the window
//! changes size, and otherwise [`REFRESH`] apart (the statistics then are
//! readable, not a blur); between layouts each frame paints the last one's
//! triangles again, which costs almost nothing. (egui asks to lay out again
//! after every pass whose text changed size, that is every frame here: it is
//! heard only for the first [`SIZING_PASSES`], while new panels size themselves.)

use glint::render::FrameCalls;
use glint::world::{ControlKind, Controls};
use glint::{AfterViews, FrameStats, Gpu, OffscreenTarget};
use std::collections::VecDeque;
use winit::window::Window;

/// Frames of history in the frame-time plot.
const HISTORY: usize = 120;

/// Narrowest window, in pixels, whose panels start open.
const MIN_OPEN_WIDTH: u32 = 560;

/// Longest time between two layouts of the panels (the statistics' refresh).
const REFRESH: std::time::Duration = std::time::Duration::from_millis(250);

/// Layouts after which egui's own requests to lay out again are not heard.
const SIZING_PASSES: u32 = 3;

/// The overlay and its egui state.
pub struct Overlay {
    ctx: egui::Context,
    state: egui_winit::State,
    renderer: egui_wgpu::Renderer,
    /// Whether it is drawn (`H`).
    pub visible: bool,
    /// Recent frame times, ms, oldest first.
    history: VecDeque<f32>,
    /// Whether the draw-call list is open (the renderer then explains frames).
    pub calls_open: bool,
    /// The last layout's triangles, its scale and the target size it was
    /// made for, and when.
    laid_out: Option<Layout>,
    /// Whether egui had input (or asked to lay out again while sizing) since the last layout.
    due: bool,
    /// Layouts so far.
    layouts: u32,
    /// CPU time of the last recording into a frame, ms.
    record_ms: f64,
}

/// One layout of the panels, painted until the next.
struct Layout {
    primitives: Vec<egui::ClippedPrimitive>,
    pixels_per_point: f32,
    size: (u32, u32),
    at: std::time::Instant,
}

impl Overlay {
    /// An overlay for `window`, drawing into targets of `format`.
    pub fn new(window: &Window, gpu: &Gpu, format: wgpu::TextureFormat) -> Self {
        let ctx = egui::Context::default();
        let side = gpu.device.limits().max_texture_dimension_2d as usize;
        let state = egui_winit::State::new(ctx.clone(), egui::ViewportId::ROOT, window, None, None, Some(side));
        let renderer = egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        Self {
            ctx,
            state,
            renderer,
            visible: true,
            history: VecDeque::new(),
            calls_open: false,
            laid_out: None,
            due: true,
            layouts: 0,
            record_ms: 0.0,
        }
    }

    /// Pass a window event to egui; whether egui used it (a click on a panel,
    /// typing into a field), so the viewer leaves it alone.
    pub fn on_event(&mut self, window: &Window, event: &winit::event::WindowEvent) -> bool {
        if !self.visible {
            return false;
        }
        let response = self.state.on_window_event(window, event);
        // Input lays the panels out again; a redraw request (every frame) does not.
        use winit::event::WindowEvent as E;
        let input = matches!(
            event,
            E::KeyboardInput { .. }
                | E::ModifiersChanged(_)
                | E::Ime(_)
                | E::CursorMoved { .. }
                | E::CursorLeft { .. }
                | E::MouseWheel { .. }
                | E::MouseInput { .. }
                | E::Touch(_)
                | E::Focused(_)
                | E::ScaleFactorChanged { .. }
        );
        self.due |= response.repaint && input;
        response.consumed
    }

    /// Note a frame's time for the plot.
    pub fn record(&mut self, frame_ms: f32) {
        if self.history.len() == HISTORY {
            self.history.pop_front();
        }
        self.history.push_back(frame_ms);
    }

    /// Before the frame: lay out the panels again where due (applying what
    /// the user changes to `controls`), from the last frame's `stats` and
    /// `calls`, for a target of `size`. Returns the CPU time it took, ms
    /// (`None` while hidden); recording the panels into the frame
    /// ([`AfterViews`]) adds its own time ([`Overlay::take_record_ms`]).
    pub fn prepare(
        &mut self,
        (window, gpu): (&Window, &Gpu),
        size: (u32, u32),
        controls: &mut Controls,
        (stats, calls): (&[FrameStats], Option<&FrameCalls>),
    ) -> Option<f64> {
        if !self.visible {
            return None;
        }
        let start = std::time::Instant::now();
        let stale = self.laid_out.as_ref().is_none_or(|l| l.size != size || l.at.elapsed() >= REFRESH);
        if self.due || stale {
            self.lay_out((window, gpu), size, controls, (stats, calls));
        }
        Some(start.elapsed().as_secs_f64() * 1e3)
    }

    /// The CPU time of the last recording into a frame, ms (0 when none).
    pub fn take_record_ms(&mut self) -> f64 {
        std::mem::take(&mut self.record_ms)
    }

    /// Run egui over the panels (applying what the user changes to
    /// `controls`), keeping the triangles to paint and updating its textures.
    fn lay_out(
        &mut self,
        (window, gpu): (&Window, &Gpu),
        size: (u32, u32),
        controls: &mut Controls,
        (stats, calls): (&[FrameStats], Option<&FrameCalls>),
    ) {
        let input = self.state.take_egui_input(window);
        let history = &self.history;
        let mut calls_open = self.calls_open;
        // In a small window the panels start folded, so the scene shows.
        let open = size.0 >= MIN_OPEN_WIDTH;
        let mut output = self.ctx.run_pass(input, |ctx| {
            let panel = |name: &'static str, corner: egui::Align2, x: f32| {
                egui::Window::new(name).anchor(corner, [x, 8.0]).vscroll(true).max_width(280.0).default_open(open)
            };
            panel("controls", egui::Align2::LEFT_TOP, 8.0).show(ctx, |ui| controls_panel(ui, controls));
            panel("stats", egui::Align2::RIGHT_TOP, -8.0).show(ctx, |ui| {
                stats_panel(ui, history, stats);
                calls_open = egui::CollapsingHeader::new("draw calls (this frame)")
                    .show(ui, |ui| calls_list(ui, calls))
                    .fully_open();
            });
        });
        self.calls_open = calls_open;
        let again = output.viewport_output.get(&egui::ViewportId::ROOT).is_some_and(|v| v.repaint_delay.is_zero());
        self.layouts += 1;
        self.due = again && self.layouts < SIZING_PASSES;
        self.state.handle_platform_output(window, std::mem::take(&mut output.platform_output));
        let primitives = self.ctx.tessellate(std::mem::take(&mut output.shapes), output.pixels_per_point);
        // Every texture change is applied (egui checks none is left).
        for (id, deltas) in output.textures_delta.set.drain() {
            for delta in &deltas {
                self.renderer.update_texture(&gpu.device, &gpu.queue, id, delta);
            }
        }
        for id in output.textures_delta.free.drain() {
            self.renderer.free_texture(&id);
        }
        let at = std::time::Instant::now();
        self.laid_out = Some(Layout { primitives, pixels_per_point: output.pixels_per_point, size, at });
    }
}

/// Every control of the scene, by section; changes go to `controls`.
fn controls_panel(ui: &mut egui::Ui, controls: &mut Controls) {
    let list = controls.list();
    for section in list.chunk_by(|a, b| a.section == b.section) {
        egui::CollapsingHeader::new(&section[0].section).default_open(true).show(ui, |ui| {
            for control in section {
                let changed = match &control.kind {
                    ControlKind::Toggle { on } => {
                        let mut on = *on;
                        ui.checkbox(&mut on, &control.label).changed().then_some(f32::from(u8::from(on)))
                    }
                    ControlKind::Slider { value, min, max, step } => {
                        let mut v = *value;
                        let slider =
                            egui::Slider::new(&mut v, *min..=*max).step_by(f64::from(*step)).text(&control.label);
                        ui.add(slider).changed().then_some(v)
                    }
                    ControlKind::Choice { index, options } => {
                        let mut chosen = *index;
                        egui::ComboBox::from_label(&control.label)
                            .selected_text(options.get(chosen).map_or("", String::as_str))
                            .show_ui(ui, |ui| {
                                for (k, option) in options.iter().enumerate() {
                                    ui.selectable_value(&mut chosen, k, option);
                                }
                            });
                        (chosen != *index).then_some(chosen as f32)
                    }
                    ControlKind::Button => ui.button(&control.label).clicked().then_some(1.0),
                };
                if let Some(value) = changed {
                    if let Err(e) = controls.set(&control.id, value) {
                        log::warn!("{e}");
                    }
                }
            }
        });
    }
    ui.label("H hides this overlay");
}

/// Frame time, its history, and each view's counts and times.
fn stats_panel(ui: &mut egui::Ui, history: &VecDeque<f32>, stats: &[FrameStats]) {
    let last = history.back().copied().unwrap_or(0.0);
    ui.label(format!("{last:.2} ms a frame, {:.0} fps", 1000.0 / last.max(1e-3)));
    frame_plot(ui, history);
    for (k, s) in stats.iter().enumerate() {
        egui::CollapsingHeader::new(format!("view {k}: {}", s.culled())).default_open(k == 0).show(ui, |ui| {
            egui::Grid::new(("stats", k)).num_columns(2).show(ui, |ui| {
                let mut row = |name: &str, value: String| {
                    ui.label(name);
                    ui.label(value);
                    ui.end_row();
                };
                row("draw calls", format!("{} ({} late)", s.draw_calls, s.late_draw_calls));
                row("draws", s.draws.to_string());
                row("pipelines bound", s.pipelines_bound.to_string());
                row("bind groups set", s.bind_groups_set.to_string());
                row("instances", format!("{} submitted, {} visible", s.instances_submitted, s.instances_drawn));
                row("culled", s.instances_culled.to_string());
                row("tiles", format!("{} drawn of {} tested", s.tiles_drawn, s.tiles_tested));
                row("shadow views", format!("{} ({} draws)", s.shadow_views, s.passes.shadow.draws));
                row("particles", format!("{} drawn, {} alive", s.particles_drawn, s.particles_alive));
                row("simulations", s.simulations.to_string());
                row("bytes uploaded", s.bytes_uploaded.total.to_string());
                let c = &s.cpu_ms;
                let stages = [
                    ("prepare", c.prepare),
                    ("cull", c.cull),
                    ("queue", c.queue),
                    ("sort", c.sort),
                    ("batch", c.batch),
                    ("upload", c.upload),
                    ("encode", c.encode),
                    ("submit", c.submit),
                ];
                let cpu =
                    |stages: &[(&str, f64)]| stages.iter().map(|(n, ms)| format!("{n} {ms:.3}")).collect::<Vec<_>>();
                row("CPU ms", format!("flush {:.3}", c.total));
                row("", cpu(&stages[..4]).join(", "));
                row("", cpu(&stages[4..]).join(", "));
                let gpu = s.gpu.as_ref().map_or("not measured here".to_owned(), |g| {
                    let post: Vec<String> = g.post_ms.iter().map(|ms| format!("{ms:.3}")).collect();
                    let shadow = g.shadow_ms.map_or(String::new(), |ms| format!("shadows {ms:.3}, "));
                    let depth = g.depth_prepass_ms.map_or(String::new(), |ms| format!("depth {ms:.3}, "));
                    let ao = g.ambient_occlusion_ms.map_or(String::new(), |ms| format!("ambient occlusion {ms:.3}, "));
                    format!("{shadow}{depth}{ao}forward {:.3}, post [{}]", g.forward_ms, post.join(", "))
                });
                row("GPU ms", gpu);
            });
        });
    }
}

/// A small line plot of the recent frame times, 0 at the bottom.
fn frame_plot(ui: &mut egui::Ui, history: &VecDeque<f32>) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(240.0, 48.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, egui::Color32::from_black_alpha(120));
    let top = history.iter().copied().fold(1.0_f32, f32::max);
    let points: Vec<egui::Pos2> = (history.iter().enumerate())
        .map(|(k, ms)| {
            let x = rect.left() + rect.width() * k as f32 / (HISTORY - 1) as f32;
            egui::pos2(x, rect.bottom() - rect.height() * ms / top)
        })
        .collect();
    painter.add(egui::Shape::line(points, egui::Stroke::new(1.5, egui::Color32::LIGHT_GREEN)));
    painter.text(
        rect.left_top(),
        egui::Align2::LEFT_TOP,
        format!("{top:.1} ms"),
        egui::FontId::monospace(10.0),
        egui::Color32::GRAY,
    );
}

/// The frame's passes and draw calls, one line each.
fn calls_list(ui: &mut egui::Ui, calls: Option<&FrameCalls>) {
    let Some(calls) = calls else {
        ui.label("(from the next frame)");
        return;
    };
    egui::ScrollArea::vertical().max_height(240.0).show(ui, |ui| {
        for pass in &calls.passes {
            ui.label(egui::RichText::new(format!("{} ({:?})", pass.name, pass.kind)).strong());
            for call in &pass.draw_calls {
                let names: Vec<String> = call
                    .batches
                    .iter()
                    .map(|b| format!("{} '{}' × '{}'", b.queue, b.material_name, b.mesh_name))
                    .collect();
                let what = if names.is_empty() { call.what.clone() } else { names.join(", ") };
                ui.label(format!(
                    "  {}: {} draws, {} instances; set {}: {what}",
                    call.command,
                    call.draws,
                    call.instances,
                    if call.changed.is_empty() { "nothing".to_owned() } else { call.changed.join(", ") }
                ));
            }
        }
    });
}

/// The panels as last laid out, drawn over the frame's picture in the frame's
/// own encoder (uploading egui's buffers first), when shown.
impl AfterViews for Overlay {
    fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &OffscreenTarget,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(layout) = self.laid_out.as_ref().filter(|_| self.visible) else { return Vec::new() };
        let start = std::time::Instant::now();
        let size = (target.width(), target.height());
        let screen =
            egui_wgpu::ScreenDescriptor { size_in_pixels: [size.0, size.1], pixels_per_point: layout.pixels_per_point };
        let before = self.renderer.update_buffers(device, queue, encoder, &layout.primitives, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("overlay"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target.color_view(),
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })],
                ..Default::default()
            });
            self.renderer.render(&mut pass.forget_lifetime(), &layout.primitives, &screen);
        }
        self.record_ms = start.elapsed().as_secs_f64() * 1e3;
        before
    }
}
