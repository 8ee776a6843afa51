"""Progress of a solve the way Python users expect: the caller's callback, else a tqdm bar
per phase when tqdm is installed, else nothing."""

import sys
import time


class TqdmProgress:
    """Draws the solve's phases as tqdm bars on stderr, one bar at a time: a phase with a
    known total shows its count, an open count (iterations) a running number. Nothing is
    drawn before the solve has run a second (as the CLI's bar); bars vanish when done."""

    QUIET_START = 1.0

    def __init__(self, tqdm):
        self._tqdm = tqdm
        self._bar = None
        self._phase = None
        self._start = time.monotonic()

    def __call__(self, phase, done, total):
        if time.monotonic() - self._start < self.QUIET_START:
            return True
        if phase != self._phase or self._bar is None:
            self.close()
            self._phase = phase
            self._bar = self._tqdm(total=total, desc=phase, leave=False, file=sys.stderr,
                                   dynamic_ncols=True)
        if total is not None and self._bar.total != total:
            self._bar.total = total
        if done >= self._bar.n:
            self._bar.update(done - self._bar.n)
        else:
            self._bar.n = done
            self._bar.refresh()
        return True

    def close(self):
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def choose(progress):
    """The callable the solve reports to and a closer: ``progress`` itself when callable,
    a tqdm bar when it is None and tqdm is installed, else none (False: quiet)."""
    if callable(progress):
        return progress, lambda: None
    if progress is None:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            return None, lambda: None
        bar = TqdmProgress(tqdm)
        return bar, bar.close
    if progress is False:
        return None, lambda: None
    raise ValueError(
        f"progress must be a callable (phase, done, total), None or False, got {progress!r}")
