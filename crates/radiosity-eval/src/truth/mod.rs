//! Truths to measure against: each object's mean radiosity by Monte Carlo path tracing
//! ([`path_trace`]), those means beside the discrete reference at increasing mesh resolution
//! ([`validate`]), which tells discretization error from solver error, and a fast form-factor
//! operator against a trusted one by their systems' exact solutions ([`operator_distance`]).

pub(crate) mod operator_distance;
pub(crate) mod path_trace;
pub(crate) mod validate;
