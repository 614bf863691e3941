"""The package's dependency direction (see docs/architecture.md): every module stands on a floor of the table in
docs/architecture.md and imports only from its floor or below; nothing outside `motiondiff.cli` imports it, the
studies and the demo do not import each other, and no two modules import each other, directly or around a loop.
Imports are read from the source (every `import`, also inside functions), so a test import cannot hide one."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"
PACKAGE = SRC / "motiondiff"
ARCHITECTURE = SRC.parent / "docs" / "architecture.md"

# the top layers and who may import them: the CLI only itself; the web demo the CLI and itself; the research studies
# the CLI and themselves; the pipelines the CLI, the studies, the demo and themselves
ALLOWED_ABOVE = {
    "motiondiff.cli": ("motiondiff.cli",),
    "motiondiff.demo": ("motiondiff.cli", "motiondiff.demo"),
    "motiondiff.studies": ("motiondiff.cli", "motiondiff.studies"),
    "motiondiff.pipelines": ("motiondiff.cli", "motiondiff.studies", "motiondiff.demo", "motiondiff.pipelines"),
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imports_of(path: Path) -> set[str]:
    """Every motiondiff module a file imports (`from a.b import c` counts a.b and, when it is a module, a.b.c)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            found.add(base)
            found.update(f"{base}.{a.name}" for a in node.names)
    return {m for m in found if m.startswith("motiondiff")}


def graph() -> dict[str, set[str]]:
    files = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    edges = {}
    for name, path in files.items():
        edges[name] = {m for m in imports_of(path) if m in files and m != name}
    return edges


def _layer_violations(edges) -> list[str]:
    bad = []
    for src, targets in edges.items():
        for dst in targets:
            for top, allowed in ALLOWED_ABOVE.items():
                if (dst == top or dst.startswith(top + ".")) and not any(
                    src == a or src.startswith(a + ".") for a in allowed
                ):
                    bad.append(f"{src} imports {dst}")
    return sorted(bad)


def _cycles(edges) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in list(edges):
        if v not in index:
            visit(v)
    return out


def floors() -> dict[str, int]:
    """The ladder of docs/architecture.md: each package named in a `| floor | packages | ... |` row -> its floor."""
    table = {}
    for line in ARCHITECTURE.read_text(encoding="utf-8").splitlines():
        row = re.match(r"\|\s*(\d+)\s*\|([^|]*)\|", line)
        if row:
            table.update({name: int(row.group(1)) for name in re.findall(r"`(motiondiff[\w.]*)`", row.group(2))})
    return table


def floor_of(module: str, table: dict[str, int]) -> int | None:
    owners = [p for p in table if module == p or module.startswith(p + ".")]
    return table[max(owners, key=len)] if owners else None


def _floor_violations(edges, table) -> list[str]:
    return sorted(f"{src} (floor {floor_of(src, table)}) imports {dst} (floor {floor_of(dst, table)})"
                  for src, targets in edges.items() for dst in targets
                  if None not in (floor_of(src, table), floor_of(dst, table))
                  and floor_of(dst, table) < floor_of(src, table))  # fmt: skip


def test_the_architecture_table_places_every_module():
    table = floors()
    assert sorted(set(table.values())) == list(range(1, 10)), table
    unplaced = [m for m in graph() if m != "motiondiff" and floor_of(m, table) is None]
    assert not unplaced, "modules that docs/architecture.md does not place on a floor:\n" + "\n".join(unplaced)


def test_every_import_points_down_the_ladder():
    bad = _floor_violations(graph(), floors())
    assert not bad, "imports that point up the floors of docs/architecture.md:\n" + "\n".join(bad)


