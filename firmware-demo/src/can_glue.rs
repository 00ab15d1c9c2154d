//! How a real firmware wires the core's Sans-IO node to a CAN peripheral through the
//! `embedded_can` traits: frames the node wants sent go to `transmit`, frames the peripheral
//! received go to `handle_frame`. `LoopbackCan` stands in for a HAL's CAN driver under QEMU.

use embedded_can::nb::Can;
use embedded_can::{ExtendedId, Frame as _, Id};
use propid_core::can::Frame;
use propid_core::node::{Event, Node};
use propid_core::time::Instant;

/// Moves frames between a node and any `embedded_can::nb::Can` peripheral. Returns the number
/// of frames transmitted and calls `on_event` for what the node received.
pub fn pump<C, const P: usize, const S: usize, const E: usize, const Q: usize>(
    node: &mut Node<P, S, E, Q>,
    can: &mut C,
    now: Instant,
    mut on_event: impl FnMut(Event<'_>),
) -> usize
where
    C: Can,
{
    let mut sent = 0;
    while let Some(frame) = node.poll_transmit(now) {
        let Some(id) = ExtendedId::new(frame.id()) else { continue };
        let Some(hw) = C::Frame::new(id, frame.data()) else { continue };
        // A full mailbox drops the frame here; a real driver would retry on the next interrupt.
        if can.transmit(&hw).is_ok() {
            sent += 1;
        }
    }
    while let Ok(hw) = can.receive() {
        let Id::Extended(id) = hw.id() else { continue };
        if let Some(frame) = Frame::new(now, id.as_raw(), hw.data()) {
            if let Some(e) = node.handle_frame(now, &frame) {
                on_event(e);
            }
        }
    }
    sent
}

/// A CAN "peripheral" with a fixed transmit FIFO and nothing to receive: what the demo has instead
/// of a bus. It counts what would have gone out.
pub struct LoopbackCan {
    /// Frames accepted for transmission.
    pub transmitted: u32,
    /// Bytes of data accepted.
    pub bytes: u32,
}

/// `LoopbackCan` never fails.
#[derive(Debug)]
pub struct NoError;

impl embedded_can::Error for NoError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl Can for LoopbackCan {
    type Frame = Frame;
    type Error = NoError;

    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, NoError> {
        self.transmitted += 1;
        self.bytes += frame.data().len() as u32;
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<Frame, NoError> {
        Err(nb::Error::WouldBlock)
    }
}
