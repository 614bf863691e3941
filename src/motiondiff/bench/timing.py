"""Medians of repeated wall-clock timings, and the peak resident memory while a piece of work runs."""

from __future__ import annotations

import os
import resource
import statistics
import threading
import time
from collections.abc import Callable


def median_seconds(fn: Callable[[], object], repeats: int = 3, warmup: int = 1) -> dict:
    """Run ``fn`` ``warmup`` times untimed (allocations, lazy init, oneDNN kernel choice), then ``repeats`` times;
    returns {"median_s", "times_s"}."""
    if repeats < 1 or warmup < 0:
        raise ValueError(f"repeats must be >= 1 and warmup >= 0, got {repeats} and {warmup}")
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return {"median_s": statistics.median(times), "times_s": times}


def rss_bytes() -> int:
    """Resident memory of this process now (Linux /proc; elsewhere the peak so far, which is all getrusage gives)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


class PeakMemory:
    """``with PeakMemory() as m: work()`` then ``m.peak_bytes``: the highest RSS seen, sampled every ``interval`` s
    in a thread (the process-wide ru_maxrss cannot tell one piece of work from the ones before it)."""

    def __init__(self, interval: float = 0.005):
        self.interval, self.peak_bytes = interval, 0
        self._stop = threading.Event()

    def _watch(self) -> None:
        while not self._stop.is_set():
            self.peak_bytes = max(self.peak_bytes, rss_bytes())
            self._stop.wait(self.interval)

    def __enter__(self) -> PeakMemory:
        self.peak_bytes = rss_bytes()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        self.peak_bytes = max(self.peak_bytes, rss_bytes())


def format_seconds(s: float) -> str:
    """A duration as the tables show it: milliseconds under a second, else seconds."""
    return f"{s * 1e3:.2f} ms" if s < 1 else f"{s:.2f} s"
