//! Tests of the montecarlo backend.
