//! Placeholder until the estimator benchmark lands.
fn main() {}
