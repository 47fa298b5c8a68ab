"""Where a benchmark ran: the machine and the commit, for the JSON it writes (shared)."""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import xarray as xr


def machine() -> dict:
    """CPU, cores, memory, OS and the versions that set xbsm's speed."""
    info = {"python": sys.version.split()[0], "platform": platform.platform(),
            "machine": platform.machine(), "processor": platform.processor() or None,
            "cpu_count": os.cpu_count(), "numpy": np.__version__, "xarray": xr.__version__}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                info["memory_gib"] = round(int(line.split()[1]) / 2**20, 1)
                break
    except OSError:
        pass
    return info


ROOT = Path(__file__).resolve().parent.parent


def commit(root: Path | str = ROOT) -> dict:
    """The commit measured, and which files under xbsm/ differed from it.

    ``root`` is the checkout (default: the one this recipe belongs to); a benchmark
    that times another checkout side by side records that checkout's commit.
    """
    def git(*args):
        # rstrip only: a porcelain status line starts with a space (" M xbsm/...")
        proc = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True)
        return proc.stdout.rstrip("\n") if proc.returncode == 0 else None

    changed = [line[3:] for line in (git("status", "--porcelain", "--", "xbsm") or "").splitlines()]
    return {"commit": git("rev-parse", "--short", "HEAD"),
            "xbsm_modified_since_commit": bool(changed), "xbsm_files_changed": changed}
