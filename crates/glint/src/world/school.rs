//! Core layer: a scene's fish school as it runs. The `.scn` block
//! ([`SchoolDesc`]) is what the file says; a [`SchoolSim`] is the school
//! stepped from its seeded start to the time of the last pose, on the CPU
//! (the same time always gives the same school), and the entities it moves.

use crate::asset::{MeshRef, SceneDesc, SchoolDesc};
use crate::sim::school::School;
use crate::Entity;
use std::ops::Range;

/// One school's run, from its start; none for parameters that cannot make a
/// school (a description changed after loading: [`SceneDesc::check_pose`]
/// refuses to pose it).
pub(crate) struct SchoolSim {
    school: Option<School>,
}

impl SchoolSim {
    /// At its start.
    pub(crate) fn new(desc: &SchoolDesc) -> Self {
        Self { school: School::new(desc.params.clone()).ok() }
    }

    /// Advance (or restart and advance) to `time`; returns whether it moved.
    /// The posing budget and parameters were checked before ([`SceneDesc::check_pose`]).
    pub(crate) fn pose(&mut self, desc: &SchoolDesc, time: f32) -> bool {
        let target = desc.steps_to(time);
        let restarted = self.school.as_ref().is_some_and(|s| s.steps() > target);
        if restarted {
            *self = Self::new(desc);
        }
        let Some(school) = &mut self.school else { return false };
        let moved = restarted || school.steps() < target;
        while school.steps() < target {
            school.step(desc.dt);
        }
        moved
    }

    /// Put its fish and predator into their entities: `ranges` are the placed
    /// entities of each of `scene`'s entity blocks (a model's parts each have one).
    pub(crate) fn show(&self, desc: &SchoolDesc, scene: &SceneDesc, ranges: &[Range<usize>], entities: &mut [Entity]) {
        let Some(school) = &self.school else { return };
        let fish: Vec<_> = school.fish().iter().enumerate().map(|(i, f)| f.transform(desc.fish_scale(i))).collect();
        let phases: Vec<f32> = school.fish().iter().map(|f| f.phase).collect();
        place(scene, desc.fish_entity, &fish, &phases, &ranges[desc.fish_entity], entities);
        if let (Some(k), Some(h)) = (desc.predator_entity, school.predator()) {
            place(scene, k, &[h.transform(desc.predator_size)], &[h.phase], &ranges[k], entities);
        }
    }
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
