"""``encoder-conformance firmware-ci``: the whole loop a firmware team's CI needs, in one command.

1. the bus: the CAN channel if the kernel has it (a vcan made with ``ip link``), else the user-space
   SocketCAN bus (``vcan``: a hub in a private folder, wire mode, as an adapter);
2. the firmware simulator: the given command, started on that bus (its output in
   ``<report>/firmware-simulator.log``), and a power switch that stops and restarts its process, so the
   store/restore and LSS tests that need a power cycle run; power off is SIGTERM to its whole process group
   and a wait (up to STOP_GRACE_S) until every process of it has ended, so it stores what it keeps at
   shutdown as a device keeps it in flash; only then SIGKILL;
3. wait until the device answers an SDO read of 1000h (its boot time, up to ``--boot-timeout``); with ``--probe
   EDS`` the profile is probed from it then (``firmware_probe.py``: kept as probed-profile.yaml in the report);
4. the conformance run (``run``, every option of it; ``--history off`` unless you give ``--history``: a CI
   job has no use for the station history), its exit code returned unchanged: 0 conformant,
   1 firmware non-conformant, 6 incomplete, 69 infrastructure (bus, simulator silent or dead), 70 not restored,
   3 a bug of the tool, 4 usage, 5 no tests selected; 130 Ctrl-C, 143 SIGTERM. The report folder keeps
   junit.xml, report.html and run-summary.json for the artifacts.

A simulator that ends by itself (CANopenLinux ends its process on NMT reset node unless it is restarted in a
loop) is named as such (exit 69). The simulator and the hub are stopped and the state folder is removed at the
end, also on an error, Ctrl-C or SIGTERM.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from encoder_conformance.cli import firmware_probe
from encoder_conformance.deadline import Deadline
from encoder_conformance.errors import UsageError
from encoder_conformance.exit_codes import DESCRIPTIONS, RunExit, interrupted_by

#: the helper process: the power switch and the boot wait, started under the bus's environment
HELPER = [sys.executable, "-m", "encoder_conformance.cli.firmware_ci"]
STATE_PID = "simulator.pid"
STATE_COMMAND = "simulator.command"
STATE_EXIT = "simulator.exit"  # the simulator's exit status, written by its keeper when it ends
STOP_GRACE_S = 5.0  # power off: how long the simulator's processes may take to end after SIGTERM
KILL_WAIT_S = 1.0  # after SIGKILL: how long to wait for the processes to be gone
GROUP_POLL_S = 0.02  # how often power off looks whether the process group has ended
BOOT_NO_ANSWER, BOOT_SIMULATOR_EXITED = 1, 2  # wait-boot's exit statuses besides 0
KEEP_RUNNING = ('a firmware simulator must keep running across NMT reset node (restart it in a loop, see README '
                '"Firmware CI")')
PIPELINE_DIR = Path(__file__).with_name("pipelines")
PIPELINES = {"github": "github-actions.yml", "gitlab": "gitlab-ci.yml"}  # --example NAME -> the file it prints
PROBE_EVERY_S = 0.2


def add_firmware_ci_parser(sub: argparse._SubParsersAction) -> None:
    """The ``firmware-ci`` command (its helpers, the power switch and the boot wait, are ``helper_main``)."""
    ci = sub.add_parser(
        "firmware-ci", help="CI against a firmware simulator: bus, simulator, power switch, run, exit code",
        description=__doc__.split("\n\n")[1] if __doc__ else None,
        epilog="Arguments it does not know go to 'run' (e.g. --node-id 4, -k heartbeat, --strict). The run "
               "records nothing in the station history (firmware-ci gives it --history off) unless you give "
               "--history PATH: a CI job has no use for it.")
    ci.add_argument("--example", choices=sorted(PIPELINES),
                    help="print an example pipeline file (github: GitHub Actions with kernel vcan; gitlab: a container "
                         "job with the user-space bus) and exit")
    ci.add_argument("--simulator", metavar="COMMAND",
                    help="the command that starts your firmware simulator on the channel, e.g. "
                         "'./build/fw_sim vcan0' (run by the shell; it must stay in the foreground and keep "
                         "running across NMT reset node: restart it in a loop if it ends there)")
    ci.add_argument("--profile", help="your device profile (YAML file or shipped id)")
    ci.add_argument("--probe", metavar="EDS",
                    help="instead of --profile: probe the simulator (profile from-eds EDS --probe, with the same "
                         "command, bus and restart handling as the run), keep the profile as probed-profile.yaml in "
                         "the report folder and run with it")
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
    missing = [option for option, value in (("--simulator", args.simulator),
                                            ("--profile (or --probe EDS)", args.profile or args.probe)) if not value]
    if missing:
        raise UsageError(f"give {' and '.join(missing)} (or --example github|gitlab for a pipeline file)")
    if args.probe:
        default_node_id = firmware_probe.check_probe(args)  # the EDS's
    else:
        check_profile("--profile", args.profile)
        default_node_id = load_profile(args.profile).profile.bus.node_id
    node_id = _node_id(extra) or default_node_id
    report = args.report_dir.resolve()
    report.mkdir(parents=True, exist_ok=True)
    state = Path(tempfile.mkdtemp(prefix="fwci-"))  # short: the hub's socket path is limited to 107 bytes
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        (state / STATE_COMMAND).write_text(args.simulator, encoding="utf-8")
        with _bus(args.can_channel, state) as env:
            env["FWCI_LOG"] = str(report / "firmware-simulator.log")
            _power(state, env, on=True)
            try:
                return _run_when_booted(args, extra, node_id, report, state, env)
            finally:
                _power(state, env, on=False)
    except KeyboardInterrupt:
        return interrupted_by(_SIGNALS[-1]) if _SIGNALS else RunExit.INTERRUPTED  # 143 for SIGTERM, else 130
    finally:
        shutil.rmtree(state, ignore_errors=True)  # the hub's folder and the power switch's files


_SIGNALS: list[int] = []  # the signals that ended firmware-ci (its exit code says which)


def _interrupt(signum: int, frame: object) -> None:
    _SIGNALS.append(signum)
    raise KeyboardInterrupt  # SIGTERM (a CI job cancelled): stop the simulator and the bus as Ctrl-C does


def _run_when_booted(args: argparse.Namespace, extra: list[str], node_id: int, report: Path, state: Path,
                     env: dict[str, str]) -> int:
    helper = [*HELPER, "--state", str(state), "--can-channel", args.can_channel]
    booted = subprocess.run([*helper, "wait-boot", "--node-id", str(node_id), "--timeout", str(args.boot_timeout)],
                            env=env, check=False)
    if booted.returncode != 0:
        exited = _exited_by_itself(state)
        if exited is None:
            print(f"firmware-ci: the simulator did not answer an SDO read of 1000h at node-ID {node_id} within "
                  f"{args.boot_timeout} s (see {env['FWCI_LOG']}; --node-id N where it has another); exit "
                  f"{RunExit.COULD_NOT_TEST}: infrastructure",
                  file=sys.stderr)
        else:
            print(f"firmware-ci: the simulator exited by itself ({exited}) before it answered an SDO read of 1000h "
                  f"(see {env['FWCI_LOG']}); {KEEP_RUNNING}; exit {RunExit.COULD_NOT_TEST}: infrastructure",
                  file=sys.stderr)
        return RunExit.COULD_NOT_TEST
    if args.probe:
        probed = firmware_probe.probe(args, node_id, report, env, lambda: _exited_by_itself(state))
        if isinstance(probed, int):
            return probed
        args.profile = str(probed)
    status = subprocess.run(_run_command(args, extra, report, helper), env=env, check=False).returncode
    exited = _exited_by_itself(state)
    if exited is not None and status != RunExit.PASSED:
        print(f"firmware-ci: the run ended with {status} ({DESCRIPTIONS.get(status, 'see the run output')}) "
              f"because the simulator exited by itself ({exited}; see {env['FWCI_LOG']}); {KEEP_RUNNING}; "
              f"exit {RunExit.COULD_NOT_TEST}: infrastructure, not a verdict on the firmware; report in {report}",
              file=sys.stderr)
        return RunExit.COULD_NOT_TEST
    if exited is not None:
        print(f"firmware-ci: note: the simulator exited by itself ({exited}; see {env['FWCI_LOG']}); "
              f"{KEEP_RUNNING}", file=sys.stderr)
    print(f"firmware-ci: exit {status}: {DESCRIPTIONS.get(status, 'see the run output')}; "
          f"report in {report}", file=sys.stderr)
    return status


def _run_command(args: argparse.Namespace, extra: list[str], report: Path, helper: list[str]) -> list[str]:
    """The ``run`` command line: the bus, the report folder, the power switch (unless ``--no-power-switch``), no
    station history unless ``extra`` gives one, then ``extra``."""
    command = [sys.executable, "-m", "encoder_conformance", "run", "--profile", args.profile,
               "--can-interface", "socketcan", "--can-channel", args.can_channel, "--report-dir", str(report)]
    if not any(arg == "--history" or arg.startswith("--history=") for arg in extra):
        command += ["--history", "off"]  # a CI job has no use for the station history (in a checkout: reports/)
    if not args.no_power_switch:
        command += ["--allow-destructive",
                    "--power-off-cmd", shlex.join([*helper, "power-off"]),
                    "--power-on-cmd", shlex.join([*helper, "power-on"])]
    return [*command, *extra]


def _exited_by_itself(state: Path) -> str | None:
    """How the simulator started last ended if it ended without a power off (its keeper wrote its exit status),
    e.g. "exit status 3", "killed by SIGSEGV"; None while it runs."""
    try:
        code = int((state / STATE_EXIT).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if code >= 0:
        return f"exit status {code}"
    try:
        return f"killed by {signal.Signals(-code).name}"
    except ValueError:
        return f"killed by signal {-code}"


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
    return _wait_boot(args.can_channel, args.node_id, args.timeout, args.state)


def _start_simulator(state: Path) -> int:
    """Power on: a keeper process (forked, a session and process group of its own) starts the simulator's command
    in its group and waits for it; when it ends the keeper writes its exit status (``STATE_EXIT``: a simulator
    that ended by itself is told from a silent one). The keeper's pid, the group's id, goes to ``STATE_PID``.
    Returns once the simulator is started (the helper's caller waits for its output pipes to close: the keeper
    keeps none of them open)."""
    command = (state / STATE_COMMAND).read_text(encoding="utf-8")
    (state / STATE_EXIT).unlink(missing_ok=True)
    started, ready = os.pipe()
    if os.fork() != 0:
        os.close(ready)
        with os.fdopen(started, "rb") as pipe:
            pipe.read()  # end of file: the keeper wrote the pid file (or failed)
        return 0 if (state / STATE_PID).exists() else 1
    os.close(started)
    try:
        _keep(state, command, ready)
    finally:
        os._exit(0)


def _keep(state: Path, command: str, ready: int) -> None:
    """The keeper (in the forked child): the simulator started and waited for; its exit status written."""
    os.setsid()
    devnull = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(devnull, fd)  # not the helper's pipes: its caller would wait for them to close
    # a handler, not SIG_IGN (which the simulator would inherit): power off's SIGTERM is for the simulator; the
    # keeper stays until the simulator has ended, so the group ends after the exit status is written
    for signum in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(signum, _keep_running)
    with open(os.environ.get("FWCI_LOG", os.devnull), "ab") as log:
        process = subprocess.Popen(command, shell=True, stdin=subprocess.DEVNULL, stdout=log, stderr=log)
    (state / STATE_PID).write_text(str(os.getpid()), encoding="utf-8")
    os.close(ready)
    code = process.wait()
    with contextlib.suppress(OSError):  # the state folder may be gone (firmware-ci ended)
        (state / STATE_EXIT).write_text(str(code), encoding="utf-8")


def _keep_running(signum: int, frame: object) -> None:
    """The keeper's handler of SIGTERM, SIGINT and SIGHUP: nothing (it ends when the simulator has ended)."""


