//! `propid demo`: the whole pipeline on a simulated stand, no hardware.
//!
//! ```text
//!  pseudo-terminal pair (a real pty; the bytes are real SLCAN; an in-memory bus on Windows)
//!   ├─ thread: sim-drive (Stand with a hidden effect) ─ SlcanTransport ─┐
//!   └─ drive (init, pattern, STANDBY) ───────────────── SlcanTransport ─┘
//!  ─► run.tsv ─► fit (fit.yaml, fit.svg) ─► diagnose (diagnose.txt, diagnose.json, diagnose.svg)
//!  ─► report.md in the output folder
//! ```

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use propid_core::dsdl::Readiness;
use propid_transport::CanTransport;

use propid_drive_host::drive::run_drive;
use propid_drive_host::realtime::{Clock, SystemClock};
use propid_drive_host::sim_drive::SimDriveThread;
use propid_drive_host::stand::{Played, StandPlant};
use propid_drive_proto::drive::DriveConfig;
use propid_drive_proto::sim_drive::{SimDrive, SimDriveConfig};
use propid_drive_proto::StopReason;

use crate::settings::{command_args, setting, ConfigErrors, Names};
use propid_drive_proto::excitation::Schedule;
use propid_drive_proto::settings::{InitDuration, PatternDuration};
use propid_science::diagnose::{diagnose, read_samples, report_figure, to_text};
use propid_science::excitation::Pattern;
use propid_science::fit::{figure, fit_path, to_yaml, FitOptions};
use propid_science::stand::StandConfig;

setting! {
    /// The demo's pattern duration.
    DemoDuration: PatternDuration = Names::flag("duration"),
        "Pattern duration [s] (real time) [default: 20]",
        within PatternDuration;
    /// The demo's init phase.
    DemoInit: InitDuration = Names::flag("init-duration"),
        "Init phase at the high setpoint [s] [default: 2]",
        within InitDuration;
}

command_args! {
    /// Arguments of `propid demo`.
    pub struct Args {
        settings {
            duration: DemoDuration as "S",
            init_duration: DemoInit as "S",
        }
        registers {}
        nested {}
        /// Folder for the recording, the report and the plots.
        #[arg(short, long, default_value = "propid-demo")]
        pub out: PathBuf,
        /// Excitation (a chirp separates the effects better than the seed's sinusoid).
        #[arg(long, default_value_t = Pattern::Chirp)]
        pub pattern: Pattern,
        /// A torque lag hidden in the simulated drive [s] (0: none), for diagnose to find.
        #[arg(long, default_value_t = 0.012)]
        pub torque_lag: f64,
        /// Noise seed of the simulated stand.
        #[arg(long, default_value_t = 1)]
        pub seed: u64,
        /// Serve a live page of the run (plots, running estimate, bus health, a STOP button) on this
        /// address (the URL with its per-run token is printed on stderr).
        #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
        pub live: Option<String>,
        /// Allow --live on an address other than loopback.
        #[arg(long)]
        pub live_allow_remote: bool,
    }
}

