"""The simulator's log (``simulator.log`` in a run's report folder): what a bench engineer follows.

One INFO line per event, never one per frame, so the log costs a run nothing measurable: the start
(profiles, node-IDs, serial numbers, faults, addresses), power off/on, resets and reboots, NMT state
changes, the boot-up, what was written to or removed from the non-volatile memory (store / restore
defaults / LSS store), LSS configuration. Warnings and errors of any module (a behaviour that failed
on a frame, a dropped python-can-remote client) come out at their own level.

The ``sim`` process writes it to stderr, which the launcher (sim/process.py) sends to the file. In a
test process (the in-process twin) nothing is configured, so the INFO lines are not even formatted.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable

from encoder_conformance.sim.engine.hooks import NodeHooks, ReloadEvent
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import Key

LOGGER = "encoder_conformance.sim"
log = logging.getLogger(LOGGER)

#: how a (re)start shows in the log
_RELOADS = {"power_on": "power on (or reboot): everything loaded from NVM", "nmt_81h": "NMT reset node",
            "nmt_82h": "NMT reset communication"}
_SHOWN_KEYS = 6  # NVM writes name this many objects, then "... and N more"


def configure_logging() -> None:
    """Warnings of every library, and the simulator's own events, on stderr with a time stamp."""
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr,
                        format="%(asctime)s.%(msecs)03d %(levelname)s %(name)s: %(message)s", datefmt="%H:%M:%S")
    log.setLevel(logging.INFO)


def nvm_text(verb: str, keys: list[Key]) -> str:
    """'stored 3 value(s) in NVM: 1017h.0, 1800h.5, 6000h.0'."""
    shown = ", ".join(f"{index:04X}h.{sub}" for index, sub in sorted(keys)[:_SHOWN_KEYS])
    more = f" and {len(keys) - _SHOWN_KEYS} more" if len(keys) > _SHOWN_KEYS else ""
    return f"{verb} {len(keys)} value(s) in NVM: {shown}{more}"


class EventLog:
    """A behaviour that only listens: the node's power, resets, NMT states and NVM changes, one line each."""

    def __init__(self, node_id: Callable[[], int]) -> None:
        self._node_id = node_id

    def register(self, hooks: NodeHooks) -> None:
        hooks.reload.append(self._reloaded)
        hooks.powered_off.append(lambda: self._info("power off"))
        hooks.state.append(self._state)

    def nvm_changed(self, verb: str, keys: list[Key]) -> None:
        if keys and log.isEnabledFor(logging.INFO):
            self._info(nvm_text(verb, keys))

    def _reloaded(self, event: ReloadEvent) -> None:
        self._info(_RELOADS.get(event.name, event.name))

    def _state(self, state: NmtState) -> None:
        self._info(f"NMT state {state.name.lower().replace('_', '-')}")

    def _info(self, text: str) -> None:
        log.info("node %d: %s", self._node_id(), text)
