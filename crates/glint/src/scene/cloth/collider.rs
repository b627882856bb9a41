//! Rigid obstacles for cloth ([`Collider`]): planes, spheres and boxes, as a
//! scene or the command line writes them, with the signed distance that
//! `sim::cloth`'s contact energy pushes nodes out along.

use glam::DVec3;

/// A rigid obstacle for cloth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Collider {
    /// The half-space below a plane through `point` with unit `normal` pointing out.
    Plane {
        /// A point on the plane.
        point: DVec3,
        /// Unit normal, pointing to the free side.
        normal: DVec3,
    },
    /// A solid ball.
    Sphere {
        /// Centre, metres.
        centre: DVec3,
        /// Radius, metres.
        radius: f64,
    },
    /// A solid axis-aligned box (a table top).
    Box {
        /// Lowest corner, metres.
        min: DVec3,
        /// Highest corner, metres.
        max: DVec3,
    },
}

impl Collider {
    /// Parse `plane PX PY PZ NX NY NZ`, `sphere CX CY CZ R` or
    /// `box MINX MINY MINZ MAXX MAXY MAXZ`; the error says what was expected.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut words = text.split_whitespace();
        let kind = words.next().unwrap_or("");
        let numbers: Vec<f64> =
            words
                .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect::<Option<_>>()
                .ok_or_else(|| format!("{}: collider values must be finite numbers", crate::text::quote(text)))?;
        let v = |i: usize| DVec3::new(numbers[i], numbers[i + 1], numbers[i + 2]);
        match (kind, numbers.len()) {
            ("plane", 6) if v(3).length() > 0.0 => Ok(Self::Plane { point: v(0), normal: v(3).normalize() }),
            ("sphere", 4) if numbers[3] > 0.0 => Ok(Self::Sphere { centre: v(0), radius: numbers[3] }),
            ("box", 6) if v(0).cmplt(v(3)).all() => Ok(Self::Box { min: v(0), max: v(3) }),
            _ => Err(format!(
                "{} is not a collider: expected 'plane PX PY PZ NX NY NZ' (normal not zero), \
                 'sphere CX CY CZ R' (R > 0) or 'box MINX MINY MINZ MAXX MAXY MAXZ' (min below max)",
                crate::text::quote(text)
            )),
        }
    }

    /// Signed distance from `x` to the collider's surface (negative inside) and
    /// the outward unit direction in which it grows fastest.
    pub fn distance(&self, x: DVec3) -> (f64, DVec3) {
        match *self {
            Self::Plane { point, normal } => ((x - point).dot(normal), normal),
            Self::Sphere { centre, radius } => {
                let d = x - centre;
                let length = d.length();
                let n = if length > 0.0 { d / length } else { DVec3::Z };
                (length - radius, n)
            }
            Self::Box { min, max } => {
                let centre = 0.5 * (min + max);
                let half = 0.5 * (max - min);
                let local = x - centre;
                let q = local.abs() - half;
                let outside = q.max(DVec3::ZERO);
                if outside.length_squared() > 0.0 {
                    let length = outside.length();
                    (length, (outside * local.signum()) / length)
                } else {
                    // Inside: the nearest face.
                    let axis = if q.x >= q.y && q.x >= q.z {
                        0
                    } else if q.y >= q.z {
                        1
                    } else {
                        2
                    };
                    let mut n = DVec3::ZERO;
                    n[axis] = local[axis].signum();
                    (q[axis], n)
                }
            }
        }
    }
}
