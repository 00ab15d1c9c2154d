//! The transmit queue: frames leave in Cyphal priority order, each before its deadline or never.
//!
//! ```text
//!  push(now, header, payload, deadline) ──► FrameSplitter ──► room? ──► insert by priority
//!        │ expired frames dropped (counted)            │ no: lower-priority transfers displaced,
//!        │ an unsent transfer of the same subject       │     or the new transfer refused (counted)
//!        └─ superseded (counted)                        ▼
//!  pop(now) ──► the in-progress transfer's next frame, else the first frame of the
//!               highest-priority, oldest transfer; a frame past its deadline is dropped (counted)
//! ```
//!
//! The rules are those of the Cyphal stacks (libcanard, canadensis), with two additions a motor
//! driver needs:
//! - **Priority, then FIFO.** A transfer of a higher priority leaves before any of a lower one;
//!   transfers of equal priority leave in the order they were pushed.
//! - **A started transfer is finished first.** Once the first frame of a multi-frame transfer has
//!   left, its remaining frames are next, in order, whatever is pushed meanwhile: a receiver never
//!   sees two of this node's transfers interleaved.
//! - **Deadlines.** Every frame carries its transfer's deadline; a frame popped after it is dropped
//!   and counted, never sent (so the rest of a transfer whose deadline passed is dropped too).
//! - **Supersede.** A new message on a subject replaces a queued transfer of that subject none of
//!   whose frames has left yet: a setpoint that waited is stale once a newer one exists.
//! - **Transfer-IDs of messages are taken as they leave.** [`TxQueue::pop_assigning`] gives a
//!   message transfer its ID when its first frame leaves (and the same ID to the rest of it), so a
//!   transfer that never left (superseded, expired, purged) leaves no gap in the sequence a
//!   receiver sees. A gap would be harmless but for one case: receivers deduplicate by transfer-ID
//!   (PyCyphal, libcanard: a start of transfer whose ID equals the last one taken, or the one
//!   after a transfer cut short, is a repeat), and a gap of a multiple of 32, or one less, lands
//!   exactly there. After a congested second a stop's zero setpoint was discarded so by PyCyphal
//!   (`host-cli/tests/pycyphal_congestion.rs`).
//! - **A full queue refuses, never blocks.** When a transfer does not fit, expired frames are
//!   dropped first, then queued transfers of strictly lower priority are displaced (newest first);
//!   if that is still not enough room the new transfer is refused and counted, and the queue is
//!   left as it was. A heartbeat is never stuck behind bulk traffic of lower priority.
//!
//! Storage is one fixed array of `N` frames, kept in sending order from the back: the next frame
//! to send is the last element, so popping is O(1) and pushing is one partition search and one
//! rotation, O(N). Nothing allocates.

use crate::can::{
    Frame, FrameSplitter, Mtu, Priority, SubjectId, TransferHeader, TransferKind, TxError,
};
use crate::time::Instant;

/// Transmit-side counters. Frames and transfers are counted separately, as each field says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TxStats {
    /// Frames handed out to be sent.
    pub sent: u64,
    /// Frames dropped because their deadline had passed before they could leave.
    pub expired: u64,
    /// Transfers replaced by a newer message on the same subject before any of their frames left.
    pub superseded: u64,
    /// Transfers dropped from a full queue to make room for one of higher priority.
    pub displaced: u64,
    /// Transfers refused because the queue had no room for them.
    pub refused: u64,
    /// Frames dropped by [`TxQueue::purge`].
    pub purged: u64,
}

/// One queued frame and what the queue needs to know about its transfer.
#[derive(Clone, Debug)]
struct Entry {
    frame: Frame,
    deadline: Instant,
    priority: Priority,
    /// The subject of a message transfer (`None` for service transfers).
    subject: Option<SubjectId>,
    /// Position of this frame in its transfer, 0-based.
    index: u16,
    /// Frames in its transfer.
    frames: u16,
}

