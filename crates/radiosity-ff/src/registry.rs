//! Form-factor backends by name: the [`BackendRegistry`] that reads `NAME[:key=value…]` into a
//! [`BackendSpec`] through the parsers its backends were registered with.
//!
//! ## Rule
//!
//! A backend is registered under a name, with a help line, the `key=value` parameters it takes
//! ([`ParamDoc`]) and a parser of the items after the name: typed, from a parameter struct that
//! implements [`BackendParams`] ([`BackendRegistry::register`]; the keys are checked against its
//! [`BackendParams::PARAMS`] before it reads them), or as a closure
//! ([`BackendRegistry::register_fn`], which also gets the registry, so that a backend naming
//! another, as `matrix`'s `of`, reads it through the same names). A parser gives a
//! [`BackendArgument`]: what the parameters are, their canonical argument, and how to build the
//! source ([`FormFactorBackend`](crate::FormFactorBackend)) from the scene.
//!
//! [`BackendRegistry::parse`] looks the name up; the first entry of that name decides (a
//! later entry of the same name is never reached: start from [`BackendRegistry::empty`] to
//! give a built-in name another meaning). An unknown name is [`FfError::UnknownBackend`], with
//! the list of names ([`BackendRegistry::names`]) and, when a known name is within
//! [`radiosity_core::suggest::suggestion_distance`] edits (Damerau–Levenshtein), that name as a
//! suggestion. Refused parameters are one sentence beginning `form-factor backend 'NAME'` and
//! naming the key ([`KeyValueParams`]).
//!
//! This file names no backend. The built-ins ([`BackendRegistry::builtin`]), in this order:
//! `analytic`, `hemicube`, `montecarlo`, `hierarchical` and `matrix` ([`crate::builtins`]).
//!
//! ## References
//!
//! - Damerau 1964, "A technique for computer detection and correction of spelling errors",
//!   Communications of the ACM 7(3).

use crate::error::FfError;
use crate::spec::{BackendArgument, BackendParams, BackendSpec};
use radiosity_geom::{KeyValueParams, ParamDoc};
use std::fmt;
use std::sync::Arc;

/// What a registry entry does with the items after the name.
type ParseFn = dyn Fn(&[&str], &BackendRegistry) -> Result<Arc<dyn BackendArgument>, FfError> + Send + Sync;

/// One backend of a [`BackendRegistry`].
#[derive(Clone)]
pub struct BackendEntry {
    name: String,
    help: String,
    params: &'static [ParamDoc],
    parse: Arc<ParseFn>,
}

impl BackendEntry {
    /// The name on the command line.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// What the backend does, in one line.
    pub fn help(&self) -> &str {
        &self.help
    }

    /// The `key=value` parameters it takes.
    pub fn params(&self) -> &'static [ParamDoc] {
        self.params
    }
}

impl fmt::Debug for BackendEntry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("BackendEntry").field("name", &self.name).field("help", &self.help).finish_non_exhaustive()
    }
}

/// Form-factor backends by name (module doc).
#[derive(Clone, Debug, Default)]
pub struct BackendRegistry {
    entries: Vec<BackendEntry>,
}

impl BackendRegistry {
    /// A registry with no backend: every name is unknown until backends are registered.
    pub fn empty() -> BackendRegistry {
        BackendRegistry::default()
    }

    /// Adds the backend of parameter struct `P`, after those already there.
    pub fn register<P: BackendParams>(&mut self) -> &mut BackendRegistry {
        self.register_fn(P::NAME, P::HELP, P::PARAMS, |items, _| {
            let params = KeyValueParams::parse(&owner(P::NAME), items.iter().copied(), P::PARAMS)?;
            Ok(Arc::new(P::from_params(&params)?))
        })
    }

    /// Adds a backend, after those already there, from its name, help line, parameters and a
    /// closure that reads the items after the name (`["res=64", "seed=3"]`) with this registry
    /// at hand; its refusals should begin `form-factor backend 'NAME'` and name the key, as
    /// [`KeyValueParams`]'s do.
    pub fn register_fn<F>(
        &mut self,
        name: impl Into<String>,
        help: impl Into<String>,
        params: &'static [ParamDoc],
        parse: F,
    ) -> &mut BackendRegistry
    where
        F: Fn(&[&str], &BackendRegistry) -> Result<Arc<dyn BackendArgument>, FfError> + Send + Sync + 'static,
    {
        self.entries.push(BackendEntry { name: name.into(), help: help.into(), params, parse: Arc::new(parse) });
        self
    }

    /// The backends, in the order they are listed.
    pub fn entries(&self) -> &[BackendEntry] {
        &self.entries
    }

    /// Parses `NAME[:key=value…]`.
    pub fn parse(&self, arg: &str) -> Result<BackendSpec, FfError> {
        let mut parts = arg.split(':').filter(|s| !s.is_empty());
        let name = parts.next().unwrap_or_default();
        let items: Vec<&str> = parts.collect();
        self.parse_named(name, &items)
    }

    /// Parses the backend `name` with the items after it.
    pub fn parse_named(&self, name: &str, items: &[&str]) -> Result<BackendSpec, FfError> {
        let Some(entry) = self.entries.iter().find(|e| e.name == name) else {
            return Err(FfError::UnknownBackend {
                name: name.to_string(),
                valid: self.names(),
                suggestion: self.suggest(name),
            });
        };
        Ok(BackendSpec::from_argument(&entry.name, (entry.parse)(items, self)?))
    }

