//! Receive: frames in, whole transfers out, in fixed memory.
//!
//! The [`Reassembler`] keeps a fixed pool of `SESSIONS` sessions, one per (port, source node)
//! pair it has heard from, each with an `EXTENT`-byte buffer; when the pool is full the
//! least-recently active idle session is reused. Every frame goes through the same checks, in
//! order, and a rejected frame is returned as an [`RxError`] (and counted in [`RxStats`]):
//!
//! 1. the CAN ID is Cyphal ([`CanId::parse`]) and the frame has a tail byte;
//! 2. the port is subscribed, and a service transfer is addressed to this node;
//! 3. single-frame transfers: toggle 1; not a repeat of the last transfer-ID from this source
//!    within the transfer-ID timeout; anonymous transfers are single-frame only;
//! 4. multi-frame transfers: a start frame opens (or restarts) the session; every later frame
//!    must carry the same transfer-ID and the expected toggle; the end frame closes it and the
//!    CRC-16/CCITT-FALSE over payload, padding and CRC must leave a zero residue.
//!
//! Payload past the subscription's extent is dropped (implicit truncation) but still covered by
//! the CRC check. The transfer's timestamp is that of its first frame.

use core::time::Duration;

use super::{
    CanId, Frame, NodeId, Port, SubjectId, TailByte, TransferHeader, TransferKind, TRANSFER_CRC,
};
use crate::time::Instant;

/// A port to receive on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Subscription {
    /// Subject, or service requests/responses addressed to this node.
    pub port: Port,
    /// Bytes of payload kept per transfer (the DSDL extent); more is truncated.
    pub extent: usize,
    /// A transfer with the same transfer-ID from the same source within this time is a
    /// duplicate; a multi-frame transfer must complete within it.
    pub transfer_id_timeout: Duration,
}

/// A reassembled transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transfer<'a> {
    /// Priority, kind, port, source, transfer-ID.
    pub header: TransferHeader,
    /// Timestamp of the first frame.
    pub timestamp: Instant,
    /// The payload, truncated to the subscription's extent. For CAN FD this includes the
    /// zero padding of the last frame (receivers cannot tell padding from data; DSDL implicit
    /// truncation absorbs it).
    pub payload: &'a [u8],
}

/// Why a frame was not accepted (or did not complete a transfer).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxError {
    /// Not a Cyphal/CAN frame (reserved ID bits set, or no tail byte).
    NotCyphal,
    /// Nobody subscribed to this port.
    NotSubscribed,
    /// A service transfer addressed to another node.
    NotForUs,
    /// A continuation frame without a transfer in progress (its start was lost or timed out).
    MissingStart,
    /// The toggle bit is not the expected one (a repeated or lost frame).
    BadToggle,
    /// A continuation frame with another transfer-ID than the transfer in progress.
    WrongTransferId,
    /// The transfer CRC does not match.
    BadCrc,
    /// The same transfer-ID from the same source again within the transfer-ID timeout.
    DuplicateTransfer,
    /// An anonymous frame that is not a single-frame transfer.
    AnonymousMultiFrame,
    /// Every session is busy with a transfer in progress.
    OutOfSessions,
}

impl RxError {
    /// Every reason, in the order [`RxStats`] counts them.
    pub const ALL: [RxError; 10] = [
        RxError::NotCyphal,
        RxError::NotSubscribed,
        RxError::NotForUs,
        RxError::MissingStart,
        RxError::BadToggle,
        RxError::WrongTransferId,
        RxError::BadCrc,
        RxError::DuplicateTransfer,
        RxError::AnonymousMultiFrame,
        RxError::OutOfSessions,
    ];

