//! A Sans-IO Cyphal node.
