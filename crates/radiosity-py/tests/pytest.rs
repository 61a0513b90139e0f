//! The Python package's pytest suite (`tests/python`), run by `cargo test --workspace`.
//!
//! The package is tested over the extension module this test was built beside: the library
//! of this crate, which cargo builds (as `cdylib` and `rlib`) before its integration tests,
//! in the same debug build as every other test, so no second build of the workspace. The
//! module is staged with the package's Python sources in `target/python-package`, and numpy,
//! scipy and pytest are installed into a virtual environment, `target/python-venv` (never
//! into the system's Python), from `tests/python/requirements.txt`; the suite runs on every
//! core (pytest-xdist). It needs Python 3.9 or later with its `venv` module (`$PYTHON`, else
//! `python3`).

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `command`, failing the test with its output unless it succeeds.
fn run(command: &mut Command, what: &str) {
    let output = command.output().unwrap_or_else(|e| panic!("could not {what}: {e} ({command:?})"));
    assert!(
        output.status.success(),
        "could not {what} ({command:?}):\n{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// The extension module cargo built for this test, beside the test's own executable.
fn extension_module() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's executable");
    let deps = exe.parent().expect("the test's folder");
    ["libradiosity_py.so", "libradiosity_py.dylib"]
        .iter()
        .map(|name| deps.join(name))
        .find(|path| path.is_file())
        .unwrap_or_else(|| panic!("cargo did not build the extension module libradiosity_py in {}", deps.display()))
}

/// Copies the package's Python sources and the extension module into `stage`.
fn stage_package(crate_dir: &Path, stage: &Path, module: &Path) {
    let package = stage.join("radiosity");
    if stage.exists() {
        std::fs::remove_dir_all(stage).expect("clear the staged package");
    }
    std::fs::create_dir_all(&package).expect("create the staged package");
    for entry in std::fs::read_dir(crate_dir.join("python/radiosity")).expect("the package's sources") {
        let path = entry.expect("a source file").path();
        if path.extension().is_some_and(|e| e == "py") {
            std::fs::copy(&path, package.join(path.file_name().expect("a file name"))).expect("copy a source file");
        }
    }
    std::fs::copy(module, package.join("_radiosity.abi3.so")).expect("copy the extension module");
}

#[test]
fn the_python_package_passes_its_pytest_suite() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let target = crate_dir.join("../../target");
    let module = extension_module();
    let venv = target.join("python-venv");
    let python = venv.join("bin/python");
    if !python.is_file() {
        let base = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
        run(
            Command::new(&base).args(["-m", "venv"]).arg(&venv),
            "create the virtual environment (needs Python 3 with venv)",
        );
    }
    let requirements = crate_dir.join("tests/python/requirements.txt");
    run(
        Command::new(&python)
            // Byte-compiling every module of scipy at install would take longer than the few
            // that are imported take to compile when they are.
            .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--no-compile", "-r"])
            .arg(&requirements),
        "install numpy, scipy and pytest into target/python-venv",
    );
    let stage = target.join("python-package");
    stage_package(crate_dir, &stage, &module);
    run(
        Command::new(&python)
            // Spread over the cores (pytest-xdist): `cargo test` runs this binary alone, and its
            // one test would otherwise keep one core busy and leave the others idle.
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "auto"])
            .arg(crate_dir.join("tests/python"))
            .env("PYTHONPATH", &stage),
        "pass the pytest suite of the Python package",
    );
}
