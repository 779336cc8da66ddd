"""The suite on two hosts, and faults on the link between them.

Two network namespaces stand for two machines ("host A", the rig's computer, and "host B", the
control room's), made inside the test's own loopback-only namespace (scripts/netns-run) and
joined by a veth pair, 10.232.0.1/24 on A and 10.232.0.2/24 on B, multicast routed over it.
Neither has a route anywhere else: nothing leaves the machine. Each namespace is held by a
`sleep` started with `unshare --net`; processes join one with `nsenter`, so nothing is left
behind in /run/netns.

Host A runs the virtual rig, the thermal gate and the sequencer; host B the recorder, the
quality node and the Foxglove node, every node its own process (`tyrerig node NAME --config`),
all on one DDS domain, as docs/deployment.md describes.

1. Latency across the link: the rig in real time at 1 kHz (the launch file of `tyrerig bench
   suite-latency`), the bench's probe attached on host B (`--attach`) for 10 s.
2. The full GS2MF FreeRolling procedure, the rig in real time x20 (100 Hz rig samples = 2,000
   per wall second; ~154 s), with three faults on the link:
   (a) the link down for 2 s;
   (b) 10 % of the packets dropped at random, both ways, for 10 s (nftables `numgen random` on
       each end's ingress; the kernel here has no netem qdisc);
   (c) the link down for 6 s: longer than the rig's send window (8,192 samples, RustDDS)
       lasts at 2,000 samples/s (~4.1 s). Without RustDDS patch 3 (vendor/rustdds/PATCHES.md)
       B's unacknowledged readers held the window full and the rig's writer refused every sample
       from ~4.1 s into the outage, for host A's readers too; with it a reader that owes
       acknowledgements and sends none for 2 s is made inactive and no longer holds the window.
   Asserted: the procedure completes and host B's log has it from the rig's first sample to the
   end; every sample missing from B's log is in its loss record (format tyrerig-loss/2), gap range
   by gap range, and what the rig made after B's last sample (by the rig's own final count,
   `virtual_rig: published` on /diagnostics, recorded in B's log) is the record's tail; no loss
   begins while the link is healthy (only during a fault or in the seconds after it, as B
   catches up, or while B's kernel drops datagrams at B's full sockets: B short of CPU, not the
   link); B notes each outage; the rig's writer refused nothing while the link was down
   for 6 s (its own count before and after (c)) and the sequencer did not hold the rig then;
   every gap of more than 0.6 s in host A's own samples (the rig's writer refusing samples
   while B's readers hold its send window: B catching up after a fault, acknowledging as it
   goes) made the sequencer hold the rig at zero slip within a second, and every hold ended with
   the samples back and the interrupted sweep rerun; B's Foxglove node delivers a rig sample to
   a WebSocket client. Whether (a) costs samples depends on how fast B catches up after it (the
   2 s outage is at the edge of patch 3's 2 s): measured and printed, not asserted; so is what
   (c) costs B, and what the writer refused after (c) as B caught up.

Prints the figures docs/deployment.md quotes (lines starting `TWO HOSTS`).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import threading
import time
from datetime import datetime
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from conftest import REPO, stop, wait_for

CONFIG = REPO / "launch-config"
FREEROLLING = CONFIG / "procedures" / "gs2mf_freerolling.toml"
HOST_A = ("thermal", "sequencer", "virtual_rig")  # started in this order (the rig waits for readers)
HOST_B = ("recorder", "quality", "foxglove")
ADDR = {"A": "10.232.0.1", "B": "10.232.0.2"}
TIME_SCALE = 20.0
FOXGLOVE_PORT = 18765
PHASE_COMPLETE = 8

LOSS_RULES = """
table netdev tyrerig_link_loss {{
  chain ingress {{
    type filter hook ingress device "{dev}" priority 0; policy accept;
    numgen random mod 10 == 0 counter drop
  }}
}}
"""


def strip_ansi(text: str) -> str:
    return re.sub(r"\x1b\[[0-9;]*m", "", text)


def wall_s(stamp: str) -> float:
    """A log line's RFC 3339 UTC stamp (`2026-11-24T01:59:41.300470Z`) as Unix time."""
    return datetime.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()


def log_lines(path: Path, pattern: str) -> list[tuple[float, str]]:
    """(wall time, line) of every line of a node's log that matches `pattern`."""
    out = []
    for line in strip_ansi(path.read_text()).splitlines():
        if re.search(pattern, line):
            m = re.match(r"(\S+Z)\s", line)
            if m:
                out.append((wall_s(m[1]), line))
    return out


