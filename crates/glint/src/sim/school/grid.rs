//! A uniform grid over a school's bounds, rebuilt every step by counting sort:
//! each fish's cell, the fish per cell, their running sum (each cell's first
//! slot) and the fish in cell order. Cells are at least the view radius wide,
//! so a fish's neighbours lie in its own cell and the 26 around it; fish
//! outside the bounds count in the nearest border cell, which keeps that true
//! (clamping never moves two points further apart in cells).

use glam::{IVec3, Vec3};
use p3_maybe_rayon::prelude::*;

pub use crate::scene::school::{GridShape, MAX_GRID_CELLS as MAX_CELLS};

/// The fish sorted by cell: `order[start[c]..start[c + 1]]` are cell `c`'s
/// fish, in the order they were numbered.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Its shape.
    pub shape: GridShape,
    /// Each cell's first slot in `order`, and one past the end.
    pub start: Vec<u32>,
    /// Fish numbers, cell by cell.
    pub order: Vec<u32>,
    /// Each fish's cell.
    cell_of: Vec<u32>,
}

impl Grid {
    /// A grid of `shape` holding no fish yet.
    pub fn new(shape: GridShape) -> Self {
        let start = vec![0; shape.cells() as usize + 1];
        Self { shape, start, order: Vec::new(), cell_of: Vec::new() }
    }

    /// Sort `positions` into its cells: cells found in parallel, then
    /// counted, summed and scattered (a stable counting sort, O(n + cells)).
    pub fn rebuild(&mut self, positions: &[Vec3]) {
        let shape = self.shape;
        let cells = shape.cells() as usize;
        self.cell_of = positions.par_iter().map(|&p| shape.index(shape.coords(p))).collect();
        self.start.clear();
        self.start.resize(cells + 1, 0);
        for &c in &self.cell_of {
            self.start[c as usize + 1] += 1;
        }
        for c in 0..cells {
            self.start[c + 1] += self.start[c];
        }
        self.order.resize(positions.len(), 0);
        let mut next = self.start[..cells].to_vec();
        for (i, &c) in self.cell_of.iter().enumerate() {
            self.order[next[c as usize] as usize] = i as u32;
            next[c as usize] += 1;
        }
    }

    /// The slots of `order` for the cells around (and including) the one
    /// holding `p`: up to 9 ranges, x-runs of three cells merged into one.
    pub fn around(&self, p: Vec3) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let shape = self.shape;
        let c = shape.coords(p);
        let hi = shape.dims.as_ivec3() - 1;
        let (x0, x1) = ((c.x - 1).max(0), (c.x + 1).min(hi.x));
        (-1..=1).flat_map(move |dz| (-1..=1).map(move |dy| (dy, dz))).filter_map(move |(dy, dz)| {
            let (y, z) = (c.y + dy, c.z + dz);
            if y < 0 || z < 0 || y > hi.y || z > hi.z {
                return None;
            }
            let first = shape.index(IVec3::new(x0, y, z)) as usize;
            let last = shape.index(IVec3::new(x1, y, z)) as usize;
            Some(self.start[first] as usize..self.start[last + 1] as usize)
        })
    }

    /// Every fish `j != i` within `radius` of fish `i` (strictly closer), by
    /// the grid, in ascending order.
    pub fn neighbours(&self, positions: &[Vec3], i: usize, radius: f32) -> Vec<u32> {
        let p = positions[i];
        let mut found: Vec<u32> = self
            .around(p)
            .flat_map(|slots| self.order[slots].iter().copied())
            .filter(|&j| j as usize != i && positions[j as usize].distance_squared(p) < radius * radius)
            .collect();
        found.sort_unstable();
        found
    }
}

/// The same search by testing every pair: the grid's reference in tests.
pub fn brute_neighbours(positions: &[Vec3], i: usize, radius: f32) -> Vec<u32> {
    let p = positions[i];
    (0..positions.len() as u32)
        .filter(|&j| j as usize != i && positions[j as usize].distance_squared(p) < radius * radius)
        .collect()
}
