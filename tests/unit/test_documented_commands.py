"""Every command the documentation shows exists (issue 42): each `python -m motiondiff...` module resolves and runs as
a script, each `motiondiff-<name>` is a console script of the package, each `python <script>.py` is a root script.
Read from the README, docs/*.md, the data folders' READMEs and the notebooks; the records under docs/results keep
the commands as they were run and are not read."""

from __future__ import annotations

import importlib.util
import re
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md")), *sorted((REPO / "data").glob("*/README.md")),
         *sorted((REPO / "notebooks").glob("*.ipynb"))]  # fmt: skip
MODULE = re.compile(r"python -m (motiondiff(?:\.\w+)+)(?![\w.<])")  # not a placeholder (motiondiff.studies.<name>)
CONSOLE = re.compile(r"(?<![\w/.-])(motiondiff-[a-z]+(?:-[a-z]+)*)\b")
SCRIPT = re.compile(r"python ([a-z_]+\.py)\b")


def _found(pattern: re.Pattern) -> dict[str, list[str]]:
    where: dict[str, list[str]] = {}
    for page in PAGES:
        for name in pattern.findall(page.read_text(encoding="utf-8")):
            where.setdefault(name, []).append(page.relative_to(REPO).as_posix())
    return where


MODULES, CONSOLES, SCRIPTS = _found(MODULE), _found(CONSOLE), _found(SCRIPT)


def test_the_pages_show_commands_at_all():
    assert len(MODULES) >= 10 and len(CONSOLES) >= 3 and len(SCRIPTS) >= 5


@pytest.mark.parametrize("module", sorted(MODULES))
def test_every_documented_module_runs_as_a_script(module):
    spec = importlib.util.find_spec(module)
    assert spec is not None and spec.origin, f"{module} (shown in {MODULES[module]}) does not exist"
    source = Path(spec.origin).read_text(encoding="utf-8")
    assert 'if __name__ == "__main__"' in source, f"{module} (shown in {MODULES[module]}) has no __main__ block"


def test_every_documented_console_script_is_installed_by_the_package():
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    unknown = {name: pages for name, pages in CONSOLES.items() if name not in scripts and name != "motiondiff-0"}
    assert not unknown, f"console scripts the docs show but pyproject.toml does not install: {unknown}"


def test_every_documented_root_script_exists():
    missing = {name: pages for name, pages in SCRIPTS.items() if not (REPO / name).is_file()}
    assert not missing, f"root scripts the docs show that the checkout lacks: {missing}"
