//! Convergence tables as CSV and Markdown, under snapshot tests, and significant-digit
//! rounding.

use radiosity_eval::round_significant;
use radiosity_eval::{ConvergenceTable, TableRow};
use radiosity_solvers::{Cost, Unit};

fn table() -> ConvergenceTable {
    let mut t = ConvergenceTable::new();
    let row = |solver: &str, step, columns, seconds, ff_seconds, e_rms, e_max, residual: f64| TableRow {
        solver: solver.to_string(),
        step,
        cost: Cost::default().with(Unit::Columns, columns).with_seconds(ff_seconds, seconds - ff_seconds),
        e_rms,
        e_max,
        residual,
        bound: residual * 10.0,
        std_error: f64::NAN,
    };
    t.push(row("pr", 0, 0, 0.0, 0.0, 1.0, 1.0, 0.6123456));
    t.push(row("pr", 480, 480, 1.23456789, 1.19876543, 4.7123456e-3, 2.0987654e-2, 1.5e-3));
    t.push(row("xu-g30-m480", 960, 512, 2.71846, 2.5, 4.2e-5, 9.99996e-5, 3.14159e-9));
    t.push(row("odd, \"name\" | here", 1, 1, 123456.7, 2.5e-7, f64::INFINITY, 0.000123449, 1e-300));
    t
}

#[test]
fn csv_snapshot() {
    let mut out = Vec::new();
    table().write_csv(&mut out).unwrap();
    insta::assert_snapshot!(String::from_utf8(out).unwrap());
}

#[test]
fn markdown_snapshot() {
    let mut out = Vec::new();
    table().write_markdown(&mut out).unwrap();
    insta::assert_snapshot!(String::from_utf8(out).unwrap());
}

#[test]
fn fewer_digits() {
    let mut out = Vec::new();
    table().with_significant_digits(2).write_markdown(&mut out).unwrap();
    insta::assert_snapshot!(String::from_utf8(out).unwrap());
}

#[test]
fn without_timings() {
    // Both formats lose the same three columns (the seconds and their clock), and nothing else.
    let t = table().without_timings();
    let (mut csv, mut markdown) = (Vec::new(), Vec::new());
    t.write_csv(&mut csv).unwrap();
    t.write_markdown(&mut markdown).unwrap();
    let (csv, markdown) = (String::from_utf8(csv).unwrap(), String::from_utf8(markdown).unwrap());
    assert!(csv.starts_with("solver,step,columns,e_rms,e_max,residual,bound\n"), "{csv}");
    insta::assert_snapshot!(format!("{csv}\n{markdown}"));
}

#[test]
fn products_are_written_when_a_row_made_one() {
    // A table of column methods has no `products` column; one where a row made a product by F
    // (a Krylov solver, `jacobi:sweep=product`) has it, after `columns`, in both formats.
    let mut without = Vec::new();
    table().write_csv(&mut without).unwrap();
    assert!(String::from_utf8(without).unwrap().starts_with("solver,step,columns,seconds,"));
    let mut t = table();
    let mut krylov = t.rows()[2].clone();
    (krylov.solver, krylov.cost[Unit::Products]) = ("gmres-30".to_string(), 7);
    t.push(krylov);
    let (mut csv, mut markdown) = (Vec::new(), Vec::new());
    t.write_csv(&mut csv).unwrap();
    t.without_timings().write_markdown(&mut markdown).unwrap();
    let (csv, markdown) = (String::from_utf8(csv).unwrap(), String::from_utf8(markdown).unwrap());
    assert!(csv.starts_with("solver,step,columns,products,seconds,ff_seconds,"), "{csv}");
    assert!(csv.contains("\ngmres-30,960,512,7,") && csv.contains("\npr,480,480,0,"), "{csv}");
    assert!(markdown.starts_with("| solver | step | columns | products | e_rms |"), "{markdown}");
}

#[test]
fn rays_and_standard_errors_are_written_when_a_row_has_them() {
    // A table of deterministic solvers has neither `rays` nor `std_error`; one where a row
    // cast rays has both, `rays` after `products`' place and `std_error` after `bound`, the
    // deterministic rows with 0 rays and no standard error.
    let mut t = table();
    let mut sampled = t.rows()[1].clone();
    (sampled.solver, sampled.cost[Unit::Columns], sampled.cost[Unit::Rays], sampled.std_error) =
        ("stochastic-jacobi".to_string(), 0, 1_000_000, 1.2345678e-3);
    t.push(sampled);
    let (mut csv, mut markdown) = (Vec::new(), Vec::new());
    t.write_csv(&mut csv).unwrap();
    t.without_timings().write_markdown(&mut markdown).unwrap();
    let (csv, markdown) = (String::from_utf8(csv).unwrap(), String::from_utf8(markdown).unwrap());
    assert!(
        csv.starts_with("solver,step,columns,rays,seconds,ff_seconds,clock,e_rms,e_max,residual,bound,std_error\n"),
        "{csv}"
    );
    assert!(csv.contains("\nstochastic-jacobi,480,0,1000000,") && csv.ends_with(",0.01500,0.001235\n"), "{csv}");
    assert!(csv.contains("\npr,480,480,0,") && csv.contains(",0.01500,NaN\n"), "{csv}");
    assert!(
        markdown.starts_with("| solver | step | columns | rays | e_rms | e_max | residual | bound | std_error |"),
        "{markdown}"
    );
}

fn check(x: f64, digits: usize, expect: &str) {
    assert_eq!(round_significant(x, digits), expect, "{x} to {digits} digits");
}

#[test]
fn significant_digits() {
    check(0.0, 4, "0");
    check(1.0, 4, "1.000");
    check(-1.23456, 4, "-1.235");
    check(9.99996, 4, "10.00");
    check(0.00012345, 3, "0.000123");
    check(0.000099996, 4, "0.0001000");
    check(0.0000999949, 4, "9.999e-5");
    check(123456.0, 4, "123500");
    check(999999.7, 4, "1.000e6");
    check(1.5e-12, 4, "1.500e-12");
    check(42.0, 0, "40");
    check(f64::NAN, 4, "NaN");
    check(f64::NEG_INFINITY, 4, "-inf");
}
