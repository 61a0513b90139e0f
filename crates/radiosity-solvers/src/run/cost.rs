//! What a run spends: one [`Cost`], counted in [`Unit`]s and in seconds on the run's clock.
//!
//! Every family pays in its own unit: point and group methods in columns of F, Krylov methods
//! in products `F x` over a source that multiplies itself, stochastic relaxation in rays,
//! shooting on a hierarchy in links. The [`crate::Problem`] counts each unit as it is spent
//! ([`crate::Problem::spent`]), the executor copies the counts into the state after every
//! step, and from there one value reaches the recorder's points, the stop rules
//! (`columns=`, `products=`, `rays=`, `links=`), the reports and the run summary. A new unit
//! is a variant of [`Unit`] and the family that spends it: the rules, axes, tables and
//! summaries read [`Unit::ALL`].
//!
//! Seconds are kept as in docs/design.md §3.3: form-factor seconds (the columns', products',
//! rays' or links' own, on the run's [`Clock`]: measured, or charged by the source) and
//! solving seconds (measured), of which the group steps' own work is kept apart.

use radiosity_core::Clock;
use std::fmt;
use std::ops::{Index, IndexMut};

/// A unit a run's cost is counted in (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Unit {
    /// Columns (or rows) of F computed ([`crate::Problem::column`]).
    Columns,
    /// Columns served again from a solver's memory ([`crate::ColumnMemory`]): free, and not
    /// counted in `Columns`.
    Reused,
    /// Products `F x` the source computed itself ([`crate::Problem::multiply`]), each in
    /// `O(links + n)` or a pass over a stored matrix: counted beside columns, not in them.
    Products,
    /// Rays cast by a solver that samples transport ([`crate::Problem::cast`]).
    Rays,
    /// Links of a hierarchy touched, when the source shows its links: the cost of shooting
    /// from the nodes of a hierarchy, and of columns and products over it.
    Links,
}

impl Unit {
    /// Every unit, in the order tables and summaries list them.
    pub const ALL: [Unit; 5] = [Unit::Columns, Unit::Reused, Unit::Products, Unit::Rays, Unit::Links];

    /// The unit's key: in a stop rule (`rays=1e7`), a JSON summary and a file name.
    pub fn key(self) -> &'static str {
        match self {
            Unit::Columns => "columns",
            Unit::Reused => "columns_reused",
            Unit::Products => "products",
            Unit::Rays => "rays",
            Unit::Links => "links",
        }
    }

    /// What a count in this unit is, after the number: `columns computed`, `rays cast`.
    pub fn spent(self) -> &'static str {
        match self {
            Unit::Columns => "columns computed",
            Unit::Reused => "columns reused",
            Unit::Products => "products computed",
            Unit::Rays => "rays cast",
            Unit::Links => "links touched",
        }
    }

    /// The unit's plural name, for a column heading or a progress bar: `columns`, `rays`.
    pub fn name(self) -> &'static str {
        match self {
            Unit::Reused => "reused columns",
            other => other.key(),
        }
    }

    /// Whether the unit is paid for: everything but columns served again from memory. Only
    /// paid units have a stop rule and a cost axis.
    pub fn paid(self) -> bool {
        self != Unit::Reused
    }

    /// The paid unit whose key is `key`.
    pub fn from_key(key: &str) -> Option<Unit> {
        Unit::ALL.into_iter().find(|u| u.paid() && u.key() == key)
    }

    /// The unit's place in [`Unit::ALL`]: its discriminant, since `ALL` lists the variants in
    /// order (checked at compile time below).
    pub(crate) fn at(self) -> usize {
        self as usize
    }
}

// `ALL` lists the variants in declaration order, so a unit's discriminant is its place in it.
const _: () = {
    let mut i = 0;
    while i < Unit::ALL.len() {
        assert!(Unit::ALL[i] as usize == i);
        i += 1;
    }
};

impl fmt::Display for Unit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.key())
    }
}

