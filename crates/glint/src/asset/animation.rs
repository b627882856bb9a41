//! Beginner layer: a model's node hierarchy and its keyframe animations
//! (translation, rotation and scale channels with step, linear and cubic-spline
//! interpolation, as glTF defines them). [`Model::pose`](super::Model::pose)
//! evaluates them at a time and moves the model's parts.

use glam::{Mat4, Quat, Vec3, Vec4};

/// One node of a model's hierarchy: its rest transform and the part instances it places.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelNode {
    /// Parent node (always earlier in [`Model::nodes`](super::Model::nodes)); `None` at a root.
    pub parent: Option<usize>,
    /// Rest translation.
    pub translation: Vec3,
    /// Rest rotation.
    pub rotation: Quat,
    /// Rest scale.
    pub scale: Vec3,
    /// `(part, k)`: this node's world transform is `parts[part].transforms[k]`.
    pub placements: Vec<(usize, usize)>,
    /// Rest weights of its mesh's morph targets (empty without morph targets).
    pub weights: Vec<f32>,
}

/// What a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// Translation (xyz).
    Translation,
    /// Rotation (a quaternion, xyzw).
    Rotation,
    /// Scale (xyz).
    Scale,
    /// Morph-target weights: each key holds one weight per target, four to a `Vec4`.
    Weights,
}

/// How a channel fills the time between keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Hold each key until the next.
    Step,
    /// Straight lines (spherical for rotations).
    Linear,
    /// Hermite curves through the keys with in and out tangents.
    CubicSpline,
}

/// Keyframes for one property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node ([`Model::nodes`](super::Model::nodes) index).
    pub node: usize,
    /// What is animated.
    pub property: Property,
    /// How keys are joined.
    pub interpolation: Interpolation,
    /// Key times in seconds, non-decreasing.
    pub times: Vec<f32>,
    /// One value per key (three for cubic splines: in-tangent, value, out-tangent);
    /// xyz in `x, y, z` for translation and scale. A value of [`Property::Weights`]
    /// is several `Vec4`s (as many for every key).
    pub values: Vec<Vec4>,
}

/// A named set of channels played together.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Name from the file.
    pub name: String,
    /// Its channels.
    pub channels: Vec<Channel>,
}

impl Animation {
    /// The last key time over all channels.
    pub fn duration(&self) -> f32 {
        self.channels.iter().filter_map(|c| c.times.last()).fold(0.0, |a, &b| a.max(b))
    }
}

impl Channel {
    /// Check the keys: finite, non-decreasing times and one value (three for
    /// cubic splines) per key.
    pub fn validate(&self) -> Result<(), String> {
        if self.times.is_empty() {
            return Err("no keys".into());
        }
        if self.times.iter().any(|t| !t.is_finite()) || self.times.windows(2).any(|w| w[1] < w[0]) {
            return Err("key times must be finite and non-decreasing".into());
        }
        let per_key = self.per_key();
        let width = self.width();
        let wide_ok = width >= 1 && (width == 1 || self.property == Property::Weights);
        if !wide_ok || self.values.len() != self.times.len() * per_key * width {
            let expected = self.times.len() * per_key;
            return Err(format!("{} values for {} keys, expected {expected}", self.values.len(), self.times.len()));
        }
        if self.values.iter().any(|v| !v.is_finite()) {
            return Err("key values must be finite".into());
        }
        Ok(())
    }

