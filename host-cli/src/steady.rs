//! Steady-state (plateau) analysis of the drag law (not yet implemented).
