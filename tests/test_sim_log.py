"""The simulator's log: one line per event a bench engineer follows, none per frame."""

from __future__ import annotations

import logging

import pytest

from encoder_conformance.sim.engine.hooks import NodeHooks, ReloadEvent
from encoder_conformance.sim.engine.nmt import NmtState
from encoder_conformance.sim.engine.nvm import NonVolatileMemory
from encoder_conformance.sim.engine.sim_log import LOGGER, EventLog, nvm_text


def test_nvm_changes_name_the_objects_and_the_count():
    assert nvm_text("stored", [(0x1017, 0), (0x1800, 5)]) == "stored 2 value(s) in NVM: 1017h.0, 1800h.5"
    many = nvm_text("stored", [(0x2000, sub) for sub in range(10)])
    assert many.endswith("2000h.5 and 4 more")


def test_the_node_events_come_out_one_line_each(caplog: pytest.LogCaptureFixture):
    hooks, nvm = NodeHooks(), NonVolatileMemory()
    events = EventLog(lambda: 5)
    events.register(hooks)
    nvm.listeners.append(events.nvm_changed)
    with caplog.at_level(logging.INFO, logger=LOGGER):
        hooks.emit_reload(ReloadEvent("nmt_81h", everything=True))
        hooks.emit_state(NmtState.OPERATIONAL)
        nvm.put_many({(0x1017, 0): 100})
        nvm.remove_many([(0x1017, 0)])
        for listener in hooks.powered_off:
            listener()
    assert [record.getMessage() for record in caplog.records] == [
        "node 5: NMT reset node",
        "node 5: NMT state operational",
        "node 5: stored 1 value(s) in NVM: 1017h.0",
        "node 5: removed (back to defaults) 1 value(s) in NVM: 1017h.0",
        "node 5: power off",
    ]
