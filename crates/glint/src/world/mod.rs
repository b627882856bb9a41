//! Core layer, above [`asset`](crate::asset) and [`render`](crate::render): a
//! [`World`] is a loaded scene placed in a renderer and run. It holds what the
//! file described ([`SceneDesc`]: cameras, lights, environment, materials,
//! models, cloth, school and emitter blocks), the entities that draw it, its running simulations
//! and the time it was last posed at. The `glint` CLI, the viewer and the web
//! page each hold one:
//!
//! ```no_run
//! use glint::{asset::load_scene, Gpu, OffscreenTarget, Renderer, World};
//!
//! let gpu = Gpu::headless()?;
//! let mut renderer = Renderer::new(&gpu);
//! let mut world = World::place(load_scene("scenes/showcase.scn".as_ref())?, &mut renderer)?;
//! let views = world.views(None);
//! let mut target = OffscreenTarget::new(&gpu, 640, 360, 4)?;
//! for frame in 0..3 {
//!     world.pose(frame as f32 / 30.0, &mut renderer)?;
//!     world.draw(&mut renderer, &views, &mut target)?;
//! }
//! # Ok::<(), glint::Error>(())
//! ```

mod clock;
mod cloth;
mod controls;
mod particles;
mod place;
mod player;
mod school;
mod sim_state;

use crate::asset::{MeshRef, SceneDesc};
use crate::scene::{Entity, LightKind, Lighting, SimPath, Transparency, View};
use crate::sim::cloth::ClothView;
use crate::sim::particles::ParticleKernels;
use crate::{AfterViews, FrameInput, FrameOutput, FrameStats, OffscreenTarget, RenderError, Renderer, SubFrame};
use cloth::ClothSim;
use particles::EmitterSim;
use school::SchoolSim;

pub use clock::{Played, SceneClock, MAX_FRAME_ADVANCE};
pub use controls::{Control, ControlKind, Controls};
pub use place::PlacedScene;
pub use player::{Moves, Player};
pub use sim_state::{SimKind, SimRecord, SimState, FORMAT as SIM_STATE_FORMAT};

/// A scene placed in a renderer, with its simulations and clock.
pub struct World {
    desc: SceneDesc,
    placed: PlacedScene,
    cloths: Vec<ClothSim>,
    schools: Vec<SchoolSim>,
    emitters: Vec<EmitterSim>,
    /// The time of the last frame drawn (−1 before the first), for the
    /// particles spawned since.
    drawn_at: f32,
    /// The placed entities of each entity block of `desc`.
    ranges: Vec<std::ops::Range<usize>>,
    time: f32,
    /// The time its simulations stand at: the last pose's, or the state's
    /// they resumed from; `None` at their start (or after a failed pose or
    /// frame, when they may start again).
    stepped_to: Option<f32>,
    /// Whether a material moves with time ([`Material::motion`](crate::Material::motion)),
    /// so the frames need the scene time.
    moves: bool,
    /// Each light's shadows while they are turned off ([`World::set_shadows`]).
    shadows_off: Option<Vec<Option<crate::scene::ShadowSettings>>>,
}

impl World {
    /// Add `desc`'s textures, render targets, materials, shapes and models to
    /// `renderer` ([`Renderer::place_scene`]), a particle layer for each
    /// emitter, and start its clock at 0: every cloth at rest, every school
    /// at its seeded start, no particle spawned. Errors when the device
    /// cannot hold the emitters' layers (out of memory).
    pub fn place(desc: SceneDesc, renderer: &mut Renderer) -> Result<Self, crate::RenderError> {
        let (mut placed, mut cloths, mut schools) = renderer.place_scene_and_runs(&desc);
        let ranges = school::entity_ranges(&desc);
        for (sim, school) in schools.iter_mut().zip(&desc.schools) {
            sim.move_to_gpu((school, &desc, &ranges), &mut placed.entities, renderer);
        }
        // Each cloth's entities follow the entity blocks', its surface first.
        let mut next = ranges.last().map_or(0, |r| r.end);
        for (sim, cloth) in cloths.iter_mut().zip(&desc.cloths) {
            let count = place::cloth_entity_count(sim.view.as_ref());
            if let Some(surface) = placed.entities[next..].first_mut().filter(|_| count > 0) {
                sim.move_to_gpu(cloth, surface, renderer);
            }
            next += count;
        }
        // The emitters stepped by compute shaders share one set of kernels.
        let kernels = (renderer.computes() && !desc.emitters.is_empty())
            .then(|| std::sync::Arc::new(ParticleKernels::new(renderer.device_and_queue().0)));
        let emitters = (desc.emitters.iter())
            .map(|e| EmitterSim::new(e, (&placed.textures, kernels.as_ref()), renderer))
            .collect::<Result<_, _>>()?;
        let models = desc.models.iter().flat_map(|m| &m.materials);
        let moves = desc.materials.iter().chain(models).any(|m| m.material.motion.is_some());
        Ok(Self {
            desc,
            placed,
            cloths,
            schools,
            emitters,
            drawn_at: -1.0,
            ranges,
            time: 0.0,
            stepped_to: None,
            moves,
            shadows_off: None,
        })
    }

