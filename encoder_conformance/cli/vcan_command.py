"""``vcan``: the user-space SocketCAN bus, its own parser (encoder_conformance/vcan/command.py)."""

from __future__ import annotations

import argparse


def _cmd_vcan(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.vcan.command import main as vcan_main

    given: list[str] = args.argv
    return vcan_main(given[given.index("vcan") + 1:])  # as typed: its own parser reads them


def add_vcan_parser(sub: argparse._SubParsersAction) -> None:
    """``vcan``: the user-space SocketCAN bus, its own parser (encoder_conformance/vcan/command.py)."""
    vcan = sub.add_parser("vcan", add_help=False, help="a user-space SocketCAN bus for programs that speak "
                                                       "SocketCAN (a firmware simulator, can-utils): up, run, down")
    vcan.add_argument("vcan_args", nargs=argparse.REMAINDER, help="up | run | down | env | status | build ...")
    vcan.set_defaults(func=_cmd_vcan)