/// A fixed-capacity priority queue of outgoing frames with deadlines. See the module documentation.
#[derive(Debug)]
pub struct TxQueue<const N: usize> {
    /// Sending order from the back: `entries[len - 1]` leaves first. The last `pinned` entries are
    /// the remaining frames of the transfer in progress; before them, whole transfers sorted by
    /// priority level, non-increasing, newest first within a level.
    entries: heapless::Vec<Entry, N>,
    pinned: usize,
    /// The transfer-ID given to the message transfer in progress by [`TxQueue::pop_assigning`].
    pinned_transfer_id: Option<u8>,
    stats: TxStats,
}

impl<const N: usize> Default for TxQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> TxQueue<N> {
    /// An empty queue.
    pub const fn new() -> Self {
        TxQueue {
            entries: heapless::Vec::new(),
            pinned: 0,
            pinned_transfer_id: None,
            stats: TxStats {
                sent: 0,
                expired: 0,
                superseded: 0,
                displaced: 0,
                refused: 0,
                purged: 0,
            },
        }
    }

    /// Frames waiting.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True if no frame is waiting.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Frames the queue can hold.
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Counters so far.
    pub fn stats(&self) -> TxStats {
        self.stats
    }

    /// Frames of messages on `subject_id` waiting (including the rest of one in progress).
    pub fn pending_frames(&self, subject_id: SubjectId) -> usize {
        self.entries
            .iter()
            .filter(|e| e.subject == Some(subject_id))
            .count()
    }

    /// The earliest deadline among the waiting frames.
    pub fn earliest_deadline(&self) -> Option<Instant> {
        self.entries.iter().map(|e| e.deadline).min()
    }

    /// Drops every waiting frame, the rest of a transfer in progress included; returns how many.
    pub fn purge(&mut self) -> usize {
        let n = self.entries.len();
        self.entries.clear();
        self.pinned = 0;
        self.stats.purged += n as u64;
        n
    }

    /// Drops the rest of the transfer in progress (counted as expired): its deadline passed, or
    /// its first frame, popped, never reached the bus. Returns how many frames went.
    pub fn drop_in_progress(&mut self) -> usize {
        let n = self.pinned;
        self.entries.truncate(self.entries.len() - n);
        self.pinned = 0;
        self.stats.expired += n as u64;
        n
    }

    /// Frames `payload` for `header` at `mtu` and queues the frames, to leave by `deadline`.
    ///
    /// A message supersedes any queued, not yet started transfer on the same subject. Fails with
    /// [`TxError::QueueFull`] (counted in [`TxStats::refused`]) when there is no room even after
    /// dropping expired frames and displacing lower-priority transfers; the queue is then unchanged
    /// apart from the expired frames. Framing errors are returned as they are and not counted.
    pub fn push(
        &mut self,
        now: Instant,
        header: &TransferHeader,
        payload: &[u8],
        mtu: Mtu,
        deadline: Instant,
    ) -> Result<(), TxError> {
        let frames = FrameSplitter::new(header, payload, mtu, now)?;
        let n = frames.frame_count();
        if n > N || n > usize::from(u16::MAX) {
            self.stats.refused += 1;
            return Err(TxError::QueueFull);
        }
        let subject = match header.kind {
            TransferKind::Message { subject_id } => Some(subject_id),
            _ => None,
        };
        let level = header.priority.level();
        self.drop_expired(now);

        // What could go to make room: superseded transfers of this subject, then transfers of a
        // strictly lower priority from the back of the sending order (the newest lowest first).
        let open = self.entries.len() - self.pinned;
        let superseded_frames = match subject {
            Some(s) => self.entries[..open]
                .iter()
                .filter(|e| e.subject == Some(s))
                .count(),
            None => 0,
        };
        let mut free = N - self.entries.len() + superseded_frames;
        let mut displace_end = 0;
        while free < n && displace_end < open {
            let e = &self.entries[displace_end];
            if e.priority.level() <= level {
                break;
            }
            // `entries[displace_end]` is the last frame of a whole (not started) transfer.
            if e.subject.is_none() || e.subject != subject {
                free += usize::from(e.frames);
            }
            displace_end += usize::from(e.frames);
        }
        if free < n {
            self.stats.refused += 1;
            return Err(TxError::QueueFull);
        }
        if superseded_frames > 0 || displace_end > 0 {
            let mut i = 0;
            let (mut superseded, mut displaced) = (0, 0);
            self.entries.retain(|e| {
                let pos = i;
                i += 1;
                if pos >= open {
                    return true;
                }
                let ours = subject.is_some() && e.subject == subject;
                let gone = ours || pos < displace_end;
                if gone && e.index == 0 {
                    if ours {
                        superseded += 1;
                    } else {
                        displaced += 1;
                    }
                }
                !gone
            });
            self.stats.superseded += superseded;
            self.stats.displaced += displaced;
        }

        // Insert after every transfer of a lower priority (larger level) and before those of an
        // equal or higher one, which were pushed earlier or leave earlier.
        let open = self.entries.len() - self.pinned;
        let at = self.entries[..open].partition_point(|e| e.priority.level() > level);
        let start = self.entries.len();
        for (index, frame) in frames.enumerate() {
            // Room was made above; `index < n ≤ u16::MAX`.
            let _ = self.entries.push(Entry {
                frame,
                deadline,
                priority: header.priority,
                subject,
                index: index as u16,
                frames: n as u16,
            });
        }
        self.entries[start..].reverse();
        self.entries[at..].rotate_right(n);
        Ok(())
    }

