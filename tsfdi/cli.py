"""The ``tsfdi`` command line: ``tsfdi <command> [options]`` (also ``python -m tsfdi``).

Sub-commands register themselves in :data:`COMMANDS` through :func:`command`: a function that adds its
options to an ``argparse`` parser and a function that runs it. Adding a sub-command is one decorated pair.

Data files (CSV, netCDF such as ``tsfdi simulate`` writes, PX4 flight logs, folders of per-topic CSV files) are
read by :func:`tsfdi.read_records`, its keywords set by the data flags (``--rows-where`` is ``rows_where``): one
``DataFrame`` per record with the chosen columns as named channels and a ``time`` index in seconds, so the models
match channels by name. Window lengths and steps follow pandas ``rolling``: a bare integer counts
samples, a time span (``"2s"``, ``"500ms"``) is converted with the sampling frequency.

Errors never end in a traceback: :func:`main` prints the sub-command's usage and ``tsfdi <command>: error: ...``
naming the flag, file and column the user typed, and returns 2, as ``argparse`` does for a bad flag value.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi import __version__
from tsfdi import cli_options as opt
from tsfdi.baselines import Records
from tsfdi.io import TIME_COLUMNS, TIME_UNITS, read_records

__all__ = ["main", "command", "COMMANDS"]

#: name -> (help, add_arguments(parser), run(args) -> int)
COMMANDS: dict[str, tuple[str, Callable, Callable]] = {}

def command(name: str, help: str, add_arguments: Callable[[argparse.ArgumentParser], None]):
    """Register ``run(args) -> int`` as the sub-command ``name``."""
    def deco(run):
        COMMANDS[name] = (help, add_arguments, run)
        return run
    return deco



# ------------------------------------------------------------------------------------------------ reading data
#: read_records' keywords and the flags that set them (for its messages)
_FLAGS = {"paths": "data", "columns": "--columns", "time": "--time-column", "time_unit": "--time-unit", "fs": "--fs",
          "start": "--start", "stop": "--stop", "rows_where": "--rows-where", "margin": "--margin",
          "resample": "--resample", "nan_policy": "--nan-policy", "records": "--record", "where": "--where",
          "topics": "--topics"}
_KEYWORD = "|".join(_FLAGS)


def _flags(msg: str) -> str:
    """A message of :func:`tsfdi.read_records` with its keywords written as the flags that set them."""
    msg = re.sub(rf"\b({_KEYWORD})=(True\b|'[^']*'|[^\s,;)]*)",       # keyword=value first: "records=7: ..."
                 lambda m: _FLAGS[m.group(1)] + ("" if m.group(2) == "True" else " " + m.group(2).strip("'")), msg)
    msg = re.sub(rf"^({_KEYWORD})(?=[ :=])", lambda m: _FLAGS[m.group(1)], msg.replace("start / stop",
                                                                                       "--start / --stop"))
    return re.sub(rf"\b(with|give|out|of|or) ({_KEYWORD})\b(?!-)", lambda m: f"{m.group(1)} {_FLAGS[m.group(2)]}", msg)


@dataclasses.dataclass
class _Data:
    """The records a command works on (:func:`tsfdi.read_records`, named by :meth:`tsfdi.Records.origin` and
    :meth:`tsfdi.Records.names`) and how the command line speaks of them.

    ``split``: whether the records may be pieces of longer ones (``--rows-where``, ``--nan-policy omit``, the gaps
    of a flight log or of ``--resample``): a piece too short for the command is then dropped with a note instead
    of refused. ``rows``: ``"--start 10 / --stop 35"`` when the part used was selected by row numbers. ``inputs``:
    per record, the ``--u`` columns (the input of ARX models) beside ``frames``, or ``None``."""

    rec: Records
    frames: list
    split: bool = False
    rows: str = ""
    inputs: list | None = None

    def u(self, i: int) -> pd.DataFrame | None:
        """The input of record ``i`` (``None`` without ``--u``)."""
        return None if self.inputs is None else self.inputs[i]

    @property
    def columns(self) -> list[str]:
        return list(self.rec.channels)

    @property
    def path(self) -> str:
        return ", ".join(dict.fromkeys(self.rec.files))

    def about(self, i: int) -> str:
        """:meth:`tsfdi.Records.origin` for an error about record ``i``'s data, with the row numbers that cut it."""
        if not self.rows:
            return self.rec.origin(i)
        first = self.rows.split()[1]
        return (f"{self.rec.origin(i)} ({self.rows}: a bare integer is a row number, not a time; write e.g. '{first}s' "
                "for seconds)")

    def span(self, n: int) -> str:
        """``"200 samples = 2 s"`` at this sampling frequency."""
        return f"{n} sample{'s' if n != 1 else ''} = {n / self.rec.fs:.6g} s"

    def keep(self, pos: list[int]) -> _Data:
        return _Data(self.rec.read(np.asarray(pos, dtype=int)), [self.frames[i] for i in pos], True, self.rows,
                     None if self.inputs is None else [self.inputs[i] for i in pos])


def _read(args: argparse.Namespace, columns: list[str] | None = None, require_choice: bool = False,
          inputs: list[str] | None = None) -> _Data:
    """The records of the data files ``args.data`` (:func:`tsfdi.read_records` with the data flags); ``columns``
    are used without ``--columns`` (the channels of a model); ``require_choice`` as in read_records (fit /
    select-order). ``inputs``: the ``--u`` columns, read with the others (the same rows, split together) and kept
    apart in :attr:`_Data.inputs`."""
    if args.margin and not args.rows_where:
        raise ValueError("--margin trims the runs of --rows-where: give --rows-where too")
    outputs = opt.csv_list(args.columns) if args.columns else columns
    both = [c for c in inputs or () if c in (outputs or ())]
    if both:
        raise ValueError(f"--u {both[0]}: the column is also an output (--columns {','.join(outputs)}); a column is "
                         "either the model's output or its input")
    try:
        rec = read_records(args.data, columns=None if outputs is None else outputs + list(inputs or ()),
                           time=args.time_column, time_unit=args.time_unit, fs=args.fs, start=args.start,
                           stop=args.stop, rows_where=args.rows_where, margin=args.margin, resample=args.resample,
                           nan_policy=args.nan_policy, records=[r for g in args.record or [] for r in g] or None,
                           where=args.where, topics=args.topics, require_choice=require_choice)
    except (ValueError, TypeError) as exc:
        msg = str(exc)
        if any(f"no column {c!r}" in msg for c in inputs or ()):        # said of an input column: --u, not --columns
            msg = re.sub(r"^columns\b", "--u", msg)
        raise ValueError(_flags(msg)) from None
    rows = " / ".join(f"--{f} {getattr(args, f)}" for f in ("start", "stop") if isinstance(getattr(args, f), int))
    split = bool(args.topics or args.resample or args.rows_where or args.nan_policy == "omit")
    if not inputs:
        return _Data(rec, rec.frames(), split, rows)
    missing = [c for c in inputs if c not in rec.channels]       # (all numeric columns read: one is not there)
    if missing:
        raise ValueError(f"--u {missing[0]}: {', '.join(dict.fromkeys(rec.files))} has no numeric column "
                         f"{missing[0]!r}; its columns are {list(rec.channels)}")
    keep = [j for j, c in enumerate(rec.channels) if c not in inputs]
    frames = rec.frames()
    out = dataclasses.replace(rec, values=[v[:, keep] for v in rec.values],
                              channels=tuple(rec.channels[j] for j in keep))
    return _Data(out, [f.drop(columns=inputs) for f in frames], split, rows, [f[inputs] for f in frames])


def _drop_short(data: _Data, need: int, why: str) -> _Data:
    """The records of at least ``need`` samples: shorter pieces of a split record are dropped with a note, a short
    record of the file is refused."""
    short = [i for i, f in enumerate(data.frames) if len(f) < need]
    if not short:
        return data
    if not data.split or len(short) == len(data.frames):
        i = short[0]
        raise ValueError(f"{data.about(i)} is too short: {data.span(len(data.frames[i]))} at {data.rec.fs:g} Hz, "
                         f"{why} needs at least {need}")
    print(f"note: dropped {len(short)} piece(s) of split records shorter than {need} samples ({why})",
          file=sys.stderr)
    return data.keep([i for i in range(len(data.frames)) if i not in set(short)])


def _reword(exc: Exception, data: _Data, subs: tuple = (), record: int = 0) -> ValueError:
    """A library error about ``y`` / ``signal`` (``y[i]`` for record ``i`` of pooled records, else ``record``) told
    about the user's file."""
    msg = str(exc)
    m = re.match(r"(y|signal)(?:\[(\d+)\])?(:? )", msg)
    if m:
        i = int(m.group(2)) if m.group(2) else record
        msg = data.about(i if i < len(data.frames) else 0) + m.group(3) + msg[m.end():]
    for old, new in subs:
        msg = msg.replace(old, new)
    return ValueError(msg)


def _each(data: _Data, run: Callable) -> Iterator[tuple[int, pd.DataFrame, Any]]:
    """``(i, frame, run(i, frame))`` record by record, a library error told about record ``i`` (:func:`_reword`)."""
    for i, frame in enumerate(data.frames):
        try:
            out = run(i, frame)
        except (ValueError, TypeError) as exc:
            raise _reword(exc, data, record=i) from None
        yield i, frame, out


