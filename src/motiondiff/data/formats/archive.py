"""Read files from a zip archive or a folder through one small interface (datasets ship as either).

Bounds: a zip member may declare at most MAX_MEMBER_BYTES, and reading stops as soon as it inflates beyond what it
declares (zip bombs lie about their size). Folders are walked following links to folders (a link loop or a broken
link is refused, never skipped); nothing is ever extracted, and a member named outside the archive ('../x') is refused.
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path, PurePosixPath

MAX_MEMBER_BYTES = 256 * 2**20  # uncompressed size of one zip member (prepare reads up to 4 at once)
_CHUNK = 2**20


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
            self._names = _walk(self.path)
        elif not self.path.is_file():  # a pipe or device would block or never end
            raise SourceError(f"{self.path} is a pipe or device, not a file: pass a dataset zip or its unzipped folder")
        else:
            try:
                self._zip = zipfile.ZipFile(self.path)
                self._names = sorted(n for n in self._zip.namelist() if not n.endswith("/"))
                _refuse_outside_names(self.path, self._names)
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
                return self._read_member(full)
            return (self.path / full).read_bytes()
        except (KeyError, OSError, zipfile.BadZipFile) as err:
            raise SourceError(f"{self.path}: cannot read {name} ({err})") from None

    def _read_member(self, full: str) -> bytes:
        """A zip member's bytes, refused when it declares more than MAX_MEMBER_BYTES or inflates beyond that."""
        info = self._zip.getinfo(full)
        if info.file_size > MAX_MEMBER_BYTES:
            raise SourceError(
                f"{self.path}: member {full} declares {info.file_size / 2**20:.0f} MB uncompressed, more than the "
                f"{MAX_MEMBER_BYTES // 2**20} MB a file may be; unpack the archive and split or remove that file"
            )
        parts, size = [], 0
        try:  # zipfile stops at the declared size and checks the CRC: a member that lies fails one or the other
            with self._zip.open(info) as member:
                while chunk := member.read(_CHUNK):
                    size += len(chunk)
                    if size > info.file_size:
                        raise zipfile.BadZipFile("more bytes than declared")
                    parts.append(chunk)
        except zipfile.BadZipFile as err:
            raise SourceError(
                f"{self.path}: member {full} does not inflate to the {info.file_size} bytes it declares ({err}): a zip "
                "bomb or a corrupt archive; re-download the archive from its source"
            ) from None
        return b"".join(parts)

    def read_text(self, name: str) -> str:
        return self.read_bytes(name).decode("utf-8-sig", errors="replace")

    def __repr__(self) -> str:
        return f"Source({str(self.path)!r})"


def _walk(root: Path) -> list[str]:
    """Every file under `root` (POSIX names relative to it), links to folders followed; SourceError for a link loop
    or a broken link, so no file is left out without a word."""
    names, seen = [], set()
    for folder, _dirs, files in os.walk(root, followlinks=True, onerror=_raise):
        real = os.path.realpath(folder)
        if real in seen:
            raise SourceError(f"{root}: {folder} is a link to a folder already read (a link loop, or a second "
                              "link to it); remove the link")  # fmt: skip
        seen.add(real)
        for name in files:  # (os.walk lists a broken link with the files)
            path = Path(folder, name)
            if not path.exists():
                raise SourceError(f"{root}: {path} is a broken link (to {os.readlink(path)}); fix or remove it")
            if path.is_file():
                names.append(path.relative_to(root).as_posix())
    return sorted(names)


def _raise(err: OSError) -> None:
    raise SourceError(f"cannot read the folder {err.filename} ({err.strerror or err}); check its permissions")


def _refuse_outside_names(path: Path, names: list[str]) -> None:
    """SourceError for a member whose name points outside the archive ('../x', '/x', 'C:x'): nothing is extracted,
    but such a name is a hostile or broken archive, and it would become a clip id."""
    for name in names:
        parts = PurePosixPath(name.replace("\\", "/")).parts
        if name.startswith(("/", "\\")) or ".." in parts or (parts and ":" in parts[0]):
            raise SourceError(f"{path}: member {name!r} points outside the archive (a hostile or broken zip); "
                              "re-download it or remove that member")  # fmt: skip
