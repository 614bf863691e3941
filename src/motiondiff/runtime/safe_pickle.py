"""Loading pickles that strangers made, without letting them run code.

A pickle can name any importable callable and have it called while loading (`os.system` included). The files read
here (official GloVe indices, HumanAct12/UESTC pose caches) are plain data: dicts and lists of numbers, strings and
numpy arrays. `load_pickle` resolves only the globals in `allowed` and refuses everything else before it is called.
"""

from __future__ import annotations

import pickle
from collections.abc import Collection
from pathlib import Path

from motiondiff.runtime.errors import UsageError

# What numpy arrays, dtypes and numpy scalars pickle to (numpy 1.x wrote `numpy.core`, numpy 2 writes `numpy._core`).
# These only rebuild arrays from bytes; object arrays' items go through the same restricted unpickler.
NUMPY_DATA: frozenset[tuple[str, str]] = frozenset(
    [("numpy", "ndarray"), ("numpy", "dtype")]
    + [(f"numpy.{core}.multiarray", f) for core in ("core", "_core") for f in ("_reconstruct", "scalar")]
    + [(f"numpy.{core}.numeric", "_frombuffer") for core in ("core", "_core")]
)
# Containers and values that protocols < 4 (or Python 2 files) write as globals; lists, dicts, tuples, strings and
# numbers have their own opcodes and need nothing.
BUILTIN_DATA: frozenset[tuple[str, str]] = frozenset(
    [("builtins", n) for n in ("set", "frozenset", "bytearray", "complex", "slice")]
    + [("__builtin__", n) for n in ("set", "frozenset", "bytearray", "complex", "slice")]
    + [("_codecs", "encode")]  # protocol 2 spells bytes as _codecs.encode(str, "latin1")
)
PLAIN_DATA = BUILTIN_DATA | NUMPY_DATA


class RefusedPickle(UsageError, pickle.UnpicklingError):
    """A pickle that names code, or is no pickle at all: one line naming the file (never a traceback)."""


class _RestrictedUnpickler(pickle.Unpickler):
    def __init__(self, file, source: Path, allowed: Collection[tuple[str, str]]):
        super().__init__(file, encoding="latin1")  # Python 2 files: numpy's byte strings load as latin-1
        self._source, self._allowed = source, frozenset(allowed)

    def find_class(self, module, name):
        if (module, name) not in self._allowed:
            raise RefusedPickle(
                f"{self._source}: {module}.{name} is not allowed (only plain data - containers, numbers, strings"
                f"{', numpy arrays' if self._allowed & NUMPY_DATA else ''} - may be loaded from this file)"
            )
        if module == "__builtin__":
            module = "builtins"
        return super().find_class(_numpy_module(module), name)


def _numpy_module(module: str) -> str:
    """numpy 2 renamed `numpy.core` to `numpy._core` (the old name is a warning alias): use the installed one."""
    import numpy

    new = int(numpy.__version__.split(".")[0]) >= 2
    old_prefix, new_prefix = ("numpy.core.", "numpy._core.") if new else ("numpy._core.", "numpy.core.")
    return new_prefix + module[len(old_prefix) :] if module.startswith(old_prefix) else module


def load_pickle(path: str | Path, allowed: Collection[tuple[str, str]] = PLAIN_DATA):
    """Unpickle `path`, resolving only the (module, name) globals in `allowed` (default: numpy arrays and builtin
    containers). Anything else raises `RefusedPickle` (a UsageError and a `pickle.UnpicklingError`) naming the file
    and the refused global, before any of the file's code could run; so does a file that is not a whole pickle."""
    path = Path(path)
    with open(path, "rb") as f:
        try:
            return _RestrictedUnpickler(f, path, allowed).load()
        except RefusedPickle:
            raise
        except (pickle.UnpicklingError, EOFError, ValueError, TypeError, IndexError, KeyError, AttributeError) as err:
            raise RefusedPickle(
                f"{path} is not a readable pickle ({type(err).__name__}: {str(err)[:120]}): restore "
                "the file (it is truncated or corrupt)"
            ) from None
