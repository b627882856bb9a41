//! Core layer: a scene's fish school as it runs. The `.scn` block
//! ([`SchoolDesc`]) is what the file says; a [`SchoolSim`] is the school
//! stepped from its seeded start to the time of the last pose (the same time
//! always gives the same school), and the entities it moves: on the CPU,
//! their transforms set after each pose; on the GPU (`"sim" "gpu"` where the
//! renderer computes), stepped in the frame's simulate stage and written
//! into their instance records there ([`GpuSchool::draw_in_place`]), the
//! entities' transforms left at the start.

use super::sim_state::{chunks, value_bytes, values, SimKind, SimRecord};
use crate::asset::{MeshRef, SceneDesc, SchoolDesc};
use crate::render::cull::transform_aabb;
use crate::render::GpuSimulation;
use crate::scene::{Aabb, SimPath};
use crate::sim::school::{GpuSchool, School, SchoolDrawing, Swimmer, Swimmers, MAX_PART_TRANSFORMS};
use crate::{Entity, Renderer};
use glam::{Mat4, Vec3};
use std::ops::Range;

/// Where a school steps.
enum Run {
    Cpu(Box<School>),
    /// On the GPU, with the steps recorded so far (taken or pending).
    Gpu(Box<GpuSchool>, u64),
}

/// One school's run, from its start; none for parameters that cannot make a
/// school (a description changed after loading: [`SceneDesc::check_pose`]
/// refuses to pose it).
pub(crate) struct SchoolSim {
    run: Option<Run>,
    /// Resumed from a simulation cache since the last pose, so the next
    /// one shows it even where it takes no step.
    resumed: bool,
}

impl SchoolSim {
    /// At its start, on the CPU.
    pub(crate) fn new(desc: &SchoolDesc) -> Self {
        Self { run: School::new(desc.params.clone()).ok().map(|s| Run::Cpu(Box::new(s))), resumed: false }
    }

    /// Move it onto the GPU, drawn in place, where `desc` asks and `renderer`
    /// computes: its entities (`ranges`, as [`entity_ranges`] gives them, of
    /// `scene`'s entity blocks) get their records from the simulation. It
    /// stays on the CPU where a model part repeats its mesh more than
    /// [`MAX_PART_TRANSFORMS`] times, a model is skinned or animated (posed
    /// on the CPU every frame), or the GPU cannot make its buffers.
    pub(crate) fn move_to_gpu(
        &mut self,
        (desc, scene, ranges): (&SchoolDesc, &SceneDesc, &[Range<usize>]),
        entities: &mut [Entity],
        renderer: &Renderer,
    ) {
        let Some(Run::Cpu(school)) = &self.run else { return };
        if desc.sim != SimPath::Gpu || !renderer.computes() {
            return;
        }
        let mut drawings = drawings_of(scene, desc.fish_entity, Swimmers::Fish { size: desc.size }, ranges, entities);
        if let Some(k) = desc.predator_entity {
            drawings.extend(drawings_of(scene, k, Swimmers::Predator { size: desc.predator_size }, ranges, entities));
        }
        if drawings.iter().any(|(_, d)| d.parts.len() > MAX_PART_TRANSFORMS) {
            log::warn!(
                "school (line {}): a model part drawn more than {MAX_PART_TRANSFORMS} times a fish steps on the CPU",
                desc.line
            );
            return;
        }
        // Skinned or animated models pose their entities on the CPU every frame.
        let blocks = [Some(desc.fish_entity), desc.predator_entity];
        let animated = blocks.into_iter().flatten().any(|k| match scene.entities[k].mesh {
            MeshRef::Model(m) => !scene.models[m].animations.is_empty(),
            MeshRef::Shape(_) => false,
        });
        if animated || drawings.iter().any(|(k, _)| !entities[*k].joints().is_empty()) {
            log::warn!("school (line {}): a skinned or animated model steps on the CPU", desc.line);
            return;
        }
        let on_gpu = GpuSchool::on_device(renderer.device_and_queue(), school).and_then(|mut gpu| {
            let list = drawings.iter().map(|(_, d)| d.clone()).collect();
            gpu.draw_in_place(renderer.device_and_queue().0, list).map(|()| gpu)
        });
        let gpu = match on_gpu {
            Ok(gpu) => gpu,
            Err(e) => return log::warn!("school (line {}): stepped on the CPU: {e}", desc.line),
        };
        // Where the swimmers start: inside the bounds once they step, but a
        // cluster's ball or the predator's start may reach outside them.
        let start = school.fish().iter().chain(school.predator()).map(|f| f.position);
        let bounds = desc.params.bounds;
        let start = Aabb::from_points(start)
            .map_or(bounds, |b| Aabb { min: b.min.min(bounds.min), max: b.max.max(bounds.max) });
        for (k, drawing) in &drawings {
            let entity = &mut entities[*k];
            let reach = renderer.registry().reach(entity.shape, entity.material).map(|r| (r.local, r.walk));
            let held = held_box((desc, start), drawing, reach);
            entity.set_gpu_instances(Some(held));
        }
        self.run = Some(Run::Gpu(Box::new(gpu), 0));
    }

