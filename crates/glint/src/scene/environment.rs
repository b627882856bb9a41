//! Beginner layer: a scene's [`Environment`]: the background (a colour or a
//! sky gradient), fog, ambient light and image-based lighting.

use glam::Vec3;

/// What is drawn where no geometry is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Background {
    /// One linear colour (the clear colour).
    Color(Vec3),
    /// A sky: `bottom` at and below the horizon blending to `top` straight up.
    Gradient {
        /// Colour looking straight up.
        top: Vec3,
        /// Colour at the horizon and below.
        bottom: Vec3,
    },
}

/// Exponential-squared distance fog: `visibility = exp(−(density · distance)²)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fog {
    /// Linear colour far things fade to.
    pub color: Vec3,
    /// Per world unit; 0.02 hides things about 100 units away.
    pub density: f32,
}

/// Where image-based light comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EnvironmentSource {
    /// The sky this environment's gradient and the first directional light
    /// describe, baked by glint ([`EnvironmentImage::sky`](crate::scene::EnvironmentImage::sky))
    /// and baked again when either changes (time of day).
    Sky,
    /// An image added with [`Registry::add_environment`](crate::render::Registry::add_environment).
    Image(super::EnvironmentId),
}

/// Image-based lighting: materials lit by an environment (prefiltered for
/// each roughness, its diffuse light as spherical harmonics), and the sky drawn
/// from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentLight {
    /// The environment.
    pub source: EnvironmentSource,
    /// Its radiance is multiplied by this.
    pub intensity: f32,
    /// Its turn about +Y, in radians (counter-clockwise seen from above).
    pub rotation: f32,
    /// How blurred the sky is drawn: 0 sharp, 1 the roughest prefiltered level.
    pub sky_blur: f32,
}

impl EnvironmentLight {
    /// `source` at intensity 1, unturned, its sky sharp.
    pub fn new(source: EnvironmentSource) -> Self {
        Self { source, intensity: 1.0, rotation: 0.0, sky_blur: 0.0 }
    }
}

/// Scene-wide lighting settings (the Scene block, `@group(0)`, with the lights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Environment {
    /// Background colour or sky gradient.
    pub background: Background,
    /// Ambient light colour, multiplied by each material's `ambient` (where
    /// there is no [`light`](Self::light)).
    pub ambient: Vec3,
    /// Image-based lighting, in place of the ambient colour; with it the sky
    /// is drawn from the environment.
    pub light: Option<EnvironmentLight>,
    /// Distance fog over materials that accept it.
    pub fog: Option<Fog>,
    /// The scene time in seconds, which moves materials with a
    /// [`Motion`](super::Motion) (the same time draws the same picture).
    pub time: f32,
    /// The wind [`Motion::Wind`](super::Motion::Wind) materials bend in.
    pub wind: super::Wind,
    /// Sun glare (0: none): an additive sphere around the view in the first
    /// directional light's direction and colour, drawn after everything else
    /// without a depth test, so the view brightens against the sun.
    pub glare: f32,
}

impl Default for Environment {
    fn default() -> Self {
        Self {
            background: Background::Color(Vec3::new(0.05, 0.05, 0.06)),
            ambient: Vec3::splat(0.1),
            light: None,
            fog: None,
            time: 0.0,
            wind: super::Wind::default(),
            glare: 0.0,
        }
    }
}
