//! The simulation: a continuous state integrated by RK4 over each control period, with the drive's
//! discrete decisions (setpoint, angle sample, brake) held over the period.
//!
//! State vector (SI units, true time):
//!
//! | index | state | when it moves |
//! |---|---|---|
//! | `I`, `Z` | phase current, PI integrator | a current loop is simulated |
//! | `W`, `TH` | rotor speed ω, angle θ (unwrapped) | always |
//! | `ICS` | filtered measured current | current-sense filter |
//! | `THH`, `WH` | observer angle θ̂, velocity ω̂ | PLL |
//! | `AH` | filtered acceleration estimate | acceleration filter |
//! | `LCX`, `LCV` | load-cell reading and its rate | load cell |
//! | `ED`, `EL`, `EX` | work done by the drive, lost in drag and bearing, done by the disturbance | always |
//! | `TCX`, `TCV` | thrust-cell reading and its rate | thrust cell |
//! | `IBF` | the ESC's filtered bus current | DC bus |

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Exp, Normal};

use crate::config::{ConfigError, Disturbance, MechConfig, Run, TorqueReport, VelocityEstimator};
use crate::record::{Energy, Record, Truth};

const I: usize = 0;
const Z: usize = 1;
const W: usize = 2;
const TH: usize = 3;
const ICS: usize = 4;
const THH: usize = 5;
const WH: usize = 6;
const AH: usize = 7;
const LCX: usize = 8;
const LCV: usize = 9;
const ED: usize = 10;
const EL: usize = 11;
const EX: usize = 12;
const TCX: usize = 13;
const TCV: usize = 14;
const IBF: usize = 15;
const N: usize = 16;

type State = [f64; N];

/// The drive's decisions, held over one control period.
#[derive(Clone, Copy, Debug)]
struct Hold {
    /// Current reference [A].
    i_ref: f64,
    /// Sampled (quantised) rotor angle [rad].
    theta_meas: f64,
    /// Braking torque magnitude in effect [N·m].
    brake: f64,
}

/// Torques and the acceleration at one instant.
#[derive(Clone, Copy, Debug)]
struct Forces {
    current: f64,
    motor: f64,
    cogging: f64,
    brake: f64,
    bearing: f64,
    drag: f64,
    disturbance: f64,
    /// Torque between rotor and stator: what a load cell under the stator carries.
    rotor_stator: f64,
    acceleration: f64,
}

/// Parameters derived once from the configuration.
#[derive(Clone, Copy, Debug)]
struct Derived {
    h: f64,
    kt_nominal: f64,
    /// Current-loop gains (0 when the loop is ideal).
    kp: f64,
    ki: f64,
    loop_on: bool,
    /// Width of the linear zone of the regularised sign function [rad/s].
    omega_eps: f64,
    /// Observer gains.
    pll: Option<(f64, f64)>,
    /// Load cell ω_n² and 2ζω_n.
    cell: Option<(f64, f64)>,
    /// Thrust cell ω_n² and 2ζω_n.
    thrust_cell: Option<(f64, f64)>,
}

/// The DC side at one instant.
#[derive(Clone, Copy, Debug)]
struct BusState {
    /// Motor (q-axis) voltage [V].
    motor_voltage: f64,
    /// Bus voltage [V].
    voltage: f64,
    /// Bus current [A].
    current: f64,
    /// Duty.
    duty: f64,
}

/// A mechanism-level stand that runs one recording from rest ([`MechStand::run`] consumes it).
pub struct MechStand {
    c: MechConfig,
    d: Derived,
    x: State,
    hold: Hold,
    /// The observer's velocity estimate one control period ago (for its acceleration output).
    previous_velocity_estimate: f64,
    /// Whole turns taken out of the angle states θ and θ̂ (they are kept in [0, 2π)).
    turns: f64,
    rng: StdRng,
    /// The instruments' own noise and clock phase (no draw from `rng` changes when they are on).
    instrument_rng: StdRng,
}

fn normal(sigma: f64) -> Normal<f64> {
    // σ is validated ≥ 0 and finite, for which Normal::new cannot fail.
    Normal::new(0.0, sigma).unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("σ = 0 is valid"))
}

