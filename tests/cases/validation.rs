//! One test per rejection class of `case::validate`.

use crate::{assert_error, base_case, base_value};
use mpsfsi::case::{parse_case_value, validate, Case, CaseError, Limits};
use serde_json::{json, Value};

/// Validate the base case after `edit` on its JSON; the error it must give.
#[track_caller]
fn rejected_json(edit: impl FnOnce(&mut Value)) -> CaseError {
    let mut v = base_value();
    edit(&mut v);
    let case = parse_case_value(v).expect("the edited case still parses");
    validate(&case, &Limits::default()).expect_err("the edited case must be rejected")
}

/// Validate the base case after `edit` on the Rust value (for what JSON cannot say).
#[track_caller]
fn rejected(edit: impl FnOnce(&mut Case)) -> CaseError {
    let mut case = base_case();
    edit(&mut case);
    validate(&case, &Limits::default()).expect_err("the edited case must be rejected")
}

#[test]
fn base_case_is_valid() {
    validate(&base_case(), &Limits::default()).expect("the base case is valid");
}

#[test]
fn shipped_cases_are_valid() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).expect("cases/ exists") {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let case = mpsfsi::case::load_case_file(&path, &[])
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            validate(&case, &Limits::default())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            seen += 1;
        }
    }
    assert!(seen > 0, "no case found in {}", dir.display());
}

#[test]
fn non_finite_numbers_name_their_path() {
    let e = rejected(|c| c.fluid.gravity[1] = f64::NAN);
    assert_error(&e, "fluid.gravity[1]", "finite");
    let e = rejected(|c| c.bodies[1].polygon[2][0] = f64::INFINITY);
    assert_error(&e, "bodies[1].polygon[2][0]", "finite");
    let e = rejected(|c| c.scheme.max_speed = Some(f64::NEG_INFINITY));
    assert_error(&e, "scheme.max_speed", "finite");
    let e = rejected(|c| c.output.probes[1].position[1] = f64::NAN);
    assert_error(&e, "output.probes[1].position[1]", "finite");
}

#[test]
fn non_finite_reports_the_first_in_field_order_with_its_value() {
    let e = rejected(|c| {
        c.scheme.radius = f64::NAN;
        c.time.end = f64::NAN;
        c.fluid.gravity[0] = f64::NEG_INFINITY;
    });
    assert_error(&e, "fluid.gravity[0]", "must be a finite number (got -inf)");
}

#[test]
fn non_finite_inside_motion_names_the_tagged_fields() {
    let e = rejected(|c| {
        if let mpsfsi::case::Motion::Free { velocity, .. } = &mut c.bodies[1].motion {
            velocity[0] = f64::INFINITY;
        }
    });
    assert_error(&e, "bodies[1].motion.velocity[0]", "finite");
}

#[test]
fn non_positive_density() {
    assert_error(
        &rejected_json(|v| v["fluid"]["density"] = json!(0.0)),
        "fluid.density",
        "positive",
    );
    assert_error(
        &rejected_json(|v| v["fluid"]["density"] = json!(-1000.0)),
        "fluid.density",
        "positive",
    );
}

#[test]
fn negative_viscosity() {
    let e = rejected_json(|v| v["fluid"]["kinematic_viscosity"] = json!(-1.0e-6));
    assert_error(&e, "fluid.kinematic_viscosity", "negative");
}

#[test]
fn zero_viscosity_is_allowed() {
    let mut case = base_case();
    case.fluid.kinematic_viscosity = 0.0;
    validate(&case, &Limits::default()).expect("inviscid is valid");
}

#[test]
fn non_positive_particle_spacing() {
    assert_error(
        &rejected_json(|v| v["particle_spacing"] = json!(0.0)),
        "particle_spacing",
        "positive",
    );
    assert_error(
        &rejected_json(|v| v["particle_spacing"] = json!(-0.01)),
        "particle_spacing",
        "positive",
    );
}

#[test]
fn non_positive_time_control() {
    assert_error(
        &rejected_json(|v| v["time"]["end"] = json!(0.0)),
        "time.end",
        "positive",
    );
    assert_error(
        &rejected_json(|v| v["time"]["cfl"] = json!(-0.2)),
        "time.cfl",
        "positive",
    );
    assert_error(
        &rejected_json(|v| v["time"]["max_dt"] = json!(0.0)),
        "time.max_dt",
        "positive",
    );
}

#[test]
fn kernel_radii_must_exceed_one_spacing() {
    assert_error(
        &rejected_json(|v| v["scheme"]["radius"] = json!(0.0)),
        "scheme.radius",
        "greater than 1",
    );
    assert_error(
        &rejected_json(|v| v["scheme"]["radius"] = json!(1.0)),
        "scheme.radius",
        "greater than 1",
    );
    assert_error(
        &rejected_json(|v| v["scheme"]["laplacian_radius"] = json!(-3.1)),
        "scheme.laplacian_radius",
        "greater than 1",
    );
}

