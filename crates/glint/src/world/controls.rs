//! What a user can change in a running scene, described once for every front
//! end: the viewer draws [`Controls::list`] with egui, the web page as HTML
//! controls beside its canvas. Each [`Control`] has a stable id; a front end
//! shows its kind and value, and hands a new value back to [`Controls::set`]
//! as a number (a toggle 0 or 1, a choice its index, a button anything).
//!
//! The choices take effect through three calls a frame loop makes:
//! [`Controls::apply`] (density, time of day and shadows, into the world and
//! renderer), [`Controls::views`] (the chosen camera, culling, ambient
//! occlusion, post effects and exposure) and [`Controls::advance`] (pause, speed and restart of the
//! scene clock).

use super::World;
use crate::asset::SceneDesc;
use crate::scene::MAX_POST_EFFECTS;
use crate::scene::{AmbientOcclusion, Camera, Culling, PostEffect, SmaaPreset, Tonemap, Transparency, View};
use crate::Renderer;
use serde::Serialize;

/// One thing a user can change.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Control {
    /// Stable id, for [`Controls::set`]: "camera", "post.0.1.intensity", ….
    pub id: String,
    /// The section it belongs in: "View", "Scene", "Time", "Post: view 0".
    pub section: String,
    /// What it is called on screen.
    pub label: String,
    /// Its kind and current value.
    pub kind: ControlKind,
}

/// A control's kind and current value.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ControlKind {
    /// On or off.
    Toggle {
        /// Whether it is on.
        on: bool,
    },
    /// A number in a range.
    Slider {
        /// The value.
        value: f32,
        /// Least value.
        min: f32,
        /// Greatest value.
        max: f32,
        /// Step between values.
        step: f32,
    },
    /// One of a list.
    Choice {
        /// The chosen one's index.
        index: usize,
        /// The options.
        options: Vec<String>,
    },
    /// An action.
    Button,
}

/// The culling choices, after "as the scene says".
const CULLINGS: [(Culling, &str); 3] = [(Culling::Off, "off"), (Culling::Cpu, "CPU"), (Culling::Gpu, "GPU")];

/// The tonemap operators, in the order shown.
const TONEMAPS: [(Tonemap, &str); 4] =
    [(Tonemap::None, "none"), (Tonemap::Reinhard, "Reinhard"), (Tonemap::Aces, "ACES"), (Tonemap::Agx, "AgX")];

/// The anti-aliasing choices, after "as the scene says": the chain's own
/// FXAA or SMAA is taken out and the chosen effect added at the chain's end,
/// in every view that draws into the picture (`None`: neither).
const ANTIALIASING: [(Option<PostEffect>, &str); 6] = [
    (None, "none"),
    (Some(PostEffect::Fxaa), "FXAA"),
    (Some(PostEffect::Smaa { preset: SmaaPreset::Low }), "SMAA low"),
    (Some(PostEffect::Smaa { preset: SmaaPreset::Medium }), "SMAA medium"),
    (Some(PostEffect::Smaa { preset: SmaaPreset::High }), "SMAA high"),
    (Some(PostEffect::Smaa { preset: SmaaPreset::Ultra }), "SMAA ultra"),
];

/// The largest level-of-detail error offered, pixels.
const LOD_ERROR_MAX: f32 = 8.0;

/// The clock speeds offered, times real time.
const SPEED_RANGE: (f32, f32) = (0.0, 4.0);

