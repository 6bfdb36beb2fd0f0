use crate::{scratch_dir, small_tank};
use mpsfsi::case::{parse_case_value, Limits, ValidCase};
use mpsfsi::engine::Simulation;
use mpsfsi::math::Vec2;
use mpsfsi::output::snapshots::SnapshotWriter;
use mpsfsi::output::vtk::{
    parse_pvd, parse_vtu, pvd_string, vtu_string, PvdEntry, VtuFields, PARTICLES_PART, WALLS_PART,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn vtu_round_trips_points_and_point_data() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let n = 37;
    let position: Vec<Vec2> = (0..n)
        .map(|_| Vec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
        .collect();
    let velocity: Vec<Vec2> = (0..n)
        .map(|_| Vec2::new(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)))
        .collect();
    let pressure: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..1e4)).collect();
    let number_density: Vec<f64> = (0..n).map(|_| rng.random_range(5.0..7.0)).collect();
    let free_surface: Vec<bool> = (0..n).map(|i| i % 3 == 0).collect();
    let fields = VtuFields {
        position: &position,
        velocity: &velocity,
        pressure: &pressure,
        number_density: &number_density,
        n0: Some(6.5),
        free_surface: &free_surface,
        density: Some(998.2),
        spacing: Some(0.01),
        particle_spacing: None,
    };
    let grid = parse_vtu(&vtu_string(&fields, 0.125)).unwrap();
    assert_eq!(grid.points.len(), n);
    assert_eq!(grid.cells, n);
    assert_eq!(grid.time, Some(0.125));
    assert_eq!(grid.field_data["density"], 998.2);
    assert_eq!(grid.field_data["particle_spacing"], 0.01);
    assert_eq!(grid.offsets, (1..=n).collect::<Vec<_>>());
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-8 * (1.0 + b.abs());
    for i in 0..n {
        assert!(
            close(grid.points[i][0], position[i].x)
                && close(grid.points[i][1], position[i].y)
                && grid.points[i][2] == 0.0
        );
    }
    let (components, v) = &grid.point_data["velocity"];
    assert_eq!(*components, 3);
    for i in 0..n {
        assert!(
            close(v[3 * i], velocity[i].x)
                && close(v[3 * i + 1], velocity[i].y)
                && v[3 * i + 2] == 0.0
        );
    }
    let p = grid.scalar("pressure").unwrap();
    let nd = grid.scalar("number_density").unwrap();
    let ratio = grid.scalar("number_density_ratio").unwrap();
    let fs = grid.scalar("free_surface").unwrap();
    for i in 0..n {
        assert!(close(p[i], pressure[i]));
        assert!(close(nd[i], number_density[i]));
        assert!(close(ratio[i], number_density[i] / 6.5));
        assert_eq!(fs[i], if free_surface[i] { 1.0 } else { 0.0 });
    }
}

#[test]
fn the_reader_rejects_truncated_or_inconsistent_files() {
    let position = vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)];
    let zeros = vec![Vec2::zeros(); 2];
    let s = vec![0.0; 2];
    let f = vec![false; 2];
    let text = vtu_string(
        &VtuFields {
            position: &position,
            velocity: &zeros,
            pressure: &s,
            number_density: &s,
            n0: None,
            free_surface: &f,
            density: None,
            spacing: None,
            particle_spacing: None,
        },
        0.0,
    );
    assert!(parse_vtu(&text).is_ok());
    assert!(
        parse_vtu(&text[..text.len() / 2]).is_err(),
        "half a file is not a valid grid"
    );
    assert!(
        parse_vtu(&text.replace("NumberOfPoints=\"2\"", "NumberOfPoints=\"3\"")).is_err(),
        "counts must agree"
    );
    let entries = vec![
        PvdEntry {
            time: 0.5,
            file: "a.vtu".into(),
            part: PARTICLES_PART,
        },
        PvdEntry {
            time: 0.5,
            file: "b.vtu".into(),
            part: WALLS_PART,
        },
    ];
    let pvd = pvd_string(&entries);
    assert_eq!(parse_pvd(&pvd).unwrap(), entries);
    assert!(parse_pvd(&pvd[..pvd.len() - 12]).is_err());
}

