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

/// Samples kept raw before their block is summed: an update only stores its sample, and a full
/// block is summed plainly in the working precision, in one pass with independent partial sums
/// per lane (so the compiler can use SIMD without reassociating anything), then added to the
/// compensated totals.
const BLOCK: usize = 32;

/// The raw samples of the open block, one array per column.
#[derive(Clone, Copy, Debug)]
struct Buffer<T, const N: usize> {
    phi: [[T; BLOCK]; N],
    y: [T; BLOCK],
    /// The samples' weights, only when `weighted` (an unweighted update writes none).
    w: [T; BLOCK],
    /// Samples stored, 0..BLOCK.
    len: usize,
    /// A weight other than 1 is among them, and `w[..len]` holds every weight; otherwise each
    /// weight is 1 and `w` is not read.
    weighted: bool,
}

/// The plain sums of one block.
struct BlockSums<T, const N: usize> {
    phi_phi: [[T; N]; N],
    phi_y: [T; N],
    y_y: T,
    weight: T,
    /// λ^len: how much the totals decay when this block is added to them.
    decay: T,
}

/// Partial sums kept apart while a block is summed: as many as one SIMD register holds (16 bytes
/// on x86-64 and AArch64), one on a scalar FPU such as the Cortex-M4F's.
const fn lanes(size_of_t: usize) -> usize {
    if cfg!(all(target_arch = "arm", not(target_feature = "neon"))) || size_of_t >= 16 {
        1
    } else if size_of_t >= 8 {
        2
    } else {
        4
    }
}

impl<T: RealField + Copy, const N: usize> Buffer<T, N> {
    fn empty() -> Self {
        Buffer {
            phi: [[T::zero(); BLOCK]; N],
            y: [T::zero(); BLOCK],
            w: [T::zero(); BLOCK],
            len: 0,
            weighted: false,
        }
    }

    /// Sums the first `len` samples; sample k is weighted by w[k]·λ^(len−1−k).
    #[inline(always)]
    fn sums(&self, len: usize, lambda: T) -> BlockSums<T, N> {
        if !self.weighted && lambda == T::one() {
            let mut out = match lanes(core::mem::size_of::<T>()) {
                1 => self.pass::<1, false>(&[T::one(); BLOCK], len),
                2 => self.pass::<2, false>(&[T::one(); BLOCK], len),
                _ => self.pass::<4, false>(&[T::one(); BLOCK], len),
            };
            out.weight = T::from_usize(len).unwrap_or(T::zero());
            return out;
        }
        // Each sample's weight, discounted by its age within the block.
        let mut s = [T::zero(); BLOCK];
        let mut f = T::one();
        for k in (0..len).rev() {
            s[k] = self.weight(k) * f;
            f *= lambda;
        }
        let mut out = match lanes(core::mem::size_of::<T>()) {
            1 => self.pass::<1, true>(&s, len),
            2 => self.pass::<2, true>(&s, len),
            _ => self.pass::<4, true>(&s, len),
        };
        out.decay = f;
        out
    }

    /// Sample k's weight.
    #[inline(always)]
    fn weight(&self, k: usize) -> T {
        if self.weighted {
            self.w[k]
        } else {
            T::one()
        }
    }

