//! The Cyphal node type the host's machines are built on, and two facts about frames they read.

use propid_core::can::Frame;
use propid_core::node::{Node, Registry};

/// Register slots of the host nodes.
pub const HOST_REGISTERS: usize = 32;

/// The registers of a host node.
pub type HostRegistry = Registry<HOST_REGISTERS>;

/// The node type of the host tools: 8 ports, 16 sessions, 515-byte transfers (a whole
/// `uavcan.register.Access` request), 256 queued frames, [`HOST_REGISTERS`] registers.
pub type HostNode = Node<8, 16, 515, 256, HOST_REGISTERS>;

/// Whether `frame` ends a transfer (its tail byte's end-of-transfer bit).
pub(crate) fn ends_transfer(frame: &Frame) -> bool {
    frame.data().last().is_some_and(|t| t & 0x40 != 0)
}

/// The subject-ID of a message frame (`None` for a service frame).
pub(crate) fn subject_of(frame: &Frame) -> Option<u16> {
    let id = frame.id();
    // Bit 25: service; bits 8..=20: subject-ID.
    (id & (1 << 25) == 0).then_some(((id >> 8) & 0x1FFF) as u16)
}
