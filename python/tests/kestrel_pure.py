"""The pure-Python modules of python/kestrel loaded without kestrel/__init__.py (which imports the
compiled kestrel._core): a package `_kestrel_pure` over the same directory, so their relative imports
(`from .feetech import ...`) work where the extension is not built."""
import importlib
import pathlib
import sys
import types

KESTREL_DIR = pathlib.Path(__file__).resolve().parents[1] / "kestrel"


def load(name: str):
    """kestrel.<name>, from the built package when it imports, else from its file."""
    try:
        return importlib.import_module(f"kestrel.{name}")
    except ImportError:
        pass
    if "_kestrel_pure" not in sys.modules:
        pkg = types.ModuleType("_kestrel_pure")
        pkg.__path__ = [str(KESTREL_DIR)]
        sys.modules["_kestrel_pure"] = pkg
    return importlib.import_module(f"_kestrel_pure.{name}")