    /// Sums a full block: each entry is a pairwise sum of its 32 products (elementwise array
    /// operations, which the compiler turns into SIMD without reassociating anything; error
    /// ~log₂32·ε instead of ~32·ε for a running sum).
    #[inline(always)]
    fn full_sums(&self, lambda: T) -> BlockSums<T, N> {
        let mut out = BlockSums {
            phi_phi: [[T::zero(); N]; N],
            phi_y: [T::zero(); N],
            y_y: T::zero(),
            weight: T::from_usize(BLOCK).unwrap_or(T::zero()),
            decay: T::one(),
        };
        if !self.weighted && lambda == T::one() && N > 3 {
            // Many entries: one pairwise dot product after the other keeps fewer values live.
            for i in 0..N {
                for j in i..N {
                    out.phi_phi[i][j] = pairwise_dot(&self.phi[i], &self.phi[j]);
                }
                out.phi_y[i] = pairwise_dot(&self.phi[i], &self.y);
            }
            out.y_y = pairwise_dot(&self.y, &self.y);
            return out;
        }
        if !self.weighted && lambda == T::one() {
            // Every product of the block at once, position by position (each column is read
            // once for all its entries), in the same pairwise order as `pairwise_dot`: the
            // first three halvings for positions k, k+4, …, k+28 ([`tree8`]), then the last two.
            // (Up to three regressors: with more, the partial sums no longer fit in registers.)
            let mut pp = [[[T::zero(); 4]; N]; N];
            let mut py = [[T::zero(); 4]; N];
            let mut yy = [T::zero(); 4];
            for k in 0..4 {
                for i in 0..N {
                    for j in i..N {
                        pp[i][j][k] = tree8(&self.phi[i], &self.phi[j], k);
                    }
                    py[i][k] = tree8(&self.phi[i], &self.y, k);
                }
                yy[k] = tree8(&self.y, &self.y, k);
            }
            let last = |v: [T; 4]| (v[0] + v[2]) + (v[1] + v[3]);
            for i in 0..N {
                for j in i..N {
                    out.phi_phi[i][j] = last(pp[i][j]);
                }
                out.phi_y[i] = last(py[i]);
            }
            out.y_y = last(yy);
            return out;
        }
        let mut s = [T::zero(); BLOCK];
        let mut f = T::one();
        for k in (0..BLOCK).rev() {
            s[k] = self.weight(k) * f;
            f *= lambda;
        }
        out.decay = f;
        for i in 0..N {
            let sphi: [T; BLOCK] = core::array::from_fn(|k| s[k] * self.phi[i][k]);
            for j in i..N {
                out.phi_phi[i][j] = pairwise_dot(&sphi, &self.phi[j]);
            }
            out.phi_y[i] = pairwise_dot(&sphi, &self.y);
        }
        let sy: [T; BLOCK] = core::array::from_fn(|k| s[k] * self.y[k]);
        out.y_y = pairwise_dot(&sy, &self.y);
        out.weight = pairwise_sum(s);
        out
    }

    /// One pass over the block: L partial sums per entry of the upper triangle of [Φ y]ᵀ[Φ y];
    /// with `SCALED`, sample k's products are multiplied by s[k].
    #[inline(always)]
    fn pass<const L: usize, const SCALED: bool>(
        &self,
        s: &[T; BLOCK],
        len: usize,
    ) -> BlockSums<T, N> {
        if N == 3 && L == 1 {
            return self.pass3::<SCALED>(s, len);
        }
        let mut acc = Lanes::<T, N, L>::zero();
        let whole = len / L * L;
        let mut k0 = 0;
        while k0 < whole {
            acc.add::<L, SCALED>(self, s, k0);
            k0 += L;
        }
        for k in whole..len {
            acc.add::<1, SCALED>(self, s, k);
        }
        acc.fold()
    }

    /// [`Buffer::pass`] for three regressors and one lane (the load estimator on a scalar FPU),
    /// written out so the ten running sums stay in registers at any optimisation level.
    #[inline(always)]
    fn pass3<const SCALED: bool>(&self, s: &[T; BLOCK], len: usize) -> BlockSums<T, N> {
        let z = T::zero();
        let (mut a00, mut a01, mut a02, mut a11, mut a12, mut a22) = (z, z, z, z, z, z);
        let (mut b0, mut b1, mut b2, mut yy, mut ww) = (z, z, z, z, z);
        let (p0, p1, p2) = (&self.phi[0], &self.phi[1], &self.phi[2]);
        for k in 0..len.min(BLOCK) {
            let (x0, x1, x2, y) = (p0[k], p1[k], p2[k], self.y[k]);
            let (s0, s1, s2, sy) = if SCALED {
                let sk = s[k];
                ww += sk;
                (sk * x0, sk * x1, sk * x2, sk * y)
            } else {
                (x0, x1, x2, y)
            };
            a00 += s0 * x0;
            a01 += s0 * x1;
            a02 += s0 * x2;
            a11 += s1 * x1;
            a12 += s1 * x2;
            a22 += s2 * x2;
            b0 += s0 * y;
            b1 += s1 * y;
            b2 += s2 * y;
            yy += sy * y;
        }
        let mut out = BlockSums {
            phi_phi: [[z; N]; N],
            phi_y: [z; N],
            y_y: yy,
            weight: ww,
            decay: T::one(),
        };
        let pp = &mut out.phi_phi;
        (pp[0][0], pp[0][1], pp[0][2]) = (a00, a01, a02);
        (pp[1][1], pp[1][2], pp[2][2]) = (a11, a12, a22);
        (out.phi_y[0], out.phi_y[1], out.phi_y[2]) = (b0, b1, b2);
        out
    }
}

