//! Core layer: view frustums, world bounds (Arvo) and frustum culling on
//! structure-of-arrays bounds: one array of box centres, one of half extents.

use glam::{Mat4, Vec3A, Vec4};
use p3_maybe_rayon::prelude::*;
use std::ops::Range;

/// Half extent that marks a box as never visible (instances with invalid
/// transforms). Finite on purpose: a −∞ extent times a plane normal's zero
/// component is NaN, which the conservative test would keep.
pub const NEVER_VISIBLE_EXTENT: f32 = -1e30;

/// Instance counts above this are culled in parallel chunks (rayon).
pub const PARALLEL_CULL_THRESHOLD: usize = 32 * 1024;
const CHUNK: usize = 8 * 1024;

/// The six planes of a view volume, each `(normal, d)` with the normal pointing inwards:
/// a point `p` is inside a plane when `normal · p + d ≥ 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    planes: [Vec4; 6],
}

/// How a box lies against a frustum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Containment {
    /// Entirely outside one plane: nothing of it can be seen.
    Outside,
    /// Crossing at least one plane.
    Intersecting,
    /// Inside all six planes.
    Inside,
}

impl Frustum {
    /// The frustum of a view-projection matrix for wgpu clip space (z in 0..1),
    /// by Gribb and Hartmann's row combinations, planes normalised.
    pub fn from_view_proj(m: Mat4) -> Self {
        let rows = [m.row(0), m.row(1), m.row(2), m.row(3)];
        let planes = [
            rows[3] + rows[0], // left
            rows[3] - rows[0], // right
            rows[3] + rows[1], // bottom
            rows[3] - rows[1], // top
            rows[2],           // near (z ≥ 0)
            rows[3] - rows[2], // far
        ]
        .map(|p| p / p.truncate().length());
        Self { planes }
    }

    /// The planes, inward normals.
    pub fn planes(&self) -> &[Vec4; 6] {
        &self.planes
    }

    /// Classify the box `center ± extent`. Conservative: a box with NaN in it is
    /// never reported `Outside`.
    pub fn classify(&self, center: Vec3A, extent: Vec3A) -> Containment {
        let mut inside = true;
        for p in &self.planes {
            let n = Vec3A::from(p.truncate());
            let dist = n.dot(center) + p.w;
            let radius = n.abs().dot(extent);
            if dist + radius < 0.0 {
                return Containment::Outside;
            }
            // NaN compares false both ways, so it never counts as fully inside either.
            let inside_this_plane = dist - radius >= 0.0;
            inside &= inside_this_plane;
        }
        if inside {
            Containment::Inside
        } else {
            Containment::Intersecting
        }
    }

    /// Whether any part of the box `center ± extent` may be inside. Conservative
    /// (NaN → visible). A box with extent [`NEVER_VISIBLE_EXTENT`] and a finite
    /// centre is always outside: instances with invalid transforms are stored that
    /// way, so culling drops them with no extra test.
    #[inline]
    pub fn intersects(&self, center: Vec3A, extent: Vec3A) -> bool {
        // Written as "not outside" so that NaN (comparing false) keeps the box.
        !self.planes.iter().any(|p| {
            let n = Vec3A::from(p.truncate());
            n.dot(center) + p.w + n.abs().dot(extent) < 0.0
        })
    }
}

/// World-space box of the local box `center ± extent` under `m` (Arvo 1990):
/// the centre is transformed; the extent is `|M₃|·e`, two vector operations
/// instead of transforming eight corners.
#[inline]
pub fn transform_aabb(m: &Mat4, center: Vec3A, extent: Vec3A) -> (Vec3A, Vec3A) {
    let c = m.transform_point3a(center);
    let e = Vec3A::from(m.x_axis.truncate()).abs() * extent.x
        + Vec3A::from(m.y_axis.truncate()).abs() * extent.y
        + Vec3A::from(m.z_axis.truncate()).abs() * extent.z;
    (c, e)
}

/// World boxes as structure of arrays, one array per component, so that the
/// culler loads four boxes' centre x (then y, z, extents) into one SIMD register.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Boxes {
    cx: Vec<f32>,
    cy: Vec<f32>,
    cz: Vec<f32>,
    ex: Vec<f32>,
    ey: Vec<f32>,
    ez: Vec<f32>,
}

