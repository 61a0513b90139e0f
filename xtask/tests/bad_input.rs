//! Every kind of bad input, through the commands that do the work (`solve` above all, also
//! `compare`, `render`, `export` and `ff`): each fails with one clear sentence on stderr, exit
//! code 1, no panic, and the sentence names what was wrong.
//!
//! Every failure here happens before any heavy work: arguments are checked before geometry
//! is built, files fail while loading, and output paths are checked before solving. Where a
//! command must load a scene first, the scene is small (`furnace:res=2`).

use super::{failure, fixture};
use std::path::PathBuf;

/// Runs a command that must fail and checks the sentence contains every one of `words`.
fn refused(args: &[&str], words: &[&str]) -> String {
    let e = failure(args);
    for w in words {
        assert!(e.contains(w), "{args:?}: expected '{w}' in {e}");
    }
    e
}

/// `solve --scene SCENE --solver pr`, which must fail naming `words`.
fn solve_refuses(scene: &str, words: &[&str]) {
    refused(&["solve", "--scene", scene, "--solver", "pr", "--until", "steps=1"], words);
}

/// A path in a fresh temporary folder of this test process, which the test removes.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("radiosity-bad-input-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    fn path(&self, name: &str) -> String {
        self.0.join(name).to_str().unwrap().to_string()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn bad_gltf_files_are_refused_by_every_command() {
    // (fixture, words the sentence must contain besides the file's name)
    let cases: [(&str, &[&str]); 7] = [
        ("white.gltf", &["material 'snow'", "reflectivity 1", "below 1"]),
        ("nan.gltf", &["mesh 'broken'", "NaN or infinite", "POSITION"]),
        ("no_position.gltf", &["mesh 'normals only'", "no POSITION attribute"]),
        ("truncated.glb", &["truncated", "binary glTF header"]),
        ("garbage.gltf", &["not glTF JSON"]),
        ("bad_index.gltf", &["mesh 'holey'", "vertex 7"]),
        ("lines.gltf", &["mesh 'wire'", "mode LINES"]),
    ];
    for (file, words) in cases {
        let path = fixture(file);
        let e = refused(&["solve", "--scene", &path, "--solver", "pr"], words);
        assert!(e.contains(&path), "{file}: the sentence names the file: {e}");
    }
    // The other commands load scenes the same way and say the same.
    let dir = TempDir::new("gltf");
    let (png, glb) = (dir.path("never.png"), dir.path("never.glb"));
    let white = fixture("white.gltf");
    refused(&["ff", "--scene", &white], &["white.gltf", "material 'snow'"]);
    refused(&["compare", "--scene", &fixture("nan.gltf"), "--solvers", "pr"], &["nan.gltf", "NaN or infinite"]);
    refused(&["render", "--scene", &fixture("truncated.glb"), "--solver", "pr", "--out", &png], &["truncated.glb"]);
    refused(&["export", "--scene", &fixture("garbage.gltf"), "--solver", "pr", "--out", &glb], &["garbage.gltf"]);
    assert!(std::fs::read_dir(&dir.0).unwrap().next().is_none(), "nothing was written");
}

#[test]
fn bad_mgf_files_are_refused() {
    // (fixture, words the sentence must contain besides the file's name and line)
    let cases: [(&str, &[&str]); 7] = [
        ("mgf/not_a_name.mgf", &["it has no faces", "skipped 1 line whose first word is not an entity name"]),
        ("mgf/undefined_vertex.mgf", &["undefined vertex 'v12'"]),
        ("mgf/undefined_material.mgf", &["undefined material 'nowhere'"]),
        ("mgf/cycle_a.mgf", &["cycle_a.mgf", "include cycle"]),
        ("mgf/missing_include.mgf", &["cannot read included file", "no_such_file.mgf"]),
        ("mgf/two_vertices.mgf", &["it has no faces", "skipped 1 face or hole with fewer than 3 vertices"]),
        (
            "mgf/nested_arrays.mgf",
            &["nested_arrays.mgf:12", "would make 1000000000000 instances", "more than the 1000000 a file may create"],
        ),
    ];
    for (file, words) in cases {
        let e = refused(&["solve", "--scene", &fixture(file), "--solver", "pr"], words);
        assert!(e.contains(".mgf:"), "{file}: the sentence names the file and line: {e}");
    }
    refused(
        &["compare", "--scene", &fixture("mgf/not_a_name.mgf"), "--solvers", "pr"],
        &["not_a_name.mgf:3", "no usable triangles"],
    );
    // A file that would make too much is refused by every command that loads it, at once.
    refused(&["scenes", "--explain", &fixture("mgf/nested_arrays.mgf")], &["nested_arrays.mgf:12", "instances"]);
}