@pytest.mark.parametrize("floor", range(2, 10))
def test_a_planted_upward_import_at_each_floor_fails(floor):
    table, edges = floors(), {k: set(v) for k, v in graph().items()}
    src = sorted(m for m in edges if floor_of(m, table) == floor)[0]
    dst = sorted(m for m in edges if floor_of(m, table) == floor - 1)[0]
    assert not _floor_violations(edges, table)
    edges[src].add(dst)
    assert _floor_violations(edges, table) == [f"{src} (floor {floor}) imports {dst} (floor {floor - 1})"]


def test_nothing_below_imports_the_cli_the_studies_or_the_pipelines():
    bad = _layer_violations(graph())
    assert not bad, "imports that point up the layers:\n" + "\n".join(bad)


def test_no_import_cycles():
    cycles = _cycles(graph())
    assert not cycles, "modules that import each other (directly or around a loop):\n" + "\n".join(map(str, cycles))


@pytest.mark.parametrize(
    "extra, expect",
    [
        ({"motiondiff.metrics": {"motiondiff.cli.common"}}, "layers"),
        ({"motiondiff.pipelines.motion": {"motiondiff.studies.behaviour"}}, "layers"),
        ({"motiondiff.lit.generation": {"motiondiff.pipelines.motion"}}, "layers"),
        ({"motiondiff.pipelines.output": {"motiondiff.demo.models"}}, "layers"),
        ({"motiondiff.studies.behaviour": {"motiondiff.demo.app"}}, "layers"),
        (
            {
                "motiondiff.data.representations.clip": {"motiondiff.metrics"},
                "motiondiff.metrics": {"motiondiff.data.representations.clip"},
            },
            "cycle",
        ),
    ],
)
def test_the_checks_fail_on_a_planted_violation(extra, expect):
    edges = {k: set(v) for k, v in graph().items()}
    for k, v in extra.items():
        edges.setdefault(k, set()).update(v)
    if expect == "layers":
        assert _layer_violations(edges)
    else:
        assert any("motiondiff.data.representations.clip" in c for c in _cycles(edges))


# the commands are shells (issue 40): what they share lives in non-command modules (cli.common, cli.outputs,
# cli.validate, cli.prompt_inputs, cli.evaluation) or below, never in another command or a study; cli.entry
# dispatches to the commands and is not one
SHELLS = ("motiondiff.cli.sample", "motiondiff.cli.edit", "motiondiff.cli.sample_guided")
COMMANDS = (*SHELLS, "motiondiff.cli.evaluate", "motiondiff.cli.train", "motiondiff.cli.train_vae",
            "motiondiff.cli.train_latent", "motiondiff.cli.train_evaluator", "motiondiff.cli.preset_audit",
            "motiondiff.cli.demo")  # fmt: skip


def _shell_violations(edges) -> list[str]:
    return sorted(f"{src} imports {dst}" for src in COMMANDS for dst in edges.get(src, ())
                  if (dst in COMMANDS and dst != src) or dst.startswith("motiondiff.studies"))  # fmt: skip


def test_no_command_imports_another_command_or_a_study():
    bad = _shell_violations(graph())
    assert not bad, "commands that borrow from another command or a study:\n" + "\n".join(bad)


SHELL_LINES = 150  # a command that needs more is doing a pipeline's work


def test_the_generation_commands_are_short():
    long = {
        m: n for m in SHELLS if (n := len((SRC / (m.replace(".", "/") + ".py")).read_text().splitlines())) > SHELL_LINES
    }
    assert not long, f"commands over {SHELL_LINES} lines (move the work into the pipelines): {long}"


@pytest.mark.parametrize("extra", [{"motiondiff.cli.edit": {"motiondiff.cli.sample"}},
                                   {"motiondiff.cli.sample": {"motiondiff.studies.behaviour"}},
                                   {"motiondiff.cli.train": {"motiondiff.cli.evaluate"}}])  # fmt: skip
def test_the_shell_check_fails_on_a_planted_borrowing(extra):
    edges = {k: set(v) for k, v in graph().items()}
    for k, v in extra.items():
        edges[k] = edges.get(k, set()) | v
    assert _shell_violations(edges)
