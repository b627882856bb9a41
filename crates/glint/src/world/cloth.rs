//! Core layer: a scene's cloth as it runs. The `.scn` block ([`ClothDesc`]) is
//! what the file says, with the mesh at rest; a [`ClothSim`] is the simulation
//! stepping from that rest state, and its meshes at rest and now.

use crate::asset::ClothDesc;
use crate::sim::cloth::{Cloth, ClothView, Integrator};
use crate::Diagnostic;
use std::path::Path;

/// One cloth's running simulation: the solver and the steps it has taken, and
/// its meshes at rest and as of the last pose; none of them for a setup that
/// cannot be simulated (a description changed after loading:
/// [`SceneDesc::check_pose`](crate::asset::SceneDesc::check_pose) refuses to pose it).
pub(crate) struct ClothSim {
    run: Option<(Box<Cloth>, u64)>,
    rest: Option<ClothView>,
    pub(crate) view: Option<ClothView>,
}

impl ClothSim {
    /// `desc` started, at rest.
    pub(crate) fn new(desc: &ClothDesc) -> Self {
        let Ok(cloth) = Cloth::start(&desc.setup) else { return Self { run: None, rest: None, view: None } };
        let rest = ClothView::new(&cloth, desc.debug).ok();
        Self { run: rest.is_some().then(|| (Box::new(cloth), 0)), view: rest.clone(), rest }
    }

    /// Advance (or restart and advance) to `time` seconds and update the view;
    /// returns whether the view changed. A static cloth takes its one
    /// equilibrium step whatever the time. Refuses work past the posing budget
    /// before stepping ([`ClothDesc::check_pose`]); a step that fails is
    /// [`Error::Posing`](crate::Error::Posing), naming `scene`, the block's line
    /// and the time it stepped from.
    pub(crate) fn pose(&mut self, desc: &ClothDesc, time: f32, scene: &Path) -> Result<bool, crate::Error> {
        let target = desc.check_pose(time, 0, scene)?;
        let Some(rest) = &self.rest else { return Ok(false) };
        let (mut run, restarted) = match self.run.take() {
            Some(run) if run.1 <= target => (run, false),
            earlier => {
                if target == 0 && desc.integrator != Integrator::Static {
                    // The rest state: no solver is needed to show it.
                    self.view = Some(rest.clone());
                    return Ok(earlier.is_some());
                }
                let cloth =
                    Cloth::start(&desc.setup).map_err(|e| Diagnostic::at(scene, desc.line, format!("cloth: {e}")))?;
                ((Box::new(cloth), 0), true)
            }
        };
        let moved = restarted || run.1 < target;
        while run.1 < target {
            let from = run.0.time;
            let failed = |source| {
                let place = Diagnostic::at(scene, desc.line, format!("cloth, stepping from {from} s"));
                crate::Error::Posing { place, source }
            };
            run.0.step(desc.dt, desc.integrator).map_err(failed)?;
            run.1 += 1;
        }
        if let Some(view) = self.view.as_mut().filter(|_| moved) {
            view.update(&run.0);
        }
        self.run = Some(run);
        Ok(moved)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asset::{parse_scene, SceneDesc};

    fn parse(body: &str) -> SceneDesc {
        parse_scene(Path::new("dir/t.scn"), &format!("{{\n\"classname\" \"cloth\"\n{body}}}\n")).unwrap()
    }

    /// The bounds of `cloth`'s surface as last posed.
    fn surface(cloth: &ClothSim) -> crate::scene::Aabb {
        cloth.view.as_ref().expect("a cloth that can be simulated").surface.aabb()
    }

    #[test]
    fn posing_steps_to_the_time_and_restarts_when_it_goes_back() {
        let scene = parse("\"size\" \"1 1\"\n\"resolution\" \"4 4\"\n\"pins\" \"z<=-0.5\"\n\"dt\" \"0.05\"\n");
        let desc = &scene.cloths[0];
        let mut cloth = ClothSim::new(desc);
        let at = |cloth: &mut ClothSim, time: f32| cloth.pose(desc, time, Path::new("t.scn"));
        let rest = surface(&cloth);
        assert!(!at(&mut cloth, 0.0).unwrap(), "time 0 is the rest state it already has");
        assert!(at(&mut cloth, 0.5).unwrap());
        let swung = surface(&cloth);
        assert!(swung.min.y < rest.min.y - 0.2, "the free edge fell: {swung:?}");
        assert!(!at(&mut cloth, 0.52).unwrap(), "less than a step later: no new step");
        assert!(at(&mut cloth, 0.1).unwrap(), "earlier: restarted from rest");
        assert!(surface(&cloth).min.y > swung.min.y);
        assert!(at(&mut cloth, 0.0).unwrap(), "back to rest");
        assert_eq!(surface(&cloth), rest);
        let err = at(&mut cloth, 1e6).unwrap_err().to_string();
        assert!(err.starts_with("t.scn:1: cloth: time 1000000 s is 20000000 steps"), "{err}");
    }

    #[test]
    fn a_started_cloth_solves_as_its_block_says() {
        let scene = parse("\"size\" \"2 1\"\n\"resolution\" \"3 2\"\n\"solve\" \"realtime\"\n");
        let cloth = Cloth::start(&scene.cloths[0].setup).unwrap();
        assert_eq!(cloth.solve(), crate::sim::cloth::Solve::Realtime);
    }

    #[test]
    fn a_static_cloth_takes_its_equilibrium_step_at_any_time() {
        // A 0.1 m cantilever clamped by its back two rows of nodes (one row
        // alone would be a hinge, free to swing).
        let body = "\"size\" \"0.1 0.1\"\n\"resolution\" \"5 5\"\n\"pins\" \"z<=-0.02\"\n\"young\" \"1e9\"\n";
        let scene = parse(&format!("{body}\"integrator\" \"static\"\n"));
        let desc = &scene.cloths[0];
        let mut cloth = ClothSim::new(desc);
        assert!(cloth.pose(desc, 0.0, Path::new("t.scn")).unwrap());
        let hanging = surface(&cloth);
        assert!(hanging.min.y < -1e-4, "it sags at equilibrium: {hanging:?}");
        assert!(!cloth.pose(desc, 5.0, Path::new("t.scn")).unwrap(), "the same equilibrium later");
    }

    #[test]
    fn a_cloth_that_cannot_be_solved_names_its_scene_block_and_time() {
        // No pins and no floor: a static sheet under gravity has no equilibrium.
        let scene = parse("\"resolution\" \"3 3\"\n\"integrator\" \"static\"\n");
        let err = ClothSim::new(&scene.cloths[0]).pose(&scene.cloths[0], 0.0, Path::new("dir/t.scn")).unwrap_err();
        assert_eq!(err.exit_code(), 3);
        let text = err.to_string();
        assert!(text.starts_with("dir/t.scn:1: cloth, stepping from 0 s: "), "{text}");
    }
}