def _add_data_args(p: argparse.ArgumentParser, *, columns_help: str = "comma-separated columns to use "
                   "(default all numeric columns)", records_help: str = "default every record") -> None:
    p.add_argument("data", nargs="+",
                   help="one or more data files, read with the same options (the records of several files are "
                        "pooled by fit / select-order and each tested by detect / identify / monitor): CSV file (a "
                        "time column, see --time-column and --time-unit), netCDF file such as 'tsfdi simulate' "
                        "writes (variables over time, or over record and time), or PX4 flight log (.ulg, see "
                        "--topics)")
    p.add_argument("--columns", default=None, help=columns_help)
    p.add_argument("--time-column", default=None,
                   help="CSV column holding the time (numbers, see --time-unit, or dates and times): the index, "
                        "never a data channel (default: a column named "
                        f"{' / '.join(TIME_COLUMNS).replace('%', '%%')}; without one --fs is required)")
    p.add_argument("--time-unit", choices=tuple(TIME_UNITS), default=None,
                   help="unit of the CSV time column's numbers: s (default), ms, us or ns (e.g. a 'timestamp' in ms "
                        "since boot); --start / --stop times stay in seconds")
    p.add_argument("--fs", type=opt.positive, default=None,
                   help="sampling frequency in Hz: needed without a time column (CSV) or coordinate (netCDF), and "
                        "for a flight log (the rate of its grid); beside a time column it must agree with it "
                        "within 1%%")
    p.add_argument("--record", type=opt.record_numbers, action="append", default=None, metavar="N[,N...]",
                   help=f"netCDF records to use, by the 'record' coordinate (repeatable; {records_help})")
    p.add_argument("--where", type=opt.where, action="append", default=None, metavar="KEY=VALUE[,VALUE...]",
                   help="netCDF records whose per-record coordinate KEY holds one of the VALUEs, e.g. "
                        "'state=healthy' (repeatable: every condition holds)")
    p.add_argument("--topics", default=None,
                   help="PX4 flight log (.ulg): comma-separated topics to read, put on one grid at --fs (required) "
                        "by zero-order hold and split into records at logging gaps; their columns are "
                        "'topic.field', e.g. 'vehicle_attitude.q[0]'")
    p.add_argument("--start", type=opt.instant, default=None,
                   help="first sample used: a time on the record's clock such as '110s', or a row number (an "
                        "integer, from 0)")
    p.add_argument("--stop", type=opt.instant, default=None,
                   help="end of the part used (excluded): a time such as '130s' or a row number")
    p.add_argument("--resample", action="store_true",
                   help="CSV file with uneven time stamps: put the rows on a uniform grid at --fs by zero-order hold "
                        "(as a flight log), split into records at logging gaps")
    p.add_argument("--rows-where", action="append", default=None, metavar="COLUMN>VALUE",
                   help="keep the rows where a column (used or not) compares so with a number, e.g. "
                        "'controller.cmd_thrust>0' for the airborne part of a flight (repeatable: every condition "
                        "holds); each run of kept rows becomes a record (runs too short for the command are "
                        "dropped), after --start / --stop")
    p.add_argument("--margin", type=lambda t: opt.duration(t, strict=False), default=0.0,
                   help="time left out at both ends of every run of --rows-where, e.g. '1s' after take-off and "
                        "before landing (default 0s)")
    p.add_argument("--nan-policy", choices=("raise", "omit"), default="raise",
                   help="empty, NaN or infinite values in a used column: 'raise' refuses them, 'omit' splits each "
                        "record at those rows into records (pieces too short for the command are dropped)")


def _check_out(flag: str, path: str | None) -> None:
    """Refuse an output file whose folder does not exist (before any work is done)."""
    if path is None:
        return
    folder = Path(path).expanduser().parent
    if not folder.is_dir():
        raise ValueError(f"{flag} {path}: the folder {str(folder)!r} does not exist")


# ---------------------------------------------------------------------------------------------------- models
def _load(flag: str, spec: str, path: str) -> Any:
    from tsfdi.models import ARResults, ARXResults, FPResults, VARResults, VARXResults, load

    try:
        res = load(path)
    except (OSError, ValueError, TypeError) as exc:
        raise ValueError(f"{flag} {spec}: {exc}") from None
    if not isinstance(res, (ARResults, VARResults, ARXResults, VARXResults, FPResults)):
        raise ValueError(f"{flag} {spec}: {type(res).__name__} of a {type(res.model).__name__} model; the command "
                         "line tests AR / VAR / ARX models and their functionally pooled forms (FP-AR / FP-VAR / "
                         "FP-ARX), and VARX models")
    return res


def _load_models(flag: str, specs: list[str]) -> dict:
    """``NAME=PATH`` or ``PATH`` (name = the file's stem) -> loaded models; a name given twice is refused."""
    models, given = {}, {}
    for spec in specs:
        name, sep, path = spec.partition("=")
        if not sep:
            name, path = Path(spec).stem, spec
        if not name or not path:
            raise ValueError(f"{flag} {spec}: expected NAME=PATH or PATH")
        if name in given:
            raise ValueError(f"{flag}: the name {name!r} is given twice ({given[name]} and {spec}); name each model "
                             "as NAME=PATH")
        given[name] = spec
        models[name] = _load(flag, spec, path)
    return models


def _channels(res: Any) -> list[str]:
    return [str(c) for c in res.model.data.channels]


def _inputs(res: Any) -> tuple[list[str], bool] | None:
    """The inputs of an ARX / VARX / FP-ARX model and whether they are named (fitted on columns), or ``None`` (AR /
    VAR)."""
    records = res.model.u_records            # (an FP model's are those of its point family)
    if records is None:
        return None
    u = records[0]          # columns of a DataFrame, or a named Series (one input)
    return [str(c) for c in u.channels], bool(u.named or (not u.vector and u.name is not None))


def _family(res: Any) -> str:
    """The family of an input-output model with its article, for the messages: ``"an ARX"``, ``"a VARX"``."""
    name = type(res.model).__name__.replace("FP", "FP-")
    return f"{'a' if name.startswith('V') else 'an'} {name}"


def _input_columns(args: argparse.Namespace, models: dict) -> list[str] | None:
    """The ``--u`` columns of the models (keyed by how the user gave them, ``"--baseline m.npz"``): by default the
    inputs an ARX / VARX model was fitted with; ``None`` for AR / VAR models (``--u`` refused)."""
    ins = {flag: _inputs(m) for flag, m in models.items()}
    (first, have), *rest = ins.items()
    for flag, other in rest:
        if (other is None) != (have is None):
            arx, plain = (first, flag) if other is None else (flag, first)
            raise ValueError(f"{arx} is {_family(models[arx])} (input-output) model and {plain} an AR / VAR model: "
                             "their residuals are of different data (the output given --u, the output alone); test "
                             "one kind")
        if other is not None and set(other[0]) != set(have[0]):
            raise ValueError(f"{flag} was fitted with the inputs {other[0]} but {first} with {have[0]}: the models "
                             "must share their inputs")
    if have is None:
        if args.u is not None:
            raise ValueError(f"--u {','.join(args.u)}: {' and '.join(models)} "
                             f"{'has' if len(models) == 1 else 'have'} no input (AR / VAR); leave --u out")
        return None
    names, named = have
    if args.u is None:
        if not named:
            raise ValueError(f"{first} is {_family(models[first])} model of {len(names)} unnamed input(s): give "
                             "their columns with --u COL[,COL...], in the order of the model's inputs")
        return names
    if not named:
        if len(args.u) != len(names):
            raise ValueError(f"--u {','.join(args.u)}: {first} was fitted with {len(names)} input(s)")
        return args.u
    missing, extra = [c for c in names if c not in args.u], [c for c in args.u if c not in names]
    if missing or extra:
        raise ValueError(f"--u {','.join(args.u)}: {first} was fitted with the inputs {names}"
                         + (f"; missing {missing}" if missing else "") + (f"; not an input: {extra}" if extra else ""))
    return names


def _u_arg(p: argparse.ArgumentParser, fit: bool = False) -> None:
    p.add_argument("--u", type=opt.column_list, default=None, metavar="COL[,COL...]",
                   help="input columns of an ARX / VARX model, e.g. the controller's commands "
                        "(controller.cmd_roll,controller.cmd_pitch,controller.cmd_yaw): " + (
                            "fit an ARX model (FP-ARX with --k) of the one --columns output given them, or a VARX "
                            "model of several --columns outputs" if fit else
                            "the inputs of the ARX / VARX models given (default: the columns they were fitted with); "
                            "refused for AR / VAR models"))


def _check_channels(data: _Data, models: dict) -> None:
    """Every model (keyed by how the user gave it, ``"--baseline m.npz"``) has as many channels as the data has
    columns."""
    k = len(data.columns)
    bad = {n: _channels(m) for n, m in models.items() if len(_channels(m)) != k}
    if bad:
        name, ch = next(iter(bad.items()))
        raise ValueError(f"--columns: {data.path} gives {k} column(s) {data.columns} but {name} was fitted on "
                         f"{len(ch)} channel(s) {ch}; choose them with --columns")


