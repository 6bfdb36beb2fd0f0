//! Published and computed reference answers the benchmark and the tests compare with, each
//! with its source (docs/references.md gives every one).

use crate::math::Real;

/// Martin & Moyce (1952), "An experimental study of the collapse of liquid columns on a
/// rigid horizontal plane", Phil. Trans. R. Soc. A 244, 312-324: surge front of a
/// column of width a and height 2a (n² = 2). T = t sqrt(2 g / a), Z = x_front / a
/// (x from the back wall).
pub const MARTIN_MOYCE_SURGE: [(Real, Real); 15] = [
    (0.41, 1.11),
    (0.84, 1.22),
    (1.19, 1.44),
    (1.43, 1.67),
    (1.63, 1.89),
    (1.83, 2.11),
    (1.98, 2.33),
    (2.20, 2.56),
    (2.32, 2.78),
    (2.51, 3.00),
    (2.65, 3.22),
    (2.83, 3.44),
    (2.98, 3.67),
    (3.11, 3.89),
    (3.33, 4.11),
];

/// Martin & Moyce (1952), same paper: residual column height H / (2a) against
/// t sqrt(g / a).
pub const MARTIN_MOYCE_COLUMN: [(Real, Real); 14] = [
    (0.56, 0.94),
    (0.77, 0.89),
    (0.93, 0.83),
    (1.08, 0.78),
    (1.28, 0.72),
    (1.46, 0.67),
    (1.66, 0.61),
    (1.84, 0.56),
    (2.00, 0.50),
    (2.21, 0.44),
    (2.45, 0.39),
    (2.70, 0.33),
    (3.06, 0.28),
    (3.44, 0.22),
];

/// The benchmark compares the surge front for T in this range: earlier times depend on
/// how the column is released (docs/references.md), later ones are beyond the table.
pub const SURGE_COMPARISON_RANGE: (Real, Real) = (1.0, 3.0);

/// Koshizuka & Oka (1996) MPS dam-break geometry: column width L (m); the column is 2L
/// high in a tank 4L wide.
pub const KOSHIZUKA_OKA_COLUMN_WIDTH: Real = 0.146;

/// Vertical force coefficient C_F = F / (rho V³ t) of a 30° deadrise wedge entering
/// at constant speed: the nonlinear self-similar solution computed for this project
/// (docs/references.md; reproduces Zhao & Faltinsen 1993, J. Fluid Mech. 246, peak pressures
/// within 0.6%), ±0.3%.
pub const WEDGE_30_FORCE_COEFFICIENT: Real = 14.04;

/// The modified Logvinovich model's C_F of the same wedge at constant speed (docs/references.md,
/// Korobkin 2004): 7 % above the similarity solution.
pub const LOGVINOVICH_30_FORCE_COEFFICIENT: Real = 15.09;

/// The largest pressure on a wedge entering at constant speed, Cp_max = p_max / (½ ρ V²),
/// and its height above the undisturbed surface over V t, by deadrise in degrees: Zhao &
/// Faltinsen (1993), J. Fluid Mech. 246, similarity solution (docs/references.md).
pub const SIMILARITY_PEAK: [(Real, Real, Real); 6] = [
    (10.0, 77.85, 0.5556),
    (15.0, 33.27, 0.5361),
    (20.0, 17.77, 0.5087),
    (25.0, 10.69, 0.4709),
    (30.0, 6.927, 0.4243),
    (40.0, 3.266, 0.2866),
];

/// The 30° wedge's Cp along the wetted face at z/(Vt) = −1 (keel) … 0.3 (docs/references.md,
/// the project's self-similar solution; `analysis::similarity` holds the whole profile).
pub const WEDGE_30_FACE_PRESSURE: [(Real, Real); 8] = [
    (-1.0, 4.59),
    (-0.75, 4.54),
    (-0.5, 4.62),
    (-0.25, 4.83),
    (0.0, 5.25),
    (0.1, 5.52),
    (0.2, 5.88),
    (0.3, 6.35),
];