    /// Values per key: three for cubic splines (in-tangent, value, out-tangent).
    fn per_key(&self) -> usize {
        if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        }
    }

    /// `Vec4`s in one value (1, except for weights).
    fn width(&self) -> usize {
        self.values.len() / (self.times.len() * self.per_key()).max(1)
    }

    /// The channel's value at `time` (clamped to the first and last keys); the
    /// first four weights of a [`Property::Weights`] channel.
    pub fn sample(&self, time: f32) -> Vec4 {
        self.sample_part(time, 0)
    }

    /// Every `Vec4` of the channel's value at `time` (one, except for weights).
    pub fn sample_all(&self, time: f32) -> Vec<Vec4> {
        (0..self.width()).map(|c| self.sample_part(time, c)).collect()
    }

    /// `Vec4` number `c` of the value at `time`.
    fn sample_part(&self, time: f32, c: usize) -> Vec4 {
        let (cubic, width) = (self.interpolation == Interpolation::CubicSpline, self.width());
        let at = |k: usize| k * width + c;
        let value = |k: usize| if cubic { self.values[at(3 * k + 1)] } else { self.values[at(k)] };
        let last = self.times.len() - 1;
        let next = self.times.partition_point(|&t| t <= time);
        if next == 0 {
            return value(0);
        }
        if next > last {
            return value(last);
        }
        let k = next - 1;
        let dt = self.times[next] - self.times[k];
        let s = if dt > 0.0 { (time - self.times[k]) / dt } else { 0.0 };
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if rotation => {
                let (a, b) = (Quat::from_vec4(value(k)), Quat::from_vec4(value(next)));
                Vec4::from(a.normalize().slerp(b.normalize(), s))
            }
            Interpolation::Linear => value(k).lerp(value(next), s),
            Interpolation::CubicSpline => {
                let (p0, m0) = (self.values[at(3 * k + 1)], self.values[at(3 * k + 2)] * dt);
                let (p1, m1) = (self.values[at(3 * next + 1)], self.values[at(3 * next)] * dt);
                let (s2, s3) = (s * s, s * s * s);
                let v = p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + m0 * (s3 - 2.0 * s2 + s)
                    + p1 * (-2.0 * s3 + 3.0 * s2)
                    + m1 * (s3 - s2);
                if rotation {
                    v.normalize_or(Vec4::W)
                } else {
                    v
                }
            }
        }
    }
}

/// Nodes posed at one time.
pub(crate) struct Pose {
    /// World (model-space) transform of each node.
    pub world: Vec<Mat4>,
    /// Morph-target weights of each node.
    pub weights: Vec<Vec<f32>>,
}

