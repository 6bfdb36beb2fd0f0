//! `--set PATH=VALUE` overrides (case::apply_override through load_case_file).

use crate::base_value;
use mpsfsi::case::{apply_override, load_case_file, parse_case_value, LaplacianKind, Motion};
use serde_json::{json, Value};

fn overridden(assignments: &[&str]) -> Result<mpsfsi::case::Case, mpsfsi::case::CaseError> {
    let mut v = base_value();
    for a in assignments {
        apply_override(&mut v, a)?;
    }
    parse_case_value(v)
}

#[test]
fn nested_number() {
    let case = overridden(&["time.end=0.25", "particle_spacing=0.0025"]).unwrap();
    assert_eq!(case.time.end, 0.25);
    assert_eq!(case.particle_spacing, 0.0025);
}

#[test]
fn array_index_in_both_spellings() {
    let case = overridden(&["bodies[1].motion.mass=3.5", "bodies.0.position=[0.0, 0.2]"]).unwrap();
    match &case.bodies[1].motion {
        Motion::Free { mass, .. } => assert_eq!(*mass, 3.5),
        other => panic!("bodies[1] should stay free: {other:?}"),
    }
    assert_eq!(case.bodies[0].position, [0.0, 0.2]);
}

#[test]
fn string_enum_value_without_quotes() {
    let case = overridden(&["scheme.laplacian=classic"]).unwrap();
    assert_eq!(case.scheme.laplacian, LaplacianKind::Classic);
    let case = overridden(&["scheme.laplacian=\"corrected_higher_order\""]).unwrap();
    assert_eq!(case.scheme.laplacian, LaplacianKind::CorrectedHigherOrder);
}

#[test]
fn unknown_enum_value_names_the_path() {
    let e = overridden(&["scheme.laplacian=hl"]).expect_err("unknown variant");
    assert_eq!(e.path, "scheme.laplacian");
    assert!(e.message.contains("higher_order"), "{e:?}");
}

#[test]
fn creates_missing_objects() {
    let mut v = base_value();
    v.as_object_mut().unwrap().remove("scheme");
    apply_override(&mut v, "scheme.radius=2.4").unwrap();
    assert_eq!(v["scheme"], json!({ "radius": 2.4 }));
    assert_eq!(parse_case_value(v).unwrap().scheme.radius, 2.4);
}

#[test]
fn index_out_of_range() {
    let e = overridden(&["bodies[5].name=x"]).expect_err("only two bodies");
    assert!(
        e.path.starts_with("bodies") && e.path.contains('5'),
        "{e:?}"
    );
    assert!(e.message.contains("out of range"), "{e:?}");
}

#[test]
fn field_inside_a_number() {
    let e = overridden(&["time.end.value=1"]).expect_err("time.end is a number");
    assert!(e.path.starts_with("time.end"), "{e:?}");
    assert!(e.message.contains("cannot set a field"), "{e:?}");
}

#[test]
fn misspelt_field_is_rejected_by_the_parser() {
    let e = overridden(&["time.ends=1"]).expect_err("no field ends");
    assert!(e.path.starts_with("time"), "{e:?}");
    assert!(e.message.contains("ends"), "{e:?}");
}

#[test]
fn missing_equals_sign() {
    let e = overridden(&["time.end"]).expect_err("no value");
    assert!(e.message.contains("PATH=VALUE"), "{e:?}");
}

#[test]
fn wrong_type_after_override() {
    let e = overridden(&["fluid.density=water"]).expect_err("a string density");
    assert_eq!(e.path, "fluid.density");
}

#[test]
fn overrides_apply_to_files() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/cases/tiny.json");
    let case = load_case_file(
        &path,
        &["time.end=0.5".into(), "walls[0].name=floor".into()],
    )
    .unwrap();
    assert_eq!(case.time.end, 0.5);
    assert_eq!(case.walls[0].name, "floor");
    let untouched = load_case_file(&path, &[]).unwrap();
    assert_eq!(untouched.time.end, 0.01);
    let _: Value = serde_json::to_value(&untouched).unwrap();
}
