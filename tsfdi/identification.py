"""Fault detection and identification by residual hypothesis tests (Dutta et al., Figs. 3, 10-13).

``detect`` drives a signal through one baseline model and tests its residuals (healthy vs fault).
``identify`` drives it through every candidate model (healthy and fault models) and applies the same test to
each: the paper's multiple binary hypothesis tests. A model is *accepted* when its residuals pass the test
(for vector residuals: every channel passes). One accepted model is an identification, several are an
ambiguity ("confusion between those types of failures"), none means no decision.
"""

from __future__ import annotations

import html
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from tsfdi._data import as_signal
from tsfdi._validation import int_like
from tsfdi.detection.base import ResidualTest
from tsfdi.detection.decision import Decision
from tsfdi.detection.whiteness import LjungBox

__all__ = ["detect", "identify", "identify_windows", "Identification", "WindowedIdentification"]


def _check_test(test: Any) -> ResidualTest:
    if test is None:
        return LjungBox()
    if not isinstance(test, ResidualTest):
        raise TypeError(f"test must be a residual test object (FTest, LjungBox, GLRT, ...), got "
                        f"{type(test).__name__}")
    return test


def _check_model(res: Any, name: str, nchan: int, arg: str) -> None:
    if not hasattr(res, "residuals"):
        raise TypeError(f"{arg} must hold fitted results (AR or VAR) with a residuals() method; "
                        f"{name!r} is a {type(res).__name__}")
    neqs = int(getattr(res, "neqs", 1))
    if neqs != nchan:
        raise ValueError(f"signal has {nchan} channel(s) but {arg} {name!r} was fitted on {neqs} channel(s)")


def detect(signal: Any, baseline: Any, test: ResidualTest | None = None, *, u: Any = None) -> Decision:
    """Healthy-vs-fault decision: drive ``signal`` through ``baseline`` and test the residuals.

    Parameters
    ----------
    signal : array_like, Series, DataFrame or DataArray
        Current signal :math:`Z_u` (scalar or vector, time on axis 0).
    baseline : fitted results
        The healthy model :math:`M_0` (``tsfdi.AR(...).fit()`` or ``tsfdi.VAR(...).fit()``).
    test : ResidualTest, optional
        :class:`~tsfdi.FTest`, :class:`~tsfdi.LjungBox` (default, ``lags=20``) or :class:`~tsfdi.GLRT`.
        What the test needs from the baseline (reference variance and degrees of freedom for the F test,
        sigma for the GLRT) is taken from the fitted results.
    u : array_like, optional
        Input signal for an input-output baseline (``tsfdi.ARX(...).fit()``), passed to its ``residuals``.

    Returns
    -------
    Decision
        ``reject`` True means fault (H1).
    """
    test = _check_test(test)
    sig = as_signal(signal, "signal", allow_constant=True)
    _check_model(baseline, "baseline", sig.nchan, "baseline")
    resid = baseline.residuals(signal) if u is None else baseline.residuals(signal, u)
    return test.test(resid, **test.reference(baseline))


