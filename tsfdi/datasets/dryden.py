"""Dryden continuous turbulence: linear (u, v, w) and angular (p, q, r) gusts.

The gusts are the outputs of linear shaping filters driven by white noise, in the MIL-F-8785C form
(identical to the MIL-HDBK-1797 form once its lateral/vertical scale lengths are halved) with the
low-altitude (h < 1000 ft) scale lengths and intensities. The paper that tsfdi reproduces (Dutta et al.,
"Statistical Time Series Methods for Multicopter Fault Detection and Identification", section "Data
Generation for Model Identification") uses this model at 5 m altitude with the hexacopter's hub-to-hub
distance, 0.6096 m, as the span ``b``.

Notes
-----
Low-altitude scale lengths and intensities (altitude ``h`` in feet, W20 the wind speed at 20 ft):

.. math::

    L_w = h,\\quad L_u = L_v = \\frac{h}{(0.177 + 0.000823 h)^{1.2}},\\quad
    \\sigma_w = 0.1 W_{20},\\quad \\frac{\\sigma_u}{\\sigma_w} = \\frac{\\sigma_v}{\\sigma_w}
    = \\frac{1}{(0.177 + 0.000823 h)^{0.4}}

with W20 = 15 / 30 / 45 kn for light / moderate / severe turbulence. The altitude is clamped below at
10 ft as in MIL-F-8785C. ``scale_length=L`` replaces the three scale lengths by one value
(:math:`L_u = L_v = L_w = L`; paper 003 gives its length scale as the hub-to-hub distance, 0.6096 m); the
intensities stay those of the altitude and level. The shaping filters (``V`` the airspeed, ``b`` the span) are

.. math::

    H_u(s) &= \\sigma_u \\sqrt{\\tfrac{2 L_u}{\\pi V}} \\frac{1}{1 + \\tfrac{L_u}{V} s}, \\qquad
    H_{v}(s) = \\sigma_v \\sqrt{\\tfrac{L_v}{\\pi V}}
             \\frac{1 + \\tfrac{\\sqrt{3} L_v}{V} s}{(1 + \\tfrac{L_v}{V} s)^2}, \\quad H_w \\text{ alike}, \\\\
    H_p(s) &= \\sigma_w \\sqrt{\\tfrac{0.8}{V}}
             \\frac{(\\pi / 4b)^{1/6}}{L_w^{1/3} (1 + \\tfrac{4b}{\\pi V} s)}, \\quad
    H_q(s) = \\frac{s / V}{1 + \\tfrac{4b}{\\pi V} s} H_w(s), \\quad
    H_r(s) = -\\frac{s / V}{1 + \\tfrac{3b}{\\pi V} s} H_v(s).

They are driven by independent white noises of intensity :math:`\\pi` (the MIL-F-8785C normalisation in
which the one-sided PSD :math:`\\Phi(\\omega) = |H(j\\omega)|^2` in rad/s integrates to the variance);
``q`` shares the noise of ``w`` and ``r`` that of ``v``, ``p`` has its own. The sign of ``q`` and ``r``
follows MIL-F-8785C; for a symmetric multirotor it has no effect on the statistics.

**Discretisation.** The eight-state realisation :math:`dx = A x\\,dt + B\\,dW` is discretised *exactly* in
the covariance sense: :math:`x_{k+1} = A_d x_k + w_k`, :math:`A_d = e^{A\\Delta t}`,
:math:`w_k \\sim N(0, Q_d)`, :math:`Q_d = \\int_0^{\\Delta t} e^{As} B B^T e^{A^T s} ds`, both computed with
Van Loan's matrix exponential. The sampled sequence then has exactly the autocovariance of the
continuous process at the sampling instants, for any step. A zero-order-hold discretisation is not used
because white noise held over a step is not the continuous white noise (its variance would have to be
chosen as :math:`\\pi/\\Delta t` and the result is only approximate). The initial state is drawn from the
stationary covariance (continuous Lyapunov equation), so there is no warm-up transient.

The analytic one-sided PSD in Hz returned by :meth:`DrydenTurbulence.psd` is
:math:`S(f) = 2\\pi |H(j 2\\pi f)|^2`, so :math:`\\int_0^\\infty S(f) df = \\sigma^2`.

References
----------
.. [1] MIL-F-8785C, Military Specification: Flying Qualities of Piloted Airplanes, 1980.
.. [2] MIL-HDBK-1797, Flying Qualities of Piloted Aircraft, 1997.
.. [3] T. M. I. Hakim and O. Arifianto, "Implementation of Dryden Continuous Turbulence Model into
       Simulink for LSA-02 Flight Test Simulation", J. Phys.: Conf. Ser. 1005, 012017, 2018.
.. [4] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE TAC 23(3), 1978.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg

from tsfdi._validation import check_rng, float_like, int_like, option

__all__ = ["DrydenTurbulence", "dryden_turbulence", "draw_gusts", "INTENSITIES", "COMPONENTS"]

#: Wind speed at 20 ft (knots) for each turbulence intensity (MIL-F-8785C low altitude).
INTENSITIES = {"light": 15.0, "moderate": 30.0, "severe": 45.0}
#: Gust components in output order.
COMPONENTS = ("u", "v", "w", "p", "q", "r")
UNITS = {"u": "m/s", "v": "m/s", "w": "m/s", "p": "rad/s", "q": "rad/s", "r": "rad/s"}

_FT = 0.3048
_KT = 0.514444


def _stable_factor(q: np.ndarray) -> np.ndarray:
    """Square-root factor ``F`` (eigenvectors times root eigenvalues) with ``F F^T = q`` for a PSD matrix
    (tiny negative eigenvalues clipped)."""
    q = 0.5 * (q + q.T)
    w, v = np.linalg.eigh(q)
    w = np.clip(w, 0.0, None)
    return v * np.sqrt(w)


@dataclass(frozen=True)
class DrydenTurbulence:
    """Dryden low-altitude turbulence model (MIL-F-8785C), usable on its own.

    Parameters
    ----------
    altitude : float
        Altitude above ground in metres (> 0; clamped below at 10 ft for the scale lengths).
    airspeed : float
        Mean airspeed ``V`` in m/s (> 0): converts the spatial (frozen) turbulence into time.
    span : float
        Span ``b`` in metres for the angular gusts (the paper: hub-to-hub distance 0.6096 m).
    intensity : {"light", "moderate", "severe"}
        W20 = 15 / 30 / 45 kn. Ignored when ``sigmas`` is given.
    sigmas : tuple of 3 floats, optional
        Explicit ``(sigma_u, sigma_v, sigma_w)`` in m/s (each >= 0).
    scale_length : float, optional
        One turbulence scale length in metres (> 0) for all three components, ``L_u = L_v = L_w``. Paper 003
        (Dutta et al., "Data Generation") says its Dryden model depends on "altitude, length scale, and
        turbulence intensity" with the length scale equal to the hexacopter's hub-to-hub distance 0.6096 m.
        ``None`` (default): the MIL-F-8785C low-altitude scale lengths of the altitude (module docstring). The
        intensities (``sigma_u, sigma_v, sigma_w``) do not depend on it; the angular gusts use ``L_w``.
    intensity_scale : float
        Factor (> 0) on the MIL-F-8785C intensities of ``intensity`` (default 1: the standard's). Not used with
        ``sigmas``.

    Notes
    -----
    See the module docstring for the equations and the exact discretisation.
    """

    altitude: float = 5.0
    airspeed: float = 5.0
    span: float = 0.6096
    intensity: str = "severe"
    sigmas: tuple | None = None
    scale_length: float | None = None
    intensity_scale: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "intensity_scale", float_like(self.intensity_scale, "intensity_scale", minimum=0.0,
                                                               strict_min=True))
        object.__setattr__(self, "altitude", float_like(self.altitude, "altitude", minimum=0.0, strict_min=True))
        object.__setattr__(self, "airspeed", float_like(self.airspeed, "airspeed", minimum=0.0, strict_min=True))
        object.__setattr__(self, "span", float_like(self.span, "span", minimum=0.0, strict_min=True))
        if self.scale_length is not None:
            object.__setattr__(self, "scale_length", float_like(self.scale_length, "scale_length", minimum=0.0,
                                                                strict_min=True))
        object.__setattr__(self, "intensity", option(self.intensity, "intensity", tuple(INTENSITIES)))
        if self.sigmas is not None:
            s = np.asarray(self.sigmas, dtype=float)
            if s.shape != (3,) or not np.all(np.isfinite(s)) or np.any(s < 0):
                raise ValueError(f"sigmas must be three finite non-negative numbers (sigma_u, sigma_v, sigma_w), "
                                 f"got {self.sigmas!r}")
            object.__setattr__(self, "sigmas", tuple(float(x) for x in s))

    # ----------------------------------------------------------------------------------------------
    @property
    def length_scales(self) -> tuple[float, float, float]:
        """``(L_u, L_v, L_w)`` in metres: MIL-F-8785C low altitude, or ``scale_length`` for all three."""
        if self.scale_length is not None:
            return self.scale_length, self.scale_length, self.scale_length
        h = max(self.altitude / _FT, 10.0)
        lw = h
        luv = h / (0.177 + 0.000823 * h) ** 1.2
        return luv * _FT, luv * _FT, lw * _FT

    @property
    def linear_sigmas(self) -> tuple[float, float, float]:
        """Specified ``(sigma_u, sigma_v, sigma_w)`` in m/s."""
        if self.sigmas is not None:
            return self.sigmas
        h = max(self.altitude / _FT, 10.0)
        sw = 0.1 * INTENSITIES[self.intensity] * _KT * self.intensity_scale
        su = sw / (0.177 + 0.000823 * h) ** 0.4
        return su, su, sw

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Continuous realisation ``(A, B, C)``: ``dx = A x dt + B dW`` (unit-intensity ``W``), ``g = C x``.

        States: ``[u, v1, v2, w1, w2, p, qz, rz]``; noises ``[n_u, n_v, n_w, n_p]``; outputs u, v, w, p, q, r.
        """
        V, b = self.airspeed, self.span
        lu, lv, lw = self.length_scales
        su, sv, sw = self.linear_sigmas
        sp = np.sqrt(np.pi)  # white-noise intensity pi
        A = np.zeros((8, 8))
        B = np.zeros((8, 4))
        C = np.zeros((6, 8))
        # u: K / (1 + tau s)
        tu = lu / V
        A[0, 0] = -1.0 / tu
        B[0, 0] = sp * su * np.sqrt(2.0 * lu / (np.pi * V)) / tu
        C[0, 0] = 1.0

        def second_order(i, noise, sig, L):
            # K (1 + sqrt3 tau s) / (1 + tau s)^2, controllable canonical form
            tau = L / V
            K = sig * np.sqrt(L / (np.pi * V))
            a1, a0 = 2.0 / tau, 1.0 / tau ** 2
            A[i, i + 1] = 1.0
            A[i + 1, i] = -a0
            A[i + 1, i + 1] = -a1
            B[i + 1, noise] = sp
            return np.array([K / tau ** 2, K * np.sqrt(3.0) * tau / tau ** 2])

        cv = second_order(1, 1, sv, lv)
        cw = second_order(3, 2, sw, lw)
        C[1, 1:3] = cv
        C[2, 3:5] = cw
        # p: first order with its own noise
        tp = 4.0 * b / (np.pi * V)
        kp = sw * np.sqrt(0.8 / V) * (np.pi / (4.0 * b)) ** (1.0 / 6.0) / lw ** (1.0 / 3.0)
        A[5, 5] = -1.0 / tp
        B[5, 3] = sp * kp / tp
        C[3, 5] = 1.0
        # q = (s/V)/(1 + tp s) w = (w - z)/(V tp), z' = (w - z)/tp
        A[6, 3:5] += cw / tp
        A[6, 6] = -1.0 / tp
        C[4, 3:5] = cw / (V * tp)
        C[4, 6] = -1.0 / (V * tp)
        # r = -(s/V)/(1 + tr s) v
        tr = 3.0 * b / (np.pi * V)
        A[7, 1:3] += cv / tr
        A[7, 7] = -1.0 / tr
        C[5, 1:3] = -cv / (V * tr)
        C[5, 7] = 1.0 / (V * tr)
        return A, B, C

    def discretize(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Exact discretisation: ``(A_d, F)`` with ``x[k+1] = A_d x[k] + F e[k]``, ``e ~ N(0, I_8)``.

        ``F F^T = Q_d`` is the covariance of the integrated noise over one step (Van Loan).
        """
        dt = float_like(dt, "dt", minimum=0.0, strict_min=True)
        A, B, _ = self.state_space()
        n = A.shape[0]
        M = np.zeros((2 * n, 2 * n))
        M[:n, :n] = -A
        M[:n, n:] = B @ B.T
        M[n:, n:] = A.T
        E = linalg.expm(M * dt)
        Ad = E[n:, n:].T
        Qd = Ad @ E[:n, n:]
        return Ad, _stable_factor(Qd)

    def stationary_covariance(self) -> np.ndarray:
        """Stationary state covariance ``P`` solving ``A P + P A^T + B B^T = 0``."""
        A, B, _ = self.state_space()
        return linalg.solve_continuous_lyapunov(A, -B @ B.T)

    def std(self) -> np.ndarray:
        """Stationary standard deviations of ``(u, v, w, p, q, r)`` (the linear ones equal the spec)."""
        _, _, C = self.state_space()
        return np.sqrt(np.diag(C @ self.stationary_covariance() @ C.T))

    def psd(self, f) -> np.ndarray:
        """Analytic one-sided PSD ``S(f) = 2 pi |H(j 2 pi f)|^2`` in units^2/Hz, shape ``(6, len(f))``."""
        f = np.atleast_1d(np.asarray(f, dtype=float))
        A, B, C = self.state_space()
        s = 2j * np.pi * f
        out = np.empty((6, f.size))
        eye = np.eye(A.shape[0])
        for k, sk in enumerate(s):
            H = C @ np.linalg.solve(sk * eye - A, B)  # (6, 4), unit intensity
            out[:, k] = 2.0 * np.sum(np.abs(H) ** 2, axis=1)
        return out

    def simulate(self, n: int, dt: float, rng=None, *, records: int | None = None) -> np.ndarray:
        """Sample ``n`` steps of the six gusts at spacing ``dt``.

        Parameters
        ----------
        n : int
            Number of samples (>= 1).
        dt : float
            Step in seconds (> 0).
        rng : None, int or numpy.random.Generator
            Source of the white noise.
        records : int, optional
            Number of independent realisations; when given the result has shape ``(records, n, 6)``.

        Returns
        -------
        ndarray, shape (n, 6) or (records, n, 6)
            Columns u, v, w (m/s), p, q, r (rad/s).
        """
        n = int_like(n, "n", minimum=1)
        dt = float_like(dt, "dt", minimum=0.0, strict_min=True)
        rng = check_rng(rng)
        nrec = 1 if records is None else int_like(records, "records", minimum=1)
        sampler = self.sampler(dt)
        out = np.empty((nrec, n, 6))
        for i in range(nrec):
            out[i] = draw_gusts(sampler, n, rng)
        return out[0] if records is None else out

    def sampler(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A_d, F, C, S0)`` for :func:`draw_gusts`: the discretisation and the factor of the stationary
        covariance (computed once per model and step, not once per record)."""
        Ad, F = self.discretize(dt)
        _, _, C = self.state_space()
        return Ad, F, C, _stable_factor(self.stationary_covariance())


def draw_gusts(sampler: tuple, n: int, rng: np.random.Generator) -> np.ndarray:
    """One realisation of ``n`` samples: ``x0 = S0 z`` (stationary start), then ``x[k+1] = A_d x[k] + F e[k]``,
    returning ``C x[k]`` for k = 0..n-1 (numba-compiled loop). Draws 8 then ``n * 8`` normals from ``rng``."""
    from tsfdi.datasets._hexacopter_core import dryden_recursion

    Ad, F, C, S0 = sampler
    x0 = S0 @ rng.standard_normal(8)
    e = rng.standard_normal((n, 8))
    return dryden_recursion(np.ascontiguousarray(Ad), np.ascontiguousarray(F), np.ascontiguousarray(C),
                            np.ascontiguousarray(x0, dtype=float), np.ascontiguousarray(e, dtype=float))


def dryden_turbulence(duration: float, fs: float = 1000.0, *, altitude: float = 5.0, airspeed: float = 5.0,
                      span: float = 0.6096, intensity: str = "severe", sigmas=None, scale_length=None,
                      intensity_scale: float = 1.0, rng=None):
    """Dryden gust time histories as an ``xarray.DataArray`` with dims ``(time, component)``.

    Parameters
    ----------
    duration : float
        Length in seconds (> 0).
    fs : float
        Sampling frequency in Hz (> 0).
    altitude, airspeed, span, intensity, sigmas, scale_length, intensity_scale
        See :class:`DrydenTurbulence`.
    rng : None, int or numpy.random.Generator
        Source of randomness.

    Returns
    -------
    xarray.DataArray
        Gusts u, v, w (m/s) and p, q, r (rad/s); ``attrs`` hold the model's parameters.

    Examples
    --------
    >>> g = dryden_turbulence(10.0, fs=100.0, intensity="light", rng=0)
    >>> g.sizes["component"]
    6
    """
    import xarray as xr

    duration = float_like(duration, "duration", minimum=0.0, strict_min=True)
    fs = float_like(fs, "fs", minimum=0.0, strict_min=True)
    model = DrydenTurbulence(altitude=altitude, airspeed=airspeed, span=span, intensity=intensity, sigmas=sigmas,
                             scale_length=scale_length, intensity_scale=intensity_scale)
    n = max(int(round(duration * fs)), 1)
    g = model.simulate(n, 1.0 / fs, rng)
    lu, lv, lw = model.length_scales
    return xr.DataArray(
        g, dims=("time", "component"),
        coords={"time": np.arange(n) / fs, "component": list(COMPONENTS)},
        name="gust",
        attrs={"units": "m/s (u, v, w); rad/s (p, q, r)", "model": "Dryden MIL-F-8785C low altitude",
               "altitude_m": model.altitude, "airspeed_m_s": model.airspeed, "span_m": model.span,
               "intensity": model.intensity if model.sigmas is None else "explicit sigmas",
               "sigma_u_v_w": list(model.linear_sigmas), "L_u_v_w": [lu, lv, lw], "fs": fs},
    )
