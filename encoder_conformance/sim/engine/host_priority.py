"""The twin's claim on the host's processors: a device on a bench has a processor of its own.

A twin shares the host with the tester and, in a CI job, with whatever else runs there. When the host is
loaded, the kernel's fair scheduler makes a twin's timer thread wait behind the other processes: its heartbeats
and event-timer TPDOs come late, and a conformant twin fails a timing check for the host's sake (seen with six
suite runs at a time on two cores: event-timer intervals of 59.7 ms against a 55 ms limit). The tester's own
lateness is measured and makes such a check inconclusive; the twin's is not visible to the tester, as a real
device's would not be. So the twin asks for a higher scheduling weight (a lower nice value) before it starts its
threads, which inherit it. Where the process may not (no CAP_SYS_NICE, not root), it keeps its weight and says
so in its log: its timing is then as good as the host's load lets it be.
"""

from __future__ import annotations

import os

#: nice value the twin asks for: about nine times the weight of a process at 0 under the fair scheduler (its
#: table: 9548 against 1024), enough for a twin's few milliseconds of work per period to go first, short of the
#: -20 an operator may want for a process of their own
TWIN_NICE = -10


def raise_twin_priority() -> str:
    """Ask for ``TWIN_NICE`` for this thread and the threads it starts; one line for the log, saying what came of it."""
    if not hasattr(os, "setpriority"):
        return "scheduling priority: unchanged (no setpriority on this platform)"
    current = os.getpriority(os.PRIO_PROCESS, 0)
    if current <= TWIN_NICE:
        return f"scheduling priority: nice {current} (kept)"
    try:
        os.setpriority(os.PRIO_PROCESS, 0, TWIN_NICE)
    except OSError as error:  # EPERM/EACCES: not permitted; the twin runs at the host's usual weight
        return f"scheduling priority: nice {current} kept ({error.strerror}: a loaded host can delay the twin's timers)"
    return f"scheduling priority: nice {current} -> {TWIN_NICE} (a device has a processor of its own)"
