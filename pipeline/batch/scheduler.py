"""Which Dask scheduler a batch trusts, and a check, bounded in time, that the peer is one (docs/cluster.md, "Whom a
batch trusts"): a scheduler runs code in this process, so its address never comes from a (shared) config.
"""

from __future__ import annotations

import os
import socket
import ssl
import struct
import time
from dataclasses import dataclass
from importlib.util import find_spec

from gyrolab.errors import ConfigError, shorten

#: the command-line option that names the scheduler
OPTION = "--scheduler"
#: Dask's own environment variable (it feeds Dask's ``scheduler-address`` setting)
ENVIRONMENT = "DASK_SCHEDULER_ADDRESS"
IN_PROCESS = ("process", "")
LOCAL = "local"
#: seconds a scheduler has to greet us before it is called silent
CONNECT_TIMEOUT = 10
#: a scheduler's greeting (Dask's handshake: compression, python and pickle versions) is a few hundred bytes
MAX_GREETING_BYTES = 1 << 16
DEFAULT_PORT = 8786
WHERE_TO_PUT_IT = (f"give it on the command line (gyrolab --batch {OPTION} ADDRESS ...), in {ENVIRONMENT} or in "
                   "Dask's configuration (scheduler-address; docs/cluster.md)")

_command_line: str | None = None


@dataclass(frozen=True)
class Choice:
    """Where a batch's chunks run (None: this process) and where that came from, for the log."""

    scheduler: str | None
    source: str


def use_command_line_scheduler(value: str | None) -> None:
    """Set the command line's scheduler (what ``--scheduler VALUE`` does; None: not given)."""
    global _command_line
    _command_line = value


def choose_scheduler(configured: object = None) -> Choice:
    """The scheduler of a batch: the command line's, else ``batch.scheduler``'s (``configured``: ``process`` or
    ``local``; an address there is refused), else Dask's own (``DASK_SCHEDULER_ADDRESS``, its configuration files),
    else this process."""
    text = check_configured(configured)
    if _command_line is not None:
        return Choice(_command_line or None, f"the command line ({OPTION})")
    if configured is not None and text:
        return Choice(None if text in IN_PROCESS else text, "batch.scheduler")
    address = os.environ.get(ENVIRONMENT, "").strip()
    if address:
        return Choice(address, f"the environment ({ENVIRONMENT})")
    address = _dask_configured()
    if address:
        return Choice(address, "Dask's configuration (scheduler-address)")
    return Choice(None, "the default")


def check_configured(configured: object) -> str:
    """``batch.scheduler`` from a config, stripped; ConfigError for an address (module docstring).

    The check alone, without looking up Dask's own setting (which imports Dask): the preflight of every run."""
    text = "" if configured is None else str(configured).strip()
    if text not in (*IN_PROCESS, LOCAL):
        raise ConfigError(f"batch.scheduler={shorten(text)!r} is not read from a config: connecting to a Dask "
                          f"scheduler lets it run code in this process, so a config file or an experiment may only "
                          f"say process or local; {WHERE_TO_PUT_IT}")
    return text


def _dask_configured() -> str:
    """Dask's ``scheduler-address`` setting (its YAML files), read only when Dask is installed."""
    if find_spec("dask") is None:
        return ""
    import dask.config  # optional (the cluster extra)

    return str(dask.config.get("scheduler-address", None) or "").strip()


def probe(address: str, source: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """ConfigError in one sentence unless a Dask scheduler greets us at ``address`` within ``timeout`` s: the first
    message a Dask peer sends (its handshake, a length-prefixed msgpack mapping with the keys ``compression`` and
    ``python``) decoded with plain msgpack, which never runs code; ``tls://`` with Dask's TLS settings."""
    from distributed.comm.addressing import parse_address, parse_host_port  # optional (the cluster extra)

    where = f"at {address} (from {source})"
    scheme, location = parse_address(address)
    host, port = parse_host_port(location, DEFAULT_PORT)
    deadline = time.monotonic() + timeout
    try:
        connection = socket.create_connection((host, port), timeout=timeout)
    except OSError as error:
        reason = " ".join(str(error.strerror or error).split()) or type(error).__name__
        raise ConfigError(f"no Dask scheduler answers {where} within {timeout:g} s ({shorten(reason, 80)}); start "
                          "one (dask scheduler) or give the address of a running one") from None
    try:
        if scheme == "tls":
            connection = _tls_context().wrap_socket(connection, server_hostname=host)
        greeting = _greeting(connection, deadline)
    except (TimeoutError, socket.timeout):
        raise ConfigError(f"the peer {where} accepted the connection but sent nothing within {timeout:g} s (a Dask "
                          "scheduler greets at once); check the address and port (a tls:// scheduler needs a tls:// "
                          "address)") from None
    except ssl.SSLError as error:
        raise ConfigError(f"the TLS handshake with {address} (from {source}) failed ({shorten(str(error), 100)}); "
                          "check Dask's distributed.comm.tls settings (docs/cluster.md)") from None
    except OSError as error:
        reason = " ".join(str(error.strerror or error).split()) or type(error).__name__
        raise ConfigError(f"the peer {where} closed the connection before greeting as a Dask scheduler would "
                          f"({shorten(reason, 80)}); check the address and port") from None
    finally:
        connection.close()
    if greeting is None:
        raise ConfigError(f"the peer {where} is not a Dask scheduler (what it sent is not Dask's handshake); check "
                          "the address and port")


def _greeting(connection: socket.socket, deadline: float) -> dict | None:
    """The peer's handshake mapping, or None when what it sends is not one."""
    import msgpack  # optional (the cluster extra: distributed's)

    (size,) = struct.unpack("Q", _receive(connection, 8, deadline))
    if not 16 <= size <= MAX_GREETING_BYTES:
        return None
    body = _receive(connection, size, deadline)
    (n_frames,) = struct.unpack_from("Q", body)
    if not 1 <= n_frames <= 16 or len(body) < 8 * (n_frames + 1):
        return None
    lengths = struct.unpack_from(f"{n_frames}Q", body, 8)
    start = 8 * (n_frames + 1)
    if start + lengths[0] > len(body):
        return None
    try:
        message = msgpack.unpackb(body[start:start + lengths[0]], raw=False, strict_map_key=False)
    except Exception:  # noqa: BLE001 - any decoding failure means: not Dask's handshake
        return None
    return message if isinstance(message, dict) and {"compression", "python"} <= set(message) else None


def _receive(connection: socket.socket, n: int, deadline: float) -> bytes:
    """Exactly ``n`` bytes before ``deadline`` (TimeoutError), or OSError when the peer closes first."""
    data = bytearray()
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError
        connection.settimeout(left)
        piece = connection.recv(n - len(data))
        if not piece:
            raise ConnectionResetError(0, "connection closed by the peer")
        data += piece
    return bytes(data)


def _tls_context() -> ssl.SSLContext:
    """The client's TLS context from Dask's configuration (``distributed.comm.tls.*``)."""
    from distributed.security import Security  # optional (the cluster extra)

    context = Security().get_connection_args("client").get("ssl_context")
    if context is None:
        raise ConfigError("a tls:// scheduler needs Dask's TLS settings (distributed.comm.tls.ca-file, "
                          "distributed.comm.tls.client.cert and .key, or the DASK_DISTRIBUTED__COMM__TLS__* "
                          "variables; docs/cluster.md)")
    return context

