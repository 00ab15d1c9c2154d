//! Placeholder until the reassembly benchmark lands.
fn main() {}
