use nalgebra::{RealField, SMatrix, SVector};

/// Why a least-squares problem could not be solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SolveError {
    /// Fewer samples than unknowns.
    TooFewSamples,
    /// A regressor was zero in every sample: its parameter cannot be identified.
    NoExcitation {
        /// Index of the regressor.
        regressor: usize,
    },
    /// The (scaled) normal matrix is singular: the regressors are linearly dependent.
    Singular,
    /// The constraints admit no solution.
    Infeasible,
}

/// A least-squares solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution<T, const N: usize> {
    /// The parameters.
    pub theta: [T; N],
    /// Covariance of the parameters (residual variance × (ΦᵀΦ)⁻¹).
    pub covariance: [[T; N]; N],
    /// Standard error of each parameter.
    pub stderr: [T; N],
    /// Root-mean-square residual.
    pub rms: T,
    /// Condition number (1-norm) of the column-scaled normal matrix: the excitation check.
    /// Large values (≳ 10⁶ in f64, ≳ 10³ in f32) mean the data cannot tell some parameters
    /// apart.
    pub condition_number: T,
    /// Effective number of samples (with forgetting: the discounted weight).
    pub samples: T,
    /// Which constraints are active at the solution (only from `solve_constrained`).
    pub active_constraints: u32,
}

/// Kahan-compensated running sum.
#[derive(Clone, Copy, Debug)]
struct Compensated<T> {
    sum: T,
    carry: T,
}

impl<T: RealField + Copy> Compensated<T> {
    fn zero() -> Self {
        Compensated {
            sum: T::zero(),
            carry: T::zero(),
        }
    }

    fn add(&mut self, x: T) {
        let y = x - self.carry;
        let t = self.sum + y;
        self.carry = (t - self.sum) - y;
        self.sum = t;
    }

    fn scale(&mut self, k: T) {
        self.sum *= k;
        self.carry *= k;
    }

    fn merge(&mut self, other: &Self) {
        self.add(other.sum);
        self.add(-other.carry);
    }
}

/// Incremental normal equations of a linear least-squares problem y ≈ φᵀθ with `N` regressors,
/// in fixed memory.
#[derive(Clone, Copy, Debug)]
pub struct NormalEquations<T, const N: usize> {
    /// ΦᵀΦ (upper triangle used).
    phi_phi: [[Compensated<T>; N]; N],
    /// Φᵀy.
    phi_y: [Compensated<T>; N],
    /// yᵀy.
    y_y: Compensated<T>,
    /// Σ weights (sample count without forgetting).
    weight: Compensated<T>,
    /// Forgetting factor λ ∈ (0, 1]; 1 keeps every sample forever.
    forgetting: T,
}

impl<T: RealField + Copy, const N: usize> Default for NormalEquations<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: RealField + Copy, const N: usize> NormalEquations<T, N> {
    /// Empty equations; every sample counts equally.
    pub fn new() -> Self {
        NormalEquations {
            phi_phi: [[Compensated::zero(); N]; N],
            phi_y: [Compensated::zero(); N],
            y_y: Compensated::zero(),
            weight: Compensated::zero(),
            forgetting: T::one(),
        }
    }

    /// Empty equations that discount old samples by λ per update (λ = 0.999 at 1 kHz remembers
    /// about one second).
    pub fn with_forgetting(lambda: T) -> Self {
        let mut s = Self::new();
        s.forgetting = lambda;
        s
    }

    /// Adds one sample with unit weight.
    pub fn update(&mut self, phi: &[T; N], y: T) {
        self.update_weighted(phi, y, T::one());
    }

    /// Adds one sample with weight `w`.
    pub fn update_weighted(&mut self, phi: &[T; N], y: T, w: T) {
        if self.forgetting != T::one() {
            let k = self.forgetting;
            for row in &mut self.phi_phi {
                for c in row.iter_mut() {
                    c.scale(k);
                }
            }
            for c in &mut self.phi_y {
                c.scale(k);
            }
            self.y_y.scale(k);
            self.weight.scale(k);
        }
        for i in 0..N {
            let wi = w * phi[i];
            for j in i..N {
                self.phi_phi[i][j].add(wi * phi[j]);
            }
            self.phi_y[i].add(wi * y);
        }
        self.y_y.add(w * y * y);
        self.weight.add(w);
    }

    /// Adds the samples of `other` (as if they had been given to `self`).
    pub fn merge(&mut self, other: &Self) {
        for i in 0..N {
            for j in i..N {
                self.phi_phi[i][j].merge(&other.phi_phi[i][j]);
            }
            self.phi_y[i].merge(&other.phi_y[i]);
        }
        self.y_y.merge(&other.y_y);
        self.weight.merge(&other.weight);
    }

