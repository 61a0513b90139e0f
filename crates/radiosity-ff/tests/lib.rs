//! Integration tests of radiosity-ff: backends against closed forms, closure, reciprocity,
//! determinism and the guard rails.

mod allocation;
mod analytic;
mod closed_forms;
mod distributed;
mod hemicube;
mod hierarchical;
mod matrix;
mod montecarlo;
mod nodal;
mod pair_visibility;
mod scale;
mod scene_transport;
mod shared_checks;
