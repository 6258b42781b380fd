"""OnlineDetector(statistic="sprt"): Wald's restarted SPRT on the pairs' prediction errors as a stream statistic,
and its thresholds from a few short healthy logs (issue 34)."""

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from scipy.signal import lfilter
from test_online import PAPER001, assert_streams_like_a_block, two_pairs

from tsfdi.detection.glrt import GLRT
from tsfdi.detection.sequential import SPRT
from tsfdi.exceptions import ConvergenceWarning, TsfdiWarning
from tsfdi.online import OnlineDetector

FS = 50.0


def short_log(rng, seconds=30.0):
    """Two healthy ARX pairs, ``seconds`` at 50 Hz (the shape of a short autopilot log)."""
    n = int(seconds * FS)
    u = rng.standard_normal((n, 2))
    e = 0.1 * rng.standard_normal((n, 2))
    ya = lfilter([1.0], [1.0, -0.7], u[:, 0] + e[:, 0])
    yb = lfilter([1.0], [1.0, -0.5], 0.8 * u[:, 1] + e[:, 1])
    return np.column_stack([ya, yb]), u


def sprt_detector(**kw):
    """The SPRT on the synthetic pairs, whose output follows the input at the same sample (paper 001's settings)."""
    return OnlineDetector(["a", "b"], **{**PAPER001, "na": 1, "nb": 1, "statistic": "sprt", **kw})


def test_sprt_statistic_detects_a_bias_and_restarts():
    y, u = two_pairs(bias=0.3)
    det = sprt_detector()
    assert det.threshold == pytest.approx(np.log(0.99 / 1e-9))          # the default SPRT's upper bound
    assert det.glrt is None and det.sprt.restart
    out = det.run(y, u)
    fa = out.first_alarms
    assert fa.loc["a", "position"] == -1 and fa.loc["a", "armed_at"] > 0
    assert 3000 <= fa.loc["b", "position"] <= 3010 and fa.loc["b", "source"] == "sprt"
    s = np.asarray(out.statistic)
    armed = int(fa.loc["a", "armed_at"])
    assert np.isnan(s[:armed, 0]).all() and np.isfinite(s[armed:, 0]).all()
    # the walk restarts at its lower bound: on the healthy pair it never passes the threshold and keeps coming back
    assert np.nanmax(s[:, 0]) < det.threshold and (s[armed:, 0] <= det.sprt.lower).sum() > 100


def test_sprt_statistic_streaming_equals_block():
    y, u = two_pairs(n=3400, bias=0.3)
    assert assert_streams_like_a_block(sprt_detector, y, u).first_alarm is not None


def test_sprt_statistic_freezes_the_model_at_the_first_alarm():
    y, u = two_pairs(bias=0.3)
    det = sprt_detector()
    out = det.run(y, u)
    k = int(out.first_alarms.loc["b", "position"])
    assert det.models[1].frozen and not det.models[0].frozen
    free = sprt_detector(freeze_on_alarm=False)
    free.run(y[:k], u[:k])
    np.testing.assert_allclose(det.models[1].theta_, free.models[1].theta_, rtol=1e-12)   # alarmed sample not learned


def test_sprt_options_are_checked():
    with pytest.raises(ValueError, match="glrt must be None with statistic='sprt'"):
        sprt_detector(glrt=GLRT(window=20, alpha=1e-6))
    with pytest.raises(ValueError, match="restart=True"):
        sprt_detector(sprt=SPRT("variance", ratio=4.0))
    with pytest.raises(ValueError, match="restart=True"):
        sprt_detector(sprt=SPRT("model", restart=True))
    with pytest.raises(TypeError, match="sprt must be a tsfdi.SPRT"):
        sprt_detector(sprt="wald")
    with pytest.raises(ValueError, match="statistic"):
        OnlineDetector(2, statistic="cusum")
    assert OnlineDetector(2, statistic="zscore").sprt is None and OnlineDetector(2, statistic="zscore").threshold == 4.5


