#!/usr/bin/env bash
# Creates bench/placo/.venv with PlaCo 0.10.2 and numpy for compare.py. Idempotent: does
# nothing when the venv already has them. PYTHON picks the interpreter (default python3.11,
# else python3; PlaCo ships wheels for CPython 3.10+ on Linux and macOS).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
venv="$here/.venv"
placo_version="0.10.2"

if [[ -z "${PYTHON:-}" ]]; then
    if command -v python3.11 >/dev/null 2>&1; then PYTHON=python3.11; else PYTHON=python3; fi
fi

installed() {
    [[ -x "$venv/bin/python" ]] && "$venv/bin/python" - "$placo_version" <<'PY' 2>/dev/null
import sys
from importlib.metadata import version
import numpy  # noqa: F401
import placo  # noqa: F401
sys.exit(0 if version("placo") == sys.argv[1] else 1)
PY
}

if installed; then
    echo "bench/placo/.venv: placo $placo_version already installed"
    exit 0
fi

if [[ ! -x "$venv/bin/python" ]]; then
    "$PYTHON" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet "placo==$placo_version" numpy
installed || { echo "bench/placo/.venv: placo $placo_version did not install" >&2; exit 1; }
echo "bench/placo/.venv: placo $placo_version installed"
