//! The peer's process times ([`radiosity_eval::bench::peer`]) on stand-in programs whose costs
//! are known: sleeping costs wall time and no CPU, computing costs CPU no greater than the wall
//! time of a single-threaded program, a failing program is an error, and without an executable
//! the report says it has no peer measurement.

use radiosity_eval::bench::peer::{self, NO_PEER, Peer, PeerCase, PeerRun};
use std::path::{Path, PathBuf};

/// A shell script in a folder of this test's own, made executable.
fn script(name: &str, body: &str) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let dir = std::env::temp_dir().join(format!("radiosity-peer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, format!("#!/bin/sh\n{body}\n")).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    path
}

#[test]
fn sleeping_costs_wall_time_and_computing_costs_cpu() {
    let sleeper = script("sleeper", "sleep 0.4");
    let t = peer::time_process(&sleeper, &[]).unwrap();
    assert!(t.wall >= 0.4, "{t:?}");
    assert!(t.user + t.system < 0.2, "a sleeping program used CPU: {t:?}");

    // A counting loop in the shell: CPU time of its own, and on one thread no more CPU than
    // wall time (one tick of slack for the clock's resolution).
    let counter = script("counter", "i=0; while [ $i -lt 200000 ]; do i=$((i+1)); done");
    let t = peer::time_process(&counter, &[]).unwrap();
    assert!(t.user + t.system > 0.0, "{t:?}");
    assert!(t.user + t.system <= t.wall + 0.011, "{t:?}");
}

#[test]
fn the_peer_is_given_its_case_and_a_failure_is_an_error() {
    let log = std::env::temp_dir().join(format!("radiosity-peer-args-{}", std::process::id()));
    let echo = script("echo", &format!("echo \"$@\" > {}", log.display()));
    let case = PeerCase { method: "StochJacobi", iterations: 20 };
    let given = Peer::new(&echo).unwrap();
    peer::run_case(&given, &case, Path::new("room.mgf")).unwrap();
    let args = std::fs::read_to_string(&log).unwrap();
    assert_eq!(args.trim(), "room.mgf -raytracing-method none -radiance-method StochJacobi -iterations 20 -timings");
    std::fs::remove_file(&log).unwrap();

    let failing = script("failing", "exit 3");
    let e = peer::time_process(&failing, &[]).unwrap_err().to_string();
    assert!(e.contains("failed") && e.contains('3'), "{e}");
    let e = Peer::new(Path::new("/nonexistent/rpk")).unwrap_err().to_string();
    assert!(e.contains("/nonexistent/rpk") && e.contains("not a file"), "{e}");
}

#[test]
fn the_report_says_when_there_is_no_peer_and_shows_the_medians_when_there_is() {
    let (markdown, json) = peer::report(None, &[], None);
    assert!(markdown.contains(NO_PEER), "{markdown}");
    assert!(json.peer.is_none() && json.cases.is_empty() && json.missing.as_deref() == Some(NO_PEER));

    let times = |wall: f64| peer::ProcessTimes { wall, user: wall / 2.0, system: 0.01 };
    let given = Peer { executable: PathBuf::from("/opt/rpk"), commit: Some("37e5ff4".into()) };
    let run = PeerRun {
        method: "StochJacobi".into(),
        iterations: 20,
        command: "/opt/rpk room.mgf".into(),
        runs: vec![times(1.0), times(3.0), times(2.0)],
    };
    let (markdown, json) = peer::report(Some(&given), std::slice::from_ref(&run), None);
    assert!(!markdown.contains(NO_PEER) && markdown.contains("37e5ff4"), "{markdown}");
    // The medians: wall 2 s, user 1 s, system 10 ms.
    assert!(markdown.contains("| `StochJacobi` | 20 | 3 | 2.00 s | 1.00 s | 10.0 ms |"), "{markdown}");
    assert!(json.cases.len() == 1 && json.missing.is_none());
}
