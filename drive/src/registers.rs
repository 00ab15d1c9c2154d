//! The registers of propid's two nodes, named and typed as their real counterparts name them.
//!
//! ```text
//!  drive_defaults() ─► register file (name: value lines) ─► environment (NAME__WITH__DOTS) ─► flags
//!     └──────────── each step: propid_core::node::parse_value (PyCyphal's rules), origin named ──┐
//!  apply_drive_registers(registers, &mut DriveConfig) ─► DriveConfig::validate ─► Drive serves them
//! ```
//!
//! - `propid drive` has the seed's PyCyphal registers: `setpoint_rat_lo_hi` (`real64[2]`, as
//!   PyCyphal's `setdefault(…, [0.1, 0.9])` makes it), `period`, `pattern_duration`,
//!   `init_duration`, `setpoint_period` (`real64[1]`), `uavcan.node.id` (`natural16[1]`, 65535
//!   unset), `uavcan.node.description`, and for each port `uavcan.{pub,sub}.NAME.id`
//!   (`natural16[1]`, 65535 unset) and the read-only `uavcan.{pub,sub}.NAME.type`.
//! - `propid sim-drive` has Telega's (telega.zubax.com, "Cyphal interface"):
//!   `mns.pub_interval_min` (`real32[1]`, s), `mns.local_timestamp` (`bit[1]`),
//!   `mns.deadman_timeout` (`real32[1]`, s, read-only here), `uavcan.pub.dynamics.id`,
//!   `uavcan.sub.readiness.id`, `uavcan.sub.setpoint_r_torq.id` and their types.
//!
//! A register file here is text, one `name: value` (or `name = value`) per line, `#` comments,
//! values written as environment variables are (space-separated numbers, or text). PyCyphal's own
//! register files are SQLite databases; they are not read.

use std::path::Path;

use propid_core::can::{NodeId, SubjectId};
use propid_core::dsdl::Value;
use propid_core::node::{parse_value, Registry};
use propid_io::InputError;

use crate::drive::{ConfigError, DriveConfig};
use crate::sim_drive::SimDriveConfig;

/// Register slots of the host nodes.
pub const HOST_REGISTERS: usize = 32;

/// The registers of a host node.
pub type HostRegistry = Registry<HOST_REGISTERS>;

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

fn add(r: &mut HostRegistry, name: &str, value: Value, mutable: bool, persistent: bool) {
    // Cannot fail: the names are distinct, valid, and fewer than HOST_REGISTERS.
    let _ = r.add(name, value, mutable, persistent);
}

fn n16(v: Option<u16>) -> Value {
    Value::natural16(&[v.unwrap_or(UNSET)]).unwrap_or_default()
}

fn real64(v: &[f64]) -> Value {
    Value::real64(v).unwrap_or_default()
}

fn text(s: &str) -> Value {
    Value::string(s).unwrap_or_default()
}

fn port(r: &mut HostRegistry, kind: &str, name: &str, id: Option<u16>, ty: &str, persistent: bool) {
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
    add(&mut r, "uavcan.node.id", n16(None), true, p);
    add(&mut r, "uavcan.node.description", text(""), true, p);
    add(&mut r, "setpoint_rat_lo_hi", real64(&[0.1, 0.9]), true, p);
    add(&mut r, "period", real64(&[2.0]), true, p);
    add(&mut r, "pattern_duration", real64(&[200.0]), true, p);
    add(&mut r, "init_duration", real64(&[5.0]), true, p);
    add(&mut r, "setpoint_period", real64(&[0.005]), true, p);
    port(&mut r, "pub", "readiness", None, READINESS_TYPE, p);
    port(&mut r, "pub", "sp_rat", None, SETPOINT_TYPE, p);
    port(&mut r, "sub", "fb_dyn", None, FEEDBACK_TYPE, p);
    r
}