def _k_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--k", type=opt.operating_point, action="append", default=None, metavar="NAME[=VALUE,...]",
                   help="operating point of the functionally pooled models (from 'tsfdi fit --k'): NAME=VALUE, the "
                        "logged value of every record, or NAME=VALUE,VALUE,... one per data file in the order given, "
                        "or NAME, the per-record coordinate NAME of netCDF data, repeated for each of the models' "
                        "parameters (e.g. --k depth=2.5; values without NAME= are those of the models' only "
                        "parameter); or 'estimate': each "
                        "record's maximum-likelihood operating point (tsfdi.models.FPResults.estimate_k on the whole "
                        "record), printed with its 95%% interval, the record then tested at it. Required with a "
                        "functionally pooled model, refused without one")


def _k_given(args: argparse.Namespace, data: _Data, *, fit: bool = False, only: str | None = None
             ) -> dict[str, np.ndarray]:
    """``--k NAME=VALUE,...`` as NAME -> one value per record of ``data`` (each file's value on its records; one
    value for every file, except when fitting). Values without a name are those of ``k`` when fitting, else of the
    models' ``only`` parameter."""
    files = [os.fspath(f) for f in args.data]
    per_file = [files.index(f) for f in data.rec.files]
    given: dict[str, np.ndarray] = {}
    for name, values in args.k:
        if not name and not fit and only is None:
            raise ValueError(f"--k {','.join(f'{v:g}' for v in values)}: the models have several operating "
                             "parameters; name the one given, --k NAME=VALUE")
        name = name or ("k" if fit else only)
        if name in given:
            raise ValueError(f"--k {name}: given twice")
        if values is None:
            given[name] = _k_coordinate(name, data)
            continue
        if len(values) != len(files) and (fit or len(values) != 1):
            raise ValueError(f"--k {name}: {len(values)} value(s) for {len(files)} data file(s); give one per file, "
                             "in the order of the files" + ("" if fit else ", or one for every file"))
        given[name] = np.asarray(values if len(values) > 1 else values * len(files))[per_file]
    return given


def _k_coordinate(name: str, data: _Data) -> np.ndarray:
    """``--k NAME``: the per-record coordinate ``NAME`` of the netCDF data files (over ``record``, or a scalar for a
    file of one record), one value per record of ``data``."""
    import xarray as xr

    by_file: dict[str, dict] = {}
    out = np.empty(len(data.frames))
    for i, (path, rid) in enumerate(zip(data.rec.files, data.rec.ids)):
        if path not in by_file:
            try:
                with xr.open_dataset(path, engine="h5netcdf") as ds:
                    var = ds.variables.get(name)
                    if var is None or var.dims not in ((), ("record",)) or var.dtype.kind not in "iuf":
                        have = [str(c) for c, v in ds.variables.items()
                                if v.dims == ("record",) and v.dtype.kind in "iuf" and c != "record"]
                        raise ValueError(f"--k {name}: {path} has no numeric per-record coordinate {name!r}; its "
                                         f"per-record coordinates are {have}")
                    labels = ds["record"].values if "record" in ds.coords else np.arange(ds.sizes.get("record", 1))
                    values = np.broadcast_to(np.asarray(var.values, dtype=float), labels.shape)
                    by_file[path] = dict(zip(map(str, labels), values.tolist()))
            except (OSError, TypeError, KeyError):
                raise ValueError(f"--k {name}: the per-record coordinate of netCDF data, but {path} is not a netCDF "
                                 f"file; give --k {name}=VALUE,... (one value per data file)") from None
        values, rid = by_file[path], str(rid)
        key = rid if rid in values else rid.rpartition(".")[0]          # a piece "2.0" of record "2"
        if key not in values and len(values) > 1:
            raise ValueError(f"--k {name}: no {name!r} for {data.rec.origin(i)} in {path}")
        out[i] = values[key] if key in values else next(iter(values.values()))     # a file of one record
        if not np.isfinite(out[i]):
            raise ValueError(f"--k {name}: {data.rec.origin(i)} has {name} = {out[i]}")
    return out


def _operating_points(args: argparse.Namespace, data: _Data, models: dict) -> tuple[list[dict], list[dict]]:
    """Per record of ``data``: the point results of every model of ``models`` (keyed by how the user gave it,
    ``"--baseline fp.npz"`` / ``"--models f1"``; a functionally pooled one at its ``--k``, logged or estimated and
    printed) and the operating points used (flag -> {parameter: value})."""
    from tsfdi.exceptions import CoverageWarning
    from tsfdi.models import FPResults

    fp = {flag: m for flag, m in models.items() if isinstance(m, FPResults)}
    if args.k and not fp:
        raise ValueError(f"--k: the operating point of a functionally pooled model ('tsfdi fit --k'), but "
                         f"{' and '.join(models)} {'is a point model' if len(models) == 1 else 'are point models'}; "
                         "leave --k out")
    if fp and not args.k:
        flag, m = next(iter(fp.items()))
        names = m.model.k_names
        raise ValueError(f"{flag} is a functionally pooled model over {_fp_range(m.model.k_range, names)}: give its "
                         f"operating point with {' '.join(f'--k {n}=VALUE' for n in names)} (logged) or --k estimate "
                         "(from each record)")
    estimate = bool(args.k) and any(name == "estimate" for name, _ in args.k)
    if estimate and len(args.k) > 1:
        raise ValueError("--k estimate estimates every parameter of the models; give it alone")
    names = list(dict.fromkeys(n for m in fp.values() for n in m.model.k_names))
    given = {} if estimate or not fp else _k_given(args, data, only=names[0] if len(names) == 1 else None)
    for flag, m in fp.items():
        missing = [n for n in m.model.k_names if n not in given]
        if not estimate and missing:
            raise ValueError(f"--k: {flag} is a functionally pooled model over {', '.join(m.model.k_names)}; give "
                             f"{' '.join(f'--k {n}=VALUE' for n in missing)}")
    unused = [n for n in given if not any(n in m.model.k_names for m in fp.values())]
    if unused:
        raise ValueError(f"--k {unused[0]}: no model is pooled over {unused[0]!r} (their operating parameters: "
                         f"{', '.join(names)})")
    for flag, m in fp.items():          # a logged point beyond the fitted range: the polynomials extrapolate
        for n, (lo, hi) in zip(m.model.k_names, m.model.k_range if given else []):
            out = sorted({float(v) for v in given[n] if not lo <= v <= hi})
            if out:
                warnings.warn(f"--k {n}={','.join(f'{v:g}' for v in out)}: outside the range {flag} was fitted on "
                              f"({n} in [{lo:g}, {hi:g}]), where its polynomials extrapolate", CoverageWarning,
                              stacklevel=2)
    points, used = [], []
    for i, frame in enumerate(data.frames):
        at, ks = {}, {}
        for flag, m in models.items():
            if flag not in fp:
                at[flag] = m
                continue
            if estimate:
                k = _estimate(data, i, frame, flag, m)
            else:
                k = np.array([given[n][i] for n in m.model.k_names])
            at[flag] = m.at(k)
            ks[flag] = dict(zip(m.model.k_names, k.tolist()))
        points.append(at)
        used.append(ks)
    return points, used


def _estimate(data: _Data, i: int, frame: pd.DataFrame, flag: str, model: Any) -> np.ndarray:
    """:meth:`tsfdi.models.FPResults.estimate_k` of record ``i``, printed with its interval (warnings naming the
    record)."""
    if max(model.model.degree) == 0:
        raise ValueError(f"--k estimate: {flag} has degree 0: it does not depend on "
                         f"{', '.join(model.model.k_names)}, which cannot be estimated from it; give "
                         f"{' '.join(f'--k {n}=VALUE' for n in model.model.k_names)}")
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            est = model.estimate_k(frame, data.u(i))
        except (ValueError, TypeError) as exc:
            raise _reword(exc, data, record=i) from None
    where = f"{data.rec.origin(i)}, {flag}"
    for w in said:
        warnings.warn(f"{where}: {w.message}", w.category, stacklevel=2)
    level = f"{100 * (1 - est.alpha):g} %"
    parts = [f"{n} = {v:.6g} ({level} interval {lo:.6g} to {hi:.6g})"
             for n, v, (lo, hi) in zip(est.names, est.k_hat, est.conf_int)]
    print(f"{where}: estimated {', '.join(parts)}" + (
        "; at a bound of the fitted range: the record may lie outside it" if est.at_bound else ""))
    return np.asarray(est.k_hat, dtype=float)


def _k_columns(used: dict, baseline: str | None = None) -> dict[str, float]:
    """The operating points of one record as table columns: ``k_NAME`` for ``baseline`` (the flag of the baseline),
    ``k_NAME_MODEL`` for a model of ``--models`` (the prefix keeps them apart from the table's own columns)."""
    return {(f"k_{n}" if flag == baseline else f"k_{n}_{flag.rpartition(' ')[2]}"): v
            for flag, ks in used.items() for n, v in ks.items()}


def _test(args: argparse.Namespace, threshold: Any = "theoretical") -> Any:
    """The test of ``--method``: one, or (several joined by '+') their :class:`tsfdi.AnyOf`, sharing ``--alpha`` by
    Sidak."""
    from tsfdi.detection import AnyOf, FTest, LjungBox, MeanTest

    tests = [LjungBox(lags=args.lags, alpha=args.alpha, threshold=threshold) if m == "whiteness" else
             (FTest if m == "variance" else MeanTest)(alpha=args.alpha, threshold=threshold) for m in args.method]
    return tests[0] if len(tests) == 1 else AnyOf(tests)


