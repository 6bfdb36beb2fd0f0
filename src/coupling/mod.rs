//! Rigid bodies through rapier2d (f64): the only module that imports rapier.
//!
//! The engine sees a body as a wall object with a pose, a velocity and an
//! acceleration ([`WallState`]) and hands back the force and moment the fluid put on
//! it during a step ([`crate::engine::WallLoad`]). Around every fluid step:
//!
//! 1. [`Coupling::before_step`]: prescribed bodies get their imposed velocity for the
//!    step (constant, or the mean of the time table over the step, so the
//!    displacement is the exact integral of the table) in rapier (kinematic
//!    velocity-based bodies) and in their wall state. The velocity is that of the
//!    polygon's centroid, and the body turns about the centroid.
//! 2. `Simulation::step(dt)` moves the fluid with the bodies at their predicted pose.
//! 3. [`Coupling::after_step`]: for free (dynamic) bodies, reset rapier's user forces
//!    (they persist across steps), add the fluid force and moment, gravity M g and
//!    the added-mass stabilisation terms ([`added_mass`]), step rapier with the same
//!    dt (rapier resolves body–wall and body–body contact), and write the new pose,
//!    velocity and acceleration back into the wall states.
//!
//! World gravity in rapier is zero: gravity is added as the force M g so that the
//! added-mass estimate in the rapier mass does not weigh anything.
//!
//! Fixed walls become fixed polyline colliders, bodies polygon colliders of zero
//! density (their mass properties are set explicitly: the case mass, the inertia
//! given or from the polygon at uniform density, the centroid as centre of mass).

pub mod added_mass;

pub use crate::case::prescribed::{Kinematics, PrescribedVelocity};
pub use added_mass::AddedMass;

use crate::case::{Case, Dof, Motion};
use crate::engine::Simulation;
use crate::geometry::{centroid, polar_moment_about_centroid, signed_area};
use crate::math::{cross, rotate, vec2, Real, Vec2};
use crate::state_io::{StateError, StateReader, StateWriter};
use rapier2d_f64::prelude::{
    ColliderBuilder, LockedAxes, MassProperties, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle,
    Vector,
};

/// One row of bodies.csv (centre of mass, angle, velocities): defined with the writers.
pub use crate::output::BodySample;

/// Coupling choices that are not part of the case format.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CouplingOptions {
    pub added_mass: AddedMass,
}

#[derive(Debug, Clone)]
enum BodyKind {
    Prescribed(PrescribedVelocity),
    Free(FreeBody),
}

#[derive(Debug, Clone)]
struct FreeBody {
    mass: Real,
    inertia: Real,
    free_x: bool,
    free_y: bool,
    free_rotation: bool,
    /// Added-mass estimate used in the last step.
    added_mass: Real,
    added_inertia: Real,
    /// Acceleration of the last step (a^n of the stabilisation).
    acceleration: Vec2,
    angular_acceleration: Real,
}

/// What a free body carries from one step to the next besides rapier's state.
#[derive(serde::Serialize, serde::Deserialize)]
struct FreeState {
    added_mass: Real,
    added_inertia: Real,
    acceleration: Vec2,
    angular_acceleration: Real,
}

fn free_state(b: &CoupledBody) -> Option<FreeState> {
    match &b.kind {
        BodyKind::Free(f) => Some(FreeState {
            added_mass: f.added_mass,
            added_inertia: f.added_inertia,
            acceleration: f.acceleration,
            angular_acceleration: f.angular_acceleration,
        }),
        BodyKind::Prescribed(_) => None,
    }
}

#[derive(Debug, Clone)]
struct CoupledBody {
    name: String,
    /// Index into `Simulation::walls`.
    wall: usize,
    handle: RigidBodyHandle,
    /// Centre of mass in the body frame.
    local_com: Vec2,
    kind: BodyKind,
}

