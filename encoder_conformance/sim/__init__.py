"""The simulated encoder: a protocol engine on raw python-can frames (DESIGN.md §3).

Not built on canopen.LocalNode (it serves SDO in stopped, stays in state 0 after a reset,
drops RTR frames and has no SYNC/event-timer TPDOs); canopen's ObjectDictionary is the data
model. Suites never import this package.
"""