def test_short_healthy_logs_calibrate_the_sprt():
    """The issue's refusal: 0.031 h of healthy data could not set a threshold for 60 false alarms per hour."""
    rng = np.random.default_rng(5)
    logs = [short_log(rng, 37.0) for _ in range(3)]
    ys, us = [lg[0] for lg in logs], [lg[1] for lg in logs]
    with pytest.raises(ValueError, match="healthy hours are needed"):
        OnlineDetector(["a", "b"], **{**PAPER001, "na": 1, "nb": 1}).calibrate(ys, us, false_alarms_per_hour=60, fs=FS)
    det = sprt_detector().calibrate(ys, us, false_alarms_per_hour=60, fs=FS)
    cal = det.calibration_
    assert cal.healthy_hours == pytest.approx(3 * 37.0 / 3600) and cal.estimator == "sprt cycle maxima"
    assert det.threshold == cal.threshold > 0 and det.sprt.scale_ == cal.sprt_scale
    low, central, high = cal.rate_band
    assert low <= central <= 60.0 <= high     # a new log's rate: right-skewed, its mean the stated 60
    assert cal.tail["sprt"]["n_u"] == 20 and cal.healthy_episodes <= 3
    with pytest.raises(ValueError, match="fs .* is needed: healthy run 0"):
        sprt_detector().calibrate(ys, us, false_alarms_per_hour=60)
    with pytest.raises(ValueError, match="not positive: require fewer false alarms"):
        sprt_detector().calibrate(ys, us, false_alarms_per_hour=1e7, fs=FS)
    with pytest.raises(ValueError, match="at least 3 armed"):
        OnlineDetector(["a"], **{**PAPER001, "na": 1, "nb": 1, "statistic": "sprt"}).calibrate(
            [y[:, :1] for y in ys[:2]], [u[:, :1] for u in us[:2]], false_alarms_per_hour=60, fs=FS)
    with pytest.raises(ValueError, match="returned to its lower bound"), pytest.warns(ConvergenceWarning):
        sprt_detector().calibrate([y[:330] for y in ys], [u[:330] for u in us], false_alarms_per_hour=60, fs=FS)


def test_sprt_calibration_leaves_a_record_too_short_for_its_own_exponent_out_of_the_spread():
    """The spread between logs comes from every armed record's own Wald exponent. A record whose pair armed too late
    to estimate it is left out of that spread only, named in a warning with how many records remain (it is left out
    by its length, not its values; its samples still count in the pooled walk and its hours in the rate); the
    calibration is refused only when fewer than three records remain. Before, one such record refused the whole
    detector (issue 34: what refused whole groups of pairs on ALFA)."""
    rng = np.random.default_rng(5)
    logs = [short_log(rng, 37.0) for _ in range(3)]
    ys, us = [lg[0] for lg in logs], [lg[1] for lg in logs]
    ref = sprt_detector().calibrate(ys, us, false_alarms_per_hour=60, fs=FS).calibration_
    with pytest.warns(TsfdiWarning, match=r"^1 armed \(run, pair\) record\(s\) with fewer than 320 armed samples, too "
                      r"few for their own Wald exponent: healthy run 3, pair 'b' \(123\) -- left out of the spread "
                      r"between logs, which 7 of the 8 records give"):
        cal = sprt_detector().calibrate(ys + [ys[0][:500]], us + [us[0][:500]], false_alarms_per_hour=60,
                                        fs=FS).calibration_
    assert cal.runs == 4 and cal.healthy_hours == pytest.approx((3 * 37.0 + 10.0) / 3600)
    assert cal.sprt_scale != ref.sprt_scale and cal.tail["sprt"]["log_exponent_sd"] > 0    # its samples pooled
    # a run that ends before arm_after leaves its pairs no armed sample: both named, not an internal error
    with pytest.warns(TsfdiWarning, match=r"^2 armed .*healthy run 3, pair 'a' \(0\), healthy run 3, pair 'b' \(0\) "
                      r"-- left out of the spread between logs, which 6 of the 8"):
        sprt_detector(arm_after=600).calibrate(ys + [ys[0][:500]], us + [us[0][:500]], false_alarms_per_hour=60,
                                               fs=FS)
    # too few records left for the spread: refused, naming the short ones
    with pytest.raises(ValueError, match=r"from at least 3 records of at least 320 armed samples, the healthy runs "
                       r"give 2 \(the other armed \(run, pair\) record\(s\) .*healthy run 1, pair 'a' \(0\), "
                       r"healthy run 1, pair 'b' \(0\), healthy run 2, pair 'a' \(0\), "
                       r"healthy run 2, pair 'b' \(0\)\)"):
        sprt_detector(arm_after=600).calibrate([ys[0], ys[1][:500], ys[2][:500]], [us[0], us[1][:500], us[2][:500]],
                                               false_alarms_per_hour=60, fs=FS)


