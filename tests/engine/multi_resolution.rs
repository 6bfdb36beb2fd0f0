//! Multi-resolution layouts (`case.refinement`): the coarsening partitions the fluid,
//! the scaled neighbour list is the brute-force one, and still water with a resolution
//! jump across its column stays still with the exact load (the issue's criteria:
//! tank load within 0.1 %, maximum speed below 1 mm/s over 2 s, net flux across the
//! jump below 0.1 % of the fine region's volume); with the automatic layout's third
//! level (4 l0) it stays as still.

use mpsfsi::case::{parse_case_str, Limits, ValidCase};
use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::engine::refinement::{coarsen, FarLevel, FineBox};
use mpsfsi::engine::resolution::Scales;
use mpsfsi::engine::Simulation;
use mpsfsi::math::Vec2;

const L0: f64 = 0.01;

/// Still water 1 m × 0.5 m at 1 cm, fine in a box that crosses the column and the
/// surface, so the jump runs both horizontally and vertically through the water.
const STILL: &str = r#"{
  "name": "still-water-with-a-jump",
  "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
  "particle_spacing": 0.01,
  "domain": { "min": [-0.1, -0.1], "max": [1.1, 0.8] },
  "fluid_blocks": [ { "polygon": [[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.0, 0.5]] } ],
  "walls": [ { "name": "tank", "polyline": [[0.0, 0.7], [0.0, 0.0], [1.0, 0.0], [1.0, 0.7]] } ],
  "refinement": { "fine": [ { "min": [0.3, 0.2], "max": [0.7, 0.6] } ] },
  "time": { "end": 2.0, "cfl": 0.2, "max_dt": 0.0005 },
  "output": { "load_interval": 0.01 }
}"#;

/// Still water 2 m × 0.6 m at 1 cm with the automatic layout: a box moving up at
/// 0.1 mm/s in the air above the water's middle makes l0 around it, 2 l0 beyond and
/// 4 l0 in the two far corners of the water.
const STILL_THREE_LEVELS: &str = r#"{
  "name": "still-water-three-levels",
  "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
  "particle_spacing": 0.01,
  "domain": { "min": [-0.1, -0.1], "max": [2.1, 1.0] },
  "fluid_blocks": [ { "polygon": [[0.0, 0.0], [2.0, 0.0], [2.0, 0.6], [0.0, 0.6]] } ],
  "walls": [ { "name": "tank", "polyline": [[0.0, 0.8], [0.0, 0.0], [2.0, 0.0], [2.0, 0.8]] } ],
  "bodies": [ {
    "name": "box",
    "polygon": [[-0.1, 0.0], [0.1, 0.0], [0.1, 0.05], [-0.1, 0.05]],
    "position": [1.0, 0.65],
    "motion": { "type": "prescribed", "velocity": [0.0, 1.0e-4] }
  } ],
  "time": { "end": 1.0, "cfl": 0.2, "max_dt": 0.0005 },
  "output": { "load_interval": 0.01 }
}"#;

fn lattice(nx: usize, ny: usize) -> Vec<(Vec2, Vec2)> {
    let mut sites = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let p = Vec2::new((i as f64 + 0.5) * L0, (j as f64 + 0.5) * L0);
            sites.push((p, Vec2::new(0.1, 0.0)));
        }
    }
    sites
}

/// `p` is the centre of a block of `sites` × `sites` lattice sites from the origin: each
/// coordinate is (k + 1/2) `sites` l0 for a whole k.
fn assert_centred(p: Vec2, sites: i64) {
    for c in [p.x, p.y] {
        let k = c / L0;
        assert!(
            (k - k.round()).abs() < 1e-9 && k.round() as i64 % sites == sites / 2,
            "{p:?} is no centre of {sites} x {sites} sites"
        );
    }
}

