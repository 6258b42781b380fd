"""Synthetic healthy / fault VAR systems shared by the monitor, evaluation and CLI tests."""

from __future__ import annotations

import numpy as np

FS = 100.0
#: VAR(2) coefficient matrices (papers' sign: y[t] + A1 y[t-1] + A2 y[t-2] = e[t]) of each state
SYSTEMS = {
    "healthy": (np.array([[-1.2, 0.1], [0.0, -0.9]]), np.array([[0.5, 0.0], [0.1, 0.3]])),
    "f1": (np.array([[-0.4, 0.3], [-0.2, -1.1]]), np.array([[0.2, 0.0], [0.0, 0.5]])),
    "f2": (np.array([[-1.5, -0.2], [0.1, 0.2]]), np.array([[0.7, 0.1], [0.0, 0.3]])),
}
SIGMA = {"healthy": 1.0, "f1": 2.0, "f2": 1.5}


def _run(state: str, e: np.ndarray, y0: np.ndarray) -> np.ndarray:
    a1, a2 = SYSTEMS[state]
    y = np.vstack([y0, np.zeros_like(e)])
    for t in range(2, y.shape[0]):
        y[t] = e[t - 2] - a1 @ y[t - 1] - a2 @ y[t - 2]
    return y[2:]


def record(state: str, n: int, rng, failure: int | None = None, healthy_state: str = "healthy") -> np.ndarray:
    """``n`` samples: ``healthy_state`` until sample ``failure`` then ``state`` (``failure=None``: ``state`` all
    along); 200 burn-in samples dropped."""
    burn = 200
    if failure is None:
        e = rng.standard_normal((n + burn, 2)) * SIGMA[state]
        return _run(state, e, np.zeros((2, 2)))[burn:]
    first = _run(healthy_state, rng.standard_normal((failure + burn, 2)) * SIGMA[healthy_state], np.zeros((2, 2)))
    second = _run(state, rng.standard_normal((n - failure, 2)) * SIGMA[state], first[-2:])
    return np.vstack([first, second])[burn:]


def dataset(n_per_state: int, n: int, failure: int, rng):
    """Records, states and failure times (s) of ``n_per_state`` records per state."""
    recs, states, ft = [], [], []
    for s in SYSTEMS:
        for _ in range(n_per_state):
            if s == "healthy":
                recs.append(record(s, n, rng))
                ft.append(np.nan)
            else:
                recs.append(record(s, n, rng, failure))
                ft.append(failure / FS)
            states.append(s)
    return recs, states, np.array(ft)
