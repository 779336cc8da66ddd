"""DDS Security (issue 14): only participants with credentials from the rig's keystore take part.

- The secure suite (``tyrerig run --keystore``) runs a procedure end to end and logs what the
  plain suite logs; meanwhile a participant without credentials (plain Python cyclonedds)
  discovers none of the suite's endpoints, reads no sample, and its ABORTs never arrive.
- Operator stations (``tyrerig command``): an operator enclave is heard, a monitor enclave is
  refused by its own access control, an operator enclave from another keystore is not admitted.
- A second implementation (Cyclone DDS's C library with its DDS Security plugins, Debian's
  ``libddsc0debian``) accepts our keystore's documents and enforces them: a monitor enclave may
  not write commands, a Cyclone rig enclave's samples reach a Cyclone monitor enclave, and
  participants without credentials or from another keystore read nothing.
- RustDDS and Cyclone DDS 0.10.2 interoperate with security: a Cyclone monitor enclave reads the
  secured test pattern's signed samples from tyrerig (RustDDS 0.15.1 as vendored with tyrerig's
  patches, vendor/rustdds/PATCHES.md 2a-2e; docs/security.md, "Interoperability").

Needs tyrerig built with ``--features security`` (scripts/test does) and Debian's Cyclone DDS
packages (``.ci/run`` installs them).
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path

import pytest
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap.reader import make_reader

import cyclone_c_peer
from conftest import REPO, stop, taken
from tyre_msgs_idl import types

SUITE_ENCLAVES = ["/rig/recorder", "/rig/thermal", "/rig/sequencer", "/rig/quality", "/rig/virtual_rig"]


def security(tyrerig: Path, *args: str) -> str:
    out = subprocess.run([str(tyrerig), "security", *args], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, f"tyrerig security {' '.join(args)}: {out.stderr}"
    return out.stdout


@pytest.fixture(scope="module")
def keystores(tyrerig: Path, tmp_path_factory) -> dict:
    """Ours (the suite's enclaves, operators, monitors, a pattern rig, Cyclone stations) and
    another keystore (another identity CA and permissions CA) with an operator."""
    root = tmp_path_factory.mktemp("keystores")
    ours, theirs = root / "ours", root / "theirs"
    security(tyrerig, "create-keystore", str(ours))
    security(tyrerig, "create-enclave", str(ours), *SUITE_ENCLAVES)
    security(tyrerig, "create-enclave", str(ours), "/rig/run_watcher", "/rig/viewer", "/rig/cyclone_monitor",
             "--role", "monitor")
    security(tyrerig, "create-enclave", str(ours), "/rig/pattern", "/rig/cyclone_rig", "--role", "rig")
    security(tyrerig, "create-enclave", str(ours), "/rig/operator_1", "--role", "operator")
    security(tyrerig, "create-keystore", str(theirs))
    security(tyrerig, "create-enclave", str(theirs), "/rig/operator_1", "/rig/cyclone_monitor", "--role", "operator")
    return {"ours": ours, "theirs": theirs}


def enclave(ks: Path, name: str) -> str:
    return str(ks / "enclaves" / name.strip("/"))


def raw_log(path: Path) -> dict:
    """The CDR bytes of every message per topic, in log order (CRCs checked)."""
    topics: dict = {}
    with open(path, "rb") as f:
        for _, channel, message in make_reader(f, validate_crcs=True).iter_messages():
            topics.setdefault(channel.topic, []).append(message.data)
    return topics


def short_launch_config(root: Path) -> Path:
    """launch-config with a short StaticLong (one pressure, two loads, two repeats: 40 s of rig
    time instead of 765 s), so the secured run fits in CI; rig config and tyres are the shipped."""
    lc = root / "launch-config"
    (lc / "procedures").mkdir(parents=True)
    shipped = REPO / "launch-config"
    os.symlink(shipped / "virtual_rig.toml", lc / "virtual_rig.toml")
    os.symlink(shipped / "tyres", lc / "tyres")
    text = (shipped / "procedures" / "gs2mf_staticlong.toml").read_text()
    for old, new in (('pressures = ["low", "mid", "high"]', 'pressures = ["mid"]'),
                     ("loads = [0.4, 0.6, 0.8, 1.0, 1.2, 1.4]", "loads = [0.6, 1.0]"),
                     ("repeat = 4 ", "repeat = 2 ")):
        assert old in text, f"gs2mf_staticlong.toml changed: {old!r} not found"
        text = text.replace(old, new)
    (lc / "procedures" / "gs2mf_staticlong.toml").write_text(text)
    return lc


#: Topics whose content two plain runs of the same procedure and seed log byte for byte the
#: same (the end-of-run summaries depend on when the producers stop; /clock is best effort).
DETERMINISTIC = ["/rig/sample", "/rig/setpoint", "/rig/procedure/state", "/rig/thermal/state",
                 "/rig/quality/report", "/diagnostics"]
# The status name of the rig's count of its samples (node_runtime::WriterTally), as CDR bytes.
RIG_TALLY = b"virtual_rig: published\x00"


class Stranger:
    """A plain DDS participant (Python cyclonedds, no credentials) on the rig's domain: it reads
    ``rig/sample``, can send ABORTs, and keeps what it matched and read. (It uses matched-endpoint
    handles, not the builtin DCPSPublication/DCPSSubscription readers: cyclonedds-python 11 crashes
    decoding RustDDS's builtin-topic samples, secured or not.)"""

    def __init__(self, domain_id: int):
        self.dp = DomainParticipant(domain_id)
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll,
                  Policy.Durability.Volatile)
        self.samples = DataReader(self.dp, Topic(self.dp, "rt/rig/sample", types["RigSample"]), qos=qos)
        self.commands = DataWriter(self.dp, Topic(self.dp, "rt/rig/procedure/command", types["ProcedureCommand"]),
                                   qos=qos)
        self.read = self.matched_writers = self.matched_readers = self.aborts = 0

    def watch(self, proc: subprocess.Popen, abort: bool) -> None:
        while proc.poll() is None:
            if abort:
                self.commands.write(types["ProcedureCommand"](command=types["ProcedureCommand"].ABORT,
                                                              operator_name="stranger"))
                self.aborts += 1
            self.read += len(taken(self.samples, 1000))
            self.matched_writers = max(self.matched_writers, len(self.samples.get_matched_publications()))
            self.matched_readers = max(self.matched_readers, len(self.commands.get_matched_subscriptions()))
            time.sleep(0.2)


def run_watched(cmd: list, cwd: Path, log: Path, stranger: Stranger, abort: bool) -> int:
    proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.DEVNULL, stderr=open(log, "w"))
    try:
        stranger.watch(proc, abort)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
    return proc.returncode


