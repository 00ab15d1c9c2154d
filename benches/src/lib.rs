//! Benchmarks live in `benches/benches/`.
#![deny(missing_docs)]