#[test]
fn coarsening_partitions_the_fluid_and_keeps_the_fine_boxes_fine() {
    let fine = FineBox {
        min: Vec2::new(0.105, 0.0),
        max: Vec2::new(0.2, 0.1),
    };
    // 41 × 30 sites: the last column has no partner, so it stays fine
    let sites = lattice(41, 30);
    let (pos, vel, scale) = coarsen(sites, Vec2::repeat(L0), &[fine], None);
    // the volume (sum of s²) is the number of sites: nothing lost, nothing doubled
    let volume: f64 = scale.iter().map(|s| s * s).sum();
    assert_eq!(volume, (41 * 30) as f64);
    let coarse: Vec<usize> = (0..pos.len()).filter(|&i| scale[i] == 2.0).collect();
    assert!(coarse.len() > 200, "{} coarse particles", coarse.len());
    for &i in &coarse {
        let p = pos[i];
        // a coarse particle's cell [p - l0, p + l0]² touches no fine box
        assert!(
            p.x + L0 <= fine.min.x + 1e-9
                || p.x - L0 >= fine.max.x - 1e-9
                || p.y - L0 >= fine.max.y - 1e-9,
            "coarse particle at {p:?} inside the fine box"
        );
        // centred on 2 x 2 sites of the lattice: at odd multiples of l0
        assert_centred(p, 2);
        assert!((vel[i] - Vec2::new(0.1, 0.0)).norm() < 1e-12);
    }
    // the unpaired last column and the fine box's cells stay fine
    assert!(pos
        .iter()
        .zip(&scale)
        .any(|(p, &s)| s == 1.0 && (p.x - 40.5 * L0).abs() < 1e-9));
    let inside_box = pos
        .iter()
        .zip(&scale)
        .filter(|(p, _)| p.x > 0.12 && p.x < 0.2 && p.y < 0.1)
        .all(|(_, &s)| s == 1.0);
    assert!(inside_box);
}

/// The third level: 4 l0 squares only outside the far box, centred on 4 × 4 sites, with
/// no l0 particle and no edge of the water within their reach (4 r_e = 10 l0 of their
/// centre), and the volume kept.
#[test]
fn a_third_level_keeps_its_reach_clear_of_finer_particles_and_of_the_edges() {
    let (nx, ny) = (120, 80);
    let fine = FineBox {
        min: Vec2::new(0.3, 0.5),
        max: Vec2::new(0.5, 0.8),
    };
    let far = FineBox {
        min: Vec2::new(0.2, 0.4),
        max: Vec2::new(0.6, 0.8),
    };
    let level = FarLevel {
        boxes: &[far],
        radius: 2.5,
    };
    let (pos, vel, scale) = coarsen(lattice(nx, ny), Vec2::repeat(L0), &[fine], Some(level));
    let volume: f64 = scale.iter().map(|s| s * s).sum();
    assert_eq!(volume, (nx * ny) as f64);
    let squares: Vec<usize> = (0..pos.len()).filter(|&i| scale[i] == 4.0).collect();
    assert!(squares.len() > 100, "{} particles of 4 l0", squares.len());
    let (w, h) = (nx as f64 * L0, ny as f64 * L0);
    let reach = 4.0 * 2.5 * L0;
    for &i in &squares {
        let p = pos[i];
        assert!(
            !far.touches_cell(p - Vec2::repeat(2.0 * L0), p + Vec2::repeat(2.0 * L0)),
            "{p:?} in the far box"
        );
        assert_centred(p, 4);
        assert!(
            p.x >= reach - 1e-9
                && p.y >= reach - 1e-9
                && w - p.x >= reach - 1e-9
                && h - p.y >= reach - 1e-9,
            "{p:?} within {reach} m of the water's edge"
        );
        for j in 0..pos.len() {
            if (pos[j] - p).norm() < reach {
                assert!(
                    scale[j] >= 2.0,
                    "an l0 particle at {:?} within reach of {p:?}",
                    pos[j]
                );
            }
        }
        assert!((vel[i] - Vec2::new(0.1, 0.0)).norm() < 1e-12);
    }
    // without the far level the same sites give the two-level layout
    let (_, _, two) = coarsen(lattice(nx, ny), Vec2::repeat(L0), &[fine], None);
    assert!(two.iter().all(|&s| s <= 2.0));
}

