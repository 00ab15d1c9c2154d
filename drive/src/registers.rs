//! The registers of propid's two nodes, named and typed as their real counterparts name them.
//!
//! ```text
//!  defaults ─► register file (name: value lines) ─► environment (NAME__WITH__DOTS) ─► flags
//!     └──────────────── each step: propid_core::node::parse_value (PyCyphal's rules) ───────────┐
//!  drive_config(registers) ─► DriveConfig (validated)      drive_registers(cfg) ─► the Node serves them
//! ```
//!
//! - `propid drive` has the seed's PyCyphal registers: `setpoint_rat_lo_hi` (`real64[2]`, as
//!   PyCyphal's `setdefault(…, [0.1, 0.9])` makes it), `period`, `pattern_duration`,
//!   `init_duration`, `setpoint_period` (`real64`), `uavcan.node.id` (`natural16`, 65535 unset),
//!   `uavcan.node.description`, and for each port `uavcan.{pub,sub}.NAME.id` (`natural16`, 65535
//!   unset) and the immutable `uavcan.{pub,sub}.NAME.type`. All mutable; persistent when a
//!   register file is used (as PyCyphal's registry reports).
//! - `propid sim-drive` has Telega's (telega.zubax.com, "Cyphal interface"):
//!   `mns.pub_interval_min` (`real32`, s), `mns.local_timestamp` (`bit`), `mns.deadman_timeout`,
//!   `uavcan.pub.dynamics.id`, `uavcan.sub.readiness.id`, `uavcan.sub.setpoint_r_torq.id` and their
//!   types.
//!
//! A register file here is text, one `name: value` (or `name = value`) per line, `#` comments,
//! values written as environment variables are (space-separated numbers, or text). PyCyphal's own
//! register files are SQLite databases; they are not read.

use std::path::Path;

use propid_core::dsdl::Value;
use propid_core::node::{parse_value, Registry};
use propid_io::InputError;
use propid_science::excitation::{Excitation, Pattern};

use crate::drive::DriveConfig;
use crate::sim_drive::SimDriveConfig;

/// Register slots of the host nodes.
pub const HOST_REGISTERS: usize = 32;

/// The registers of a host node.
pub type HostRegistry = Registry<HOST_REGISTERS>;

/// "Unset" for node-IDs and port-IDs.
pub const UNSET: u16 = 65535;

/// The data types of the drive's ports, as the `.type` registers report them.
pub const READINESS_TYPE: &str = "zubax.service.Readiness.1.0";
/// Setpoint type.
pub const SETPOINT_TYPE: &str = "zubax.primitive.real16.Vector31.1.0";
/// Feedback type.
pub const FEEDBACK_TYPE: &str = "zubax.physics.dynamics.DoF3rdTs.1.0";

/// The seed's feedback interval requirement: at least 100 Hz.
pub const MAX_FEEDBACK_INTERVAL: f64 = 0.01;

