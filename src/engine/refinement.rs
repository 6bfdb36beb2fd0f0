//! The multi-resolution layout (`case.refinement`): the fluid lattice of spacing l0 is
//! merged, 2 × 2 sites at a time, into particles of spacing 2 l0 wherever the load is
//! not decided, and with `"auto"` those, 2 × 2 at a time, into particles of 4 l0 farther
//! out.
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
//!
//! A third level (`far`): four coarse cells of one 4 l0 square, anchored at the same
//! point, become one particle of scale 4 at its centre when the square touches no far
//! box and every 2 l0 cell within [`far_clearance`] cells of it is a coarse cell. So a
//! particle of 4 l0 has only 2 l0 particles within its reach: none of l0 (a pair of
//! spacings 1 and 4 is not a jump the operators were checked across), no wall or free
//! surface (those keep their finer rows, as above).

pub use crate::case::layout::{
    far_boxes, far_clearance, fine_boxes, unsupported_by_multi_resolution, FineBox, AUTO_MARGIN,
    FAR_MARGIN,
};
use crate::math::{Real, Vec2};
use std::collections::{HashMap, HashSet};

/// Where the layout may go to 4 l0: outside `boxes`, for neighbour lists of `radius`
/// (in spacings l0, the larger of r_e and the Laplacian's).
#[derive(Debug, Clone, Copy)]
pub struct FarLevel<'a> {
    pub boxes: &'a [FineBox],
    pub radius: Real,
}

/// Merge the lattice sites `(position, velocity)` of `pitch` (columns l0 apart, rows l0
/// or a little less, `case::layout::block_rows`) into coarse cells outside `boxes`, and
/// those into squares of four cells outside the `far` boxes (module docs): positions,
/// velocities and scales (1, 2 or 4).
pub fn coarsen(
    sites: Vec<(Vec2, Vec2)>,
    pitch: Vec2,
    boxes: &[FineBox],
    far: Option<FarLevel>,
) -> (Vec<Vec2>, Vec<Vec2>, Vec<Real>) {
    let Some(&(first, _)) = sites.first() else {
        return (Vec::new(), Vec::new(), Vec::new());
    };
    let cell = 2.0 * pitch;
    let anchor = first - 0.5 * pitch;
    let key = |p: Vec2| {
        let q = (p - anchor).component_div(&cell);
        (q.x.floor() as i64, q.y.floor() as i64)
    };
    // the sites of each cell that sit exactly on the anchored lattice
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (k, (p, _)) in sites.iter().enumerate() {
        let q = (p - anchor).component_div(&pitch) - Vec2::repeat(0.5);
        if (q.x - q.x.round()).abs() < 1e-6 && (q.y - q.y.round()).abs() < 1e-6 {
            cells.entry(key(*p)).or_default().push(k);
        }
    }
    let mut merged = vec![false; sites.len()];
    let mut coarse: Cells = Vec::new();
    for (&(cx, cy), members) in &cells {
        let lo = anchor + Vec2::new(cx as Real, cy as Real).component_mul(&cell);
        let hi = lo + cell;
        if members.len() != 4 || boxes.iter().any(|b| b.touches_cell(lo, hi)) {
            continue;
        }
        let velocity = members.iter().map(|&k| sites[k].1).sum::<Vec2>() / 4.0;
        for &k in members {
            merged[k] = true;
        }
        coarse.push(((cx, cy), velocity));
    }
    coarse.sort_by_key(|&((cx, cy), _)| (cy, cx));
    let (coarse, coarser) = match far {
        Some(far) => merge_far(coarse, anchor, cell, far),
        None => (coarse, Vec::new()),
    };
    // fine sites in their original order, then coarse cells row by row, then squares
    let (mut pos, mut vel, mut scale) = (Vec::new(), Vec::new(), Vec::new());
    for (k, (p, v)) in sites.into_iter().enumerate() {
        if !merged[k] {
            pos.push(p);
            vel.push(v);
            scale.push(1.0);
        }
    }
    for (level, cells) in [(1.0, coarse), (2.0, coarser)] {
        for ((cx, cy), v) in cells {
            let centre = (Vec2::new(cx as Real, cy as Real) + Vec2::repeat(0.5))
                .component_mul(&(level * cell));
            pos.push(anchor + centre);
            vel.push(v);
            scale.push(2.0 * level);
        }
    }
    (pos, vel, scale)
}

/// Cells of one level: the key (column, row) of each from the anchor, and its velocity.
type Cells = Vec<((i64, i64), Vec2)>;

/// The coarse cells `coarse` (keys in cells of `cell` = 2 pitch from `anchor`, row by row)
/// merged four at a time into 4 l0 squares where `far` allows (module docs): the cells
/// left, row by row, and the squares (keys in 4 l0), row by row.
fn merge_far(coarse: Cells, anchor: Vec2, cell: Vec2, far: FarLevel) -> (Cells, Cells) {
    let present: HashSet<(i64, i64)> = coarse.iter().map(|c| c.0).collect();
    let clear = far_clearance(far.radius);
    let mut squares: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (k, ((cx, cy), _)) in coarse.iter().enumerate() {
        squares
            .entry((cx.div_euclid(2), cy.div_euclid(2)))
            .or_default()
            .push(k);
    }
    let mut merged = vec![false; coarse.len()];
    let mut coarser: Cells = Vec::new();
    for (&(sx, sy), members) in &squares {
        let lo = anchor + Vec2::new(sx as Real, sy as Real).component_mul(&(2.0 * cell));
        let hi = lo + 2.0 * cell;
        if members.len() != 4 || far.boxes.iter().any(|b| b.touches_cell(lo, hi)) {
            continue;
        }
        let (x0, y0) = (2 * sx - clear, 2 * sy - clear);
        let (x1, y1) = (2 * sx + 1 + clear, 2 * sy + 1 + clear);
        if !(y0..=y1).all(|y| (x0..=x1).all(|x| present.contains(&(x, y)))) {
            continue;
        }
        let velocity = members.iter().map(|&k| coarse[k].1).sum::<Vec2>() / 4.0;
        for &k in members {
            merged[k] = true;
        }
        coarser.push(((sx, sy), velocity));
    }
    let left: Cells = coarse
        .into_iter()
        .zip(merged)
        .filter_map(|(c, m)| (!m).then_some(c))
        .collect();
    coarser.sort_by_key(|&((cx, cy), _)| (cy, cx));
    (left, coarser)
}