#[test]
fn bad_scene_parameters_are_refused() {
    // Every count that sets a scene's resolution, negative and zero.
    let mgf = fixture("mgf/basic.mgf");
    let counts = [
        ("furnace", "res", "from 1 to 1000"),
        ("cornell", "res", "from 1 to 1000"),
        ("inner-box", "res", "from 1 to 1000"),
        ("multi-cubes", "divisions", "from 1 to 200"),
        ("labyrinth", "cells", "from 1 to 100"),
        ("labyrinth", "lights", "from 1 to 121"),
        (mgf.as_str(), "div", "from 1 to 64"),
    ];
    for (scene, key, range) in counts {
        for value in ["-1", "0"] {
            let param = format!("{key}={value}");
            solve_refuses(&format!("{scene}:{param}"), &[scene, &param, "is invalid", range]);
        }
    }
    // The scenes sized by a patch edge in metres.
    for (scene, range) in [("office", "from 0.01 to 10"), ("labyrinth", "from 0.02 to 10")] {
        for value in ["-1", "0"] {
            let param = format!("size={value}");
            solve_refuses(&format!("{scene}:{param}"), &[scene, &param, range]);
        }
    }
    solve_refuses("labyrinth:cells=2:lights=5", &["lights=5", "from 1 to 4"]);
    solve_refuses("office:desks=10", &["office", "desks=10", "from 0 to 9"]);

    // Reflectivities at or above 1 and below 0, grey or RGB.
    for rho in ["1", "1.5", "-0.1", "0.5/1/0.2", "0.5/-0.1/0.2", "0.5/0.5"] {
        let param = format!("rho={rho}");
        solve_refuses(&format!("furnace:res=2:{param}"), &["furnace", &param, "[0, 1)"]);
    }
    solve_refuses("inner-box:res=2:rho=0.2/0.5/1", &["inner-box", "rho=0.2/0.5/1", "[0, 1)"]);
    solve_refuses("furnace:res=2:emission=-1", &["emission=-1", ">= 0"]);
    solve_refuses("multi-cubes:cube=1", &["multi-cubes", "cube=1", "(0, 1)"]);

    // Values that are not numbers (or not the right kind of number).
    solve_refuses("furnace:res=abc", &["furnace", "res=abc", "an integer"]);
    solve_refuses("cornell:res=2.5", &["cornell", "res=2.5", "an integer"]);
    solve_refuses("cornell:res=", &["cornell", "res=", "an integer"]);
    solve_refuses("furnace:res=2:rho=abc", &["rho=abc", "a reflectivity"]);
    solve_refuses("furnace:res=2:rho=nan", &["rho=nan", "a reflectivity"]);
    solve_refuses("multi-cubes:cube=nan", &["cube=nan"]);
    solve_refuses("furnace:res=2:block=maybe", &["block=maybe", "true or false"]);
    solve_refuses("labyrinth:seed=-1", &["seed=-1", "seed"]);

    // Unknown keys, on built-in scenes and on files; and a key without a value.
    solve_refuses("furnace:colour=red", &["scene 'furnace'", "no parameter 'colour'", "res, rho, emission, block"]);
    solve_refuses("office:res=4", &["scene 'office'", "no parameter 'res'", "size, desks, light"]);
    let quad = fixture("quad.gltf");
    solve_refuses(&format!("{quad}:bogus=1"), &[&quad, "no parameter 'bogus'", "size"]);
    solve_refuses(&format!("{mgf}:res=2"), &[&mgf, "no parameter 'res'", "size, div"]);
    solve_refuses("cornell:res", &["'res'", "key=value"]);
    solve_refuses("multicubes", &["unknown scene 'multicubes'", "multi-cubes"]);

    // The other commands check scenes the same way.
    refused(&["compare", "--scene", "furnace:res=0", "--solvers", "pr"], &["res=0", "from 1 to 1000"]);
    refused(&["ff", "--scene", "furnace:rho=1"], &["rho=1", "[0, 1)"]);
}