/// What a run has spent (module doc): a count in every [`Unit`] (`cost[Unit::Rays]`) and its
/// seconds on its clock.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cost {
    counts: [u64; Unit::ALL.len()],
    /// Seconds the form factors cost on the run's clock: the columns', products', and, measured
    /// on either clock, the rays' and links' ([`crate::Problem::ff_seconds`]).
    pub ff_seconds: f64,
    /// Seconds spent in the solver outside its form factors, measured.
    pub solve_seconds: f64,
    /// Of `solve_seconds`, the seconds of the group steps' own work: building and solving
    /// group systems and shooting their solution, and for group-accelerated shooting choosing
    /// the group too. Time accounting, shown beside the form-factor time; what the group steps
    /// did is in the solver's record ([`crate::Run::record`]).
    pub group_seconds: f64,
    /// The clock `ff_seconds` is counted on ([`crate::Problem::clock`]).
    pub clock: Clock,
}

impl Cost {
    /// The cost with `count` in `unit`, for writing one in an expression.
    #[must_use]
    pub fn with(mut self, unit: Unit, count: u64) -> Cost {
        self[unit] = count;
        self
    }

    /// The cost with `ff_seconds` of form factors and `solve_seconds` of solving, for writing
    /// one in an expression.
    #[must_use]
    pub fn with_seconds(mut self, ff_seconds: f64, solve_seconds: f64) -> Cost {
        (self.ff_seconds, self.solve_seconds) = (ff_seconds, solve_seconds);
        self
    }

    /// The run's seconds: form factors and solving, on its clock. What a `time=` rule reads.
    pub fn seconds(&self) -> f64 {
        self.ff_seconds + self.solve_seconds
    }

    /// The paid units with a count above zero, in [`Unit::ALL`]'s order, with their counts.
    pub fn paid(&self) -> impl Iterator<Item = (Unit, u64)> + '_ {
        Unit::ALL.into_iter().filter(|u| u.paid()).map(|u| (u, self[u])).filter(|&(_, k)| k > 0)
    }

    /// The unit the run's cost is read in: columns when it computed any (or spent nothing),
    /// otherwise the last paid unit in [`Unit::ALL`]'s order it spent: links for a run over a
    /// hierarchy (products and node shooting count them), rays for a solver that samples
    /// transport, products for a Krylov run over a source that multiplies itself.
    pub fn principal(&self) -> Unit {
        if self[Unit::Columns] > 0 {
            return Unit::Columns;
        }
        self.paid().last().map_or(Unit::Columns, |(u, _)| u)
    }

    /// Whether the run cast rays and computed neither a column nor a product: a solver that
    /// samples transport, whose cost is its rays.
    pub fn only_rays(&self) -> bool {
        self[Unit::Rays] > 0 && self[Unit::Columns] == 0 && self[Unit::Products] == 0
    }
}

impl Index<Unit> for Cost {
    type Output = u64;

    fn index(&self, unit: Unit) -> &u64 {
        &self.counts[unit.at()]
    }
}

impl IndexMut<Unit> for Cost {
    fn index_mut(&mut self, unit: Unit) -> &mut u64 {
        &mut self.counts[unit.at()]
    }
}

/// The paid counts, columns first and always, then the others above zero: `659 columns`,
/// `0 columns + 12 products (4100 links)`, `1000 rays` for a run that only cast rays. Links
/// are written in parentheses when columns or products also count them.
impl fmt::Display for Cost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.only_rays() {
            return write!(f, "{} rays", self[Unit::Rays]);
        }
        write!(f, "{} columns", self[Unit::Columns])?;
        let linked = self[Unit::Columns] + self[Unit::Products] > 0;
        for (unit, k) in self.paid().filter(|&(u, _)| u != Unit::Columns) {
            match unit {
                Unit::Links if linked => write!(f, " ({k} links)")?,
                other => write!(f, " + {k} {}", other.name())?,
            }
        }
        Ok(())
    }
}

#[cfg(feature = "serde")]
impl serde::Serialize for Cost {
    /// As flat keys: `clock`, every unit's [`Unit::key`], `seconds`, `ff_seconds`,
    /// `group_seconds`.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(Unit::ALL.len() + 4))?;
        map.serialize_entry("clock", self.clock.name())?;
        for unit in Unit::ALL {
            map.serialize_entry(unit.key(), &self[unit])?;
        }
        map.serialize_entry("seconds", &self.seconds())?;
        map.serialize_entry("ff_seconds", &self.ff_seconds)?;
        map.serialize_entry("group_seconds", &self.group_seconds)?;
        map.end()
    }
}
