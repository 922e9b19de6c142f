"""Starts the real sportsim-server on a free loopback port for tests, and stops it."""
import os
import re
import signal
import subprocess
import time


class ServerProcess:
    """sportsim-server --listen 127.0.0.1:0; the port comes from its first stdout line."""

    def __init__(self, server_bin, *extra_args):
        self.proc = subprocess.Popen(
            [server_bin, "--listen", "127.0.0.1:0", *extra_args],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()
        m = re.search(r"listening on (\S+):(\d+)$", line.strip())
        if not m:
            self.proc.kill()
            raise RuntimeError("server did not start: %r %r" % (line, self.proc.stderr.read()))
        self.port = int(m.group(2))
        self.address = "127.0.0.1:%d" % self.port

    def terminate(self, sig=signal.SIGTERM, timeout=10):
        """Sends `sig` and returns (exit code, seconds to exit, stdout rest)."""
        t0 = time.monotonic()
        self.proc.send_signal(sig)
        out, _ = self.proc.communicate(timeout=timeout)
        return self.proc.returncode, time.monotonic() - t0, out

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
