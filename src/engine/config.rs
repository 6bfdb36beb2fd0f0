//! The configuration of one simulation, fixed for the run: the parameters, the method
//! (the engine's form of the case's `scheme` block) and the step control. The case
//! format is the contract and stays as it is; it is converted here once, into closed
//! enums that carry their own data, so a stage matches on a variant and finds what it
//! needs inside it.

use super::params::MpsParameters;
use crate::case::{
    self, Case, GradientKind, KernelKind, LaplacianKind, Scheme, SolverKind, ViscosityKind,
    WallKinematics, WallLoadKind,
};
use crate::math::{rotate, vec2, Real, Vec2};

/// Source term of the pressure Poisson equation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// PND deviation (n* - n0)/n0 (Koshizuka & Oka 1996).
    Pnd,
    /// Higher-order source HS (Ikari, Khayyer & Gotoh 2015 eq. 3).
    HigherOrder,
    /// HS plus error-compensating terms ECS (Ikari, Khayyer & Gotoh 2015 eqs. 10-11).
    HigherOrderEcs,
    /// Velocity divergence plus the PND deviation relaxed by `relaxation` (Sun et al. 2022
    /// eq. 49 family).
    Mixed { relaxation: Real },
}

/// The pressure equation of the particles away from the free surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// The HL Laplacian of the pressure equals (rho/dt) times the source.
    Approximate,
    /// The corrected velocity itself has the source's HS divergence, with a share
    /// `blend` of the Laplacian row kept (`step::exact`).
    Exact { blend: Real },
}

/// How particles are kept apart beyond the pressure solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpacingControl {
    None,
    /// Pairwise inelastic collision below `distance` (in l0).
    Collision {
        distance: Real,
    },
}

/// Free-surface detection: n* below `threshold` n0, confirmed by a one-sided
/// neighbourhood (|Σ w r/r²| l0 / n above `asymmetry`); the Dirichlet value at the
/// hydrostatic pressure half a spacing below the surface when `offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeSurface {
    pub threshold: Real,
    pub asymmetry: Real,
    pub offset: bool,
    /// The graded test (`Scheme::soft_surface`).
    pub soft: bool,
}

/// The corrected gradient's repulsive minimum-pressure term: `strength` over pairs
/// closer than `distance` (in l0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stabilization {
    pub strength: Real,
    pub distance: Real,
}

/// The linear solver of the pressure equation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solver {
    pub kind: SolverKind,
    pub tolerance: Real,
    /// The relative energy-norm error at which conjugate gradients stop (0: none).
    pub energy_tolerance: Real,
    pub max_iterations: usize,
    pub amg_rebuild_interval: usize,
}

/// The numerical method: every choice of the `scheme` block, resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct Method {
    pub kernel: KernelKind,
    pub gradient: GradientKind,
    pub stabilization: Stabilization,
    pub laplacian: LaplacianKind,
    /// Pair weights of the pressure equation divided by the mean fill n*/n0, floored
    /// at this value (`scheme.laplacian_fill_floor` below 1).
    pub laplacian_fill_floor: Option<Real>,
    pub source: Source,
    pub projection: Projection,
    pub solver: Solver,
    pub free_surface: FreeSurface,
    pub clip_negative_pressure: bool,
    /// rho alpha / dt² on the diagonal (artificial compressibility alpha).
    pub compressibility: Real,
    pub hydrostatic_ghosts: bool,
    pub viscosity: ViscosityKind,
    pub spacing_control: SpacingControl,
    /// Inelastic wall impulse below this distance (in l0).
    pub wall_repulsion_distance: Real,
    /// Restitution of the collisions and of the wall impulse.
    pub restitution: Real,
    pub velocity_filter: Option<Real>,
    pub shifting: Option<Real>,
    pub wall_load: WallLoadKind,
    pub wall_kinematics: WallKinematics,
}