def _tests(args: argparse.Namespace, models: dict, window: int | None) -> Any:
    """The test of ``args``: one with the theoretical threshold for every model, or (``--threshold calibrated``)
    one per model calibrated for windows of ``window`` samples (:meth:`tsfdi.LjungBox.calibrated_for`).
    ``models`` maps a name (the key the engine uses) to ``(flag text, results)``."""
    from tsfdi.detection import ScaledChi2Threshold

    if args.threshold == "theoretical":
        for flag, value in (("--min-windows", args.min_windows), ("--min-records", args.min_records)):
            if value is not None:
                raise ValueError(f"{flag} is for --threshold calibrated")
        return _test(args)
    min_windows = 30 if args.min_windows is None else args.min_windows
    if min_windows < 5:
        raise ValueError(f"--min-windows must be at least 5, got {min_windows}")
    if window is None:
        raise ValueError("--threshold calibrated needs --window: the threshold is calibrated for windows of one "
                         "length")
    flags = {f"models[{name!r}]": flag for name, (flag, _) in models.items()}
    try:
        if args.min_records is not None and args.min_records < 2:
            raise ValueError(f"--min-records must be at least 2, got {args.min_records}")
        threshold = ScaledChi2Threshold(args.alpha, min_windows=min_windows, min_records=args.min_records)
        return _test(args, threshold).calibrated_for(
            {name: res for name, (_, res) in models.items()}, window=window)
    except ValueError as exc:
        which, _, rest = str(exc).partition(": ")
        raise ValueError(f"--threshold calibrated, {flags.get(which, which)}: {rest}") from None


def _test_args(p: argparse.ArgumentParser, lags: int = 20) -> None:
    p.add_argument("--method", type=opt.method, default="whiteness", metavar="{whiteness,variance,mean}[+...]",
                   help="residual test: Ljung-Box whiteness test, F test of the residual variance, or test of a "
                        "shift of the residual mean (a new trim: what a closed loop leaves of a compensated "
                        "fault; use it with --threshold calibrated); several joined by '+' (e.g. "
                        "whiteness+variance+mean) flag a window when one of them rejects, each at its Sidak share "
                        "of --alpha (tsfdi.AnyOf)")
    p.add_argument("--alpha", type=opt.probability, default=1e-3,
                   help="false-alarm rate of a tested window's decision (the channels share it by Sidak, as the "
                        "test classes do by default); the test classes of tsfdi default to 0.05 for one test, the "
                        "command tests many windows (at 0.05, one false alarm in 20 windows)")
    p.add_argument("--lags", type=opt.count, default=lags,
                   help="Ljung-Box lags (20 as LjungBox(); 25 for monitor, as in paper 003)")
    p.add_argument("--threshold", choices=("theoretical", "calibrated"), default="theoretical",
                   help="theoretical: the test's chi-square / F law, exact only for the data the model was fitted "
                        "on; calibrated: the law of the statistic fitted to the model's held-out residuals (each "
                        "record it was fitted on, through the model fitted on the others; one record is cut into "
                        "blocks), so that --alpha holds on new records (needs --window)")
    p.add_argument("--min-windows", type=opt.count, default=None,
                   help="--threshold calibrated: fewest non-overlapping windows of held-out residuals the threshold "
                        "may rest on (default 30, at least 5); with few, its bound over the records is wider")
    p.add_argument("--min-records", type=opt.count, default=None,
                   help="--threshold calibrated: fewest held-out records the threshold may rest on (default: what "
                        "--alpha needs for a new record's spread to be predicted, 3 at 0.01, 4 at 0.001; at least "
                        "2); with fewer the threshold widens, as the spread of few records is uncertain")


def _window_args(p: argparse.ArgumentParser, window_help: str, *, required: bool = False) -> None:
    samples = ("a bare integer counts samples (as pandas rolling), a time span such as '2s' or '500ms' is "
               "converted with the sampling frequency")
    p.add_argument("--window", type=opt.span, default=None, required=required, help=f"{window_help}: {samples}")
    p.add_argument("--step", type=opt.span, default="1s", help=f"distance between window starts: {samples}")


def _min_samples(args: argparse.Namespace, models: dict) -> tuple[int, str]:
    """Fewest samples a tested window needs (the models' largest order plus the test's ``min_resid``), and why."""
    order = max(int(m.model.max_lag) for m in models.values())
    test = " + ".join({"whiteness": f"--lags {args.lags}", "variance": "the F test", "mean": "the mean test"}[m]
                      for m in args.method)
    return order + _test(args).min_resid, f"the models' largest order ({order}) with {test}"


def _windows_in_samples(args: argparse.Namespace, data: _Data, models: dict) -> tuple[int, int]:
    """``--window`` and ``--step`` in samples, checked against the records and the models' orders."""
    from tsfdi._data import window_samples

    W = window_samples(args.window, "--window", data.rec.fs, minimum=2)
    S = window_samples(args.step, "--step", data.rec.fs, minimum=1)
    need, why = _min_samples(args, models)
    if W < need:
        raise ValueError(f"--window {args.window}: {data.span(W)} at {data.rec.fs:g} Hz is too short; {why} needs "
                         f"at least {need} samples")
    shortest = min(range(len(data.frames)), key=lambda i: len(data.frames[i]))
    if W > len(data.frames[shortest]) and not data.split:
        raise ValueError(f"--window {args.window}: {data.span(W)} is longer than {data.about(shortest)} "
                         f"({data.span(len(data.frames[shortest]))} at {data.rec.fs:g} Hz)")
    print(f"window {data.span(W)}, step {data.span(S)}, at {data.rec.fs:g} Hz")
    return W, S


def _table(rows: list[pd.DataFrame], data: _Data) -> pd.DataFrame:
    """Per-record tables stacked, with a leading ``record`` column when the data holds records."""
    names = data.rec.names()
    if any(names):
        rows = [r.assign(record=rid)[["record", *r.columns]] for r, rid in zip(rows, names)]
    return pd.concat(rows, ignore_index=True)


def _show(table: pd.DataFrame) -> None:
    print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}") if len(table) else "(no rows)")


def _write(flag: str, table: pd.DataFrame, path: str | None) -> None:
    if path:
        try:
            table.to_csv(path, index=False)
        except OSError as exc:
            raise ValueError(f"{flag} {path}: cannot write the file ({exc.strerror or exc})") from None
        print(f"wrote {path}")


# ---------------------------------------------------------------------------------------------------- simulate
def _simulate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, help="output file: netCDF, or a zarr store (format 2) for a name ending in "
                                                ".zarr; either is chunked by record")
    p.add_argument("--records-per-case", type=opt.count, default=20, help="records per state and turbulence level")
    p.add_argument("--seed", type=opt.seed, default=2024, help="base seed (record k uses SeedSequence([seed, k]))")
    p.add_argument("--duration", type=opt.duration, default="60s", help="record length, a time span such as '60s'")
    p.add_argument("--failure-time", type=opt.time_from_start, default="10s",
                   help="failure instant from the record's start, a time span such as '10s'")
    p.add_argument("--speed", type=opt.finite, default=5.0, help="forward speed in m/s")
    p.add_argument("--aircraft", choices=("regular", "bidirectional"), default="regular",
                   help="regular (default): blade-element rotors that turn one way, rotor drag, weathervane, gains "
                        "scheduled over the speed; bidirectional: tsfdi's previous aircraft (bidirectional rotors, "
                        "lumped rotor coefficients, no rotor drag or weathervane), for comparison only")
    p.add_argument("--scale-length", type=opt.scale_length, default=argparse.SUPPRESS, metavar="M",
                   help="Dryden scale length in m of the three linear gusts, or 'mil' for the MIL-F-8785C low-altitude "
                        "lengths of the altitude (default: tsfdi.datasets.hexacopter.PAPER_SCALE_LENGTH, paper 003's "
                        "hub-to-hub distance)")
    p.add_argument("--intensity-scale", type=opt.positive, default=argparse.SUPPRESS, metavar="K",
                   help="factor on the MIL-F-8785C turbulence intensities (default: "
                        "tsfdi.datasets.hexacopter.PAPER_INTENSITY_SCALE, chosen on paper 003's published physical "
                        "quantities; 1: the standard's). The previous shipped file: --aircraft bidirectional "
                        "--scale-length mil --intensity-scale 1")
    p.add_argument("--states", default="healthy,rotor1,rotor2,rotor6",
                   help="comma-separated states: healthy, rotor1 .. rotor6")
    p.add_argument("--turbulence", default="light,moderate,severe",
                   help="comma-separated Dryden levels: none, light, moderate, severe")
    p.add_argument("--dt", type=opt.duration, default="1ms", help="integration step, a time span such as '1ms'")
    p.add_argument("--fs", type=opt.positive, default=100.0, help="output sampling frequency in Hz")
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
    p.add_argument("--chunk", type=opt.count, default=20,
                   help="records per chunk: the chunks are simulated in parallel on the dask scheduler and written "
                        "as they come, so memory holds a few chunks (each chunk x duration x fs x 34 x 8 bytes, and "
                        "the 1 kHz integration of 16 records at a time), whatever the number of records")
    p.add_argument("--scheduler", default="threads",
                   help="dask scheduler of the chunks: threads, processes, synchronous, or the address of a running "
                        "dask.distributed scheduler (e.g. tcp://10.0.0.1:8786) to simulate on its cluster")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


