"""Fault injection: the suite as separate OS processes (``tyrerig launch --processes``), nodes
killed, stopped and restarted by signal while a procedure runs, watched by a Cyclone DDS control
room that timestamps what it sees.

The rig runs in real time, 10x accelerated (100 Hz rig samples = 1,000 samples per wall second),
through the GS2MF FreeRolling procedure. Each test injects one fault and checks the safe
behaviour the suite promises:

- the rig stopped (SIGSTOP 2 s) or killed: the sequencer holds zero slip in the same control
  cycle it notices, alarms within 1 s, and (after SIGCONT) reruns the interrupted sweep;
- the thermal node killed: an alarm within 1 s, no sweep released while no fresh thermal state
  comes, the procedure goes on once a new thermal node runs;
- the sequencer killed: the rig's own watchdog holds zero slip and alarms; a new sequencer
  resumes from its checkpoint at the interrupted sweep;
- the quality node killed: the recorder notices its stream stop; the procedure is unaffected;
- the recorder killed and restarted: the first file recovers to its last complete chunk, the
  second file continues beside it, and the rig's publisher never stalls;
- the recorder killed beside a second recorder: for a minute after the kill the second recorder,
  and every other reader of the rig, loses nothing (the killed reader stops holding the rig's send
  window, vendor/rustdds/PATCHES.md patch 3).

Each test prints one row of the fault table in docs/reliability.md: fault, time to detect (wall
time from the signal to the alarm reaching the control room) and data lost (from the logs).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from datetime import datetime
from pathlib import Path

import pytest
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from conftest import REPO, stop, taken, wait_for
from tyre_msgs_idl import types

PHASE_SWEEP, PHASE_THERMAL_PAUSE, PHASE_PAUSED = 1, 2, 5
ERROR = 2  # diagnostic_msgs/DiagnosticStatus.ERROR


def level_of(status) -> int:
    """DiagnosticStatus.level (an IDL byte: int or a one-byte bytes, by binding version)."""
    lv = status.level
    return lv[0] if isinstance(lv, (bytes, bytearray)) else int(lv)
CONFIG = REPO / "launch-config"


FREEROLLING = CONFIG / "procedures" / "gs2mf_freerolling.toml"


def short_procedure(tmp: Path) -> Path:
    """GS2MF FreeRolling's heating sweep and first graph sweeps without the 470 s of warm-up
    and step-steer before them: thermal pauses from ~1 s of wall time on."""
    text = FREEROLLING.read_text()
    header = text[:text.index("[[section]]")]
    body = text[text.index('[[section]]\nname = "heating_sweep"'):text.index('[[section]]\nname = "on_centre')]
    path = tmp / "short_freerolling.toml"
    path.write_text(header.replace('name = "gs2mf_freerolling"', 'name = "short_freerolling"') + body)
    return path


SECOND_RECORDER = """
[[node]]
name = "recorder_b"
kind = "recorder"
[node.config]
output = "run_b.mcap"
flush_interval_s = 0.25
"""


def launch_file(tmp: Path, domain_id: int, procedure: Path = FREEROLLING, second_recorder: bool = False) -> Path:
    path = tmp / "faults.toml"
    path.write_text(f"""
