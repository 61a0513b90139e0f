//! What each rank of a distributed run built and spent ([`Lab::rank_reports`]): the figures of
//! its part of the operator, its peak memory, and the time and bytes of its collective sums.

use super::setup::Lab;
use super::summary::{RankReport, RunSummary};
use crate::memory::peak_rss;
use radiosity_core::{Collective, Real, Traffic};
use std::sync::Arc;

impl Lab<'_> {
    /// The lab with its runs solved over `ranks` where its source is not split itself: the
    /// solvers that sample transport then divide their rays between the ranks
    /// ([`radiosity_solvers::Problem::with_collective`]), and every solver's decisions that
    /// read a clock are rank 0's. Every rank builds the same lab and makes the same runs.
    pub fn over_ranks(mut self, ranks: Arc<dyn Collective>) -> Self {
        self.ranks = Some(ranks);
        self
    }

    /// The ranks the lab's runs are solved over: its source's, or those of
    /// [`Lab::over_ranks`].
    fn collective(&self) -> Option<&dyn Collective> {
        self.source.collective().or(self.ranks.as_deref())
    }

    /// What this rank's sums have cost so far, when the lab's runs are solved over ranks:
    /// take it before a run, for [`Lab::rank_reports`].
    pub fn traffic(&self) -> Option<Traffic> {
        self.collective().map(|c| c.traffic())
    }

    /// Every rank's report, in rank order, on every rank, when the lab's runs are solved over
    /// ranks: a collective call, which every rank makes after the same run, with the traffic
    /// taken before it (`before`) and this rank's summary of the run (`run`: its operator
    /// seconds, and the rays it cast, `rays_here` of the record of a solver that samples).
    pub fn rank_reports(&self, before: Traffic, run: &RunSummary) -> Option<Vec<RankReport>> {
        let ranks = self.collective()?;
        let now = ranks.traffic();
        let run_rays = run.record.get("rays_here").and_then(|v| v.as_u64()).unwrap_or(0);
        let own = [
            peak_rss().map_or(-1.0, |b| b as Real),
            run.cost.ff_seconds,
            (now.sums - before.sums) as Real,
            now.seconds - before.seconds,
            (now.bytes_sent - before.bytes_sent) as Real,
            run_rays as Real,
        ];
        let runs = ranks.gather(&own);
        let parts = self.figures.as_ref().map(|f| f.ranks.as_slice()).unwrap_or_default();
        let count = |k: usize, label: &str| parts.get(k).and_then(|p| p.count(label)).unwrap_or(0.0);
        Some(
            runs.iter()
                .enumerate()
                .map(|(k, run)| RankReport {
                    rank: k,
                    build_seconds: parts.get(k).map_or(0.0, |p| p.seconds),
                    build_stages: parts.get(k).map(|p| p.stages.clone()).unwrap_or_default(),
                    operator_bytes: parts.get(k).map_or(0, |p| p.bytes as u64),
                    link_bytes: count(k, "link bytes") as u64,
                    links: (count(k, "far links") + count(k, "near links")) as u64,
                    rays: count(k, "shadow rays") as u64,
                    tasks: count(k, "tasks") as u64,
                    estimated_share: count(k, "estimated share"),
                    peak_rss: (run[0] >= 0.0).then_some(run[0] as u64),
                    run_operator_seconds: run[1],
                    run_sums: run[2] as u64,
                    run_sum_seconds: run[3],
                    run_bytes_sent: run[4] as u64,
                    run_rays: run[5] as u64,
                })
                .collect(),
        )
    }
}
