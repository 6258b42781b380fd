"""What the figures show: separate BIC and RSS/SSS axes with integer orders, channel names on the axes, legends,
confusion tables whose rows add up to 100 %, and a demo report that embeds its figures and states its units."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

import tsfdi
from tsfdi import plotting
from tsfdi.monitoring import MonitorResult

CHANNELS = ["roll", "pitch"]


@pytest.fixture(autouse=True)
def close_figures():
    import matplotlib.pyplot as plt

    yield
    plt.close("all")


def var_signal(n: int, seed: int, scale: float = 1.0) -> pd.DataFrame:
    """Two coupled AR(2) channels with a time index in s (100 Hz)."""
    e = np.random.default_rng(seed).standard_normal((n + 200, 2)) * scale
    x = np.column_stack([lfilter([1.0], [1.0, -1.2, 0.5], e[:, 0]),
                         lfilter([1.0], [1.0, -0.6, 0.2], e[:, 1] + 0.5 * e[:, 0])])[200:]
    return pd.DataFrame(x, columns=CHANNELS, index=pd.Index(np.arange(n) / 100.0, name="time"))


def tick_values(axis) -> np.ndarray:
    """The major tick positions inside the axis' view interval."""
    lo, hi = sorted(axis.get_view_interval())
    t = np.asarray(axis.get_majorticklocs())
    return t[(t >= lo) & (t <= hi)]


def test_order_selection_two_axes_integer_ticks():
    sel = tsfdi.select_order(var_signal(3000, 0), max_lags=11, model="var")
    fig = sel.plot()
    top, bottom = fig.axes
    assert top.get_ylabel() == "BIC - min BIC" and bottom.get_ylabel() == "RSS/SSS (%)"
    assert bottom.get_xlabel() == "model order (lags)" and bottom.get_yscale() == "log"
    # each criterion on its own axes: the BIC curve is not drawn on the RSS/SSS axes and vice versa
    bic, = [ln for ln in top.get_lines() if ln.get_label() == "BIC - min BIC"]
    rss, = [ln for ln in bottom.get_lines() if ln.get_label() == "RSS/SSS"]
    np.testing.assert_allclose(bic.get_ydata(), sel.table["bic"] - sel.table["bic"].min())
    np.testing.assert_allclose(rss.get_ydata(), sel.table["rss_sss"])
    assert min(bic.get_ydata()) == 0.0
    fig.canvas.draw()
    for a in (top, bottom):
        ticks = tick_values(a.xaxis)
        assert ticks.size >= 3 and np.array_equal(ticks, np.round(ticks)), ticks
        labels = [t.get_text() for t in a.get_legend().get_texts()]
        assert f"min BIC: order {sel.selected}" in labels and f"RSS/SSS stable: order {sel.stabilized}" in labels
    import matplotlib.pyplot as plt

    _, axes = plt.subplots(1, 2)
    assert sel.plot(ax=axes) is axes[0].figure
    with pytest.raises(ValueError, match="ax must be a sequence of two Axes"):
        sel.plot(ax=axes[0])


def test_variance_evolution_names_and_legend():
    recs = [var_signal(3000, 1), var_signal(3000, 2, scale=2.0)]
    fig = plotting.plot_variance_evolution(recs, fs=100.0, window=5.0, thresholds=[1.0, 2.0], failure_time=10.0)
    assert [a.get_ylabel() for a in fig.axes] == ["var(roll)", "var(pitch)"]
    legend = fig.axes[0].get_legend()
    assert legend is not None
    assert {t.get_text() for t in legend.get_texts()} == {"steady-state threshold", "failure at 10 s"}
    fig = plotting.plot_variance_evolution(recs, fs=100.0, window=5.0, labels=["healthy", "fault"])
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["healthy", "fault"]
    # numpy input has no names: the generic ones
    fig = plotting.plot_variance_evolution(recs[0].to_numpy(), fs=100.0, window=5.0)
    assert [a.get_ylabel() for a in fig.axes] == ["var(y0)", "var(y1)"]