[runtime]
domain_id = {domain_id}
{SECOND_RECORDER if second_recorder else ""}
[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "run.mcap"
flush_interval_s = 0.25
on_existing = "new_file"

[[node]]
name = "virtual_rig"
kind = "virtual_rig"
[node.config]
rig_config = "{CONFIG / 'virtual_rig.toml'}"
clock = "realtime"
time_scale = 10.0
start_delay_s = 3.0

[[node]]
name = "thermal"
kind = "thermal"

[[node]]
name = "sequencer"
kind = "sequencer"
[node.config]
procedure = "{procedure}"
autostart = true
checkpoint = "run.checkpoint.json"

[[node]]
name = "quality"
kind = "quality"
""")
    return path


def children(pid: int) -> dict[str, int]:
    """Node name → pid of the launcher's child processes (`tyrerig node <name> …`)."""
    out = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            argv = (entry / "cmdline").read_bytes().split(b"\0")
        except (OSError, IndexError, ValueError):
            continue
        if ppid == pid and len(argv) > 2 and argv[1] == b"node":
            out[argv[2].decode()] = int(entry.name)
    return out


class ControlRoom:
    """A Cyclone DDS participant watching /diagnostics, procedure/state and setpoints, with the
    wall time each message arrived."""

    def __init__(self, domain_id: int):
        self.dp = DomainParticipant(domain_id)
        keep_all = lambda d: Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll, d)
        vol, tl = Policy.Durability.Volatile, Policy.Durability.TransientLocal
        self.diag_reader = DataReader(self.dp, Topic(self.dp, "rt/diagnostics",
                                                     types["diagnostic_msgs/msg/DiagnosticArray"]), qos=keep_all(vol))
        self.state_reader = DataReader(self.dp, Topic(self.dp, "rt/rig/procedure/state",
                                                      types["ProcedureState"]), qos=keep_all(tl))
        self.setpoint_reader = DataReader(self.dp, Topic(self.dp, "rt/rig/setpoint", types["RigSetpoint"]),
                                          qos=keep_all(vol))
        self.diags: list[tuple[float, object]] = []  # (wall time, DiagnosticStatus)
        self.states: list[tuple[float, object]] = []
        self.setpoints: list[tuple[float, object]] = []

    def poll(self) -> None:
        now = time.monotonic()
        for d in taken(self.diag_reader, 1000):
            self.diags.extend((now, st) for st in d.status)
        self.states.extend((now, s) for s in taken(self.state_reader, 1000))
        self.setpoints.extend((now, s) for s in taken(self.setpoint_reader, 10000))

    def wait_diag(self, name: str, after: float, timeout: float, level: int | None = None, text: str = ""):
        """The first status named `name` (and containing `text`) that arrived after `after`."""
        def found():
            self.poll()
            for t, st in self.diags:
                if t >= after and st.name == name and text in st.message and (level is None or level_of(st) == level):
                    return t, st
            return None
        return wait_for(found, timeout, f"/diagnostics {name!r} {text!r}", interval=0.01)

    def wait_state(self, pred, after: float, timeout: float, what: str):
        def found():
            self.poll()
            for t, s in self.states:
                if t >= after and pred(s):
                    return t, s
            return None
        return wait_for(found, timeout, what, interval=0.01)


class Suite:
    def __init__(self, tyrerig: Path, tmp: Path, domain_id: int, procedure: Path = FREEROLLING,
                 second_recorder: bool = False):
        self.tyrerig, self.tmp = tyrerig, tmp
        self.launch = launch_file(tmp, domain_id, procedure, second_recorder)
        n = 6 if second_recorder else 5
        self.log = open(tmp / "suite.log", "w")
        self.proc = subprocess.Popen([str(tyrerig), "launch", str(self.launch), "--processes"], cwd=tmp,
                                     stdout=self.log, stderr=subprocess.STDOUT)
        self.extra: list[subprocess.Popen] = []
        self.pids = wait_for(lambda: (c := children(self.proc.pid)) and len(c) == n and c, 20.0, f"{n} node processes")

    def restart(self, node: str) -> subprocess.Popen:
        p = subprocess.Popen([str(self.tyrerig), "node", node, "--config", str(self.launch)], cwd=self.tmp,
                             stdout=self.log, stderr=subprocess.STDOUT)
        self.extra.append(p)
        return p

    def close(self) -> str:
        for p in self.extra:
            if p.poll() is None and "recorder" not in p.args:
                stop(p, signal.SIGINT)
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            self.proc.wait(timeout=60)
        for p in self.extra:
            if p.poll() is None:
                time.sleep(0.5)
                stop(p, signal.SIGINT)
        self.log.close()
        return (self.tmp / "suite.log").read_text()


@pytest.fixture
def suite(tyrerig, domain_id, tmp_path):
    room = ControlRoom(domain_id)
    s = Suite(tyrerig, tmp_path, domain_id)
    s.room = room
    yield s
    s.close()


