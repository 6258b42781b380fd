"""Loader of the hexacopter benchmark dataset shipped in the repository's ``data/`` folder."""

from __future__ import annotations

from pathlib import Path

__all__ = ["load_hexacopter", "shipped_path", "REGENERATE_COMMAND"]

#: The command line that produced ``data/hexacopter.nc`` (also in ``data/README.md``).
REGENERATE_COMMAND = "tsfdi simulate --out data/hexacopter.nc --records-per-case 20 --seed 2024 --shipped"


def shipped_path() -> Path:
    """Path of ``<repository>/data/hexacopter.nc`` (located relative to the package)."""
    return Path(__file__).resolve().parents[2] / "data" / "hexacopter.nc"


def load_hexacopter(path=None):
    """The shipped benchmark: 4 states x 3 turbulence levels x 20 records x 60 s at 100 Hz.

    Design of the paper's Table 1 (Dutta et al.): healthy, rotor 1, rotor 2 and rotor 6 failure at 10 s,
    light / moderate / severe Dryden turbulence, 5 m/s forward flight at 5 m altitude. Variables: roll,
    pitch, yaw (unwrapped heading), yaw rate ``r`` and the four controls (collective, roll, pitch, yaw;
    rad/s), stored as int32 counts far below the AR(10) one-step prediction error (see ``data/README.md``),
    plus the per-record flag ``lost_control`` (no record of the shipped design is lost).

    Parameters
    ----------
    path : str or Path, optional
        Another file written by ``tsfdi simulate``; default the shipped one.

    Returns
    -------
    xarray.Dataset
        Dims ``(record, time)``; coordinates ``state``, ``turbulence``, ``speed``, ``seed``,
        ``failure_time``, ``failed_rotor``. Loaded into memory (the file is closed).
    """
    import xarray as xr

    p = shipped_path() if path is None else Path(path)
    if not p.exists():
        raise FileNotFoundError(f"hexacopter dataset not found at {p}; regenerate it from the repository root "
                                f"with: {REGENERATE_COMMAND}")
    with xr.open_dataset(p, engine="h5netcdf") as ds:
        return ds.load()