/// The drive's registers holding `cfg`'s values (what the node serves while it drives).
pub fn drive_registers(cfg: &DriveConfig, persistent: bool) -> HostRegistry {
    let mut r = drive_defaults(persistent);
    let ex = &cfg.excitation;
    let set = |r: &mut HostRegistry, name: &str, v: Value| {
        let _ = r.set(name, &v);
    };
    set(
        &mut r,
        "uavcan.node.id",
        n16(Some(u16::from(cfg.node_id.get()))),
    );
    set(&mut r, "setpoint_rat_lo_hi", real64(&[ex.lo, ex.hi]));
    set(&mut r, "period", real64(&[ex.period]));
    set(&mut r, "pattern_duration", real64(&[ex.duration]));
    set(&mut r, "init_duration", real64(&[ex.init_duration]));
    set(&mut r, "setpoint_period", real64(&[cfg.setpoint_period]));
    set(
        &mut r,
        DRIVE_READINESS_ID,
        n16(cfg.readiness_id.map(SubjectId::get)),
    );
    set(&mut r, DRIVE_SETPOINT_ID, n16(Some(cfg.setpoint_id.get())));
    set(&mut r, DRIVE_FEEDBACK_ID, n16(Some(cfg.feedback_id.get())));
    r
}

/// The simulated Telega's registers for `cfg`, with local timestamps on or off.
pub fn sim_drive_registers(cfg: &SimDriveConfig, local_timestamp: bool) -> HostRegistry {
    let mut r = HostRegistry::new();
    add(
        &mut r,
        "uavcan.node.id",
        n16(Some(u16::from(cfg.node_id.get()))),
        true,
        true,
    );
    add(&mut r, "uavcan.node.description", text(""), true, true);
    let interval = Value::real32(&[cfg.interval as f32]).unwrap_or_default();
    add(&mut r, PUB_INTERVAL_MIN, interval, true, true);
    let ts = Value::bit(&[local_timestamp]).unwrap_or_default();
    add(&mut r, LOCAL_TIMESTAMP, ts, true, true);
    let deadman = Value::real32(&[crate::sim_drive::SIM_DEADMAN.as_secs_f32()]).unwrap_or_default();
    add(&mut r, "mns.deadman_timeout", deadman, false, true);
    port(
        &mut r,
        "pub",
        "dynamics",
        Some(cfg.feedback_id.get()),
        FEEDBACK_TYPE,
        true,
    );
    port(
        &mut r,
        "sub",
        "readiness",
        cfg.readiness_id.map(SubjectId::get),
        READINESS_TYPE,
        true,
    );
    port(
        &mut r,
        "sub",
        "setpoint_r_torq",
        Some(cfg.setpoint_id.get()),
        SETPOINT_TYPE,
        true,
    );
    r
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

/// The value `text` gives register `current` (PyCyphal's rules; `true`/`false` for bits); the
/// error names `origin` (a flag, a variable, `file:line`) and the register.
pub fn parse_for(
    current: &Value,
    name: &str,
    text: &str,
    origin: &str,
) -> Result<Value, InputError> {
    parse_value(current, normalize_bool(text)).ok_or_else(|| {
        InputError::invalid(format!(
            "{origin}: `{text}` is not a valid {} for register {name}",
            describe(current)
        ))
    })
}

/// Sets one register from text; the error names `origin`.
pub fn set_text(
    r: &mut HostRegistry,
    name: &str,
    text: &str,
    origin: &str,
) -> Result<(), InputError> {
    let current = r
        .get(name)
        .ok_or_else(|| InputError::invalid(format!("{origin}: no register named {name}")))?;
    let value = parse_for(&current.value, name, text, origin)?;
    r.set(name, &value)
        .map_err(|e| InputError::invalid(format!("{origin}: {name}: {e}")))
}

/// Applies a register file's `name: value` lines.
pub fn apply_file(r: &mut HostRegistry, path: &Path, contents: &str) -> Result<(), InputError> {
    for (i, line) in contents.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let origin = format!("{}:{}", path.display(), i + 1);
        let (name, value) = line
            .split_once(':')
            .or_else(|| line.split_once('='))
            .ok_or_else(|| {
                InputError::invalid(format!("{origin}: expected `name: value`, got `{line}`"))
            })?;
        set_text(r, name.trim(), value.trim(), &origin)?;
    }
    Ok(())
}

