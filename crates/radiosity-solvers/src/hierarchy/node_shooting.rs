//! `h-southwell`, `h-pr`, `h-xu`, `h-jacobi`, `h-gauss-seidel`: shooting from the nodes of a
//! hierarchy through their own links, the unshot radiosity kept on the nodes
//! ([`super::pipeline`]).
//!
//! A step is one round: some nodes shoot, one push brings what they sent down to the patches,
//! and one pull adds it to the radiosity and to the unshot radiosity of every node above
//! ([`super::pipeline`]). The rounds differ in the nodes they shoot:
//!
//! - `h-southwell`: the nodes with the largest residual they hold, `Σ_c σ_kc power_kc` (what
//!   shooting takes off the bound: Southwell's rule on the nodes), largest first, until they
//!   hold `share` of the whole (0.5 by default);
//! - `h-pr`: likewise by unshot power `Σ_c power_kc` (progressive refinement's rule, area
//!   weighted, on the nodes);
//! - `h-xu`: `h-pr`'s rounds with an ambient overshoot at every pull, `δ_i = ρ_i t̄` per
//!   channel, `t̄` the area-weighted mean of the light the pull brings: the next bounce of that
//!   light, estimated as Xu estimates multiple reflections, by the ambient (Xu's direct part
//!   needs a row of every patch and is left out). Every bounce, `1 / (1 − ρ̄)` times more,
//!   diverged on a stored system of the tests (with spatial groups): on a hierarchy every
//!   patch a pull reaches is overshot, not one shooter a step;
//! - `h-jacobi`: every node that holds anything, every round: a round is a sweep over the links,
//!   as RenderPark's Jacobi iterates its hierarchy (one product's links);
//! - `h-gauss-seidel`: the nodes in `blocks` slices of their numbering (a parent before its
//!   children; at most one slice a node), one slice a round, so that what a slice sends is
//!   pulled before the next one shoots: block Gauss–Seidel over the nodes, `blocks` rounds a
//!   sweep.
//!
//! **Holes.** An overshot patch, and a group whose interreflections were solved ahead
//! (`groups`), have a negative residual, a hole, until the light they anticipated comes back
//! through their own links. Where there can be holes (`h-xu`, groups), a pull holds them
//! (takes `max(t, 0)`, then overshoots and solves the groups), so that every node's unshot radiosity stays non-negative and the bound
//! tight: a group's solve of a hole would amplify it, and pulled holes would swing the
//! radiosity. If a channel's holes outweigh the light still unshot on the nodes and the light
//! the round brings, that light cannot fill them; the pull then takes `t` as it is, without
//! overshoot or groups (counted as `holes_released`).
//!
//! Why a share, not one node a round: a push and a pull cost `O(nodes)` whatever the round
//! shoots, so a round must move enough to pay for them; what a round sent stays out of sight of
//! the choice until its push, and a share of a half keeps the choice current while it moves
//! most of the residual in a few rounds. `share=1` is `h-jacobi`'s round.
//!
//! Every variant takes groups (`groups=clusters|spatial|unshot`, `g=M`, [`super::groups`]).
//!
//! Each round's cost is counted in links touched ([`Problem::through_links`]), and so is the
//! start's, the send shares read from every link once; over a source that shows no links, a
//! node is a patch and a shot a column.
//!
//! ## References
//!
//! - Gortler, Cohen & Slusallek 1994, "Radiosity and relaxation methods", IEEE CG&A 14(6):
//!   Southwell relaxation on a hierarchy, with push and pull.
//! - Hanrahan, Salzman & Aupperle 1991, "A rapid hierarchical radiosity algorithm", SIGGRAPH:
//!   Jacobi and Gauss–Seidel sweeps over the links.
//! - Rousselle & Renaud, "Group accelerated shooting methods for radiosity": the group step.
//! - Xu & Fussell 1994, "A fast solver of radiosity equation systems", Pacific Graphics.

use crate::error::SolverError;
use crate::hierarchy::groups::{Grouping, Groups};
use crate::hierarchy::pipeline::Pipeline;
use crate::naming::{ParseSolverError, SolverParams, split_params, validated};
use crate::run::executor::{Solver, StepKind};
use crate::run::problem::Problem;
use crate::run::record::Record;
use crate::run::residual_bound::ResidualBound;
use crate::run::state::State;
use radiosity_core::Real;
use std::str::FromStr;
use std::time::Instant;

/// Which nodes a round shoots (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeOrder {
    /// The largest residual first (`h-southwell`).
    Southwell,
    /// The largest unshot power first (`h-pr`, `h-xu`).
    Progressive,
    /// Every node (`h-jacobi`).
    Jacobi,
    /// A slice of the nodes a round (`h-gauss-seidel`).
    GaussSeidel,
}