    /// Advance (or restart and advance) to `time`: on the CPU now, on the
    /// GPU in the next frame's simulate stage ([`simulation`](Self::simulation)).
    /// Returns whether its CPU fish moved (their entities need [`show`](Self::show)).
    /// The posing budget and parameters were checked before ([`SceneDesc::check_pose`]).
    pub(crate) fn pose(&mut self, desc: &SchoolDesc, time: f32, queue: &wgpu::Queue) -> bool {
        let target = desc.steps_to(time);
        match &mut self.run {
            None => false,
            Some(Run::Cpu(school)) => {
                let restarted = school.steps() > target;
                if restarted {
                    // The parameters made a school once: they make it again.
                    if let Ok(start) = School::new(desc.params.clone()) {
                        **school = start;
                    }
                }
                let moved = restarted || school.steps() < target || std::mem::take(&mut self.resumed);
                while school.steps() < target {
                    school.step(desc.dt);
                }
                moved
            }
            Some(Run::Gpu(gpu, steps)) => {
                if *steps > target {
                    // The parameters made a school once: they make it again.
                    if let Ok(start) = School::new(desc.params.clone()) {
                        gpu.restart(queue, &start);
                        *steps = 0;
                    }
                }
                let more = target.saturating_sub(*steps);
                gpu.advance(queue, u32::try_from(more).unwrap_or(u32::MAX), desc.dt);
                *steps += more;
                false
            }
        }
    }

    /// Its state for a simulation cache ([`World::sim_state`](super::World::sim_state)),
    /// `None` when it cannot run or has GPU steps pending.
    pub(crate) fn save(&self, gpu: (&wgpu::Device, &wgpu::Queue)) -> Result<Option<SimRecord>, crate::GpuError> {
        let record = |path, steps, chunks| SimRecord { kind: SimKind::School, path, steps, chunks };
        Ok(match &self.run {
            None => None,
            Some(Run::Gpu(school, steps)) => school.save(gpu)?.map(|chunks| record(SimPath::Gpu, *steps, chunks)),
            Some(Run::Cpu(school)) => {
                let fish = value_bytes(school.fish().iter().map(swimmer_values));
                let predator = value_bytes(school.predator().into_iter().map(swimmer_values));
                Some(record(SimPath::Cpu, school.steps(), vec![fish, predator]))
            }
        })
    }