    /// Effective number of samples.
    pub fn count(&self) -> T {
        self.weight.sum
    }

    /// ΦᵀΦ as a full symmetric matrix.
    pub fn matrix(&self) -> [[T; N]; N] {
        let mut m = [[T::zero(); N]; N];
        for i in 0..N {
            for j in i..N {
                m[i][j] = self.phi_phi[i][j].sum;
                m[j][i] = self.phi_phi[i][j].sum;
            }
        }
        m
    }

    /// Φᵀy.
    pub fn vector(&self) -> [T; N] {
        core::array::from_fn(|i| self.phi_y[i].sum)
    }

    /// Σ y².
    pub fn sum_y_squared(&self) -> T {
        self.y_y.sum
    }

    /// The residual sum of squares at θ: yᵀy − 2θᵀΦᵀy + θᵀΦᵀΦθ (never negative).
    pub fn residual_sum_of_squares(&self, theta: &[T; N]) -> T {
        let a = self.matrix();
        let b = self.vector();
        let mut ss = self.y_y.sum;
        for i in 0..N {
            ss -= (b[i] + b[i]) * theta[i];
            for j in 0..N {
                ss += theta[i] * a[i][j] * theta[j];
            }
        }
        if ss < T::zero() {
            T::zero()
        } else {
            ss
        }
    }

    /// Column scales 1/√(ΦᵀΦ)ᵢᵢ that give the normal matrix a unit diagonal.
    fn scales(&self) -> Result<[T; N], SolveError> {
        let mut d = [T::one(); N];
        for (i, di) in d.iter_mut().enumerate() {
            let aii = self.phi_phi[i][i].sum;
            if aii <= T::zero() || !aii.is_finite() {
                return Err(SolveError::NoExcitation { regressor: i });
            }
            *di = T::one() / aii.sqrt();
        }
        Ok(d)
    }

    fn scaled_matrix(&self, d: &[T; N]) -> SMatrix<T, N, N> {
        let a = self.matrix();
        SMatrix::<T, N, N>::from_fn(|i, j| a[i][j] * d[i] * d[j])
    }

    /// Unconstrained least squares.
    pub fn solve(&self) -> Result<Solution<T, N>, SolveError> {
        if self.weight.sum < T::from_usize(N).unwrap_or(T::one()) {
            return Err(SolveError::TooFewSamples);
        }
        let d = self.scales()?;
        let s = self.scaled_matrix(&d);
        let chol = nalgebra::Cholesky::new(s).ok_or(SolveError::Singular)?;
        let b = self.vector();
        let sb = SVector::<T, N>::from_fn(|i, _| b[i] * d[i]);
        let z = chol.solve(&sb);
        let theta: [T; N] = core::array::from_fn(|i| z[i] * d[i]);
        if theta.iter().any(|t| !t.is_finite()) {
            return Err(SolveError::Singular);
        }
        Ok(self.solution_at::<0>(theta, &d, &s, &[], 0))
    }

    /// Least squares subject to `M` linear inequalities g_kᵀθ ≤ h_k, exactly (see the module
    /// documentation). `M` must be at most 8.
    pub fn solve_constrained<const M: usize>(
        &self,
        g: &[[T; N]; M],
        h: &[T; M],
    ) -> Result<Solution<T, N>, SolveError> {
        const { assert!(M <= 8, "at most 8 constraints") };
        if self.weight.sum < T::from_usize(N).unwrap_or(T::one()) {
            return Err(SolveError::TooFewSamples);
        }
        let d = self.scales()?;
        let s = self.scaled_matrix(&d);
        let b = self.vector();
        // In scaled variables z = θ / d: minimise ½zᵀSz − (Db)ᵀz subject to (g∘d)ᵀz ≤ h.
        // Each constraint row is normalised so the KKT system is well scaled.
        let mut gs: [[T; N]; M] =
            core::array::from_fn(|k| core::array::from_fn(|i| g[k][i] * d[i]));
        let mut h = *h;
        for (row, hk) in gs.iter_mut().zip(h.iter_mut()) {
            let norm = row.iter().fold(T::zero(), |acc, x| acc + *x * *x).sqrt();
            if norm > T::zero() {
                for x in row.iter_mut() {
                    *x /= norm;
                }
                *hk /= norm;
            }
        }
        let sb: [T; N] = core::array::from_fn(|i| b[i] * d[i]);
        let mut best: Option<([T; N], T, u32)> = None;
        for set in 0u32..(1 << M) {
            if set.count_ones() as usize > N {
                continue;
            }
            let Some(z) = kkt_solve::<T, N, M>(&s, &sb, &gs, &h, set) else {
                continue;
            };
            // Feasible? Constraints in the active set hold by construction (up to rounding);
            // the others must hold exactly, so a point a rounding error outside a bound loses to
            // the point on it.
            let feasible = (0..M).all(|k| {
                set & (1 << k) != 0
                    || (0..N).fold(T::zero(), |acc, i| acc + gs[k][i] * z[i]) <= h[k]
            });
            if !feasible {
                continue;
            }
            let theta: [T; N] = core::array::from_fn(|i| z[i] * d[i]);
            let ss = self.residual_sum_of_squares(&theta);
            if best.as_ref().is_none_or(|(_, bs, _)| ss < *bs) {
                best = Some((theta, ss, set));
            }
        }
        let (theta, _, set) = best.ok_or(SolveError::Infeasible)?;
        Ok(self.solution_at(theta, &d, &s, &gs, set))
    }

