//! The mechanical load model shared by the host simulator and the firmware demo.