/// Everything a user has chosen for one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Controls {
    /// The scene's cameras (a view's post controls are its camera's).
    scene_cameras: Vec<Camera>,
    /// How many cameras there are to choose from (at least one), before the free camera.
    cameras: usize,
    /// The chosen camera: one of the scene's, or `cameras` for the free one.
    camera: usize,
    /// 0 for as each camera says, else 1 + an index of [`CULLINGS`].
    culling: usize,
    /// 0 for as each camera says, else 1 + an index of [`ANTIALIASING`].
    antialiasing: usize,
    /// Whether views draw levels of detail, and the error they allow in
    /// pixels where chosen (else as each camera says).
    levels: bool,
    lod_error: Option<f32>,
    /// Whether the scene has point or spot lights, and whether clustered
    /// views draw the heat map of lights per cluster.
    has_positional: bool,
    cluster_heat: bool,
    /// Whether the scene has shadow-casting lights, and whether they cast.
    has_shadows: bool,
    shadows: bool,
    /// EV added to every tonemap's exposure (where any view tonemaps).
    has_tonemap: bool,
    exposure: f32,
    /// Whether the cloths draw their debug view (`None`: the scene has no cloth).
    cloth_debug: Option<bool>,
    /// Whether the scene has tiled instances, and the share drawn.
    has_tiles: bool,
    density: f32,
    /// The hour of the sun and sky, where the scene has one.
    time_of_day: Option<f32>,
    paused: bool,
    speed: f32,
    restart: bool,
    /// Each camera's post effects (as the scene gave them), and which are on.
    post: Vec<Vec<(PostEffect, bool)>>,
    /// Each camera's ambient occlusion settings (the scene's, else the
    /// defaults), and whether it is on.
    occlusion: Vec<(AmbientOcclusion, bool)>,
    /// Which of [`SAMPLES`] each frame averages.
    samples: usize,
    /// The shadow-casting directional lights' angular size in degrees (soft
    /// shadows), where the scene has such a light.
    sun_size: Option<f32>,
    /// How every view draws transparency, an index of
    /// [`Transparency::ALL`], where the scene has something transparent.
    transparency: Option<usize>,
    /// Whether exact transparency is offered (where the adapter can draw it:
    /// [`for_adapter`](Self::for_adapter)).
    offers_exact: bool,
}

/// The samples per pixel a frame may average (an accumulated still each
/// frame: for screenshots, as `glint render --spp`).
const SAMPLES: [u32; 4] = [1, 4, 16, 64];
/// The largest sun size the control offers, in degrees (as `.scn` files may give).
const SUN_SIZE_MAX: f32 = 20.0;

impl Controls {
    /// The controls of the scene `desc` describes, everything as it says, its
    /// first camera chosen, drawing `density` of every tile.
    pub fn new(desc: &SceneDesc, density: f32) -> Self {
        let chains = desc.camera_views.iter().map(|c| &c.post);
        let has_tonemap = chains.clone().flatten().any(|e| matches!(e, PostEffect::Tonemap { .. }));
        Self {
            scene_cameras: desc.cameras.clone(),
            cameras: desc.cameras.len().max(1),
            camera: 0,
            culling: 0,
            antialiasing: 0,
            levels: true,
            lod_error: None,
            has_positional: desc.lights.iter().any(|l| !matches!(l.kind, crate::scene::LightKind::Directional { .. })),
            cluster_heat: false,
            has_shadows: desc.lights.iter().any(|l| l.shadows.is_some()),
            shadows: true,
            has_tonemap,
            exposure: 0.0,
            cloth_debug: (!desc.cloths.is_empty()).then(|| desc.cloths.iter().any(|c| c.debug)),
            has_tiles: desc.entities.iter().any(|e| e.tiles.is_some()),
            density,
            time_of_day: desc.time_of_day,
            paused: false,
            speed: 1.0,
            restart: false,
            post: chains.map(|chain| chain.iter().map(|&e| (e, true)).collect()).collect(),
            occlusion: (desc.camera_views.iter())
                .map(|c| (c.ambient_occlusion.unwrap_or_default(), c.ambient_occlusion.is_some()))
                .collect(),
            samples: 0,
            sun_size: (desc.lights.iter())
                .filter(|l| matches!(l.kind, crate::scene::LightKind::Directional { .. }))
                .find_map(|l| l.shadows)
                .map(|s| s.light_size.min(SUN_SIZE_MAX)),
            transparency: desc.has_transparency().then_some(desc.transparency as usize),
            offers_exact: true,
        }
    }

    /// These controls for `gpu`: exact transparency offered only where it
    /// can draw it ([`Gpu::fragment_lists`](crate::Gpu::fragment_lists)), or
    /// where the scene asks for it (its frames are then refused with the
    /// reason, until another way is chosen).
    pub fn for_adapter(self, gpu: &crate::Gpu) -> Self {
        let asked = self.transparency == Some(Transparency::Exact as usize);
        Self { offers_exact: gpu.fragment_lists() || asked, ..self }
    }