#[test]
fn non_positive_solver_tolerance() {
    let e = rejected_json(|v| v["scheme"]["solver_tolerance"] = json!(0.0));
    assert_error(&e, "scheme.solver_tolerance", "positive");
    let e = rejected_json(|v| v["scheme"]["solver_max_iterations"] = json!(0));
    assert_error(&e, "scheme.solver_max_iterations", "positive");
    let e = rejected_json(|v| v["scheme"]["amg_rebuild_interval"] = json!(0));
    assert_error(&e, "scheme.amg_rebuild_interval", "positive");
}

#[test]
fn scheme_ranges() {
    assert_error(
        &rejected_json(|v| v["scheme"]["velocity_filter"] = json!(0.8)),
        "scheme.velocity_filter",
        "[0, 0.5]",
    );
    for bad in [0.0, 1.2] {
        assert_error(
            &rejected_json(|v| v["scheme"]["laplacian_fill_floor"] = json!(bad)),
            "scheme.laplacian_fill_floor",
            "(0, 1]",
        );
    }
    assert_error(
        &rejected_json(|v| v["scheme"]["surface_threshold"] = json!(1.5)),
        "scheme.surface_threshold",
        "(0, 1]",
    );
    assert_error(
        &rejected_json(|v| v["scheme"]["collision_restitution"] = json!(2.0)),
        "scheme.collision_restitution",
        "[0, 1]",
    );
    assert_error(
        &rejected_json(|v| v["scheme"]["compressibility"] = json!(-1e-9)),
        "scheme.compressibility",
        "negative",
    );
}

#[test]
fn exact_projection_requirements() {
    for bad in [0.0, 1.5] {
        assert_error(
            &rejected_json(|v| {
                v["scheme"]["projection"] = json!("exact");
                v["scheme"]["exact_projection_blend"] = json!(bad);
            }),
            "scheme.exact_projection_blend",
            "(0, 1]",
        );
    }
    assert_error(
        &rejected_json(|v| {
            v["scheme"]["projection"] = json!("exact");
            v["scheme"]["source"] = json!("pnd");
        }),
        "scheme.projection",
        "divergence source",
    );
    assert_error(
        &rejected_json(|v| {
            v["scheme"]["projection"] = json!("exact");
            v["scheme"]["compressibility"] = json!(1e-9);
        }),
        "scheme.projection",
        "compressibility",
    );
}

#[test]
fn domain_min_not_below_max() {
    let e = rejected_json(|v| v["domain"]["min"] = json!([-0.5, 0.5]));
    assert_error(&e, "domain", "in y");
    let e = rejected_json(|v| v["domain"]["max"] = json!([-0.6, 0.5]));
    assert_error(&e, "domain", "in x");
}

#[test]
fn fluid_block_outside_the_domain() {
    let e = rejected_json(|v| v["fluid_blocks"][0]["polygon"][2] = json!([0.6, 0.0]));
    assert_error(&e, "fluid_blocks[0].polygon[2]", "outside the domain");
}

#[test]
fn no_fluid_block() {
    assert_error(
        &rejected_json(|v| v["fluid_blocks"] = json!([])),
        "fluid_blocks",
        "at least one",
    );
}

#[test]
fn polygon_with_fewer_than_three_vertices() {
    let e = rejected_json(|v| v["bodies"][0]["polygon"] = json!([[0.0, 0.0], [0.05, 0.03]]));
    assert_error(&e, "bodies[0].polygon", "at least 3");
    let e = rejected_json(|v| v["fluid_blocks"][0]["polygon"] = json!([]));
    assert_error(&e, "fluid_blocks[0].polygon", "at least 3");
}

#[test]
fn polygon_with_zero_area() {
    let e = rejected_json(|v| {
        v["fluid_blocks"][0]["polygon"] = json!([[-0.3, -0.3], [0.0, -0.3], [0.3, -0.3]])
    });
    assert_error(&e, "fluid_blocks[0].polygon", "zero area");
}

#[test]
fn polygon_with_repeated_vertex() {
    let e = rejected_json(|v| {
        v["bodies"][1]["polygon"] = json!([
            [-0.02, -0.02],
            [0.02, -0.02],
            [0.02, -0.02],
            [0.02, 0.02],
            [-0.02, 0.02]
        ])
    });
    assert_error(&e, "bodies[1].polygon[2]", "repeats");
    // closing the polygon by repeating the first vertex gets a hint
    let e = rejected_json(|v| {
        v["bodies"][1]["polygon"] = json!([
            [-0.02, -0.02],
            [0.02, -0.02],
            [0.02, 0.02],
            [-0.02, 0.02],
            [-0.02, -0.02]
        ])
    });
    assert_error(&e, "bodies[1].polygon[0]", "close themselves");
}

