//! Depression filling, D8 flow directions and flow accumulation on a regular grid.
//!
//! # Algorithm
//!
//! * **Priority-Flood** (Barnes, Lehman & Mulla 2014, "Priority-Flood: An optimal
//!   depression-filling and watershed-labeling algorithm for digital elevation models",
//!   *Computers & Geosciences* 62, Algorithm 2 "improved priority-flood"): the outlets (grid edge,
//!   sea) seed a min-priority queue; cells are popped lowest first and each unvisited neighbour is
//!   raised to at least the popped cell's level. Neighbours that are raised go to a plain FIFO
//!   "pit" queue, which is drained before the priority queue, so the filled surface of a
//!   depression is exactly flat (every post of it has the same `f32`, its spill height).
//!   Ties in the priority queue break on the cell index, so the result is deterministic.
//! * **Flow directions**: D8 steepest descent (O'Callaghan & Mark 1984, "The extraction of
//!   drainage networks from digital elevation data", *CVGIP* 28): each cell drains to the
//!   neighbour with the largest drop per metre on the filled surface. Cells with no lower
//!   neighbour (flats, filled depressions) drain to the neighbour that flooded them, which leads
//!   across the flat to its spill point along a breadth-first tree. Every receiver was popped
//!   before its donor, so the pop order is a topological order of the drainage graph and the
//!   graph has no cycle.
//! * **Flow accumulation**: number of cells draining through each cell (itself included),
//!   summed donor to receiver in reverse pop order, in exact integers.
//!
//! # Limits
//!
//! D8 routes each cell to a single receiver (no dispersion), so flow paths are quantised to
//! 45 degrees; paths across flats are breadth-first trees, straight rather than meandering.

use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// Receiver of an outlet (a cell that drains off the grid).
pub(crate) const NO_RECEIVER: u32 = u32::MAX;

/// Neighbour offsets `(dx, dy)`, 4-neighbours first, then diagonals.
pub(crate) const NEIGHBOURS: [(i64, i64); 8] = [
    (1, 0),
    (0, 1),
    (-1, 0),
    (0, -1),
    (1, 1),
    (-1, 1),
    (-1, -1),
    (1, -1),
];

/// A rectangular grid of `nx * ny` cells, row-major (`idx = y * nx + x`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dims {
    pub nx: usize,
    pub ny: usize,
}

impl Dims {
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.nx * self.ny
    }

    /// The neighbour of `idx` at offset `(dx, dy)`, if inside the grid.
    #[inline]
    pub(crate) fn offset(&self, idx: usize, dx: i64, dy: i64) -> Option<usize> {
        let x = (idx % self.nx) as i64 + dx;
        let y = (idx / self.nx) as i64 + dy;
        if x < 0 || y < 0 || x >= self.nx as i64 || y >= self.ny as i64 {
            None
        } else {
            Some(y as usize * self.nx + x as usize)
        }
    }

    /// True for cells on the outer ring of the grid.
    #[inline]
    pub(crate) fn is_edge(&self, idx: usize) -> bool {
        let x = idx % self.nx;
        let y = idx / self.nx;
        x == 0 || y == 0 || x + 1 == self.nx || y + 1 == self.ny
    }
}

