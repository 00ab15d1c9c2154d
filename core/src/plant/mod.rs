//! The mechanical load: a rotor with a propeller, as the simulator and the firmware demo see it.
//!
//! ```text
//!  J·dω/dt = τ − c1·ω − c2·|ω|^p·sgn ω − C·sgn ω + A·sin(k·θ + φ)        dθ/dt = ω
//! ```
//! τ is the torque the motor applies; c1 viscous friction, c2 the drag coefficient with exponent
//! p (2 for an ideal propeller, whose torque coefficient does not depend on speed), C Coulomb
//! friction, and A·sin(kθ + φ) a torque ripple periodic in rotor angle. [`Load::step`]
//! integrates it with the classical fourth-order Runge–Kutta method, the torque held over the
//! step. Generic over f32 (the firmware's FPU) and f64.

use num_traits::Float;

/// Parameters of the load. [`LoadParams::propeller`] gives the seed's model (p = 2, no Coulomb
/// friction, no ripple).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadParams<T> {
    /// Inertia J [kg·m²].
    pub inertia: T,
    /// Viscous friction c1 [N·m·s/rad].
    pub c1: T,
    /// Drag coefficient c2 [N·m·(s/rad)^p].
    pub c2: T,
    /// Drag exponent p (2 for speed-independent torque coefficient).
    pub drag_exponent: T,
    /// Coulomb friction C [N·m].
    pub coulomb: T,
    /// Torque ripple amplitude A [N·m].
    pub ripple_amplitude: T,
    /// Ripple periods per revolution k.
    pub ripple_harmonic: T,
    /// Ripple phase φ [rad].
    pub ripple_phase: T,
}

impl<T: Float> LoadParams<T> {
    /// The seed's model: inertia and quadratic drag only.
    pub fn propeller(inertia: T, c2: T) -> Self {
        LoadParams {
            inertia,
            c1: T::zero(),
            c2,
            drag_exponent: T::one() + T::one(),
            coulomb: T::zero(),
            ripple_amplitude: T::zero(),
            ripple_harmonic: T::one(),
            ripple_phase: T::zero(),
        }
    }

    /// The resisting and disturbing torque at speed ω and angle θ (everything but τ).
    pub fn load_torque(&self, omega: T, theta: T) -> T {
        let s = signum(omega);
        let drag = if self.drag_exponent == T::one() + T::one() {
            self.c2 * omega * omega.abs()
        } else {
            self.c2 * omega.abs().powf(self.drag_exponent) * s
        };
        let ripple = if self.ripple_amplitude == T::zero() {
            T::zero()
        } else {
            self.ripple_amplitude * (self.ripple_harmonic * theta + self.ripple_phase).sin()
        };
        -(self.c1 * omega) - drag - self.coulomb * s + ripple
    }

    /// dω/dt for applied torque τ at speed ω and angle θ.
    pub fn acceleration(&self, torque: T, omega: T, theta: T) -> T {
        (torque + self.load_torque(omega, theta)) / self.inertia
    }
}

/// sgn with sgn(0) = 0 (a rotor at rest feels no Coulomb torque from this model).
fn signum<T: Float>(x: T) -> T {
    if x > T::zero() {
        T::one()
    } else if x < T::zero() {
        -T::one()
    } else {
        T::zero()
    }
}

/// The load's state and parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Load<T> {
    /// Parameters.
    pub params: LoadParams<T>,
    /// Angular velocity ω [rad/s].
    pub velocity: T,
    /// Rotor angle θ [rad], unwrapped.
    pub position: T,
}

impl<T: Float> Load<T> {
    /// A load spinning at `velocity`.
    pub fn new(params: LoadParams<T>, velocity: T) -> Self {
        Load {
            params,
            velocity,
            position: T::zero(),
        }
    }

    /// dω/dt now, for applied torque τ.
    pub fn acceleration(&self, torque: T) -> T {
        self.params
            .acceleration(torque, self.velocity, self.position)
    }