#[test]
fn self_intersecting_polygon() {
    // a bow tie: edges 0-1 and 2-3 cross
    let e = rejected_json(|v| {
        v["bodies"][1]["polygon"] =
            json!([[-0.02, -0.02], [0.02, 0.02], [0.02, -0.02], [-0.02, 0.02]])
    });
    assert_error(&e, "bodies[1].polygon", "self-intersecting");
    let e = rejected_json(|v| {
        v["fluid_blocks"][0]["polygon"] =
            json!([[-0.3, -0.3], [0.3, 0.0], [0.3, -0.3], [-0.3, 0.0]])
    });
    assert_error(&e, "fluid_blocks[0].polygon", "self-intersecting");
}

#[test]
fn clockwise_body_polygon() {
    let e = rejected_json(|v| {
        let poly = v["bodies"][0]["polygon"].as_array_mut().unwrap();
        poly.reverse();
    });
    assert_error(&e, "bodies[0].polygon", "counter-clockwise");
}

#[test]
fn clockwise_fluid_block_is_allowed() {
    let mut v = base_value();
    v["fluid_blocks"][0]["polygon"]
        .as_array_mut()
        .unwrap()
        .reverse();
    validate(&parse_case_value(v).unwrap(), &Limits::default())
        .expect("fluid blocks may have either orientation");
}

#[test]
fn polyline_with_fewer_than_two_points() {
    let e = rejected_json(|v| v["walls"][0]["polyline"] = json!([[0.0, 0.0]]));
    assert_error(&e, "walls[0].polyline", "at least 2");
    let e = rejected_json(|v| {
        v["walls"][0]["polyline"] = json!([[-0.3, -0.3], [0.3, -0.3]]);
        v["walls"][0]["closed"] = json!(true);
    });
    assert_error(&e, "walls[0].polyline", "at least 3");
}

#[test]
fn polyline_with_zero_length_segment() {
    let e = rejected_json(|v| {
        v["walls"][0]["polyline"] = json!([
            [-0.3, 0.3],
            [-0.3, -0.3],
            [-0.3, -0.3],
            [0.3, -0.3],
            [0.3, 0.3]
        ])
    });
    assert_error(&e, "walls[0].polyline[2]", "zero-length");
}

#[test]
fn body_overlapping_a_wall() {
    // the wedge moved onto the right tank wall
    let e = rejected_json(|v| v["bodies"][0]["position"] = json!([0.3, 0.1]));
    assert_error(&e, "bodies[0]", "overlaps wall 'tank'");
}

#[test]
fn body_overlap_accounts_for_the_angle() {
    // a long thin plate clear of the wall when flat, crossing it when turned 90°
    let plate = |v: &mut Value| {
        v["bodies"][1]["polygon"] = json!([[-0.2, -0.01], [0.2, -0.01], [0.2, 0.01], [-0.2, 0.01]]);
        v["bodies"][1]["position"] = json!([0.0, -0.2]);
    };
    let mut ok = base_value();
    plate(&mut ok);
    validate(&parse_case_value(ok).unwrap(), &Limits::default()).expect("the flat plate is clear");
    let e = rejected_json(|v| {
        plate(v);
        v["bodies"][1]["angle"] = json!(std::f64::consts::FRAC_PI_2);
    });
    assert_error(&e, "bodies[1]", "overlaps wall");
}

#[test]
fn bodies_overlapping_each_other() {
    let e = rejected_json(|v| v["bodies"][1]["position"] = json!([0.05, 0.13]));
    assert_error(&e, "bodies[1]", "overlaps body 'wedge'");
}

#[test]
fn body_inside_another_body() {
    // no edges cross: the box lies wholly inside the wedge
    let e = rejected_json(|v| {
        v["bodies"][1]["polygon"] = json!([
            [-0.005, -0.005],
            [0.005, -0.005],
            [0.005, 0.005],
            [-0.005, 0.005]
        ]);
        v["bodies"][1]["position"] = json!([0.0, 0.15]);
    });
    assert_error(&e, "bodies[1]", "overlaps body 'wedge'");
}

#[test]
fn free_body_with_non_positive_mass_or_inertia() {
    assert_error(
        &rejected_json(|v| v["bodies"][1]["motion"]["mass"] = json!(0.0)),
        "bodies[1].motion.mass",
        "positive",
    );
    assert_error(
        &rejected_json(|v| v["bodies"][1]["motion"]["inertia"] = json!(-1.0)),
        "bodies[1].motion.inertia",
        "positive",
    );
}

