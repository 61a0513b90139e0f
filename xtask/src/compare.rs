//! `cargo xtask compare [--scene SCENE] [--solvers S1,S2,…] [--ff BACKEND] [--transport WHERE]
//! [--until RULES] [--reference KIND] [--out DIR]`: runs several solvers on one scene against
//! its reference, and writes what a researcher reads and shows ([`radiosity_eval::Comparison`]):
//! `convergence.csv`, `report.md` and plots of e_rms (with `--reference none`, of the
//! certified bound) against steps, columns, rays (when a solver samples transport) and
//! seconds, under `results/<scene>-<date-time>/` or `--out`. A summary table ends the output.
//! Deterministic solvers and solvers that sample transport go in one comparison, each stopped
//! by the rules that count what it spends (`--until columns=2n,rays=1e7`).

use crate::bars::Bars;
use crate::experiment::{ReferenceArg, check_measurable, check_out_dir, default_out, lab, prepare_over};
use crate::ranks::Ranks;
use anyhow::{Result, bail};
use radiosity_eval::ReferenceKind;
use radiosity_eval::{ColumnCost, Comparison, ComparisonWatch, Lab, Transport};
use radiosity_ff::BackendSpec;
use radiosity_geom::PreparedScene;
use radiosity_solvers::{Solver, SolverRegistry, StopRules};
use std::path::{Path, PathBuf};

/// The paper's multi-cubes comparison (its figure 1).
pub const DEFAULT_SOLVERS: &str = "pr,xu,pr-g30,xu-g30,pr-g30-m480,xu-g30-m480";

/// What `compare` and `watch` both take: the comparison to run.
#[derive(Debug, clap::Args)]
pub struct ComparisonArgs {
    /// The scene: a built-in name with `:key=value` parameters, or a .gltf, .glb or .mgf path.
    #[arg(long, default_value = "multi-cubes")]
    pub scene: String,
    /// The solvers, comma-separated (names as for `solve`).
    #[arg(long, default_value = DEFAULT_SOLVERS)]
    pub solvers: String,
    /// The form-factor backend, with `:key=value` parameters.
    #[arg(long = "ff", value_name = "BACKEND", default_value = "analytic", long_help = crate::experiment::backend_help())]
    pub ff: String,
    #[command(flatten)]
    pub transport: crate::experiment::TransportArg,
    /// Stop rules for every solver (a solver that samples transport computes no columns: give
    /// it a rays=, steps=, time= or rms= rule too, e.g. columns=2n,rays=1e7).
    #[arg(long, value_name = "RULES", default_value = "columns=2n")]
    pub until: String,
    #[command(flatten)]
    pub reference: ReferenceArg,
    /// How solvers pay for their columns, which names the clock of every seconds figure:
    /// `computed` computes every column when a solver asks for it (the `measured` clock, wall
    /// time); `charged` reads them from the stored matrix of a `matrix` reference and charges
    /// each the backend's measured cost (the `charged` clock: several times faster, but its
    /// seconds do not rank the default comparison's solvers as measured ones do).
    #[arg(long, value_name = "HOW", default_value_t = ColumnCost::default(), value_parser = parse_columns)]
    pub columns: ColumnCost,
}

impl ComparisonArgs {
    /// The plan these arguments make, checked before any geometry is built.
    pub fn plan(&self, ranks: &Ranks) -> Result<Plan> {
        radiosity_geom::SceneSpec::parse(&self.scene)?;
        Ok(Plan::on_ranks(&self.scene, &self.solvers, &self.ff, &self.until, self.reference.parse()?, ranks)?
            .with_columns(self.columns)
            .with_transport(self.transport.transport))
    }
}

/// Arguments of `compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: ComparisonArgs,
    /// The output folder (default `results/<scene>-<date-time>/`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Also writes `page.html` into the output folder: the page of `watch`, kept as one file
    /// that opens from disk, with a slider over each run.
    #[arg(long)]
    html: bool,
    #[command(flatten)]
    pub ranks: crate::ranks::RanksArg,
}

/// A comparison whose arguments were all checked before any geometry is built.
pub struct Plan {
    /// The scene argument.
    pub scene: String,
    solvers: Vec<Box<dyn Solver>>,
    spec: BackendSpec,
    rules: StopRules,
    kind: ReferenceKind,
    columns: ColumnCost,
    transport: Transport,
    /// Whether this process writes the results: rank 0, or a single process.
    writes: bool,
    /// The ranks this process is one of, when it is one of several.
    world: Option<std::sync::Arc<dyn radiosity_core::Collective>>,
}

impl Plan {
    /// Checks every argument, so a typo fails at once.
    pub fn new(scene: &str, solvers: &str, ff: &str, until: &str, kind: ReferenceKind) -> Result<Plan> {
        Plan::on_ranks(scene, solvers, ff, until, kind, &Ranks::default())
    }

