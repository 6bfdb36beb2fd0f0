//! Weight functions w(r) as zero-sized types, with the derivatives the HS source
//! and the HL Laplacian need. All vanish at and beyond r_e; MPS needs no
//! normalisation (operators divide by n0).
//!
//! Notation: q = r / r_e.

use crate::case::KernelKind;
use crate::math::Real;

/// A weight function and its first two radial derivatives.
pub trait Kernel: Copy + Send + Sync + 'static {
    fn w(r: Real, re: Real) -> Real;
    /// dw/dr
    fn dw(r: Real, re: Real) -> Real;
    /// d²w/dr²
    fn d2w(r: Real, re: Real) -> Real;
    /// Weight of the higher-order Laplacian (Ikari, Khayyer & Gotoh 2015 eq. 9): w'' - w'/r.
    #[inline]
    fn hl(r: Real, re: Real) -> Real {
        Self::d2w(r, re) - Self::dw(r, re) / r
    }
    /// (w, w'/r) for the number density and the HS divergence, w'/r taken as 0 at r = 0.
    #[inline]
    fn w_and_dw_over_r(r: Real, re: Real) -> (Real, Real) {
        let dw_r = if r < re && r > 0.0 {
            Self::dw(r, re) / r
        } else {
            0.0
        };
        (Self::w(r, re), dw_r)
    }
}

/// Koshizuka & Oka (1996): w = r_e/r - 1. Singular at r = 0, which keeps particles apart.
#[derive(Debug, Clone, Copy, Default)]
pub struct Koshizuka;

impl Kernel for Koshizuka {
    #[inline]
    fn w(r: Real, re: Real) -> Real {
        if r < re && r > 0.0 {
            re / r - 1.0
        } else {
            0.0
        }
    }
    #[inline]
    fn dw(r: Real, re: Real) -> Real {
        if r < re && r > 0.0 {
            -re / (r * r)
        } else {
            0.0
        }
    }
    #[inline]
    fn d2w(r: Real, re: Real) -> Real {
        if r < re && r > 0.0 {
            2.0 * re / (r * r * r)
        } else {
            0.0
        }
    }
    /// One division for both: with three, the number-density stage at 160k particles took
    /// 13 ms a step instead of 9.
    #[inline]
    fn w_and_dw_over_r(r: Real, re: Real) -> (Real, Real) {
        if r < re && r > 0.0 {
            let inv = 1.0 / r;
            let q = re * inv;
            (q - 1.0, -q * inv * inv)
        } else {
            (0.0, 0.0)
        }
    }
    #[inline]
    fn hl(r: Real, re: Real) -> Real {
        // w'' - w'/r = 3 r_e / r³ (Khayyer & Gotoh 2010, 2D)
        if r < re && r > 0.0 {
            3.0 * re / (r * r * r)
        } else {
            0.0
        }
    }
}

/// Non-singular cubic: w = (1 - q)³. Bounded at r = 0.
#[derive(Debug, Clone, Copy, Default)]
pub struct NonSingular;

impl Kernel for NonSingular {
    #[inline]
    fn w(r: Real, re: Real) -> Real {
        let q = r / re;
        if q < 1.0 {
            (1.0 - q).powi(3)
        } else {
            0.0
        }
    }
    #[inline]
    fn dw(r: Real, re: Real) -> Real {
        let q = r / re;
        if q < 1.0 {
            -3.0 * (1.0 - q).powi(2) / re
        } else {
            0.0
        }
    }
    #[inline]
    fn d2w(r: Real, re: Real) -> Real {
        let q = r / re;
        if q < 1.0 {
            6.0 * (1.0 - q) / (re * re)
        } else {
            0.0
        }
    }
}

/// Wendland C2 (Ikari, Khayyer & Gotoh 2015 eq. 26): w = (1 - q)⁴ (1 + 4q).
#[derive(Debug, Clone, Copy, Default)]
pub struct WendlandC2;

impl Kernel for WendlandC2 {
    #[inline]
    fn w(r: Real, re: Real) -> Real {
        let q = r / re;
        if q < 1.0 {
            (1.0 - q).powi(4) * (1.0 + 4.0 * q)
        } else {
            0.0
        }
    }
    #[inline]
    fn dw(r: Real, re: Real) -> Real {
        let q = r / re;
        if q < 1.0 {
            -20.0 * q * (1.0 - q).powi(3) / re
        } else {
            0.0
        }
    }
    #[inline]
    fn d2w(r: Real, re: Real) -> Real {
        let q = r / re;
        if q < 1.0 {
            20.0 * (1.0 - q).powi(2) * (4.0 * q - 1.0) / (re * re)
        } else {
            0.0
        }
    }
    #[inline]
    fn hl(r: Real, re: Real) -> Real {
        let q = r / re;
        if q < 1.0 {
            60.0 * q * (1.0 - q).powi(2) / (re * re)
        } else {
            0.0
        }
    }
}

/// Call `$body` with the kernel type chosen by a [`KernelKind`] bound to `$K`:
/// the variant is matched once, the loops inside are monomorphised.
#[macro_export]
macro_rules! with_kernel {
    ($kind:expr, $K:ident => $body:expr) => {
        match $kind {
            $crate::case::KernelKind::Koshizuka => {
                type $K = $crate::engine::kernel::Koshizuka;
                $body
            }
            $crate::case::KernelKind::NonSingular => {
                type $K = $crate::engine::kernel::NonSingular;
                $body
            }
            $crate::case::KernelKind::WendlandC2 => {
                type $K = $crate::engine::kernel::WendlandC2;
                $body
            }
        }
    };
}

/// Weight of `kind` at r, for code that is not performance critical.
pub fn weight(kind: KernelKind, r: Real, re: Real) -> Real {
    with_kernel!(kind, K => K::w(r, re))
}
