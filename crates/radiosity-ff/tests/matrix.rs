//! Tests of the matrix backend.
