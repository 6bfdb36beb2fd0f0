//! The cell-grid CSR neighbour list equals brute force on seeded random clouds.

use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::math::Vec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn neighbour_search_equals_brute_force() {
    for (seed, n, radius) in [
        (1u64, 500usize, 0.05),
        (2, 2000, 0.021),
        (3, 3000, 0.1),
        (4, 50, 0.3),
    ] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let x: Vec<Vec2> = (0..n)
            .map(|_| Vec2::new(rng.random_range(-0.3..0.7), rng.random_range(0.0..0.5)))
            .collect();
        let list = NeighborList::build(&x, radius);
        assert_eq!(list.len(), n);
        for i in 0..n {
            let mut got: Vec<u32> = list.of(i).to_vec();
            got.sort_unstable();
            let want: Vec<u32> = (0..n)
                .filter(|&j| j != i && (x[j] - x[i]).norm() < radius)
                .map(|j| j as u32)
                .collect();
            assert_eq!(got, want, "seed {seed}, particle {i}");
        }
    }
}

#[test]
fn empty_and_single_particle_clouds() {
    let list = NeighborList::build(&[], 0.1);
    assert!(list.is_empty());
    let list = NeighborList::build(&[Vec2::new(1.0, 2.0)], 0.1);
    assert_eq!(list.of(0).len(), 0);
}