    /// Advances by `dt` with torque τ (RK4).
    pub fn step(&mut self, dt: T, torque: T) {
        let p = &self.params;
        let half = dt / (T::one() + T::one());
        let six = T::from(6.0).unwrap_or(T::one());
        let two = T::one() + T::one();
        let (w0, x0) = (self.velocity, self.position);
        let k1w = p.acceleration(torque, w0, x0);
        let k1x = w0;
        let k2w = p.acceleration(torque, w0 + half * k1w, x0 + half * k1x);
        let k2x = w0 + half * k1w;
        let k3w = p.acceleration(torque, w0 + half * k2w, x0 + half * k2x);
        let k3x = w0 + half * k2w;
        let k4w = p.acceleration(torque, w0 + dt * k3w, x0 + dt * k3x);
        let k4x = w0 + dt * k3w;
        self.velocity = w0 + dt / six * (k1w + two * k2w + two * k3w + k4w);
        self.position = x0 + dt / six * (k1x + two * k2x + two * k3x + k4x);
    }
}

/// A first-order lag y' = (u − y)/τ, discretised exactly for a piecewise-constant input: the
/// model of a current loop, a filtered measurement or an estimator's smoothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstOrderLag<T> {
    /// Time constant τ [s] (0 passes the input through).
    pub time_constant: T,
    /// Output.
    pub value: T,
}

impl<T: Float> FirstOrderLag<T> {
    /// A lag starting at `value`.
    pub fn new(time_constant: T, value: T) -> Self {
        FirstOrderLag {
            time_constant,
            value,
        }
    }

    /// Advances by `dt` with input `u`; returns the output.
    pub fn step(&mut self, dt: T, u: T) -> T {
        if self.time_constant <= T::zero() {
            self.value = u;
        } else {
            let k = T::one() - (-dt / self.time_constant).exp();
            self.value = self.value + k * (u - self.value);
        }
        self.value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spins_up_to_the_drag_limited_speed() {
        // Steady state: τ = c2·ω² → ω = √(τ/c2).
        let mut load = Load::new(LoadParams::propeller(2e-5f64, 1.5e-8), 0.0);
        for _ in 0..50_000 {
            load.step(1e-4, 0.06);
        }
        let want = (0.06f64 / 1.5e-8).sqrt();
        assert!(
            (load.velocity / want - 1.0).abs() < 1e-6,
            "{}",
            load.velocity
        );
        assert!(
            load.acceleration(0.06).abs() < 0.1,
            "at rest: {}",
            load.acceleration(0.06)
        );
        // The same in f32 (the firmware's arithmetic).
        let mut l32 = Load::new(LoadParams::propeller(2e-5f32, 1.5e-8), 0.0);
        for _ in 0..50_000 {
            l32.step(1e-4, 0.06);
        }
        // Near steady state the f32 increments fall below the rounding step of ω (~1e-4 rad/s).
        assert!(
            (l32.velocity as f64 / want - 1.0).abs() < 1e-3,
            "{}",
            l32.velocity
        );
    }

    #[test]
    fn rk4_matches_the_closed_form_of_a_linear_load() {
        // J ω' = τ − c1 ω: ω(t) = τ/c1 (1 − e^{−c1 t / J}).
        let mut p = LoadParams::propeller(1e-3f64, 0.0);
        p.c1 = 1e-3;
        let mut load = Load::new(p, 0.0);
        for _ in 0..1000 {
            load.step(1e-3, 0.5);
        }
        let want = 0.5 / 1e-3 * (1.0 - (-1.0f64).exp());
        assert!((load.velocity - want).abs() < 1e-9, "{}", load.velocity);
    }

    #[test]
    fn friction_exponent_and_ripple() {
        let mut p = LoadParams::propeller(1.0f64, 1.0);
        p.drag_exponent = 1.5;
        p.coulomb = 0.25;
        p.ripple_amplitude = 0.5;
        p.ripple_harmonic = 3.0;
        let q = p.load_torque(4.0, core::f64::consts::FRAC_PI_6);
        assert!((q - (-8.0 - 0.25 + 0.5)).abs() < 1e-12, "{q}");
        assert!((p.load_torque(-4.0, 0.0) - (8.0 + 0.25)).abs() < 1e-12);
        let mut lag = FirstOrderLag::new(0.1f64, 0.0);
        let y = lag.step(0.1, 1.0);
        assert!((y - (1.0 - (-1.0f64).exp())).abs() < 1e-12);
    }
}