#[test]
fn velocity_table_not_increasing() {
    let e = rejected_json(|v| v["bodies"][0]["motion"]["table"][1]["time"] = json!(0.0));
    assert_error(&e, "bodies[0].motion.table[1].time", "strictly increasing");
    let e = rejected_json(|v| v["bodies"][0]["motion"]["table"] = json!([]));
    assert_error(&e, "bodies[0].motion.table", "at least one");
}

#[test]
fn particle_count_above_the_limit() {
    // 0.6 m x 0.3 m at l0 = 0.01: 1800 particles on the uniform layout
    let mut case = base_case();
    case.refinement = mpsfsi::case::Refinement::None;
    let e = validate(
        &case,
        &Limits {
            max_particles: 1000,
        },
    )
    .expect_err("above the limit");
    assert_error(
        &e,
        "particle_spacing",
        "estimated from the fluid block areas",
    );
    assert!(
        e.message.contains("1800") && e.message.contains("1000"),
        "{e:?}"
    );
    validate(
        &case,
        &Limits {
            max_particles: 1800,
        },
    )
    .expect("at the limit");
}

/// On a multi-resolution layout the estimate counts the fluid outside the fine boxes at
/// (2 l0)²: for the shipped wedge at its 5 mm it bounds the layout's count from above
/// within 10 %, and a limit between it and the uniform count accepts the case with
/// `"auto"` and rejects it with `"none"`.
#[test]
fn the_particle_estimate_counts_the_multi_resolution_layout() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases/wedge_30deg_constant_velocity.json");
    let case = mpsfsi::case::load_case_file(&path, &[]).unwrap();
    let params = mpsfsi::engine::params::MpsParameters::new(&case);
    let built = mpsfsi::engine::scene::build_scene(&case, &params)
        .particles
        .len() as f64;
    let estimate = mpsfsi::case::estimated_particles(&case).unwrap();
    assert!(
        (built..=1.1 * built).contains(&estimate),
        "estimate {estimate:.0} for {built} particles"
    );
    let mut uniform = case.clone();
    uniform.refinement = mpsfsi::case::Refinement::None;
    let uniform_estimate = mpsfsi::case::estimated_particles(&uniform).unwrap();
    assert!(
        uniform_estimate > 2.0 * estimate,
        "{uniform_estimate} vs {estimate}"
    );
    let limits = Limits {
        max_particles: (1.5 * estimate) as usize,
    };
    validate(&case, &limits).expect("the two-level layout fits");
    let e = validate(&uniform, &limits).expect_err("the uniform layout does not");
    assert_error(&e, "particle_spacing", "exceed the limit");
}

/// The scene takes the far level's clearance from the scheme's radius in spacings, as
/// the estimate does: at l0 = 3.7 mm, where (2.5 l0) / l0 rounds one ulp above 2.5, the
/// shipped wedge's layout has the particles of its neighbour spacing 3.7 mm + 0.01 µm
/// (the same lattice, the clearance exact) to within a lattice row, not a 2 l0 cell's
/// ring more along the far boxes.
#[test]
fn the_far_clearance_does_not_depend_on_round_off_of_the_spacing() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases/wedge_30deg_constant_velocity.json");
    let built = |l0: f64| {
        let mut case = mpsfsi::case::load_case_file(&path, &[]).unwrap();
        case.particle_spacing = l0;
        let params = mpsfsi::engine::params::MpsParameters::new(&case);
        let n = mpsfsi::engine::scene::build_scene(&case, &params)
            .particles
            .len() as f64;
        (n, mpsfsi::case::estimated_particles(&case).unwrap())
    };
    let radius = mpsfsi::case::load_case_file(&path, &[])
        .unwrap()
        .scheme
        .neighbour_radius();
    assert!(
        radius * 0.0037 / 0.0037 > radius,
        "the spacing must round up"
    );
    let (odd, odd_estimate) = built(0.0037);
    let (exact, _) = built(0.003_700_000_01);
    assert!(
        (odd - exact).abs() < 0.002 * exact,
        "{odd} particles at 3.7 mm against {exact}"
    );
    assert!(odd_estimate >= odd, "estimate {odd_estimate:.0} for {odd}");
}

