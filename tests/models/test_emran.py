"""EMRAN (paper 004, eqs. 1-5): growth criteria, winner-only adaptation and pruning on constructed cases, online
approximation of known functions, agreement with the plain numpy loop of benchmarks/emran_throughput.py, stream
equivalence, data kinds and bad input."""

import copy

import numpy as np
import pytest

import tsfdi
from tsfdi.models.emran import EMRAN
from conftest import as_kind, assert_kind
from _scripts import load_script


@pytest.fixture(scope="module")
def reference():
    return load_script("benchmarks/emran_throughput.py")


def test_exported():
    assert tsfdi.models.EMRAN is EMRAN
    assert tsfdi.models.EMRANResults is not None


# ------------------------------------------------------------------------------ growth (eqs. 2-4)
def test_first_sample_grows_a_unit_with_the_mran_initialisation():
    net = EMRAN(2, error_threshold=0.5, rms_threshold=0.1, distance_threshold=1.0, distance_start=3.0,
                overlap=0.5)
    e = net.update([1.0, -2.0], 2.0)
    assert e == 2.0                                        # no unit, bias 0: the error is y
    assert net.n_units == 1 and net.n_grown == 1
    np.testing.assert_array_equal(net.centres_, [[1.0, -2.0]])     # mu = x
    np.testing.assert_array_equal(net.weights_, [2.0])             # alpha = e
    np.testing.assert_array_equal(net.widths_, [0.5 * 3.0])        # first unit: kappa * eps_max
    assert net.bias_ == 0.0                                # nothing else changes at a growth step


def test_second_unit_width_is_overlap_times_distance_to_nearest_centre():
    net = EMRAN(1, error_threshold=0.5, rms_threshold=0.0, distance_threshold=1.0, overlap=0.7)
    net.update(0.0, 1.0)
    net.update(4.0, 1.0)                                   # prediction ~ exp(-16 / 0.49) ~ 0: e ~ 1 > E1, d = 4 > E3
    assert net.n_units == 2
    np.testing.assert_allclose(net.widths_, [0.7 * 1.0, 0.7 * 4.0])
    np.testing.assert_allclose(net.centres_.ravel(), [0.0, 4.0])


@pytest.mark.parametrize("blocked", ["none", "error", "rms", "distance"])
def test_each_growth_criterion_alone_blocks_growth(blocked):
    # a unit at x = 0 (alpha = 3, sigma = 0.5) predicted exactly 8 times (e = 0), then one sample for which exactly
    # one criterion fails; "none": every criterion holds (x = 5: d = 5 > E3 = 1, e = 1 > E1 = 0.5, RMS 1 > 0.2)
    opts = dict(error_threshold=0.5, rms_threshold=0.2, rms_window=1, distance_threshold=1.0, overlap=0.5)
    x, y = 5.0, 1.0
    if blocked == "error":
        y = 0.4                                            # |e| = 0.4 <= E1
    elif blocked == "rms":
        opts.update(rms_window=10, rms_threshold=2.0)      # RMS of [3, 0 x 8, 1] = 1 <= E2 = 2
    elif blocked == "distance":
        x, y = 0.9, 6.0                                    # d = 0.9 <= E3, e = 6 - 3 exp(-3.24) = 5.9
    net = EMRAN(1, **opts)
    res = net.run(np.r_[np.zeros(9), x], np.r_[np.full(9, 3.0), y])
    assert res.grew[0] and not res.grew[1:9].any()
    np.testing.assert_array_equal(np.asarray(res.resid)[1:9], 0.0)
    assert res.grew[9] == (blocked == "none")
    assert net.n_units == (2 if blocked == "none" else 1)


def test_distance_schedule_decays_from_start_to_threshold():
    # eps_n = max(eps_max gamma^n, eps_min): a sample at distance 2 is not novel at n = 1 (eps = 4 * 0.5) ...
    net = EMRAN(1, error_threshold=0.0, rms_threshold=0.0, distance_threshold=0.5, distance_start=4.0,
                distance_decay=0.5)
    # n = 0: eps = 4, grows (no unit); n = 1: eps = 2 < d = 2.1: grows; n = 2: eps = 1 > d = 0.9: adapts (the
    # winner at 2.1 moves towards 3); n = 3: eps = 0.5, d >= 1: grows
    res = net.run(np.array([0.0, 2.1, 3.0, 4.0]), np.array([1.0, 5.0, 5.0, 5.0]))
    np.testing.assert_array_equal(res.grew, [True, True, False, True])
    np.testing.assert_array_equal(res.adapted, [False, False, True, False])
    same = EMRAN(1, error_threshold=0.0, rms_threshold=0.0, distance_threshold=0.5, distance_start=4.0)
    assert not same.run(np.array([0.0, 2.1]), np.array([1.0, 5.0])).grew[1]     # no decay: eps stays 4


