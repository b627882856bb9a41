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
    /// xyz in `x, y, z` for translation and scale.
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
        let per_key = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if self.values.len() != self.times.len() * per_key {
            return Err(format!("{} values for {} keys, expected {}", self.values.len(), self.times.len(), per_key));
        }
        Ok(())
    }

    /// The channel's value at `time` (clamped to the first and last keys).
    pub fn sample(&self, time: f32) -> Vec4 {
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| if cubic { self.values[3 * k + 1] } else { self.values[k] };
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
                let (p0, m0) = (self.values[3 * k + 1], self.values[3 * k + 2] * dt);
                let (p1, m1) = (self.values[3 * next + 1], self.values[3 * next] * dt);
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

/// World transforms of `nodes` with `animation` (if any) applied at `time`.
pub(crate) fn pose_nodes(nodes: &[ModelNode], animation: Option<&Animation>, time: f32) -> Vec<Mat4> {
    let mut locals: Vec<(Vec3, Quat, Vec3)> = nodes.iter().map(|n| (n.translation, n.rotation, n.scale)).collect();
    for c in animation.iter().flat_map(|a| &a.channels) {
        let Some(local) = locals.get_mut(c.node) else { continue };
        let v = c.sample(time);
        match c.property {
            Property::Translation => local.0 = v.truncate(),
            Property::Rotation => local.1 = Quat::from_vec4(v).normalize(),
            Property::Scale => local.2 = v.truncate(),
        }
    }
    let mut world: Vec<Mat4> = Vec::with_capacity(nodes.len());
    for (node, &(t, r, s)) in nodes.iter().zip(&locals) {
        let local = Mat4::from_scale_rotation_translation(s, r, t);
        let parent = node.parent.and_then(|p| world.get(p).copied()).unwrap_or(Mat4::IDENTITY);
        world.push(parent * local);
    }
    world
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
        };
        let nodes = [node(None), node(Some(0))];
        let up = channel(Property::Translation, Interpolation::Linear, &[0.0, 1.0], &[Vec4::ZERO, Vec4::Y]);
        let animation = Animation { name: "lift".into(), channels: vec![up] };
        let world = pose_nodes(&nodes, Some(&animation), 1.0);
        assert_eq!(world[0].w_axis.truncate(), Vec3::Y, "the root moved to its key");
        assert_eq!(world[1].w_axis.truncate(), Vec3::new(1.0, 1.0, 0.0), "the child rides along");
        assert_eq!(animation.duration(), 1.0);
    }
}