@dataclass(frozen=True)
class Identification:
    """Outcome of :func:`identify`: one decision per candidate model.

    Attributes
    ----------
    decisions : dict
        Model name -> :class:`~tsfdi.detection.decision.Decision` of its residuals (insertion order kept).
    test : str
        Name of the test used.
    span : tuple or None
        ``(start, stop)`` sample positions of the signal window (set by :func:`identify_windows`).
    """

    decisions: dict
    test: str = ""
    span: tuple | None = None

    @property
    def accepted(self) -> tuple:
        """Names of the models whose residuals pass the test (every channel accepts), in model order."""
        return tuple(name for name, d in self.decisions.items() if not d.reject)

    @property
    def label(self) -> str | None:
        """The single accepted model, else ``None``."""
        acc = self.accepted
        return acc[0] if len(acc) == 1 else None

    @property
    def status(self) -> str:
        """``"identified"`` (one model accepted), ``"ambiguous"`` (several) or ``"none"`` (no decision)."""
        n = len(self.accepted)
        return "identified" if n == 1 else ("ambiguous" if n > 1 else "none")

    @property
    def ranking(self) -> tuple:
        """Model names from most to least plausible: by signal-level p-value (descending), ties and tests
        without p-values broken by the largest statistic/threshold ratio (ascending)."""
        def key(item):
            name, d = item
            p = d.signal_pvalue
            return (-(p if np.isfinite(p) else 0.0), d.margin)

        return tuple(name for name, _ in sorted(self.decisions.items(), key=key))

    def to_frame(self):
        """A ``DataFrame`` with one row per (model, channel): statistic, threshold, p-value, df, reject,
        and whether the model is accepted."""
        import pandas as pd

        rows = []
        for name, d in self.decisions.items():
            for i, c in enumerate(d.channels):
                df = d.df[i]
                rows.append({"model": name, "channel": c, "statistic": d.statistic[i], "threshold": d.threshold[i],
                             "pvalue": d.pvalue[i], "df": df if np.ndim(df) == 0 else tuple(df),
                             "reject": bool(d.channel_reject[i]), "model_accepted": not d.reject})
        return pd.DataFrame(rows).set_index(["model", "channel"])

    def summary(self) -> str:
        lines = [f"Identification by {self.test}: status = {self.status}, label = {self.label}",
                 f"  accepted: {', '.join(self.accepted) or '-'}",
                 f"  ranking:  {', '.join(self.ranking)}"]
        lines.append(self.to_frame().to_string())
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"Identification(status={self.status!r}, label={self.label!r}, accepted={self.accepted}, "
                f"test={self.test!r})")

    def _repr_html_(self) -> str:
        return (f"<div><b>Identification</b> by {html.escape(self.test)}: status = <b>{self.status}</b>, "
                f"label = <b>{html.escape(str(self.label))}</b><br>accepted: "
                f"{html.escape(', '.join(self.accepted) or '-')}{self.to_frame().to_html()}</div>")

    def plot(self, ax: Any = None, **kwargs: Any) -> Any:
        """Grouped bars of the statistic per model and channel against the critical limit
        (Dutta et al., Figs. 12-13). Returns the ``Figure``."""
        from tsfdi.plotting.decision import plot_identification

        return plot_identification(self, ax=ax, **kwargs)


def _check_models(models: Any) -> Mapping:
    if not isinstance(models, Mapping):
        raise TypeError(f"models must be a mapping name -> fitted results, got {type(models).__name__}")
    if len(models) == 0:
        raise ValueError("models is empty: give at least one fitted model (name -> results)")
    return models


def identify(signal: Any, models: Mapping, test: ResidualTest | None = None, *, u: Any = None) -> Identification:
    """Multi-class identification by one binary test per candidate model (Dutta et al., eq. 11 and the
    residual uncorrelatedness method).

    Parameters
    ----------
    signal : array_like, Series, DataFrame or DataArray
        Current signal (scalar for AR models, ``(nobs, s)`` for VAR models).
    models : mapping
        Name -> fitted results (``tsfdi.AR(...).fit()`` / ``tsfdi.VAR(...).fit()``), e.g. the healthy
        model and one model per fault type. All must have the signal's number of channels.
    test : ResidualTest, optional
        The test applied to each model's residuals (default ``LjungBox()``).
    u : array_like, optional
        Input signal when the candidates are input-output models (``tsfdi.ARX``).

    Returns
    -------
    Identification
    """
    test = _check_test(test)
    models = _check_models(models)
    sig = as_signal(signal, "signal", allow_constant=True)
    for name, res in models.items():
        _check_model(res, name, sig.nchan, "models")
    decisions = {}
    for name, res in models.items():
        resid = res.residuals(sig) if u is None else res.residuals(sig, u)
        decisions[name] = test.test(resid, **test.reference(res))
    return Identification(decisions=decisions, test=type(test).__name__)


