"""One file-naming scheme for the commands and the Python API (issue 40): `<prompt slug>_<k>`, k counting the
motions of each prompt, and prompts that slug alike never share a name."""

from __future__ import annotations

from motiondiff.export.naming import motion_stems, slug


def test_each_prompt_numbers_its_own_motions():
    prompts = ["a person walks forward", "a person walks forward", "A person bows!", None, "a person walks forward"]
    assert motion_stems(prompts) == ["a_person_walks_forward_00", "a_person_walks_forward_01", "a_person_bows_00",
                                     "unconditioned_00", "a_person_walks_forward_02"]  # fmt: skip


def test_prompts_that_slug_alike_get_distinct_names():
    stems = motion_stems(["🙂", "🙃", "a person bows", "A PERSON BOWS"])
    assert stems == ["prompt_00", "prompt_2_00", "a_person_bows_00", "a_person_bows_2_00"]
    assert slug("x" * 100) == "x" * 48