def test_the_secure_suite_logs_what_the_plain_one_does_and_strangers_hear_nothing(
        tyrerig, domain_id, keystores, tmp_path):
    run = [str(tyrerig), "run", "--procedure", "staticlong", "--seed", "3", "--quiet",
           "--launch-config", str(short_launch_config(tmp_path))]
    # The control: on the plain suite, a participant without credentials matches the rig and
    # the recorder and reads the samples (it only listens: its ABORT would end the run).
    listener = Stranger(domain_id)
    rc = run_watched([*run, "--out", "plain.mcap", "--summary-json", "plain.json"], tmp_path,
                     tmp_path / "plain.log", listener, abort=False)
    assert rc == 0, (tmp_path / "plain.log").read_text()[-4000:]
    assert listener.read > 0 and listener.matched_writers > 0 and listener.matched_readers > 0, vars(listener)

    # On the secure suite the same participant matches nothing, reads nothing, and sends ABORT
    # all through the run. --max-speed: RustDDS's secured participants take ~10x longer per
    # message than plain ones (docs/security.md); at 4x real time the recorder outside the
    # lockstep loop keeps up.
    stranger = Stranger(domain_id)
    rc = run_watched([*run, "--out", "secure.mcap", "--summary-json", "secure.json",
                      "--keystore", str(keystores["ours"]), "--max-speed", "4"], tmp_path,
                     tmp_path / "secure.log", stranger, abort=True)
    assert rc == 0, (tmp_path / "secure.log").read_text()[-4000:]
    assert stranger.aborts > 10, "the stranger should have been sending all along"
    assert stranger.read == 0, f"a participant without credentials read {stranger.read} samples"
    assert stranger.matched_writers == 0 and stranger.matched_readers == 0, \
        f"a participant without credentials matched the suite's endpoints: {vars(stranger)}"

    p = json.loads((tmp_path / "plain.json").read_text())
    s = json.loads((tmp_path / "secure.json").read_text())
    assert p["completed"] and s["completed"], "the stranger's ABORTs must not have stopped the secure run"
    for key in ("sweeps", "total_rig_time_s"):
        assert s[key] == p[key], key
    # The same alarms — but for a thermal_lost raised in the first seconds of rig time: secured
    # discovery (handshakes per participant pair) can take longer than 0.5 s of the lockstep
    # rig's time on a loaded machine, and the sequencer then rightly holds (no sweep is released
    # before the gate has spoken). That is start-up timing, not a difference in what is logged.
    def settled(alarms):
        return [a for a in alarms if not (a["check"] == "thermal_lost" and a["rig_time_s"] < 3.0)]
    assert settled(s["alarms"]) == settled(p["alarms"]), "alarms"
    plain_log, secure_log = raw_log(tmp_path / "plain.mcap"), raw_log(tmp_path / "secure.mcap")
    assert "/rig/procedure/command" not in secure_log, "a command reached the secure suite's recorder"
    for topic in DETERMINISTIC:
        secure, plain = secure_log[topic], plain_log[topic]
        if topic == "/diagnostics":
            # The rig's count of its samples goes out once a wall second and names its writer's
            # GUID: neither is the same in two runs.
            secure, plain = ([m for m in log if RIG_TALLY not in m] for log in (secure, plain))
        if topic == "/rig/thermal/state":
            # The same start-up timing: a thermal participant still finishing its handshakes
            # when the rig starts misses the first samples (seen: 34 of 4016 at load 4). What it
            # then publishes must be the plain run's, message for message; at most 1 s is missed.
            late = len(plain) - len(secure)
            assert 0 <= late <= 100, f"{topic}: {late} messages fewer in the secure log"
            plain = plain[late:]
        assert secure == plain, f"{topic}: the secure log differs from the plain one"
    for topic in ("/rig/channels/live", "/rig/channels/sweep_summary", "/rig/channels/derived"):
        assert len(secure_log[topic]) == len(plain_log[topic]), topic
    assert len(secure_log["/rig/channels/live"]) == len(secure_log["/rig/sample"])