/// The name `h-S[:share=θ][:blocks=B][:groups=clusters|spatial|unshot][:g=M]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeShootingParams {
    /// Which nodes a round shoots.
    pub order: NodeOrder,
    /// Whether pulls are overshot (`h-xu`).
    pub overshoot: bool,
    /// The share of the residual a Southwell or PR round shoots, in `(0, 1]`.
    pub share: Real,
    /// The rounds of a Gauss–Seidel sweep.
    pub blocks: usize,
    /// The groups a pull solves.
    pub grouping: Grouping,
}

/// The default share of a round.
pub const DEFAULT_SHARE: Real = 0.5;
/// The default rounds of a Gauss–Seidel sweep.
pub const DEFAULT_BLOCKS: usize = 8;
/// The default size of a group.
pub const DEFAULT_GROUP: usize = 32;

impl NodeShootingParams {
    /// The parameters of `head` with the defaults.
    fn of(head: &str) -> Option<NodeShootingParams> {
        let (order, overshoot) = match head {
            "h-southwell" => (NodeOrder::Southwell, false),
            "h-pr" => (NodeOrder::Progressive, false),
            "h-xu" => (NodeOrder::Progressive, true),
            "h-jacobi" => (NodeOrder::Jacobi, false),
            "h-gauss-seidel" => (NodeOrder::GaussSeidel, false),
            _ => return None,
        };
        Some(NodeShootingParams {
            order,
            overshoot,
            share: DEFAULT_SHARE,
            blocks: DEFAULT_BLOCKS,
            grouping: Grouping::None,
        })
    }

    /// The canonical name: the head and the parameters that are not defaults.
    pub fn name(&self) -> String {
        let mut name = match (self.order, self.overshoot) {
            (NodeOrder::Southwell, _) => "h-southwell",
            (NodeOrder::Progressive, false) => "h-pr",
            (NodeOrder::Progressive, true) => "h-xu",
            (NodeOrder::Jacobi, _) => "h-jacobi",
            (NodeOrder::GaussSeidel, _) => "h-gauss-seidel",
        }
        .to_string();
        if self.share != DEFAULT_SHARE {
            name += &format!(":share={}", self.share);
        }
        if self.blocks != DEFAULT_BLOCKS {
            name += &format!(":blocks={}", self.blocks);
        }
        let (kind, size) = match self.grouping {
            Grouping::None => (None, DEFAULT_GROUP),
            Grouping::Clusters { size } => (Some("clusters"), size),
            Grouping::Spatial { size } => (Some("spatial"), size),
            Grouping::Unshot { size } => (Some("unshot"), size),
        };
        if let Some(kind) = kind {
            name += &format!(":groups={kind}");
            if size != DEFAULT_GROUP {
                name += &format!(":g={size}");
            }
        }
        name
    }
}

impl FromStr for NodeShootingParams {
    type Err = ParseSolverError;

    fn from_str(name: &str) -> Result<NodeShootingParams, ParseSolverError> {
        let (head, params) = split_params(name);
        let mut p = NodeShootingParams::of(head).ok_or(ParseSolverError::OtherFamily)?;
        let refuse = |why: String| ParseSolverError::Refused(SolverError::BadParams(format!("solver '{name}': {why}")));
        let (mut groups, mut size) = (None, DEFAULT_GROUP);
        for param in params.split(':').filter(|s| !s.is_empty()) {
            let (key, value) = param.split_once('=').ok_or_else(|| refuse(format!("'{param}' is not key=value")))?;
            match key {
                "share" if matches!(p.order, NodeOrder::Southwell | NodeOrder::Progressive) => {
                    p.share = value.parse().map_err(|_| refuse(format!("share takes a number, not '{value}'")))?;
                }
                "blocks" if p.order == NodeOrder::GaussSeidel => {
                    p.blocks = value.parse().map_err(|_| refuse(format!("blocks takes a count, not '{value}'")))?;
                }
                "groups" => {
                    groups = Some(match value {
                        "clusters" | "spatial" | "unshot" => value,
                        _ => return Err(refuse(format!("groups takes clusters, spatial or unshot, not '{value}'"))),
                    })
                }
                "g" => size = value.parse().map_err(|_| refuse(format!("g takes a group size, not '{value}'")))?,
                _ => return Err(refuse(format!("'{key}' is not a parameter of {head} ({})", Self::SYNTAX))),
            }
        }
        p.grouping = match groups {
            None if size != DEFAULT_GROUP => return Err(refuse("g= needs groups=clusters, spatial or unshot".into())),
            None => Grouping::None,
            Some("clusters") => Grouping::Clusters { size },
            Some("spatial") => Grouping::Spatial { size },
            Some(_) => Grouping::Unshot { size },
        };
        validated(name, p)
    }
}

