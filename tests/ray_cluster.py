"""A real local Ray cluster for the tests that train or play leagues on Ray."""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import psutil

from ports import free_port


class LocalRayCluster:
    """A real Ray cluster on 127.0.0.1 (a head and ``nodes - 1`` more nodes, one CPU each; two by default),
    started with ``ray start`` and stopped by the PIDs of every process that carries its own temp folder or port."""

    def __init__(self, port: int | None = None, nodes: int = 2):
        """``port``: the head's (GCS) port; default a free loopback port, so no other cluster on the machine (another
        test process's, or one a user runs) is ever joined or disturbed."""
        # Ray's Unix sockets live under its temp folder, and a socket path may not exceed 107 bytes: pytest's
        # tmp_path is too deep, a fresh folder in the system's temp directory is not
        self.port, self.temp = port or free_port(), Path(tempfile.mkdtemp(prefix="ray"))
        self.ray = str(Path(sys.executable).with_name("ray"))
        common = ["--num-cpus=1", "--object-store-memory=150000000", "--disable-usage-stats",
                  "--node-ip-address=127.0.0.1"]
        subprocess.run([self.ray, "start", "--head", f"--port={self.port}", f"--temp-dir={self.temp}",
                        "--include-dashboard=false", *common], check=True, capture_output=True, timeout=120)
        for _ in range(nodes - 1):
            subprocess.run([self.ray, "start", f"--address=127.0.0.1:{self.port}", *common], check=True,
                           capture_output=True, timeout=120)

    @property
    def address(self) -> str:
        return f"127.0.0.1:{self.port}"

    def processes(self) -> list[psutil.Process]:
        # Ray's client server names the head by the machine's own address, not 127.0.0.1: match the port alone
        on_port = re.compile(rf":{self.port}(?!\d)")
        found = []
        for proc in psutil.process_iter(["cmdline"]):
            cmdline = " ".join(proc.info["cmdline"] or ())
            if (str(self.temp) in cmdline or "ray" in cmdline and on_port.search(cmdline)) \
                    and proc.pid != psutil.Process().pid:
                found.append(proc)
        return found

    def stop(self) -> None:
        for proc in self.processes():
            try:
                proc.kill()
            except psutil.NoSuchProcess:
                pass
        psutil.wait_procs(self.processes(), timeout=20)
        shutil.rmtree(self.temp, ignore_errors=True)
