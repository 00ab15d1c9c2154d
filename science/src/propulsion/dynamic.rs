//! Coefficients from dynamic runs (a sine, a chirp, steps too short to settle): the load cell
//! seen through its own lag, read only where it updates.
//!
//! ```text
//!  thrust cell:  T_k = A·L_τ[(ω/ω_r)^p](t_k) + T₀
//!  torque cell:  Q_k = A·L_τ[(ω/ω_r)^p](t_k) + J·L_τ[dω/dt](t_k) + Q₀
//! ```
//! L_τ is a first-order lag τ·ẏ = u − y, integrated exactly for an input linear between rows
//! (first-order hold: y⁺ = α·y + (1 − α)·u + β·(u⁺ − u), α = e^(−h/τ), β = 1 − τ(1 − α)/h),
//! the way the diagnosis reads a force sensor's lag. A cell that holds its reading between
//! samples repeats a value in consecutive rows: only rows where the value changes are fitted.
//! A, J and T₀/Q₀ are linear (least squares); p and τ are found by golden section (p outside,
//! τ inside); their standard errors come from the curvature of the residual sum of squares
//! (σ_θ² = 2σ²/∂²RSS/∂θ²). The torque cell carries J·dω/dt (the rotor accelerating), the
//! thrust cell nothing of the kind.

use propid_core::estimate::NormalEquations;

use super::law::golden_min;

/// y = L_τ[u] on the rows' times (first-order hold; NaN inputs hold the last one).
pub fn lag(t: &[f64], u: &[f64], tau: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(u.len());
    let mut y = f64::NAN;
    let mut prev_u = f64::NAN;
    let mut prev_t = f64::NAN;
    for (&tk, &uk) in t.iter().zip(u) {
        if !uk.is_finite() {
            out.push(y);
            continue;
        }
        if !y.is_finite() || tau <= 0.0 {
            y = uk;
        } else {
            let h = tk - prev_t;
            if h > 0.0 {
                let alpha = (-h / tau).exp();
                let beta = 1.0 - tau * (1.0 - alpha) / h;
                y = alpha * y + (1.0 - alpha) * prev_u + beta * (uk - prev_u);
            }
        }
        prev_u = uk;
        prev_t = tk;
        out.push(y);
    }
    out
}

/// Rows where `values` has a new finite reading (a held value counts at its first row).
pub fn updates(values: &[f64]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut last = f64::NAN;
    for (k, &v) in values.iter().enumerate() {
        if v.is_finite() && v != last {
            out.push(k);
            last = v;
        } else if !v.is_finite() {
            last = f64::NAN;
        }
    }
    out
}

/// A least-squares solve at one lag: the lagged regressor, θ = [A, J, offset], their standard
/// errors, the RSS and the RMS residual.
type Solved = (Vec<f64>, [f64; 3], [f64; 3], f64, f64);

/// The dynamic fit of one cell.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicFit {
    /// A: the value at the reference speed.
    pub amplitude: f64,
    /// Its standard error.
    pub amplitude_stderr: f64,
    /// p.
    pub exponent: f64,
    /// Its standard error.
    pub exponent_stderr: f64,
    /// τ [s].
    pub lag: f64,
    /// Its standard error.
    pub lag_stderr: f64,
    /// The fitted zero T₀ or Q₀.
    pub offset: f64,
    /// Its standard error.
    pub offset_stderr: f64,
    /// J (torque cell only) [kg·m²].
    pub inertia: Option<(f64, f64)>,
    /// Rows fitted (the cell's updates).
    pub samples: usize,
    /// RMS residual.
    pub rms: f64,
    /// For the band table: (row index, measured minus the fitted offset and inertia term,
    /// the lagged law regressor) at each fitted row.
    pub rows: Vec<(usize, f64, f64)>,
}

