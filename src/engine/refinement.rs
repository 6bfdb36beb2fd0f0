//! The multi-resolution layout (`case.refinement`): the fluid lattice of spacing l0 is
//! merged, 2 × 2 sites at a time, into particles of spacing 2 l0 wherever the load is
//! not decided.
//!
//! A coarse cell is a 2 l0 × 2 l0 square of the lattice anchored at the first
//! particle. It becomes one particle of scale 2 at its centre, with the mean velocity of
//! its four sites, when all four sites hold a particle (the cell is inside the fluid and
//! clear of every surface, so walls and free surfaces keep their fine rows wherever a
//! cell is cut) and the cell touches no fine box. The two lattices then share their
//! cell boundaries: a coarse particle sits l0 from the edge of its cell as a fine one
//! sits l0/2 from its own, so the virtual wall lattice of either (first row half a
//! spacing behind the surface) continues it. The fine boxes come from the case
//! ([`crate::case::layout`]).

pub use crate::case::layout::{fine_boxes, unsupported_by_multi_resolution, FineBox, AUTO_MARGIN};
use crate::math::{Real, Vec2};
use std::collections::HashMap;

/// Merge the lattice sites `(position, velocity)` of spacing `l0` into coarse cells
/// outside `boxes` (module docs): positions, velocities and scales (1 or 2).
pub fn coarsen(
    sites: Vec<(Vec2, Vec2)>,
    l0: Real,
    boxes: &[FineBox],
) -> (Vec<Vec2>, Vec<Vec2>, Vec<Real>) {
    let Some(&(first, _)) = sites.first() else {
        return (Vec::new(), Vec::new(), Vec::new());
    };
    let cell = 2.0 * l0;
    let anchor = first - Vec2::repeat(0.5 * l0);
    let key = |p: Vec2| {
        let q = (p - anchor) / cell;
        (q.x.floor() as i64, q.y.floor() as i64)
    };
    // the sites of each cell that sit exactly on the anchored lattice
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (k, (p, _)) in sites.iter().enumerate() {
        let q = (p - anchor) / l0 - Vec2::repeat(0.5);
        if (q.x - q.x.round()).abs() < 1e-6 && (q.y - q.y.round()).abs() < 1e-6 {
            cells.entry(key(*p)).or_default().push(k);
        }
    }
    let mut merged = vec![false; sites.len()];
    let mut coarse: Vec<((i64, i64), Vec2)> = Vec::new();
    for (&(cx, cy), members) in &cells {
        let lo = anchor + Vec2::new(cx as Real, cy as Real) * cell;
        let hi = lo + Vec2::repeat(cell);
        if members.len() != 4 || boxes.iter().any(|b| b.touches_cell(lo, hi)) {
            continue;
        }
        let velocity = members.iter().map(|&k| sites[k].1).sum::<Vec2>() / 4.0;
        for &k in members {
            merged[k] = true;
        }
        coarse.push(((cx, cy), velocity));
    }
    // fine sites in their original order, then coarse cells row by row
    coarse.sort_by_key(|&((cx, cy), _)| (cy, cx));
    let (mut pos, mut vel, mut scale) = (Vec::new(), Vec::new(), Vec::new());
    for (k, (p, v)) in sites.into_iter().enumerate() {
        if !merged[k] {
            pos.push(p);
            vel.push(v);
            scale.push(1.0);
        }
    }
    for ((cx, cy), v) in coarse {
        pos.push(anchor + (Vec2::new(cx as Real, cy as Real) + Vec2::repeat(0.5)) * cell);
        vel.push(v);
        scale.push(2.0);
    }
    (pos, vel, scale)
}
