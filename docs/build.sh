#!/usr/bin/env bash
# Build the documentation site with warnings as errors.
#   docs/build.sh                      render the notebooks as committed (no outputs)
#   TSFDI_DOCS_EXECUTE=1 docs/build.sh execute the notebooks during the build (needs ../shared/data/alfa)
# Extra arguments go to sphinx-build. Output: docs/_build/html/index.html
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${PYTHON:-.venv/bin/python}"
[ -x "$PY" ] || PY=python3
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" MPLBACKEND=Agg
exec "$PY" -m sphinx -W --keep-going -b html docs docs/_build/html "$@"
