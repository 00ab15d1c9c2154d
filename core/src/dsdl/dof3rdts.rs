//! `zubax.physics.dynamics.DoF3rdTs.1.0`: the drive's timestamped dynamics feedback (sealed,
//! 23 bytes): a `zubax.Timestamp` then position, velocity, acceleration and force.

use super::{BitReader, BitWriter, DataType, DecodeError};

/// `zubax.Timestamp.1.0`: `truncated uint53 microsecond`, `void3` (7 bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Timestamp {
    /// Microseconds on the publisher's clock; 0 means unknown. Serialization keeps the low 53
    /// bits (truncated cast).
    pub microsecond: u64,
}

impl Timestamp {
    /// The reserved value meaning "time unknown".
    pub const UNKNOWN: u64 = 0;
}

/// `zubax.physics.kinematics.DoF2nd.1.0`: position and velocity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DoF2ndKinematics {
    /// [m] or [rad].
    pub position: f32,
    /// [m/s] or [rad/s].
    pub velocity: f32,
}

/// `zubax.physics.kinematics.DoF3rd.1.0`: position, velocity and acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DoF3rdKinematics {
    /// Position and velocity.
    pub base: DoF2ndKinematics,
    /// [m/s²] or [rad/s²].
    pub acceleration: f32,
}

/// `zubax.physics.dynamics.DoF3rd.1.0`: kinematics plus force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DoF3rdDynamics {
    /// Position, velocity, acceleration.
    pub kinematics: DoF3rdKinematics,
    /// [N] or [N·m].
    pub force: f32,
}

/// `zubax.physics.dynamics.DoF3rdTs.1.0`: what a Telega publishes as its dynamics feedback.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DoF3rdTs {
    /// When the state was sampled, on the drive's clock.
    pub timestamp: Timestamp,
    /// The state.
    pub value: DoF3rdDynamics,
}

impl DataType for DoF3rdTs {
    const EXTENT_BYTES: usize = 23;
    const MAX_SIZE_BYTES: usize = 23;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        w.write_uint(self.timestamp.microsecond, 53);
        w.skip(3);
        let v = &self.value;
        w.write_f32(v.kinematics.base.position);
        w.write_f32(v.kinematics.base.velocity);
        w.write_f32(v.kinematics.acceleration);
        w.write_f32(v.force);
        Self::MAX_SIZE_BYTES
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let microsecond = r.read_uint(53);
        r.skip(3);
        let position = r.read_f32();
        let velocity = r.read_f32();
        let acceleration = r.read_f32();
        let force = r.read_f32();
        Ok(DoF3rdTs {
            timestamp: Timestamp { microsecond },
            value: DoF3rdDynamics {
                kinematics: DoF3rdKinematics {
                    base: DoF2ndKinematics { position, velocity },
                    acceleration,
                },
                force,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // From the PyCyphal vector "dof3rdts typical".
    const TYPICAL: [u8; 23] = [
        0xcb, 0x04, 0xfb, 0x71, 0x1f, 0x01, 0x00, 0x00, 0x00, 0xc0, 0x3f, 0x00, 0x00, 0x80, 0xbe,
        0x0a, 0xe8, 0x1c, 0x41, 0x00, 0x00, 0xc8, 0x42,
    ];

    #[test]
    fn parse_emit() {
        let m = DoF3rdTs::deserialize(&TYPICAL).unwrap();
        assert_eq!(m.timestamp.microsecond, 1_234_567_890_123);
        assert_eq!(m.value.kinematics.base.position, 1.5);
        assert_eq!(m.value.kinematics.base.velocity, -0.25);
        assert_eq!(m.value.force, 100.0);
        let mut buf = [0u8; 23];
        assert_eq!(m.serialize(&mut buf), 23);
        assert_eq!(buf, TYPICAL);
    }

    #[test]
    fn timestamp_truncates_to_53_bits_and_void_is_zero() {
        let m = DoF3rdTs {
            timestamp: Timestamp {
                microsecond: (1 << 53) + 5,
            },
            ..Default::default()
        };
        let mut buf = [0xFFu8; 23];
        m.serialize(&mut buf);
        assert_eq!(&buf[..7], &[5, 0, 0, 0, 0, 0, 0]);
        // Void bits set on the wire are ignored.
        let mut wire = buf;
        wire[6] = 0xE0;
        assert_eq!(
            DoF3rdTs::deserialize(&wire).unwrap().timestamp.microsecond,
            5
        );
    }
}
