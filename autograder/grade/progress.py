"""A progress line for the batch: tqdm when it is installed, else a plain counter on stderr."""

from __future__ import annotations

import sys
import threading
import time


class Progress:
    """Counts finished notebooks; silent when ``enabled`` is False."""

    def __init__(self, total: int, enabled: bool = True):
        self.total, self.n, self.enabled = total, 0, enabled
        self.bar = None
        self.t0 = time.monotonic()
        self.lock = threading.Lock()
        self.step = max(1, total // 20)
        if enabled:
            try:
                from tqdm import tqdm

                self.bar = tqdm(total=total, unit="notebook", desc="grading", file=sys.stderr)
            except ImportError:
                self.bar = None

    def update(self) -> None:
        """One more notebook graded."""
        with self.lock:
            self.n += 1
            if not self.enabled:
                return
            if self.bar is not None:
                self.bar.update(1)
            elif self.n % self.step == 0 or self.n == self.total:
                print(f"grading {self.n}/{self.total} ({time.monotonic() - self.t0:.0f} s)",
                      file=sys.stderr, flush=True)

    def close(self) -> None:
        """End the bar."""
        if self.enabled and self.bar is not None:
            self.bar.close()