/// A fluid block whose height is not a whole number of spacings keeps its top and
/// bottom where the case draws them: the 25° drop test's 1.1 m tank at 12 mm (91.67
/// spacings) fills 92 rows pressed to 11.957 mm, the top row half a pitch below the
/// still surface (y = 0) and the bottom row half a pitch above the floor. Filled at
/// l0 from the floor, the top row sat at −14 mm and the surface 8 mm low. The
/// multi-resolution layout still merges the pressed lattice: the shipped wedge with its
/// tank 1.203 m deep (240.6 spacings) has under a third of the uniform count, as at
/// 1.2 m, and the estimate bounds it.
#[test]
fn a_fluid_block_keeps_its_surface_whatever_its_height() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let drop = mpsfsi::case::load_case_file(
        &root.join("tests/data/drop_tests/wedge_25deg_94kg.json"),
        &[],
    )
    .unwrap();
    let params = mpsfsi::engine::params::MpsParameters::new(&drop);
    let scene = mpsfsi::engine::scene::build_scene(&drop, &params);
    let ys = scene.particles.position.iter().map(|p| p.y);
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    let pitch = 1.1 / 92.0;
    assert!((hi + 0.5 * pitch).abs() < 1e-9, "top row at {hi}");
    assert!(
        (lo - (-1.1 + 0.5 * pitch)).abs() < 1e-9,
        "bottom row at {lo}"
    );

    let wedge = |depth: f64| {
        let mut case = mpsfsi::case::load_case_file(
            &root.join("cases/wedge_30deg_constant_velocity.json"),
            &[],
        )
        .unwrap();
        for p in case.fluid_blocks[0].polygon.iter_mut() {
            if p[1] < -1.0 {
                p[1] = -depth;
            }
        }
        for w in case.walls.iter_mut() {
            for p in w.polyline.iter_mut() {
                if p[1] < -1.0 {
                    p[1] = -depth;
                }
            }
        }
        let params = mpsfsi::engine::params::MpsParameters::new(&case);
        let built = mpsfsi::engine::scene::build_scene(&case, &params);
        let top = built
            .particles
            .position
            .iter()
            .map(|p| p.y)
            .fold(f64::NEG_INFINITY, f64::max);
        let estimate = mpsfsi::case::estimated_particles(&case).unwrap();
        (built.particles.len() as f64, top, estimate)
    };
    let (whole, whole_top, _) = wedge(1.2);
    let (pressed, pressed_top, estimate) = wedge(1.203);
    let uniform = 4.0 * 1.203 / (0.005 * 0.005);
    assert!(
        pressed < uniform / 3.0,
        "{pressed} particles against {uniform} uniform"
    );
    assert!(
        (pressed - whole).abs() < 0.02 * whole,
        "{pressed} particles at 1.203 m against {whole} at 1.2 m"
    );
    assert!((whole_top + 0.0025).abs() < 1e-9 && (pressed_top + 0.5 * 1.203 / 241.0).abs() < 1e-9);
    assert!(estimate >= pressed, "estimate {estimate:.0} for {pressed}");
}

#[test]
fn non_positive_output_intervals() {
    assert_error(
        &rejected_json(|v| v["output"]["load_interval"] = json!(0.0)),
        "output.load_interval",
        "positive",
    );
    assert_error(
        &rejected_json(|v| v["output"]["snapshot_interval"] = json!(-1.0)),
        "output.snapshot_interval",
        "positive",
    );
    assert_error(
        &rejected_json(|v| v["output"]["filter_window"] = json!(0.0)),
        "output.filter_window",
        "positive",
    );
}

#[test]
fn null_output_intervals_are_allowed() {
    let mut v = base_value();
    v["output"]["load_interval"] = Value::Null;
    v["output"]["snapshot_interval"] = Value::Null;
    validate(&parse_case_value(v).unwrap(), &Limits::default()).expect("null intervals are valid");
}

/// The load interval: absent or "auto" gives a thousand rows over the run, at most 1 ms
/// apart (a 15 ms impact gets 15 µs rows, a 4 s run 1 ms ones); null gives every step;
/// a word other than "auto" is rejected with the field's path.
#[test]
fn load_interval_auto_every_step_or_seconds() {
    use mpsfsi::case::LoadInterval;
    let mut v = base_value();
    v["output"].as_object_mut().unwrap().remove("load_interval");
    let absent = parse_case_value(v.clone()).unwrap();
    assert_eq!(absent.output.load_interval, LoadInterval::Auto);
    assert_eq!(LoadInterval::Auto.seconds(0.015), Some(0.015 / 1000.0));
    assert_eq!(LoadInterval::Auto.seconds(4.0), Some(1.0e-3));
    v["output"]["load_interval"] = json!("auto");
    let auto = parse_case_value(v.clone()).unwrap();
    assert_eq!(auto.output.load_interval, LoadInterval::Auto);
    assert_eq!(
        serde_json::to_value(&auto.output).unwrap()["load_interval"],
        json!("auto")
    );
    v["output"]["load_interval"] = Value::Null;
    let every = parse_case_value(v.clone()).unwrap();
    assert_eq!(every.output.load_interval, LoadInterval::EveryStep);
    assert_eq!(every.output.load_interval.seconds(1.0), None);
    v["output"]["load_interval"] = json!(2.5e-4);
    let fixed = parse_case_value(v.clone()).unwrap();
    assert_eq!(fixed.output.load_interval.seconds(1.0), Some(2.5e-4));
    v["output"]["load_interval"] = json!("often");
    let e = parse_case_value(v).expect_err("an unknown word is not an interval");
    assert_error(&e, "output.load_interval", "auto");
}

