"""The simulated encoder's engine: what the twin's process runs (host, scheduler, per node its behaviours, the
faults and variants that break or vary them, the control channel's server, the log). Only ``sim/`` imports it: the
tester side reaches it through ``sim/twin.py``, ``sim/process.py`` and the control channel (DESIGN.md §2);
the project's own tests may import it to test its parts.

Not built on canopen.LocalNode (it serves SDO in stopped, stays in state 0 after a reset,
drops RTR frames and has no SYNC/event-timer TPDOs); canopen's ObjectDictionary is the data
model.
"""
