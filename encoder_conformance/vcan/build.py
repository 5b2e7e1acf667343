"""Compile the preload library (preload.c, with preload_links.c and preload_netlink.c) with the machine's C
compiler at first use, into a cache keyed by sources and compiler.

The library goes to ``$XDG_CACHE_HOME/encoder-conformance/`` (``~/.cache/...``; a per-user folder in the
temporary directory when that is not writable) as ``vcan-preload-<hash>.so``, where the hash covers the
sources, the compiler command and its version and the flags: an edited source or another compiler builds
anew, an unchanged one is reused. ``$CC`` names the compiler (else ``cc``, ``gcc``, ``clang``).
"""

from __future__ import annotations

import hashlib
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from encoder_conformance.errors import BuildError

SOURCES = [Path(__file__).with_name(name) for name in ("preload.c", "preload_links.c", "preload_netlink.c")]
HEADER = Path(__file__).with_name("preload.h")
FLAGS = ["-shared", "-fPIC", "-O2", "-Wall", "-U_FORTIFY_SOURCE"]
LIBS = ["-ldl", "-lpthread"]
COMPILERS = ("cc", "gcc", "clang")


def compiler() -> list[str]:
    """The compiler command: ``$CC`` if set, else the first of cc, gcc, clang on PATH."""
    named = os.environ.get("CC", "").strip()
    if named:
        command = shlex.split(named)
        if shutil.which(command[0]) is None:
            raise BuildError(f"the C compiler named by $CC ({command[0]}) is not installed")
        return command
    for name in COMPILERS:
        found = shutil.which(name)
        if found:
            return [found]
    raise BuildError("the virtual CAN bus needs a C compiler to build its preload library and found none "
                     "(looked for $CC, cc, gcc, clang): install one, e.g. 'apt-get install gcc'")


def cache_dir() -> Path:
    """Where built libraries are kept (created if missing)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    for folder in (Path(base) / "encoder-conformance",
                   Path(tempfile.gettempdir()) / f"encoder-conformance-cache-{os.getuid()}"):
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(folder, os.W_OK):
            return folder
    raise BuildError(f"no writable cache folder for the preload library (tried {base} and the temporary folder)")


def _version(command: list[str]) -> str:
    try:
        done = subprocess.run([*command, "--version"], capture_output=True, text=True, timeout=30, check=False)
    except OSError as error:
        raise BuildError(f"the C compiler {command[0]} cannot be run: {error}") from error
    return done.stdout


def library(*, force: bool = False) -> Path:
    """The path of the built preload library, compiling it first if the cache has no matching build."""
    if sys.platform != "linux":
        raise BuildError(f"the virtual CAN bus is Linux only (it stands in for Linux SocketCAN through LD_PRELOAD "
                         f"of glibc's socket calls); this is {sys.platform}")
    command = compiler()
    key = hashlib.sha256()
    sources = [path.read_bytes() for path in [*SOURCES, HEADER]]
    for part in (*sources, " ".join(command).encode(), _version(command).encode(), " ".join(FLAGS + LIBS).encode(),
                 platform.machine().encode()):
        key.update(part)
        key.update(b"\0")
    target = cache_dir() / f"vcan-preload-{key.hexdigest()[:16]}.so"
    if target.exists() and not force:
        return target
    if any(c.isspace() or c == ":" for c in str(target)):
        raise BuildError(f"LD_PRELOAD cannot name a path with spaces or colons: {target} (set XDG_CACHE_HOME)")
    handle, partial = tempfile.mkstemp(prefix=target.stem, suffix=".so.part", dir=target.parent)
    os.close(handle)
    try:
        done = subprocess.run([*command, *FLAGS, "-o", partial, *map(str, SOURCES), *LIBS],
                              capture_output=True, text=True, timeout=300, check=False)
        if done.returncode != 0:
            hint = ""
            if "linux/can" in done.stderr or "stdio.h" in done.stderr:
                hint = " (missing headers: 'apt-get install libc6-dev linux-libc-dev')"
            raise BuildError(f"compiling {', '.join(path.name for path in SOURCES)} with {command[0]} failed{hint}:\n"
                             f"{done.stderr.strip()}")
        os.replace(partial, target)  # atomic: a concurrent build of the same key is harmless
    finally:
        if os.path.exists(partial):
            os.unlink(partial)
    return target