    /// Every control, in the order shown.
    pub fn list(&self) -> Vec<Control> {
        let mut list = Vec::new();
        let mut add = |id: String, section: &str, label: &str, kind| {
            list.push(Control { id, section: section.into(), label: label.into(), kind });
        };
        let mut cameras: Vec<String> = (0..self.cameras).map(|k| format!("camera {k}")).collect();
        cameras.push("free camera (Enter)".into());
        add("camera".into(), "View", "camera", ControlKind::Choice { index: self.camera, options: cameras });
        let mut cullings = vec!["as the scene says".to_owned()];
        cullings.extend(CULLINGS.iter().map(|(_, n)| (*n).to_owned()));
        add("culling".into(), "View", "culling", ControlKind::Choice { index: self.culling, options: cullings });
        let mut options = vec!["as the scene says".to_owned()];
        options.extend(ANTIALIASING.iter().map(|(_, n)| (*n).to_owned()));
        let kind = ControlKind::Choice { index: self.antialiasing, options };
        add("antialiasing".into(), "View", "anti-aliasing (post)", kind);
        add("levels".into(), "View", "levels of detail", ControlKind::Toggle { on: self.levels });
        let error = self.lod_error.unwrap_or(crate::scene::DEFAULT_LOD_ERROR);
        let kind = ControlKind::Slider { value: error, min: 0.0, max: LOD_ERROR_MAX, step: 0.05 };
        add("lod_error".into(), "View", "level error (px)", kind);
        let options = SAMPLES.iter().map(|n| n.to_string()).collect();
        add("samples".into(), "View", "samples per pixel", ControlKind::Choice { index: self.samples, options });
        if let Some(index) = self.transparency {
            let offered = if self.offers_exact { Transparency::ALL.len() } else { Transparency::ALL.len() - 1 };
            let options = Transparency::NAMES[..offered].iter().map(|n| (*n).to_owned()).collect();
            add("transparency".into(), "View", "transparency", ControlKind::Choice { index, options });
        }
        if self.has_positional {
            let kind = ControlKind::Toggle { on: self.cluster_heat };
            add("cluster_heat".into(), "View", "lights per cluster (heat map)", kind);
        }
        if self.has_shadows {
            add("shadows".into(), "Scene", "shadows", ControlKind::Toggle { on: self.shadows });
        }
        if let Some(value) = self.sun_size {
            let kind = ControlKind::Slider { value, min: 0.0, max: SUN_SIZE_MAX, step: 0.1 };
            add("sun_size".into(), "Scene", "sun size (°): soft shadows", kind);
        }
        if self.has_tonemap {
            let kind = ControlKind::Slider { value: self.exposure, min: -4.0, max: 4.0, step: 0.1 };
            add("exposure".into(), "Scene", "exposure (EV)", kind);
        }
        if let Some(on) = self.cloth_debug {
            add("cloth_debug".into(), "Scene", "cloth debug view", ControlKind::Toggle { on });
        }
        if self.has_tiles {
            let kind = ControlKind::Slider { value: self.density, min: 0.0, max: 1.0, step: 0.05 };
            add("density".into(), "Scene", "density", kind);
        }
        if let Some(hours) = self.time_of_day {
            let kind = ControlKind::Slider { value: hours, min: 0.0, max: 24.0, step: 0.25 };
            add("time_of_day".into(), "Scene", "time of day (h)", kind);
        }
        add("paused".into(), "Time", "paused (Space)", ControlKind::Toggle { on: self.paused });
        let (min, max) = SPEED_RANGE;
        add("speed".into(), "Time", "speed", ControlKind::Slider { value: self.speed, min, max, step: 0.05 });
        add("restart".into(), "Time", "restart", ControlKind::Button);
        for (v, (settings, on)) in self.occlusion.iter().enumerate() {
            let section = format!("Ambient occlusion: camera {v}");
            let id = |name: &str| format!("ssao.{v}.{name}");
            add(id("on"), &section, "ambient occlusion", ControlKind::Toggle { on: *on });
            let (radius, intensity) = (settings.radius, settings.intensity);
            add(
                id("radius"),
                &section,
                "radius",
                ControlKind::Slider { value: radius, min: 0.05, max: 4.0, step: 0.05 },
            );
            add(
                id("intensity"),
                &section,
                "intensity",
                ControlKind::Slider { value: intensity, min: 0.0, max: 4.0, step: 0.1 },
            );
        }
        for (v, effects) in self.post.iter().enumerate() {
            let section = format!("Post: camera {v}");
            for (k, (effect, on)) in effects.iter().enumerate() {
                let id = |name: &str| format!("post.{v}.{k}.{name}");
                add(id("on"), &section, effect.name(), ControlKind::Toggle { on: *on });
                for (name, value, min, max) in parameters(effect) {
                    add(id(name), &section, name, ControlKind::Slider { value, min, max, step: (max - min) / 100.0 });
                }
                if let PostEffect::Tonemap { operator, .. } = effect {
                    let index = TONEMAPS.iter().position(|(t, _)| t == operator).unwrap_or(0);
                    let options = TONEMAPS.iter().map(|(_, n)| (*n).to_owned()).collect();
                    add(id("operator"), &section, "operator", ControlKind::Choice { index, options });
                }
                if let PostEffect::Smaa { preset } = effect {
                    let options = SmaaPreset::NAMES.iter().map(|n| (*n).to_owned()).collect();
                    add(id("preset"), &section, "preset", ControlKind::Choice { index: *preset as usize, options });
                }
            }
        }
        list
    }