@command("simulate", "simulate hexacopter records (Dryden turbulence, rotor failures) to a netCDF file or zarr store "
         "chunked by record, the chunks in parallel on dask", _simulate_args)
def _simulate(args: argparse.Namespace) -> int:
    import importlib.util

    from tsfdi.datasets.hexacopter import BIDIRECTIONAL_HEXACOPTER, FleetSpread, write_hexacopter_dataset

    _check_out("--out", args.out)
    zarr = Path(args.out).suffix.lower() == ".zarr"
    if importlib.util.find_spec("dask") is None:      # without the fleet extra: netCDF, simulated in memory
        if zarr or args.scheduler != "threads":
            raise ValueError(f"{'--out ' + args.out if zarr else '--scheduler'}: needs dask and zarr (pip install "
                             "'tsfdi[fleet]')")
        args.chunk = None
    t0 = time.perf_counter()
    fleet = None if args.fleet is None else FleetSpread.from_spec(args.fleet)
    try:
        written = write_hexacopter_dataset(args.out, args.records_per_case, seed=args.seed, duration=args.duration,
                                           failure_time=args.failure_time, speed=args.speed,
                                           states=tuple(s.strip() for s in args.states.split(",")),
                                           turbulence=tuple(s.strip() for s in args.turbulence.split(",")),
                                           dt=args.dt, fs=args.fs, fleet=fleet, shipped=args.shipped,
                                           params=BIDIRECTIONAL_HEXACOPTER if args.aircraft == "bidirectional" else None,
                                           **{k: getattr(args, k) for k in ("scale_length", "intensity_scale")
                                              if hasattr(args, k)},
                                           chunks=args.chunk, scheduler=args.scheduler, progress=not args.no_progress)
    except OSError as exc:
        raise ValueError(f"--out {args.out}: cannot write the file ({exc.strerror or exc})") from None
    except ValueError as exc:                       # tsfdi.fleet's words for the dask scheduler
        raise ValueError(re.sub(r"^scheduler\b", "--scheduler", str(exc))) from None
    print(f"wrote {written.sizes['record']} records to {args.out} in {time.perf_counter() - t0:.1f} s; "
          f"lost control in {int(written['lost_control'].sum())} record(s)")
    return 0


# ----------------------------------------------------------------------------------------------------- demo
def _demo_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="tsfdi-demo", help="output folder for the figures and tables")
    p.add_argument("--data", default=None, help="hexacopter netCDF file (default: the shipped data/hexacopter.nc)")
    p.add_argument("--records-per-case", type=opt.two_or_more, default=None,
                   help="use only the first N records of each state and turbulence level (N >= 2; default all)")
    p.add_argument("--fit-records", type=opt.count, default=10,
                   help="baseline records per state and turbulence level, pooled (excluded from the evaluation)")
    p.add_argument("--pool", choices=("level", "all"), default="level",
                   help="baseline models per turbulence level, or one set across levels")
    p.add_argument("--order", type=opt.order, default="20", help="model order: an integer, 'bic' or 'rss_sss'")
    p.add_argument("--windows", type=opt.spans, default="5s,10s,20s",
                   help="comma-separated window lengths: time spans such as '10s', or integers counting samples")
    p.add_argument("--models", default=None, help="comma-separated models: roll, pitch, yaw_rate, var (default all)")
    p.add_argument("--methods", default="whiteness,variance", help="comma-separated: whiteness, variance")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.add_argument("--no-figures", action="store_true", help="do not write figures")


@command("demo", "run the whole Dutta et al. study on the shipped hexacopter data: baselines (Table 2), "
                 "identification (Table 4), detection rates and figures", _demo_args)
def _demo(args: argparse.Namespace) -> int:
    from tsfdi.datasets import load_hexacopter
    from tsfdi.datasets.hexacopter import SIGNAL_CHANNELS
    from tsfdi.study import demo_report, hexacopter_study, paper_tests, write_report

    _check_out("--out", args.out)
    t0 = time.perf_counter()
    try:
        data = load_hexacopter(args.data)
    except (OSError, ValueError) as exc:
        if isinstance(exc, FileNotFoundError):
            raise ValueError(f"--data {args.data}: the file does not exist") from None
        raise ValueError(f"--data {args.data}: cannot be read as a hexacopter netCDF file ({exc})") from None
    models = opt.csv_list(args.models)
    tests = paper_tests(models or [*SIGNAL_CHANNELS, "var"], opt.csv_list(args.methods))
    bases, ev = hexacopter_study(data, records_per_case=args.records_per_case, models=models, tests=tests,
                                 windows=args.windows, fit_records=args.fit_records, pool=args.pool,
                                 order=args.order, progress=not args.no_progress)
    print(demo_report(bases, ev))
    written = write_report(bases, ev, data, args.out, figures=not args.no_figures)
    print(f"wrote {written[0]} and {len(written) - 2} figure(s) under {written[0].parent / 'figures'} in "
          f"{time.perf_counter() - t0:.1f} s")
    return 0


# ------------------------------------------------------------------------------------------- fit / select-order
def _order_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, records_help="required when the file holds several records; several are pooled into one "
                                   "model")
    p.add_argument("--model", choices=("ar", "var"), default=None,
                   help="ar (one column) or var (several); default from the number of columns (with --u: arx of "
                        "one column, varx of several)")
    _u_arg(p, fit=True)
    p.add_argument("--nk", type=lambda t: opt.integer(t, 0), default=0,
                   help="with --u: the input delay in samples (0: u[t] acts on y[t], as a command on the rate it "
                        "drives within a sample)")
    p.add_argument("--max-lags", type=opt.count, default=20, help="largest order searched")
    p.add_argument("--trend", choices=("n", "c"), default="n",
                   help="n: no intercept (signals about zero, as the papers' models); c: an intercept, for signals "
                        "with a non-zero level such as commands holding a trim (then --method mean tests a change "
                        "of that level)")
    p.add_argument("--criterion", choices=("logdet", "trace"), default="logdet",
                   help="BIC of a VAR from the log-determinant or the trace of the residual covariance")
    p.add_argument("--k", type=opt.operating_point, action="append", default=None, metavar="NAME[=VALUE,...]",
                   help="operating parameter of the records, making the model functionally pooled (FP-AR / FP-VAR, "
                        "tsfdi.models.FPVAR: its coefficients are Legendre polynomials of k, fitted on every record "
                        "at once): one value per data file, in the order of the files, every record of a file at "
                        "its file's value, e.g. --k depth=0,0,4 for three files (at least two distinct values; "
                        "without NAME= the parameter is named k); "
                        "or NAME, the per-record coordinate NAME of netCDF data (e.g. --k mass for the records of "
                        "'tsfdi simulate --fleet'); repeat --k for several parameters (--k speed=2,5,8 --k "
                        "mass=1.2,1.2,1.5)")
    p.add_argument("--max-degree", type=lambda t: opt.integer(t, 0), default=None,
                   help="with --k: largest degree searched (default 2, or one less than the fewest distinct values "
                        "of a parameter)")


def _fit_records(args: argparse.Namespace) -> tuple[_Data, str, list]:
    """The records of ``args`` to fit on, the model kind (``"ar"`` / ``"var"`` / ``"arx"`` / ``"varx"``) and the
    signals (the inputs of an ARX / VARX in ``data.inputs``)."""
    data = _read(args, require_choice=True, inputs=args.u)
    data = _drop_short(data, args.max_lags + args.nk + 2, f"--max-lags {args.max_lags}")
    k = len(data.columns)
    if args.u is None and args.nk:
        raise ValueError(f"--nk {args.nk} is the input delay of an ARX / VARX model: give its inputs with --u, or "
                         "leave it "
                         "out")
    if args.u is not None:
        if args.model is not None:
            raise ValueError(f"--model {args.model}: with --u the model is an ARX (one output given the inputs) or a "
                             "VARX (several outputs given the inputs), from the number of --columns; leave --model out")
        if k != 1 and args.k is not None:
            raise ValueError(f"--u with --k: a functionally pooled input-output model (FP-ARX) has one output, but the "
                             f"data gives {k} other column(s) {data.columns}: pick the output with --columns (one "
                             "FP-ARX per output)")
        return (data, "arx", [f.iloc[:, 0] for f in data.frames]) if k == 1 else (data, "varx", list(data.frames))
    model = args.model or ("ar" if k == 1 else "var")
    if model == "ar" and k != 1:
        raise ValueError(f"--model ar needs one column, got {k} {data.columns}: pick one with --columns")
    if model == "var" and k < 2:
        raise ValueError(f"--model var needs at least two columns, got {data.columns}: add some with --columns")
    return data, model, [f.iloc[:, 0] if model == "ar" else f for f in data.frames]


def _order_selection(args: argparse.Namespace) -> tuple[Any, _Data, str]:
    """``select_order`` on the records of ``args`` (pooled when several)."""
    from tsfdi.selection import select_order

    data, model, ys = _fit_records(args)
    try:
        us = data.inputs
        sel = select_order(ys if len(ys) > 1 else ys[0], args.max_lags, model, trend=args.trend,
                           criterion=args.criterion, **({} if us is None else {"u": us if len(us) > 1 else us[0],
                                                                             "nk": args.nk}))
    except (ValueError, TypeError) as exc:
        raise _reword(exc, data, (("lags=", "--max-lags "),)) from None
    return sel, data, model


