//! `uavcan.node.ExecuteCommand.1.3` (fixed service 435): restart, store, factory reset, ….
//!
//! Both sections are delimited (not sealed): request extent 300 bytes (at most 258 used),
//! response extent 48 (at most 48). Versions 1.1 and 1.2 have the same request layout; their
//! response lacks `output`, which reads as empty here (implicit zero extension).

use super::register::read_length;
use super::{BitReader, BitWriter, DataType, DecodeError};

/// The fixed service-ID of `uavcan.node.ExecuteCommand`.
pub const EXECUTE_COMMAND_SERVICE_ID: u16 = 435;

/// `uavcan.node.ExecuteCommand.1.3` request.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExecuteCommandRequest {
    /// A standard command (`COMMAND_*`, 65529..=65535) or a vendor one (0..=32767).
    pub command: u16,
    /// Command-specific text (a file path for a software update), at most 255 bytes.
    pub parameter: heapless::Vec<u8, 255>,
}

impl ExecuteCommandRequest {
    /// Reboot the node.
    pub const COMMAND_RESTART: u16 = 65535;
    /// Shut down.
    pub const COMMAND_POWER_OFF: u16 = 65534;
    /// Begin a software update from the file named by `parameter`.
    pub const COMMAND_BEGIN_SOFTWARE_UPDATE: u16 = 65533;
    /// Return the configuration to factory defaults.
    pub const COMMAND_FACTORY_RESET: u16 = 65532;
    /// Cease activity immediately, enter a safe state.
    pub const COMMAND_EMERGENCY_STOP: u16 = 65531;
    /// Store the persistent registers to non-volatile memory.
    pub const COMMAND_STORE_PERSISTENT_STATES: u16 = 65530;
    /// Identify physically (blink, beep).
    pub const COMMAND_IDENTIFY: u16 = 65529;
}

impl DataType for ExecuteCommandRequest {
    const EXTENT_BYTES: usize = 300;
    const MAX_SIZE_BYTES: usize = 258;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        w.write_uint(u64::from(self.command), 16);
        w.write_uint(self.parameter.len() as u64, 8);
        w.write_bytes(&self.parameter);
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let command = r.read_uint(16) as u16;
        let n = read_length(&mut r, 8, 255)?;
        let mut parameter = heapless::Vec::new();
        for _ in 0..n {
            let _ = parameter.push(r.read_uint(8) as u8);
        }
        Ok(ExecuteCommandRequest { command, parameter })
    }
}

/// `uavcan.node.ExecuteCommand.1.3` response.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExecuteCommandResponse {
    /// `STATUS_*`.
    pub status: u8,
    /// Command-specific output, at most 46 bytes (standard commands leave it empty).
    pub output: heapless::Vec<u8, 46>,
}

impl ExecuteCommandResponse {
    /// Started or executed.
    pub const STATUS_SUCCESS: u8 = 0;
    /// Could not start, or the outcome was not reached.
    pub const STATUS_FAILURE: u8 = 1;
    /// Denied.
    pub const STATUS_NOT_AUTHORIZED: u8 = 2;
    /// Unknown or unsupported command.
    pub const STATUS_BAD_COMMAND: u8 = 3;
    /// The parameter cannot be used with this command.
    pub const STATUS_BAD_PARAMETER: u8 = 4;
    /// Not now.
    pub const STATUS_BAD_STATE: u8 = 5;
    /// An unexpected failure.
    pub const STATUS_INTERNAL_ERROR: u8 = 6;

    /// A response with `status` and no output.
    pub fn status(status: u8) -> Self {
        ExecuteCommandResponse {
            status,
            output: heapless::Vec::new(),
        }
    }
}

impl DataType for ExecuteCommandResponse {
    const EXTENT_BYTES: usize = 48;
    const MAX_SIZE_BYTES: usize = 48;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        w.write_uint(u64::from(self.status), 8);
        w.write_uint(self.output.len() as u64, 8);
        w.write_bytes(&self.output);
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let status = r.read_uint(8) as u8;
        let n = read_length(&mut r, 8, 46)?;
        let mut output = heapless::Vec::new();
        for _ in 0..n {
            let _ = output.push(r.read_uint(8) as u8);
        }
        Ok(ExecuteCommandResponse { status, output })
    }
}