#[test]
fn the_collection_is_valid_after_every_snapshot() {
    let case = parse_case_value(small_tank()).unwrap();
    let mut sim = Simulation::new(&case);
    let dir = scratch_dir("pvd-every-write");
    let mut writer = SnapshotWriter::create(&dir, Some(0.01))
        .unwrap()
        .expect("an interval makes a writer");
    let pvd = dir.join("snapshots/run.pvd");
    assert!(
        parse_pvd(&std::fs::read_to_string(&pvd).unwrap())
            .unwrap()
            .is_empty(),
        "an empty but valid index at start"
    );
    // (time, step, snapshot due?)
    let script = [
        (0.0, 0, true),
        (0.004, 8, false),
        (0.0099999999999, 20, true),
        (0.015, 30, false),
        (0.0201, 40, true),
        (0.0201, 40, false),
    ];
    let mut expected = 0;
    let mut last_file = String::new();
    for (time, step, due) in script {
        sim.time = time;
        sim.steps = step;
        writer.record(&sim).unwrap();
        if due {
            expected += 1;
            last_file = format!("step_{step:06}.vtu");
        }
        let entries = parse_pvd(&std::fs::read_to_string(&pvd).unwrap()).unwrap();
        assert_eq!(entries.len(), 2 * expected, "after t = {time}");
        let particles: Vec<_> = entries
            .iter()
            .filter(|e| e.part == PARTICLES_PART)
            .collect();
        assert_eq!(particles.len(), expected, "one particle file per snapshot");
        let last = particles.last().unwrap();
        assert_eq!(last.file, last_file);
        let walls = entries.iter().rfind(|e| e.part == WALLS_PART).unwrap();
        assert_eq!(
            walls.time, last.time,
            "walls and particles share the snapshot's time"
        );
        assert!(dir.join("snapshots").join(&walls.file).is_file());
        let grid =
            parse_vtu(&std::fs::read_to_string(dir.join("snapshots").join(&last.file)).unwrap())
                .unwrap();
        assert_eq!(grid.points.len(), sim.particle_count());
    }
    assert!(
        SnapshotWriter::create(&dir, None).unwrap().is_none(),
        "no interval, no writer"
    );
}

#[test]
fn a_run_writes_one_snapshot_per_interval_with_all_particles() {
    let case = ValidCase::new(parse_case_value(small_tank()).unwrap(), &Limits::default()).unwrap();
    let dir = scratch_dir("run-snapshots");
    let summary = mpsfsi::run::run_case(&case, &dir, &mut mpsfsi::run::Quiet).unwrap();
    assert_eq!(summary.status, mpsfsi::run::RunStatus::Succeeded);
    let entries: Vec<PvdEntry> =
        parse_pvd(&std::fs::read_to_string(dir.join("snapshots/run.pvd")).unwrap())
            .unwrap()
            .into_iter()
            .filter(|e| e.part == PARTICLES_PART)
            .collect();
    // t = 0, 0.01, ..., 0.05
    assert_eq!(entries.len(), 6, "{entries:?}");
    for (k, e) in entries.iter().enumerate() {
        assert!(
            (e.time - 0.01 * k as f64).abs() < 1e-3,
            "snapshot {k} at {}",
            e.time
        );
        let grid =
            parse_vtu(&std::fs::read_to_string(dir.join("snapshots").join(&e.file)).unwrap())
                .unwrap();
        assert_eq!(grid.points.len(), summary.particles);
        assert_eq!(grid.scalar("pressure").unwrap().len(), summary.particles);
        assert_eq!(grid.time, Some(e.time));
    }
    assert!(entries.windows(2).all(|w| w[1].time > w[0].time));
}
