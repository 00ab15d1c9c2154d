//! The tail byte: the last data byte of every Cyphal/CAN frame.
//!
//! `start[7] end[6] toggle[5] transfer_id[4:0]`. The toggle is 1 in the first frame of a
//! transfer and alternates; a single-frame transfer therefore has the tail `0xE0 | tid`.

/// A parsed tail byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TailByte {
    /// First frame of the transfer.
    pub start: bool,
    /// Last frame of the transfer.
    pub end: bool,
    /// Alternates from frame to frame, starting at 1.
    pub toggle: bool,
    /// Transfer-ID modulo 32.
    pub transfer_id: u8,
}

impl TailByte {
    /// Parses a tail byte.
    pub const fn parse(b: u8) -> TailByte {
        TailByte {
            start: b & 0x80 != 0,
            end: b & 0x40 != 0,
            toggle: b & 0x20 != 0,
            transfer_id: b & 0x1F,
        }
    }

    /// Emits the byte.
    pub const fn emit(&self) -> u8 {
        (self.start as u8) << 7
            | (self.end as u8) << 6
            | (self.toggle as u8) << 5
            | (self.transfer_id & 0x1F)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_emit() {
        let t = TailByte::parse(0xE7);
        assert!(t.start && t.end && t.toggle);
        assert_eq!(t.transfer_id, 7);
        assert_eq!(t.emit(), 0xE7);
        let t = TailByte::parse(0x05);
        assert!(!t.start && !t.end && !t.toggle);
        assert_eq!(t.emit(), 0x05);
    }
}
