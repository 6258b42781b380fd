"""`tsfdi simulate`: writes a netCDF that regenerates make_hexacopter_dataset; bad input exits 2."""

import numpy as np
import pytest
import xarray as xr

from tsfdi.cli import COMMANDS, main
from tsfdi.datasets import make_hexacopter_dataset


def test_simulate_writes_dataset(tmp_path, capsys):
    out = tmp_path / "h.nc"
    rc = main(["simulate", "--out", str(out), "--records-per-case", "1", "--duration", "2s", "--failure-time", "1s",
               "--states", "healthy,rotor2", "--turbulence", "light", "--seed", "3"])
    assert rc == 0 and "wrote 2 records" in capsys.readouterr().out
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        ref = make_hexacopter_dataset(1, seed=3, duration=2.0, failure_time=1.0, states=("healthy", "rotor2"),
                                      turbulence=("light",))
        np.testing.assert_array_equal(ds["roll"].values, ref["roll"].values)
        assert list(ds.state.values) == ["healthy", "rotor2"]


def test_simulate_shipped_packing(tmp_path):
    out = tmp_path / "s.nc"
    assert main(["simulate", "--out", str(out), "--records-per-case", "1", "--duration", "1s", "--failure-time",
                 "0.5s", "--states", "rotor1", "--turbulence", "severe", "--shipped"]) == 0
    with xr.open_dataset(out, engine="h5netcdf", mask_and_scale=False) as ds:
        assert ds["roll"].dtype == np.int32 and "p" not in ds and "r" in ds


def test_bad_input_exits_2(tmp_path, capsys):
    rc = main(["simulate", "--out", str(tmp_path / "x.nc"), "--states", "rotor9", "--duration", "1s"])
    assert rc == 2 and "failed_rotor" in capsys.readouterr().err
    rc = main(["simulate", "--out", str(tmp_path / "x.nc"), "--turbulence", "hurricane", "--duration", "1s"])
    assert rc == 2 and "turbulence" in capsys.readouterr().err
    rc = main(["simulate", "--out", str(tmp_path / "x.nc"), "--dt", "0s", "--duration", "1s"])
    assert rc == 2 and "dt" in capsys.readouterr().err


def test_no_command_prints_help_and_registry(capsys):
    assert main([]) == 2
    assert "simulate" in capsys.readouterr().out
    assert "simulate" in COMMANDS




def test_simulate_fleet_writes_the_drawn_aircraft(tmp_path):
    from tsfdi.datasets.hexacopter import FLEET_COORDS, FleetSpread

    out = tmp_path / "f.nc"
    args = ["simulate", "--records-per-case", "1", "--duration", "1s", "--failure-time", "0.5s", "--states",
            "healthy,rotor1", "--turbulence", "light", "--seed", "3"]
    assert main(args + ["--out", str(out), "--fleet", "mass=0.1,cg_offset=0.02"]) == 0
    ref = make_hexacopter_dataset(1, seed=3, duration=1.0, failure_time=0.5, states=("healthy", "rotor1"),
                                  turbulence=("light",), fleet=FleetSpread(mass=0.1, cg_offset=0.02))
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        for name in FLEET_COORDS:
            np.testing.assert_array_equal(ds[name].values, ref[name].values, err_msg=name)
        np.testing.assert_array_equal(ds["roll"].values, ref["roll"].values)
        assert "fleet" in ds.attrs
    assert main(args + ["--out", str(tmp_path / "s.nc"), "--fleet", "default", "--shipped"]) == 0
    with xr.open_dataset(tmp_path / "s.nc", engine="h5netcdf") as ds:
        assert set(FLEET_COORDS) <= set(ds.coords)


def test_simulate_fleet_bad_spec_exits_2(tmp_path, capsys):
    base = ["simulate", "--out", str(tmp_path / "x.nc"), "--duration", "1s"]
    assert main(base + ["--fleet", "mass=2"]) == 2 and "mass" in capsys.readouterr().err
    assert main(base + ["--fleet", "weight=0.1"]) == 2 and "fleet" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "--help"])
    out = capsys.readouterr().out
    assert exc.value.code == 0 and "--fleet" in out and "cg_offset" in out and "--records-per-case" in out


def test_simulate_aircraft_option(tmp_path):
    """--aircraft bidirectional writes the records of BIDIRECTIONAL_HEXACOPTER; the default is the regular aircraft."""
    from tsfdi.datasets import BIDIRECTIONAL_HEXACOPTER
    kw = dict(seed=3, duration=1.0, failure_time=0.5, states=("rotor2",), turbulence=("light",))
    for choice, params in (("bidirectional", BIDIRECTIONAL_HEXACOPTER), ("regular", None)):
        out = tmp_path / f"{choice}.nc"
        assert main(["simulate", "--out", str(out), "--records-per-case", "1", "--duration", "1s", "--failure-time",
                     "0.5s", "--states", "rotor2", "--turbulence", "light", "--seed", "3", "--aircraft", choice]) == 0
        ref = make_hexacopter_dataset(1, params=params, **kw)
        with xr.open_dataset(out, engine="h5netcdf") as ds:
            np.testing.assert_array_equal(ds["roll"].values, ref["roll"].values)
    with xr.open_dataset(tmp_path / "regular.nc", engine="h5netcdf") as a, \
            xr.open_dataset(tmp_path / "bidirectional.nc", engine="h5netcdf") as b:
        assert not np.array_equal(a["roll"].values, b["roll"].values)


def test_simulate_bad_aircraft_exits_2(tmp_path, capsys):
    rc = main(["simulate", "--out", str(tmp_path / "x.nc"), "--aircraft", "quad", "--duration", "1s"])
    assert rc == 2 and "--aircraft" in capsys.readouterr().err