@pytest.fixture
def two_recorder_suite(tyrerig, domain_id, tmp_path):
    """The suite with a second recorder (`recorder_b`, writing run_b.mcap)."""
    room = ControlRoom(domain_id)
    s = Suite(tyrerig, tmp_path, domain_id, second_recorder=True)
    s.room = room
    yield s
    s.close()


@pytest.fixture
def short_suite(tyrerig, domain_id, tmp_path):
    """The suite running `short_procedure`."""
    room = ControlRoom(domain_id)
    s = Suite(tyrerig, tmp_path, domain_id, short_procedure(tmp_path))
    s.room = room
    yield s
    s.close()


def sample_seqs(path: Path) -> list[int]:
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [m.seq for _, _, _, m in reader.iter_decoded_messages(topics=["/rig/sample"])]


def sample_log(path: Path) -> list[tuple[int, int]]:
    """(log time in ns since the epoch, RigSample.seq) of every sample in a log."""
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(msg.log_time, m.seq) for _, _, msg, m in reader.iter_decoded_messages(topics=["/rig/sample"])]


def loss_record(path: Path) -> dict[str, str]:
    """The last `tyrerig.loss` record of a log."""
    with open(path, "rb") as f:
        records = [m for m in make_reader(f).iter_metadata() if m.name == "tyrerig.loss"]
    assert records, f"{path}: no tyrerig.loss record"
    return records[-1].metadata


def gaps(seqs: list[int]) -> int:
    return sum(b - a - 1 for a, b in zip(seqs, seqs[1:]) if b > a + 1)


def strip_ansi(text: str) -> str:
    return re.sub(r"\x1b\[[0-9;]*m", "", text)


def wall_s(stamp: str) -> float:
    """A log line's RFC 3339 UTC stamp (`2026-11-24T01:59:41.300470Z`) as Unix time."""
    return datetime.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()


def row(fault: str, detect_s: float | None, lost: str) -> None:
    shown = "–" if detect_s is None else f"{detect_s:.3f} s"
    print(f"\nFAULT TABLE | {fault} | {shown} | {lost} |")


def in_sweep(suite: Suite, after: float = 0.0, timeout: float = 40.0, index: int = 1):
    return suite.room.wait_state(lambda s: s.phase == PHASE_SWEEP and s.sweep_index >= index, after, timeout,
                                 f"sweep {index} running")


def last_setpoint_is_zero_slip(suite: Suite, t0: float) -> None:
    """Setpoints answering samples already in flight may follow the fault; the last one (the
    hold) must be zero slip."""
    time.sleep(0.3)
    suite.room.poll()
    after = [s for t, s in suite.room.setpoints if t >= t0]
    assert after, "no hold setpoint after the fault"
    assert after[-1].slip_angle_deg == 0.0 and after[-1].slip_ratio == 0.0, after[-1]


def test_rig_stopped_2s_is_held_safe_and_the_sweep_reruns(suite):
    """The rig process stopped for 2 s (SIGSTOP) is detected and held at zero slip; continued
    (SIGCONT), it talks DDS again and the interrupted sweep reruns. Linux fails `epoll_wait` with
    EINTR after a stop even with no handler; the vendored RustDDS polls again instead of ending
    its participant's event loop (vendor/rustdds/PATCHES.md, patch 1)."""
    _, st = in_sweep(suite)
    time.sleep(0.3)
    suite.room.poll()
    k = suite.room.states[-1][1].sweep_index
    os.kill(suite.pids["virtual_rig"], signal.SIGSTOP)
    t0 = time.monotonic()
    try:
        t_alarm, st = suite.room.wait_diag("sequencer: rig_silent", t0, 5.0, level=ERROR)
        last_setpoint_is_zero_slip(suite, t0)
        suite.room.wait_state(lambda s: s.phase == PHASE_PAUSED, t0, 2.0, "PAUSED")
        time.sleep(max(0.0, t0 + 2.0 - time.monotonic()))
    finally:
        os.kill(suite.pids["virtual_rig"], signal.SIGCONT)
    t_cont = time.monotonic()
    suite.room.wait_diag("sequencer: rig_silent", t_cont, 10.0, text="interrupted sweep reruns")
    _, rerun = suite.room.wait_state(lambda s: s.phase == PHASE_SWEEP, t_cont, 20.0, "the sweep rerunning")
    assert rerun.sweep_index <= k, f"resumed at sweep {rerun.sweep_index}, interrupted at {k}"
    time.sleep(1.0)
    out = suite.close()
    # Every DDS thread of the continued rig survived: RustDDS logs the failed poll as it ends a
    # loop ('dp_event_loop poll failed' or, for discovery, 'Failed in waiting of poll', both with
    # 'Interrupted system call'). The discovery thread, idle in epoll_wait, meets EINTR in nearly
    # every run; whether the busy event loop does depends on timing, so the resume alone passed
    # unpatched on a loaded machine (vendor/rustdds/PATCHES.md).
    eintr = [line for line in strip_ansi(out).splitlines() if "Interrupted system call" in line]
    assert not eintr, f"a DDS poll loop ended on EINTR: {eintr}"
    seqs = sample_seqs(suite.tmp / "run.mcap")
    assert gaps(seqs) == 0, "samples lost while the rig was stopped"
    assert t_alarm - t0 < 1.0, f"alarm after {t_alarm - t0:.3f} s"
    row("rig stopped (SIGSTOP) for 2 s", t_alarm - t0, f"0 of {len(seqs)} samples (the rig's time stood still)")


