//! Instrumental variables beside the normal equations: least squares when a regressor is itself
//! a noisy measurement.
//!
//! Noise in a regressor biases its least-squares coefficient towards zero by
//! var(noise)/var(regressor) (errors in variables). Given, for each sample, an instrument row z
//! that is correlated with the regressor row φ but not with its noise nor with the equation error
//! (for the slope of a noisy signal: the slope of samples outside the slope's window), the
//! estimate θ = (ZᵀΦ)⁻¹Zᵀy has no such bias at any noise level. Columns that are measured without
//! noise are their own instruments (z = φ there), so with z = φ everywhere this is least squares.
//!
//! ```text
//!  sample (φ, z, y) ─► ΦᵀΦ, Φᵀy, yᵀy (a NormalEquations, for residuals at any θ)
//!                   ─► ZᵀΦ, Zᵀy, ZᵀZ                         (O(N²) per sample, fixed memory)
//!                   ─► solve: θ = (ZᵀΦ)⁻¹Zᵀy, cov θ = σ²·(ZᵀΦ)⁻¹ZᵀZ(ZᵀΦ)⁻ᵀ
//! ```
//! Sums merge by addition, so blocks of samples (folds of a cross-validation, threads) are
//! accumulated apart and combined.

use nalgebra::RealField;

use super::{NormalEquations, SolveError};

/// An instrumental-variable estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IvSolution<T, const N: usize> {
    /// The parameters.
    pub theta: [T; N],
    /// Their standard errors, from σ²·(ZᵀΦ)⁻¹ZᵀZ(ZᵀΦ)⁻ᵀ with σ² the residual variance at θ.
    pub stderr: [T; N],
}

/// The sums an instrumental-variable estimate needs, for `N` regressors.
#[derive(Clone, Copy, Debug)]
pub struct InstrumentalEquations<T, const N: usize> {
    ls: NormalEquations<T, N>,
    zx: [[T; N]; N],
    zy: [T; N],
    zz: [[T; N]; N],
}

impl<T: RealField + Copy, const N: usize> Default for InstrumentalEquations<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: RealField + Copy, const N: usize> InstrumentalEquations<T, N> {
    /// Empty sums.
    pub fn new() -> Self {
        InstrumentalEquations {
            ls: NormalEquations::new(),
            zx: [[T::zero(); N]; N],
            zy: [T::zero(); N],
            zz: [[T::zero(); N]; N],
        }
    }

    /// Adds one sample: regressors `phi`, their instruments `z`, target `y`.
    #[inline]
    pub fn update(&mut self, phi: &[T; N], z: &[T; N], y: T) {
        self.ls.update(phi, y);
        for r in 0..N {
            self.zy[r] += z[r] * y;
            for c in 0..N {
                self.zx[r][c] += z[r] * phi[c];
                self.zz[r][c] += z[r] * z[c];
            }
        }
    }

    /// Adds the samples of `other`.
    pub fn merge(&mut self, other: &Self) {
        self.ls.merge(&other.ls);
        for r in 0..N {
            self.zy[r] += other.zy[r];
            for c in 0..N {
                self.zx[r][c] += other.zx[r][c];
                self.zz[r][c] += other.zz[r][c];
            }
        }
    }

    /// The least-squares sums of the same samples (residuals at any θ, the sample count, the
    /// least-squares solution).
    pub fn least_squares(&self) -> &NormalEquations<T, N> {
        &self.ls
    }

    /// θ = (ZᵀΦ)⁻¹Zᵀy and its standard errors. Rows and columns are scaled to unit diagonals
    /// of ZᵀZ and ΦᵀΦ before the inverse (regressors differ by orders of magnitude).
    pub fn solve(&self) -> Result<IvSolution<T, N>, SolveError> {
        let n = self.ls.count();
        if n < T::from_usize(N).unwrap_or(T::one()) {
            return Err(SolveError::TooFewSamples);
        }
        let xx = self.ls.matrix();
        let mut dx = [T::one(); N];
        let mut dz = [T::one(); N];
        for i in 0..N {
            if !(xx[i][i] > T::zero() && xx[i][i].is_finite()) {
                return Err(SolveError::NoExcitation { regressor: i });
            }
            if !(self.zz[i][i] > T::zero() && self.zz[i][i].is_finite()) {
                return Err(SolveError::NoExcitation { regressor: i });
            }
            dx[i] = T::one() / xx[i][i].sqrt();
            dz[i] = T::one() / self.zz[i][i].sqrt();
        }
        let a: [[T; N]; N] =
            core::array::from_fn(|r| core::array::from_fn(|c| self.zx[r][c] * dz[r] * dx[c]));
        // (ZᵀΦ)⁻¹ of the scaled system, column by column.
        let mut inv = [[T::zero(); N]; N];
        for k in 0..N {
            let e: [T; N] = core::array::from_fn(|r| if r == k { T::one() } else { T::zero() });
            let col = gauss(a, e).ok_or(SolveError::Singular)?;
            for r in 0..N {
                inv[r][k] = col[r];
            }
        }
        let u: [T; N] = core::array::from_fn(|r| {
            (0..N).fold(T::zero(), |acc, c| acc + inv[r][c] * self.zy[c] * dz[c])
        });
        let theta: [T; N] = core::array::from_fn(|c| u[c] * dx[c]);
        if theta.iter().any(|t| !t.is_finite()) {
            return Err(SolveError::Singular);
        }
        let dof = n - T::from_usize(N).unwrap_or(T::zero());
        let dof = if dof < T::one() { T::one() } else { dof };
        let sigma2 = self.ls.residual_sum_of_squares(&theta) / dof;
        // cov(u) = σ²·A⁻¹·(D_z ZᵀZ D_z)·A⁻ᵀ; only its diagonal is needed.
        let stderr: [T; N] = core::array::from_fn(|k| {
            let mut v = T::zero();
            for r in 0..N {
                for c in 0..N {
                    v += inv[k][r] * self.zz[r][c] * dz[r] * dz[c] * inv[k][c];
                }
            }
            let v = v * sigma2;
            (if v > T::zero() { v.sqrt() } else { T::zero() }) * dx[k]
        });
        Ok(IvSolution { theta, stderr })
    }
}