/// `L` independent partial sums of each entry of the upper triangle of [Φ y]ᵀ[Φ y] and of the
/// weights.
struct Lanes<T, const N: usize, const L: usize> {
    pp: [[[T; L]; N]; N],
    py: [[T; L]; N],
    yy: [T; L],
    ww: [T; L],
}

impl<T: RealField + Copy, const N: usize, const L: usize> Lanes<T, N, L> {
    #[inline(always)]
    fn zero() -> Self {
        Lanes {
            pp: [[[T::zero(); L]; N]; N],
            py: [[T::zero(); L]; N],
            yy: [T::zero(); L],
            ww: [T::zero(); L],
        }
    }

    /// Adds samples k0..k0+W, sample k0+l to lane l.
    #[inline(always)]
    fn add<const W: usize, const SCALED: bool>(
        &mut self,
        buf: &Buffer<T, N>,
        s: &[T; BLOCK],
        k0: usize,
    ) {
        for l in 0..W {
            let k = k0 + l;
            let y = buf.y[k];
            let sk = s[k];
            let sy = if SCALED { sk * y } else { y };
            for i in 0..N {
                let zi = buf.phi[i][k];
                let szi = if SCALED { sk * zi } else { zi };
                for j in i..N {
                    self.pp[i][j][l] += szi * buf.phi[j][k];
                }
                self.py[i][l] += szi * y;
            }
            self.yy[l] += sy * y;
            if SCALED {
                self.ww[l] += sk;
            }
        }
    }

    /// Folds the lanes pairwise, the way a SIMD register is folded in halves.
    #[inline(always)]
    fn fold(&self) -> BlockSums<T, N> {
        let f = |v: &[T; L]| {
            let mut v = *v;
            let mut width = L;
            while width > 1 {
                width /= 2;
                for l in 0..width {
                    v[l] += v[l + width];
                }
            }
            v[0]
        };
        let mut out = BlockSums {
            phi_phi: [[T::zero(); N]; N],
            phi_y: [T::zero(); N],
            y_y: f(&self.yy),
            weight: f(&self.ww),
            decay: T::one(),
        };
        for i in 0..N {
            for j in i..N {
                out.phi_phi[i][j] = f(&self.pp[i][j]);
            }
            out.phi_y[i] = f(&self.py[i]);
        }
        out
    }
}

/// The partial sum of `pairwise_dot(a, b)` that ends up in its element k < 4 after the halvings
/// by 16, 8 and 4: the products at k, k+4, …, k+28, added in that order.
#[inline(always)]
fn tree8<T: RealField + Copy>(a: &[T; BLOCK], b: &[T; BLOCK], k: usize) -> T {
    let p = |m: usize| a[k + 4 * m] * b[k + 4 * m];
    // Halving by 16 adds position +16 (m + 4), by 8 position +8 (m + 2), by 4 position +4.
    ((p(0) + p(4)) + (p(2) + p(6))) + ((p(1) + p(5)) + (p(3) + p(7)))
}

/// Σₖ a[k]·b[k] over a full block, summed pairwise.
#[inline(always)]
fn pairwise_dot<T: RealField + Copy>(a: &[T; BLOCK], b: &[T; BLOCK]) -> T {
    pairwise_sum(core::array::from_fn(|k| a[k] * b[k]))
}

/// Σₖ p[k], pairwise: p[k] += p[k + w] for w = 16, 8, 4, 2, 1.
#[inline(always)]
fn pairwise_sum<T: RealField + Copy>(mut p: [T; BLOCK]) -> T {
    let mut w = BLOCK / 2;
    while w > 0 {
        for k in 0..w {
            p[k] += p[k + w];
        }
        w /= 2;
    }
    p[0]
}

/// The sums folded into plain values, for solving.
struct Sums<T, const N: usize> {
    /// ΦᵀΦ, full.
    a: [[T; N]; N],
    /// Φᵀy.
    b: [T; N],
    /// yᵀy.
    y_y: T,
    /// Σ weights.
    n: T,
}

