//! Form factors: kernels and backends (analytic, hemicube, Monte Carlo, stored matrix) that
//! implement [`radiosity_core::ColumnSource`]. Not implemented yet; this crate is the only one
//! that will turn geometry into form factors.
