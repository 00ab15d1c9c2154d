//! `propid telega`: find drives on the bus, read their registers, check the seed's prerequisites
//! (feedback at ≥ 100 Hz, local timestamps on), fix them when asked and store them when asked;
//! a thin command over [`propid_drive_host::telega::BlockingClient`].

use std::time::Duration;

use anyhow::bail;
use propid_core::can::{Mtu, NodeId, SubjectId};
use propid_core::dsdl::{ExecuteCommandRequest, ExecuteCommandResponse, Value};
use propid_drive_host::realtime::SystemClock;
use propid_drive_host::register_file::parse_text;
use propid_drive_host::telega::BlockingClient;
use propid_drive_proto::registers::{self, check_prerequisites, Problem};
use propid_drive_proto::settings::Range;
use propid_transport::CanTransport;

use crate::bus::{Bus, BusArgs};
use crate::settings::{
    command_args, environment, fill, seconds_in, setting, ConfigError, ConfigErrors, Names,
};
use crate::InputError;

setting! {
    /// How long to listen.
    Listen: f64 = Names::flag("listen"),
        "How long to listen for heartbeats [s] [default: 1.5]",
        |text: &str| seconds_in(text, Range { lo: 0.0, lo_open: true, hi: 60.0, hi_open: false, unit: "s" });
}

command_args! {
    /// Arguments of `propid telega`.
    pub struct Args {
        settings {
            listen: Listen as "S",
        }
        registers {}
        nested {
            bus: BusArgs,
        }
        /// This tool's own node-ID.
        #[arg(long, default_value = "126")]
        pub node_id: NodeId,
        /// The drive's node-ID (default: every node heard that has Telega's registers).
        #[arg(long)]
        pub drive: Option<NodeId>,
        /// The feedback subject propid will listen on (checked against uavcan.pub.dynamics.id).
        #[arg(long)]
        pub feedback_id: Option<SubjectId>,
        /// Write a register, NAME=VALUE (repeatable; `true`/`false` for bits).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        pub set: Vec<String>,
        /// Write the values the seed's prerequisites need (mns.pub_interval_min 0.005,
        /// mns.local_timestamp true, and uavcan.pub.dynamics.id when --feedback-id is given).
        #[arg(long)]
        pub fix: bool,
        /// Ask the drive to store its registers (ExecuteCommand STORE_PERSISTENT_STATES).
        #[arg(long)]
        pub store: bool,
        /// Print every register, not only the checked ones.
        #[arg(long)]
        pub all: bool,
    }
}

fn client_err(e: String) -> anyhow::Error {
    anyhow::Error::msg(e)
}

/// Writes `text` into register `name` of `drive`, converted to the register's current type;
/// returns the value the drive then holds.
fn write(
    client: &mut BlockingClient<'_>,
    drive: NodeId,
    name: &str,
    text: &str,
) -> anyhow::Result<Value> {
    let current = client
        .access(drive, name, Value::Empty)
        .map_err(client_err)?
        .filter(|r| !r.value.is_empty())
        .ok_or_else(|| InputError::invalid(format!("drive {drive} has no register {name}")))?;
    if !current.mutable {
        bail!("drive {drive}: {name} is read-only");
    }
    let value = parse_text(&current.value, text).ok_or_else(|| {
        InputError::invalid(format!(
            "--set: `{text}` is not a valid {} for register {name}",
            registers::describe(&current.value)
        ))
    })?;
    let after = client
        .access(drive, name, value.clone())
        .map_err(client_err)?
        .ok_or_else(|| anyhow::anyhow!("drive {drive} did not answer the write of {name}"))?;
    if after.value != value {
        bail!(
            "drive {drive} kept {name} = {} (wrote {})",
            registers::show(&after.value),
            registers::show(&value)
        );
    }
    Ok(after.value)
}

