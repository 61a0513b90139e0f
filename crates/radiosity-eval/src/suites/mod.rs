//! Suites that run many cases through the lab and write what they found: the stress suite
//! (every solver on every backend over stiff and extreme scenes, judged by certified bounds)
//! and the bench (columns per second, matrix assembly, group solves, time and memory to
//! accuracy, the cost of a column as scenes grow).

pub mod bench;
pub mod stress;
