//! The load model: J·dω/dt = Q − c1·ω − c2·ω|ω|, fitted the way the seed fits it.
//!
//! Regressors φ = (Q, −ω, −ω|ω|), target a = dω/dt, parameters θ = (1/J, c1/J, c2/J). The seed's
//! bounds on the physical parameters become linear inequalities on θ, which keeps them exact:
//! J ∈ [J_min, J_max] ⇔ 1/J_max ≤ θ₀ ≤ 1/J_min; 0 ≤ c1 ≤ c1_max ⇔ 0 ≤ θ₁ ≤ c1_max·θ₀; likewise
//! c2. Standard errors of J, c1, c2 follow from the covariance of θ by the delta method.

use nalgebra::RealField;

use super::{NormalEquations, Solution, SolveError};

/// Bounds on the physical parameters, as the seed's options define them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadBounds<T> {
    /// Smallest inertia [kg·m²] (seed default 1e-9).
    pub mass_min: T,
    /// Largest inertia [kg·m²] (seed default 1e3).
    pub mass_max: T,
    /// Largest viscous coefficient [N·m·s/rad] (seed default 0: no viscous friction).
    pub c1_max: T,
    /// Largest quadratic drag coefficient [N·m·s²/rad²] (seed default 1e2).
    pub c2_max: T,
}

impl<T: RealField + Copy> Default for LoadBounds<T> {
    fn default() -> Self {
        let f = |x: f64| T::from_f64(x).unwrap_or(T::zero());
        LoadBounds {
            mass_min: f(1e-9),
            mass_max: f(1e3),
            c1_max: T::zero(),
            c2_max: f(1e2),
        }
    }
}

/// Fitted load parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadEstimate<T> {
    /// Inertia J [kg·m²] (the seed's `mass`).
    pub mass: T,
    /// Viscous coefficient [N·m·s/rad].
    pub c1: T,
    /// Quadratic drag coefficient [N·m·s²/rad²].
    pub c2: T,
    /// Standard error of `mass`.
    pub mass_stderr: T,
    /// Standard error of `c1`.
    pub c1_stderr: T,
    /// Standard error of `c2`.
    pub c2_stderr: T,
    /// RMS of the acceleration residual [rad/s²].
    pub rms: T,
    /// Condition number of the scaled normal matrix (excitation check).
    pub condition_number: T,
    /// Samples used.
    pub samples: T,
    /// Bounds the solution sits on: `[mass, c1, c2]`.
    pub at_bound: [bool; 3],
    /// The solution in θ = (1/J, c1/J, c2/J) form.
    pub theta: Solution<T, 3>,
}

/// Accumulates samples of the load and fits J, c1, c2.
#[derive(Clone, Copy, Debug)]
pub struct LoadEstimator<T> {
    equations: NormalEquations<T, 3>,
}

impl<T: RealField + Copy> Default for LoadEstimator<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: RealField + Copy> LoadEstimator<T> {
    /// An empty estimator.
    pub fn new() -> Self {
        LoadEstimator {
            equations: NormalEquations::new(),
        }
    }

    /// An estimator that forgets old samples by λ per update (online use).
    pub fn with_forgetting(lambda: T) -> Self {
        LoadEstimator {
            equations: NormalEquations::with_forgetting(lambda),
        }
    }

    /// The regressor row of one sample.
    pub fn regressors(torque: T, velocity: T) -> [T; 3] {
        [torque, -velocity, -velocity * velocity.abs()]
    }

    /// Adds one sample: torque Q [N·m], velocity ω [rad/s], acceleration [rad/s²].
    pub fn update(&mut self, torque: T, velocity: T, acceleration: T) {
        self.equations
            .update(&Self::regressors(torque, velocity), acceleration);
    }

    /// Adds the samples of another estimator.
    pub fn merge(&mut self, other: &Self) {
        self.equations.merge(&other.equations);
    }

    /// The estimator of the same samples with torque, ω and ω|ω| multiplied by `s`
    /// ([`NormalEquations::scale_regressors`]): a flipped torque sign is `[-1, 1, 1]`, a
    /// velocity logged in rpm `[1, k, k²]` with k = 2π/60.
    pub fn scale_regressors(&mut self, s: &[T; 3]) {
        self.equations.scale_regressors(s);
    }

    /// The underlying normal equations.
    pub fn equations(&self) -> &NormalEquations<T, 3> {
        &self.equations
    }

    /// Samples so far.
    pub fn count(&self) -> T {
        self.equations.count()
    }

