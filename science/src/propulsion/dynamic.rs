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
//! samples repeats a value in consecutive rows: only rows where the value changes are fitted, and
//! since the cell took that reading at an unknown instant of the row interval before, the model is
//! read half an interval back (so the lag reported is the cell's own, not the cell's plus the
//! holding). The first 5·τ_max of the record are not fitted (the cell's state before it is
//! unknown).
//! A, J and T₀/Q₀ are linear (least squares); p and τ are found by golden section (p outside,
//! τ inside); their standard errors come from the curvature of the residual sum of squares
//! (σ_θ² = 2σ²/∂²RSS/∂θ²). The torque cell carries J·dω/dt (the rotor accelerating), the
//! thrust cell nothing of the kind.

use propid_core::estimate::NormalEquations;

use super::law::golden_min;

/// Longest load-cell lag a dynamic fit considers [s].
pub const MAX_LAG: f64 = 0.5;

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

/// The median interval between rows [s].
pub(crate) fn median_interval(t: &[f64]) -> f64 {
    let mut dts: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    if dts.is_empty() {
        return f64::NAN;
    }
    dts.sort_by(f64::total_cmp);
    dts[dts.len() / 2]
}

/// The variance a first-order lag τ leaves of white noise sampled every `h` seconds: the
/// energy of the first-order-hold filter's impulse response (1 at τ = 0).
pub(crate) fn smoothing_gain(h: f64, tau: f64) -> f64 {
    if tau <= 0.0 || h.is_nan() || h <= 0.0 {
        return 1.0;
    }
    let alpha = (-h / tau).exp();
    let beta = 1.0 - tau * (1.0 - alpha) / h;
    let h1 = alpha * beta + (1.0 - alpha - beta);
    beta * beta + h1 * h1 / (1.0 - alpha * alpha)
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

/// dω/dt as the slope of a local straight line through the 2·`half` + 1 rows around each row
/// (zero phase: no lag; it attenuates only what changes within the window), and the standard
/// deviation of its noise for a speed noise σ_ω at the median row interval h:
/// σ_ω·√(12/(m(m² − 1)))/h with m points. NaN where the window is incomplete.
pub fn derivative(t: &[f64], speed: &[f64], half: usize) -> (Vec<f64>, f64) {
    let n = t.len();
    let mut out = vec![f64::NAN; n];
    for (k, slot) in out
        .iter_mut()
        .enumerate()
        .take(n.saturating_sub(half))
        .skip(half)
    {
        let (ts, ws) = (&t[k - half..=k + half], &speed[k - half..=k + half]);
        let m = ts.len() as f64;
        let (mt, mw) = (ts.iter().sum::<f64>() / m, ws.iter().sum::<f64>() / m);
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for (tj, wj) in ts.iter().zip(ws) {
            sxy += (tj - mt) * (wj - mw);
            sxx += (tj - mt) * (tj - mt);
        }
        *slot = if sxx > 0.0 { sxy / sxx } else { f64::NAN };
    }
    let m = (2 * half + 1) as f64;
    let noise =
        super::plateau::noise_of(speed) * (12.0 / (m * (m * m - 1.0))).sqrt() / median_interval(t);
    (out, noise)
}

/// Fits a cell's law through its lag. `acceleration` (dω/dt and the standard deviation of its
/// noise) is given for a torque cell (J·dω/dt).
/// `None` when fewer than 50 updates remain.
pub fn fit(
    t: &[f64],
    speed: &[f64],
    acceleration: Option<(&[f64], f64)>,
    cell: &[f64],
    omega_ref: f64,
    fixed_exponent: Option<f64>,
) -> Option<DynamicFit> {
    let top = speed
        .iter()
        .map(|w| w.abs())
        .filter(|w| w.is_finite())
        .fold(0.0, f64::max);
    let t0 = t.first().copied().unwrap_or(0.0);
    let rows: Vec<usize> = updates(cell)
        .into_iter()
        // The cell's state before the record is unknown: its first 5·τ_max are not fitted.
        .filter(|&k| t[k] > t0 + 5.0 * MAX_LAG)
        .filter(|&k| speed[k].is_finite() && speed[k].abs() > 0.05 * top)
        .filter(|&k| acceleration.is_none_or(|(a, _)| a[k].is_finite()))
        .collect();
    if rows.len() < 50 {
        return None;
    }
    // A cell that holds its reading (values repeated in consecutive rows) took each new one at an
    // unknown instant during the row interval before it appears: on average half an interval
    // earlier. Its model is then read half a row back (the mean of the row and the one before).
    let finite = cell.iter().filter(|v| v.is_finite()).count();
    let held = (rows.len() as f64) < 0.9 * finite as f64;
    let at = |y: &[f64], k: usize| {
        if held && k > 0 && y[k - 1].is_finite() {
            0.5 * (y[k - 1] + y[k])
        } else {
            y[k]
        }
    };
    let lagged_accel = |tau: f64| acceleration.map(|(a, _)| lag(t, a, tau));
    let log_speed: Vec<f64> = speed.iter().map(|w| (w.abs() / omega_ref).ln()).collect();
    let regressor = |p: f64| -> Vec<f64> { log_speed.iter().map(|l| (p * l).exp()).collect() };
    // Least squares at a given regressor and lag: (lagged regressor, θ = [A, J, offset], their
    // standard errors, RSS, RMS).
    let solve = |u: &[f64], tau: f64| -> Option<Solved> {
        let ul = lag(t, u, tau);
        match lagged_accel(tau) {
            Some(al) => {
                let mut eq = NormalEquations::<f64, 3>::new();
                for &k in &rows {
                    eq.update(&[at(&ul, k), at(&al, k), 1.0], cell[k]);
                }
                let s = eq.solve().ok()?;
                let rss = eq.residual_sum_of_squares(&s.theta);
                Some((ul, s.theta, s.stderr, rss, s.rms))
            }
            None => {
                let mut eq = NormalEquations::<f64, 2>::new();
                for &k in &rows {
                    eq.update(&[at(&ul, k), 1.0], cell[k]);
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
    // A lag smooths the noise of the regressors (the speed's in (ω/ω_r)^p, the acceleration's in
    // J·dω/dt), which lowers the residual without being any truer: that part of the residual is
    // put back before lags are compared (as the diagnosis does for a force sensor's lag).
    let speed_noise = super::plateau::noise_of(speed);
    let interval = median_interval(t);
    let accel_noise = acceleration.map_or(0.0, |(_, noise)| noise);
    let put_back = |p: f64, u: &[f64], theta: &[f64; 3], tau: f64| {
        let lost = 1.0 - smoothing_gain(interval, tau);
        // σ_u = |du/dω|·σ_ω = p·u·σ_ω/|ω|.
        let drag: f64 = rows
            .iter()
            .map(|&k| (theta[0] * p * u[k] * speed_noise / speed[k].abs()).powi(2))
            .sum();
        let inertia = rows.len() as f64 * (theta[1] * accel_noise).powi(2);
        lost * (drag + inertia)
    };
    let rss_of = |p: f64, u: &[f64], tau: f64| {
        solve(u, tau).map_or(f64::INFINITY, |s| s.3 + put_back(p, u, &s.1, tau))
    };
    // The best lag for a regressor (0 when no lag fits better: golden section never reaches the
    // end of its interval).
    let best_tau = |p: f64, u: &[f64]| {
        let tau = golden_min(0.0, MAX_LAG, |tau| rss_of(p, u, tau), 26);
        if rss_of(p, u, 0.0) <= rss_of(p, u, tau) {
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
                rss_of(p, &u, best_tau(p, &u))
            },
            22,
        )
    });
    let u = regressor(p);
    let tau = best_tau(p, &u);
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
        curvature_stderr(&|q| rss_of(q, &regressor(q), tau), p, 0.01)
    };
    // At τ = 0 the curvature is taken one step inside the admissible range.
    let h_tau = (0.05 * tau).max(2e-4);
    let lag_stderr = curvature_stderr(&|x| rss_of(p, &u, x), tau.max(h_tau), h_tau);
    let al = lagged_accel(tau);
    let fitted_rows = rows
        .iter()
        .map(|&k| {
            let inertia_term = al.as_ref().map_or(0.0, |a| theta[1] * at(a, k));
            (k, cell[k] - theta[2] - inertia_term, at(&ul, k))
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
        // ω = 800 + 300 sin(πt); thrust 1e-5·ω^2.1 + 0.05 through a 30 ms lag, sampled by the
        // cell at 83.3 Hz on its own clock (between rows) and held; rows every 2 ms.
        let fine = 0.0002;
        let tf: Vec<f64> = (0..200_000).map(|k| k as f64 * fine).collect();
        let omega = |t: f64| 800.0 + 300.0 * (std::f64::consts::PI * t).sin();
        let truth: Vec<f64> = tf
            .iter()
            .map(|t| 1e-5 * omega(*t).powf(2.1) + 0.05)
            .collect();
        let lagged = lag(&tf, &truth, 0.03);
        let (mut t, mut w, mut held) = (Vec::new(), Vec::new(), Vec::new());
        let mut value = lagged[0];
        for (j, tj) in tf.iter().enumerate() {
            if j % 60 == 37 {
                value = lagged[j] + 1e-3 * (((j * 7919) % 101) as f64 / 101.0 - 0.5);
            }
            if j % 10 == 0 {
                t.push(*tj);
                w.push(omega(*tj));
                held.push(value);
            }
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
        // The zero, to 0.1 % of the thrust at the reference speed.
        assert!((f.offset - 0.05).abs() < 1e-3 * a, "{}", f.offset);
    }
}