/// Applies the environment variables that name registers (others are ignored).
pub fn apply_environment(
    r: &mut HostRegistry,
    vars: impl IntoIterator<Item = (String, String)>,
) -> Result<(), InputError> {
    let names: Vec<String> = r
        .iter()
        .filter(|x| x.mutable)
        .filter_map(|x| x.name.as_str().map(String::from))
        .collect();
    let vars: Vec<(String, String)> = vars.into_iter().collect();
    for name in names {
        let var = environment_name(&name);
        if let Some((_, value)) = vars.iter().find(|(k, _)| *k == var) {
            set_text(r, &name, value, &format!("environment variable {var}"))?;
        }
    }
    Ok(())
}

/// A register file's text holding the mutable registers' values (what `apply_file` reads).
pub fn render_file(r: &HostRegistry) -> String {
    let mut out = String::from("# propid registers: name: value (see docs/REGISTERS.md)\n");
    for reg in r.iter().filter(|x| x.mutable) {
        let value = match &reg.value {
            v if v.is_numeric() => (0..v.len())
                .filter_map(|i| v.float_at(i))
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(" "),
            v => v.as_str().unwrap_or("").to_string(),
        };
        out += &format!("{}: {value}\n", reg.name.as_str().unwrap_or("?"));
    }
    out
}

fn first(r: &HostRegistry, name: &str) -> Option<f64> {
    r.get(name).and_then(|x| x.value.float_at(0))
}

/// A subject-ID register (65535: unset).
pub fn subject_register(
    r: &HostRegistry,
    name: &'static str,
) -> Result<Option<SubjectId>, ConfigError> {
    match first(r, name) {
        Some(v) if v >= f64::from(UNSET) => Ok(None),
        Some(v) => SubjectId::try_from(v as u64)
            .map(Some)
            .map_err(|e| ConfigError::new(name, format!("{e} (65535: unset)"))),
        None => Ok(None),
    }
}