class Host:
    """A network namespace standing for one machine, held by a sleeping process."""

    def __init__(self, name: str):
        self.name, self.dev = name, f"tyr{name}"
        self.holder = subprocess.Popen(["unshare", "--net", "--", "sleep", "100000"])
        # unshare execs sleep once the namespace is made: wait until the pid's namespace differs.
        own = os.readlink("/proc/self/ns/net")
        wait_for(lambda: os.readlink(f"/proc/{self.holder.pid}/ns/net") != own, 5.0, f"host {name}'s namespace")
        self.pid = self.holder.pid

    def cmd(self, *argv: str) -> list[str]:
        return ["nsenter", "-t", str(self.pid), "-n", "--", *argv]

    def run(self, *argv: str, stdin: str | None = None) -> str:
        done = subprocess.run(self.cmd(*argv), input=stdin, capture_output=True, text=True)
        assert done.returncode == 0, f"host {self.name}: {' '.join(argv)}: {done.stderr}"
        return done.stdout

    def popen(self, argv: list[str], log: Path, cwd: Path) -> subprocess.Popen:
        return subprocess.Popen(self.cmd(*argv), cwd=cwd, stdout=open(log, "w"), stderr=subprocess.STDOUT)

    def configure(self) -> None:
        ip = ADDR[self.name]
        for argv in (["ip", "link", "set", "lo", "up"], ["ip", "link", "set", "lo", "multicast", "on"],
                     ["ip", "addr", "add", f"{ip}/24", "dev", self.dev], ["ip", "link", "set", self.dev, "multicast", "on"],
                     ["ip", "link", "set", self.dev, "up"]):
            self.run(*argv)
        self.route_multicast()

    def route_multicast(self) -> None:
        """SPDP discovery is multicast: 224.0.0.0/4 over the link (taking a link down drops the route)."""
        self.run("ip", "route", "replace", "224.0.0.0/4", "dev", self.dev)

    def close(self) -> None:
        self.holder.kill()
        self.holder.wait()


class Link:
    """Hosts A and B joined by a veth pair, nothing else up in either."""

    def __init__(self):
        self.a, self.b = Host("A"), Host("B")
        subprocess.run(["ip", "link", "add", "tyrA", "type", "veth", "peer", "name", "tyrB"], check=True)
        subprocess.run(["ip", "link", "set", "tyrA", "netns", str(self.a.pid)], check=True)
        subprocess.run(["ip", "link", "set", "tyrB", "netns", str(self.b.pid)], check=True)
        for h in (self.a, self.b):
            h.configure()
            # Only loopback and the link are up, and nothing is routed beyond the link.
            up = {line.split(":")[1].strip().split("@")[0] for line in h.run("ip", "-o", "link", "show", "up").splitlines()}
            assert up == {"lo", h.dev}, up
            assert "default" not in h.run("ip", "route"), h.run("ip", "route")

    def down(self) -> None:
        self.a.run("ip", "link", "set", "tyrA", "down")

    def up(self) -> None:
        self.a.run("ip", "link", "set", "tyrA", "up")
        wait_for(lambda: "state UP" in self.b.run("ip", "link", "show", "tyrB"), 5.0, "the link up on B")
        for h in (self.a, self.b):
            h.route_multicast()

    def start_loss(self) -> None:
        for h in (self.a, self.b):
            h.run("nft", "-f", "-", stdin=LOSS_RULES.format(dev=h.dev))

    def stop_loss(self) -> dict[str, int]:
        """Removes the loss rules; packets dropped per receiving host."""
        dropped = {}
        for h in (self.a, self.b):
            rules = h.run("nft", "list", "table", "netdev", "tyrerig_link_loss")
            dropped[h.name] = int(re.search(r"counter packets (\d+)", rules)[1])
            h.run("nft", "delete", "table", "netdev", "tyrerig_link_loss")
        return dropped

    def close(self) -> None:
        self.a.close()
        self.b.close()