    /// The solution's statistics. `gs` are the constraint rows in scaled variables and `active`
    /// the set of those the solution sits on: an active constraint removes a direction from the
    /// parameter space, so the covariance is that of the restricted problem,
    /// S⁻¹ − S⁻¹Gᵀ(G S⁻¹ Gᵀ)⁻¹G S⁻¹ (G: the active rows), zero across the bound. (Using the
    /// unconstrained S⁻¹ instead overstates the error of every parameter correlated with the
    /// bounded one: the seed's c1 = 0 bound and c2 are nearly collinear on a propeller.)
    fn solution_at<const M: usize>(
        &self,
        theta: [T; N],
        d: &[T; N],
        s: &SMatrix<T, N, N>,
        gs: &[[T; N]; M],
        active: u32,
    ) -> Solution<T, N> {
        let n = self.weight.sum;
        let ss = self.residual_sum_of_squares(&theta);
        let free = N - (active.count_ones() as usize).min(N);
        let dof = n - T::from_usize(free).unwrap_or(T::zero());
        let sigma2 = if dof > T::zero() { ss / dof } else { T::zero() };
        let mut covariance = [[T::zero(); N]; N];
        let mut stderr = [T::zero(); N];
        // Condition number in the 1-norm, ‖S‖₁·‖S⁻¹‖₁, of the column-scaled matrix.
        let norm1 = |m: &SMatrix<T, N, N>| {
            (0..N).fold(T::zero(), |acc, j| {
                acc.max((0..N).fold(T::zero(), |col, i| col + m[(i, j)].abs()))
            })
        };
        let mut condition_number = T::max_value().unwrap_or(T::one());
        if let Some(inv) = s.try_inverse() {
            let restricted = restrict(&inv, gs, active).unwrap_or(inv);
            for i in 0..N {
                for j in 0..N {
                    covariance[i][j] = sigma2 * restricted[(i, j)] * d[i] * d[j];
                }
                stderr[i] = covariance[i][i].max(T::zero()).sqrt();
            }
            condition_number = norm1(s) * norm1(&inv);
        }
        Solution {
            theta,
            covariance,
            stderr,
            rms: if n > T::zero() {
                (ss / n).sqrt()
            } else {
                T::zero()
            },
            condition_number,
            samples: n,
            active_constraints: active,
        }
    }
}

/// P − P Gᵀ (G P Gᵀ)⁻¹ G P for the rows of `gs` in `active` (none: `None`). Unused rows of the
/// fixed-size G are zero, with a unit diagonal in G P Gᵀ so that it stays invertible.
fn restrict<T: RealField + Copy, const N: usize, const M: usize>(
    p: &SMatrix<T, N, N>,
    gs: &[[T; N]; M],
    active: u32,
) -> Option<SMatrix<T, N, N>> {
    let mut g = SMatrix::<T, N, N>::zeros();
    let mut used = 0;
    for (k, row) in gs.iter().enumerate() {
        if active & (1 << k) != 0 && used < N {
            for i in 0..N {
                g[(used, i)] = row[i];
            }
            used += 1;
        }
    }
    if used == 0 {
        return None;
    }
    let pg = p * g.transpose();
    let mut m = g * pg;
    for r in used..N {
        m[(r, r)] = T::one();
    }
    let minv = m.try_inverse()?;
    Some(p - pg * minv * pg.transpose())
}

