import os
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
# tests/support/pty_run.py: a program's stderr on a pseudo-terminal (the progress-line tests).
sys.path.insert(0, str(ROOT / "tests" / "support"))


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def kestrel_cli(root):
    """The `kestrel` CLI built by the C++ build (build/host/sim/kestrel), or KESTREL_CLI."""
    p = pathlib.Path(os.environ.get("KESTREL_CLI", root / "build" / "host" / "sim" / "kestrel"))
    if not p.exists():
        pytest.skip(f"{p} not built (run the C++ build first or set KESTREL_CLI)")
    return p
