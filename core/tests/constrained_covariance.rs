//! The covariance of a fit that sits on a bound is that of the restricted problem: with the
//! seed's bound c1 ≤ 0 active, the standard errors of J and c2 must equal those of the model
//! without c1 — not those of the free three-parameter model, where c1 and c2 are nearly
//! collinear and the errors come out several times too large.

use propid_core::estimate::{LoadBounds, LoadEstimator, NormalEquations};

#[test]
fn an_active_bound_removes_its_direction_from_the_covariance() {
    // A propeller-like load: J = 2e-5, c2 = 1.5e-8, driven between two speeds, with noise.
    let (j, c2) = (2.0e-5f64, 1.5e-8f64);
    let mut est = LoadEstimator::<f64>::new();
    let mut two = NormalEquations::<f64, 2>::new();
    let mut state = 12345u64;
    let mut noise = || {
        // xorshift: fixed, dependency-free noise in [−1, 1).
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    };
    let mut w = 1000.0f64;
    for k in 0..20_000 {
        let t = k as f64 * 0.002;
        let f = 0.05 + 0.04 * (std::f64::consts::TAU * 0.5 * t).sin();
        let a = (f - c2 * w * w) / j;
        w += a * 0.002;
        let measured = a + 20.0 * noise();
        est.update(f, w, measured);
        two.update(&[f, -w * w.abs()], measured);
    }
    let bounded = est.estimate(&LoadBounds::default()).unwrap();
    assert!(bounded.at_bound[1], "c1 sits on its bound");
    assert_eq!(bounded.c1_stderr, 0.0, "no error across an active bound");
    let sol = two.solve().unwrap();
    let [t0, t2] = sol.theta;
    let jac_j = [-1.0 / (t0 * t0), 0.0];
    let jac_c2 = [-t2 / (t0 * t0), 1.0 / t0];
    let sd = |g: [f64; 2]| {
        let c = sol.covariance;
        (g[0] * g[0] * c[0][0] + 2.0 * g[0] * g[1] * c[0][1] + g[1] * g[1] * c[1][1]).sqrt()
    };
    let (sj, sc) = (sd(jac_j), sd(jac_c2));
    assert!(
        (bounded.mass_stderr / sj - 1.0).abs() < 1e-6,
        "J: {} vs {sj}",
        bounded.mass_stderr
    );
    assert!(
        (bounded.c2_stderr / sc - 1.0).abs() < 1e-6,
        "c2: {} vs {sc}",
        bounded.c2_stderr
    );
}