impl SolverParams for NodeShootingParams {
    const SYNTAX: &'static str =
        "h-southwell, h-pr, h-xu, h-jacobi, h-gauss-seidel[:share=θ][:blocks=B][:groups=clusters|spatial|unshot][:g=M]";
    const HELP: &'static str = "shooting from the nodes of a hierarchy through their own links, the unshot radiosity on the nodes, pushed and pulled once a round; cost in links touched";
    const EXAMPLES: &'static [&'static str] = &[
        "h-southwell",
        "h-pr",
        "h-xu",
        "h-jacobi",
        "h-gauss-seidel",
        "h-xu:groups=clusters",
        "h-xu:groups=spatial",
        "h-pr:groups=unshot:g=16",
    ];

    fn build(&self) -> Result<Box<dyn Solver>, SolverError> {
        if !(self.share > 0.0 && self.share <= 1.0) {
            return Err(SolverError::BadParams(format!("share must be in (0, 1], not {}", self.share)));
        }
        if self.blocks == 0 {
            return Err(SolverError::BadParams("blocks must be at least 1".into()));
        }
        if let Grouping::Clusters { size } | Grouping::Spatial { size } | Grouping::Unshot { size } = self.grouping
            && !(2..=1024).contains(&size)
        {
            return Err(SolverError::BadParams(format!("g must be between 2 and 1024, not {size}")));
        }
        Ok(Box::new(NodeShooting { params: *self, ..NodeShooting::default() }))
    }
}

/// A node shooter (module doc).
#[derive(Debug)]
pub struct NodeShooting {
    params: NodeShootingParams,
    pipeline: Option<Pipeline>,
    groups: Groups,
    /// What a push brings (`t`), what a pull holds of it, and what it takes (`s`).
    brought: Vec<Real>,
    held: Vec<Real>,
    taken: Vec<Real>,
    /// Pulls that took their holes back ([`NodeShooting::take`]).
    released: u64,
    sending: Vec<bool>,
    /// The nodes a Southwell or PR round ranks, with their priorities.
    order: Vec<(Real, usize)>,
    rounds: u64,
    nodes_shot: u64,
}

impl Default for NodeShooting {
    fn default() -> NodeShooting {
        NodeShooting {
            params: NodeShootingParams::of("h-southwell").expect("a head of the family"),
            pipeline: None,
            groups: Groups::default(),
            brought: Vec::new(),
            held: Vec::new(),
            taken: Vec::new(),
            released: 0,
            sending: Vec::new(),
            order: Vec::new(),
            rounds: 0,
            nodes_shot: 0,
        }
    }
}

impl NodeShooting {
    /// Marks in `self.sending` the nodes this round shoots (module doc).
    fn choose(&mut self, pipeline: &Pipeline) {
        let nodes = pipeline.nodes();
        self.sending.clear();
        self.sending.resize(nodes, false);
        let holds = |node: usize| pipeline.power(node).iter().any(|p| *p > 0.0);
        match self.params.order {
            NodeOrder::Jacobi => (0..nodes).for_each(|node| self.sending[node] = holds(node)),
            NodeOrder::GaussSeidel => {
                // No slice empty: at most as many slices as nodes.
                let blocks = (self.params.blocks as u64).min(nodes as u64).max(1);
                let slice = (self.rounds % blocks) as usize;
                let range = slice * nodes / blocks as usize..(slice + 1) * nodes / blocks as usize;
                range.for_each(|node| self.sending[node] = holds(node));
            }
            NodeOrder::Southwell | NodeOrder::Progressive => {
                let priority = |node: usize| match self.params.order {
                    NodeOrder::Southwell => pipeline.gain(node),
                    _ => pipeline.power(node).iter().sum(),
                };
                let order = &mut self.order;
                order.clear();
                order.extend((0..nodes).map(|node| (priority(node), node)).filter(|(p, _)| *p > 0.0));
                let total: Real = order.iter().map(|(p, _)| p).sum();
                order.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
                let mut taken = 0.0;
                for &(p, node) in order.iter() {
                    if taken >= self.params.share * total {
                        break;
                    }
                    self.sending[node] = true;
                    taken += p;
                }
            }
        }
    }