impl Method {
    /// The engine's form of a (resolved) scheme block.
    pub fn new(s: &Scheme) -> Self {
        let positive = |v: Real| (v > 0.0).then_some(v);
        Self {
            kernel: s.kernel,
            gradient: s.gradient,
            stabilization: Stabilization {
                strength: s.gradient_stabilization,
                distance: s.stabilization_distance,
            },
            laplacian: s.laplacian,
            laplacian_fill_floor: (s.laplacian_fill_floor < 1.0).then_some(s.laplacian_fill_floor),
            source: match s.source {
                case::SourceKind::Pnd => Source::Pnd,
                case::SourceKind::HigherOrder => Source::HigherOrder,
                case::SourceKind::HigherOrderEcs => Source::HigherOrderEcs,
                case::SourceKind::Mixed => Source::Mixed {
                    relaxation: s.mixed_relaxation,
                },
            },
            projection: match s.projection {
                case::Projection::Approximate => Projection::Approximate,
                case::Projection::Exact => Projection::Exact {
                    blend: s.exact_projection_blend,
                },
            },
            solver: Solver {
                kind: s.solver,
                tolerance: s.solver_tolerance,
                energy_tolerance: s.solver_energy_tolerance,
                max_iterations: s.solver_max_iterations,
                amg_rebuild_interval: s.amg_rebuild_interval,
            },
            free_surface: FreeSurface {
                threshold: s.surface_threshold,
                asymmetry: s.surface_asymmetry,
                offset: s.surface_offset,
                soft: s.soft_surface,
            },
            clip_negative_pressure: s.clip_negative_pressure,
            compressibility: s.compressibility,
            hydrostatic_ghosts: s.hydrostatic_ghosts,
            viscosity: s.viscosity,
            spacing_control: match s.spacing_control {
                case::SpacingControl::None => SpacingControl::None,
                case::SpacingControl::Collision => SpacingControl::Collision {
                    distance: s.collision_distance,
                },
            },
            wall_repulsion_distance: s.wall_repulsion_distance,
            restitution: s.collision_restitution,
            velocity_filter: positive(s.velocity_filter),
            shifting: positive(s.shifting),
            wall_load: s.wall_load,
            wall_kinematics: s.wall_kinematics,
        }
    }
}

/// A sponge layer in engine form (see `case::DampingZone`).
#[derive(Debug, Clone, Copy)]
pub struct DampingLayer {
    pub start: Vec2,
    /// Unit vector from the inner to the outer edge.
    pub direction: Vec2,
    pub length: Real,
    /// 1/s at the outer edge.
    pub strength: Real,
}

impl DampingLayer {
    pub fn new(zone: &case::DampingZone) -> Self {
        let start = vec2(zone.start);
        let span = vec2(zone.end) - start;
        Self {
            start,
            direction: span / span.norm(),
            length: span.norm(),
            strength: zone.strength,
        }
    }

    /// Damping rate at `x` (1/s): strength s², s the fraction of the way into the layer.
    #[inline]
    pub fn rate(&self, x: Vec2) -> Real {
        let s = ((x - self.start).dot(&self.direction) / self.length).clamp(0.0, 1.0);
        self.strength * s * s
    }
}

/// The step guard's limit as a multiple of the Courant number: a particle may move 1.5 cfl
/// spacings in a step (a step at the start-of-step Courant number that accelerates its
/// fastest particle by half is still taken).
pub const DISPLACEMENT_FACTOR: Real = 1.5;

/// The automatic speed limit's allowance on a body's jet-root speed: the jet tip moves at
/// about twice the root speed (Zhao & Faltinsen 1993), and splash particles at the tip
/// faster still; 6 leaves a factor 3 on the tip.
pub const JET_ALLOWANCE: Real = 6.0;

/// The smallest deadrise the jet estimate takes (5°): flatter faces (a box, a cylinder's
/// keel) would give an unbounded Wagner jet speed, 18 times the entry speed at 5°.
const MIN_DEADRISE: Real = 5.0 * std::f64::consts::PI / 180.0;

/// Wagner's jet-root speed π V / (2 tan β) of a body entering at its fastest speed V
/// (prescribed: the constant or the table's fastest; free: its initial speed plus the
/// free-fall speed `fall` over the domain), β the smallest deadrise of the polygon's
/// edges that face the motion (the direction of that velocity, or gravity's from rest).
pub fn jet_root_speed(body: &crate::case::Body, gravity: Vec2, fall: Real) -> Real {
    let v = given_velocity(body);
    let (velocity, speed) = match &body.motion {
        crate::case::Motion::Prescribed { .. } => (v, v.norm()),
        crate::case::Motion::Free { .. } => {
            let heading = if v.norm() > 0.0 { v } else { gravity };
            (heading, v.norm() + fall)
        }
    };
    if speed <= 0.0 || velocity.norm() <= 0.0 {
        return 0.0;
    }
    match leading_deadrise(body, velocity / velocity.norm()) {
        Some(deadrise) => std::f64::consts::PI * speed / (2.0 * deadrise.max(MIN_DEADRISE).tan()),
        None => 0.0,
    }
}

