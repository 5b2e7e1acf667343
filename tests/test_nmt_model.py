"""The CiA 301 NMT model the state-machine suite compares devices with (encoder_conformance/models/nmt.py)."""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import NmtCommand, NmtState
from encoder_conformance.models.nmt import NmtModel, Tracked

NODE = 5


def _model(**kwargs) -> NmtModel:
    model = NmtModel(NODE, **kwargs)
    model.track(Tracked(0x1017, 0, 2, stored=0, current=0))
    model.track(Tracked(0x1801, 1, 4, stored=0x281, current=0x281, forced_bits=0x80000000,
                        forced_at=frozenset({"nmt_81h", "nmt_82h"})))
    model.track(Tracked(0x2103, 0, 1, stored=0, current=0))
    return model


@pytest.mark.parametrize(("command", "state"), [(NmtCommand.START, NmtState.OPERATIONAL),
                                                (NmtCommand.STOP, NmtState.STOPPED),
                                                (NmtCommand.ENTER_PRE_OPERATIONAL, NmtState.PRE_OPERATIONAL)])
def test_state_commands_to_the_node_or_all_nodes(command, state):
    for target in (NODE, 0):
        model = _model(state=NmtState.OPERATIONAL if state is not NmtState.OPERATIONAL else NmtState.STOPPED)
        assert model.command(command, target) is False
        assert model.state is state
        assert model.heartbeat_byte == int(state)


def test_command_to_another_node_changes_nothing():
    model = _model()
    model.write((0x2103, 0), 7)
    assert model.command(NmtCommand.START, NODE + 1) is False
    assert model.command(NmtCommand.RESET_NODE, NODE + 1) is False
    assert model.state is NmtState.PRE_OPERATIONAL
    assert model.expected((0x2103, 0)) == 7


def test_services_per_state():
    model = _model()
    assert (model.sdo_answered, model.pdo_allowed) == (True, False)
    model.command(NmtCommand.START, NODE)
    assert (model.sdo_answered, model.pdo_allowed) == (True, True)
    model.command(NmtCommand.STOP, NODE)
    assert (model.sdo_answered, model.pdo_allowed) == (False, False)


def test_state_changes_keep_values():
    model = _model()
    model.write((0x1017, 0), 50)
    for command in (NmtCommand.START, NmtCommand.STOP, NmtCommand.ENTER_PRE_OPERATIONAL):
        model.command(command, 0)
    assert model.heartbeat_ms == 50


def test_reset_communication_reloads_the_communication_area_only():
    model = _model()
    model.write((0x1017, 0), 50)
    model.write((0x2103, 0), 7)
    model.command(NmtCommand.START, NODE)
    assert model.command(NmtCommand.RESET_COMMUNICATION, 0) is True
    assert model.state is NmtState.PRE_OPERATIONAL
    assert model.heartbeat_ms == 0
    assert model.expected((0x2103, 0)) == 7


def test_reset_node_reloads_everything_and_forced_bits_come_on_top():
    model = _model(boot_state=NmtState.OPERATIONAL)  # a documented autostart
    model.write((0x2103, 0), 7)
    model.write((0x1801, 1), 0x281)
    assert model.command(NmtCommand.RESET_NODE, NODE) is True
    assert model.state is NmtState.OPERATIONAL
    assert model.expected((0x2103, 0)) == 0
    assert model.expected((0x1801, 1)) == 0x80000281


def test_auto_stored_value_survives_resets_and_preop_only_gate():
    model = NmtModel(NODE)
    model.track(Tracked(0x1017, 0, 2, stored=0, current=0, auto_stored=True))
    model.track(Tracked(0x1800, 2, 1, stored=254, current=254, preop_only=True))
    model.write((0x1017, 0), 50)
    model.command(NmtCommand.RESET_NODE, 0)
    assert model.heartbeat_ms == 50
    assert model.may_write((0x1800, 2))
    model.command(NmtCommand.START, NODE)
    assert not model.may_write((0x1800, 2))
    assert model.may_write((0x1017, 0))
    model.command(NmtCommand.STOP, NODE)
    assert not model.may_write((0x1017, 0))