def _stop_simulator(state: Path) -> int:
    """Power off: SIGTERM to the simulator's process group, then a wait (up to ``STOP_GRACE_S``) until every
    process of it has ended (a simulator started through a shell, or in a restart loop, stores at shutdown
    what it keeps: killing it when the shell ends would lose that), and only then SIGKILL to what is left."""
    try:
        group = int((state / STATE_PID).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return 0
    with contextlib.suppress(ProcessLookupError):
        os.killpg(group, signal.SIGTERM)
    if not _group_ends(group, STOP_GRACE_S):
        with contextlib.suppress(ProcessLookupError):
            os.killpg(group, signal.SIGKILL)
        _group_ends(group, KILL_WAIT_S)
    (state / STATE_PID).unlink(missing_ok=True)
    (state / STATE_EXIT).unlink(missing_ok=True)  # ended by the power switch, not by itself
    return 0


def _group_ends(group: int, timeout: float) -> bool:
    """Whether every process of process group ``group`` has ended within ``timeout`` s (looked at every
    ``GROUP_POLL_S``)."""
    deadline = Deadline(timeout)
    while _group_running(group):
        if deadline.expired():
            return False
        time.sleep(GROUP_POLL_S)
    return True


def _group_running(group: int) -> bool:
    """Whether a process of group ``group`` still runs. A zombie has ended (only its parent has not read its
    status; an orphan's may be never read where the container's init does not reap), so it does not count."""
    try:
        os.killpg(group, 0)
    except ProcessLookupError:
        return False  # no process, not even a zombie
    except PermissionError:
        pass
    try:
        names = [name for name in os.listdir("/proc") if name.isdigit()]
    except OSError:
        return True  # no /proc: a zombie cannot be told from a process
    for name in names:
        try:
            with open(f"/proc/{name}/stat", "rb") as stat:
                fields = stat.read()
        except OSError:
            continue  # ended meanwhile
        state, _parent, process_group = fields[fields.rindex(b")") + 2 :].split()[:3]
        if int(process_group) == group and state not in (b"Z", b"X"):
            return True
    return False


def _wait_boot(channel: str, node_id: int, timeout: float, state: Path) -> int:
    """Ask for 1000h every 0.2 s until the device answers (any SDO response, an abort too): 0; ``BOOT_NO_ANSWER``
    when the time is up, ``BOOT_SIMULATOR_EXITED`` as soon as the simulator has ended by itself."""
    import can

    from encoder_conformance.cia.cia301 import SDO_REQUEST_BASE, SDO_RESPONSE_BASE

    request = bytes([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0])  # initiate upload 1000h sub 0
    deadline = Deadline(timeout)
    with can.Bus(interface="socketcan", channel=channel) as bus:
        bus.set_filters([{"can_id": SDO_RESPONSE_BASE + node_id, "can_mask": 0x7FF}])
        while not deadline.expired():
            if (state / STATE_EXIT).exists():
                return BOOT_SIMULATOR_EXITED
            bus.send(can.Message(arbitration_id=SDO_REQUEST_BASE + node_id, data=request, is_extended_id=False))
            if bus.recv(timeout=min(PROBE_EVERY_S, deadline.remaining())) is not None:
                return 0
    return BOOT_SIMULATOR_EXITED if (state / STATE_EXIT).exists() else BOOT_NO_ANSWER


if __name__ == "__main__":
    sys.exit(helper_main(sys.argv[1:]))