fn add(r: &mut HostRegistry, name: &str, value: Value, mutable: bool, persistent: bool) {
    // Cannot fail: the names are distinct and fewer than HOST_REGISTERS.
    r.add(name, value, mutable, persistent)
        .unwrap_or_else(|e| panic!("register {name}: {e}"));
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

/// The drive's registers holding `cfg`'s values (what the node serves while it drives).
pub fn drive_registers(cfg: Option<&DriveConfig>, persistent: bool) -> HostRegistry {
    let mut r = HostRegistry::new();
    let ex = cfg.map(|c| c.excitation);
    let p = persistent;
    add(
        &mut r,
        "uavcan.node.id",
        n16(cfg.map(|c| u16::from(c.node_id))),
        true,
        p,
    );
    add(&mut r, "uavcan.node.description", text(""), true, p);
    let (lo, hi) = ex.map_or((0.1, 0.9), |e| (e.lo, e.hi));
    add(&mut r, "setpoint_rat_lo_hi", real64(&[lo, hi]), true, p);
    add(
        &mut r,
        "period",
        real64(&[ex.map_or(2.0, |e| e.period)]),
        true,
        p,
    );
    let duration = ex.map_or(200.0, |e| e.duration);
    add(&mut r, "pattern_duration", real64(&[duration]), true, p);
    let init = ex.map_or(5.0, |e| e.init_duration);
    add(&mut r, "init_duration", real64(&[init]), true, p);
    let sp = cfg.map_or(0.005, |c| c.setpoint_period);
    add(&mut r, "setpoint_period", real64(&[sp]), true, p);
    port(
        &mut r,
        "pub",
        "readiness",
        cfg.and_then(|c| c.readiness_id),
        READINESS_TYPE,
        p,
    );
    port(
        &mut r,
        "pub",
        "sp_rat",
        cfg.map(|c| c.setpoint_id),
        SETPOINT_TYPE,
        p,
    );
    port(
        &mut r,
        "sub",
        "fb_dyn",
        cfg.map(|c| c.feedback_id),
        FEEDBACK_TYPE,
        p,
    );
    r
}

/// The simulated Telega's registers for `cfg`, with local timestamps on or off.
pub fn sim_drive_registers(cfg: &SimDriveConfig, local_timestamp: bool) -> HostRegistry {
    let mut r = HostRegistry::new();
    add(
        &mut r,
        "uavcan.node.id",
        n16(Some(u16::from(cfg.node_id))),
        true,
        true,
    );
    add(&mut r, "uavcan.node.description", text(""), true, true);
    let interval = Value::real32(&[cfg.interval as f32]).unwrap_or_default();
    add(&mut r, "mns.pub_interval_min", interval, true, true);
    let ts = Value::bit(&[local_timestamp]).unwrap_or_default();
    add(&mut r, "mns.local_timestamp", ts, true, true);
    let deadman = Value::real32(&[0.5]).unwrap_or_default();
    add(&mut r, "mns.deadman_timeout", deadman, false, true);
    port(
        &mut r,
        "pub",
        "dynamics",
        Some(cfg.feedback_id),
        FEEDBACK_TYPE,
        true,
    );
    port(
        &mut r,
        "sub",
        "readiness",
        cfg.readiness_id,
        READINESS_TYPE,
        true,
    );
    port(
        &mut r,
        "sub",
        "setpoint_r_torq",
        Some(cfg.setpoint_id),
        SETPOINT_TYPE,
        true,
    );
    r
}

/// What the simulated Telega obeys, read from its registers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimSettings {
    /// Feedback interval [s] (`mns.pub_interval_min`).
    pub interval: f64,
    /// Feedback carries the drive's timestamp (`mns.local_timestamp`).
    pub local_timestamp: bool,
}

impl SimSettings {
    /// Reads the registers; an interval that is not a positive number (or under 0.1 ms) keeps
    /// `previous`.
    pub fn read(r: &HostRegistry, previous: f64) -> SimSettings {
        let interval = first(r, "mns.pub_interval_min")
            .filter(|x| x.is_finite() && *x >= 1e-4)
            .unwrap_or(previous);
        let local_timestamp = first(r, "mns.local_timestamp").is_none_or(|x| x != 0.0);
        SimSettings {
            interval,
            local_timestamp,
        }
    }
}

/// The environment variable of a register: upper case, `.` → `__` (the specification's rule).
pub fn environment_name(register: &str) -> String {
    register.to_ascii_uppercase().replace('.', "__")
}

/// Sets one register from text; the error names `origin` (a flag, a variable, `file:line`).
pub fn set_text(
    r: &mut HostRegistry,
    name: &str,
    text: &str,
    origin: &str,
) -> Result<(), InputError> {
    let current = r
        .get(name)
        .ok_or_else(|| InputError(format!("{origin}: no register named {name}")))?;
    let value = parse_value(&current.value, text).ok_or_else(|| {
        InputError(format!(
            "{origin}: `{text}` is not a valid {} for register {name}",
            describe(&current.value)
        ))
    })?;
    r.set(name, &value)
        .map_err(|e| InputError(format!("{origin}: {name}: {e}")))
}

