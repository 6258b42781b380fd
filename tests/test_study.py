"""The study's split (issue 30): choices on the shipped development records, evaluation on records simulated from
a seed drawn at run time, printed in the report and stored nowhere else."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest
from _scripts import load_script

from tsfdi.study import evaluation_seed

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def study_script():
    """docs/scripts/study.py as a module (its main() is not run)."""
    return load_script("docs/scripts/study.py")


def test_evaluation_seed_is_drawn_anew():
    seeds = {evaluation_seed() for _ in range(3)}
    assert len(seeds) == 3                       # three equal 31-bit draws: probability 2**-62
    assert all(isinstance(s, int) and 0 <= s < 2**31 for s in seeds)


class _Stop(Exception):
    pass


def _printed_seed(mod, monkeypatch, capsys, argv):
    """The evaluation seed that ``main()`` prints first (stopped right after, before any data is read)."""
    def stop(*args, **kwargs):
        raise _Stop

    monkeypatch.setattr(mod, "load_hexacopter", stop)
    monkeypatch.setattr("sys.argv", ["study.py", *argv])
    with pytest.raises(_Stop):
        mod.main()
    out = capsys.readouterr().out
    m = re.match(r"evaluation seed: (\d+)", out)
    assert m, out
    return int(m.group(1)), out


def test_documented_run_draws_its_seed(study_script, monkeypatch, capsys):
    """``python docs/scripts/study.py`` (no option) draws a new seed at every run; ``--seed`` only re-runs one."""
    first, _ = _printed_seed(study_script, monkeypatch, capsys, [])
    second, _ = _printed_seed(study_script, monkeypatch, capsys, [])
    assert first != second
    given, out = _printed_seed(study_script, monkeypatch, capsys, ["--seed", "17"])
    assert given == 17 and "debugging only" in out


#: a small design with the shape of the shipped command line, for the tests
SMALL = ("tsfdi simulate --out data/hexacopter.nc --records-per-case 1 --seed 2024 --shipped --duration 2s "
         "--failure-time 1s --states healthy,rotor1 --turbulence light")


def test_evaluation_records_are_the_shipped_kind_of_data(study_script, monkeypatch, tmp_path):
    """The evaluation records come from the shipped file's own command line with another seed: same options, same
    int32 packing, the records numbered after the development records'."""
    import numpy as np

    from tsfdi.cli import main
    from tsfdi.datasets import load_hexacopter
    from tsfdi.datasets.hexacopter import PACK_SCALE, SHIPPED_VARIABLES

    monkeypatch.setattr(study_script, "REGENERATE_COMMAND", SMALL)
    assert study_script.shipped_seed() == 2024
    evl = study_script.simulate_like_shipped(7, after=240)
    assert int(evl.attrs["base_seed"]) == 7 and evl.sizes["record"] == 2
    assert evl["record"].values.tolist() == [240, 241]
    assert set(SHIPPED_VARIABLES) <= set(evl.data_vars) and "p" not in evl.data_vars     # the shipped variables only
    counts = evl["pitch"].values / PACK_SCALE["pitch"]
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)                      # int32 counts
    # what the shipped command line itself writes with that seed, value for value
    out = tmp_path / "same.nc"
    assert main(["simulate", "--out", str(out), "--records-per-case", "1", "--seed", "7", "--shipped", "--duration",
                 "2s", "--failure-time", "1s", "--states", "healthy,rotor1", "--turbulence", "light",
                 "--no-progress"]) == 0
    ref = load_hexacopter(out)
    np.testing.assert_array_equal(evl["pitch"].values, ref["pitch"].values)
    study_script.same_simulator(ref, evl)
    other = study_script.simulate_like_shipped(7, "--aircraft", "bidirectional")
    with pytest.raises(ValueError, match="parameters"):
        study_script.same_simulator(ref, other)


def test_shipped_file_has_the_seed_of_its_command_line(study_script):
    from tsfdi.datasets import load_hexacopter

    assert study_script.shipped_seed() == int(load_hexacopter().attrs["base_seed"])


def test_a_command_line_that_does_not_pack_stops_the_study(study_script, monkeypatch):
    monkeypatch.setattr(study_script, "REGENERATE_COMMAND", "tsfdi simulate --out x.nc --seed 2024")
    with pytest.raises(ValueError, match="--shipped"):
        study_script.shipped_command(5, "y.nc")


def test_results_print_a_seed_stored_nowhere_else():
    """docs/results.md prints its evaluation seed; no other file of the repository holds that number."""
    text = (ROOT / "docs" / "results.md").read_text()
    m = re.search(r"\*\*Evaluation seed: (\d+)\*\*", text)
    assert m, "docs/results.md does not print its evaluation seed"
    seed = m.group(1)
    assert seed != "2024"
    assert "| evaluation records | seed " + seed in text          # the table of what was chosen on which records
    try:
        files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                               check=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    holders = []
    for name in files:
        p = ROOT / name
        if name == "docs/results.md" or p.suffix not in {".py", ".md", ".toml", ".txt", ".json", ".cfg", ".rst"}:
            continue
        if p.is_file() and re.search(rf"\b{seed}\b", p.read_text(errors="ignore")):
            holders.append(name)
    assert not holders, f"the evaluation seed {seed} is written in {holders}"