def _fit_args(p: argparse.ArgumentParser) -> None:
    _order_args(p)
    p.add_argument("--out", required=True, help="output .npz file for the fitted model")
    p.add_argument("--lags", type=opt.count, default=None, help="fixed order (default: the order of smallest BIC)")
    p.add_argument("--coefficients", action="store_true", help="print the coefficient tables too (default: the "
                   "model's header only; tsfdi.load(FILE).summary() shows them in Python)")
    p.add_argument("--quiet", action="store_true", help="print only the one-line result and where it was saved")
    p.add_argument("--degree", type=lambda t: opt.integer(t, 0), default=None,
                   help="with --k: the polynomials' degree in every parameter (default: the degree of smallest "
                        "BIC, 0 .. --max-degree, with the order, on a common sample: tsfdi.models.select_fp_order)")


@command("fit", "fit an AR / VAR baseline model (order by BIC) on records of a CSV, netCDF or flight-log file and "
                "save it (.npz); with --u, an ARX (one output) or VARX (several) given the input columns; with --k, "
                "a functionally pooled model over operating points", _fit_args)
def _fit(args: argparse.Namespace) -> int:
    _check_out("--out", args.out)
    if args.lags is not None and args.lags > args.max_lags:
        raise ValueError(f"--lags {args.lags} exceeds --max-lags {args.max_lags}")
    if args.k is not None:
        return _fit_fp(args)
    for flag, value in (("--degree", args.degree), ("--max-degree", args.max_degree)):
        if value is not None:
            raise ValueError(f"{flag} is the degree of a functionally pooled model: give the records' operating "
                             "points with --k, or leave it out")
    sel, data, model = _order_selection(args)
    res = sel.fit(args.lags)
    if bool(np.asarray(sel.values["exact"])[list(sel.orders).index(res.lags)]):
        said = "; ".join(sel.spec.collinear_channels())
        raise ValueError(f"{model.upper()}({res.lags}) fits the {len(data.columns)} column(s) of {data.path} exactly: "
                         f"collinear or constant channels{f' ({said})' if said else ''}, so the model would explain "
                         "any flight and detect nothing; not saved. Choose the channels with --columns"
                         + (" and --u (an input that copies the output explains it exactly)" if args.u else ""))
    name = (f"{model.upper()}({res.lags}, {res.lags}, nk={args.nk}) of {data.columns} given --u {args.u}" if args.u else
            f"{model.upper()}({res.lags}) on {data.columns}")
    return _save_fitted(res, args, f"{name} from {len(data.frames)} record(s) "
                        f"at {data.rec.fs:g} Hz ({res.nobs} samples): BIC {res.bic:.6g}, RSS/SSS {res.rss_sss:.4g} %, "
                        f"SPP {res.spp:.2f}")


def _save_fitted(res: Any, args: argparse.Namespace, *lines: str) -> int:
    """``fit``: save ``res`` to ``--out``, print ``lines``, the summary (its coefficient tables with
    ``--coefficients``; nothing with ``--quiet``) and where it was saved."""
    try:
        written = res.save(args.out)
    except OSError as exc:
        raise ValueError(f"--out {args.out}: cannot write the file ({exc.strerror or exc})") from None
    for line in lines:
        print(line)
    if not args.quiet:
        summary = res.summary()
        print(str(summary if args.coefficients else dataclasses.replace(summary, tables=[])))
    print(f"saved to {written}")
    return 0


def _fp_records(args: argparse.Namespace) -> tuple[_Data, str, list, pd.DataFrame, int]:
    """``fit`` / ``select-order --k``: the records, the model kind, the signals, their operating points (a DataFrame,
    one column per parameter) and the largest degree to search."""
    if any(name == "estimate" for name, _ in args.k):
        raise ValueError("--k estimate is for detect / identify / monitor (the k of a record under a fitted model); "
                         f"{args.command} needs the operating point of every data file: --k NAME=VALUE,VALUE,...")
    data, model, ys = _fit_records(args)
    k = pd.DataFrame(_k_given(args, data, fit=True))
    distinct = k.nunique()
    if (distinct < 2).any():
        name = distinct.idxmin()
        raise ValueError(f"--k {name}: every record is at {name} = {k[name].iloc[0]:g}; a functionally pooled model "
                         "needs records at two or more operating points")
    most = int(distinct.min()) - 1          # a degree needs one more distinct value of every parameter
    degree = getattr(args, "degree", None)
    if None not in (degree, args.max_degree) and degree > args.max_degree:
        raise ValueError(f"--degree {degree} exceeds --max-degree {args.max_degree}")
    for flag, value in (("--degree", degree), ("--max-degree", args.max_degree)):
        if value is not None and value > most:
            raise ValueError(f"{flag} {value}: {distinct.idxmin()} takes {most + 1} distinct values in the records, "
                             f"enough for degree {most} at most")
    return data, model, ys, k, next(v for v in (degree, args.max_degree, min(2, most)) if v is not None)


def _fp_range(k_range: Any, names: Any) -> str:
    return ", ".join(f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi) in zip(names, k_range))


def _fit_fp(args: argparse.Namespace) -> int:
    """``fit --k``: an FP-AR / FP-VAR over the records' operating points, order and degree by BIC unless given."""
    from tsfdi.models import FPAR, FPARX, FPVAR, select_fp_order

    data, model, ys, k, max_degree = _fp_records(args)
    subs = (("max_lags", "--max-lags"), ("lags=", "--lags "), ("degree=", "--degree "), ("k: ", "--k: "))
    inputs = {} if data.inputs is None else {"u": data.inputs, "nk": args.nk}
    try:
        if args.lags is not None and args.degree is not None:
            res = (FPARX(ys, data.inputs, k, args.lags, args.lags, args.nk, args.degree, args.trend) if inputs else
                   {"ar": FPAR, "var": FPVAR}[model](ys, k, args.lags, args.degree, args.trend)).fit()
            how = "given"
        else:
            sel = select_fp_order(ys, k, args.max_lags, max_degree, model, trend=args.trend, **inputs)
            bic = sel.table["bic"]
            if args.lags is not None:
                bic = bic[bic.index.get_level_values("lags") == args.lags]
            if args.degree is not None:
                bic = bic[bic.index.get_level_values("degree") == args.degree]
            if not np.isfinite(bic).any():
                raise ValueError("no order and degree asked for gives a well-conditioned fit")
            lags, degree = bic.idxmin()
            res = sel.fit(int(lags), int(degree))
            how = f"BIC over lags 1..{args.max_lags}, degree 0..{max_degree}"
    except (ValueError, TypeError) as exc:
        raise _reword(exc, data, subs) from None
    m = res.model
    order = f"{m.na}, {m.na}, nk={args.nk}" if inputs else f"{m.na}"
    lines = [f"FP-{model.upper()}({order}), degree {', '.join(map(str, m.degree))} ({how}) over "
             f"{_fp_range(m.k_range, m.k_names)} on {data.columns} "
             f"from {len(data.frames)} record(s) at {len(k.drop_duplicates())} operating point(s), {data.rec.fs:g} Hz "
             f"({res.nobs} samples): BIC {res.bic:.6g}"]
    if max(m.degree) == 0:
        lines.append(f"note: degree 0: the model does not depend on {', '.join(m.k_names)} (one pooled "
                     f"{model.upper()}), which detect / identify / monitor --k estimate cannot estimate from it; "
                     "--degree 1 fits a dependence")
    return _save_fitted(res, args, *lines)


def _select_order_args(p: argparse.ArgumentParser) -> None:
    _order_args(p)
    p.add_argument("--out", default=None, help="write the table to this CSV file")


@command("select-order", "tabulate BIC, AIC, RSS/SSS and SPP of the orders 1 .. --max-lags on a common sample "
                         "(with --k: the log-likelihood, AIC and BIC of every order and degree of a functionally "
                         "pooled model)", _select_order_args)
def _select_order(args: argparse.Namespace) -> int:
    from tsfdi.models import select_fp_order

    _check_out("--out", args.out)
    if args.k is None:
        if args.max_degree is not None:
            raise ValueError("--max-degree is the degree of a functionally pooled model: give the records' operating "
                             "points with --k, or leave it out")
        sel, data, model = _order_selection(args)
        print(f"{model.upper()} on {data.columns} from {len(data.frames)} record(s) at {data.rec.fs:g} Hz")
    else:
        data, model, ys, k, max_degree = _fp_records(args)
        try:
            sel = select_fp_order(ys, k, args.max_lags, max_degree, model, trend=args.trend,
                                  **({} if data.inputs is None else {"u": data.inputs, "nk": args.nk}))
        except (ValueError, TypeError) as exc:
            raise _reword(exc, data, (("max_lags", "--max-lags"),)) from None
        print(f"FP-{model.upper()} over {_fp_range(sel.spec['k_range'], k.columns)} on {data.columns} from "
              f"{len(data.frames)} record(s) at {len(k.drop_duplicates())} operating point(s), {data.rec.fs:g} Hz")
    print(str(sel.summary()))
    _write("--out", sel.table.reset_index(), args.out)
    return 0