/// "natural16[1]", "real64[2]", "string", ….
pub fn describe(v: &Value) -> String {
    if v.is_numeric() {
        format!("{}[{}]", v.type_name(), v.len())
    } else {
        v.type_name().to_string()
    }
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
            .ok_or_else(|| InputError(format!("{origin}: expected `name: value`, got `{line}`")))?;
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

/// A register file's text holding the mutable registers' values.
pub fn render_file(r: &HostRegistry) -> String {
    let mut out = String::new();
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

fn port_id(r: &HostRegistry, name: &str) -> Result<Option<u16>, InputError> {
    match first(r, name) {
        Some(v) if v < f64::from(UNSET) && v > 8191.0 => Err(InputError(format!(
            "register {name} = {v}: a subject-ID is 0..=8191 (65535: unset)"
        ))),
        Some(v) if v <= 8191.0 => Ok(Some(v as u16)),
        _ => Ok(None),
    }
}

/// The drive's configuration from its registers, validated before anything is sent.
pub fn drive_config(
    r: &HostRegistry,
    mtu: usize,
    pattern: Pattern,
    deadman: f64,
    fit: bool,
) -> Result<DriveConfig, InputError> {
    let node_id =
        match first(r, "uavcan.node.id") {
            Some(v) if v <= 127.0 => v as u8,
            Some(v) if v >= f64::from(UNSET) => return Err(InputError(
                "uavcan.node.id is not set: give --node-id, UAVCAN__NODE__ID or a register file"
                    .into(),
            )),
            Some(v) => return Err(InputError(format!("uavcan.node.id = {v}: must be 0..=127"))),
            None => return Err(InputError("uavcan.node.id is missing".into())),
        };
    let need = |name: &str, flag: &str| -> Result<u16, InputError> {
        port_id(r, name)?.ok_or_else(|| {
            InputError(format!(
                "{name} is not set: give --{flag}, {} or a register file",
                environment_name(name)
            ))
        })
    };
    let setpoint_id = need("uavcan.pub.sp_rat.id", "setpoint-id")?;
    let feedback_id = need("uavcan.sub.fb_dyn.id", "feedback-id")?;
    let readiness_id = port_id(r, "uavcan.pub.readiness.id")?;
    let lohi = r.get("setpoint_rat_lo_hi").map(|x| &x.value);
    let (lo, hi) = match lohi.map(|v| (v.float_at(0), v.float_at(1))) {
        Some((Some(lo), Some(hi))) => (lo, hi),
        _ => {
            return Err(InputError(
                "setpoint_rat_lo_hi must hold two numbers".into(),
            ))
        }
    };
    let get = |name: &str| first(r, name).unwrap_or(f64::NAN);
    let cfg = DriveConfig {
        node_id,
        mtu,
        readiness_id,
        setpoint_id,
        feedback_id,
        excitation: Excitation {
            lo,
            hi,
            period: get("period"),
            duration: get("pattern_duration"),
            init_duration: get("init_duration"),
            pattern,
        },
        setpoint_period: get("setpoint_period"),
        deadman,
        fit,
    };
    cfg.validate()?;
    Ok(cfg)
}

/// What the seed needs from a drive's registers, and what spoils the data otherwise.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// The register to change.
    pub register: String,
    /// Its value now ("missing" if the drive lacks it).
    pub found: String,
    /// The value to write (as text, for `propid telega --set`).
    pub wanted: String,
    /// Why.
    pub why: String,
}

/// Checks a drive's registers (name → value) against the seed's prerequisites: feedback at
/// ≥ 100 Hz (`mns.pub_interval_min` ≤ 0.01 s) and local timestamps on (`mns.local_timestamp`).
/// `feedback_id`, when given, must be the drive's `uavcan.pub.dynamics.id`.
pub fn check_prerequisites(
    registers: &[(String, Value)],
    feedback_id: Option<u16>,
) -> Vec<Problem> {
    let get = |n: &str| registers.iter().find(|(k, _)| k == n).map(|(_, v)| v);
    let mut problems = Vec::new();
    match get("mns.pub_interval_min").and_then(|v| v.float_at(0)) {
        Some(x) if x <= MAX_FEEDBACK_INTERVAL && x > 0.0 => {}
        found => problems.push(Problem {
            register: "mns.pub_interval_min".into(),
            found: found.map_or("missing".into(), |x| format!("{x}")),
            wanted: "0.005".into(),
            why: "feedback must arrive at 100 Hz or more (the seed uses 0.005 s)".into(),
        }),
    }
    match get("mns.local_timestamp").and_then(|v| v.float_at(0)) {
        Some(x) if x != 0.0 => {}
        found => problems.push(Problem {
            register: "mns.local_timestamp".into(),
            found: found.map_or("missing".into(), |x| (x != 0.0).to_string()),
            wanted: "true".into(),
            why: "the feedback must carry the drive's own timestamps".into(),
        }),
    }
    if let Some(want) = feedback_id {
        let have = get("uavcan.pub.dynamics.id").and_then(|v| v.float_at(0));
        if have != Some(f64::from(want)) {
            problems.push(Problem {
                register: "uavcan.pub.dynamics.id".into(),
                found: have.map_or("missing".into(), |x| format!("{x}")),
                wanted: want.to_string(),
                why: format!("propid listens for the feedback on subject {want}"),
            });
        }
    }
    problems
}

/// Hands `registers` to `node` to serve (List, Access), answers ExecuteCommand with the
/// `commands` the owner carries out (BAD_COMMAND for others) and publishes port.List.
pub fn serve(
    node: &mut crate::HostNode,
    registers: &HostRegistry,
    commands: &[u16],
    now: propid_core::time::Instant,
) {
    for r in registers.iter() {
        let name = r.name.as_str().unwrap_or_default();
        // Cannot fail: HostNode has as many slots as HostRegistry and free port slots.
        let _ = node.add_register(name, r.value.clone(), r.mutable, r.persistent);
    }
    let _ = node.serve_commands(commands);
    node.enable_port_list(now);
}

/// `true`/`false` as 1/0 (what people type for `bit` registers), else the text unchanged.
pub fn normalize_bool(text: &str) -> &str {
    match text.trim() {
        "true" | "True" | "TRUE" => "1",
        "false" | "False" | "FALSE" => "0",
        t => t,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_then_environment_then_flags() {
        let mut r = drive_registers(None, false);
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
        let cfg = drive_config(&r, 8, Pattern::Sine, 0.5, false).unwrap();
        assert_eq!(
            (cfg.node_id, cfg.setpoint_id, cfg.feedback_id),
            (10, 24, 110)
        );
        assert_eq!(cfg.readiness_id, None);
        assert_eq!(cfg.excitation.period, 2.5);
        assert_eq!((cfg.excitation.lo, cfg.excitation.hi), (0.2, 0.8));
        // The served registers hold the same values.
        let served = drive_registers(Some(&cfg), false);
        assert_eq!(served.get("period").unwrap().value, real64(&[2.5]));
        assert_eq!(
            served.get("uavcan.pub.readiness.id").unwrap().value,
            n16(None)
        );
    }

    #[test]
    fn bad_values_are_refused_with_their_origin() {
        let mut r = drive_registers(None, false);
        let e = apply_file(&mut r, Path::new("x.reg"), "\n\nperiod: fast\n").unwrap_err();
        assert_eq!(
            e.0,
            "x.reg:3: `fast` is not a valid real64[1] for register period"
        );
        let e = apply_file(&mut r, Path::new("x.reg"), "no_such: 1").unwrap_err();
        assert_eq!(e.0, "x.reg:1: no register named no_such");
        let e = set_text(&mut r, "uavcan.node.id", "-1", "UAVCAN__NODE__ID").unwrap_err();
        assert!(e.0.contains("natural16[1]"), "{}", e.0);
        let e = drive_config(&r, 8, Pattern::Sine, 0.5, false).unwrap_err();
        assert!(e.0.starts_with("uavcan.node.id is not set"), "{}", e.0);
        set_text(&mut r, "uavcan.node.id", "10", "t").unwrap();
        set_text(&mut r, "uavcan.pub.sp_rat.id", "9000", "t").unwrap();
        let e = drive_config(&r, 8, Pattern::Sine, 0.5, false).unwrap_err();
        assert!(e.0.contains("0..=8191"), "{}", e.0);
        set_text(&mut r, "uavcan.pub.sp_rat.id", "24", "t").unwrap();
        set_text(&mut r, "uavcan.sub.fb_dyn.id", "110", "t").unwrap();
        set_text(&mut r, "setpoint_rat_lo_hi", "0.9 0.1", "t").unwrap();
        assert!(drive_config(&r, 8, Pattern::Sine, 0.5, false).is_err());
    }

    #[test]
    fn prerequisites() {
        let sim = SimDriveConfig::example(Default::default(), 1);
        let good: Vec<(String, Value)> = sim_drive_registers(&sim, true)
            .iter()
            .map(|x| (x.name.as_str().unwrap().to_string(), x.value.clone()))
            .collect();
        assert!(check_prerequisites(&good, Some(110)).is_empty());
        let mut slow = sim;
        slow.interval = 0.05;
        let bad: Vec<(String, Value)> = sim_drive_registers(&slow, false)
            .iter()
            .map(|x| (x.name.as_str().unwrap().to_string(), x.value.clone()))
            .collect();
        let p = check_prerequisites(&bad, Some(111));
        let names: Vec<&str> = p.iter().map(|p| p.register.as_str()).collect();
        assert_eq!(
            names,
            [
                "mns.pub_interval_min",
                "mns.local_timestamp",
                "uavcan.pub.dynamics.id"
            ]
        );
        assert_eq!(p[1].found, "false");
        assert!(
            render_file(&sim_drive_registers(&slow, false)).contains("mns.local_timestamp: 0\n")
        );
    }
}
