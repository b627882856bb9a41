//! Typed reading of one `.scn` block's pairs: every getter marks its key as used,
//! so keys nobody asked for can be reported as unknown.

use super::scn_syntax::{Block, Pair};
use super::{Diagnostic, ShapeKind};
use crate::text::quote;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// The pairs of one block, looked up by key; reports keys never asked for.
pub(crate) struct Fields<'b> {
    pub path: &'b Path,
    pub class: &'b str,
    pub block: &'b Block,
    pub used: Vec<bool>,
}

impl<'b> Fields<'b> {
    pub(crate) fn get(&mut self, key: &str) -> Option<&'b Pair> {
        let i = self.block.pairs.iter().rposition(|p| p.key == key)?;
        self.used[i] = true;
        Some(&self.block.pairs[i])
    }

    pub(crate) fn require(&mut self, key: &str) -> Result<&'b Pair, Diagnostic> {
        self.get(key).ok_or_else(|| {
            Diagnostic::at(
                self.path,
                self.block.line,
                format!("{} block is missing the required key \"{key}\"", self.class),
            )
        })
    }

    pub(crate) fn numbers<const N: usize>(&mut self, key: &str, what: &str) -> Result<Option<[f32; N]>, Diagnostic> {
        self.get(key).map(|p| numbers::<N>(self.path, p, what)).transpose()
    }

    pub(crate) fn vec3(&mut self, key: &str) -> Result<Option<Vec3>, Diagnostic> {
        Ok(self.numbers::<3>(key, "3 numbers (x y z)")?.map(Vec3::from))
    }

    /// A vector of three numbers no longer than `most`.
    pub(crate) fn bounded_vec3(&mut self, key: &str, most: f32) -> Result<Option<Vec3>, Diagnostic> {
        let line = self.get(key).map_or(self.block.line, |p| p.line);
        match self.vec3(key)? {
            Some(v) if v.length() > most => {
                let message = format!("\"{key}\" is {} long, expected at most {most}", v.length());
                Err(Diagnostic::at(self.path, line, message))
            }
            v => Ok(v),
        }
    }

    /// A rectangle "x y w h" of fractions of the image, inside 0..1 and not empty.
    pub(crate) fn viewport(&mut self, key: &str) -> Result<Option<crate::scene::Viewport>, Diagnostic> {
        let Some(pair) = self.get(key) else {
            return Ok(None);
        };
        let [x, y, width, height] =
            numbers::<4>(self.path, pair, "4 numbers (x y width height, fractions of the image)")?;
        let viewport = crate::scene::Viewport { x, y, width, height };
        if !viewport.is_valid() {
            let message = format!(
                "\"{key}\" \"{x} {y} {width} {height}\" is not a rectangle inside the image: x and y must be at least 0, \
                 width and height more than 0, x + width and y + height at most 1"
            );
            return Err(Diagnostic::at(self.path, pair.line, message));
        }
        Ok(Some(viewport))
    }

    pub(crate) fn color(&mut self, key: &str) -> Result<Option<Vec3>, Diagnostic> {
        let Some(pair) = self.get(key) else {
            return Ok(None);
        };
        let c = Vec3::from(numbers::<3>(self.path, pair, "3 numbers (r g b)")?);
        if c.min_element() < 0.0 {
            return Err(Diagnostic::at(self.path, pair.line, format!("\"{key}\" must not be negative")));
        }
        Ok(Some(c))
    }

    pub(crate) fn number(
        &mut self,
        key: &str,
        range: std::ops::RangeInclusive<f32>,
    ) -> Result<Option<f32>, Diagnostic> {
        let Some(pair) = self.get(key) else {
            return Ok(None);
        };
        let [v] = numbers::<1>(self.path, pair, "a number")?;
        if !range.contains(&v) {
            return Err(Diagnostic::at(
                self.path,
                pair.line,
                format!("\"{key}\" is {v}, expected a value in {}..={}", range.start(), range.end()),
            ));
        }
        Ok(Some(v))
    }

    /// A whole number in `range`.
    pub(crate) fn integer(
        &mut self,
        key: &str,
        range: std::ops::RangeInclusive<i64>,
    ) -> Result<Option<i64>, Diagnostic> {
        let Some(pair) = self.get(key) else { return Ok(None) };
        match pair.value.trim().parse::<i64>() {
            Ok(v) if range.contains(&v) => Ok(Some(v)),
            _ => Err(Diagnostic::at(
                self.path,
                pair.line,
                format!(
                    "\"{key}\" is {}, expected a whole number in {}..={}",
                    quote(&pair.value),
                    range.start(),
                    range.end()
                ),
            )),
        }
    }

    pub(crate) fn flag(&mut self, key: &str) -> Result<Option<bool>, Diagnostic> {
        let Some(pair) = self.get(key) else {
            return Ok(None);
        };
        match pair.value.trim() {
            "0" => Ok(Some(false)),
            "1" => Ok(Some(true)),
            v => Err(Diagnostic::at(self.path, pair.line, format!("\"{key}\" is {}, expected 0 or 1", quote(v)))),
        }
    }

    pub(crate) fn choice(&mut self, key: &str, options: &[&str]) -> Result<Option<(usize, &'b Pair)>, Diagnostic> {
        let Some(pair) = self.get(key) else {
            return Ok(None);
        };
        match options.iter().position(|o| *o == pair.value.trim()) {
            Some(i) => Ok(Some((i, pair))),
            None => Err(Diagnostic::at(
                self.path,
                pair.line,
                format!("\"{key}\" is {}, expected one of: {}", quote(&pair.value), options.join(", ")),
            )),
        }
    }

    pub(crate) fn mesh(&mut self, key: &str) -> Result<ShapeKind, Diagnostic> {
        let pair = self.require(key)?;
        if pair.value.trim() == "blob" {
            let detail = self.integer("detail", 3..=1024)?.unwrap_or(32) as u32;
            let seed = self.integer("mesh_seed", 0..=i64::from(u32::MAX))?.unwrap_or(0) as u32;
            return Ok(ShapeKind::Blob { detail, seed });
        }
        ShapeKind::from_name(pair.value.trim()).ok_or_else(|| {
            let names: Vec<_> = ShapeKind::ALL.iter().map(|k| k.name()).collect();
            Diagnostic::at(
                self.path,
                pair.line,
                format!("unknown mesh {}, expected one of: {}, blob", quote(&pair.value), names.join(", ")),
            )
        })
    }

    /// Warnings for keys this class does not know, and for keys given twice.
    pub(crate) fn leftovers(&self) -> Vec<Diagnostic> {
        // Whether a later pair has the same key: by comparing with every later
        // pair in a short block, through a map of each key's last pair in a long
        // one, so that a block of N pairs is checked in linear time.
        let pairs = &self.block.pairs;
        let last: Option<HashMap<&str, usize>> =
            (pairs.len() > 32).then(|| pairs.iter().enumerate().map(|(i, p)| (p.key.as_str(), i)).collect());
        let repeated = |i: usize, key: &str| match &last {
            Some(last) => last.get(key).is_some_and(|&j| j > i),
            None => pairs[i + 1..].iter().any(|p| p.key == key),
        };
        let mut out = Vec::new();
        for (i, pair) in pairs.iter().enumerate() {
            if repeated(i, &pair.key) {
                out.push(Diagnostic::at(
                    self.path,
                    pair.line,
                    format!("{} is given again later in this block; the last one is used", quote(&pair.key)),
                ));
            } else if !self.used[i] && pair.key != "classname" {
                out.push(Diagnostic::at(
                    self.path,
                    pair.line,
                    format!("unknown key {} in {} block (ignored)", quote(&pair.key), self.class),
                ));
            }
        }
        out
    }
}

/// Parse exactly `N` finite numbers from a pair's value.
pub(crate) fn numbers<const N: usize>(path: &Path, pair: &Pair, what: &str) -> Result<[f32; N], Diagnostic> {
    let bad = |detail: String| Diagnostic::at(path, pair.line, format!("\"{}\": {detail}, expected {what}", pair.key));
    let mut out = [0.0; N];
    let mut count = 0;
    for word in pair.value.split_whitespace() {
        let v: f32 = word.parse().map_err(|_| bad(format!("bad number {}", quote(word))))?;
        if !v.is_finite() {
            return Err(bad(format!("{} is not a finite number", quote(word))));
        }
        if count < N {
            out[count] = v;
        }
        count += 1;
    }
    if count != N {
        return Err(bad(format!("found {count} numbers")));
    }
    Ok(out)
}
