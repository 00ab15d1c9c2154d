//! Opening a CAN bus from a PyCyphal-style interface string.
//!
//! `UAVCAN__CAN__IFACE` (or `--iface`): `socketcan:can0` or `slcan:/dev/ttyACM0@115200`;
//! `UAVCAN__CAN__BITRATE` ("1000000" or "1000000 4000000"); `UAVCAN__CAN__MTU` (8 or 64).

use propid_transport::{parse_bitrate, CanTransport, IfaceSpec};

use crate::InputError;

/// Which bus, as PyCyphal's registers (or the same flags) say: shared by `drive` and `sim-drive`.
#[derive(clap::Args, Debug, Clone)]
pub struct BusArgs {
    /// CAN interface: `socketcan:can0` or `slcan:/dev/ttyACM0@115200` (uavcan.can.iface).
    #[arg(long, env = "UAVCAN__CAN__IFACE")]
    pub iface: Option<String>,
    /// Frame size: 8 (Classic CAN) or 64 (CAN FD) (uavcan.can.mtu).
    #[arg(long, env = "UAVCAN__CAN__MTU", default_value_t = 8)]
    pub mtu: usize,
    /// Bit rate(s), "ARBITRATION [DATA]" (uavcan.can.bitrate).
    #[arg(long, env = "UAVCAN__CAN__BITRATE", default_value = "1000000")]
    pub bitrate: String,
}

impl BusArgs {
    /// Opens the bus these arguments name.
    pub fn open(&self) -> anyhow::Result<Box<dyn CanTransport>> {
        let iface = self.iface.as_deref().ok_or_else(|| {
            InputError::invalid("no interface: give --iface or UAVCAN__CAN__IFACE".into())
        })?;
        open(iface, &self.bitrate, self.mtu)
    }
}

/// Opens the interface. SLCAN is Classic CAN only: MTU 64 is refused before anything is sent.
pub fn open(iface: &str, bitrate: &str, mtu: usize) -> anyhow::Result<Box<dyn CanTransport>> {
    let spec = IfaceSpec::parse(iface).map_err(|e| InputError::invalid(e.to_string()))?;
    let (arbitration, _data) =
        parse_bitrate(bitrate).map_err(|e| InputError::invalid(e.to_string()))?;
    if mtu != 8 && mtu != 64 {
        return Err(InputError::invalid(format!(
            "MTU must be 8 (Classic CAN) or 64 (CAN FD), got {mtu}"
        ))
        .into());
    }
    Ok(match spec {
        IfaceSpec::Slcan { path, baud } => {
            if mtu != 8 {
                return Err(InputError::invalid(format!(
                    "{iface}: SLCAN carries Classic CAN only; set UAVCAN__CAN__MTU=8 (got {mtu})"
                ))
                .into());
            }
            Box::new(propid_slcan::SlcanTransport::open(
                &path,
                baud,
                arbitration,
            )?)
        }
        IfaceSpec::SocketCan { name } => open_socketcan(iface, &name, mtu)?,
    })
}

#[cfg(target_os = "linux")]
fn open_socketcan(_iface: &str, name: &str, mtu: usize) -> anyhow::Result<Box<dyn CanTransport>> {
    Ok(Box::new(propid_socketcan::SocketCanTransport::open(
        name, mtu,
    )?))
}

#[cfg(not(target_os = "linux"))]
fn open_socketcan(iface: &str, _name: &str, _mtu: usize) -> anyhow::Result<Box<dyn CanTransport>> {
    Err(InputError::invalid(format!(
        "{iface}: socketcan is only available on Linux; use an SLCAN adapter (slcan:DEVICE[@BAUD])"
    ))
    .into())
}
