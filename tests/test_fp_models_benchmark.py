"""benchmarks/fp_models.py (issue 32), its CrazyPAD rows on reduced paths: the healthy baselines over both airframes
(pooled and FP, leave one flight out), the detection rule of a flight, the between-flight spread of the depth
estimate chosen on the fitting depths only, and the detection of the cut flights through models of the depth (FP-VAR
likelihood ratio, trim over depth and airframe, healthy trim; nested folds on a subset of depths), and the
detectability section's arithmetic (flight summaries, the predictive law and its power, the session scatter).

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


# ------------------------------------------------------------------ detection through models of the depth
def test_chibar_point_is_the_boundary_mixture():
    bench = load_benchmark()
    from scipy import stats
    # one part: half the mass at 0, so the upper alpha point is chi2_1's upper 2 alpha point
    assert bench.chibar_isf(0.01, 1) == pytest.approx(stats.chi2.isf(0.02, 1))
    rng = np.random.default_rng(3)
    draws = (rng.standard_normal((400_000, 3)).clip(min=0) ** 2).sum(axis=1)     # three boundary LR statistics
    assert np.mean(draws > bench.chibar_isf(0.01, 3)) == pytest.approx(0.01, abs=0.001)
    assert np.mean(draws > stats.chi2.isf(0.01, 3)) < 0.005                        # chi2_3 would be conservative
    assert bench.chibar_mean(3) == pytest.approx(draws.mean(), rel=0.01)


class _Flight:
    def __init__(self, log):
        self.drone, self.log, self.segments = "E8", log, (None,)


def test_detection_folds_never_fit_or_calibrate_on_the_judged_flight():
    bench = load_benchmark()
    items = ([(0.0, _Flight(f"n{i}")) for i in range(4)]
             + [(d, _Flight(f"c{d}{i}")) for d in (1.0, 2.0) for i in range(2)])
    seen = []

    def fit(fitted):
        seen.append({f.log for _, f in fitted})
        return frozenset(f.log for _, f in fitted)

    def stat(model, flight):
        assert flight.log not in model                  # never judged by a model that saw it
        return {"lr": float(len(model)), "crit": 10.0, "mean0": 1.0, "lr_parts": (0.0, 0.0), "crit_part": 5.0,
                "k_hat": 0.0, "lo": 0.0, "hi": 1.0}

    t = bench.detection_folds(items, fit, stat)
    assert list(t.log) == ["c1.00", "c1.01", "c2.00", "c2.01", "n0", "n1", "n2", "n3"]
    # a depth fold: its model without the depth (6 items), its scale from the 4 normal flights each also left out
    # (5 items each): mean statistic 5 over the nominal mean 1
    assert (t.lr[t.depth > 0] == 6).all() and (t.scale[t.depth > 0] == 5).all()
    # a normal flight's fold: its model on the other 7, its scale from the other 3 normal flights (6 items each)
    assert (t.lr[t.depth == 0] == 7).all() and (t.scale[t.depth == 0] == 6).all()
    assert all(len(s) in (5, 6, 7) for s in seen) and len(seen) == len({frozenset(s) for s in seen})   # fitted once
    one = bench.detection_folds(items, fit, stat, depths=[2.0], normals=[1])
    assert list(one.log) == ["c2.00", "c2.01", "n1"]
    # nominal: above crit 10; calibrated: above scale 5 x 10; windows: parts above crit_part 5 above the band
    d = bench.decide(t.assign(lr=[60.0, 20.0] + [0.0] * 6, lr_parts=[(9.0, 9.0), (9.0, 0.0)] + [(0.0, 0.0)] * 6))
    assert list(d.nominal[:2]) == [True, True] and list(d.calibrated[:2]) == [True, False]
    assert list(d.windows[:2]) == [True, False]       # 2 of 2 parts above the band of alpha, 1 of 2 inside it


@pytest.fixture(scope="module")
def small_items(bench, choice):
    """The normal flights and the cut flights of three depths."""
    return [it for it in bench.cut_flights(choice) if it[0] in (0.0, 1.0, 2.0, 4.0)]


def test_trim_detection_on_a_subset(bench, choice, small_items, capsys):
    cp = bench.cp
    airframes = bench.airframe_k(f.drone for d, f in small_items if d == 0.0)
    window = cp.samples(bench.WINDOW_S)
    fit, stat = bench.trim_model(airframes, window), bench.trim_stat(airframes, window)
    t = bench.detection_folds(small_items, fit, stat, depths=[2.0], normals=[0, 7])
    normal = [f for d, f in small_items if d == 0.0]
    assert list(t.depth) == [2.0] * 6 + [0.0, 0.0] and list(t.log[6:]) == [normal[0].log, normal[7].log]
    assert ((t.lr >= 0) & (t.lo <= t.k_hat) & (t.k_hat <= t.hi) & (t.scale > 0)).all()
    assert t.k_hat.between(0.0, 4.0).all() and set(t.degree) <= set(bench.TRIM_DEGREES)
    assert (t.lr_parts.map(len) == 4).all()              # two segments of two whole 2 s windows each
    # the flight's record: whole windows of each segment end to end, one window never spanning two segments
    f = normal[0]
    rec = bench.trim_record(f, window)
    segs = f.arrays(cp.COMMANDS)
    np.testing.assert_array_equal(rec[:window], segs[0][:window])
    np.testing.assert_array_equal(rec[-window:], segs[1][len(segs[1]) // window * window - window:
                                                        len(segs[1]) // window * window])
    # the flight's statistic at its airframe: the flight's mean trim against the fold's surface, by hand
    res = fit([it for it in small_items if it[0] != 2.0])
    d2 = [f for d, f in small_items if d == 2.0][0]
    x = bench.trim_record(d2, window)
    m = x.reshape(-1, window, 3).mean(axis=1)
    V = res.S_rec + res.S_within / len(m)
    G = bench.fp_basis(np.array([[0.0, airframes[d2.drone]]]), res.model.degree, res.model.k_range)
    r = m.mean(axis=0) - (G @ res.params2d)[0]
    q0 = r @ np.linalg.solve(V, r)
    got = stat(res, d2)
    assert q0 - got["lr"] == pytest.approx(min(bench.trim_profile(res, m.mean(axis=0, keepdims=True),
                                                                 airframes[d2.drone], V)[1][0]))
    bench.report_detection_folds(t, "trim")
    out = capsys.readouterr().out
    assert "2.0        6" in out and "normal flights (leave one out)" in out and "depth degree chosen" in out


def test_fp_var_detection_on_a_subset(bench, choice, small_items):
    t = bench.detection_folds(small_items, bench.var_model(choice), bench.var_stat(choice), depths=[4.0], normals=[])
    assert list(t.depth) == [4.0] * 6 and (t.lr_parts.map(len) == 2).all()
    assert (t.crit == bench.chibar_isf(0.01, 2)).all() and (t.mean0 == 1.0).all()     # two segments, two parts
    assert (t.lr == t.lr_parts.map(sum)).all() and (t.scale > 0).all()
    assert t.k_hat.between(0.0, 2.0).all()            # bounded to its fold's range (0-2 mm without 4 mm)


def test_healthy_trim_sees_no_cut_flight(bench, small_items, capsys):
    cp = bench.cp
    airframes = bench.airframe_k(f.drone for d, f in small_items if d == 0.0)
    window = cp.samples(bench.WINDOW_S)
    fit, stat = bench.healthy_trim_model(airframes, window), bench.healthy_trim_stat(airframes, window)
    normal = [it for it in small_items if it[0] == 0.0]
    res = fit(small_items)
    np.testing.assert_array_equal(res.params2d, fit(normal).params2d)        # the cut flights are not fitted
    assert res.nobs == len(normal)
    # a flight's distance from its airframe's healthy trim, by hand: the airframe's surface is its flights' mean
    cut = [f for d, f in small_items if d == 4.0][0]
    m = bench.trim_record(cut, window).reshape(-1, window, 3).mean(axis=1)
    own = np.vstack([bench.trim_record(f, window) for _, f in normal if f.drone == cut.drone])
    r = m.mean(axis=0) - own.reshape(-1, window, 3).mean(axis=(0, 1))
    got = stat(res, cut)
    assert got["lr"] == pytest.approx(r @ np.linalg.solve(res.S_rec + res.S_within / len(m), r), rel=1e-9)
    assert got["crit"] == pytest.approx(11.3448667, rel=1e-6) and got["mean0"] == 3.0 and len(got["lr_parts"]) == 4
    t = bench.detection_folds(small_items, fit, stat, depths=[1.0], normals=[2])
    assert list(t.depth) == [1.0] * 6 + [0.0] and t.k_hat.isna().all() and (t.scale > 0).all()
    bench.report_detection_folds(t, "healthy trim")
    out = capsys.readouterr().out
    assert "calibration scale median" in out and "RMSE" not in out and "k_hat" not in out    # no depth estimate


def test_healthy_trim_by_segment_takes_each_segment_at_its_position(bench, small_items):
    cp = bench.cp
    airframes = bench.airframe_k(f.drone for d, f in small_items if d == 0.0)
    window = cp.samples(bench.WINDOW_S)
    fit, stat = bench.healthy_trim_model(airframes, window, True), bench.healthy_trim_stat(airframes, window, True)
    normal = [f for d, f in small_items if d == 0.0]
    res = fit(small_items)
    assert res.nobs == sum(len(f.segments) for f in normal) and list(res.model.k_names) == ["k0", "k1"]
    # with both parameters categorical (degree 1 each), the surface at (airframe, position) is the mean of the window
    # means of that airframe's segments at that position, and a window spreads about its own segment's mean
    cut = [f for d, f in small_items if d == 4.0][0]
    dev = []
    for pos, x in enumerate(cut.arrays(cp.COMMANDS)):
        same = [y[:len(y) - len(y) % window] for f in normal if f.drone == cut.drone
                for i, y in enumerate(f.arrays(cp.COMMANDS)) if i == pos]
        trim = np.vstack([y.reshape(-1, window, 3).mean(axis=1) for y in same]).mean(axis=0)
        dev.append(x[:len(x) - len(x) % window].reshape(-1, window, 3).mean(axis=1) - trim)
    dev = np.vstack(dev)
    r = dev.mean(axis=0)
    got = stat(res, cut)
    assert got["lr"] == pytest.approx(r @ np.linalg.solve(res.S_rec + res.S_within / len(dev), r), rel=1e-9)
    # the segments' systematic difference is in the surface, not in the windows' spread
    flat = bench.healthy_trim_model(airframes, window)(small_items)
    assert res.S_within[1, 1] < 0.5 * flat.S_within[1, 1]
    assert got["lr"] != pytest.approx(bench.healthy_trim_stat(airframes, window)(flat, cut)["lr"])


# ------------------------------------------------------------------ detectability limit (section 4), without data
def _summary_table(rng, normal=(5, 3), cut=(), cols=("a", "b")):
    """Flights of airframes 'E8' / 'E9' (normal counts ``normal``; ``cut``: (drone, depth, shift vector) per cut
    flight), every summary N(airframe mean + shift, 1) with airframe means 10 and -10."""
    rows = []
    for drone, n in zip(("E8", "E9"), normal):
        rows += [{"depth": 0.0, "drone": drone, "log": f"{drone}_n{i}"} for i in range(n)]
    rows += [{"depth": d, "drone": drone, "log": f"{drone}_c{i}", "shift": s} for i, (drone, d, s) in enumerate(cut)]
    t = pd.DataFrame(rows)
    base = np.where(t.drone == "E8", 10.0, -10.0)[:, None] + rng.standard_normal((len(t), len(cols)))
    shift = np.array([s if isinstance(s, np.ndarray) else np.zeros(len(cols)) for s in t.get("shift", [0] * len(t))])
    return t.drop(columns="shift", errors="ignore").assign(**dict(zip(cols, (base + shift).T)))


def test_null_spread_pools_each_airframe_about_its_own_mean():
    bench = load_benchmark()
    t = pd.DataFrame({"depth": [0.0] * 5 + [3.0], "drone": ["E8", "E8", "E8", "E9", "E9", "E8"],
                      "log": list("abcdef"), "a": [1.0, 2.0, 3.0, 10.0, 14.0, 99.0]})
    mu, S, df, n_a = bench.null_spread(t, ["a"])
    assert mu.loc["E8", "a"] == 2.0 and mu.loc["E9", "a"] == 12.0       # the cut flight (99) is not in the null
    assert df == 3 and S[0, 0] == pytest.approx((1 + 0 + 1 + 4 + 4) / 3) and n_a.to_dict() == {"E8": 3, "E9": 2}


def test_predictive_power_is_the_t_and_hotelling_law():
    bench = load_benchmark()
    from scipy import stats
    # one summary: the two-sided predictive t, noncentral with delta / sqrt(1 + 1/n_a)
    df, n_a, z = 6, 5, 4.0
    lam = z / np.sqrt(1 + 1 / n_a)
    crit = stats.t.isf(0.005, df)
    want = stats.nct.sf(crit, df, lam) + stats.nct.cdf(-crit, df, lam)
    assert bench.predictive_power(lam ** 2, 1, df) == pytest.approx(want, rel=1e-6)
    assert bench.predictive_power(0.0, 3, df) == pytest.approx(0.01, rel=1e-6)        # no shift: the size
    assert bench.predictive_power(0.0, 1, np.inf) == pytest.approx(0.01, rel=1e-6)
    z50 = bench.detectable_effect(0.5, n_a, df)
    assert bench.predictive_power(z50 ** 2 / (1 + 1 / n_a), 1, df) == pytest.approx(0.5, abs=1e-9)
    assert bench.detectable_effect(0.5, np.inf, np.inf) == pytest.approx(stats.norm.isf(0.005), abs=0.01)
    assert z50 > bench.detectable_effect(0.5, 50, 200) > bench.detectable_effect(0.5, np.inf, np.inf)
    with pytest.raises(ValueError, match="2 degrees of freedom cannot estimate the covariance of 3 summaries"):
        bench.predictive_power(1.0, 3, 2)


def test_predictive_test_holds_its_size_and_leaves_the_normal_flight_out():
    bench = load_benchmark()
    rng = np.random.default_rng(2032)
    cut_p, normal_p = [], []
    for _ in range(1500):                            # 8 normal flights and a new one, all from the null
        t = _summary_table(rng, cut=[("E9", 1.0, None)])
        pt = bench.predictive_test(t, ["a", "b"])
        cut_p.append(pt.pvalue.iloc[-1])
        normal_p += list(pt.pvalue.iloc[:-1])
    assert list(pt.df) == [5] * 8 + [6]            # a normal flight judged against the 7 others
    # exact law: the p-values uniform, the rate of p < 0.05 in its 99 % binomial band (without the factor
    # 1 + 1/n_a: 0.074 for the new flight, outside)
    for p, n in ((np.array(cut_p), 1500), (np.array(normal_p), 1500 * 8)):
        lo, hi = stats_band(n, 0.05)
        assert lo <= np.mean(p < 0.05) <= hi and abs(np.mean(p) - 0.5) < 0.03
    shifted = _summary_table(rng, cut=[("E8", 2.0, np.array([8.0, 0.0]))])
    assert bench.predictive_test(shifted, ["a", "b"]).detected.iloc[-1]
    with pytest.raises(ValueError, match="no normal flight of airframe 'E7'"):
        bench.predictive_test(shifted.assign(drone=["E8"] * 8 + ["E7"]), ["a"])


def stats_band(n, p):
    from scipy import stats
    return stats.binom.ppf(0.005, n, p) / n, stats.binom.ppf(0.995, n, p) / n


def test_depth_effects_and_session_scatter_by_hand():
    bench = load_benchmark()
    rng = np.random.default_rng(7)
    t = _summary_table(rng, cut=[("E8", 1.0, None), ("E8", 1.0, None), ("E8", 2.0, None)], cols=("a",))
    eff = bench.depth_effects(t, ["a"])
    mu, S, df, n_a = bench.null_spread(t, ["a"])
    sd = np.sqrt(S[0, 0])
    one = t[(t.depth == 1.0)].a - mu.loc["E8", "a"]
    assert list(eff.depth) == [1.0, 2.0] and list(eff.flights) == [2, 1]
    assert eff["z a"][0] == pytest.approx(one.mean() / sd)
    assert eff["se a"][0] == pytest.approx(one.std() / np.sqrt(2) / sd)
    assert np.isnan(eff["se a"][1])
    assert eff["power a"][0] == pytest.approx(bench.predictive_power(eff["z a"][0] ** 2 / (1 + 1 / 5), 1, df))
    assert bench.joint_power(t, ["a"])[("E8", 1.0)] == pytest.approx(eff["power a"][0])   # one summary: the t
    # session scatter: depth means on a parabola plus offsets +-1 (sigma units), flights' se 0.5 (two flights)
    depths = np.arange(1.0, 7.0)
    off = np.array([1, -1, 1, -1, 1, -1.0])
    e = pd.DataFrame({"depth": depths, "flights": 2, "z a": 0.3 * depths ** 2 + off, "se a": 0.5})
    resid = off - np.polyval(np.polyfit(depths, off, 2), depths)
    tau, within = bench.session_spread(e, "a")
    assert tau == pytest.approx(np.sqrt(np.sum(resid ** 2) / 3 - 0.25)) and within == pytest.approx(0.5 * np.sqrt(2))
    assert bench.session_spread(e.assign(**{"z a": 0.3 * depths ** 2}), "a")[0] == 0.0     # on the curve: none
    with pytest.raises(ValueError, match="3 depths"):
        bench.session_spread(e[:3], "a")


def test_flight_summaries_by_hand(bench, choice, small_items):
    cp = bench.cp
    t = bench.flight_summaries(small_items, choice)
    assert list(t.log) == [f.log for _, f in small_items] and list(t.columns[3:]) == list(bench.SUMMARIES)
    window = cp.samples(bench.WINDOW_S)
    normal = [f for d, f in small_items if d == 0.0]
    cut = [f for d, f in small_items if d == 4.0][0]
    row = t[(t.depth == 4.0) & (t.log == cut.log)].iloc[0]
    segs = [x[:len(x) - len(x) % window] for x in cut.arrays(cp.COMMANDS)]
    np.testing.assert_allclose([row[c] for c in bench.TRIMS], np.vstack(segs).mean(axis=0), rtol=1e-12)
    # the spread about each segment's own mean, not about the flight's (the segments hold different trims)
    dev = np.vstack([s - s.mean(axis=0) for s in segs])
    sd = np.sqrt((dev ** 2).sum(axis=0) / (len(dev) - len(segs)))
    np.testing.assert_allclose([row[c] for c in bench.SPREADS], np.log(sd), rtol=1e-12)
    # a normal flight's residuals through the healthy VAR fitted without it; a cut flight's through all normal flights
    for depth, f, fitted in ((0.0, normal[0], normal[1:]), (4.0, cut, normal)):
        var = tsfdi.VAR(cp.records(fitted, choice.channels), choice.order, trend="c").fit()
        e = np.vstack([np.asarray(var.residuals(x)) for x in f.arrays(choice.channels)])
        got = t[(t.depth == depth) & (t.log == f.log)].iloc[0]
        assert got["resid all"] == pytest.approx(np.linalg.slogdet(np.cov(e.T))[1], rel=1e-9)
