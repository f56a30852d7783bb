"""SIGTERM from the start of ``python -m pdfem``: held until a run's own handler takes over.

A batch scheduler may send SIGTERM at any moment, also while the interpreter imports numba and
the run sets up (seconds for a large bed). From the entry point on, a SIGTERM is only
remembered (:func:`hold`); a run's handler (:func:`pdfem.io.restart.catch_sigterm`) takes it
over, so the run stops after its first step with a checkpoint and exits 0, as at any later
moment. Commands that do not run a simulation get the default action back (:func:`release`),
and a SIGTERM that came meanwhile is delivered then.
"""

import os
import signal

_held = {"pending": False}


def _remember(signum, frame):
    """The held handler: note the signal."""
    _held["pending"] = True


def hold():
    """Remember SIGTERM instead of dying of it (main thread only)."""
    try:
        signal.signal(signal.SIGTERM, _remember)
    except ValueError:
        pass


def pending():
    """True when a SIGTERM arrived while it was held."""
    return _held["pending"]


def release():
    """The default SIGTERM action back; a SIGTERM held meanwhile is delivered now."""
    if signal.getsignal(signal.SIGTERM) is _remember:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if _held["pending"]:
            os.kill(os.getpid(), signal.SIGTERM)
