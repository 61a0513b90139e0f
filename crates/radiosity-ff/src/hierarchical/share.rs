//! The refinement cut into tasks from its top: dealt to the ranks by their estimated cost, each
//! refined by the one rank it is dealt to, and within a rank (or one process, rank 0 of 1)
//! shared by its threads.
//!
//! The refinement is a tree of tasks: the links within a node (its children's, and those
//! between its two children) and the links between two nodes (settled, or split into two such
//! tasks). Every rank expands the top of that tree the same way, to the same **frontier** of
//! tasks with at most `limit` patches each (the links settled on the way are rank 0's, and so
//! are the rays traced for them, although every rank traces them), then deals the frontier to
//! the ranks, largest estimated cost first, each task to the rank with the least so far
//! (Graham's LPT rule). Every rank builds the same tree and makes the same decisions, so no
//! geometry is sent; a pair of patches belongs to exactly one task, so each link is built by
//! exactly one rank, the same link the single process builds (the tasks refine exactly as the
//! single process does, segments inherited from split links included).
//!
//! A task's cost is estimated by its patches: the links within a node grow about linearly with
//! its patches, and a pair of nodes still on the frontier is a pair of neighbours, whose links
//! grow with the patches near their contact. [`TASKS_PER_RANK`] tasks a rank (the default) keep the deal
//! balanced where the estimate is off (docs/distributed.md measures the balance).
//!
//! ## References
//!
//! - R. Graham, "Bounds on multiprocessing timing anomalies", SIAM J. Appl. Math. 17(2), 1969.
//! - J. Singh, A. Gupta, M. Levoy, "Parallel visualization algorithms: performance and
//!   architectural implications", IEEE Computer 27(7), 1994 (hierarchical radiosity's
//!   parallel refinement by tasks on interactions).

use super::links::{Links, Refiner, Segment, Split, Watch};
use super::shaft::ROOT;
use super::tree::ClusterTree;
use crate::hierarchical::BuildProgress;
use rayon::prelude::*;

/// Tasks the frontier is cut into for each rank, by default: more balance the deal better where
/// the estimate is off, at the cost of a deeper frontier, which every rank expands.
pub const TASKS_PER_RANK: usize = 32;

/// A piece of the refinement.
pub(super) enum Task {
    /// The links within a node.
    Within(u32),
    /// The links between two disjoint nodes, with the segments they inherit and where their
    /// shafts' patches may be.
    Between { a: u32, b: u32, traced: Vec<Segment>, candidates: Vec<u32> },
}

impl Task {
    /// The patches the task covers.
    fn patches(&self, tree: &ClusterTree) -> u32 {
        match self {
            Task::Within(k) => tree.nodes[*k as usize].count,
            Task::Between { a, b, .. } => tree.nodes[*a as usize].count + tree.nodes[*b as usize].count,
        }
    }

    /// The pairs of patches the task settles.
    fn pairs(&self, tree: &ClusterTree) -> u64 {
        match self {
            Task::Within(k) => {
                let c = u64::from(tree.nodes[*k as usize].count);
                c * c.saturating_sub(1) / 2
            }
            Task::Between { a, b, .. } => {
                u64::from(tree.nodes[*a as usize].count) * u64::from(tree.nodes[*b as usize].count)
            }
        }
    }
}

/// What one rank of `ranks` refines.
pub(super) struct Share {
    /// The links this rank built.
    pub links: Links,
    /// The tasks of the frontier dealt to this rank.
    pub tasks: usize,
    /// This rank's estimated cost, as a share of the whole (`1 / ranks` when balanced).
    pub estimated: f64,
    /// Seconds spent expanding the frontier.
    pub frontier: f64,
}

