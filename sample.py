"""Generate motion: python sample.py text="a person walks forward" [num_samples=3 guidance=2.5 length=4 ...]"""

from motiondiff.cli.entry import sample

if __name__ == "__main__":
    sample()