/// Runs `propid demo`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut errors = ConfigErrors::default();
    let duration = errors.or(args.duration, PatternDuration::from_const(20.0));
    let init_duration = errors.or(args.init_duration, InitDuration::from_const(2.0));
    let (Some(duration), Some(init_duration), Ok(())) =
        (duration, init_duration, errors.clone().check())
    else {
        return Err(errors.into());
    };
    let stand = StandConfig {
        torque_lag: args.torque_lag,
        ..StandConfig::default()
    };
    stand.validate()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let schedule = Schedule {
        duration,
        init_duration,
        ..Schedule::SEED
    };
    let played = Played::new(schedule, args.pattern);
    let excitation = *played.excitation();
    let cfg = DriveConfig {
        fit: true,
        ..DriveConfig::example(played)
    };
    let (mut transport, telega_end, pty) = link()?;
    eprintln!(
        "demo: simulated Telega (J = {:.2e} kg·m², c2 = {:.2e}, hidden torque lag {} ms) and the driver talk SLCAN over {pty}",
        stand.inertia,
        stand.c2,
        stand.torque_lag * 1e3
    );
    let plant = StandPlant::boxed(stand, args.seed)?;
    let telega = SimDriveThread::spawn(
        SimDrive::new(SimDriveConfig::example(), plant, SystemClock.now()),
        telega_end,
    );
    let tsv = args.out.join("run.tsv");
    let mut file =
        std::fs::File::create(&tsv).with_context(|| format!("cannot create {}", tsv.display()))?;
    // Ctrl-C, or STOP on the live page, stops the drive with STANDBY as always.
    let stop = Arc::new(AtomicBool::new(false));
    let _handlers = crate::signals::install(&stop)?;
    let mut live = crate::live::start_for_drive(
        args.live.as_deref(),
        args.live_allow_remote,
        &stop,
        played,
        "propid demo",
    )?;
    let outcome = run_drive(
        cfg,
        transport.as_mut(),
        &SystemClock,
        &stop,
        &mut file,
        &mut |e| {
            crate::cmd::drive::print_event(e, &excitation, true);
            if let Some((_, view)) = live.as_mut() {
                view.on_event(e);
            }
        },
    );
    // The simulated drive stops once the stop commands the driver sent have arrived (the bound
    // is for a lost frame, which the check below then reports).
    let r = &outcome.report;
    let (_, summary) = telega.stop_after_stop_commands(
        r.standby_sent,
        r.zero_setpoints_sent,
        std::time::Duration::from_secs(5),
    );
    let summary = summary.map_err(anyhow::Error::msg)?;
    let standby_last =
        summary.last_readiness == Some(Readiness::STANDBY) && summary.last_setpoint == Some(0.0);
    eprintln!(
        "demo: {} rows recorded; the simulated Telega {} last",
        outcome.report.rows,
        if standby_last {
            "saw STANDBY and a zero setpoint"
        } else {
            "did NOT see STANDBY and a zero setpoint"
        }
    );
    if outcome.report.reason != StopReason::Completed {
        anyhow::bail!("the drive stopped early: {}", outcome.report.reason);
    }

    // Fit, as the seed regressor would, and plot.
    let fit_options = FitOptions {
        diameter: Some(0.1778),
        ..FitOptions::default()
    };
    let (fit, samples) = fit_path(&tsv, &fit_options, &mut |_, _| {})?;
    let fit_yaml = to_yaml(&fit);
    std::fs::write(args.out.join("fit.yaml"), &fit_yaml)?;
    crate::plot::write(&args.out.join("fit.svg"), &figure(&fit, &samples))?;

    // Diagnose.
    let (all, _) = read_samples(&tsv)?;
    let report = diagnose(&all, Default::default())
        .map_err(|e| anyhow::anyhow!("{}: {}", tsv.display(), e))?;
    let text = to_text(&report, &tsv.display().to_string());
    std::fs::write(args.out.join("diagnose.txt"), &text)?;
    std::fs::write(
        args.out.join("diagnose.json"),
        serde_json::to_string_pretty(&report)?,
    )?;
    crate::plot::write(&args.out.join("diagnose.svg"), &report_figure(&report))?;

    let mut md = String::new();
    md += "# propid demo\n\n";
    md += &format!(
        "A simulated Telega (inertia {:.3e} kg·m², drag {:.3e} N·m·s²/rad², a hidden torque lag of {} ms) was driven \
         over SLCAN on a pseudo-terminal for {} s ({} pattern); {} feedback rows were recorded in `run.tsv`. \
         After the pattern the driver commanded STANDBY and a zero setpoint: {}.\n\n",
        stand.inertia,
        stand.c2,
        stand.torque_lag * 1e3,
        duration,
        args.pattern,
        outcome.report.rows,
        if standby_last { "the simulated drive saw STANDBY last" } else { "the simulated drive did NOT see STANDBY last" }
    );
    md += "## Fit (the seed's model and bounds, solved exactly)\n\n```yaml\n";
    md += &fit_yaml;
    md += "```\n\n![fit](fit.svg)\n\n## Diagnosis\n\n```text\n";
    md += &text;
    md += "```\n\n![diagnosis](diagnose.svg)\n";
    std::fs::write(args.out.join("report.md"), &md)?;
    let reproduce = [format!(
        "propid demo --out {} --duration {} --init-duration {} --pattern {} --torque-lag {} --seed {}",
        args.out.display(),
        duration,
        init_duration,
        args.pattern,
        args.torque_lag,
        args.seed
    )];
    let page = crate::cmd::report::build(&tsv, &fit_options, &reproduce)?;
    let html_path = args.out.join("report.html");
    std::fs::write(&html_path, page)
        .with_context(|| format!("cannot write {}", html_path.display()))?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}")?;
    writeln!(
        out,
        "demo: fit J = {:.4e} kg·m², c2 = {:.4e} (truth {:.4e}, {:.4e}); report in {} (open {} in a browser)",
        fit.mass,
        fit.c2,
        stand.inertia,
        stand.c2,
        args.out.join("report.md").display(),
        html_path.display()
    )?;
    if !standby_last {
        anyhow::bail!("the simulated drive did not see STANDBY last");
    }
    Ok(())
}

/// The driver's end, the simulated Telega's end and a name for the link.
type Link = (Box<dyn CanTransport>, Box<dyn CanTransport>, String);

/// SLCAN over a real pseudo-terminal pair where the OS has them.
#[cfg(unix)]
fn link() -> anyhow::Result<Link> {
    use propid_slcan::SlcanTransport;
    use serialport::{SerialPort, TTYPort};
    let (drive_end, telega_end) = TTYPort::pair().context("cannot open a pseudo-terminal pair")?;
    let pty = drive_end.name().unwrap_or_else(|| "pty".into());
    Ok((
        Box::new(SlcanTransport::from_tty(drive_end, &pty)?),
        Box::new(SlcanTransport::from_tty(telega_end, "pty-telega")?),
        pty,
    ))
}

/// Windows has no pseudo-terminals: the demo's two ends meet on an in-memory Classic CAN bus.
#[cfg(not(unix))]
fn link() -> anyhow::Result<Link> {
    let (a, b) = propid_transport::MemoryBus::pair(8);
    Ok((Box::new(a), Box::new(b), "an in-memory bus".into()))
}
