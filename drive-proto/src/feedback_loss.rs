//! Feedback lost on its way, as the receiver can tell it: from gaps in the publisher's
//! transfer-IDs and in the drive's own timestamps.
//!
//! ```text
//!  DoF3rdTs (transfer-ID, drive timestamp) ─► LossCounter::observe
//!    transfer-ID gap (mod 32)      lost between the publisher's queue and propid: on the bus, in
//!                                  the adapter, the kernel or the host's reader (a publisher that
//!                                  numbers transfers as they leave, as propid's nodes do, leaves
//!                                  no gap for what it dropped itself)
//!    timestamp gap / its interval  lost anywhere, the drive's own queue included (needs the
//!                                  drive's local timestamps; 0 = unknown is skipped)
//! ```
//! The interval is the median of the last few timestamp steps, so a drive whose publication
//! interval is changed mid-run (`mns.pub_interval_min`) is followed within a few messages.

/// Feedback transfers lost, counted two ways (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FeedbackLoss {
    /// Missing transfer-IDs (modulo 32: a gap of 32 or more consecutive transfers is undercounted).
    pub by_transfer_id: u64,
    /// Missing publication instants by the drive's own clock.
    pub by_timestamp: u64,
}

impl FeedbackLoss {
    /// The larger of the two counts: what is known to be lost at least.
    pub fn lost(&self) -> u64 {
        self.by_transfer_id.max(self.by_timestamp)
    }
}

/// Timestamp steps kept for the interval's median.
const STEPS: usize = 15;
/// Modulo of Cyphal/CAN transfer-IDs.
const TRANSFER_ID_MODULO: u16 = 32;

/// Counts the gaps in one publisher's feedback stream.
#[derive(Clone, Debug, Default)]
pub struct LossCounter {
    last_transfer_id: Option<u8>,
    last_timestamp: Option<u64>,
    steps: [u64; STEPS],
    filled: usize,
    next: usize,
    loss: FeedbackLoss,
}

impl LossCounter {
    /// A counter that has seen nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// One received transfer: its transfer-ID and the drive's timestamp [µs] (0: unknown).
    pub fn observe(&mut self, transfer_id: u8, timestamp_us: u64) {
        if let Some(last) = self.last_transfer_id {
            let step = (u16::from(transfer_id) + TRANSFER_ID_MODULO - u16::from(last))
                % TRANSFER_ID_MODULO;
            // 0: a repeat (deduplicated upstream; not a loss).
            self.loss.by_transfer_id += u64::from(step.saturating_sub(1));
        }
        self.last_transfer_id = Some(transfer_id);
        if timestamp_us == 0 {
            return;
        }
        if let Some(last) = self.last_timestamp.filter(|l| timestamp_us > *l) {
            let step = timestamp_us - last;
            if let Some(interval) = self.interval() {
                // A step of k intervals (±½) lost k − 1 messages.
                let k = (step + interval / 2) / interval;
                self.loss.by_timestamp += k.saturating_sub(1);
            }
            self.steps[self.next] = step;
            self.next = (self.next + 1) % STEPS;
            self.filled = (self.filled + 1).min(STEPS);
        }
        self.last_timestamp = Some(timestamp_us);
    }

    /// The publication interval [µs]: the median of the recent timestamp steps (after three).
    fn interval(&self) -> Option<u64> {
        if self.filled < 3 {
            return None;
        }
        let mut s = self.steps;
        let s = &mut s[..self.filled];
        s.sort_unstable();
        Some(s[s.len() / 2]).filter(|i| *i > 0)
    }

    /// What was counted so far.
    pub fn loss(&self) -> FeedbackLoss {
        self.loss
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_in_transfer_ids_and_timestamps_are_counted() {
        let mut c = LossCounter::new();
        // Every 2 ms, transfer-IDs wrapping at 32; messages 10, 11 and 40 lost.
        for k in 0u64..100 {
            if [10, 11, 40].contains(&k) {
                continue;
            }
            c.observe((k % 32) as u8, 1_000 + k * 2_000 + (k % 3) * 40);
        }
        assert_eq!(
            c.loss(),
            FeedbackLoss {
                by_transfer_id: 3,
                by_timestamp: 3
            }
        );
        // The interval changes to 5 ms: once the median has moved (8 of 15 steps), no more
        // steps are counted as loss.
        let mut c2 = c.clone();
        let mut ts = 1_000 + 99 * 2_000;
        let mut counts = Vec::new();
        for k in 100u64..140 {
            ts += 5_000;
            c2.observe((k % 32) as u8, ts);
            counts.push(c2.loss().by_timestamp);
        }
        assert_eq!(
            counts[8..].iter().min(),
            counts[8..].iter().max(),
            "{counts:?}"
        );
        assert_eq!(c2.loss().by_transfer_id, 3);
        // Unknown timestamps (0) are skipped; transfer-IDs still count.
        let mut c3 = LossCounter::new();
        for tid in [0u8, 1, 2, 5, 6] {
            c3.observe(tid, 0);
        }
        assert_eq!(c3.loss().by_transfer_id, 2);
        assert_eq!(c3.loss().by_timestamp, 0);
        assert_eq!(c3.loss().lost(), 2);
    }
}