impl Refiner<'_> {
    /// The links of rank `rank` of `ranks` (module doc), about `tasks_per_rank` tasks a rank,
    /// its progress reported to `observe` over its own pairs of patches.
    pub(super) fn refine_share(
        &self,
        (rank, ranks): (usize, usize),
        tasks_per_rank: usize,
        observe: &(dyn Fn(BuildProgress) + Sync),
    ) -> Share {
        let start = std::time::Instant::now();
        let n = self.tree.nodes[ROOT as usize].count as usize;
        let limit = ((n / (ranks * tasks_per_rank.max(1))) as u32).max(1);
        let mut settled = Links::default();
        let tasks = self.watched(Watch::new(n, &|_| {})).frontier(limit, &mut settled);
        let (owner, load) = deal(&tasks, self.tree, ranks);
        let frontier = start.elapsed().as_secs_f64();
        let total: u64 = load.iter().sum();
        let estimated = if total > 0 { load[rank] as f64 / total as f64 } else { 0.0 };
        let mut mine: Vec<Task> = tasks.into_iter().zip(&owner).filter(|(_, o)| **o == rank).map(|(t, _)| t).collect();
        // The largest first, so that the threads do not end waiting on one large task.
        mine.sort_by_key(|t| std::cmp::Reverse(t.patches(self.tree)));
        let own_pairs: u64 = mine.iter().map(|t| t.pairs(self.tree)).sum();
        let count = mine.len();
        let watched = self.watched(Watch::over(own_pairs, observe));
        // Each thread refines task after task into links of its own (the lists built from
        // them are sorted, so which thread gathered a link changes nothing), then they are
        // joined: a few joins, not one a task.
        let mut links = mine
            .into_par_iter()
            .fold(Links::default, |mut out, task| {
                match task {
                    Task::Within(k) => watched.refine_self(k, &mut out),
                    Task::Between { a, b, traced, candidates } => {
                        watched.refine_pair(a, b, traced, &candidates, &mut out)
                    }
                }
                // A task settles fewer pairs than a thousandth of the rank's: reported as it ends,
                // or the rank's progress would stay at nothing until its last task.
                watched.watch.flush(&mut out);
                out
            })
            .reduce(Links::default, |mut x, y| {
                x.append(y);
                x
            });
        watched.watch.flush(&mut links);
        if rank == 0 {
            links.append(settled);
        }
        Share { links, tasks: count, estimated, frontier }
    }

    /// The tasks of the refinement from the root's link with itself, each task with more than
    /// `limit` patches expanded, in a fixed order; the links settled on the way go to `out`.
    fn frontier(&self, limit: u32, out: &mut Links) -> Vec<Task> {
        let mut tasks = Vec::new();
        let mut stack = vec![Task::Within(ROOT)];
        while let Some(task) = stack.pop() {
            if task.patches(self.tree) <= limit {
                tasks.push(task);
                continue;
            }
            match task {
                Task::Within(k) => {
                    if let Some([a, b]) = self.tree.nodes[k as usize].children {
                        stack.push(Task::Between { a, b, traced: Vec::new(), candidates: vec![ROOT] });
                        stack.push(Task::Within(b));
                        stack.push(Task::Within(a));
                    }
                }
                Task::Between { a, b, traced, candidates } => {
                    let mut kept = Vec::new();
                    if let Some(Split { halves: [(a0, b0, t0), (a1, b1, t1)], candidates }) =
                        self.step(a, b, traced, &candidates, &mut kept, out)
                    {
                        let candidates = candidates.to_vec();
                        stack.push(Task::Between { a: a1, b: b1, traced: t1, candidates: candidates.clone() });
                        stack.push(Task::Between { a: a0, b: b0, traced: t0, candidates });
                    }
                }
            }
        }
        tasks
    }
}

/// The rank each task goes to, and each rank's estimated cost: largest estimated cost first
/// (ties by position), each to the rank with the least estimated cost so far (ties to the
/// lowest rank).
fn deal(tasks: &[Task], tree: &ClusterTree, ranks: usize) -> (Vec<usize>, Vec<u64>) {
    let mut by_cost: Vec<(u32, usize)> = tasks.iter().enumerate().map(|(k, t)| (t.patches(tree), k)).collect();
    by_cost.sort_unstable_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
    let mut load = vec![0u64; ranks];
    let mut owner = vec![0; tasks.len()];
    for (cost, k) in by_cost {
        let least = (0..ranks).min_by_key(|&r| (load[r], r)).unwrap_or(0);
        load[least] += u64::from(cost);
        owner[k] = least;
    }
    (owner, load)
}

#[cfg(test)]
mod tests {
    use super::*;
    use radiosity_geom::PreparedScene;

    #[test]
    fn the_deal_gives_every_task_one_rank_and_keeps_the_loads_within_the_largest_task() {
        let prepared = PreparedScene::load("cornell:res=6").unwrap();
        let tree = ClusterTree::new(prepared.scene());
        // Every node's links within it, and every pair of siblings: tasks of very unequal costs.
        let tasks: Vec<Task> = (0..tree.nodes.len() as u32)
            .map(Task::Within)
            .chain(tree.nodes.iter().filter_map(|n| n.children).map(|[a, b]| Task::Between {
                a,
                b,
                traced: Vec::new(),
                candidates: Vec::new(),
            }))
            .collect();
        let largest = tasks.iter().map(|t| u64::from(t.patches(&tree))).max().unwrap();
        for ranks in [1, 2, 3, 7] {
            let (owner, load) = deal(&tasks, &tree, ranks);
            assert_eq!(owner.len(), tasks.len());
            assert!(owner.iter().all(|&r| r < ranks));
            // Each rank's load is the cost of its tasks, and together they are every task's.
            for (r, &l) in load.iter().enumerate() {
                let own: u64 =
                    tasks.iter().zip(&owner).filter(|(_, o)| **o == r).map(|(t, _)| u64::from(t.patches(&tree))).sum();
                assert_eq!(own, l, "{ranks} ranks, rank {r}");
            }
            // Largest first, each to the least loaded: no two loads differ by more than one task.
            let (lo, hi) = (load.iter().min().unwrap(), load.iter().max().unwrap());
            assert!(hi - lo <= largest, "{ranks} ranks: loads {load:?}, largest task {largest}");
            assert_eq!(deal(&tasks, &tree, ranks), (owner, load), "{ranks} ranks: the deal is not deterministic");
        }
    }
}
