"""Evaluate a trained model: python evaluate.py [checkpoint=...] [replications=20]; sweep: -m guidance=0,1,2.5,5"""

from motiondiff.cli.entry import evaluate

if __name__ == "__main__":
    evaluate()
