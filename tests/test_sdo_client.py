"""The byte-exact SDO client (dut/sdo/sdo_client.py) against the simulator's SDO server, expedited to block.

A twin of the block-transfer self-test profile on a private virtual bus; each test checks that the
client reads what a conformant server sends as conformant, and names what a faulty one breaks.
"""

from __future__ import annotations

import struct

import pytest

from encoder_conformance.cia.cia301 import SdoAbortCode, block_crc
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.sdo.sdo_client import SdoProtocolClient
from encoder_conformance.profile.loader import load_profile
from tests import sim_rig
from tests.sim_rig import REPO, Rig

rig = sim_rig.rig  # the shared simulator fixture
BLOCK_PROFILE = REPO / "tests" / "data" / "profiles" / "cia406-block-sdo.yaml"


def _client(rig: Rig, faults: tuple[str, ...] = ()) -> SdoProtocolClient:
    profile = load_profile(str(BLOCK_PROFILE)).profile
    node, _ = rig.boot(profile, faults=faults)
    dut = DeviceUnderTest(rig.network, rig.log, profile, node.node_id)
    dut.node.sdo.RESPONSE_TIMEOUT = 0.5
    return SdoProtocolClient(dut)


@pytest.fixture
def client(rig: Rig) -> SdoProtocolClient:
    return _client(rig)


def test_crc_is_ccitt_xmodem():
    """CiA 301 §7.2.4.3.16's CRC: the CCITT check value of '123456789' is 31C3h."""
    assert block_crc(b"123456789") == 0x31C3


def test_expedited_and_segmented_upload(client):
    expedited = client.upload(0x1000, 0)
    assert expedited.ok, expedited.describe()
    assert len(expedited.data) == 4
    segmented = client.upload(0x6009, 0)
    assert segmented.ok, segmented.describe()
    assert len(segmented.data) == 8


def test_segmented_download_reads_back(client):
    result = client.download(0x1017, 0, (1234).to_bytes(2, "little"))
    assert result.ok, result.describe()
    assert client.upload(0x1017, 0).data == (1234).to_bytes(2, "little")


def test_expedited_download_without_size_takes_the_objects_size(client):
    response = client.expedited_download(0x1017, 0, (777).to_bytes(4, "little"), size_indicated=False)
    assert response is not None
    assert response.raw[0] == 0x60
    assert client.upload(0x1017, 0).data == (777).to_bytes(2, "little")


def test_wrong_toggle_aborts(client):
    assert client.initiate_upload(0x6009, 0).segmented_size == 8
    response = client.upload_segment(toggle=1)
    assert response is not None
    assert response.abort_code == SdoAbortCode.TOGGLE_BIT
    assert response.raw[1:4] == struct.pack("<HB", 0x6009, 0)


@pytest.mark.parametrize("crc", [True, False])
def test_block_upload_matches_segmented(client, crc):
    block = client.block_upload(0x6009, 0, blksize=1, crc=crc)
    assert block.ok, block.describe()
    assert block.data == client.upload(0x6009, 0).data


@pytest.mark.parametrize("crc", [True, False])
def test_block_download_reads_back(client, crc):
    result = client.block_download(0x1017, 0, (4321).to_bytes(2, "little"), crc=crc)
    assert result.ok, result.describe()
    assert client.upload(0x1017, 0).data == (4321).to_bytes(2, "little")


def test_block_download_with_wrong_crc_aborts(client):
    result = client.block_download(0x1017, 0, (4321).to_bytes(2, "little"), crc_value=0xBEEF)
    assert result.abort is not None
    assert result.abort.abort_code == SdoAbortCode.CRC_ERROR


def test_block_download_out_of_order_segment_is_not_acknowledged(client):
    assert client.block_download_initiate(0x1017, 0, 2).raw[0] & 0xE3 == 0xA0
    ack = client.wait_response(client.send_block_segment(2, b"\x01\x02", last=True))
    assert ack is not None
    assert ack.raw[:2] == b"\xa2\x00", ack
    client.abort(0x1017, 0)


@pytest.mark.parametrize(("fault", "problem"), [
    ("segmented_upload_truncated", "announced 8 bytes"),
])
def test_upload_names_what_a_faulty_server_breaks(rig, fault, problem):
    result = _client(rig, (fault,)).upload(0x6009, 0)
    assert any(problem in text for text in result.problems), result.describe()


def test_block_upload_names_a_wrong_crc(rig):
    result = _client(rig, ("block_crc_wrong",)).block_upload(0x6009, 0)
    assert any("CRC" in text for text in result.problems), result.describe()


def test_download_names_a_confirmation_for_another_entry(rig):
    result = _client(rig, ("download_response_wrong_mux",)).download(0x1017, 0, b"\x01\x02")
    assert any("echo" in text for text in result.problems), result.describe()