#[test]
fn scaled_neighbour_list_is_the_brute_force_list_of_pair_radii() {
    let (pos, _, scale) = coarsen(
        lattice(30, 30),
        Vec2::repeat(L0),
        &[FineBox {
            min: Vec2::new(0.1, 0.1),
            max: Vec2::new(0.2, 0.2),
        }],
        None,
    );
    // disorder, so distances fall on both sides of the pair radii
    let pos: Vec<Vec2> = pos
        .iter()
        .enumerate()
        .map(|(i, p)| p + Vec2::new((i as f64 * 0.37).sin(), (i as f64 * 0.71).cos()) * 0.2 * L0)
        .collect();
    let radius = 2.5 * L0;
    let scales = Scales::new(&scale, true);
    let list = NeighborList::build_scaled(&pos, radius, scales);
    for i in 0..pos.len() {
        let mut got: Vec<u32> = list.of(i).to_vec();
        got.sort_unstable();
        let want: Vec<u32> = (0..pos.len())
            .filter(|&j| {
                let rij = radius * 0.5 * (scale[i] + scale[j]);
                j != i && (pos[j] - pos[i]).norm() < rij
            })
            .map(|j| j as u32)
            .collect();
        assert_eq!(got, want, "particle {i} at {:?} (s = {})", pos[i], scale[i]);
    }
}

#[test]
fn still_water_with_a_resolution_jump_stays_still_with_the_exact_load() {
    let case = ValidCase::new(parse_case_str(STILL).unwrap(), &Limits::default()).unwrap();
    let mut sim = Simulation::new(&case);
    let s = sim.particles.scale.clone();
    assert!(s.contains(&1.0) && s.contains(&2.0), "two levels");
    let (rho, g) = (1000.0, 9.81);
    // the water's weight: Σ ρ V_i g, V_i = (s_i l0)²
    let weight: f64 = s.iter().map(|s| rho * (s * L0).powi(2) * g).sum();
    let fine_box = |p: &Vec2| p.x > 0.3 && p.x < 0.7 && p.y > 0.2;
    let fine_volume = |sim: &Simulation| -> f64 {
        (0..sim.particle_count())
            .filter(|&i| sim.particles.scale[i] == 1.0 && fine_box(&sim.particles.position[i]))
            .count() as f64
            * L0
            * L0
    };
    let fine_start = fine_volume(&sim);
    let mut max_speed: f64 = 0.0;
    let mut worst_load: f64 = 0.0;
    while sim.time < case.time.end - 1e-12 {
        let dt = sim.next_dt();
        sim.step(dt).unwrap();
        max_speed = max_speed.max(sim.max_particle_speed());
        let load = -sim.loads[0].force.y;
        worst_load = worst_load.max((load / weight - 1.0).abs());
    }
    assert_eq!(sim.stats.removed, 0);
    assert!(max_speed < 1e-3, "max speed {max_speed:.3e} m/s");
    assert!(
        worst_load < 1e-3,
        "tank load off by {:.4} %",
        100.0 * worst_load
    );
    let flux = (fine_volume(&sim) - fine_start).abs() / fine_start;
    assert!(
        flux < 1e-3,
        "net flux across the jump {:.4} %",
        100.0 * flux
    );
    println!(
        "max speed {max_speed:.2e} m/s, tank load within {:.5} %, flux {:.5} %",
        100.0 * worst_load,
        100.0 * flux
    );
}

#[test]
fn still_water_on_three_levels_stays_still_with_the_exact_load() {
    let case = ValidCase::new(
        parse_case_str(STILL_THREE_LEVELS).unwrap(),
        &Limits::default(),
    )
    .unwrap();
    let mut sim = Simulation::new(&case);
    let s = sim.particles.scale.clone();
    assert!(
        s.contains(&1.0) && s.contains(&2.0) && s.contains(&4.0),
        "three levels"
    );
    let weight: f64 = s.iter().map(|s| 1000.0 * (s * L0).powi(2) * 9.81).sum();
    let tank = sim.wall_names().iter().position(|n| n == "tank").unwrap();
    let (mut max_speed, mut worst_load): (f64, f64) = (0.0, 0.0);
    while sim.time < case.time.end - 1e-12 {
        let dt = sim.next_dt();
        sim.step(dt).unwrap();
        max_speed = max_speed.max(sim.max_particle_speed());
        let load = -sim.loads[tank].force.y;
        worst_load = worst_load.max((load / weight - 1.0).abs());
    }
    println!(
        "three levels: max speed {max_speed:.2e} m/s, tank load within {:.5} %",
        100.0 * worst_load
    );
    assert_eq!(sim.stats.removed, 0);
    assert!(max_speed < 1e-3, "max speed {max_speed:.3e} m/s");
    assert!(
        worst_load < 1e-3,
        "tank load off by {:.4} %",
        100.0 * worst_load
    );
}
