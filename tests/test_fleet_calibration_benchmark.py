"""Smoke tests of part 1 of benchmarks/fleet_calibration.py (issue 31): the yardstick that judges the calibrated F and
Ljung-Box rows against the binomial band. Every fleet is fitted and calibrated on its own records and judged on one
window of each of a few new records, so that the judged windows are (nearly) independent draws of the decision's
rate."""

from __future__ import annotations

import numpy as np
import pytest

from _scripts import load_script

FC = load_script("benchmarks/fleet_calibration.py")


def test_fleets_are_simulated_together_each_from_its_own_generator():
    """Simulating a chunk of fleets in one recursion must give each fleet exactly the records its own generator
    ``[seed, records, f]`` gives alone (``records`` fitting records and the new records): nothing shared."""
    got = FC.fleets_of(7, 5, 3, 2, 2)
    assert len(got) == 2
    for f, (fit, new) in enumerate(got):
        ref, _ = FC.fleet_records(np.random.default_rng([7, 5, 3 + f]), 7)
        assert len(fit) == 5 and len(new) == 2 and new[0].shape == (FC.N, 3)
        for x, y in zip(fit + new, ref):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)
    assert not np.allclose(got[0][1][0], got[1][1][0])


def test_rows_and_fleets_draw_their_own_records():
    """The rows (5, 10, 20 fitting records) and the fleets of a row share no record, so one unlucky draw cannot move
    every row, and a fleet's new records are none of its fitting records."""
    fit5, new5 = FC.fleets_of(11, 5, 0, 1, 2)[0]
    fit10, new10 = FC.fleets_of(11, 10, 0, 1, 2)[0]
    records = fit5 + new5 + fit10 + new10
    assert not any(np.allclose(x, y) for i, x in enumerate(records) for y in records[i + 1:])


def test_each_fleet_is_judged_on_one_window_of_each_of_its_new_records(monkeypatch):
    """Each fleet contributes exactly ``windows`` windows, one of each of as many new records: windows of one record
    share its noise level, so with the F test two of them are flagged together far more often than two of different
    records (development seed 90001: design effect 1.25-1.31 at 2 windows of one record, 1.00-1.04 at one window of
    each of 2 records), and the design before judged 10 windows of each of several new records per fleet. The judged
    residuals are those of the new records' first windows through the fleet's baseline."""
    judged, flags = [], FC.decision_flags
    monkeypatch.setattr(FC, "decision_flags", lambda test, resid: judged.append(resid) or flags(test, resid))
    rows = FC.fleet_rows(5, 11, 2, 2)
    assert len(rows) == 2 * len(FC.ALPHAS) * 2
    assert {r[1] for r in rows} == {0, 1} and all(r[5] == 2 and 0 <= r[4] <= 2 for r in rows)
    for f, (fit, new) in enumerate(FC.fleets_of(11, 5, 0, 2, 2)):
        base = FC.tsfdi.VAR(fit, 2).fit()
        for resid in judged[4 * f:4 * f + 4]:
            assert len(resid) == 2
            for r, x in zip(resid, new):
                assert r.shape == (FC.WINDOW - 2, 3)
                np.testing.assert_allclose(r, np.asarray(base.residuals(x[:FC.WINDOW])))


def test_fleet_table_pools_the_fleets_of_every_row(capsys):
    tab = FC.fleet_table(11, fleets=2, windows=1)
    assert len(tab) == 12 and set(tab.flagged.str.split("/").str[1].astype(int)) == {2}
    assert set(tab.records) == set(FC.RECORDS) and {"band %", "fleet 99.9 % CI %", "SE fleets/binomial"} <= set(tab)
    out = capsys.readouterr().out
    assert "evaluation seed 11" in out and "each of 1 new record(s)" in out


@pytest.mark.parametrize("argv", [["--windows", "0"], ["--windows", "11"], ["--fleets", "1"]])
def test_part_one_options_are_checked(argv, capsys):
    with pytest.raises(SystemExit):
        FC.main(argv + ["--no-crazypad", "--no-hexacopter"])
    assert f"--windows 1 to {FC.MAX_WINDOWS}" in capsys.readouterr().err
