//! Shooting on the hierarchy: the unshot radiosity kept on the nodes of a tree and shot
//! through each node's own links ([`radiosity_core::LinkSource`]), at their cost, not a
//! column's `O(n)`: the pipeline of charges, shots, pushes and pulls with its bound
//! (`pipeline`), the groups a pull solves (`groups`), and the solvers (`node_shooting`).

pub(crate) mod groups;
pub(crate) mod node_shooting;
pub(crate) mod pipeline;