/// Maps an `f32` to a `u32` whose unsigned order is the float's total order.
#[inline]
fn ordered_bits(v: f32) -> u32 {
    let b = v.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Result of a priority flood.
pub(crate) struct Flood {
    /// Depression-filled heights (>= the input everywhere; flat over each filled depression).
    pub filled: Vec<f32>,
    /// Receiver of each cell (`NO_RECEIVER` for outlets and cells never reached).
    pub receiver: Vec<u32>,
    /// Cells in the order they were popped: every receiver comes before its donors.
    pub order: Vec<u32>,
}

/// Priority-Flood depression filling from `outlets`, then D8 receivers on the filled surface
/// (D4 when `connectivity` is 4: flooding and receivers use the four edge neighbours only).
///
/// `cell_dx` and `cell_dy` are the cell sizes in metres (used for drop per metre).
///
/// With `jitter_seed`, each (cell, direction) slope is multiplied by a fixed pseudo-random factor
/// in `[0.7, 1.3)` before the steepest one is chosen: a randomised D8 that lets flow paths wander
/// and merge on planar slopes instead of running in parallel lines.
pub(crate) fn priority_flood(
    height: &[f32],
    dims: Dims,
    outlets: &[u32],
    cell_dx: f64,
    cell_dy: f64,
    jitter_seed: Option<u64>,
    connectivity: usize,
) -> Flood {
    let neighbours = &NEIGHBOURS[..connectivity.clamp(4, 8)];
    let n = dims.len();
    let mut filled = height.to_vec();
    let mut receiver = vec![NO_RECEIVER; n];
    let mut closed = vec![false; n];
    let mut order = Vec::with_capacity(n);
    // Key: (level << 32 | tie-break, index). Without a jitter seed the tie-break is the index
    // and raised cells go to the FIFO pit queue (Barnes' improvement); with one, raised cells
    // stay in the priority queue with a random tie-break, so flats are crossed by random
    // spanning trees (invasion percolation) rather than by straight breadth-first rays.
    let mut open: BinaryHeap<Reverse<u64>> = BinaryHeap::with_capacity(4 * (dims.nx + dims.ny));
    let mut pit: VecDeque<u32> = VecDeque::new();
    // With jitter the low 32 bits hold 12 random bits above a 20-bit index (jittered grids are
    // coarse: fewer than 2^20 cells); without, the index itself.
    let jitter_seed = jitter_seed.filter(|_| n < (1 << 20));
    let index_mask: u64 = if jitter_seed.is_some() {
        (1 << 20) - 1
    } else {
        u64::from(u32::MAX)
    };
    let key = |level: f32, i: usize| -> u64 {
        let tie = match jitter_seed {
            Some(seed) => {
                ((crate::noise::mix64(seed ^ 0xA5A5_5A5A ^ i as u64) >> 52) << 20) | i as u64
            }
            None => i as u64,
        };
        (u64::from(ordered_bits(level)) << 32) | tie
    };
    for &o in outlets {
        let o = o as usize;
        if o < n && !closed[o] {
            closed[o] = true;
            open.push(Reverse(key(filled[o], o)));
        }
    }
    let (nx, ny) = (dims.nx as i64, dims.ny as i64);
    loop {
        let c = if let Some(c) = pit.pop_front() {
            c as usize
        } else if let Some(Reverse(k)) = open.pop() {
            (k & index_mask) as usize
        } else {
            break;
        };
        order.push(c as u32);
        let level = filled[c];
        let (cx, cy) = ((c % dims.nx) as i64, (c / dims.nx) as i64);
        for &(dx, dy) in neighbours {
            let (x, y) = (cx + dx, cy + dy);
            if x < 0 || y < 0 || x >= nx || y >= ny {
                continue;
            }
            let nb = (y * nx + x) as usize;
            if closed[nb] {
                continue;
            }
            closed[nb] = true;
            receiver[nb] = c as u32;
            if filled[nb] <= level {
                filled[nb] = level;
                if jitter_seed.is_none() {
                    pit.push_back(nb as u32);
                    continue;
                }
            }
            open.push(Reverse(key(filled[nb], nb)));
        }
    }
    steepest_descent(
        &filled,
        dims,
        cell_dx,
        cell_dy,
        jitter_seed,
        neighbours,
        &mut receiver,
    );
    Flood {
        filled,
        receiver,
        order,
    }
}

/// Replaces each flood receiver by the D8 steepest-descent neighbour where one is strictly lower.
fn steepest_descent(
    filled: &[f32],
    dims: Dims,
    cell_dx: f64,
    cell_dy: f64,
    jitter_seed: Option<u64>,
    neighbours: &[(i64, i64)],
    receiver: &mut [u32],
) {
    let diag = (cell_dx * cell_dx + cell_dy * cell_dy).sqrt();
    let inv_dist: [f64; 8] = [
        1.0 / cell_dx,
        1.0 / cell_dy,
        1.0 / cell_dx,
        1.0 / cell_dy,
        1.0 / diag,
        1.0 / diag,
        1.0 / diag,
        1.0 / diag,
    ];
    let nx = dims.nx;
    let ny = dims.ny;
    receiver
        .par_chunks_mut(nx)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, rec) in row.iter_mut().enumerate() {
                let c = y * nx + x;
                if *rec == NO_RECEIVER {
                    continue;
                }
                let hc = filled[c];
                let mut best = 0.0f64;
                let mut best_idx = NO_RECEIVER;
                for (k, &(dx, dy)) in neighbours.iter().enumerate() {
                    let xx = x as i64 + dx;
                    let yy = y as i64 + dy;
                    if xx < 0 || yy < 0 || xx >= nx as i64 || yy >= ny as i64 {
                        continue;
                    }
                    let nb = yy as usize * nx + xx as usize;
                    let drop = f64::from(hc) - f64::from(filled[nb]);
                    if drop > 0.0 {
                        let mut s = drop * inv_dist[k];
                        if let Some(seed) = jitter_seed {
                            let h = crate::noise::mix64(seed ^ ((c as u64) << 3 | k as u64));
                            s *= 0.7 + 0.6 * crate::noise::unit_from_hash(h);
                        }
                        if s > best {
                            best = s;
                            best_idx = nb as u32;
                        }
                    }
                }
                if best_idx != NO_RECEIVER {
                    *rec = best_idx;
                }
            }
        });
}

