"""Serve the history page: uvicorn on one socket, loopback (127.0.0.1:8600) unless told otherwise.

The socket is bound here before uvicorn starts, so an address in use or not allowed is one line naming --listen
(and port 0 picks a free port, printed); the history is opened once read-only first, so a wrong --db is one
line too. Ctrl-C stops the server (exit 0).
"""

from __future__ import annotations

import socket

import uvicorn

from encoder_conformance.errors import UsageError
from encoder_conformance.history.backend import open_db
from encoder_conformance.history.target import Target
from encoder_conformance.history.web.app import make_app


def _bind(host: str, port: int) -> socket.socket:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    try:
        return socket.create_server((host, port), family=family, reuse_port=False)
    except OSError as exc:
        raise UsageError(f"--listen {host}:{port}: cannot listen there ({exc.strerror or exc}); give a free port "
                         "of this computer, such as 127.0.0.1:8601") from None


def serve(target: Target, host: str, port: int) -> int:
    with open_db(target, create=False, readonly=True):
        pass  # HistoryError: the command prints it in one line
    sock = _bind(host, port)
    bound = sock.getsockname()[1]
    shown = f"[{host}]" if ":" in host else host
    print(f"history serve: http://{shown}:{bound}/ (read-only, {target}); Ctrl-C stops", flush=True)
    config = uvicorn.Config(make_app(target), log_level="warning", access_log=False, server_header=False,
                            lifespan="off")
    uvicorn.Server(config).run(sockets=[sock])
    return 0
