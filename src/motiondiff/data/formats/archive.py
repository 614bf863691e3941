"""Read files from a zip archive or a folder through one small interface (datasets ship as either)."""

from __future__ import annotations

import zipfile
from pathlib import Path, PurePosixPath


class SourceError(ValueError):
    """A source path that is missing, unreadable or not a zip/folder."""


class Source:
    """Files of a zip or a folder, by POSIX-style relative name ("data/x.bvh")."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._zip: zipfile.ZipFile | None = None
        if not self.path.exists():
            raise SourceError(
                f"{self.path}: no such file or folder; pass the path of a dataset zip or its unzipped folder"
            )
        if self.path.is_dir():
            self._names = sorted(p.relative_to(self.path).as_posix() for p in self.path.rglob("*") if p.is_file())
        else:
            try:
                self._zip = zipfile.ZipFile(self.path)
                self._names = sorted(n for n in self._zip.namelist() if not n.endswith("/"))
            except (zipfile.BadZipFile, OSError) as err:
                raise SourceError(
                    f"{self.path}: cannot read it as a zip ({err}); re-download the archive or pass its unzipped folder"
                ) from None
        self._strip_single_top_folder()

    def _strip_single_top_folder(self) -> None:
        """Accept archives that wrap everything in one top folder ("bandai-ds1/data/...")."""
        self._prefix = ""
        tops = {PurePosixPath(n).parts[0] for n in self._names}
        if len(tops) == 1 and all(len(PurePosixPath(n).parts) > 1 for n in self._names):
            top = tops.pop()
            if not any(n == top for n in self._names):
                self._prefix = top + "/"
                self._names = [n[len(self._prefix) :] for n in self._names]

    def names(self) -> list[str]:
        return list(self._names)

    def exists(self, name: str) -> bool:
        return name in self._names

    def read_bytes(self, name: str) -> bytes:
        full = self._prefix + name
        try:
            if self._zip is not None:
                return self._zip.read(full)
            return (self.path / full).read_bytes()
        except (KeyError, OSError, zipfile.BadZipFile) as err:
            raise SourceError(f"{self.path}: cannot read {name} ({err})") from None

    def read_text(self, name: str) -> str:
        return self.read_bytes(name).decode("utf-8-sig", errors="replace")

    def __repr__(self) -> str:
        return f"Source({str(self.path)!r})"