impl MechStand {
    /// A stand at rest. Checks the configuration.
    pub fn new(config: MechConfig, seed: u64) -> Result<Self, ConfigError> {
        config.validate()?;
        let c = config;
        let h = 1.0 / c.drive.control_rate;
        let kt_nominal = c.motor.kt / (1.0 + c.drive.kt_error);
        let (kp, ki, loop_on) = match c.drive.current_loop {
            Some(cl) => (
                c.motor.inductance * cl.bandwidth,
                c.motor.resistance * cl.bandwidth,
                true,
            ),
            None => (0.0, 0.0, false),
        };
        let b = &c.rotor.bearing;
        let brake = c.drive.braking.map_or(0.0, |b| b.torque);
        // The sign of ω is regularised as clamp(ω/ω_ε, −1, 1): in that zone the friction torques
        // act as a viscous term of slope F/ω_ε, a pole at −F/(J·ω_ε). ω_ε is chosen so that this
        // pole times the step stays ≤ 0.5 (RK4 accurate and stable), and it is tiny (0.05 rad/s for
        // 5 mN·m on 2·10⁻⁵ kg·m² at 10 kHz) against the speeds a stand runs at.
        let sticky = b.coulomb.max(b.breakaway) + brake;
        let omega_eps = (2.0 * sticky * h / c.rotor.inertia).max(1e-9);
        let pll = match c.sensing.kinematics.velocity {
            VelocityEstimator::Ideal => None,
            VelocityEstimator::Pll {
                natural_hz,
                damping,
            } => {
                let wn = std::f64::consts::TAU * natural_hz;
                Some((2.0 * damping * wn, wn * wn))
            }
        };
        let cell = match c.sensing.torque {
            TorqueReport::LoadCell {
                natural_hz,
                damping,
                ..
            } => {
                let wn = std::f64::consts::TAU * natural_hz;
                Some((wn * wn, 2.0 * damping * wn))
            }
            _ => None,
        };
        let thrust_cell = c.instruments.thrust_cell.map(|tc| {
            let wn = std::f64::consts::TAU * tc.natural_hz;
            (wn * wn, 2.0 * tc.damping * wn)
        });
        Ok(MechStand {
            c,
            d: Derived {
                h,
                kt_nominal,
                kp,
                ki,
                loop_on,
                omega_eps,
                pll,
                cell,
                thrust_cell,
            },
            x: [0.0; N],
            hold: Hold {
                i_ref: 0.0,
                theta_meas: 0.0,
                brake: 0.0,
            },
            previous_velocity_estimate: 0.0,
            turns: 0.0,
            rng: StdRng::seed_from_u64(seed),
            instrument_rng: StdRng::seed_from_u64(seed ^ 0x696e_7374_7275_6d00),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &MechConfig {
        &self.c
    }

    fn sgn(&self, w: f64) -> f64 {
        (w / self.d.omega_eps).clamp(-1.0, 1.0)
    }

    /// The current the rotor sees: the loop's state, or an ideal loop's reference limited
    /// quasi-statically by the supply voltage.
    fn current(&self, x: &State, hold: &Hold) -> f64 {
        if self.d.loop_on {
            x[I]
        } else {
            let m = &self.c.motor;
            if m.supply_voltage.is_finite() {
                let emf = m.kt * x[W];
                hold.i_ref.clamp(
                    (-m.supply_voltage - emf) / m.resistance,
                    (m.supply_voltage - emf) / m.resistance,
                )
            } else {
                hold.i_ref
            }
        }
    }

    /// The propeller's thrust at speed ω [N].
    fn thrust(&self, w: f64) -> f64 {
        let t = &self.c.instruments.thrust;
        if t.k == 0.0 {
            return 0.0;
        }
        let aw = w.abs();
        let mut x = t.k * aw.powf(t.exponent);
        if t.ct_slope != 0.0 {
            x *= 1.0 + t.ct_slope * (aw / t.ct_reference_speed - 1.0);
        }
        x
    }

    /// The motor (q-axis) voltage: the PI loop's output, or for an ideal loop R·i + K_t·ω.
    fn motor_voltage(&self, x: &State, hold: &Hold) -> f64 {
        let m = &self.c.motor;
        if self.d.loop_on {
            let e = hold.i_ref - x[I];
            (self.d.kp * e + x[Z] + self.d.kt_nominal * x[W])
                .clamp(-m.supply_voltage, m.supply_voltage)
        } else {
            m.resistance * self.current(x, hold) + m.kt * x[W]
        }
    }

    /// The DC side: V_bus from the source and its resistance for the power v·i drawn
    /// (V_bus² − V_s·V_bus + R_s·v·i = 0), I_bus = v·i/V_bus, d = v/V_bus.
    fn bus(&self, x: &State, hold: &Hold) -> Option<BusState> {
        let b = self.c.instruments.bus?;
        let v = self.motor_voltage(x, hold);
        let p = v * self.current(x, hold);
        let disc = (b.source_voltage * b.source_voltage - 4.0 * b.source_resistance * p).max(0.0);
        let vb = 0.5 * (b.source_voltage + disc.sqrt());
        Some(BusState {
            motor_voltage: v,
            voltage: vb,
            current: p / vb,
            duty: v / vb,
        })
    }

    /// Torques at state `x` with the disturbance torque `disturbance`.
    fn forces(&self, disturbance: f64, x: &State, hold: &Hold) -> Forces {
        let r = &self.c.rotor;
        let w = x[W];
        let s = self.sgn(w);
        let current = self.current(x, hold);
        let motor = self.c.motor.kt * current;
        let cogging = if r.cogging.amplitude != 0.0 {
            // θ is kept within a turn (see `run`) and n is an integer, so the argument stays small
            // (sin of a large argument takes glibc's slow path).
            r.cogging.amplitude * (r.cogging.harmonic * x[TH] + r.cogging.phase).sin()
        } else {
            0.0
        };
        let brake = -hold.brake * s;
        let b = &r.bearing;
        let mut bearing = b.viscous * w;
        if b.coulomb != 0.0 || b.breakaway != 0.0 {
            let v = w / b.stribeck_speed;
            // exp(−50) < 2·10⁻²²: beyond that the term is below f64 resolution of F_c, and exp's
            // underflow path is slow.
            let stribeck = if b.breakaway > 0.0 && v * v < 50.0 {
                (b.breakaway - b.coulomb) * (-v * v).exp()
            } else {
                0.0
            };
            bearing += (b.coulomb + stribeck) * s;
        }
        let dr = &r.drag;
        let aw = w.abs();
        let mut drag = if dr.exponent == 2.0 {
            dr.k * w * aw
        } else {
            dr.k * aw.powf(dr.exponent) * w.signum()
        };
        if dr.cq_slope != 0.0 {
            drag *= 1.0 + dr.cq_slope * (aw / dr.cq_reference_speed - 1.0);
        }
        Forces {
            current,
            motor,
            cogging,
            brake,
            bearing,
            drag,
            disturbance,
            rotor_stator: motor + cogging + brake - bearing,
            acceleration: (motor + cogging + brake - bearing - drag + disturbance) / r.inertia,
        }
    }

    /// The external disturbance at pattern time `t`.
    fn disturbance(&self, t: f64) -> f64 {
        match self.c.disturbance {
            Disturbance::None => 0.0,
            Disturbance::Periodic { amplitude, hz } => {
                amplitude * (std::f64::consts::TAU * hz * t).sin()
            }
            Disturbance::Bump {
                amplitude,
                start,
                width,
            } => {
                if t > start && t < start + width {
                    amplitude * 0.5 * (1.0 - (std::f64::consts::TAU * (t - start) / width).cos())
                } else {
                    0.0
                }
            }
        }
    }

    /// dx/dt, the disturbance torque given.
    fn deriv(&self, disturbance: f64, x: &State, hold: &Hold) -> State {
        let f = self.forces(disturbance, x, hold);
        let mut dx = [0.0; N];
        let w = x[W];
        if self.d.loop_on {
            let m = &self.c.motor;
            let e = hold.i_ref - x[I];
            let v_raw = self.d.kp * e + x[Z] + self.d.kt_nominal * w;
            let v = v_raw.clamp(-m.supply_voltage, m.supply_voltage);
            let winding_up =
                (v_raw > m.supply_voltage && e > 0.0) || (v_raw < -m.supply_voltage && e < 0.0);
            dx[Z] = if winding_up { 0.0 } else { self.d.ki * e };
            dx[I] = (v - m.resistance * x[I] - m.kt * w) / m.inductance;
        }
        dx[W] = f.acceleration;
        dx[TH] = w;
        if let TorqueReport::Current { filter, .. } = self.c.sensing.torque {
            if filter > 0.0 {
                dx[ICS] = (f.current - x[ICS]) / filter;
            }
        }
        let velocity_rate = match self.d.pll {
            None => f.acceleration,
            Some((k1, k2)) => {
                let e = hold.theta_meas - x[THH];
                dx[THH] = x[WH] + k1 * e;
                dx[WH] = k2 * e;
                k2 * e
            }
        };
        let tau_a = self.c.sensing.kinematics.acceleration_filter;
        if tau_a > 0.0 {
            dx[AH] = (velocity_rate - x[AH]) / tau_a;
        }
        if let Some((wn2, two_zeta_wn)) = self.d.cell {
            dx[LCX] = x[LCV];
            dx[LCV] = wn2 * (f.rotor_stator - x[LCX]) - two_zeta_wn * x[LCV];
        }
        if let Some((wn2, two_zeta_wn)) = self.d.thrust_cell {
            dx[TCX] = x[TCV];
            dx[TCV] = wn2 * (self.thrust(w) - x[TCX]) - two_zeta_wn * x[TCV];
        }
        if let Some(b) = self.c.instruments.bus {
            if b.current_filter > 0.0 {
                if let Some(bus) = self.bus(x, hold) {
                    dx[IBF] = (bus.current - x[IBF]) / b.current_filter;
                }
            }
        }
        dx[ED] = (f.motor + f.cogging + f.brake) * w;
        dx[EL] = (f.drag + f.bearing) * w;
        dx[EX] = f.disturbance * w;
        dx
    }

    fn rk4(&mut self, t: f64) {
        let h = self.d.h;
        let hold = self.hold;
        let x = self.x;
        let add = |a: &State, k: &State, s: f64| {
            let mut o = *a;
            for (o, k) in o.iter_mut().zip(k) {
                *o += s * k;
            }
            o
        };
        let (d0, d1, d2) = (
            self.disturbance(t),
            self.disturbance(t + h / 2.0),
            self.disturbance(t + h),
        );
        let k1 = self.deriv(d0, &x, &hold);
        let k2 = self.deriv(d1, &add(&x, &k1, h / 2.0), &hold);
        let k3 = self.deriv(d1, &add(&x, &k2, h / 2.0), &hold);
        let k4 = self.deriv(d2, &add(&x, &k3, h), &hold);
        for i in 0..N {
            self.x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }

    /// The drive's velocity and acceleration estimates (true time units) at the tick.
    fn estimates(&self, f: &Forces) -> (f64, f64) {
        let x = &self.x;
        let (velocity, rate) = match self.d.pll {
            None => (x[W], f.acceleration),
            // Not k2·e at the tick: right after a new angle sample e jumps by the angle travelled
            // in a period (ω·h), which would add a term ∝ ω. The observer's mean rate over the
            // last period is what a discrete observer reports (h/2 later than ω̂).
            Some(_) => (x[WH], (x[WH] - self.previous_velocity_estimate) / self.d.h),
        };
        let acceleration = if self.c.sensing.kinematics.acceleration_filter > 0.0 {
            x[AH]
        } else {
            rate
        };
        (velocity, acceleration)
    }

    fn quantise(&self, theta: f64) -> f64 {
        match self.c.sensing.kinematics.counts_per_rev {
            // Floor, like a counter: a constant offset of half a count on average, no lag.
            Some(n) => {
                let q = std::f64::consts::TAU / n as f64;
                (theta / q).floor() * q
            }
            None => theta,
        }
    }

    /// Runs `run` from rest with the setpoint `pattern(t)` (t in seconds since the pattern began;
    /// values are clamped to [−1, 1], NaN reads as 0) and hands each feedback message that reaches
    /// the host to `sink`, in order. Returns the number of messages delivered.
    ///
    /// Cost: about 0.1 µs of CPU per control period and state (13 states, RK4); see the crate
    /// documentation for the measured figure.
    pub fn run(
        mut self,
        run: &Run,
        pattern: impl Fn(f64) -> f64,
        mut sink: impl FnMut(&Record),
    ) -> Result<u64, ConfigError> {
        run.validate()?;
        let c = self.c;
        let h = self.d.h;
        let link = c.link;
        let clock = link.clock;
        let init_ticks = (run.init_duration / h).round() as u64;
        let total_ticks = init_ticks + (run.duration / h).floor() as u64;
        let stamp = normal(clock.stamp_jitter);
        let latency = (link.latency_jitter > 0.0)
            .then(|| Exp::new(1.0 / link.latency_jitter).ok())
            .flatten();
        let noise_f = normal(c.sensing.noise.force);
        let noise_v = normal(c.sensing.noise.velocity);
        let noise_a = normal(c.sensing.noise.acceleration);
        let (cell_noise, cell_offset, cell_period) = match c.sensing.torque {
            TorqueReport::LoadCell {
                noise,
                offset,
                rate,
                ..
            } => (normal(noise), offset, 1.0 / rate),
            _ => (normal(0.0), 0.0, f64::INFINITY),
        };
        let (cs_noise, cs_offset) = match c.sensing.torque {
            TorqueReport::Current { noise, offset, .. } => (normal(noise), offset),
            _ => (normal(0.0), 0.0),
        };
        // The cell's ADC runs on its own clock: a random phase against the drive's ticks.
        let mut cell_next = if cell_period.is_finite() {
            self.rng.random::<f64>() * cell_period
        } else {
            f64::INFINITY
        };
        let mut cell_held = cell_offset;
        let ins = c.instruments;
        let (thrust_noise, thrust_offset, thrust_period) = match ins.thrust_cell {
            Some(tc) => (normal(tc.noise), tc.offset, 1.0 / tc.rate),
            None => (normal(0.0), 0.0, f64::INFINITY),
        };
        let mut thrust_next = if thrust_period.is_finite() {
            self.instrument_rng.random::<f64>() * thrust_period
        } else {
            f64::INFINITY
        };
        let mut thrust_held: Option<f64> = None;
        let (bus_noise_v, bus_noise_i) = match ins.bus {
            Some(b) => (normal(b.noise_voltage), normal(b.noise_current)),
            None => (normal(0.0), normal(0.0)),
        };
        let mut braking = false;
        let mut next_message: u64 = 0;
        let mut delivered = 0u64;
        let device_time =
            |tp: f64| clock.offset + (1.0 + clock.rate_error) * tp + 0.5 * clock.drift * tp * tp;

        for tick in 0..=total_ticks {
            let t_sim = tick as f64 * h;
            let tp = (tick as f64 - init_ticks as f64) * h;
            // The drive's decisions for this period.
            let setpoint = if tick < init_ticks {
                run.init_setpoint
            } else {
                let s = pattern(tp);
                if s.is_nan() {
                    0.0
                } else {
                    s.clamp(-1.0, 1.0)
                }
            };
            let torque_command = setpoint * c.drive.max_torque;
            self.hold.i_ref = torque_command / self.d.kt_nominal;
            // Whole turns out of θ and θ̂ together: the observer's error and the cogging phase are
            // unchanged, and the counter's count changes by a whole number of turns.
            let k = (self.x[TH] / std::f64::consts::TAU).floor();
            if k != 0.0 {
                self.x[TH] -= k * std::f64::consts::TAU;
                self.x[THH] -= k * std::f64::consts::TAU;
                self.turns += k;
            }
            self.hold.theta_meas = self.quantise(self.x[TH]);
            if let Some(b) = c.drive.braking {
                let f = self.forces(self.disturbance(tp), &self.x, &self.hold);
                let (_, a_est) = self.estimates(&f);
                braking = if braking {
                    a_est <= -b.off_threshold
                } else {
                    a_est < -b.on_threshold
                };
                self.hold.brake = if braking { b.torque } else { 0.0 };
            }
            while t_sim + 1e-12 >= thrust_next {
                thrust_held = Some(
                    self.x[TCX] + thrust_offset + thrust_noise.sample(&mut self.instrument_rng),
                );
                thrust_next += thrust_period;
            }
            while t_sim + 1e-12 >= cell_next {
                // The report's force noise is the cell's too: drawn with its reading and held
                // with it (a Tyto log repeats the exact value until the next reading).
                cell_held = self.x[LCX]
                    + cell_offset
                    + cell_noise.sample(&mut self.rng)
                    + noise_f.sample(&mut self.rng);
                cell_next += cell_period;
            }

            if tick >= init_ticks {
                let tau = device_time(tp);
                let due = clock.offset + next_message as f64 / link.rate;
                if tau + 1e-12 >= due {
                    next_message = ((tau - clock.offset) * link.rate + 1e-9).floor() as u64 + 1;
                    let dropped = link.drop_probability > 0.0
                        && self.rng.random::<f64>() < link.drop_probability;
                    if !dropped {
                        let f = self.forces(self.disturbance(tp), &self.x, &self.hold);
                        let (v_est, a_est) = self.estimates(&f);
                        let bus = self.bus(&self.x, &self.hold);
                        let force = match c.sensing.torque {
                            TorqueReport::Setpoint => torque_command,
                            TorqueReport::Current { filter, .. } => {
                                let i = if filter > 0.0 { self.x[ICS] } else { f.current };
                                self.d.kt_nominal * (i + cs_offset + cs_noise.sample(&mut self.rng))
                            }
                            TorqueReport::LoadCell { .. } => cell_held,
                        };
                        // The drive measures time with its own clock: rates in device units.
                        let g = 1.0 + clock.rate_error + clock.drift * tp;
                        let position = match self.d.pll {
                            Some(_) => self.x[THH],
                            None => self.hold.theta_meas,
                        };
                        let rng = &mut self.rng;
                        let record = Record {
                            ts_local: link.host_offset
                                + tp
                                + link.latency
                                + latency.map_or(0.0, |e| e.sample(rng)),
                            t: tau + stamp.sample(rng),
                            force: if cell_period.is_finite() {
                                force
                            } else {
                                force + noise_f.sample(rng)
                            },
                            velocity: v_est / g + noise_v.sample(rng),
                            acceleration: a_est / (g * g) + noise_a.sample(rng),
                            position: position.rem_euclid(std::f64::consts::TAU),
                            setpoint,
                            thrust: thrust_held,
                            voltage: bus
                                .map(|b| b.voltage + bus_noise_v.sample(&mut self.instrument_rng)),
                            current: bus.map(|b| {
                                let filtered = match ins.bus {
                                    Some(cfg) if cfg.current_filter > 0.0 => self.x[IBF],
                                    _ => b.current,
                                };
                                filtered + bus_noise_i.sample(&mut self.instrument_rng)
                            }),
                            duty: bus.map(|b| b.duty),
                            truth: Truth {
                                time: tp,
                                torque_command,
                                current: f.current,
                                motor_torque: f.motor,
                                cogging_torque: f.cogging,
                                brake_torque: f.brake,
                                bearing_torque: f.bearing,
                                drag_torque: f.drag,
                                disturbance: f.disturbance,
                                rotor_stator_torque: f.rotor_stator,
                                velocity: self.x[W],
                                acceleration: f.acceleration,
                                position: self.x[TH] + std::f64::consts::TAU * self.turns,
                                thrust: self.thrust(self.x[W]),
                                motor_voltage: bus.map(|b| b.motor_voltage),
                                bus_voltage: bus.map(|b| b.voltage),
                                bus_current: bus.map(|b| b.current),
                                energy: Energy {
                                    drive: self.x[ED],
                                    loss: self.x[EL],
                                    external: self.x[EX],
                                },
                            },
                        };
                        sink(&record);
                        delivered += 1;
                    }
                }
            }
            if tick < total_ticks {
                self.previous_velocity_estimate = self.x[WH];
                self.rk4(tp);
            }
        }
        Ok(delivered)
    }
}

/// Simulates `run` on a stand built from `config` with noise seed `seed` and returns every
/// delivered feedback message.
pub fn simulate(
    config: MechConfig,
    run: &Run,
    pattern: impl Fn(f64) -> f64,
    seed: u64,
) -> Result<Vec<Record>, ConfigError> {
    let stand = MechStand::new(config, seed)?;
    let mut out = Vec::with_capacity((run.duration * config.link.rate) as usize + 2);
    stand.run(run, pattern, |r| out.push(*r))?;
    Ok(out)
}
