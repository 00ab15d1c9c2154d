//! What the host receives, with the ground truth beside it, and the TSV propid reads.

use std::io::Write;

/// Work done on the rotor since the start of the simulation (init phase included) [J].
///
/// Energy balance: `½·J·ω² = drive − loss + external` (from rest), checked by a test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Energy {
    /// By the motor: electromagnetic, cogging and braking torque.
    pub drive: f64,
    /// Dissipated in drag and bearing friction.
    pub loss: f64,
    /// By the external disturbance.
    pub external: f64,
}

/// The true state at the instant the message was built (true time, SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truth {
    /// True time since the pattern began [s].
    pub time: f64,
    /// Torque command: setpoint × max torque [N·m].
    pub torque_command: f64,
    /// Phase (q-axis) current [A].
    pub current: f64,
    /// Electromagnetic torque Kt·i [N·m].
    pub motor_torque: f64,
    /// Cogging torque [N·m].
    pub cogging_torque: f64,
    /// Braking torque not shown by the current (negative opposes positive rotation) [N·m].
    pub brake_torque: f64,
    /// Bearing friction torque (opposes rotation when positive with ω > 0) [N·m].
    pub bearing_torque: f64,
    /// Aerodynamic drag torque (opposes rotation when positive with ω > 0) [N·m].
    pub drag_torque: f64,
    /// External disturbance torque [N·m].
    pub disturbance: f64,
    /// Torque between rotor and stator (what a load cell carries) [N·m].
    pub rotor_stator_torque: f64,
    /// Rotor speed [rad/s].
    pub velocity: f64,
    /// Rotor acceleration [rad/s²].
    pub acceleration: f64,
    /// Rotor angle, unwrapped [rad].
    pub position: f64,
    /// Thrust [N].
    pub thrust: f64,
    /// Motor (q-axis) voltage [V] (without a DC bus: `None`).
    pub motor_voltage: Option<f64>,
    /// Bus voltage [V].
    pub bus_voltage: Option<f64>,
    /// Bus current before the ESC's filter [A].
    pub bus_current: Option<f64>,
    /// Work done so far.
    pub energy: Energy,
}

/// One feedback message as the host logs it, plus the truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Host receive time [s].
    pub ts_local: f64,
    /// Device timestamp [s] (device clock).
    pub t: f64,
    /// Reported torque [N·m].
    pub force: f64,
    /// Reported angular velocity [rad/s of device time].
    pub velocity: f64,
    /// Reported angular acceleration [rad/s² of device time].
    pub acceleration: f64,
    /// Reported rotor angle in [0, 2π) [rad].
    pub position: f64,
    /// The ratiometric setpoint in effect when the message was built.
    pub setpoint: f64,
    /// The thrust cell's held reading [N] (`None` without a cell, and before its first reading).
    pub thrust: Option<f64>,
    /// Reported bus voltage [V] (`None` without a DC bus).
    pub voltage: Option<f64>,
    /// Reported bus current, through the ESC's filter [A].
    pub current: Option<f64>,
    /// The ESC's duty v/V_bus.
    pub duty: Option<f64>,
    /// Ground truth.
    pub truth: Truth,
}

/// The column names propid writes (`ts_local t force velocity acceleration position`), in order.
pub const TSV_HEADER: [&str; 6] = [
    "ts_local",
    "t",
    "force",
    "velocity",
    "acceleration",
    "position",
];

fn push_number(line: &mut String, v: f64) {
    use std::fmt::Write as _;
    if v.is_nan() {
        line.push_str("nan");
    } else {
        // Writing to a String cannot fail.
        let _ = write!(line, "{v}");
    }
}

/// Streams records as propid's TSV: the header line, then one row per record, numbers formatted
/// as Rust's `{}` (shortest round-trip), NaN as `nan` — the same bytes propid's own writer makes.
/// With `with_setpoint`, a `setpoint` column follows `position` (propid's reader finds columns by
/// name and ignores the ones it does not know).
pub struct TsvSink<W: Write> {
    out: W,
    with_setpoint: bool,
    with_stand: bool,
    line: String,
}

/// The stand columns propid reads beside the drive's (`thrust voltage current command`; the
/// duty is written as `command`).
pub const STAND_HEADER: [&str; 4] = ["thrust", "voltage", "current", "command"];

impl<W: Write> TsvSink<W> {
    /// Writes the header.
    pub fn new(out: W, with_setpoint: bool) -> std::io::Result<Self> {
        Self::with_stand(out, with_setpoint, false)
    }

    /// Writes the header, with the stand columns ([`STAND_HEADER`]) after the others when
    /// `with_stand`.
    pub fn with_stand(mut out: W, with_setpoint: bool, with_stand: bool) -> std::io::Result<Self> {
        let mut line = TSV_HEADER.join("\t");
        if with_setpoint {
            line.push_str("\tsetpoint");
        }
        if with_stand {
            for c in STAND_HEADER {
                line.push('\t');
                line.push_str(c);
            }
        }
        line.push('\n');
        out.write_all(line.as_bytes())?;
        Ok(TsvSink {
            out,
            with_setpoint,
            with_stand,
            line,
        })
    }

    /// Writes one row.
    pub fn write(&mut self, r: &Record) -> std::io::Result<()> {
        self.line.clear();
        let fields = [
            r.ts_local,
            r.t,
            r.force,
            r.velocity,
            r.acceleration,
            r.position,
        ];
        let optional = [
            (self.with_setpoint, &[r.setpoint][..]),
            (
                self.with_stand,
                &[r.thrust, r.voltage, r.current, r.duty].map(|v| v.unwrap_or(f64::NAN))[..],
            ),
        ];
        let extra = optional
            .iter()
            .filter(|(on, _)| *on)
            .flat_map(|(_, v)| v.iter());
        for (i, v) in fields.iter().chain(extra).enumerate() {
            if i > 0 {
                self.line.push('\t');
            }
            push_number(&mut self.line, *v);
        }
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }

    /// Flushes and returns the writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Writes `records` through a [`TsvSink`].
pub fn write_tsv<W: Write>(out: W, records: &[Record], with_setpoint: bool) -> std::io::Result<()> {
    let mut sink = TsvSink::new(out, with_setpoint)?;
    for r in records {
        sink.write(r)?;
    }
    sink.finish().map(|_| ())
}
