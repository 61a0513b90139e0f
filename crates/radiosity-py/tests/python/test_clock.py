"""The clock every seconds figure is counted on: chosen with ``columns=``, named in every
result (``measured`` for columns computed, ``charged`` for columns read from the stored matrix
and charged), and the one a ``time=`` rule stops on."""

import csv

import numpy as np
import pytest

import radiosity

CLOCKS = (("computed", "measured"), ("charged", "charged"))


def test_a_comparison_names_its_clock_in_every_output(cornell, tmp_path):
    figures = {}
    for columns, clock in CLOCKS:
        comparison = radiosity.Lab(cornell, columns=columns).compare(["pr", "xu-g10"], until="columns=n")
        assert comparison.clock == clock
        table = comparison.table()
        assert table["clock"] == clock
        assert comparison.summary().splitlines()[0].endswith(f"seconds ({clock})")
        out = tmp_path / columns
        comparison.write(out)
        with open(out / "convergence.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        assert rows and all(row["clock"] == clock for row in rows)
        assert f"Seconds ({clock}):" in (out / "report.md").read_text()
        assert f"{clock} seconds" in (out / "e_rms-seconds.svg").read_text()
        figures[columns] = {key: table[key] for key in ("step", "columns", "e_rms")}
    # The numbers are the same either way, but for the seconds.
    for key, computed in figures["computed"].items():
        assert np.array_equal(computed, figures["charged"][key]), key


def test_the_defaults_are_the_command_lines(cornell):
    # `compare` and `solve` compute their columns by default.
    assert radiosity.Lab(cornell).compare(["pr"], until="columns=8").clock == "measured"
    run = radiosity.solve(cornell, "pr", until="columns=8")
    assert run.clock == run.stats["clock"] == "measured"


@pytest.mark.parametrize("columns,clock", CLOCKS)
def test_a_time_rule_stops_where_the_printed_seconds_pass_it(cornell, columns, clock):
    run = radiosity.solve(cornell, "pr", until="time=20ms", columns=columns)
    assert run.clock == run.stats["clock"] == clock
    assert run.stats["termination"] == "time limit of 0.020 s reached"
    seconds = run.points["seconds"]
    assert seconds[-2] < 0.02 <= seconds[-1]
    assert seconds[-1] == pytest.approx(run.stats["seconds"], rel=1e-12)


def test_an_unknown_way_to_pay_for_columns_is_refused(cornell):
    with pytest.raises(ValueError, match="it must be computed or charged"):
        radiosity.solve(cornell, "pr", columns="free")
    with pytest.raises(ValueError, match="it must be computed or charged"):
        radiosity.Lab(cornell, columns="free").compare(["pr"])