/// The velocity the case gives a body: a prescribed body's fastest (the constant one or
/// the table's fastest sample), a free body's initial one.
pub fn given_velocity(body: &crate::case::Body) -> Vec2 {
    match &body.motion {
        crate::case::Motion::Prescribed {
            velocity, table, ..
        } => table
            .iter()
            .flatten()
            .map(|s| vec2(s.velocity))
            .chain(std::iter::once(vec2(*velocity)))
            .fold(
                Vec2::zeros(),
                |a, b| if b.norm() > a.norm() { b } else { a },
            ),
        crate::case::Motion::Free { velocity, .. } => vec2(*velocity),
    }
}

/// The smallest deadrise (rad) of the polygon's edges that face the unit direction `d`,
/// the body placed at its angle; `None` when no edge faces it. (The mean deadrise at the
/// leading vertex, the wedge-entry time scale of the load filter, is
/// `output::filter::vertex_deadrise`.)
pub fn leading_deadrise(body: &crate::case::Body, d: Vec2) -> Option<Real> {
    let points: Vec<Vec2> = body
        .polygon
        .iter()
        .map(|p| rotate(vec2(*p), body.angle))
        .collect();
    // counter-clockwise polygon: the outward normal of edge a→b is (t.y, -t.x)
    let deadrise = (0..points.len())
        .filter_map(|k| {
            let t = points[(k + 1) % points.len()] - points[k];
            let leading = Vec2::new(t.y, -t.x).dot(&d) > 1e-9 * t.norm();
            (leading && t.norm() > 0.0).then(|| (t.dot(&d).abs() / t.norm()).asin())
        })
        .fold(Real::INFINITY, Real::min);
    deadrise.is_finite().then_some(deadrise)
}

/// Time step, domain and the guards that end or trim a run.
#[derive(Debug, Clone)]
pub struct StepControl {
    pub cfl: Real,
    pub max_dt: Real,
    /// The step guard: the farthest a particle may move in one step, in spacings. dt is
    /// set from the speeds at the start of the step (cfl), and the correction can
    /// accelerate a jet-root particle several-fold within it: at cfl 0.2 on a 20° wedge
    /// such particles moved more than a spacing per step and the force read 33 % high.
    pub displacement_limit: Real,
    /// Particles that leave this box are removed.
    pub domain_min: Vec2,
    pub domain_max: Vec2,
    /// Speed above which the run is declared diverged.
    pub speed_limit: Real,
    /// How many particles may be removed for exceeding `speed_limit`
    /// (`scheme.runaway_allowance`).
    pub runaway_budget: usize,
    /// Sponge layers (case `damping_zones`).
    pub damping: Vec<DampingLayer>,
}

/// Everything fixed for the run.
#[derive(Debug, Clone)]
pub struct Config {
    pub params: MpsParameters,
    pub method: Method,
    /// The case's scheme block as resolved (what summary.json reports).
    pub scheme: Scheme,
    pub control: StepControl,
    /// The layout has more than one spacing (`Particles::scale`, `resolution`).
    pub multi_resolution: bool,
}

impl Config {
    /// The configuration of a (validated) case whose scene has `particles` particles in
    /// the box `domain_min`..`domain_max`, the fastest particle or wall moving at `fastest`.
    pub fn new(
        case: &Case,
        params: MpsParameters,
        (domain_min, domain_max): (Vec2, Vec2),
        particles: usize,
        fastest: Real,
    ) -> Self {
        let g = vec2(case.fluid.gravity).norm();
        let height = (domain_max.y - domain_min.y).max(domain_max.x - domain_min.x);
        let fall = (2.0 * g * height).sqrt();
        let jets = case
            .bodies
            .iter()
            .map(|b| JET_ALLOWANCE * jet_root_speed(b, vec2(case.fluid.gravity), fall))
            .fold(0.0, Real::max);
        let speed_limit = case
            .scheme
            .max_speed
            .unwrap_or((10.0 * (fall + fastest) + 1.0).max(jets));
        let scheme = case.scheme.clone().resolved();
        Self {
            params,
            method: Method::new(&scheme),
            scheme,
            control: StepControl {
                cfl: case.time.cfl,
                max_dt: case.time.max_dt,
                displacement_limit: DISPLACEMENT_FACTOR * case.time.cfl,
                domain_min,
                domain_max,
                speed_limit,
                runaway_budget: (case.scheme.runaway_allowance.max(0.0) * particles as Real).floor()
                    as usize,
                damping: case.damping_zones.iter().map(DampingLayer::new).collect(),
            },
            multi_resolution: false,
        }
    }
}