impl Boxes {
    /// Number of boxes.
    pub fn len(&self) -> usize {
        self.cx.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.cx.is_empty()
    }

    /// Grow or shrink to `n` boxes (new ones are points at the origin).
    pub fn resize(&mut self, n: usize) {
        for v in [&mut self.cx, &mut self.cy, &mut self.cz, &mut self.ex, &mut self.ey, &mut self.ez] {
            v.resize(n, 0.0);
        }
    }

    /// Set box `i` to `center ± extent`.
    pub fn set(&mut self, i: usize, center: Vec3A, extent: Vec3A) {
        (self.cx[i], self.cy[i], self.cz[i]) = (center.x, center.y, center.z);
        (self.ex[i], self.ey[i], self.ez[i]) = (extent.x, extent.y, extent.z);
    }

    /// Mark box `i` as never visible (see [`NEVER_VISIBLE_EXTENT`]).
    pub fn set_never_visible(&mut self, i: usize) {
        self.set(i, Vec3A::ZERO, Vec3A::splat(NEVER_VISIBLE_EXTENT));
    }

    /// Whether box `i` is a real box (not marked never visible).
    pub fn is_valid(&self, i: usize) -> bool {
        self.ex[i] >= 0.0
    }

    /// Centre of box `i`.
    pub fn center(&self, i: usize) -> Vec3A {
        Vec3A::new(self.cx[i], self.cy[i], self.cz[i])
    }

    /// Half extent of box `i`.
    pub fn extent(&self, i: usize) -> Vec3A {
        Vec3A::new(self.ex[i], self.ey[i], self.ez[i])
    }

    /// Append boxes `range` of `other`.
    pub fn extend_from(&mut self, other: &Boxes, range: Range<usize>) {
        let pairs = [
            (&mut self.cx, &other.cx),
            (&mut self.cy, &other.cy),
            (&mut self.cz, &other.cz),
            (&mut self.ex, &other.ex),
            (&mut self.ey, &other.ey),
            (&mut self.ez, &other.ez),
        ];
        for (dst, src) in pairs {
            dst.extend_from_slice(&src[range.clone()]);
        }
    }
}

/// One plane as six SIMD splats: normal, its absolute value, and d.
struct PlaneLanes {
    n: [Vec4; 3],
    abs_n: [Vec4; 3],
    d: Vec4,
}

/// Append every index in `range` whose box the frustum may see, in order. Tests
/// four boxes per SIMD operation; runs chunks on rayon's threads above
/// [`PARALLEL_CULL_THRESHOLD`].
pub fn cull_boxes(frustum: &Frustum, boxes: &Boxes, range: Range<usize>, out: &mut Vec<u32>) {
    if range.len() >= PARALLEL_CULL_THRESHOLD {
        let starts: Vec<usize> = range.clone().step_by(CHUNK).collect();
        let chunks: Vec<Vec<u32>> = starts
            .par_iter()
            .map(|&start| {
                let mut visible = Vec::with_capacity(CHUNK);
                cull_serial(frustum, boxes, start..(start + CHUNK).min(range.end), &mut visible);
                visible
            })
            .collect();
        for chunk in chunks {
            out.extend_from_slice(&chunk);
        }
    } else {
        cull_serial(frustum, boxes, range, out);
    }
}

