"""EMRAN throughput: tsfdi.EMRAN (numba kernel) against a plain numpy per-sample loop of the same algorithm.

Run: ``python benchmarks/emran_throughput.py`` (~30 s). Prints samples/s (median of repeats) of both on the same
data in the same process, their ratio, the number of hidden units reached and the largest difference between the
two implementations' prediction errors (they run the same algorithm, so it is at rounding level).

The data: ``y = sin(x_1) cos(x_2) + 0.3 x_3 (+ x_4^2 / 4 ...)`` on standard-normal inputs, 2, 4 and 8 inputs; the
network grows to a few tens of units. Paper 004 reports 0.2 ms per sample at most on a 1.6 GHz Pentium with at most
9 units (section VIII), i.e. >= 5e3 samples/s.
"""

import os

os.environ["OPENBLAS_NUM_THREADS"] = "1"

import time  # noqa: E402

import numpy as np  # noqa: E402

from tsfdi.models.emran import EMRAN  # noqa: E402

#: the EMRAN defaults, passed explicitly to both implementations
OPTIONS = dict(error_threshold=0.1, rms_threshold=0.05, rms_window=20, distance_threshold=0.3, distance_start=None,
               distance_decay=1.0, overlap=0.8, P0=1.0, process_noise=1e-4, measurement_noise=0.1,
               prune_threshold=0.01, prune_window=50, max_units=100)


def numpy_emran(X, y, *, error_threshold, rms_threshold, rms_window, distance_threshold, distance_start,
                distance_decay, overlap, P0, process_noise, measurement_noise, prune_threshold, prune_window,
                max_units):
    """The EMRAN of ``tsfdi.EMRAN`` (EKF rule) written as a plain numpy loop: the reference.

    Returns the a-priori prediction errors and the number of units after each sample.
    """
    n, nin = X.shape
    p = nin + 2
    eps_max = distance_threshold if distance_start is None else distance_start
    min_width = 1e-3 * distance_threshold
    mu = np.zeros((0, nin))
    width = np.zeros(0)
    alpha = np.zeros(0)
    P = np.zeros((0, p, p))
    inactive = np.zeros(0, dtype=int)
    bias, pbias = 0.0, P0
    errs2 = []
    err = np.empty(n)
    units = np.empty(n, dtype=int)
    for t in range(n):
        x = X[t]
        d2 = ((x - mu) ** 2).sum(axis=1)
        phi = np.exp(-d2 / width ** 2)
        e = y[t] - (bias + alpha @ phi)
        err[t] = e
        errs2 = (errs2 + [e * e])[-rms_window:]
        rms = np.sqrt(np.mean(errs2))
        K = len(alpha)
        dmin = np.sqrt(d2.min()) if K else np.inf
        eps_n = max(eps_max * distance_decay ** t, distance_threshold)
        if abs(e) > error_threshold and rms > rms_threshold and dmin > eps_n and K < max_units:
            mu = np.vstack([mu, x])
            width = np.append(width, max(overlap * (dmin if K else eps_max), min_width))
            alpha = np.append(alpha, e)
            P = np.concatenate([P, P0 * np.eye(p)[None]])
            inactive = np.append(inactive, 0)
        else:
            Pw = np.zeros((p + 1, p + 1)) if K else np.zeros((1, 1))
            Pw[0, 0] = pbias
            a = np.ones(1)
            if K:
                w = int(np.argmax(phi))
                g = 2 * alpha[w] * phi[w] / width[w] ** 2
                a = np.concatenate([[1.0, phi[w]], g * (x - mu[w]), [g * d2[w] / width[w]]])
                Pw[1:, 1:] = P[w]
            v = Pw @ a
            s = measurement_noise + a @ v
            step = v * (e / s)
            bias += step[0]
            Pw = Pw - np.outer(v, v) / s + process_noise * np.eye(len(a))
            pbias = Pw[0, 0]
            if K:
                alpha[w] += step[1]
                mu[w] += step[2:2 + nin]
                width[w] = max(width[w] + step[-1], min_width)
                P[w] = Pw[1:, 1:]
                o = np.abs(alpha) * phi
                if K > 1 and o.max() > 0:
                    inactive = np.where(o < prune_threshold * o.max(), inactive + 1, 0)
                    keep = inactive < prune_window
                    mu, width, alpha, P, inactive = mu[keep], width[keep], alpha[keep], P[keep], inactive[keep]
        units[t] = len(alpha)
    return err, units


def data(n, nin, rng):
    X = rng.standard_normal((n, nin))
    y = np.sin(X[:, 0]) * np.cos(X[:, 1]) + 0.3 * X[:, 2 % nin] + (X[:, 3:] ** 2).sum(axis=1) / 4
    return X, y + 0.02 * rng.standard_normal(n)


def median_time(fn, repeats):
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def main():
    rng = np.random.default_rng(0)
    n_fast, n_ref = 200_000, 5_000
    EMRAN(2).run(*data(100, 2, rng))      # compile (cached) outside the timing
    print(f"load average at start: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores (timings are shared-machine)")
    print(f"{'inputs':>6} {'units':>6} {'tsfdi samples/s':>16} {'numpy samples/s':>16} {'ratio':>7}   agreement")
    for nin in (2, 4, 8):
        X, y = data(n_fast, nin, rng)
        tf = median_time(lambda: EMRAN(nin, **OPTIONS).run(X, y), 5)
        tr = median_time(lambda: numpy_emran(X[:n_ref], y[:n_ref], **OPTIONS), 3)
        net = EMRAN(nin, **OPTIONS)
        res = net.run(X[:n_ref], y[:n_ref])
        ref_err, ref_units = numpy_emran(X[:n_ref], y[:n_ref], **OPTIONS)
        diff = np.max(np.abs(np.asarray(res.resid) - ref_err))
        same_units = bool(np.array_equal(res.n_units, ref_units))
        print(f"{nin:>6} {net.n_units:>6} {n_fast / tf:>16.3e} {n_ref / tr:>16.3e} {(n_fast / tf) / (n_ref / tr):>7.0f}"
              f"   max|de|={diff:.1e}, same units: {same_units}")


if __name__ == "__main__":
    main()
