//! Neighbour search: a uniform cell grid filled by counting sort, then a CSR list
//! of the neighbours of every particle within a radius. Built in parallel over
//! fixed chunks of particles and concatenated in order, so the list (and every
//! sum over it) is the same whatever the number of threads.

use super::resolution::Scales;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// Cells of side `cell_size` covering a bounding box; particles sorted by cell.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct CellGrid {
    pub origin: Vec2,
    pub cell_size: Real,
    pub nx: usize,
    pub ny: usize,
    /// `cell_start[c]..cell_start[c + 1]` indexes `sorted` for cell c.
    pub cell_start: Vec<u32>,
    /// Particle indices ordered by cell, increasing index within a cell.
    pub sorted: Vec<u32>,
}

impl CellGrid {
    pub fn build(positions: &[Vec2], cell_size: Real) -> Self {
        assert!(cell_size > 0.0);
        if positions.is_empty() {
            return Self {
                origin: Vec2::zeros(),
                cell_size,
                nx: 1,
                ny: 1,
                cell_start: vec![0, 0],
                sorted: vec![],
            };
        }
        let (mut lo, mut hi) = (positions[0], positions[0]);
        for p in positions {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let origin = lo - Vec2::new(cell_size, cell_size);
        let nx = (((hi.x - origin.x) / cell_size).floor() as usize + 2).max(1);
        let ny = (((hi.y - origin.y) / cell_size).floor() as usize + 2).max(1);
        let cell_of: Vec<u32> = positions
            .par_iter()
            .map(|p| {
                let cx = ((p.x - origin.x) / cell_size) as usize;
                let cy = ((p.y - origin.y) / cell_size) as usize;
                (cy.min(ny - 1) * nx + cx.min(nx - 1)) as u32
            })
            .collect();
        let mut cell_start = vec![0u32; nx * ny + 1];
        for &c in &cell_of {
            cell_start[c as usize + 1] += 1;
        }
        for c in 0..nx * ny {
            cell_start[c + 1] += cell_start[c];
        }
        let mut fill = cell_start.clone();
        let mut sorted = vec![0u32; positions.len()];
        for (i, &c) in cell_of.iter().enumerate() {
            sorted[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        Self {
            origin,
            cell_size,
            nx,
            ny,
            cell_start,
            sorted,
        }
    }

    /// Cell coordinates of a point, clamped to the grid.
    #[inline]
    pub fn cell_coords(&self, p: Vec2) -> (isize, isize) {
        (
            ((p.x - self.origin.x) / self.cell_size).floor() as isize,
            ((p.y - self.origin.y) / self.cell_size).floor() as isize,
        )
    }

    /// The cell of a point, clamped to the grid (as the particles were filed).
    #[inline]
    pub fn clamped_cell(&self, p: Vec2) -> (usize, usize) {
        let (cx, cy) = self.cell_coords(p);
        (
            (cx.max(0) as usize).min(self.nx - 1),
            (cy.max(0) as usize).min(self.ny - 1),
        )
    }

    /// For every cell, the largest `value(j)` over the particles j in the cells within
    /// `reach` cells of it (0 where there is none): a separable running maximum.
    pub fn dilated_max(&self, reach: isize, value: impl Fn(usize) -> Real + Sync) -> Vec<Real> {
        // rows in parallel (a step of the shipped wedge dilates 48 000 cells 4 out: a
        // millisecond on one thread, against 7 ms for its whole list); a maximum has no
        // order, so the result is the same on any number of threads
        let (nx, ny) = (self.nx, self.ny);
        let mut own = vec![0.0; nx * ny];
        own.par_iter_mut().enumerate().for_each(|(c, m)| {
            for &j in &self.sorted[self.cell_start[c] as usize..self.cell_start[c + 1] as usize] {
                *m = Real::max(*m, value(j as usize));
            }
        });
        let r = reach.max(0) as usize;
        let mut rows = vec![0.0; nx * ny];
        rows.par_chunks_mut(nx).enumerate().for_each(|(y, row)| {
            let own = &own[y * nx..(y + 1) * nx];
            for (x, v) in row.iter_mut().enumerate() {
                let (a, b) = (x.saturating_sub(r), (x + r).min(nx - 1));
                *v = own[a..=b].iter().fold(0.0, |m: Real, v| m.max(*v));
            }
        });
        let mut out = vec![0.0; nx * ny];
        out.par_chunks_mut(nx).enumerate().for_each(|(y, row)| {
            let (a, b) = (y.saturating_sub(r), (y + r).min(ny - 1));
            for (x, v) in row.iter_mut().enumerate() {
                *v = (a..=b).fold(0.0, |m: Real, yy| m.max(rows[yy * nx + x]));
            }
        });
        out
    }

    /// Call `f(j)` for every particle in the cells within `reach` cells of `p`.
    #[inline]
    pub fn for_each_near(&self, p: Vec2, reach: isize, mut f: impl FnMut(usize)) {
        let (cx, cy) = self.cell_coords(p);
        for y in (cy - reach).max(0)..=(cy + reach).min(self.ny as isize - 1) {
            let row = y as usize * self.nx;
            let x0 = (cx - reach).max(0) as usize;
            let x1 = (cx + reach).min(self.nx as isize - 1);
            if x1 < x0 as isize {
                continue;
            }
            let a = self.cell_start[row + x0] as usize;
            let b = self.cell_start[row + x1 as usize + 1] as usize;
            for &j in &self.sorted[a..b] {
                f(j as usize);
            }
        }
    }
}

/// Compressed-sparse-row neighbour list: `indices[offsets[i]..offsets[i + 1]]` are
/// the neighbours j != i of particle i with |x_j - x_i| < radius.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct NeighborList {
    pub radius: Real,
    pub offsets: Vec<u32>,
    pub indices: Vec<u32>,
    pub grid: CellGrid,
}

const CHUNK: usize = 1024;

impl NeighborList {
    pub fn build(positions: &[Vec2], radius: Real) -> Self {
        Self::build_into(positions, radius, Vec::new())
    }

    /// [`Self::build`] written into `pairs` (a buffer to reuse: its capacity is kept).
    fn build_into(positions: &[Vec2], radius: Real, pairs: Vec<u32>) -> Self {
        // cells of half the radius, searched two out: 25 cells of (r/2)² hold 6.25 r² of
        // candidates against 9 r² for 9 cells of side r
        let grid = CellGrid::build(positions, 0.5 * radius);
        let r2 = radius * radius;
        Self::from_rows(positions.len(), grid, radius, pairs, |i, grid, idx| {
            let xi = positions[i];
            grid.for_each_near(xi, 2, |j| {
                if j != i && (positions[j] - xi).norm_squared() < r2 {
                    idx.push(j as u32);
                }
            });
        })
    }

    /// With multi-resolution scales: the neighbours j of i with |x_j - x_i| < radius
    /// s_ij (the pair radius of `resolution`, symmetric). The cells are those of the
    /// finest radius; a particle searches as many cells out as its largest pair radius
    /// needs. Uniform scales give [`Self::build`]'s list.
    pub fn build_scaled(positions: &[Vec2], radius: Real, scales: Scales) -> Self {
        Self::build_scaled_into(positions, radius, scales, Vec::new())
    }

    /// [`Self::build_scaled`] written into `pairs` (a buffer to reuse: its capacity is
    /// kept).
    pub fn build_scaled_into(
        positions: &[Vec2],
        radius: Real,
        scales: Scales,
        pairs: Vec<u32>,
    ) -> Self {
        if scales.is_uniform() {
            return Self::build_into(positions, radius, pairs);
        }
        let (s_min, s_max) = scales.range();
        let cell = radius * s_min;
        let grid = CellGrid::build(positions, cell);
        // the largest scale a partner of a particle in each cell can have: a pair is at
        // most s_max radius apart, so its partner lies within `far` cells. A fine
        // particle away from the jump then searches one cell out, not two (9 cells
        // instead of 25), and finds the same neighbours in the same order.
        let far = (s_max * radius / cell - 1e-9).ceil() as isize;
        let partner_scale = grid.dilated_max(far, |j| scales.of(j));
        Self::from_rows(positions.len(), grid, radius, pairs, |i, grid, idx| {
            let xi = positions[i];
            let (cx, cy) = grid.clamped_cell(xi);
            let s_near = partner_scale[cy * grid.nx + cx];
            let s_i = scales.of(i);
            let reach = (0.5 * (s_i + s_near) * radius / cell - 1e-9).ceil() as isize;
            // a row whose partners within reach are all of the finest level (over half of
            // the shipped wedge's particles) has one pair radius: no scale to look up
            let uniform = s_i == s_min && s_near == s_min;
            let r_row = radius * s_min;
            grid.for_each_near(xi, reach.max(1), |j| {
                let rj = if uniform {
                    r_row
                } else {
                    radius * scales.pair(i, j).0
                };
                if j != i && (positions[j] - xi).norm_squared() < rj * rj {
                    idx.push(j as u32);
                }
            });
        })
    }

    /// The list whose row i `row(i, grid, out)` appends, built over fixed chunks in
    /// parallel and appended in order, a wave of chunks at a time: the next wave is
    /// computed while the last one is appended, so the chunks of the whole list are never
    /// alive beside it (they were, with the list and the last step's, the memory peak of
    /// a step: 76 of 150 MB at 160k particles). The pairs go into `pairs`, cleared.
    fn from_rows(
        n: usize,
        grid: CellGrid,
        radius: Real,
        mut indices: Vec<u32>,
        row: impl Fn(usize, &CellGrid, &mut Vec<u32>) + Sync,
    ) -> Self {
        indices.clear();
        let per_row = if n > 0 {
            indices.capacity().div_ceil(n)
        } else {
            0
        };
        let chunk = |c: usize| -> (Vec<u32>, Vec<u32>) {
            let rows = c * CHUNK..((c + 1) * CHUNK).min(n);
            let mut counts = Vec::with_capacity(rows.len());
            let mut idx = Vec::with_capacity(rows.len() * (per_row + per_row / 8).max(24));
            for i in rows {
                let before = idx.len();
                row(i, &grid, &mut idx);
                counts.push((idx.len() - before) as u32);
            }
            (counts, idx)
        };
        let chunks = n.div_ceil(CHUNK);
        let wave = 8 * rayon::current_num_threads().max(1);
        let compute = |first: usize| -> Vec<(Vec<u32>, Vec<u32>)> {
            (first..(first + wave).min(chunks))
                .into_par_iter()
                .map(chunk)
                .collect()
        };
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0u32);
        let mut pending = compute(0);
        let mut first = 0;
        while !pending.is_empty() {
            first += wave;
            let append = || {
                for (counts, idx) in &pending {
                    for c in counts {
                        offsets.push(offsets.last().unwrap() + c);
                    }
                    indices.extend_from_slice(idx);
                }
            };
            let (next, ()) = rayon::join(|| compute(first), append);
            pending = next;
        }
        Self {
            radius,
            offsets,
            indices,
            grid,
        }
    }

    #[inline]
    pub fn of(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The buffer of the pairs, for the next list to reuse.
    pub fn into_pairs(self) -> Vec<u32> {
        self.indices
    }

    /// Total number of (i, j) pairs stored.
    pub fn pair_count(&self) -> usize {
        self.indices.len()
    }
}