# --------------------------------------------------------------------------------------------------- detect
def _detect_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, columns_help="comma-separated columns, matched to the baseline's channels by name (default: "
                                   "the baseline's channels)")
    p.add_argument("--baseline", required=True, help="healthy model (.npz from 'tsfdi fit')")
    _u_arg(p)
    _window_args(p, "window length (default: each whole record)")
    _test_args(p)
    _k_arg(p)
    p.add_argument("--out", default=None, help="write the table to this CSV file")


@command("detect", "test a signal against a healthy baseline model: the decision per record, or per window",
         _detect_args)
def _detect(args: argparse.Namespace) -> int:
    from tsfdi.identification import detect
    from tsfdi.windows import ResidualWindows

    _check_out("--out", args.out)
    baseline = _load("--baseline", args.baseline, args.baseline)
    flag = f"--baseline {args.baseline}"
    data = _read(args, _channels(baseline), inputs=_input_columns(args, {flag: baseline}))
    _check_channels(data, {flag: baseline})
    rows = []
    if args.window is None:
        data = _drop_short(data, *_min_samples(args, {"baseline": baseline}))
        points, used = _operating_points(args, data, {flag: baseline})
        _warn_uncovered(args.baseline, [p[flag] for p in points], data)
        test = _tests(args, {}, None)
        # the library's own coverage warning ("detect: ...") is the one _warn_uncovered said above, naming the file
        for i, frame, d in _each(data, lambda i, frame: _quiet(detect, frame, points[i][flag], test, u=data.u(i))):
            print(f"{data.rec.origin(i)} ({data.span(len(frame))} at {data.rec.fs:g} Hz, {frame.index[0]:g} s to "
                  f"{frame.index[-1]:g} s):\n{str(d.summary())}\n")
            per_channel = [np.atleast_1d(np.asarray(a))[None, :] for a in (d.statistic, d.threshold, d.pvalue,
                                                                            d.reject)]
            rows.append(_detect_rows(data, frame, [0], len(frame), d.channels, *per_channel).assign(
                **_k_columns(used[i], flag)))
    else:
        W, S = _windows_in_samples(args, data, {"baseline": baseline})
        data = _drop_short(data, W, f"--window {args.window}")
        points, used = _operating_points(args, data, {flag: baseline})
        _warn_uncovered(args.baseline, [p[flag] for p in points], data)
        test = _tests(args, {"baseline": (flag, baseline)}, W)
        for i, frame, ws in _each(data, lambda i, frame: ResidualWindows({"baseline": points[i][flag]}).fit(
                frame, u=data.u(i)).statistics(test, window=W, step=S, loglik=False)):
            rows.append(_detect_rows(data, frame, ws.starts, W, ws.channels, ws.statistic[:, 0], ws.threshold[:, 0],
                                     ws.pvalue[:, 0], ws.channel_reject[:, 0]).assign(**_k_columns(used[i], flag)))
    table = _table(rows, data)
    if args.window is not None:
        _show(table)
    n = int(table["fault"].sum())
    print(f"fault in {n} of {len(table)} {'window' if args.window is not None else 'record'}(s)")
    _write("--out", table, args.out)
    return 0


def _warn_uncovered(path: str, baselines: list, data: _Data) -> None:
    """A warning per record of ``data`` that the records its baseline (``baselines[i]``: the ``--baseline`` model, at
    the record's operating point when functionally pooled) was fitted on do not cover
    (:func:`tsfdi.coverage.coverage` at its default rate), when they are enough to say (an AR / VAR fitted on at least
    :data:`~tsfdi.coverage.MIN_RECORDS` records): its decisions are then out of the baseline's domain."""
    from tsfdi.coverage import MIN_RECORDS, coverage, warn_if_not_covered
    from tsfdi.exceptions import CoverageWarning
    from tsfdi.models import ARResults, VARResults

    first = baselines[0]
    if not isinstance(first, (ARResults, VARResults)) or len(first.model.records) < MIN_RECORDS:
        return
    try:
        held = first.model.held_out_residuals()
    except ValueError as exc:     # e.g. an FP fold with too few operating points: the tests themselves may still run
        warnings.warn(f"--baseline {path}: coverage not checked: {exc}", CoverageWarning, stacklevel=2)
        return
    for i, (frame, baseline) in enumerate(zip(data.frames, baselines)):
        where = f"{data.rec.origin(i)} against --baseline {path}"
        try:
            cov = coverage(baseline, frame, held_out=held)
        except ValueError as exc:         # e.g. a record too short for its summaries: the test itself may still run
            warnings.warn(f"{where}: coverage not checked: {exc}", CoverageWarning, stacklevel=2)
            continue
        warn_if_not_covered(cov, where)


def _quiet(run: Callable, *args: Any, **kwargs: Any) -> Any:
    """``run(*args, **kwargs)`` without the library's coverage warnings (the command says them itself, naming the
    file)."""
    from tsfdi.exceptions import CoverageWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CoverageWarning)
        return run(*args, **kwargs)


def _detect_rows(data: _Data, frame: pd.DataFrame, starts: Any, W: int, channels: Any, stat: Any, thr: Any,
                 pv: Any, rej: Any) -> pd.DataFrame:
    """One row per window: times on the record's clock, per channel statistic / threshold / p-value, fault."""
    start = frame.index.to_numpy()[np.asarray(starts, dtype=int)]
    out = {"start": start, "end": np.round(start + W / data.rec.fs, 9)}
    for j, c in enumerate(channels):
        out[f"statistic_{c}"] = np.asarray(stat)[:, j]
        out[f"threshold_{c}"] = np.asarray(thr)[:, j]
        out[f"pvalue_{c}"] = np.asarray(pv)[:, j]
    out["fault"] = np.asarray(rej, dtype=bool).any(axis=1)
    return pd.DataFrame(out)


# ------------------------------------------------------------------------------------------------- identify
def _identify_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, columns_help="comma-separated columns, matched to the models' channels by name (default: the "
                                   "models' channels)")
    p.add_argument("--models", required=True, nargs="+", metavar="NAME=PATH",
                   help="saved models (.npz from 'tsfdi fit'), as NAME=PATH or PATH (name = file stem); each "
                        "name once")
    _u_arg(p)
    _window_args(p, "window length (default: each whole record)")
    _test_args(p)
    p.add_argument("--rule", choices=("paper", "likelihood", "pvalue", "sprt"), default="paper",
                   help="decision rule turning the models' acceptances into a label; 'sprt': one sequential "
                        "decision per record (the multi-hypothesis sequential probability ratio test on the models' "
                        "per-sample log-likelihoods, from the record's first sample; no window, no residual test), "
                        "with its decision time")
    p.add_argument("--sprt-alpha", type=opt.probability, default=0.01,
                   help="error probability of the sequential rule's bound (--rule sprt)")
    _k_arg(p)
    p.add_argument("--out", default=None, help="write the table to this CSV file")


def _identify_sequential(args: argparse.Namespace, data: _Data, models: dict) -> list[pd.DataFrame]:
    """``identify --rule sprt``: one row per record, the model the sequential test decides for and when."""
    from tsfdi.detection.sequential import msprt
    from tsfdi.windows import ResidualWindows

    if args.window is not None:
        raise ValueError("--window does not apply to --rule sprt (one sequential decision per record); leave it out")
    if args.threshold != "theoretical":
        raise ValueError("--threshold calibrated does not apply to --rule sprt (no residual test); leave it out")
    order = max(int(m.model.max_lag) for m in models.values())
    data = _drop_short(data, order + 2, f"the models' largest order ({order}) with --rule sprt")
    points, used = _operating_points(args, data, {f"--models {n}": m for n, m in models.items()})
    rows = []
    for i, frame, seq in _each(data, lambda i, frame: msprt(ResidualWindows(dict(zip(models, points[i].values()))).fit(
            frame, u=data.u(i)).loglik(), alpha=args.sprt_alpha, models=list(models))):
        t = frame.index.to_numpy()
        decided = seq.label >= 0
        rows.append(pd.DataFrame({"start": [t[order]],
                                  "decision_time": [t[order + seq.decision_time - 1] if decided else np.nan],
                                  "status": ["identified" if decided else "undecided"],
                                  "label": [list(models)[seq.label] if decided else ""], **_k_columns(used[i])}))
    return rows


@command("identify", "identify which saved model fits a signal, per record or window by window", _identify_args)
def _identify(args: argparse.Namespace) -> int:
    from tsfdi.identification import identify_windows

    _check_out("--out", args.out)
    models = _load_models("--models", args.models)
    given = {f"--models {n}": m for n, m in models.items()}
    data = _read(args, _channels(next(iter(models.values()))), inputs=_input_columns(args, given))
    _check_channels(data, given)
    if args.rule == "sprt":
        table = _table(_identify_sequential(args, data, models), data)
        _show(table)
        _write("--out", table, args.out)
        return 0
    if args.window is None:
        data = _drop_short(data, *_min_samples(args, models))
    else:
        W, S = _windows_in_samples(args, data, models)
        data = _drop_short(data, W, f"--window {args.window}")
    points, used = _operating_points(args, data, {f"--models {n}": m for n, m in models.items()})
    test = _tests(args, {n: (f"--models {n}", m) for n, m in models.items()}, None if args.window is None else W)
    rows = []
    whole = args.window is None         # each record is one window
    for i, frame, wins in _each(data, lambda i, frame: identify_windows(
            frame, dict(zip(models, points[i].values())), test, window=len(frame) if whole else W,
            step=len(frame) if whole else S, u=data.u(i))):
        start = frame.index.to_numpy()[wins.starts]
        table = pd.DataFrame({"start": start, "end": np.round(start + wins.windows.window / data.rec.fs, 9)})
        for j, name in enumerate(wins.models):
            table[f"pvalue_{name}"] = wins.windows.min_pvalue[:, j]
            table[f"accept_{name}"] = wins.accepted[:, j]
        # the status is that of the paper rule (how many models accept), whichever rule picks the label
        table["status"] = wins.status
        table["label"] = [lab or "" for lab in wins.decide(args.rule)]
        rows.append(table.assign(**_k_columns(used[i])))
    table = _table(rows, data)
    _show(table)
    _write("--out", table, args.out)
    return 0