fn cull_serial(frustum: &Frustum, boxes: &Boxes, range: Range<usize>, out: &mut Vec<u32>) {
    let lanes: [PlaneLanes; 6] = frustum.planes.map(|p| PlaneLanes {
        n: [Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z)],
        abs_n: [Vec4::splat(p.x.abs()), Vec4::splat(p.y.abs()), Vec4::splat(p.z.abs())],
        d: Vec4::splat(p.w),
    });
    let mut i = range.start;
    while i + 4 <= range.end {
        let load = |v: &[f32]| Vec4::from_slice(&v[i..i + 4]);
        let (cx, cy, cz) = (load(&boxes.cx), load(&boxes.cy), load(&boxes.cz));
        let (ex, ey, ez) = (load(&boxes.ex), load(&boxes.ey), load(&boxes.ez));
        let mut outside = 0u32;
        for p in &lanes {
            let reach =
                cx * p.n[0] + cy * p.n[1] + cz * p.n[2] + p.d + ex * p.abs_n[0] + ey * p.abs_n[1] + ez * p.abs_n[2];
            // NaN compares false, so a NaN box is never outside (conservative).
            outside |= reach.cmplt(Vec4::ZERO).bitmask();
        }
        for lane in 0..4 {
            if outside & (1 << lane) == 0 {
                out.push((i + lane) as u32);
            }
        }
        i += 4;
    }
    for j in i..range.end {
        if frustum.intersects(boxes.center(j), boxes.extent(j)) {
            out.push(j as u32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use rand::{Rng, SeedableRng};

    fn camera_frustum() -> (Frustum, Mat4) {
        let view = glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y);
        let proj = glam::camera::rh::proj::directx::perspective(1.0, 1.5, 0.5, 50.0);
        let vp = proj * view;
        (Frustum::from_view_proj(vp), vp)
    }

    /// Brute force: the box is visible unless all 8 corners are outside the same
    /// clip-space plane (the classic conservative test the plane test must equal).
    fn brute_force(vp: Mat4, c: Vec3, e: Vec3) -> bool {
        let corners: Vec<Vec4> = (0..8)
            .map(|i| {
                let s = Vec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                );
                vp * (c + e * s).extend(1.0)
            })
            .collect();
        let outside = |f: &dyn Fn(&Vec4) -> bool| corners.iter().all(f);
        !(outside(&|p| p.x < -p.w)
            || outside(&|p| p.x > p.w)
            || outside(&|p| p.y < -p.w)
            || outside(&|p| p.y > p.w)
            || outside(&|p| p.z < 0.0)
            || outside(&|p| p.z > p.w))
    }

    #[test]
    fn plane_test_matches_brute_force_on_random_boxes() {
        let (frustum, vp) = camera_frustum();
        let mut rng = rand_pcg::Pcg32::seed_from_u64(9);
        let mut seen = [0, 0];
        for _ in 0..20_000 {
            let c =
                Vec3::new(rng.random_range(-30.0..30.0), rng.random_range(-30.0..30.0), rng.random_range(-60.0..15.0));
            let e = Vec3::new(rng.random_range(0.0..3.0), rng.random_range(0.0..3.0), rng.random_range(0.0..3.0));
            let expected = brute_force(vp, c, e);
            let got = frustum.intersects(c.into(), e.into());
            // The plane test is conservative near frustum corners (a box can straddle
            // two planes yet miss the volume); it must never cull a visible box.
            if expected {
                assert!(got, "visible box culled: c={c} e={e}");
            }
            seen[got as usize] += 1;
            if !got {
                assert!(!expected);
            }
        }
        assert!(seen[0] > 1000 && seen[1] > 1000, "random scene should have both: {seen:?}");
    }

    #[test]
    fn boxes_exactly_on_each_plane_are_kept_and_just_beyond_are_culled() {
        let (frustum, _) = camera_frustum();
        let middle = Vec3::new(0.0, 0.0, -5.0); // inside, 15 units in front of the eye
        for p in frustum.planes() {
            let n = p.truncate();
            // The middle point projected onto this plane: on it, inside the other five.
            let on = middle - n * (n.dot(middle) + p.w);
            assert!((n.dot(on) + p.w).abs() < 1e-4);
            assert!(frustum.intersects(on.into(), Vec3A::splat(0.01)), "box centred on a plane is kept");
            assert!(frustum.intersects((on - n * 0.009).into(), Vec3A::splat(0.01)), "box crossing a plane is kept");
            assert!(
                !frustum.intersects((on - n * 0.02).into(), Vec3A::splat(0.01)),
                "box just beyond a plane is culled"
            );
        }
    }

    #[test]
    fn huge_degenerate_and_nan_boxes() {
        let (frustum, _) = camera_frustum();
        // Huge box around everything.
        assert_eq!(frustum.classify(Vec3A::ZERO, Vec3A::splat(1e30)), Containment::Intersecting);
        assert!(frustum.intersects(Vec3A::ZERO, Vec3A::splat(f32::INFINITY)));
        // Zero-size boxes are points.
        assert!(frustum.intersects(Vec3A::ZERO, Vec3A::ZERO));
        assert!(!frustum.intersects(Vec3A::new(0.0, 0.0, 20.0), Vec3A::ZERO), "behind the camera");
        // NaN is conservative: kept, never "inside".
        assert!(frustum.intersects(Vec3A::splat(f32::NAN), Vec3A::ONE));
        assert_eq!(frustum.classify(Vec3A::splat(f32::NAN), Vec3A::ONE), Containment::Intersecting);
        // The invalid-instance encoding is always culled.
        assert!(!frustum.intersects(Vec3A::ZERO, Vec3A::splat(NEVER_VISIBLE_EXTENT)));
        assert_eq!(frustum.classify(Vec3A::ZERO, Vec3A::splat(NEVER_VISIBLE_EXTENT)), Containment::Outside);
        // A small box in the middle is fully inside.
        assert_eq!(frustum.classify(Vec3A::ZERO, Vec3A::splat(0.5)), Containment::Inside);
        assert_eq!(frustum.classify(Vec3A::new(0.0, 0.0, 30.0), Vec3A::ONE), Containment::Outside);
    }

    #[test]
    fn arvo_bounds_contain_every_transformed_corner_tightly() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(3);
        for _ in 0..500 {
            let m = Mat4::from_scale_rotation_translation(
                Vec3::new(rng.random_range(0.1..3.0), rng.random_range(0.1..3.0), rng.random_range(0.1..3.0)),
                glam::Quat::from_euler(glam::EulerRot::XYZ, rng.random(), rng.random(), rng.random()),
                Vec3::new(rng.random(), rng.random(), rng.random()) * 10.0,
            );
            let (c, e) = (Vec3A::new(0.1, -0.2, 0.3), Vec3A::new(0.5, 0.25, 1.0));
            let (wc, we) = transform_aabb(&m, c, e);
            let corners: Vec<Vec3A> = (0..8)
                .map(|i| {
                    m.transform_point3a(
                        c + e * Vec3A::new(
                            if i & 1 == 0 { -1.0 } else { 1.0 },
                            if i & 2 == 0 { -1.0 } else { 1.0 },
                            if i & 4 == 0 { -1.0 } else { 1.0 },
                        ),
                    )
                })
                .collect();
            let (lo, hi) = corners
                .iter()
                .fold((Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
            assert!(
                (wc - we - lo).abs().max_element() < 1e-4 && (wc + we - hi).abs().max_element() < 1e-4,
                "Arvo bounds must equal the corners' bounds"
            );
        }
    }

    #[test]
    fn simd_and_parallel_culling_equal_the_scalar_test() {
        let (frustum, _) = camera_frustum();
        let mut rng = rand_pcg::Pcg32::seed_from_u64(1);
        let n = PARALLEL_CULL_THRESHOLD * 3 + 17;
        let mut boxes = Boxes::default();
        boxes.resize(n);
        for i in 0..n {
            let c =
                Vec3A::new(rng.random_range(-40.0..40.0), rng.random_range(-40.0..40.0), rng.random_range(-60.0..20.0));
            boxes.set(i, c, Vec3A::splat(rng.random_range(0.0..2.0)));
        }
        boxes.set_never_visible(5);
        boxes.set(6, Vec3A::splat(f32::NAN), Vec3A::ONE);
        let scalar = |r: Range<usize>| -> Vec<u32> {
            r.filter(|&i| frustum.intersects(boxes.center(i), boxes.extent(i))).map(|i| i as u32).collect()
        };
        for range in [0..n, 3..1000, 0..3, 100..PARALLEL_CULL_THRESHOLD + 101] {
            let mut fast = Vec::new();
            cull_boxes(&frustum, &boxes, range.clone(), &mut fast);
            assert_eq!(fast, scalar(range.clone()), "{range:?}");
        }
        let mut all = Vec::new();
        cull_boxes(&frustum, &boxes, 0..n, &mut all);
        assert!(!all.contains(&5) && all.contains(&6), "never-visible dropped, NaN kept");
        assert!(all.len() > 1000 && all.len() < n);
    }
}
