"""Structured residuals and isolation (paper 002, Table 2): the signature-table logic on every fired pattern, the
airspeed parity relations on synthetic data with known faults, sample / window / record isolation, inputs."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest

import tsfdi
from tsfdi.isolation import (STATUS, Isolation, IsolationSeries, ResidualSet, airspeed_from_gps,
                             airspeed_parity)
from tests.conftest import as_kind, assert_kind, to_numpy
from _scripts import load_script

TABLE2 = pd.DataFrame([[1, 1, 0], [1, 0, 1], [0, 1, 1]], index=["R1", "R2", "R3"],
                      columns=["pitot", "gps2air", "thrust"])

# signature tables with every kind of ambiguity: Table 2, identical columns (b, c), a zero column (d), one residual
TABLES = {
    "table2": TABLE2,
    "identical": pd.DataFrame([[1, 1, 1, 0], [0, 1, 1, 1], [1, 0, 0, 1]], index=["r1", "r2", "r3"],
                              columns=list("abcd")),
    "zero column": pd.DataFrame([[1, 0, 0, 1], [1, 1, 0, 0]], index=["r1", "r2"], columns=list("abdz")).assign(d=0),
    "one residual": pd.DataFrame([[1, 1]], index=["r"], columns=["u", "v"]),
}


def _expected(table: pd.DataFrame, pattern: tuple) -> tuple[str, tuple]:
    """Column matching by its definition: the sensors whose column equals the pattern."""
    cols = [s for s in table.columns if tuple(table[s].astype(bool)) == pattern]
    if not any(pattern):
        return "none", ()
    return ("isolated" if len(cols) == 1 else "several" if cols else "not isolable"), tuple(cols)


@pytest.mark.parametrize("name", list(TABLES))
def test_every_fired_pattern(name):
    table = TABLES[name]
    rs = ResidualSet(table)
    seen = set()
    for pattern in itertools.product((False, True), repeat=len(table)):
        iso = rs.match(list(pattern))
        status, cands = _expected(table, pattern)
        assert (iso.status, iso.candidates) == (status, cands), pattern
        assert iso.label == (cands[0] if status == "isolated" else None)
        assert iso.fired == tuple(n for n, f in zip(table.index, pattern) if f)
        assert rs.match(iso.fired).candidates == cands               # by names too
        seen.add(iso.status)
    # the same decisions row by row in a series holding every pattern
    fired = np.array(list(itertools.product((False, True), repeat=len(table))))
    ser = IsolationSeries(fired, rs.names, rs.sensors, rs.incidence, np.arange(len(fired)), np.arange(len(fired)) + 1)
    assert ser.status.tolist() == [rs.match(list(f)).status for f in fired]
    assert ser.labels == [rs.match(list(f)).label for f in fired]
    assert set(ser.status) <= set(STATUS)


def test_table2_decisions_and_isolability():
    rs = airspeed_parity()
    assert rs.table.equals(TABLE2.rename_axis("residual"))
    assert rs.isolable == ("pitot", "gps2air", "thrust")
    assert rs.match(["R1", "R2"]).label == "pitot"          # a pitot fault fires R1 and R2, not R3 (paper 002)
    assert rs.match(["R1", "R3"]).label == "gps2air"
    assert rs.match(["R2", "R3"]).label == "thrust"
    assert rs.match(["R1"]).status == "not isolable"
    assert rs.match(["R1", "R2", "R3"]).status == "not isolable"
    assert rs.match([]).status == "none"
    amb = ResidualSet(TABLES["identical"])
    assert amb.isolable == ("a", "d") and amb.match(["r1", "r2"]).candidates == ("b", "c")
    assert ResidualSet(TABLES["zero column"]).isolable == ("a", "b", "z")


def test_mapping_and_frame_give_the_same_table():
    rs = ResidualSet({"R1": ("pitot", "gps2air"), "R2": ("pitot", "thrust"), "R3": ("gps2air", "thrust")})
    assert rs.table.equals(ResidualSet(TABLE2).table)
    assert ResidualSet.pairwise(["a", "b", "c", "d"]).isolable == ("a", "b", "c", "d")
    assert len(ResidualSet.pairwise(["a", "b", "c", "d"]).names) == 6


# ---------------------------------------------------------------------------------------------- synthetic flights
FS = 20.0


def _estimates(rng, n=2400, fault=None, start=1600, size=2.0):
    """Three estimates of one airspeed with independent noise; ``fault`` adds ``size`` to one of them from
    ``start`` on."""
    true = 16 + np.cumsum(rng.standard_normal(n)) * 0.03
    est = pd.DataFrame({"pitot": true + 0.3 * rng.standard_normal(n),
                        "gps2air": true + 0.4 * rng.standard_normal(n),
                        "thrust": true + 0.5 * rng.standard_normal(n)},
                       index=pd.date_range("2024-01-01", periods=n, freq="50ms", name="time"))
    if fault is not None:
        est.loc[est.index[start:], fault] += size
    return est


@pytest.fixture(scope="module")
def calibrated():
    rng = np.random.default_rng(0)
    rs = airspeed_parity(tsfdi.GLRT(40, threshold=tsfdi.EmpiricalThreshold(1e-4)))
    rs.calibrate([rs.residuals(_estimates(rng)) for _ in range(4)])
    return rs


@pytest.mark.parametrize("sensor", ["pitot", "gps2air", "thrust"])
def test_worked_example_isolates_the_faulty_estimate(calibrated, sensor):
    rng = np.random.default_rng({"pitot": 1, "gps2air": 2, "thrust": 3}[sensor])
    resid = calibrated.residuals(_estimates(rng, fault=sensor))
    ser = calibrated.isolate_samples(resid)
    assert ser.fired[1600:1640].any()                               # detected within 2 s
    assert 1600 <= ser.first_isolation <= 1640 and ser.isolated == sensor     # never isolated before the fault
    assert set(ser.labels[1640:]) == {sensor}                       # it stays isolated
    row = ser.confirmed(40)
    assert ser.labels[row] == sensor and row == ser.first_isolation + 39
    assert ser.index[0] == resid.index[0] and isinstance(ser.to_frame().index, pd.DatetimeIndex)
    assert ser[row].span == (row, row + 1) and ser[row].label == sensor
    healthy = calibrated.isolate_samples(resid.iloc[:1600])
    assert healthy.first_isolation is None and healthy.confirmed(1) is None


def test_record_and_window_isolation(calibrated):
    rng = np.random.default_rng(4)
    resid = calibrated.residuals(_estimates(rng, fault="pitot"))
    iso = calibrated.isolate(resid.iloc[1600:2000])
    assert isinstance(iso, Isolation) and iso.label == "pitot" and iso.span == (0, 400)
    assert set(iso.decisions) == {"R1", "R2", "R3"} and iso.decisions["R3"].accept
    assert iso.to_frame()["fired"].tolist() == [True, True, False]
    assert "pitot" in str(iso.summary())
    win = calibrated.isolate_windows(resid, "10s", "5s")
    assert len(win) == (2400 - 200) // 100 + 1 and win.starts[1] == 100 and win.stops[0] == 200
    for w in (0, 10, len(win) - 1):
        ref = calibrated.isolate(resid.iloc[win.starts[w]:win.stops[w]])
        assert win[w].fired == ref.fired and win[w].span == (win.starts[w], win.stops[w])
    assert win.labels[-1] == "pitot" and win.index[-1] == resid.index[-1]


def test_kinds(kind, calibrated):
    rng = np.random.default_rng(5)
    est = _estimates(rng, n=800, fault="thrust", start=500)
    signals = as_kind(est.to_numpy(), kind, channels=list(est.columns))
    if kind == "numpy":
        with pytest.raises(ValueError, match="no column 'pitot'"):
            calibrated.residuals(signals)
        resid = est[["pitot"]].to_numpy() - est[["gps2air", "thrust"]].to_numpy()
        resid = np.column_stack([resid, est["gps2air"] - est["thrust"]])
    else:
        resid = calibrated.residuals(signals)
        assert_kind(resid, kind, 2)
    np.testing.assert_allclose(to_numpy(resid), calibrated.residuals(est).to_numpy())
    ser = calibrated.isolate_samples(resid)
    assert ser.isolated == "thrust"
    assert (ser.index is None) == (kind == "numpy")


def test_residual_columns_are_matched_by_name(calibrated):
    rng = np.random.default_rng(6)
    resid = calibrated.residuals(_estimates(rng, fault="gps2air"))
    shuffled = resid[["R3", "R1", "R2"]]
    assert calibrated.isolate_samples(shuffled).isolated == "gps2air"
    with pytest.raises(ValueError, match=r"missing channel\(s\) \['R3'\]"):
        calibrated.isolate_samples(resid[["R1", "R2"]])


def test_calibration_is_per_residual():
    rng = np.random.default_rng(7)
    rs = airspeed_parity(tsfdi.GLRT(40, threshold=tsfdi.EmpiricalThreshold(1e-3)))
    rs.calibrate(rs.residuals(_estimates(rng, n=6000)))
    scales = [float(t.scale_[0]) for t in rs.tests.values()]
    np.testing.assert_allclose(scales, [0.5, np.sqrt(0.34), np.sqrt(0.41)], rtol=0.06)   # sqrt of summed variances
    assert len({id(t) for t in rs.tests.values()}) == 3
    z = ResidualSet(TABLE2, tsfdi.ZScore(6.0)).calibrate(rs.residuals(_estimates(rng, n=500)))  # nothing to calibrate
    assert z.isolate_samples(rs.residuals(_estimates(rng, n=500))).status.shape == (500,)


def test_record_level_tests_cannot_isolate_samples():
    rs = ResidualSet(TABLE2, tsfdi.LjungBox(lags=5))
    resid = np.random.default_rng(8).standard_normal((300, 3))
    with pytest.raises(TypeError, match="decides per record"):
        rs.isolate_samples(resid)
    assert rs.isolate_windows(resid, 100, 100).fired.shape == (3, 3)


def test_airspeed_from_gps_is_the_law_of_cosines(kind):
    rng = np.random.default_rng(9)
    vg, psi_g = rng.uniform(5, 30, 50), rng.uniform(-np.pi, np.pi, 50)
    vw, psi_w = rng.uniform(0, 10, 50), rng.uniform(-np.pi, np.pi, 50)
    eq4 = np.sqrt(vw ** 2 + vg ** 2 - 2 * vg * vw * np.cos(psi_w - psi_g))
    out = airspeed_from_gps(as_kind(vg, kind), psi_g, vw, psi_w, scale=0.97)
    assert_kind(out, kind, 1)
    np.testing.assert_allclose(to_numpy(out), 0.97 * eq4, rtol=1e-12)
    # a tail wind of the ground speed's size leaves no airspeed; constants broadcast
    np.testing.assert_allclose(airspeed_from_gps([10.0, 10.0], [0.0, np.pi], 10.0, 0.0), [0.0, 20.0], atol=1e-12)


@pytest.mark.parametrize("build, exc, match", [
    (lambda: ResidualSet(TABLE2 * 2), ValueError, "0 / 1"),
    (lambda: ResidualSet(TABLE2.rename(index={"R2": "R1"})), ValueError, "duplicate residual names"),
    (lambda: ResidualSet({"R1": ("a",), "R2": ()}), ValueError, r"\['R2'\] depend on no sensor"),
    (lambda: ResidualSet({"R1": "ab"}), TypeError, "sequence of sensor names"),
    (lambda: ResidualSet([[1, 0]]), TypeError, "incidence must be a DataFrame"),
    (lambda: ResidualSet(TABLE2, {"R1": tsfdi.GLRT()}), ValueError, r"no test for residual\(s\) \['R2', 'R3'\]"),
    (lambda: ResidualSet(TABLE2, "glrt"), TypeError, "must be a residual test"),
    (lambda: ResidualSet(TABLE2, functions={"R1": len}), ValueError, "no function for residual"),
    (lambda: ResidualSet.pairwise(["a", "a"]), ValueError, "two distinct names"),
    (lambda: ResidualSet(TABLE2).residuals(np.zeros((5, 3))), ValueError, "no residual functions"),
    (lambda: ResidualSet(TABLE2).match(["R4"]), ValueError, r"unknown residual\(s\) \['R4'\]"),
    (lambda: ResidualSet(TABLE2).match([True, False]), ValueError, "one bool per residual"),
    (lambda: ResidualSet(TABLE2).isolate_windows(np.zeros((5, 3)), 6), ValueError, "window must be <="),
    (lambda: ResidualSet(TABLE2).isolate_windows(np.zeros((50, 3)), "2s"), ValueError, "sampling frequency"),
    (lambda: airspeed_from_gps([1.0, 2.0], [0.0], 1.0, 0.0), ValueError, "course must have one value per sample"),
    (lambda: airspeed_parity().isolate_samples(np.zeros((50, 2))), ValueError, "channel"),
])
def test_errors_name_the_argument(build, exc, match):
    with pytest.raises(exc, match=match):
        build()


def test_confirmed_hold():
    fired = np.zeros((10, 3), dtype=bool)
    fired[2:4] = [True, True, False]          # pitot for 2 rows
    fired[5:9] = [True, False, True]          # gps2air for 4 rows
    rs = airspeed_parity()
    ser = IsolationSeries(fired, rs.names, rs.sensors, rs.incidence, np.arange(10), np.arange(10) + 1)
    assert ser.confirmed(1) == ser.first_isolation == 2 and ser.isolated == "pitot"
    assert ser.confirmed(2) == 3 and ser.confirmed(3) == 7 and ser.labels[7] == "gps2air"
    assert ser.confirmed(5) is None and ser.first_detection == 2
    with pytest.raises(ValueError, match="hold must be >= 1"):
        ser.confirmed(0)
    frame = ser.to_frame()
    assert frame.columns.tolist() == ["start", "stop", "R1", "R2", "R3", "status", "label"]
    assert "isolated" in repr(ser)


def test_confirmed_equals_the_run_count():
    """confirmed(hold) is the first row ending a run of ``hold`` rows isolating the same sensor, checked against a
    plain count on random fired patterns with long runs."""
    rs = airspeed_parity()
    rng = np.random.default_rng(7)
    for _ in range(50):
        rows = np.repeat(rng.integers(0, 8, size=30), rng.integers(1, 6, size=30))
        fired = ((rows[:, None] >> np.arange(3)) & 1).astype(bool)
        ser = IsolationSeries(fired, rs.names, rs.sensors, rs.incidence, np.arange(len(rows)),
                              np.arange(len(rows)) + 1)
        for hold in (1, 2, 3, 5, 9):
            run, prev, expected = 0, None, None
            for i, lab in enumerate(ser.labels):
                run = run + 1 if lab is not None and lab == prev else int(lab is not None)
                prev = lab
                if run >= hold:
                    expected = i
                    break
            assert ser.confirmed(hold) == expected


# ---------------------------------------------------------------------------------------------- benchmark 2 on ALFA
def _bench(alfa=None):
    """benchmarks/alfa_isolation.py, reading the ALFA copy ``alfa`` (its functions on arrays need none)."""
    bench = load_script("benchmarks/alfa_isolation.py")
    if alfa is not None:
        bench.DATA = alfa
    return bench


def test_alfa_benchmark_block_run_is_the_sample_loop(shared_alfa):
    """benchmarks/alfa_isolation.py feeds the GLRTs in blocks; the fired residuals equal those of the plain loop
    (offset, one GLRT stream per residual, offset adaptation held while any residual alarms), on flight
    07-30-16-39-00_2 fault-free and with a 5 m/s bias; a fault scenario continued from the fault-free state at its
    start equals the run from scratch."""
    bench = _bench(shared_alfa)
    names = bench.pitot_flights(bench.DATA)
    assert names == [f"carbonZ_{n}_engine_failure" for n in ("2018-07-18-15-53-31_1", "2018-07-18-15-53-31_2",
                                                             "2018-07-30-16-39-00_1", "2018-07-30-16-39-00_2")]
    flights = [bench.load(f) for f in names]
    assert [round(len(a) / bench.FS) for a in flights] == [76, 33, 77, 52]
    train, test = flights[:3], flights[3]
    settings = bench.Settings(100, 5e-4, 0.998, 5.0, 40)
    mon = bench.Monitor(bench.Fit(train), settings, train)
    valid = bench.level(test, settings.gate)
    pitot = test["airspeed"].to_numpy()
    for p in (pitot, bench.inject(pitot, "bias+", 400, 5.0)):
        raw = mon.fit.residuals(test, p)
        run = bench.Run(mon.parity, mon.gain, raw)
        run.advance(raw, valid, len(raw))
        streams = [mon.parity.tests[n].stream() for n in mon.parity.names]
        offset, loop, held = raw[:40].mean(axis=0), [], 0
        for k in range(len(raw)):
            out = raw[k] - offset if valid[k] else np.zeros(3)
            alarm = False
            if k >= bench.ARM:
                loop.append([s.update(out[c])[0] > s.threshold for c, s in enumerate(streams)])
                alarm = any(loop[-1])
            held += bool(valid[k] and alarm)
            if valid[k] and not alarm:
                offset = offset + mon.gain * (raw[k] - offset)
        np.testing.assert_array_equal(run.series(mon.parity).fired, np.array(loop))
    assert held > 100                                        # the bias is detected: the adaptation was held
    healthy, faulty = mon.flight(test, 5.0, (40,))
    row = next(f for f in faulty if f["kind"] == "bias-" and f["start_s"] == 15.0)
    stop = 300 + bench.HORIZON
    raw = mon.fit.residuals(test, bench.inject(pitot[:stop], "bias-", 300, 5.0))
    run = bench.Run(mon.parity, mon.gain, raw)
    run.advance(raw, valid, stop)
    tail = run.series(mon.parity, 300 - bench.ARM)
    assert row["isolated 40"] == tail.labels[tail.confirmed(40)] and row["delay_s"] == tail.first_detection / 20


def test_alfa_benchmark_offsets_closed_form():
    """The block offsets of benchmarks/alfa_isolation.py (closed form) equal the recursion, held on invalid
    samples, over several blocks (no data needed)."""
    bench = _bench()
    rng = np.random.default_rng(3)
    raw, valid = rng.normal(size=(1000, 3)), rng.random(1000) > 0.3
    o, rec = np.array([1.0, -2.0, 0.5]), []
    for k in range(1000):
        rec.append(o)
        o = o + 0.002 * (raw[k] - o) if valid[k] else o
    rec.append(o)
    np.testing.assert_allclose(bench.adapt(raw, valid, np.array([1.0, -2.0, 0.5]), 0.002), np.array(rec),
                               rtol=1e-12, atol=1e-12)


def test_residual_columns_are_named_against_the_residual_set():
    rs = ResidualSet(TABLE2)
    frame = pd.DataFrame(np.random.default_rng(0).standard_normal((200, 3)), columns=["R1", "R2", "Rx"])
    with pytest.raises(ValueError, match=r"residuals: missing channel\(s\) \['R3'\]; extra channel\(s\) \['Rx'\]; "
                                         r"the residual set is built on channels \['R1', 'R2', 'R3'\]"):
        rs.isolate(frame)
