//! Radiosity solvers (gathering, shooting, overshooting, group and group-accelerated), generic
//! over [`radiosity_core::ColumnSource`]. Not implemented yet; this crate depends on
//! `radiosity-core` only and is tested on small in-memory matrices.
