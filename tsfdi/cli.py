"""The ``tsfdi`` command line: ``tsfdi <command> [options]``.

Sub-commands register themselves in :data:`COMMANDS` through :func:`command`: a function that adds its
options to an ``argparse`` parser and a function that runs it. Adding a sub-command is one decorated pair.

Errors never end in a traceback: for a flag with a bad value ``argparse`` prints the usage and an error naming the
flag, for a file that cannot be read or written, or data the library refuses, :func:`main` prints
``tsfdi <command>: error: ...`` naming the flag or file; either way :func:`main` returns 2 (the exit status).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable

__all__ = ["main", "command", "COMMANDS"]

#: name -> (help, add_arguments(parser), run(args) -> int)
COMMANDS: dict[str, tuple[str, Callable, Callable]] = {}


def command(name: str, help: str, add_arguments: Callable[[argparse.ArgumentParser], None]):
    """Register ``run(args) -> int`` as the sub-command ``name``."""
    def deco(run):
        COMMANDS[name] = (help, add_arguments, run)
        return run
    return deco


# ------------------------------------------------------------------------------ flag values (argparse types)
def _finite(text: str) -> float:
    """A finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value


def _positive(text: str) -> float:
    """A finite number > 0."""
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return value


def _nonnegative(text: str) -> float:
    """A finite number >= 0."""
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def _probability(text: str) -> float:
    """A number strictly between 0 and 1."""
    value = _finite(text)
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"must be strictly between 0 and 1, got {text!r}")
    return value


def _integer(text: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {text!r}")
    return value


def _count(text: str) -> int:
    """An integer >= 1."""
    return _integer(text, 1)


def _seed(text: str) -> int:
    """An integer >= 0."""
    return _integer(text, 0)


def _two_or_more(text: str) -> int:
    """An integer >= 2."""
    return _integer(text, 2)


def _write_error(flag: str, path: str, exc: OSError) -> ValueError:
    return ValueError(f"{flag} {path}: cannot write the file ({exc.strerror or exc})")


def _simulate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, help="output netCDF file")
    p.add_argument("--records-per-case", type=_count, default=20, help="records per state and turbulence level")
    p.add_argument("--seed", type=_seed, default=2024, help="base seed (record k uses SeedSequence([seed, k]))")
    p.add_argument("--duration", type=_positive, default=60.0, help="record length in s")
    p.add_argument("--failure-time", type=_nonnegative, default=10.0, help="failure instant in s")
    p.add_argument("--speed", type=_finite, default=5.0, help="forward speed in m/s")
    p.add_argument("--states", default="healthy,rotor1,rotor2,rotor6",
                   help="comma-separated states: healthy, rotor1 .. rotor6")
    p.add_argument("--turbulence", default="light,moderate,severe",
                   help="comma-separated Dryden levels: none, light, moderate, severe")
    p.add_argument("--dt", type=_positive, default=0.001, help="integration step in s")
    p.add_argument("--fs", type=_positive, default=100.0, help="output sampling frequency in Hz")
    p.add_argument("--fleet", default=None, metavar="SPEC",
                   help="a fleet of aircraft of one type (Hansen et al.): each record's mass, centre-of-gravity "
                        "offset, motor constants and inertia drawn from its seed, uniformly around the nominal "
                        "aircraft, and written as the record coordinates mass (kg), cg_x, cg_y (m), "
                        "motor_constant, inertia (factors). SPEC is 'default' (mass=0.05, cg_offset=0.01, "
                        "motor_constant=0.03, inertia=0.05) or comma-separated NAME=VALUE overriding some of "
                        "them, e.g. 'mass=0.1,cg_offset=0.02' (relative spreads except cg_offset in m; see "
                        "tsfdi.datasets.hexacopter.FleetSpread). Default: one aircraft, no fleet")
    p.add_argument("--shipped", action="store_true",
                   help="write only the shipped variables packed as int32 counts (see data/README.md); "
                        "default: every channel as float64")


@command("simulate", "simulate hexacopter records (Dryden turbulence, rotor failures) to a netCDF file",
         _simulate_args)
def _simulate(args: argparse.Namespace) -> int:
    from tsfdi.datasets.hexacopter import FleetSpread, encode_for_file, make_hexacopter_dataset

    t0 = time.perf_counter()
    fleet = None if args.fleet is None else FleetSpread.from_spec(args.fleet)
    ds = make_hexacopter_dataset(args.records_per_case, seed=args.seed, duration=args.duration,
                                 failure_time=args.failure_time, speed=args.speed,
                                 states=tuple(s.strip() for s in args.states.split(",")),
                                 turbulence=tuple(s.strip() for s in args.turbulence.split(",")),
                                 dt=args.dt, fs=args.fs, fleet=fleet)
    if args.shipped:
        ds, enc = encode_for_file(ds)
    else:
        enc = {v: {"zlib": True, "shuffle": True} for v in ds.data_vars}
    try:
        ds.to_netcdf(args.out, engine="h5netcdf", encoding=enc)
    except OSError as exc:
        raise _write_error("--out", args.out, exc) from None
    nlost = int(ds["lost_control"].sum())
    print(f"wrote {ds.sizes['record']} records to {args.out} in {time.perf_counter() - t0:.1f} s; "
          f"lost control in {nlost} record(s)")
    return 0


