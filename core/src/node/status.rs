//! What a node's heartbeat says about it: `uavcan.node.Health.1.0` and `uavcan.node.Mode.1.0` as
//! types, so a value outside the 2-bit and 3-bit fields cannot be set.

use crate::dsdl::Heartbeat;

/// `uavcan.node.Health.1.0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Health {
    /// All is well.
    Nominal = Heartbeat::HEALTH_NOMINAL,
    /// A minor problem; the node still performs its function.
    Advisory = Heartbeat::HEALTH_ADVISORY,
    /// Degraded.
    Caution = Heartbeat::HEALTH_CAUTION,
    /// Cannot perform its function.
    Warning = Heartbeat::HEALTH_WARNING,
}

/// `uavcan.node.Mode.1.0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Mode {
    /// Normal operation.
    Operational = Heartbeat::MODE_OPERATIONAL,
    /// Starting up.
    Initialization = Heartbeat::MODE_INITIALIZATION,
    /// Under maintenance.
    Maintenance = Heartbeat::MODE_MAINTENANCE,
    /// Being updated.
    SoftwareUpdate = Heartbeat::MODE_SOFTWARE_UPDATE,
}

impl Health {
    /// The health a heartbeat reports (`None` for a value outside 0..=3).
    pub fn from_value(value: u8) -> Option<Health> {
        [
            Health::Nominal,
            Health::Advisory,
            Health::Caution,
            Health::Warning,
        ]
        .into_iter()
        .find(|h| *h as u8 == value)
    }
}

impl Mode {
    /// The mode a heartbeat reports (`None` for a value the DSDL does not define).
    pub fn from_value(value: u8) -> Option<Mode> {
        [
            Mode::Operational,
            Mode::Initialization,
            Mode::Maintenance,
            Mode::SoftwareUpdate,
        ]
        .into_iter()
        .find(|m| *m as u8 == value)
    }
}
