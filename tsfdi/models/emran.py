"""Online radial-basis-function network trained by EMRAN (paper 004, Samy, Postlethwaite, Gu; Li, Sundararajan,
Saratchandran).

The network predicts a scalar ``y`` from an input vector ``x``::

    ys(x) = alpha_0 + sum_k alpha_k exp(-||x - mu_k||^2 / sigma_k^2)

It starts with no hidden unit (only the bias ``alpha_0``) and, sample by sample, either *grows* (adds a unit
centred on ``x``) when the sample is novel by all three criteria of paper 004, eqs. 2-4, or *adapts* the
parameters of the winner unit only (the Extended MRAN of Li et al.), and *prunes* units whose contribution stays
negligible (the MRAN rule of Lu et al.). :meth:`EMRAN.update` returns the a-priori prediction error, the residual
that paper 004's residual evaluation (:class:`tsfdi.detection.moving.MovingSquaredError`) averages.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numba
import numpy as np

from tsfdi._data import as_signal, check_paired
from tsfdi._validation import float_like, int_like, option
from tsfdi.models.lstsq import check_size

__all__ = ["EMRAN", "EMRANResults"]

#: largest magnitude of an input or output sample: squared distances of up to ~1e100 inputs stay finite
MAX_SAMPLE = 1e100
#: a width never shrinks below this fraction of ``distance_threshold`` (the EKF step may drive it to zero)
MIN_WIDTH_FRACTION = 1e-3

# bits of the per-sample flag array written by the kernel
_GREW = 1
_PRUNED = 2
_SKIPPED = 4
_ADAPTED = 8

# integer state slots: units, learning samples (for the distance decay), skipped, ring position, errors in the ring,
# frozen, units added, units pruned, samples seen
_I_UNITS, _I_LEARNED, _I_SKIPPED, _I_POS, _I_COUNT, _I_FROZEN, _I_GROWN, _I_PRUNED, _I_SEEN = range(9)
# float state slots: bias, bias variance, sum of the squared errors in the ring
_F_BIAS, _F_PBIAS, _F_SUM = range(3)


@numba.njit(cache=True, nogil=True)
def _emran_kernel(X, y, e1, e2, eps_max, eps_min, gamma, kappa, p0, q0, r0, delta, prune_window, eta, decay,
                  min_width, mu, width, alpha, P, inactive, ring, ist, fst,
                  out_pred, out_err, out_rms, out_units, out_flags):  # pragma: no cover - compiled
    """Process the samples ``X[t], y[t]`` in order, updating the state arrays in place (see :class:`EMRAN`)."""
    n, nin = X.shape
    kmax = mu.shape[0]
    m = ring.shape[0]
    p = nin + 2
    phi = np.empty(kmax)
    d2 = np.empty(kmax)
    a = np.empty(p + 1)
    v = np.empty(p + 1)
    Pw = np.empty((p + 1, p + 1))
    for t in range(n):
        ist[_I_SEEN] += 1
        finite = np.isfinite(y[t])
        for j in range(nin):
            if not np.isfinite(X[t, j]):
                finite = False
        flags = 0
        if not finite:
            ist[_I_SKIPPED] += 1
            out_pred[t] = np.nan
            out_err[t] = np.nan
            out_rms[t] = np.nan
            out_units[t] = ist[_I_UNITS]
            out_flags[t] = _SKIPPED
            continue
        K = ist[_I_UNITS]
        # prediction: activations, nearest centre (eq. 4) and most active unit (the winner)
        ys = fst[_F_BIAS]
        dmin2 = np.inf
        win = -1
        amax = -1.0
        for k in range(K):
            s = 0.0
            for j in range(nin):
                dj = X[t, j] - mu[k, j]
                s += dj * dj
            d2[k] = s
            phi[k] = np.exp(-s / (width[k] * width[k]))
            ys += alpha[k] * phi[k]
            if s < dmin2:
                dmin2 = s
            if phi[k] > amax:
                amax = phi[k]
                win = k
        e = y[t] - ys
        out_pred[t] = ys
        out_err[t] = e
        # windowed RMS of the last m errors (eq. 3); the sum is recomputed whenever the ring wraps (no drift)
        pos = ist[_I_POS]
        if ist[_I_COUNT] == m:
            fst[_F_SUM] -= ring[pos]
        else:
            ist[_I_COUNT] += 1
        ring[pos] = e * e
        fst[_F_SUM] += e * e
        pos += 1
        if pos == m:
            pos = 0
            tot = 0.0
            for i in range(m):
                tot += ring[i]
            fst[_F_SUM] = tot
        ist[_I_POS] = pos
        rms = np.sqrt(max(fst[_F_SUM], 0.0) / ist[_I_COUNT])
        out_rms[t] = rms
        if ist[_I_FROZEN] == 1:
            out_units[t] = K
            out_flags[t] = 0
            continue
        # growth criteria (eqs. 2-4) with the MRAN distance schedule eps_n = max(eps_max gamma^n, eps_min)
        eps_n = max(eps_max * gamma ** ist[_I_LEARNED], eps_min)
        dmin = np.sqrt(dmin2)
        ist[_I_LEARNED] += 1
        if abs(e) > e1 and rms > e2 and dmin > eps_n and K < kmax:
            for j in range(nin):
                mu[K, j] = X[t, j]
            alpha[K] = e
            width[K] = max(kappa * (dmin if K > 0 else eps_max), min_width)
            for i in range(p):
                for j in range(p):
                    P[K, i, j] = p0 if i == j else 0.0
            inactive[K] = 0
            ist[_I_UNITS] = K + 1
            ist[_I_GROWN] += 1
            flags |= _GREW
        else:
            # adapt the bias and the winner's weight, centre and width (EKF, or eq. 5 when eta > 0)
            q = p + 1 if K > 0 else 1
            a[0] = 1.0
            w = win
            if K > 0:
                f = phi[w]
                s2 = width[w] * width[w]
                a[1] = f
                g = 2.0 * alpha[w] * f / s2
                for j in range(nin):
                    a[2 + j] = g * (X[t, j] - mu[w, j])
                a[2 + nin] = g * d2[w] / width[w]
            if eta > 0.0:
                fst[_F_BIAS] += eta * (a[0] * e - decay * fst[_F_BIAS])
                if K > 0:
                    alpha[w] += eta * (a[1] * e - decay * alpha[w])
                    for j in range(nin):
                        mu[w, j] += eta * (a[2 + j] * e - decay * mu[w, j])
                    width[w] += eta * (a[2 + nin] * e - decay * width[w])
            else:
                # decoupled EKF on [alpha_0, winner]: P blockdiag(p_bias, P_w), cross terms not kept
                for i in range(q):
                    for j in range(q):
                        Pw[i, j] = 0.0
                Pw[0, 0] = fst[_F_PBIAS]
                for i in range(1, q):
                    for j in range(1, q):
                        Pw[i, j] = P[win, i - 1, j - 1]
                s = r0
                for i in range(q):
                    acc = 0.0
                    for j in range(q):
                        acc += Pw[i, j] * a[j]
                    v[i] = acc
                    s += a[i] * acc
                ge = e / s
                fst[_F_BIAS] += v[0] * ge
                if K > 0:
                    alpha[win] += v[1] * ge
                    for j in range(nin):
                        mu[win, j] += v[2 + j] * ge
                    width[win] += v[2 + nin] * ge
                for i in range(q):
                    for j in range(q):
                        Pw[i, j] -= v[i] * v[j] / s
                    Pw[i, i] += q0
                fst[_F_PBIAS] = Pw[0, 0]
                for i in range(1, q):
                    for j in range(1, q):
                        P[win, i - 1, j - 1] = Pw[i, j]
            if K > 0 and width[win] < min_width:
                width[win] = min_width
            flags |= _ADAPTED
            # pruning (MRAN): a unit whose normalised output |alpha_k phi_k| / max_j |alpha_j phi_j| stays below
            # delta for prune_window consecutive samples is removed; activations of this sample's prediction
            omax = 0.0
            for k in range(K):
                o = abs(alpha[k]) * phi[k]
                if o > omax:
                    omax = o
            if K > 1 and omax > 0.0:
                k = 0
                while k < K:
                    if abs(alpha[k]) * phi[k] < delta * omax:
                        inactive[k] += 1
                    else:
                        inactive[k] = 0
                    if inactive[k] >= prune_window:
                        last = K - 1
                        if k != last:       # the last unit takes the pruned one's slot
                            for j in range(nin):
                                mu[k, j] = mu[last, j]
                            width[k] = width[last]
                            alpha[k] = alpha[last]
                            inactive[k] = inactive[last]
                            phi[k] = phi[last]
                            for i in range(p):
                                for j in range(p):
                                    P[k, i, j] = P[last, i, j]
                        K -= 1
                        ist[_I_PRUNED] += 1
                        flags |= _PRUNED
                    else:
                        k += 1
                ist[_I_UNITS] = K
        out_units[t] = ist[_I_UNITS]
        out_flags[t] = flags


@dataclass(frozen=True, eq=False)
class EMRANResults:
    """Histories of one :meth:`EMRAN.run` call, in the caller's data kind.

    Attributes
    ----------
    prediction : ndarray, Series or DataArray, shape (nobs,)
        A-priori network output ``ys(x_t)`` with the parameters before sample ``t`` (NaN for a skipped sample).
    resid : same kind, shape (nobs,)
        A-priori prediction errors ``e_t = y_t - ys(x_t)`` (paper 004, eq. 2 without the absolute value); NaN for a
        skipped sample.
    rms : same kind, shape (nobs,)
        Windowed RMS error of eq. 3 after sample ``t`` (over the last ``rms_window`` errors, fewer at the start).
    n_units : ndarray of int, shape (nobs,)
        Hidden units after each sample.
    grew, pruned, adapted, skipped : ndarray of bool, shape (nobs,)
        Per-sample flags: a unit was added; at least one unit was pruned; the bias and winner were adapted; the
        sample was skipped (non-finite, ``nonfinite="skip"``).
    n_skipped : int
        Non-finite samples skipped so far.
    start : int
        Samples given to the network before this run.
    """

    prediction: Any
    resid: Any
    rms: Any
    n_units: np.ndarray
    grew: np.ndarray
    pruned: np.ndarray
    adapted: np.ndarray
    skipped: np.ndarray
    n_skipped: int
    start: int

    @cached_property
    def nobs(self) -> int:
        """Number of samples in this run."""
        return int(self.n_units.shape[0])


class EMRAN:
    r"""Online RBF network grown, adapted and pruned by the Extended Minimal Resource Allocating Network.

    Parameters
    ----------
    n_inputs : int, default 1
        Dimension of the input vector ``x``.
    error_threshold : float, default 0.1
        :math:`E_1` of paper 004, eq. 2 (:math:`e_{min}` of MRAN): a unit is added only when
        :math:`|e_i| > E_1`. In the units of ``y``.
    rms_threshold : float, default 0.05
        :math:`E_2` of eq. 3 (:math:`e'_{min}` of MRAN): and only when the RMS of the last ``rms_window`` errors
        exceeds it. In the units of ``y``.
    rms_window : int, default 20
        :math:`M` of eq. 3, samples (MRAN's sliding window of errors).
    distance_threshold : float, default 0.3
        :math:`E_3` of eq. 4: and only when the input lies farther than this from the nearest centre. In the
        units of ``x``. With ``distance_start`` it is MRAN's final :math:`\epsilon_{min}`.
    distance_start : float, optional
        MRAN's :math:`\epsilon_{max}`: the distance threshold of sample :math:`n` is
        :math:`\max(\epsilon_{max}\gamma^n, \epsilon_{min})` (coarse units first, finer ones later; Lu et al.).
        Default: ``distance_threshold`` (a fixed :math:`E_3`, as paper 004 writes eq. 4). Also sets the width of
        the first unit (``overlap * distance_start``).
    distance_decay : float, default 1.0
        MRAN's :math:`\gamma` in (0, 1] (1: no decay).
    overlap : float, default 0.8
        MRAN's overlap factor :math:`\kappa`: a new unit has width :math:`\kappa\, d_i` (:math:`d_i` of eq. 4).
    P0 : float, default 1.0
        MRAN's :math:`p_0`: initial variance of each new unit's parameters (and of the bias) in the EKF.
    process_noise : float, default 1e-4
        MRAN's :math:`Q` (:math:`q_0`): added to the diagonal of the adapted covariance block at each step, so the
        network keeps adapting (random-walk parameters).
    measurement_noise : float, default 0.1
        MRAN's :math:`R`: variance of the output noise assumed by the EKF, in squared ``y`` units. Larger values
        adapt more slowly.
    prune_threshold : float, default 0.01
        MRAN's :math:`\delta`: a unit whose output :math:`|\alpha_k \phi_k(x)|` is below this fraction of the
        largest unit output ...
    prune_window : int, default 50
        ... for this many consecutive samples (MRAN's :math:`M_w`) is removed.
    max_units : int, default 100
        Largest number of hidden units (not in the papers: the kernel's arrays are allocated once). At the limit a
        novel sample adapts the winner instead of adding a unit.
    learning_rate : float, optional
        :math:`\eta` of paper 004, eq. 5: when given, the bias and the winner's parameters follow the gradient
        rule :math:`\Theta \leftarrow \Theta + \eta\,(e\,\partial ys / \partial\Theta - \sigma\Theta)` instead of
        the EKF (paper 004 uses 0.0007 online, 0.04 offline). Default: EKF (Li et al.).
    weight_decay : float, default 0.0
        The stabilising factor :math:`\sigma` of eq. 5 (used with ``learning_rate`` only).
    nonfinite : {"raise", "skip"}, default "raise"
        NaN / inf in ``x`` or ``y``: "raise" raises ``ValueError`` naming the sample; "skip" leaves the sample
        out (NaN prediction and error, no learning) and counts it in ``n_skipped``.

    Raises
    ------
    ValueError
        An option outside its range (named), or ``max_units`` whose arrays would exceed 2 GiB.
    TypeError
        A non-numeric option.

    Notes
    -----
    Network (paper 004, Fig. 1; Lu et al., eq. 1), with Gaussian units:

    .. math:: ys(\mathbf{x}) = \alpha_0 + \sum_{k=1}^{K} \alpha_k \phi_k(\mathbf{x}), \qquad
              \phi_k(\mathbf{x}) = \exp\left(-\lVert\mathbf{x} - \boldsymbol\mu_k\rVert^2 / \sigma_k^2\right).

    Per sample :math:`(\mathbf{x}_i, y_i)`, with :math:`e_i = y_i - ys(\mathbf{x}_i)` computed before any change:

    1. **Growth** when all three criteria hold (eqs. 2-4): :math:`|e_i| > E_1`;
       :math:`e_{i,RMS} = \sqrt{\sum_{j=i-M+1}^{i} e_j^2 / M} > E_2` (over the errors available while fewer
       than :math:`M` were seen); :math:`d_i = \lVert\mathbf{x}_i - \boldsymbol\mu_{ir}\rVert > E_3`,
       :math:`\boldsymbol\mu_{ir}` the nearest centre (:math:`d_i = \infty` without units). The new unit has
       :math:`\alpha = e_i`, :math:`\boldsymbol\mu = \mathbf{x}_i`, :math:`\sigma = \kappa d_i` and covariance
       :math:`p_0 I`; nothing else changes at that sample.
    2. **Adaptation** otherwise, of the bias and of the *winner* only -- the most active unit, largest
       :math:`\phi_k(\mathbf{x}_i)` (paper 004, section III.C; Li et al.'s EMRAN) -- by the extended Kalman filter
       of MRAN on :math:`\boldsymbol\theta = [\alpha_0, \alpha_w, \boldsymbol\mu_w, \sigma_w]` with gradient
       :math:`\mathbf{a} = [1, \phi_w, \phi_w \frac{2\alpha_w}{\sigma_w^2}(\mathbf{x}-\boldsymbol\mu_w),
       \phi_w \frac{2\alpha_w}{\sigma_w^3}\lVert\mathbf{x}-\boldsymbol\mu_w\rVert^2]`:
       :math:`\mathbf{k} = P\mathbf{a} / (R + \mathbf{a}'P\mathbf{a})`, :math:`\boldsymbol\theta \leftarrow
       \boldsymbol\theta + \mathbf{k} e_i`, :math:`P \leftarrow P - \mathbf{k}\mathbf{a}'P + Q I`. Each unit keeps
       its own covariance block and the bias its variance; the cross-covariances between them are not kept (a
       decoupled EKF, which is what updating only the winner amounts to). With ``learning_rate`` the step is
       eq. 5 instead. A width is kept above ``1e-3 * distance_threshold``.
    3. **Pruning** (MRAN), after an adaptation step: with :math:`o_k = |\alpha_k| \phi_k(\mathbf{x}_i)` (this
       sample's activations), a unit with :math:`o_k < \delta \max_j o_j` for ``prune_window`` consecutive
       samples is removed with its covariance block. A sample far from every unit (all :math:`o_k` zero) counts
       for none.

    Defaults. The papers give the roles of the constants but tune their values per problem (paper 004 publishes
    none but the learning rates). The defaults here are this library's choice for inputs and output of about unit
    scale: **standardise** ``x`` and ``y`` (e.g. with the mean and standard deviation of training data), since
    :math:`E_1, E_2, R` are in the units of ``y`` and :math:`E_3` in those of ``x``.

    Samples must lie within ``+-1e100`` (``ValueError`` beyond, naming ``x`` or ``y``). The loop is compiled with
    numba (``cache=True``); :meth:`update` and :meth:`run` share it, so feeding a stream sample by sample, in chunks
    or at once gives identical results.

    References
    ----------
    .. [1] I. Samy, I. Postlethwaite, D. Gu, "Neural network based sensor validation scheme demonstrated on an
       unmanned air vehicle (UAV) model" (paper 004), eqs. 1-5.
    .. [2] Y. Li, N. Sundararajan, P. Saratchandran, "Analysis of minimal radial basis function network algorithm
       for real-time identification of nonlinear dynamic systems", IEE Proc. Control Theory Appl. 147(4), 2000
       (EMRAN: winner-only updates).
    .. [3] L. Yingwei (Lu), N. Sundararajan, P. Saratchandran, "A sequential learning scheme for function
       approximation using minimal radial basis function neural networks", Neural Computation 9(2), 1997 (MRAN:
       growth, EKF, pruning).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> x = rng.uniform(-2, 2, 3000)
    >>> net = EMRAN(1)
    >>> res = net.run(x, np.sin(2 * x))
    >>> bool(np.sqrt(np.mean(np.asarray(res.resid)[-500:] ** 2)) < 0.1)
    True
    """

    def __init__(self, n_inputs: int = 1, *, error_threshold: float = 0.1, rms_threshold: float = 0.05,
                 rms_window: int = 20, distance_threshold: float = 0.3, distance_start: float | None = None,
                 distance_decay: float = 1.0, overlap: float = 0.8, P0: float = 1.0, process_noise: float = 1e-4,
                 measurement_noise: float = 0.1, prune_threshold: float = 0.01, prune_window: int = 50,
                 max_units: int = 100, learning_rate: float | None = None, weight_decay: float = 0.0,
                 nonfinite: str = "raise"):
        self.n_inputs = int_like(n_inputs, "n_inputs", minimum=1)
        self.error_threshold = float_like(error_threshold, "error_threshold", minimum=0.0)
        self.rms_threshold = float_like(rms_threshold, "rms_threshold", minimum=0.0)
        self.rms_window = int_like(rms_window, "rms_window", minimum=1)
        self.distance_threshold = float_like(distance_threshold, "distance_threshold", minimum=0.0,
                                             strict_min=True, maximum=MAX_SAMPLE)
        self.distance_start = float_like(distance_start, "distance_start", minimum=self.distance_threshold,
                                         maximum=MAX_SAMPLE, optional=True)
        self.distance_decay = float_like(distance_decay, "distance_decay", minimum=0.0, maximum=1.0,
                                         strict_min=True)
        self.overlap = float_like(overlap, "overlap", minimum=0.0, strict_min=True)
        self.P0 = float_like(P0, "P0", minimum=0.0, strict_min=True, maximum=1e100)
        self.process_noise = float_like(process_noise, "process_noise", minimum=0.0, maximum=1e100)
        self.measurement_noise = float_like(measurement_noise, "measurement_noise", minimum=0.0, strict_min=True,
                                            maximum=1e100)
        self.prune_threshold = float_like(prune_threshold, "prune_threshold", minimum=0.0, maximum=1.0)
        self.prune_window = int_like(prune_window, "prune_window", minimum=1)
        self.max_units = int_like(max_units, "max_units", minimum=1)
        self.learning_rate = float_like(learning_rate, "learning_rate", minimum=0.0, strict_min=True,
                                        optional=True)
        self.weight_decay = float_like(weight_decay, "weight_decay", minimum=0.0)
        self.nonfinite = option(nonfinite, "nonfinite", ("raise", "skip"))
        p = self.n_inputs + 2
        check_size(self.max_units * p * p, f"max_units={self.max_units:,}, n_inputs={self.n_inputs:,}: the "
                   f"covariance blocks ({self.max_units:,} x {p:,} x {p:,})")
        check_size(self.rms_window, f"rms_window={self.rms_window:,}: the error window")
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Return to the initial state: no unit, bias 0 with variance ``P0``, no error history, not frozen."""
        k, n, p = self.max_units, self.n_inputs, self.n_inputs + 2
        self._mu = np.zeros((k, n))
        self._width = np.zeros(k)
        self._alpha = np.zeros(k)
        self._P = np.zeros((k, p, p))
        self._inactive = np.zeros(k, dtype=np.int64)
        self._ring = np.zeros(self.rms_window)
        self._ist = np.zeros(9, dtype=np.int64)
        self._fst = np.array([0.0, self.P0, 0.0])

    @property
    def n_units(self) -> int:
        """Current number of hidden units."""
        return int(self._ist[_I_UNITS])

    @property
    def centres_(self) -> np.ndarray:
        """Centres of the hidden units, shape (n_units, n_inputs) (a copy)."""
        return self._mu[:self.n_units].copy()

    @property
    def widths_(self) -> np.ndarray:
        """Widths :math:`\\sigma_k` of the hidden units, shape (n_units,) (a copy)."""
        return self._width[:self.n_units].copy()

    @property
    def weights_(self) -> np.ndarray:
        """Output weights :math:`\\alpha_k` of the hidden units, shape (n_units,) (a copy)."""
        return self._alpha[:self.n_units].copy()

    @property
    def bias_(self) -> float:
        """The bias :math:`\\alpha_0`."""
        return float(self._fst[_F_BIAS])

    @property
    def nobs(self) -> int:
        """Samples given to the network since construction or :meth:`reset` (skipped ones included)."""
        return int(self._ist[_I_SEEN])

    @property
    def n_skipped(self) -> int:
        """Non-finite samples skipped so far."""
        return int(self._ist[_I_SKIPPED])

    @property
    def n_grown(self) -> int:
        """Units added so far (pruned ones included)."""
        return int(self._ist[_I_GROWN])

    @property
    def n_pruned(self) -> int:
        """Units pruned so far."""
        return int(self._ist[_I_PRUNED])

    @property
    def frozen(self) -> bool:
        """Whether learning was stopped by :meth:`freeze`."""
        return bool(self._ist[_I_FROZEN])

    def freeze(self) -> None:
        """Stop learning from the next sample on: no growth, adaptation or pruning; predictions and errors are
        still computed (paper 004, section VII: training stopped when a fault is detected). :meth:`reset` undoes
        it."""
        self._ist[_I_FROZEN] = 1

    def predict(self, X: Any) -> Any:
        """Network output for inputs ``X`` (shape (nobs, n_inputs) or (nobs,) for one input) without learning,
        in the caller's data kind. NaN / inf inputs raise ``ValueError``."""
        sx = self._signal_x(X)
        self._check_range(sx.values, "X")
        xv = sx.values
        out = np.full(xv.shape[0], self.bias_)
        for k in range(self.n_units):
            d2 = ((xv - self._mu[k]) ** 2).sum(axis=1)
            out += self._alpha[k] * np.exp(-d2 / self._width[k] ** 2)
        return sx.wrap(out, 0, vector=False, name="prediction")

    # ------------------------------------------------------------------ processing
    def _signal_x(self, X: Any, finite: bool = True):
        sx = as_signal(X, "X", min_nobs=1, allow_constant=True, finite=finite)
        if sx.nchan != self.n_inputs:
            raise ValueError(f"X must have n_inputs={self.n_inputs} column(s), got {sx.nchan}")
        return sx

    def _check_range(self, v: np.ndarray, name: str) -> None:
        if v.size == 0 or (-MAX_SAMPLE <= v.min() and v.max() <= MAX_SAMPLE):
            return
        big = (np.abs(v) > MAX_SAMPLE) & np.isfinite(v)
        if big.any():
            first = int(np.argwhere(big)[0][0])
            raise ValueError(f"{name} has a sample of magnitude {np.abs(v[first]).max():.3g} (first at sample {first} "
                             f"of this call): samples must lie within +-{MAX_SAMPLE:g}; standardise {name}")

    def _check_samples(self, xv: np.ndarray, yv: np.ndarray) -> None:
        if self.nonfinite == "raise":
            bad_x = ~np.isfinite(xv).all(axis=1)
            bad_y = ~np.isfinite(yv)
            if bad_x.any() or bad_y.any():
                which = "X" if bad_x.any() else "y"
                first = int(np.flatnonzero(bad_x | bad_y)[0])
                raise ValueError(f"{which} contains NaN/inf (first at sample {first} of this call); pass "
                                 "nonfinite='skip' to skip and count such samples")
        self._check_range(xv, "X")
        self._check_range(yv, "y")

    def _call(self, xv: np.ndarray, yv: np.ndarray):
        n = yv.shape[0]
        pred, err, rms = np.empty(n), np.empty(n), np.empty(n)
        units = np.empty(n, dtype=np.int64)
        flags = np.empty(n, dtype=np.int64)
        eps_max = self.distance_start if self.distance_start is not None else self.distance_threshold
        _emran_kernel(xv, yv, self.error_threshold, self.rms_threshold, eps_max, self.distance_threshold,
                      self.distance_decay, self.overlap, self.P0, self.process_noise, self.measurement_noise,
                      self.prune_threshold, self.prune_window, self.learning_rate or 0.0, self.weight_decay,
                      MIN_WIDTH_FRACTION * self.distance_threshold, self._mu, self._width, self._alpha, self._P,
                      self._inactive, self._ring, self._ist, self._fst, pred, err, rms, units, flags)
        return pred, err, rms, units, flags

    def update(self, x: Any, y: float) -> float:
        """Process one sample and return its a-priori prediction error ``y - ys(x)`` (paper 004, eq. 2).

        Parameters
        ----------
        x : float or array_like of length ``n_inputs``
            Input vector (real numbers).
        y : float
            Output sample (a real number: not a bool, not a string).

        Returns
        -------
        float
            The prediction error (NaN for a skipped sample).

        Raises
        ------
        TypeError
            ``x`` or ``y`` not real numbers.
        ValueError
            ``x`` of another length, NaN / inf under ``nonfinite="raise"``, or a sample beyond ``+-1e100``; the
            network is left unchanged.
        """
        if isinstance(y, (bool, np.bool_, str, bytes)) or np.asarray(y).dtype.kind not in "iuf" or np.ndim(y):
            raise TypeError(f"y must be a real number, got {y!r} ({type(y).__name__})")
        try:
            xv = np.asarray(x)
            if xv.dtype.kind not in "iuf":
                raise TypeError
            xv = np.ascontiguousarray(xv.astype(np.float64).reshape(1, -1))
        except (TypeError, ValueError):
            raise TypeError(f"x must be real number(s), got {x!r}") from None
        if xv.shape[1] != self.n_inputs:
            raise ValueError(f"x must hold n_inputs={self.n_inputs} value(s), got {xv.shape[1]}")
        yv = np.array([float(y)])
        self._check_samples(xv, yv)
        return float(self._call(xv, yv)[1][0])

    def run(self, X: Any, y: Any) -> EMRANResults:
        """Process whole arrays (continuing from the current state) and return the histories.

        Parameters
        ----------
        X : array_like, Series, DataFrame or DataArray, shape (nobs, n_inputs) or (nobs,) for one input
            Input signals.
        y : array_like, Series or DataArray, shape (nobs,)
            Output signal, same length as ``X``.

        Returns
        -------
        EMRANResults
            Histories wrapped in ``y``'s data kind (index kept).

        Raises
        ------
        ValueError
            ``X`` / ``y`` of different lengths or with different indexes (pandas / xarray, paired sample by
            sample, never aligned), ``X`` with another number of columns, NaN / inf under
            ``nonfinite="raise"`` or a sample beyond ``+-1e100``; nothing is processed.
        TypeError
            Non-numeric (or bool) ``X`` / ``y``.
        """
        sy = as_signal(y, "y", vector=False, min_nobs=1, allow_constant=True, finite=False)
        sx = self._signal_x(X, finite=False)
        yv = np.ascontiguousarray(sy.values[:, 0])
        xv = np.ascontiguousarray(sx.values)
        if xv.shape[0] != yv.shape[0]:
            raise ValueError(f"X and y must have the same length, got len(X)={xv.shape[0]} and len(y)={yv.shape[0]}")
        check_paired(sx, sy, ("X", "y"))
        self._check_samples(xv, yv)
        start = self.nobs
        pred, err, rms, units, flags = self._call(xv, yv)
        wrap = sy.wrap
        return EMRANResults(prediction=wrap(pred, 0, vector=False, name="prediction"),
                            resid=wrap(err, 0, vector=False, name="resid"),
                            rms=wrap(rms, 0, vector=False, name="rms"),
                            n_units=units, grew=(flags & _GREW) > 0, pruned=(flags & _PRUNED) > 0,
                            adapted=(flags & _ADAPTED) > 0, skipped=(flags & _SKIPPED) > 0,
                            n_skipped=self.n_skipped, start=start)

    def __repr__(self) -> str:
        rule = "EKF" if self.learning_rate is None else f"learning_rate={self.learning_rate:g}"
        return f"EMRAN(n_inputs={self.n_inputs}, n_units={self.n_units}, {rule})"
