//! The coefficient laws: thrust and torque over speed.
//!
//! ```text
//!  T = C_T·ρ·n²·D⁴        Q = C_Q·ρ·n²·D⁵        n in rev/s (ω = 2π·n), D in m, ρ in kg/m³
//!  C_P = 2π·C_Q           (P = 2π·n·Q = C_P·ρ·n³·D⁵)
//!  seed's c2:  Q = c2·ω²  ⇒  C_Q = c2·(2π)²/(ρ·D⁵)
//! ```
//! A coefficient that depends on speed (Reynolds number, blade bending) is described by a power
//! law about a reference speed n_r,
//!
//! ```text
//!  X(n) = A·(n/n_r)^p         ⇒  C(n) = C_r·(n/n_r)^(p−2),   C_r = A/(ρ·n_r²·D^m)
//! ```
//! (m = 4 for thrust, 5 for torque): p = 2 is a constant coefficient. Fitted to plateau means X_i
//! ± σ_i by weighted least squares (A linear, p by golden section), the covariance of (A, p) is
//! (JᵀWJ)⁻¹ scaled by the reduced χ² when that exceeds 1 (the plateaus scatter more than their
//! own errors: the law is not exact, and the ± says so), plus the systematic error of the load
//! cell's zero, found by refitting with the zero moved by ±σ_z (its effect on A and p, with their
//! correlation). The quadratic law (p = 2: one constant C) is fitted the same way, and a table
//! per speed band gives C without any law.

use serde::{Deserialize, Serialize};

use super::air::Air;
use super::quantity::Quantity;
use super::TAU;

/// One measured point of a law: speed, value, its standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Speed n [rev/s].
    pub n: f64,
    /// Thrust [N] or torque [N·m].
    pub value: f64,
    /// Standard error of `value`.
    pub stderr: f64,
}

/// X = A·(n/n_r)^p with the covariance of (A, p).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PowerLaw {
    /// n_r [rev/s].
    pub reference_speed: f64,
    /// A: the value at n_r [N or N·m].
    pub at_reference: f64,
    /// p.
    pub exponent: f64,
    /// Covariance [[var A, cov], [cov, var p]].
    pub covariance: [[f64; 2]; 2],
    /// Lowest and highest speed the law was fitted on [rev/s].
    pub speed_range: [f64; 2],
}

impl PowerLaw {
    /// The value at `n` rev/s.
    pub fn value(&self, n: f64) -> f64 {
        self.at_reference * (n / self.reference_speed).powf(self.exponent)
    }

    /// The speed at which the law gives `value` (value and A of the same sign).
    pub fn speed_for(&self, value: f64) -> f64 {
        self.reference_speed * (value / self.at_reference).powf(1.0 / self.exponent)
    }

    /// Standard error of [`PowerLaw::value`] at `n` from the covariance of (A, p).
    pub fn value_stderr(&self, n: f64) -> f64 {
        let x = (n / self.reference_speed).powf(self.exponent);
        let g = [x, self.at_reference * x * (n / self.reference_speed).ln()];
        quadratic_form(&self.covariance, &g).max(0.0).sqrt()
    }

    /// Standard error of [`PowerLaw::speed_for`]: n = n_r·(X/A)^(1/p).
    pub fn speed_stderr(&self, value: f64) -> f64 {
        let n = self.speed_for(value);
        let (a, p) = (self.at_reference, self.exponent);
        let g = [-n / (p * a), -n * (value / a).ln() / (p * p)];
        quadratic_form(&self.covariance, &g).max(0.0).sqrt()
    }

    /// True when `n` lies within the fitted speed range (5 % margin).
    pub fn covers(&self, n: f64) -> bool {
        n >= 0.95 * self.speed_range[0] && n <= 1.05 * self.speed_range[1]
    }
}

fn quadratic_form(c: &[[f64; 2]; 2], g: &[f64; 2]) -> f64 {
    g[0] * g[0] * c[0][0] + 2.0 * g[0] * g[1] * c[0][1] + g[1] * g[1] * c[1][1]
}

