//! `propid telega`: find drives on the bus, read their registers, check the seed's prerequisites
//! (feedback at ≥ 100 Hz, local timestamps on), fix them when asked and store them when asked.

use std::time::Duration;

use anyhow::bail;
use propid_core::dsdl::{ExecuteCommandRequest, ExecuteCommandResponse, Value};
use propid_core::node::parse_value;
use propid_drive::registers::{self, check_prerequisites, Problem};
use propid_drive::telega::{read_checked, Client};
use propid_transport::CanTransport;

use crate::InputError;

/// Arguments of `propid telega`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The bus.
    #[command(flatten)]
    pub bus: crate::bus::BusArgs,
    /// This tool's own node-ID.
    #[arg(long, default_value_t = 126)]
    pub node_id: u8,
    /// The drive's node-ID (default: every node heard that has Telega's registers).
    #[arg(long)]
    pub drive: Option<u8>,
    /// How long to listen for heartbeats [s].
    #[arg(long, default_value_t = 1.5)]
    pub listen: f64,
    /// The feedback subject propid will listen on (checked against uavcan.pub.dynamics.id).
    #[arg(long)]
    pub feedback_id: Option<u16>,
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

fn show(v: &Value) -> String {
    if v.is_numeric() {
        let single = matches!(v, Value::Real32(_) | Value::Real16(_));
        let bits = matches!(v, Value::Bit(_));
        let items: Vec<String> = (0..v.len())
            .filter_map(|i| v.float_at(i))
            .map(|x| match () {
                _ if bits => (x != 0.0).to_string(),
                // Shortest text that reads back as the same float32.
                _ if single => format!("{}", x as f32),
                _ => format!("{x}"),
            })
            .collect();
        items.join(" ")
    } else {
        format!("{:?}", v.as_str().unwrap_or("<binary>"))
    }
}

/// Writes `text` into register `name` of `drive`, converted from the register's current type;
/// returns the value the drive then holds.
fn write(client: &mut Client<'_>, drive: u8, name: &str, text: &str) -> anyhow::Result<Value> {
    let current = client
        .access(drive, name, Value::Empty)
        .map_err(anyhow::Error::msg)?
        .filter(|r| !r.value.is_empty())
        .ok_or_else(|| InputError(format!("drive {drive} has no register {name}")))?;
    let value = parse_value(&current.value, registers::normalize_bool(text)).ok_or_else(|| {
        InputError(format!(
            "`{text}` is not a valid {} for {name}",
            registers::describe(&current.value)
        ))
    })?;
    let after = client
        .access(drive, name, value.clone())
        .map_err(anyhow::Error::msg)?
        .ok_or_else(|| anyhow::anyhow!("drive {drive} did not answer the write of {name}"))?;
    if !current.mutable {
        bail!("drive {drive}: {name} is read-only");
    }
    if after.value != value {
        bail!(
            "drive {drive} kept {name} = {} (wrote {})",
            show(&after.value),
            show(&value)
        );
    }
    Ok(after.value)
}

/// The problems of every Telega-like drive heard (`only`: that node only), after reading
/// Telega's registers; nodes without them are skipped. Used by `drive` before it engages.
pub fn survey(
    transport: &mut dyn CanTransport,
    node_id: u8,
    mtu: usize,
    only: Option<u8>,
    listen: Duration,
    feedback_id: Option<u16>,
) -> anyhow::Result<Vec<(u8, String, Vec<Problem>)>> {
    let mut client = Client::new(transport, node_id, mtu);
    let heard = client.discover(listen).map_err(anyhow::Error::msg)?;
    let mut out = Vec::new();
    for id in heard.into_iter().filter(|id| only.is_none_or(|o| o == *id)) {
        let found = read_checked(&mut client, id).map_err(anyhow::Error::msg)?;
        if found.is_empty() {
            continue;
        }
        let name = client
            .get_info(id)
            .map_err(anyhow::Error::msg)?
            .map(|i| String::from_utf8_lossy(&i.name).into_owned())
            .unwrap_or_default();
        out.push((id, name, check_prerequisites(&found, feedback_id)));
    }
    Ok(out)
}

