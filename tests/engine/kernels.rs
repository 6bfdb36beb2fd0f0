//! Kernel properties: compact support, positivity, monotonic decay, and derivatives
//! equal to central finite differences.

use mpsfsi::engine::kernel::{Kernel, Koshizuka, NonSingular, WendlandC2};

fn check<K: Kernel>(name: &str) {
    let re = 2.1;
    assert_eq!(K::w(re, re), 0.0, "{name}: w(r_e) must vanish");
    assert_eq!(K::w(1.5 * re, re), 0.0, "{name}: w beyond r_e must vanish");
    let mut prev = f64::INFINITY;
    for k in 1..200 {
        let r = re * k as f64 / 200.0;
        let w = K::w(r, re);
        assert!(w > 0.0, "{name}: w({r}) = {w} must be positive inside r_e");
        assert!(w < prev, "{name}: w must decrease with r");
        prev = w;
        let h = 1e-6;
        let fd1 = (K::w(r + h, re) - K::w(r - h, re)) / (2.0 * h);
        assert!(
            (fd1 - K::dw(r, re)).abs() <= 1e-5 * (1.0 + fd1.abs()),
            "{name}: w'({r}) {} vs finite difference {fd1}",
            K::dw(r, re)
        );
        let fd2 = (K::dw(r + h, re) - K::dw(r - h, re)) / (2.0 * h);
        assert!(
            (fd2 - K::d2w(r, re)).abs() <= 1e-4 * (1.0 + fd2.abs()),
            "{name}: w''({r}) {} vs {fd2}",
            K::d2w(r, re)
        );
        let hl = K::d2w(r, re) - K::dw(r, re) / r;
        assert!(
            (hl - K::hl(r, re)).abs() <= 1e-9 * (1.0 + hl.abs()),
            "{name}: HL weight"
        );
    }
}

#[test]
fn koshizuka_kernel_properties() {
    check::<Koshizuka>("koshizuka");
}

#[test]
fn non_singular_kernel_properties() {
    check::<NonSingular>("non_singular");
    assert_eq!(NonSingular::w(0.0, 2.0), 1.0, "bounded at the origin");
}

#[test]
fn wendland_kernel_properties() {
    check::<WendlandC2>("wendland_c2");
}