# ----------------------------------------------------------------------------------------------------- demo
def _demo_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="tsfdi-demo", help="output folder for the figures and tables (default "
                                                       "./tsfdi-demo)")
    p.add_argument("--data", default=None, help="hexacopter netCDF file (default: the shipped data/hexacopter.nc)")
    p.add_argument("--records-per-case", type=_two_or_more, default=None,
                   help="use only the first N records of each state and turbulence level (N >= 2; default all)")
    p.add_argument("--fit-records", type=_count, default=10,
                   help="baseline records per state and turbulence level, pooled (default 10; excluded from the "
                        "evaluation)")
    p.add_argument("--pool", choices=("level", "all"), default="level",
                   help="baseline models per turbulence level (default) or one set across levels")
    p.add_argument("--order", type=_order, default="20",
                   help="model order: an integer (default 20), 'bic' or 'rss_sss'")
    p.add_argument("--windows", type=_windows, default="5,10,20", help="comma-separated window lengths in s")
    p.add_argument("--models", default=None, help="comma-separated models: roll, pitch, yaw_rate, var (default all)")
    p.add_argument("--methods", default="whiteness,variance", help="comma-separated: whiteness, variance")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.add_argument("--no-figures", action="store_true", help="do not write figures")


def _csv_list(text: str | None) -> list[str] | None:
    return None if text is None else [t.strip() for t in text.split(",") if t.strip()]


def _order(text: str) -> int | str:
    """A model order >= 1, 'bic' or 'rss_sss'."""
    word = text.strip().lower()
    if word in ("bic", "rss_sss"):
        return word
    try:
        return _count(word)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, 'bic' or 'rss_sss', got {text!r}") from None


def _windows(text: str) -> list[str]:
    """Comma-separated window lengths in s (each > 0) as time spans."""
    parts = _csv_list(text)
    if not parts:
        raise argparse.ArgumentTypeError(f"must hold at least one window length in s, got {text!r}")
    return [f"{_positive(w)}s" for w in parts]


@command("demo", "run the whole Dutta et al. study on the shipped hexacopter data: baselines (Table 2), "
                 "identification (Table 4), detection rates and figures", _demo_args)
def _demo(args: argparse.Namespace) -> int:
    from tsfdi.datasets import load_hexacopter
    from tsfdi.datasets.hexacopter import SIGNAL_CHANNELS
    from tsfdi.study import demo_report, hexacopter_study, paper_tests, write_report

    t0 = time.perf_counter()
    try:
        data = load_hexacopter(args.data)
    except (OSError, ValueError) as exc:
        if isinstance(exc, FileNotFoundError):
            raise
        raise ValueError(f"--data {args.data}: cannot be read as a hexacopter netCDF file ({exc})") from None
    models = _csv_list(args.models)
    tests = paper_tests(models or [*SIGNAL_CHANNELS, "var"], _csv_list(args.methods))
    bases, ev = hexacopter_study(data, records_per_case=args.records_per_case, models=models, tests=tests,
                                 windows=args.windows, fit_records=args.fit_records, pool=args.pool,
                                 order=args.order, progress=not args.no_progress)
    print(demo_report(bases, ev))
    written = write_report(bases, ev, data, args.out, figures=not args.no_figures)
    print(f"wrote {written[0]} and {len(written) - 2} figure(s) under {written[0].parent / 'figures'} in "
          f"{time.perf_counter() - t0:.1f} s")
    return 0