/// Golden-section minimum of `f` on [lo, hi].
pub(crate) fn golden_min(
    mut lo: f64,
    mut hi: f64,
    f: impl Fn(f64) -> f64,
    iterations: usize,
) -> f64 {
    const G: f64 = 0.618_033_988_749_895;
    let (mut x1, mut x2) = (hi - G * (hi - lo), lo + G * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iterations {
        if f1 <= f2 {
            (hi, x2, f2) = (x2, x1, f1);
            x1 = hi - G * (hi - lo);
            f1 = f(x1);
        } else {
            (lo, x1, f1) = (x1, x2, f2);
            x2 = lo + G * (hi - lo);
            f2 = f(x2);
        }
    }
    if f1 <= f2 {
        x1
    } else {
        x2
    }
}

/// How the load cell's zero enters a fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ZeroTreatment {
    /// Measured at rest and subtracted; its standard uncertainty enters as a systematic error.
    Subtracted {
        /// Standard uncertainty of the zero (same unit as the values).
        stderr: f64,
    },
    /// Not measured: fitted as a constant with the law.
    Fitted,
}

/// A fitted law and, when the zero was fitted, the zero ± its standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawFit {
    /// The law.
    pub law: PowerLaw,
    /// The fitted zero and its standard error.
    pub zero: Option<(f64, f64)>,
}

/// Solves the k×k system `m·x = b` by Gauss–Jordan with partial pivoting (k ≤ 3); also returns
/// the inverse.
fn solve_small(m: &[[f64; 3]; 3], k: usize) -> Option<[[f64; 3]; 3]> {
    let mut a = *m;
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate().take(k) {
        row[i] = 1.0;
    }
    for c in 0..k {
        let p = (c..k).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[p][c].abs() < 1e-300 || !a[p][c].is_finite() {
            return None;
        }
        a.swap(c, p);
        inv.swap(c, p);
        let d = a[c][c];
        for j in 0..k {
            a[c][j] /= d;
            inv[c][j] /= d;
        }
        for r in 0..k {
            if r != c {
                let f = a[r][c];
                for j in 0..k {
                    a[r][j] -= f * a[c][j];
                    inv[r][j] -= f * inv[c][j];
                }
            }
        }
    }
    Some(inv)
}

