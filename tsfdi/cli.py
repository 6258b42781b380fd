"""The ``tsfdi`` command line: ``tsfdi <command> [options]``.

Sub-commands register themselves in :data:`COMMANDS` through :func:`command`: a function that adds its
options to an ``argparse`` parser and a function that runs it. Adding a sub-command is one decorated pair.
"""

from __future__ import annotations

import argparse
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


def _simulate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, help="output netCDF file")
    p.add_argument("--records-per-case", type=int, default=20, help="records per state and turbulence level")
    p.add_argument("--seed", type=int, default=2024, help="base seed (record k uses SeedSequence([seed, k]))")
    p.add_argument("--duration", type=float, default=60.0, help="record length in s")
    p.add_argument("--failure-time", type=float, default=10.0, help="failure instant in s")
    p.add_argument("--speed", type=float, default=5.0, help="forward speed in m/s")
    p.add_argument("--states", default="healthy,rotor1,rotor2,rotor6",
                   help="comma-separated states: healthy, rotor1 .. rotor6")
    p.add_argument("--turbulence", default="light,moderate,severe",
                   help="comma-separated Dryden levels: none, light, moderate, severe")
    p.add_argument("--dt", type=float, default=0.001, help="integration step in s")
    p.add_argument("--fs", type=float, default=100.0, help="output sampling frequency in Hz")
    p.add_argument("--shipped", action="store_true",
                   help="write only the shipped variables packed as int16 (see data/README.md); "
                        "default: every channel as float64")


@command("simulate", "simulate hexacopter records (Dryden turbulence, rotor failures) to a netCDF file",
         _simulate_args)
def _simulate(args: argparse.Namespace) -> int:
    from tsfdi.datasets.hexacopter import encode_for_file, make_hexacopter_dataset

    t0 = time.perf_counter()
    ds = make_hexacopter_dataset(args.records_per_case, seed=args.seed, duration=args.duration,
                                 failure_time=args.failure_time, speed=args.speed,
                                 states=tuple(s.strip() for s in args.states.split(",")),
                                 turbulence=tuple(s.strip() for s in args.turbulence.split(",")),
                                 dt=args.dt, fs=args.fs)
    if args.shipped:
        ds, enc = encode_for_file(ds)
    else:
        enc = {v: {"zlib": True, "shuffle": True} for v in ds.data_vars}
    ds.to_netcdf(args.out, engine="h5netcdf", encoding=enc)
    nlost = int(ds["lost_control"].sum())
    print(f"wrote {ds.sizes['record']} records to {args.out} in {time.perf_counter() - t0:.1f} s; "
          f"lost control in {nlost} record(s)")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tsfdi`` command."""
    parser = argparse.ArgumentParser(prog="tsfdi", description="Statistical time-series fault detection and "
                                                               "identification")
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    for name, (help_, add, _) in COMMANDS.items():
        add(sub.add_parser(name, help=help_, description=help_))
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    try:
        return COMMANDS[args.command][2](args)
    except (ValueError, TypeError) as exc:
        print(f"tsfdi {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