    /// The counter slot of this reason: an exhaustive match, so a new variant does not compile
    /// until it has a slot (and the assertion below checks [`RxError::ALL`] agrees).
    const fn index(self) -> usize {
        match self {
            RxError::NotCyphal => 0,
            RxError::NotSubscribed => 1,
            RxError::NotForUs => 2,
            RxError::MissingStart => 3,
            RxError::BadToggle => 4,
            RxError::WrongTransferId => 5,
            RxError::BadCrc => 6,
            RxError::DuplicateTransfer => 7,
            RxError::AnonymousMultiFrame => 8,
            RxError::OutOfSessions => 9,
        }
    }
}

// `ALL` lists every slot once, in slot order.
const _: () = {
    let mut i = 0;
    while i < RxError::ALL.len() {
        assert!(RxError::ALL[i].index() == i);
        i += 1;
    }
};

/// Counters of what the reassembler did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RxStats {
    /// Frames seen.
    pub frames: u64,
    /// Transfers delivered.
    pub transfers: u64,
    /// Rejections, one counter per [`RxError`] (see [`RxStats::rejected`]).
    rejected: [u64; RxError::ALL.len()],
}

impl RxStats {
    /// How many frames were rejected for `reason`.
    pub fn rejected(&self, reason: RxError) -> u64 {
        self.rejected[reason.index()]
    }

    /// All rejections.
    pub fn rejected_total(&self) -> u64 {
        self.rejected.iter().sum()
    }
}

struct Session<const EXTENT: usize> {
    port: Port,
    source: NodeId,
    last_activity: Instant,
    /// The last delivered transfer-ID and when its transfer started.
    last_delivered: Option<(u8, Instant)>,
    /// A multi-frame transfer in progress.
    in_progress: bool,
    transfer_id: u8,
    priority: super::Priority,
    kind: TransferKind,
    started: Instant,
    next_toggle: bool,
    /// Stream bytes received so far (payload, padding, CRC).
    received: usize,
    crc: crc::Digest<'static, u16>,
    buffer: [u8; EXTENT],
}

/// Fixed-capacity Cyphal/CAN transfer reassembler: up to `PORTS` subscriptions, `SESSIONS`
/// concurrent (port, source) sessions, `EXTENT` payload bytes kept per transfer.
pub struct Reassembler<const PORTS: usize, const SESSIONS: usize, const EXTENT: usize> {
    local_node_id: Option<NodeId>,
    subscriptions: heapless::Vec<Subscription, PORTS>,
    sessions: [Option<Session<EXTENT>>; SESSIONS],
    stats: RxStats,
}

