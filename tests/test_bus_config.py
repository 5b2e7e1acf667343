"""Bus configuration precedence and the recorded source of every setting (config/bus.py).

python-can reads can.rc, CAN_* environment variables and config files; each test starts from a
clean slate (empty can.rc, no CAN_* variables, no config files) and adds one source at a time.
"""

from __future__ import annotations

import json

import can
import can.util
import pytest

from encoder_conformance.config.bus import SIMULATOR, BusConfig, resolve_bus_config
from encoder_conformance.errors import EncoderConformanceError

ENV_VARS = ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG")


@pytest.fixture(autouse=True)
def clean_can_config(monkeypatch, tmp_path):
    """No can.rc values, no CAN_* environment, no python-can config files."""
    monkeypatch.setattr(can, "rc", {})
    for name in ENV_VARS:
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(can.util, "CONFIG_FILES", [])
    monkeypatch.setenv("HOME", str(tmp_path))


def test_nothing_configured_means_simulator():
    """No interface anywhere: the built-in simulator, with the reason recorded."""
    config = resolve_bus_config(None, None, None)
    assert config.simulated
    assert config.kwargs == {"interface": SIMULATOR}
    assert "no CAN interface configured" in config.sources["interface"]


def test_simulator_named_on_the_command_line(monkeypatch):
    """--can-interface simulator wins over an interface in the environment."""
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    config = resolve_bus_config(SIMULATOR, None, None)
    assert config.simulated
    assert config.sources == {"interface": "command line"}


def test_environment_is_used_and_recorded(monkeypatch):
    """CAN_INTERFACE / CAN_CHANNEL / CAN_BITRATE are used and named as the source."""
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", "env-channel")
    monkeypatch.setenv("CAN_BITRATE", "250000")
    config = resolve_bus_config(None, None, None)
    assert not config.simulated
    assert config.kwargs["interface"] == "virtual"
    assert config.kwargs["channel"] == "env-channel"
    assert config.kwargs["bitrate"] == 250000
    assert config.sources == {
        "interface": "environment CAN_INTERFACE",
        "channel": "environment CAN_CHANNEL",
        "bitrate": "environment CAN_BITRATE",
    }


def test_command_line_beats_environment(monkeypatch):
    """Command-line values override the environment; each key keeps its own source."""
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", "env-channel")
    config = resolve_bus_config(None, "cli-channel", 500000)
    assert config.kwargs["channel"] == "cli-channel"
    assert config.kwargs["bitrate"] == 500000
    assert config.kwargs["interface"] == "virtual"
    assert config.sources["channel"] == "command line"
    assert config.sources["bitrate"] == "command line"
    assert config.sources["interface"] == "environment CAN_INTERFACE"


def test_command_line_interface_beats_environment(monkeypatch):
    """--can-interface overrides CAN_INTERFACE."""
    monkeypatch.setenv("CAN_INTERFACE", "socketcan")
    config = resolve_bus_config("virtual", "x", None)
    assert config.kwargs["interface"] == "virtual"
    assert config.sources["interface"] == "command line"


def test_can_rc_beats_environment(monkeypatch):
    """can.rc (set by a program) sits between the command line and the environment."""
    monkeypatch.setattr(can, "rc", {"interface": "virtual", "channel": "rc-channel"})
    monkeypatch.setenv("CAN_CHANNEL", "env-channel")
    config = resolve_bus_config(None, None, None)
    assert config.kwargs["channel"] == "rc-channel"
    assert config.sources == {"interface": "can.rc", "channel": "can.rc"}
    assert resolve_bus_config(None, "cli", None).sources["channel"] == "command line"


def test_can_config_json_is_recorded(monkeypatch):
    """Keys from CAN_CONFIG (JSON) are recorded as coming from CAN_CONFIG."""
    monkeypatch.setenv("CAN_CONFIG", json.dumps({"interface": "virtual", "channel": "json-channel"}))
    config = resolve_bus_config(None, None, None)
    assert config.kwargs["channel"] == "json-channel"
    assert config.sources["channel"] == "environment CAN_CONFIG"


def test_config_file_is_last(monkeypatch, tmp_path):
    """A python-can config file supplies what nothing else gives, and is named as the source."""
    conf = tmp_path / "can.conf"
    conf.write_text("[default]\ninterface = virtual\nchannel = file-channel\n", encoding="utf-8")
    monkeypatch.setattr(can.util, "CONFIG_FILES", [str(conf)])
    config = resolve_bus_config(None, None, None)
    assert config.kwargs["channel"] == "file-channel"
    assert config.sources == {"interface": "python-can config file", "channel": "python-can config file"}
    monkeypatch.setenv("CAN_CHANNEL", "env-channel")
    assert resolve_bus_config(None, None, None).kwargs["channel"] == "env-channel"


def test_describe_names_value_and_source():
    """describe() shows every setting with where it came from (report header)."""
    config = BusConfig({"interface": "virtual", "channel": "c"}, {"interface": "command line"})
    assert config.describe() == "interface='virtual' (command line), channel='c' (default)"


@pytest.mark.parametrize("where", ["command line", "environment"])
def test_unknown_interface_is_an_error(monkeypatch, where):
    """A misspelled interface is refused with its name, never replaced by the simulator."""
    if where == "environment":
        monkeypatch.setenv("CAN_INTERFACE", "pcann")
        interface = None
    else:
        interface = "pcann"
    with pytest.raises(EncoderConformanceError, match="pcann"):
        resolve_bus_config(interface, "PCAN_USBBUS1", None)
