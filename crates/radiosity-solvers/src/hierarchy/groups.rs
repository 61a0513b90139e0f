//! Groups for the node shooters: what a pull brings into a group of patches is solved with the
//! group's own exchanges, as the paper's group step does, before it is shot.
//!
//! At a pull the residual `t` is explicit at every patch (`pipeline`). For a group `G`, the
//! pull takes `s_G = (I − ρ F_GG)⁻¹ t_G` instead of `t_G`, and leaves `z_G = t_G − s_G =
//! −ρ F_GG s_G`: the light the group's internal links will bring back when its nodes shoot,
//! taken off in advance. So the group's interreflections are solved at once, and what leaves
//! the group carries all its bounces (Rousselle & Renaud §3.2, with `Φ_rr = I − ρ F_GG`).
//! A group whose system is not a nonsingular M-matrix, or whose condition number exceeds
//! [`CONDITION_LIMIT`], takes `t_G` (a fallback, counted).
//!
//! Three ways to choose groups:
//!
//! - **clusters** (`groups=clusters`): the tree's clusters of at most `g` patches whose
//!   parents hold more, each with an internal exchange (a block of `F` not all zero); their
//!   systems are solved once, at the start, and every pull applies them all;
//! - **spatial** (`groups=spatial`): runs of `g` patches in the problem's spatially coherent
//!   order ([`Problem::patch_order`]), solved once like the clusters. The tree's clusters face
//!   one way (the tree splits orientation classes first), so they hold little exchange; runs
//!   of the spatial order hold corners, boxes and furniture, whose faces see each other;
//! - **unshot** (`groups=unshot`, the paper's rule, §3.3): at every pull, the `g` patches with
//!   the most residual power `Σ_c A_i |t_ic|`, their block read from the links (or from `g`
//!   columns over one level) and solved then.

use crate::group::group_step::CONDITION_LIMIT;
use crate::hierarchy::pipeline::Pipeline;
use crate::run::problem::Problem;
use radiosity_core::dense_lu::{lu_solve_columns, m_matrix_condition};
use radiosity_core::{NO_PARENT, Real};

/// How a node shooter groups patches at a pull (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grouping {
    /// No groups: a pull takes `t`.
    None,
    /// The tree's clusters of at most `size` patches.
    Clusters {
        /// The largest cluster.
        size: usize,
    },
    /// Runs of `size` patches in the problem's spatially coherent order
    /// ([`Problem::patch_order`]).
    Spatial {
        /// The run's length.
        size: usize,
    },
    /// The `size` patches with the most residual power at every pull (the paper's rule).
    Unshot {
        /// The group's size.
        size: usize,
    },
}

/// A group's patches and, per channel, the inverse of its system (row-major).
#[derive(Debug)]
struct Solved {
    patches: Vec<usize>,
    inverse: Vec<Vec<Real>>,
}

/// The groups of a run and what they did.
#[derive(Debug, Default)]
pub(crate) struct Groups {
    /// The clusters or runs solved at the start.
    solved: Vec<Solved>,
    /// Group solves applied, and those that fell back to `t`.
    pub(crate) solves: u64,
    pub(crate) fallbacks: u64,
    /// Patches in the clusters or runs solved at the start.
    pub(crate) clustered: usize,
}

impl Groups {
    /// The groups `grouping` asks for; for clusters and runs, their systems solved.
    pub(crate) fn prepare(problem: &Problem<'_>, pipeline: &Pipeline, grouping: Grouping, channels: usize) -> Groups {
        let mut groups = Groups::default();
        let members = match grouping {
            Grouping::None | Grouping::Unshot { .. } => return groups,
            Grouping::Clusters { size } => clusters(problem, pipeline, size),
            // Without an order there are no runs (the solver refuses such a problem first).
            Grouping::Spatial { size } => match problem.patch_order() {
                Some(order) => order.chunks(size).map(<[usize]>::to_vec).collect(),
                None => return groups,
            },
        };
        for patches in members.into_iter().filter(|m| m.len() > 1) {
            let block = block(problem, &patches);
            if block.iter().all(|v| *v == 0.0) {
                continue;
            }
            if let Some(inverse) = inverses(problem, &patches, &block, channels) {
                groups.clustered += patches.len();
                groups.solved.push(Solved { patches, inverse });
            } else {
                groups.fallbacks += 1;
            }
        }
        groups
    }

