//! Placeholder until the dsdl benchmark lands.
fn main() {}
