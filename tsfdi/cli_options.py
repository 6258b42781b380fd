"""What text a flag of the ``tsfdi`` command line accepts: the ``type=`` converters of its ``argparse`` flags.

Each converter turns the text the user typed into the value :mod:`tsfdi.cli` passes to the library (a number, a
window length as pandas ``rolling`` takes it, a time in seconds, a model order, a ``KEY=VALUE`` condition), or raises
``argparse.ArgumentTypeError`` with the words ``argparse`` prints after the flag's name (``must be > 0, got '-1'``).
:class:`HelpFormatter` is how ``--help`` shows the flags' defaults.
"""

from __future__ import annotations

import argparse
import functools
import math
import warnings

import pandas as pd

__all__ = ["HelpFormatter", "finite", "integer", "positive", "probability", "count", "seed", "two_or_more", "span",
           "spans", "instant", "duration", "time_from_start", "csv_list", "column_list", "record_numbers", "where",
           "order", "METHODS", "method", "operating_point"]

#: The residual tests of ``--method``: Ljung-Box whiteness, the F test of the variance, the mean-shift test.
METHODS = ("whiteness", "variance", "mean")


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` shows every default except an absent one (``None``) and an off switch (``False``)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default is None or action.default is False:
            return action.help or ""
        return super()._get_help_string(action)


def finite(text: str, lo: float = -math.inf, hi: float = math.inf, what: str = "a finite number") -> float:
    """A finite number in (lo, hi)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not (math.isfinite(value) and lo < value < hi):
        raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}")
    return value


def integer(text: str, minimum: int) -> int:
    """An integer >= minimum."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {text!r}")
    return value


positive = functools.partial(finite, lo=0.0, what="> 0")
probability = functools.partial(finite, lo=0.0, hi=1.0, what="strictly between 0 and 1")
count, seed, two_or_more = (functools.partial(integer, minimum=m) for m in (1, 0, 2))


def scale_length(text: str) -> float | None:
    """``--scale-length``: a length in metres (> 0), or ``mil`` for the MIL-F-8785C low-altitude lengths (None)."""
    return None if text.strip().lower() == "mil" else positive(text)


def _timedelta(text: str) -> pd.Timedelta | None:
    """``text`` as a time span with a unit (``"2s"``, ``"500ms"``), or ``None`` if it is not one."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # pandas' deprecation of upper-case units
        try:
            delta = pd.Timedelta(text)
        except (ValueError, TypeError, OverflowError):
            return None
    return None if delta is pd.NaT else delta


def _bare_number(text: str) -> bool:
    """A finite number written without a unit."""
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def _rows_or_time(text: str, minimum: int, bare: str, other: str) -> int | pd.Timedelta:
    """An integer >= minimum, else a time span (``bare``: the hint for a decimal without a unit)."""
    text = text.strip()
    try:
        n = int(text)
    except ValueError:
        delta = _timedelta(text)
        if _bare_number(text) or delta is None:
            raise argparse.ArgumentTypeError((bare if _bare_number(text) else other) + f", got {text!r}") from None
        return delta
    if n < minimum:
        raise argparse.ArgumentTypeError(f"must be >= {minimum}" + (" sample or a time span such as '2s'" if minimum
                                                                    else " (a row number)") + f", got {text!r}")
    return n


def span(text: str) -> int | str:
    """A window length or step as in pandas ``rolling``: an integer >= 1 counts samples; a time span > 0 such as
    '2s' or '500ms' is kept as text (converted with the sampling frequency once it is known)."""
    value = _rows_or_time(text, 1, f"a bare number counts samples and must be an integer >= 1; write a time with its "
                          f"unit, e.g. '{text.strip()}s' or '{text.strip()}ms'", "must be a number of samples (an "
                          "integer such as 200) or a time span such as '2s' or '500ms'")
    if isinstance(value, pd.Timedelta) and value <= pd.Timedelta(0):
        raise argparse.ArgumentTypeError(f"must be a time span > 0, got {text!r}")
    return value if isinstance(value, int) else text.strip()


def spans(text: str) -> list[int | str]:
    """Comma-separated window lengths (each as :func:`span`)."""
    parts = csv_list(text)
    if not parts:
        raise argparse.ArgumentTypeError(f"must hold at least one window length such as '10s', got {text!r}")
    return [span(p) for p in parts]


def instant(text: str) -> int | float:
    """A position in a record: an integer counts rows from the first (>= 0); a time span such as '110s' is a time
    on the record's clock, returned in seconds (float)."""
    value = _rows_or_time(text, 0, "a bare number is a row number and must be an integer; write a time on the "
                          f"record's clock with its unit, e.g. '{text.strip()}s'", "must be a row number or a time "
                          "such as '110s' or '2min'")
    return value if isinstance(value, int) else value.total_seconds()


def duration(text: str, minimum: float = 0.0, strict: bool = True) -> float:
    """A time span with its unit (``"60s"``, ``"1ms"``) in seconds; a bare number is refused."""
    text = text.strip()
    delta = _timedelta(text)
    if delta is None or _bare_number(text):
        hint = f", e.g. '{text}s'" if _bare_number(text) else " such as '60s' or '1ms'"
        raise argparse.ArgumentTypeError(f"must be a time span with its unit{hint}, got {text!r}")
    seconds = delta.total_seconds()
    if seconds < minimum or (strict and seconds <= minimum):
        raise argparse.ArgumentTypeError(f"must be {'>' if strict else '>='} {minimum:g} s, got {text!r}")
    return seconds


def time_from_start(text: str) -> float:
    """A time span >= 0 with its unit, in seconds."""
    return duration(text, strict=False)


def csv_list(text: str | None) -> list[str] | None:
    """The non-empty comma-separated items of ``text`` (``None`` stays ``None``)."""
    return None if text is None else [t.strip() for t in text.split(",") if t.strip()]


def column_list(text: str) -> list[str]:
    """``COL[,COL...]``: one or more column names, each once (``--u``)."""
    names = csv_list(text)
    if not names:
        raise argparse.ArgumentTypeError(f"must name one or more columns, COL[,COL...], got {text!r}")
    twice = [c for i, c in enumerate(names) if c in names[:i]]
    if twice:
        raise argparse.ArgumentTypeError(f"must name each column once, {twice[0]!r} is given twice in {text!r}")
    return names


def record_numbers(text: str) -> list[int]:
    """Comma-separated record numbers."""
    return [seed(t) for t in csv_list(text) or [""]]


def where(text: str) -> tuple[str, list[str]]:
    """``KEY=VALUE[,VALUE...]``."""
    key, sep, value = text.partition("=")
    values = csv_list(value)
    if not sep or not key.strip() or not values:
        raise argparse.ArgumentTypeError(f"must be KEY=VALUE such as 'state=healthy', got {text!r}")
    return key.strip(), values


def order(text: str) -> int | str:
    """A model order >= 1, 'bic' or 'rss_sss'."""
    word = text.strip().lower()
    if word in ("bic", "rss_sss"):
        return word
    try:
        return count(word)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, 'bic' or 'rss_sss', got {text!r}") from None


def method(text: str) -> tuple[str, ...]:
    """``--method``: one residual test of :data:`METHODS`, or several joined by ``+`` (``whiteness+variance+mean``:
    a window is flagged when one of them rejects, :class:`tsfdi.AnyOf`), each named once, in the order given."""
    names = [t.strip().lower() for t in text.split("+")]
    bad = [t for t in names if t not in METHODS]
    if bad:
        raise argparse.ArgumentTypeError(f"must be one of {', '.join(METHODS)}, or several joined by '+' such as "
                                         f"'whiteness+variance+mean'; {bad[0]!r} is none of them, got {text!r}")
    if len(set(names)) < len(names):
        raise argparse.ArgumentTypeError(f"must name each test once, got {text!r}")
    return tuple(names)


def operating_point(text: str) -> tuple[str, list[float] | None]:
    """``--k``: ``NAME=VALUE[,VALUE...]`` (the values of an operating parameter: one per data file, or one for all),
    ``VALUE[,VALUE...]`` (``("", values)``: the model's only parameter, ``k`` when fitting), ``NAME`` (``(NAME, None)``:
    the per-record coordinate of netCDF data) or ``estimate`` (``("estimate", None)``: the operating point estimated
    from each record)."""
    word = text.strip()
    if word.lower() == "estimate":
        return "estimate", None
    name, sep, values = word.partition("=")
    if not sep and name and not _bare_number(name.split(",")[0]):
        if "," in name or any(c.isspace() for c in name):
            raise argparse.ArgumentTypeError(f"must name one coordinate (repeat --k for several), got {text!r}")
        return name, None
    name, parts = (name.strip(), csv_list(values)) if sep else ("", csv_list(word))
    if (sep and not name) or not parts or not all(_bare_number(v) for v in parts):
        raise argparse.ArgumentTypeError(f"must be NAME=VALUE[,VALUE...] such as 'depth=0,0,4' (one finite value per "
                                         f"data file, or one for all), a netCDF coordinate NAME, or 'estimate', got "
                                         f"{text!r}")
    return name, [float(v) for v in parts]