def test_wald_exponent_is_the_first_root_where_the_cumulant_is_positive_on_a_short_interval_only():
    """With negatively autocorrelated increments (the long-run variance below the variance) the cumulant equation of
    the SPRT's walk can be positive on a short interval only: here MA(1) increments, positive for h in about 1.30 to
    1.76 and negative at h = 1, 2, 4, ... Its first root is Wald's exponent. Before, the search doubled h from 1,
    stepped over the interval and refused the record ("never rises"; found on the streaming benchmark's logs with
    per-pair priors, session 38)."""
    from scipy import special

    from tsfdi.online import _long_run_variance, _wald_exponent

    e = np.random.default_rng(10).standard_normal(4001)
    z = -0.05 + e[1:] - 0.7 * e[:-1]
    extra = 0.5 * (_long_run_variance(z) - z.var())

    def cumulant(h):
        return special.logsumexp(h * z) - np.log(z.size) + h * h * extra

    assert all(cumulant(2.0 ** k) < 0 for k in range(21))
    h = _wald_exponent(z, "run")
    assert 1.2 < h < 1.35 and abs(cumulant(h)) < 1e-9
    assert all(cumulant(g) < 0 for g in np.linspace(1e-3, h, 200)[:-1])            # nothing positive before it
    # white increments: the root where the doubling search found it (h* = -2 mean / variance for normal increments)
    w = -0.05 + np.random.default_rng(11).standard_normal(4000)
    assert _wald_exponent(w, "run") == pytest.approx(0.1, rel=0.3)
    # strongly negatively correlated increments with no positive region: refused with the variance ratio
    with pytest.raises(ValueError, match=r"run: the SPRT's log-likelihood ratio never rises .* the long-run variance "
                       r"of its increments is 0\.\d\d times their variance"):
        _wald_exponent(-0.2 + e[1:] - 0.95 * e[:-1], "run")


def test_sprt_calibration_takes_a_record_drifting_up_by_less_than_two_standard_errors_as_censored():
    """A record whose log-likelihood ratio grows on average, but by less than two standard errors of its mean (from
    its long-run variance), has a small exponent its samples cannot estimate: it refused the whole detector before
    (what refused the running scale's groups of pairs on ALFA); now its exponent counts in the spread between logs as
    a value known only to lie below the exponent of its mean lowered by two standard errors (left-censored, normal
    maximum likelihood), named in a warning -- kept, not left out by its values. A record growing by more is still
    refused, naming its standard errors."""
    rng = np.random.default_rng(5)
    logs = [short_log(rng, 37.0) for _ in range(3)]
    ys, us = [lg[0] for lg in logs], [lg[1] for lg in logs]
    ref = sprt_detector().calibrate(ys, us, false_alarms_per_hour=60, fs=FS).calibration_
    r1 = np.random.default_rng(1)
    y, u = [spread_log(r1) for _ in range(3)][2]      # its spread grows 1.5x against the scale at arming
    with pytest.warns(TsfdiWarning, match=r"^2 armed \(run, pair\) record\(s\) whose SPRT log-likelihood ratio grows "
                      r"on average, though by less than 2 standard errors: healthy run 3, pair 'a' \(0.13 standard "
                      r"errors\), healthy run 3, pair 'b' \(1.7 standard errors\) -- each taken .* \(censored\)"):
        cal = sprt_detector().calibrate(ys + [y], us + [u], false_alarms_per_hour=60, fs=FS).calibration_
    assert cal.runs == 4 and cal.tail["sprt"]["log_exponent_sd"] > 5 * ref.tail["sprt"]["log_exponent_sd"]
    assert cal.threshold > ref.threshold
    y, u = spread_log(np.random.default_rng(3), rise=2.0)
    with pytest.raises(ValueError, match=r"healthy run 3, pair 'a': the SPRT's log-likelihood ratio grows on average "
                       r"\(0.04454 per sample, 3.89 standard errors\)"):
        sprt_detector().calibrate(ys + [y], us + [u], false_alarms_per_hour=60, fs=FS)


def recipe_log(rng, seconds=30.0):
    """Two healthy pairs as the defaults model them (``na=1, nb=2, nk=1``): each output follows its input one sample
    later, ``seconds`` at 50 Hz."""
    n = int(seconds * FS)
    u = rng.standard_normal((n, 2))
    e = 0.1 * rng.standard_normal((n, 2))
    xa = np.r_[0.0, u[:-1, 0]] + e[:, 0]
    xb = np.r_[0.0, 0.6 * u[:-1, 1]] + np.r_[0.0, 0.0, 0.3 * u[:-2, 1]] + e[:, 1]
    return np.column_stack([lfilter([1.0], [1.0, -0.7], xa), lfilter([1.0], [1.0, -0.5], xb)]), u


