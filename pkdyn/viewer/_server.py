"""meshcat's server, listening on one address only (run as a script by :func:`start_server`).

meshcat's ``ZMQWebSocketBridge`` binds its command socket (ZeroMQ) to 127.0.0.1 but lets tornado
listen for browsers on **every** interface (``app.listen(port)``), so anyone who can reach the
machine can read the scene. Here the web server listens on ``--host`` only (127.0.0.1 unless the
user opts in) and the command socket stays on 127.0.0.1 whatever the host.

This file is executed as a script in its own process: it imports meshcat, not pkdyn.
"""

from __future__ import annotations

import argparse
import atexit
import os
import socket
import subprocess
import sys
from typing import Any

__all__ = ["LOOPBACK", "ServerProcess", "start_server"]

LOOPBACK = "127.0.0.1"
"""Default listening address of the live viewer."""


class ServerProcess:
    """A running viewer server: its process and URLs.

    Attributes:
        proc: The server process.
        zmq_url: Command socket (always on 127.0.0.1).
        web_url: Address browsers open.
        host: Address the web server listens on.
        port: Its port.

    """

    def __init__(self, proc: subprocess.Popen[bytes], zmq_url: str, web_url: str, host: str):
        self.proc = proc
        self.zmq_url = zmq_url
        self.web_url = web_url
        self.host = host
        self.port = int(web_url.split(":")[2].split("/")[0])

    def stop(self) -> None:
        """Kill the server (idempotent)."""
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        for stream in (self.proc.stdout, self.proc.stderr):
            if stream is not None:
                stream.close()


def start_server(host: str = LOOPBACK) -> ServerProcess:
    """Start the viewer server in its own process, listening on ``host``.

    Args:
        host: Listening address of the web server (``127.0.0.1``: this machine only).

    Returns:
        The running server; stop it with :meth:`ServerProcess.stop` (also done at exit).

    Raises:
        RuntimeError: The server did not start.

    """
    args = [sys.executable, "-u", os.path.abspath(__file__), "--host", host]
    proc = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True
    )
    urls: dict[str, str] = {}
    assert proc.stdout is not None
    while len(urls) < 2:
        line = proc.stdout.readline().decode("utf-8").strip()
        if not line and proc.poll() is not None:
            err = proc.stderr.read().decode("utf-8") if proc.stderr else ""
            raise RuntimeError(f"the viewer server exited ({proc.returncode}): {err.strip()}")
        key, sep, value = line.partition("=")
        if sep and key in ("zmq_url", "web_url"):
            urls[key] = value
    server = ServerProcess(proc, urls["zmq_url"], urls["web_url"], host)
    atexit.register(server.stop)
    return server


def _bridge(host: str) -> Any:
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class LocalBridge(ZMQWebSocketBridge):  # type: ignore[misc]
        """meshcat's bridge with the web server bound to ``host`` only."""

        def make_app(self) -> Any:
            app = super().make_app()
            listen = app.listen

            def bound(port: int, address: str | None = None, **kwargs: Any) -> Any:
                return listen(port, address=host, **kwargs)

            app.listen = bound
            return app

    bridge = LocalBridge(host=LOOPBACK)  # the ZeroMQ command socket: always local
    shown = socket.gethostname() if host in ("", "0.0.0.0", "::") else host
    bridge.web_url = f"http://{shown}:{bridge.fileserver_port}/static/"
    return bridge


def main() -> None:
    """Serve until killed; print ``zmq_url=...`` and ``web_url=...`` first."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--host", default=LOOPBACK)
    args = parser.parse_args()
    bridge = _bridge(args.host)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