/// The rapier side of a simulation with bodies. Built only when the case has bodies.
pub struct Coupling {
    world: PhysicsWorld,
    bodies: Vec<CoupledBody>,
    gravity: Vec2,
    options: CouplingOptions,
    /// Wall-clock seconds spent in the coupling (both hooks), for the cost report.
    pub seconds: f64,
}

fn to_rapier(v: Vec2) -> Vector {
    Vector::new(v.x, v.y)
}

fn from_rapier(v: Vector) -> Vec2 {
    Vec2::new(v.x, v.y)
}

fn is_convex(poly: &[Vec2]) -> bool {
    let n = poly.len();
    let s = signed_area(poly).signum();
    (0..n).all(|k| {
        let (a, b, c) = (poly[k], poly[(k + 1) % n], poly[(k + 2) % n]);
        cross(b - a, c - b) * s >= -1e-12
    })
}

impl Coupling {
    /// The coupling of a case, or `None` when it has no bodies (no rapier pipeline).
    pub fn new(case: &Case, sim: &Simulation) -> Option<Self> {
        Self::with_options(case, sim, CouplingOptions::default())
    }

    pub fn with_options(case: &Case, sim: &Simulation, options: CouplingOptions) -> Option<Self> {
        if case.bodies.is_empty() {
            return None;
        }
        let mut world = PhysicsWorld {
            gravity: Vector::ZERO,
            ..PhysicsWorld::default()
        };
        // fixed walls: polylines attached to no body are fixed
        for w in &case.walls {
            let pts: Vec<Vector> = w.polyline.iter().map(|p| Vector::new(p[0], p[1])).collect();
            let n = pts.len() as u32;
            let mut idx: Vec<[u32; 2]> = (0..n.saturating_sub(1)).map(|k| [k, k + 1]).collect();
            if w.closed && n > 2 {
                idx.push([n - 1, 0]);
            }
            world
                .colliders
                .insert(ColliderBuilder::polyline(pts, Some(idx)).friction(0.0));
        }
        let mut bodies = Vec::new();
        for (wall, object) in sim.walls.iter().enumerate() {
            let Some(b) = object.body else { continue };
            let body = &case.bodies[b];
            let poly: Vec<Vec2> = body.polygon.iter().map(|p| vec2(*p)).collect();
            let local_com = centroid(&poly);
            let state = &object.state;
            let (builder, kind) = match &body.motion {
                Motion::Prescribed {
                    velocity,
                    angular_velocity,
                    table,
                } => {
                    let prescribed =
                        PrescribedVelocity::new(*velocity, *angular_velocity, table.as_ref());
                    // the imposed velocity is that of the centroid, and the body turns
                    // about it: give rapier the centroid as the centre of mass (the mass
                    // itself plays no role for a kinematic body)
                    let builder =
                        RigidBodyBuilder::kinematic_velocity_based().additional_mass_properties(
                            MassProperties::new(to_rapier(local_com), 1.0, 1.0),
                        );
                    (builder, BodyKind::Prescribed(prescribed))
                }
                Motion::Free {
                    mass,
                    inertia,
                    locked,
                    ..
                } => {
                    let area = signed_area(&poly).abs();
                    let inertia =
                        inertia.unwrap_or_else(|| mass / area * polar_moment_about_centroid(&poly));
                    let free_x = !locked.contains(&Dof::X);
                    let free_y = !locked.contains(&Dof::Y);
                    let free_rotation = !locked.contains(&Dof::Rotation);
                    let mut axes = LockedAxes::empty();
                    if !free_x {
                        axes |= LockedAxes::TRANSLATION_LOCKED_X;
                    }
                    if !free_y {
                        axes |= LockedAxes::TRANSLATION_LOCKED_Y;
                    }
                    if !free_rotation {
                        axes |= LockedAxes::ROTATION_LOCKED;
                    }
                    let builder = RigidBodyBuilder::dynamic()
                        .locked_axes(axes)
                        .can_sleep(false)
                        .additional_mass_properties(MassProperties::new(
                            to_rapier(local_com),
                            *mass,
                            inertia,
                        ));
                    let free = FreeBody {
                        mass: *mass,
                        inertia,
                        free_x,
                        free_y,
                        free_rotation,
                        added_mass: 0.0,
                        added_inertia: 0.0,
                        acceleration: Vec2::zeros(),
                        angular_acceleration: 0.0,
                    };
                    (builder, BodyKind::Free(free))
                }
            };
            let rb = builder
                .translation(to_rapier(state.position))
                .rotation(state.angle)
                .linvel(to_rapier(state.velocity))
                .angvel(state.angular_velocity);
            let pts: Vec<Vector> = poly.iter().map(|p| to_rapier(*p)).collect();
            let collider = if is_convex(&poly) {
                ColliderBuilder::convex_polyline(pts.clone())
            } else {
                None
            }
            .unwrap_or_else(|| {
                let n = pts.len() as u32;
                let idx: Vec<[u32; 2]> = (0..n).map(|k| [k, (k + 1) % n]).collect();
                ColliderBuilder::convex_decomposition(&pts, &idx)
            })
            .density(0.0)
            .friction(0.0);
            let (handle, _) = world.insert(rb, collider);
            bodies.push(CoupledBody {
                name: body.name.clone(),
                wall,
                handle,
                local_com,
                kind,
            });
        }
        Some(Self {
            world,
            bodies,
            gravity: vec2(case.fluid.gravity),
            options,
            seconds: 0.0,
        })
    }

