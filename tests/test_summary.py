"""tsfdi.summary.Summary and the summary() of models, order selection and decisions: objects with text and HTML
tables whose numbers are those of the results."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

import tsfdi
from tsfdi.summary import Summary


def ar_data(n=600, seed=0):
    rng = np.random.default_rng(seed)
    y = np.zeros(n)
    e = rng.standard_normal(n)
    for t in range(2, n):
        y[t] = 1.1 * y[t - 1] - 0.4 * y[t - 2] + e[t]
    return y


def var_frame(n=800, seed=1):
    rng = np.random.default_rng(seed)
    e = rng.standard_normal((n, 2))
    y = np.zeros((n, 2))
    for t in range(1, n):
        y[t] = [[0.5, 0.1], [0.2, 0.3]] @ y[t - 1] + e[t]
    return pd.DataFrame(y, columns=["roll", "pitch"], index=pd.date_range("2024", periods=n, freq="10ms"))


def test_summary_renders_text_and_html():
    table = pd.DataFrame({"coef": [1.23456789, -2.0], "note": ["<b>", "x & y"]}, index=["a1", "a2"])
    s = Summary("A <title>", [("Observations", 10), ("BIC", 123.456789), ("Stable", True)], [("Coefficients", table)],
                ["a note"])
    text = s.as_text()
    assert str(s) == text == repr(s)
    lines = text.splitlines()
    assert lines[0].strip() == "A <title>" and set(lines[1]) == {"="} and set(lines[-1]) == {"="}
    for piece in ("Observations  10", "BIC", "123.457", "Stable", "True", "Coefficients", "1.23457", "a2", "a note"):
        assert piece in text
    html = s.as_html()
    assert s._repr_html_() == html
    assert html.count("<table>") == 2 and "&lt;title&gt;" in html and "&lt;b&gt;" in html and "x &amp; y" in html
    assert "<title>" not in html
    assert s.tables[0][1].loc["a1", "coef"] == 1.23456789        # the numbers themselves, not rounded


def test_model_summary_holds_the_inference_table():
    y = pd.Series(ar_data(), name="roll")
    res = tsfdi.AR(y, 2, "c").fit()
    s = res.summary(alpha=0.1)
    assert isinstance(s, Summary)
    (title, table), = s.tables
    assert title == "Coefficients of roll" and list(table.index) == ["const", "a1", "a2"]
    assert list(table.columns) == ["coef", "std err", "z", "P>|z|", "[0.05", "0.95]"]
    np.testing.assert_array_equal(table["coef"], res.params)
    np.testing.assert_array_equal(table["std err"], res.bse)
    np.testing.assert_array_equal(table["P>|z|"], res.pvalues)
    np.testing.assert_allclose(table[["[0.05", "0.95]"]].to_numpy(), res.conf_int(0.1).to_numpy(), rtol=1e-14)
    header = dict(s.header)
    assert header["HQIC"] == res.hqic and header["Observations"] == res.nobs and header["Order"] == "lags=2"
    text = str(s)
    assert f"{res.bic:.6g}" in text and "RSS/SSS" in text and "statsmodels AutoReg" in text
    with pytest.raises(ValueError, match="alpha"):
        res.summary(alpha=0.0)


def test_var_summary_has_one_table_per_equation():
    res = tsfdi.VAR(var_frame(), 1, "c").fit()
    s = res.summary()
    assert [t for t, _ in s.tables] == ["Equation roll", "Equation pitch"]
    pitch = s.tables[1][1]
    np.testing.assert_array_equal(pitch["std err"], res.bse["pitch"])
    np.testing.assert_allclose(pitch["0.975]"], res.params["pitch"] + stats.norm.isf(0.025) * res.bse["pitch"],
                               rtol=1e-14)
    assert s.as_html().count("<table>") == 3 and "Equation pitch" in s.as_html()
    assert "statsmodels VAR" in str(s) and "A1.pitch" in str(s)


def test_order_selection_summary_marks_the_selected_orders():
    sel = tsfdi.select_order(ar_data(), 8)
    s = sel.summary()
    (title, table), = s.tables
    pd.testing.assert_frame_equal(table.drop(columns="selected"), sel.table)
    assert "hqic" in sel.table.columns
    marks = table["selected"]
    assert "min BIC" in marks[sel.selected] and "RSS/SSS stable" in marks[sel.stabilized]
    assert (marks.drop(list({sel.selected, sel.stabilized})) == "").all()
    assert dict(s.header)["Selected (min BIC)"] == sel.selected
    assert "min BIC" in str(s) and "min BIC" in s.as_html()


def test_decision_summary_per_channel():
    rng = np.random.default_rng(6)
    e = rng.standard_normal((400, 2))
    e[:, 1] += 0.8 * np.sin(np.arange(400) / 2.0)           # channel 1 is not white
    d = tsfdi.LjungBox(10, 0.05).test(pd.DataFrame(e, columns=["roll", "pitch"]))
    s = d.summary()
    (title, table), = s.tables
    assert list(table.index) == ["roll", "pitch"] and table.index.name == "channel"
    np.testing.assert_array_equal(table["statistic"], d.statistic)
    np.testing.assert_array_equal(table["threshold"], d.threshold)
    np.testing.assert_array_equal(table["p-value"], d.pvalue)
    assert list(table["reject"]) == [False, True] and d.reject
    header = dict(s.header)
    assert header["Signal decision"].startswith("reject H0") and header["alpha"] == 0.05
    assert "every channel accepts" in str(s)
    assert "<table>" in d._repr_html_() and "pitch" in d._repr_html_()


def test_f_test_summary_shows_both_degrees_of_freedom():
    rng = np.random.default_rng(7)
    d = tsfdi.FTest(alpha=0.01).test(rng.standard_normal((300, 2)), reference_variance=np.ones(2),
                                          reference_df=500)
    table = d.summary().tables[0][1]
    np.testing.assert_array_equal(table["df num"], d.df[:, 0])
    np.testing.assert_array_equal(table["df den"], d.df[:, 1])
