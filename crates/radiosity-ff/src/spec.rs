//! Backend arguments: the opaque [`BackendSpec`] a [`crate::BackendRegistry`] parses from
//! `NAME[:key=value…]`, and the traits a backend's parameters implement to be one:
//! [`BackendArgument`] (canonical argument, build, what is known before building) and
//! [`BackendParams`] (a typed backend's name, help line and parameters).
//!
//! A canonical argument ([`BackendSpec::canonical`]) spells out every parameter that changes
//! an entry, so that arguments giving the same entries give equal strings: it keys caches
//! (with [`crate::ENTRIES_REVISION`]) and labels results. `analytic`'s `cache`, which changes
//! no entry, is left out.
//!
//! This file names no backend: the built-ins' parameters, their registration and
//! [`BackendSpec::parse`] are [`crate::builtins`]'.

use crate::backend::{BuildObserver, FormFactorBackend, FormFactorInput, Unobserved};
use crate::error::FfError;
use crate::traced::ColumnRays;
use radiosity_geom::{KeyValueParams, ParamDoc};
use std::any::Any;
use std::fmt;
use std::sync::Arc;

/// A parsed backend argument: its name, its canonical argument, and how to build its source.
#[derive(Clone)]
pub struct BackendSpec {
    name: Arc<str>,
    argument: Arc<dyn BackendArgument>,
}

impl BackendSpec {
    /// The backend of typed parameters `params`.
    pub fn new<P: BackendParams>(params: P) -> BackendSpec {
        BackendSpec::from_argument(P::NAME, Arc::new(params))
    }

    /// The backend `name` with parameters `argument` (what a registry entry parsed).
    pub fn from_argument(name: &str, argument: Arc<dyn BackendArgument>) -> BackendSpec {
        BackendSpec { name: name.into(), argument }
    }

    /// The backend's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The canonical argument (module doc).
    pub fn canonical(&self) -> String {
        self.argument.canonical()
    }

    /// The parameters, when they are a `P`.
    pub fn params<P: Any>(&self) -> Option<&P> {
        (self.argument.as_ref() as &dyn Any).downcast_ref()
    }

    /// The parameters, as the registry parsed them.
    pub fn argument(&self) -> &dyn BackendArgument {
        self.argument.as_ref()
    }

    /// Builds the source on `input` (a stored matrix is assembled, without a cache).
    pub fn build<'a>(&self, input: FormFactorInput<'a>) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        self.argument.build(input, &Unobserved)
    }

    /// Builds the source on `input`, reporting its stages to `observer`.
    pub fn build_observed<'a>(
        &self,
        input: FormFactorInput<'a>,
        observer: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        self.argument.build(input, observer)
    }

    /// For a stored matrix, the backend it stores and whether it is rebalanced
    /// ([`BackendArgument::stores`]).
    pub fn stores(&self) -> Option<(&BackendSpec, bool)> {
        self.argument.stores()
    }

    /// The backend whose columns are computed: the one a stored matrix stores, or this one.
    pub fn columns(&self) -> &BackendSpec {
        self.stores().map_or(self, |(of, _)| of)
    }

    /// Whether the columns' backend gives single entries reciprocal by construction, so that a
    /// matrix is assembled each pair once ([`BackendArgument::pairs_once`]).
    pub fn pairs_once(&self) -> bool {
        self.columns().argument.pairs_once()
    }

    /// The rays each column traces ([`BackendArgument::column_rays`]).
    pub fn column_rays<'a>(&self, input: FormFactorInput<'a>) -> Option<ColumnRays<'a>> {
        self.argument.column_rays(input)
    }
}

/// Equal when the names and the canonical arguments are: the two give the same entries
/// (`analytic:cache=0` equals `analytic`).
impl PartialEq for BackendSpec {
    fn eq(&self, other: &BackendSpec) -> bool {
        self.name == other.name && self.canonical() == other.canonical()
    }
}

impl fmt::Debug for BackendSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("BackendSpec").field(&self.canonical()).finish()
    }
}

impl fmt::Display for BackendSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.canonical())
    }
}

/// A backend's parsed parameters: what a [`BackendSpec`] holds. Implemented by every backend's
/// parameter struct (through [`BackendParams`] for typed ones).
pub trait BackendArgument: Any + fmt::Debug + Send + Sync {
    /// The argument with every parameter that changes an entry spelled out, beginning with the
    /// name: arguments that give the same entries give equal strings, so it keys caches.
    fn canonical(&self) -> String;

    /// Builds the source on `input`, reporting its stages to `observer`.
    fn build<'a>(
        &self,
        input: FormFactorInput<'a>,
        observer: &dyn BuildObserver,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError>;

    /// Whether the source gives single entries reciprocal by construction
    /// ([`FormFactorBackend::pairs`]), so that its matrix is assembled each pair once: known
    /// before building, since it names the assembly in cache keys. False by default.
    fn pairs_once(&self) -> bool {
        false
    }

    /// For a stored matrix: the backend it stores and whether it is rebalanced. `None` by
    /// default.
    fn stores(&self) -> Option<(&BackendSpec, bool)> {
        None
    }

    /// The cache kind under which a built source is kept ([`FormFactorBackend::persist`]) and
    /// read back ([`Self::load`]), for a backend whose build is worth keeping. `None` by
    /// default.
    fn cache_kind(&self) -> Option<&'static str> {
        None
    }

    /// The source written by [`FormFactorBackend::persist`] under `key`, read back for
    /// `input`'s scene. Refused by default.
    fn load<'a>(
        &self,
        _bytes: &[u8],
        _key: &str,
        _input: FormFactorInput<'a>,
    ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
        Err(FfError::NotPersistent(self.canonical()))
    }

    /// The rays each column traces, listed without computing it ([`ColumnRays`]); `None` by
    /// default (a backend that traces nothing per column).
    fn column_rays<'a>(&self, _input: FormFactorInput<'a>) -> Option<ColumnRays<'a>> {
        None
    }
}

/// A typed backend: its name, help line and parameters, and how it reads them
/// ([`BackendRegistry::register`](crate::BackendRegistry::register)).
pub trait BackendParams: BackendArgument + Sized {
    /// The name on the command line.
    const NAME: &'static str;
    /// What the backend does, in one line.
    const HELP: &'static str;
    /// The keys it takes, with their defaults.
    const PARAMS: &'static [ParamDoc];
    /// The parameters from `params`, whose keys are known to be among [`Self::PARAMS`];
    /// refusals name the key ([`KeyValueParams::reject`]).
    fn from_params(params: &KeyValueParams) -> Result<Self, FfError>;
}

impl<'a> ColumnRays<'a> {
    /// The rays of the backend `spec` names, on `input` ([`BackendSpec::column_rays`]): `None`
    /// for `matrix`, which traces nothing once stored, and for `hierarchical`, whose rays are
    /// traced once, when it is built.
    pub fn new(spec: &BackendSpec, input: FormFactorInput<'a>) -> Option<ColumnRays<'a>> {
        spec.column_rays(input)
    }
}
