//! analysis placeholder
