"""benchmarks/fp_models.py (issue 32), its CrazyPAD rows on reduced paths: the healthy baselines over both airframes
(pooled and FP, leave one flight out), the detection rule of a flight, and the between-flight spread of the depth
estimate chosen on the fitting depths only.

The data-bound tests need ../shared/data/crazypad (``shared_crazypad`` in conftest.py)."""

import numpy as np
import pandas as pd
import pytest
from _scripts import load_script

import tsfdi


def load_benchmark():
    return load_script("benchmarks/fp_models.py")


@pytest.fixture(scope="module")
def bench(shared_crazypad):
    mod = load_benchmark()
    mod.cp.setup(shared_crazypad, conditions="cut_propeller_M3_*")
    return mod


@pytest.fixture(scope="module")
def choice(bench):
    return bench.cp.choose(bench.cp.normal_logs())


# ------------------------------------------------------------------ without data
def test_airframe_k_is_a_category_per_drone():
    bench = load_benchmark()
    assert bench.airframe_k(["E9", "E8", "E8"]) == {"E8": 0.0, "E9": 1.0}
    assert bench.airframe_k(["c", "a", "b"]) == {"a": 0.0, "b": 0.5, "c": 1.0}
    with pytest.raises(ValueError, match="two drones"):
        bench.airframe_k(["E8", "E8"])


def test_spread_is_the_excess_of_the_squared_error_over_se2():
    bench = load_benchmark()
    # two logs of two segments: errors +-1 mm around the depth with se 0.5: tau^2 = 1 - 0.25 per segment; the logs'
    # means are exact (error 0): nothing left per log
    t = pd.DataFrame({"depth": [2.0] * 4, "condition": "c", "log": ["a", "a", "b", "b"], "k_hat": [3.0, 1.0, 1.0, 3.0],
                      "se": [0.5] * 4})
    assert bench.spread(t) == pytest.approx((0.75, 0.0))
    t = t.assign(k_hat=[2.1, 2.1, 1.9, 1.9])          # errors below the standard errors: no extra spread
    assert bench.spread(t) == (0.0, 0.0)
    t = t.assign(k_hat=[3.0, 3.0, 1.0, 1.0])          # a flight-level error: the per-log component carries it
    assert bench.spread(t)[1] == pytest.approx(1.0 - 0.25 / 2)
    extra = pd.DataFrame({"depth": [2.0], "condition": "c", "log": ["z"], "k_hat": [9.0], "se": [np.inf]})
    assert bench.spread(pd.concat([t, extra])) == bench.spread(t)    # no interval: not -inf, not left to zero tau


def test_a_flight_is_detected_above_its_binomial_band():
    bench = load_benchmark()
    assert not bench.above_band(1, 4)                 # one window in four at alpha 0.01: inside the 99 % band
    assert bench.above_band(2, 4)
    assert not bench.above_band(0, 4)


# ------------------------------------------------------------------ CrazyPAD
def test_fp_baseline_is_one_var_per_airframe_with_held_out_logs(bench, choice):
    cp = bench.cp
    flights = cp.load_condition(cp.NORMAL, choice.margin)
    ks = bench.airframe_k(f.drone for f in flights)
    assert set(ks) == {"E8", "E9"}
    models = bench.healthy_baseline("fp", flights, choice, ks)
    for drone in ks:
        own = [f for f in flights if f.drone == drone]
        point = tsfdi.VAR(cp.records(own, choice.channels), choice.order, trend="c").fit()
        np.testing.assert_allclose(np.asarray(models[drone].results.params), np.asarray(point.params),
                                   rtol=1e-6, atol=1e-8 * np.abs(np.asarray(point.params)).max())
    held = models["E8"].held
    assert held is models["E9"].held and held.lags == choice.order
    assert len(held) == sum(len(f.segments) for f in flights)
    # the last log's segments: through the VAR of its airframe's other flights
    last = flights[-1]
    others = [f for f in flights if f.drone == last.drone and f is not last]
    var = tsfdi.VAR(cp.records(others, choice.channels), choice.order, trend="c").fit()
    for got, x in zip(held[-len(last.segments):], last.arrays(choice.channels)):
        np.testing.assert_allclose(got, np.asarray(var.residuals(x)), rtol=1e-6, atol=1e-6 * np.abs(got).max())
    pooled = bench.healthy_baseline("pooled", flights, choice, ks)
    assert pooled["E8"] is pooled["E9"]
    with pytest.raises(ValueError, match="kind"):
        bench.healthy_baseline("trim", flights, choice, ks)
    with pytest.raises(ValueError, match="two or more normal flights of each drone"):
        bench.healthy_baseline("fp", [f for f in flights if f.drone == "E8"] + own[:1], choice, ks)


def test_healthy_lofo_judges_the_held_out_flight_only(bench, capsys):
    logs = bench.cp.normal_logs()
    e9 = next(i for i, log in enumerate(logs) if log.startswith("E9"))
    fa = pd.concat([bench.healthy_lofo(kind, folds=[e9]) for kind in ("pooled", "fp")])
    assert set(fa.log) == {logs[e9]} and set(fa.drone) == {"E9"} and set(fa.baseline) == {"pooled", "fp"}
    assert set(fa.test) == set(bench.HEALTHY_TESTS) and set(fa.step_s) == {2.0, bench.cp.SLIDE_S}
    disjoint = fa[fa.step_s == 2.0]
    assert (disjoint.n == 4).all()                    # two segments of ~5 s: two disjoint 2 s windows each
    assert (fa[fa.step_s == bench.cp.SLIDE_S].n > 50).all()
    assert ((fa.flagged >= 0) & (fa.flagged <= fa.n)).all()
    line = bench.rate_line(disjoint[disjoint.test == bench.DETECTOR])
    assert "99 % band" in line and line.split()[-1] in ("band", "ABOVE", "below")
    bench.report_healthy(fa)
    out = capsys.readouterr().out
    assert "pooled baseline" in out and "fp baseline" in out
    n = int(disjoint[(disjoint.baseline == "fp") & (disjoint.test == bench.DETECTOR)].n.sum())
    assert f"/{n:<4d} = " in out and "sliding, step 0.1 s" in out    # the band on the disjoint windows only


def test_the_spread_of_a_fold_is_chosen_on_its_fitting_depths(bench, choice):
    data = [s for s in bench.depth_data(choice) if s.depth in (1.0, 2.0, 3.0, 4.0)]
    t = bench.depth_folds(data, 2, 1, held=[2.0])
    assert set(t.depth) == {2.0} and len(t) == sum(s.depth == 2.0 for s in data)
    assert (t.tau2 >= 0).all() and t.tau2.nunique() == 1 and t.tau2_log.nunique() == 1
    # the held-out depth's own segments, replaced by other data, change its estimates but not its fold's spread
    swapped = [bench.Segment(s.depth, s.condition, s.drone, s.log, s.x[::-1].copy()) if s.depth == 2.0 else s
               for s in data]
    u = bench.depth_folds(swapped, 2, 1, held=[2.0])
    assert u.tau2.iloc[0] == t.tau2.iloc[0] and u.tau2_log.iloc[0] == t.tau2_log.iloc[0]
    assert not np.allclose(u.k_hat, t.k_hat)
    plain = bench.depth_folds(data, 2, 1, inner=False, held=[2.0])
    assert (plain.tau2 == 0).all()
    np.testing.assert_allclose(plain.k_hat, t.k_hat)
