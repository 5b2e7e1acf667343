"""A CAN bus for separate processes: a python-can-remote server on a virtual channel.

    python -m tests.independent.bus_hub [--listen 127.0.0.1:0]

Prints ``READY ws://HOST:PORT/`` once it serves; every client (the independent device, the suite) joins the
same virtual bus with ``--can-interface remote --can-channel ws://HOST:PORT/``. Runs until SIGTERM.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import threading

from can_remote.server import RemoteServer

from .link import parse_address, wait_for_sigterm


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.independent.bus_hub", description=__doc__)
    parser.add_argument("--listen", default="127.0.0.1:0", help="HOST:PORT to serve (port 0: any free port)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    host, port = parse_address(args.listen)
    server = RemoteServer(host, port, interface="virtual", channel=f"independent-{os.getpid()}")
    threading.Thread(target=lambda: server.serve_forever(poll_interval=0.05), daemon=True).start()
    print(f"READY ws://{host}:{server.server_port}/", flush=True)
    wait_for_sigterm()
    sys.stdout.flush()
    os._exit(0)  # the clients' threads would hold the interpreter's shutdown


if __name__ == "__main__":
    sys.exit(main())
