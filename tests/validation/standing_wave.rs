//! Viscous standing wave (Souto-Iglesias et al. 2013 §5.6; docs/references.md, Standing
//! wave): one wavelength
//! (L = 1 m, k = 2 pi) in a tank with free-slip ends, depth 0.5 m, amplitude 0.025 m,
//! nu = 5e-3 m²/s, l0 = 10 mm, released at rest with a cosine surface.
//!
//! References, both analytic: the angular frequency omega² = g k tanh kH = 7.836 rad/s,
//! and the decay of the kinetic energy. Lighthill's E_k ∝ exp(-4 nu k² t) (0.790 1/s) is
//! the small-viscosity limit of the exact linear rate of Lamb §349 (0.700 1/s here,
//! nu k²/omega = 0.025); the test compares with the exact one and reports both.
//!
//! What the default strain-rate viscous term and the Laplacian form read is in
//! docs/validation.md; the Laplacian form's dissipation at a free surface is half the
//! physical one.

use super::shipped_case;
use mpsfsi::analysis::measure::{exponential_decay_rate, oscillation_peaks};
use mpsfsi::analysis::reference::{exact_energy_decay, lighthill_energy_decay, wave_frequency};
use mpsfsi::case::{Limits, ValidCase};
use mpsfsi::run::{run_case, Quiet, RunStatus};
use std::f64::consts::PI;

fn kinetic_energy_peaks(overrides: &[&str], label: &str) -> Vec<(f64, f64)> {
    let case = ValidCase::new(
        shipped_case("standing_wave.json", overrides),
        &Limits::default(),
    )
    .unwrap();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(label);
    let summary = run_case(&case, &dir, &mut Quiet).expect("the run directory is writable");
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
    let text = std::fs::read_to_string(dir.join("energy.csv")).unwrap();
    let (mut t, mut e) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        t.push(f[0]);
        e.push(f[1]);
    }
    let omega = wave_frequency(9.81, 2.0 * PI, 0.5);
    oscillation_peaks(&t, &e, 0.5 * PI / omega)
}

#[test]
fn standing_wave_oscillates_at_the_linear_frequency_and_decays_at_the_viscous_rate() {
    let k = 2.0 * PI;
    let nu = 5.0e-3;
    let omega = wave_frequency(9.81, k, 0.5);
    let exact = exact_energy_decay(9.81, nu, k).unwrap();
    let peaks = kinetic_energy_peaks(&[], "standing-wave-default");
    println!("kinetic-energy peaks (t, E_k J/m): {peaks:.4?}");
    // four seconds are five periods: ten peaks of the kinetic energy
    assert!(peaks.len() >= 9, "{} peaks", peaks.len());
    let span = peaks.last().unwrap().0 - peaks[0].0;
    let measured_omega = PI * (peaks.len() - 1) as f64 / span;
    let rate = exponential_decay_rate(&peaks).unwrap();
    println!(
        "omega {measured_omega:.4} vs {omega:.4}; decay {rate:.4} vs exact {exact:.4} (Lighthill {:.4})",
        lighthill_energy_decay(nu, k)
    );
    assert!(
        (measured_omega / omega - 1.0).abs() < 0.02,
        "omega {measured_omega} vs {omega}"
    );
    assert!(
        (rate / exact - 1.0).abs() < 0.15,
        "decay rate {rate} vs {exact}"
    );
    // the energy never comes back: each peak below the one two before it
    for w in peaks.windows(3) {
        assert!(w[2].1 < w[0].1, "energy grew: {w:?}");
    }
}
