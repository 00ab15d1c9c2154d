//! Helpers shared by the integration tests.

pub mod register_json;