def secure_launch(path: Path, domain_id: int, keystore: Path, extra: str = "") -> Path:
    """A secured launch file: the test pattern publishing samples as /rig/pattern (rig role),
    and a recorder of procedure commands."""
    path.write_text(f"""
[runtime]
namespace = "/rig"
domain_id = {domain_id}

[security]
keystore = "{keystore}"

[[node]]
name = "pattern"
kind = "test_pattern"
[node.config]
rate_hz = 50.0
count = 100000
discovery_wait_s = 0.0
topics = ["sample"]
{extra}""")
    return path


def test_operator_stations(tyrerig, domain_id, keystores, tmp_path):
    ours, theirs = keystores["ours"], keystores["theirs"]
    launch = secure_launch(tmp_path / "stations.toml", domain_id, ours, """
[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "commands.mcap"
topics = ["procedure/command"]
""")
    suite = subprocess.Popen([str(tyrerig), "launch", str(launch)], cwd=tmp_path,
                             stderr=open(tmp_path / "launch.log", "w"))

    def command(keystore: Path, station: str, operator: str, timeout_s: float, log_name: str = "") -> subprocess.Popen:
        log = tmp_path / f"{log_name or operator}.log"
        # Without a backtrace the station's error is its one-line reason, which a failed
        # assertion below prints whole.
        env = {k: v for k, v in os.environ.items() if k not in ("RUST_BACKTRACE", "RUST_LIB_BACKTRACE")}
        return subprocess.Popen(
            [str(tyrerig), "command", "start", "--keystore", str(keystore), "--enclave", station,
             "--operator", operator, "--domain-id", str(domain_id), "--timeout-s", str(timeout_s),
             # No sequencer here (a recorder is the command's only reader): nothing to confirm by.
             "--confirm-s", "0"],
            stdout=open(log.with_suffix(".out"), "w"), stderr=open(log, "w"), env=env)

    def result(log_name: str, p: subprocess.Popen) -> tuple:
        rc = p.wait(timeout=90)
        log = tmp_path / f"{log_name}.log"
        return rc, log.with_suffix(".out").read_text(), log.read_text()

    # A plain stranger sends commands too.
    dp = DomainParticipant(domain_id)
    qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll, Policy.Durability.Volatile)
    stranger = DataWriter(dp, Topic(dp, "rt/rig/procedure/command", types["ProcedureCommand"]), qos=qos)
    try:
        stations = {
            "operator": command(ours, "/rig/operator_1", "operator", 60),
            "viewer": command(ours, "/rig/viewer", "viewer", 60),
            "other keystore": command(theirs, "/rig/operator_1", "stranger-with-a-certificate", 12),
        }
        for _ in range(50):
            stranger.write(types["ProcedureCommand"](operator_name="plain-stranger"))
            time.sleep(0.1)
        results = {k: result(k if k != "other keystore" else "stranger-with-a-certificate", p)
                   for k, p in stations.items()}
        rc, _, err = results["operator"]
        if rc != 0 and "no subscriber" in err:
            # RustDDS 0.15.1 now and then stalls one secured handshake for good; the remedy
            # docs/security.md gives the operator is to send again, which is a new participant
            # and a new handshake. Seen once here, with the machine loaded by a second test run.
            print("operator station unheard; sending again as docs/security.md says:", err[-500:])
            results["operator"] = result("operator-again", command(ours, "/rig/operator_1", "operator", 60,
                                                                   log_name="operator-again"))
    finally:
        stop(suite)

    rc, out, err = results["operator"]
    assert rc == 0 and "sent" in out, f"the operator station was not heard: {err[-3000:]}"
    rc, _, err = results["viewer"]
    assert rc != 0 and "security" in err and "procedure/command" in err, \
        f"a monitor enclave must be refused a command writer, saying why: {err[-3000:]}"
    rc, _, err = results["other keystore"]
    assert rc != 0 and "no subscriber" in err, \
        f"an enclave from another keystore must not be admitted: {err[-3000:]}"
    with open(tmp_path / "commands.mcap", "rb") as f:
        heard = [types["ProcedureCommand"].deserialize(m.data).operator_name
                 for _, _, m in make_reader(f).iter_messages()]
    assert heard == ["operator"], f"only the operator station may be heard: {heard}"