    /// The next frame to send, stamped `now`, with the transfer-ID it was pushed with; frames
    /// whose deadline passed are dropped on the way.
    #[must_use]
    pub fn pop(&mut self, now: Instant) -> Option<Frame> {
        self.pop_inner(now, None)
    }

    /// As [`TxQueue::pop`], but a message transfer is given its transfer-ID as its first frame
    /// leaves, from `next_transfer_id(subject)` (called once per transfer that leaves); the rest
    /// of the transfer carries the same ID. Service transfers keep the ID they were pushed with.
    #[must_use]
    pub fn pop_assigning(
        &mut self,
        now: Instant,
        next_transfer_id: &mut dyn FnMut(SubjectId) -> u8,
    ) -> Option<Frame> {
        self.pop_inner(now, Some(next_transfer_id))
    }

    fn pop_inner(
        &mut self,
        now: Instant,
        mut next_transfer_id: Option<&mut dyn FnMut(SubjectId) -> u8>,
    ) -> Option<Frame> {
        while let Some(entry) = self.entries.pop() {
            let first = self.pinned == 0;
            if self.pinned > 0 {
                self.pinned -= 1;
            } else {
                // The first frame of the highest-priority transfer: the rest of it is next.
                self.pinned = usize::from(entry.frames - 1);
            }
            if now > entry.deadline {
                // The rest of its transfer shares the deadline: drop it too.
                self.stats.expired += 1;
                self.drop_in_progress();
                continue;
            }
            let mut frame = entry.frame;
            frame.timestamp = now;
            if first {
                self.pinned_transfer_id = match (entry.subject, next_transfer_id.as_mut()) {
                    (Some(subject), Some(next)) => Some(next(subject)),
                    _ => None,
                };
            }
            if let Some(tid) = self.pinned_transfer_id {
                frame.set_transfer_id(tid);
            }
            self.stats.sent += 1;
            return Some(frame);
        }
        None
    }