    /// Go on from `record` ([`save`](Self::save)d from the same school on
    /// the same path): the next pose steps on from it.
    pub(crate) fn load(&mut self, record: &SimRecord, queue: &wgpu::Queue) -> Result<(), String> {
        let [fish, predator] = chunks::<2>(record)?;
        match &mut self.run {
            None => return Err("the school cannot run".into()),
            Some(Run::Gpu(school, steps)) => {
                school.load(queue, fish, predator)?;
                *steps = record.steps;
            }
            Some(Run::Cpu(school)) => {
                let swimmers = |bytes| -> Result<Vec<Swimmer>, String> {
                    let swimmer = |[x, y, z, vx, vy, vz, phase]: [f32; 7]| Swimmer {
                        position: Vec3::new(x, y, z),
                        velocity: Vec3::new(vx, vy, vz),
                        phase,
                    };
                    Ok(values::<[f32; 7]>(bytes)?.into_iter().map(swimmer).collect())
                };
                let predator = match swimmers(predator)?.as_slice() {
                    [] => None,
                    [one] => Some(*one),
                    more => return Err(format!("{} predators, expected at most 1", more.len())),
                };
                school.resume(swimmers(fish)?, predator, record.steps)?;
            }
        }
        self.resumed = true;
        Ok(())
    }

    /// A frame that recorded its GPU steps failed and dropped them: start
    /// again from the seed at the next pose.
    pub(crate) fn frame_failed(&mut self) {
        if let Some(Run::Gpu(_, steps)) = &mut self.run {
            *steps = u64::MAX;
        }
    }

    /// Where it steps; `None` when it cannot run.
    pub(crate) fn path(&self) -> Option<SimPath> {
        self.run.as_ref().map(|run| match run {
            Run::Cpu(_) => SimPath::Cpu,
            Run::Gpu(..) => SimPath::Gpu,
        })
    }

    /// Its steps and placing for the frame's simulate stage, on the GPU.
    pub(crate) fn simulation(&mut self) -> Option<&mut dyn GpuSimulation> {
        match &mut self.run {
            Some(Run::Gpu(gpu, _)) => Some(gpu.as_mut()),
            _ => None,
        }
    }

    /// Put its CPU fish and predator into their entities: `ranges` are the placed
    /// entities of each of `scene`'s entity blocks (a model's parts each have one).
    pub(crate) fn show(&self, desc: &SchoolDesc, scene: &SceneDesc, ranges: &[Range<usize>], entities: &mut [Entity]) {
        let Some(Run::Cpu(school)) = &self.run else { return };
        let fish: Vec<_> = school.fish().iter().enumerate().map(|(i, f)| f.transform(desc.fish_scale(i))).collect();
        let phases: Vec<f32> = school.fish().iter().map(|f| f.phase).collect();
        place(scene, desc.fish_entity, &fish, &phases, &ranges[desc.fish_entity], entities);
        if let (Some(k), Some(h)) = (desc.predator_entity, school.predator()) {
            place(scene, k, &[h.transform(desc.predator_size)], &[h.phase], &ranges[k], entities);
        }
    }
}

/// A swimmer's state as a simulation cache keeps it: position, velocity, phase.
fn swimmer_values(f: &Swimmer) -> [f32; 7] {
    let ([x, y, z], [vx, vy, vz]) = (f.position.to_array(), f.velocity.to_array());
    [x, y, z, vx, vy, vz, f.phase]
}

/// How entity block `k`'s placed entities draw `swimmers` in place: each
/// entity's index in `entities` and its drawing (a shape: one instance a
/// swimmer; a model: each part's own transforms).
fn drawings_of(
    scene: &SceneDesc,
    k: usize,
    swimmers: Swimmers,
    ranges: &[Range<usize>],
    entities: &[Entity],
) -> Vec<(usize, SchoolDrawing)> {
    let parts: Vec<Vec<Mat4>> = match scene.entities[k].mesh {
        MeshRef::Shape(_) => vec![vec![Mat4::IDENTITY]],
        MeshRef::Model(m) => scene.models[m].parts.iter().map(|p| p.transforms.clone()).collect(),
    };
    ranges[k]
        .clone()
        .zip(parts)
        .map(|(i, parts)| (i, SchoolDrawing { entity: entities[i].key(), swimmers, parts }))
        .collect()
}