/// Incremental normal equations of a linear least-squares problem y ≈ φᵀθ with `N` regressors,
/// in fixed memory.
///
/// An update stores its sample in a block of 32; a full block is summed plainly (the upper
/// triangle of ΦᵀΦ, Φᵀy, yᵀy, the weight) and added to Kahan-compensated totals, so the
/// compensation costs once per block instead of once per sample. Reading (`matrix`, `solve`, …)
/// folds the open block in without changing the state.
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
    /// The samples not yet in the totals.
    buffer: Buffer<T, N>,
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
            buffer: Buffer::empty(),
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
    #[inline]
    pub fn update(&mut self, phi: &[T; N], y: T) {
        let b = &mut self.buffer;
        // `len < BLOCK` always; the mask lets the compiler drop the bounds checks.
        let k = b.len & (BLOCK - 1);
        for i in 0..N {
            b.phi[i][k] = phi[i];
        }
        b.y[k] = y;
        // A weight is stored only in a block that has a weight other than one.
        if b.weighted {
            b.w[k] = T::one();
        }
        b.len = k + 1;
        if b.len == BLOCK {
            self.flush();
        }
    }

    /// Adds one sample with weight `w`.
    #[inline]
    pub fn update_weighted(&mut self, phi: &[T; N], y: T, w: T) {
        let b = &mut self.buffer;
        let k = b.len & (BLOCK - 1);
        for i in 0..N {
            b.phi[i][k] = phi[i];
        }
        b.y[k] = y;
        if !b.weighted && w != T::one() {
            // The first weight other than one in this block: the samples before it had one.
            for wk in &mut b.w[..k] {
                *wk = T::one();
            }
            b.weighted = true;
        }
        if b.weighted {
            b.w[k] = w;
        }
        b.len = k + 1;
        if b.len == BLOCK {
            self.flush();
        }
    }

    /// Adds the full block to the compensated totals.
    #[inline(never)]
    fn flush(&mut self) {
        // With SIMD, pairwise sums over the block; on a scalar FPU, one pass with the running
        // sums in registers is cheaper.
        let sums = if lanes(core::mem::size_of::<T>()) == 1 {
            self.buffer.sums(BLOCK, self.forgetting)
        } else {
            self.buffer.full_sums(self.forgetting)
        };
        self.buffer.len = 0;
        self.buffer.weighted = false;
        self.fold(&sums);
    }

    /// totals ← λ^len · totals + block.
    fn fold(&mut self, b: &BlockSums<T, N>) {
        let scale = b.decay != T::one();
        for i in 0..N {
            for j in i..N {
                if scale {
                    self.phi_phi[i][j].scale(b.decay);
                }
                self.phi_phi[i][j].add(b.phi_phi[i][j]);
            }
            if scale {
                self.phi_y[i].scale(b.decay);
            }
            self.phi_y[i].add(b.phi_y[i]);
        }
        if scale {
            self.y_y.scale(b.decay);
            self.weight.scale(b.decay);
        }
        self.y_y.add(b.y_y);
        self.weight.add(b.weight);
    }

    /// A copy with the open block folded into the totals.
    fn folded(&self) -> Self {
        let mut f = *self;
        let sums = self.buffer.sums(self.buffer.len, self.forgetting);
        f.buffer.len = 0;
        f.buffer.weighted = false;
        f.fold(&sums);
        f
    }

    /// Adds the samples of `other` (as if they had been given to `self`).
    pub fn merge(&mut self, other: &Self) {
        *self = self.folded();
        let other = other.folded();
        for i in 0..N {
            for j in i..N {
                self.phi_phi[i][j].merge(&other.phi_phi[i][j]);
            }
            self.phi_y[i].merge(&other.phi_y[i]);
        }
        self.y_y.merge(&other.y_y);
        self.weight.merge(&other.weight);
    }

    /// The folded sums as plain values.
    fn sums(&self) -> Sums<T, N> {
        let f = self.folded();
        let mut a = [[T::zero(); N]; N];
        for i in 0..N {
            for j in i..N {
                a[i][j] = f.phi_phi[i][j].sum;
                a[j][i] = f.phi_phi[i][j].sum;
            }
        }
        Sums {
            a,
            b: core::array::from_fn(|i| f.phi_y[i].sum),
            y_y: f.y_y.sum,
            n: f.weight.sum,
        }
    }

    /// The equations of the same samples with regressor i multiplied by `s[i]` (a column read
    /// in another unit or with the opposite sign): ΦᵀΦ becomes S·ΦᵀΦ·S and Φᵀy becomes S·Φᵀy,
    /// exactly, with no sample read again.
    pub fn scale_regressors(&mut self, s: &[T; N]) {
        *self = self.folded();
        for i in 0..N {
            for j in i..N {
                self.phi_phi[i][j].scale(s[i] * s[j]);
            }
            self.phi_y[i].scale(s[i]);
        }
    }

    /// Effective number of samples.
    pub fn count(&self) -> T {
        self.sums().n
    }

    /// ΦᵀΦ as a full symmetric matrix.
    pub fn matrix(&self) -> [[T; N]; N] {
        self.sums().a
    }

    /// Φᵀy.
    pub fn vector(&self) -> [T; N] {
        self.sums().b
    }

    /// Σ y².
    pub fn sum_y_squared(&self) -> T {
        self.sums().y_y
    }

    /// The residual sum of squares at θ: yᵀy − 2θᵀΦᵀy + θᵀΦᵀΦθ (never negative).
    pub fn residual_sum_of_squares(&self, theta: &[T; N]) -> T {
        self.sums().residual_sum_of_squares(theta)
    }

    /// Unconstrained least squares.
    pub fn solve(&self) -> Result<Solution<T, N>, SolveError> {
        self.sums().solve()
    }

    /// Least squares subject to `M` linear inequalities g_kᵀθ ≤ h_k, exactly (see the module
    /// documentation). `M` must be at most 8.
    pub fn solve_constrained<const M: usize>(
        &self,
        g: &[[T; N]; M],
        h: &[T; M],
    ) -> Result<Solution<T, N>, SolveError> {
        self.sums().solve_constrained(g, h)
    }
}

