"""A multirun is counted before Hydra lists its jobs: the product of every swept setting's values, at most 1000."""

from __future__ import annotations

import pytest

from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.scripting import check_sweep_size


@pytest.mark.parametrize("overrides", [["seed=1"], ["guidance=1,2,3", "seed=range(0,10)"], ["seed=range(0,1000)"]])
def test_sweeps_up_to_the_bound_pass(overrides):
    check_sweep_size(overrides)


def test_a_product_over_the_bound_names_every_swept_setting():
    with pytest.raises(UsageError, match=r"more than 1000 jobs \(values per setting: a=range\(0,40\): 40, "
                                         r"b=range\(0,40\): 40\)"):  # fmt: skip
        check_sweep_size(["a=range(0,40)", "b=range(0,40)", "c=3"])
