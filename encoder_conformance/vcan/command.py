"""``vcan up | run | down | env | status | build``: the user-space SocketCAN bus from the command line.

- ``vcan up [IFNAME ...]`` creates the interfaces (default vcan0), starts the hub if none runs, and prints
  the two ``export`` lines a shell needs (``eval "$(... vcan up vcan0)"``) to run SocketCAN programs on it;
- ``vcan run [-i IFNAME ...] -- PROG [ARGS]`` does the same and runs PROG (replacing this process) under
  the preload library: ``vcan run -- candump vcan0``;
- ``vcan down [IFNAME ...]`` deletes those interfaces, or with none named stops the hub and deletes all;
- ``vcan env`` prints the export lines without starting anything, ``vcan status`` the hub and interfaces,
  ``vcan build`` the path of the preload library (compiling it if needed).

Run as ``python -m encoder_conformance.vcan ACTION ...`` (``__main__.py``). ``-d DIR`` (before or after
the action) names the hub directory; default ``$ENCODER_CONFORMANCE_VCAN_DIR``,
else a per-user folder. Exit codes: 0 done, 4 usage error, 69 the bus cannot be had here (no C compiler,
not Linux, the hub does not start).
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import sys
from pathlib import Path

from encoder_conformance.exit_codes import RunExit
from encoder_conformance.vcan.build import BuildError, library
from encoder_conformance.vcan.protocol import CAN_MTU, CANFD_MTU
from encoder_conformance.vcan.runtime import (
    ENV_DIR,
    MODES,
    HubError,
    add_interface,
    default_directory,
    down,
    environment,
    hub_pid,
    interfaces,
    start_hub,
)

UNAVAILABLE = RunExit.COULD_NOT_TEST


def _parser() -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-d", "--dir", type=Path, default=argparse.SUPPRESS,
                        help=f"hub directory (default ${ENV_DIR}, else a per-user folder)")
    parser = argparse.ArgumentParser(prog="vcan", parents=[common],
                                     description="A user-space SocketCAN bus for programs run under its preload "
                                                 "library (containers without vcan).")
    actions = parser.add_subparsers(dest="action", required=True)
    shape = argparse.ArgumentParser(add_help=False)
    shape.add_argument("--mtu", type=int, choices=(CAN_MTU, CANFD_MTU), default=CANFD_MTU,
                       help="72: CAN FD capable (default), 16: classic CAN only")
    shape.add_argument("--mode", choices=MODES, default="vcan",
                       help="vcan: every frame flagged as sent on this host, as the kernel's vcan (default); "
                            "wire: other programs' frames arrive as from a real bus (python-can is_rx=True)")
    up = actions.add_parser("up", parents=[common, shape], help="create interfaces, start the hub, print the env")
    up.add_argument("names", nargs="*", metavar="IFNAME", help="interfaces to create (default vcan0)")
    run = actions.add_parser("run", parents=[common, shape], help="run a program on the bus")
    run.add_argument("-i", "--interface", dest="names", action="append", metavar="IFNAME",
                     help="interface to create (repeatable; default vcan0)")
    run.add_argument("program", nargs=argparse.REMAINDER, help="-- PROG [ARGS]")
    remove = actions.add_parser("down", parents=[common], help="delete interfaces, or stop the hub")
    remove.add_argument("names", nargs="*", metavar="IFNAME")
    actions.add_parser("env", parents=[common], help="print the export lines")
    actions.add_parser("status", parents=[common], help="the hub and its interfaces")
    actions.add_parser("build", parents=[common], help="build the preload library, print its path")
    return parser


def _exports(env: dict[str, str]) -> str:
    return "".join(f"export {key}={shlex.quote(env[key])}\n" for key in ("LD_PRELOAD", ENV_DIR))


def _bring_up(directory: Path, names: list[str], mtu: int, mode: str) -> dict[str, str]:
    env = environment(directory)
    for name in names:
        interface = add_interface(directory, name, mtu, mode)
        print(f"vcan: {name} ifindex {interface.ifindex}, mtu {mtu}, mode {mode}", file=sys.stderr)
    pid = start_hub(directory, daemon=True)
    print(f"vcan: hub pid {pid} serving {directory}", file=sys.stderr)
    return env


def _status(directory: Path) -> int:
    pid = hub_pid(directory)
    print(f"hub directory: {directory}")
    print(f"hub: {'pid ' + str(pid) if pid else 'not running'}")
    for interface in interfaces(directory).values():
        print(f"{interface.name}: ifindex {interface.ifindex}, mtu {interface.mtu}, mode {interface.mode}, "
              f"{'up' if interface.up else 'down'}, qlen {interface.txqlen}")
    return 0


def main(argv: list[str]) -> int:
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:
        return RunExit.USAGE_ERROR if stop.code else 0
    directory = Path(getattr(args, "dir", None) or default_directory()).resolve()
    try:
        if args.action == "build":
            print(library())
            return 0
        if args.action == "status":
            return _status(directory)
        if args.action == "env":
            sys.stdout.write(_exports(environment(directory)))
            return 0
        if args.action == "down":
            if not down(directory, args.names):
                print(f"vcan: nothing to take down in {directory}", file=sys.stderr)
            return 0
        names = args.names or ([] if args.action == "run" and interfaces(directory) else ["vcan0"])
        if args.action == "up":
            sys.stdout.write(_exports(_bring_up(directory, names, args.mtu, args.mode)))
            return 0
        program = args.program[1:] if args.program[:1] == ["--"] else args.program
        if not program:
            parser.print_usage(sys.stderr)
            print("vcan run: name the program to run after --", file=sys.stderr)
            return RunExit.USAGE_ERROR
        env = _bring_up(directory, names, args.mtu, args.mode)
        if shutil.which(program[0], path=env.get("PATH")) is None:
            print(f"vcan run: program not found: {program[0]}", file=sys.stderr)
            return RunExit.USAGE_ERROR
        sys.stdout.flush()
        sys.stderr.flush()
        os.execvpe(program[0], program, env)
    except ValueError as error:
        print(f"vcan: {error}", file=sys.stderr)
        return RunExit.USAGE_ERROR
    except (BuildError, HubError, OSError) as error:
        print(f"vcan: {error}", file=sys.stderr)
        return UNAVAILABLE
    return 0  # not reached: execvpe replaced the process