def restart_cycles(det, make, y, u):
    """Restart cycles of the calibrated walk of ``det`` that reach its threshold on the healthy log ``(y, u)``: the
    rate ``calibrate`` sets (its Notes). The walk is that of a copy (``make``) with the calibrated SPRT and a
    threshold it never reaches (restarted at the lower bound only), cut into cycles after every sample at or below
    the lower bound; the last, unfinished cycle counts when it reaches the threshold."""
    walk = make(sprt=det.sprt, threshold=1e300, freeze_on_alarm=False).run(y, u).statistic
    count = 0
    for x in np.asarray(walk).T:
        x = x[np.isfinite(x)]
        if x.size:
            starts = np.r_[0, np.flatnonzero(x[:-1] <= det.sprt.lower) + 1]
            count += int((np.maximum.reduceat(x, starts) >= det.threshold).sum())
    return count


def calibrated_rate(rng, log, make, reps=100, logs=10, rate=60.0):
    """Monte Carlo of ``calibrate``: ``reps`` times three healthy ``log(rng)`` set the threshold of ``make()`` for
    ``rate`` false alarms per flight hour, then ``logs`` new ones run. Returns the restart cycles reaching the
    threshold on the new logs, the alarm episodes the calibrated detector raises on them without freezing
    (``false_alarms_per_hour()["all"]``), and the two-sided 99 % binomial band of the stated rate over their
    samples (an alarm starts at one of them, probability ``rate / (3600 fs)`` each)."""
    cycles, episodes, samples = 0, 0, 0
    for _ in range(reps):
        cal = [log(rng) for _ in range(3)]
        det = make(freeze_on_alarm=False).calibrate([c[0] for c in cal], [c[1] for c in cal],
                                                    false_alarms_per_hour=rate, fs=FS)
        for _ in range(logs):
            y, u = log(rng)
            det.reset()
            episodes += int(det.run(y, u).false_alarms_per_hour(FS).loc["all", "episodes"])
            cycles += restart_cycles(det, make, y, u)
            samples += len(y)
    p = rate / (3600.0 * FS)
    return cycles, episodes, (stats.binom.ppf(0.005, samples, p), stats.binom.ppf(0.995, samples, p))


def test_the_defaults_calibrated_on_three_30s_logs_keep_their_rate_on_ten_others():
    """Monte Carlo (fixed seed), the issue's acceptance for the default configuration (``OnlineDetector(pairs)``:
    na=1, nb=2, nk=1, forgetting 0.999, eps 0.03, the SPRT with the scale at arming): 100 times, three 30 s healthy
    logs set the threshold for 60 false alarms per flight hour; ten new 30 s logs then run. The rule: the restart
    cycles reaching the threshold on the 1,000 new logs -- the rate ``calibrate`` states: a log's first alarm and
    every alarm after the walk has returned to its lower bound -- lie in the two-sided 99 % binomial band of the
    stated rate over that exposure (the stated rate is a predictive mean over new logs, so two-sided). With this
    seed: 522 cycles in 8.33 h (62.6 per hour; band 443-559); the detector without freezing raises 525 episodes
    (63.0 per hour): after an alarm its walk restarts at 0 and may alarm again within the same burst. The count is
    overdispersed (a calibration's threshold is shared by its ten logs), so the band is the project's yardstick,
    not a calibrated acceptance region."""
    cycles, episodes, (low, high) = calibrated_rate(np.random.default_rng(2024), recipe_log,
                                                    lambda **kw: OnlineDetector(["a", "b"], **kw))
    assert (low, high) == (443, 559) and episodes >= cycles
    assert low <= cycles <= high


def spread_log(rng, seconds=30.0, rise=1.5, fault_at=None):
    """``short_log`` whose error spread grows smoothly by ``rise`` (a flight phase with more turbulence, centred at a
    random time, about 8 s long), optionally with pair b's error spread doubled from ``fault_at`` seconds on (the
    default SPRT's alternative: the error variance times 4)."""
    n = int(seconds * FS)
    t = np.arange(n) / FS
    g = 1.0 + (rise - 1.0) / (1.0 + np.exp(-(t - rng.uniform(5.0, seconds - 5.0)) / 2.0))
    u = rng.standard_normal((n, 2))
    e = 0.1 * rng.standard_normal((n, 2)) * g[:, None]
    if fault_at is not None:
        e[int(fault_at * FS):, 1] *= 2.0
    ya = lfilter([1.0], [1.0, -0.7], u[:, 0] + e[:, 0])
    yb = lfilter([1.0], [1.0, -0.5], 0.8 * u[:, 1] + e[:, 1])
    return np.column_stack([ya, yb]), u


