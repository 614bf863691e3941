"""Issue 41: what goes wrong before a command's own code runs (Hydra composing the command line and naming the run
folder) is one `error:` line with exit code 2 and no folder, like every later failure; Hydra's own flags still work
with the project's overrides before them. Each command runs in this process as its console script would."""

from __future__ import annotations

import pytest
from hostile_cli import assert_refused, files_under, run_in_process

CASES = {
    "added_misspelt_setting": (("+lenght=3",), ("adds a setting", "did you mean length")),
    "added_unknown_setting": (("+foo=bar",), ("adds a setting",)),
    "removed_setting": (("~checkpoint",), ("removes a setting",)),
    "number_beyond_the_parser": (
        (f"length={'9' * 5000}",),
        ("cannot read length= (5007 characters)", "give a shorter value"),
    ),
    "folder_name_too_long": (("hydra.run.dir=outputs/" + "d" * 300,), ("longer than the file system's 255",)),
    "unset_environment_variable": (("paths.output_dir=${oc.env:MOTIONDIFF_PROBE_UNSET}",), ("cannot be named",)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_bad_start_is_one_line_and_leaves_no_folder(case, tmp_path):
    overrides, needles = CASES[case]
    proc = run_in_process(tmp_path, "sample", "checkpoint=shipped", "text=walk", "export=none", *overrides)
    assert_refused(proc, *needles)
    assert files_under(tmp_path / "outputs") == []


def test_hydra_flags_after_the_project_overrides_still_work(tmp_path):
    proc = run_in_process(tmp_path, "edit", "clip_x0=static", "--cfg", "job")
    assert proc.returncode == 0 and "clip_x0: static" in proc.stdout, proc.stderr[-2000:]