/// Weighted least squares of the linear parameters at fixed p: (A, zero, χ²); the zero is 0
/// unless fitted. `shift` is added to every value (the zero moved for the systematic error).
fn fit_linear(
    points: &[Point],
    n_r: f64,
    p: f64,
    fitted_zero: bool,
    shift: f64,
) -> (f64, f64, f64) {
    let (mut sw, mut sx, mut sxx, mut sy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for q in points {
        let w = 1.0 / (q.stderr * q.stderr);
        let x = (q.n / n_r).powf(p);
        let y = q.value + shift;
        sw += w;
        sx += w * x;
        sxx += w * x * x;
        sy += w * y;
        sxy += w * x * y;
    }
    let (a, z) = if fitted_zero {
        let det = sw * sxx - sx * sx;
        ((sw * sxy - sx * sy) / det, (sxx * sy - sx * sxy) / det)
    } else {
        (sxy / sxx, 0.0)
    };
    let chi2 = points
        .iter()
        .map(|q| {
            let r = q.value + shift - z - a * (q.n / n_r).powf(p);
            r * r / (q.stderr * q.stderr)
        })
        .sum();
    (a, z, chi2)
}

/// Least-squares (A, p, zero) with p in [0.5, 5] unless fixed.
fn fit_all(
    points: &[Point],
    n_r: f64,
    fixed_p: Option<f64>,
    fitted_zero: bool,
    shift: f64,
) -> (f64, f64, f64, f64) {
    let p = fixed_p.unwrap_or_else(|| {
        golden_min(
            0.5,
            5.0,
            |p| fit_linear(points, n_r, p, fitted_zero, shift).2,
            60,
        )
    });
    let (a, z, chi2) = fit_linear(points, n_r, p, fitted_zero, shift);
    (a, p, z, chi2)
}

/// Points with usable standard errors: a zero or missing one is replaced by the median of the
/// others (a noiseless plateau must not get infinite weight).
fn with_floor(points: &[Point]) -> Vec<Point> {
    let mut errs: Vec<f64> = points
        .iter()
        .map(|p| p.stderr)
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    errs.sort_by(f64::total_cmp);
    let floor = errs.get(errs.len() / 2).copied().unwrap_or(1.0);
    points
        .iter()
        .map(|p| Point {
            stderr: if p.stderr.is_finite() && p.stderr > 0.0 {
                p.stderr
            } else {
                floor
            },
            ..*p
        })
        .collect()
}

/// Fits X = A·(n/n_r)^p (+ a zero, when not measured) to plateau points, p free unless
/// `fixed_p`. `None` with fewer points than parameters + 1.
pub fn fit_power_law(
    points: &[Point],
    n_r: f64,
    fixed_p: Option<f64>,
    zero: ZeroTreatment,
) -> Option<LawFit> {
    let fitted_zero = zero == ZeroTreatment::Fitted;
    // Parameter columns: A, then p (if free), then the zero (if fitted).
    let k = 1 + usize::from(fixed_p.is_none()) + usize::from(fitted_zero);
    if points.len() < k + 1 {
        return None;
    }
    let pts = with_floor(points);
    let (a, p, z, chi2) = fit_all(&pts, n_r, fixed_p, fitted_zero, 0.0);
    if !(a.is_finite() && p.is_finite() && z.is_finite()) {
        return None;
    }
    let birge = (chi2 / (pts.len() - k) as f64).max(1.0);
    let mut m = [[0.0; 3]; 3];
    for q in &pts {
        let w = 1.0 / (q.stderr * q.stderr);
        let x = (q.n / n_r).powf(p);
        let mut j = vec![x];
        if fixed_p.is_none() {
            j.push(a * x * (q.n / n_r).ln());
        }
        if fitted_zero {
            j.push(1.0);
        }
        for r in 0..k {
            for c in 0..k {
                m[r][c] += w * j[r] * j[c];
            }
        }
    }
    let inv = solve_small(&m, k)?;
    let p_index = fixed_p.is_none().then_some(1);
    let mut cov = [[birge * inv[0][0], 0.0], [0.0, 0.0]];
    if let Some(i) = p_index {
        cov[0][1] = birge * inv[0][i];
        cov[1][0] = birge * inv[i][0];
        cov[1][1] = birge * inv[i][i];
    }
    let zero_fit = fitted_zero.then(|| (z, (birge * inv[k - 1][k - 1]).sqrt()));
    if let ZeroTreatment::Subtracted { stderr } = zero {
        if stderr > 0.0 {
            // The zero moved by ±σ_z: X_i ∓ σ_z.
            let (a_hi, p_hi, _, _) = fit_all(&pts, n_r, fixed_p, false, -stderr);
            let (a_lo, p_lo, _, _) = fit_all(&pts, n_r, fixed_p, false, stderr);
            let d = [0.5 * (a_hi - a_lo), 0.5 * (p_hi - p_lo)];
            for r in 0..2 {
                for c in 0..2 {
                    cov[r][c] += d[r] * d[c];
                }
            }
        }
    }
    let lo = pts.iter().map(|q| q.n).fold(f64::INFINITY, f64::min);
    let hi = pts.iter().map(|q| q.n).fold(0.0, f64::max);
    Some(LawFit {
        law: PowerLaw {
            reference_speed: n_r,
            at_reference: a,
            exponent: p,
            covariance: cov,
            speed_range: [lo, hi],
        },
        zero: zero_fit,
    })
}

/// Which coefficient: thrust (D⁴) or torque (D⁵).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// C_T.
    Thrust,
    /// C_Q.
    Torque,
}

impl Kind {
    /// m of D^m.
    pub fn diameter_power(self) -> i32 {
        match self {
            Kind::Thrust => 4,
            Kind::Torque => 5,
        }
    }