/// Number of cells draining through each cell, itself included.
pub(crate) fn accumulate(flood: &Flood, n: usize) -> Vec<u32> {
    let mut acc = vec![1u32; n];
    for &c in flood.order.iter().rev() {
        let r = flood.receiver[c as usize];
        if r != NO_RECEIVER {
            acc[r as usize] = acc[r as usize].saturating_add(acc[c as usize]);
        }
    }
    acc
}

/// The outer ring of a grid, as outlets.
#[cfg(test)]
pub(crate) fn edge_cells(dims: Dims) -> Vec<u32> {
    (0..dims.len())
        .filter(|&i| dims.is_edge(i))
        .map(|i| i as u32)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pit_is_filled_flat_to_its_spill_height() {
        // 5x5 bowl: rim 10, one rim cell 7 (the spill), centre 3x3 at 1..3.
        let dims = Dims { nx: 5, ny: 5 };
        let mut h = vec![10.0f32; 25];
        h[2] = 7.0; // spill on the south edge
        for y in 1..4 {
            for x in 1..4 {
                h[y * 5 + x] = (x + y) as f32 * 0.5;
            }
        }
        let f = priority_flood(&h, dims, &edge_cells(dims), 1.0, 1.0, None, 8);
        for y in 1..4 {
            for x in 1..4 {
                assert_eq!(f.filled[y * 5 + x], 7.0);
            }
        }
        assert_eq!(f.filled[0], 10.0);
        let acc = accumulate(&f, 25);
        // All nine inner cells drain through the spill cell at index 2.
        assert!(acc[2] >= 10, "acc at spill {}", acc[2]);
        // The order is topological: receivers come first.
        let mut pos = [0usize; 25];
        for (i, &c) in f.order.iter().enumerate() {
            pos[c as usize] = i;
        }
        for c in 0..25 {
            let r = f.receiver[c];
            if r != NO_RECEIVER {
                assert!(pos[r as usize] < pos[c]);
                assert!(f.filled[r as usize] <= f.filled[c]);
            }
        }
    }
}
