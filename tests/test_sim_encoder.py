"""The twin's encoder function on the WDGA profile (preset, code sequence, scaling, CAM, work area, speed)
and each encoder fault, shown against the conformant twin.

Every fault runs one scenario twice, on a conformant twin and on a twin with the fault, and the two
read what the catalogue says they read. The WDGA (one CAM channel with 8 cams, work area, speed)
configures its CAMs in pre-operational, where the twin starts. Positions are set by the shaft:
with the default settings (6001h = 6501h = 16384, no offset) the position is the physical count.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import SdoAbortCode
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.schema import DeviceProfile
from encoder_conformance.sim.engine.node import SimulatedNode
from encoder_conformance.sim.fault_catalogue import TARGET_MODULES, faults_for
from tests import sim_rig

rig = sim_rig.rig  # the shared fixture

WDGA = "wachendorff-wdga-mt"
STEPS = 16384  # 6501h: physical steps per revolution
TMR = 0x40000000  # 6002h as the twin starts (the total measuring range)
OPERATING, MUR, TOTAL_RANGE, PRESET, POSITION = 0x6000, 0x6001, 0x6002, 0x6003, 0x6004
SPEED, SPEED_SCALING, OFFSET = 0x6030, 0x2106, 0x6509
CAM_STATE, CAM_ENABLE, CAM_POLARITY = 0x6300, 0x6301, 0x6302
CAM1_LOW, CAM1_HIGH, CAM1_HYSTERESIS = 0x6310, 0x6320, 0x6330
AREA_STATE, AREA_LOW, AREA_HIGH = 0x6400, 0x6401, 0x6402
CCW, SCALING = 0x01, 0x04  # 6000h bits
ABOVE, BELOW = 0x02, 0x04  # 6400h


@dataclass
class Twin:
    """One booted twin and its SDO client, with typed reads and writes."""

    rig: sim_rig.Rig
    node: SimulatedNode
    client: canopen.RemoteNode

    def write(self, index: int, sub: int, value: int) -> None:
        key = (index, sub)
        size = self.node.store.size(key) or 4
        signed = datatypes.is_signed(self.node.store.entries[key].type)
        self.client.sdo.download(index, sub, value.to_bytes(size, "little", signed=signed))

    def read(self, index: int, sub: int = 0) -> int:
        signed = datatypes.is_signed(self.node.store.entries[(index, sub)].type)
        return int.from_bytes(self.client.sdo.upload(index, sub), "little", signed=signed)

    def refusal(self, index: int, sub: int, value: int) -> int | None:
        """The abort code a write gets, None where it is confirmed."""
        try:
            self.write(index, sub, value)
        except SdoAbortedError as abort:
            return abort.code
        return None

    def move_to(self, counts: int) -> None:
        """Turn the shaft to the middle of physical count ``counts``."""
        self.node.shaft.set_turns((counts + 0.5) / STEPS)

    def position_at(self, counts: int) -> int:
        self.move_to(counts)
        return self.read(POSITION)

    def preset_at(self, counts: int, preset: int) -> None:
        self.move_to(counts)
        self.write(PRESET, 0, preset)

    def cam(self, low: int, high: int, hysteresis: int = 0, enable: int = 1, polarity: int = 0) -> None:
        """Configure CAM1 (the high limit first: quirk cam_low_below_high)."""
        self.write(CAM1_HIGH, 1, high)
        self.write(CAM1_LOW, 1, low)
        self.write(CAM1_HYSTERESIS, 1, hysteresis)
        self.write(CAM_POLARITY, 1, polarity)
        self.write(CAM_ENABLE, 1, enable)

    def cam_state_at(self, counts: int) -> int:
        self.move_to(counts)
        return self.read(CAM_STATE, 1)

    def tpdo2_position(self) -> int:
        """Start the node, send a SYNC and read the position TPDO2 (synchronous, 6004h) carries."""
        node_id = self.node.node_id
        self.rig.nmt(0x01, node_id)
        assert self.rig.scheduler_drained(0.01)
        frame = self.rig.frame(0x280 + node_id, self.rig.send(0x80))
        assert frame is not None, "no TPDO2 after SYNC"
        return int.from_bytes(bytes(frame.data)[:4], "little")


Boot = Callable[[tuple[str, ...]], Twin]


@pytest.fixture(scope="module")
def wdga() -> DeviceProfile:
    profile = load_profile(WDGA).profile
    return profile.model_copy(update={"simulator": profile.simulator.model_copy(update={"bootup_delay_ms": 5})})


@pytest.fixture
def boot(rig: sim_rig.Rig, wdga: DeviceProfile) -> Boot:
    """Boots WDGA twins on node-IDs 1, 2, ... (each with its own NVM), with the faults given."""
    node_ids = itertools.count(1)

    def booted(faults: tuple[str, ...] = ()) -> Twin:
        node_id = next(node_ids)
        node, client = rig.boot(wdga, node_id, faults, nvm_name=f"nvm-{node_id}.json")
        return Twin(rig, node, client)

    return booted


# -- the conformant twin ---------------------------------------------------------------------------
def test_preset_moves_the_position_and_sets_the_offset(boot):
    twin = boot(())
    twin.preset_at(5000, 1000)
    assert twin.read(POSITION) == 1000
    assert twin.read(OFFSET) == (1000 - 5000) % TMR
    assert twin.position_at(5100) == 1100, "the preset position follows the shaft"


def test_ccw_reverses_counting_when_the_shaft_turns(boot):
    twin = boot(())
    before = twin.position_at(1000)
    assert twin.position_at(1100) - before == 100
    twin.write(OPERATING, 0, SCALING | CCW)
    before = twin.position_at(1000)
    assert (twin.position_at(1100) - before) % TMR == TMR - 100


def test_scaling_changes_the_units(boot):
    twin = boot(())
    assert twin.position_at(STEPS) == STEPS, "one turn: 6001h units (16384)"
    twin.write(MUR, 0, 4096)
    assert twin.read(POSITION) == 4096, "one turn in 4096 units"
    twin.write(OPERATING, 0, 0)
    assert twin.read(POSITION) == STEPS, "scaling off: physical counts, 6001h ignored"


def test_multiturn_position_wraps_at_the_total_measuring_range(boot):
    twin = boot(())
    twin.write(TOTAL_RANGE, 0, 4 * STEPS)
    assert twin.position_at(4 * STEPS - 1) == 4 * STEPS - 1
    assert twin.position_at(4 * STEPS) == 0
    assert twin.position_at(5 * STEPS + 7) == STEPS + 7


def test_speed_in_units_per_second_scaled_by_2106h(boot):
    twin = boot(())
    twin.node.shaft.set_speed(0.5)
    assert twin.read(SPEED, 1) == STEPS // 2
    twin.write(SPEED_SCALING, 2, 4)
    assert twin.read(SPEED, 1) == STEPS // 8, "x 2106h sub 1 / sub 2 (1/4)"
    twin.write(OPERATING, 0, SCALING | CCW)
    assert twin.read(SPEED, 1) == -STEPS // 8, "counting down: negative"


def test_cam_state_follows_enable_polarity_and_limits(boot):
    twin = boot(())
    twin.cam(1000, 2000, enable=0)
    assert twin.cam_state_at(1500) == 0, "a disabled cam"
    twin.write(CAM_ENABLE, 1, 0x01)
    assert [twin.cam_state_at(c) for c in (999, 1000, 1500, 2000, 2001)] == [0, 1, 1, 1, 0], "edges inside"
    twin.write(CAM_POLARITY, 1, 0x01)
    assert [twin.cam_state_at(c) for c in (999, 1500, 2001)] == [1, 0, 1], "polarity inverts"
    twin.write(CAM_POLARITY, 1, 0)
    twin.write(CAM1_HIGH + 1, 1, 4000)  # CAM2: 3000..4000
    twin.write(CAM1_LOW + 1, 1, 3000)
    twin.write(CAM_ENABLE, 1, 0x03)
    assert [twin.cam_state_at(c) for c in (1500, 3500, 4500)] == [0x01, 0x02, 0x00], "bit n: cam n+1"
    twin.write(CAM1_HIGH, 1, 3000)
    assert twin.cam_state_at(2500) == 0x01, "the window moves with its limits"


def test_cam_hysteresis_holds_past_the_limit_when_leaving(boot):
    twin = boot(())
    twin.cam(1000, 2000, hysteresis=100)
    assert [twin.cam_state_at(c) for c in (500, 999, 1000)] == [0, 0, 1], "switches on at the limit"
    assert [twin.cam_state_at(c) for c in (2050, 2100, 2101)] == [1, 1, 0], "switches off 100 beyond"
    assert [twin.cam_state_at(c) for c in (2050, 2000)] == [0, 1], "back in: on at the limit again"
    assert [twin.cam_state_at(c) for c in (950, 899)] == [1, 0], "leaving downwards"


def test_low_limit_gate_refuses_a_low_limit_at_or_above_the_high_limit(boot):
    twin = boot(())
    max_below_min = SdoAbortCode.MAX_BELOW_MIN
    assert max_below_min == 0x06090036
    assert twin.refusal(CAM1_LOW, 1, 0) == max_below_min, "high limit 0 (default): low 0 is not below it"
    twin.write(CAM1_HIGH, 1, 2000)
    assert twin.refusal(CAM1_LOW, 1, 2000) == max_below_min
    assert twin.refusal(CAM1_LOW, 1, 3000) == max_below_min
    assert twin.read(CAM1_LOW, 1) == 0, "a refused low limit is not stored"
    assert twin.refusal(CAM1_LOW, 1, 1999) is None
    assert twin.refusal(CAM1_LOW, 1, -5) is None, "signed limits compare as signed"
    assert twin.refusal(CAM1_LOW + 7, 1, 10) == max_below_min, "CAM8 against its own high limit (0)"
    assert twin.refusal(CAM1_HIGH, 1, -10) is None, "the high limit itself is not checked"


def test_work_area_state(boot):
    twin = boot(())
    twin.write(AREA_LOW, 1, 1000)
    twin.write(AREA_HIGH, 1, 2000)
    states = [twin.move_to(c) or twin.read(AREA_STATE, 1) for c in (999, 1000, 1500, 2000, 2001)]
    assert states == [BELOW, 0, 0, 0, ABOVE]


# -- each fault against the conformant twin ----------------------------------------------------------
def _preset_position(twin: Twin) -> int:
    twin.preset_at(5000, 1000)
    return twin.read(POSITION)


def _offset_after_preset(twin: Twin) -> tuple[int, int]:
    twin.preset_at(5000, 1000)
    return twin.read(POSITION), twin.read(OFFSET)


def _last_value_then_wrap(twin: Twin) -> tuple[int, int]:
    """Preset the last value but one, then one step on: (the position there, one step further)."""
    twin.preset_at(5000, TMR - 2)
    return twin.position_at(5001), twin.position_at(5002)


def _ccw_step(twin: Twin) -> int:
    """6000h CCW: the change of the position when the shaft turns 100 steps on (signed)."""
    twin.write(OPERATING, 0, SCALING | CCW)
    before = twin.position_at(1000)
    change = (twin.position_at(1100) - before) % TMR
    return change - TMR if change >= TMR // 2 else change


def _one_turn_at_4096_units(twin: Twin) -> int:
    twin.write(MUR, 0, 4096)
    return twin.position_at(STEPS)


def _speed_half_turn_per_second(twin: Twin) -> int:
    twin.node.shaft.set_speed(0.5)
    return twin.read(SPEED, 1)


def _sdo_and_tpdo_position(twin: Twin) -> tuple[int, int]:
    """Scaling 8192 units/turn, shaft at 40000 counts, preset 1000: (6004h by SDO, in TPDO2)."""
    twin.write(MUR, 0, 8192)
    twin.preset_at(40000, 1000)
    return twin.read(POSITION), twin.tpdo2_position()


def _cam_state_inverted_inside(twin: Twin) -> int:
    twin.cam(1000, 2000, polarity=1)
    return twin.cam_state_at(1500)


def _cam_state_leaving_within_hysteresis(twin: Twin) -> int:
    twin.cam(1000, 2000, hysteresis=100)
    twin.move_to(1500)
    return twin.cam_state_at(2050)


def _cam_state_at_high_limit(twin: Twin) -> int:
    twin.cam(1000, 2000)
    return twin.cam_state_at(2000)


def _cam_state_after_preset_into_window(twin: Twin) -> int:
    """Shaft at 5000 counts (outside 1000..2000), preset 1500: the position is inside the window."""
    twin.cam(1000, 2000)
    twin.preset_at(5000, 1500)
    return twin.read(CAM_STATE, 1)


def _disabled_cam_inside(twin: Twin) -> int:
    twin.cam(1000, 2000, enable=0)
    return twin.cam_state_at(1500)


def _low_limit_above_high(twin: Twin) -> tuple[int | None, int]:
    """High limit 2000, then low limit 3000: (the abort code or None, 6310h.1 afterwards)."""
    twin.write(CAM1_HIGH, 1, 2000)
    return twin.refusal(CAM1_LOW, 1, 3000), twin.read(CAM1_LOW, 1)


def _area_state_above_and_below(twin: Twin) -> tuple[int, int]:
    twin.write(AREA_LOW, 1, 1000)
    twin.write(AREA_HIGH, 1, 2000)
    above = twin.move_to(2500) or twin.read(AREA_STATE, 1)
    return above, twin.move_to(500) or twin.read(AREA_STATE, 1)


def _operating_status_after_ccw(twin: Twin) -> int:
    twin.write(0x6000, 0, 0x0005)
    return twin.read(0x6500, 0)


def _module_limits_after_scaling(twin: Twin) -> tuple[int, int]:
    """650Ah sub 2/3 on a twin whose profile has them read-only: the WDGA has them constant, so the scenario
    reads what the twin computes for a halved range directly."""
    twin.write(0x6001, 0, STEPS // 2)
    twin.write(0x6002, 0, TMR // 2)
    return twin.node.encoder.module_limits()


#: fault -> (scenario, what the conformant twin reads, what the twin with the fault reads)
DEVIATIONS: dict[str, tuple[Callable[[Twin], object], object, object]] = {
    "preset_ignored": (_preset_position, 1000, 5000),
    "preset_wrong_sign": (_preset_position, 1000, 5000 + (5000 - 1000)),
    "wrap_wrong_value": (_last_value_then_wrap, (TMR - 1, 0), (0, 1)),
    "direction_ignored": (_ccw_step, -100, 100),
    "scaling_ignored": (_one_turn_at_4096_units, 4096, STEPS),
    "offset_not_shown": (_offset_after_preset, (1000, (1000 - 5000) % TMR), (1000, 0)),
    "module_identification_stale": (_module_limits_after_scaling, (0, TMR // 2 - 1), (0, 0)),
    "operating_status_stale": (_operating_status_after_ccw, 0x0005, 0x0004),
    "speed_wrong_unit": (_speed_half_turn_per_second, STEPS // 2, 30),
    "tpdo_position_unscaled": (_sdo_and_tpdo_position, (1000, 1000), (1000, 40000)),
    "cam_polarity_ignored": (_cam_state_inverted_inside, 0, 1),
    "cam_hysteresis_ignored": (_cam_state_leaving_within_hysteresis, 1, 0),
    "cam_edge_off_by_one": (_cam_state_at_high_limit, 1, 0),
    "cam_on_unscaled_value": (_cam_state_after_preset_into_window, 1, 0),
    "cam_enable_ignored": (_disabled_cam_inside, 0, 1),
    "cam_low_order_ignored": (_low_limit_above_high, (SdoAbortCode.MAX_BELOW_MIN, 0), (None, 3000)),
    "work_area_flags_swapped": (_area_state_above_and_below, (ABOVE, BELOW), (BELOW, ABOVE)),
}


def test_every_encoder_fault_has_a_scenario(wdga):
    """Every fault made for the encoder suites that can show on the WDGA has a scenario here (quirk faults of
    other profiles are shown by the fault matrix on their profile, e.g. limit_switch_flags_ignored on POSITAL)."""
    encoder_suites = {"test_encoder_position", "test_cam", "test_work_area"}
    on_wdga = set(faults_for(wdga.effects))
    assert set(DEVIATIONS) == {f for f, modules in TARGET_MODULES.items()
                               if encoder_suites & set(modules) and f in on_wdga}


@pytest.mark.parametrize("fault", sorted(DEVIATIONS))
def test_fault_deviates_from_the_conformant_twin(boot, fault):
    scenario, conformant, faulty = DEVIATIONS[fault]
    assert scenario(boot(())) == conformant, "the conformant twin"
    assert scenario(boot((fault,))) == faulty, f"the twin with {fault}"


def test_settings_are_read_again_when_a_value_they_read_changes() -> None:
    """The settings are remembered between reads (encoder.py) and computed again once any value they were read
    from changes, however it was changed (here: straight into the store, as a reload does)."""
    from encoder_conformance.sim.engine.scheduler import DeadlineScheduler

    node = SimulatedNode(load_profile(WDGA).profile, DeadlineScheduler(), lambda *args, **kwargs: None)
    encoder = node.encoder
    first = encoder.settings()
    assert encoder.settings() is first  # nothing changed: the remembered settings
    node.store.set((OPERATING, 0), node.store.get((OPERATING, 0)) ^ CCW)
    turned = encoder.settings()
    assert turned.scaling.ccw != first.scaling.ccw
    node.store.set((CAM1_LOW, 1), 1234)
    assert encoder.settings().cam_channels != turned.cam_channels
