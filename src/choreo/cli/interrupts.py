"""Ctrl-C and SIGTERM as exceptions, so every ``finally`` and context manager cleans up.

Python turns SIGINT into KeyboardInterrupt but lets SIGTERM kill the process on the spot, leaving
temporary files and child processes (ffmpeg, Blender) behind. While a command runs, both raise
:class:`Interrupted`, a KeyboardInterrupt that remembers its signal so the exit code can be the
shell's 128 + signal number (130, 143). A second signal is ignored while the first unwinds (the
clean-up is short and must not be cut); a third ends choreo at once, should something hang.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from dataclasses import dataclass
from typing import Iterator

from ..children import defer_interrupt, starting_a_child

SIGNALS = (signal.SIGINT, signal.SIGTERM)
FORCE_AFTER = 3  # signals received: the last one is left to the system's default action


class Interrupted(KeyboardInterrupt):
    """Raised in the main thread when choreo receives SIGINT or SIGTERM."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


@dataclass
class Received:
    """The first signal received while :func:`signals_raise` was active (None: none)."""

    signum: int | None = None
    count: int = 0

    @property
    def exit_code(self) -> int:
        return 128 + (self.signum or signal.SIGINT)

    @property
    def name(self) -> str:
        return signal.Signals(self.signum or signal.SIGINT).name


@contextlib.contextmanager
def signals_raise() -> Iterator[Received]:
    """For the block, SIGINT and SIGTERM raise :class:`Interrupted` (once); the handlers before
    are put back after it. A signal ignored when choreo started stays ignored. Outside the main
    thread signals cannot be handled and nothing changes."""
    received = Received()
    if threading.current_thread() is not threading.main_thread():
        yield received
        return

    def handle(signum, _frame):
        received.count += 1
        if received.count >= FORCE_AFTER:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
        if received.signum is None:
            received.signum = signum
            if starting_a_child():  # raised once the child is held, so it is killed with the rest
                defer_interrupt(Interrupted(signum))
                return
            raise Interrupted(signum)

    before = {signum: signal.getsignal(signum) for signum in SIGNALS}
    for signum, handler in before.items():
        if handler is not signal.SIG_IGN:  # ignored, as `choreo ... &` in a script ignores Ctrl-C: left so
            signal.signal(signum, handle)
    try:
        yield received
    finally:
        for signum, handler in before.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