class UdpOverflowWatch:
    """Host B's kernel count of UDP datagrams dropped because a socket's receive buffer was full
    (`RcvbufErrors` in its namespace's /proc/net/snmp), read every 0.25 s while the suite runs:
    what B's own processes did not read in time, as against what the link lost."""

    def __init__(self, host: Host):
        self.path = Path(f"/proc/{host.pid}/net/snmp")
        self.readings: list[tuple[float, int]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def read(self) -> int:
        head, values = [line.split()[1:] for line in self.path.read_text().splitlines() if line.startswith("Udp:")][:2]
        return int(dict(zip(head, values))["RcvbufErrors"])

    def _run(self) -> None:
        while not self._stop.is_set():
            self.readings.append((time.time(), self.read()))
            self._stop.wait(0.25)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()
        self.readings.append((time.time(), self.read()))

    def rose_between(self, start: float, end: float) -> int:
        """Datagrams B's sockets dropped from `start` to `end` (the readings either side)."""
        before = [n for w, n in self.readings if w <= start] or [self.readings[0][1]]
        after = [n for w, n in self.readings if w >= end] or [self.readings[-1][1]]
        return after[0] - before[-1]

    def total(self) -> int:
        return self.readings[-1][1] - self.readings[0][1]


@pytest.fixture
def link():
    if shutil.which("nsenter") is None or shutil.which("unshare") is None:
        pytest.fail("nsenter and unshare (util-linux) are needed: .ci/run installs them")
    lk = Link()
    yield lk
    lk.close()


def launch_file(tmp: Path, domain_id: int, rig: str, sequencer: str = "", recorder: str = "") -> Path:
    path = tmp / "two_hosts.toml"
    path.write_text(f"""
[runtime]
domain_id = {domain_id}

[[node]]
name = "virtual_rig"
kind = "virtual_rig"
[node.config]
rig_config = "{CONFIG / 'virtual_rig.toml'}"
clock = "realtime"
start_delay_s = 2.0
wait_for_subscribers = 5   # thermal and sequencer on A; recorder, quality and foxglove on B
{rig}

[[node]]
name = "thermal"
kind = "thermal"

[[node]]
name = "sequencer"
kind = "sequencer"
[node.config]
procedure = "{FREEROLLING}"
autostart = true
checkpoint = "{tmp / 'run.checkpoint.json'}"
{sequencer}

[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "{tmp / 'run.mcap'}"
flush_interval_s = 0.25
{recorder}

[[node]]
name = "quality"
kind = "quality"

[[node]]
name = "foxglove"
kind = "foxglove"
[node.config]
port = {FOXGLOVE_PORT}
procedure = "{FREEROLLING}"
""")
    return path


class Suite:
    """The six nodes over the two hosts, each its own process, logs in `tmp/<node>.log`."""

    def __init__(self, tyrerig: Path, link: Link, launch: Path, tmp: Path):
        self.tmp, self.link = tmp, link
        self.procs: dict[str, subprocess.Popen] = {}
        for host, names in ((link.b, HOST_B), (link.a, HOST_A)):
            for name in names:
                self.procs[name] = host.popen([str(tyrerig), "node", name, "--config", str(launch)],
                                              tmp / f"{name}.log", tmp)

    def log(self, node: str) -> Path:
        return self.tmp / f"{node}.log"

    def running_since(self, timeout: float = 60.0) -> float:
        """Wall time the rig's first sample was due (its 'virtual rig running' line)."""
        def started():
            gone = {n: p.returncode for n, p in self.procs.items() if p.poll() is not None}
            assert not gone, f"nodes exited before the rig started: {gone}; " + \
                " ".join(self.log(n).read_text()[-500:] for n in gone)
            return log_lines(self.log("virtual_rig"), "virtual rig running")

        found = wait_for(started, timeout, "the rig to start (all five readers discovered across the link)",
                         interval=0.1)
        return found[0][0]

    def stop(self) -> None:
        """Producers first, the recorder last, as `tyrerig launch` does."""
        for name in ("virtual_rig", "thermal", "sequencer"):
            stop(self.procs[name], signal.SIGINT)
        time.sleep(0.5)
        for name in ("quality", "foxglove"):
            stop(self.procs[name], signal.SIGINT)
        stop(self.procs["recorder"], signal.SIGINT, timeout=60.0)

    def kill_all(self) -> None:
        for p in self.procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()


class Tally:
    """The rig's own count of its samples (`virtual_rig: published` on /diagnostics, once a wall
    second and at its stop), as B's recorder logged it."""

    def __init__(self, log_time_ns: int, values: dict[str, str]):
        self.log_time_ns = log_time_ns
        self.writer = values["writer"]
        self.last_seq, self.published, self.refused = (int(values[k]) for k in ("last_seq", "published", "refused"))


def read_log(path: Path) -> tuple[list[tuple[int, int, float]], int, list[Tally]]:
    """(RigSample.seq, log time at the recorder [ns], rig time [s]) of every sample in the log,
    the last ProcedureState's phase, and the rig's counts of `/rig/sample` found on /diagnostics
    (in the order B logged them). One pass with the reference reader (CRCs checked);
    `RigSample.seq` and `runtime_s` are read from the CDR bytes directly (decoding 300,000
    samples with mcap-ros2-support takes a minute), and every 500th sample is decoded by
    mcap-ros2-support as well and must agree."""
    decoders: dict[int, object] = {}
    factory = DecoderFactory()
    rows: list[tuple[int, int, float]] = []
    tallies: list[Tally] = []
    phase = -1
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        for schema, channel, msg in reader.iter_messages(
                topics=["/rig/sample", "/rig/procedure/state", "/diagnostics"], log_time_order=False):
            if channel.topic == "/rig/procedure/state":
                dec = decoders.setdefault(schema.id, factory.decoder_for("cdr", schema))
                phase = dec(msg.data).phase
                continue
            if channel.topic == "/diagnostics":
                dec = decoders.setdefault(schema.id, factory.decoder_for("cdr", schema))
                for st in dec(msg.data).status:
                    values = {kv.key: kv.value for kv in st.values}
                    if st.name == "virtual_rig: published" and values.get("topic") == "/rig/sample":
                        tallies.append(Tally(msg.log_time, values))
                continue
            data = msg.data
            assert data[:2] == b"\x00\x01", "not little-endian CDR"
            # Header: stamp (int32 sec, uint32 nanosec), frame_id (uint32 length + bytes), then
            # seq (uint64) and runtime_s (float64), each aligned to 8 from the body's start.
            n = struct.unpack_from("<I", data, 4 + 8)[0]
            off = (12 + n + 7) & ~7
            seq, runtime_s = struct.unpack_from("<Qd", data, 4 + off)
            if len(rows) % 500 == 0:
                dec = decoders.setdefault(schema.id, factory.decoder_for("cdr", schema))
                m = dec(data)
                assert (m.seq, m.runtime_s) == (seq, runtime_s), (m.seq, m.runtime_s, seq, runtime_s)
            rows.append((seq, msg.log_time, runtime_s))
    return rows, phase, tallies


def seq_gaps(seqs: list[int]) -> list[tuple[int, int]]:
    return [(a + 1, b - 1) for a, b in zip(seqs, seqs[1:]) if b > a + 1]


def loss_record(path: Path) -> dict[str, str]:
    with open(path, "rb") as f:
        records = [m for m in make_reader(f).iter_metadata() if m.name == "tyrerig.loss"]
    assert records, f"{path}: no tyrerig.loss record"
    entries = records[-1].metadata
    assert entries["complete"] == "true", entries
    # Format 2 counts a stream's tail (what its writer made after the last message received).
    assert entries["format"] == "tyrerig-loss/2", entries["format"]
    return entries


def recorded_sample_gaps(entries: dict[str, str]) -> tuple[int, int, int, list[tuple[int, int]]]:
    """(samples lost in gaps, gaps in all, samples lost as the tail, the first gap ranges) the
    loss record gives for RigSample.seq."""
    lost = total = tail = 0
    ranges: list[tuple[int, int]] = []
    for k, v in entries.items():
        if not k.startswith("/rig/sample msg "):
            continue
        if k.endswith(" lost"):
            lost += int(v)
        elif k.endswith(" gaps_total"):
            total += int(v)
        elif k.endswith(" tail"):
            tail += int(v)
        elif k.endswith(" gaps") and v:
            for r in v.split():
                a, _, b = r.partition("-")
                ranges.append((int(a), int(b or a)))
    return lost, total, tail, sorted(ranges)


def percentile(sorted_values: list[float], p: float) -> float:
    return sorted_values[round((len(sorted_values) - 1) * p)]


def foxglove_serves(link: Link, topic: str) -> bool:
    """A minimal Foxglove WebSocket client on host B: the handshake, the server's `advertise`,
    a `subscribe` to `topic`, and one message of it (data from host A, through the link and
    the Foxglove node)."""
    client = r"""
import base64, json, os, socket, struct, sys, time
s = socket.create_connection(("127.0.0.1", int(sys.argv[1])), timeout=5)
key = base64.b64encode(os.urandom(16)).decode()
s.sendall(("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
           f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
           "Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n").encode())
buf = b""
while b"\r\n\r\n" not in buf:
    buf += s.recv(4096)
head, buf = buf.split(b"\r\n\r\n", 1)
assert b" 101 " in head.split(b"\r\n")[0], head
def need(n):
    global buf
    while len(buf) < n:
        chunk = s.recv(65536)
        if not chunk:
            raise EOFError
        buf += chunk
def frame():
    global buf
    need(2)
    op, n, off = buf[0] & 0x0F, buf[1] & 0x7F, 2
    if n == 126:
        need(4); n, off = int.from_bytes(buf[2:4], "big"), 4
    elif n == 127:
        need(10); n, off = int.from_bytes(buf[2:10], "big"), 10
    need(off + n)
    payload, buf = buf[off:off + n], buf[off + n:]
    return op, payload
def send_text(text):
    data, mask = text.encode(), os.urandom(4)
    n = len(data)
    head = bytes([0x81, 0x80 | n]) if n < 126 else bytes([0x81, 0x80 | 126]) + n.to_bytes(2, "big")
    s.sendall(head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data)))
deadline, channel = time.monotonic() + 10, None
while time.monotonic() < deadline:
    op, payload = frame()
    if op == 1 and channel is None:
        msg = json.loads(payload)
        if msg.get("op") == "advertise":
            channel = next((c["id"] for c in msg["channels"] if c["topic"] == sys.argv[2]), None)
            if channel is not None:
                send_text(json.dumps({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": channel}]}))
    elif op == 2 and payload[:1] == b"\x01" and struct.unpack_from("<I", payload, 1)[0] == 7:
        print("RECEIVED")
        break
"""
    out = subprocess.run(link.b.cmd(sys.executable, "-c", client, str(FOXGLOVE_PORT), topic),
                         capture_output=True, text=True, timeout=30)
    return out.returncode == 0 and out.stdout.strip() == "RECEIVED"


def test_latency_across_the_link(tyrerig, domain_id, link, tmp_path):
    """The rig at 1 kHz in real time on A; `tyrerig bench suite-latency --attach` on B times
    each sample's way to B and the messages computed from it (on A: thermal state, setpoint;
    on B: live channels) — the probe and the rig share this machine's clock."""
    launch = launch_file(tmp_path, domain_id, rig="publish_rate_hz = 1000")
    probe = subprocess.Popen(link.b.cmd(str(tyrerig), "bench", "suite-latency", "--attach", "--seconds", "10"),
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    suite = Suite(tyrerig, link, launch, tmp_path)
    try:
        out, _ = probe.communicate(timeout=90)
    finally:
        if probe.poll() is None:
            probe.kill()
        suite.stop()
        suite.kill_all()
    assert probe.returncode == 0, out
    print(f"\nTWO HOSTS latency, 1 kHz, load average {os.getloadavg()[0]:.1f}:\n{out}")
    paths = re.findall(r"sample -> (.+?)\s+(\d+) matched: p50\s+(\d+) us, p99\s+(\d+) us, max\s+(\d+) us", out)
    assert len(paths) == 4, out
    for what, matched, p50, p99, _ in paths:
        # 10 s at 1 kHz: all but the few in flight at the edges, through a working link. The
        # tail depends on the machine's load (p99 0.6 s at a load average of 9 on 2 cores), so
        # only the median is bounded.
        assert int(matched) >= 9_900, f"{what}: only {matched} of ~10,000 samples matched"
        assert int(p50) < 50_000, f"{what}: p50 {p50} us"


def test_freerolling_over_two_hosts_with_link_faults(tyrerig, domain_id, link, tmp_path):
    t_test = time.monotonic()
    have_nft = shutil.which("nft") is not None
    launch = launch_file(tmp_path, domain_id, rig=f"time_scale = {TIME_SCALE}", sequencer="exit_when_done = true")
    overflow = UdpOverflowWatch(link.b)
    suite = Suite(tyrerig, link, launch, tmp_path)
    faults: dict[str, tuple[float, float]] = {}  # name -> (wall start, wall end)
    dropped: dict[str, int] = {}
    try:
        t0 = suite.running_since()
        # Host B's Foxglove node serves the rig's samples from across the link.
        wait_for(lambda: foxglove_serves(link, "/rig/sample"), 20.0, "a /rig/sample from host B's Foxglove node")

        def at(s: float) -> None:
            time.sleep(max(0.0, t0 + s - time.time()))

        at(10.0)
        t = time.time()
        link.down()
        time.sleep(2.0)
        link.up()
        faults["a"] = (t, time.time())
        at(20.0)
        if have_nft:
            t = time.time()
            link.start_loss()
            time.sleep(10.0)
            dropped = link.stop_loss()
            faults["b"] = (t, time.time())
        at(40.0)
        t = time.time()
        link.down()
        time.sleep(6.0)
        link.up()
        faults["c"] = (t, time.time())
        # The procedure runs to its end (~154 s of wall time at x20, plus the sweep (c) reran).
        suite.procs["sequencer"].wait(timeout=240.0)
        assert suite.procs["sequencer"].returncode == 0
    finally:
        try:
            suite.stop()
        finally:
            suite.kill_all()
            overflow.stop()
    wall = time.monotonic() - t_test
    assert dropped.get("A", 1) > 0 and dropped.get("B", 1) > 0, f"the loss rules dropped nothing: {dropped}"

    # B's log: the procedure to its end, every gap in RigSample.seq in its loss record.
    log = tmp_path / "run.mcap"
    got, phase, tallies = read_log(log)
    seqs = [s for s, _, _ in got]
    assert seqs == sorted(seqs) and seqs[0] == 0, "B's log does not start with the rig's first sample"
    assert phase == PHASE_COMPLETE, "B's log does not show the procedure complete"
    gaps = seq_gaps(seqs)
    lost = sum(b - a + 1 for a, b in gaps)
    entries = loss_record(log)
    rec_lost, rec_total, rec_tail, rec_ranges = recorded_sample_gaps(entries)
    assert (rec_lost, rec_total) == (lost, len(gaps)), \
        f"log: {lost} samples missing in {len(gaps)} gaps; loss record: {rec_lost} in {rec_total}"
    assert rec_ranges == gaps[:len(rec_ranges)] and len(rec_ranges) == min(len(gaps), 100), \
        f"loss record gaps {rec_ranges[:5]}… vs the log's {gaps[:5]}…"
    # The rig's own count: its last one (sent as it stopped, before the recorder stopped) says what
    # it made; whatever of that is after B's last sample is the loss record's tail, on its writer.
    assert tallies, "no `virtual_rig: published` count of /rig/sample in B's log"
    final = tallies[-1]
    assert final.published + final.refused == final.last_seq + 1, \
        f"the rig's count: {final.published} published + {final.refused} refused, made up to seq {final.last_seq}"
    assert final.last_seq >= seqs[-1], f"B has seq {seqs[-1]}, the rig says it made up to {final.last_seq}"
    tail_key = f"/rig/sample msg {final.writer} tail"
    assert entries.get(tail_key) == str(final.last_seq - seqs[-1]) and rec_tail == final.last_seq - seqs[-1], \
        f"the rig made up to seq {final.last_seq}, B's log ends at {seqs[-1]}; loss record: " \
        f"{tail_key} = {entries.get(tail_key)}, tails {rec_tail}"

    # The rig paces its samples in real time: rig time t is published at wall time
    # base + t / TIME_SCALE, where base is found from the earliest arrivals at B (so delays
    # below are relative to the fastest delivery of the run). Runtime of a seq by interpolation.
    offs = [(lt / 1e9 - rt / TIME_SCALE, rt) for _, lt, rt in got]
    base = min(o for o, _ in offs)
    per_seq = (got[-1][2] - got[0][2]) / (got[-1][0] - got[0][0])

    def published(seq: int) -> float:
        return base + (got[0][2] + (seq - got[0][0]) * per_seq) / TIME_SCALE

    # A healthy link loses nothing: every gap in B's log begins during a fault or in the seconds
    # after it (B catching up on what the writer held for it), before the next fault.
    starts = sorted(a for a, _ in faults.values())

    def aftermath_end(name: str) -> float:
        start, end = faults[name]
        return min([end + 15.0] + [a for a in starts if a > start])

    def fault_of(t: float) -> str | None:
        return next((n for n, (a, _) in faults.items() if a - 0.1 <= t <= aftermath_end(n)), None)

    # Unless B itself could not keep up: on a loaded 2-core machine B, catching up after the 6 s
    # outage (resent samples on top of live ones, for each of its three readers), can fall behind
    # for good, and its sockets' receive buffers overflow (CI once, and here with three CPU hogs
    # beside the test: from fault (c) on, B's delay grew to 3-18 s and its kernel dropped 530,000
    # datagrams). Such a gap is B's own loss, not the link's: B's kernel counted datagrams dropped
    # at its full sockets between the first missing sample's publication and the recorder naming
    # the gap. A gap on a healthy link without that is a lost sample nobody can account for.
    missing = {int(m[1]): w for w, line in log_lines(suite.log("recorder"), r"recorder: \d+ sample\(s\) missing")
               if (m := re.search(r"missing on /rig/sample: seq (\d+)", line))}
    healthy_gaps = [g for g in gaps if fault_of(published(g[0])) is None]
    for a, _ in healthy_gaps:
        assert a in missing, f"the recorder's log does not name the gap from seq {a}"
    unexplained = [(a, b) for a, b in healthy_gaps if overflow.rose_between(published(a) - 0.5, missing[a] + 0.5) == 0]
    assert not unexplained, \
        f"B lost samples while the link was healthy and its sockets dropped nothing: {unexplained[:5]}"
    lost_overloaded = sum(b - a + 1 for a, b in healthy_gaps)
    lost_in = {n: sum(b - a + 1 for a, b in gaps if fault_of(published(a)) == n) for n in faults}

    # B noted each outage: the recorder's stream watch, at the latest when traffic came back.
    silences = log_lines(suite.log("recorder"), r"silent for \d+\.\d s while other streams flow")

    def noted(name: str, min_s: float) -> float:
        start, end = faults[name]
        hits = [w for w, line in silences if start <= w <= min(end + 5.0, aftermath_end(name))
                and float(re.search(r"silent for (\d+\.\d) s", line)[1]) >= min_s]
        assert hits, f"host B's recorder did not note outage ({name})"
        return hits[0] - start

    detect_b = {"a": noted("a", 1.5), "c": noted("c", 4.0)}
    # How soon B reported a loss: the recorder's 'missing' line for the first gap of each fault,
    # after the first missing sample was published (the gap shows with the next sample).
    reported = {}
    for name in faults:
        first = next((a for a, _ in gaps if fault_of(published(a)) == name), None)
        if first is not None:
            assert first in missing, f"the recorder's log does not name the gap from seq {first}"
            reported[name] = missing[first] - published(first)

    # Host A's control loop. Its samples stop only when the rig's writer refuses them: B's
    # readers holding the send window (8,192 samples) full. One that has not acknowledged for
    # 2 s no longer does (RustDDS patch 3); one catching up after a fault, acknowledging as it
    # goes, still does. Every gap the sequencer saw that is longer than its rig_silent_after_s
    # (0.5 s = 1,000 samples at x20; 1,200 to allow for pacing) must have made it hold the rig at
    # zero slip before it took the first sample after the gap (its 'missing' line), and within a
    # second of the gap's start unless the sequencer itself was stalled longer (a 2-core CI
    # machine under load once stopped the whole process for 2.1 s: it lost that time's samples
    # from its reader's history, held as it woke, and reran the sweep); every hold must end with
    # the samples back and the interrupted sweep rerun.
    seq_missing = [(w, int(m[1]), int(m[2] or m[1])) for w, line in
                   log_lines(suite.log("sequencer"), r"sequencer: \d+ sample\(s\) missing on /rig/sample")
                   if (m := re.search(r"seq (\d+)(?:-(\d+))?$", line))]
    holds = log_lines(suite.log("sequencer"), r"sequencer: rig_silent: no rig sample")
    backs = log_lines(suite.log("sequencer"), r"sequencer: rig_silent: rig samples back")
    assert all("held at zero slip" in line for _, line in holds), holds
    long_gaps = [(w, a, b) for w, a, b in seq_missing if b - a + 1 >= 1_200]
    detect_a = []
    for w_missing, a, b in long_gaps:
        t_gap = published(a)
        hold = next((w for w, _ in holds if t_gap <= w <= max(t_gap + 1.0, w_missing)), None)
        assert hold is not None, \
            f"host A's sequencer missed samples {a}-{b} ({(b - a + 1) / 2000:.1f} s) without holding the rig first"
        detect_a.append((t_gap, hold - t_gap))
    for w, _ in holds:
        assert any(bw > w and "interrupted sweep reruns" in line for bw, line in backs), \
            f"the sequencer held the rig at {w:.1f} and never resumed"
    # The rig logs its 1st to 5th refusal and then every 1,000th; its final count has them all.
    refusals = log_lines(suite.log("virtual_rig"), r"refused by the writer \((\d+) so far\)")
    logged = max((int(re.search(r"\((\d+) so far\)", line)[1]) for _, line in refusals), default=0)
    refused = final.refused
    assert logged == (refused if refused <= 5 else max(5, refused // 1000 * 1000)), \
        f"the rig's log counts {logged} refusals, its final count {refused}"
    a_lost = sum(b - a + 1 for _, a, b in seq_missing)

    # The 6 s outage (c) no longer stalls host A: B's readers, silent, are made inactive 2 s in
    # (the rig's writer says so in its log), and the writer refuses nothing while the link is
    # down (by its own count, from its last count before the outage to its first after it; the
    # counts are once a wall second). Before patch 3 it refused every sample from ~4.1 s in.
    def sample_published(tally: Tally) -> float:
        return published(tally.last_seq)

    c_start, c_end = faults["c"]
    before_c = [t for t in tallies if sample_published(t) <= c_start]
    after_c = [t for t in tallies if sample_published(t) >= c_end]
    assert before_c and after_c, "no count of the rig's from before and after the 6 s outage in B's log"
    last_before, first_after = max(before_c, key=lambda t: t.last_seq), min(after_c, key=lambda t: t.last_seq)
    refused_c = first_after.refused - last_before.refused
    assert refused_c == 0, f"the rig's writer refused {refused_c} samples while the link was down 6 s"
    assert not [w for w, _ in holds if c_start <= w <= c_end], "the sequencer held the rig while the link was down 6 s"
    inactive = {name: [w - faults[name][0] for w, line in
                       log_lines(suite.log("virtual_rig"), r"has sent no ACKNACK for .*topic=\"rt/rig/sample\"")
                       if faults[name][0] <= w <= aftermath_end(name)] for name in faults}
    assert inactive["c"], "the rig's writer never stopped waiting for B's readers of /rig/sample in the 6 s outage"

    def refused_text(name: str) -> str:
        """What the rig's writer refused from the fault's start until the next fault (or 15 s
        after it): the samples host A's sequencer missed, with when they were published."""
        start = faults[name][0]
        rs = [(a, b) for _, a, b in seq_missing if fault_of(published(a)) == name]
        n = sum(b - a + 1 for a, b in rs)
        stop_waiting = f"the rig's writer stopped waiting for {len(inactive[name])} reader(s) of B " \
            f"{min(inactive[name]):.2f}–{max(inactive[name]):.2f} s after the link went down; " if inactive[name] else ""
        if not n:
            return stop_waiting + "the rig's writer refused none"
        return stop_waiting + f"the rig's writer refused {n} samples ({n / 2000:.2f} s of them), published " \
            f"{published(rs[0][0]) - start:.2f}–{published(rs[-1][1]) - start:.2f} s after the link went down"

    def hold_text(name: str) -> str:
        start = faults[name][0]
        hs = [w for w, _ in holds if start <= w <= aftermath_end(name)]
        if not hs:
            return "sequencer never held"
        ds = [d for t, d in detect_a if fault_of(t) == name]
        after = f" ({min(ds):.2f}–{max(ds):.2f} s after its samples stopped)" if ds else ""
        return f"sequencer held the rig {hs[0] - start:.2f} s after the link went down{after}, resumed, sweep reran"

    def delay(name: str) -> str:
        start, end = faults[name]
        d = sorted((o - base) * 1e3 for o, rt in offs if start <= base + rt / TIME_SCALE <= end)
        if not d:
            return "no sample"
        return f"{len(d)} samples published in it reached B with delay p50 {percentile(d, 0.5):.1f} / " \
               f"p99 {percentile(d, 0.99):.0f} / max {d[-1]:.0f} ms"

    def when(name: str) -> str:
        if name not in reported:
            return "nothing to report"
        return f"reported {reported[name]:.2f} s after its first missing sample was published"

    print(f"\nTWO HOSTS run: GS2MF FreeRolling x{TIME_SCALE:.0f}, {len(seqs)} samples in B's log, "
          f"{lost} missing in {len(gaps)} gaps and a tail of {rec_tail} (all in the loss record); the rig made "
          f"{final.last_seq + 1}, its writer refused {refused}; the sequencer on A missed {a_lost}; "
          f"test wall time {wall:.0f} s, load average {os.getloadavg()[0]:.1f}; B's sockets dropped "
          f"{overflow.total()} datagrams (receive buffers full), {lost_overloaded} samples lost in "
          f"{len(healthy_gaps)} gaps on a healthy link as B fell behind")
    print(f"TWO HOSTS fault (a) link down 2 s | B noted the outage {detect_b['a']:.2f} s after it began; "
          f"{refused_text('a')}; {hold_text('a')} | B lost {lost_in['a']}, {when('a')} | {delay('a')}")
    if "b" in faults:
        print(f"TWO HOSTS fault (b) 10 % loss 10 s | packets dropped: {dropped.get('B', 0)} into B, "
              f"{dropped.get('A', 0)} into A; {refused_text('b')}; {hold_text('b')} | B lost {lost_in['b']}, "
              f"{when('b')} | {delay('b')}")
    print(f"TWO HOSTS fault (c) link down 6 s | B noted the outage {detect_b['c']:.2f} s after it began; "
          f"{refused_text('c')} (by its count, {refused_c} while the link was down); {hold_text('c')} | "
          f"B lost {lost_in['c']} in {sum(1 for a, _ in gaps if fault_of(published(a)) == 'c')} gap(s), "
          f"{when('c')} | {delay('c')}")
    if not have_nft:
        pytest.skip("fault (b), 10 % packet loss, not run: no `nft` (nftables) on this machine; .ci/run installs it")
