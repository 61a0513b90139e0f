//! Test support for scenes written by others: they are found through the setting
//! `RADIOSITY_SCENES` ([`radiosity_geom::third_party`]), and a test that needs one the checkout
//! does not have is reported as ignored, with the reason and the setting, rather than passing.
//!
//! ## Rules
//!
//! - A test target of such tests sets `harness = false` and its `main` calls [`run`] with its
//!   [`SceneTest`]s; each names the files it needs, relative to the scenes folder.
//! - The folder is the setting's, a relative one taken from the repository root (the tests'
//!   working directory is their crate's, not the root).
//! - A test whose files are all there runs. One whose files are not is ignored at run time,
//!   the reason naming the missing file, the folder and the setting (libtest-mimic's
//!   `Completion::ignored_with`, printed as `ignored (reason)`).
//! - Under `CI=true` (or `CI=1`) a missing scene is a failure instead: continuous integration
//!   always has the scenes, so it always runs these tests.

use libtest_mimic::{Arguments, Completion, Failed, Trial};
use radiosity_geom::ScenesFolder;
use radiosity_geom::third_party::SCENES_VARIABLE;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// One test that reads scenes from the third-party folder.
pub struct SceneTest {
    /// Its name, as `cargo test` filters and prints it.
    pub name: &'static str,
    /// The files it reads, relative to the scenes folder.
    pub needs: &'static [&'static str],
    /// The test: it panics to fail, as `#[test]` functions do.
    pub run: fn(&Scenes),
}

/// The scenes folder, as a test sees it.
#[derive(Clone, Debug)]
pub struct Scenes {
    folder: ScenesFolder,
}

impl Scenes {
    /// The folder the setting names, a relative one taken from the repository root.
    pub fn locate() -> Scenes {
        Scenes { folder: ScenesFolder::locate(&repository_root()) }
    }

    /// The path of `relative` in the folder, as a string for scene arguments. The file is
    /// there: [`run`] checked the test's `needs` before running it.
    pub fn path(&self, relative: &str) -> String {
        self.folder.path().join(relative).to_string_lossy().into_owned()
    }

    /// The folder, described for messages.
    pub fn describe(&self) -> String {
        self.folder.describe()
    }

    /// The files of `needs` that are not in the folder.
    fn missing<'a>(&self, needs: &[&'a str]) -> Vec<&'a str> {
        needs.iter().copied().filter(|f| self.folder.file(f).is_none()).collect()
    }
}

/// The repository's root directory.
pub fn repository_root() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    root.canonicalize().unwrap_or(root)
}

/// Whether this is a continuous-integration run (`CI=true` or `CI=1`).
fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1")
}

/// Runs `tests` under libtest-mimic with the command line's arguments (filters, `--list`,
/// `--ignored`, threads) and returns the exit code: see the module doc for what happens to a
/// test whose scenes are missing.
pub fn run(tests: Vec<SceneTest>) -> ExitCode {
    let args = Arguments::from_args();
    let scenes = Scenes::locate();
    let ci = under_ci();
    let trials = tests
        .into_iter()
        .map(|test| {
            let missing = scenes.missing(test.needs);
            let scenes = scenes.clone();
            Trial::ignorable_test(test.name, move || {
                if missing.is_empty() {
                    (test.run)(&scenes);
                    return Ok(Completion::Completed);
                }
                let why = format!(
                    "needs {} from the scenes folder {}; set {SCENES_VARIABLE} to a folder holding it (README, \"Scenes\")",
                    missing.join(", "),
                    scenes.describe()
                );
                if ci { Err(Failed::from(format!("{why}; under CI a missing scene is a failure"))) } else { Ok(Completion::ignored_with(why)) }
            })
        })
        .collect();
    libtest_mimic::run(&args, trials).exit_code()
}
