//! Which nodes are pinned, and how pinned nodes move.
//!
//! A [`PinSelector`] is written the same way on the command line
//! (`glint sim cloth --fix`) and in `.scn` files (`"pins"`):
//!
//! - a predicate on rest positions: comparisons `x<=0.01`, `y>0.2`, `z==0`
//!   (`==` within a micrometre), joined by `&&` (binds tighter) and `||`;
//! - `nodes 1 5 9`: node numbers, 1-based as in the `*Nodes` format;
//! - `none`.

use glam::{DQuat, DVec3};

/// `==` in a pin predicate holds within this distance, metres.
const EQUAL_WITHIN: f64 = 1e-6;

/// Most comparisons one predicate may hold: each is tested at every node
/// (120,001 of them on a 129 × 129 sheet took 14–24 s to select).
pub const MAX_PIN_TERMS: usize = 64;

/// A parsed pin selector.
#[derive(Clone, Debug, PartialEq)]
pub enum PinSelector {
    /// No pins.
    None,
    /// These 0-based node indices.
    Nodes(Vec<usize>),
    /// Nodes whose rest position satisfies any of the `&&` groups.
    Predicate(Vec<Vec<Comparison>>),
}

/// One `axis op value` comparison of a predicate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// 0 for x, 1 for y, 2 for z.
    pub axis: usize,
    /// The operator.
    pub op: CompareOp,
    /// The right-hand side, metres.
    pub value: f64,
}

/// A comparison operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompareOp {
    /// `<`
    Less,
    /// `<=`
    LessEqual,
    /// `>`
    Greater,
    /// `>=`
    GreaterEqual,
    /// `==` (within a micrometre)
    Equal,
}

impl PinSelector {
    /// Parse a selector; the error says what was expected.
    pub fn parse(text: &str) -> Result<Self, String> {
        let text = text.trim();
        if text.is_empty() || text == "none" {
            return Ok(Self::None);
        }
        if let Some(list) = text.strip_prefix("nodes") {
            let nodes = list
                .split([' ', ','])
                .filter(|s| !s.is_empty())
                .map(|s| match s.parse::<usize>() {
                    Ok(n) if n >= 1 => Ok(n - 1),
                    _ => Err(format!("{} is not a node number (1-based)", crate::text::quote(s))),
                })
                .collect::<Result<Vec<_>, _>>()?;
            if nodes.is_empty() {
                return Err("'nodes' needs at least one node number".into());
            }
            return Ok(Self::Nodes(nodes));
        }
        let terms = text.split("||").map(|g| g.split("&&").count()).sum::<usize>();
        if terms > MAX_PIN_TERMS {
            return Err(format!("{terms} comparisons, at most {MAX_PIN_TERMS}"));
        }
        let groups = text
            .split("||")
            .map(|group| group.split("&&").map(Comparison::parse).collect::<Result<Vec<_>, _>>())
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self::Predicate(groups))
    }

    /// One flag per node of `rest`: whether it is pinned. A node number past
    /// the end is an error.
    pub fn select(&self, rest: &[DVec3]) -> Result<Vec<bool>, String> {
        match self {
            Self::None => Ok(vec![false; rest.len()]),
            Self::Nodes(nodes) => {
                let mut pinned = vec![false; rest.len()];
                for &n in nodes {
                    *pinned
                        .get_mut(n)
                        .ok_or_else(|| format!("pin node {} is past the {} nodes", n + 1, rest.len()))? = true;
                }
                Ok(pinned)
            }
            Self::Predicate(groups) => {
                Ok(rest.iter().map(|p| groups.iter().any(|all| all.iter().all(|c| c.holds(*p)))).collect())
            }
        }
    }
}