    /// Impose the prescribed velocities over the step [t, t + dt] (t = `sim.time`).
    pub fn before_step(&mut self, sim: &mut Simulation, dt: Real) {
        let clock = std::time::Instant::now();
        for b in &self.bodies {
            let BodyKind::Prescribed(p) = &b.kind else {
                continue;
            };
            let k = p.over_step(sim.time, dt);
            let rb = &mut self.world.bodies[b.handle];
            rb.set_linvel(to_rapier(k.velocity), true);
            rb.set_angvel(k.angular_velocity, true);
            let state = &mut sim.walls[b.wall].state;
            state.velocity = k.velocity;
            state.angular_velocity = k.angular_velocity;
            state.acceleration = k.acceleration;
            state.angular_acceleration = k.angular_acceleration;
        }
        self.seconds += clock.elapsed().as_secs_f64();
    }

    /// Apply the loads of the step just taken, step rapier by `dt` and write the bodies'
    /// new states into the simulation's wall objects.
    pub fn after_step(&mut self, sim: &mut Simulation, dt: Real) {
        let clock = std::time::Instant::now();
        let model = self.options.added_mass;
        for b in &mut self.bodies {
            let BodyKind::Free(f) = &mut b.kind else {
                continue;
            };
            let load = sim.loads[b.wall];
            let (ma, ia) =
                added_mass::estimate(model, sim, b.wall, f.free_x, f.free_y, f.free_rotation);
            f.added_mass = ma;
            f.added_inertia = ia;
            let rb = &mut self.world.bodies[b.handle];
            rb.set_additional_mass_properties(
                MassProperties::new(to_rapier(b.local_com), f.mass + ma, f.inertia + ia),
                true,
            );
            // rapier keeps user forces across steps: reset, then add this step's
            rb.reset_forces(true);
            rb.reset_torques(true);
            let force = load.force + self.gravity * f.mass + f.acceleration * ma;
            let torque = load.moment + ia * f.angular_acceleration;
            rb.add_force(to_rapier(force), true);
            rb.add_torque(torque, true);
        }
        let before: Vec<(Vec2, Real)> = self
            .bodies
            .iter()
            .map(|b| {
                let rb = &self.world.bodies[b.handle];
                (from_rapier(rb.linvel()), rb.angvel())
            })
            .collect();
        self.world.integration_parameters.dt = dt;
        self.world.step();
        for (b, (v0, w0)) in self.bodies.iter_mut().zip(before) {
            let rb = &self.world.bodies[b.handle];
            let state = &mut sim.walls[b.wall].state;
            let angle = rb.rotation().angle();
            // keep the angle continuous across ±pi
            let turn = (angle - state.angle + std::f64::consts::PI)
                .rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            state.angle += turn;
            state.position = from_rapier(rb.translation());
            state.center_of_mass = state.position + rotate(b.local_com, state.angle);
            let (v, w) = (from_rapier(rb.linvel()), rb.angvel());
            if let BodyKind::Free(f) = &mut b.kind {
                f.acceleration = (v - v0) / dt;
                f.angular_acceleration = (w - w0) / dt;
                state.acceleration = f.acceleration;
                state.angular_acceleration = f.angular_acceleration;
            }
            state.velocity = v;
            state.angular_velocity = w;
        }
        self.seconds += clock.elapsed().as_secs_f64();
    }