    /// Drops every frame whose deadline has passed.
    fn drop_expired(&mut self, now: Instant) {
        let before = self.entries.len();
        if self.pinned > 0 && self.entries.last().is_some_and(|e| now > e.deadline) {
            let len = self.entries.len() - self.pinned;
            self.entries.truncate(len);
            self.pinned = 0;
        }
        self.entries.retain(|e| now <= e.deadline);
        // Frames of one transfer share a deadline, so whole transfers went and `pinned` holds.
        self.stats.expired += (before - self.entries.len()) as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(subject_id: u16, priority: Priority, tid: u8) -> TransferHeader {
        TransferHeader {
            priority,
            kind: TransferKind::Message {
                subject_id: SubjectId::from_const(subject_id),
            },
            source: Some(crate::can::NodeId::from_const(10)),
            transfer_id: tid,
        }
    }

    fn at(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    /// (subject, first payload byte) of every frame popped at `now` until the queue is empty.
    fn drain<const N: usize>(q: &mut TxQueue<N>, now: Instant) -> heapless::Vec<(u16, u8), 64> {
        let mut out = heapless::Vec::new();
        while let Some(f) = q.pop(now) {
            out.push((((f.id() >> 8) & 0x1FFF) as u16, f.data()[0]))
                .unwrap();
        }
        out
    }

    #[test]
    fn priority_then_fifo() {
        let mut q = TxQueue::<16>::new();
        let d = at(100);
        q.push(at(0), &message(1, Priority::LOW, 0), &[1], Mtu::Classic, d)
            .unwrap();
        q.push(
            at(0),
            &message(2, Priority::NOMINAL, 0),
            &[2],
            Mtu::Classic,
            d,
        )
        .unwrap();
        q.push(at(0), &message(3, Priority::HIGH, 0), &[3], Mtu::Classic, d)
            .unwrap();
        q.push(
            at(0),
            &message(4, Priority::NOMINAL, 0),
            &[4],
            Mtu::Classic,
            d,
        )
        .unwrap();
        q.push(
            at(0),
            &message(5, Priority::EXCEPTIONAL, 0),
            &[5],
            Mtu::Classic,
            d,
        )
        .unwrap();
        assert_eq!(
            &drain(&mut q, at(1))[..],
            &[(5, 5), (3, 3), (2, 2), (4, 4), (1, 1)]
        );
        assert_eq!(q.stats().sent, 5);
    }

    #[test]
    fn a_started_transfer_is_never_interleaved() {
        let mut q = TxQueue::<16>::new();
        let payload: [u8; 22] = core::array::from_fn(|i| 100 + i as u8);
        // 22 bytes on Classic CAN: 24 stream bytes in 7-byte chunks → 4 frames.
        q.push(
            at(0),
            &message(7, Priority::LOW, 0),
            &payload,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert_eq!(q.len(), 4);
        let first = q.pop(at(1)).unwrap();
        assert_eq!(first.data()[0], 100);
        // A higher-priority transfer arrives after the first frame left: it waits.
        q.push(
            at(1),
            &message(8, Priority::EXCEPTIONAL, 0),
            &[9],
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert_eq!(
            &drain(&mut q, at(2))[..],
            &[(7, 107), (7, 114), (7, 121), (8, 9)]
        );
        // Before it starts, a multi-frame transfer yields to a higher priority as a whole.
        q.push(
            at(3),
            &message(7, Priority::LOW, 1),
            &payload,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        q.push(
            at(3),
            &message(8, Priority::HIGH, 1),
            &payload,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert_eq!(
            &drain(&mut q, at(4))[..],
            &[
                (8, 100),
                (8, 107),
                (8, 114),
                (8, 121),
                (7, 100),
                (7, 107),
                (7, 114),
                (7, 121)
            ]
        );
    }

    #[test]
    fn expired_frames_are_dropped_and_counted() {
        let mut q = TxQueue::<16>::new();
        let payload = [0u8; 20];
        q.push(
            at(0),
            &message(1, Priority::NOMINAL, 0),
            &payload,
            Mtu::Classic,
            at(10),
        )
        .unwrap();
        q.push(
            at(0),
            &message(2, Priority::NOMINAL, 0),
            &[2],
            Mtu::Classic,
            at(20),
        )
        .unwrap();
        // At the deadline itself a frame still leaves.
        assert!(q.pop(at(10)).is_some());
        // After it, the rest of that transfer is dropped, never sent.
        assert_eq!(&drain(&mut q, at(11))[..], &[(2, 2)]);
        assert_eq!(q.stats().expired, 3);
        assert_eq!(q.stats().sent, 2);
        // Expired frames are also dropped when a push looks for room.
        q.push(
            at(0),
            &message(3, Priority::NOMINAL, 0),
            &[3],
            Mtu::Classic,
            at(5),
        )
        .unwrap();
        q.push(
            at(6),
            &message(4, Priority::NOMINAL, 0),
            &[4],
            Mtu::Classic,
            at(50),
        )
        .unwrap();
        assert_eq!(q.len(), 1);
        assert_eq!(q.stats().expired, 4);
    }

    #[test]
    fn a_newer_message_supersedes_an_unsent_one() {
        let mut q = TxQueue::<32>::new();
        let old = [1u8; 22];
        let new = [2u8; 22];
        q.push(
            at(0),
            &message(24, Priority::HIGH, 0),
            &old,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        q.push(
            at(0),
            &message(9, Priority::HIGH, 0),
            &[9],
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        q.push(
            at(1),
            &message(24, Priority::HIGH, 1),
            &new,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert_eq!(q.stats().superseded, 1);
        assert_eq!(q.pending_frames(SubjectId::from_const(24)), 4);
        // The superseded transfer is gone; the other subject keeps its place ahead of the new one.
        assert_eq!(
            &drain(&mut q, at(2))[..],
            &[(9, 9), (24, 2), (24, 2), (24, 2), (24, 2)]
        );
        // Once a transfer has started it is finished, not superseded.
        q.push(
            at(3),
            &message(24, Priority::HIGH, 2),
            &old,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert!(q.pop(at(3)).is_some());
        q.push(
            at(3),
            &message(24, Priority::HIGH, 3),
            &new,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert_eq!(q.stats().superseded, 1);
        assert_eq!(
            &drain(&mut q, at(4))[..],
            &[
                (24, 1),
                (24, 1),
                (24, 1),
                (24, 2),
                (24, 2),
                (24, 2),
                (24, 2)
            ]
        );
    }

    #[test]
    fn a_full_queue_refuses_and_counts() {
        let mut q = TxQueue::<6>::new();
        let four = [0u8; 22];
        q.push(
            at(0),
            &message(1, Priority::HIGH, 0),
            &four,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        // 4 + 4 > 6: refused, the queue unchanged.
        assert_eq!(
            q.push(
                at(0),
                &message(2, Priority::HIGH, 0),
                &four,
                Mtu::Classic,
                at(100)
            ),
            Err(TxError::QueueFull)
        );
        // Larger than the whole queue: refused.
        assert_eq!(
            q.push(
                at(0),
                &message(3, Priority::EXCEPTIONAL, 0),
                &[0; 60],
                Mtu::Classic,
                at(100)
            ),
            Err(TxError::QueueFull)
        );
        assert_eq!(q.stats().refused, 2);
        assert_eq!(q.len(), 4);
        // Lower-priority transfers make room for a higher one, newest first; equal ones do not.
        let mut q = TxQueue::<6>::new();
        q.push(
            at(0),
            &message(1, Priority::LOW, 0),
            &[1],
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        q.push(
            at(0),
            &message(2, Priority::SLOW, 0),
            &[2],
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        q.push(
            at(0),
            &message(3, Priority::LOW, 0),
            &four,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        q.push(
            at(0),
            &message(4, Priority::NOMINAL, 0),
            &four,
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert_eq!(q.stats().displaced, 2);
        assert_eq!(
            q.push(
                at(0),
                &message(5, Priority::NOMINAL, 0),
                &[5; 8],
                Mtu::Classic,
                at(100)
            ),
            Ok(())
        );
        assert_eq!(q.stats().displaced, 3);
        assert_eq!(
            q.push(
                at(0),
                &message(6, Priority::NOMINAL, 0),
                &[6],
                Mtu::Classic,
                at(100)
            ),
            Err(TxError::QueueFull)
        );
        assert_eq!(q.stats().refused, 1);
        assert_eq!(
            &drain(&mut q, at(1))[..],
            &[(4, 0), (4, 0), (4, 0), (4, 0), (5, 5), (5, 5)]
        );
    }

    #[test]
    fn purge_drops_everything_including_a_started_transfer() {
        let mut q = TxQueue::<16>::new();
        q.push(
            at(0),
            &message(1, Priority::LOW, 0),
            &[0; 20],
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        q.push(
            at(0),
            &message(2, Priority::LOW, 0),
            &[2],
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert!(q.pop(at(0)).is_some());
        assert_eq!(q.purge(), 4);
        assert!(q.is_empty());
        assert_eq!(q.stats().purged, 4);
        // The next transfer starts cleanly.
        q.push(
            at(1),
            &message(3, Priority::HIGH, 0),
            &[3],
            Mtu::Classic,
            at(100),
        )
        .unwrap();
        assert_eq!(&drain(&mut q, at(1))[..], &[(3, 3)]);
        assert_eq!(q.earliest_deadline(), None);
    }
}
