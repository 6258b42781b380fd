"""Recursive ARX estimation by (exponentially weighted) recursive least squares, with online anomaly flags.

The model is the MATLAB ``arx`` / :class:`tsfdi.ARX` convention (papers' sign for the AR part)::

    y[t] + a_1 y[t-1] + ... + a_na y[t-na] = sum_j (b_j1 u_j[t-nk] + ... + b_jnb u_j[t-nk-nb+1]) [+ c] + e[t]

so the regressor of sample ``t`` is ``phi[t] = [1 (trend "c" only), -y[t-1], ..., -y[t-na],
u_0[t-nk], ..., u_0[t-nk-nb+1], u_1[t-nk], ...]`` and ``theta = [c, a_1..a_na, b_0, b_1, ...]``: grouped by kind
(all ``a``, then the ``b`` of each input), whereas ``ARXResults.params`` is grouped by lag (``c, a_1, b_.1, a_2,
...``). ``RecursiveARX(theta0=arx_results)`` maps a batch fit onto this order.

The estimator is the RLS of Keipour et al. (paper 001, eqs. 4-7) with the forgetting factor of Hansen
et al. (paper 002, eqs. 14-16), implemented in the symmetric form ``P <- P / lambda - v v'`` with
``v = P phi / sqrt(lambda (lambda + phi' P phi))``. This form keeps ``P`` exactly symmetric in floating
point (``v_i v_j == v_j v_i``), which the textbook ``(P - g phi' P) / lambda`` does not; the asymmetry of
the latter grows geometrically for ``lambda < 1`` and makes the parameters drift from the exact
exponentially weighted least-squares solution.

On top of the estimator sits the online detector of paper 001, section IV:

1. the model is *stable* once ``||L(k) e(k)||_inf < eps`` (the parameter step) for ``stable_samples``
   consecutive samples (``gate="relative"``: the step relative to the parameters, both weighted by the scales
   of their regressors, a bound free of the units of ``y`` and ``u``);
2. from then on the variance of the a-priori prediction errors is tracked with Welford's recursion
   (paper 001, eq. 8); it is *stable* once it has at least ``min_variance_samples`` samples and its relative
   change per sample stays below ``variance_tol`` for ``stable_samples`` consecutive samples;
3. once both are stable, a sample whose Z-score ``(e(k) - mean) / s`` (mean and sample standard deviation
   of the errors before ``k``) exceeds ``threshold`` in absolute value is an alarm (paper 001 uses 4.5);
4. with ``freeze_on_alarm`` the parameters, ``P`` and the error statistics are frozen from the first alarm
   on, so the model does not learn the fault (paper 002, section 2: adaptation halted on alarm);
   :meth:`RecursiveARX.freeze` does the same on request (for an alarm raised by another statistic).

The whole estimator state can be snapshot and restored (:meth:`RecursiveARX.get_state` /
:meth:`RecursiveARX.set_state`), e.g. to undo the samples of a suspected fault.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numba
import numpy as np
import pandas as pd

from tsfdi._data import Signal, as_signal, check_paired
from tsfdi._validation import float_like, int_like, option
from tsfdi.models._base import ScalarOutputResults
from tsfdi.models.lstsq import check_size

__all__ = ["RecursiveARX", "RecursiveARXResults", "RecursiveARXState"]

# bits of the per-sample flag array written by the kernel
_MODEL_STABLE = 1
_VAR_STABLE = 2
_ALARM = 4
_SKIPPED = 8
_UPDATED = 16

# integer state slots
_I_VALID, _I_STABLE_CNT, _I_MODEL_STABLE, _I_NW, _I_VAR_CNT, _I_VAR_STABLE, _I_ALARMED, _I_SKIPPED, \
    _I_SEEN, _I_FIRST_ALARM, _I_FROZEN = range(11)
# float state slots
_F_MEAN, _F_M2, _F_UNIT = range(3)
#: largest weight ``phi' P phi / lambda`` of one sample relative to the covariance P it updates (see the kernel)
_MAX_WEIGHT = 1e12
#: ridge (relative to the largest variance) that restores a covariance which rounding made indefinite
_RIDGE = 2.0**-40
#: largest magnitude of a sample (outputs and inputs) and of ``P0``'s diagonal: products of the two, summed over
#: up to 16,384 parameters, stay in the floating-point range
MAX_SAMPLE = 1e152
MAX_P0 = 1e100
#: largest ``||P0||_inf * sample**2``: every product ``phi_i (P0 phi)_i`` stays finite (RecursiveARX, Notes, Scale)
MAX_P0_SAMPLE2 = 1e308


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract", "arcp", "nsz"})
def _m_phi(P, phi, px, capped, any_cap, inv_lam, half):  # pragma: no cover - compiled
    """``px = M phi`` and ``phi' px``: ``M = P`` when no coordinate is capped (the kernel folds ``1 / lambda``
    into ``s``), else ``M = F o P`` with ``F[i, k] = 1 / lambda``, ``1 / sqrt(lambda)`` or 1 as neither, one or
    both of ``i, k`` are capped. The kernel's own loop does the uncapped case; this one serves the rest."""
    d = phi.shape[0]
    for i in range(d):
        px[i] = 0.0
    for k in range(d):
        pk = phi[k]
        for i in range(d):
            f = 1.0 if not any_cap or (capped[i] and capped[k]) else (half if capped[i] or capped[k] else inv_lam)
            px[i] += P[k, i] * f * pk
    s = 0.0
    for i in range(d):
        s += phi[i] * px[i]
    return s


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract", "arcp", "nsz"})
def _diagonal(P, pcap, lam, capped):  # pragma: no cover - compiled
    """Check the variances after ``P`` changed and flag the coordinates capped at the next sample.

    Rounding may leave a variance negative (``P`` indefinite) when ``P`` is nearly singular: a ridge lifts the
    diagonal back (``2**-40`` times the largest variance plus twice the deficit); a covariance that is no
    longer finite restarts from its bound ``diag(pcap)`` (covariance resetting). A coordinate is capped (not
    forgotten) when ``P[i, i] / lambda`` would exceed ``pcap[i]``. Returns whether any is.
    """
    d = P.shape[0]
    dmin = np.inf
    dmax = 0.0
    any_cap = False
    for i in range(d):
        p = P[i, i]
        dmin = min(dmin, p)
        dmax = max(dmax, p)
        capped[i] = lam < 1.0 and p > lam * pcap[i]
        any_cap = any_cap or capped[i]
    if dmin > 0.0 and dmax < np.inf:
        return any_cap
    if dmin > -np.inf and dmax < np.inf:
        mu = _RIDGE * dmax - min(dmin, 0.0) * 2.0
        for i in range(d):
            P[i, i] += mu
    else:
        for i in range(d):
            for k in range(d):
                P[i, k] = pcap[i] if i == k else 0.0
    any_cap = False
    for i in range(d):
        capped[i] = lam < 1.0 and P[i, i] > lam * pcap[i]
        any_cap = any_cap or capped[i]
    return any_cap


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract", "arcp", "nsz"})
def _condition(P, pcap, phi, px, s, capped, any_cap, inv_lam, half, lam_s, halted):  # pragma: no cover
    """Repair ``P`` before an update whose ``s = phi' M phi`` is negative, beyond ``_MAX_WEIGHT lambda`` or not a
    number (rare). Returns the new ``s`` (and ``px``) and whether ``P``'s diagonal needs :func:`_diagonal`.

    ``s < 0``: ``P`` lost its positive definiteness to rounding (its condition number beyond ~1e16: a direction
    excited by data far larger than ``1 / sqrt(P)`` while another is not). A ridge on the diagonal, twice what
    makes ``phi' M phi`` positive plus ``_RIDGE`` times the largest variance, restores it.

    ``s > _MAX_WEIGHT lambda`` (while adapting): the sample would outweigh ``P``'s information by more than
    ``1 / _MAX_WEIGHT``, and the symmetric update would lose ``P``'s last digits (and its positive definiteness).
    ``P`` and ``pcap`` shrink so that ``phi' M phi`` is exactly ``_MAX_WEIGHT lambda``: the prior dropped is then
    ``< 1e-12`` of the sample's weight.
    """
    d = phi.shape[0]
    touched = False
    if s < 0.0:
        w = 0.0
        top = 0.0
        for i in range(d):
            f = 1.0 if not any_cap or capped[i] else inv_lam
            w += f * phi[i] * phi[i]
            top = max(top, P[i, i])
        mu = 2.0 * (-s) / w + _RIDGE * top
        for i in range(d):
            P[i, i] += mu
        s = _m_phi(P, phi, px, capped, any_cap, inv_lam, half)
        touched = True
    if not halted and not s <= _MAX_WEIGHT * lam_s:
        top = 0.0
        for i in range(d):
            top = max(top, abs(phi[i]))
        sq = 0.0
        for i in range(d):
            sq += (phi[i] / top) * px[i]
        g = _MAX_WEIGHT * lam_s / sq
        for i in range(d):
            px[i] = px[i] * g / top
            pcap[i] = pcap[i] * g / top
            for k in range(d):
                P[i, k] = P[i, k] * g / top
        s = 0.0
        for i in range(d):
            s += phi[i] * px[i]
    return s, touched


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract", "arcp", "nsz"})
def _rls_kernel(y, u, na, nb, nk, trend, lam, freeze_on_alarm, eps, n_stable, var_tol, var_min, zthr, arm_after,
                pcap, theta, P, ybuf, ubuf, ist, fst, smax,
                out_params, out_err, out_var, out_mean, out_z, out_flags):  # pragma: no cover
    """Process samples ``y[t], u[t, :]`` in order, updating the state arrays in place.

    ``ybuf[k] = y[t-1-k]`` (length ``max(na, 1)``), ``ubuf[j, k] = u_j[t-k]`` (``nk + nb`` columns).
    Non-finite samples are skipped (the caller has already rejected them when the policy is "raise").
    ``pcap`` starts as the diagonal of ``P0``: forgetting never lifts ``P[i, i]`` above it; when a dominant sample
    scales ``P`` down, ``pcap`` follows (see ``RecursiveARX``).
    The error statistics ``fst = [mean, M2, unit]`` are kept in units of ``fst[2]``, a power of two set by the
    first nonzero error, so that their squares stay in the floating-point range at any data scale.
    With ``smax`` an array the model-stability gate is the relative one of ``RecursiveARX`` (``gate="relative"``),
    whose regressor scales ``smax = [max |y|, max |u_0|, ...]`` over the finite samples are kept up to date here;
    ``smax=None`` (the absolute gate) is a separate compilation without that code (numba prunes the ``is None``
    branches on an argument's type).

    Speed (a few loop passes of length ``d`` per sample dominate for small ``d``): the counters and statistics
    live in local variables and go back to ``ist`` / ``fst`` at the end; ``P phi`` is computed by row dot
    products, two rows per pass over ``phi``, with ``phi' P phi`` in the same pass; the parameter step and the
    scaling of ``v`` share one loop; the rare repairs of ``P`` sit behind one range check of ``phi' P phi``.
    """
    n = y.shape[0]
    d = theta.shape[0]
    nin = u.shape[1]
    nu = ubuf.shape[1]
    t0 = max(na, nk + nb - 1) if nb > 0 else na
    off_b = na + trend
    inv_lam = 1.0 / lam
    half = np.sqrt(inv_lam)
    phi = np.empty(d)
    px = np.empty(d)
    capped = np.zeros(d, dtype=np.bool_)
    any_cap = _diagonal(P, pcap, lam, capped)
    valid, stable_cnt, model_stable, nw = ist[_I_VALID], ist[_I_STABLE_CNT], ist[_I_MODEL_STABLE], ist[_I_NW]
    var_cnt, var_stable, alarmed, skipped = ist[_I_VAR_CNT], ist[_I_VAR_STABLE], ist[_I_ALARMED], ist[_I_SKIPPED]
    seen, first_alarm, frozen = ist[_I_SEEN], ist[_I_FIRST_ALARM], ist[_I_FROZEN]
    mean, m2, unit = fst[_F_MEAN], fst[_F_M2], fst[_F_UNIT]
    inv_unit = 1.0 / unit if unit != 0.0 else 1.0
    scale = unit if unit != 0.0 else 1.0
    var_out = m2 / (nw - 1) * scale * scale if nw >= 2 else np.nan     # the statistics in the data's unit
    mean_out = mean * scale if nw >= 1 else np.nan
    # no adaptation from the first alarm on (freeze_on_alarm) or while frozen (freeze())
    halted = frozen == 1 or (freeze_on_alarm and alarmed == 1)
    for t in range(n):
        yt = y[t]
        finite = np.isfinite(yt)
        for j in range(nin):
            if not np.isfinite(u[t, j]):
                finite = False
        if smax is not None:    # the relative gate's regressor scales, sample t included
            if np.isfinite(yt):
                smax[0] = max(smax[0], abs(yt))
            for j in range(nin):
                if np.isfinite(u[t, j]):
                    smax[1 + j] = max(smax[1 + j], abs(u[t, j]))
        seen += 1
        # shift the input history (u_j[t] goes to column 0)
        for j in range(nin):
            for k in range(nu - 1, 0, -1):
                ubuf[j, k] = ubuf[j, k - 1]
            ubuf[j, 0] = u[t, j]
        flags = 0
        e = np.nan
        z = np.nan
        if not finite:
            skipped += 1
            valid = 0
            flags |= _SKIPPED
        else:
            valid += 1
        if finite and valid > t0:
            # regressor
            if trend == 1:
                phi[0] = 1.0
            for i in range(na):
                phi[trend + i] = -ybuf[i]
            for j in range(nin):
                for k in range(nb):
                    phi[off_b + j * nb + k] = ubuf[j, nk + k]
            yhat = 0.0
            for i in range(d):
                yhat += phi[i] * theta[i]
            e = yt - yhat
            # px = M phi and s = phi' px. M = P (1 / lambda folded into s) unless a coordinate is capped
            # (anti-windup: a coordinate whose variance would pass its P0 value is not forgotten at this sample;
            # the flags come from _diagonal, run whenever P changes)
            lam_s = lam if not any_cap else 1.0
            if not any_cap:
                s = 0.0
                for i in range(0, d - 1, 2):
                    a0 = 0.0
                    a1 = 0.0
                    for k in range(d):
                        a0 += P[i, k] * phi[k]
                        a1 += P[i + 1, k] * phi[k]
                    px[i] = a0
                    px[i + 1] = a1
                    s += phi[i] * a0 + phi[i + 1] * a1
                if d % 2 == 1:
                    a0 = 0.0
                    for k in range(d):
                        a0 += P[d - 1, k] * phi[k]
                    px[d - 1] = a0
                    s += phi[d - 1] * a0
            else:
                s = _m_phi(P, phi, px, capped, any_cap, inv_lam, half)
            touched = False
            if not 0.0 <= s <= _MAX_WEIGHT * lam_s:
                s, touched = _condition(P, pcap, phi, px, s, capped, any_cap, inv_lam, half, lam_s, halted)
            s += lam_s
            # parameter step L(k) e(k), L = P phi / (lambda + phi' P phi)
            ge = e / s
            # model-stability gate (paper 001, section IV-B): ||L e||_inf < eps, or relative to the model with
            # the regressor scales w (1, max |y|, max |u_j|): ||w o dtheta||_inf < eps ||w o theta||_inf, where the
            # step taken is 0 while halted
            if model_stable == 0:
                step_max = 0.0
                bound = eps
                if smax is not None:
                    g = 0.0 if halted else ge
                    size = 0.0
                    for i in range(d):
                        w = 1.0 if i < trend else (smax[0] if i < off_b else smax[1 + (i - off_b) // nb])
                        step_max = max(step_max, abs(px[i] * g) * w)
                        size = max(size, abs(theta[i]) * w)
                    bound = eps * size
                else:
                    for i in range(d):
                        step_max = max(step_max, abs(px[i] * ge))
                if step_max < bound:
                    stable_cnt += 1
                else:
                    stable_cnt = 0
                if stable_cnt >= n_stable:
                    model_stable = 1
            if model_stable == 1:
                flags |= _MODEL_STABLE
                if unit == 0.0 and e != 0.0 and not halted:
                    # the first nonzero error sets the unit (while halted the statistics are 0 in any unit)
                    unit = 2.0 ** np.floor(np.log2(abs(e)))
                    inv_unit = 1.0 / unit
                en = e * inv_unit     # e in the statistics' unit (exact: a power of two)
                if var_stable == 1:
                    sd = np.sqrt(m2 / (nw - 1))
                    z = (en - mean) / sd if sd > 0 else (np.inf if en != mean else 0.0)
                    if abs(z) > zthr and seen > arm_after:
                        flags |= _ALARM
                        if alarmed == 0:
                            alarmed = 1
                            first_alarm = seen - 1
                            halted = halted or freeze_on_alarm
                if not halted:
                    # Welford (paper 001, eq. 8)
                    nw += 1
                    delta = en - mean
                    mean += delta / nw
                    m2_old = m2
                    m2 += delta * (en - mean)
                    if var_stable == 0 and nw >= 3:
                        v_old = m2_old / (nw - 2)
                        v_new = m2 / (nw - 1)
                        if nw >= var_min and abs(v_new - v_old) <= var_tol * v_old:
                            var_cnt += 1
                        else:
                            var_cnt = 0
                        if var_cnt >= n_stable:
                            var_stable = 1
                    var_out = m2 / (nw - 1) * unit * unit if nw >= 2 else np.nan
                    mean_out = mean * unit
                if var_stable == 1:
                    flags |= _VAR_STABLE
            # parameter and covariance update (eqs. 6-7 / 15-16), skipped once halted: the alarmed sample
            # itself does not enter the model
            if not halted:
                c = 1.0 / np.sqrt(lam_s * s)
                for i in range(d):
                    theta[i] += px[i] * ge
                    px[i] *= c
                if not any_cap:
                    for i in range(d):
                        vi = px[i]
                        for k in range(d):
                            P[i, k] = P[i, k] * inv_lam - vi * px[k]
                    # the check of _diagonal: a variance that is not positive and finite, or one that reaches
                    # its cap, sends P through _diagonal below
                    ok = True
                    for i in range(d):
                        p = P[i, i]
                        ok &= (p > 0.0) & (p < lam * pcap[i])
                    touched |= not ok
                else:
                    for i in range(d):
                        vi = px[i]
                        for k in range(d):
                            f = 1.0 if capped[i] and capped[k] else (half if capped[i] or capped[k] else inv_lam)
                            P[i, k] = P[i, k] * f - vi * px[k]
                    touched = True
                flags |= _UPDATED
            if touched:   # P changed: check it, flag the capped coordinates of the next sample
                any_cap = _diagonal(P, pcap, lam, capped)
        # shift the output history
        for i in range(ybuf.shape[0] - 1, 0, -1):
            ybuf[i] = ybuf[i - 1]
        ybuf[0] = yt
        for i in range(d):
            out_params[t, i] = theta[i]
        out_err[t] = e
        out_var[t] = var_out
        out_mean[t] = mean_out
        out_z[t] = z
        out_flags[t] = flags
    ist[_I_VALID], ist[_I_STABLE_CNT], ist[_I_MODEL_STABLE], ist[_I_NW] = valid, stable_cnt, model_stable, nw
    ist[_I_VAR_CNT], ist[_I_VAR_STABLE], ist[_I_ALARMED], ist[_I_SKIPPED] = var_cnt, var_stable, alarmed, skipped
    ist[_I_SEEN], ist[_I_FIRST_ALARM], ist[_I_FROZEN] = seen, first_alarm, frozen
    fst[_F_MEAN], fst[_F_M2], fst[_F_UNIT] = mean, m2, unit


@dataclass(frozen=True, eq=False)
class RecursiveARXResults:
    """Histories of one :meth:`RecursiveARX.run` call, in the caller's data kind.

    Attributes
    ----------
    params : ndarray, DataFrame or DataArray, shape (nobs, d)
        Parameter estimate after each sample (row ``t`` is ``theta(t)``), columns named as in ``param_names``.
    resid : ndarray, Series or DataArray, shape (nobs,)
        A-priori prediction errors ``e(t) = y(t) - phi(t)' theta(t-1)`` (paper 001, eq. 4); NaN for samples
        without a complete regressor (start-up, after a skipped non-finite sample) and for skipped samples.
    variance : same kind, shape (nobs,)
        Welford sample variance ``s_n^2`` of the prediction errors after each sample (NaN before the model is
        stable and while fewer than two errors are counted).
    mean : same kind, shape (nobs,)
        Welford running mean of the prediction errors after each sample (NaN before the model is stable).
    zscore : same kind, shape (nobs,)
        ``(e(t) - mean) / s`` with the statistics before sample ``t``; NaN until model and variance are stable;
        ``+-inf`` when every error so far was equal (``s = 0``: a frozen sensor, an exactly predicted signal) and
        ``e(t)`` differs from them (an alarm), 0 when it does not.
    model_stable, variance_stable, alarm, skipped : ndarray of bool, shape (nobs,)
        Per-sample flags (plain numpy arrays).
    first_alarm : int or None
        Position (counted from the first sample ever given to the estimator) of the first alarm.
    first_alarm_time : object or None
        Index label of the first alarm when it falls inside this run and the input had an index.
    n_skipped : int
        Non-finite samples skipped so far (``nonfinite="skip"``).
    """

    params: Any
    resid: Any
    variance: Any
    mean: Any
    zscore: Any
    model_stable: np.ndarray
    variance_stable: np.ndarray
    alarm: np.ndarray
    skipped: np.ndarray
    first_alarm: int | None
    first_alarm_time: Any
    n_skipped: int
    param_names: tuple
    start: int

    @cached_property
    def nobs(self) -> int:
        """Number of samples in this run."""
        return int(self.alarm.shape[0])


@dataclass(frozen=True, eq=False)
class RecursiveARXState:
    """Snapshot of everything a :class:`RecursiveARX` needs to resume: from :meth:`RecursiveARX.get_state`,
    for :meth:`RecursiveARX.set_state`.

    The arrays are read-only copies, so one snapshot can be restored any number of times. The options
    (orders, forgetting factor, thresholds, ...) are not part of the state: a snapshot is restored into the
    estimator it came from or one built with the same options.

    Attributes
    ----------
    theta : ndarray, shape (d,)
        Parameter estimate.
    P : ndarray, shape (d, d)
        Covariance matrix of the recursion.
    y_history : ndarray, shape (max(na, 1),)
        Past outputs, most recent first (``y[t-1], y[t-2], ...``).
    u_history : ndarray, shape (n_inputs, max(nk + nb, 1))
        Past inputs per input, most recent first.
    counters : ndarray of int64, shape (11,)
        Sample counters and flags: samples seen and skipped, run of valid samples, the stability gates and
        their counters, the number of errors in the running statistics, alarm state, first alarm, frozen.
    error_stats : ndarray, shape (3,)
        Welford running mean and sum of squared deviations of the prediction errors, in units of the third
        entry (a power of two set by the first nonzero error; 0 before).
    P_bound : ndarray, shape (d,)
        Anti-windup bound of each variance ``P[i, i]``: the diagonal of ``P0``, scaled down with ``P`` by a
        dominant sample (see :class:`RecursiveARX`, Notes).
    regressor_scales : ndarray, shape (1 + n_inputs,)
        Largest ``|y|`` and largest ``|u_j|`` of every input over the finite samples so far: the regressor scales
        of ``gate="relative"`` (zeros under ``gate="absolute"``, which does not keep them).
    """

    theta: np.ndarray
    P: np.ndarray
    y_history: np.ndarray
    u_history: np.ndarray
    counters: np.ndarray
    error_stats: np.ndarray
    P_bound: np.ndarray
    regressor_scales: np.ndarray


class RecursiveARX:
    r"""ARX model estimated online by recursive least squares with forgetting and Z-score alarms.

    Parameters
    ----------
    na : int
        Number of output lags (``>= 0``).
    nb : int
        Number of input coefficients per input (``>= 0``).
    nk : int, default 0
        Input delay in samples (``>= 0``); ``nk = 0`` lets ``u[t]`` explain ``y[t]``.
    forgetting_factor : float, default 1.0
        ``lambda`` in [0.5, 1]; 1 gives ordinary recursive least squares (paper 001, eqs. 4-7), below 1 the
        exponentially weighted version of paper 002, eqs. 14-16 (memory about ``1 / (1 - lambda)`` samples, at
        least two).
    P0 : float or ndarray, default 1e4
        Initial covariance ``P(0)``: a positive scalar (times the identity) or a symmetric positive-definite
        ``(d, d)`` matrix, with diagonal at most ``1e100``. Large values make the estimate forget the initial
        ``theta0`` quickly. Above ``1e4`` (its largest absolute row sum :math:`\|P_0\|_\infty`) it lowers the
        largest sample accepted below ``1e152``: :math:`\|P_0\|_\infty\, x^2 \le 10^{308}` (Notes, *Scale*).
    n_inputs : int, default 1
        Number of input signals.
    trend : {"n", "c"}, default "n"
        "c" adds a constant as the first parameter.
    theta0 : array_like, Series or ARXResults, optional
        Initial parameters (default zeros): an array in the order of :attr:`param_names` (``[c, a_1..a_na, b_0,
        b_1, ...]``, grouped by kind); a Series labelled with :attr:`param_names`, or with the labels of
        ``ARXResults.params`` (``const, a1, b1.<input>, a2, ...``, grouped by lag), taken by label; or the
        :class:`~tsfdi.models.arx.ARXResults` of a batch fit of the same orders (``na``, ``nb``, ``nk``,
        ``n_inputs``, ``trend``), whose coefficients seed the estimate. The *array* ``ARXResults.params`` is
        grouped by lag, another order: pass the results themselves.
    threshold : float, default 4.5
        Z-score alarm threshold (paper 001 uses 4.5, a two-sided 99.99932 % Gaussian interval).
    eps : float, default 1e-2
        Model-stability bound: on the parameter step ``||L(k) e(k)||_inf`` in parameter units
        (``gate="absolute"``), or on the step as a fraction of the parameters (``gate="relative"``; see Notes).
    gate : {"absolute", "relative"}, default "absolute"
        Model-stability gate: paper 001's absolute bound on the parameter step, or the scale-free one of the
        Notes (the same for any units of ``y`` and ``u``).
    stable_samples : int, default 25
        Consecutive samples the stability conditions must hold (model and variance).
    variance_tol : float, default 0.01
        Relative change of the running variance per sample below which it counts as stable.
    min_variance_samples : int, default 50
        Minimum number of prediction errors in the running variance before it can be stable.
    freeze_on_alarm : bool, default False
        Freeze parameters, ``P`` and error statistics from the first alarm on (paper 002: adaptation halted
        on alarm), as :meth:`freeze` does on request.
    nonfinite : {"raise", "skip"}, default "raise"
        Policy for NaN / inf in ``y`` or ``u``: "raise" raises ``ValueError`` naming the sample; "skip" leaves
        the sample out (no update, NaN error), counts it in ``n_skipped`` and restarts regression once the
        regressor again holds only finite samples.
    arm_after : int, default 0
        Baseline phase: no Z-score alarm among the first ``arm_after`` samples given to the estimator, even
        when the gates are open (the model and the error statistics keep learning). On a real vehicle this
        is the settling time after take-off or after the switch to autonomous flight.

    Raises
    ------
    ValueError
        An option outside its range (named), or orders whose arrays would exceed 2 GiB
        (:data:`~tsfdi.models.lstsq.MAX_VALUES`): ``P`` holds ``d**2`` values (``d <= 16384``), the input
        history ``n_inputs * (nk + nb)``; checked before anything is allocated.
    TypeError
        A non-integer order or a non-numeric option.

    Notes
    -----
    Per sample (paper 001, eqs. 4-7; paper 002, eqs. 14-16)::

        e(k)     = y(k) - phi(k)' theta(k-1)
        L(k)     = P(k-1) phi(k) / (lambda + phi(k)' P(k-1) phi(k))
        theta(k) = theta(k-1) + L(k) e(k)
        P(k)     = P(k-1) / lambda - v v',   v = P(k-1) phi(k) / sqrt(lambda (lambda + phi(k)' P(k-1) phi(k)))

    which equals ``P(k) = (lambda P(k-1)^-1 + phi phi')^-1``. With ``P(0) = p0 I`` the estimate after ``N``
    samples minimises ``sum_t lambda^(N-t) e_t^2 + lambda^N |theta - theta0|^2 / p0`` (for ``lambda < 1`` the
    prior term is weighted by the anti-windup rule below instead of ``lambda^N``).

    **Model-stability gate.** A sample with a prediction error passes the gate when

    .. math:: \|L(k)\,e(k)\|_\infty < \epsilon \qquad (\texttt{gate="absolute"})

    (paper 001, section IV-B: when the parameter step stays below :math:`\epsilon` "for some time (with
    :math:`\epsilon` set to a small positive number), the model can be considered as stable for fault
    detection"), or, with :math:`\Delta\theta(k) = \theta(k) - \theta(k-1)` (the step taken: 0 while adaptation
    is halted) and :math:`D(k)` the diagonal of regressor scales -- 1 for the constant, :math:`\max_{t \le k}|y(t)|`
    for every :math:`a_i`, :math:`\max_{t \le k}|u_j(t)|` for every :math:`b_{ji}`, maxima over the finite
    samples --

    .. math:: \|D(k)\,\Delta\theta(k)\|_\infty < \epsilon\, \|D(k)\,\theta(k-1)\|_\infty
              \qquad (\texttt{gate="relative"}).

    The model is stable once ``stable_samples`` consecutive samples with a prediction error pass (samples
    without one neither count nor break the run). The absolute bound is in parameter units: a gain from a
    command in rad/s to a rate in deg/s is 57 times that to a rate in rad/s, so one ``eps`` arms in one set of
    units and never in another, and it passes at once while the estimate is still near ``theta0 = 0`` on quiet
    data. In the relative gate no term of the prediction :math:`\phi(k)'\theta` moves by more than the fraction
    :math:`\epsilon` of the largest term; both sides are in the units of ``y``, so it is unchanged when ``y`` and
    each input are rescaled, together or separately (the estimate itself follows when ``P0`` is rescaled with
    them, :math:`P_0 \propto 1/c^2` per regressor). A model that stays at ``theta = 0`` never passes it.

    **Numerical safeguards** (none acts on well-excited data of moderate scale):

    * *Covariance windup*: a coordinate whose variance ``P[i, i] / lambda`` would exceed its initial value
      ``P0[i, i]`` is not forgotten at that sample (``P <- F o P - v v'`` with ``F[i, k] = 1 / lambda`` for two
      free coordinates, ``1 / sqrt(lambda)`` for one, 1 for none), so the estimator is never less certain
      about a parameter than at the start. Without it, a parameter that the data do not excite (an input at
      rest, a frozen sensor) has its variance grow as ``lambda^-t`` until it overflows (after
      ``~700 / (1 - lambda)`` samples) and the estimate turns NaN. It also keeps the prior from being forgotten
      before the data have excited a coordinate, so with ``lambda < 1`` the start-up transient differs slightly
      from the plain recursion (by far less than the estimation noise).
    * *Dominant samples*: when a sample would carry more than ``1e12`` times the information of ``P``
      (``phi' P phi > 1e12 lambda``: data far larger than ``1 / sqrt(P0)``, e.g. raw sensor counts with
      ``P0 = 1e4``), ``P`` and its anti-windup bound are first scaled down to make that ratio exactly ``1e12``.
      The symmetric update would otherwise lose all of ``P``'s digits in the direction of ``phi`` and turn it
      indefinite (NaN parameters from then on); the prior it drops weighs less than ``1e-12`` of the sample.
    * *Rounding*: a covariance that rounding has made indefinite (``phi' P phi < 0`` or a negative variance;
      its condition number beyond ``~1e16``, e.g. with collinear regressors and strong forgetting) gets a
      ridge on the diagonal (``2**-40`` times its largest variance plus twice the deficit); one that is no
      longer finite is reset to ``diag(P_bound)``, keeping ``theta``.
    * *Scale*: a sample :math:`x` (output or input) is accepted when

      .. math:: |x| \le 10^{152} \quad\text{and}\quad \|P_0\|_\infty\, x^2 \le 10^{308},
                \qquad \|P_0\|_\infty = \max_i \textstyle\sum_k |P_0[i, k]|

      (``P0`` itself for a scalar), so up to ``1e152`` for ``P0 <= 1e4`` (the default) and up to
      :math:`10^{152} \sqrt{10^4 / \|P_0\|_\infty}` above, e.g. ``1e129`` for ``P0 = 1e50``, ``1e104`` for
      ``P0 = 1e100``; ``ValueError`` beyond, naming ``y`` or ``u``, the sample and, for the joint bound, ``P0``.
      The joint bound keeps every product :math:`\phi_i (P\phi)_i` of :math:`\phi'P\phi` finite. A sum of them
      that overflows is handled as a dominant sample, but the compiled loop (``fastmath``) may form the
      rescaling's :math:`\sum_i (\phi_i / \max_k|\phi_k|)\,(P\phi)_i` as :math:`\sum_i \phi_i (P\phi)_i /
      \max_k|\phi_k|`: a product that overflows turns the rescaling factor to 0, ``P`` collapses to 0 and the
      estimate stays at ``theta0`` without a warning (observed as soon as one product passes the largest double,
      ``1.8e308``, e.g. ``P0 = 1e50`` with samples of ``1e130``). At the first samples :math:`P = P_0` and

      .. math:: |\phi_i (P_0 \phi)_i| \le |\phi_i| \sum_k |P_0[i, k]|\,|\phi_k| \le \|P_0\|_\infty\, x^2
                \le 10^{308};

      later the data have shrunk ``P`` (:math:`P(k) \preceq P(k-1)` for :math:`\lambda = 1`, each variance capped
      at its ``P0`` value for :math:`\lambda < 1`). The tests check the estimate against batch least squares for
      scalar and matrix ``P0`` from ``1e-4`` to ``1e100`` and samples from ``1e-100`` to ``1e152``, on both sides
      of the bound. The error statistics are kept in units of a power of two set by the first nonzero
      error, so the Z-scores do not depend on the data's scale (``variance`` may underflow to 0 for errors below
      ``~1e-154``).

    The loop is compiled with numba (``cache=True``); :meth:`update` and :meth:`run` share it, so feeding a
    stream sample by sample, in chunks or at once gives identical results.

    References
    ----------
    .. [1] A. Keipour, M. Mousaei, S. Scherer, "Automatic real-time anomaly detection for autonomous aerial
       vehicles", ICRA 2019 (paper 001), eqs. 2-8, section IV.
    .. [2] S. Hansen, M. Blanke, J. Adrian, "A framework for rapid diagnosis of critical faults in UAVs"
       (paper 002), eqs. 14-16.
    """

    def __init__(self, na: int, nb: int, nk: int = 0, forgetting_factor: float = 1.0, P0: Any = 1e4,
                 n_inputs: int = 1, *, trend: str = "n", theta0: Any = None, threshold: float = 4.5,
                 eps: float = 1e-2, gate: str = "absolute", stable_samples: int = 25, variance_tol: float = 0.01,
                 min_variance_samples: int = 50, freeze_on_alarm: bool = False, nonfinite: str = "raise",
                 arm_after: int = 0):
        self.na = int_like(na, "na", minimum=0)
        self.nb = int_like(nb, "nb", minimum=0)
        self.nk = int_like(nk, "nk", minimum=0)
        self.n_inputs = int_like(n_inputs, "n_inputs", minimum=1)
        self.trend = option(trend, "trend", ("n", "c"))
        self.forgetting_factor = float_like(forgetting_factor, "forgetting_factor", minimum=0.5, maximum=1.0)
        self.threshold = float_like(threshold, "threshold", minimum=0.0, strict_min=True)
        self.eps = float_like(eps, "eps", minimum=0.0, strict_min=True)
        self.gate = option(gate, "gate", ("absolute", "relative"))
        self.stable_samples = int_like(stable_samples, "stable_samples", minimum=1)
        self.variance_tol = float_like(variance_tol, "variance_tol", minimum=0.0)
        self.min_variance_samples = int_like(min_variance_samples, "min_variance_samples", minimum=3)
        if not isinstance(freeze_on_alarm, (bool, np.bool_)):
            raise TypeError(f"freeze_on_alarm must be a bool, got {freeze_on_alarm!r}")
        self.freeze_on_alarm = bool(freeze_on_alarm)
        self.nonfinite = option(nonfinite, "nonfinite", ("raise", "skip"))
        self.arm_after = int_like(arm_after, "arm_after", minimum=0)
        d = self.n_params
        if d == 0:
            raise ValueError("na, nb and trend give a model without parameters: set na > 0, nb > 0 or trend='c'")
        check_size(d * d, f"na={self.na}, nb={self.nb}, n_inputs={self.n_inputs}: the covariance P ({d:,} x {d:,})")
        check_size(self.n_inputs * (self.nk + self.nb), f"nk={self.nk}, nb={self.nb}, n_inputs={self.n_inputs}: "
                   f"the input history ({self.n_inputs:,} x {self.nk + self.nb:,})")
        if np.ndim(P0) == 0:
            p0 = float_like(P0, "P0", minimum=0.0, strict_min=True, maximum=MAX_P0)
            self._P0 = np.eye(d) * p0
        else:
            try:
                P0 = np.asarray(P0, dtype=np.float64)
            except (TypeError, ValueError):
                raise TypeError(f"P0 must be a positive scalar or a real ({d}, {d}) matrix, got {P0!r}") from None
            if P0.shape != (d, d):
                raise ValueError(f"P0 must be a positive scalar or a ({d}, {d}) matrix, got shape {P0.shape}")
            if not np.isfinite(P0).all() or not np.allclose(P0, P0.T, rtol=1e-12, atol=0.0):
                raise ValueError("P0 must be a finite symmetric matrix")
            if np.diag(P0).max() > MAX_P0:
                raise ValueError(f"P0 must have a diagonal of at most {MAX_P0:g}, got {np.diag(P0).max():g}")
            try:
                np.linalg.cholesky(P0)
            except np.linalg.LinAlgError:
                raise ValueError("P0 must be positive definite") from None
            self._P0 = 0.5 * (P0 + P0.T)
        # largest sample magnitude: ||P0||_inf * x**2 <= MAX_P0_SAMPLE2 (Notes, Scale)
        self._p0_norm = float(np.abs(self._P0).sum(axis=1).max())       # ||P0||_inf
        self._max_sample = min(MAX_SAMPLE, float(np.sqrt(MAX_P0_SAMPLE2 / self._p0_norm)))
        if theta0 is None:
            self._theta0 = np.zeros(d)
        else:
            theta0 = self._initial_params(theta0)
            if theta0.shape != (d,) or not np.isfinite(theta0).all():
                raise ValueError(f"theta0 must hold {d} finite values, got shape {theta0.shape}")
            self._theta0 = theta0.copy()
        self.reset()

    def _arx_order(self) -> np.ndarray:
        """Positions in ``ARXResults.params`` (grouped by lag) of the parameters in the order of ``theta``."""
        const, k = self.trend == "c", self.n_inputs
        pos, at = {}, int(const)
        for g in range(1, max(self.na, self.nb) + 1):
            if g <= self.na:
                pos[("a", g)], at = at, at + 1
            if g <= self.nb:
                for j in range(k):
                    pos[("b", j, g)], at = at, at + 1
        order = [0] * const + [pos[("a", g)] for g in range(1, self.na + 1)]
        return np.array(order + [pos[("b", j, g)] for j in range(k) for g in range(1, self.nb + 1)], dtype=np.intp)

    def _initial_params(self, theta0: Any) -> np.ndarray:
        """``theta0`` in the order of ``theta``: an ARX / AR fit or an ARX-labelled Series mapped, else as given."""
        if isinstance(theta0, ScalarOutputResults):      # an ARX (or AR, for nb = 0) fit
            m = theta0.model
            mine = (self.na, self.nb, self.nk if self.nb else 0, self.n_inputs if self.nb else 0, self.trend)
            theirs = (m.na, m.nb, m.nk if m.nb else 0, m.n_inputs, m.trend)
            if mine != theirs:
                raise ValueError(f"theta0 is a {type(m).__name__} fit of other orders: (na, nb, nk, n_inputs, trend) "
                                 f"= {theirs}, this estimator has {mine}")
            return np.asarray(theta0.params, dtype=np.float64)[self._arx_order()]
        if isinstance(theta0, pd.Series):
            labels = [str(c) for c in theta0.index]
            if labels == list(self.param_names):
                return theta0.to_numpy(dtype=np.float64)
            const = ["const"] if self.trend == "c" else []
            arx = [lab.split(".")[0] for lab in labels]       # "b1.<input>" -> "b1"
            expected = const + [n for g in range(1, max(self.na, self.nb) + 1) for n in
                                ([f"a{g}"] if g <= self.na else []) + [f"b{g}"] * (self.n_inputs * (g <= self.nb))]
            if arx != expected:
                raise ValueError(f"theta0 is labelled {labels}: neither this estimator's parameters "
                                 f"{list(self.param_names)} nor those of an ARX fit of the same orders; pass an "
                                 "array in the order of param_names, or the ARXResults")
            return theta0.to_numpy(dtype=np.float64)[self._arx_order()]
        if isinstance(theta0, (str, bytes)):
            raise TypeError(f"theta0 must hold real numbers, got {theta0!r}")
        try:
            return np.asarray(theta0, dtype=np.float64).ravel()
        except (TypeError, ValueError):
            raise TypeError(f"theta0 must hold real numbers, got {type(theta0).__name__}") from None

    # ------------------------------------------------------------------ state
    @property
    def n_params(self) -> int:
        """Parameter dimension ``d = [trend] + na + n_inputs * nb``."""
        return (self.trend == "c") + self.na + self.n_inputs * self.nb

    @property
    def param_names(self) -> tuple:
        """Names of the parameters, in the order of ``theta``."""
        names = ["const"] if self.trend == "c" else []
        names += [f"a{i + 1}" for i in range(self.na)]
        for j in range(self.n_inputs):
            pre = "b" if self.n_inputs == 1 else f"b{j}_"
            names += [f"{pre}{k + 1}" for k in range(self.nb)]
        return tuple(names)

    @property
    def max_lag(self) -> int:
        """Samples before the first complete regressor: ``max(na, nk + nb - 1)`` (0 without lags), as
        :attr:`tsfdi.ARX.max_lag`; ``run`` gives NaN prediction errors for the first ``max_lag`` samples."""
        return max(self.na, self.nk + self.nb - 1 if self.nb else 0)

    def regressors(self, y: Any, u: Any = None) -> Any:
        r"""The regressor :math:`\varphi(t)` of every sample of a record ``y``, ``u`` that has a complete one.

        Row ``t - max_lag`` is :math:`\varphi(t) = [1,\ -y(t-1), \dots, -y(t-n_a),\ u_0(t-n_k), \dots,
        u_0(t-n_k-n_b+1),\ u_1(t-n_k), \dots]'` (module docstring; the constant with ``trend="c"`` only), in the
        order of ``theta`` and :attr:`param_names`, so that the a-priori error of :meth:`run` on the same record is
        ``e(t) = y(t) - phi(t)' theta(t-1)``. These are the regressors of
        :class:`~tsfdi.detection.glrt.ParameterGLRT` (paper 002's GLRT on parameter changes). The record is
        taken on its own: the estimator's state (past samples given to :meth:`update` / :meth:`run`) is not used
        and not changed.

        Parameters
        ----------
        y : array_like, Series or DataArray, shape (nobs,)
            Output signal, more than :attr:`max_lag` samples.
        u : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, n_inputs), optional
            Input signal(s), same length as ``y`` (required when ``nb > 0``).

        Returns
        -------
        ndarray, DataFrame or DataArray, shape (nobs - max_lag, d)
            Samples ``max_lag .. nobs - 1`` (the first :attr:`max_lag` have no complete regressor), in the kind of
            ``y`` with its index from position ``max_lag`` and the columns :attr:`param_names`; align ``y`` and
            the parameter history with ``[max_lag:]``.

        Raises
        ------
        ValueError
            ``y`` with at most :attr:`max_lag` samples, ``u`` of another length or number of inputs, NaN / inf
            in ``y`` or ``u`` (named, with the first sample), or regressors of more than 2 GiB.
        TypeError
            Non-numeric (or bool) ``y`` / ``u``.
        """
        lag = self.max_lag
        sy = as_signal(y, "y", vector=False, min_nobs=lag + 1, allow_constant=True)
        yv = sy.values[:, 0]
        n = yv.shape[0]
        check_size(n * self.n_params, f"y with {n:,} samples: the regressors ({n:,} x {self.n_params:,}); take them "
                   "in chunks")
        uv = self._prepare_u(u, sy)
        bad = ~np.isfinite(uv).all(axis=1)
        if bad.any():
            raise ValueError(f"u contains NaN/inf (first at sample {int(np.flatnonzero(bad)[0])})")
        cols = [np.ones(n - lag)] if self.trend == "c" else []
        cols += [0.0 - yv[lag - i:n - i] for i in range(1, self.na + 1)]      # 0.0 - : no -0.0
        cols += [uv[lag - self.nk - k:n - self.nk - k, j] for j in range(self.n_inputs) for k in range(self.nb)]
        phi = np.column_stack(cols) if cols else np.empty((n - lag, 0))
        return sy.wrap(phi, lag, channels=list(self.param_names), vector=True)

    def reset(self) -> None:
        """Return to the initial state (``theta0``, ``P0``, empty history, no alarm)."""
        self.theta_ = self._theta0.copy()
        self.P_ = self._P0.copy()
        self._ybuf = np.zeros(max(self.na, 1))
        self._ubuf = np.zeros((self.n_inputs, max(self.nk + self.nb, 1)))
        self._ist = np.zeros(11, dtype=np.int64)
        self._ist[_I_FIRST_ALARM] = -1
        self._fst = np.zeros(3)
        self._pcap = np.diag(self._P0).copy()   # anti-windup bound of each variance (see Notes)
        self._smax = np.zeros(1 + self.n_inputs)     # regressor scales of the relative gate (see Notes)

    def get_state(self) -> RecursiveARXState:
        """Snapshot of the estimator state (deep copies): parameters, ``P`` and its anti-windup bound, the
        regressor buffers, the sample counters, the stability / alarm / frozen flags, the Welford error
        statistics and the regressor scales of the relative gate.

        ``s = m.get_state(); m.run(b); m.set_state(s); m.run(b)`` gives identical outputs from both runs.
        """
        def frozen_copy(a: np.ndarray) -> np.ndarray:
            c = a.copy()
            c.setflags(write=False)
            return c

        return RecursiveARXState(theta=frozen_copy(self.theta_), P=frozen_copy(self.P_),
                                 y_history=frozen_copy(self._ybuf), u_history=frozen_copy(self._ubuf),
                                 counters=frozen_copy(self._ist), error_stats=frozen_copy(self._fst),
                                 P_bound=frozen_copy(self._pcap), regressor_scales=frozen_copy(self._smax))

    def set_state(self, state: RecursiveARXState) -> None:
        """Restore a snapshot taken by :meth:`get_state` (of this estimator or one with the same options).

        The values are copied into the estimator's own arrays (``theta_`` and ``P_`` keep their identity);
        the snapshot itself is not modified and can be restored again.
        """
        if not isinstance(state, RecursiveARXState):
            raise TypeError(f"state must be a RecursiveARXState from get_state(), got {type(state).__name__}")
        pairs = ((self.theta_, state.theta, "theta"), (self.P_, state.P, "P"),
                 (self._ybuf, state.y_history, "y_history"), (self._ubuf, state.u_history, "u_history"),
                 (self._ist, state.counters, "counters"), (self._fst, state.error_stats, "error_stats"),
                 (self._pcap, state.P_bound, "P_bound"), (self._smax, state.regressor_scales, "regressor_scales"))
        for mine, theirs, name in pairs:
            if np.shape(theirs) != mine.shape:
                raise ValueError(f"state.{name} has shape {np.shape(theirs)}, this estimator needs {mine.shape}: "
                                 "the state comes from an estimator with other orders / inputs")
        for mine, theirs, _ in pairs:
            np.copyto(mine, theirs)

    @property
    def nobs(self) -> int:
        """Samples given to the estimator since construction or :meth:`reset`."""
        return int(self._ist[_I_SEEN])

    @property
    def n_skipped(self) -> int:
        """Non-finite samples skipped so far."""
        return int(self._ist[_I_SKIPPED])

    @property
    def model_stable(self) -> bool:
        """Whether the model-stability gate (``gate``, see Notes) has held for ``stable_samples`` samples."""
        return bool(self._ist[_I_MODEL_STABLE])

    @property
    def variance_stable(self) -> bool:
        """Whether the running error variance has settled (Z-score alarms are armed)."""
        return bool(self._ist[_I_VAR_STABLE])

    @property
    def alarmed(self) -> bool:
        """Whether an alarm has been raised."""
        return bool(self._ist[_I_ALARMED])

    @property
    def frozen(self) -> bool:
        """Whether adaptation was stopped by :meth:`freeze` (an alarm under ``freeze_on_alarm`` stops it too
        but shows in :attr:`alarmed`, not here)."""
        return bool(self._ist[_I_FROZEN])

    def freeze(self) -> None:
        """Stop adapting from the next sample on: parameters, ``P`` and the error statistics stay as they are,
        prediction errors and Z-scores are still computed (used by detectors that alarm on a statistic other
        than the model's own Z-score: paper 002's adaptation halted on their alarm; ``freeze_on_alarm`` does the
        same on the model's own first alarm). :meth:`unfreeze` (or :meth:`reset`) undoes it."""
        self._ist[_I_FROZEN] = 1

    def unfreeze(self) -> None:
        """Adapt again from the next sample on, from the parameters, ``P`` and error statistics held while frozen
        (paper 002 halts adaptation only while an alarm lasts). A model frozen by ``freeze_on_alarm`` stays frozen:
        its alarm is part of its state."""
        self._ist[_I_FROZEN] = 0

    @property
    def first_alarm(self) -> int | None:
        """Position of the first alarm among all samples seen, or None."""
        k = int(self._ist[_I_FIRST_ALARM])
        return None if k < 0 else k

    @property
    def error_mean(self) -> float:
        """Running mean of the prediction errors (Welford)."""
        return float(self._fst[_F_MEAN] * (self._fst[_F_UNIT] or 1.0))

    @property
    def error_variance(self) -> float:
        """Running sample variance ``s_n^2`` of the prediction errors (NaN with fewer than two)."""
        nw = int(self._ist[_I_NW])
        unit = self._fst[_F_UNIT] or 1.0
        return float(self._fst[_F_M2] / (nw - 1) * unit * unit) if nw >= 2 else float("nan")

    # ------------------------------------------------------------------ processing
    def _no_input(self, n: int) -> np.ndarray:
        """Zero inputs for ``u=None``, which only a model without input coefficients accepts."""
        if self.nb > 0:
            raise ValueError("u is required when nb > 0")
        return np.zeros((n, self.n_inputs))

    def _prepare_u(self, u: Any, sy: Signal, name: str = "u") -> np.ndarray:
        """``u`` as a float64 ``(nobs, n_inputs)`` array paired with ``sy``: same length, and the same index when
        both carry one (never aligned silently)."""
        n = sy.nobs
        if u is None:
            return self._no_input(n)
        if self.n_inputs == 1:
            su = as_signal(u, name, min_nobs=1, allow_constant=True, finite=False)
        else:
            su = as_signal(u, name, vector=True, min_nobs=1, allow_constant=True, finite=False)
        uv = su.values
        if uv.shape[1] != self.n_inputs:
            raise ValueError(f"{name} must have n_inputs={self.n_inputs} column(s), got {uv.shape[1]}")
        if uv.shape[0] != n:
            raise ValueError(f"u and y must have the same length, got len(u)={uv.shape[0]} and len(y)={n}")
        check_paired(sy, su, ("y", name))
        return np.ascontiguousarray(uv)

    def _check_samples(self, yv: np.ndarray, uv: np.ndarray) -> None:
        """Non-finite samples under ``nonfinite="raise"`` and samples beyond ``MAX_SAMPLE`` or the joint bound with
        ``P0`` (Notes, *Scale*): ``ValueError``."""
        top = self._max_sample
        if all(v.size == 0 or (-top <= v.min() and v.max() <= top) for v in (yv, uv)):
            return      # every sample finite and in range (a NaN fails both comparisons): two reductions, no copy
        if self.nonfinite == "raise":
            bad_y = ~np.isfinite(yv)
            bad_u = ~np.isfinite(uv).all(axis=1)
            if bad_y.any() or bad_u.any():
                which = "y" if bad_y.any() else "u"
                first = int(np.flatnonzero(bad_y | bad_u)[0])
                raise ValueError(f"{which} contains NaN/inf (first at sample {first} of this call); pass "
                                 "nonfinite='skip' to skip and count such samples")
        for name, v in (("y", yv), ("u", uv)):
            big = np.abs(v) > top
            big &= ~np.isinf(v)     # NaN compares False; inf is a non-finite sample, not a large one
            if big.any():
                first = int(np.argwhere(big)[0, 0])
                where = (f"{name} has a sample of magnitude {np.abs(v[first]).max():.3g} (first at sample {first} of "
                         f"this call)")
                if top == MAX_SAMPLE:
                    raise ValueError(f"{where}: samples must lie within +-{MAX_SAMPLE:g}; rescale {name}")
                raise ValueError(f"{where}: P0 (largest absolute row sum {self._p0_norm:.3g}) allows samples within "
                                 f"+-{top:.3g} only, so that P0 * sample**2 <= {MAX_P0_SAMPLE2:g} (RecursiveARX "
                                 f"Notes, Scale); rescale {name} or lower P0")

    def _call(self, yv: np.ndarray, uv: np.ndarray):
        n = yv.shape[0]
        d = self.n_params
        out_params = np.empty((n, d))
        out_err = np.empty(n)
        out_var = np.empty(n)
        out_mean = np.empty(n)
        out_z = np.empty(n)
        out_flags = np.empty(n, dtype=np.uint8)
        smax = self._smax if self.gate == "relative" else None      # None: compiled without the relative gate
        _rls_kernel(yv, uv, self.na, self.nb, self.nk, int(self.trend == "c"), self.forgetting_factor,
                    self.freeze_on_alarm, self.eps, self.stable_samples, self.variance_tol,
                    self.min_variance_samples, self.threshold, self.arm_after, self._pcap, self.theta_, self.P_,
                    self._ybuf, self._ubuf, self._ist, self._fst, smax, out_params, out_err, out_var, out_mean, out_z,
                    out_flags)
        return out_params, out_err, out_var, out_mean, out_z, out_flags

    def update(self, y: float, u: Any = None) -> float:
        """Process one sample and return its a-priori prediction error ``y - phi' theta`` (eq. 4).

        Parameters
        ----------
        y : float
            Output sample (a real number: not a bool, not a string).
        u : float or array_like of length ``n_inputs``
            Input sample(s) (real numbers).

        Returns
        -------
        float
            The prediction error, NaN during start-up (incomplete regressor) or for a skipped sample.

        Raises
        ------
        TypeError
            ``y`` or ``u`` not real numbers (bools and strings are refused, as :meth:`run` refuses them).
        ValueError
            ``u`` with another number of inputs, NaN / inf under ``nonfinite="raise"``, or a sample beyond
            ``+-1e152`` (less with ``P0`` above ``1e4``, Notes, *Scale*); the estimator is left unchanged.
        """
        if isinstance(y, (bool, np.bool_, str, bytes)) or np.asarray(y).dtype.kind not in "iuf" or np.ndim(y):
            raise TypeError(f"y must be a real number, got {y!r} ({type(y).__name__})")
        yf = float(y)
        yv = np.array([yf])
        if u is None:
            uv = self._no_input(1)
        else:
            try:
                uv = np.asarray(u)
                if uv.dtype.kind not in "iuf":
                    raise TypeError
                uv = uv.astype(np.float64).reshape(1, -1)
            except (TypeError, ValueError):
                raise TypeError(f"u must be real number(s), got {u!r}") from None
            if uv.shape[1] != self.n_inputs:
                raise ValueError(f"u must hold n_inputs={self.n_inputs} value(s), got {uv.shape[1]}")
        if not (abs(yf) <= self._max_sample) or not (np.abs(uv) <= self._max_sample).all():   # rare: the full check
            self._check_samples(yv, uv)
        _, err, _, _, _, _ = self._call(yv, np.ascontiguousarray(uv))
        return float(err[0])

    def run(self, y: Any, u: Any = None) -> RecursiveARXResults:
        """Process whole arrays (continuing from the current state) and return the histories.

        Parameters
        ----------
        y : array_like, Series or DataArray, shape (nobs,)
            Output signal.
        u : array_like, Series, DataFrame or DataArray, shape (nobs,) or (nobs, n_inputs)
            Input signal(s), same length as ``y``.

        Returns
        -------
        RecursiveARXResults
            Histories wrapped in ``y``'s data kind (index kept).

        Raises
        ------
        ValueError
            ``y`` / ``u`` of different lengths or with NaN / inf under ``nonfinite="raise"``, a sample beyond
            ``+-1e152`` (less with ``P0`` above ``1e4``, Notes, *Scale*), or a parameter history of more than
            2 GiB (run a long signal in chunks: the results are identical); nothing is processed.
        TypeError
            Non-numeric (or bool) ``y`` / ``u``.
        """
        sy = as_signal(y, "y", vector=False, min_nobs=1, allow_constant=True, finite=False)
        yv = np.ascontiguousarray(sy.values[:, 0])
        uv = self._prepare_u(u, sy)
        n, d = yv.shape[0], self.n_params
        check_size(n * d, f"y with {n:,} samples: the parameter history ({n:,} x {d:,}); run it in chunks")
        self._check_samples(yv, uv)
        start = self.nobs
        alarm_before = self.first_alarm
        params, err, var, mean, z, flags = self._call(yv, uv)
        names = self.param_names
        first = self.first_alarm
        first_time = None
        if first is not None and alarm_before is None:
            pos = first - start
            first_time = sy.index[pos] if sy.index is not None else pos
        wrap = sy.wrap
        return RecursiveARXResults(
            params=wrap(params, 0, channels=list(names), vector=True),
            resid=wrap(err, 0, vector=False, name="resid"),
            variance=wrap(var, 0, vector=False, name="variance"),
            mean=wrap(mean, 0, vector=False, name="mean"),
            zscore=wrap(z, 0, vector=False, name="zscore"),
            model_stable=(flags & _MODEL_STABLE) > 0,
            variance_stable=(flags & _VAR_STABLE) > 0,
            alarm=(flags & _ALARM) > 0,
            skipped=(flags & _SKIPPED) > 0,
            first_alarm=first,
            first_alarm_time=first_time,
            n_skipped=self.n_skipped,
            param_names=names,
            start=start,
        )

    def __repr__(self) -> str:
        return (f"RecursiveARX(na={self.na}, nb={self.nb}, nk={self.nk}, "
                f"forgetting_factor={self.forgetting_factor}, n_inputs={self.n_inputs}, trend={self.trend!r})")