def test_rig_killed_is_held_safe(suite):
    in_sweep(suite)
    os.kill(suite.pids["virtual_rig"], signal.SIGKILL)
    t0 = time.monotonic()
    t_alarm, _ = suite.room.wait_diag("sequencer: rig_silent", t0, 5.0, level=ERROR)
    last_setpoint_is_zero_slip(suite, t0)
    suite.room.wait_state(lambda s: s.phase == PHASE_PAUSED, t0, 2.0, "PAUSED")
    suite.close()
    seqs = sample_seqs(suite.tmp / "run.mcap")
    assert gaps(seqs) == 0
    assert t_alarm - t0 < 1.0, f"alarm after {t_alarm - t0:.3f} s"
    row("rig killed (SIGKILL)", t_alarm - t0, f"0 of {len(seqs)} recorded samples (continuous up to the kill)")


def reported_sample_loss(path: Path) -> int:
    """RigSamples the recorder says it lost (its `tyrerig.loss` record, by `RigSample.seq`)."""
    with open(path, "rb") as f:
        records = [m for m in make_reader(f).iter_metadata() if m.name == "tyrerig.loss"]
    assert records, f"{path}: no tyrerig.loss record"
    entries = records[-1].metadata
    assert entries["complete"] == "true", entries
    return sum(int(v) for k, v in entries.items() if k.startswith("/rig/sample msg ") and k.endswith(" lost"))


