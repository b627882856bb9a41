//! [`PostEffect`]: the passes of a view's post-processing chain, as plain data.
//! A view with effects is drawn into a floating-point (HDR) target and each
//! effect runs in order on a full-screen triangle; the last writes the view's
//! rectangle of the output (see `render/passes/post.rs`).

use glam::Vec3;

/// Most effects one view's chain may hold.
pub const MAX_POST_EFFECTS: usize = 8;

/// How tonemapping maps linear HDR light to the displayable 0..1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tonemap {
    /// Clamped at 1.
    None,
    /// `c / (1 + c)`.
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve.
    Aces,
    /// AgX (Sobotka), in Wrensch's minimal form.
    Agx,
}

/// How hard SMAA looks for edges and how far it follows them: the presets of
/// its shader (Jimenez et al.), from cheapest to sharpest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SmaaPreset {
    /// Luma threshold 0.15, 4 search steps, no diagonals or corners.
    Low,
    /// Threshold 0.1, 8 steps, no diagonals or corners.
    Medium,
    /// Threshold 0.1, 16 steps, diagonals (8 steps) and corner rounding.
    High,
    /// Threshold 0.05, 32 steps, diagonals (16 steps) and corner rounding.
    Ultra,
}

impl SmaaPreset {
    /// The presets, in the order of [`SmaaPreset::NAMES`].
    pub const ALL: [Self; 4] = [Self::Low, Self::Medium, Self::High, Self::Ultra];
    /// Their names in `.scn` files and controls.
    pub const NAMES: [&'static str; 4] = ["low", "medium", "high", "ultra"];

    /// The shader's settings: the luma difference that makes an edge, the
    /// most search steps along a line (two pixels each) and along a
    /// diagonal (0: none), and the share of a corner's blending kept (1: no
    /// corner detection).
    pub fn settings(self) -> [f32; 4] {
        match self {
            Self::Low => [0.15, 4.0, 0.0, 1.0],
            Self::Medium => [0.1, 8.0, 0.0, 1.0],
            Self::High => [0.1, 16.0, 8.0, 0.25],
            Self::Ultra => [0.05, 32.0, 16.0, 0.25],
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// One pass of a post chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PostEffect {
    /// Light above `threshold` (luminance) blurred and added back, times `intensity`.
    Bloom {
        /// Luminance where bloom starts.
        threshold: f32,
        /// How much of the blurred light is added.
        intensity: f32,
    },
    /// Exposure then a tonemapping operator.
    Tonemap {
        /// The operator.
        operator: Tonemap,
        /// Exposure in EV: light is scaled by 2^exposure first.
        exposure: f32,
    },
    /// Fast approximate anti-aliasing: only pixels on contrast edges change.
    Fxaa,
    /// Subpixel morphological anti-aliasing (SMAA 1x: edge detection,
    /// blending weights from the shapes of the edges, neighbourhood blending).
    Smaa {
        /// How hard it looks.
        preset: SmaaPreset,
    },
    /// Sobel edge detection: pixels whose luma gradient is above `threshold` take `color`.
    Edges {
        /// Colour of the edges (linear).
        color: Vec3,
        /// Gradient magnitude (of perceived luma, 0..1 per pixel) where an edge starts.
        threshold: f32,
    },
    /// Darker corners, by up to `strength` (0..1).
    Vignette {
        /// How much the corners darken.
        strength: f32,
    },
}

impl PostEffect {
    /// Bloom with glint's defaults (threshold 1, intensity 0.5).
    pub const BLOOM: Self = Self::Bloom { threshold: 1.0, intensity: 0.5 };
    /// ACES tonemapping at exposure 0.
    pub const TONEMAP: Self = Self::Tonemap { operator: Tonemap::Aces, exposure: 0.0 };
    /// Black edges at threshold 0.4.
    pub const EDGES: Self = Self::Edges { color: Vec3::ZERO, threshold: 0.4 };
    /// A vignette of strength 0.4.
    pub const VIGNETTE: Self = Self::Vignette { strength: 0.4 };
    /// SMAA at its high preset.
    pub const SMAA: Self = Self::Smaa { preset: SmaaPreset::High };

    /// The effects, with their defaults, in the order of [`PostEffect::NAMES`].
    pub const ALL: [Self; 6] = [Self::BLOOM, Self::TONEMAP, Self::Fxaa, Self::EDGES, Self::VIGNETTE, Self::SMAA];
    /// Their names.
    pub const NAMES: [&'static str; 6] = ["bloom", "tonemap", "fxaa", "edges", "vignette", "smaa"];

    /// The effect called `name`, with its defaults.
    pub fn named(name: &str) -> Option<Self> {
        Self::NAMES.iter().position(|n| *n == name).map(|k| Self::ALL[k])
    }

    /// The chain a list of effect names (separated by white space) describes,
    /// each effect with its settings from `settings` (in the order of
    /// [`PostEffect::NAMES`]; [`PostEffect::ALL`] for the defaults). The one rule
    /// for `.scn` `post` keys and `glint bench --post`: an unknown name, a name
    /// given twice or more than [`MAX_POST_EFFECTS`] effects is an error saying
    /// what was expected.
    pub fn chain(names: &str, settings: &[Self; 6]) -> Result<Vec<Self>, String> {
        let mut chain: Vec<Self> = Vec::new();
        for name in names.split_whitespace() {
            let Some(k) = Self::NAMES.iter().position(|e| *e == name) else {
                let known = Self::NAMES.join(", ");
                return Err(format!(
                    "{} is not a post effect, expected effects among: {known}",
                    crate::text::quote(name)
                ));
            };
            if chain.iter().any(|e| e.name() == name) {
                return Err(format!("{} is named twice", crate::text::quote(name)));
            }
            if chain.len() == MAX_POST_EFFECTS {
                return Err(format!("more than {MAX_POST_EFFECTS} effects"));
            }
            chain.push(settings[k]);
        }
        Ok(chain)
    }

    /// Its name in `.scn` `post` lists and in statistics.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Bloom { .. } => "bloom",
            Self::Tonemap { .. } => "tonemap",
            Self::Fxaa => "fxaa",
            Self::Edges { .. } => "edges",
            Self::Vignette { .. } => "vignette",
            Self::Smaa { .. } => "smaa",
        }
    }
}