    /// Set control `id` to `value` (clamped to its range; a toggle is on for
    /// anything but 0, a choice takes the index, a button is pressed).
    /// Errors name what was expected, for an id or value from a page or script.
    pub fn set(&mut self, id: &str, value: f32) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("{id}: {value} is not a number"));
        }
        let control = self.list().into_iter().find(|c| c.id == id).ok_or_else(|| format!("no control '{id}'"))?;
        let on = value != 0.0;
        let clamp = |v: f32| match &control.kind {
            ControlKind::Slider { min, max, .. } => v.clamp(*min, *max),
            _ => v,
        };
        let index = |options: usize| chosen(value, options);
        match (id, &control.kind) {
            ("camera", ControlKind::Choice { options, .. }) => self.camera = index(options.len()),
            ("culling", ControlKind::Choice { options, .. }) => self.culling = index(options.len()),
            ("antialiasing", ControlKind::Choice { options, .. }) => self.antialiasing = index(options.len()),
            ("levels", _) => self.levels = on,
            ("cluster_heat", _) => self.cluster_heat = on,
            ("lod_error", _) => self.lod_error = Some(clamp(value)),
            ("shadows", _) => self.shadows = on,
            ("samples", ControlKind::Choice { options, .. }) => self.samples = index(options.len()),
            ("transparency", ControlKind::Choice { options, .. }) => self.transparency = Some(index(options.len())),
            ("sun_size", _) => self.sun_size = Some(clamp(value)),
            ("cloth_debug", _) => self.cloth_debug = Some(on),
            ("exposure", _) => self.exposure = clamp(value),
            ("density", _) => self.density = clamp(value),
            ("time_of_day", _) => self.time_of_day = Some(clamp(value)),
            ("paused", _) => self.paused = on,
            ("speed", _) => self.speed = clamp(value),
            ("restart", _) => self.restart = true,
            (ssao, _) if ssao.starts_with("ssao.") => self.set_occlusion(ssao, clamp(value), on)?,
            (post, kind) => self.set_post(post, kind, value, on)?,
        }
        Ok(())
    }

    /// Set a "ssao.V.NAME" control (`value` clamped to its range).
    fn set_occlusion(&mut self, id: &str, value: f32, on: bool) -> Result<(), String> {
        let mut parts = id.split('.').skip(1);
        let (v, name) = (parts.next().and_then(|v| v.parse::<usize>().ok()), parts.next());
        let Some((settings, enabled)) = v.and_then(|v| self.occlusion.get_mut(v)) else {
            return Err(format!("no control '{id}'"));
        };
        match name {
            Some("on") => *enabled = on,
            Some("radius") => settings.radius = value,
            Some("intensity") => settings.intensity = value,
            _ => return Err(format!("no control '{id}'")),
        }
        Ok(())
    }

    /// Set a "post.V.K.NAME" control.
    fn set_post(&mut self, id: &str, kind: &ControlKind, value: f32, on: bool) -> Result<(), String> {
        let mut parts = id.split('.').skip(1);
        let (v, k, name) = match (parts.next(), parts.next(), parts.next()) {
            (Some(v), Some(k), Some(name)) => (v.parse::<usize>(), k.parse::<usize>(), name),
            _ => return Err(format!("no control '{id}'")),
        };
        let (Ok(v), Ok(k)) = (v, k) else { return Err(format!("no control '{id}'")) };
        let (effect, enabled) = &mut self.post[v][k];
        let value = match kind {
            ControlKind::Slider { min, max, .. } => value.clamp(*min, *max),
            _ => value,
        };
        match (name, effect) {
            ("on", _) => *enabled = on,
            ("threshold", PostEffect::Bloom { threshold, .. } | PostEffect::Edges { threshold, .. }) => {
                *threshold = value
            }
            ("intensity", PostEffect::Bloom { intensity, .. }) => *intensity = value,
            ("exposure", PostEffect::Tonemap { exposure, .. }) => *exposure = value,
            ("operator", PostEffect::Tonemap { operator, .. }) => *operator = TONEMAPS[chosen(value, TONEMAPS.len())].0,
            ("strength", PostEffect::Vignette { strength }) => *strength = value,
            ("preset", PostEffect::Smaa { preset }) => *preset = SmaaPreset::ALL[chosen(value, SmaaPreset::ALL.len())],
            _ => return Err(format!("no control '{id}'")),
        }
        Ok(())
    }

    /// Whether the free camera is chosen (the front end then flies it).
    pub fn free_camera(&self) -> bool {
        self.camera == self.cameras
    }

    /// Switch between the free camera and the first of the scene's (Enter).
    pub fn toggle_free_camera(&mut self) {
        self.camera = if self.free_camera() { 0 } else { self.cameras };
    }

    /// The scene camera to show alone, or `None` for the free camera (which
    /// starts where the scene's views put it).
    pub fn scene_camera(&self) -> Option<usize> {
        (!self.free_camera()).then_some(self.camera)
    }

    /// Pause or play (Space).
    pub fn toggle_pause(&mut self) {
        self.paused = !self.paused;
    }

    /// Whether the cloths of `desc` should draw their debug view, where they
    /// do not yet: the front end then places the scene again after
    /// [`SceneDesc::set_cloth_debug`].
    pub fn cloth_debug_to_show(&self, desc: &SceneDesc) -> Option<bool> {
        self.cloth_debug.filter(|&on| desc.cloths.iter().any(|c| c.debug != on))
    }

    /// The share of every tile drawn.
    pub fn density(&self) -> f32 {
        self.density
    }

    /// Draw `density` (0..=1) of every tile (`[` and `]`, whether or not the
    /// scene has tiles).
    pub fn set_density(&mut self, density: f32) {
        self.density = density.clamp(0.0, 1.0);
    }

    /// The hour of the sun, where the scene has one.
    pub fn time_of_day(&self) -> Option<f32> {
        self.time_of_day
    }

    /// Move the sun and sky to `hours` (`,` and `.`; the scene then has a time of day).
    pub fn set_time_of_day(&mut self, hours: f32) {
        self.time_of_day = Some(hours.rem_euclid(24.0));
    }

    /// Put the density, levels of detail, the clusters' heat map, time of day,
    /// shadows and the sun's size into `world` and `renderer`
    /// (each frame: each is cheap where it did not change).
    pub fn apply(&self, world: &mut World, renderer: &mut Renderer) {
        renderer.set_density(self.density);
        renderer.set_levels_of_detail(self.levels);
        renderer.set_cluster_heat_map(self.cluster_heat);
        if let Some(hours) = self.time_of_day.filter(|&h| world.desc().time_of_day != Some(h)) {
            if let Err(e) = world.set_time_of_day(hours) {
                log::warn!("{e}");
            }
        }
        world.set_shadows(self.shadows);
        // Only once changed: the scene's suns keep their own sizes until then.
        if let Some(degrees) = self.sun_size.filter(|&d| world.sun_size() != Some(d)) {
            world.set_sun_size(degrees);
        }
    }

    /// The samples per pixel each frame averages ([`World::draw_still_then`]).
    pub fn samples_per_pixel(&self) -> u32 {
        SAMPLES[self.samples]
    }

    /// `views` (the world's, for [`scene_camera`](Self::scene_camera)) as
    /// chosen: culling, the ambient occlusion of each view of a scene camera,
    /// its post chain with the effects turned off left out and the
    /// exposure added to its tonemapping, and every chain's anti-aliasing.
    pub fn views(&self, views: Vec<View>) -> Vec<View> {
        (views.into_iter())
            .map(|mut view| {
                if self.culling > 0 {
                    view.culling = CULLINGS[self.culling - 1].0;
                }
                if let Some(pixels) = self.lod_error {
                    view.lod_error = pixels;
                }
                if let Some(k) = self.transparency {
                    view.transparency = Transparency::ALL[k];
                }
                let camera = self.scene_cameras.iter().position(|c| *c == view.camera);
                if let Some(effects) = camera.and_then(|c| self.post.get(c)) {
                    view.post = effects.iter().filter(|(_, on)| *on).map(|(e, _)| self.exposed(*e)).collect();
                }
                if let Some(&(settings, on)) = camera.and_then(|c| self.occlusion.get(c)) {
                    view.ambient_occlusion = on.then_some(settings);
                }
                let chosen = self.antialiasing.checked_sub(1).map(|k| ANTIALIASING[k]);
                if let Some((chosen, _)) = chosen.filter(|_| view.output.is_none()) {
                    view.post.retain(|e| !matches!(e, PostEffect::Fxaa | PostEffect::Smaa { .. }));
                    view.post.extend(chosen.filter(|_| view.post.len() < MAX_POST_EFFECTS));
                }
                view
            })
            .collect()
    }

    /// `effect` with the chosen exposure added, where it tonemaps.
    fn exposed(&self, effect: PostEffect) -> PostEffect {
        match effect {
            PostEffect::Tonemap { operator, exposure } => {
                PostEffect::Tonemap { operator, exposure: exposure + self.exposure }
            }
            other => other,
        }
    }

    /// How far a frame that took `real` seconds moves the scene clock
    /// (nothing while paused, else times the speed), and whether it starts
    /// again from 0 (restart was pressed since the last frame).
    pub fn advance(&mut self, real: f32) -> (f32, bool) {
        let restart = std::mem::take(&mut self.restart);
        (if self.paused { 0.0 } else { real * self.speed }, restart)
    }
}