/// Fits a cell's law through its lag. `acceleration` is given for a torque cell (J·dω/dt).
/// `None` when fewer than 50 updates remain.
pub fn fit(
    t: &[f64],
    speed: &[f64],
    acceleration: Option<&[f64]>,
    cell: &[f64],
    omega_ref: f64,
    fixed_exponent: Option<f64>,
) -> Option<DynamicFit> {
    let top = speed
        .iter()
        .map(|w| w.abs())
        .filter(|w| w.is_finite())
        .fold(0.0, f64::max);
    let rows: Vec<usize> = updates(cell)
        .into_iter()
        .filter(|&k| speed[k].is_finite() && speed[k].abs() > 0.05 * top)
        .filter(|&k| acceleration.is_none_or(|a| a[k].is_finite()))
        .collect();
    if rows.len() < 50 {
        return None;
    }
    let lagged_accel = |tau: f64| acceleration.map(|a| lag(t, a, tau));
    let regressor = |p: f64| -> Vec<f64> {
        speed
            .iter()
            .map(|w| (w.abs() / omega_ref).powf(p))
            .collect()
    };
    // Least squares at a given regressor and lag: (lagged regressor, θ = [A, J, offset], their
    // standard errors, RSS, RMS).
    let solve = |u: &[f64], tau: f64| -> Option<Solved> {
        let ul = lag(t, u, tau);
        match lagged_accel(tau) {
            Some(al) => {
                let mut eq = NormalEquations::<f64, 3>::new();
                for &k in &rows {
                    eq.update(&[ul[k], al[k], 1.0], cell[k]);
                }
                let s = eq.solve().ok()?;
                let rss = eq.residual_sum_of_squares(&s.theta);
                Some((ul, s.theta, s.stderr, rss, s.rms))
            }
            None => {
                let mut eq = NormalEquations::<f64, 2>::new();
                for &k in &rows {
                    eq.update(&[ul[k], 1.0], cell[k]);
                }
                let s = eq.solve().ok()?;
                let rss = eq.residual_sum_of_squares(&s.theta);
                Some((
                    ul,
                    [s.theta[0], 0.0, s.theta[1]],
                    [s.stderr[0], 0.0, s.stderr[1]],
                    rss,
                    s.rms,
                ))
            }
        }
    };
    let rss_of = |u: &[f64], tau: f64| solve(u, tau).map_or(f64::INFINITY, |s| s.3);
    // The best lag for a regressor (0 when no lag fits better: golden section never reaches the
    // end of its interval).
    let best_tau = |u: &[f64]| {
        let tau = golden_min(0.0, 0.5, |tau| rss_of(u, tau), 32);
        if rss_of(u, 0.0) <= rss_of(u, tau) {
            0.0
        } else {
            tau
        }
    };
    let p = fixed_exponent.unwrap_or_else(|| {
        golden_min(
            1.0,
            4.0,
            |p| {
                let u = regressor(p);
                rss_of(&u, best_tau(&u))
            },
            28,
        )
    });
    let u = regressor(p);
    let tau = best_tau(&u);
    let (ul, theta, stderr, rss0, rms) = solve(&u, tau)?;
    let n = rows.len();
    let sigma2 = rss0 / (n as f64 - 5.0).max(1.0);
    let curvature_stderr = |f: &dyn Fn(f64) -> f64, x: f64, h: f64| {
        let c = (f(x + h) - 2.0 * f(x) + f(x - h)) / (h * h);
        if c > 0.0 {
            (2.0 * sigma2 / c).sqrt()
        } else {
            f64::NAN
        }
    };
    let exponent_stderr = if fixed_exponent.is_some() {
        0.0
    } else {
        curvature_stderr(&|q| rss_of(&regressor(q), tau), p, 0.01)
    };
    // At τ = 0 the curvature is taken one step inside the admissible range.
    let h_tau = (0.05 * tau).max(2e-4);
    let lag_stderr = curvature_stderr(&|x| rss_of(&u, x), tau.max(h_tau), h_tau);
    let al = lagged_accel(tau);
    let fitted_rows = rows
        .iter()
        .map(|&k| {
            let inertia_term = al.as_ref().map_or(0.0, |a| theta[1] * a[k]);
            (k, cell[k] - theta[2] - inertia_term, ul[k])
        })
        .collect();
    Some(DynamicFit {
        amplitude: theta[0],
        amplitude_stderr: stderr[0],
        exponent: p,
        exponent_stderr,
        lag: tau,
        lag_stderr,
        offset: theta[2],
        offset_stderr: stderr[2],
        inertia: acceleration.map(|_| (theta[1], stderr[1])),
        samples: n,
        rms,
        rows: fitted_rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lag_is_exact_for_a_ramp() {
        // A ramp u = t through τ: y = t − τ(1 − e^(−t/τ)) from y(0) = 0.
        let t: Vec<f64> = (0..=200).map(|k| k as f64 * 0.01).collect();
        let y = lag(&t, &t, 0.1);
        for (tk, yk) in t.iter().zip(&y) {
            let exact = tk - 0.1 * (1.0 - (-tk / 0.1).exp());
            assert!((yk - exact).abs() < 1e-12, "{tk}: {yk} vs {exact}");
        }
        assert_eq!(lag(&t, &t, 0.0), t);
    }

    #[test]
    fn recovers_a_lagged_held_cell() {
        // ω = 800 + 300 sin(πt); thrust 1e-5·ω^2.1 through a 30 ms lag, sampled at 80 Hz and held.
        let dt = 0.002;
        let t: Vec<f64> = (0..20_000).map(|k| k as f64 * dt).collect();
        let w: Vec<f64> = t
            .iter()
            .map(|t| 800.0 + 300.0 * (std::f64::consts::PI * t).sin())
            .collect();
        let truth: Vec<f64> = w.iter().map(|w| 1e-5 * w.powf(2.1) + 0.05).collect();
        let lagged = lag(&t, &truth, 0.03);
        let mut held = vec![0.0; t.len()];
        let mut value = lagged[0];
        for k in 0..t.len() {
            if k % 6 == 0 {
                value = lagged[k] + 1e-3 * (((k * 7919) % 101) as f64 / 101.0 - 0.5);
            }
            held[k] = value;
        }
        let f = fit(&t, &w, None, &held, 800.0, None).unwrap();
        assert!((f.exponent - 2.1).abs() < 0.01, "{f:?}");
        assert!((f.lag - 0.03).abs() < 0.002, "{}", f.lag);
        let a = 1e-5 * 800f64.powf(2.1);
        assert!(
            (f.amplitude / a - 1.0).abs() < 0.005,
            "{} vs {a}",
            f.amplitude
        );
        assert!((f.offset - 0.05).abs() < 2e-3);
    }
}
