"""Baseline phase and evaluation of the whole method over many records (Dutta et al., paper 003, Tables 2-4).

:func:`fit_baselines` fits, for every aircraft state, a scalar AR model on each channel and a VAR model on all
channels with the order chosen by BIC (:func:`tsfdi.select_order`), and estimates the steady-state
rolling-variance thresholds; :attr:`Baselines.table` is the analogue of the paper's Table 2.
:func:`evaluate` then runs detection with the healthy model and identification with the fault models on every
sliding window of every record that was *not* used for fitting, for the models x methods x window lengths x
turbulence levels asked for, and returns an :class:`Evaluation` holding the per-window outcomes, the Table 4
analogue (percent of windows of each true failure accepted as each rotor), unique-correct, ambiguity and
no-decision rates, detection false-alarm and missed-fault rates and detection delays.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from tsfdi._data import as_signal, is_xarray
from tsfdi._validation import float_like, int_like, option, probability
from tsfdi.monitoring import RULES, Monitor, _bank_residuals, _banks, _rolling_variance, _window_statistics, apply_rule

__all__ = ["Baselines", "Evaluation", "Records", "baselines_table", "evaluate", "fit_baselines", "hexacopter_signals",
           "hexacopter_study", "PAPER_ALPHA", "METHODS", "RULES", "THRESHOLDS"]

#: Identification methods: the residual variance F test and the residual whiteness (Ljung-Box) test.
METHODS = ("whiteness", "variance")

#: Test thresholds: the null distribution's quantile (chi-square / F, the paper) or calibrated on held-out
#: in-state residuals (empirical, paper 002 Fig. 2).
THRESHOLDS = ("chi2", "empirical")

#: Type I risk of each method and model family in the paper's Table 3 (scalar AR on roll / pitch / yaw, VAR).
PAPER_ALPHA = {("variance", "roll"): 1e-6, ("variance", "pitch"): 1e-12, ("variance", "yaw"): 1e-12,
               ("variance", "var"): 1e-8, ("whiteness", "roll"): 1e-3, ("whiteness", "pitch"): 1e-3,
               ("whiteness", "yaw"): 1e-3, ("whiteness", "var"): 1e-3}


def _paper_alpha(method: str, model: str) -> float:
    key = "yaw" if model.startswith("yaw") else model
    return PAPER_ALPHA.get((method, key), 1e-3 if method == "whiteness" else 1e-8)


# ------------------------------------------------------------------------------------------------------------- data
def hexacopter_signals(data: Any, *, yaw: str = "rate") -> Any:
    """Roll, pitch and yaw channels of a hexacopter dataset as one ``(record, time, channel)`` DataArray.

    Parameters
    ----------
    data : xarray.Dataset
        As returned by :func:`tsfdi.datasets.load_hexacopter` (variables ``roll``, ``pitch``, ``yaw``).
    yaw : {"rate", "angle"}
        ``"rate"`` (default): the body yaw rate, channel ``yaw_rate``: the dataset's ``r`` variable when it has
        one, else the heading increment times ``fs`` (the first sample is then dropped so every channel has the
        same time axis). The heading is the integral of the yaw rate under a slow heading loop (time constant
        1 / k_heading, about 3 s), so at 100 Hz it is close to a unit-root process and an AR/VAR of order 20
        does not whiten it; with the regular aircraft it also slips by whole turns in severe turbulence.
        ``"angle"``: the raw heading.

    Returns
    -------
    xarray.DataArray
        Dims ``(record, time, channel)`` with the dataset's record coordinates.
    """
    import xarray as xr

    if not isinstance(data, xr.Dataset):
        raise TypeError(f"data must be an xarray.Dataset with roll, pitch and yaw variables, got "
                        f"{type(data).__name__}")
    yaw = option(yaw, "yaw", ("rate", "angle"))
    use_r = yaw == "rate" and "r" in data
    missing = [v for v in ("roll", "pitch", "r" if use_r else "yaw") if v not in data]
    if missing:
        raise ValueError(f"data lacks the variable(s) {missing}")
    t = np.asarray(data["time"].values, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    arrs = [np.asarray(data[v].transpose("record", "time").values, dtype=np.float64)
            for v in ("roll", "pitch", "r" if use_r else "yaw")]
    if use_r:
        names = ["roll", "pitch", "yaw_rate"]
    elif yaw == "rate":
        arrs = [a[:, 1:] for a in arrs[:2]] + [np.diff(arrs[2], axis=1) * fs]
        t = t[1:]
        names = ["roll", "pitch", "yaw_rate"]
    else:
        names = ["roll", "pitch", "yaw"]
    vals = np.stack(arrs, axis=-1)
    coords = {k: (("record",), np.asarray(c.values)) for k, c in data.coords.items()
              if c.dims == ("record",) and k != "record"}
    coords["record"] = np.asarray(data["record"].values)
    coords["time"] = t
    coords["channel"] = names
    if "lost_control" in data:
        coords["lost_control"] = (("record",), np.asarray(data["lost_control"].values, dtype=bool))
    return xr.DataArray(vals, dims=("record", "time", "channel"), coords=coords, name="attitude")


@dataclass(frozen=True, eq=False)
class Records:
    """Many records of the same channels, normalised from an xarray object or a sequence of signals.

    Attributes
    ----------
    values : list of ndarray, each (nobs, k)
    state, turbulence : ndarray of str
    failure_time : ndarray of float (NaN for healthy records)
    ids : ndarray
        Record identifiers.
    valid : ndarray of bool
        False for records that cannot be used (lost control: NaN after the loss).
    channels : tuple of str
    fs : float
    """

    values: list
    state: np.ndarray
    turbulence: np.ndarray
    failure_time: np.ndarray
    ids: np.ndarray
    valid: np.ndarray
    channels: tuple
    fs: float

    @classmethod
    def from_data(cls, data: Any, *, states: Any = None, failure_times: Any = None, turbulence: Any = None,
                  fs: float | None = None, name: str = "data") -> Records:
        """Build from a hexacopter ``Dataset``, a ``(record, time, channel)`` DataArray or a sequence of
        signals (numpy / pandas / xarray, each ``(nobs, k)``) with ``states`` (and optional ``failure_times``,
        ``turbulence``) given per record."""
        if isinstance(data, Records):
            return data
        import xarray as xr

        if isinstance(data, xr.Dataset):
            data = hexacopter_signals(data)
        if isinstance(data, xr.DataArray) and data.ndim == 3 and "record" in data.dims:
            da = data.transpose("record", "time", ...)
            t = np.asarray(da["time"].values, dtype=float)
            fs_ = 1.0 / float(np.median(np.diff(t))) if fs is None else float_like(fs, "fs", minimum=0.0,
                                                                                    strict_min=True)
            n = da.sizes["record"]

            def coord(key, given, default):
                if given is not None:
                    return np.asarray(given)
                return np.asarray(da[key].values) if key in da.coords else np.full(n, default)

            st = coord("state", states, None)
            if st[0] is None:
                raise ValueError(f"{name} needs a 'state' coordinate (or pass states=)")
            lost = np.asarray(da["lost_control"].values, dtype=bool) if "lost_control" in da.coords else \
                np.zeros(n, bool)
            vals = [np.asarray(v, dtype=np.float64) for v in da.values]
            valid = ~lost & np.array([np.all(np.isfinite(v)) for v in vals])
            chans = tuple(str(c) for c in da[da.dims[2]].values)
            return cls(vals, st.astype(str), coord("turbulence", turbulence, "").astype(str),
                       coord("failure_time", failure_times, np.nan).astype(float),
                       np.asarray(da["record"].values) if "record" in da.coords else np.arange(n), valid, chans, fs_)
        if isinstance(data, (str, bytes)) or not isinstance(data, Sequence) or len(data) == 0:
            raise TypeError(f"{name} must be a hexacopter xarray.Dataset, a (record, time, channel) DataArray or a "
                            f"non-empty sequence of signals, got {type(data).__name__}")
        if states is None:
            raise ValueError(f"states is required when {name} is a sequence of signals (one state per record)")
        sigs = [as_signal(d, f"{name}[{i}]", vector=True) for i, d in enumerate(data)]
        k = {s.nchan for s in sigs}
        if len(k) != 1:
            raise ValueError(f"every record of {name} must have the same number of channels, got {sorted(k)}")
        n = len(sigs)
        st = np.asarray(states).astype(str)
        if st.shape != (n,):
            raise ValueError(f"states must have one entry per record ({n}), got shape {st.shape}")
        ft = np.full(n, np.nan) if failure_times is None else np.asarray(failure_times, dtype=float)
        tb = np.full(n, "") if turbulence is None else np.asarray(turbulence).astype(str)
        if ft.shape != (n,) or tb.shape != (n,):
            raise ValueError(f"failure_times and turbulence must have one entry per record ({n})")
        fs_ = 1.0 if fs is None else float_like(fs, "fs", minimum=0.0, strict_min=True)
        return cls([s.values for s in sigs], st, tb, ft, np.arange(n), np.ones(n, bool), tuple(sigs[0].channels),
                   fs_)


def _segment(rec: Records, i: int, settle: float, duration: float | None) -> np.ndarray:
    ft = rec.failure_time[i]
    t0 = (ft if np.isfinite(ft) else 0.0) + settle
    a = int(round(t0 * rec.fs))
    b = None if duration is None else a + int(round(duration * rec.fs))
    seg = rec.values[i][a:b]
    if b is not None and seg.shape[0] < b - a:
        raise ValueError(f"record {rec.ids[i]} is too short for a {duration} s segment starting at {t0} s")
    return seg


# ---------------------------------------------------------------------------------------------------- baselines
@dataclass(frozen=True, eq=False)
class Baselines:
    """Baseline models of every state (outcome of :func:`fit_baselines`).

    Attributes
    ----------
    models : dict
        Model name (a channel name for a scalar AR, ``"var"`` for the VAR) -> {state -> fitted results}.
    selections : dict
        ``(model name, state)`` -> :class:`~tsfdi.OrderSelection`.
    channels : tuple of str
        Channel names of the records.
    healthy : str
        Name of the healthy state.
    faults : tuple of str
        Names of the fault states (the identification candidates).
    steady_thresholds : ndarray, shape (k,)
        Rolling-variance threshold of each channel below which a post-failure signal is steady.
    steady_window : float
        Rolling-variance window in seconds.
    fit_records : tuple
        Identifiers of the records used for fitting (excluded from :func:`evaluate`).
    fs : float
        Sampling frequency in Hz.
    heldout : dict
        ``(model name, state)`` -> list of out-of-sample residual records, one per fitting record of that state:
        the residuals of the record through the model refitted (same order) on the state's *other* fitting
        records (leave one record out; filled by ``fit_baselines(..., calibrate=True)``, else empty). They
        calibrate data-driven test thresholds (:meth:`calibrated_tests`).
    """

    models: dict
    selections: dict
    channels: tuple
    healthy: str
    faults: tuple
    steady_thresholds: np.ndarray
    steady_window: float
    fit_records: tuple
    fs: float
    segments: dict = field(default_factory=dict, repr=False)
    heldout: dict = field(default_factory=dict, repr=False)
    _calibrated: dict = field(default_factory=dict, repr=False)
    _banks: dict = field(default_factory=dict, repr=False)

    def model_channels(self, model: str) -> list[int]:
        """Channel positions a model uses (all for ``"var"``)."""
        if model == "var":
            return list(range(len(self.channels)))
        if model not in self.channels:
            raise ValueError(f"model must be 'var' or one of the channels {self.channels}, got {model!r}")
        return [self.channels.index(model)]

    @property
    def table(self) -> pd.DataFrame:
        """Table 2 analogue: one row per (state, model) with the order, parameters, SPP, RSS/SSS and BIC.

        SPP is the paper's samples per parameter: estimation samples x channels / estimated AR parameters.
        ``records`` is the number of pooled fitting records; ``q_insample`` the median Ljung-Box ``Q`` (20 lags)
        of the in-sample residuals over 20 s blocks (``20 * fs`` samples; the whole record when shorter) and
        channels, to compare with the median of chi2(20), about 19.3.
        """
        rows = []
        for state in (self.healthy,) + self.faults:
            for name, per_state in self.models.items():
                res = per_state[state]
                vec = name == "var"
                rows.append({"state": state, "model": "VAR" if vec else "AR",
                             "signals": ",".join(self.channels) if vec else name,
                             "order": f"{'VAR' if vec else 'AR'}({res.lags})", "lags": int(res.lags),
                             "parameters": int(res.df_model), "records": len(_resid_list(res)),
                             "nobs": int(res.nobs), "spp": float(res.spp), "rss_sss": float(res.rss_sss),
                             "bic": float(res.bic), "q_insample": _insample_q(res, int(round(20 * self.fs))),
                             "stable": bool(res.is_stable)})
        return pd.DataFrame(rows)

    def monitor(self, model: str = "var", *, window: float = 20.0, step: float = 1.0, method: str = "whiteness",
                alpha: float | None = None, lags: int | None = None, rule: str = "paper",
                thresholds: str = "chi2", bank: bool = False) -> Monitor:
        """A :class:`~tsfdi.Monitor` with this baseline's healthy and fault models, tests and thresholds
        (``thresholds="empirical"``: each model's test calibrated by :meth:`calibrated_tests`; ``bank=True``:
        every state is the :meth:`bank` of its per-record models)."""
        thresholds = option(thresholds, "thresholds", THRESHOLDS)
        _check_bank(bank, thresholds)
        chans = self.model_channels(model)
        states = self.state_models(model, bank)
        if thresholds == "empirical":
            tests = self.calibrated_tests(model, method, window, alpha=alpha, lags=lags)
            test: Any = {f: tests[f] for f in self.faults}
            det = tests[self.healthy]
        else:
            test = _make_test(method, model, alpha, lags, window, self.fs)
            det = None
        return Monitor(states[self.healthy], {f: states[f] for f in self.faults},
                       window=window, step=step, fs=self.fs, test=test, detection_test=det,
                       steady_thresholds=self.steady_thresholds[chans], steady_window=self.steady_window, rule=rule)

    def bank(self, model: str, state: str) -> tuple:
        r"""The bank of ``state``: ``model`` refitted on each of the state's fitting records on its own.

        The pooled model of :attr:`models` averages the dynamics of its fitting records. Records of one state
        differ (in turbulence each flies its own trim and gusts, so its linearised dynamics differ a little), and
        on a new record the pooled model's residuals are less white than the chi-square law says. A bank keeps one
        model per fitting record (same order, trend and hold-back as the pooled model); a window is explained by
        the state when *any* member accepts it (:func:`~tsfdi.monitoring.window_statistics`). If the new record
        behaves like one of the fitting records, the member fitted on it rejects with probability about
        ``alpha``, and the bank (which rejects only when every member does) at most that: the false-alarm rate
        stays near its expectation where the pooled model's does not (docs/results.md, "Banks of per-record
        models").

        Returns
        -------
        tuple of fitted results
            One per fitting record of ``state``, in the order of :attr:`fit_records`.
        """
        if model not in self.models:
            raise ValueError(f"model must be one of the fitted models {list(self.models)}, got {model!r}")
        if state not in self.models[model]:
            raise ValueError(f"state must be one of {list(self.models[model])}, got {state!r}")
        key = (model, state)
        if key not in self._banks:
            res = self.models[model][state]
            spec = res.model
            chans = self.model_channels(model)
            segs = [g[:, chans] if model == "var" else g[:, chans[0]] for g in self.segments[state]]
            self._banks[key] = tuple(type(spec)(g, int(res.lags), trend=spec.trend, hold_back=spec.hold_back).fit()
                                     for g in segs)
        return self._banks[key]

    def state_models(self, model: str, bank: bool = False) -> dict:
        """State -> the pooled fitted model of ``model`` (the paper), or with ``bank=True`` its :meth:`bank`."""
        return {s: (self.bank(model, s) if bank else self.models[model][s]) for s in (self.healthy,) + self.faults}

    def calibrated_tests(self, model: str, method: str, window: float, *, alpha: float | None = None,
                         lags: int | None = None, step: int = 1) -> dict:
        """Per state, the ``method`` test of ``model`` for ``window``-second windows with its threshold calibrated on
        that state's leave-one-record-out residuals (:attr:`heldout`).

        Parameters
        ----------
        model, method, window, alpha, lags :
            As in :func:`evaluate` (default alpha: the paper's Table 3, default lags: 20).
        step : int
            Samples between calibration windows (default every sample).

        Returns
        -------
        dict
            State -> calibrated :class:`~tsfdi.LjungBox` / :class:`~tsfdi.FTest` (``threshold="empirical"``).

        Notes
        -----
        Hansen et al. (paper 002, Fig. 2) set the threshold at the :math:`1-\alpha` quantile of the statistic in
        normal operation. Here "normal" is each model's own state, and the statistics are computed out of sample
        (a record the model was not fitted on), as on the evaluation records: every fitting record in turn is
        left out, the model (same order) is refitted on the others and the left-out record's residual windows
        give statistics. The evaluation records are never used.
        """
        method = option(method, "method", METHODS)
        if model not in self.models:
            raise ValueError(f"model must be one of the fitted models {list(self.models)}, got {model!r}")
        window = float_like(window, "window", minimum=0.0, strict_min=True)
        step = int_like(step, "step", minimum=1)
        key = (model, method, window, alpha, lags, step)
        if key in self._calibrated:
            return self._calibrated[key]
        if not self.heldout:
            raise ValueError("baselines have no held-out residuals: fit them with fit_baselines(..., calibrate=True) "
                             "to calibrate thresholds")
        W = int(round(window * self.fs))
        out = {}
        for state in (self.healthy,) + self.faults:
            res = self.models[model][state]
            test = _make_test(method, model, alpha, lags, window, self.fs, threshold="empirical")
            n = W - int(res.lags)
            recs = self.heldout[(model, state)]
            try:
                test.calibrate([e for e in recs if e.shape[0] >= n], window=n, step=step, **test.reference(res))
            except ValueError as err:
                raise ValueError(f"cannot calibrate the {method} test of model {model!r}, state {state!r}, "
                                 f"{window:g} s windows: {err}") from None
            out[state] = test
        self._calibrated[key] = out
        return out

    def select_alpha(self, model: str = "var", method: str = "whiteness", window: float = 20.0,
                     alphas: Sequence[float] = (1e-3, 1e-4, 1e-5, 1e-6), *, lags: int | None = None,
                     step: float = 1.0, bank: bool = False) -> pd.DataFrame:
        """Choose the identification alpha on the fitting records, leaving each record out (paper's rule).

        Every fitting record of every fault state is cut into ``window``-second windows ``step`` s apart and
        driven through each fault model: through its own state's model refitted without it (:attr:`heldout`)
        and through the other states' models, which never saw it. Each window is then identified by the paper's
        rule (a model is accepted when every channel's test accepts at ``alpha``) for every candidate alpha.
        The evaluation records are not used, so the choice can be evaluated on them honestly.

        Parameters
        ----------
        model, method, window, lags :
            As in :func:`evaluate`.
        alphas : sequence of float
            Candidate per-channel alphas, each in (0, 1).
        step : float
            Seconds between window starts.
        bank : bool
            Identify with the states' :meth:`bank` instead of their pooled models: the held-out record's own
            state is its bank without the member fitted on that record (no ``calibrate=True`` needed).

        Returns
        -------
        pandas.DataFrame
            Indexed by alpha: percent of held-out windows identified uniquely and correctly (``correct``),
            uniquely but wrongly (``wrong``), ambiguous (``ambiguous``), with no model accepted (``none``), and
            the number of windows. ``attrs["selected"]`` is the alpha with the highest ``correct`` rate (the
            largest such alpha on ties: the least conservative test that identifies best).

        Notes
        -----
        Dutta et al. (paper 003, Table 3) set each method's alpha (1e-3 to 1e-12) so as to minimise the
        confusion between failures. Out-of-sample residuals carry the baseline's estimation error, so at the
        nominal alpha the matching model is rejected more often than alpha (notes of :class:`~tsfdi.LjungBox`);
        this choice measures that on held-out records instead of assuming it away.
        """
        method = option(method, "method", METHODS)
        if model not in self.models:
            raise ValueError(f"model must be one of the fitted models {list(self.models)}, got {model!r}")
        _check_bank(bank, "chi2")
        if not bank and not self.heldout:
            raise ValueError("baselines have no held-out residuals: fit them with fit_baselines(..., calibrate=True) "
                             "to select alpha")
        window = float_like(window, "window", minimum=0.0, strict_min=True)
        step_n = max(1, int(round(float_like(step, "step", minimum=0.0, strict_min=True) * self.fs)))
        alphas = np.array([probability(a, "alphas") for a in np.atleast_1d(alphas)], dtype=float)
        if alphas.size == 0:
            raise ValueError("alphas must hold at least one value")
        chan = None if model == "var" else self.channels.index(model)
        W = int(round(window * self.fs))
        test = _make_test(method, model, float(alphas[0]), lags, window, self.fs)
        accepted, truth = [], []
        for state in self.faults:
            for j, seg in enumerate(self.segments[state]):
                per_model = []
                x = seg if chan is None else seg[:, chan]
                for f in self.faults:
                    res = self.models[model][f]
                    n = W - int(res.lags)
                    if seg.shape[0] - int(res.lags) < n:    # record shorter than one window: skipped (for/else)
                        break
                    if bank:
                        members = [(r, None) for i, r in enumerate(self.bank(model, f)) if f != state or i != j]
                        if not members:
                            raise ValueError(f"select_alpha with bank=True needs at least two fitting records per "
                                             f"state; state {f!r} has one")
                    else:
                        members = [(res, self.heldout[(model, state)][j] if f == state else None)]
                    acc = False
                    for r, e in members:
                        e = np.asarray(r.residuals(x) if e is None else e, dtype=np.float64)
                        e = e.reshape(e.shape[0], -1)
                        ref = test.reference(r)
                        stat = test.window_statistic(e, n, step_n, **ref)
                        pval = test._threshold_pvalue(stat, n, **ref)[1]
                        # accepted at alpha when every channel's p-value exceeds it: (windows, alphas); a bank
                        # accepts when any member does
                        acc = acc | np.all(pval[:, :, None] > alphas[None, None, :], axis=1)
                    per_model.append(acc)
                else:
                    m = min(a.shape[0] for a in per_model)
                    accepted.append(np.stack([a[:m] for a in per_model], axis=-1))
                    truth.append(np.full(m, self.faults.index(state)))
        if not accepted:
            raise ValueError(f"no fitting record is longer than a {window:g} s window")
        acc = np.concatenate(accepted)          # (windows, alphas, faults)
        true = np.concatenate(truth)
        n_acc = acc.sum(axis=-1)
        unique = n_acc == 1
        right = acc[np.arange(acc.shape[0]), :, true]
        table = pd.DataFrame({"correct": 100.0 * (unique & right).mean(axis=0),
                              "wrong": 100.0 * (unique & ~right).mean(axis=0),
                              "ambiguous": 100.0 * (n_acc > 1).mean(axis=0),
                              "none": 100.0 * (n_acc == 0).mean(axis=0),
                              "windows": acc.shape[0]}, index=pd.Index(alphas, name="alpha"))
        best = table["correct"].max()
        table.attrs["selected"] = float(alphas[table["correct"].to_numpy() >= best].max())
        return table

    def __repr__(self) -> str:
        return (f"Baselines(models={list(self.models)}, healthy={self.healthy!r}, faults={self.faults}, "
                f"fit_records={len(self.fit_records)})")


def _check_bank(bank: Any, thresholds: str) -> None:
    if not isinstance(bank, (bool, np.bool_)):
        raise TypeError(f"bank must be a bool, got {bank!r}")
    if bank and thresholds == "empirical":
        raise ValueError("bank=True needs thresholds='chi2': the calibrated thresholds belong to the pooled models "
                         "(their leave-one-record-out residuals), not to the members of a bank")


def _resid_list(res: Any) -> list:
    e = res.resid
    return [np.asarray(r, dtype=np.float64) for r in e] if isinstance(e, list) else [np.asarray(e, np.float64)]


def _insample_q(res: Any, block: int, lags: int = 20) -> float:
    """Median Ljung-Box Q of the in-sample residuals over non-overlapping blocks and channels."""
    from tsfdi.detection.whiteness import ljungbox_windows

    qs = []
    for e in _resid_list(res):
        e = e.reshape(e.shape[0], -1)
        n = min(block, e.shape[0])
        if n <= lags + 1:
            continue
        qs.append(ljungbox_windows(e, lags, n, n).ravel())
    return float(np.median(np.concatenate(qs))) if qs else float("nan")


def fit_baselines(data: Any, *, states: Any = None, failure_times: Any = None, turbulence: Any = None,
                  fs: float | None = None, healthy: str = "healthy", fit_records: Any = "first",
                  fit_turbulence: Any = None, settle: float = 10.0, duration: float | None = 20.0,
                  models: Sequence[str] | None = None, max_lags: int = 20, var_max_lags: int = 20,
                  order: Any = "bic", steady_window: float = 10.0, steady_factor: float = 1.0,
                  calibrate: bool = False) -> Baselines:
    r"""Baseline phase: fit a scalar AR model per channel and a VAR on all channels for every state.

    Parameters
    ----------
    data : xarray.Dataset, xarray.DataArray or mapping or sequence of signals
        A hexacopter dataset (:func:`tsfdi.datasets.load_hexacopter`; converted by :func:`hexacopter_signals`),
        a ``(record, time, channel)`` DataArray with ``state`` (and ``failure_time``, ``turbulence``)
        coordinates, a sequence of ``(nobs, k)`` signals with ``states=`` (numpy, pandas or xarray each), or a
        mapping state -> signal (one steady-state segment per state, used whole).
    states, failure_times, turbulence : array_like, optional
        Per-record labels for a sequence of signals.
    fs : float, optional
        Sampling frequency in Hz (from the time coordinate for xarray input, else 1).
    healthy : str
        Name of the healthy state; every other state is a fault state.
    fit_records : "first", "all", int or sequence
        Records used for fitting: the first valid record of each (state, turbulence) cell (default), every
        valid record, the first ``n`` valid records of each cell (an int), or explicit record identifiers. They
        are listed in :attr:`Baselines.fit_records` and excluded by :func:`evaluate`. The records of one state
        are pooled: their regressions are stacked (each record holds back its own first samples, no junction
        between records), which shrinks the estimation error of the parameters.
    fit_turbulence : str or sequence, optional
        Restrict fitting records to these turbulence levels (the paper fits on "severe" only); several levels
        give models pooled across them.
    settle : float
        Seconds after the failure (after 0 for records without failure) where the fitting segment starts:
        the post-failure transient is excluded.
    duration : float or None
        Length of the fitting segment in seconds (the paper's 20 s); ``None`` uses the rest of the record.
    models : sequence of str, optional
        Which models to fit: channel names (scalar AR) and/or ``"var"``; default all channels and ``"var"``.
    max_lags, var_max_lags : int
        Largest AR / VAR order searched (on a common sample of the pooled records).
    order : {"bic", "rss_sss"} or int
        ``"bic"``: the BIC minimum (paper eq. 5); ``"rss_sss"``: the order where the RSS/SSS curve (eq. 6)
        stabilises (:attr:`tsfdi.OrderSelection.stabilized`, the paper's Fig. 8 reading); an int: that order
        for every model (at most the search bound).
    steady_window : float
        Rolling-variance window (s) of the steady-state check.
    steady_factor : float
        Thresholds are ``steady_factor`` times the largest rolling variance of each channel over the steady
        parts (from ``settle`` after the failure) of the fault-state fitting records (the paper's rule with
        factor 1).
    calibrate : bool
        Also compute, for every model and state with at least two fitting records, the leave-one-record-out
        residuals (:attr:`Baselines.heldout`) that calibrate data-driven thresholds
        (``evaluate(..., thresholds="empirical")``): each fitting record in turn through the model refitted on
        the state's other fitting records.

    Returns
    -------
    Baselines

    Notes
    -----
    The segments of the fitting records of one state are passed to the model as a list of records: the
    least-squares regressions are stacked (no junction between records) and the Gram matrices of the order
    selection add up. Order selection follows the paper: BIC (eq. 5) or the RSS/SSS stabilisation (eq. 6)
    over orders ``1..max_lags``; :attr:`Baselines.table` also reports the median Ljung-Box ``Q`` (20 lags) of
    the in-sample residuals over 20 s blocks, a check of their whiteness.

    References
    ----------
    Dutta et al. (paper 003), section "Parametric Model Identification", Table 2 and the Fig. 7 discussion.
    """
    from tsfdi.selection import select_order

    settle = float_like(settle, "settle", minimum=0.0)
    duration = None if duration is None else float_like(duration, "duration", minimum=0.0, strict_min=True)
    max_lags = int_like(max_lags, "max_lags", minimum=1)
    var_max_lags = int_like(var_max_lags, "var_max_lags", minimum=1)
    steady_window = float_like(steady_window, "steady_window", minimum=0.0, strict_min=True)
    steady_factor = float_like(steady_factor, "steady_factor", minimum=0.0, strict_min=True)
    if isinstance(order, str):
        order = option(order, "order", ("bic", "rss_sss"))
    else:
        order = int_like(order, "order", minimum=1, maximum=max(max_lags, var_max_lags))
    if not isinstance(calibrate, (bool, np.bool_)):
        raise TypeError(f"calibrate must be a bool, got {calibrate!r}")
    if isinstance(data, Mapping) and not is_xarray(data):
        if not data:
            raise ValueError("data is an empty mapping: give one signal per state")
        names = list(data)
        data = [data[s] for s in names]
        states, failure_times, turbulence = names, None, None
        fit_records, settle, duration = "all", 0.0, None
    rec = Records.from_data(data, states=states, failure_times=failure_times, turbulence=turbulence, fs=fs)
    uniq = list(dict.fromkeys(rec.state.tolist()))
    if healthy not in uniq:
        raise ValueError(f"healthy state {healthy!r} not found among the states {uniq}")
    faults = tuple(s for s in uniq if s != healthy)
    if not faults:
        raise ValueError("data has no fault state: at least one state other than the healthy one is needed")
    # which records fit
    ok = rec.valid.copy()
    if fit_turbulence is not None:
        levels = [fit_turbulence] if isinstance(fit_turbulence, str) else list(fit_turbulence)
        ok &= np.isin(rec.turbulence, levels)
    per_cell = None
    if isinstance(fit_records, str):
        fit_records = option(fit_records, "fit_records", ("first", "all"))
        per_cell = 1 if fit_records == "first" else None
        if fit_records == "all":
            chosen = np.flatnonzero(ok)
    elif isinstance(fit_records, (int, np.integer)) and not isinstance(fit_records, bool):
        per_cell = int_like(fit_records, "fit_records", minimum=1)
    if per_cell is not None:
        seen: dict = {}
        chosen = []
        for i in np.flatnonzero(ok):
            key = (rec.state[i], rec.turbulence[i])
            if seen.get(key, 0) < per_cell:
                seen[key] = seen.get(key, 0) + 1
                chosen.append(i)
        chosen = np.array(chosen, dtype=int)
    elif not isinstance(fit_records, str):
        wanted = list(fit_records)
        pos = {v: i for i, v in enumerate(rec.ids.tolist())}
        bad = [w for w in wanted if w not in pos]
        if bad:
            raise ValueError(f"fit_records {bad} are not record identifiers of data")
        chosen = np.array([pos[w] for w in wanted], dtype=int)
        if not np.all(rec.valid[chosen]):
            raise ValueError("fit_records contains records that lost control or hold NaN")
    names = list(rec.channels) + ["var"] if models is None else list(models)
    for m in names:
        if m != "var" and m not in rec.channels:
            raise ValueError(f"models must hold channel names {rec.channels} or 'var', got {m!r}")
    out: dict = {m: {} for m in names}
    sels: dict = {}
    segments: dict = {}
    for state in (healthy,) + faults:
        idx = [i for i in chosen if rec.state[i] == state]
        if not idx:
            raise ValueError(f"no valid fitting record for state {state!r}")
        segs = [_segment(rec, i, settle, duration) for i in idx]
        segments[state] = segs
        for m in names:
            if m == "var":
                sel = select_order([pd.DataFrame(g, columns=list(rec.channels)) for g in segs], var_max_lags, "var")
            else:
                j = rec.channels.index(m)
                sel = select_order([pd.Series(g[:, j], name=m) for g in segs], max_lags, "ar")
            sels[(m, state)] = sel
            p = sel.selected if order == "bic" else sel.stabilized if order == "rss_sss" else \
                min(order, sel.max_lags)
            out[m][state] = sel.fit(p)
    heldout: dict = {}
    if calibrate:
        for state, segs in segments.items():
            if len(segs) < 2:
                raise ValueError(f"calibrate=True needs at least two fitting records per state; state {state!r} "
                                 f"has {len(segs)}")
            for m in names:
                heldout[(m, state)] = _leave_one_out(out[m][state], segs,
                                                     None if m == "var" else rec.channels.index(m))
    # steady-state thresholds: largest rolling variance over the post-settle parts of the fault fitting records
    V = int(round(steady_window * rec.fs))
    step = max(1, int(round(0.1 * rec.fs)))
    peaks = []
    for i in chosen:
        if rec.state[i] in faults:
            post = _segment(rec, i, settle, None)
            if post.shape[0] >= V:
                peaks.append(_rolling_variance(post, V, step).max(axis=0))
    thr = steady_factor * np.max(peaks, axis=0) if peaks else np.full(len(rec.channels), np.inf)
    return Baselines(models=out, selections=sels, channels=rec.channels, healthy=healthy, faults=faults,
                     steady_thresholds=thr, steady_window=steady_window,
                     fit_records=tuple(rec.ids[chosen].tolist()), fs=rec.fs, segments=segments, heldout=heldout)


def _leave_one_out(res: Any, segs: list, channel: int | None) -> list:
    """Residuals of each segment through the model (same order, trend, hold-back) refitted on the others."""
    spec = res.model
    recs = [g if channel is None else g[:, channel] for g in segs]
    kw = {"trend": spec.trend, "hold_back": spec.hold_back}
    out = []
    for j in range(len(recs)):
        others = [r for i, r in enumerate(recs) if i != j]
        fit = type(spec)(others if len(others) > 1 else others[0], int(res.lags), **kw).fit()
        e = np.asarray(fit.residuals(recs[j]), dtype=np.float64)
        out.append(e.reshape(e.shape[0], -1))
    return out


# ---------------------------------------------------------------------------------------------------- evaluation
def _default_lags(window: float, fs: float) -> int:
    """Ljung-Box lags for a window: 20, fewer for short windows (at least 10 samples per lag)."""
    return int(min(20, max(2, round(window * fs) // 10)))


def _make_test(method: str, model: str, alpha: float | None, lags: int | None, window: float, fs: float,
               threshold: str = "chi2"):
    from tsfdi.detection.variance import FTest
    from tsfdi.detection.whiteness import LjungBox

    method = option(method, "method", METHODS)
    a = _paper_alpha(method, model) if alpha is None else probability(alpha, "alpha")
    emp = threshold == "empirical"
    if method == "variance":
        return FTest(alpha=a, threshold="empirical" if emp else "f")
    return LjungBox(lags=_default_lags(window, fs) if lags is None else int_like(lags, "lags", minimum=1), alpha=a,
                    threshold="empirical" if emp else "chi2")


@dataclass(frozen=True, eq=False)
class Evaluation:
    """Outcome of :func:`evaluate`.

    Attributes
    ----------
    identification : pandas.DataFrame
        One row per (record, model, method, window length, window) of a fault record, windows starting at least
        ``settle`` s after the failure: ``record, state, turbulence, model, method, window, start``, one bool
        column ``acc_<fault>`` per fault model (its test accepts), and ``label_<rule>`` per rule (the identified
        fault or ``""``; for ``"paper"`` ``"ambiguous"`` / ``"none"`` when not unique).
    detection : pandas.DataFrame
        One row per (record, model, method, window length, window) of every evaluated record: ``fault_true``
        (the window starts after the failure), ``alarm`` (the healthy model's test rejects), ``pre`` (the window
        ends before the failure), ``start``, ``end``.
    faults : tuple of str
    rules : tuple of str
    alphas : dict
        ``(model, method)`` -> alpha used.
    lags : dict
        window length -> Ljung-Box lags.
    records : pandas.DataFrame
        The records evaluated (id, state, turbulence) and those skipped with the reason.
    thresholds : {"chi2", "empirical"}
        How the test thresholds were set.
    bank : bool
        Whether every state was the bank of its per-record models (:meth:`Baselines.bank`).
    calibration : pandas.DataFrame
        Per turbulence level (baselines), model, method, window length, state and channel: the null
        distribution's critical value (``distribution``) and, with ``thresholds="empirical"``, the calibrated
        one (``empirical``), its calibration sample size and estimate (``"empirical"`` quantile or ``"gpd"``
        tail).
    """

    identification: pd.DataFrame
    detection: pd.DataFrame
    faults: tuple
    rules: tuple
    alphas: dict
    lags: dict
    records: pd.DataFrame
    nchan: dict = field(default_factory=dict)
    thresholds: str = "chi2"
    bank: bool = False
    calibration: pd.DataFrame = field(default_factory=pd.DataFrame)

    # -- identification
    def confusion(self, rule: str = "paper") -> pd.DataFrame:
        """Percent of the windows of each true failure accepted (``"paper"``, several may be accepted) or
        labelled (other rules) as each fault, per model, method and window length (paper's Table 4 numbers).

        Returns
        -------
        DataFrame indexed by ``(model, method, window, true)`` with one column per fault.
        """
        rule = option(rule, "rule", self.rules)
        df = self.identification
        keys = ["model", "method", "window", "state"]
        if rule == "paper":
            cols = [f"acc_{f}" for f in self.faults]
            tab = df.groupby(keys, sort=False)[cols].mean() * 100.0
            tab.columns = list(self.faults)
        else:
            lab = df[f"label_{rule}"]
            tab = pd.concat({f: (lab == f) for f in self.faults}, axis=1).groupby(
                [df[k] for k in keys], sort=False).mean() * 100.0
        tab.index = tab.index.set_names(["model", "method", "window", "true"])
        return tab

    def rates(self) -> pd.DataFrame:
        """Per model, method, window length, true failure and rule: percent of windows identified uniquely and
        correctly (``correct``), uniquely but wrongly (``wrong``), ambiguous (``ambiguous``) and with no
        decision (``none``), and the number of windows."""
        df = self.identification
        keys = ["model", "method", "window", "state"]
        parts = []
        for rule in self.rules:
            lab = df[f"label_{rule}"]
            known = lab.isin(self.faults)
            flags = pd.DataFrame({"correct": known & (lab == df["state"]), "wrong": known & (lab != df["state"]),
                                  "ambiguous": lab == "ambiguous", "none": (lab == "none") | (lab == "")})
            g = flags.groupby([df[k] for k in keys], sort=False)
            t = g.mean() * 100.0
            t["windows"] = g.size()
            t["rule"] = rule
            parts.append(t.reset_index().rename(columns={"state": "true"}))
        return pd.concat(parts, ignore_index=True).set_index(["model", "method", "window", "true", "rule"])

    def table4(self, window: float | None = None, rule: str = "paper") -> pd.DataFrame:
        """The paper's Table 4 layout: rows ``(model, method)``, one column per true failure holding
        ``"a/b/c"``, the percent of its windows accepted (or labelled) as each fault, for one window length."""
        conf = self.confusion(rule)
        wins = sorted(conf.index.get_level_values("window").unique())
        window = wins[-1] if window is None else float(window)
        if window not in wins:
            raise ValueError(f"window must be one of the evaluated lengths {wins}, got {window}")
        sub = conf.xs(window, level="window")
        out = {}
        for (model, method, true), row in sub.iterrows():
            out.setdefault((model, method), {})[true] = "/".join(f"{v:.2f}" for v in row.values)
        frame = pd.DataFrame.from_dict(out, orient="index")
        frame.index = frame.index.set_names(["model", "method"])
        return frame[[f for f in self.faults if f in frame.columns]]

    # -- detection
    def detection_rates(self) -> pd.DataFrame:
        """Per model, method and window length: ``false_alarm`` (percent of healthy-record windows flagged),
        ``expected_false_alarm`` (percent, ``1 - (1 - alpha)^k`` for ``k`` channels tested at ``alpha``),
        ``disjoint_windows`` and ``disjoint_alarms`` (the healthy windows that do not overlap: in each record those
        starting at a multiple of the window length from its first window, and how many of them are flagged),
        ``false_alarm_pvalue`` (binomial probability of at least ``disjoint_alarms`` alarms in
        ``disjoint_windows`` independent windows at the expected rate: sliding windows 1 s apart share most of
        their samples, so one excursion flags a run of them and only the disjoint ones can be counted as
        independent trials; small values mean more false alarms than the expectation allows),
        ``missed_fault`` (percent of fault-record windows starting after the failure not flagged),
        ``missed_records`` (fault records with no alarm after the failure), ``delay_median`` and ``delay_max``
        (s, from the failure to the end of the first flagged window ending after it)."""
        det = self.detection
        keys = ["model", "method", "window"]
        rows = []
        for key, g in det.groupby(keys, sort=False):
            h = g[g["state"] == self._healthy]
            first = h.groupby("record", sort=False)["start"].transform("min")
            lag = (h["start"] - first) / key[2]
            disjoint = h[np.isclose(lag, np.round(lag))]
            f = g[(g["state"] != self._healthy) & g["fault_true"]]
            post = g[(g["state"] != self._healthy) & ~g["pre"]]
            delays = []
            missed = 0
            for _, r in post.groupby("record", sort=False):
                hit = r[r["alarm"]]
                if len(hit):
                    delays.append(float(hit["end"].iloc[0] - r["failure_time"].iloc[0]))
                else:
                    missed += 1
            a = self.alphas[(key[0], key[1])]
            k = self.nchan.get(key[0], 1)
            p0 = 1.0 - (1.0 - a) ** k
            n_dis, x_dis = len(disjoint), int(disjoint["alarm"].sum())
            rows.append({"model": key[0], "method": key[1], "window": key[2],
                         "false_alarm": 100.0 * h["alarm"].mean() if len(h) else np.nan,
                         "expected_false_alarm": 100.0 * p0, "healthy_windows": len(h),
                         "disjoint_windows": n_dis, "disjoint_alarms": x_dis,
                         "false_alarm_pvalue": float(stats.binom.sf(x_dis - 1, n_dis, p0)) if n_dis else np.nan,
                         "missed_fault": 100.0 * (1.0 - f["alarm"].mean()) if len(f) else np.nan,
                         "missed_records": missed,
                         "delay_median": float(np.median(delays)) if delays else np.nan,
                         "delay_max": float(np.max(delays)) if delays else np.nan})
        return pd.DataFrame(rows).set_index(keys)

    @property
    def _healthy(self) -> str:
        return str(self.records.attrs.get("healthy", "healthy"))

    def summary(self) -> str:
        """Table 4 (paper rule) per window length, the rates of every rule and the detection rates as text."""
        parts = []
        for w in sorted(self.identification["window"].unique()):
            for rule in self.rules:
                parts.append(f"Identification, {w:g} s windows, rule {rule!r} (percent of windows of each true "
                             f"failure {'accepted' if rule == 'paper' else 'labelled'} as {'/'.join(self.faults)}):")
                parts.append(self.table4(w, rule).to_string())
        parts.append("Rates (percent of windows):")
        parts.append(self.rates().round(2).to_string())
        parts.append("Detection with the healthy model:")
        parts.append(self.detection_rates().round(4).to_string())
        return "\n\n".join(parts)

    def __repr__(self) -> str:
        return (f"Evaluation(windows={len(self.identification)} identification, {len(self.detection)} detection, "
                f"faults={self.faults}, rules={self.rules})")


def evaluate(data: Any, baselines: Baselines, *, models: Sequence[str] = ("var",),
             methods: Sequence[str] = ("whiteness",), windows: Sequence[float] = (5.0, 10.0, 20.0),
             turbulence: Any = None, step: float = 1.0, settle: float = 10.0, alpha: Any = None, lags: Any = None,
             rules: Sequence[str] = ("paper", "likelihood"), detection: bool = True, progress: bool = True,
             states: Any = None, failure_times: Any = None, fs: float | None = None,
             thresholds: str = "chi2", bank: bool = False) -> Evaluation:
    r"""Detection and identification over many records, per sliding window (Dutta et al., Table 4).

    Parameters
    ----------
    data : xarray.Dataset, xarray.DataArray or sequence of signals
        Records as accepted by :func:`fit_baselines`; the records in ``baselines.fit_records`` and records that
        lost control (NaN) are skipped.
    baselines : Baselines or mapping
        From :func:`fit_baselines`, or a mapping turbulence level -> :class:`Baselines` (condition-scheduled
        baselines: each record is tested with the models of its own turbulence level; levels not in the mapping
        are skipped).
    models : sequence of str
        Model names of ``baselines`` (channel names for scalar AR, ``"var"``).
    methods : sequence of {"whiteness", "variance"}
        Ljung-Box residual uncorrelatedness test or residual variance F test.
    windows : sequence of float
        Window lengths in seconds.
    turbulence : str or sequence, optional
        Turbulence levels to evaluate (default all).
    step : float
        Seconds between window starts (the paper's 1 s).
    settle : float
        Identification windows start at least ``settle`` s after the failure (post-failure steady state).
    alpha : float or dict, optional
        Type I risk for every test, or a dict ``(model, method) -> alpha``; default the paper's Table 3
        (:data:`PAPER_ALPHA`). Each channel is tested at ``alpha`` and a model is accepted only if every channel
        accepts (paper's rule for vector residuals).
    lags : int or dict, optional
        Ljung-Box lags, or a dict window length -> lags; default 20 (at least 10 samples per lag).
    rules : sequence of str
        Decision rules (:data:`tsfdi.monitoring.RULES`); ``"paper"`` is always included.
    detection : bool
        Also test every window of every record with the healthy model (false alarms, missed faults, delays).
    progress : bool
        Show a tqdm progress bar over records.
    states, failure_times, fs :
        Per-record labels and sampling frequency for a sequence of signals.
    thresholds : {"chi2", "empirical"}
        ``"chi2"`` (the paper): each test's critical value from its null distribution (chi-square for the
        Ljung-Box test, F for the variance test). ``"empirical"``: every model (healthy and each fault) has its
        own thresholds, the per-channel :math:`1-\alpha` quantiles of its test statistic on its own
        leave-one-record-out fitting residuals (:meth:`Baselines.calibrated_tests`; needs
        ``fit_baselines(..., calibrate=True)``), and p-values are empirical (paper 002, Fig. 2). Evaluation
        records are never used for calibration.
    bank : bool
        ``False`` (the paper): every state is its model pooled over its fitting records. ``True``: every state
        (healthy and each fault) is the bank of its models fitted on each fitting record alone
        (:meth:`Baselines.bank`), accepted on a window when any member accepts; detection alarms when every
        healthy member rejects. Needs ``thresholds="chi2"``.

    Returns
    -------
    Evaluation

    Notes
    -----
    Every record is filtered once through each model and all windows' statistics come from prefix sums
    (:func:`tsfdi.monitoring.window_statistics`, :func:`tsfdi.detection.ljungbox_windows`).
    """
    if isinstance(baselines, Baselines):
        by_level = None
    elif isinstance(baselines, Mapping) and baselines and all(isinstance(b, Baselines) for b in baselines.values()):
        by_level = {str(k): b for k, b in baselines.items()}
    else:
        raise TypeError("baselines must be the result of tsfdi.fit_baselines or a mapping turbulence level -> "
                        f"Baselines, got {type(baselines).__name__}")
    first = baselines if by_level is None else next(iter(by_level.values()))
    rec = Records.from_data(data, states=states, failure_times=failure_times, fs=fs)
    for b in ([first] if by_level is None else by_level.values()):
        if rec.channels != b.channels:
            raise ValueError(f"data has channels {rec.channels} but the baselines were fitted on {b.channels}")
        if abs(rec.fs - b.fs) > 1e-9 * b.fs:
            raise ValueError(f"data is sampled at {rec.fs} Hz but the baselines at {b.fs} Hz")
        if (b.healthy, b.faults) != (first.healthy, first.faults):
            raise ValueError("every Baselines of the mapping must have the same healthy and fault states")
    models = [models] if isinstance(models, str) else list(models)
    for m in models:
        if m not in first.models:
            raise ValueError(f"models must be among the fitted models {list(first.models)}, got {m!r}")
    methods = [option(m, "methods", METHODS) for m in ([methods] if isinstance(methods, str) else methods)]
    wins = [float_like(w, "windows", minimum=0.0, strict_min=True) for w in np.atleast_1d(windows)]
    if not models or not methods or not wins:
        raise ValueError("models, methods and windows must each hold at least one entry")
    rules = tuple(dict.fromkeys(["paper"] + [option(r, "rules", RULES) for r in rules]))
    step_n = max(1, int(round(float_like(step, "step", minimum=0.0, strict_min=True) * rec.fs)))
    settle = float_like(settle, "settle", minimum=0.0)
    healthy, faults = first.healthy, first.faults
    fit = set(first.fit_records) if by_level is None else {r for b in by_level.values() for r in b.fit_records}
    use = rec.valid & ~np.isin(rec.ids, list(fit)) & np.isin(rec.state, (healthy,) + faults)
    if by_level is not None:
        use &= np.isin(rec.turbulence, list(by_level))
    if turbulence is not None:
        use &= np.isin(rec.turbulence, [turbulence] if isinstance(turbulence, str) else list(turbulence))
    reasons = np.where(np.isin(rec.ids, list(fit)), "fitting record",
                       np.where(~rec.valid, "lost control / non-finite",
                                np.where(use, "", "not selected")))
    recs = pd.DataFrame({"record": rec.ids, "state": rec.state, "turbulence": rec.turbulence,
                         "evaluated": use, "skipped": reasons})
    recs.attrs["healthy"] = healthy
    if not use.any():
        raise ValueError("no record left to evaluate (all are fitting records, invalid or not selected)")

    thresholds = option(thresholds, "thresholds", THRESHOLDS)
    _check_bank(bank, thresholds)
    alphas, lag_of, tests = {}, {}, {}
    for m in models:
        for meth in methods:
            a = alpha.get((m, meth)) if isinstance(alpha, Mapping) else alpha
            for w in wins:
                lg = lags.get(w) if isinstance(lags, Mapping) else lags
                t = _make_test(meth, m, a, lg, w, rec.fs)
                tests[(m, meth, w)] = t
                alphas[(m, meth)] = t.alpha
                if meth == "whiteness":
                    lag_of[w] = t.lags

    ident_parts, det_parts = [], []
    idx = np.flatnonzero(use)
    iterator = idx
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(idx, desc="tsfdi evaluate", unit="record")
    for i in iterator:
        x_all = rec.values[i]
        state, ft = rec.state[i], rec.failure_time[i]
        is_fault = state != healthy
        base = first if by_level is None else by_level[rec.turbulence[i]]
        for m in models:
            sig = as_signal(x_all[:, base.model_channels(m)], "signal", allow_constant=True)
            x = sig.values
            per_state = base.state_models(m, bank)
            # each record is filtered once through every (member) model; the windows of every length and
            # method are slices of these residuals
            banks_h = _banks({"h": per_state[healthy]})
            resid_h = _bank_residuals(banks_h, x) if detection else None
            banks_f = _banks({f: per_state[f] for f in faults})
            resid_f = _bank_residuals(banks_f, x) if is_fault else None
            for meth in methods:
                for w in wins:
                    W = int(round(w * rec.fs))
                    test = tests[(m, meth, w)]
                    if thresholds == "empirical":
                        cal = base.calibrated_tests(m, meth, w, alpha=test.alpha,
                                                    lags=getattr(test, "lags", None))
                        test_h, test_f = cal[healthy], {f: cal[f] for f in faults}
                    else:
                        test_h = test_f = test
                    if detection:
                        wh = _window_statistics(sig.nobs, sig.channels, banks_h, resid_h, {"h": test_h}, window=W,
                                                step=step_n)
                        d, starts = wh["decisions"]["h"], wh["starts"]
                        st, en = starts / rec.fs, (starts + W) / rec.fs
                        det_parts.append(pd.DataFrame({
                            "record": rec.ids[i], "state": state, "turbulence": rec.turbulence[i], "model": m,
                            "method": meth, "window": w, "start": st, "end": en,
                            "failure_time": ft, "fault_true": is_fault & (st >= ft),
                            "pre": ~is_fault | (en <= ft), "alarm": d["reject"]}))
                    if not is_fault:
                        continue
                    ws = _window_statistics(sig.nobs, sig.channels, banks_f, resid_f, test_f, window=W, step=step_n)
                    starts = ws["starts"]
                    keep = starts / rec.fs >= ft + settle
                    if not keep.any():
                        continue
                    rej = np.array([ws["decisions"][f]["reject"] for f in faults])[:, keep]
                    pmin = np.array([ws["decisions"][f]["pvalue"].min(axis=1) for f in faults])[:, keep]
                    ll = ws["loglik"][:, keep]
                    cols = {"record": rec.ids[i], "state": state, "turbulence": rec.turbulence[i], "model": m,
                            "method": meth, "window": w, "start": starts[keep] / rec.fs}
                    for j, f in enumerate(faults):
                        cols[f"acc_{f}"] = ~rej[j]
                    names = np.array(list(faults) + ["ambiguous", "none"], dtype=object)
                    for rule in rules:
                        lab = apply_rule(rej, ll, pmin, rule)
                        cols[f"label_{rule}"] = names[np.where(lab >= 0, lab, np.where(lab == -2, len(faults),
                                                                                       len(faults) + 1))]
                    ident_parts.append(pd.DataFrame(cols))
    ident = pd.concat(ident_parts, ignore_index=True) if ident_parts else pd.DataFrame(
        columns=["record", "state", "turbulence", "model", "method", "window", "start"]
        + [f"acc_{f}" for f in faults] + [f"label_{r}" for r in rules])
    det = pd.concat(det_parts, ignore_index=True) if det_parts else pd.DataFrame(
        columns=["record", "state", "turbulence", "model", "method", "window", "start", "end", "failure_time",
                 "fault_true", "pre", "alarm"])
    cal_rows = []
    for lvl, b in ([("", first)] if by_level is None else by_level.items()):
        for (m, meth, w), t in tests.items():
            chans = [b.channels[c] for c in b.model_channels(m)]
            cal = b.calibrated_tests(m, meth, w, alpha=t.alpha, lags=getattr(t, "lags", None)) \
                if thresholds == "empirical" else {}
            for state in (healthy,) + faults:
                res = b.models[m][state]
                n = int(round(w * rec.fs)) - int(res.lags)
                dist = t._null_threshold(len(chans), n, **t.reference(res))
                for c, ch in enumerate(chans):
                    row = {"turbulence": lvl, "model": m, "method": meth, "window": w, "state": state,
                           "channel": ch, "distribution": float(dist[c])}
                    if state in cal:
                        row["empirical"] = float(cal[state].threshold_[c])
                        row["calibration_size"] = int(cal[state].calibration_[c].size)
                        row["estimate"] = cal[state].thresholds_[c].method_
                    cal_rows.append(row)
    return Evaluation(identification=ident, detection=det, faults=faults, rules=rules, alphas=alphas, lags=lag_of,
                      records=recs, nchan={m: len(first.model_channels(m)) for m in models}, thresholds=thresholds,
                      bank=bool(bank), calibration=pd.DataFrame(cal_rows))


def hexacopter_study(data: Any = None, *, records_per_case: int | None = None, models: Sequence[str] | None = None,
                     methods: Sequence[str] = METHODS, windows: Sequence[float] = (5.0, 10.0, 20.0),
                     rules: Sequence[str] = ("paper", "likelihood", "pvalue"), lags: Any = None, settle: float = 10.0,
                     fit_records: int = 10, pool: str = "level", order: Any = 20, max_lags: int = 20,
                     var_max_lags: int = 20, progress: bool = True, thresholds: str = "chi2",
                     bank: bool = False) -> tuple[dict, Evaluation]:
    """The whole study of paper 003 on a hexacopter dataset: pooled baselines, then evaluation.

    The first ``fit_records`` valid records of each state and turbulence level fit the baselines (whole
    post-settle part of each record, pooled without junctions; see :func:`fit_baselines`); every other valid
    record is evaluated. With ``pool="level"`` each level has its own models and every record is tested with
    the models of its level (condition-scheduled baselines); with ``pool="all"`` one set of models is fitted on
    the fitting records of all levels.

    Parameters
    ----------
    data : xarray.Dataset, optional
        Default the shipped :func:`tsfdi.datasets.load_hexacopter`.
    records_per_case : int, optional
        Use only the first ``records_per_case`` records of each (state, turbulence) cell (more than
        ``fit_records``: those fit, the others are evaluated); default all.
    models, methods, windows, rules, lags, settle, progress :
        As in :func:`evaluate`; ``models`` defaults to every channel and ``"var"``.
    fit_records : int
        Fitting records per state and turbulence level (reduced to ``records_per_case - 1`` when fewer).
    pool : {"level", "all"}
        Models per turbulence level, or one set pooled across levels.
    order, max_lags, var_max_lags :
        Order choice and search bounds of :func:`fit_baselines`. Default order 20: on the shipped data BIC on
        the pooled records picks VAR(12-15) whose in-sample residuals are still correlated (docs/results.md).
    thresholds : {"chi2", "empirical"}
        Test thresholds (:func:`evaluate`); ``"empirical"`` fits the baselines with ``calibrate=True``
        (leave-one-record-out residuals of the fitting records).
    bank : bool
        Every state as the bank of its per-record models (:func:`evaluate`, :meth:`Baselines.bank`).

    Returns
    -------
    baselines : dict
        Turbulence level -> :class:`Baselines` (with ``pool="all"`` every level maps to the same object).
    evaluation : Evaluation
    """
    if data is None:
        from tsfdi.datasets import load_hexacopter

        data = load_hexacopter()
    import xarray as xr

    if not isinstance(data, xr.Dataset):
        raise TypeError(f"data must be a hexacopter xarray.Dataset, got {type(data).__name__}")
    fit_records = int_like(fit_records, "fit_records", minimum=1)
    pool = option(pool, "pool", ("level", "all"))
    thresholds = option(thresholds, "thresholds", THRESHOLDS)
    if records_per_case is not None:
        n = int_like(records_per_case, "records_per_case", minimum=2)
        fit_records = min(fit_records, n - 1)
        st, tb = data["state"].values, data["turbulence"].values
        keep, count = [], {}
        for i in range(data.sizes["record"]):
            key = (st[i], tb[i])
            count[key] = count.get(key, 0) + 1
            if count[key] <= n:
                keep.append(i)
        data = data.isel(record=keep)
    levels = list(dict.fromkeys(np.asarray(data["turbulence"].values).astype(str).tolist()))
    sig = hexacopter_signals(data)
    names = list(sig["channel"].values) + ["var"] if models is None else list(models)
    with warnings.catch_warnings():
        from tsfdi.exceptions import UnstableModelWarning

        warnings.simplefilter("ignore", UnstableModelWarning)
        kw = dict(duration=None, settle=settle, models=names, fit_records=fit_records, order=order,
                  max_lags=max_lags, var_max_lags=var_max_lags, calibrate=thresholds == "empirical")
        if pool == "level":
            bases = {lvl: fit_baselines(sig, fit_turbulence=lvl, **kw) for lvl in levels}
        else:
            one = fit_baselines(sig, **kw)
            bases = dict.fromkeys(levels, one)
    ev = evaluate(sig, bases, models=names, methods=methods, windows=windows, rules=rules, lags=lags,
                  settle=settle, progress=progress, thresholds=thresholds, bank=bank)
    return bases, ev


def baselines_table(baselines: Any) -> pd.DataFrame:
    """Table 2 analogue of one :class:`Baselines` or of a mapping turbulence level -> Baselines (one
    ``turbulence`` column added)."""
    if isinstance(baselines, Baselines):
        return baselines.table
    if not isinstance(baselines, Mapping) or not all(isinstance(b, Baselines) for b in baselines.values()):
        raise TypeError("baselines must be a Baselines or a mapping turbulence level -> Baselines")
    frames, seen = [], {}
    for lvl, b in baselines.items():       # one Baselines shared by several levels (pooled) is listed once
        seen.setdefault(id(b), (b, []))[1].append(str(lvl))
    for b, lvls in seen.values():
        t = b.table
        t.insert(0, "turbulence", lvls[0] if len(lvls) == 1 else "+".join(lvls))
        frames.append(t)
    return pd.concat(frames, ignore_index=True)
