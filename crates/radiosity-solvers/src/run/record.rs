//! A solver's own figures at the end of a run, as an ordered list of keys and typed values.
//!
//! What a run costs and where it stands is the same for every solver and lives in
//! [`crate::State`]. What only some solvers know (how many group steps ran, how large their
//! groups were, the worst condition number met, how often a group fell back) is theirs to
//! report: [`crate::Solver::record`] returns a [`Record`], and the executor stores it in
//! [`crate::Run::record`]. A caller prints every entry in order, or asks for the keys it
//! knows ([`Record::count`], [`Record::real`]). The keys of the built-in solvers are listed
//! where they are recorded ([`crate::group::group_step::GroupStats`],
//! [`crate::group::group_accelerated`]).

use radiosity_core::Real;
use std::fmt;

/// One value of a [`Record`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Value {
    /// A count of things (steps, fallbacks, patches).
    Count(u64),
    /// A real number (a mean, a condition number; may be infinite).
    Real(Real),
    /// A text.
    Text(String),
}

impl From<u64> for Value {
    fn from(v: u64) -> Value {
        Value::Count(v)
    }
}

impl From<usize> for Value {
    fn from(v: usize) -> Value {
        Value::Count(v as u64)
    }
}

impl From<Real> for Value {
    fn from(v: Real) -> Value {
        Value::Real(v)
    }
}

impl From<String> for Value {
    fn from(v: String) -> Value {
        Value::Text(v)
    }
}

impl From<&str> for Value {
    fn from(v: &str) -> Value {
        Value::Text(v.to_string())
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Count(v) => write!(f, "{v}"),
            Value::Real(v) => write!(f, "{v}"),
            Value::Text(v) => write!(f, "{v}"),
        }
    }
}

/// An ordered list of `key = value` entries, each key at most once.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Record {
    entries: Vec<(String, Value)>,
}

impl Record {
    /// An empty record.
    pub fn new() -> Record {
        Record::default()
    }

    /// Sets `key` to `value`: in place if the key is there, at the end otherwise.
    pub fn set(&mut self, key: impl Into<String>, value: impl Into<Value>) -> &mut Record {
        let (key, value) = (key.into(), value.into());
        match self.entries.iter_mut().find(|(k, _)| *k == key) {
            Some((_, slot)) => *slot = value,
            None => self.entries.push((key, value)),
        }
        self
    }

    /// The record with `key` set to `value` ([`Record::set`]), for building one in an
    /// expression.
    #[must_use]
    pub fn with(mut self, key: impl Into<String>, value: impl Into<Value>) -> Record {
        self.set(key, value);
        self
    }

    /// The value of `key`, if recorded.
    pub fn get(&self, key: &str) -> Option<&Value> {
        self.entries.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// The value of `key` if it is a count.
    pub fn count(&self, key: &str) -> Option<u64> {
        match self.get(key)? {
            Value::Count(v) => Some(*v),
            _ => None,
        }
    }

    /// The value of `key` if it is a real number.
    pub fn real(&self, key: &str) -> Option<Real> {
        match self.get(key)? {
            Value::Real(v) => Some(*v),
            _ => None,
        }
    }

    /// The value of `key` if it is a text.
    pub fn text(&self, key: &str) -> Option<&str> {
        match self.get(key)? {
            Value::Text(v) => Some(v),
            _ => None,
        }
    }

    /// The entries, in the order they were first set.
    pub fn iter(&self) -> Entries<'_> {
        Entries(self.entries.iter())
    }

    /// The number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there is no entry.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// The entries of a [`Record`], in order ([`Record::iter`]).
#[derive(Clone, Debug)]
pub struct Entries<'r>(std::slice::Iter<'r, (String, Value)>);

impl<'r> Iterator for Entries<'r> {
    type Item = (&'r str, &'r Value);

    fn next(&mut self) -> Option<Self::Item> {
        self.0.next().map(|(k, v)| (k.as_str(), v))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.0.size_hint()
    }
}

impl ExactSizeIterator for Entries<'_> {}

impl<'r> IntoIterator for &'r Record {
    type Item = (&'r str, &'r Value);
    type IntoIter = Entries<'r>;

    fn into_iter(self) -> Entries<'r> {
        self.iter()
    }
}

/// `key=value` entries in order, separated by `, ` (empty for an empty record).
impl fmt::Display for Record {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (at, (key, value)) in self.entries.iter().enumerate() {
            if at > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{key}={value}")?;
        }
        Ok(())
    }
}