#[test]
fn probe_outside_the_domain() {
    let e = rejected_json(|v| v["output"]["probes"][1]["position"] = json!([0.1, -0.7]));
    assert_error(&e, "output.probes[1].position", "outside the domain");
}

/// A gauge on a body: its body must exist, it must sit on the body's surface (in the
/// body's frame, within half a spacing: 5 mm here), and a diameter needs a body.
#[test]
fn gauges_on_bodies() {
    let gauge = |position: Value| json!({ "name": "g", "body": "wedge", "position": position });
    // on the wedge's face (0,0)-(0.05,0.03), and 4 mm off it
    let on_face = parse_case_value({
        let mut v = base_value();
        v["output"]["probes"][1] = gauge(json!([0.025, 0.015]));
        v["output"]["probes"][1]["diameter"] = json!(0.004);
        v
    })
    .unwrap();
    validate(&on_face, &Limits::default()).expect("a gauge on the face is valid");
    let off = 0.004 / (0.05f64.powi(2) + 0.03f64.powi(2)).sqrt();
    let near = [0.025 + 0.03 * off, 0.015 - 0.05 * off];
    let near_case = parse_case_value({
        let mut v = base_value();
        v["output"]["probes"][1] = gauge(json!(near));
        v
    })
    .unwrap();
    validate(&near_case, &Limits::default()).expect("4 mm from the face is within 5 mm");

    let e = rejected_json(|v| v["output"]["probes"][1] = gauge(json!([0.025, 0.005])));
    assert_error(
        &e,
        "output.probes[1].position",
        "within half a particle spacing",
    );
    let e = rejected_json(|v| {
        v["output"]["probes"][1] = gauge(json!([0.025, 0.015]));
        v["output"]["probes"][1]["body"] = json!("hull");
    });
    assert_error(&e, "output.probes[1].body", "bodies: wedge, box");
    let e = rejected_json(|v| v["output"]["probes"][1]["diameter"] = json!(0.004));
    assert_error(&e, "output.probes[1].diameter", "gauge on a body");
    let e = rejected_json(|v| {
        v["output"]["probes"][1] = gauge(json!([0.025, 0.015]));
        v["output"]["probes"][1]["diameter"] = json!(0.0);
    });
    assert_error(&e, "output.probes[1].diameter", "positive");
    // a gauge's position is in the body's frame: the world domain does not bound it
    let far_body = parse_case_value({
        let mut v = base_value();
        v["bodies"][0]["position"] = json!([0.1, 0.1]);
        v["output"]["probes"][1] = gauge(json!([0.025, 0.015]));
        v
    })
    .unwrap();
    validate(&far_body, &Limits::default()).expect("the gauge moves with the body");
}

#[test]
fn duplicate_names() {
    let e = rejected_json(|v| v["bodies"][1]["name"] = json!("wedge"));
    assert_error(&e, "bodies[1].name", "duplicate");
    // a body may not take a wall's name either: both label rows of loads.csv
    let e = rejected_json(|v| v["bodies"][0]["name"] = json!("tank"));
    assert_error(&e, "bodies[0].name", "duplicate name 'tank'");
    let e = rejected_json(|v| v["output"]["probes"][1]["name"] = json!("p1"));
    assert_error(&e, "output.probes[1].name", "duplicate");
}

#[test]
fn empty_or_csv_breaking_names() {
    assert_error(
        &rejected_json(|v| v["walls"][0]["name"] = json!(" ")),
        "walls[0].name",
        "empty",
    );
    assert_error(
        &rejected_json(|v| v["bodies"][0]["name"] = json!("a,b")),
        "bodies[0].name",
        "commas",
    );
}

#[test]
fn unknown_scheme_name_lists_the_valid_ones() {
    let mut v = base_value();
    v["scheme"]["laplacian"] = json!("higher_ordr");
    let e = parse_case_value(v).expect_err("unknown variant");
    assert_error(&e, "scheme.laplacian", "higher_order");
    assert!(
        e.message.contains("higher_ordr") && e.message.contains("classic"),
        "{e:?}"
    );
}

#[test]
fn unknown_field_is_rejected_with_its_path() {
    let mut v = base_value();
    v["fluid"]["densty"] = json!(1000.0);
    let e = parse_case_value(v).expect_err("unknown field");
    assert!(e.path.starts_with("fluid"), "{e:?}");
    assert!(e.message.contains("densty"), "{e:?}");
}

#[test]
fn wrong_type_names_its_path() {
    let mut v = base_value();
    v["bodies"][1]["motion"]["mass"] = json!("heavy");
    let e = parse_case_value(v).expect_err("a string mass");
    assert!(e.path.starts_with("bodies[1].motion"), "{e:?}");
}

