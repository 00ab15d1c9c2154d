//! The registers of propid's two nodes, named and typed as their real counterparts name them.
//!
//! ```text
//!  drive_defaults() ── the seed's registers with its defaults (what a register file starts from)
//!  drive::drive_registers(cfg), sim_drive::sim_drive_registers(cfg) ── a machine's values
//!  serve(node, registers) ── List/Access, ExecuteCommand, port.List every 10 s
//!  check_prerequisites(what a drive holds) ── what would spoil the seed's data, and the fix
//! ```
//!
//! - `propid drive` has the seed's PyCyphal registers: `setpoint_rat_lo_hi` (`real64[2]`, as
//!   PyCyphal's `setdefault(…, [0.1, 0.9])` makes it), `period`, `pattern_duration`,
//!   `init_duration`, `setpoint_period` (`real64[1]`), and the limits `max_speed`,
//!   `soft_start_setpoint`, `soft_start_duration`, `ramp_duration`, `speed_watchdog` (`real64[1]`,
//!   0 = off, rad/s and s), `uavcan.node.id` (`natural16[1]`, 65535
//!   unset), `uavcan.node.description`, and for each port `uavcan.{pub,sub}.NAME.id`
//!   (`natural16[1]`, 65535 unset) and the read-only `uavcan.{pub,sub}.NAME.type`.
//! - `propid sim-drive` has Telega's (telega.zubax.com, "Cyphal interface"):
//!   `mns.pub_interval_min` (`real32[1]`, s), `mns.local_timestamp` (`bit[1]`),
//!   `mns.deadman_timeout` (`real32[1]`, s, read-only here), `uavcan.pub.dynamics.id`,
//!   `uavcan.sub.readiness.id`, `uavcan.sub.setpoint_r_torq.id` and their types.
//!
//! Reading and writing register files, and the environment, is the host's business
//! (`propid_drive_host::register_file`).

use propid_core::can::{IdError, SubjectId};
use propid_core::dsdl::Value;
use propid_core::time::Instant;

use crate::excitation::Schedule;
use crate::limits::{Limits, SoftStart};
use crate::node::{HostNode, HostRegistry};
use crate::settings::SetpointPeriod;

/// "Unset" for node-IDs and port-IDs.
pub const UNSET: u16 = 65535;

/// The data type of the readiness port, as its `.type` register reports it.
pub const READINESS_TYPE: &str = "zubax.service.Readiness.1.0";
/// The setpoint's type.
pub const SETPOINT_TYPE: &str = "zubax.primitive.real16.Vector31.1.0";
/// The feedback's type.
pub const FEEDBACK_TYPE: &str = "zubax.physics.dynamics.DoF3rdTs.1.0";

/// The seed's feedback interval requirement: at least 100 Hz.
pub const MAX_FEEDBACK_INTERVAL: f64 = 0.01;
/// What `propid telega --fix` writes into `mns.pub_interval_min` (the seed's value).
pub const SEED_FEEDBACK_INTERVAL: &str = "0.005";

/// This node's ID (`natural16[1]`, 65535: unset).
pub const NODE_ID: &str = "uavcan.node.id";
/// This node's description (`string`).
pub const NODE_DESCRIPTION: &str = "uavcan.node.description";
/// The seed's setpoint range (`real64[2]`).
pub const SETPOINT_RAT_LO_HI: &str = "setpoint_rat_lo_hi";
/// The seed's pattern period (`real64[1]`, s).
pub const PERIOD: &str = "period";
/// The seed's pattern duration (`real64[1]`, s).
pub const PATTERN_DURATION: &str = "pattern_duration";
/// The seed's init phase (`real64[1]`, s).
pub const INIT_DURATION: &str = "init_duration";
/// The seed's setpoint publication period (`real64[1]`, s).
pub const SETPOINT_PERIOD: &str = "setpoint_period";

/// The highest speed allowed (`real64[1]`, rad/s; 0: none).
pub const MAX_SPEED: &str = "max_speed";
/// The soft start's setpoint magnitude (`real64[1]`, ratiometric, in the direction of hi).
pub const SOFT_START_SETPOINT: &str = "soft_start_setpoint";
/// How long the soft start lasts (`real64[1]`, s; 0: no soft start).
pub const SOFT_START_DURATION: &str = "soft_start_duration";
/// How long the ramp to hi after the soft start lasts (`real64[1]`, s; 0: no ramp).
pub const RAMP_DURATION: &str = "ramp_duration";
/// The speed watchdog's margin (`real64[1]`, rad/s; 0: off).
pub const SPEED_WATCHDOG: &str = "speed_watchdog";

