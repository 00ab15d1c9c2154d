//! Transmit framing: one transfer in, its frames out, without allocation.
//!
//! A payload of at most MTU − 1 bytes is one frame: payload, zero padding up to a valid CAN FD
//! length, tail byte (no CRC). A longer payload is split into frames of MTU − 1 bytes plus a
//! tail; the byte stream is `payload ‖ padding ‖ CRC-16 (big-endian)`, where the padding (CAN FD
//! only) makes the last frame a valid FD length and is covered by the CRC.

use super::{fd_length_at_least, CanId, Frame, Mtu, TransferHeader, TransferKind, TRANSFER_CRC};
use crate::time::Instant;

/// Why a transfer cannot be framed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TxError {
    /// Anonymous transfers must fit one frame.
    AnonymousMultiFrame,
    /// Anonymous service transfers do not exist.
    AnonymousService,
    /// The transmit queue is full.
    QueueFull,
    /// Every port slot of the node is taken (transfer-ID counters or response subscriptions).
    TooManyPorts,
}

impl core::fmt::Display for TxError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            TxError::AnonymousMultiFrame => "anonymous transfers must fit in one frame",
            TxError::AnonymousService => "service transfers cannot be anonymous",
            TxError::QueueFull => "the transmit queue is full",
            TxError::TooManyPorts => "every port slot of the node is taken",
        })
    }
}

/// Stream length of a multi-frame transfer before padding: payload and CRC.
fn unpadded_len(payload_len: usize) -> usize {
    payload_len + 2
}

/// An iterator over the frames of one transfer.
pub struct FrameSplitter<'a> {
    can_id: u32,
    timestamp: Instant,
    payload: &'a [u8],
    padding: usize,
    crc: [u8; 2],
    /// Bytes of the stream (payload, padding, CRC) per frame.
    chunk: usize,
    /// Total stream length; equals the payload length for single-frame transfers.
    stream_len: usize,
    /// Frames not yet produced.
    remaining: usize,
    offset: usize,
    toggle: bool,
    transfer_id: u8,
}

impl<'a> FrameSplitter<'a> {
    /// Frames `payload` for `header` at the given MTU; `timestamp` is stamped on every frame.
    pub fn new(
        header: &TransferHeader,
        payload: &'a [u8],
        mtu: Mtu,
        timestamp: Instant,
    ) -> Result<Self, TxError> {
        let chunk = mtu.bytes() - 1;
        let single_frame = payload.len() <= chunk;
        if header.source.is_none() {
            if !matches!(header.kind, TransferKind::Message { .. }) {
                return Err(TxError::AnonymousService);
            }
            if !single_frame {
                return Err(TxError::AnonymousMultiFrame);
            }
        }
        let pseudo_id = payload.iter().fold(0u8, |a, b| a.wrapping_add(*b)) & 0x7F;
        let can_id = CanId {
            priority: header.priority,
            kind: header.kind,
            source: header.source,
        }
        .emit(pseudo_id)
        .ok_or(TxError::AnonymousService)?;
        let (padding, stream_len, crc) = if single_frame {
            let padding = match mtu {
                Mtu::Classic => 0,
                Mtu::Fd => fd_length_at_least(payload.len() + 1) - (payload.len() + 1),
            };
            (padding, payload.len() + padding, [0; 2])
        } else {
            let unpadded = unpadded_len(payload.len());
            let frames = unpadded.div_ceil(chunk);
            let last = unpadded - chunk * (frames - 1);
            let padding = fd_length_at_least(last + 1) - (last + 1);
            let mut digest = TRANSFER_CRC.digest();
            digest.update(payload);
            for _ in 0..padding {
                digest.update(&[0]);
            }
            (padding, unpadded + padding, digest.finalize().to_be_bytes())
        };
        Ok(FrameSplitter {
            can_id,
            timestamp,
            payload,
            padding,
            crc,
            chunk,
            stream_len,
            remaining: if single_frame {
                1
            } else {
                (unpadded_len(payload.len()) + padding).div_ceil(chunk)
            },
            offset: 0,
            toggle: true,
            transfer_id: header.transfer_id & 0x1F,
        })
    }

    /// The number of frames this transfer takes.
    pub fn frame_count(&self) -> usize {
        self.remaining
    }

