#!/usr/bin/env bash
# Build the documentation site with warnings as errors, then check that it shows its figures and renders math
# offline (docs/scripts/check_site.py: prints the image counts; fails the build when a page group has none).
#   docs/build.sh                      execute the notebooks and the gallery, render everything (~30 s)
#   TSFDI_DOCS_EXECUTE=0 docs/build.sh execute nothing (a quick look at the text; the site check then fails)
# Extra arguments go to sphinx-build. Output: docs/_build/html/index.html
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${PYTHON:-.venv/bin/python}"
[ -x "$PY" ] || PY=python3
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
"$PY" -m sphinx -W --keep-going -b html docs docs/_build/html "$@"
"$PY" docs/scripts/check_site.py docs/_build/html
