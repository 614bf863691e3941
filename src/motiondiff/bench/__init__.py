"""Speed measurements of this machine: `make bench` runs `bench/run.py`. Timing helpers, FLOP counting and
the workloads live here so tests can check them; results go to bench/results/ (JSON + Markdown)."""
