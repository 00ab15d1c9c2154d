//! Cross-crate integration tests live in `tests/tests/`.
#![deny(missing_docs)]
