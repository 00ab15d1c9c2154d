//! Fixed-memory incremental least squares for the load's inertia and drag.
//!
//! The seed regressor fitted `m`, `c1`, `c2` with L-BFGS-B and numerical gradients over the whole
//! file. Its objective, Σ (a − (F − c1·ω − c2·ω|ω|)/m)², is linear in
//! θ = (1/m, c1/m, c2/m): a = θ₀·F − θ₁·ω − θ₂·ω|ω|. So it has an exact solution, and the data
//! needed for it fits in a handful of numbers.
//!
//! ## How data flows
//! ```text
//!  sample (F, ω, a) ─► regressor φ = (F, −ω, −ω|ω|), target y = a
//!                   ─► NormalEquations::update: ΦᵀΦ += φφᵀ, Φᵀy += φy, yᵀy += y²   (O(N²), fixed memory)
//!                   ─► NormalEquations::solve / solve_constrained: θ, covariance, RMS, condition
//!                   ─► LoadEstimator: θ → mass, c1, c2 with the seed's bounds, standard errors
//! ```
//! - [`NormalEquations`] is generic over the number of regressors `N` and the float type (f32 on
//!   an MCU without a double-precision FPU, f64 on a host). It supports a forgetting factor for
//!   online use and [`NormalEquations::merge`], so a large file can be split across threads and
//!   the pieces summed.
//! - **Numerical care**: sums are Kahan-compensated (f32 over 10⁶ samples keeps its precision);
//!   solving equilibrates the columns (the matrix is scaled to a unit diagonal before Cholesky),
//!   so regressors of wildly different magnitude (F ~ 0.05 N·m, ω|ω| ~ 10⁶ rad²/s²) do not lose
//!   accuracy; the condition number of the scaled matrix is reported as the excitation check.
//! - **Bounds** are linear inequalities on θ ([`NormalEquations::solve_constrained`]): the
//!   optimum of a convex quadratic under linear inequalities is the optimum of the
//!   equality-constrained problem on its active set, so trying every active set and keeping the
//!   best feasible point is exact (the sets are few: at most 2^M for M constraints).

// Matrix code reads as the algebra does: with indices.
#![allow(clippy::needless_range_loop)]

mod iv;
mod load;
mod normal;

pub use iv::{InstrumentalEquations, IvSolution};
pub use load::{LoadBounds, LoadEstimate, LoadEstimator};
pub use normal::{NormalEquations, Solution, SolveError};
