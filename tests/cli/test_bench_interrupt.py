"""The bench's wind-down after an interrupt: each part is waited for, through a second interrupt."""

from __future__ import annotations

import subprocess
import sys
import time

from jswim.bench.runner import wait_through_interrupts


class _Stubborn:
    """A process whose first waits are cut by interrupts (Stop pressed again and again)."""

    def __init__(self, interrupts: int) -> None:
        self.left = interrupts
        self.killed = False
        self.waited = 0

    def wait(self, timeout=None):
        self.waited += 1
        if self.left:
            self.left -= 1
            raise KeyboardInterrupt
        return 0

    def kill(self):
        self.killed = True


def test_a_second_interrupt_does_not_abandon_a_part():
    proc = _Stubborn(interrupts=2)
    wait_through_interrupts(proc, time.monotonic() + 5)
    assert proc.waited == 3 and not proc.killed


def test_a_part_still_running_at_the_deadline_is_killed():
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    t0 = time.monotonic()
    wait_through_interrupts(proc, time.monotonic() + 0.2)
    assert proc.returncode is not None and time.monotonic() - t0 < 5