    /// What a pull takes of what the round brought (`t`, in `brought`), into `taken` (module
    /// doc, "Holes"): holes held, overshot (`h-xu`), then each group's part solved; or `t` as
    /// it is when some channel's holes outweigh the light unshot on the nodes and the light the
    /// round brings. Returns the seconds the groups took.
    fn take(&mut self, problem: &Problem<'_>, pipeline: &Pipeline) -> f64 {
        // Without overshoot or groups nothing makes a hole: a pull takes `t`.
        if !self.params.overshoot && self.params.grouping == Grouping::None {
            self.taken.clone_from(&self.brought);
            return 0.0;
        }
        let system = problem.system();
        let (area, k, n) = (system.areas(), problem.channels(), problem.n());
        let total: Real = area.iter().sum();
        let unshot = pipeline.unshot_norms();
        let mut held = std::mem::take(&mut self.held);
        held.clone_from(&self.brought);
        for (c, unshot) in unshot.into_iter().enumerate() {
            let (lit, holes) = (0..n).fold((0.0, 0.0), |(lit, holes), i| {
                let t = self.brought[i * k + c];
                (lit + area[i] * t.max(0.0), holes + area[i] * (-t).max(0.0))
            });
            if holes > lit + unshot {
                // The light to come will not fill the holes: they are taken back as they are.
                self.taken.clone_from(&self.brought);
                self.released += 1;
                self.held = held;
                return 0.0;
            }
            let ambient = if self.params.overshoot { lit / total } else { 0.0 };
            for i in 0..n {
                // A hole is held; a value that is not finite is kept, for the pull to report.
                let t = &mut held[i * k + c];
                *t = if *t < 0.0 { 0.0 } else { *t } + system.rho(i, c) * ambient;
            }
        }
        let start = Instant::now();
        self.groups.relax(problem, self.params.grouping, &held, &mut self.taken);
        self.held = held;
        start.elapsed().as_secs_f64()
    }
}

impl Solver for NodeShooting {
    fn name(&self) -> String {
        self.params.name()
    }

    fn applicable(&self, problem: &Problem<'_>) -> Result<(), SolverError> {
        let reason = match self.params.grouping {
            Grouping::Clusters { .. } if problem.link_source().is_none() => {
                "groups=clusters needs a hierarchy, and these form factors show no links (--ff hierarchical does)"
            }
            Grouping::Spatial { .. } if problem.patch_order().is_none() => {
                "groups=spatial needs a spatially coherent order of the patches (Problem::with_patch_order; the lab gives one)"
            }
            _ => return Ok(()),
        };
        Err(SolverError::NotApplicable { solver: self.name(), reason: reason.into() })
    }

    fn init(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let pipeline = Pipeline::start(problem, state);
        let start = Instant::now();
        self.groups = Groups::prepare(problem, &pipeline, self.params.grouping, state.channels);
        state.cost.group_seconds += start.elapsed().as_secs_f64();
        self.pipeline = Some(pipeline);
        (self.rounds, self.nodes_shot, self.released) = (0, 0, 0);
        Ok(())
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        let mut pipeline = self.pipeline.take().expect("init starts the pipeline");
        self.choose(&pipeline);
        let shot = self.sending.iter().filter(|s| **s).count() as u64;
        let touched = pipeline.shoot_and_push(problem, &self.sending, &mut self.brought);
        state.cost.group_seconds += self.take(problem, &pipeline);
        let pulled = pipeline.pull(problem, state, &self.brought, &self.taken);
        self.pipeline = Some(pipeline);
        pulled?;
        self.rounds += 1;
        self.nodes_shot += shot;
        Ok(Record::new().with("nodes_shot", shot).with("links_touched", touched))
    }

    fn residual_power(&self, problem: &Problem<'_>, _state: &State) -> Option<Real> {
        self.pipeline.as_ref().map(|p| p.residual_power(problem))
    }

    fn residual_bound(&self, problem: &Problem<'_>, _state: &State) -> Option<ResidualBound> {
        self.pipeline.as_ref().map(|p| p.bound(problem))
    }

    /// A round: some nodes' links, one push and one pull.
    fn step_kind(&self) -> StepKind {
        StepKind::Round
    }

    fn record(&self) -> Record {
        let mut record = Record::new();
        record.set("rounds", self.rounds).set("nodes_shot", self.nodes_shot).set("holes_released", self.released);
        if let Some(pipeline) = &self.pipeline {
            // What the run holds of its own: the pipeline, and a round's flags and vectors.
            let own = self.sending.capacity() + (self.brought.capacity() + self.taken.capacity()) * size_of::<Real>();
            record.set("state_bytes", (pipeline.bytes() + own) as u64);
        }
        if self.params.grouping != Grouping::None {
            record
                .set("group_solves", self.groups.solves)
                .set("group_fallbacks", self.groups.fallbacks)
                .set("clustered_patches", self.groups.clustered as u64);
        }
        record
    }
}
