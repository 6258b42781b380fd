"""The study's split (issue 30): choices on the shipped development records, evaluation on records simulated from
a seed drawn at run time, printed in the report and stored nowhere else."""

from __future__ import annotations

import importlib.util
import re
import subprocess
from pathlib import Path

import pytest

from tsfdi.study import evaluation_seed

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "docs" / "scripts" / "study.py"


@pytest.fixture(scope="module")
def study_script():
    """docs/scripts/study.py as a module (its main() is not run)."""
    spec = importlib.util.spec_from_file_location("docs_study", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


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


def test_evaluation_records_have_the_shipped_design(study_script):
    """The evaluation records are simulated with the shipped file's command line, int32 packing included, and the
    shipped file is what that command line writes."""
    from tsfdi.datasets import load_hexacopter

    design = study_script.shipped_design()
    assert design["shipped"] is True
    dev = load_hexacopter()
    assert design["seed"] == int(dev.attrs["base_seed"])
    assert design["records_per_case"] == int(dev.attrs["records_per_case"])


def test_an_unknown_option_of_the_command_line_stops_the_study(study_script, monkeypatch):
    monkeypatch.setattr(study_script, "REGENERATE_COMMAND",
                        "tsfdi simulate --out data/hexacopter.nc --seed 2024 --shipped --dt 0.002")
    with pytest.raises(ValueError, match="--dt"):
        study_script.shipped_design()
    monkeypatch.setattr(study_script, "REGENERATE_COMMAND", "tsfdi simulate --out x.nc --seed 2024")
    with pytest.raises(ValueError, match="int32"):
        study_script.shipped_design()


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
