//! The CAN bus, as PyCyphal's registers name it: `uavcan.can.iface` (`socketcan:can0` or
//! `slcan:/dev/ttyACM0@115200`), `uavcan.can.mtu` (8 or 64), `uavcan.can.bitrate` ("1000000" or
//! "1000000 4000000") — each also a flag and an environment variable (`UAVCAN__CAN__IFACE`, …).
//! Shared by `drive`, `sim-drive` and `telega`.

use propid_core::can::Mtu;
use propid_transport::{parse_bitrate, CanTransport, IfaceSpec};

use crate::settings::{command_args, setting, ConfigErrors, Names, Problem, Setting};

setting! {
    /// The CAN interface.
    Iface: IfaceSpec = Names::register("iface", "uavcan.can.iface", "UAVCAN__CAN__IFACE"),
        "CAN interface: `socketcan:can0` or `slcan:/dev/ttyACM0@115200`",
        |text: &str| IfaceSpec::parse(text).map_err(|error| Problem::Iface {
            text: text.to_string(),
            error,
        });
    /// The frame size.
    FrameSize: Mtu = Names::register("mtu", "uavcan.can.mtu", "UAVCAN__CAN__MTU"),
        "Frame size: 8 (Classic CAN) or 64 (CAN FD) [default: 8]",
        crate::settings::mtu;
    /// The bit rates.
    Bitrate: (u32, u32) = Names::register("bitrate", "uavcan.can.bitrate", "UAVCAN__CAN__BITRATE"),
        "Bit rate(s), \"ARBITRATION [DATA]\" [default: 1000000]",
        |text: &str| parse_bitrate(text).map_err(Problem::Bitrate);
}

command_args! {
    /// Which bus, as given (flags, then the environment, then a register file).
    #[derive(Default)]
    pub struct BusArgs {
        settings {
            iface: Iface as "IFACE",
            mtu: FrameSize as "BYTES",
            bitrate: Bitrate as "BIT/S",
        }
        registers {}
        nested {}
    }
}

/// The bus, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Bus {
    /// The interface.
    pub iface: IfaceSpec,
    /// The frame size.
    pub mtu: Mtu,
    /// Arbitration and data bit rates [bit/s].
    pub bitrate: (u32, u32),
}

impl Bus {
    /// The bus `raw` names; what is wrong goes to `errors` (all of it).
    pub fn check(raw: BusArgs, errors: &mut ConfigErrors) -> Option<Bus> {
        let BusArgs {
            iface,
            mtu,
            bitrate,
        } = raw;
        let mtu_origin = mtu.as_ref().map(|g| g.origin.clone());
        let iface = errors.required(iface);
        let mtu = errors.or(mtu, Mtu::Classic);
        let bitrate = errors.or(bitrate, (1_000_000, 1_000_000));
        let (iface, mtu, bitrate) = (iface?, mtu?, bitrate?);
        if matches!(iface, IfaceSpec::Slcan { .. }) && mtu != Mtu::Classic {
            errors.setting(
                <FrameSize as Setting>::NAMES,
                mtu_origin,
                Problem::Conflict("SLCAN carries Classic CAN only: set it to 8".into()),
            );
            return None;
        }
        Some(Bus {
            iface,
            mtu,
            bitrate,
        })
    }

    /// Opens the bus. An operating system's refusal is said once, with the path and what fixes
    /// it.
    pub fn open(&self) -> anyhow::Result<Box<dyn CanTransport>> {
        Ok(match &self.iface {
            IfaceSpec::Slcan { path, baud } => Box::new(propid_slcan::SlcanTransport::open(
                path,
                *baud,
                self.bitrate.0,
            )?),
            IfaceSpec::SocketCan { name } => open_socketcan(name, self.mtu)?,
        })
    }
}

#[cfg(target_os = "linux")]
fn open_socketcan(name: &str, mtu: Mtu) -> anyhow::Result<Box<dyn CanTransport>> {
    Ok(Box::new(propid_socketcan::SocketCanTransport::open(
        name,
        mtu.bytes(),
    )?))
}

#[cfg(not(target_os = "linux"))]
fn open_socketcan(name: &str, _mtu: Mtu) -> anyhow::Result<Box<dyn CanTransport>> {
    Err(crate::InputError::invalid(format!(
        "socketcan:{name}: socketcan is only available on Linux; use an SLCAN adapter (slcan:DEVICE[@BAUD])"
    ))
    .into())
}