/// One line per problem: which register to change, to what, why, and the command that does it.
pub fn explain(drive: NodeId, problems: &[Problem]) -> String {
    problems
        .iter()
        .map(|p| {
            format!(
                "drive {drive}: {p}: propid telega --drive {drive} --set {}={} --store",
                p.register, p.wanted
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The port-IDs a drive's registers hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrivePorts {
    /// uavcan.pub.dynamics.id.
    pub feedback: Option<SubjectId>,
    /// uavcan.sub.setpoint_r_torq.id.
    pub setpoint: Option<SubjectId>,
    /// uavcan.sub.readiness.id.
    pub readiness: Option<SubjectId>,
}

fn subject(found: &[(String, Value)], name: &str) -> Option<SubjectId> {
    let v = found.iter().find(|(k, _)| k == name)?.1.float_at(0)?;
    SubjectId::try_from(v as u64).ok().filter(|_| v >= 0.0)
}

/// For `drive --from-telega`: reads `drive`'s port-IDs and checks its prerequisites; a drive
/// that does not answer or whose configuration would spoil the data is refused, naming the
/// registers to change.
pub fn drive_ports(
    transport: &mut dyn CanTransport,
    node_id: NodeId,
    mtu: Mtu,
    drive: NodeId,
) -> anyhow::Result<DrivePorts> {
    let mut client = BlockingClient::new(transport, &SystemClock, node_id, mtu);
    let mut names = registers_checked_and_ports();
    names.dedup();
    let found = client.read(drive, &names).map_err(client_err)?;
    if found.is_empty() {
        bail!("drive {drive} does not answer uavcan.register.Access (is it on the bus, with this node-ID?)");
    }
    let problems = check_prerequisites(&found, None);
    if !problems.is_empty() {
        bail!(
            "drive {drive} is not configured for identification; not engaging it:\n{}",
            explain(drive, &problems)
        );
    }
    Ok(DrivePorts {
        feedback: subject(&found, registers::TELEGA_FEEDBACK_ID),
        setpoint: subject(&found, registers::TELEGA_SETPOINT_ID),
        readiness: subject(&found, registers::TELEGA_READINESS_ID),
    })
}

fn registers_checked_and_ports() -> Vec<&'static str> {
    let mut v = propid_drive_proto::telega::CHECKED_REGISTERS.to_vec();
    v.extend([
        registers::TELEGA_SETPOINT_ID,
        registers::TELEGA_READINESS_ID,
    ]);
    v
}

fn flags(mutable: bool, persistent: bool) -> &'static str {
    match (mutable, persistent) {
        (true, true) => "mutable, persistent",
        (true, false) => "mutable",
        (false, true) => "read-only, persistent",
        (false, false) => "read-only",
    }
}

/// Runs `propid telega`.
pub fn run(mut args: Args) -> anyhow::Result<()> {
    let mut errors = ConfigErrors::default();
    fill(&mut args, &environment(), None, &[], &mut errors);
    let mut assignments = Vec::new();
    for a in &args.set {
        match a.split_once('=') {
            Some((n, v)) => assignments.push((n.trim().to_string(), v.trim().to_string())),
            None => errors.push(ConfigError::Flag {
                flag: "set",
                why: format!("`{a}`: expected NAME=VALUE"),
            }),
        }
    }
    let listen = errors.or(args.listen.take(), 1.5);
    let bus = Bus::check(std::mem::take(&mut args.bus), &mut errors);
    let (Some(listen), Some(bus), Ok(())) = (listen, bus, errors.clone().check()) else {
        return Err(errors.into());
    };
    let mut transport = bus.open()?;
    let mut client = BlockingClient::new(transport.as_mut(), &SystemClock, args.node_id, bus.mtu);
    let heard = client
        .discover(Duration::from_secs_f64(listen))
        .map_err(client_err)?;
    let drives: Vec<NodeId> = match args.drive {
        Some(d) if heard.contains(&d) => vec![d],
        Some(d) => bail!("no heartbeat from node {d} within {listen} s"),
        None => heard.clone(),
    };
    let mut unresolved = 0;
    let mut telegas = 0;
    for id in drives {
        let found = client.read_checked(id).map_err(client_err)?;
        if found.is_empty() && args.drive.is_none() {
            continue; // not a Telega
        }
        telegas += 1;
        let name = client
            .get_info(id)
            .map_err(client_err)?
            .map(|i| String::from_utf8_lossy(&i.name).into_owned())
            .unwrap_or_else(|| "(no GetInfo answer)".into());
        println!("drive {id}: {name}");
        if args.all {
            match client.list(id).map_err(client_err)? {
                Some(names) => {
                    for n in names {
                        if let Some(r) = client.access(id, &n, Value::Empty).map_err(client_err)? {
                            println!(
                                "  {n} = {} ({}; {})",
                                registers::show(&r.value),
                                registers::describe(&r.value),
                                flags(r.mutable, r.persistent)
                            );
                        }
                    }
                }
                None => println!("  (does not answer uavcan.register.List)"),
            }
        } else {
            for (n, v) in &found {
                println!("  {n} = {}", registers::show(v));
            }
        }
        let mut writes = assignments.clone();
        if args.fix {
            for p in check_prerequisites(&found, args.feedback_id) {
                if !writes.iter().any(|(n, _)| *n == p.register) {
                    writes.push((p.register, p.wanted));
                }
            }
        }
        for (n, v) in &writes {
            let after = write(&mut client, id, n, v)?;
            println!("  set {n} = {}", registers::show(&after));
        }
        if args.store {
            match client
                .execute(id, ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES)
                .map_err(client_err)?
            {
                Some(ExecuteCommandResponse::STATUS_SUCCESS) => println!("  stored"),
                Some(s) => bail!("drive {id} refused to store its registers (status {s})"),
                None => bail!("drive {id} did not answer the store command"),
            }
        }
        let now = client.read_checked(id).map_err(client_err)?;
        let problems = check_prerequisites(&now, args.feedback_id);
        if problems.is_empty() {
            println!("  ready: feedback at 100 Hz or more, with the drive's own timestamps");
        } else {
            unresolved += problems.len();
            eprintln!("{}", explain(id, &problems));
        }
    }
    if telegas == 0 {
        let ids: Vec<String> = heard.iter().map(|n| n.to_string()).collect();
        bail!(
            "no drive with Telega's registers among the nodes heard ({})",
            if ids.is_empty() {
                "none".to_string()
            } else {
                ids.join(", ")
            }
        );
    }
    if unresolved > 0 {
        bail!(
            "{unresolved} prerequisite(s) not met; run again with --fix (and --store to keep them)"
        );
    }
    Ok(())
}
