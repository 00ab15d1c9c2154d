//! Fixed-memory incremental least squares for the load's inertia and drag.
