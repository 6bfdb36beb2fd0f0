//! Where the default scheme's slamming loads are validated (docs/validation.md), and the
//! advice `mpsfsi check` and `mpsfsi run` print for a body that enters the water outside
//! that envelope: a flat face, a small deadrise, or too few spacings across the body.

use crate::case::{Body, Case, Motion};
use crate::engine::config::given_velocity;
use crate::math::{perp, rotate, vec2, Real, Vec2};

/// Spacings across a body from which a 15–40° wedge reads C_F within 5 % (at 12–25 the
/// quick bench's 30° wedges read 17–24 % high).
const MIN_SPACINGS_ACROSS: Real = 100.0;

/// Deadrise (degrees) below which the validated spacing doubles: the 10° wedge reads
/// +8.2 % at 100 spacings across (four offsets) and −1.0 % at 200.
const SMALL_DEADRISE_DEG: Real = 15.0;

/// Spacings across a body of small deadrise for 5 %.
const SMALL_DEADRISE_SPACINGS: Real = 200.0;

/// Deadrise (degrees) below which a face counts as flat: the default scheme carries an
/// impulsively started flat plate's added mass 7–13 % high.
const FLAT_DEG: Real = 5.0;

/// A free body whose mass per metre is at most this multiple of the added mass of a
/// plate of its breadth, ρπB²/8 (the water it sets moving once the breadth is wet), is
/// light: its motion is set by its added mass, and the measured light bodies slow less
/// than their experiments did. The 25° wedge of 94 kg/m (0.17) follows quasi-steady
/// potential flow within 1.3 % and, like that theory, loses 10 % too little speed against
/// its drop test; the half-buoyant cylinder (1.0) sinks 9 % too deep. The shipped 241
/// kg/m free fall (2.45) is within 1.5 % of potential flow.
const LIGHT_BODY_SHARE: Real = 2.0;

/// Advice for every body that enters the water outside the validated envelope: a body
/// with a velocity (prescribed, or a free body's initial one), judged by the deadrise
/// over the width it will wet ([`wetted_deadrise`]) and its breadth across the velocity
/// (one line at most), and a free body that is light ([`LIGHT_BODY_SHARE`]). A body at
/// rest (a floating box, a drop from rest) gets none.
pub fn impact_advice(case: &Case) -> Vec<String> {
    let l0 = case.particle_spacing;
    case.bodies
        .iter()
        .flat_map(|body| {
            let velocity = given_velocity(body);
            if velocity.norm() <= 0.0 {
                return Vec::new();
            }
            let d = velocity / velocity.norm();
            let breadth = breadth_across(body, d);
            // the depth it reaches by the end of the run
            let depth = velocity.norm() * case.time.end;
            let entry = entry_advice(body, d, depth, breadth / l0);
            let light = light_body_advice(case, body, breadth);
            entry.into_iter().chain(light).collect()
        })
        .collect()
}

/// The body's extent across the unit direction `d`, at its angle.
fn breadth_across(body: &Body, d: Vec2) -> Real {
    let across = perp(d);
    let (lo, hi) = body
        .polygon
        .iter()
        .map(|p| rotate(vec2(*p), body.angle).dot(&across))
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    hi - lo
}

/// The advice for a free body of `breadth` across its velocity that is light.
fn light_body_advice(case: &Case, body: &Body, breadth: Real) -> Option<String> {
    let Motion::Free { mass, .. } = &body.motion else {
        return None;
    };
    let plate = case.fluid.density * std::f64::consts::PI * breadth * breadth / 8.0;
    (*mass <= LIGHT_BODY_SHARE * plate).then(|| {
        format!(
            "body {}: light ({mass} kg/m against an added mass of about {} kg/m once its {breadth:.3} m breadth is wet): its speed is set by its added mass; a 25° wedge of 94 kg/m follows potential flow within 1.3 % but, like that theory, loses 10 % less speed than its drop test did (docs/validation.md, light drop tests)",
            body.name,
            three_digits(plate)
        )
    })
}