#[test]
fn a_scene_that_emits_nothing_is_refused_before_any_form_factor() {
    // Its radiosity is zero everywhere: there is no relative error to measure.
    let e = refused(
        &["solve", "--scene", "furnace:res=2:emission=0", "--solver", "pr"],
        &["scene 'furnace:res=2:emission=0'", "emits no light"],
    );
    assert!(e.contains("no error to measure"), "{e}");
    refused(&["compare", "--scene", "furnace:res=2:emission=0", "--solvers", "pr"], &["emits no light"]);
}

#[test]
fn bad_stop_rules_are_refused() {
    // (rule, what the sentence says is wrong with it)
    let cases = [
        ("columns=0", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("columns=-3", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("columns=2x", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("columns=2.5", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("rays=0", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("rays=1e-3", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("steps=", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("steps=0", "a positive integer (such as 480 or 1e7) or a multiple of n"),
        ("rms=0", "a positive number"),
        ("rms=-1", "a positive number"),
        ("rms=abc", "a positive number"),
        ("residual=nan", "a positive number"),
        ("residual=0", "a positive number"),
        ("time=5", "a duration with a unit"),
        ("time=abc", "a duration with a unit"),
        ("time=-1s", "a positive number"),
        ("bogus=1", "unknown rule"),
        ("columns", "key=value"),
    ];
    for (rule, reason) in cases {
        let e = refused(
            &["solve", "--scene", "furnace:res=2", "--solver", "pr", "--until", rule],
            &[&format!("invalid stop rule '{rule}'"), reason],
        );
        assert!(e.contains("rules are columns=N"), "{rule}: the sentence lists the rules: {e}");
    }
    // A bad rule among good ones is named alone.
    refused(
        &["solve", "--scene", "furnace:res=2", "--solver", "pr", "--until", "steps=10,rms=-1"],
        &["invalid stop rule 'rms=-1'"],
    );
    let dir = TempDir::new("rules");
    let png = dir.path("never.png");
    let glb = dir.path("never.glb");
    let compare = ["compare", "--scene", "furnace:res=2", "--solvers", "pr", "--until", "time=5"];
    refused(&compare, &["invalid stop rule 'time=5'"]);
    let render = ["render", "--scene", "furnace:res=2", "--solver", "pr", "--until", "rms=0", "--out", &png];
    refused(&render, &["invalid stop rule 'rms=0'"]);
    let export = ["export", "--scene", "furnace:res=2", "--solver", "pr", "--until", "steps=", "--out", &glb];
    refused(&export, &["invalid stop rule 'steps='"]);
    assert!(std::fs::read_dir(&dir.0).unwrap().next().is_none(), "nothing was written");
}

#[test]
fn bad_backends_are_refused() {
    // (backend, words of the sentence)
    let cases: [(&str, &[&str]); 17] = [
        (
            "radiance",
            &["unknown form-factor backend 'radiance'", "analytic, hemicube, montecarlo, hierarchical, matrix"],
        ),
        ("analytic:rays=0", &["backend 'analytic'", "rays=0", "from 1 to"]),
        ("analytic:order=0", &["backend 'analytic'", "order=0", "from 1 to 32"]),
        ("analytic:tol=2", &["backend 'analytic'", "tol=2", "(0, 1]"]),
        ("analytic:tol=0", &["backend 'analytic'", "tol=0", "(0, 1]"]),
        ("hemicube:res=3", &["backend 'hemicube'", "res=3", "even"]),
        ("hemicube:res=0", &["backend 'hemicube'", "res=0", "from 2 to 4096"]),
        ("montecarlo:rays=0", &["backend 'montecarlo'", "rays=0", "from 1 to"]),
        ("hierarchical:eps=0", &["backend 'hierarchical'", "eps=0", "(0, 1]"]),
        ("hierarchical:rays=0", &["backend 'hierarchical'", "rays=0", "from 1 to 4096"]),
        ("hierarchical:shadows=2", &["backend 'hierarchical'", "shadows=2", "(0, 1]"]),
        ("hierarchical:budget=-1", &["backend 'hierarchical'", "budget=-1"]),
        ("hierarchical:oracle=light", &["backend 'hierarchical'", "oracle=light", "flux or area"]),
        ("hierarchical:floor=0", &["backend 'hierarchical'", "floor=0", "(0, 1]"]),
        ("hierarchical:passes=5", &["backend 'hierarchical'", "passes=5", "from 1 to 4"]),
        ("analytic:bogus=1", &["backend 'analytic'", "no parameter 'bogus'", "order, tol, rays, budget, seed"]),
        ("matrix:rebalance=maybe", &["backend 'matrix'", "rebalance=maybe", "true or false"]),
    ];
    for (backend, words) in cases {
        refused(&["solve", "--scene", "furnace:res=2", "--solver", "pr", "--ff", backend], words);
    }
    // The stored matrix of another backend checks that backend's parameters.
    refused(
        &["solve", "--scene", "furnace:res=2", "--solver", "pr", "--ff", "matrix:of=hemicube:res=3"],
        &["backend 'hemicube'", "res=3"],
    );
    // Conjugate gradients need reciprocal form factors: refused in one sentence that names
    // the solvers that need none.
    refused(
        &["solve", "--scene", "furnace:res=2", "--solver", "cg", "--ff", "hemicube:res=16"],
        &["cg cannot solve this system", "state no reciprocity bound", "gmres-30 and bicgstab need no symmetry"],
    );
    let e = failure(&["solve", "--scene", "furnace:res=2", "--solver", "pr", "--ff", "matrix:of=matrix"]);
    assert!(e.contains("of=matrix") && e.contains("assembled from a column backend"), "{e}");
    let e = failure(&["solve", "--scene", "furnace:res=2", "--solver", "pr", "--ff", "analytic:order"]);
    assert!(e.contains("backend 'analytic'") && e.contains("'order'") && e.contains("key=value"), "{e}");

    let dir = TempDir::new("backends");
    let png = dir.path("never.png");
    let glb = dir.path("never.glb");
    refused(&["ff", "--scene", "furnace:res=2", "--ff", "hemicube:res=3"], &["hemicube", "res=3"]);
    refused(&["compare", "--scene", "furnace:res=2", "--solvers", "pr", "--ff", "montecarlo:rays=0"], &["rays=0"]);
    refused(
        &["render", "--scene", "furnace:res=2", "--solver", "pr", "--ff", "analytic:tol=2", "--out", &png],
        &["tol=2"],
    );
    refused(
        &["export", "--scene", "furnace:res=2", "--solver", "pr", "--ff", "nonsense", "--out", &glb],
        &["'nonsense'"],
    );
    assert!(std::fs::read_dir(&dir.0).unwrap().next().is_none(), "nothing was written");
}

#[test]
fn bad_solvers_are_refused() {
    let solve = |solver: &str, words: &[&str]| {
        refused(&["solve", "--scene", "furnace:res=2", "--solver", solver], words);
    };
    // An unknown name: one sentence, and where every family is listed.
    solve("magic", &["unknown solver 'magic'", "cargo xtask solve --help"]);
    solve("sor-abc", &["unknown solver 'sor-abc'", "cargo xtask solve --help"]);
    solve("sor-2.5", &["solver 'sor-2.5'", "0 < ω < 2", "not 2.5"]);
    solve("sor-0", &["solver 'sor-0'", "0 < ω < 2", "not 0"]);
    solve("relax-2", &["solver 'relax-2'", "0 < ω < 2", "not 2"]);
    solve("xu-g0", &["solver 'xu-g0'", "at least one patch"]);
    solve("group-pr-g0", &["solver 'group-pr-g0'", "at least one patch"]);
    solve("pr-g30-m10", &["solver 'pr-g30-m10'", "memory (m10)", "group (g30)"]);
    solve("pr-g30:f=0", &["solver 'pr-g30:f=0'", "'f=0'", "f=auto, f=timed or f ≥ 1"]);
    solve("pr-g30:groups=bogus", &["solver 'pr-g30:groups=bogus'", "'groups=bogus'", "unshot", "interaction"]);
    solve("group-gs-g30:groups=bogus", &["solver 'group-gs-g30'", "'groups=bogus'", "index", "spatial"]);
    solve("xu-g30:bogus=1", &["'bogus=1' is not a parameter"]);
    solve("southwell-g30", &["solver 'southwell-g30'", "group acceleration", "not to southwell"]);
    solve("pr:f=10", &["solver 'pr' takes no parameters", "'f=10'"]);

    // compare names the solver the same way, without the `reference` of `solve`.
    let e =
        refused(&["compare", "--scene", "furnace:res=2", "--solvers", "pr,sor-0"], &["solver 'sor-0'", "0 < ω < 2"]);
    assert!(!e.contains("reference"), "{e}");
    let dir = TempDir::new("solvers");
    let png = dir.path("never.png");
    let glb = dir.path("never.glb");
    refused(&["render", "--scene", "furnace:res=2", "--solver", "xu-g0", "--out", &png], &["solver 'xu-g0'"]);
    refused(&["export", "--scene", "furnace:res=2", "--solver", "relax-2", "--out", &glb], &["solver 'relax-2'"]);
    assert!(std::fs::read_dir(&dir.0).unwrap().next().is_none(), "nothing was written");
}

#[test]
fn missing_scene_files_are_named() {
    let dir = TempDir::new("missing");
    for name in ["room.gltf", "room.glb", "room.mgf"] {
        let path = dir.path(name);
        refused(&["solve", "--scene", &path, "--solver", "pr"], &[&format!("cannot read {path}"), "No such file"]);
    }
    let path = dir.path("room.glb");
    refused(&["compare", "--scene", &path, "--solvers", "pr"], &[&path]);
    refused(&["ff", "--scene", &path], &[&path]);
}

#[test]
fn outputs_that_cannot_be_written_are_refused_before_solving() {
    let dir = TempDir::new("outputs");
    fn run<'a>(command: &'a str, out: &'a str) -> Vec<&'a str> {
        vec![command, "--scene", "furnace:res=2", "--solver", "pr", "--until", "steps=1", "--out", out]
    }

    // Into folders that do not exist yet: they are created, as compare creates its own.
    for (command, file) in [("solve", "run.json"), ("render", "image.png"), ("export", "solved.glb")] {
        let out = format!("{}/{command}/{file}", dir.path("new/folders"));
        super::xtask(&run(command, &out)).success();
        assert!(std::path::Path::new(&out).is_file(), "{command} did not write {out}");
    }
    // Onto an existing directory.
    for (command, name) in [("solve", "run.json"), ("render", "image.png"), ("export", "solved.glb")] {
        let out = dir.path(name);
        std::fs::create_dir(&out).unwrap();
        refused(&run(command, &out), &[&format!("cannot write {out}"), "is a directory"]);
    }
    // Below a file.
    let file = dir.path("file");
    std::fs::write(&file, b"").unwrap();
    let out = format!("{file}/run.json");
    refused(&run("solve", &out), &[&format!("cannot write {out}"), &format!("{file} is a file, not a folder")]);
    let out = format!("{file}/deeper/run.json");
    refused(&run("solve", &out), &[&format!("cannot write {out}"), &format!("{file} is a file, not a folder")]);
    // Where no folder can be made: refused in one sentence before the scene is loaded (the
    // one line on stderr is the refusal: nothing was loaded or solved).
    for command in ["solve", "render", "export"] {
        let file = match command {
            "render" => "x.png",
            "export" => "x.glb",
            _ => "x.json",
        };
        let out = format!("/proc/nope/{file}");
        refused(&run(command, &out), &[&format!("cannot write {out}"), "cannot be made"]);
    }
    let args = ["compare", "--scene", "furnace:res=2", "--solvers", "pr", "--out", "/proc/nope/r"];
    refused(&args, &["output folder /proc/nope/r", "cannot be made"]);

    // compare creates its folder, however deep...
    let folder = dir.path("a/b/c");
    let args = ["compare", "--scene", "furnace:res=2", "--solvers", "pr", "--until", "steps=4", "--out", &folder];
    super::xtask(&args).success();
    assert!(std::path::Path::new(&folder).join("report.md").exists());
    // ...but not over or below a file.
    for out in [file.clone(), format!("{file}/results")] {
        let args = ["compare", "--scene", "furnace:res=2", "--solvers", "pr", "--out", &out];
        refused(&args, &[&format!("output folder {out}"), &format!("{file} is a file")]);
    }
}

#[test]
fn typos_get_a_suggestion_in_one_sentence() {
    let solve = |scene: &str, extra: &[&str]| {
        let args = [&["solve", "--scene", scene, "--solver", "pr"][..], extra].concat();
        refused(&args, &[])
    };
    let e = solve("cornell", &["--until", "colums=2n"]);
    assert!(e.contains("unknown rule (did you mean 'columns'?)"), "{e}");
    let e = solve("cornell", &["--ff", "hierarchical:epsilon=0.1"]);
    assert!(e.contains("no parameter 'epsilon' (did you mean 'eps'?)"), "{e}");
    let e = solve("cornel", &[]);
    assert!(e.contains("unknown scene 'cornel' (did you mean 'cornell'?)"), "{e}");
    let e = solve("cornell:rez=3", &[]);
    assert!(e.contains("no parameter 'rez' (did you mean 'res'?)"), "{e}");
    let e = refused(&["solve", "--scene", "cornell", "--solver", "xuu"], &["did you mean 'xu'?", "solve --help"]);
    assert_eq!(e.lines().count(), 1, "{e}");
    refused(&["solve", "--scene", "cornell", "--solver", "refrence"], &["did you mean 'reference'"]);
    // A scene file: the scenes folder's nearest file, by its path or by its name alone.
    let dir = TempDir::new("typo-scenes");
    std::fs::create_dir_all(dir.path("mgf/salon")).unwrap();
    std::fs::write(dir.path("mgf/salon/classroom.mgf"), b"").unwrap();
    for typo in ["mgf/salon/clasroom.mgf", "clasroom.mgf"] {
        let args = ["solve", "--scene", typo, "--solver", "pr"];
        let out = super::xtask_in_env(&args, "RADIOSITY_SCENES", &dir.path("")).failure().get_output().clone();
        let e = String::from_utf8(out.stderr).unwrap();
        assert!(e.ends_with("did you mean mgf/salon/classroom.mgf?\n") && e.lines().count() == 1, "{typo}: {e}");
    }
}

#[test]
fn bad_command_lines_are_one_sentence() {
    refused(&["solve", "--scene", "furnace:res=2"], &["--solver"]);
    refused(&["solve", "--scene", "furnace:res=2", "--solver", "pr", "--frobnicate"], &["--frobnicate"]);
    refused(&["stress", "--cases", "rho-0.5"], &["unknown case 'rho-0.5'", "rho-0.999"]);
    refused(&["stress", "--backends", "radiance"], &["unknown backend 'radiance'", "analytic+closure"]);
    refused(&["stress", "--solvers", "xu-q30"], &["unknown solver 'xu-q30'"]);
    refused(&["frobnicate"], &["frobnicate"]);
}