impl<T: RealField + Copy, const N: usize> Sums<T, N> {
    /// The residual sum of squares at θ: yᵀy − 2θᵀΦᵀy + θᵀΦᵀΦθ (never negative).
    fn residual_sum_of_squares(&self, theta: &[T; N]) -> T {
        let (a, b) = (&self.a, &self.b);
        let mut ss = self.y_y;
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
            let aii = self.a[i][i];
            if aii <= T::zero() || !aii.is_finite() {
                return Err(SolveError::NoExcitation { regressor: i });
            }
            *di = T::one() / aii.sqrt();
        }
        Ok(d)
    }

    fn scaled_matrix(&self, d: &[T; N]) -> SMatrix<T, N, N> {
        let a = &self.a;
        SMatrix::<T, N, N>::from_fn(|i, j| a[i][j] * d[i] * d[j])
    }

    /// Unconstrained least squares.
    fn solve(&self) -> Result<Solution<T, N>, SolveError> {
        if self.n < T::from_usize(N).unwrap_or(T::one()) {
            return Err(SolveError::TooFewSamples);
        }
        let d = self.scales()?;
        let s = self.scaled_matrix(&d);
        let chol = nalgebra::Cholesky::new(s).ok_or(SolveError::Singular)?;
        let b = self.b;
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
    fn solve_constrained<const M: usize>(
        &self,
        g: &[[T; N]; M],
        h: &[T; M],
    ) -> Result<Solution<T, N>, SolveError> {
        const { assert!(M <= 8, "at most 8 constraints") };
        if self.n < T::from_usize(N).unwrap_or(T::one()) {
            return Err(SolveError::TooFewSamples);
        }
        let d = self.scales()?;
        let s = self.scaled_matrix(&d);
        let b = self.b;
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
        let n = self.n;
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
    fn blocks_weights_and_forgetting_match_a_direct_sum() {
        // 100 samples: three full blocks and an open one; weights and forgetting on.
        let lambda = 0.99;
        let mut ne = NormalEquations::<f64, 3>::with_forgetting(lambda);
        let mut direct = [[0.0; 3]; 3];
        let mut s = 3u64;
        for k in 0..100 {
            let phi = [lcg(&mut s), lcg(&mut s), lcg(&mut s)];
            let w = if k % 7 == 0 { 2.5 } else { 1.0 };
            ne.update_weighted(&phi, 0.0, w);
            for row in direct.iter_mut() {
                for v in row.iter_mut() {
                    *v *= lambda;
                }
            }
            for i in 0..3 {
                for j in 0..3 {
                    direct[i][j] += w * phi[i] * phi[j];
                }
            }
            if k == 40 || k == 99 {
                let m = ne.matrix();
                for i in 0..3 {
                    for j in 0..3 {
                        assert!((m[i][j] - direct[i][j]).abs() < 1e-13, "{k} {i}{j}");
                    }
                }
            }
        }
        let expected_weight = (0..100)
            .map(|k| if k % 7 == 0 { 2.5 } else { 1.0 } * lambda.powi(99 - k))
            .sum::<f64>();
        assert!((ne.count() - expected_weight).abs() < 1e-12);
        // Merging an open block into a half-full one equals feeding both in order.
        let mut a = NormalEquations::<f64, 2>::new();
        let mut b = NormalEquations::<f64, 2>::new();
        let mut all = NormalEquations::<f64, 2>::new();
        for k in 0..50 {
            let phi = [k as f64, 1.0];
            if k < 20 {
                a.update(&phi, 2.0)
            } else {
                b.update(&phi, 2.0)
            }
            all.update(&phi, 2.0);
        }
        a.merge(&b);
        assert_eq!(a.matrix(), all.matrix());
        assert_eq!(a.vector(), all.vector());
        assert_eq!(a.count(), 50.0);
    }

    /// A full unweighted block is summed with every product at once, in exactly the pairwise
    /// order of `pairwise_dot` (bit for bit), in f64 and f32.
    #[test]
    fn full_block_sums_are_the_pairwise_dots_bit_for_bit() {
        fn check<T: RealField + Copy + core::fmt::Debug>(cast: impl Fn(f64) -> T) {
            let mut s = 11u64;
            for _ in 0..50 {
                let mut b = Buffer::<T, 3>::empty();
                for k in 0..BLOCK {
                    for i in 0..3 {
                        b.phi[i][k] = cast(lcg(&mut s) * 10f64.powi((k % 7) as i32 - 3));
                    }
                    b.y[k] = cast(lcg(&mut s));
                }
                let got = b.full_sums(T::one());
                for i in 0..3 {
                    for j in i..3 {
                        assert_eq!(got.phi_phi[i][j], pairwise_dot(&b.phi[i], &b.phi[j]));
                    }
                    assert_eq!(got.phi_y[i], pairwise_dot(&b.phi[i], &b.y));
                }
                assert_eq!(got.y_y, pairwise_dot(&b.y, &b.y));
            }
        }
        check::<f64>(|v| v);
        check::<f32>(|v| v as f32);
    }

    /// Unweighted and weighted updates mixed inside blocks (the first weight other than one
    /// arriving after unweighted samples, with forgetting) match a direct sum.
    #[test]
    fn unweighted_then_weighted_in_one_block_match_a_direct_sum() {
        for lambda in [1.0, 0.97] {
            let mut ne = NormalEquations::<f64, 2>::with_forgetting(lambda);
            let mut direct = [[0.0; 2]; 2];
            let mut weight = 0.0;
            let mut s = 5u64;
            for k in 0..150 {
                let phi = [lcg(&mut s), lcg(&mut s)];
                let w = if k % 32 == 20 || k % 45 == 3 {
                    3.0
                } else {
                    1.0
                };
                if k % 3 == 0 {
                    ne.update_weighted(&phi, 1.0, w);
                } else if w == 1.0 {
                    ne.update(&phi, 1.0);
                } else {
                    ne.update_weighted(&phi, 1.0, w);
                }
                weight = weight * lambda + w;
                for (i, row) in direct.iter_mut().enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v = *v * lambda + w * phi[i] * phi[j];
                    }
                }
                let m = ne.matrix();
                for i in 0..2 {
                    for j in 0..2 {
                        assert!((m[i][j] - direct[i][j]).abs() < 1e-12, "{lambda} {k}");
                    }
                }
                assert!((ne.count() - weight).abs() < 1e-12, "{lambda} {k}");
            }
        }
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
