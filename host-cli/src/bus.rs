//! Opening a CAN bus from a PyCyphal-style interface string (not yet implemented).
