"""``encoder-conformance firmware-ci``: the whole loop a firmware team's CI needs, in one command.

1. the bus: the CAN channel if the kernel has it (a vcan made with ``ip link``), else the user-space
   SocketCAN bus (``vcan``: a hub in a private folder, wire mode, as an adapter);
2. the firmware simulator: the given command, started on that bus (its output in
   ``<report>/firmware-simulator.log``), and a power switch that stops and restarts its process, so the
   store/restore and LSS tests that need a power cycle run;
3. wait until the device answers an SDO read of 1000h (its boot time, up to ``--boot-timeout``);
4. the conformance run (``run``, every option of it), its exit code returned unchanged: 0 conformant,
   1 firmware non-conformant, 69 infrastructure (bus, simulator silent or dead), 70 not restored, 3 a bug of
   the tool, 4 usage. The report folder keeps junit.xml, report.html and run-summary.json for the artifacts.

The simulator and the hub are stopped at the end, also on Ctrl-C or SIGTERM.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import select
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from encoder_conformance.errors import UsageError
from encoder_conformance.exit_codes import DESCRIPTIONS, RunExit

#: the helper process: the power switch and the boot wait, started under the bus's environment
HELPER = [sys.executable, "-m", "encoder_conformance.cli.firmware_ci"]
STATE_PID = "simulator.pid"
STATE_COMMAND = "simulator.command"
STOP_GRACE_S = 5.0
PIPELINE_DIR = Path(__file__).with_name("pipelines")
PIPELINES = {"github": "github-actions.yml", "gitlab": "gitlab-ci.yml"}  # --example NAME -> the file it prints
PROBE_EVERY_S = 0.2


def add_firmware_ci_parser(sub: argparse._SubParsersAction) -> None:
    """The ``firmware-ci`` command (its helpers, the power switch and the boot wait, are ``helper_main``)."""
    ci = sub.add_parser(
        "firmware-ci", help="CI against a firmware simulator: bus, simulator, power switch, run, exit code",
        description=__doc__.split("\n\n")[1] if __doc__ else None,
        epilog="Arguments it does not know go to 'run' (e.g. --node-id 4, -k heartbeat, --strict).")
    ci.add_argument("--example", choices=sorted(PIPELINES),
                    help="print an example pipeline file (github: GitHub Actions with kernel vcan; gitlab: a container "
                         "job with the user-space bus) and exit")
    ci.add_argument("--simulator", metavar="COMMAND",
                    help="the command that starts your firmware simulator on the channel, e.g. "
                         "'./build/fw_sim vcan0' (run by the shell; it must stay in the foreground)")
    ci.add_argument("--profile", help="your device profile (YAML file or shipped id)")
    ci.add_argument("--can-channel", default="vcan0", help="the SocketCAN channel (default vcan0)")
    ci.add_argument("--report-dir", default="conformance-report", type=Path,
                    help="where junit.xml, report.html, run-summary.json and the simulator's log go "
                         "(default ./conformance-report)")
    ci.add_argument("--boot-timeout", default=10.0, type=float, metavar="SECONDS",
                    help="how long the simulator may take to answer its first SDO request (default 10 s)")
    ci.add_argument("--no-power-switch", action="store_true",
                    help="do not stop and restart the simulator as a power switch (power-cycle tests skip)")
    ci.set_defaults(func=cmd_firmware_ci, parser=ci)


def cmd_firmware_ci(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.cli.usage import UsageError, check_profile
    from encoder_conformance.profile.loader import load_profile

    if args.example:
        print((PIPELINE_DIR / PIPELINES[args.example]).read_text(encoding="utf-8"), end="")
        return 0
    missing = [option for option, value in (("--simulator", args.simulator), ("--profile", args.profile)) if not value]
    if missing:
        raise UsageError(f"give {' and '.join(missing)} (or --example github|gitlab for a pipeline file)")
    check_profile("--profile", args.profile)
    node_id = _node_id(extra) or load_profile(args.profile).profile.bus.node_id
    report = args.report_dir.resolve()
    report.mkdir(parents=True, exist_ok=True)
    state = Path(tempfile.mkdtemp(prefix="fwci-"))  # short: the hub's socket path is limited to 107 bytes
    (state / STATE_COMMAND).write_text(args.simulator, encoding="utf-8")
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        with _bus(args.can_channel, state) as env:
            env["FWCI_LOG"] = str(report / "firmware-simulator.log")
            _power(state, env, on=True)
            try:
                return _run_when_booted(args, extra, node_id, report, state, env)
            finally:
                _power(state, env, on=False)
    except KeyboardInterrupt:
        return RunExit.INTERRUPTED


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt  # SIGTERM (a CI job cancelled): stop the simulator and the bus as Ctrl-C does


def _run_when_booted(args: argparse.Namespace, extra: list[str], node_id: int, report: Path, state: Path,
                     env: dict[str, str]) -> int:
    python = [sys.executable, "-m", "encoder_conformance"]
    helper = [*HELPER, "--state", str(state), "--can-channel", args.can_channel]
    booted = subprocess.run([*helper, "wait-boot", "--node-id", str(node_id), "--timeout", str(args.boot_timeout)],
                            env=env, check=False)
    if booted.returncode != 0:
        print(f"firmware-ci: the simulator did not answer an SDO read of 1000h at node-ID {node_id} within "
              f"{args.boot_timeout} s (see {env['FWCI_LOG']}); exit {RunExit.COULD_NOT_TEST}: infrastructure",
              file=sys.stderr)
        return RunExit.COULD_NOT_TEST
    command = [*python, "run", "--profile", args.profile, "--can-interface", "socketcan", "--can-channel",
               args.can_channel, "--report-dir", str(report), *extra]
    if not args.no_power_switch:
        command += ["--allow-destructive",
                    "--power-off-cmd", shlex.join([*helper, "power-off"]),
                    "--power-on-cmd", shlex.join([*helper, "power-on"])]
    status = subprocess.run(command, env=env, check=False).returncode
    print(f"firmware-ci: exit {status}: {DESCRIPTIONS.get(status, 'see the run output')}; "
          f"report in {report}", file=sys.stderr)
    return status


def _node_id(extra: list[str]) -> int | None:
    """``--node-id N`` among the arguments for ``run``, if given."""
    for i, arg in enumerate(extra):
        if arg == "--node-id" and i + 1 < len(extra):
            return int(extra[i + 1])
        if arg.startswith("--node-id="):
            return int(arg.split("=", 1)[1])
    return None


@contextlib.contextmanager
def _bus(channel: str, state: Path) -> Iterator[dict[str, str]]:
    """The environment the simulator and the run need to reach ``channel``: the kernel's interface as it is,
    else the user-space bus (started here, stopped at the end)."""
    if Path("/sys/class/net", channel).exists():
        print(f"firmware-ci: using the kernel's CAN interface {channel}", file=sys.stderr)
        yield dict(os.environ)
        return
    from encoder_conformance.vcan import up
    from encoder_conformance.vcan.build import BuildError

    try:
        bus = up([channel], state / "vcan", mode="wire")
    except BuildError as exc:
        raise UsageError(f"firmware-ci: no kernel interface {channel} and no user-space bus: {exc}") from None
    print(f"firmware-ci: no kernel interface {channel}: using the user-space SocketCAN bus", file=sys.stderr)
    with bus:
        yield dict(bus.env)


def _power(state: Path, env: dict[str, str], on: bool) -> None:
    subprocess.run([*HELPER, "--state", str(state), "power-on" if on else "power-off"], env=env, check=True)


def helper_main(argv: list[str]) -> int:
    """The power switch (stop / start the simulator's process) and the boot wait, run under the bus's env:
    ``python -m encoder_conformance.cli.firmware_ci --state DIR power-on | power-off | wait-boot``."""
    parser = argparse.ArgumentParser(prog="firmware-ci helper")
    parser.add_argument("action", choices=["power-off", "power-on", "wait-boot"])
    parser.add_argument("--state", type=Path, required=True)
    parser.add_argument("--can-channel", default="vcan0")
    parser.add_argument("--node-id", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=10.0)
    args = parser.parse_args(argv)
    if args.action == "power-on":
        return _start_simulator(args.state)
    if args.action == "power-off":
        return _stop_simulator(args.state)
    return _wait_boot(args.can_channel, args.node_id, args.timeout)


def _start_simulator(state: Path) -> int:
    command = (state / STATE_COMMAND).read_text(encoding="utf-8")
    log = open(os.environ.get("FWCI_LOG", os.devnull), "ab")  # noqa: SIM115 - handed to the child
    process = subprocess.Popen(command, shell=True, stdin=subprocess.DEVNULL, stdout=log, stderr=log,
                               start_new_session=True)
    (state / STATE_PID).write_text(str(process.pid), encoding="utf-8")
    return 0


def _stop_simulator(state: Path) -> int:
    """SIGTERM to the simulator's process group, SIGKILL after a grace time: power off."""
    try:
        pid = int((state / STATE_PID).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return 0
    try:
        ended = os.pidfd_open(pid)  # readable once the process has ended (not our child: no wait() for it)
    except ProcessLookupError:
        ended = None
    with contextlib.suppress(ProcessLookupError):
        os.killpg(pid, signal.SIGTERM)
    if ended is not None:
        poll = select.poll()
        poll.register(ended, select.POLLIN)
        poll.poll(STOP_GRACE_S * 1000)
        os.close(ended)
    with contextlib.suppress(ProcessLookupError):
        os.killpg(pid, signal.SIGKILL)
    (state / STATE_PID).unlink(missing_ok=True)
    return 0


def _wait_boot(channel: str, node_id: int, timeout: float) -> int:
    """Ask for 1000h every 0.2 s until the device answers (any SDO response, an abort too): 0, else 1."""
    import can

    from encoder_conformance.cia.cia301 import SDO_REQUEST_BASE, SDO_RESPONSE_BASE

    request = bytes([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0])  # initiate upload 1000h sub 0
    deadline = time.monotonic() + timeout
    with can.Bus(interface="socketcan", channel=channel) as bus:
        bus.set_filters([{"can_id": SDO_RESPONSE_BASE + node_id, "can_mask": 0x7FF}])
        while time.monotonic() < deadline:
            bus.send(can.Message(arbitration_id=SDO_REQUEST_BASE + node_id, data=request, is_extended_id=False))
            if bus.recv(timeout=min(PROBE_EVERY_S, max(0.0, deadline - time.monotonic()))) is not None:
                return 0
    return 1


if __name__ == "__main__":
    sys.exit(helper_main(sys.argv[1:]))