/// `x` to three significant digits (565, 98.2, 4.75).
fn three_digits(x: Real) -> String {
    let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// The advice for the face a body leads with, moving `depth` along the unit direction
/// `d` with `spacings` spacings across it.
fn entry_advice(body: &Body, d: Vec2, depth: Real, spacings: Real) -> Option<String> {
    let deadrise = wetted_deadrise(body, d, depth)?.to_degrees();
    let name = &body.name;
    if deadrise < FLAT_DEG {
        Some(format!(
            "body {name}: the face it leads with is flat (deadrise {deadrise:.1}°): the default scheme reads a flat impact's added mass 7-13 % high; `scheme.projection = \"exact\"` carries it within 2.1 % over a short impact (docs/validation.md)"
        ))
    } else if deadrise < SMALL_DEADRISE_DEG && spacings < SMALL_DEADRISE_SPACINGS {
        Some(format!(
            "body {name}: deadrise {deadrise:.1}° with {spacings:.0} spacings across: below {SMALL_DEADRISE_DEG}° the slamming load reads within 5 % from {SMALL_DEADRISE_SPACINGS} spacings across (a 10° wedge reads +8 % at 100; docs/validation.md)"
        ))
    } else if spacings < MIN_SPACINGS_ACROSS {
        Some(format!(
            "body {name}: {spacings:.0} spacings across: the slamming load reads within 5 % from {MIN_SPACINGS_ACROSS} spacings across (a 30° wedge reads 17-24 % high at 12-25; docs/validation.md)"
        ))
    } else {
        None
    }
}

/// The deadrise (rad) of the body's leading profile averaged over the width it wets
/// when it moves `depth` along the unit direction `d` from first contact: each edge that
/// faces `d`, cut at `depth` behind the leading point, counts with the width it spans
/// across `d`. A wedge gets its deadrise whatever the depth (until the chines); a flat
/// face 0; a circle, whose first segment is nearly flat, the mean slope of the arc it
/// wets (about 20° for a radius of 0.25 m entering 6 cm). The depth is capped at the
/// body's own extent. `None` when no edge faces `d`.
pub fn wetted_deadrise(body: &Body, d: Vec2, depth: Real) -> Option<Real> {
    let across = perp(d);
    // (across, behind the leading point) of each vertex, the body at its angle
    let points: Vec<Vec2> = body
        .polygon
        .iter()
        .map(|p| rotate(vec2(*p), body.angle))
        .map(|p| Vec2::new(p.dot(&across), -p.dot(&d)))
        .collect();
    let lead = points.iter().map(|p| p.y).fold(Real::INFINITY, Real::min);
    let extent = points.iter().map(|p| p.y - lead).fold(0.0, Real::max);
    let depth = depth.min(extent);
    let (mut width, mut weighted) = (0.0, 0.0);
    for k in 0..points.len() {
        let (a, b) = (points[k], points[(k + 1) % points.len()]);
        let t = b - a;
        // counter-clockwise polygon: the outward normal of a→b is (t.y, -t.x); the frame
        // (across, -d) is a rotation in which d points along -y, so the edge faces d
        // where t.x > 0
        let facing = t.x > 1e-12 * t.norm();
        if !facing || t.norm() == 0.0 {
            continue;
        }
        // the part of the edge within `depth` of the leading point
        let (ya, yb) = (a.y - lead, b.y - lead);
        if ya.min(yb) > depth {
            continue;
        }
        let cut = |p: Vec2, q: Vec2, yp: Real, yq: Real| -> Vec2 {
            if yq <= depth || yp == yq {
                q
            } else {
                p + (q - p) * ((depth - yp) / (yq - yp))
            }
        };
        let (p, q) = (cut(b, a, yb, ya), cut(a, b, ya, yb));
        let w = (q.x - p.x).abs();
        let deadrise = (t.y.abs() / t.norm()).asin();
        width += w;
        weighted += w * deadrise;
    }
    (width > 0.0).then(|| weighted / width)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::parse_case_str;

    /// A tank with one body of `polygon` moving as `motion` (JSON), at spacing `l0`.
    fn case_with(polygon: &str, motion: &str, l0: Real) -> Case {
        parse_case_str(&format!(
            r#"{{ "name": "t", "fluid": {{}}, "particle_spacing": {l0},
                "domain": {{ "min": [-2.1, -1.3], "max": [2.1, 1.0] }},
                "fluid_blocks": [ {{ "polygon": [[-2, -1.2], [2, -1.2], [2, 0], [-2, 0]] }} ],
                "bodies": [ {{ "name": "b", "polygon": {polygon}, "motion": {motion} }} ],
                "time": {{ "end": 0.01 }} }}"#
        ))
        .unwrap()
    }

    /// A wedge of breadth 0.5 m and `deg` degrees deadrise, keel at the origin.
    fn wedge(deg: Real) -> String {
        let h = 0.25 * deg.to_radians().tan();
        format!("[[0, 0], [0.25, {h}], [0.25, 0.5], [-0.25, 0.5], [-0.25, {h}]]")
    }

    const DOWN: &str = r#"{ "type": "prescribed", "velocity": [0, -6] }"#;

    #[test]
    fn a_wedge_in_the_validated_envelope_gets_no_advice() {
        assert!(impact_advice(&case_with(&wedge(30.0), DOWN, 0.005)).is_empty());
        assert!(impact_advice(&case_with(&wedge(15.0), DOWN, 0.005)).is_empty());
        assert!(impact_advice(&case_with(&wedge(10.0), DOWN, 0.0025)).is_empty());
    }

    #[test]
    fn a_small_deadrise_asks_for_twice_the_spacings() {
        let advice = impact_advice(&case_with(&wedge(10.0), DOWN, 0.005));
        assert_eq!(advice.len(), 1);
        assert!(
            advice[0].contains("deadrise 10.0° with 100 spacings"),
            "{}",
            advice[0]
        );
    }

    #[test]
    fn a_coarse_wedge_asks_for_a_hundred_spacings() {
        let advice = impact_advice(&case_with(&wedge(30.0), DOWN, 0.02));
        assert_eq!(advice.len(), 1);
        assert!(advice[0].contains("25 spacings across"), "{}", advice[0]);
    }

    #[test]
    fn a_flat_face_and_a_body_at_rest() {
        let box_polygon = "[[-0.25, 0], [0.25, 0], [0.25, 0.2], [-0.25, 0.2]]";
        let advice = impact_advice(&case_with(box_polygon, DOWN, 0.005));
        assert!(advice[0].contains("flat"), "{}", advice[0]);
        // a free box at rest (floating, or dropped from rest) is not judged
        let at_rest = r#"{ "type": "free", "mass": 50 }"#;
        assert!(impact_advice(&case_with(box_polygon, at_rest, 0.005)).is_empty());
        // a free wedge thrown in at 10° and 5 mm is (heavy: 5 times its plate's added
        // mass, so the deadrise is all there is to say)
        let thrown = r#"{ "type": "free", "mass": 500, "velocity": [0, -5] }"#;
        assert_eq!(
            impact_advice(&case_with(&wedge(10.0), thrown, 0.005)).len(),
            1
        );
    }

    /// A free body lighter than twice the added mass of a plate of its breadth is told
    /// that the default slows it too little; a heavier one, a prescribed one and one
    /// dropped from rest are not. The 30° wedge of breadth 0.5 m: plate 98.2 kg/m.
    #[test]
    fn a_light_free_body_is_told_it_slows_too_little() {
        let free =
            |mass: Real| format!(r#"{{ "type": "free", "mass": {mass}, "velocity": [0, -6] }}"#);
        let advice = impact_advice(&case_with(&wedge(30.0), &free(60.25), 0.005));
        assert_eq!(advice.len(), 1, "{advice:?}");
        assert!(
            advice[0].contains("light (60.25 kg/m against an added mass of about 98.2 kg/m"),
            "{}",
            advice[0]
        );
        assert!(impact_advice(&case_with(&wedge(30.0), &free(196.0), 0.005)).len() == 1);
        assert!(impact_advice(&case_with(&wedge(30.0), &free(241.0), 0.005)).is_empty());
        assert!(impact_advice(&case_with(&wedge(30.0), DOWN, 0.005)).is_empty());
        let at_rest = r#"{ "type": "free", "mass": 10 }"#;
        assert!(impact_advice(&case_with(&wedge(30.0), at_rest, 0.005)).is_empty());
    }

    /// A 128-sided circle's first segment has a deadrise of 1.4°, but over the arc it
    /// wets it is no flat face: entering 6 cm (6 m/s for 10 ms), radius 0.25 m, the
    /// mean slope of the wetted arc is the integral of asin(x/R) over the half-width
    /// sqrt(2Rh - h²), divided by it: 19.4°.
    #[test]
    fn a_circle_is_judged_by_the_arc_it_wets_not_its_first_segment() {
        let r: Real = 0.25;
        let sides = 128;
        // a vertex at the bottom: the two lowest segments are tilted by half a side
        let circle: Vec<String> = (0..sides)
            .map(|k| {
                let a = -std::f64::consts::FRAC_PI_2
                    + 2.0 * std::f64::consts::PI * k as Real / sides as Real
                    + std::f64::consts::PI / sides as Real;
                format!("[{}, {}]", r * a.cos(), r + r * a.sin())
            })
            .collect();
        // 125 spacings across, within the envelope but for the deadrise
        let case = case_with(&format!("[{}]", circle.join(", ")), DOWN, 0.004);
        let body = &case.bodies[0];
        let d = Vec2::new(0.0, -1.0);
        let first = crate::engine::config::leading_deadrise(body, d)
            .unwrap()
            .to_degrees();
        assert!(first < 1.5, "the first segment's deadrise {first}");
        // the mean slope of the wetted arc, by quadrature
        let h = 0.06;
        let c = (2.0 * r * h - h * h).sqrt();
        let n = 10_000;
        let exact = (0..n)
            .map(|k| ((k as Real + 0.5) / n as Real * c / r).asin())
            .sum::<Real>()
            / n as Real;
        let wetted = wetted_deadrise(body, d, h).unwrap();
        assert!(
            (wetted - exact).abs() < 0.3_f64.to_radians(),
            "wetted deadrise {:.2}° against the arc's {:.2}°",
            wetted.to_degrees(),
            exact.to_degrees()
        );
        assert!(
            impact_advice(&case).is_empty(),
            "{:?}",
            impact_advice(&case)
        );
    }

    /// A wedge reads its own deadrise whatever the depth below its chines, and a heeled
    /// wedge the width-weighted mean of its two faces.
    #[test]
    fn a_wedge_reads_its_deadrise_and_a_heeled_one_the_mean_of_its_faces() {
        let d = Vec2::new(0.0, -1.0);
        for deg in [10.0, 30.0] {
            let case = case_with(&wedge(deg), DOWN, 0.005);
            for h in [0.001, 0.03] {
                let beta = wetted_deadrise(&case.bodies[0], d, h).unwrap();
                assert!(
                    (beta.to_degrees() - deg).abs() < 1e-9,
                    "{deg}° at {h}: {beta}"
                );
            }
        }
        // faces of 20° and 40° (keel at the origin): at depth h each wets h / tan β
        let (t20, t40) = (20.0_f64.to_radians().tan(), 40.0_f64.to_radians().tan());
        let polygon = format!(
            "[[0, 0], [0.3, {}], [0.3, 0.5], [-0.3, 0.5], [-0.3, {}]]",
            0.3 * t20,
            0.3 * t40
        );
        let case = case_with(&polygon, DOWN, 0.005);
        let h = 0.05;
        let (w20, w40) = (h / t20, h / t40);
        let mean = (20.0 * w20 + 40.0 * w40) / (w20 + w40);
        let beta = wetted_deadrise(&case.bodies[0], d, h).unwrap().to_degrees();
        assert!((beta - mean).abs() < 1e-9, "{beta} against {mean}");
    }
}
