//! [`Lighting`], what lights a frame: its lights and its environment. Plain
//! data the frame's calls take by value, so a renderer holds no scene.

use super::{Environment, Light};

/// The lights of a frame and its environment (background, ambient light and
/// fog): together the Scene block (`@group(0)`). Every frame call that takes it
/// ([`Renderer::flush`](crate::Renderer::flush) and the others) also takes a
/// plain list of lights, which is that list under the default environment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting<'a> {
    /// The lights, at most [`MAX_LIGHTS`](super::MAX_LIGHTS).
    pub lights: &'a [Light],
    /// Background, ambient light and fog.
    pub environment: Environment,
}

impl<'a> Lighting<'a> {
    /// `lights` under `environment`.
    pub fn new(lights: &'a [Light], environment: Environment) -> Self {
        Self { lights, environment }
    }

    /// No lights, under the default environment.
    pub fn none() -> Self {
        Self::from(&[][..])
    }
}

impl<'a> From<&'a [Light]> for Lighting<'a> {
    fn from(lights: &'a [Light]) -> Self {
        Self::new(lights, Environment::default())
    }
}

impl<'a, const N: usize> From<&'a [Light; N]> for Lighting<'a> {
    fn from(lights: &'a [Light; N]) -> Self {
        Self::from(&lights[..])
    }
}

impl<'a> From<&'a Vec<Light>> for Lighting<'a> {
    fn from(lights: &'a Vec<Light>) -> Self {
        Self::from(lights.as_slice())
    }
}

impl<'a> From<&Lighting<'a>> for Lighting<'a> {
    fn from(lighting: &Lighting<'a>) -> Self {
        *lighting
    }
}
