"""``sim`` and ``sim-control``: serve simulated devices (python-can-remote or a CAN bus), switch their power."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from encoder_conformance.cli import usage
from encoder_conformance.cli.usage import UsageError, host_port, positive_int
from encoder_conformance.cli.usage import node_id_arg as node_id_type
from encoder_conformance.exit_codes import RunExit


def _cmd_sim(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.sim.twin import plan_nodes, serve

    for profile in args.profile:
        usage.check_profile("--profile", profile)
    usage.check_faults("--fault", args.fault)
    usage.check_output_file("--nvm", args.nvm)
    try:
        plan = plan_nodes(args.profile, args.node_id, args.copies, args.unconfigured)
        can_bus = _sim_can_bus(args)
        return serve(plan, args.listen, args.control, args.fault, args.nvm, args.ready_line, can_bus)
    except ValueError as exc:  # a combination of options, or a port that cannot be had
        raise UsageError(str(exc)) from None


def _sim_can_bus(args: argparse.Namespace) -> tuple[str, str] | None:
    """``sim --can-interface I --can-channel C``: both or neither (a served twin sits on one bus)."""
    if (args.can_interface is None) != (args.can_channel is None):
        given = "--can-interface" if args.can_interface is not None else "--can-channel"
        raise UsageError(f"sim {given}: give --can-interface and --can-channel together (e.g. socketcan vcan0), "
                         "or neither to serve python-can-remote on --listen")
    return None if args.can_interface is None else (args.can_interface, args.can_channel)


def _cmd_sim_control(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.sim.process import (  # light: a bench's power command starts it often
        SimulatorControl,
        parse_address,
    )

    try:
        control = SimulatorControl(parse_address(args.control))
    except OSError as exc:
        print(f"sim-control: cannot reach the control channel {args.control}: {exc}", file=sys.stderr)
        return RunExit.COULD_NOT_TEST
    try:
        getattr(control, args.action.replace("-", "_"))()
    finally:
        control.close()
    return 0


def add_sim_parsers(sub: argparse._SubParsersAction) -> None:
    """``sim`` and ``sim-control``: serve simulated devices (python-can-remote or a CAN bus), switch their power."""
    sim_control = sub.add_parser("sim-control", help="switch a served simulator's power (a bench power switch)")
    sim_control.add_argument("--control", required=True, type=host_port,
                             help="HOST:PORT of the simulator's control channel")
    sim_control.add_argument("action", choices=["power-off", "power-on", "power-cycle"])
    sim_control.set_defaults(func=_cmd_sim_control)

    sim = sub.add_parser("sim", help="serve simulated devices on a python-can-remote endpoint or a CAN bus")
    sim.add_argument("--profile", action="append", required=True, help="profile id or file (repeat for more nodes)")
    sim.add_argument("--listen", default="127.0.0.1:54701", type=host_port,
                     help="HOST:PORT for python-can-remote clients (default 127.0.0.1:54701; port 0: any free one)")
    sim.add_argument("--can-interface", default=None, metavar="INTERFACE",
                     help="sit on this python-can interface instead of serving --listen, e.g. socketcan (with "
                          "--can-channel vcan0: a kernel vcan or `encoder-conformance vcan up`)")
    sim.add_argument("--can-channel", default=None, metavar="CHANNEL", help="the channel of --can-interface")
    sim.add_argument("--control", default=None, type=host_port,
                     help="HOST:PORT for the control channel (power cycle ...; default: none)")
    sim.add_argument("--node-id", type=node_id_type, action="append", default=[], metavar="1..127",
                     help="node-ID per profile (default: the profile's)")
    sim.add_argument("--copies", type=positive_int, default=1, metavar="N",
                     help="N units of the profile with serial numbers base, base+1, ... (the profile's "
                          "simulator.serial_number) and consecutive node-ids from --node-id or the profile's")
    sim.add_argument("--unconfigured", action="store_true",
                     help="the nodes wait unconfigured (node-id 255) for an LSS master (see 'lss')")
    sim.add_argument("--fault", action="append", default=[], help="inject a named fault (see 'faults')")
    sim.add_argument("--nvm", type=Path, help="file for the non-volatile memory (default: in memory)")
    sim.add_argument("--ready-line", action="store_true", help=argparse.SUPPRESS)
    sim.set_defaults(func=_cmd_sim, parser=sim)
