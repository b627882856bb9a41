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

/// Scene-wide lighting settings (the Scene block, `@group(0)`, with the lights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Environment {
    /// Background colour or sky gradient.
    pub background: Background,
    /// Ambient light colour, multiplied by each material's `ambient`.
    pub ambient: Vec3,
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
            fog: None,
            time: 0.0,
            wind: super::Wind::default(),
            glare: 0.0,
        }
    }
}
