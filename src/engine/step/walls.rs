//! The step's view of the wall model: the kernel weights the wall sums use, and the
//! walls placed at a pose.

use crate::case::LaplacianKind;
use crate::engine::kernel::Kernel;
use crate::engine::simulation::Simulation;
use crate::engine::walls::{PlacedWall, WallKernels, WallWeights};
use crate::math::Real;
use std::marker::PhantomData;

pub(super) struct KernelWeights<K> {
    re: Real,
    re_lap: Real,
    classic_laplacian: bool,
    _k: PhantomData<K>,
}

impl<K: Kernel> KernelWeights<K> {
    pub(super) fn new(sim: &Simulation) -> Self {
        Self {
            re: sim.config.params.re,
            re_lap: sim.config.params.re_lap,
            // Imoto's second-order Laplacian is the classic one (Imoto 2022 Theorem 3.1)
            classic_laplacian: matches!(
                sim.config.method.laplacian,
                LaplacianKind::Classic | LaplacianKind::SecondOrder
            ),
            _k: PhantomData,
        }
    }

    /// Whether the Laplacian weight is w (classic and second-order Laplacians) rather
    /// than the HL weight w'' - w'/r.
    #[inline]
    pub(super) fn classic_laplacian(&self) -> bool {
        self.classic_laplacian
    }

    /// The wall lattice's Laplacian weight at distance r.
    #[inline]
    pub(super) fn laplacian(&self, r: Real) -> Real {
        if self.classic_laplacian {
            K::w(r, self.re_lap)
        } else {
            K::hl(r, self.re_lap)
        }
    }
}

impl<K: Kernel> WallWeights for KernelWeights<K> {
    fn w(&self, r: Real) -> Real {
        K::w(r, self.re)
    }
    fn dw(&self, r: Real) -> Real {
        K::dw(r, self.re)
    }
    fn lap(&self, r: Real) -> Real {
        self.laplacian(r)
    }
}

pub(super) fn wall_kernels(sim: &Simulation) -> WallKernels {
    WallKernels {
        l0: sim.config.params.l0,
        re: sim.config.params.re,
        re_lap: sim.config.params.re_lap,
    }
}

pub(super) fn placed_walls(sim: &Simulation, dt: Real) -> Vec<PlacedWall> {
    sim.walls
        .iter()
        .map(|w| PlacedWall::new(w, w.state.advanced(dt)))
        .collect()
}
