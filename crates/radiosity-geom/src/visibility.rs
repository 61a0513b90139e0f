//! visibility placeholder