impl Comparison {
    fn parse(text: &str) -> Result<Self, String> {
        let text = text.trim();
        let expected =
            || format!("{} is not a pin condition: expected AXIS OP NUMBER, e.g. x<=0.01", crate::text::quote(text));
        let axis = match text.chars().next() {
            Some('x') => 0,
            Some('y') => 1,
            Some('z') => 2,
            _ => return Err(expected()),
        };
        let rest = text[1..].trim_start();
        let (op, number) = [
            ("<=", CompareOp::LessEqual),
            (">=", CompareOp::GreaterEqual),
            ("==", CompareOp::Equal),
            ("<", CompareOp::Less),
            (">", CompareOp::Greater),
            ("=", CompareOp::Equal),
        ]
        .iter()
        .find_map(|(symbol, op)| rest.strip_prefix(symbol).map(|n| (*op, n.trim())))
        .ok_or_else(expected)?;
        let value = number.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(expected)?;
        Ok(Self { axis, op, value })
    }

    fn holds(&self, p: DVec3) -> bool {
        let v = p[self.axis];
        match self.op {
            CompareOp::Less => v < self.value,
            CompareOp::LessEqual => v <= self.value + EQUAL_WITHIN,
            CompareOp::Greater => v > self.value,
            CompareOp::GreaterEqual => v >= self.value - EQUAL_WITHIN,
            CompareOp::Equal => (v - self.value).abs() <= EQUAL_WITHIN,
        }
    }
}

/// A rigid motion of all pinned nodes: at time t a pin starting at p is at
/// `centre + R(ω t)(p − centre) + v t`, R the rotation by |ω| t radians about ω.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PinMotion {
    /// Linear velocity v, m/s.
    pub velocity: DVec3,
    /// Angular velocity ω, rad/s.
    pub angular_velocity: DVec3,
    /// Centre of the rotation, metres.
    pub centre: DVec3,
}

impl PinMotion {
    /// Where a pin that started at `start` is at time `t`.
    pub fn at(&self, start: DVec3, t: f64) -> DVec3 {
        let turn = DQuat::from_scaled_axis(self.angular_velocity * t);
        self.centre + turn * (start - self.centre) + self.velocity * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn predicates_select_by_rest_position() {
        let rest = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.005, 1.0, 0.0), DVec3::new(0.5, 1.0, 0.0)];
        assert_eq!(PinSelector::parse("x<=0.01").unwrap().select(&rest).unwrap(), [true, true, false]);
        assert_eq!(PinSelector::parse("x <= 0.01 && y>0.5").unwrap().select(&rest).unwrap(), [false, true, false]);
        assert_eq!(PinSelector::parse("x==0 || x>=0.5").unwrap().select(&rest).unwrap(), [true, false, true]);
        assert_eq!(PinSelector::parse("nodes 1, 3").unwrap().select(&rest).unwrap(), [true, false, true]);
        assert_eq!(PinSelector::parse("none").unwrap().select(&rest).unwrap(), [false, false, false]);
    }

    #[test]
    fn bad_selectors_say_what_was_expected() {
        for (text, says) in [
            ("w<1", "expected AXIS OP NUMBER"),
            ("x<=", "expected AXIS OP NUMBER"),
            ("x~1", "expected AXIS OP NUMBER"),
            ("x<1 &&", "expected AXIS OP NUMBER"),
            ("x<nan", "expected AXIS OP NUMBER"),
            ("nodes 0", "1-based"),
            ("nodes", "at least one"),
        ] {
            let error = PinSelector::parse(text).unwrap_err();
            assert!(error.contains(says), "{text}: {error}");
        }
        let error = PinSelector::parse("nodes 4").unwrap().select(&[DVec3::ZERO; 3]).unwrap_err();
        assert!(error.contains("past the 3 nodes"), "{error}");
    }

    #[test]
    fn pin_motion_is_rigid() {
        let motion = PinMotion {
            velocity: DVec3::new(0.0, 0.0, 1.0),
            angular_velocity: DVec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
            centre: DVec3::ZERO,
        };
        let p = motion.at(DVec3::X, 1.0);
        assert!((p - DVec3::new(0.0, 1.0, 1.0)).length() < 1e-12, "{p}");
        assert_eq!(PinMotion::default().at(DVec3::X, 3.0), DVec3::X);
    }
}
