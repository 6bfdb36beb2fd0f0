//! Prescribed (kinematic) motion: a constant velocity or a velocity time table,
//! linearly interpolated and held constant outside its range.

use crate::case::VelocitySample;
use crate::engine::math::{vec2, Real, Vec2};

/// Imposed velocity of a prescribed body.
#[derive(Debug, Clone)]
pub enum PrescribedVelocity {
    Constant { velocity: Vec2, angular_velocity: Real },
    /// Samples sorted by time.
    Table(Vec<VelocitySample>),
}

/// Velocity, angular velocity, acceleration and angular acceleration at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics {
    pub velocity: Vec2,
    pub angular_velocity: Real,
    pub acceleration: Vec2,
    pub angular_acceleration: Real,
}

impl PrescribedVelocity {
    pub fn new(velocity: [Real; 2], angular_velocity: Real, table: Option<&Vec<VelocitySample>>) -> Self {
        match table {
            Some(t) if !t.is_empty() => {
                let mut t = t.clone();
                t.sort_by(|a, b| a.time.total_cmp(&b.time));
                Self::Table(t)
            }
            _ => Self::Constant { velocity: vec2(velocity), angular_velocity },
        }
    }

    /// Kinematics at time `t` (the acceleration is the slope of the table segment).
    pub fn at(&self, t: Real) -> Kinematics {
        match self {
            Self::Constant { velocity, angular_velocity } => Kinematics {
                velocity: *velocity,
                angular_velocity: *angular_velocity,
                acceleration: Vec2::zeros(),
                angular_acceleration: 0.0,
            },
            Self::Table(s) => {
                let hold = |k: &VelocitySample| Kinematics {
                    velocity: vec2(k.velocity),
                    angular_velocity: k.angular_velocity,
                    acceleration: Vec2::zeros(),
                    angular_acceleration: 0.0,
                };
                let first = &s[0];
                let last = &s[s.len() - 1];
                if t <= first.time {
                    return hold(first);
                }
                if t >= last.time {
                    return hold(last);
                }
                // first k with s[k].time > t; 1 <= k < len
                let k = s.partition_point(|x| x.time <= t);
                let (a, b) = (&s[k - 1], &s[k]);
                let span = b.time - a.time;
                let f = (t - a.time) / span;
                let (va, vb) = (vec2(a.velocity), vec2(b.velocity));
                Kinematics {
                    velocity: va + (vb - va) * f,
                    angular_velocity: a.angular_velocity + (b.angular_velocity - a.angular_velocity) * f,
                    acceleration: (vb - va) / span,
                    angular_acceleration: (b.angular_velocity - a.angular_velocity) / span,
                }
            }
        }
    }

    /// Kinematics to impose over the step [t, t + dt]: the mean velocity of the step
    /// (exact displacement for a piecewise-linear table) and the mean acceleration.
    pub fn over_step(&self, t: Real, dt: Real) -> Kinematics {
        match self {
            Self::Constant { .. } => self.at(t),
            Self::Table(_) => {
                let mid = self.at(t + 0.5 * dt);
                let (a, b) = (self.at(t), self.at(t + dt));
                // mean velocity over the step: Simpson is exact for piecewise-linear
                // velocity within one segment; across a kink it is the trapezoid of halves
                let (m1, m2) = (self.at(t + 0.25 * dt), self.at(t + 0.75 * dt));
                let velocity = (a.velocity + m1.velocity * 2.0 + mid.velocity * 2.0 + m2.velocity * 2.0 + b.velocity) / 8.0;
                let angular_velocity = (a.angular_velocity
                    + 2.0 * (m1.angular_velocity + mid.angular_velocity + m2.angular_velocity)
                    + b.angular_velocity)
                    / 8.0;
                Kinematics {
                    velocity,
                    angular_velocity,
                    acceleration: (b.velocity - a.velocity) / dt,
                    angular_acceleration: (b.angular_velocity - a.angular_velocity) / dt,
                }
            }
        }
    }
}