/// (Cp_max, z_max / (V t)) of the tabulated deadrise within 0.5° of `beta` (radians);
/// None between the table's angles, where the peak is not interpolated.
pub fn similarity_peak(beta: Real) -> Option<(Real, Real)> {
    SIMILARITY_PEAK
        .iter()
        .find(|(deg, _, _)| (beta.to_degrees() - deg).abs() <= 0.5)
        .map(|&(_, cp, z)| (cp, z))
}

/// Wagner (1932) C_F = pi³ / (4 tan² beta): an upper bound, 66% high at 30°.
pub fn wagner_force_coefficient(beta: Real) -> Real {
    std::f64::consts::PI.powi(3) / (4.0 * beta.tan().powi(2))
}

/// Angular frequency of a linear gravity wave, omega² = g k tanh(k H) (docs/references.md,
/// Standing wave).
pub fn wave_frequency(g: Real, k: Real, depth: Real) -> Real {
    (g * k * (k * depth).tanh()).sqrt()
}

/// Lighthill's (2001) decay rate of a standing wave's kinetic energy, E_k ∝
/// exp(-4 nu k² t): the leading order in nu k² / omega of the exact linear rate below.
pub fn lighthill_energy_decay(nu: Real, k: Real) -> Real {
    4.0 * nu * k * k
}

/// The exact linear decay rate of a free-surface wave's energy in deep water (Lamb
/// 1932, §349): -2 Re(s) for the root s (time factor e^{st}) of
/// (s + 2 nu k²)² + g k = 4 nu² k³ sqrt(k² + s / nu) near the inviscid i omega, found by
/// Newton's method from Lighthill's estimate. Lighthill's 4 nu k² is its limit for
/// nu k² / omega -> 0; at nu k² / omega = 0.025 (the shipped standing wave) it is 13 %
/// above this value. None when Newton's method does not converge.
pub fn exact_energy_decay(g: Real, nu: Real, k: Real) -> Option<Real> {
    use nalgebra::Complex;
    let nk2 = nu * k * k;
    let residual = |s: Complex<Real>| {
        let root = (Complex::new(k * k, 0.0) + s / nu).sqrt();
        let f = (s + 2.0 * nk2).powi(2) + g * k - root * (4.0 * nu * nu * k.powi(3));
        let df = (s + 2.0 * nk2) * 2.0 - (Complex::new(2.0 * nu * k.powi(3), 0.0) / root);
        (f, df)
    };
    let mut s = Complex::new(-2.0 * nk2, (g * k).sqrt());
    for _ in 0..100 {
        let (f, df) = residual(s);
        let step = f / df;
        s -= step;
        if step.norm() <= 1e-13 * s.norm() {
            return Some(-2.0 * s.re);
        }
    }
    None
}

/// The momentum model of a wedge falling freely into calm water: Wagner's entry force
/// F = d(m_a V)/dt with an added mass of the penetration h only, calibrated to the
/// similarity solution, m_a(h) = C_F rho h² / 2 (so that F = C_F rho V³ t at constant
/// speed), and M dV/dt = M g - F (downward positive): (M + m_a(h)) V = M (V0 + g t),
/// dh/dt = V, from contact at t = 0 (docs/references.md, constant-velocity wedge entry).
#[derive(Debug, Clone, Copy)]
pub struct FreeFallModel {
    /// Downward speed at contact (m/s).
    pub v0: Real,
    /// Downward gravity (m/s²).
    pub g: Real,
    /// Body mass per metre (kg/m).
    pub mass: Real,
    pub force_coefficient: Real,
    pub density: Real,
}

/// A model of a body falling freely into calm water: its downward speed from contact.
pub trait FreeFall {
    /// Downward speed at contact (m/s).
    fn initial_speed(&self) -> Real;
    /// The downward speed at each of `times` (ascending, from contact).
    fn speeds(&self, times: &[Real]) -> Vec<Real>;
}