/// A world box holding every instance `drawing` puts anywhere in `desc`'s
/// bounds or the box `start` (the bounds and where the swimmers start), at
/// any heading: grown by the farthest any point of the entity's shape
/// (`reach`: its box grown by its material's motion) gets from the swimmer's
/// position at the largest scale.
fn held_box((desc, start): (&SchoolDesc, Aabb), drawing: &SchoolDrawing, reach: Option<(Aabb, f32)>) -> Aabb {
    let scale = match drawing.swimmers {
        Swimmers::Fish { .. } => desc.largest_fish_scale(),
        Swimmers::Predator { size } => size,
    };
    let (local, walk) = reach.unwrap_or((Aabb { min: Vec3::splat(-1.0), max: Vec3::ONE }, 0.0));
    // The farthest corner of each part's box from the swimmer's position.
    let (c, e) = (local.center().into(), local.half_extent().into());
    let part_reach = |t: &Mat4| {
        let (c, e) = transform_aabb(t, c, e);
        (c.abs() + e).length()
    };
    let farthest = drawing.parts.iter().map(part_reach).fold(0.0, f32::max);
    let grow = Vec3::splat(farthest * scale + walk);
    // Confinement ends above the floor, even a floor above the bounds.
    let (lo, mut hi) = (start.min, start.max);
    hi.y = hi.y.max(desc.params.floor.unwrap_or(hi.y));
    Aabb { min: lo - grow, max: hi + grow }
}

/// Entity block `k`'s placed entities at `transforms` and tail `phases`.
fn place(
    scene: &SceneDesc,
    k: usize,
    transforms: &[glam::Mat4],
    phases: &[f32],
    range: &Range<usize>,
    entities: &mut [Entity],
) {
    match scene.entities[k].mesh {
        MeshRef::Shape(_) => {
            let entity = &mut entities[range.start];
            entity.transforms_mut().clone_from_slice(transforms);
            entity.phases_mut().clone_from(&phases.to_vec());
        }
        MeshRef::Model(m) => {
            for (part, entity) in scene.models[m].parts.iter().zip(&mut entities[range.clone()]) {
                *entity.transforms_mut() = part.placed(transforms);
                let each = part.transforms.len();
                *entity.phases_mut() = phases.iter().flat_map(|&p| std::iter::repeat_n(p, each)).collect();
            }
        }
    }
}

