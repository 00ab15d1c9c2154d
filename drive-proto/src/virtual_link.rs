//! Two machines on a modelled CAN link, in virtual time.
//!
//! ```text
//!  A ── poll_transmit ─► [a→b: capacity frames in flight, one every frame_time] ─► B.handle_frame
//!  B ── poll_transmit ─► [b→a: the same]                                         ─► A.handle_frame
//!  a full direction refuses the frame: handle_blocked (the machine offers it again later)
//!  step(): the clock jumps to the earliest of both poll_timeouts and the next delivery
//! ```
//! Nothing sleeps: the seed's 200 s run takes as long as its frames take to compute. The same
//! inputs give the same run, frame for frame, so tests can compare exact row counts and phases.

use std::collections::VecDeque;
use std::time::Duration;

use propid_core::can::Frame;
use propid_core::time::Instant;

use crate::machine::Machine;

/// The link's properties, the same in both directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkModel {
    /// Time between two frames leaving one direction's queue (0: as fast as they come).
    pub frame_time: Duration,
    /// Delay from leaving the queue to arriving.
    pub latency: Duration,
    /// Frames one direction holds at most before refusing more (`usize::MAX`: unbounded).
    pub capacity: usize,
}

impl LinkModel {
    /// A fast, unbounded link: 100 µs latency, no queueing delay.
    pub fn ideal() -> Self {
        LinkModel {
            frame_time: Duration::ZERO,
            latency: Duration::from_micros(100),
            capacity: usize::MAX,
        }
    }
}

#[derive(Default)]
struct Direction {
    in_flight: VecDeque<(Instant, Frame)>,
    last_departure: Option<Instant>,
    refused: u64,
    delivered: u64,
}

/// Two directions of a link and a virtual clock. See the module documentation.
pub struct VirtualLink {
    model: LinkModel,
    now: Instant,
    ab: Direction,
    ba: Direction,
    /// When set, B's frames are dropped before they reach the link (a silent drive).
    pub mute_b: bool,
}

impl VirtualLink {
    /// A link whose clock starts at `start`.
    pub fn new(model: LinkModel, start: Instant) -> Self {
        VirtualLink {
            model,
            now: start,
            ab: Direction::default(),
            ba: Direction::default(),
            mute_b: false,
        }
    }

    /// The virtual time.
    pub fn now(&self) -> Instant {
        self.now
    }

    /// Frames refused because a direction was full: (a→b, b→a).
    pub fn refused(&self) -> (u64, u64) {
        (self.ab.refused, self.ba.refused)
    }

    /// Frames delivered: (a→b, b→a).
    pub fn delivered(&self) -> (u64, u64) {
        (self.ab.delivered, self.ba.delivered)
    }

    /// Advances the clock to the next thing that happens and lets it happen: deliveries, then
    /// each machine's transmissions. Returns false when neither machine plans anything and no
    /// frame is in flight.
    pub fn step<A: Machine, B: Machine>(&mut self, a: &mut A, b: &mut B) -> bool {
        let next = [
            a.poll_timeout(),
            b.poll_timeout(),
            self.ab.in_flight.front().map(|(t, _)| *t),
            self.ba.in_flight.front().map(|(t, _)| *t),
        ]
        .into_iter()
        .flatten()
        .min();
        let Some(next) = next else { return false };
        self.now = self.now.max(next);
        let now = self.now;
        deliver(&mut self.ab, now, b);
        deliver(&mut self.ba, now, a);
        transmit(&mut self.ab, &self.model, now, a, false);
        transmit(&mut self.ba, &self.model, now, b, self.mute_b);
        true
    }
}

fn deliver<M: Machine>(dir: &mut Direction, now: Instant, to: &mut M) {
    while dir.in_flight.front().is_some_and(|(t, _)| *t <= now) {
        if let Some((t, mut frame)) = dir.in_flight.pop_front() {
            frame.timestamp = t;
            dir.delivered += 1;
            to.handle_frame(now, &frame);
        }
    }
}

fn transmit<M: Machine>(
    dir: &mut Direction,
    model: &LinkModel,
    now: Instant,
    from: &mut M,
    mute: bool,
) {
    while let Some(frame) = from.poll_transmit(now) {
        if mute {
            continue;
        }
        if dir.in_flight.len() >= model.capacity {
            dir.refused += 1;
            from.handle_blocked(now, frame);
            break;
        }
        let depart = dir.last_departure.map_or(now, |d| d.max(now)) + model.frame_time;
        dir.last_departure = Some(depart);
        dir.in_flight.push_back((depart + model.latency, frame));
    }
}