impl FreeFall for FreeFallModel {
    fn initial_speed(&self) -> Real {
        self.v0
    }
    /// Integrated with a step of 0.1 µs, far below a run's.
    fn speeds(&self, times: &[Real]) -> Vec<Real> {
        let Self {
            v0,
            g,
            mass,
            force_coefficient: c_f,
            density: rho,
        } = *self;
        let (dt, mut h, mut v) = (1e-7, 0.0, v0);
        march(times, dt, v0, |t| {
            h += v * dt;
            v = mass * (v0 + g * t) / (mass + 0.5 * c_f * rho * h * h);
            v
        })
    }
}

/// The speed at each of `times` (ascending) of a march from speed `v0` at t = 0 in steps
/// of `dt`: `step(t)` takes one step to time t and returns the speed there.
fn march(times: &[Real], dt: Real, v0: Real, mut step: impl FnMut(Real) -> Real) -> Vec<Real> {
    let (mut t, mut v) = (0.0, v0);
    times
        .iter()
        .map(|&at| {
            while t < at {
                t += dt;
                v = step(t);
            }
            v
        })
        .collect()
}

/// The modified Logvinovich model of a wedge of deadrise `beta` (radians) falling freely
/// (docs/references.md; Korobkin 2004): the body pressure
/// p/rho = V c c'/s + V' (s + f(x) - h) - V²/2 [1 + x² / (s² (1 + f'²))], s = sqrt(c² - x²),
/// integrated where it is positive, with Wagner's wetted half-width c = pi h / (2 tan beta),
/// and closed with M dV/dt = M g - F (downward positive), from contact at t = 0.
///
/// Its force at constant speed is C_F = 15.09, 7 % above the similarity solution;
/// [`LogvinovichFreeFall::matching`] scales it onto the similarity solution and keeps the
/// model's split between the V² and the dV/dt terms. That split is where it parts from
/// [`FreeFallModel`]: the dV/dt term carries rho h² (pi k²/2 + k² tan beta - 2k),
/// k = pi / (2 tan beta) (10.46 rho h² at 30°), where the momentum model carries
/// C_F rho h²/2 (7.02), so a light body, whose deceleration matters most, loses less speed.
#[derive(Debug, Clone, Copy)]
pub struct LogvinovichFreeFall {
    /// Downward speed at contact (m/s).
    pub v0: Real,
    /// Downward gravity (m/s²).
    pub g: Real,
    /// Body mass per metre (kg/m).
    pub mass: Real,
    pub density: Real,
    /// Deadrise angle (radians).
    pub beta: Real,
    pub force_scale: Real,
}

impl LogvinovichFreeFall {
    /// Quadrature points over the wetted width, x = c sin(theta): the pressure's
    /// 1/s singularity at the edges becomes a bounded integrand.
    const POINTS: usize = 500;

    /// The model of the same fall as `momentum`, on a wedge of deadrise `beta`, with its
    /// force scaled so that at constant speed it carries the momentum model's C_F: the
    /// two then differ only in how they split the force between V² and dV/dt.
    pub fn matching(momentum: &FreeFallModel, beta: Real) -> Self {
        let unscaled = Self {
            v0: momentum.v0,
            g: momentum.g,
            mass: momentum.mass,
            density: momentum.density,
            beta,
            force_scale: 1.0,
        };
        // C_F at constant speed does not depend on h or V (self-similar)
        let own = unscaled.force(1.0, 1.0, 0.0) / momentum.density;
        Self {
            force_scale: momentum.force_coefficient / own,
            ..unscaled
        }
    }

