//! Cyphal/CAN: the CAN ID layout, the tail byte, transmit framing and receive reassembly.
//!
//! ## One transfer, both ways
//! ```text
//!  transmit: TransferHeader + payload ──► FrameSplitter ──► Frame, Frame, … (tail byte, CRC, FD padding)
//!  receive:  Frame (+ timestamp) ──► CanId::parse ──► TailByte ──► Reassembler ──► Transfer { header, payload }
//! ```
//! - [`CanId`]: the 29-bit identifier: priority, message or service, port-ID, node-IDs.
//! - [`NodeId`] (0..=127), [`SubjectId`] (0..=8191), [`ServiceId`] (0..=511): IDs as types, made
//!   once where a number enters (`TryFrom`, `FromStr` with a message naming the range); nothing
//!   past that point checks a range again.
//! - [`TailByte`]: the last data byte of every frame: start, end, toggle, transfer-ID.
//! - [`FrameSplitter`]: an iterator of frames for one transfer, Classic CAN (MTU 8) or CAN FD
//!   (MTU 64); multi-frame transfers carry a CRC-16/CCITT-FALSE, big-endian, after the padding.
//! - [`Reassembler`]: fixed-capacity receive state: subscriptions, per-source sessions, transfer-ID
//!   de-duplication. It never allocates; every rejected frame is a typed [`RxError`].
//!
//! A [`Frame`] implements [`embedded_can::Frame`], so it moves between this crate, the transports
//! and any HAL without conversion glue.

mod frame;
mod id;
mod ids;
mod rx;
mod tail;
mod tx;

pub use frame::{Frame, MAX_DATA_LEN};
pub use id::{CanId, Priority};
pub use ids::{IdError, IdKind, NodeId, ServiceId, SubjectId};
pub use rx::{Reassembler, RxError, RxStats, Subscription, Transfer};
pub use tail::TailByte;
pub use tx::{FrameSplitter, TxError};

/// CRC-16/CCITT-FALSE as Cyphal/CAN uses it for multi-frame transfers.
pub const TRANSFER_CRC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);

/// Default transfer-ID timeout (the Cyphal specification's recommended 2 s).
pub const DEFAULT_TRANSFER_ID_TIMEOUT: core::time::Duration = core::time::Duration::from_secs(2);

/// The maximum transmission unit: data bytes per frame, tail byte included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mtu {
    /// Classic CAN: 8 bytes.
    Classic,
    /// CAN FD: 64 bytes.
    Fd,
}

impl Mtu {
    /// Data bytes per frame, tail byte included.
    pub const fn bytes(self) -> usize {
        match self {
            Mtu::Classic => 8,
            Mtu::Fd => 64,
        }
    }

    /// The MTU for a byte count (8 → Classic, 64 → FD).
    pub fn from_bytes(n: usize) -> Option<Mtu> {
        match n {
            8 => Some(Mtu::Classic),
            64 => Some(Mtu::Fd),
            _ => None,
        }
    }
}

/// What a transfer is and where it goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TransferKind {
    /// A message on a subject (broadcast).
    Message {
        /// Subject-ID.
        subject_id: SubjectId,
    },
    /// A service request to `destination`.
    Request {
        /// Service-ID.
        service_id: ServiceId,
        /// Server node-ID.
        destination: NodeId,
    },
    /// A service response to `destination`.
    Response {
        /// Service-ID.
        service_id: ServiceId,
        /// Client node-ID.
        destination: NodeId,
    },
}

impl TransferKind {
    /// The port this transfer travels on.
    pub fn port(&self) -> Port {
        match *self {
            TransferKind::Message { subject_id } => Port::Subject(subject_id),
            TransferKind::Request { service_id, .. } => Port::Request(service_id),
            TransferKind::Response { service_id, .. } => Port::Response(service_id),
        }
    }
}

/// A port a receiver can subscribe to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Port {
    /// Messages on a subject-ID.
    Subject(SubjectId),
    /// Requests to this node on a service-ID.
    Request(ServiceId),
    /// Responses to this node on a service-ID.
    Response(ServiceId),
}

/// Everything about a transfer except its payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransferHeader {
    /// Priority (0 = exceptional … 7 = optional).
    pub priority: Priority,
    /// Message, request or response, with its port and destination.
    pub kind: TransferKind,
    /// Source node-ID; `None` for anonymous messages.
    pub source: Option<NodeId>,
    /// Transfer-ID modulo 32.
    pub transfer_id: u8,
}

/// The valid CAN FD data lengths; Cyphal pads frames with zeros up to the next one.
const FD_LENGTHS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// The smallest valid CAN FD data length ≥ `n` (`n` ≤ 64).
pub fn fd_length_at_least(n: usize) -> usize {
    FD_LENGTHS.iter().copied().find(|&l| l >= n).unwrap_or(64)
}
