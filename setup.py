"""Packaging hook: an installed motiondiff carries what it needs to run from any folder.

The configs (conf/), the released models and evaluators (checkpoints/) and the embedded real data (data/) stay at the
top of the repository, where the project keeps them; a wheel built from it copies them into motiondiff/_bundled/,
which `motiondiff.runtime.paths` finds first. An editable install reads them in place.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
BUNDLED = {"conf": "conf", "checkpoints": "checkpoints", "data": "data"}  # repo folder -> motiondiff/_bundled/<name>


def skip(folder: str, names: list[str]) -> set[str]:
    """Caches, and data/bandai: the full dataset a user prepares (about 450 MB), not part of the package."""
    left_out = {n for n in names if n == "__pycache__" or n.endswith(".pyc")}
    return left_out | ({"bandai"} & set(names) if Path(folder) == ROOT / "data" else set())


class BuildWithResources(build_py):
    def run(self):
        super().run()
        target = Path(self.build_lib) / "motiondiff" / "_bundled"
        for src, name in BUNDLED.items():
            if (ROOT / src).is_dir():
                shutil.copytree(ROOT / src, target / name, ignore=skip, dirs_exist_ok=True)


setup(cmdclass={"build_py": BuildWithResources})