    /// The amount a pull takes for the residual `t`: `t`, with each group's part solved
    /// (module doc).
    pub(crate) fn relax(&mut self, problem: &Problem<'_>, grouping: Grouping, t: &[Real], s: &mut Vec<Real>) {
        s.clear();
        s.extend_from_slice(t);
        let k = problem.channels();
        match grouping {
            Grouping::None => {}
            Grouping::Clusters { .. } | Grouping::Spatial { .. } => {
                for group in &self.solved {
                    apply(group, t, s, k);
                }
                self.solves += self.solved.len() as u64;
            }
            Grouping::Unshot { size } => {
                let area = problem.system().areas();
                let power = |i: usize| area[i] * t[i * k..(i + 1) * k].iter().map(|v| v.abs()).sum::<Real>();
                let mut order: Vec<usize> = (0..problem.n()).filter(|&i| power(i) > 0.0).collect();
                if order.len() < 2 {
                    return;
                }
                let size = size.min(order.len());
                order.select_nth_unstable_by(size - 1, |&a, &b| power(b).total_cmp(&power(a)).then(a.cmp(&b)));
                let mut patches = order[..size].to_vec();
                patches.sort_unstable();
                let block = block(problem, &patches);
                match inverses(problem, &patches, &block, k) {
                    Some(inverse) => {
                        apply(&Solved { patches, inverse }, t, s, k);
                        self.solves += 1;
                    }
                    None => self.fallbacks += 1,
                }
            }
        }
    }
}

/// The tree's clusters of at most `size` patches whose parents hold more: each patch's is the
/// first node up its path that is one.
fn clusters(problem: &Problem<'_>, pipeline: &Pipeline, size: usize) -> Vec<Vec<usize>> {
    let (parents, sizes) = (pipeline.parents(), pipeline.sizes());
    let cut = |node: usize| {
        sizes[node] <= size && sizes[node] > 1 && (parents[node] == NO_PARENT || sizes[parents[node] as usize] > size)
    };
    // Each patch's cluster: the first node up its path that is in the cut.
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); pipeline.nodes()];
    let leaves = problem.link_source().map(|l| l.leaves().to_vec()).unwrap_or_default();
    for (p, &leaf) in leaves.iter().enumerate() {
        let mut node = leaf;
        while node != NO_PARENT {
            if cut(node as usize) {
                members[node as usize].push(p);
                break;
            }
            node = parents[node as usize];
        }
    }
    members
}

/// `F` between `patches`, row-major: from the links, or from their columns over one level.
fn block(problem: &Problem<'_>, patches: &[usize]) -> Vec<Real> {
    let m = patches.len();
    let mut block = vec![0.0; m * m];
    if problem.through_links(0, |l| l.block(patches, &mut block)).is_none() {
        let mut column = vec![0.0; problem.n()];
        for (b, &j) in patches.iter().enumerate() {
            problem.column(j, &mut column);
            for (a, &i) in patches.iter().enumerate() {
                block[a * m + b] = column[i];
            }
        }
    }
    block
}

/// Per channel, `(I − ρ F_GG)⁻¹`, or `None` when a channel's system is not a nonsingular
/// M-matrix or is conditioned worse than [`CONDITION_LIMIT`].
fn inverses(problem: &Problem<'_>, patches: &[usize], block: &[Real], k: usize) -> Option<Vec<Vec<Real>>> {
    let m = patches.len();
    let system = problem.system();
    (0..k)
        .map(|c| {
            let n: Vec<Real> = (0..m * m).map(|ab| system.rho(patches[ab / m], c) * block[ab]).collect();
            // The unit vectors and, for the condition number, the ones: one factorisation.
            let mut rhs: Vec<Vec<Real>> = (0..m).map(|b| (0..m).map(|a| Real::from(a == b)).collect()).collect();
            rhs.push(vec![1.0; m]);
            let phi = |a: usize, b: usize| Real::from(a == b) - n[a * m + b];
            let solved = lu_solve_columns(m, false, phi, &rhs).ok()?;
            let condition = m_matrix_condition(m, &n, &solved[m])?;
            if condition > CONDITION_LIMIT {
                return None;
            }
            let mut inverse = vec![0.0; m * m];
            for (b, y) in solved[..m].iter().enumerate() {
                for a in 0..m {
                    inverse[a * m + b] = y[a];
                }
            }
            Some(inverse)
        })
        .collect()
}

/// `s_G = (I − ρ F_GG)⁻¹ t_G`.
fn apply(group: &Solved, t: &[Real], s: &mut [Real], k: usize) {
    let m = group.patches.len();
    for c in 0..k {
        let inverse = &group.inverse[c];
        for (a, &i) in group.patches.iter().enumerate() {
            s[i * k + c] = (0..m).map(|b| inverse[a * m + b] * t[group.patches[b] * k + c]).sum();
        }
    }
}