def test_running_scale_follows_a_healthy_spread_change_and_finds_a_fault():
    """scale_forgetting: the errors standardised by a lagged running scale. A healthy log whose error spread grows
    by 1.5 (variance 2.25) alarms against the scale fixed at arming and not against the running one; a fault of the
    SPRT's alternative is still found at once, because its errors meet the scale from before it for scale_lag
    samples -- without the lag a fast scale adapts it away."""
    rng = np.random.default_rng(11)
    for _ in range(5):
        y, u = spread_log(rng)
        assert sprt_detector().run(y, u).first_alarm is not None
        assert sprt_detector(scale_forgetting=0.995).run(y, u).first_alarm is None
    det = sprt_detector(scale_forgetting=0.995)
    assert det.scale_lag == 50 and det.scale_forgetting == 0.995 and sprt_detector().scale_forgetting is None
    found = {100: 0, 0: 0}
    for seed in range(5):
        y, u = spread_log(np.random.default_rng(seed), rise=1.0, fault_at=20.0)
        out = sprt_detector(scale_forgetting=0.995).run(y, u)
        assert out.first_alarm_pair == "b" and 0 <= out.first_alarm - 1000 <= 70
        for lag in found:
            found[lag] += sprt_detector(scale_forgetting=0.95, scale_lag=lag).run(y, u).first_alarm is not None
    # a scale with 20 samples' memory: the fault found while the lag keeps its errors out, mostly adapted away without
    assert found == {100: 5, 0: 1}
    with pytest.raises(ValueError, match="scale_forgetting must be < 1"):
        sprt_detector(scale_forgetting=1.0)
    with pytest.raises(ValueError, match="scale_forgetting must be > 0"):
        sprt_detector(scale_forgetting=0)
    with pytest.raises(TypeError, match="scale_forgetting must be a real number"):
        sprt_detector(scale_forgetting="0.995")
    with pytest.raises(ValueError, match="scale_lag must be >= 0"):
        sprt_detector(scale_forgetting=0.995, scale_lag=-1)
    with pytest.raises(ValueError, match="scale_forgetting=0.995 needs statistic='sprt'"):
        OnlineDetector(2, statistic="zscore", scale_forgetting=0.995)


@pytest.mark.filterwarnings("ignore::tsfdi.exceptions.ConvergenceWarning")     # chunks of 7 end before arming
@pytest.mark.parametrize("settle", [0, 120])
def test_running_scale_streaming_equals_block(settle):
    """Block, chunks and samples give the same walk, alarms and first alarms with the running scale, across the
    lag and across skipped (NaN) samples, which neither enter the scale nor count in the lag."""
    y, u = spread_log(np.random.default_rng(3), seconds=60.0, fault_at=45.0)
    y[[700, 701, 1500, 2300], 1] = np.nan
    kw = dict(scale_forgetting=0.99, scale_lag=30, settle=settle)
    ref = assert_streams_like_a_block(lambda: sprt_detector(**kw), y, u, sizes=(7, 777))
    assert ref.first_alarm_pair == "b" and ref.first_alarm >= 2250


def test_running_scale_calibrates_logs_whose_spread_varies():
    """calibrate with scale_forgetting standardises the healthy logs as the walk does. Three 30 s logs whose spread
    grows by 1.5 are refused with the scale fixed at arming (the walk drifts up) and calibrated with the running
    one; Monte Carlo (fixed seed) as the issue's acceptance test (:func:`calibrated_rate`): the restart cycles
    reaching the threshold on the 1,000 new logs lie in the two-sided 99 % binomial band of the stated 60 per hour.
    With this seed: 552 cycles in 8.33 h (66.2 per hour; band 443-559). The 589 alarm episodes (70.7 per hour) of
    the detector without freezing, which the earlier version of this test counted within a factor 1.5, add the
    alarms after a restart at 0 within the same burst: not the rate ``calibrate`` states (its Notes)."""
    rng = np.random.default_rng(1)
    logs = [spread_log(rng) for _ in range(3)]
    ys, us = [lg[0] for lg in logs], [lg[1] for lg in logs]
    with pytest.raises(ValueError, match="healthy"):
        sprt_detector().calibrate(ys, us, false_alarms_per_hour=60, fs=FS)
    det = sprt_detector(scale_forgetting=0.995).calibrate(ys, us, false_alarms_per_hour=60, fs=FS)
    assert det.calibration_.estimator == "sprt cycle maxima" and det.threshold > 0
    cycles, episodes, (low, high) = calibrated_rate(rng, spread_log,
                                                    lambda **kw: sprt_detector(scale_forgetting=0.995, **kw))
    assert episodes >= cycles
    assert low <= cycles <= high
