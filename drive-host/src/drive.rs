//! The driver on a real bus: [`propid_drive_proto::drive::Drive`] in the real-time loop, its
//! rows written to a TSV as they come (each flushed before the next).

use std::io::Write;
use std::sync::atomic::AtomicBool;

use propid_drive_proto::drive::{Drive, DriveConfig, DriveEvent, StopReport};
use propid_drive_proto::StopReason;
use propid_io::tsv::{Row, TsvWriter};
use propid_transport::CanTransport;

use crate::realtime::{run_realtime, Clock, RunOutcome};

/// What [`run_drive`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveOutcome {
    /// The machine's report: why it stopped, rows, stop commands handed out, counters.
    pub report: StopReport,
    /// What the loop saw of the link (did the stop commands leave the transport?).
    pub link: RunOutcome,
}

impl DriveOutcome {
    /// True when the stop commands were handed out and left the transport.
    pub fn standby_delivered(&self, readiness: bool) -> bool {
        self.report.stop_commands_sent(readiness) && self.link.flushed
    }
}

/// Runs a [`Drive`] in real time on `transport` (see [`run_realtime`]): the TSV goes to `out`
/// (header when the pattern starts, each row flushed as it comes, before `on_event` sees it), and
/// every event goes to `on_event`.
pub fn run_drive(
    cfg: DriveConfig,
    transport: &mut dyn CanTransport,
    clock: &dyn Clock,
    stop: &AtomicBool,
    out: &mut dyn Write,
    on_event: &mut dyn FnMut(&DriveEvent),
) -> DriveOutcome {
    let drive = Drive::new(cfg, clock.now());
    run_drive_machine(drive, transport, clock, stop, out, on_event)
}

/// [`run_drive`] for a [`Drive`] built by the caller (e.g. with [`Drive::with_registers`]).
pub fn run_drive_machine(
    mut drive: Drive,
    transport: &mut dyn CanTransport,
    clock: &dyn Clock,
    stop: &AtomicBool,
    out: &mut dyn Write,
    on_event: &mut dyn FnMut(&DriveEvent),
) -> DriveOutcome {
    let mut out = Some(out);
    let mut writer: Option<TsvWriter<&mut dyn Write>> = None;
    let mut report = None;
    let link = run_realtime(&mut drive, transport, clock, stop, &mut |event| {
        match &event {
            DriveEvent::PatternStarted => {
                if let Some(o) = out.take() {
                    writer = Some(TsvWriter::new(o, true).map_err(|e| e.to_string())?);
                }
            }
            DriveEvent::Row(row) => {
                if let Some(w) = writer.as_mut() {
                    let row = Row::new(row.ts_local, row.sample);
                    w.write(&row).map_err(|e| e.to_string())?;
                }
            }
            DriveEvent::Stopped(r) => report = Some(r.clone()),
            _ => {}
        }
        on_event(&event);
        Ok(())
    });
    let report = report.unwrap_or_else(|| {
        let now = drive.snapshot();
        StopReport {
            reason: StopReason::Transport("the drive loop ended before the drive stopped".into()),
            rows: now.rows,
            feedback_lost: now.feedback_lost,
            damaged_frames: 0,
            standby_sent: 0,
            zero_setpoints_sent: 0,
            tx: now.tx,
            estimate: now.estimate,
        }
    });
    DriveOutcome { report, link }
}