/// The drive's setpoint register (`uavcan.pub.sp_rat.id`), as the seed names its port.
pub const DRIVE_SETPOINT_ID: &str = "uavcan.pub.sp_rat.id";
/// The drive's feedback register.
pub const DRIVE_FEEDBACK_ID: &str = "uavcan.sub.fb_dyn.id";
/// The drive's readiness register.
pub const DRIVE_READINESS_ID: &str = "uavcan.pub.readiness.id";

/// Telega's feedback publication register.
pub const TELEGA_FEEDBACK_ID: &str = "uavcan.pub.dynamics.id";
/// Telega's ratiometric torque setpoint subscription register.
pub const TELEGA_SETPOINT_ID: &str = "uavcan.sub.setpoint_r_torq.id";
/// Telega's readiness subscription register.
pub const TELEGA_READINESS_ID: &str = "uavcan.sub.readiness.id";
/// Telega's minimum feedback publication interval, in seconds.
pub const PUB_INTERVAL_MIN: &str = "mns.pub_interval_min";
/// Telega's switch for timestamping feedback with its own clock.
pub const LOCAL_TIMESTAMP: &str = "mns.local_timestamp";

pub(crate) fn add(r: &mut HostRegistry, name: &str, value: Value, mutable: bool, persistent: bool) {
    // Cannot fail: the names are distinct, valid, and fewer than HOST_REGISTERS.
    let _ = r.add(name, value, mutable, persistent);
}

/// A `natural16[1]` value; `None` is [`UNSET`].
pub fn n16(v: Option<u16>) -> Value {
    Value::natural16(&[v.unwrap_or(UNSET)]).unwrap_or_default()
}

/// A `real64[N]` value.
pub fn real64(v: &[f64]) -> Value {
    Value::real64(v).unwrap_or_default()
}

/// A `string` value.
pub fn text(s: &str) -> Value {
    Value::string(s).unwrap_or_default()
}

pub(crate) fn port(
    r: &mut HostRegistry,
    kind: &str,
    name: &str,
    id: Option<u16>,
    ty: &str,
    persistent: bool,
) {
    add(
        r,
        &format!("uavcan.{kind}.{name}.id"),
        n16(id),
        true,
        persistent,
    );
    add(
        r,
        &format!("uavcan.{kind}.{name}.type"),
        text(ty),
        false,
        persistent,
    );
}

/// The drive's registers with the seed's defaults (node and port IDs unset). `persistent`: a
/// register file keeps them (as PyCyphal's registry reports for a file-backed node).
pub fn drive_defaults(persistent: bool) -> HostRegistry {
    let mut r = HostRegistry::new();
    let p = persistent;
    let seed = Schedule::SEED;
    let (lo, hi) = (seed.range.lo(), seed.range.hi());
    add(&mut r, NODE_ID, n16(None), true, p);
    add(&mut r, NODE_DESCRIPTION, text(""), true, p);
    add(&mut r, SETPOINT_RAT_LO_HI, real64(&[lo, hi]), true, p);
    add(&mut r, PERIOD, real64(&[seed.period.get()]), true, p);
    add(
        &mut r,
        PATTERN_DURATION,
        real64(&[seed.duration.get()]),
        true,
        p,
    );
    add(
        &mut r,
        INIT_DURATION,
        real64(&[seed.init_duration.get()]),
        true,
        p,
    );
    let period = SetpointPeriod::SEED.get();
    add(&mut r, SETPOINT_PERIOD, real64(&[period]), true, p);
    for (name, value) in limit_values(&Limits::DEFAULT) {
        add(&mut r, name, real64(&[value]), true, p);
    }
    port(&mut r, "pub", "readiness", None, READINESS_TYPE, p);
    port(&mut r, "pub", "sp_rat", None, SETPOINT_TYPE, p);
    port(&mut r, "sub", "fb_dyn", None, FEEDBACK_TYPE, p);
    r
}

