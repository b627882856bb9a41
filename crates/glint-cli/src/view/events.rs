//! The viewer's window events: keys, mouse and wheel (what the overlay uses
//! goes to it alone), redraws, and the frame that runs scripted actions,
//! reloads and draws.

use super::{App, Input};
use glam::Vec2;
use glint::Error;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, DeviceId, ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::WindowId;

/// The first `glint-NNNN.png` in the current folder that does not exist yet.
fn next_screenshot_path() -> PathBuf {
    (1..=9999)
        .map(|n| PathBuf::from(format!("glint-{n:04}.png")))
        .find(|p| !p.exists())
        .unwrap_or_else(|| PathBuf::from("glint-screenshot.png"))
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.view.is_some() {
            return;
        }
        let Some(desc) = self.desc.take() else { return };
        match self.open(event_loop, desc) {
            Ok(view) => self.view = Some(view),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(view) = &mut self.view else { return };
        // What the overlay uses (a click on a panel, a drag of a slider) moves nothing else.
        let used = view.overlay.on_event(&view.window, &event);
        let result = match event {
            WindowEvent::KeyboardInput { .. } | WindowEvent::MouseInput { .. } | WindowEvent::MouseWheel { .. }
                if used =>
            {
                Ok(())
            }
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) => view.resize(size).map_err(Error::from),
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return };
                match event.state {
                    ElementState::Released => {
                        view.input.held.remove(&code);
                        Ok(())
                    }
                    ElementState::Pressed => {
                        view.input.held.insert(code);
                        match code {
                            KeyCode::Escape => {
                                event_loop.exit();
                                Ok(())
                            }
                            KeyCode::F12 if !event.repeat => view.screenshot(&next_screenshot_path()),
                            KeyCode::KeyH if !event.repeat => {
                                view.overlay.visible = !view.overlay.visible;
                                Ok(())
                            }
                            KeyCode::Enter if !event.repeat => {
                                view.controls.toggle_free_camera();
                                Ok(())
                            }
                            KeyCode::Space if !event.repeat => {
                                view.controls.toggle_pause();
                                Ok(())
                            }
                            KeyCode::BracketLeft | KeyCode::BracketRight => {
                                let step = if code == KeyCode::BracketLeft { -0.1 } else { 0.1 };
                                view.set_density(view.controls.density() + step);
                                Ok(())
                            }
                            KeyCode::Comma | KeyCode::Period => {
                                let step = if code == KeyCode::Comma { -0.5 } else { 0.5 };
                                view.set_time_of_day(view.time_of_day() + step);
                                Ok(())
                            }
                            _ => Ok(()),
                        }
                    }
                }
            }
            WindowEvent::MouseInput { button: MouseButton::Right, state, .. } => {
                view.set_looking(state == ElementState::Pressed);
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                view.input.wheel += match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                Ok(())
            }
            WindowEvent::Focused(false) => {
                view.set_looking(false);
                view.input = Input::default();
                Ok(())
            }
            WindowEvent::RedrawRequested => self.frame(event_loop, true),
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn device_event(&mut self, _event_loop: &ActiveEventLoop, _id: DeviceId, event: DeviceEvent) {
        if let (Some(view), DeviceEvent::MouseMotion { delta }) = (&mut self.view, event) {
            if view.input.looking {
                view.input.look += Vec2::new(delta.0 as f32, delta.1 as f32);
            }
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(view) = &self.view {
            let played = view.player.clock.total;
            eprintln!(
                "glint view: {} frames drawn in {:.2} s ({:.1} ms a frame); the scene played {:.2} s, {:.2}x real time",
                played.frames,
                played.real,
                played.frame_ms(),
                played.scene,
                played.speed()
            );
            let shown = view.overlay_ms.len();
            if let Some(median) = crate::bench::median(&mut view.overlay_ms.clone()) {
                let mean = view.overlay_ms.iter().sum::<f64>() / shown as f64;
                eprintln!(
                    "glint view: the overlay took {median:.3} ms of CPU a frame (median; mean {mean:.3}) over the {shown} frames shown with it"
                );
            }
        }
        if let (Some(view), Some(path), Ok(())) = (&self.view, &self.args.screenshot, &self.result) {
            if let Err(e) = view.screenshot(path) {
                self.result = Err(e);
            }
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(view) = &self.view else { return };
        let (width, height) = view.surface.size();
        if width > 0 && height > 0 {
            view.window.request_redraw();
            event_loop.set_control_flow(ControlFlow::Poll);
        } else {
            // Minimised: nothing to draw into, but frames still count (so `--frames`
            // ends) at a gentle pace instead of spinning.
            event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(16)));
            if let Err(e) = self.frame(event_loop, false) {
                self.fail(event_loop, e);
            }
        }
    }
}

impl App {
    /// One frame: scripted actions, hot reload, drawing (when `draw`), and the
    /// `--frames` / `--screenshot` ending.
    fn frame(&mut self, event_loop: &ActiveEventLoop, draw: bool) -> Result<(), Error> {
        let Some(view) = &mut self.view else { return Ok(()) };
        view.frames += 1;
        let frame = view.frames;
        for step in self.args.script.iter().filter(|s| s.frame == frame) {
            view.do_action(&step.action)?;
        }
        let density = view.controls.density();
        let placing = (self.args.cull, density, self.args.lod);
        view.reload_if_changed(&self.args.scene, self.args.camera, placing);
        view.show_cloth_debug_if_chosen(self.args.camera, placing)?;
        if draw {
            view.draw()?;
        }
        if self.args.frames.is_some_and(|n| view.frames >= n) {
            event_loop.exit();
        }
        Ok(())
    }
}
