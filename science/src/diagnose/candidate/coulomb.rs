//! `coulomb_friction`: a constant torque opposing rotation (bearings, seals, cogging's mean, or a
//! torque estimate's offset on a rotor that reverses). Regressor −sgn ω.

use super::torque_term::TorqueTerm;
use super::{BaseTerm, Shape};

/// See the module documentation.
pub(crate) const COULOMB_FRICTION: TorqueTerm = TorqueTerm {
    name: "coulomb_friction",
    unit: "N·m",
    column: |at| -at.sgn,
    design: f64::signum,
    positive: true,
    shape: Shape::Constant { odd: true },
    base_term: |_| BaseTerm::None,
    explanation: |value| {
        format!("a constant torque of {value:.3e} N·m opposes rotation (bearing or cogging friction, or a torque-estimate offset)")
    },
};
