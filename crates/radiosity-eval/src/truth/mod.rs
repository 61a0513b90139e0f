//! A truth of the continuous problem: each object's mean radiosity by Monte Carlo path
//! tracing ([`path_trace`]), and those means beside the discrete reference at increasing mesh
//! resolution ([`validate`]), which tells discretization error from solver error.

pub(crate) mod operator_distance;
pub(crate) mod path_trace;
pub(crate) mod validate;