impl<const PORTS: usize, const SESSIONS: usize, const EXTENT: usize>
    Reassembler<PORTS, SESSIONS, EXTENT>
{
    /// An empty reassembler. Service transfers are accepted only if addressed to
    /// `local_node_id` (none when it is `None`).
    pub fn new(local_node_id: Option<NodeId>) -> Self {
        Reassembler {
            local_node_id,
            subscriptions: heapless::Vec::new(),
            sessions: [const { None }; SESSIONS],
            stats: RxStats::default(),
        }
    }

    /// Subscribes to a port (replacing an existing subscription to the same port). Returns the
    /// subscription back if all `PORTS` slots are taken.
    pub fn subscribe(&mut self, subscription: Subscription) -> Result<(), Subscription> {
        if let Some(s) = self
            .subscriptions
            .iter_mut()
            .find(|s| s.port == subscription.port)
        {
            *s = subscription;
            return Ok(());
        }
        self.subscriptions.push(subscription)
    }

    /// Stops receiving on a port and drops its sessions.
    pub fn unsubscribe(&mut self, port: Port) {
        self.subscriptions.retain(|s| s.port != port);
        for slot in &mut self.sessions {
            if slot.as_ref().is_some_and(|s| s.port == port) {
                *slot = None;
            }
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> RxStats {
        self.stats
    }

    /// The ports subscribed to.
    pub fn subscriptions(&self) -> &[Subscription] {
        &self.subscriptions
    }

    /// Static RAM one session takes, in bytes.
    pub const fn session_size() -> usize {
        core::mem::size_of::<Option<Session<EXTENT>>>()
    }

    /// Takes one frame; returns a transfer when the frame completes one.
    pub fn accept<'s>(&'s mut self, frame: &'s Frame) -> Result<Option<Transfer<'s>>, RxError> {
        self.stats.frames += 1;
        let result = accept_frame(
            self.local_node_id,
            &self.subscriptions,
            &mut self.sessions,
            frame,
        );
        match &result {
            Ok(Some(_)) => self.stats.transfers += 1,
            Ok(None) => {}
            Err(e) => self.stats.rejected[e.index()] += 1,
        }
        result
    }
}

fn accept_frame<'s, const EXTENT: usize>(
    local_node_id: Option<NodeId>,
    subscriptions: &[Subscription],
    sessions: &'s mut [Option<Session<EXTENT>>],
    frame: &'s Frame,
) -> Result<Option<Transfer<'s>>, RxError> {
    {
        let id = CanId::parse(frame.id()).ok_or(RxError::NotCyphal)?;
        let (&tail_byte, body) = frame.data().split_last().ok_or(RxError::NotCyphal)?;
        let tail = TailByte::parse(tail_byte);
        let port = id.kind.port();
        let sub = *subscriptions
            .iter()
            .find(|s| s.port == port)
            .ok_or(RxError::NotSubscribed)?;
        match id.kind {
            TransferKind::Request { destination, .. }
            | TransferKind::Response { destination, .. } => {
                if local_node_id != Some(destination) {
                    return Err(RxError::NotForUs);
                }
            }
            TransferKind::Message { .. } => {}
        }
        let now = frame.timestamp;
        let header = TransferHeader {
            priority: id.priority,
            kind: id.kind,
            source: id.source,
            transfer_id: tail.transfer_id,
        };
        let extent = sub.extent.min(EXTENT);
        let Some(source) = id.source else {
            // Anonymous: single-frame only, no session, no de-duplication possible.
            if !(tail.start && tail.end && tail.toggle) {
                return Err(RxError::AnonymousMultiFrame);
            }
            return Ok(Some(Transfer {
                header,
                timestamp: now,
                payload: &body[..body.len().min(extent)],
            }));
        };
        let timeout = sub.transfer_id_timeout;
        let index = session_index(sessions, port, source, now, timeout, tail.start)?;
        let Some(session) = sessions[index].as_mut() else {
            return Err(RxError::OutOfSessions);
        };
        // A transfer in progress that outlived the timeout is abandoned.
        if session.in_progress && now.saturating_duration_since(session.started) > timeout {
            session.in_progress = false;
        }
        if tail.start {
            if !tail.toggle {
                return Err(RxError::BadToggle);
            }
            if session.in_progress && session.transfer_id == tail.transfer_id {
                // The first frame again while its transfer is in progress: a repeated frame.
                return Err(RxError::BadToggle);
            }
            if let Some((tid, at)) = session.last_delivered {
                if tid == tail.transfer_id && now.saturating_duration_since(at) <= timeout {
                    session.in_progress = false;
                    return Err(RxError::DuplicateTransfer);
                }
            }
            session.last_activity = now;
            if tail.end {
                session.in_progress = false;
                session.last_delivered = Some((tail.transfer_id, now));
                return Ok(Some(Transfer {
                    header,
                    timestamp: now,
                    payload: &body[..body.len().min(extent)],
                }));
            }
            session.in_progress = true;
            session.transfer_id = tail.transfer_id;
            session.priority = id.priority;
            session.kind = id.kind;
            session.started = now;
            session.next_toggle = true;
            session.received = 0;
            session.crc = TRANSFER_CRC.digest();
        } else {
            if !session.in_progress {
                return Err(RxError::MissingStart);
            }
            if session.transfer_id != tail.transfer_id {
                return Err(RxError::WrongTransferId);
            }
            if session.next_toggle != tail.toggle {
                return Err(RxError::BadToggle);
            }
            session.last_activity = now;
        }
        // Append the frame's bytes to the stream.
        session.next_toggle = !session.next_toggle;
        session.crc.update(body);
        let stored = session.received.min(extent);
        let room = extent - stored;
        let take = body.len().min(room);
        session.buffer[stored..stored + take].copy_from_slice(&body[..take]);
        session.received += body.len();
        if !tail.end {
            return Ok(None);
        }
        session.in_progress = false;
        let crc = core::mem::replace(&mut session.crc, TRANSFER_CRC.digest()).finalize();
        if session.received < 2 || crc != 0 {
            return Err(RxError::BadCrc);
        }
        session.last_delivered = Some((session.transfer_id, session.started));
        let payload_len = (session.received - 2).min(extent);
        Ok(Some(Transfer {
            header: TransferHeader {
                priority: session.priority,
                kind: session.kind,
                source: Some(source),
                transfer_id: session.transfer_id,
            },
            timestamp: session.started,
            payload: &session.buffer[..payload_len],
        }))
    }
}