    /// The scene as its file described it.
    pub fn desc(&self) -> &SceneDesc {
        &self.desc
    }

    /// The entities that draw it, as of the last pose; a school stepped on
    /// the GPU keeps its fish's entities at their start (its records are
    /// written on the GPU: [`Entity::with_gpu_instances`]), so only
    /// [`draw`](Self::draw) shows them where they swim.
    pub fn entities(&self) -> &[Entity] {
        &self.placed.entities
    }

    /// Its lights under its environment, for each frame: at the time of the
    /// last pose where a material moves with time (elsewhere the Scene block
    /// stays the same from frame to frame, and is not uploaded again).
    pub fn lighting(&self) -> Lighting<'_> {
        lighting_at(&self.desc, self.moves.then_some(self.time))
    }

    /// The meshes of cloth `index` (in file order) as of the last pose: its
    /// surface, and with the debug view its edge ribbons and pins; `None` for
    /// one that cannot run, or that steps on the GPU (drawn from its buffers,
    /// never read back).
    pub fn cloth_view(&self, index: usize) -> Option<&ClothView> {
        self.cloths.get(index).and_then(ClothSim::cpu_view)
    }

    /// The time of the last pose, in seconds (0 before the first).
    pub fn time(&self) -> f32 {
        self.time
    }

    /// The time its simulations stand at (the last pose's, or the state's
    /// they resumed from); `None` at their start, or after a failed pose or
    /// frame.
    pub fn simulated_to(&self) -> Option<f32> {
        self.stepped_to
    }

    /// The views a picture of it draws: camera `camera` alone over the whole
    /// image (after the cameras drawing render targets, which it may show), or
    /// else [`SceneDesc::views`]. A camera the scene lacks counts as none.
    pub fn views(&self, camera: Option<usize>) -> Vec<View> {
        let (desc, targets) = (&self.desc, &self.placed.render_targets);
        match camera.filter(|&k| k < desc.cameras.len()) {
            None => desc.views(targets),
            Some(k) => desc.target_views(targets).into_iter().chain([desc.camera_view(k)]).collect(),
        }
    }

    /// Pose every model at `time` seconds ([`Model::pose`](crate::asset::Model::pose)),
    /// advance every cloth and school to `time`, turn swaying lights, and move the matching entities
    /// along: only entities of animated models, moved cloths and schools change, so only they are
    /// uploaded again; morphed meshes and cloth surfaces replace their shapes in
    /// `renderer` (one vertex-buffer write each).
    ///
    /// Errors (exit code 3 in the CLI) when a cloth cannot reach `time`: more
    /// steps or work than the posing budget allows from where the simulations
    /// stand (the last pose, or their start for an earlier time:
    /// [`SceneDesc::check_pose_from`]; before any step), or a step
    /// that does not converge ([`Error::Posing`](crate::Error::Posing)).
    pub fn pose(&mut self, time: f32, renderer: &mut Renderer) -> Result<(), crate::Error> {
        let desc = &mut self.desc;
        desc.check_pose_from(self.stepped_to, time)?;
        // Set again once every simulation has stepped.
        let from = self.stepped_to.take();
        let entities = &mut self.placed.entities;
        let mut next = 0;
        let mut posed: Vec<Option<(bool, Vec<usize>)>> = vec![None; desc.models.len()];
        for e in &desc.entities {
            let MeshRef::Model(i) = e.mesh else {
                next += 1;
                continue;
            };
            let (moved, morphed) = posed[i].get_or_insert_with(|| {
                let model = &mut desc.models[i];
                (!model.animations.is_empty(), model.pose(time))
            });
            let model = &desc.models[i];
            for (k, (part, entity)) in model.parts.iter().zip(entities[next..].iter_mut()).enumerate() {
                if *moved {
                    *entity.transforms_mut() = part.placed(&e.transforms);
                    entity.joints_mut().clone_from(&part.joints);
                }
                if morphed.contains(&k) {
                    renderer.update_shape(entity.shape, part.mesh.clone());
                }
            }
            next += model.parts.len();
        }
        for (sim, cloth) in self.cloths.iter_mut().zip(&desc.cloths) {
            let count = place::cloth_entity_count(sim.view.as_ref());
            let on_gpu = match entities[next..].first_mut().filter(|_| count > 0) {
                Some(surface) => sim.pose_on_gpu(cloth, time, renderer.device_and_queue().1, surface),
                None => false,
            };
            if !on_gpu && sim.pose(cloth, time, &desc.path)? {
                let Some(view) = &sim.view else { continue };
                let meshes = std::iter::once(&view.surface).chain(&view.edges);
                for (entity, mesh) in entities[next..].iter().zip(meshes) {
                    renderer.update_shape(entity.shape, mesh.clone());
                }
                // Pins that did not move are not uploaded again.
                if count == 3 {
                    let (moved, pins) = (place::pin_transforms(view), &mut entities[next + 2]);
                    if pins.transforms() != moved {
                        *pins.transforms_mut() = moved;
                    }
                }
            }
            next += count;
        }
        for sway in &desc.light_sways {
            desc.lights[sway.light].kind = crate::scene::LightKind::Directional { direction: sway.direction_at(time) };
        }
        for circle in &desc.light_circles {
            use crate::scene::LightKind::{Point, Spot};
            if let Point { position, .. } | Spot { position, .. } = &mut desc.lights[circle.light].kind {
                *position = circle.position_at(time);
            }
        }
        for (sim, emitter) in self.emitters.iter_mut().zip(&desc.emitters) {
            sim.pose(emitter, time);
        }
        for (sim, school) in self.schools.iter_mut().zip(&desc.schools) {
            if sim.pose(school, time, renderer.device_and_queue().1) {
                sim.show(school, desc, &self.ranges, entities);
            }
        }
        self.time = time;
        // A simulation on the GPU steps when the next frame is drawn: until
        // then they all count as where they were (at their start, when this
        // pose went back), so poses without frames between add up.
        self.stepped_to = match self.steps_on_gpu() {
            false => Some(time),
            true => from.filter(|&f| f <= time),
        };
        Ok(())
    }

    /// Whether any of its simulations steps on the GPU.
    fn steps_on_gpu(&self) -> bool {
        let gpu = Some(SimPath::Gpu);
        self.cloths.iter().any(|c| c.path() == gpu)
            || self.schools.iter().any(|s| s.path() == gpu)
            || self.emitters.iter().any(|e| e.path() == gpu)
    }

    /// Move its sun, sky and glare to `hours` of the day
    /// ([`SceneDesc::set_time_of_day`]), from the next frame's
    /// [`lighting`](Self::lighting) on. A scene with no room for a sun
    /// keeps its lights, and the error says so (its sky still moves).
    pub fn set_time_of_day(&mut self, hours: f32) -> Result<(), crate::Diagnostic> {
        let before = self.desc.lights.len();
        let set = self.desc.set_time_of_day(hours);
        // A sun added goes first: the shadows kept while they are off move on with their lights.
        if let Some(saved) = self.shadows_off.as_mut().filter(|_| self.desc.lights.len() > before) {
            saved.insert(0, None);
        }
        set
    }

    /// Turn every light's shadows off (keeping their settings) or back on,
    /// from the next frame's [`lighting`](Self::lighting) on.
    pub fn set_shadows(&mut self, on: bool) {
        match (on, self.shadows_off.take()) {
            (false, None) => {
                self.shadows_off = Some(self.desc.lights.iter_mut().map(|l| l.shadows.take()).collect());
            }
            (true, Some(saved)) => self.desc.lights.iter_mut().zip(saved).for_each(|(l, s)| l.shadows = s),
            (_, kept) => self.shadows_off = kept,
        }
    }

    /// The first shadow-casting directional light's angular size in degrees
    /// (while shadows are off, the size it will have when they are back).
    pub fn sun_size(&self) -> Option<f32> {
        let saved = |k: usize| self.shadows_off.as_ref().and_then(|s| s.get(k).copied().flatten());
        (self.desc.lights.iter().enumerate())
            .filter(|(_, l)| matches!(l.kind, LightKind::Directional { .. }))
            .find_map(|(k, l)| l.shadows.or_else(|| saved(k)))
            .map(|s| s.light_size)
    }

    /// Give every shadow-casting directional light an angular size of
    /// `degrees` (soft shadows: [`ShadowSettings::light_size`](crate::scene::ShadowSettings::light_size);
    /// 0: hard), kept while shadows are off, from the next frame on.
    pub fn set_sun_size(&mut self, degrees: f32) {
        for (k, light) in self.desc.lights.iter_mut().enumerate() {
            if !matches!(light.kind, LightKind::Directional { .. }) {
                continue;
            }
            let saved = self.shadows_off.as_mut().and_then(|s| s.get_mut(k)).and_then(Option::as_mut);
            for settings in light.shadows.as_mut().into_iter().chain(saved) {
                settings.light_size = degrees;
            }
        }
    }

    /// Draw `views` of it into `target` (one [`Renderer::render_frame`], each
    /// view keyed by its place in `views`) and return each view's statistics,
    /// with the scene's particles alive and spawned since the last frame
    /// drawn. Its emitters' billboards go first: written from the CPU, or
    /// stepped to the time of the last pose by compute passes in the frame's
    /// simulate stage (its GPU emitters are the frame's simulations); alpha-blended ones sorted back to front
    /// from the last view's camera (the picture's own, after any views into
    /// render targets).
    pub fn draw(
        &mut self,
        renderer: &mut Renderer,
        views: &[View],
        target: &mut OffscreenTarget,
    ) -> Result<Vec<FrameStats>, RenderError> {
        Ok(self.draw_then(renderer, (views, target), Vec::new())?.views)
    }

    /// [`draw`](Self::draw) as an accumulated still of `samples` sub-frames
    /// ([`SubFrame`]: jittered cameras and ambient-occlusion noise, averaged
    /// in HDR before each view's post chain), all at the time of the last
    /// pose, its simulations stepped once; 1 (or 0) draws a frame of its own. Returns
    /// the last sub-frame's statistics, its particles counted since the last
    /// frame drawn before the still.
    pub fn draw_still(
        &mut self,
        renderer: &mut Renderer,
        (views, target): (&[View], &mut OffscreenTarget),
        samples: u32,
    ) -> Result<Vec<FrameStats>, RenderError> {
        Ok(self.draw_still_then(renderer, (views, target), Vec::new(), samples)?.views)
    }

    /// [`draw_still`](Self::draw_still), with `after` recorded into its last
    /// sub-frame after its views (an overlay, the blit onto a window), and
    /// that sub-frame's whole output.
    pub fn draw_still_then(
        &mut self,
        renderer: &mut Renderer,
        (views, target): (&[View], &mut OffscreenTarget),
        after: Vec<&mut dyn AfterViews>,
        samples: u32,
    ) -> Result<FrameOutput, RenderError> {
        let since = self.drawn_at;
        for index in 0..samples.saturating_sub(1) {
            self.drawn_at = since; // each sub-frame counts particles over the whole interval
            let sample = SubFrame { index, count: samples };
            self.draw_sample(renderer, (views, &mut *target), Vec::new(), sample)?;
        }
        self.drawn_at = since;
        let last = SubFrame { index: samples.max(1) - 1, count: samples.max(1) };
        self.draw_sample(renderer, (views, target), after, last)
    }

    /// [`draw`](Self::draw), with `after` recorded into the frame after its
    /// views (an overlay, the blit onto a window: [`FrameInput::then`]), and
    /// the whole frame's output.
    pub fn draw_then(
        &mut self,
        renderer: &mut Renderer,
        (views, target): (&[View], &mut OffscreenTarget),
        after: Vec<&mut dyn AfterViews>,
    ) -> Result<FrameOutput, RenderError> {
        self.draw_still_then(renderer, (views, target), after, 1)
    }

    /// [`draw_then`](Self::draw_then) as sub-frame `sample`.
    fn draw_sample(
        &mut self,
        renderer: &mut Renderer,
        (views, target): (&[View], &mut OffscreenTarget),
        after: Vec<&mut dyn AfterViews>,
        sample: SubFrame,
    ) -> Result<FrameOutput, RenderError> {
        // Alpha-blended particles are sorted from the picture's own camera,
        // unless it draws transparency in any order (weighted or exact).
        let picture = views.last().filter(|v| renderer.transparency_of(v, target.samples()) == Transparency::Sorted);
        let eye = picture.map(|v| v.camera.eye);
        let lighting = lighting_at(&self.desc, self.moves.then_some(self.time));
        let mut input = FrameInput::new(&self.placed.entities, lighting).views(views).sample(sample);
        let mut paths = crate::scene::SimulationPaths::default();
        for (sim, emitter) in self.emitters.iter_mut().zip(&self.desc.emitters) {
            paths.emitters.add(if sim.on_gpu() { SimPath::Gpu } else { SimPath::Cpu });
            if let Some(on_gpu) = sim.draw(emitter, self.time, eye, renderer) {
                input = input.simulate(on_gpu);
            }
        }
        for sim in &mut self.schools {
            sim.path().into_iter().for_each(|path| paths.schools.add(path));
            if let Some(on_gpu) = sim.simulation() {
                input = input.simulate(on_gpu);
            }
        }
        for sim in &mut self.cloths {
            sim.path().into_iter().for_each(|path| paths.cloths.add(path));
            if let Some(on_gpu) = sim.simulation() {
                input = input.simulate(on_gpu);
            }
        }
        // Borrowed for this frame only, so the simulations can be told if it fails.
        input.after = after.into_iter().map(|work| -> &mut dyn AfterViews { work }).collect();
        let output = renderer.render_frame(input, target);
        if output.is_err() {
            // The frame's commands, GPU steps among them, were dropped.
            self.schools.iter_mut().for_each(SchoolSim::frame_failed);
            self.cloths.iter_mut().for_each(ClothSim::frame_failed);
            self.emitters.iter_mut().for_each(EmitterSim::frame_failed);
            self.stepped_to = None;
        }
        let mut output = output?;
        if self.steps_on_gpu() {
            // The frame took every step posed.
            self.stepped_to = Some(self.time);
        }
        output.views.iter_mut().for_each(|v| v.simulations = paths);
        particles::count(&self.desc.emitters, (self.drawn_at, self.time), &mut output.views);
        self.drawn_at = self.time;
        Ok(output)
    }

    /// Its simulations in the order of [`sim_state`](Self::sim_state)'s
    /// records (cloths, schools, emitters, each in file order), each with
    /// where it steps (`None`: it cannot run).
    pub fn simulations(&self) -> Vec<(SimKind, Option<SimPath>)> {
        (self.cloths.iter().map(|c| (SimKind::Cloth, c.path())))
            .chain(self.schools.iter().map(|s| (SimKind::School, s.path())))
            .chain(self.emitters.iter().map(|e| (SimKind::Emitter, e.path())))
            .collect()
    }

    /// Every simulation's state as of the last frame drawn (its cloths, then
    /// its schools, then its emitters), read back from the GPU where they step
    /// there: what [`resume`](Self::resume) goes on from. Errors for one that
    /// cannot run, or that was posed since the last frame (its GPU steps
    /// still pending).
    pub fn sim_state(&self, renderer: &Renderer) -> Result<SimState, crate::GpuError> {
        let Some(time) = self.stepped_to else {
            let why =
                "its simulations were not posed and drawn since they were placed (or since a failed pose or frame)";
            return Err(crate::GpuError::Failed(format!("no state to save: {why}")));
        };
        let gpu = renderer.device_and_queue();
        let missing = |kind: &str, k: usize| {
            let why = "it cannot run, or was posed after the last frame drawn (its GPU steps pending)";
            crate::GpuError::Failed(format!("{kind} {} has no state to save: {why}", k + 1))
        };
        let mut records = Vec::new();
        for (k, sim) in self.cloths.iter().enumerate() {
            records.push(sim.save(gpu)?.ok_or_else(|| missing("cloth", k))?);
        }
        for (k, sim) in self.schools.iter().enumerate() {
            records.push(sim.save(gpu)?.ok_or_else(|| missing("school", k))?);
        }
        for (k, sim) in self.emitters.iter().enumerate() {
            records.push(sim.save(gpu)?.ok_or_else(|| missing("emitter", k))?);
        }
        Ok(SimState { time, records })
    }

    /// Go on from `state` ([`sim_state`](Self::sim_state) of the same scene,
    /// on the same paths): each simulation steps on from its record at the
    /// next pose (or starts again from time 0 for an earlier time), exactly
    /// as it would have from time 0. Errors, saying which simulation and
    /// why, where the records are not this world's: other kinds or counts,
    /// another path (CPU or GPU), steps that do not reach the time it was
    /// saved at (then nothing is resumed), or records of another size (then
    /// those before it were resumed: place the world again before drawing
    /// it). After an error the posing limits count from the simulations' start.
    pub fn resume(&mut self, state: &SimState, renderer: &Renderer) -> Result<(), String> {
        let queue = renderer.device_and_queue().1;
        // Until every record is in, the simulations stand nowhere known.
        self.stepped_to = None;
        let ours = self.simulations();
        let theirs: Vec<SimKind> = state.records.iter().map(|r| r.kind).collect();
        let kinds: Vec<SimKind> = ours.iter().map(|o| o.0).collect();
        if theirs != kinds {
            return Err(format!(
                "it holds {}, where the scene has {}",
                SimKind::listed(&theirs),
                SimKind::listed(&kinds)
            ));
        }
        for (k, (record, (kind, path))) in state.records.iter().zip(&ours).enumerate() {
            let nth = ours[..k].iter().filter(|o| o.0 == *kind).count() + 1;
            if *path != Some(record.path) {
                let on = |p: Option<SimPath>| match p {
                    Some(SimPath::Gpu) => "on the GPU",
                    Some(SimPath::Cpu) => "on the CPU",
                    None => "nowhere (it cannot run)",
                };
                return Err(format!(
                    "{} {nth} stepped {} when it was saved, but steps {} here",
                    kind.name(),
                    on(Some(record.path)),
                    on(*path)
                ));
            }
        }
        // Each record took the steps that reach the time it was saved at:
        // the posing limits count on from there.
        let t = state.time;
        let desc = &self.desc;
        let steps = (desc.cloths.iter().map(|c| c.steps_to(t)))
            .chain(desc.schools.iter().map(|s| s.steps_to(t)))
            .chain(desc.emitters.iter().map(|e| e.steps_to(t)));
        for (k, (record, want)) in state.records.iter().zip(steps).enumerate() {
            if record.steps != want {
                let nth = ours[..k].iter().filter(|o| o.0 == record.kind).count() + 1;
                let saved = record.steps;
                return Err(format!(
                    "{} {nth}: {saved} steps saved at {t} s, where {want} reach that time",
                    record.kind.name()
                ));
            }
        }
        let mut records = state.records.iter();
        let mut go_on = |k: usize, kind: SimKind, load: &mut dyn FnMut(&SimRecord) -> Result<(), String>| {
            let record = records.next().expect("the kinds match");
            load(record).map_err(|e| format!("{} {}: {e}", kind.name(), k + 1))
        };
        for (k, (sim, desc)) in self.cloths.iter_mut().zip(&self.desc.cloths).enumerate() {
            go_on(k, SimKind::Cloth, &mut |r| sim.load(desc, r, queue))?;
        }
        for (k, sim) in self.schools.iter_mut().enumerate() {
            go_on(k, SimKind::School, &mut |r| sim.load(r, queue))?;
        }
        for (k, sim) in self.emitters.iter_mut().enumerate() {
            go_on(k, SimKind::Emitter, &mut |r| sim.load(r, queue))?;
        }
        self.stepped_to = Some(state.time);
        Ok(())
    }

    /// Whether its emitters step with compute shaders (else on the CPU).
    pub fn particles_on_gpu(&self) -> bool {
        self.emitters.iter().any(EmitterSim::on_gpu)
    }

    /// Where each of its cloths steps, in file order (`None`: one that
    /// cannot run): on the GPU, drawn in place, where its `"solve"` asks
    /// `gpu` and the renderer computes.
    pub fn cloth_paths(&self) -> Vec<Option<SimPath>> {
        self.cloths.iter().map(ClothSim::path).collect()
    }

    /// Where each of its schools steps, in file order (`None`: one that
    /// cannot run): on the GPU, drawn in place, where its `"sim"` asks and
    /// the renderer computes.
    pub fn school_paths(&self) -> Vec<Option<SimPath>> {
        self.schools.iter().map(SchoolSim::path).collect()
    }
}

/// `desc`'s lights under its environment, at scene time `time` where a
/// material moves with it.
fn lighting_at(desc: &SceneDesc, time: Option<f32>) -> Lighting<'_> {
    let mut lighting = desc.lighting();
    if let Some(time) = time {
        lighting.environment.time = time;
    }
    lighting
}
