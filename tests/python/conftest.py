"""Shared fixtures: the tyrerig binary, launch files in temporary directories, DDS domain."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def tyrerig() -> Path:
    """The tyrerig binary (`.ci/run` builds it; TYRERIG_BIN overrides)."""
    path = Path(os.environ.get("TYRERIG_BIN", REPO / "target" / "debug" / "tyrerig"))
    if not path.exists():
        subprocess.run(["cargo", "build", "-q", "--bin", "tyrerig"], cwd=REPO, check=True)
    return path


@pytest.fixture(scope="session")
def domain_id() -> int:
    d = int(os.environ.get("ROS_DOMAIN_ID", "0"))
    if d == 0:
        pytest.fail("DDS tests must run on a non-zero ROS_DOMAIN_ID inside scripts/netns-run")
    return d


def stop(proc: subprocess.Popen, sig=signal.SIGINT, timeout=30.0) -> int:
    """Signals a process and waits for it; kills it if it does not stop."""
    if proc.poll() is None:
        proc.send_signal(sig)
    try:
        return proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise


def wait_for(predicate, timeout: float, what: str, interval: float = 0.05):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(interval)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def taken(reader, n: int) -> list:
    """The samples with data of `reader.take(N=n)`. cyclonedds also hands out an `InvalidSample`
    when an instance's state changes (its writer left or unregistered it): it carries no fields,
    and reading one as a message fails (seen once in CI: `'InvalidSample' object has no attribute
    'clock'`)."""
    from cyclonedds.internal import InvalidSample

    return [s for s in reader.take(N=n) if not isinstance(s, InvalidSample)]