/// Finds the session of (port, source), or makes one from a free or idle slot. Only a start
/// frame may open a new session.
fn session_index<const EXTENT: usize>(
    sessions: &mut [Option<Session<EXTENT>>],
    port: Port,
    source: NodeId,
    now: Instant,
    timeout: Duration,
    is_start: bool,
) -> Result<usize, RxError> {
    if let Some(i) = sessions.iter().position(|s| {
        s.as_ref()
            .is_some_and(|s| s.port == port && s.source == source)
    }) {
        return Ok(i);
    }
    if !is_start {
        return Err(RxError::MissingStart);
    }
    // A free slot, else the least recently active session that is idle or whose transfer has
    // stalled (no frame for longer than the transfer-ID timeout).
    let slot = match sessions.iter().position(Option::is_none) {
        Some(i) => i,
        None => sessions
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.as_ref().map(|s| (i, s)))
            .filter(|(_, s)| {
                !s.in_progress || now.saturating_duration_since(s.last_activity) > timeout
            })
            .min_by_key(|(_, s)| s.last_activity)
            .map(|(i, _)| i)
            .ok_or(RxError::OutOfSessions)?,
    };
    sessions[slot] = Some(Session {
        port,
        source,
        last_activity: now,
        last_delivered: None,
        in_progress: false,
        transfer_id: 0,
        priority: super::Priority::NOMINAL,
        kind: TransferKind::Message {
            subject_id: SubjectId::from_const(0),
        },
        started: now,
        next_toggle: true,
        received: 0,
        crc: TRANSFER_CRC.digest(),
        buffer: [0; EXTENT],
    });
    Ok(slot)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::can::{FrameSplitter, Mtu, Priority};

    fn sub(subject: u16) -> Subscription {
        Subscription {
            port: Port::Subject(SubjectId::from_const(subject)),
            extent: 64,
            transfer_id_timeout: Duration::from_secs(2),
        }
    }

    fn frame(id: u32, data: &[u8], ms: u64) -> Frame {
        Frame::new(Instant::from_millis(ms), id, data).unwrap()
    }

    #[test]
    fn single_frame_and_duplicates() {
        let mut r: Reassembler<4, 4, 64> = Reassembler::new(None);
        r.subscribe(sub(100)).unwrap();
        let f = frame(0x1060_642A, &[0x03, 0xE0], 0);
        assert_eq!(r.accept(&f).unwrap().unwrap().payload, &[0x03]);
        // Same transfer-ID again within the timeout: duplicate.
        assert_eq!(
            r.accept(&frame(0x1060_642A, &[0x03, 0xE0], 10)),
            Err(RxError::DuplicateTransfer)
        );
        // After the timeout it is a new transfer.
        assert!(r
            .accept(&frame(0x1060_642A, &[0x03, 0xE0], 2100))
            .unwrap()
            .is_some());
        // Unsubscribed port.
        assert_eq!(
            r.accept(&frame(0x1060_652A, &[0x03, 0xE0], 0)),
            Err(RxError::NotSubscribed)
        );
        // Toggle 0 on a single frame.
        assert_eq!(
            r.accept(&frame(0x1060_642A, &[0x03, 0xC1], 0)),
            Err(RxError::BadToggle)
        );
        // No tail byte.
        assert_eq!(
            r.accept(&frame(0x1060_642A, &[], 0)),
            Err(RxError::NotCyphal)
        );
    }

    #[test]
    fn multi_frame_errors() {
        let header = TransferHeader {
            priority: Priority::NOMINAL,
            kind: TransferKind::Message {
                subject_id: SubjectId::from_const(100),
            },
            source: Some(NodeId::from_const(42)),
            transfer_id: 5,
        };
        let payload = [7u8; 20];
        let frames: heapless::Vec<Frame, 8> =
            FrameSplitter::new(&header, &payload, Mtu::Classic, Instant::ZERO)
                .unwrap()
                .collect();
        let mut r: Reassembler<1, 2, 64> = Reassembler::new(None);
        r.subscribe(sub(100)).unwrap();
        // Missing start.
        assert_eq!(r.accept(&frames[1]), Err(RxError::MissingStart));
        assert_eq!(r.accept(&frames[0]), Ok(None));
        // Repeated frame: bad toggle.
        assert_eq!(r.accept(&frames[0]), Err(RxError::BadToggle));
        assert_eq!(r.accept(&frames[1]), Ok(None));
        assert_eq!(r.accept(&frames[1]), Err(RxError::BadToggle));
        assert_eq!(r.accept(&frames[2]), Ok(None));
        let t = r.accept(&frames[3]).unwrap().unwrap();
        assert_eq!(t.payload, &payload);
        assert_eq!(t.header, header);
        // Corrupted payload: bad CRC.
        let mut bad = frames.clone();
        let mut d = [0u8; 8];
        d.copy_from_slice(bad[1].data());
        d[0] ^= 1;
        bad[1] = Frame::new(Instant::ZERO, bad[1].id(), &d).unwrap();
        let mut r2: Reassembler<1, 2, 64> = Reassembler::new(None);
        r2.subscribe(sub(100)).unwrap();
        for f in &bad[..3] {
            assert_eq!(r2.accept(f), Ok(None));
        }
        assert_eq!(r2.accept(&bad[3]), Err(RxError::BadCrc));
        assert_eq!(r2.stats().rejected(RxError::BadCrc), 1);
    }

    #[test]
    fn truncates_to_extent_but_checks_crc() {
        let header = TransferHeader {
            priority: Priority::NOMINAL,
            kind: TransferKind::Message {
                subject_id: SubjectId::from_const(1),
            },
            source: Some(NodeId::from_const(1)),
            transfer_id: 0,
        };
        let payload: [u8; 30] = core::array::from_fn(|i| i as u8);
        let mut r: Reassembler<1, 1, 64> = Reassembler::new(None);
        r.subscribe(Subscription {
            extent: 10,
            ..sub(1)
        })
        .unwrap();
        let mut out = None;
        for f in FrameSplitter::new(&header, &payload, Mtu::Classic, Instant::ZERO).unwrap() {
            if let Some(t) = r.accept(&f).unwrap() {
                out = Some(t.payload.len());
                assert_eq!(t.payload, &payload[..10]);
            }
        }
        assert_eq!(out, Some(10));
    }

    #[test]
    fn services_need_our_address() {
        let mut r: Reassembler<1, 1, 8> = Reassembler::new(Some(NodeId::from_const(42)));
        r.subscribe(Subscription {
            port: Port::Request(crate::can::ServiceId::from_const(430)),
            extent: 0,
            transfer_id_timeout: Duration::from_secs(2),
        })
        .unwrap();
        // GetInfo request 10 → 42.
        assert!(r.accept(&frame(0x136B_950A, &[0xE0], 0)).unwrap().is_some());
        // 10 → 43.
        assert_eq!(
            r.accept(&frame(0x136B_958A, &[0xE1], 0)),
            Err(RxError::NotForUs)
        );
    }
}