    /// Downward force per metre at penetration `h`, downward speed `v` and acceleration
    /// `dv` (the model's force, times `force_scale`).
    pub fn force(&self, h: Real, v: Real, dv: Real) -> Real {
        let tan_beta = self.beta.tan();
        let k = std::f64::consts::PI / (2.0 * tan_beta);
        let (c, dc) = (k * h, k * v);
        if c <= 0.0 {
            return 0.0;
        }
        let d_theta = std::f64::consts::PI / Self::POINTS as Real;
        let integral: Real = (0..Self::POINTS)
            .map(|m| {
                let theta = (m as Real + 0.5) * d_theta - 0.5 * std::f64::consts::PI;
                let (s, x) = (c * theta.cos(), c * theta.sin());
                // p dx / rho with dx = s dtheta: the sign of p
                let p_dx = v * c * dc + dv * (s + x.abs() * tan_beta - h) * s
                    - 0.5 * v * v * (s + x * x / (s * (1.0 + tan_beta * tan_beta)));
                p_dx.max(0.0)
            })
            .sum();
        self.force_scale * self.density * integral * d_theta
    }
}

impl FreeFall for LogvinovichFreeFall {
    fn initial_speed(&self) -> Real {
        self.v0
    }
    /// Integrated with a step of 1 µs. The force is affine in dV/dt where the pressure
    /// is positive, so each step solves M dV/dt = M g - F for dV/dt with that slope,
    /// three times (the positive region moves with dV/dt): a fixed-point iteration
    /// would diverge once the dV/dt term outweighs the body.
    fn speeds(&self, times: &[Real]) -> Vec<Real> {
        let (dt, mut t, mut h, mut v, mut dv) = (1e-6, 0.0, 0.0, self.v0, self.g);
        let m = self.mass;
        times
            .iter()
            .map(|&at| {
                while t < at {
                    for _ in 0..3 {
                        let f = self.force(h, v, dv);
                        let slope = self.force(h, v, dv + 1.0) - f;
                        dv = (m * self.g - f + slope * dv) / (m + slope);
                    }
                    v += dv * dt;
                    h += v * dt;
                    t += dt;
                }
                v
            })
            .collect()
    }
}

/// The quasi-steady potential-flow model of a wedge falling freely into calm water: at
/// each instant the similarity solution's force at the body's depth and speed,
/// C_F rho V² h, plus its acceleration reaction, `acceleration_added_mass` rho h² dV/dt
/// (the potential-flow added mass of the similarity solution's wetted geometry,
/// `analysis::similarity::SimilaritySolution::acceleration_added_mass`), closed with
/// M dV/dt = M g - F (downward positive): dV/dt = (M g - C_F rho V² h) / (M + k rho h²),
/// from contact at t = 0.
/// The momentum model ([`FreeFallModel`]) is the same with k = C_F/2; potential flow
/// gives 1.19 C_F/2 at 30° (8.31 rho h²), so a light body loses less speed than that
/// model says.
#[derive(Debug, Clone, Copy)]
pub struct PotentialFlowFreeFall {
    /// Downward speed at contact (m/s).
    pub v0: Real,
    /// Downward gravity (m/s²).
    pub g: Real,
    /// Body mass per metre (kg/m).
    pub mass: Real,
    pub density: Real,
    /// C_F = F / (rho V³ t) at constant speed.
    pub force_coefficient: Real,
    /// The added mass of the acceleration, in rho h².
    pub acceleration_added_mass: Real,
}

impl FreeFall for PotentialFlowFreeFall {
    fn initial_speed(&self) -> Real {
        self.v0
    }
    /// Integrated with a step of 0.1 µs (midpoint rule), far below a run's.
    fn speeds(&self, times: &[Real]) -> Vec<Real> {
        let Self {
            v0,
            g,
            mass,
            density: rho,
            force_coefficient: c_f,
            acceleration_added_mass: k,
        } = *self;
        let rate = |h: Real, v: Real| (mass * g - c_f * rho * v * v * h) / (mass + k * rho * h * h);
        let (dt, mut h, mut v) = (1e-7, 0.0, v0);
        march(times, dt, v0, |_| {
            let (hm, vm) = (h + 0.5 * dt * v, v + 0.5 * dt * rate(h, v));
            h += dt * vm;
            v += dt * rate(hm, vm);
            v
        })
    }
}
