//! The README quotes what `cargo xtask compare` prints: its table, but for the seconds (which
//! depend on the machine and are stamped in the README with their commit), is checked
//! against what the command prints now, so that the front door cannot go stale.

use super::xtask;

/// The line `compare` prints under its table by default: which clock its seconds are on.
const DEFAULT_CLOCK_LINE: &str =
    "seconds (measured): form factors and solving timed, every column computed when a solver asked for it";

/// The fenced table between the README's compare-output markers, one line a row.
fn readme_table() -> Vec<String> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let begin = readme.find("<!-- compare-output:begin -->").expect("the README marks the compare output");
    let end = readme.find("<!-- compare-output:end -->").expect("the README marks the compare output's end");
    readme[begin..end]
        .lines()
        .skip(1)
        .filter(|l| !l.starts_with("```") && !l.trim().is_empty())
        .map(str::to_string)
        .collect()
}

/// A summary row without its last field, the seconds; the header as it is.
fn without_seconds(row: &str) -> Vec<String> {
    let fields: Vec<String> = row.split_whitespace().map(str::to_string).collect();
    if row.starts_with("solver") { fields } else { fields[..fields.len() - 1].to_vec() }
}

#[test]
fn the_readme_quotes_what_compare_prints() {
    let dir = std::env::temp_dir().join(format!("radiosity-readme-{}", std::process::id()));
    let out = xtask(&["compare", "--out", dir.to_str().unwrap()]).success().get_output().stdout.clone();
    std::fs::remove_dir_all(&dir).unwrap();
    let printed = String::from_utf8(out).unwrap();
    let table: Vec<&str> = printed.lines().take_while(|l| !l.starts_with("seconds (")).collect();
    let quoted = readme_table();
    assert_eq!(quoted.len(), table.len(), "README:\n{}\nprinted:\n{printed}", quoted.join("\n"));
    for (q, p) in quoted.iter().zip(&table) {
        assert_eq!(without_seconds(q), without_seconds(p), "README:\n{}\nprinted:\n{printed}", quoted.join("\n"));
    }
    // How the seconds were counted is said beside the table, and the README names it.
    assert!(printed.contains(DEFAULT_CLOCK_LINE), "{printed}");
}