# ------------------------------------------------------------------------------ adaptation
def test_ekf_step_of_the_bias_by_hand():
    # no unit and |e| <= E1: the bias alone is adapted, k = p / (R + p) with p = P0 = 1, R = 0.1
    net = EMRAN(1, error_threshold=10.0, P0=1.0, measurement_noise=0.1, process_noise=1e-4)
    e = net.update(0.0, 1.0)
    assert e == 1.0 and net.n_units == 0
    assert net.bias_ == pytest.approx(1.0 / 1.1, rel=1e-15)
    assert net._fst[1] == pytest.approx(1.0 - 1.0 / 1.1 + 1e-4, rel=1e-14)     # p - k a' p + Q
    e2 = net.update(0.0, 1.0)
    assert e2 == pytest.approx(1.0 - 1.0 / 1.1, rel=1e-14)


def test_gradient_rule_of_eq5_by_hand():
    net = EMRAN(1, error_threshold=10.0, learning_rate=0.1, weight_decay=0.5)
    net.update(0.0, 1.0)
    assert net.bias_ == pytest.approx(0.1 * 1.0, rel=1e-15)             # theta += eta (e * 1 - sigma * 0)
    net.update(0.0, 1.0)                                                 # e = 0.9
    assert net.bias_ == pytest.approx(0.1 + 0.1 * (0.9 - 0.5 * 0.1), rel=1e-14)


def test_only_the_winner_is_adapted():
    net = EMRAN(1, error_threshold=0.5, rms_threshold=0.0, distance_threshold=1.0, overlap=0.8)
    net.update(0.0, 1.0)
    net.update(3.0, -1.0)
    assert net.n_units == 2
    c, w, a = net.centres_, net.widths_, net.weights_
    net.update(0.4, 0.5)                                   # near unit 0 (d = 0.4 < E3): adapt, unit 0 most active
    c2, w2, a2 = net.centres_, net.widths_, net.weights_
    assert c2[0, 0] != c[0, 0] and w2[0] != w[0] and a2[0] != a[0]
    assert c2[1, 0] == c[1, 0] and w2[1] == w[1] and a2[1] == a[1]


# ------------------------------------------------------------------------------ pruning
def test_unit_pruned_after_prune_window_inactive_samples():
    # unit A at 0 (sigma 0.2), unit B at 5 (sigma 1); at x = 0, |alpha_B phi_B| / |alpha_A phi_A| ~ e^-25 < delta
    net = EMRAN(1, error_threshold=0.5, rms_threshold=0.0, distance_threshold=1.0, overlap=0.2,
                prune_threshold=0.01, prune_window=5)
    res = net.run(np.array([0.0, 5.0] + [0.0] * 8), np.ones(10))
    np.testing.assert_array_equal(res.grew, [True, True] + [False] * 8)
    np.testing.assert_array_equal(res.n_units, [1, 2, 2, 2, 2, 2, 1, 1, 1, 1])
    np.testing.assert_array_equal(res.pruned, [False] * 6 + [True] + [False] * 3)   # 5th inactive sample
    assert net.n_pruned == 1
    np.testing.assert_array_equal(net.centres_, [[0.0]])     # the active unit stays


def test_a_single_unit_is_never_pruned():
    net = EMRAN(1, error_threshold=0.5, rms_threshold=0.0, prune_window=1)
    net.run(np.zeros(50), np.ones(50))
    assert net.n_units == 1 and net.n_pruned == 0


def test_max_units_caps_growth():
    net = EMRAN(1, error_threshold=0.0, rms_threshold=0.0, distance_threshold=0.01, max_units=3)
    net.run(np.arange(10.0), (-1.0) ** np.arange(10))
    assert net.n_units == 3 and net.n_grown == 3