    /// The byte at `i` of the stream payload ‖ padding ‖ CRC.
    fn stream_byte(&self, i: usize) -> u8 {
        let p = self.payload.len();
        if i < p {
            self.payload[i]
        } else if i < p + self.padding {
            0
        } else {
            self.crc[i - p - self.padding]
        }
    }
}

impl Iterator for FrameSplitter<'_> {
    type Item = Frame;

    fn next(&mut self) -> Option<Frame> {
        if self.remaining == 0 {
            return None;
        }
        let n = (self.stream_len - self.offset).min(self.chunk);
        let mut data = [0u8; 64];
        for (k, d) in data.iter_mut().enumerate().take(n) {
            *d = self.stream_byte(self.offset + k);
        }
        let start = self.offset == 0;
        self.offset += n;
        self.remaining -= 1;
        data[n] = super::TailByte {
            start,
            end: self.remaining == 0,
            toggle: self.toggle,
            transfer_id: self.transfer_id,
        }
        .emit();
        self.toggle = !self.toggle;
        Frame::new(self.timestamp, self.can_id, &data[..=n])
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.remaining, Some(self.remaining))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::can::Priority;

    fn header(subject_id: u16, tid: u8) -> TransferHeader {
        TransferHeader {
            priority: Priority::NOMINAL,
            kind: TransferKind::Message {
                subject_id: crate::can::SubjectId::from_const(subject_id),
            },
            source: Some(crate::can::NodeId::from_const(42)),
            transfer_id: tid,
        }
    }

    #[test]
    fn single_frame_readiness() {
        let frames: heapless::Vec<Frame, 4> =
            FrameSplitter::new(&header(100, 0), &[3], Mtu::Classic, Instant::ZERO)
                .unwrap()
                .collect();
        assert_eq!(frames.len(), 1);
        assert_eq!(frames[0].id(), 0x1060_642A);
        assert_eq!(frames[0].data(), &[0x03, 0xE0]);
    }

    #[test]
    fn empty_payload_is_one_tail_byte() {
        let frames: heapless::Vec<Frame, 4> =
            FrameSplitter::new(&header(1, 7), &[], Mtu::Fd, Instant::ZERO)
                .unwrap()
                .collect();
        assert_eq!(frames.len(), 1);
        assert_eq!(frames[0].data(), &[0xE7]);
    }

    #[test]
    fn fd_single_frame_pads_before_the_tail() {
        let payload = [1u8, 2, 3, 4, 5, 6, 7, 8];
        let frames: heapless::Vec<Frame, 4> =
            FrameSplitter::new(&header(1, 1), &payload, Mtu::Fd, Instant::ZERO)
                .unwrap()
                .collect();
        assert_eq!(frames[0].data(), &[1, 2, 3, 4, 5, 6, 7, 8, 0, 0, 0, 0xE1]);
    }

    #[test]
    fn multi_frame_classic_has_crc_and_toggles() {
        // 8 bytes on Classic CAN: 7 + (1 + CRC 2) → 2 frames.
        let payload = [0u8, 1, 2, 3, 4, 5, 6, 7];
        let s = FrameSplitter::new(&header(1, 3), &payload, Mtu::Classic, Instant::ZERO).unwrap();
        assert_eq!(s.frame_count(), 2);
        let frames: heapless::Vec<Frame, 4> = s.collect();
        let crc = TRANSFER_CRC.checksum(&payload).to_be_bytes();
        assert_eq!(frames[0].data(), &[0, 1, 2, 3, 4, 5, 6, 0xA3]);
        assert_eq!(frames[1].data(), &[7, crc[0], crc[1], 0x43]);
    }

    #[test]
    fn anonymous_rules() {
        let mut h = header(1, 0);
        h.source = None;
        assert_eq!(
            FrameSplitter::new(&h, &[0; 8], Mtu::Classic, Instant::ZERO).err(),
            Some(TxError::AnonymousMultiFrame)
        );
        let f = FrameSplitter::new(&h, &[0x55], Mtu::Classic, Instant::ZERO)
            .unwrap()
            .next()
            .unwrap();
        assert_eq!(f.id() & 0x7F, 0x55);
        assert_ne!(f.id() & (1 << 24), 0);
    }
}
