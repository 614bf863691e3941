"""The one error type for mistakes a user can fix (a bad prompt, length, name or path): every entry point prints it
as one line naming the fix and exits with code 2, and the library raises it wherever input is checked."""

from __future__ import annotations

from pathlib import Path


class UsageError(ValueError):
    """A mistake the user can fix (bad prompt, length, name, path); printed as one line, exit code 2."""


class DatasetNotFoundError(FileNotFoundError):
    """A dataset root, or a file/folder it must contain, is missing.

    The message names the missing path, the layout the loader expects and where to get the data, because the
    usual cause is a wrong `root` or an unprepared download, not a bug.
    """

    def __init__(self, missing: str | Path, *, dataset: str, layout: str, how_to_get: str, detail: str = ""):
        self.path = Path(missing)  # not `filename`: setting that makes OSError print "[Errno None] None: ..."
        self.dataset = dataset
        lines = [f"{dataset}: {self.path} not found{': ' + detail if detail else ''}."]
        lines += ["Expected layout:", layout.rstrip(), f"How to get it: {how_to_get}"]
        super().__init__("\n".join(lines))


class RepresentationError(ValueError):
    """A motion representation the dataset cannot give (wrong skeleton, no rotations) or one that does not exist;
    the message names the ones that work."""