# ------------------------------------------------------------------------------------------------- fit / identify
def _read_signal(path: str, columns: list[str] | None, fs: float | None):
    """A ``DataFrame`` (time index in s) from a CSV (first column time if named ``time``) or netCDF file.

    Every failure is a ``ValueError`` naming the file (the positional ``data``)."""
    from pathlib import Path

    import numpy as np
    import pandas as pd

    from tsfdi._data import read_csv

    p = Path(path)
    if not p.exists():
        raise ValueError(f"data file {path} does not exist")
    if p.suffix.lower() in (".nc", ".nc4", ".netcdf", ".cdf"):
        import xarray as xr

        try:
            with xr.open_dataset(p, engine="h5netcdf") as ds:
                ds = ds.load()
        except (OSError, ValueError, TypeError) as exc:
            raise ValueError(f"data: {path} cannot be read as a netCDF file ({exc})") from None
        names = columns or [v for v in ds.data_vars if ds[v].dims == ("time",)]
        missing = [c for c in names if c not in ds]
        if missing:
            raise ValueError(f"{path} lacks the variable(s) {missing}")
        if not names:
            raise ValueError(f"{path} has no 1-D time series variable")
        bad = [c for c in names if ds[c].ndim != 1]
        if bad:
            raise ValueError(f"variables {bad} of {path} are not 1-D time series (select one record first)")
        try:
            df = pd.DataFrame({c: np.asarray(ds[c].values, dtype=float) for c in names},
                              index=pd.Index(np.asarray(ds[ds[names[0]].dims[0]].values), name="time"))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"data: the variables {names} of {path} must be numeric series of one length ({exc})") \
                from None
    else:
        df = read_csv(p, "data")
        if "time" in df.columns:
            df = df.set_index("time")
        if columns:
            missing = [c for c in columns if c not in df.columns]
            if missing:
                raise ValueError(f"{path} lacks the column(s) {missing}")
            df = df[columns]
    if df.shape[1] == 0:
        raise ValueError(f"{path} has no data column")
    if len(df) == 0:
        raise ValueError(f"data: {path} has no rows")
    for c in df.columns:
        if pd.api.types.is_bool_dtype(df[c].dtype) or not pd.api.types.is_numeric_dtype(df[c].dtype):
            raise ValueError(f"data: column {c!r} of {path} is not numeric")
    if df.index.name == "time":
        t = pd.to_numeric(pd.Series(df.index), errors="coerce").to_numpy(dtype=float)
        if not np.all(np.isfinite(t)):
            raise ValueError(f"data: the 'time' column of {path} must hold finite times in s")
        df.index = pd.Index(t, name="time")
    if fs is None:
        if df.index.name == "time" and len(df) > 1:
            step = float(np.median(np.diff(np.asarray(df.index, dtype=float))))
            if not (step > 0 and math.isfinite(1.0 / step)):
                raise ValueError(f"data: the 'time' column of {path} does not increase (median step {step:g} s): "
                                 "give --fs")
            fs = 1.0 / step
        else:
            fs = 1.0
    return df.astype(float), float(fs)


def _rows(seconds: float, fs: float, n: int) -> int:
    """``round(seconds * fs)`` clipped to ``[0, n]`` (without overflowing for huge products)."""
    x = seconds * fs
    return 0 if x <= 0 else n if x >= n else min(int(round(x)), n)


def _first_time(df) -> float:
    """Time (s) of the first row: the ``time`` index when there is one, else 0."""
    return float(df.index[0]) if df.index.name == "time" else 0.0


def _fit_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", help="CSV (optional 'time' column) or netCDF file with one record")
    p.add_argument("--out", required=True, help="output .npz file for the fitted model")
    p.add_argument("--columns", default=None, help="comma-separated channels (default all)")
    p.add_argument("--model", choices=("ar", "var"), default=None,
                   help="ar (one column) or var (several); default from the number of columns")
    p.add_argument("--max-lags", type=_count, default=20, help="largest order searched (BIC)")
    p.add_argument("--lags", type=_count, default=None, help="fixed order instead of the BIC choice")
    p.add_argument("--start", type=_finite, default=None, help="first time (s) used")
    p.add_argument("--stop", type=_finite, default=None, help="last time (s) used")
    p.add_argument("--fs", type=_positive, default=None, help="sampling frequency (Hz; default from the time column)")


@command("fit", "fit an AR / VAR baseline model (order by BIC) on a CSV or netCDF record and save it (.npz)",
         _fit_args)
def _fit(args: argparse.Namespace) -> int:
    import warnings

    from tsfdi.selection import select_order

    if args.lags is not None and args.lags > args.max_lags:
        raise ValueError(f"--lags {args.lags} exceeds --max-lags {args.max_lags}")
    df, fs = _read_signal(args.data, _csv_list(args.columns), args.fs)
    # --start / --stop are times on the record's clock, which need not start at 0
    t0 = _first_time(df)
    n = len(df)
    a = 0 if args.start is None else _rows(args.start - t0, fs, n)
    b = None if args.stop is None else _rows(args.stop - t0, fs, n)
    df = df.iloc[a:b]
    if len(df) == 0:
        raise ValueError(f"--start / --stop select no row of {args.data} ({n} rows from {t0:g} s at {fs:g} Hz)")
    model = args.model or ("ar" if df.shape[1] == 1 else "var")
    if model == "ar" and df.shape[1] != 1:
        raise ValueError(f"--model ar needs one column, got {df.shape[1]}: pick one with --columns")
    if model == "var" and df.shape[1] < 2:
        raise ValueError("--model var needs at least two columns")
    y = df.iloc[:, 0] if model == "ar" else df
    sel = select_order(y, args.max_lags, model)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sel.fit(args.lags)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    try:
        written = res.save(args.out)
    except OSError as exc:
        raise _write_error("--out", args.out, exc) from None
    print(f"{model.upper()}({res.lags}) on {list(df.columns)} ({res.nobs} samples): BIC {res.bic:.6g}, "
          f"RSS/SSS {res.rss_sss:.4g} %, SPP {res.spp:.2f}; saved to {written}")
    return 0