    /// "C_T" or "C_Q".
    pub fn symbol(self) -> &'static str {
        match self {
            Kind::Thrust => "C_T",
            Kind::Torque => "C_Q",
        }
    }

    /// The dimensional value's unit.
    pub fn unit(self) -> &'static str {
        match self {
            Kind::Thrust => "N",
            Kind::Torque => "N·m",
        }
    }

    /// ρ·n²·D^m: the value of a coefficient of 1.
    pub fn scale(self, density: f64, n: f64, diameter: f64) -> f64 {
        density * n * n * diameter.powi(self.diameter_power())
    }
}

/// One speed band of the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Band {
    /// Lower edge [rev/s].
    pub from: f64,
    /// Upper edge [rev/s].
    pub to: f64,
    /// Plateaus in the band.
    pub plateaus: usize,
    /// Their weighted mean speed [rev/s].
    pub speed: f64,
    /// The coefficient in the band.
    pub coefficient: Quantity,
    /// Rotational Reynolds number ρ·n·D²/μ at the band's speed.
    pub reynolds: f64,
    /// Blade Reynolds number at 75 % radius (when the chord is known).
    pub reynolds_075: Option<f64>,
    /// Tip Mach number.
    pub tip_mach: f64,
    /// Whether the power law agrees with the band within 3 standard errors.
    pub law_agrees: bool,
}

/// A coefficient's identification: the laws, the band table, the zero used.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coefficient {
    /// Thrust or torque.
    pub kind: Kind,
    /// How it was measured.
    pub method: super::Method,
    /// Points (plateaus, or load-cell updates for the dynamic method) it rests on.
    pub points: usize,
    /// The coefficient at the reference speed from the power law.
    pub at_reference: Quantity,
    /// The reference speed [rev/s].
    pub reference_speed: f64,
    /// The power law's exponent p of X ∝ n^p (2: a constant coefficient).
    pub exponent: Quantity,
    /// The constant coefficient of the quadratic law (p = 2) over the whole speed range.
    pub quadratic: Quantity,
    /// The power law itself (what `propid size` evaluates).
    pub law: Option<PowerLaw>,
    /// Whether sizing uses the power law (its exponent differs from 2 by more than three
    /// standard errors) or the quadratic one.
    pub speed_dependent: bool,
    /// The table per speed band.
    pub bands: Vec<Band>,
    /// The load cell's zero as used, described.
    pub zero: String,
    /// The zero fitted with the law when it was not measured at rest [N or N·m].
    pub fitted_zero: Option<Quantity>,
    /// The inertia a torque cell carries, J·dω/dt (dynamic method) [kg·m²].
    pub inertia: Option<Quantity>,
    /// The load cell's lag (dynamic method) [s].
    pub sensor_lag: Option<Quantity>,
}

impl Coefficient {
    /// The law sizing evaluates: the power law when the exponent is not 2, else the quadratic.
    pub fn sizing_law(&self, density: f64, diameter: f64) -> Option<PowerLaw> {
        let law = self.law?;
        if self.speed_dependent {
            return Some(law);
        }
        let c = self.quadratic.value()?;
        let s = self.quadratic.stderr()?;
        let scale = self.kind.scale(density, law.reference_speed, diameter);
        Some(PowerLaw {
            at_reference: c * scale,
            exponent: 2.0,
            covariance: [[(s * scale).powi(2), 0.0], [0.0, 0.0]],
            ..law
        })
    }
}

/// "Nice" band width: 1, 2, 2.5 or 5 × 10^k rpm, about a quarter of the range.
pub(crate) fn band_width_rpm(range_rpm: f64) -> f64 {
    let raw = (range_rpm / 4.0).max(1.0);
    let e = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * e)
        .find(|w| *w >= raw)
        .unwrap_or(10.0 * e)
}