# ------------------------------------------------------------------------------ approximation
def test_approximates_a_nonlinear_function_online():
    """sin(2x) on [-2, 2], 3000 online samples: RMS a-priori error of the last 500 < 0.02, grid error < 0.05."""
    rng = np.random.default_rng(0)
    x = rng.uniform(-2.0, 2.0, 3000)
    net = EMRAN(1)
    res = net.run(x, np.sin(2.0 * x))
    tail = np.asarray(res.resid)[-500:]
    assert np.sqrt(np.mean(tail ** 2)) < 0.02             # measured 0.0054
    grid = np.linspace(-1.9, 1.9, 39)
    assert np.max(np.abs(net.predict(grid) - np.sin(2.0 * grid))) < 0.05
    assert 4 <= net.n_units <= 20


def test_approximates_a_two_input_function_with_noise():
    """y = sin(x1) cos(x2) + noise(0.05) on standard-normal inputs: RMS error of the last 2000 errors < 0.1."""
    rng = np.random.default_rng(1)
    X = rng.standard_normal((8000, 2))
    f = np.sin(X[:, 0]) * np.cos(X[:, 1])
    net = EMRAN(2)
    res = net.run(X, f + 0.05 * rng.standard_normal(8000))
    tail = np.asarray(res.resid)[-2000:]
    assert np.sqrt(np.mean(tail ** 2)) < 0.1
    Xt = rng.standard_normal((500, 2)) * 0.8
    truth = np.sin(Xt[:, 0]) * np.cos(Xt[:, 1])
    assert np.sqrt(np.mean((net.predict(Xt) - truth) ** 2)) < 0.08


def test_kernel_equals_the_plain_numpy_loop(reference):
    rng = np.random.default_rng(2)
    X, y = reference.data(2000, 3, rng)
    opts = dict(reference.OPTIONS, prune_window=20, distance_start=1.5, distance_decay=0.999)
    res = EMRAN(3, **opts).run(X, y)
    err, units = reference.numpy_emran(X, y, **opts)
    np.testing.assert_allclose(np.asarray(res.resid), err, rtol=0, atol=1e-10)
    np.testing.assert_array_equal(res.n_units, units)
    assert res.pruned.any() and res.grew.sum() > 5         # the case exercises growth and pruning


# ------------------------------------------------------------------------------ streaming, state, kinds
def test_update_chunks_and_run_are_identical():
    rng = np.random.default_rng(3)
    X = rng.standard_normal((400, 2))
    y = np.tanh(X[:, 0]) + 0.1 * X[:, 1]
    a = EMRAN(2).run(X, y)
    b = EMRAN(2)
    errs = [b.update(X[t], y[t]) for t in range(400)]
    c = EMRAN(2)
    parts = [c.run(X[i:i + 97], y[i:i + 97]) for i in range(0, 400, 97)]
    np.testing.assert_array_equal(np.asarray(a.resid), errs)
    np.testing.assert_array_equal(np.asarray(a.resid), np.concatenate([np.asarray(p.resid) for p in parts]))
    assert parts[1].start == 97 and c.nobs == 400


def test_freeze_stops_learning_and_reset_restarts():
    rng = np.random.default_rng(4)
    x = rng.uniform(-1, 1, 300)
    net = EMRAN(1)
    net.run(x, np.sin(3 * x))
    state = (net.centres_, net.widths_, net.weights_, net.bias_)
    net.freeze()
    res = net.run(x, np.sin(3 * x) + 1.0)                  # a bias fault: not learnt
    assert net.frozen and not res.adapted.any() and not res.grew.any()
    for before, after in zip(state, (net.centres_, net.widths_, net.weights_, net.bias_)):
        np.testing.assert_array_equal(before, after)
    np.testing.assert_allclose(np.asarray(res.resid), 1.0 + np.sin(3 * x) - np.asarray(net.predict(x)), atol=1e-12)
    net.reset()
    assert net.n_units == 0 and not net.frozen and net.nobs == 0


def test_deepcopy_continues_identically():
    rng = np.random.default_rng(5)
    x = rng.uniform(-1, 1, 200)
    net = EMRAN(1)
    net.run(x[:100], np.sin(3 * x[:100]))
    twin = copy.deepcopy(net)
    np.testing.assert_array_equal(np.asarray(net.run(x[100:], x[100:]).resid),
                                  np.asarray(twin.run(x[100:], x[100:]).resid))