    /// The bounded fit (the seed's objective and bounds, solved exactly).
    pub fn estimate(&self, bounds: &LoadBounds<T>) -> Result<LoadEstimate<T>, SolveError> {
        let z = T::zero();
        let one = T::one();
        // g·θ ≤ h rows: θ₀ ≤ 1/J_min, −θ₀ ≤ −1/J_max, −θ₁ ≤ 0, θ₁ − c1_max·θ₀ ≤ 0, −θ₂ ≤ 0,
        // θ₂ − c2_max·θ₀ ≤ 0.
        let g = [
            [one, z, z],
            [-one, z, z],
            [z, -one, z],
            [-bounds.c1_max, one, z],
            [z, z, -one],
            [-bounds.c2_max, z, one],
        ];
        let h = [one / bounds.mass_min, -one / bounds.mass_max, z, z, z, z];
        let sol = self.equations.solve_constrained(&g, &h)?;
        Ok(Self::to_physical(sol))
    }

    /// The unconstrained fit (c1 and c2 may come out negative).
    pub fn estimate_unbounded(&self) -> Result<LoadEstimate<T>, SolveError> {
        Ok(Self::to_physical(self.equations.solve()?))
    }

    fn to_physical(sol: Solution<T, 3>) -> LoadEstimate<T> {
        let [t0, t1, t2] = sol.theta;
        let mass = T::one() / t0;
        let c1 = t1 / t0;
        let c2 = t2 / t0;
        // Delta method: rows are ∂(J, c1, c2)/∂θ.
        let jac = [
            [-mass * mass, T::zero(), T::zero()],
            [-t1 * mass * mass, mass, T::zero()],
            [-t2 * mass * mass, T::zero(), mass],
        ];
        let cov = sol.covariance;
        let var = |r: &[T; 3]| {
            let mut v = T::zero();
            for i in 0..3 {
                for j in 0..3 {
                    v += r[i] * cov[i][j] * r[j];
                }
            }
            v.max(T::zero()).sqrt()
        };
        let a = sol.active_constraints;
        LoadEstimate {
            mass,
            c1,
            c2,
            mass_stderr: var(&jac[0]),
            c1_stderr: var(&jac[1]),
            c2_stderr: var(&jac[2]),
            rms: sol.rms,
            condition_number: sol.condition_number,
            samples: sol.samples,
            at_bound: [a & 0b11 != 0, a & 0b1100 != 0, a & 0b11_0000 != 0],
            theta: sol,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Noiseless samples of a 7-inch propeller-like load under a sinusoidal torque, integrated
    /// with small steps; returns (Q, ω, a) triples.
    fn propeller_samples(
        j: f64,
        c1: f64,
        c2: f64,
        n: usize,
    ) -> impl Iterator<Item = (f64, f64, f64)> {
        let dt = 1e-3;
        let mut w = 300.0;
        (0..n).map(move |k| {
            let t = k as f64 * dt;
            let q = 0.02 + 0.015 * (core::f64::consts::TAU * t / 2.0).sin();
            let a = (q - c1 * w - c2 * w * w.abs()) / j;
            let out = (q, w, a);
            w += a * dt;
            out
        })
    }

    #[test]
    fn recovers_a_propeller_in_f64_and_f32() {
        let (j, c2) = (2.1e-5, 1.4e-8);
        let mut e64 = LoadEstimator::<f64>::new();
        let mut e32 = LoadEstimator::<f32>::new();
        for (q, w, a) in propeller_samples(j, 0.0, c2, 20_000) {
            e64.update(q, w, a);
            e32.update(q as f32, w as f32, a as f32);
        }
        let f = e64.estimate(&LoadBounds::default()).unwrap();
        assert!((f.mass / j - 1.0).abs() < 1e-9, "{}", f.mass);
        assert!((f.c2 / c2 - 1.0).abs() < 1e-9, "{}", f.c2);
        assert_eq!(f.c1, 0.0);
        assert!(f.at_bound[1] && !f.at_bound[0] && !f.at_bound[2]);
        // f32 with magnitudes 1e-5 and 1e-8: column scaling and compensated sums keep it close.
        let g = e32.estimate(&LoadBounds::default()).unwrap();
        assert!(
            ((g.mass as f64) / j - 1.0).abs() < 1e-6,
            "f32 mass {}",
            g.mass
        );
        assert!(((g.c2 as f64) / c2 - 1.0).abs() < 1e-6, "f32 c2 {}", g.c2);
    }

    #[test]
    fn bounds_are_exact() {
        let (j, c1, c2) = (2.0e-5, 2.0e-6, 1.0e-8);
        let mut e = LoadEstimator::<f64>::new();
        for (q, w, a) in propeller_samples(j, c1, c2, 20_000) {
            e.update(q, w, a);
        }
        let free = e
            .estimate(&LoadBounds {
                c1_max: 1.0,
                ..LoadBounds::default()
            })
            .unwrap();
        assert!((free.c1 / c1 - 1.0).abs() < 1e-6);
        assert_eq!(free.at_bound, [false, false, false]);
        let capped = e
            .estimate(&LoadBounds {
                mass_max: 1.5e-5,
                c1_max: 1.0,
                ..LoadBounds::default()
            })
            .unwrap();
        assert!((capped.mass - 1.5e-5).abs() < 1e-15);
        assert!(capped.at_bound[0]);
    }
}