/// Fits both laws and the band table from plateau points.
#[allow(clippy::too_many_arguments)]
pub fn coefficient_from_points(
    kind: Kind,
    points: &[Point],
    zero: ZeroTreatment,
    zero_description: String,
    air: &Air,
    diameter: f64,
    chord: Option<f64>,
    reference_speed: Option<f64>,
) -> Coefficient {
    let n_r = reference_speed.unwrap_or_else(|| {
        // The log-mean speed of the points: A and p are then nearly uncorrelated.
        let s: f64 = points.iter().map(|p| p.n.ln()).sum::<f64>() / points.len().max(1) as f64;
        s.exp()
    });
    let scale = |n: f64| kind.scale(air.density, n, diameter);
    let free_fit = fit_power_law(points, n_r, None, zero);
    let quad_fit = fit_power_law(points, n_r, Some(2.0), zero);
    let free = free_fit.map(|f| f.law);
    let quad = quad_fit.map(|f| f.law);
    // A fitted zero is taken off the points for the band table.
    let zero_stderr = match zero {
        ZeroTreatment::Subtracted { stderr } => stderr,
        ZeroTreatment::Fitted => 0.0,
    };
    let fitted = free_fit.or(quad_fit).and_then(|f| f.zero);
    let shifted: Vec<Point>;
    let points = match fitted {
        Some((z, z_se)) => {
            shifted = points
                .iter()
                .map(|p| Point {
                    value: p.value - z,
                    stderr: (p.stderr * p.stderr + z_se * z_se).sqrt(),
                    ..*p
                })
                .collect();
            &shifted[..]
        }
        None => points,
    };
    let zero_description = match fitted {
        Some((z, z_se)) => format!("{zero_description}: {z:+.4} ± {z_se:.4} {}", kind.unit()),
        None => zero_description,
    };
    let too_few = |need: usize| {
        Quantity::cannot_judge(
            "1",
            format!(
                "{} steady plateau(s) with a {} reading; this needs at least {need} at different speeds",
                points.len(),
                kind.unit()
            ),
        )
    };
    let (at_reference, exponent) = match &free {
        Some(law) => (
            Quantity::judge(
                law.at_reference / scale(n_r),
                law.covariance[0][0].sqrt() / scale(n_r),
                "1",
            ),
            Quantity::judge(law.exponent, law.covariance[1][1].sqrt(), "1"),
        ),
        None => (too_few(3), too_few(3)),
    };
    let quadratic = match &quad {
        Some(law) => Quantity::judge(
            law.at_reference / scale(n_r),
            law.covariance[0][0].sqrt() / scale(n_r),
            "1",
        ),
        None => too_few(2),
    };
    let speed_dependent = match (exponent.identified(), exponent.stderr()) {
        (Some(p), Some(s)) => (p - 2.0).abs() > 3.0 * s,
        _ => false,
    };

    // The band table.
    let mut bands = Vec::new();
    if let (Some(lo), Some(hi)) = (
        points.iter().map(|p| p.n).reduce(f64::min),
        points.iter().map(|p| p.n).reduce(f64::max),
    ) {
        let width = band_width_rpm((hi - lo) * 60.0) / 60.0;
        let mut from = (lo / width).floor() * width;
        while from <= hi {
            let to = from + width;
            let inside: Vec<&Point> = points
                .iter()
                .filter(|p| p.n >= from && (p.n < to || (p.n == hi && p.n <= to)))
                .collect();
            if !inside.is_empty() {
                bands.push(band(
                    kind,
                    &inside,
                    from,
                    to,
                    zero_stderr,
                    air,
                    diameter,
                    chord,
                    free.as_ref(),
                ));
            }
            from = to;
        }
    }
    Coefficient {
        kind,
        method: super::Method::Plateaus,
        points: points.len(),
        at_reference,
        reference_speed: n_r,
        exponent,
        quadratic,
        law: free.or(quad),
        speed_dependent,
        bands,
        zero: zero_description,
        fitted_zero: fitted
            .map(|(z, se)| Quantity::judge_relative(z, se, kind.unit(), f64::INFINITY)),
        inertia: None,
        sensor_lag: None,
    }
}

