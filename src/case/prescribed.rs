//! Prescribed (kinematic) motion: a constant velocity or a velocity time table,
//! linearly interpolated and held constant outside its range.

use super::VelocitySample;
use crate::math::{vec2, Real, Vec2};

/// Imposed velocity of a prescribed body.
#[derive(Debug, Clone)]
pub enum PrescribedVelocity {
    Constant {
        velocity: Vec2,
        angular_velocity: Real,
    },
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
    pub fn new(
        velocity: [Real; 2],
        angular_velocity: Real,
        table: Option<&Vec<VelocitySample>>,
    ) -> Self {
        match table {
            Some(t) if !t.is_empty() => {
                let mut t = t.clone();
                t.sort_by(|a, b| a.time.total_cmp(&b.time));
                Self::Table(t)
            }
            _ => Self::Constant {
                velocity: vec2(velocity),
                angular_velocity,
            },
        }
    }

    /// Kinematics at time `t` (the acceleration is the slope of the table segment).
    pub fn at(&self, t: Real) -> Kinematics {
        match self {
            Self::Constant {
                velocity,
                angular_velocity,
            } => Kinematics {
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
                    angular_velocity: a.angular_velocity
                        + (b.angular_velocity - a.angular_velocity) * f,
                    acceleration: (vb - va) / span,
                    angular_acceleration: (b.angular_velocity - a.angular_velocity) / span,
                }
            }
        }
    }

    /// Kinematics to impose over the step [t, t + dt]: the mean velocity of the step
    /// (so the displacement is exactly the integral of the table) and the mean
    /// acceleration.
    pub fn over_step(&self, t: Real, dt: Real) -> Kinematics {
        match self {
            Self::Constant { .. } => self.at(t),
            Self::Table(s) => {
                // the table is linear between breakpoints: trapezoids between the step
                // ends and the breakpoints inside the step integrate it exactly
                let mut times = vec![t];
                times.extend(s.iter().map(|k| k.time).filter(|&k| k > t && k < t + dt));
                times.push(t + dt);
                let mut velocity = Vec2::zeros();
                let mut angular_velocity = 0.0;
                for w in times.windows(2) {
                    let (a, b) = (self.at(w[0]), self.at(w[1]));
                    let h = w[1] - w[0];
                    velocity += (a.velocity + b.velocity) * (0.5 * h);
                    angular_velocity += 0.5 * h * (a.angular_velocity + b.angular_velocity);
                }
                let (a, b) = (self.at(t), self.at(t + dt));
                Kinematics {
                    velocity: velocity / dt,
                    angular_velocity: angular_velocity / dt,
                    acceleration: (b.velocity - a.velocity) / dt,
                    angular_acceleration: (b.angular_velocity - a.angular_velocity) / dt,
                }
            }
        }
    }
}