/// One line per problem: which register to change, to what, and why.
pub fn explain(drive: u8, problems: &[Problem]) -> String {
    problems
        .iter()
        .map(|p| {
            format!(
                "drive {drive}: {} is {}; set it to {} ({}): propid telega --drive {drive} --set {}={} --store",
                p.register, p.found, p.wanted, p.why, p.register, p.wanted
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Runs `propid telega`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut assignments = Vec::new();
    for a in &args.set {
        let (n, v) = a
            .split_once('=')
            .ok_or_else(|| InputError(format!("--set `{a}`: expected NAME=VALUE")))?;
        assignments.push((n.trim().to_string(), v.trim().to_string()));
    }
    if !(args.listen > 0.0 && args.listen <= 60.0) {
        return Err(InputError(format!(
            "--listen must be in (0, 60] s (got {})",
            args.listen
        ))
        .into());
    }
    let mut transport = args.bus.open()?;
    let mut client = Client::new(transport.as_mut(), args.node_id, args.bus.mtu);
    let heard = client
        .discover(Duration::from_secs_f64(args.listen))
        .map_err(anyhow::Error::msg)?;
    let drives: Vec<u8> = match args.drive {
        Some(d) if heard.contains(&d) => vec![d],
        Some(d) => bail!("no heartbeat from node {d} within {} s", args.listen),
        None => heard.clone(),
    };
    let mut unresolved = 0;
    let mut telegas = 0;
    for id in drives {
        let found = read_checked(&mut client, id).map_err(anyhow::Error::msg)?;
        if found.is_empty() && args.drive.is_none() {
            continue; // not a Telega
        }
        telegas += 1;
        let name = client
            .get_info(id)
            .map_err(anyhow::Error::msg)?
            .map(|i| String::from_utf8_lossy(&i.name).into_owned())
            .unwrap_or_else(|| "(no GetInfo answer)".into());
        println!("drive {id}: {name}");
        if args.all {
            match client.read_all(id).map_err(anyhow::Error::msg)? {
                Some(all) => {
                    for r in all {
                        let flags = match (r.mutable, r.persistent) {
                            (true, true) => "mutable, persistent",
                            (true, false) => "mutable",
                            (false, true) => "read-only, persistent",
                            (false, false) => "read-only",
                        };
                        println!(
                            "  {} = {} ({}; {flags})",
                            r.name,
                            show(&r.value),
                            registers::describe(&r.value)
                        );
                    }
                }
                None => println!("  (does not answer uavcan.register.List)"),
            }
        } else {
            for (n, v) in &found {
                println!("  {n} = {}", show(v));
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
            println!("  set {n} = {}", show(&after));
        }
        if args.store {
            match client
                .execute(id, ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES)
                .map_err(anyhow::Error::msg)?
            {
                Some(ExecuteCommandResponse::STATUS_SUCCESS) => println!("  stored"),
                Some(s) => bail!("drive {id} refused to store its registers (status {s})"),
                None => bail!("drive {id} did not answer the store command"),
            }
        }
        let now = read_checked(&mut client, id).map_err(anyhow::Error::msg)?;
        let problems = check_prerequisites(&now, args.feedback_id);
        if problems.is_empty() {
            println!("  ready: feedback at >= 100 Hz with local timestamps");
        } else {
            unresolved += problems.len();
            eprintln!("{}", explain(id, &problems));
        }
    }
    if telegas == 0 {
        bail!(
            "no drive with Telega's registers among the nodes heard ({:?})",
            heard
        );
    }
    if unresolved > 0 {
        bail!("{unresolved} prerequisite(s) not met; run again with --fix (and --store)");
    }
    Ok(())
}
