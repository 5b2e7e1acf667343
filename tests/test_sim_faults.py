"""Every catalogued fault is one small class next to the behaviour it breaks, and nothing else."""

from __future__ import annotations

import ast
from pathlib import Path

import encoder_conformance.sim.engine.node
from encoder_conformance.open_points import variants
from encoder_conformance.sim.engine.faults import FaultSet, assemble, implemented_faults
from encoder_conformance.sim.engine.heartbeat import HeartbeatProducer
from encoder_conformance.sim.fault_catalogue import SIMULATOR_DEVIATIONS as FAULTS

SIM = Path(encoder_conformance.sim.engine.node.__file__).parent


def test_every_catalogued_fault_has_exactly_one_implementation():
    """A fault breaks one behaviour; a conformant variant is a reading of the whole device and may shape several (the
    SYNC producer variant: 1005h's rules and the first SYNC's time)."""
    implemented = implemented_faults()
    assert sorted(set(FAULTS) - set(implemented)) == [], "faults in the catalogue without an implementation"
    assert sorted(set(implemented) - set(FAULTS)) == [], "implementations of faults the catalogue lacks"
    twice = {name: owners for name, owners in implemented.items() if len(owners) != 1 and name not in variants()}
    assert twice == {}, "faults implemented in more than one behaviour"


def test_no_behaviour_asks_which_faults_are_active():
    """Faults are put in when a behaviour is assembled; no simulator module checks fault names."""
    askers = []
    for path in SIM.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and node.attr == "active" and path.name != "faults.py":
                askers.append(f"{path.name}:{node.lineno}")
    assert askers == []


def test_assemble_puts_the_active_faults_in_front():
    assert assemble(HeartbeatProducer, FaultSet()) is HeartbeatProducer
    faulty = assemble(HeartbeatProducer, FaultSet(["heartbeat_slow_20pct", "heartbeat_wrong_dlc"]))
    assert issubclass(faulty, HeartbeatProducer)
    assert [c.__name__ for c in faulty.__mro__[1:3]] == ["SlowHeartbeat", "LongHeartbeat"]