def _identify_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", help="CSV (optional 'time' column) or netCDF file with one record")
    p.add_argument("--models", required=True, nargs="+", help="saved models (.npz from 'tsfdi fit'), as "
                                                               "NAME=PATH or PATH (name = file stem)")
    p.add_argument("--columns", default=None, help="comma-separated channels, in the models' order (default all)")
    p.add_argument("--window", type=_positive, default=None, help="window length in s (default the whole record)")
    p.add_argument("--step", type=_positive, default=1.0, help="seconds between windows")
    p.add_argument("--fs", type=_positive, default=None, help="sampling frequency (Hz; default from the time column)")
    p.add_argument("--method", choices=("whiteness", "variance"), default="whiteness")
    p.add_argument("--alpha", type=_probability, default=1e-3, help="type I risk per channel")
    p.add_argument("--lags", type=_count, default=20, help="Ljung-Box lags")
    p.add_argument("--rule", choices=("paper", "likelihood", "pvalue"), default="paper")
    p.add_argument("--out", default=None, help="write the table to this CSV file")


@command("identify", "identify which saved model fits a CSV / netCDF record, window by window", _identify_args)
def _identify(args: argparse.Namespace) -> int:
    from pathlib import Path

    import pandas as pd

    from tsfdi.detection import FTest, LjungBox
    from tsfdi.identification import identify_windows
    from tsfdi.models import load

    df, fs = _read_signal(args.data, _csv_list(args.columns), args.fs)
    models = {}
    for spec in args.models:
        name, _, path = spec.rpartition("=")
        name = name or Path(path).stem
        try:
            models[name] = load(path)
        except (OSError, ValueError, TypeError) as exc:
            raise ValueError(f"--models {spec}: {exc}") from None
    n = len(df)
    W = n
    if args.window is not None:
        if args.window * fs > n:
            raise ValueError(f"--window {args.window:g} s is longer than the record ({n} rows at {fs:g} Hz)")
        W = _rows(args.window, fs, n)
        if W < 2:
            raise ValueError(f"--window {args.window:g} s is {W} sample(s) at {fs:g} Hz; at least 2 are needed")
    S = max(1, _rows(args.step, fs, n))
    test = LjungBox(lags=args.lags, alpha=args.alpha) if args.method == "whiteness" else FTest(alpha=args.alpha)
    x = df.to_numpy()
    if any(int(getattr(m, "neqs", 1)) != x.shape[1] for m in models.values()):
        raise ValueError(f"the data has {x.shape[1]} column(s) {list(df.columns)} but the models have "
                         f"{sorted({int(getattr(m, 'neqs', 1)) for m in models.values()})}: choose --columns")
    wins = identify_windows(x, models, test, window=W, step=S)
    t0 = _first_time(df)
    table = pd.DataFrame({"start": t0 + wins.starts / fs, "end": t0 + wins.stops / fs})
    for j, n in enumerate(wins.models):
        table[f"pvalue_{n}"] = wins.windows.min_pvalue[:, j]
        table[f"accept_{n}"] = wins.accepted[:, j]
    # the status is that of the paper rule (how many models accept), whichever rule picks the label
    table["status"] = wins.status
    table["label"] = [lab or "" for lab in wins.decide(args.rule)]
    with pd.option_context("display.width", 160, "display.max_rows", 200):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    if args.out:
        try:
            table.to_csv(args.out, index=False)
        except OSError as exc:
            raise _write_error("--out", args.out, exc) from None
        print(f"wrote {args.out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tsfdi`` command.

    Returns 0 on success and 2 on any error (a bad flag value, an unreadable or unwritable file, data the
    library refuses), after printing a message that names the flag or file; ``--help`` exits with status 0.
    """
    parser = argparse.ArgumentParser(prog="tsfdi", description="Statistical time-series fault detection and "
                                                               "identification")
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    for name, (help_, add, _) in COMMANDS.items():
        add(sub.add_parser(name, help=help_, description=help_))
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:     # argparse has printed the usage and the flag's error
        if exc.code in (0, None):
            raise
        return 2
    if args.command is None:
        parser.print_help()
        return 2
    try:
        return COMMANDS[args.command][2](args)
    except (ValueError, TypeError, OSError) as exc:
        print(f"tsfdi {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