/// Fills `cfg` from the drive's registers (node-ID, port-IDs, the excitation, the setpoint
/// period) and validates it; the error names the register.
pub fn apply_drive_registers(r: &HostRegistry, cfg: &mut DriveConfig) -> Result<(), ConfigError> {
    let node_id = match first(r, "uavcan.node.id") {
        Some(v) if v >= f64::from(UNSET) => None,
        Some(v) => Some(
            NodeId::try_from(v as u64)
                .map_err(|e| ConfigError::new("uavcan.node.id", e.to_string()))?,
        ),
        None => None,
    };
    cfg.node_id = node_id.ok_or_else(|| ConfigError::new("uavcan.node.id", "is not set"))?;
    cfg.setpoint_id = subject_register(r, DRIVE_SETPOINT_ID)?
        .ok_or_else(|| ConfigError::new(DRIVE_SETPOINT_ID, "is not set"))?;
    cfg.feedback_id = subject_register(r, DRIVE_FEEDBACK_ID)?
        .ok_or_else(|| ConfigError::new(DRIVE_FEEDBACK_ID, "is not set"))?;
    cfg.readiness_id = subject_register(r, DRIVE_READINESS_ID)?;
    let lohi = r.get("setpoint_rat_lo_hi").map(|x| &x.value);
    let (Some(lo), Some(hi)) = (
        lohi.and_then(|v| v.float_at(0)),
        lohi.and_then(|v| v.float_at(1)),
    ) else {
        return Err(ConfigError::new(
            "setpoint_rat_lo_hi",
            "must hold two numbers",
        ));
    };
    let get = |name: &str| first(r, name).unwrap_or(f64::NAN);
    cfg.excitation.lo = lo;
    cfg.excitation.hi = hi;
    cfg.excitation.period = get("period");
    cfg.excitation.duration = get("pattern_duration");
    cfg.excitation.init_duration = get("init_duration");
    cfg.setpoint_period = get("setpoint_period");
    cfg.validate()
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
pub fn serve(
    node: &mut crate::HostNode,
    registers: &HostRegistry,
    commands: &[u16],
    now: propid_core::time::Instant,
) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use propid_science::excitation::Excitation;

    fn example() -> DriveConfig {
        DriveConfig::example(Excitation {
            lo: 0.1,
            hi: 0.9,
            period: 2.0,
            duration: 200.0,
            init_duration: 5.0,
            pattern: propid_science::excitation::Pattern::Sine,
        })
    }

    #[test]
    fn file_then_environment_then_flags() {
        let mut r = drive_defaults(false);
        let file =
            "# the seed's example\nuavcan.node.id: 10\nuavcan.pub.sp_rat.id = 24\nperiod: 3\n";
        apply_file(&mut r, Path::new("drive.reg"), file).unwrap();
        apply_environment(
            &mut r,
            [
                ("UAVCAN__SUB__FB_DYN__ID".to_string(), "110".to_string()),
                ("PERIOD".to_string(), "2.5".to_string()),
                ("HOME".to_string(), "/root".to_string()),
            ],
        )
        .unwrap();
        set_text(
            &mut r,
            "setpoint_rat_lo_hi",
            "0.2 0.8",
            "--setpoint-rat-lo-hi",
        )
        .unwrap();
        let mut cfg = example();
        apply_drive_registers(&r, &mut cfg).unwrap();
        assert_eq!(
            (
                cfg.node_id.get(),
                cfg.setpoint_id.get(),
                cfg.feedback_id.get()
            ),
            (10, 24, 110)
        );
        assert_eq!(cfg.readiness_id, None);
        assert_eq!(cfg.excitation.period, 2.5);
        assert_eq!((cfg.excitation.lo, cfg.excitation.hi), (0.2, 0.8));
        // The served registers hold the same values.
        let served = drive_registers(&cfg, false);
        assert_eq!(served.get("period").unwrap().value, real64(&[2.5]));
        assert_eq!(served.get(DRIVE_READINESS_ID).unwrap().value, n16(None));
    }

    #[test]
    fn bad_values_are_refused_with_their_origin() {
        let mut r = drive_defaults(false);
        let e = apply_file(&mut r, Path::new("x.reg"), "\n\nperiod: fast\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "x.reg:3: `fast` is not a valid real64[1] for register period"
        );
        let e = apply_file(&mut r, Path::new("x.reg"), "no_such: 1").unwrap_err();
        assert_eq!(e.to_string(), "x.reg:1: no register named no_such");
        let e = set_text(&mut r, "uavcan.node.id", "-1", "UAVCAN__NODE__ID").unwrap_err();
        assert!(e.to_string().contains("natural16[1]"), "{e}");
        let mut cfg = example();
        let e = apply_drive_registers(&r, &mut cfg).unwrap_err();
        assert_eq!(e.setting, "uavcan.node.id");
        set_text(&mut r, "uavcan.node.id", "10", "t").unwrap();
        set_text(&mut r, DRIVE_SETPOINT_ID, "9000", "t").unwrap();
        let e = apply_drive_registers(&r, &mut cfg).unwrap_err();
        assert!(e.problem.contains("0..=8191"), "{}", e.problem);
        set_text(&mut r, DRIVE_SETPOINT_ID, "24", "t").unwrap();
        set_text(&mut r, DRIVE_FEEDBACK_ID, "110", "t").unwrap();
        set_text(&mut r, "setpoint_rat_lo_hi", "0.9 0.1", "t").unwrap();
        assert!(apply_drive_registers(&r, &mut cfg).is_err());
    }

    #[test]
    fn prerequisites() {
        let sim = SimDriveConfig::example(Default::default(), 1);
        let as_list = |r: &HostRegistry| -> Vec<(String, Value)> {
            r.iter()
                .map(|x| (x.name.as_str().unwrap().to_string(), x.value.clone()))
                .collect()
        };
        let good = as_list(&sim_drive_registers(&sim, true));
        assert!(check_prerequisites(&good, Some(SubjectId::from_const(110))).is_empty());
        let mut slow = sim;
        slow.interval = 0.05;
        let bad = as_list(&sim_drive_registers(&slow, false));
        let p = check_prerequisites(&bad, Some(SubjectId::from_const(111)));
        let names: Vec<&str> = p.iter().map(|p| p.register.as_str()).collect();
        assert_eq!(
            names,
            [PUB_INTERVAL_MIN, LOCAL_TIMESTAMP, TELEGA_FEEDBACK_ID]
        );
        assert_eq!(p[0].found, "0.05");
        assert_eq!(p[1].found, "false");
        assert!(
            render_file(&sim_drive_registers(&slow, false)).contains("mns.local_timestamp: 0\n")
        );
    }
}