    /// Rapier's world (bodies, contacts and their warm-start impulses) and each free
    /// body's added mass and last acceleration (the stabilisation reads them), for a
    /// checkpoint; [`Coupling::restore_state`] reads them back into the coupling the
    /// same case builds.
    pub fn save_state(&self, w: &mut StateWriter) -> std::io::Result<()> {
        w.put(&self.world)?;
        let free: Vec<FreeState> = self.bodies.iter().filter_map(free_state).collect();
        w.put(&free)?;
        w.put(&self.seconds)
    }

    pub fn restore_state(&mut self, r: &mut StateReader) -> Result<(), StateError> {
        self.world = r.take()?;
        let saved: Vec<FreeState> = r.take()?;
        let mut saved = saved.into_iter();
        for b in &mut self.bodies {
            let BodyKind::Free(f) = &mut b.kind else {
                continue;
            };
            let s = saved.next().ok_or_else(|| {
                StateError::Mismatch("fewer free bodies saved than the case has".into())
            })?;
            (f.added_mass, f.added_inertia) = (s.added_mass, s.added_inertia);
            (f.acceleration, f.angular_acceleration) = (s.acceleration, s.angular_acceleration);
        }
        if saved.next().is_some() || self.world.bodies.len() != self.bodies.len() {
            return Err(StateError::Mismatch(
                "the saved bodies are not the case's".into(),
            ));
        }
        self.seconds = r.take()?;
        Ok(())
    }

    /// Centre of mass, angle and velocities of every body (bodies.csv), in case order.
    pub fn samples(&self, sim: &Simulation) -> Vec<BodySample> {
        self.bodies
            .iter()
            .map(|b| {
                let s = &sim.walls[b.wall].state;
                let (v, w) = match &b.kind {
                    // report the imposed velocity at this instant, not the step mean
                    BodyKind::Prescribed(p) => {
                        let k = p.at(sim.time);
                        (k.velocity, k.angular_velocity)
                    }
                    BodyKind::Free(_) => (s.velocity, s.angular_velocity),
                };
                BodySample {
                    name: b.name.clone(),
                    x: s.center_of_mass.x,
                    y: s.center_of_mass.y,
                    angle: s.angle,
                    vx: v.x,
                    vy: v.y,
                    omega: w,
                }
            })
            .collect()
    }

    /// Current added-mass estimates (mass, inertia) per body, in case order (zero for
    /// prescribed bodies), for diagnostics.
    pub fn added_mass(&self) -> Vec<(Real, Real)> {
        self.bodies
            .iter()
            .map(|b| match &b.kind {
                BodyKind::Free(f) => (f.added_mass, f.added_inertia),
                BodyKind::Prescribed(_) => (0.0, 0.0),
            })
            .collect()
    }

    /// Number of bodies coupled.
    pub fn len(&self) -> usize {
        self.bodies.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }
}