#[test]
fn negative_stabiliser_settings() {
    let e = rejected_json(|v| v["scheme"]["gradient_stabilization"] = json!(-0.5));
    assert_error(&e, "scheme.gradient_stabilization", "negative");
    let e = rejected_json(|v| v["scheme"]["stabilization_distance"] = json!(-1.0));
    assert_error(&e, "scheme.stabilization_distance", "negative");
}

/// Every number of a JSON value, by its pointer.
fn number_pointers(v: &Value, here: String, out: &mut Vec<String>) {
    match v {
        Value::Number(_) => out.push(here),
        Value::Array(items) => items
            .iter()
            .enumerate()
            .for_each(|(i, x)| number_pointers(x, format!("{here}/{i}"), out)),
        Value::Object(map) => map
            .iter()
            .for_each(|(k, x)| number_pointers(x, format!("{here}/{k}"), out)),
        _ => {}
    }
}

#[test]
fn random_bad_numbers_are_rejected_or_built_without_panics() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261122);
    let mut pointers = Vec::new();
    number_pointers(&base_value(), String::new(), &mut pointers);
    let nasty = [0.0, -1.0, 1.0e300, -1.0e300, 1.0e-300, 0.5, 2.0, 1.0e6];
    let limits = Limits {
        max_particles: 20_000,
    };
    let (mut accepted, mut rejected_count) = (0, 0);
    for _ in 0..400 {
        let mut v = base_value();
        for _ in 0..rng.random_range(1..4) {
            let p = &pointers[rng.random_range(0..pointers.len())];
            *v.pointer_mut(p).unwrap() = json!(nasty[rng.random_range(0..nasty.len())]);
        }
        let Ok(case) = parse_case_value(v) else {
            continue;
        };
        match validate(&case, &limits) {
            Ok(()) => {
                accepted += 1;
                let params = mpsfsi::engine::params::MpsParameters::new(&case);
                let scene = mpsfsi::engine::scene::build_scene(&case, &params);
                assert!(
                    scene.particles.len() <= limits.max_particles,
                    "the estimate bounds the scene"
                );
            }
            Err(e) => {
                rejected_count += 1;
                assert!(!e.message.is_empty(), "{e:?}");
            }
        }
    }
    assert!(
        accepted > 0 && rejected_count > 0,
        "accepted {accepted}, rejected {rejected_count}"
    );
}

#[test]
fn design_example_case_is_valid() {
    // the case format's full example (docs/contracts.md): a prescribed wedge over a tank,
    // every block written out
    let v = json!({
      "name": "wedge-30deg-constant-velocity",
      "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
      "particle_spacing": 0.005,
      "domain": { "min": [-1.0, -1.0], "max": [1.0, 0.6] },
      "fluid_blocks": [ { "polygon": [[-0.8, -0.6], [0.8, -0.6], [0.8, 0.0], [-0.8, 0.0]] } ],
      "walls": [ { "name": "tank", "polyline": [[-0.8, 0.3], [-0.8, -0.6], [0.8, -0.6], [0.8, 0.3]] } ],
      "bodies": [ {
          "name": "wedge",
          "polygon": [[0.0, 0.0], [0.25, 0.1443], [0.25, 0.3], [-0.25, 0.3], [-0.25, 0.1443]],
          "position": [0.0, 0.0],
          "angle": 0.0,
          "motion": { "type": "prescribed", "velocity": [0.0, -6.15], "angular_velocity": 0.0 }
      } ],
      "time": { "end": 0.02, "cfl": 0.2, "max_dt": 1.0e-4 },
      "output": { "load_interval": 1.0e-5, "snapshot_interval": null, "probes": [ { "name": "p1", "position": [0.0, -0.3] }, { "name": "keel_gauge", "body": "wedge", "position": [0.05, 0.0289], "diameter": 0.004 } ] },
      "scheme": { }
    });
    validate(&parse_case_value(v).unwrap(), &Limits::default())
        .expect("the full example case is valid");
}

#[test]
fn damping_zone_with_negative_strength_or_no_length() {
    assert_error(
        &rejected_json(|v| {
            v["damping_zones"] =
                json!([{ "start": [0.1, 0.0], "end": [0.2, 0.0], "strength": -1.0 }])
        }),
        "damping_zones[0].strength",
        ">= 0",
    );
    assert_error(
        &rejected_json(|v| {
            v["damping_zones"] = json!([
                { "start": [0.1, 0.0], "end": [0.2, 0.0], "strength": 5.0 },
                { "start": [0.1, 0.0], "end": [0.1, 0.0], "strength": 5.0 }
            ])
        }),
        "damping_zones[1].end",
        "differ from start",
    );
}

