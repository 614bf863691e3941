"""Where each demo request writes its files: a fresh folder under the demo's output folder, removed again when the
request is refused or fails, and the oldest ones removed once more than KEEP_REQUESTS are there, so a demo that runs
for days neither litters its folder with empty runs nor fills the disk. (Gradio copies what a page shows into its
own cache, so an old request's files can go while its page is still open.)"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
from pathlib import Path

KEEP_REQUESTS = 20
# the folder name prefixes of this module's requests (one per mode): nothing else in the folder is touched
KINDS = ("run", "edit", "inbetween", "timeline")


@contextlib.contextmanager
def request_folder(root: Path, kind: str):
    """Yield a new folder ``<root>/<kind>-XXXX`` for one request; on any failure it goes, on success the oldest
    request folders beyond KEEP_REQUESTS go."""
    assert kind in KINDS, kind
    folder = Path(tempfile.mkdtemp(prefix=f"{kind}-", dir=root))
    try:
        yield folder
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    prune(root)


def prune(root: Path, keep: int = KEEP_REQUESTS) -> None:
    """Remove the oldest request folders of ``root`` beyond the newest ``keep``."""
    folders = [p for p in root.iterdir() if p.is_dir() and not p.is_symlink() and p.name.split("-")[0] in KINDS]
    for old in sorted(folders, key=lambda p: p.stat().st_mtime)[:-keep]:
        shutil.rmtree(old, ignore_errors=True)