def test_acf_decision_identification_name_channels():
    x = var_signal(4000, 3)
    healthy = tsfdi.VAR(x.iloc[:2000], 2).fit()
    other = tsfdi.VAR(var_signal(2000, 4, scale=3.0) ** 2, 2).fit()
    fig = plotting.plot_acf(healthy.residuals(x.iloc[2000:]), lags=10)
    titles = {a.get_title() for a in fig.axes}
    assert {"ACF roll", "ACF pitch", "CCF roll vs pitch(t-k)"} <= titles
    test = tsfdi.LjungBox(lags=10, alpha=1e-3)
    fig = tsfdi.detect(x.iloc[2000:], healthy, test).plot()
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == CHANNELS
    fig = tsfdi.identify(x.iloc[2000:], {"healthy": healthy, "other": other}, test).plot()
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == CHANNELS


def test_monitor_plot_labels_channels_by_name():
    """The variance curves are labelled by the channel of their ``variance_<channel>`` column."""
    w = pd.DataFrame({"start": [0.0, 1.0, 2.0], "end": [5.0, 6.0, 7.0], "detect_statistic": [0.5, 2.0, 3.0],
                      "detect_pvalue": [0.5, 1e-4, 1e-5], "fault": [False, True, True],
                      "variance_roll": [1.0, 2.0, 3.0], "variance_pitch": [1.0, 1.5, 1.2],
                      "phase": ["healthy", "transient", "steady"], "status": ["", "", "identified"],
                      "label": [None, None, "rotor1"], "accepted": ["", "", "rotor1"]})
    ev = [tsfdi.MonitorEvent(6.0, "detection", None, "fault", window=(1.0, 6.0))]
    fig = MonitorResult(events=ev, windows=w, detection_time=6.0, steady_time=None, label="rotor1").plot()
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == CHANNELS
    assert fig.axes[1].get_legend() is not None


def test_confusion_plot_sets_the_undecided_columns_apart():
    """The confusion table's numbers (rows adding to 100 with ambiguous / none columns) are tested in
    tests/test_evaluation.py; here the plot of such a table."""
    paper = pd.DataFrame([[50.0, 0.0, 25.0, 25.0], [0.0, 50.0, 25.0, 25.0]], index=pd.Index(["a", "b"]),
                         columns=["a", "b", "ambiguous", "none"])
    fig = plotting.plot_confusion(paper, title="t")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["a", "b", "ambiguous", "none"]
    assert ax.get_xlabel() == "decided as" and ax.get_ylabel() == "true failure"
    # the undecided columns are set apart by a vertical line between "b" and "ambiguous"
    assert any(np.allclose(ln.get_xdata(), 1.5) for ln in ax.get_lines())
    cells = sorted(float(t.get_text()) for t in ax.texts)
    assert cells == sorted(paper.to_numpy().ravel())


@pytest.fixture(scope="module")
def demo_report(tmp_path_factory):
    """The demo's report on a subset of the shipped data (as ``tsfdi demo --records-per-case 3``)."""
    from tsfdi.datasets import load_hexacopter
    from tsfdi.study import hexacopter_study, write_report

    data = load_hexacopter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", tsfdi.TsfdiWarning)
        bases, ev = hexacopter_study(data, records_per_case=3, fit_records=2, models=["var"], windows=["20s"],
                                     tests={"whiteness": tsfdi.LjungBox(lags=20, alpha=1e-3)}, order="bic",
                                     progress=False)
    out = tmp_path_factory.mktemp("demo")
    paths = write_report(bases, ev, data, out)
    return out, paths, ev