/// The option a choice control's `value` picks among `options`: its index,
/// clamped to the list.
fn chosen(value: f32, options: usize) -> usize {
    (value.max(0.0) as usize).min(options.saturating_sub(1))
}

/// An effect's numeric parameters: name, value and range.
fn parameters(effect: &PostEffect) -> Vec<(&'static str, f32, f32, f32)> {
    match *effect {
        PostEffect::Bloom { threshold, intensity } => {
            vec![("threshold", threshold, 0.0, 4.0), ("intensity", intensity, 0.0, 2.0)]
        }
        PostEffect::Tonemap { exposure, .. } => vec![("exposure", exposure, -4.0, 4.0)],
        PostEffect::Fxaa | PostEffect::Smaa { .. } => Vec::new(),
        PostEffect::Edges { threshold, .. } => vec![("threshold", threshold, 0.0, 1.0)],
        PostEffect::Vignette { strength } => vec![("strength", strength, 0.0, 1.0)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asset::parse_scene;

    fn controls(scene: &str) -> Controls {
        Controls::new(&parse_scene("t.scn".as_ref(), scene).expect("scene"), 1.0)
    }

    const SCENE: &str = r#"
{ "classname" "world"
"time_of_day" "9" }
{ "classname" "camera"
"origin" "0 1 5"
"post" "bloom tonemap" }
{ "classname" "camera"
"origin" "5 1 0" }
{ "classname" "light_directional"
"direction" "0 -1 0"
"shadows" "1" }
{ "classname" "entity"
"mesh" "cube" }
"#;

    #[test]
    fn the_list_follows_the_scene() {
        let c = controls(SCENE);
        let ids: Vec<String> = c.list().into_iter().map(|c| c.id).collect();
        for id in ["camera", "culling", "levels", "lod_error", "shadows", "exposure", "time_of_day", "paused", "speed"]
        {
            assert!(ids.contains(&id.to_owned()), "{id} in {ids:?}");
        }
        assert!(!ids.contains(&"density".to_owned()), "no tiles, no density");
        assert!(!ids.contains(&"cluster_heat".to_owned()), "a sun alone, no clusters");
        assert!(ids.contains(&"post.0.0.intensity".to_owned()) && ids.contains(&"post.0.1.operator".to_owned()));
        let plain = controls("{ \"classname\" \"camera\" }\n{ \"classname\" \"light_point\"\n\"origin\" \"0 1 0\" }\n");
        let ids: Vec<String> = plain.list().into_iter().map(|c| c.id).collect();
        assert!(!ids.iter().any(|i| i == "shadows" || i == "exposure" || i == "time_of_day"), "{ids:?}");
        assert!(ids.iter().any(|i| i == "cluster_heat"), "a point light: the clusters' heat map {ids:?}");
        let mut plain = plain;
        plain.set("cluster_heat", 1.0).unwrap();
        assert!(plain.list().iter().any(|c| c.id == "cluster_heat" && c.kind == ControlKind::Toggle { on: true }));
    }

    #[test]
    fn setting_a_control_changes_what_it_claims() {
        let mut c = controls(SCENE);
        let base = vec![View::new(c.scene_cameras[0]).with_post(vec![PostEffect::BLOOM, PostEffect::TONEMAP])];
        assert_eq!(c.views(base.clone())[0].lod_error, crate::scene::DEFAULT_LOD_ERROR, "as the camera says");
        c.set("post.0.0.on", 0.0).unwrap();
        c.set("exposure", 1.5).unwrap();
        c.set("culling", 2.0).unwrap();
        c.set("lod_error", 99.0).unwrap();
        let views = c.views(base.clone());
        assert_eq!(views[0].lod_error, LOD_ERROR_MAX, "the error clamps to its range");
        assert_eq!(views[0].post, vec![PostEffect::Tonemap { operator: Tonemap::Aces, exposure: 1.5 }]);
        assert_eq!(views[0].culling, Culling::Cpu);
        assert_eq!(views[0].ambient_occlusion, None, "the scene's camera has none");
        c.set("ssao.0.on", 1.0).unwrap();
        c.set("ssao.0.radius", 99.0).unwrap();
        c.set("ssao.0.intensity", 2.0).unwrap();
        let occlusion = c.views(base.clone())[0].ambient_occlusion.expect("turned on");
        assert_eq!((occlusion.radius, occlusion.intensity), (4.0, 2.0), "the radius clamps to 4");
        c.set("post.0.1.operator", 3.0).unwrap();
        assert!(matches!(c.views(base)[0].post[0], PostEffect::Tonemap { operator: Tonemap::Agx, .. }));
        assert_eq!(c.samples_per_pixel(), 1, "a frame of its own");
        c.set("samples", 2.0).unwrap();
        assert_eq!(c.samples_per_pixel(), 16);
        c.set("samples", 9.0).unwrap();
        assert_eq!(c.samples_per_pixel(), 64, "the last choice");
        let sun = |c: &Controls| c.list().into_iter().find(|c| c.id == "sun_size").map(|c| c.kind);
        assert_eq!(sun(&c), Some(ControlKind::Slider { value: 0.0, min: 0.0, max: SUN_SIZE_MAX, step: 0.1 }));
        c.set("sun_size", 99.0).unwrap();
        assert!(matches!(sun(&c), Some(ControlKind::Slider { value, .. }) if value == SUN_SIZE_MAX));
        let unshadowed = controls("{ \"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\" }\n");
        assert_eq!(sun(&unshadowed), None, "no shadows, no sun size");
        c.set("speed", 9.0).unwrap();
        assert_eq!(c.advance(0.5), (2.0, false), "speed clamps to 4");
        c.set("paused", 1.0).unwrap();
        c.set("restart", 0.0).unwrap();
        assert_eq!(c.advance(0.5), (0.0, true), "paused: the clock stays; restart once");
        assert_eq!(c.advance(0.5), (0.0, false));
        c.set("camera", 99.0).unwrap();
        assert!(c.free_camera(), "the last choice is the free camera");
        c.toggle_free_camera();
        assert_eq!(c.scene_camera(), Some(0));
        let bad = [
            ("nothing", 1.0),
            ("post.7.0.on", 1.0),
            ("post.0.0.exposure", 1.0),
            ("speed", f32::NAN),
            ("ssao.5.on", 1.0),
        ];
        for (id, value) in bad {
            assert!(c.set(id, value).is_err(), "{id}");
        }
    }

    #[test]
    fn the_anti_aliasing_choice_ends_every_chain() {
        let mut c = controls(SCENE);
        let chain = vec![PostEffect::TONEMAP, PostEffect::Fxaa, PostEffect::VIGNETTE];
        // Views of a camera not the scene's (the free one) keep their own
        // chains as the scene says; a view into a render target keeps it always.
        let other = Camera::orthographic(2.0, 0.1, 20.0);
        let into_target = View::new(other).with_post(chain.clone()).with_output(crate::scene::RenderTargetId(0));
        let base = vec![View::new(other).with_post(chain.clone()), View::new(other), into_target];
        assert_eq!(c.views(base.clone())[0].post, chain, "as the scene says");
        c.set("antialiasing", 5.0).unwrap();
        let views = c.views(base.clone());
        let high = PostEffect::Smaa { preset: SmaaPreset::High };
        assert_eq!(views[0].post, vec![PostEffect::TONEMAP, PostEffect::VIGNETTE, high], "FXAA gives way to SMAA");
        assert_eq!(views[1].post, vec![high], "a view without a chain gets one");
        assert_eq!(views[2].post, chain, "a render target's view keeps its chain");
        c.set("antialiasing", 1.0).unwrap();
        let views = c.views(base);
        assert_eq!((views[0].post.len(), views[1].post.len()), (2, 0), "none: neither");
        // A scene's own SMAA has a preset control.
        let mut own = controls("{ \"classname\" \"camera\"\n\"post\" \"tonemap smaa\" }\n");
        own.set("post.0.1.preset", 0.0).unwrap();
        let view = vec![View::new(own.scene_cameras[0]).with_post(vec![PostEffect::TONEMAP, PostEffect::SMAA])];
        assert_eq!(own.views(view)[0].post[1], PostEffect::Smaa { preset: SmaaPreset::Low });
        assert!(own.set("post.0.0.preset", 1.0).is_err(), "tonemap has no preset");
    }

    #[test]
    fn the_transparency_choice_is_offered_where_something_is_transparent() {
        let c = controls(SCENE);
        assert!(c.list().iter().all(|c| c.id != "transparency"), "nothing transparent, no control");
        let glass = "{ \"classname\" \"world\"\n\"transparency\" \"weighted\" }\n\
                     { \"classname\" \"material\"\n\"name\" \"glass\"\n\"alpha_mode\" \"blend\" }\n";
        let mut c = controls(glass);
        let choice = |c: &Controls| c.list().into_iter().find(|c| c.id == "transparency").map(|c| c.kind);
        let options: Vec<String> = Transparency::NAMES.iter().map(|n| (*n).to_owned()).collect();
        assert_eq!(choice(&c), Some(ControlKind::Choice { index: 1, options }), "as the world says");
        let view = vec![View::new(Camera::orthographic(2.0, 0.1, 20.0))];
        assert_eq!(c.views(view.clone())[0].transparency, Transparency::Weighted);
        c.set("transparency", 2.0).unwrap();
        assert_eq!(c.views(view.clone())[0].transparency, Transparency::Exact);
        c.set("transparency", 0.0).unwrap();
        assert_eq!(c.views(view)[0].transparency, Transparency::Sorted);
        // Where the adapter cannot keep lists, exact is not offered.
        let Some(gpu) = crate::gpu::test_gpu().and_then(|g| g.with_webgl2_limits().ok()) else { return };
        let mut c = controls(glass).for_adapter(&gpu);
        c.set("transparency", 2.0).unwrap();
        let options: Vec<String> = Transparency::NAMES[..2].iter().map(|n| (*n).to_owned()).collect();
        assert_eq!(choice(&c), Some(ControlKind::Choice { index: 1, options }), "weighted at most");
    }
}