/// `nodes` with `animation` (if any) applied at `time`.
pub(crate) fn pose_nodes(nodes: &[ModelNode], animation: Option<&Animation>, time: f32) -> Pose {
    let mut locals: Vec<(Vec3, Quat, Vec3)> = nodes.iter().map(|n| (n.translation, n.rotation, n.scale)).collect();
    let mut weights: Vec<Vec<f32>> = nodes.iter().map(|n| n.weights.clone()).collect();
    for c in animation.iter().flat_map(|a| &a.channels) {
        let Some(local) = locals.get_mut(c.node) else { continue };
        let v = c.sample(time);
        match c.property {
            Property::Translation => local.0 = v.truncate(),
            Property::Rotation => local.1 = Quat::from_vec4(v).normalize(),
            Property::Scale => local.2 = v.truncate(),
            Property::Weights => {
                let sampled = c.sample_all(time).into_iter().flat_map(|v| v.to_array());
                for (w, x) in weights[c.node].iter_mut().zip(sampled) {
                    *w = x;
                }
            }
        }
    }
    let mut world: Vec<Mat4> = Vec::with_capacity(nodes.len());
    for (node, &(t, r, s)) in nodes.iter().zip(&locals) {
        let local = Mat4::from_scale_rotation_translation(s, r, t);
        let parent = node.parent.and_then(|p| world.get(p).copied()).unwrap_or(Mat4::IDENTITY);
        world.push(parent * local);
    }
    Pose { world, weights }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(property: Property, interpolation: Interpolation, times: &[f32], values: &[Vec4]) -> Channel {
        Channel { node: 0, property, interpolation, times: times.to_vec(), values: values.to_vec() }
    }

    #[test]
    fn step_linear_and_clamping() {
        let keys = [Vec4::ZERO, Vec4::new(2.0, 0.0, 0.0, 0.0)];
        let linear = channel(Property::Translation, Interpolation::Linear, &[1.0, 2.0], &keys);
        assert_eq!(linear.sample(1.5), Vec4::new(1.0, 0.0, 0.0, 0.0));
        assert_eq!(linear.sample(0.0), keys[0], "before the first key");
        assert_eq!(linear.sample(9.0), keys[1], "after the last key");
        let step = channel(Property::Translation, Interpolation::Step, &[1.0, 2.0], &keys);
        assert_eq!(step.sample(1.99), keys[0]);
        assert_eq!(step.sample(2.0), keys[1]);
    }

    #[test]
    fn rotations_slerp_and_cubic_splines_pass_through_their_keys() {
        let quarter = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let r = channel(Property::Rotation, Interpolation::Linear, &[0.0, 1.0], &[Vec4::W, Vec4::from(quarter)]);
        let half = Quat::from_vec4(r.sample(0.5));
        assert!(half.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4)) < 1e-5);
        // Keys 0 → 1 with zero tangents: an ease curve, 0.5 at the middle, exact at keys.
        let z = Vec4::ZERO;
        let cubic = channel(Property::Scale, Interpolation::CubicSpline, &[0.0, 2.0], &[z, z, z, z, Vec4::ONE, z]);
        assert_eq!(cubic.sample(0.0), z);
        assert_eq!(cubic.sample(2.0), Vec4::ONE);
        assert!((cubic.sample(1.0) - Vec4::splat(0.5)).length() < 1e-6);
        assert!(cubic.sample(0.5).x < 0.25, "eases in: below the straight line");
    }

    #[test]
    fn weight_channels_sample_every_target() {
        // Two keys of six weights each: two Vec4s a key.
        let (a, b) = ([Vec4::ZERO, Vec4::ZERO], [Vec4::ONE, Vec4::new(2.0, 4.0, 0.0, 0.0)]);
        let c = channel(Property::Weights, Interpolation::Linear, &[0.0, 1.0], &[a[0], a[1], b[0], b[1]]);
        c.validate().expect("8 Vec4s for 2 keys is 2 a key");
        assert_eq!(c.sample_all(0.5), vec![Vec4::splat(0.5), Vec4::new(1.0, 2.0, 0.0, 0.0)]);
        let node = ModelNode {
            parent: None,
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
            placements: Vec::new(),
            weights: vec![9.0; 6],
        };
        let animation = Animation { name: "morph".into(), channels: vec![c] };
        assert_eq!(pose_nodes(&[node], Some(&animation), 1.0).weights[0], [1.0, 1.0, 1.0, 1.0, 2.0, 4.0]);
        let translation = channel(Property::Translation, Interpolation::Linear, &[0.0], &[Vec4::ZERO, Vec4::ZERO]);
        assert!(translation.validate().is_err(), "only weights have several Vec4s a key");
    }

    #[test]
    fn malformed_channels_are_rejected() {
        let v = [Vec4::ZERO; 2];
        assert!(channel(Property::Scale, Interpolation::Linear, &[1.0, 0.5], &v).validate().is_err());
        assert!(channel(Property::Scale, Interpolation::Linear, &[0.0, f32::NAN], &v).validate().is_err());
        assert!(channel(Property::Scale, Interpolation::CubicSpline, &[0.0, 1.0], &v).validate().is_err());
        assert!(channel(Property::Scale, Interpolation::Linear, &[], &[]).validate().is_err());
        assert!(channel(Property::Scale, Interpolation::Linear, &[0.0, 1.0], &v).validate().is_ok());
    }

    #[test]
    fn children_follow_their_animated_parents() {
        let node = |parent| ModelNode {
            parent,
            translation: Vec3::X,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
            placements: Vec::new(),
            weights: Vec::new(),
        };
        let nodes = [node(None), node(Some(0))];
        let up = channel(Property::Translation, Interpolation::Linear, &[0.0, 1.0], &[Vec4::ZERO, Vec4::Y]);
        let animation = Animation { name: "lift".into(), channels: vec![up] };
        let world = pose_nodes(&nodes, Some(&animation), 1.0).world;
        assert_eq!(world[0].w_axis.truncate(), Vec3::Y, "the root moved to its key");
        assert_eq!(world[1].w_axis.truncate(), Vec3::new(1.0, 1.0, 0.0), "the child rides along");
        assert_eq!(animation.duration(), 1.0);
    }
}