/// Solves the equality-constrained problem min ½zᵀSz − bᵀz s.t. g_kᵀz = h_k for k in `set`,
/// through its KKT system (padded to a fixed size with identity rows so no allocation is
/// needed). `None` if the system is singular (dependent constraints).
fn kkt_solve<T: RealField + Copy, const N: usize, const M: usize>(
    s: &SMatrix<T, N, N>,
    b: &[T; N],
    g: &[[T; N]; M],
    h: &[T; M],
    set: u32,
) -> Option<[T; N]> {
    const K: usize = 16;
    let mut kkt = SMatrix::<T, K, K>::identity();
    let mut rhs = SVector::<T, K>::zeros();
    for i in 0..N {
        for j in 0..N {
            kkt[(i, j)] = s[(i, j)];
        }
        rhs[i] = b[i];
    }
    let mut row = N;
    for k in 0..M {
        if set & (1 << k) == 0 {
            continue;
        }
        for i in 0..N {
            kkt[(row, i)] = g[k][i];
            kkt[(i, row)] = g[k][i];
        }
        kkt[(row, row)] = T::zero();
        rhs[row] = h[k];
        row += 1;
    }
    if N + M > K {
        return None;
    }
    // A singular KKT system means dependent constraints: the set is skipped. A nearly singular
    // one can give a poor point, but only a feasible point with the lowest objective is kept, and
    // the true optimum's own active set is always among those tried.
    let x = kkt.lu().solve(&rhs)?;
    let z: [T; N] = core::array::from_fn(|i| x[i]);
    z.iter().all(|v| v.is_finite()).then_some(z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    }

    #[test]
    fn recovers_exact_parameters_and_merges() {
        let truth = [2.0, -3.0, 0.5];
        let mut a = NormalEquations::<f64, 3>::new();
        let mut b = NormalEquations::<f64, 3>::new();
        let mut all = NormalEquations::<f64, 3>::new();
        let mut s = 1u64;
        for k in 0..1000 {
            let phi = [lcg(&mut s), lcg(&mut s), lcg(&mut s)];
            let y = truth.iter().zip(phi).map(|(t, p)| t * p).sum::<f64>();
            if k % 2 == 0 {
                a.update(&phi, y)
            } else {
                b.update(&phi, y)
            }
            all.update(&phi, y);
        }
        a.merge(&b);
        let sol = a.solve().unwrap();
        let sol_all = all.solve().unwrap();
        for i in 0..3 {
            assert!((sol.theta[i] - truth[i]).abs() < 1e-9);
            assert!((sol.theta[i] - sol_all.theta[i]).abs() < 1e-12);
        }
        assert!(sol.rms < 1e-9);
        assert!(sol.condition_number < 10.0);
    }

    #[test]
    fn constrained_matches_hand_solution() {
        // y = 2 φ0 + 3 φ1; constrain θ1 ≤ 1: the optimum moves to the boundary.
        let mut ne = NormalEquations::<f64, 2>::new();
        let mut s = 7u64;
        for _ in 0..500 {
            let phi = [lcg(&mut s), lcg(&mut s)];
            ne.update(&phi, 2.0 * phi[0] + 3.0 * phi[1]);
        }
        let sol = ne.solve_constrained(&[[0.0, 1.0]], &[1.0]).unwrap();
        assert!((sol.theta[1] - 1.0).abs() < 1e-9);
        assert_eq!(sol.active_constraints, 1);
        // Inactive constraint: same as unconstrained.
        let free = ne.solve_constrained(&[[0.0, 1.0]], &[10.0]).unwrap();
        assert!((free.theta[1] - 3.0).abs() < 1e-9);
        assert_eq!(free.active_constraints, 0);
        // Infeasible: θ1 ≤ −1 and −θ1 ≤ −1.
        assert_eq!(
            ne.solve_constrained(&[[0.0, 1.0], [0.0, -1.0]], &[-1.0, -1.0])
                .err(),
            Some(SolveError::Infeasible)
        );
    }

    #[test]
    fn forgetting_tracks_a_change() {
        let mut ne = NormalEquations::<f32, 1>::with_forgetting(0.99);
        for _ in 0..2000 {
            ne.update(&[1.0], 5.0);
        }
        for _ in 0..2000 {
            ne.update(&[1.0], -1.0);
        }
        let sol = ne.solve().unwrap();
        assert!((sol.theta[0] + 1.0).abs() < 1e-3, "{}", sol.theta[0]);
        assert!(ne.count() < 101.0);
    }

    #[test]
    fn reports_missing_excitation_and_dependence() {
        let mut ne = NormalEquations::<f64, 2>::new();
        for k in 0..10 {
            ne.update(&[k as f64, 0.0], 1.0);
        }
        assert_eq!(
            ne.solve().err(),
            Some(SolveError::NoExcitation { regressor: 1 })
        );
        let mut dep = NormalEquations::<f64, 2>::new();
        for k in 0..10 {
            dep.update(&[k as f64, 2.0 * k as f64], 1.0);
        }
        assert!(dep.solve().is_err() || dep.solve().unwrap().condition_number > 1e10);
        assert_eq!(
            NormalEquations::<f64, 2>::new().solve().err(),
            Some(SolveError::TooFewSamples)
        );
    }
}
