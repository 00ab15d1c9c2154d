use crate::time::Instant;

/// Longest CAN FD data field, in bytes.
pub const MAX_DATA_LEN: usize = 64;

/// One CAN frame with an extended (29-bit) identifier, Classic (≤ 8 bytes) or FD (≤ 64 bytes),
/// stamped with the time the caller received it (or, for frames to send, the time it was made).
#[derive(Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// When the frame was received (receive side) or produced (transmit side).
    pub timestamp: Instant,
    id: u32,
    len: u8,
    data: [u8; MAX_DATA_LEN],
}

impl Frame {
    /// A frame with a 29-bit extended ID. `None` if the ID has more than 29 bits or the data
    /// is longer than [`MAX_DATA_LEN`].
    pub fn new(timestamp: Instant, id: u32, data: &[u8]) -> Option<Self> {
        if id > 0x1FFF_FFFF || data.len() > MAX_DATA_LEN {
            return None;
        }
        let mut buf = [0u8; MAX_DATA_LEN];
        buf[..data.len()].copy_from_slice(data);
        Some(Frame {
            timestamp,
            id,
            len: data.len() as u8,
            data: buf,
        })
    }

    /// The 29-bit extended CAN ID.
    pub fn id(&self) -> u32 {
        self.id
    }

    /// The data bytes (the Cyphal tail byte is the last one).
    pub fn data(&self) -> &[u8] {
        &self.data[..usize::from(self.len)]
    }

    /// Rewrites the transfer-ID in the Cyphal tail byte (its low five bits; `tid` is taken modulo
    /// 32). The transfer CRC covers the payload only, so a multi-frame transfer stays valid when
    /// every one of its frames is given the same new ID. Does nothing to a frame without data.
    pub(crate) fn set_transfer_id(&mut self, tid: u8) {
        if let Some(tail) = self.data[..usize::from(self.len)].last_mut() {
            *tail = (*tail & !0x1F) | (tid & 0x1F);
        }
    }

    /// True if the frame does not fit Classic CAN (more than 8 data bytes).
    pub fn is_fd(&self) -> bool {
        self.len > 8
    }
}

impl core::fmt::Debug for Frame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Frame({:08X}#", self.id)?;
        for b in self.data() {
            write!(f, "{b:02X}")?;
        }
        write!(f, " @{}us)", self.timestamp.as_micros())
    }
}

impl embedded_can::Frame for Frame {
    fn new(id: impl Into<embedded_can::Id>, data: &[u8]) -> Option<Self> {
        match id.into() {
            embedded_can::Id::Extended(id) => Frame::new(Instant::ZERO, id.as_raw(), data),
            // Cyphal/CAN uses extended IDs only.
            embedded_can::Id::Standard(_) => None,
        }
    }

    fn new_remote(_id: impl Into<embedded_can::Id>, _dlc: usize) -> Option<Self> {
        // Cyphal never uses remote frames.
        None
    }

    fn is_extended(&self) -> bool {
        true
    }

    fn is_remote_frame(&self) -> bool {
        false
    }

    fn id(&self) -> embedded_can::Id {
        // `new` guarantees the ID fits 29 bits.
        embedded_can::Id::Extended(
            embedded_can::ExtendedId::new(self.id).unwrap_or(embedded_can::ExtendedId::ZERO),
        )
    }

    fn dlc(&self) -> usize {
        usize::from(self.len)
    }

    fn data(&self) -> &[u8] {
        Frame::data(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_oversized() {
        assert!(Frame::new(Instant::ZERO, 0x2000_0000, &[]).is_none());
        assert!(Frame::new(Instant::ZERO, 1, &[0; 65]).is_none());
        let f = Frame::new(Instant::ZERO, 0x1060642A, &[3, 0xE0]).unwrap();
        assert_eq!(f.data(), &[3, 0xE0]);
        assert!(!f.is_fd());
        assert_eq!(embedded_can::Frame::dlc(&f), 2);
    }
}