/// Solves a·x = b by Gaussian elimination with partial pivoting; `None` if singular.
fn gauss<T: RealField + Copy, const N: usize>(mut a: [[T; N]; N], mut b: [T; N]) -> Option<[T; N]> {
    let tiny = T::from_f64(1e-14).unwrap_or(T::zero());
    for k in 0..N {
        let mut p = k;
        for r in k + 1..N {
            if a[r][k].abs() > a[p][k].abs() {
                p = r;
            }
        }
        if a[p][k].abs() < tiny {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        let pivot = a[k];
        for r in k + 1..N {
            let f = a[r][k] / pivot[k];
            for c in k..N {
                a[r][c] -= f * pivot[c];
            }
            b[r] -= f * b[k];
        }
    }
    let mut x = [T::zero(); N];
    for k in (0..N).rev() {
        let mut sum = T::zero();
        for c in k + 1..N {
            sum += a[k][c] * x[c];
        }
        x[k] = (b[k] - sum) / a[k][k];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = 2·x₀ + 3·x₁ with x₁ measured with noise: least squares shrinks its coefficient, the
    /// instrument (the noise-free x₁ plus independent noise) does not.
    #[test]
    fn an_instrument_removes_the_noise_bias() {
        let mut rng = 12345u64;
        let mut uniform = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((rng >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut iv = InstrumentalEquations::<f64, 2>::new();
        for k in 0..20000 {
            let x0 = (k as f64 * 0.01).sin();
            let x1 = (k as f64 * 0.003).cos();
            let y = 2.0 * x0 + 3.0 * x1;
            let measured = [x0, x1 + 2.0 * uniform()];
            let instrument = [x0, x1 + 2.0 * uniform()];
            iv.update(&measured, &instrument, y);
        }
        let ls = iv.least_squares().solve().unwrap().theta;
        assert!(ls[1] < 2.0, "least squares is biased: {ls:?}");
        let sol = iv.solve().unwrap();
        assert!((sol.theta[1] - 3.0).abs() < 5.0 * sol.stderr[1], "{sol:?}");
        assert!((sol.theta[0] - 2.0).abs() < 5.0 * sol.stderr[0], "{sol:?}");
        assert!(sol.stderr.iter().all(|s| *s > 0.0));
    }

    /// With every column its own instrument it is least squares, and merging halves equals one
    /// pass.
    #[test]
    fn its_own_instrument_is_least_squares_and_halves_merge() {
        let (mut all, mut a, mut b) = (
            InstrumentalEquations::<f64, 2>::new(),
            InstrumentalEquations::<f64, 2>::new(),
            InstrumentalEquations::<f64, 2>::new(),
        );
        for k in 0..1000 {
            let phi = [(k as f64 * 0.1).sin(), 1.0];
            let y = 0.5 * phi[0] - 0.25 + 1e-3 * (k as f64 * 1.7).sin();
            all.update(&phi, &phi, y);
            if k < 500 { &mut a } else { &mut b }.update(&phi, &phi, y);
        }
        a.merge(&b);
        let (x, y) = (all.solve().unwrap(), a.solve().unwrap());
        let ls = all.least_squares().solve().unwrap();
        for i in 0..2 {
            assert!((x.theta[i] - ls.theta[i]).abs() < 1e-12);
            assert!((x.theta[i] - y.theta[i]).abs() < 1e-12);
            assert!((x.stderr[i] / ls.stderr[i] - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn a_silent_column_is_named() {
        let mut iv = InstrumentalEquations::<f64, 2>::new();
        for k in 0..10 {
            iv.update(&[k as f64, 0.0], &[k as f64, 0.0], 1.0);
        }
        assert_eq!(iv.solve(), Err(SolveError::NoExcitation { regressor: 1 }));
    }
}
