"""Independent MCAP readers (Python ``mcap`` with CRC validation, ``mcap-ros2-support``) on a log
recorded by the Rust recorder node through DDS, with the publisher in another process: every
topic, every message, every field equal to what was published."""

from __future__ import annotations

import subprocess
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from conftest import stop, wait_for
from pattern import expected, plain, stamp_sec

COUNT = 40
TOPICS = {
    "/rig/sample": "tyre_msgs/msg/RigSample",
    "/rig/setpoint": "tyre_msgs/msg/RigSetpoint",
    "/rig/procedure/state": "tyre_msgs/msg/ProcedureState",
    "/rig/procedure/command": "tyre_msgs/msg/ProcedureCommand",
    "/rig/thermal/state": "tyre_msgs/msg/ThermalState",
    "/rig/channels/live": "tyre_msgs/msg/LiveChannels",
    "/rig/channels/sweep_summary": "tyre_msgs/msg/SweepSummary",
    "/rig/channels/derived": "tyre_msgs/msg/DerivedMeasurement",
    "/rig/quality/report": "tyre_msgs/msg/QualityReport",
    "/rig/model/state": "tyre_msgs/msg/ModelState",
    "/rig/model/covariance": "tyre_msgs/msg/ModelCovariance",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "/clock": "rosgraph_msgs/msg/Clock",
}


def test_recording_through_dds_reads_back_in_python(tyrerig, domain_id, tmp_path: Path):
    launch = tmp_path / "rec.toml"
    launch.write_text(f"""
[runtime]
domain_id = {domain_id}

[[node]]
name = "pattern"
kind = "test_pattern"
[node.config]
rate_hz = 20.0
count = {COUNT}
# The recorder starts in its own process: publish once it has subscribed to every topic.
wait_for_subscribers = 1
discovery_wait_s = 1.0

[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "logs/rec.mcap"
[node.config.metadata.tyre]
file = "MagicFormula61_Paramerters.tir"
[node.config.metadata.procedure]
name = "test_pattern"
""")
    recorder = subprocess.Popen([str(tyrerig), "node", "recorder", "--config", str(launch)], cwd=tmp_path)
    pattern = subprocess.Popen([str(tyrerig), "node", "pattern", "--config", str(launch)], cwd=tmp_path)
    try:
        assert pattern.wait(timeout=60) == 0
        # /clock is best effort; the reliable topics must be complete. Give the last ones time.
        wait_for(lambda: (tmp_path / "logs/rec.mcap").stat().st_size > 0, 5, "the log file")
        import time
        time.sleep(1.0)
    finally:
        assert stop(recorder) == 0

    path = tmp_path / "logs/rec.mcap"
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        assert header.profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes, "summary with chunk indexes"
        channels = {c.topic: c for c in summary.channels.values()}
        assert set(channels) == set(TOPICS)
        for topic, ros_type in TOPICS.items():
            ch = channels[topic]
            assert ch.message_encoding == "cdr"
            schema = summary.schemas[ch.schema_id]
            assert schema.encoding == "ros2msg" and schema.name == ros_type
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        assert metadata["tyre"]["file"] == "MagicFormula61_Paramerters.tir"
        assert metadata["tyrerig"]["namespace"] == "/rig"

        by_topic = {t: {} for t in TOPICS}
        for _schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            n = stamp_sec(decoded)
            assert n not in by_topic[channel.topic], f"{channel.topic}: message {n} twice"
            by_topic[channel.topic][n] = decoded
            # publish_time is the message's stamp
            stamp = decoded.header.stamp if hasattr(decoded, "header") else decoded.clock
            assert message.publish_time == stamp.sec * 1_000_000_000 + stamp.nanosec

    for topic, ros_type in TOPICS.items():
        got = by_topic[topic]
        if topic == "/clock":
            # Best effort by the ROS convention: loss is allowed, corruption is not.
            assert len(got) >= COUNT // 2, f"{topic}: only {len(got)} messages"
        else:
            assert sorted(got) == list(range(COUNT)), f"{topic}: {sorted(got)}"
        for n, decoded in got.items():
            assert plain(decoded) == plain(expected(ros_type, n)), f"{topic} message {n}"