/// The limit registers and their values for `limits` (0 for a limit that is off; the soft
/// start's setpoint is kept when it is off, as a register file would keep it).
pub fn limit_values(limits: &Limits) -> [(&'static str, f64); 5] {
    let soft = limits.soft_start;
    [
        (MAX_SPEED, limits.max_speed.map_or(0.0, |m| m.get())),
        (
            SOFT_START_SETPOINT,
            soft.unwrap_or(SoftStart::DEFAULT).setpoint.get(),
        ),
        (SOFT_START_DURATION, soft.map_or(0.0, |s| s.duration.get())),
        (RAMP_DURATION, limits.ramp.map_or(0.0, |r| r.get())),
        (SPEED_WATCHDOG, limits.watchdog.map_or(0.0, |w| w.get())),
    ]
}

/// The environment variable of a register: upper case, `.` → `__` (the specification's rule,
/// as PyCyphal maps them).
pub fn environment_name(register: &str) -> String {
    register.to_ascii_uppercase().replace('.', "__")
}

/// `true`/`false` as 1/0 (what people type for `bit` registers), else the text unchanged.
pub fn normalize_bool(text: &str) -> &str {
    match text.trim() {
        "true" | "True" | "TRUE" => "1",
        "false" | "False" | "FALSE" => "0",
        t => t,
    }
}

/// The type as `natural16[1]`, `real64[2]`, `string`, …
pub fn describe(v: &Value) -> String {
    if v.is_numeric() {
        format!("{}[{}]", v.type_name(), v.len())
    } else {
        v.type_name().to_string()
    }
}

/// A value as people write it: numbers space-separated (bits as true/false), text as is.
pub fn show(v: &Value) -> String {
    if v.is_numeric() {
        let single = matches!(v, Value::Real32(_) | Value::Real16(_));
        let bits = matches!(v, Value::Bit(_));
        let items: Vec<String> = (0..v.len())
            .filter_map(|i| v.float_at(i))
            .map(|x| {
                if bits {
                    (x != 0.0).to_string()
                } else if single {
                    // The shortest text that reads back as the same float32.
                    format!("{}", x as f32)
                } else {
                    format!("{x}")
                }
            })
            .collect();
        items.join(" ")
    } else {
        v.as_str().unwrap_or("<binary>").to_string()
    }
}

/// A subject-ID register (65535 or absent: unset).
pub fn subject_register(r: &HostRegistry, name: &str) -> Result<Option<SubjectId>, IdError> {
    match r.get(name).and_then(|x| x.value.float_at(0)) {
        Some(v) if v >= f64::from(UNSET) => Ok(None),
        Some(v) => SubjectId::try_from(v as u64).map(Some),
        None => Ok(None),
    }
}

/// What the seed needs from a drive's registers, and what spoils the data otherwise.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// The register to change.
    pub register: String,
    /// Its value now ("missing" if the drive lacks it).
    pub found: String,
    /// The value to write (as text).
    pub wanted: String,
    /// Why.
    pub why: String,
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} is {}; set it to {} ({})",
            self.register, self.found, self.wanted, self.why
        )
    }
}

/// Checks a drive's registers (name → value) against the seed's prerequisites: feedback at
/// ≥ 100 Hz (`mns.pub_interval_min` ≤ 0.01 s) and local timestamps on (`mns.local_timestamp`).
/// `feedback_id`, when given, must be the drive's `uavcan.pub.dynamics.id`.
pub fn check_prerequisites(
    registers: &[(String, Value)],
    feedback_id: Option<SubjectId>,
) -> Vec<Problem> {
    let get = |n: &str| registers.iter().find(|(k, _)| k == n).map(|(_, v)| v);
    let mut problems = Vec::new();
    match get(PUB_INTERVAL_MIN).and_then(|v| v.float_at(0)) {
        Some(x) if x <= MAX_FEEDBACK_INTERVAL && x > 0.0 => {}
        found => problems.push(Problem {
            register: PUB_INTERVAL_MIN.into(),
            found: found.map_or("missing".into(), |x| format!("{}", x as f32)),
            wanted: SEED_FEEDBACK_INTERVAL.into(),
            why: "feedback must arrive at 100 Hz or more; the seed uses 0.005 s".into(),
        }),
    }
    match get(LOCAL_TIMESTAMP).and_then(|v| v.float_at(0)) {
        Some(x) if x != 0.0 => {}
        found => problems.push(Problem {
            register: LOCAL_TIMESTAMP.into(),
            found: found.map_or("missing".into(), |x| (x != 0.0).to_string()),
            wanted: "true".into(),
            why: "the feedback must carry the drive's own timestamps".into(),
        }),
    }
    if let Some(want) = feedback_id {
        let have = get(TELEGA_FEEDBACK_ID).and_then(|v| v.float_at(0));
        if have != Some(f64::from(want.get())) {
            problems.push(Problem {
                register: TELEGA_FEEDBACK_ID.into(),
                found: have.map_or("missing".into(), |x| format!("{x}")),
                wanted: want.to_string(),
                why: format!("propid listens for the feedback on subject {want}"),
            });
        }
    }
    problems
}

/// Hands `registers` to `node` to serve (List, Access), answers ExecuteCommand with the
/// `commands` the owner carries out (BAD_COMMAND for others) and publishes port.List from `now`.
pub fn serve(node: &mut HostNode, registers: &HostRegistry, commands: &[u16], now: Instant) {
    for r in registers.iter() {
        let name = r.name.as_str().unwrap_or_default();
        // Cannot fail: HostNode has as many register slots as HostRegistry, and port slots for
        // the services beside the machines' few subscriptions.
        let _ = node.add_register(name, r.value.clone(), r.mutable, r.persistent);
    }
    if !commands.is_empty() {
        let _ = node.serve_commands(commands);
    }
    node.enable_port_list(now);
}