#[test]
fn refinement_forms_and_their_errors() {
    // the three forms parse; "auto" is what a case without the field gets
    for (form, expected) in [
        (json!("none"), mpsfsi::case::Refinement::None),
        (json!("auto"), mpsfsi::case::Refinement::Auto),
    ] {
        let mut v = base_value();
        v["refinement"] = form;
        assert_eq!(parse_case_value(v).unwrap().refinement, expected);
    }
    assert_eq!(base_case().refinement, mpsfsi::case::Refinement::Auto);
    let mut v = base_value();
    v["refinement"] = json!({ "fine": [{ "min": [-0.5, -0.5], "max": [0.5, 0.0] }] });
    let case = parse_case_value(v).unwrap();
    validate(&case, &Limits::default()).expect("a fine box is valid");
    // a misspelt mode names the field and the forms it takes
    let mut v = base_value();
    v["refinement"] = json!("automatic");
    let e = parse_case_value(v).expect_err("unknown mode");
    assert_error(&e, "refinement", "\"none\", \"auto\"");
    let mut v = base_value();
    v["refinement"] = json!({ "fine": [], "levels": 3 });
    let e = parse_case_value(v).expect_err("unknown field");
    assert!(e.path.starts_with("refinement"), "{e:?}");
    assert!(e.message.contains("levels"), "{e:?}");
    // an inverted box, an empty list, a single-resolution scheme with explicit boxes
    assert_error(
        &rejected_json(|v| {
            v["refinement"] = json!({ "fine": [{ "min": [0.5, -0.5], "max": [-0.5, 0.0] }] })
        }),
        "refinement.fine[0]",
        "below max",
    );
    assert_error(
        &rejected_json(|v| v["refinement"] = json!({ "fine": [] })),
        "refinement.fine",
        "at least one box",
    );
    assert_error(
        &rejected_json(|v| {
            v["refinement"] = json!({ "fine": [{ "min": [-0.5, -0.5], "max": [0.5, 0.0] }] });
            v["scheme"]["laplacian"] = json!("least_squares");
        }),
        "refinement",
        "scheme.laplacian",
    );
}

#[test]
fn an_array_where_the_schema_has_an_object_is_rejected_with_its_path() {
    // serde's derived structs also read an array of their fields in order: the output
    // block has optional fields first, so `[null, null]` used to pass as one
    for (edit, path) in [
        (json!({ "output": [null, null] }), "output"),
        (json!({ "fluid": [] }), "fluid"),
    ] {
        let mut v = base_value();
        for (k, value) in edit.as_object().unwrap() {
            v[k] = value.clone();
        }
        let e = parse_case_value(v).expect_err("an array is not an object");
        assert_error(&e, path, "expected an object");
    }
    let mut v = base_value();
    v["fluid_blocks"][0] = json!([[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]]);
    let e = parse_case_value(v).expect_err("a block is an object");
    assert_error(&e, "fluid_blocks[0]", "got an array");
}

/// The case README.md shows a new user ("Case format") is valid, follows the README's own
/// advice for an impact (B/l0 >= 100, a tank 8B x 2.4B) and gets the particle count the
/// README states (42k, within 5 %).
#[test]
fn the_readme_example_case_is_valid_and_follows_its_advice() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let section = &readme[readme
        .find("## Case format")
        .expect("a Case format section")..];
    let start = section.find("```json\n").expect("a json block") + "```json\n".len();
    let text = &section[start..start + section[start..].find("```").unwrap()];
    let case = mpsfsi::case::parse_case_str(text).expect("the README example parses");
    validate(&case, &Limits::default()).expect("the README example is valid");
    let xs: Vec<f64> = case.bodies[0].polygon.iter().map(|p| p[0]).collect();
    let breadth =
        xs.iter().cloned().fold(f64::MIN, f64::max) - xs.iter().cloned().fold(f64::MAX, f64::min);
    assert!(
        breadth / case.particle_spacing >= 100.0 - 1e-9,
        "B/l0 = {}",
        breadth / case.particle_spacing
    );
    let block = &case.fluid_blocks[0].polygon;
    let width = block.iter().map(|p| p[0]).fold(f64::MIN, f64::max)
        - block.iter().map(|p| p[0]).fold(f64::MAX, f64::min);
    let depth = -block.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
    assert!(
        width >= 8.0 * breadth - 1e-9 && depth >= 2.4 * breadth - 1e-9,
        "tank {width} x {depth}"
    );
    // the README says 42k particles
    let params = mpsfsi::engine::params::MpsParameters::new(&case);
    let particles = mpsfsi::engine::scene::build_scene(&case, &params)
        .particles
        .len() as f64;
    assert!(
        (particles / 42_000.0 - 1.0).abs() < 0.05,
        "{particles} particles"
    );
}
