//! Tests of the hemicube backend.