    /// [`Plan::new`] for a process that is one of `ranks`: the backend is its part, and only
    /// rank 0 writes.
    pub fn on_ranks(
        scene: &str,
        solvers: &str,
        ff: &str,
        until: &str,
        kind: ReferenceKind,
        ranks: &Ranks,
    ) -> Result<Plan> {
        let spec = ranks.backend(ff)?;
        let registry = SolverRegistry::builtin();
        let solvers = solvers
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|name| registry.build(name))
            .collect::<Result<Vec<_>, _>>()?;
        if solvers.is_empty() {
            bail!("--solvers names no solver");
        }
        let rules = StopRules::parse(until)?;
        check_measurable(&rules, kind)?;
        for solver in &solvers {
            radiosity_eval::check_rules(solver.as_ref(), &rules)?;
        }
        Ok(Plan {
            scene: scene.to_string(),
            solvers,
            spec,
            rules,
            kind,
            columns: ColumnCost::default(),
            transport: Transport::default(),
            writes: ranks.reports(),
            world: ranks.world(),
        })
    }

    /// Sets how solvers pay for their columns ([`ColumnCost`]).
    pub fn with_columns(mut self, columns: ColumnCost) -> Plan {
        self.columns = columns;
        self
    }

    /// Sets where the solvers that sample transport cast their rays ([`Transport`]).
    pub fn with_transport(mut self, transport: Transport) -> Plan {
        self.transport = transport;
        self
    }

    /// The form-factor backend every solver runs on.
    pub fn backend(&self) -> &BackendSpec {
        &self.spec
    }

    /// Runs every solver and writes the report, table and plots into `out`.
    pub fn execute(self, out: &Path) -> Result<Comparison> {
        Ok(self.execute_with(out, |_, _, _| Ok(()))?.0)
    }

    /// [`Plan::execute`], watched by what `watch` makes of the prepared scene, the lab and
    /// the solvers' names once the lab is set up; the watch is handed back with the comparison.
    pub fn execute_with<W: ComparisonWatch>(
        self,
        out: &Path,
        watch: impl FnOnce(&PreparedScene, &Lab<'_>, Vec<String>) -> Result<W>,
    ) -> Result<(Comparison, W)> {
        let prepared = prepare_over(&self.scene, None, self.world.as_deref())?;
        radiosity_eval::require_emitters(&prepared)?;
        let report = prepared.report();
        eprintln!("{}: {} patches; left out: {}", report.scene, report.patches, report.left_out_phrase());
        let mut lab = lab(&prepared, &self.spec, true, self.kind, self.columns, self.transport, &Bars::new())?;
        if let Some(world) = self.world {
            lab = lab.over_ranks(world);
        }
        let mut watch = watch(&prepared, &lab, self.solvers.iter().map(|s| s.name()).collect())?;
        let comparison = lab.compare_watched(self.solvers, &self.rules, &Bars::new(), &mut watch)?;
        for note in &comparison.notes {
            eprintln!("warning: {note}");
        }
        // Distributed, rank 0 alone writes.
        if self.writes {
            comparison.write(out)?;
        }
        Ok((comparison, watch))
    }
}

/// Reads `--columns` ([`ColumnCost::name`]).
pub(crate) fn parse_columns(value: &str) -> Result<ColumnCost, String> {
    value.parse().map_err(|e: radiosity_eval::EvalError| e.to_string())
}

/// Runs `compare`.
pub fn run(args: &Args, ranks: &Ranks) -> Result<()> {
    let plan = args.run.plan(ranks)?;
    let out = args.out.clone().unwrap_or_else(|| default_out(&args.run.scene));
    if ranks.reports() {
        check_out_dir(&out)?;
    }
    let comparison = if args.html {
        let (scene, until) = (args.run.scene.clone(), args.run.until.clone());
        let (comparison, watch) = plan.execute_with(&out, |prepared, lab, solvers| {
            let feed = crate::page::feed(&scene, &until, prepared, lab, solvers)?;
            Ok(radiosity_eval::FeedWatch::new(feed, Default::default()))
        })?;
        if ranks.reports() {
            crate::page::write_kept(&watch.feed(), &comparison, &out, &out.join("page.html"))?;
        }
        comparison
    } else {
        plan.execute(&out)?
    };
    print!("{}", comparison.summary());
    println!("{}: {}", comparison.clock.seconds_label(), comparison.seconds_phrase());
    if let Some(build) = &comparison.backend_build {
        println!("form factors {}: {build}, outside every solver's seconds", comparison.backend);
    }
    let what = if args.html {
        "report.md, convergence.csv, plots and page.html"
    } else {
        "report.md, convergence.csv and plots"
    };
    println!("wrote {} ({what})", out.display());
    Ok(())
}
