"""Argument checks that name the offending argument.

Every public function validates its options through these helpers so that a bad value raises a
``ValueError`` / ``TypeError`` whose message starts with the argument's name.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = ["MAX_VALUES", "boolean", "int_like", "float_like", "option", "probability", "check_rng", "sample_vector"]

#: largest number of float64 values (2 GiB) that one array may hold: the regressor of a fit, the covariance of a
#: recursive estimator, a simulated signal or data set. Orders and lengths are checked against it before anything is
#: allocated.
MAX_VALUES = 2**28


def boolean(value: Any, name: str) -> bool:
    """Return ``value`` as a ``bool`` if it is one (Python or numpy) or raise naming ``name``."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r} ({type(value).__name__})")
    return bool(value)


def int_like(value: Any, name: str, *, minimum: int | None = None, maximum: int | None = None,
             optional: bool = False) -> int | None:
    """Return ``value`` as an ``int`` or raise naming ``name``.

    Booleans and non-integral floats are rejected.
    """
    if type(value) is int and (minimum is None or value >= minimum) and (maximum is None or value <= maximum):
        return value                        # the common case in one test
    if value is None and optional:
        return None
    # numpy counts timedelta64 as an integer type: a time span is not a count (a plain int skips the abstract-class
    # checks, which cost more than the rest of the call; bool is a subclass of int, not int)
    if type(value) is not int and (isinstance(value, (bool, np.bool_, np.timedelta64))
                                   or not isinstance(value, (numbers.Integral, np.integer))):
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            value = int(value)
        else:
            raise TypeError(f"{name} must be an integer, got {value!r} ({type(value).__name__})")
    value = int(value)
    if minimum is not None and value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name} must be <= {maximum}, got {value}")
    return value


def float_like(value: Any, name: str, *, minimum: float | None = None, maximum: float | None = None,
               strict_min: bool = False, strict_max: bool = False, optional: bool = False) -> float | None:
    """Return ``value`` as a finite ``float`` or raise naming ``name``.

    ``strict_min`` / ``strict_max`` make the bounds exclusive.
    """
    if type(value) is float and math.isfinite(value) and (minimum is None or (
            value > minimum if strict_min else value >= minimum)) and (maximum is None or (
            value < maximum if strict_max else value <= maximum)):
        return value                        # the common case in one test
    if value is None and optional:
        return None
    if type(value) is not float and (isinstance(value, (bool, np.bool_, np.timedelta64))
                                     or not isinstance(value, (numbers.Real, np.floating, np.integer))):
        raise TypeError(f"{name} must be a real number, got {value!r} ({type(value).__name__})")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value}")
    if minimum is not None and (value <= minimum if strict_min else value < minimum):
        raise ValueError(f"{name} must be {'>' if strict_min else '>='} {minimum}, got {value}")
    if maximum is not None and (value >= maximum if strict_max else value > maximum):
        raise ValueError(f"{name} must be {'<' if strict_max else '<='} {maximum}, got {value}")
    return value


def probability(value: Any, name: str = "alpha") -> float:
    """Return ``value`` as a float strictly inside (0, 1) or raise naming ``name``."""
    return float_like(value, name, minimum=0.0, maximum=1.0, strict_min=True, strict_max=True)


def option(value: Any, name: str, options: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``options`` (case-insensitive) or raise naming ``name``."""
    if type(value) is str and type(options) is tuple and value in options:    # the common case: no copies
        return value
    options = tuple(options)
    if not isinstance(value, str) or value.lower() not in options:
        raise ValueError(f"{name} must be one of {', '.join(repr(o) for o in options)}, got {value!r}")
    return value.lower()


def check_rng(rng: Any, name: str = "rng") -> np.random.Generator:
    """Turn ``None | int | numpy.random.Generator`` into a ``Generator``; an int seed must be >= 0."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or (isinstance(rng, (numbers.Integral, np.integer))
                       and not isinstance(rng, (bool, np.bool_, np.timedelta64))):
        if rng is not None and int(rng) < 0:
            raise ValueError(f"{name} must be None, a non-negative int seed or a numpy.random.Generator, got {rng}")
        return np.random.default_rng(rng)
    raise TypeError(f"{name} must be None, an int seed or a numpy.random.Generator, got {type(rng).__name__}")


def sample_vector(value: Any, nchan: int, name: str = "x") -> np.ndarray:
    """One sample of a stream as a float64 vector of ``nchan`` values (a number for one channel), or raise naming
    ``name``; whether NaN / inf are allowed is the caller's check."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or value is None:
        raise TypeError(f"{name} must be a number or one number per channel, got {value!r}")
    try:
        v = np.asarray(value)
        if v.dtype.kind in "USO" and any(isinstance(e, (str, bytes)) for e in np.ravel(v)):
            raise TypeError     # numbers written as text are not parsed, as signals' are not
        v = np.atleast_1d(v.astype(np.float64))
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number or one number per channel, got {value!r}") from None
    if v.shape != (nchan,):
        raise ValueError(f"{name} must hold {nchan} value(s), got shape {np.shape(value)}")
    return v
