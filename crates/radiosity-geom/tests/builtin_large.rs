//! Tests: builtin_large.