    /// The names, comma-separated, in order.
    pub fn names(&self) -> String {
        self.entries.iter().map(|e| e.name.as_str()).collect::<Vec<_>>().join(", ")
    }

    /// A help text for a command line: one line per backend, its name and what it does, then
    /// one line per parameter with its default; each line ends with a newline.
    pub fn help(&self) -> String {
        let width = self.entries.iter().map(|e| e.name.chars().count()).max().unwrap_or(0);
        let mut out = String::new();
        for entry in &self.entries {
            out.push_str(&format!("{:width$}  {}\n", entry.name, entry.help));
            for p in entry.params {
                out.push_str(&format!("{:width$}    {}={}: {}\n", "", p.key, p.default, p.doc));
            }
        }
        out
    }

    /// The known name nearest to `name`, if one is near enough to be a typo (module doc).
    pub fn suggest(&self, name: &str) -> Option<String> {
        radiosity_core::suggest::nearest(name, self.entries.iter().map(|e| e.name.as_str())).map(str::to_string)
    }
}

/// The owner named by a backend's refusals: `form-factor backend 'NAME'`.
pub fn owner(name: &str) -> String {
    format!("form-factor backend '{name}'")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{BuildObserver, FormFactorBackend, FormFactorInput};
    use radiosity_core::{ColumnSource, Real};
    use radiosity_geom::{SceneAnalysis, Visibility, load_scene};

    /// `F_ij = c` off the diagonal: a backend of one's own, registered with a closure.
    #[derive(Debug)]
    struct Uniform(Real);

    struct UniformColumns(usize, Real);

    impl ColumnSource for UniformColumns {
        fn patch_count(&self) -> usize {
            self.0
        }

        fn fill_column(&self, j: usize, column: &mut [Real]) {
            column.iter_mut().enumerate().for_each(|(i, f)| *f = if i == j { 0.0 } else { self.1 });
        }
    }

    impl FormFactorBackend for UniformColumns {}

    impl BackendArgument for Uniform {
        fn canonical(&self) -> String {
            format!("uniform:c={}", self.0)
        }

        fn build<'a>(
            &self,
            input: FormFactorInput<'a>,
            _: &dyn BuildObserver,
        ) -> Result<Box<dyn FormFactorBackend + 'a>, FfError> {
            Ok(Box::new(UniformColumns(input.scene.len(), self.0)))
        }
    }

    const UNIFORM_PARAMS: &[ParamDoc] = &[ParamDoc { key: "c", default: "0.1", doc: "every entry" }];

    fn with_uniform() -> BackendRegistry {
        let mut registry = BackendRegistry::builtin();
        registry.register_fn("uniform", "every entry c", UNIFORM_PARAMS, |items, _| {
            let p = KeyValueParams::parse(&owner("uniform"), items.iter().copied(), UNIFORM_PARAMS)?;
            Ok(Arc::new(Uniform(p.real("c", 0.1, |c| (0.0..=1.0).contains(&c), "an entry in [0, 1]")?)))
        });
        registry
    }

    #[test]
    fn the_built_ins_are_listed_in_order_and_typos_get_the_nearest_name() {
        let registry = BackendRegistry::builtin();
        assert_eq!(registry.names(), "analytic, hemicube, montecarlo, hierarchical, matrix");
        assert_eq!(registry.suggest("hemicub").as_deref(), Some("hemicube"));
        assert_eq!(registry.suggest("radiance"), None);
        let e = registry.parse("analytc:order=2").unwrap_err().to_string();
        assert!(e.contains("unknown form-factor backend 'analytc' (did you mean 'analytic'?)"), "{e}");
        let help = registry.help();
        for entry in registry.entries() {
            assert!(help.contains(entry.name()), "{help}");
            entry.params().iter().for_each(|p| assert!(help.contains(&format!("{}={}", p.key, p.default)), "{help}"));
        }
        assert!(BackendRegistry::empty().parse("analytic").is_err());
    }

    #[test]
    fn a_registered_backend_parses_builds_and_is_stored_as_a_matrix() {
        let registry = with_uniform();
        let spec = registry.parse("uniform:c=0.25").unwrap();
        assert_eq!((spec.name(), spec.canonical().as_str()), ("uniform", "uniform:c=0.25"));
        let e = registry.parse("uniform:c=2").unwrap_err().to_string();
        assert!(e.contains("form-factor backend 'uniform'") && e.contains("c=2"), "{e}");
        assert!(BackendRegistry::builtin().parse("uniform").is_err());

        let scene = load_scene("furnace:res=2").unwrap().scene;
        let visibility = Visibility::new(&scene);
        let analysis = SceneAnalysis::new(&scene, &visibility);
        let input = FormFactorInput { scene: &scene, visibility: visibility.clone(), analysis: &analysis };
        let stored = registry.parse("matrix:of=uniform:c=0.25").unwrap();
        assert_eq!(stored.canonical(), "matrix:of=uniform:rebalance=false:c=0.25");
        assert!(!stored.pairs_once(), "a column backend is assembled column by column");
        let built = stored.build(input).unwrap();
        let matrix = built.stored().expect("a stored matrix");
        let n = scene.len();
        for (i, j) in [(0, 1), (1, 0), (3, 3), (n - 1, 0)] {
            assert_eq!(matrix.get(i, j), if i == j { 0.0 } else { 0.25 }, "({i}, {j})");
        }
        let e = registry.parse("matrix:of=matrix").unwrap_err().to_string();
        assert!(e.contains("of=matrix") && e.contains("assembled from a column backend"), "{e}");
    }
}