def test_thermal_node_gone_releases_no_sweep(short_suite):
    """The thermal node killed as a thermal pause begins: the sequencer alarms at once, and the
    pause outlasts a normal one (rig samples still flowing) without releasing; a new thermal
    node releases it and the procedure goes on.

    The killed node's reliable reader of rig/sample never acknowledges again, and RustDDS keeps
    it matched until its participant lease ends (~50 s). Unpatched, the rig's send window (8,192
    samples) filled ~8 s after the kill and the rig's samples were refused for every reader until
    the lease ended; the vendored RustDDS stops waiting for it after 2 s without an ACKNACK
    (vendor/rustdds/PATCHES.md, patch 3). The new node's reader can make the rig refuse a few
    samples as it matches (RustDDS counts it as having acknowledged nothing until its first
    ACKNACK). Whichever path a run takes, every sample lost must be in the recorder's loss
    record."""
    suite = short_suite
    # A normal pause first, to know how long one takes on this machine.
    t_a, first = suite.room.wait_state(lambda s: s.phase == PHASE_THERMAL_PAUSE, 0.0, 90.0, "a thermal pause")
    t_b, _ = suite.room.wait_state(lambda s: s.phase != PHASE_THERMAL_PAUSE, t_a, 60.0, "the first pause ending")
    normal_pause_s = t_b - t_a
    # The next pause: the thermal node is killed as it begins.
    _, pause = suite.room.wait_state(lambda s: s.phase == PHASE_THERMAL_PAUSE and s.sweep_index > first.sweep_index,
                                     t_b, 90.0, "the next thermal pause")
    os.kill(suite.pids["thermal"], signal.SIGKILL)
    t0 = time.monotonic()
    t_alarm, _ = suite.room.wait_diag("sequencer: thermal_lost", t0, 5.0, level=ERROR)
    # Held for twice a normal pause (at least 3 s = 30 s of rig time), well inside the ~8 s the
    # rig's samples still flow: the pause must not release on the last, stale thermal state.
    hold_s = max(3.0, 2.0 * normal_pause_s)
    assert hold_s < 7.0, f"a normal pause took {normal_pause_s:.1f} s: too long to outlast before the window fills"
    time.sleep(max(0.0, t0 + hold_s - time.monotonic()))
    suite.room.poll()
    during = [s for t, s in suite.room.states if t >= t0]
    assert all(s.phase == PHASE_THERMAL_PAUSE for s in during), \
        f"left the pause without a thermal node: phases {sorted({s.phase for s in during})}"
    assert not [st for t, st in suite.room.diags if t >= t0 and st.name == "sequencer: rig_silent"], \
        "the rig went silent during the hold: the check did not run on a flowing rig"
    # A new thermal node: fresh states release the pause, the procedure goes on (at once, or
    # after the killed reader's lease ends if the rig's window filled first).
    t_new = time.monotonic()
    suite.restart("thermal")
    suite.room.wait_diag("sequencer: thermal_lost", t_new, 70.0, text="fresh again")
    t_next, _ = suite.room.wait_state(lambda s: s.phase == PHASE_SWEEP and s.sweep_index > pause.sweep_index,
                                      t_new, 70.0, "the next sweep after the new thermal node")
    suite.close()
    seqs = sample_seqs(suite.tmp / "run.mcap")
    lost, reported = gaps(seqs), reported_sample_loss(suite.tmp / "run.mcap")
    assert lost == reported, f"{lost} samples missing from the log, {reported} in its loss record"
    assert t_alarm - t0 < 1.0, f"alarm after {t_alarm - t0:.3f} s"
    row("thermal node killed (SIGKILL) as a pause began, restarted", t_alarm - t0,
        f"pause held {hold_s:.1f} s without release (the first pause: {normal_pause_s:.1f} s); the next sweep "
        f"{t_next - t_new:.1f} s after the restart; {lost} of {len(seqs) + lost} samples lost, {reported} in the "
        f"loss record")


def test_sequencer_killed_rig_holds_and_restart_resumes_the_sweep(suite):
    in_sweep(suite)
    time.sleep(0.3)
    suite.room.poll()
    k = suite.room.states[-1][1].sweep_index
    os.kill(suite.pids["sequencer"], signal.SIGKILL)
    t0 = time.monotonic()
    t_alarm, _ = suite.room.wait_diag("virtual_rig: setpoint_watchdog", t0, 5.0, level=ERROR)
    t_new = time.monotonic()
    suite.restart("sequencer")
    _, resumed = suite.room.wait_state(lambda s: s.phase == PHASE_SWEEP, t_new, 30.0, "the resumed sweep")
    assert resumed.sweep_index <= k, f"resumed at sweep {resumed.sweep_index}, killed during {k}"
    time.sleep(1.0)
    suite.close()
    seqs = sample_seqs(suite.tmp / "run.mcap")
    assert gaps(seqs) == 0
    assert t_alarm - t0 < 1.0, f"alarm after {t_alarm - t0:.3f} s"
    row("sequencer killed (SIGKILL), restarted", t_alarm - t0,
        f"0 of {len(seqs)} samples; the interrupted sweep (index {k}) reran from the checkpoint")