#[allow(clippy::too_many_arguments)]
fn band(
    kind: Kind,
    inside: &[&Point],
    from: f64,
    to: f64,
    zero_stderr: f64,
    air: &Air,
    diameter: f64,
    chord: Option<f64>,
    law: Option<&PowerLaw>,
) -> Band {
    let pts: Vec<Point> = with_floor(&inside.iter().map(|p| **p).collect::<Vec<_>>());
    // Each plateau's coefficient and its error; the band's weighted mean.
    let cs: Vec<(f64, f64)> = pts
        .iter()
        .map(|p| {
            let s = kind.scale(air.density, p.n, diameter);
            (p.value / s, p.stderr / s)
        })
        .collect();
    let (mut sw, mut swx, mut swn) = (0.0, 0.0, 0.0);
    for ((c, e), p) in cs.iter().zip(&pts) {
        let w = 1.0 / (e * e);
        sw += w;
        swx += w * c;
        swn += w * p.n;
    }
    let mean = swx / sw;
    let speed = swn / sw;
    let chi2: f64 = cs.iter().map(|(c, e)| ((c - mean) / e).powi(2)).sum();
    let birge = if cs.len() > 1 {
        (chi2 / (cs.len() - 1) as f64).max(1.0)
    } else {
        1.0
    };
    let stat = (birge / sw).sqrt();
    let zero = zero_stderr / kind.scale(air.density, speed, diameter);
    let stderr = (stat * stat + zero * zero).sqrt();
    let law_agrees = law.is_none_or(|l| {
        let c_law = l.value(speed) / kind.scale(air.density, speed, diameter);
        let e_law = l.value_stderr(speed) / kind.scale(air.density, speed, diameter);
        (c_law - mean).abs() <= 3.0 * (stderr * stderr + e_law * e_law).sqrt()
    });
    Band {
        from,
        to,
        plateaus: cs.len(),
        speed,
        coefficient: Quantity::judge(mean, stderr, "1"),
        reynolds: air.reynolds_rotational(speed, diameter),
        reynolds_075: chord.map(|c| air.reynolds_075(speed, diameter, c)),
        tip_mach: air.tip_mach(speed, diameter),
        law_agrees,
    }
}

/// ω [rad/s] → n [rev/s].
pub fn rev_per_s(omega: f64) -> f64 {
    omega / TAU
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_power_law_and_its_inverse() {
        let pts: Vec<Point> = (0..8)
            .map(|k| {
                let n = 60.0 + 25.0 * k as f64;
                let noise = 1e-3 * ((k * 37 % 11) as f64 - 5.0);
                Point {
                    n,
                    value: 2e-4 * n.powf(2.2) * (1.0 + noise),
                    stderr: 5e-3 * 2e-4 * n.powf(2.2),
                }
            })
            .collect();
        let fitted = ZeroTreatment::Subtracted { stderr: 0.0 };
        let law = fit_power_law(&pts, 140.0, None, fitted).unwrap().law;
        assert!((law.exponent - 2.2).abs() < 0.01, "{law:?}");
        let t = law.value(150.0);
        assert!((law.speed_for(t) - 150.0).abs() < 1e-9);
        assert!(law.value_stderr(150.0) > 0.0 && law.speed_stderr(t) > 0.0);
        let quad = fit_power_law(&pts, 140.0, Some(2.0), fitted).unwrap().law;
        assert_eq!(quad.exponent, 2.0);
        assert_eq!(quad.covariance[1][1], 0.0);
        assert!(fit_power_law(&pts[..2], 140.0, None, fitted).is_none());
        // With an unknown zero of 0.05 added to every point, fitting the zero recovers both.
        let offset: Vec<Point> = pts
            .iter()
            .map(|p| Point {
                value: p.value + 0.05,
                ..*p
            })
            .collect();
        let f = fit_power_law(&offset, 140.0, None, ZeroTreatment::Fitted).unwrap();
        assert!((f.law.exponent - 2.2).abs() < 0.02, "{f:?}");
        assert!((f.zero.unwrap().0 - 0.05).abs() < 0.02, "{f:?}");
    }

    #[test]
    fn band_widths_are_round_rpm() {
        assert_eq!(band_width_rpm(10_000.0), 2500.0);
        assert_eq!(band_width_rpm(13_000.0), 5000.0);
        assert_eq!(band_width_rpm(3_000.0), 1000.0);
    }
}