@pytest.fixture(scope="module")
def cyclone_peer(tmp_path_factory) -> Path:
    return cyclone_c_peer.build(tmp_path_factory.mktemp("cyclone_peer"))


def run_peers(peer: Path, domain_id: int, jobs: dict) -> dict:
    """Runs Cyclone peer commands concurrently; returns exit code, stdout, stderr of each."""
    env = cyclone_c_peer.enclave_env(domain_id)
    procs = {k: subprocess.Popen([str(peer), *args], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                 text=True) for k, args in jobs.items()}
    return {k: (p.wait(timeout=90), *p.communicate()) for k, p in procs.items()}


def samples_in(out: str) -> list:
    return [json.loads(line) for line in out.splitlines() if line.startswith("{")]


def test_cyclone_dds_runs_a_secured_domain_on_our_keystore(domain_id, keystores, cyclone_peer):
    ours, theirs = keystores["ours"], keystores["theirs"]
    r = run_peers(cyclone_peer, domain_id, {
        "monitor reads": ["read", enclave(ours, "/rig/cyclone_monitor"), "30", "20"],
        "other keystore reads": ["read", enclave(theirs, "/rig/cyclone_monitor"), "1", "10"],
        "plain reads": ["read", "-", "1", "10"],
        "monitor commands": ["command", enclave(ours, "/rig/cyclone_monitor"), "1", "monitor"],
        "rig publishes": ["sample", enclave(ours, "/rig/cyclone_rig"), "60", "15"],
    })
    # Cyclone's own access control, reading our permissions: a monitor may not command.
    rc, out, err = r["monitor commands"]
    assert rc == 3 and "WRITER_REFUSED" in out, f"{out} {err[-2000:]}"
    # Two Cyclone participants with our enclaves authenticate and exchange signed samples.
    rc, out, err = r["rig publishes"]
    assert rc == 0 and out.startswith("SENT 60"), f"{out} {err[-2000:]}"
    rc, out, err = r["monitor reads"]
    rows = samples_in(out)
    assert rc == 0 and len(rows) >= 30, f"exit {rc}, {len(rows)} samples: {err[-2000:]}"
    assert all(row["fx_n"] == row["seq"] + 0.5 and row["header"]["frame_id"] == "iso_w" for row in rows)
    # Without credentials, or with another keystore's, nothing.
    for who in ("other keystore reads", "plain reads"):
        rc, out, err = r[who]
        assert rc == 2 and not samples_in(out), f"{who}: exit {rc}: {out[:300]} {err[-1000:]}"


def test_cyclone_dds_reads_the_rust_suites_samples(tyrerig, domain_id, keystores, cyclone_peer, tmp_path):
    launch = secure_launch(tmp_path / "pattern.toml", domain_id, keystores["ours"])
    env = {**os.environ, "RUST_LOG": "error,rustdds::discovery::secure_discovery=error,rustdds::dds::pubsub=off"}
    suite = subprocess.Popen([str(tyrerig), "launch", str(launch)], cwd=tmp_path, env=env,
                             stderr=open(tmp_path / "launch.log", "w"))
    try:
        r = run_peers(cyclone_peer, domain_id, {
            "monitor": ["read", enclave(keystores["ours"], "/rig/cyclone_monitor"), "20", "12"]})
    finally:
        stop(suite)
    handshake = [line for line in (tmp_path / "launch.log").read_text().splitlines() if "handshake" in line]
    rc, out, err = r["monitor"]
    assert rc == 0 and len(samples_in(out)) == 20, f"exit {rc}; RustDDS said: {handshake[:4]}"
