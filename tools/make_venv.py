"""Create the project's virtual environment, even where ``ensurepip`` is missing.

Debian's ``python3`` without the ``python3-venv`` package cannot run
``python -m venv`` with pip.  In that case the environment is created without
pip and pip is bootstrapped from its wheel on PyPI (a wheel of pip can run
itself: ``python pip.whl/pip install pip.whl``).  Only the standard library is
used, because nothing else is installed yet.

Usage: ``python3 tools/make_venv.py .venv``
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import urllib.request
import venv
from pathlib import Path

PYPI_JSON = "https://pypi.org/pypi/pip/json"


def _bootstrap_pip(python: Path) -> None:
    with urllib.request.urlopen(PYPI_JSON, timeout=60) as resp:
        meta = json.load(resp)
    wheel = next(
        f for f in meta["urls"] if f["packagetype"] == "bdist_wheel" and f["filename"].endswith(".whl")
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / wheel["filename"]
        with urllib.request.urlopen(wheel["url"], timeout=120) as resp:
            path.write_bytes(resp.read())
        subprocess.check_call([str(python), f"{path}/pip", "install", "-q", str(path)])


def main(target: str) -> int:
    env_dir = Path(target)
    try:
        venv.create(env_dir, with_pip=True, clear=False)
    except subprocess.CalledProcessError:
        print("make_venv: ensurepip is unavailable; bootstrapping pip from PyPI", file=sys.stderr)
        venv.create(env_dir, with_pip=False, clear=True)
        _bootstrap_pip(env_dir / "bin" / "python")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else ".venv"))
