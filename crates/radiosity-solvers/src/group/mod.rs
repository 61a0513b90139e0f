//! Group solvers: the group shooting step ([`group_step`]) and the solvers built on it, group
//! shooting ([`group_shooting`]) and group-accelerated shooting, the paper's method
//! ([`group_accelerated`]), with the solvers' column [`memory`]; and group gathering
//! ([`group_gathering`]), which builds on point gathering's update instead.

pub(crate) mod group_accelerated;
pub(crate) mod group_gathering;
pub(crate) mod group_shooting;
pub(crate) mod group_step;
pub(crate) mod memory;