def test_data_kinds(kind):
    rng = np.random.default_rng(6)
    X = rng.standard_normal((120, 2))
    y = X[:, 0] ** 2
    res = EMRAN(2).run(as_kind(X, kind, ["a", "b"]), as_kind(y, kind))
    for series in (res.resid, res.prediction, res.rms):
        assert_kind(series, kind, 1)
    if kind == "pandas":
        assert res.resid.index.equals(as_kind(y, kind).index)
    ref = EMRAN(2).run(X, y)
    np.testing.assert_array_equal(np.asarray(res.resid), ref.resid)


def test_nonfinite_policy():
    X = np.array([[0.0], [np.nan], [1.0]])
    y = np.array([1.0, 2.0, np.inf])
    with pytest.raises(ValueError, match="X contains NaN/inf .first at sample 1"):
        EMRAN(1).run(X, y)
    net = EMRAN(1, nonfinite="skip")
    res = net.run(X, y)
    assert np.isnan(np.asarray(res.resid)[1:]).all() and res.skipped.tolist() == [False, True, True]
    assert net.n_skipped == 2 and net.nobs == 3


@pytest.mark.parametrize("call, exc, match", [
    (lambda: EMRAN(2).run(np.zeros((5, 3)), np.zeros(5)), ValueError, "X must have n_inputs=2"),
    (lambda: EMRAN(1).run(np.zeros(5), np.zeros(4)), ValueError, "same length"),
    (lambda: EMRAN(1).run(np.zeros(5), np.zeros((5, 2))), ValueError, "y must be a scalar signal"),
    (lambda: EMRAN(1).update(0.0, True), TypeError, "y must be a real number"),
    (lambda: EMRAN(1).update("a", 1.0), TypeError, "x must be real number"),
    (lambda: EMRAN(1).update([0.0, 1.0], 1.0), ValueError, "x must hold n_inputs=1"),
    (lambda: EMRAN(1).update(1e120, 1.0), ValueError, "X has a sample of magnitude 1e\\+120"),
    (lambda: EMRAN(1).run(np.array(["a", "b"]), np.zeros(2)), TypeError, "X must contain real numbers"),
    (lambda: EMRAN(0), ValueError, "n_inputs must be >= 1"),
    (lambda: EMRAN(1, distance_threshold=0.0), ValueError, "distance_threshold must be > 0"),
    (lambda: EMRAN(1, distance_threshold=1.0, distance_start=0.5), ValueError, "distance_start must be >= 1.0"),
    (lambda: EMRAN(1, distance_decay=1.5), ValueError, "distance_decay must be <= 1.0"),
    (lambda: EMRAN(1, learning_rate=0.0), ValueError, "learning_rate must be > 0"),
    (lambda: EMRAN(1, nonfinite="drop"), ValueError, "nonfinite must be one of"),
    (lambda: EMRAN(n_inputs=30, max_units=2**20), ValueError, "max_units=1,048,576"),
    (lambda: EMRAN(1, overlap="big"), TypeError, "overlap must be a real number"),
])
def test_bad_input_names_the_argument(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


def test_failed_update_leaves_the_network_unchanged():
    net = EMRAN(1)
    net.update(0.5, 1.0)
    before = (net.nobs, net.bias_, net.weights_.tolist())
    with pytest.raises(ValueError):
        net.update(np.nan, 1.0)
    assert (net.nobs, net.bias_, net.weights_.tolist()) == before


def test_x_and_y_with_different_indexes_or_a_gap_are_refused():
    """Issue 29, items 1 and 5: EMRAN paired pandas X and y by position and ran across a logging gap."""
    import pandas as pd

    rng = np.random.default_rng(29)
    t = pd.date_range("2024", periods=100, freq="10ms")
    X = pd.DataFrame(rng.standard_normal((100, 2)), index=t)
    y = pd.Series(np.sin(X[0].to_numpy()), index=t)
    with pytest.raises(ValueError, match=r"X and y have different indexes \(first at sample 0"):
        EMRAN(2).run(X, y.set_axis(t + pd.Timedelta("10ms")))
    gap = t.delete(range(40, 60))
    with pytest.raises(ValueError, match=r"y is not uniformly sampled: a gap of 0.21 s after sample 39"):
        EMRAN(2).run(X.iloc[:80].set_axis(gap), y.iloc[:80].set_axis(gap))
    assert EMRAN(2).run(X, y).resid.index.equals(t)