def test_report_embeds_its_figures(demo_report):
    out, paths, _ = demo_report
    text = (out / "report.md").read_text()
    links = re.findall(r"!\[([^\]]+)\]\(([^)]+)\)", text)
    pngs = sorted(p.relative_to(out).as_posix() for p in (out / "figures").glob("*.png"))
    assert len(pngs) >= 6
    assert sorted(src for _, src in links) == pngs
    for caption, src in links:
        assert not Path(src).is_absolute() and (out / src).is_file() and caption
    assert paths[0] == out / "report.md" and sorted(p.relative_to(out).as_posix() for p in paths[2:]) == pngs


UNIT = re.compile(r"\((?:[^()|]*, )?(?:%|s|samples)(?: per parameter)?\)")


def test_report_tables_state_units(demo_report):
    out, _, ev = demo_report
    text = (out / "report.md").read_text()
    headers = [ln for i, ln in enumerate(text.splitlines()[:-1]) if ln.startswith("| ")
               and text.splitlines()[i + 1].startswith("|---")]
    assert len(headers) >= 5
    for h in headers:
        assert UNIT.search(h), f"no unit in table header {h}"
    assert "nobs (samples)" in text and "delay_median (s)" in text and "false_alarm (%)" in text
    # the decisions of the paper's rule: every row adds up to 100 %
    conf = ev.confusion("paper")
    np.testing.assert_allclose(conf.sum(axis=1), 100.0)
    assert "ambiguous (%) | none (%)" in text


def test_report_says_its_records_are_development_records(demo_report):
    """The demo's figures are on the shipped development records, on which the study's settings were chosen: the
    report says so first and points to the evaluation (issue 30)."""
    from tsfdi.study import DEVELOPMENT_NOTE

    out, _, _ = demo_report
    text = (out / "report.md").read_text()
    assert text.startswith(DEVELOPMENT_NOTE)
    assert "development records" in DEVELOPMENT_NOTE and "not an evaluation" in DEVELOPMENT_NOTE
    assert "fresh seed" in DEVELOPMENT_NOTE


def test_monitor_run_on_named_signal_labels_channels():
    x = var_signal(3000, 5)
    healthy = tsfdi.VAR(x.iloc[:1500], 2).fit()
    other = tsfdi.VAR(var_signal(1500, 6, scale=3.0) ** 2, 2).fit()
    result = tsfdi.Monitor(healthy, {"healthy": healthy, "other": other}, window="5s", step="1s",
                           test=tsfdi.LjungBox(lags=10, alpha=1e-3)).run(x.iloc[1500:])
    fig = result.plot()
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == CHANNELS


def test_monitor_plot_has_no_empty_panel_and_times_have_units():
    """Issue 29: the monitor plot had empty panels (no label panel content for a detection-only monitor, no variance
    when the windows are shorter than the steady window) and "detection at 1" without a unit."""
    rng = np.random.default_rng(29)
    y = np.r_[rng.standard_normal(600), 4 * rng.standard_normal(600)]
    base = tsfdi.AR(rng.standard_normal(3000), 2).fit()
    for fs, unit in ((100.0, "s"), (None, "samples")):
        mon = tsfdi.Monitor(base, window=200, step=100, steady_window=1000, fs=fs, test=tsfdi.FTest(1e-3))
        res = mon.run(y)
        assert res.detection_time is not None
        fig = res.plot()
        for ax in fig.axes:                                   # every panel holds data
            assert ax.get_lines() or ax.collections
            assert any(np.isfinite(np.asarray(ln.get_ydata(), dtype=float)).any() for ln in ax.get_lines())
        assert fig.axes[-1].get_xlabel() == f"time of the window end ({unit})"
        texts = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
        assert f"detection at {res.detection_time:g} {unit}" in texts
        assert len(fig.axes) == 2                            # variance (late windows) and detection; no label panel
    # no window long enough for a variance: the detection panel alone
    res = tsfdi.Monitor(base, window=200, step=100, steady_window=1500, fs=100.0, test=tsfdi.FTest(1e-3)).run(y)
    assert len(res.plot().axes) == 1
