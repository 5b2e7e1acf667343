"""The acceptance selection: which conformance tests `encoder-conformance accept` runs, and why each.

Goods-in asks "is this the encoder we bought, and does it basically work" of a device fresh from the
factory, in seconds, without changing anything it remembers. The selection is one list here (easier to
audit than markers spread over the suites); `accept` passes these node ids to pytest, so only their
modules are collected. Every test in it is non-destructive (no store, no restore defaults, no node-ID or
bit-rate change, no reset: tests/test_accept.py checks the markers), and the run itself takes no reset
(custody reads the values as found only; a POSITAL reboots for 4 s).

Why each test is in it:

- identity (whole module test_identity.py): 1000h device type, 1008h name, 1018h vendor-ID, product code,
  revision within the profile's range, record size, serial number consistent (650Bh) and in its format:
  "is this the product we bought". A device that is plainly another product (vendor-ID and product code
  both differ) is rejected by the start-up check and reported as an identity failure, not "could not test".
- working order (whole module test_working_order.py): no error the device reports at start-up that no test caused
  (an EMCY since the tester opened the bus, 1001h set; its code named by CiA 301's table 21, or documented by the
  quirk error_at_start_up_documented), and NMT start reaches operational (heartbeat 05h): a device that reports a
  hardware error at every start and never sends process data is not accepted.
- test_factory_default: every factory default the profile declares (communication objects, PDO mapping,
  application parameters), read as found: a device at goods-in is in its delivery state, so the values
  a customer's configuration relies on must be the manual's.
- test_default_mapping_names_mappable_objects: the default TPDO mappings point at objects that exist
  and are mappable with their length (what a PLC's configuration relies on).
- test_expedited_upload_byte_exact: an SDO upload answers with exactly the bytes of the object.
- test_pdo_in_operational / test_no_pdo_outside_operational[stopped]: NMT start makes TPDOs arrive, NMT stop
  silences them (NMT and PDO basic function; pre-operational is the full run's, it costs another 0.2 s).
- test_heartbeat_period_within_tolerance: the heartbeat keeps its period (captured over
  ACCEPT_HEARTBEAT_INTERVALS intervals instead of the full run's 50: a 20 % slow producer shows in ten).
- test_position_plausible_and_moving: the position is inside the measuring range and moves with the
  shaft (simulator or --shaft-drive) and with a preset where presetting changes nothing stored (the run
  gives the reference point back by presetting again).
"""

from __future__ import annotations

import pytest

from encoder_conformance.paths import SUITES_DIR
from encoder_conformance.plugin.option_table import pytest_name

KIND = "accept"
KIND_OPTION = pytest_name("--run-kind")  # a row of plugin/option_table.py

#: heartbeat intervals an acceptance captures (a full run: the profile's timing.heartbeat_intervals)
ACCEPT_HEARTBEAT_INTERVALS = 10

#: (module, test function or None for the whole module): the acceptance selection, see the docstring
SELECTION: tuple[tuple[str, str | None], ...] = (
    ("test_identity.py", None),
    ("test_working_order.py", None),
    ("test_object_dictionary.py", "test_factory_default"),
    ("test_pdo_mapping.py", "test_default_mapping_names_mappable_objects"),
    ("test_sdo_protocol.py", "test_expedited_upload_byte_exact"),
    ("test_nmt.py", "test_pdo_in_operational"),
    ("test_nmt.py", "test_no_pdo_outside_operational[stopped]"),
    ("test_heartbeat.py", "test_heartbeat_period_within_tolerance"),
    ("test_encoder_position.py", "test_position_plausible_and_moving"),
)

#: tests only an acceptance runs (a full run selects them out): the fault matrix, which runs full runs, leaves them
#: to tests/test_coverage_verdict.py (a faulty twin fails them at goods-in, a conformant one passes)
GOODS_IN_ONLY: frozenset[str] = frozenset({"test_no_error_reported_at_start_up", "test_nmt_start_reaches_operational"})
GOODS_IN_MODULE = "test_working_order"  # their module: no fault group targets it (the fault matrix runs full runs)

#: the pytest node id of the start-up check's verdict when the device is another product
IDENTITY_CHECK = "start-up check: identity"


def pytest_args() -> list[str]:
    """The selection as pytest arguments (absolute paths with ``::test``)."""
    return [str(SUITES_DIR / module) + (f"::{test}" if test else "") for module, test in SELECTION]


def is_acceptance(config: pytest.Config) -> bool:
    return config.getoption(KIND_OPTION, default="run") == KIND
