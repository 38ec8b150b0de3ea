"""Stopping a batch cleanly on a signal: interrupt computing, never a commit or a manifest record.

A batch process (the one the user started, or a local worker process) installs :class:`StopSignals`.
A signal always marks ``requested``; it raises :class:`Cancelled` at once only inside
:meth:`StopSignals.interruptible` (computing a capture, waiting for results), never while a capture's
outputs are being renamed into place or its result is being recorded. Outside, the code checks
``requested`` at its next safe point. So a capture whose outputs were all written is always reported
and recorded, and one that was stopped leaves nothing (:func:`lfproc.atomic.all_or_nothing`).
"""

from __future__ import annotations

import contextlib
import signal


class Cancelled(BaseException):
    """A capture (or the whole batch) stopped by a signal before its outputs were committed.

    A ``BaseException``, like ``KeyboardInterrupt``: ``except Exception`` around a capture's work (which
    turns bugs into failed captures) lets it through.
    """


class StopSignals:
    """Handle ``signums`` in this (main) thread: mark a stop, raise :class:`Cancelled` only where safe."""

    def __init__(self, signums=(signal.SIGINT, signal.SIGTERM)):
        self.signums = tuple(signums)
        self.requested = False
        self._raise_now = False
        self._previous = {}

    def __enter__(self):
        try:
            for signum in self.signums:
                self._previous[signum] = signal.signal(signum, self._handle)
        except ValueError:  # not the main thread (an embedding application): leave signals alone
            self._previous.clear()
        return self

    def __exit__(self, *exc):
        for signum, previous in self._previous.items():
            signal.signal(signum, previous)
        self._previous.clear()
        return False

    def _handle(self, signum, frame):
        self.requested = True
        if self._raise_now:
            self._raise_now = False
            raise Cancelled

    @contextlib.contextmanager
    def interruptible(self):
        """A block a signal may stop at once (raising :class:`Cancelled`); raises at entry if one came."""
        self.check()
        self._raise_now = True
        try:
            self.check()  # a signal between the check above and the flag
            yield
        finally:
            self._raise_now = False

    def commit_point(self) -> None:
        """Leave the interruptible block for good (outputs are about to be renamed into place, then
        reported): a signal from here on only marks the stop; one that came before abandons the capture."""
        self._raise_now = False
        self.check()

    def check(self) -> None:
        """Raise :class:`Cancelled` if a stop was requested (before committing, between results)."""
        if self.requested:
            self._raise_now = False
            raise Cancelled


@contextlib.contextmanager
def signals_blocked(signums=(signal.SIGINT, signal.SIGTERM)):
    """Block ``signums`` in this thread: a process started inside inherits the block through ``exec``, so
    a Ctrl-C that reaches the whole process group can neither interrupt its start-up nor kill it before
    it has read what ``spawn`` sends it (which would leave ``Process.start`` waiting for ever); it
    decides what to do with them once it runs (``_local._worker_main``). Signals to this process stay
    pending and reach its handler when the block ends.

    multiprocessing's resource tracker, started by the first ``spawn`` of a process, unblocks these
    signals in the thread that starts it: it is started before the block.
    """
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, signums)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