class WindowedIdentification:
    """:func:`identify` on every sliding window of a record, held as arrays; windows as objects on demand.

    Attributes
    ----------
    models : tuple of str
        Candidate model names (axis 1 of the arrays).
    channels : tuple of str
    starts, stops : ndarray of int
        Window ``w`` covers signal samples ``[starts[w], stops[w])``.
    statistic, threshold, pvalue : ndarray, shape (n_windows, n_models, n_channels)
    channel_reject : ndarray of bool, shape (n_windows, n_models, n_channels)
    accepted : ndarray of bool, shape (n_windows, n_models)
        Model accepted in the window (every channel accepts).
    labels : list
        The single accepted model per window, else ``None``.
    status : list of str
        ``"identified" | "ambiguous" | "none"`` per window.

    Indexing (``result[w]``) or iterating gives :class:`Identification` objects, built when asked for.
    """

    def __init__(self, models: tuple, channels: tuple, starts: np.ndarray, window: int,
                 decisions: list[dict] | None = None, *, arrays: dict | None = None,
                 make_decision: Any = None, test: str = "") -> None:
        self.models, self.channels, self.test = tuple(models), tuple(channels), test
        self.starts = np.asarray(starts, dtype=np.int64)
        self.stops = self.starts + int(window)
        if decisions is not None:
            def stack(attr):
                return np.array([[getattr(d[m], attr) for m in self.models] for d in decisions])
            arrays = {a: stack(a) for a in ("statistic", "threshold", "pvalue", "channel_reject")}
            self._decisions = decisions
        else:
            self._decisions = None
        self.statistic = arrays["statistic"]
        self.threshold = arrays["threshold"]
        self.pvalue = arrays["pvalue"]
        self.channel_reject = arrays["channel_reject"]
        self._make_decision = make_decision
        self.accepted = ~self.channel_reject.any(axis=2)
        n_acc = self.accepted.sum(axis=1)
        self.status = ["identified" if a == 1 else ("ambiguous" if a > 1 else "none") for a in n_acc]
        self.labels = [self.models[int(np.argmax(row))] if a == 1 else None for row, a in zip(self.accepted, n_acc)]

    def __len__(self) -> int:
        return self.starts.size

    def __getitem__(self, w: int) -> Identification:
        w = int(w)
        if w < 0:
            w += len(self)
        if not 0 <= w < len(self):
            raise IndexError(f"window index out of range (0..{len(self) - 1})")
        if self._decisions is not None:
            dec = self._decisions[w]
        else:
            dec = {m: self._make_decision(i, self.statistic[w, i]) for i, m in enumerate(self.models)}
        return Identification(decisions=dec, test=self.test, span=(int(self.starts[w]), int(self.stops[w])))

    def __iter__(self):
        return (self[w] for w in range(len(self)))

    def to_frame(self):
        """One row per window: start, stop, status, label."""
        import pandas as pd

        return pd.DataFrame({"start": self.starts, "stop": self.stops, "status": self.status, "label": self.labels})

    def __repr__(self) -> str:
        counts = {s: self.status.count(s) for s in ("identified", "ambiguous", "none")}
        return f"WindowedIdentification(windows={len(self)}, models={self.models}, {counts})"


def identify_windows(signal: Any, models: Mapping, test: ResidualTest | None = None, *, window: int,
                     step: int = 1) -> WindowedIdentification:
    """:func:`identify` on every sliding window of one record.

    Window ``w`` covers signal samples ``[w * step, w * step + window)``. For a per-channel
    :class:`~tsfdi.LjungBox` the record is filtered once through each model (a fixed model's residuals of a
    window are a slice of the record's residuals) and all windows' statistics come from
    :func:`~tsfdi.detection.whiteness.ljungbox_windows` (O(N * lags) for all windows); other tests are
    applied window by window.

    Returns
    -------
    WindowedIdentification
        Arrays over windows, models and channels; ``result[w]`` is the :class:`Identification` of window ``w``
        (with ``span = (start, stop)``), equal to ``identify(signal[start:stop], models, test)``.
    """
    test = _check_test(test)
    models = _check_models(models)
    sig = as_signal(signal, "signal", allow_constant=True)
    window = int_like(window, "window", minimum=2)
    step = int_like(step, "step", minimum=1)
    if window > sig.nobs:
        raise ValueError(f"window must be <= the signal length {sig.nobs}, got {window}")
    for name, res in models.items():
        _check_model(res, name, sig.nchan, "models")
    starts = np.arange(0, sig.nobs - window + 1, step)
    names = tuple(models)
    chans = tuple(sig.channels)
    if isinstance(test, LjungBox) and test.multivariate is None:
        qs, nres = [], []
        for name, res in models.items():
            p = int(res.lags)
            if window - p <= test.lags:
                raise ValueError(f"window must exceed lags + the model order ({test.lags} + {p}) for "
                                 f"models {name!r}, got {window}")
            e = np.asarray(res.residuals(sig.values if sig.vector else sig.values[:, 0]), dtype=np.float64)
            qs.append(test.window_statistic(e, window - p, step))
            nres.append(window - p)
        q = np.stack(qs, axis=1)                                   # (W, M, k)
        thr, pv = test._threshold_pvalue(q)                        # chi-square or calibrated, as in test()
        arrays = {"statistic": q, "threshold": np.broadcast_to(thr, q.shape), "pvalue": pv,
                  "channel_reject": q > thr}

        def make(i: int, stat_row: np.ndarray) -> Decision:
            return test._decision(stat_row, nres[i], chans)

        return WindowedIdentification(names, chans, starts, window, arrays=arrays, make_decision=make,
                                      test=type(test).__name__)
    vals = sig.values if sig.vector else sig.values[:, 0]
    decisions = [identify(vals[s0:s0 + window], models, test).decisions for s0 in starts]
    return WindowedIdentification(names, chans, starts, window, decisions, test=type(test).__name__)
