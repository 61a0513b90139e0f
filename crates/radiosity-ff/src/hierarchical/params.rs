//! The hierarchical operator's parameters (`hierarchical:key=value…`): their meaning, their
//! defaults and the keys a backend argument takes.

use super::brightness::Oracle;
use radiosity_core::Real;
use radiosity_geom::ParamDoc;

/// Parameters of the hierarchical operator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HierarchicalParams {
    /// The largest error estimate a far link may have: what it may change a receiver's
    /// radiosity by, relative to the RMS radiosity (`oracle=flux`), or a row of `F`
    /// (`oracle=area`).
    pub eps: Real,
    /// A far link larger than `shadows · eps` (in the same units) is split when its rays
    /// disagree: its visible fraction would be one number for all its pairs.
    pub shadows: Real,
    /// The most shadow rays a far link larger than `shadows · eps` traces; smaller ones trace a
    /// quarter.
    pub rays: usize,
    /// Agreeing shadow rays a far link larger than `shadows · eps` needs before it is trusted,
    /// per unit of its transfer bound over `shadows · eps` (sequential testing, `links`): at
    /// least a quarter of `rays`, at most `rays`.
    pub trust: Real,
    /// The near pairs' shadow-ray budget: the analytic backend's `budget` (rays per unit of a
    /// pair's unoccluded form factor), lower than that backend's own default: it trades the
    /// near pairs' visibility noise for build time (measured in `docs/hierarchical.md`).
    pub budget: usize,
    /// The near pairs' largest Gauss–Legendre order: the analytic backend's `order`.
    pub order: usize,
    /// The relative quadrature error the near pairs' rule aims at: the analytic backend's
    /// `tol`.
    pub tolerance: Real,
    /// The seed of the rays (and of the near links' analytic entries).
    pub seed: u64,
    /// What a link's error is weighed by: the flux it carries (the default) or its area.
    pub oracle: Oracle,
    /// The smallest weight of a patch's estimated brightness and of its reflectivity under the
    /// flux oracle: every link stays within `eps / floor²` of a row of `F` (`eps / floor`
    /// towards a receiver that reflects).
    pub floor: Real,
    /// Refinement passes: the first driven by the estimated brightness, each later one by the
    /// radiosity of the operator the pass before built (multigridding, module doc).
    pub passes: usize,
    /// Whether each row is held to at most 1 by weighing its estimated part at both ends
    /// (closure, module doc); without it the rows are left as the links give them.
    pub closure: bool,
    /// Whether a link between patches or flat clusters searches its shaft for patches before
    /// tracing rays: a clear shaft gives the tally its rays would have, without them, so the
    /// operator is the same either way (`links`). Off by default: at the default `rays` the
    /// search costs more than it saves on the scenes measured (`docs/hierarchical.md`).
    pub shafts: bool,
}

impl Default for HierarchicalParams {
    fn default() -> Self {
        HierarchicalParams {
            eps: 3e-3,
            shadows: 0.03,
            rays: 14,
            trust: 1.5,
            budget: 512,
            order: 8,
            tolerance: 1e-3,
            seed: 0,
            oracle: Oracle::Flux,
            floor: 0.1,
            passes: 1,
            closure: true,
            shafts: false,
        }
    }
}

/// Parameters of `hierarchical`.
pub const HIERARCHICAL_PARAMS: &[ParamDoc] = &[
    ParamDoc {
        key: "eps",
        default: "3e-3",
        doc: "largest error estimate of a far link: a receiver's radiosity relative to the RMS radiosity (a row of F with oracle=area)",
    },
    ParamDoc {
        key: "shadows",
        default: "0.03",
        doc: "a far link larger than shadows·eps is split when its rays disagree, in (0, 1]",
    },
    ParamDoc {
        key: "rays",
        default: "14",
        doc: "the most shadow rays a far link larger than shadows·eps traces (a quarter for smaller ones), 1 to 4096",
    },
    ParamDoc {
        key: "trust",
        default: "1.5",
        doc: "agreeing rays a far link larger than shadows·eps needs, per unit of its bound over shadows·eps, in (0, 4096] (between a quarter of rays and rays; 4096: every ray)",
    },
    ParamDoc {
        key: "budget",
        default: "512",
        doc: "the near pairs' shadow rays per unit of unoccluded form factor (the analytic backend's budget)",
    },
    ParamDoc {
        key: "order",
        default: "8",
        doc: "the near pairs' largest Gauss-Legendre order, 1 to 32 (the analytic backend's order)",
    },
    ParamDoc {
        key: "tol",
        default: "1e-3",
        doc: "the relative quadrature error the near pairs' rule aims at, in (0, 1] (the analytic backend's tol)",
    },
    ParamDoc { key: "seed", default: "0", doc: "seed of the rays" },
    ParamDoc {
        key: "oracle",
        default: "flux",
        doc: "what a link's error is weighed by: flux (estimated sender radiosity times receiver reflectivity) or area",
    },
    ParamDoc {
        key: "floor",
        default: "0.1",
        doc: "the flux oracle's smallest weight of a brightness or a reflectivity, in (0, 1]: every link stays within eps/floor² of a row of F",
    },
    ParamDoc {
        key: "passes",
        default: "1",
        doc: "refinement passes, 1 to 4: the first by the estimated brightness, each later one by the radiosity the pass before gives",
    },
    ParamDoc {
        key: "closure",
        default: "true",
        doc: "hold every row to at most 1 by weighing its far links and far pairs at both ends, reciprocity kept; its near links (analytic entries) are left as they are (false: rows as the links give them)",
    },
    ParamDoc {
        key: "shafts",
        default: "false",
        doc: "links between patches or flat clusters search their shafts for patches first, and a clear one traces no ray: the same operator, fewer rays, a faster build only where links trace many rays (rays=64)",
    },
];