# -------------------------------------------------------------------------------------------------- monitor
def _monitor_args(p: argparse.ArgumentParser) -> None:
    _add_data_args(p, columns_help="comma-separated columns, matched to the baseline's channels by name (default: "
                                   "the baseline's channels)")
    p.add_argument("--baseline", required=True, help="healthy model (.npz from 'tsfdi fit')")
    p.add_argument("--models", nargs="+", default=None, metavar="NAME=PATH",
                   help="fault models identifying the windows after a detection, as NAME=PATH or PATH (name = "
                        "file stem); default none: detection only")
    _u_arg(p)
    _window_args(p, "window length (required, except with --rule sprt)")
    p.add_argument("--steady-window", type=opt.span, default="10s",
                   help="rolling-variance window of the steady-state check (paper 003): identification starts once "
                        "the variance of every channel over this window is below its threshold, the largest over "
                        "the records the --models were fitted on; an integer counts samples, a time span such as "
                        "'10s' is converted with the sampling frequency")
    _test_args(p, lags=25)
    p.add_argument("--rule", choices=("paper", "likelihood", "pvalue", "sprt"), default="paper",
                   help="decision rule turning the fault models' acceptances into a label; 'sprt': sequential "
                        "monitoring, sample by sample (no window, no residual test): a restarted SPRT of the "
                        "baseline's residual variance detects, then the restarted multi-hypothesis SPRT of the "
                        "--models' log-likelihoods identifies, each event at its deciding sample")
    p.add_argument("--sprt-alpha", type=opt.probability, default=0.01,
                   help="--rule sprt: error probabilities of the detection SPRT (alpha = beta) and of the "
                        "identification's bound")
    p.add_argument("--sprt-ratio", type=opt.positive, default=2.0,
                   help="--rule sprt: the residual variance ratio (to the baseline's) the detection SPRT tests for")
    _k_arg(p)
    p.add_argument("--out", default=None, help="write the events to this CSV file")


def _monitor_sequential(args: argparse.Namespace, data: _Data, models: dict) -> tuple:
    """``monitor --rule sprt``: no window, no residual test; the detection SPRT of ``--sprt-ratio`` and
    ``--sprt-alpha``: the records long enough to have a residual, the step in samples, the SPRT and Monitor's
    keywords."""
    from tsfdi._data import window_samples
    from tsfdi.detection.sequential import SPRT

    if args.window is not None:
        raise ValueError("--window does not apply to --rule sprt (the statistic is sequential, sample by sample); "
                         "leave it out")
    if args.threshold != "theoretical":
        raise ValueError("--threshold calibrated does not apply to --rule sprt (no residual test); leave it out")
    if args.sprt_ratio == 1.0:
        raise ValueError("--sprt-ratio must differ from 1 (the fault's variance would be the baseline's)")
    S = window_samples(args.step, "--step", data.rec.fs, minimum=1)
    order = max(int(m.model.max_lag) for m in models.values())
    data = _drop_short(data, order + 1, f"the models' largest order ({order}) with --rule sprt")
    print(f"sequential (SPRT, variance ratio {args.sprt_ratio:g}, alpha {args.sprt_alpha:g}), rows every "
          f"{data.span(S)}, at {data.rec.fs:g} Hz")
    detection = SPRT("variance", ratio=args.sprt_ratio, alpha=args.sprt_alpha, beta=args.sprt_alpha, restart=True)
    return data, S, detection, {"sprt_alpha": args.sprt_alpha}


@command("monitor", "slide windows over a signal (or decide sample by sample, --rule sprt): detection with a "
                    "healthy baseline, then identification with fault models; prints and writes the events",
         _monitor_args)
def _monitor(args: argparse.Namespace) -> int:
    from tsfdi._data import window_samples
    from tsfdi.coverage import warn_if_not_covered
    from tsfdi.monitoring import Monitor

    _check_out("--out", args.out)
    baseline = _load("--baseline", args.baseline, args.baseline)
    models = _load_models("--models", args.models) if args.models else {}
    flag = f"--baseline {args.baseline}"
    given = {flag: baseline, **{f"--models {n}": m for n, m in models.items()}}
    data = _read(args, _channels(baseline), inputs=_input_columns(args, given))
    _check_channels(data, given)
    V = window_samples(args.steady_window, "--steady-window", data.rec.fs, minimum=2)
    if args.rule == "sprt":
        data, S, detection_test, sprt = _monitor_sequential(args, data, {"baseline": baseline, **models})
        points, used = _operating_points(args, data, given)
        W = test = None
    else:
        if args.window is None:
            raise ValueError("--window is required (except with --rule sprt)")
        W, S = _windows_in_samples(args, data, {"baseline": baseline, **models})
        data = _drop_short(data, W, f"--window {args.window}")
        points, used = _operating_points(args, data, given)
        tests = _tests(args, {"": (f"--baseline {args.baseline}", baseline),
                              **{n: (f"--models {n}", m) for n, m in models.items()}}, W)
        if isinstance(tests, dict):         # calibrated: the baseline's own test detects, each model's identifies
            detection_test = tests.pop("")
            test = tests or None
        else:
            test, detection_test = tests, None
        sprt = {}

    def build(at: dict) -> Monitor:
        """The monitor of the point models ``at`` (one per record when some are functionally pooled)."""
        healthy, *faults = at.values()
        try:
            return Monitor(healthy, dict(zip(models, faults)) or None, window=W, step=S, fs=data.rec.fs, test=test,
                           detection_test=detection_test, steady_window=V, rule=args.rule, **sprt)
        except (ValueError, TypeError) as exc:      # the steady-state thresholds come from the --models' records
            if str(exc).startswith("steady_window"):
                raise _reword(exc, data, (("steady_window", "--steady-window"), (" or steady_thresholds", ""))) \
                    from None
            raise ValueError(f"--baseline / --models: {exc}") from None

    shared = None if any(used) else build(points[0])
    rows = []
    for i, frame, result in _each(data, lambda i, frame: _quiet((shared or build(points[i])).run, frame,
                                                                u=data.u(i))):
        if result.coverage is not None:       # Monitor.run's check, said naming the file
            warn_if_not_covered(result.coverage, f"{data.rec.origin(i)} against --baseline {args.baseline}")
        events = result.to_frame()
        t0 = float(frame.index[0])
        for c in ("time", "window_start", "window_end"):       # times on the record's clock
            events[c] = t0 + events[c]
        print(f"{data.rec.origin(i)}: detection at "
              f"{'-' if result.detection_time is None else f'{t0 + result.detection_time:g} s'}, label "
              f"{result.label or '-'}" + ("" if result.identification_time is None else
                                          f" (decided at {t0 + result.identification_time:g} s)"))
        rows.append(events.assign(**_k_columns(used[i], flag)))
    table = _table(rows, data)
    _show(table)
    _write("--out", table, args.out)
    return 0


# ----------------------------------------------------------------------------------------------------- main
def _parser() -> tuple[argparse.ArgumentParser, dict]:
    parser = argparse.ArgumentParser(prog="tsfdi", description="Statistical time-series fault detection and "
                                                               "identification")
    parser.add_argument("--version", action="version", version=f"tsfdi {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    subs = {}
    for name, (help_, add, _) in COMMANDS.items():
        subs[name] = sub.add_parser(name, help=help_, description=help_, formatter_class=opt.HelpFormatter)
        add(subs[name])
    return parser, subs


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tsfdi`` command.

    Returns 0 on success and 2 on any error (a bad flag value, an unreadable or unwritable file, data the
    library refuses), after printing a message that names the flag, file and column; ``--help`` and
    ``--version`` exit with status 0. Warnings are printed as one line each, ``tsfdi <command>: warning: ...``.
    """
    parser, subs = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:     # argparse has printed the usage and the flag's error
        if exc.code in (0, None):
            raise
        return 2
    if args.command is None:
        parser.print_help()
        return 2
    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.showwarning = lambda message, *a, **k: print(f"tsfdi {args.command}: warning: "
                                                              f"{_flags(str(message))}", file=sys.stderr)
        try:
            return COMMANDS[args.command][2](args)
        except BrokenPipeError:              # the reader of stdout has gone (``tsfdi ... | head``): stop quietly
            sys.stdout = open(os.devnull, "w")
            return 1
        except ImportError as exc:          # an optional dependency: its message says what to install
            print(f"tsfdi {args.command}: error: {exc}", file=sys.stderr)
            return 2
        except (ValueError, TypeError, OSError) as exc:
            subs[args.command].print_usage(sys.stderr)
            print(f"tsfdi {args.command}: error: {exc}", file=sys.stderr)
            return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
