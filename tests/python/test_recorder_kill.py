"""SIGKILL the recorder mid-run, then `tyrerig mcap recover`: every message of every complete
chunk must be in the recovered file (counted independently by Python's linear MCAP reader), and
the recovered file must pass the independent reader's CRC checks."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Message
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory

from conftest import stop


def messages_in_complete_chunks(path: Path) -> int:
    count = 0
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False).records:
                if isinstance(record, Message):
                    count += 1
        except (McapError, EOFError, ValueError, Exception):  # the cut-off tail
            pass
    return count


def test_killed_recorder_loses_only_the_open_chunk(tyrerig, domain_id, tmp_path: Path):
    launch = tmp_path / "kill.toml"
    launch.write_text(f"""
[runtime]
domain_id = {domain_id}

[[node]]
name = "pattern"
kind = "test_pattern"
[node.config]
rate_hz = 500.0
discovery_wait_s = 1.0
topics = ["sample"]

[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "killed.mcap"
topics = ["sample"]
flush_interval_s = 0.25
""")
    recorder = subprocess.Popen([str(tyrerig), "node", "recorder", "--config", str(launch)], cwd=tmp_path)
    pattern = subprocess.Popen([str(tyrerig), "node", "pattern", "--config", str(launch)], cwd=tmp_path)
    try:
        time.sleep(5.0)
        recorder.send_signal(signal.SIGKILL)
        recorder.wait(timeout=10)
    finally:
        stop(pattern)

    killed = tmp_path / "killed.mcap"
    in_chunks = messages_in_complete_chunks(killed)
    assert in_chunks > 500, f"only {in_chunks} messages reached the disk in ~4 s at 500 Hz"

    out = tmp_path / "recovered.mcap"
    done = subprocess.run([str(tyrerig), "mcap", "recover", str(killed), "-o", str(out)],
                          capture_output=True, text=True, check=True)
    assert f"recovered {in_chunks} messages" in done.stdout, done.stdout

    with open(out, "rb") as f:
        reader = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        assert reader.get_summary() is not None
        ns = [m.header.stamp.sec for _, _, _, m in reader.iter_decoded_messages()]
    assert len(ns) == in_chunks
    # The pattern's message numbers are contiguous: nothing inside the kept chunks is missing.
    assert ns == list(range(ns[0], ns[0] + len(ns)))
