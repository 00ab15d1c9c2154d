//! `viscous_friction`: a torque ∝ ω opposing rotation (the seed's c1, which its defaults force to
//! zero). Regressor −ω.

use super::torque_term::TorqueTerm;
use super::{BaseTerm, Shape};

/// See the module documentation.
pub(crate) const VISCOUS_FRICTION: TorqueTerm = TorqueTerm {
    name: "viscous_friction",
    unit: "N·m·s/rad",
    column: |at| -at.omega,
    design: |w| w,
    positive: true,
    shape: Shape::SpeedLaw,
    base_term: BaseTerm::C1,
    explanation: |value| {
        format!("a torque of {value:.3e} N·m per rad/s opposes rotation (viscous friction; the seed's c1, which its defaults force to zero)")
    },
};