def test_quality_node_killed_is_noticed_and_the_run_goes_on(suite):
    in_sweep(suite)
    os.kill(suite.pids["quality"], signal.SIGKILL)
    t0 = time.monotonic()
    t_alarm, _ = suite.room.wait_diag("recorder: stream_silent", t0, 5.0, level=ERROR, text="/rig/channels/live")
    suite.room.poll()
    progress_at_kill = suite.room.states[-1][1].progress
    suite.restart("quality")
    suite.room.wait_diag("recorder: stream_silent", t0, 20.0, text="flowing again")
    suite.room.wait_state(lambda s: s.progress > progress_at_kill, t0, 10.0, "the procedure going on")
    suite.close()
    seqs = sample_seqs(suite.tmp / "run.mcap")
    with open(suite.tmp / "run.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        live = [m.sample_seq for _, _, _, m in reader.iter_decoded_messages(topics=["/rig/channels/live"])]
    assert gaps(seqs) == 0
    assert t_alarm - t0 < 1.0, f"alarm after {t_alarm - t0:.3f} s"
    row("quality node killed (SIGKILL), restarted", t_alarm - t0,
        f"0 samples; {gaps(live)} live-channel messages not computed while it was down")


def test_recorder_restarted_mid_run_keeps_both_files_and_never_stalls_the_rig(suite):
    """The recorder killed and restarted at once. The killed recorder's reliable reader never
    acknowledges again and stays matched until its participant lease ends (~50 s, RustDDS).
    Unpatched, the rig's send window (8,192 samples) filled ~8 s after the kill and the rig
    refused every sample for every reader until the lease ended; the vendored RustDDS stops
    waiting for a reader that has sent no ACKNACK for 2 s (vendor/rustdds/PATCHES.md, patch 3),
    so the window never fills: the rig keeps publishing, the sequencer never holds it, and what
    a log lost is in its loss record. The new recorder's reader may cost a few samples as it
    matches (docs/reliability.md, "Known limits"). The first file recovers to its last complete
    chunk; the second continues it."""
    in_sweep(suite)
    os.kill(suite.pids["recorder"], signal.SIGKILL)
    t0 = time.monotonic()
    suite.restart("recorder")
    # Past the ~8 s the rig's send window lasted at 1,000 samples/s before patch 3. The control
    # room takes what queued up meanwhile (decoding ~11,000 setpoints takes it seconds), then
    # must see setpoints still coming in the last second.
    time.sleep(11.0)
    suite.room.poll()
    mark = time.monotonic()
    time.sleep(1.0)
    suite.room.poll()
    recent = [s for t, s in suite.room.setpoints if t >= mark]
    held = [st for t, st in suite.room.diags if t >= t0 and st.name == "sequencer: rig_silent"]
    out = suite.close()
    # The rig logs its 1st-5th and every 1,000th refused sample with the wall time.
    refusals = [(wall_s(m[1]), int(m[2])) for m in
                re.finditer(r"(\S+Z)\s.*?refused by the writer \((\d+) so far\)", strip_ansi(out))]
    assert recent, "no setpoints in the last second: the rig (or its sequencer) stalled"
    assert not held, "the sequencer held the rig: samples stopped reaching it after the kill"
    assert not refusals or refusals[-1][1] < 100, \
        f"the rig refused {refusals[-1][1]}+ samples: the killed reader held its send window"
    first, second = suite.tmp / "run.mcap", suite.tmp / "run.1.mcap"
    assert second.exists(), out[-3000:]
    recovered = suite.tmp / "run.recovered.mcap"
    done = subprocess.run([str(suite.tyrerig), "mcap", "recover", str(first), "-o", str(recovered)],
                          capture_output=True, text=True, check=True)
    assert "recovered" in done.stdout
    a, b = sample_seqs(recovered), sample_seqs(second)
    assert gaps(a) == 0, "the first file lost samples before the kill"
    assert gaps(b) == reported_sample_loss(second), "the second file lost samples its loss record does not show"
    assert b[0] > a[-1], (a[-1], b[0])
    lost = b[0] - a[-1] - 1
    info = subprocess.run([str(suite.tyrerig), "mcap", "info", str(second)], capture_output=True, text=True,
                          check=True).stdout
    assert "continues" in info and "run.mcap" in info
    row("recorder killed (SIGKILL), restarted at once", None,
        f"{lost} samples between the recovered first file (last seq {a[-1]}) and the second (first seq {b[0]}); "
        f"the second file: {gaps(b)} missing, all in its loss record; "
        + (f"the rig refused {refusals[-1][1]} sample(s)" if refusals else "the rig refused none")
        + "; the sequencer never held the rig")


def test_recorder_killed_costs_the_other_recorder_nothing(two_recorder_suite):
    """One of two recorders killed (SIGKILL) and not restarted. Its reliable readers stay matched
    until its participant lease ends (~50 s, RustDDS) and never acknowledge again. Unpatched, the
    rig's send window (8,192 samples) filled ~8 s after the kill: the rig refused every sample
    for every reader until the lease ended, the sequencer held the rig, and the other recorder's
    log simply ended (its loss record said nothing was lost: a tail that never arrives leaves no
    gap). With the vendored RustDDS's patch 3 the rig's writer stops waiting for the dead reader
    after 2 s without an ACKNACK. For a minute after the kill: the other recorder's log is
    continuous and its loss record clean, the rig refuses nothing, the sequencer never holds the
    rig, and the rig's own count (its `virtual_rig: published` tallies) agrees with the log."""
    suite = two_recorder_suite
    in_sweep(suite)
    os.kill(suite.pids["recorder"], signal.SIGKILL)
    t0, kill_wall = time.monotonic(), time.time()
    time.sleep(60.0)
    suite.room.poll()
    held = [st for t, st in suite.room.diags if t >= t0 and st.name == "sequencer: rig_silent"]
    tallies = [{kv.key: kv.value for kv in st.values} for t, st in suite.room.diags
               if st.name == "virtual_rig: published"]
    out = strip_ansi(suite.close())
    b = sample_log(suite.tmp / "run_b.mcap")
    seqs = [seq for _, seq in b]
    after = [seq for log_ns, seq in b if log_ns >= kill_wall * 1e9]
    record = loss_record(suite.tmp / "run_b.mcap")
    refused = re.findall(r"refused by the writer", out)
    # The rig's writer says when it stopped waiting for the killed reader.
    inactive = [wall_s(m[1]) for m in re.finditer(
        r"(\S+Z)\s.*?has sent no ACKNACK for [0-9.]+ s .*?topic=\"rt/rig/sample\"", out)]
    # What happened, before any check (a failing run still says it).
    span = (after[-1] - after[0] + 1) if after else 0
    print(f"\nMEASURED | second recorder: {len(seqs)} samples, {gaps(seqs)} missing by RigSample.seq; after the "
          f"kill {len(after)} samples spanning seq {after[0] if after else '-'}-{after[-1] if after else '-'} "
          f"({span - len(after)} missing); loss record lost_total {record.get('lost_total')}; the rig logged "
          f"{len(refused)} refusal line(s) (last: {(re.findall(r'refused by the writer [(]([0-9]+) so far', out) or ['-'])[-1]} "
          f"so far); rig_silent {len(held)}; rig tallies {len(tallies)}; log ends "
          f"{(b[-1][0] / 1e9 - kill_wall) if b else float('nan'):.1f} s after the kill |")
    assert not refused, f"the rig refused {len(refused)} logged sample(s) after a recorder was killed"
    assert not held, "the sequencer held the rig: samples stopped reaching it after the kill"
    assert gaps(seqs) == 0 and record["complete"] == "true" and record["lost_total"] == "0", record
    # A minute at 1,000 samples per wall second; a rig that stalled would have far fewer.
    assert len(after) > 45_000 and after == list(range(after[0], after[0] + len(after))), \
        f"{len(after)} samples after the kill, {gaps(after)} missing"
    assert tallies and all(t["refused"] == "0" for t in tallies), tallies[-3:]
    assert int(tallies[-1]["last_seq"]) <= seqs[-1], (tallies[-1], seqs[-1])
    assert inactive, "the rig's writer never said it stopped waiting for the killed reader"
    row("recorder killed (SIGKILL), a second recorder running", inactive[0] - kill_wall,
        f"0 of {len(after)} samples lost by the second recorder in the 60 s after the kill ({len(seqs)} in its log, "
        f"continuous, loss record clean); the rig refused none and was never held; time to detect = the rig's "
        f"writer stops waiting for the killed reader")