/// The placed entities of each of `scene`'s entity blocks, in order (as
/// [`Renderer::place_scene`](crate::Renderer::place_scene) makes them).
pub(crate) fn entity_ranges(scene: &SceneDesc) -> Vec<Range<usize>> {
    let mut next = 0;
    scene
        .entities
        .iter()
        .map(|e| {
            let count = match e.mesh {
                MeshRef::Shape(_) => 1,
                MeshRef::Model(m) => scene.models[m].parts.len(),
            };
            next += count;
            next - count..next
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::Run;
    use crate::render::cull::transform_aabb;
    use crate::render::resources::blocks::InstanceGpu;
    use crate::{OffscreenTarget, Renderer, World};
    use glam::{Mat4, Vec3A, Vec4};

    #[test]
    fn the_gpu_places_each_fish_as_the_cpu_would_place_the_gpus_fish() {
        // Half a second in, the fish the GPU stepped (read back) placed as the
        // CPU places fish (each one's frame, size, material, shadows flag and
        // tail phase) are the records the placing pass wrote over the start,
        // and each fish's box is the store's box of that record.
        let Some(gpu) = crate::gpu::test_gpu() else { return };
        if !gpu.culls_on_gpu() {
            return;
        }
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repo");
        let options = crate::asset::LoadOptions { asset_roots: vec![root.clone()], ..Default::default() };
        let desc = crate::asset::load_scene_with(&root.join("tests/scenes/school.scn"), options).expect("scene");
        let mut renderer = Renderer::new(&gpu);
        let mut world = World::place(desc, &mut renderer).expect("placed");
        world.pose(0.5, &mut renderer).expect("posed");
        let mut target = OffscreenTarget::new(&gpu, 16, 16, 1).expect("target");
        let frame = world.draw(&mut renderer, &world.views(None), &mut target).expect("frame")[0].frame;
        let Some(Run::Gpu(on_gpu, 30)) = &world.schools[0].run else { panic!("30 steps on the GPU") };
        let school = on_gpu.read(&gpu).expect("the school");
        let desc = &world.desc.schools[0];
        let swimmers: Vec<Mat4> = (school.fish().iter().enumerate().map(|(i, f)| f.transform(desc.fish_scale(i))))
            .chain(school.predator().map(|h| h.transform(desc.predator_size)))
            .collect();
        let phases: Vec<f32> = school.fish().iter().chain(school.predator()).map(|f| f.phase).collect();
        let store = &renderer.res.store;
        let records = gpu.read_buffer(renderer.res.instances.array().buffer().expect("a buffer")).expect("records");
        let boxes = gpu.read_buffer(renderer.res.instances.bounds().expect("boxes")).expect("boxes");
        let (records, boxes): (&[[u32; 16]], &[[f32; 8]]) =
            (bytemuck::cast_slice(&records), bytemuck::cast_slice(&boxes));
        // The fish's entity, then the shark's: swimmer by swimmer, by each model's one part.
        let mut swimmer = 0;
        for block in [desc.fish_entity, desc.predator_entity.expect("a shark")] {
            let entity = &world.entities()[world.ranges[block].start];
            let crate::asset::MeshRef::Model(m) = world.desc.entities[block].mesh else { panic!("a model") };
            let [part] = world.desc.models[m].parts[0].transforms[..] else { panic!("one transform") };
            let range = store.gpu_range(entity.key(), frame).expect("written on the GPU");
            let (c, e) = (Vec3A::from(range.local.center()), Vec3A::from(range.local.half_extent()));
            for k in range.first as usize..(range.first + range.count) as usize {
                let placed = swimmers[swimmer] * part;
                let expected =
                    InstanceGpu::new(&placed, entity.material, entity.receive_shadows).with_phase(phases[swimmer]);
                let (cpu, on_gpu): ([u32; 16], [u32; 16]) = (bytemuck::cast(expected), records[k]);
                for i in 0..12 {
                    let (a, b) = (f32::from_bits(cpu[i]), f32::from_bits(on_gpu[i]));
                    assert!((a - b).abs() <= 1e-5 * a.abs().max(1.0), "record {k} value {i}: CPU {a}, GPU {b}");
                }
                assert_eq!(cpu[12..15], on_gpu[12..15], "material and joints");
                assert_eq!(cpu[15] & 0xffff, on_gpu[15] & 0xffff, "the shadows flag");
                assert!((cpu[15] >> 16).abs_diff(on_gpu[15] >> 16) <= 1, "the tail phase");
                let row = |i: usize| Vec4::from_array(std::array::from_fn(|j| f32::from_bits(on_gpu[4 * i + j])));
                let m = Mat4::from_cols(row(0), row(1), row(2), Vec4::W).transpose();
                let (center, extent) = transform_aabb(&m, c, e);
                let got = (Vec3A::from_slice(&boxes[k][..3]), Vec3A::from_slice(&boxes[k][4..7]));
                assert!((got.0 - center).abs().max_element() < 1e-4, "box {k}: {got:?} against {center}");
                assert!((got.1 - extent).abs().max_element() < 1e-4, "box {k}: {got:?} against {extent}");
                swimmer += 1;
            }
        }
        assert_eq!(swimmer, 401, "400 fish and the shark");
    }
}
