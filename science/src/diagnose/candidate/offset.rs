//! `force_offset`: the reported force reads F₀ when no torque acts (a current-sense or load-cell
//! zero). Regressor −1: on a rotor that never reverses, the same column as a Coulomb friction.

use super::torque_term::TorqueTerm;
use super::{BaseTerm, Shape};

/// See the module documentation.
pub(crate) const FORCE_OFFSET: TorqueTerm = TorqueTerm {
    name: "force_offset",
    unit: "N·m",
    column: |_| -1.0,
    design: |_| 1.0,
    positive: false,
    shape: Shape::Constant { odd: false },
    base_term: |_| BaseTerm::None,
    explanation: |value| {
        format!("the reported force reads {value:+.3e} N·m when no torque acts (a current-sense or load-cell zero offset)")
    },
};
